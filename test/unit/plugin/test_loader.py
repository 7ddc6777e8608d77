"""PluginLoader: plugins found by name through the ament index, pluginlib's way."""

import os
import textwrap

import pytest
from rm_base.plugin import (
    PluginBase,
    PluginDescriptionError,
    PluginLoader,
    PluginNotFoundError,
)

MODULE = """
from rm_base.plugin import PluginBase


class Good(PluginBase):
    pass


class NotAPlugin:
    pass
"""

XML = """
<class_libraries>
  <library path="toy_plugins">
    <class name="toy_plugins/Good" type="toy_plugins_mod.Good"
           base_class_type="rm_base::PluginBase">
      <description>  A good
        plugin. </description>
    </class>
    <class name="toy_plugins/NotAPlugin" type="toy_plugins_mod.NotAPlugin"
           base_class_type="rm_base::PluginBase"/>
    <class name="toy_plugins/Missing" type="toy_plugins_mod.Missing"
           base_class_type="rm_base::PluginBase"/>
    <class name="toy_plugins/BadModule" type="toy_plugins_nowhere.Thing"
           base_class_type="rm_base::PluginBase"/>
    <class type="toy_plugins_mod.Good" base_class_type="rm_base::PluginBase"/>
  </library>
  <library path="other">
    <class name="rviz/Display" type="toy_plugins_mod.Good" base_class_type="rviz_common::Display"/>
  </library>
</class_libraries>
"""


def make_prefix(root, package, xml_text, xml_rel='share/{pkg}/plugins.xml'):
    """Lay out an install prefix as colcon would for a package exporting rm_base plugins."""
    rel = xml_rel.format(pkg=package)
    xml_file = root / rel
    xml_file.parent.mkdir(parents=True, exist_ok=True)
    xml_file.write_text(textwrap.dedent(xml_text))
    marker = root / 'share/ament_index/resource_index/rm_base__pluginlib__plugin' / package
    marker.parent.mkdir(parents=True, exist_ok=True)
    marker.write_text(rel + '\n')
    return root


@pytest.fixture
def toy_prefix(tmp_path, monkeypatch):
    prefix = make_prefix(tmp_path / 'install', 'toy_plugins', XML)
    (tmp_path / 'src').mkdir()
    (tmp_path / 'src' / 'toy_plugins_mod.py').write_text(MODULE)
    monkeypatch.syspath_prepend(str(tmp_path / 'src'))
    monkeypatch.setenv('AMENT_PREFIX_PATH', str(prefix))
    return prefix


def test_declared_plugins_are_listed_by_name(toy_prefix):
    declared = PluginLoader().declared()
    assert list(declared) == [
        'toy_plugins/BadModule', 'toy_plugins/Good', 'toy_plugins/Missing',
        'toy_plugins/NotAPlugin', 'toy_plugins_mod.Good',
    ]
    good = declared['toy_plugins/Good']
    assert good.type == 'toy_plugins_mod.Good'
    assert good.package == 'toy_plugins'
    assert good.library == 'toy_plugins'
    assert good.description == 'A good plugin.'
    assert good.xml_path == os.path.join(toy_prefix, 'share/toy_plugins/plugins.xml')


def test_a_class_without_name_is_found_by_its_type(toy_prefix):
    assert 'toy_plugins_mod.Good' in PluginLoader().available()


def test_classes_of_another_base_class_are_not_listed(toy_prefix):
    assert 'rviz/Display' not in PluginLoader().available()


def test_load_by_name_returns_the_class_and_create_an_instance(toy_prefix):
    loader = PluginLoader()
    cls = loader.load('toy_plugins/Good')
    assert issubclass(cls, PluginBase) and cls.__name__ == 'Good'
    assert isinstance(loader.create('toy_plugins/Good'), cls)


def test_when_name_is_unknown_expect_error_naming_plugin_and_listing_available(toy_prefix):
    with pytest.raises(
        PluginNotFoundError,
        match=r"^plugin 'chassis': unknown plugin type 'toy_plugins/Godo'; "
        r'available: toy_plugins/BadModule, toy_plugins/Good, ',
    ) as info:
        PluginLoader().load('toy_plugins/Godo', plugin='chassis')
    assert info.value.plugin == 'chassis'


def test_when_nothing_is_installed_expect_a_hint(tmp_path, monkeypatch):
    monkeypatch.setenv('AMENT_PREFIX_PATH', str(tmp_path))
    with pytest.raises(PluginNotFoundError, match=r'available: none \(is the package'):
        PluginLoader().load('toy_plugins/Good')


def test_when_ament_prefix_path_is_unset_expect_not_found(monkeypatch):
    monkeypatch.delenv('AMENT_PREFIX_PATH', raising=False)
    assert PluginLoader().available() == []


def test_when_class_is_not_a_plugin_expect_description_error(toy_prefix):
    with pytest.raises(PluginDescriptionError, match='NotAPlugin is not a subclass of PluginBase'):
        PluginLoader().load('toy_plugins/NotAPlugin', plugin='x')


def test_when_class_is_missing_expect_description_error_naming_the_xml(toy_prefix):
    with pytest.raises(PluginDescriptionError, match=r'plugins.xml .*Missing does not exist'):
        PluginLoader().load('toy_plugins/Missing', plugin='x')


def test_when_module_cannot_be_imported_expect_description_error(toy_prefix):
    with pytest.raises(
        PluginDescriptionError,
        match=r"^plugin 'x' \(toy_plugins/BadModule\): declared in .* as 'toy_plugins_nowhere"
        r".Thing': cannot import toy_plugins_nowhere: ModuleNotFoundError",
    ):
        PluginLoader().load('toy_plugins/BadModule', plugin='x')


def test_a_malformed_xml_is_skipped_with_a_warning(toy_prefix, tmp_path, monkeypatch):
    broken = make_prefix(tmp_path / 'broken', 'broken_plugins', '<library><class')
    monkeypatch.setenv('AMENT_PREFIX_PATH', f'{toy_prefix}{os.pathsep}{broken}')
    warnings = []
    available = PluginLoader(warn=warnings.append).available()
    assert 'toy_plugins/Good' in available
    assert len(warnings) == 1
    assert 'skipped plugin description' in warnings[0]
    assert 'broken_plugins' in warnings[0]


def test_the_same_name_in_two_packages_uses_the_overlay_and_warns(
    toy_prefix, tmp_path, monkeypatch
):
    overlay = make_prefix(tmp_path / 'overlay', 'twin_plugins', """
        <library path="twin">
          <class name="toy_plugins/Good" type="twin.Good" base_class_type="rm_base::PluginBase"/>
        </library>""")
    # The overlay comes first on AMENT_PREFIX_PATH, as `source overlay/setup.bash` puts it.
    monkeypatch.setenv('AMENT_PREFIX_PATH', f'{overlay}{os.pathsep}{toy_prefix}')
    warnings = []
    declared = PluginLoader(warn=warnings.append).declared()
    assert declared['toy_plugins/Good'].package == 'twin_plugins'
    assert "'toy_plugins/Good' is declared by twin_plugins" in warnings[0]
