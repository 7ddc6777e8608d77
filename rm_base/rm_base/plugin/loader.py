"""Find and load plugins by name, the way pluginlib does, from the ament resource index.

A package provides plugins by installing

- a plugin description XML in pluginlib's format, e.g. ``share/<pkg>/plugins.xml``::

      <library path="rm_plugins">
        <class name="rm_plugins/StandChassis" type="rm_plugins.chassis.StandChassis"
               base_class_type="rm_base::PluginBase">
          <description>Mecanum/omni chassis with follow, twist and gyro modes.</description>
        </class>
      </library>

  (``type`` is the Python path ``module.Class``; several ``<library>`` elements may sit in
  a ``<class_libraries>`` root), and
- the marker ``share/ament_index/resource_index/rm_base__pluginlib__plugin/<pkg>`` whose
  content is that XML's path relative to the install prefix (one per line), exactly what
  ``pluginlib_export_plugin_description_file(rm_base plugins.xml)`` writes for C++.

The package.xml carries ``<export><rm_base plugin="${prefix}/plugins.xml"/></export>`` as
pluginlib packages do. rm_base never names a plugin package: everything on
AMENT_PREFIX_PATH is searched when a plugin is asked for.
"""

from __future__ import annotations

import importlib
import os
import xml.etree.ElementTree as ET
from collections.abc import Callable
from dataclasses import dataclass

from ament_index_python.resources import get_resource, get_resources
from ament_index_python.search_paths import get_search_paths

from rm_base.plugin.base import PluginBase
from rm_base.plugin.errors import PluginDescriptionError, PluginNotFoundError

BASE_PACKAGE = 'rm_base'
BASE_CLASS_TYPE = 'rm_base::PluginBase'


@dataclass(frozen=True)
class PluginDescription:
    """One ``<class>`` entry of a plugin description XML.

    Attributes:
        name: lookup name, e.g. ``rm_plugins/StandChassis`` (the ``type`` if no name).
        type: Python path of the class, ``module.Class`` (or ``module:Class``).
        package: package that exports the XML.
        library: the ``<library path>`` (informational for Python plugins).
        description: text of ``<description>``.
        xml_path: absolute path of the XML file.
    """

    name: str
    type: str
    package: str
    library: str
    description: str
    xml_path: str


class PluginLoader:
    """Lists and loads the plugins declared for a base class on AMENT_PREFIX_PATH.

    Args:
        base_package: the package whose plugins to find (resource type
            ``<base_package>__pluginlib__plugin``).
        base_class_type: classes declared with another ``base_class_type`` are ignored.
        warn: receives one line per unusable XML file or entry (skipped, as pluginlib does).
    """

    def __init__(
        self,
        base_package: str = BASE_PACKAGE,
        base_class_type: str = BASE_CLASS_TYPE,
        *,
        warn: Callable[[str], object] | None = None,
    ) -> None:
        self.resource_type = f'{base_package}__pluginlib__plugin'
        self.base_class_type = base_class_type
        self._warn = warn

    def declared(self) -> dict[str, PluginDescription]:
        """Return every declared plugin by lookup name (first on AMENT_PREFIX_PATH wins)."""
        found: dict[str, PluginDescription] = {}
        for xml_path, package in self._description_files():
            for description in self._parse(xml_path, package):
                if description.name in found:
                    first = found[description.name]
                    self._warning(
                        f"plugin '{description.name}' is declared by {first.package} "
                        f'({first.xml_path}) and {package} ({xml_path}); using the first'
                    )
                    continue
                found[description.name] = description
        return dict(sorted(found.items()))

    def available(self) -> list[str]:
        """Return the sorted lookup names of all declared plugins."""
        return list(self.declared())

    def describe(self, type_name: str, *, plugin: str = '') -> PluginDescription:
        """Return the description of type_name.

        Args:
            type_name: lookup name, e.g. ``rm_plugins/StandChassis``.
            plugin: instance name, for the error message.

        Raises:
            PluginNotFoundError: no package declares type_name; lists the names that exist.
        """
        declared = self.declared()
        if type_name in declared:
            return declared[type_name]
        where = f"plugin '{plugin}': " if plugin else ''
        available = ', '.join(declared) if declared else (
            'none (is the package that provides it built, and its install/setup.bash sourced?)'
        )
        raise PluginNotFoundError(
            f"{where}unknown plugin type '{type_name}'; available: {available}", plugin=plugin
        )

    def load(self, type_name: str, *, plugin: str = '') -> type[PluginBase]:
        """Import and return the class declared as type_name.

        Raises:
            PluginNotFoundError: type_name is not declared.
            PluginDescriptionError: the class cannot be imported or is not a PluginBase.
        """
        description = self.describe(type_name, plugin=plugin)
        module_name, _, class_name = description.type.replace(':', '.').rpartition('.')
        where = f"plugin '{plugin}' ({type_name})" if plugin else f"plugin type '{type_name}'"
        origin = f'declared in {description.xml_path} as {description.type!r}'
        if not module_name or not class_name:
            raise PluginDescriptionError(
                f'{where}: {origin}, which is not a module.Class path', plugin=plugin
            )
        try:
            module = importlib.import_module(module_name)
        except Exception as err:  # any error while importing the plugin's module
            raise PluginDescriptionError(
                f'{where}: {origin}: cannot import {module_name}: {type(err).__name__}: {err}',
                plugin=plugin,
            ) from err
        cls = getattr(module, class_name, None)
        if not (isinstance(cls, type) and issubclass(cls, PluginBase)):
            problem = 'does not exist' if cls is None else 'is not a subclass of PluginBase'
            raise PluginDescriptionError(
                f'{where}: {origin}: {module_name}.{class_name} {problem}', plugin=plugin
            )
        return cls

    def create(self, type_name: str, *, plugin: str = '') -> PluginBase:
        """Return a new, uninitialised instance of the plugin class type_name."""
        return self.load(type_name, plugin=plugin)()

    # -- internals ------------------------------------------------------------------------

    def _description_files(self) -> list[tuple[str, str]]:
        try:
            packages = get_resources(self.resource_type)
            order = {prefix: index for index, prefix in enumerate(get_search_paths())}
        except OSError:  # AMENT_PREFIX_PATH unset or empty: nothing installed
            return []
        files = []
        # Overlays come first on AMENT_PREFIX_PATH, and win, as everywhere in ROS.
        for package in sorted(packages, key=lambda p: (order.get(packages[p], 0), p)):
            content, prefix = get_resource(self.resource_type, package)
            for line in content.splitlines():
                if line.strip():
                    files.append((os.path.join(prefix, line.strip()), package))
        return files

    def _parse(self, xml_path: str, package: str) -> list[PluginDescription]:
        try:
            root = ET.parse(xml_path).getroot()
        except (OSError, ET.ParseError) as err:
            self._warning(f'skipped plugin description {xml_path} of {package}: {err}')
            return []
        if root.tag == 'library':
            libraries = [root]
        elif root.tag == 'class_libraries':
            libraries = root.findall('library')
        else:
            self._warning(
                f'skipped plugin description {xml_path} of {package}: root element is '
                f'<{root.tag}>, expected <library> or <class_libraries>'
            )
            return []
        descriptions = []
        for library in libraries:
            for entry in library.findall('class'):
                class_type = entry.get('type', '').strip()
                if entry.get('base_class_type', '').strip() != self.base_class_type:
                    continue  # a plugin for another base class, as pluginlib skips it
                if not class_type:
                    self._warning(f'skipped a <class> without type in {xml_path}')
                    continue
                descriptions.append(
                    PluginDescription(
                        name=(entry.get('name') or class_type).strip(),
                        type=class_type,
                        package=package,
                        library=library.get('path', ''),
                        description=' '.join((entry.findtext('description') or '').split()),
                        xml_path=xml_path,
                    )
                )
        return descriptions

    def _warning(self, message: str) -> None:
        if self._warn is not None:
            self._warn(message)
