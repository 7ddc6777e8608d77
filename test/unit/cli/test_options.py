"""The CLI's number options: a clear refusal for what no clock or rate can hold."""

import argparse

import pytest
from rm_bringup.cli.options import finite_float, nonnegative_float, positive_float


@pytest.mark.parametrize(('kind', 'text', 'value'), [
    (positive_float, '20', 20.0),
    (positive_float, '0.5', 0.5),
    (positive_float, '1e-9', 1e-9),
    (positive_float, '1e9', 1e9),
    (nonnegative_float, '0', 0.0),
    (nonnegative_float, '1e9', 1e9),
    (finite_float, '-0.5', -0.5),
    (finite_float, '0', 0.0),
])
def test_a_usable_number_is_taken(kind, text, value):
    assert kind(text) == value


@pytest.mark.parametrize(('kind', 'text', 'said'), [
    (positive_float, 'fast', "'fast' is not a number"),
    (positive_float, '0', '0 is not positive'),
    (positive_float, '-1', '-1 is not positive'),
    (positive_float, 'nan', 'nan is not a finite number'),
    (positive_float, 'inf', 'inf is not a finite number'),
    (positive_float, '1e300', '1e300 is beyond 1e+09'),
    (positive_float, '1e-300', '1e-300 is below 1e-09'),  # a rate whose period overflowed
    (nonnegative_float, '-0.1', '-0.1 is negative'),
    (nonnegative_float, 'inf', 'inf is not a finite number'),
    (nonnegative_float, '-inf', '-inf is not a finite number'),
    (finite_float, 'nan', 'nan is not a finite number'),  # a step's target, a gain
    (finite_float, '-inf', '-inf is not a finite number'),
])
def test_what_no_clock_holds_is_refused_naming_it(kind, text, said):
    with pytest.raises(argparse.ArgumentTypeError) as refused:
        kind(text)
    assert str(refused.value) == said
