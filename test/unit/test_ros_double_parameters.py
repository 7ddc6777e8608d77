"""A whole number set on a double parameter becomes that double; nothing else changes."""

import pytest
from rclpy.parameter import Parameter
from rm_base.ros.double_parameters import widened

T = Parameter.Type


@pytest.mark.parametrize(('value', 'held', 'expected'), [
    (30, T.DOUBLE, (T.DOUBLE, 30.0)),
    ([1, 2], T.DOUBLE_ARRAY, (T.DOUBLE_ARRAY, [1.0, 2.0])),
    (30, T.INTEGER, (T.INTEGER, 30)),  # an integer parameter keeps its integers
    (30, None, (T.INTEGER, 30)),  # undeclared: rclpy says so, unchanged
    (2.5, T.DOUBLE, (T.DOUBLE, 2.5)),
    ('30', T.DOUBLE, (T.STRING, '30')),  # refused as the wrong type, as before
    (True, T.DOUBLE, (T.BOOL, True)),  # a bool is no number here
    ([1, 2], T.INTEGER_ARRAY, (T.INTEGER_ARRAY, [1, 2])),
])
def test_only_an_integer_for_a_double_is_widened(value, held, expected):
    parameter = widened(Parameter('gain', value=value), held)
    assert parameter.name == 'gain'
    assert (parameter.type_, list(parameter.value) if isinstance(value, list)
            else parameter.value) == expected
