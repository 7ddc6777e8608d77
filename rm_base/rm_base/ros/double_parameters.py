"""A whole number given for a double parameter is set as the double it is.

``ros2 param set /can_bridge joints.yaw.position_pid.kp 30`` sends an integer, and so does a
Foxglove client for ``30`` (JSON has one kind of number). rclpy refuses an integer for a
parameter of type double before the node's own checks see it, while a config file's
``kp: 30`` is taken at start-up. A node's pre-set callback (:func:`integers_as_doubles`)
makes a live set take what start-up takes.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

from rclpy.node import Node
from rclpy.parameter import Parameter

# what an integer (array) becomes when the parameter holds a double (array)
_WIDER: dict[Parameter.Type, tuple[Parameter.Type, Callable[[Any], Any]]] = {
    Parameter.Type.INTEGER: (Parameter.Type.DOUBLE, float),
    Parameter.Type.INTEGER_ARRAY: (Parameter.Type.DOUBLE_ARRAY, lambda v: [float(x) for x in v]),
}


def integers_as_doubles(node: Node) -> Callable[[Sequence[Parameter]], list[Parameter]]:
    """The callback for ``node.add_pre_set_parameters_callback``."""

    def convert(parameters: Sequence[Parameter]) -> list[Parameter]:
        return [widened(parameter, _held_type(node, parameter.name)) for parameter in parameters]

    return convert


def widened(parameter: Parameter, held: Parameter.Type | None) -> Parameter:
    """The parameter as a double (array) if it is an integer (array) and held is one."""
    wider = _WIDER.get(parameter.type_)
    if wider is None or held is not wider[0]:
        return parameter
    kind, convert = wider
    return Parameter(parameter.name, kind, convert(parameter.value))


def _held_type(node: Node, name: str) -> Parameter.Type | None:
    """The type of the value the node holds for name (None for an undeclared name)."""
    return node.get_parameter(name).type_ if node.has_parameter(name) else None
