"""A parameter declared once is a ROS declaration, a validation, a typed field and a docs row.

A fictional plugin declares its parameter set as a dataclass (rm_base.config.schema); adding
one field to it must show up in all four places with nothing else written.
"""

import dataclasses

import pytest
import rclpy
from rclpy.parameter import Parameter
from rm_base.config import schema
from rm_base.config.schema import declare, group, number, numbers, one_of
from rm_base.plugin import PluginBase, PluginParams
from rm_base.plugin.errors import PluginConfigError
from rm_base.plugin.params import declared_parameters
from rm_bringup.param_reference import markdown_table


@dataclasses.dataclass(frozen=True, kw_only=True)
class Lamp:
    """A group of its own: ``<plugin>.lamp.*``."""

    colour: int = declare(one_of, 1, choices=(1, 2, 3), description='lamp colour code')


@dataclasses.dataclass(frozen=True, kw_only=True)
class FictionalParams:
    gain: float = declare(number, description='how hard it pushes', unit='N*m/rad', gt=0.0)
    # the parameter this test adds: nothing but this line declares it
    reach: float = declare(
        number, 0.25, tunable=True, description='how far it reaches', unit='m', le=1.0
    )
    steps: tuple[float, ...] = declare(numbers, (0.1, 0.2), description='steps', unit='m')
    lamp: Lamp = group(Lamp)


class Fictional(PluginBase):
    def on_init(self):
        self.config = self.params.read(FictionalParams)

    def update(self, now):
        return None


def _init(ros_context, **values):
    overrides = [Parameter(f'fictional.{k}', value=v) for k, v in values.items()]
    node = rclpy.create_node('fictional', context=ros_context, parameter_overrides=overrides)
    plugin = Fictional()
    try:
        plugin.init(node, 'fictional', PluginParams(node, 'fictional', 'test/Fictional'))
    except Exception:
        node.destroy_node()
        raise
    return node, plugin


def test_the_new_parameter_is_declared_on_the_node_with_its_unit_and_bounds(ros_context):
    node, _ = _init(ros_context, gain=2.0)
    try:
        descriptor = node.describe_parameter('fictional.reach')
        assert descriptor.description == 'how far it reaches [m]'
        assert 'unit: m' in descriptor.additional_constraints
        assert '<= 1.0' in descriptor.additional_constraints
        assert node.get_parameter('fictional.reach').value == 0.25
        assert node.get_parameter('fictional.lamp.colour').value == 1
    finally:
        node.destroy_node()


def test_a_value_out_of_its_bounds_is_refused_naming_the_plugin_key_and_bound(ros_context):
    with pytest.raises(PluginConfigError) as caught:
        _init(ros_context, gain=2.0, reach=1.5)
    assert "parameter 'fictional.reach' must be <= 1.0, got 1.5" in str(caught.value)
    colour = r"'fictional\.lamp\.colour' must be one of 1, 2, 3"
    with pytest.raises(PluginConfigError, match=colour):
        _init_group(ros_context)
    with pytest.raises(PluginConfigError, match=r"'fictional\.gain' is required"):
        _init(ros_context)


def _init_group(ros_context):
    node = rclpy.create_node(
        'fictional', context=ros_context,
        parameter_overrides=[
            Parameter('fictional.gain', value=2.0), Parameter('fictional.lamp.colour', value=7)
        ],
    )
    try:
        Fictional().init(node, 'fictional', PluginParams(node, 'fictional', 'test/Fictional'))
    finally:
        node.destroy_node()


def test_the_new_parameter_is_a_typed_field_of_the_plugins_config(ros_context):
    node, plugin = _init(ros_context, gain=2, reach=0.5, steps=[0.3, 0.4])
    try:
        config = plugin.config
        assert isinstance(config, FictionalParams)
        assert config.reach == 0.5 and isinstance(config.gain, float) and config.gain == 2.0
        assert config.steps == (0.3, 0.4) and config.lamp == Lamp(colour=1)
    finally:
        node.destroy_node()


def test_the_new_parameter_has_its_docs_row_from_the_class_and_from_the_node(ros_context):
    rows = schema.rows(FictionalParams, 'fictional.')
    assert [r.key for r in rows] == [
        'fictional.gain', 'fictional.reach', 'fictional.steps', 'fictional.lamp.colour',
    ]
    markdown = markdown_table(rows)
    assert '| `fictional.reach` | double | m | `0.25` | <= 1.0 | yes | how far it reaches |' in (
        markdown)
    node, _ = _init(ros_context, gain=2.0)
    try:
        # what the running node declared is what the class says, row for row
        declared = [p for p in declared_parameters(node) if p.key in {r.key for r in rows}]
        assert markdown_table(declared) == markdown
    finally:
        node.destroy_node()
