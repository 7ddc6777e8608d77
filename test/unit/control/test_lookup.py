import math

import pytest
from hypothesis import given
from hypothesis import strategies as st
from rm_base.control import LookupTable
from rm_base.errors import ConfigError, InputRejectedError

# Bullet speed [m/s] -> friction wheel speed [rad/s].
TABLE = LookupTable([(15.0, 450.0), (18.0, 540.0), (30.0, 780.0)])


@pytest.mark.parametrize(
    ('x', 'expected'),
    [
        (15.0, 450.0),  # first point
        (18.0, 540.0),  # inner point
        (30.0, 780.0),  # last point
        # 16.5 is half-way from 15 to 18: 450 + (540 - 450) * 0.5 = 495
        (16.5, 495.0),
        # 27 is 9/12 of the way from 18 to 30: 540 + 240 * 0.75 = 720
        (27.0, 720.0),
        (10.0, 450.0),  # below the table: held at the first value
        (35.0, 780.0),  # above the table: held at the last value
    ],
)
def test_when_looking_up_expect_linear_interpolation_clamped_at_ends(x, expected):
    assert TABLE(x) == pytest.approx(expected)


def test_when_y_decreasing_expect_interpolation_works():
    table = LookupTable([(0.0, 10.0), (10.0, 0.0)])
    # 10 - 10 * 0.25 = 7.5
    assert table(2.5) == pytest.approx(7.5)
    assert not table.increasing


def test_when_built_from_columns_expect_same_table():
    table = LookupTable.from_columns([15.0, 18.0, 30.0], [450.0, 540.0, 780.0])
    assert table.points == TABLE.points


def test_when_inverted_expect_wheel_speed_to_bullet_speed():
    # 660 is half-way from 540 to 780: x = 18 + 12 * 0.5 = 24
    assert TABLE.inverted()(660.0) == pytest.approx(24.0)


def test_when_decreasing_table_inverted_expect_points_reordered():
    inverse = LookupTable([(0.0, 10.0), (10.0, 0.0)]).inverted()
    assert inverse.points == ((0.0, 10.0), (10.0, 0.0))
    assert inverse(7.5) == pytest.approx(2.5)


def test_when_inverting_table_with_flat_part_expect_config_error():
    with pytest.raises(ConfigError, match='strictly monotonic'):
        LookupTable([(0.0, 1.0), (1.0, 1.0), (2.0, 2.0)]).inverted()


@pytest.mark.parametrize(
    ('points', 'message'),
    [
        ([(0.0, 1.0)], 'at least 2'),
        ([(0.0, 1.0), (0.0, 2.0)], 'strictly increasing'),
        ([(1.0, 1.0), (0.0, 2.0)], 'strictly increasing'),
        ([(0.0, 1.0), (1.0, 3.0), (2.0, 2.0)], 'monotonic'),
        ([(0.0, 1.0), (1.0, math.nan)], 'finite'),
        ([(0.0, 1.0), (math.inf, 2.0)], 'finite'),
        ([(0.0, 1.0), (1.0, '2')], 'numbers'),
        ([(0.0, 1.0), (1.0, True)], 'numbers'),
        ([(0.0, 1.0), (1.0,)], r'\(x, y\)'),
    ],
)
def test_when_points_invalid_expect_config_error(points, message):
    with pytest.raises(ConfigError, match=message):
        LookupTable(points)


def test_when_columns_differ_in_length_expect_config_error():
    with pytest.raises(ConfigError, match='differ in length'):
        LookupTable.from_columns([1.0, 2.0], [1.0])


@pytest.mark.parametrize('x', [math.nan, math.inf, -math.inf])
def test_when_input_not_finite_expect_rejected(x):
    with pytest.raises(InputRejectedError, match='finite'):
        TABLE(x)


increasing_tables = st.lists(
    st.tuples(st.floats(min_value=0.01, max_value=10.0), st.floats(min_value=0.0, max_value=100.0)),
    min_size=1,
    max_size=8,
).map(
    # Cumulative sums of positive steps: x strictly increasing, y non-decreasing.
    lambda steps: LookupTable(
        [(0.0, 0.0)]
        + [
            (sum(dx for dx, _ in steps[: i + 1]), sum(dy for _, dy in steps[: i + 1]))
            for i in range(len(steps))
        ]
    )
)
queries = st.floats(min_value=-10.0, max_value=100.0)


@given(increasing_tables, queries, queries)
def test_invariant_lookup_is_monotone(table, a, b):
    low, high = min(a, b), max(a, b)
    assert table(low) <= table(high)


@given(increasing_tables, queries)
def test_invariant_lookup_stays_within_table_values(table, x):
    ys = [y for _, y in table.points]
    assert min(ys) <= table(x) <= max(ys)


@given(increasing_tables)
def test_invariant_lookup_passes_through_its_points(table):
    for x, y in table.points:
        assert table(x) == pytest.approx(y)
