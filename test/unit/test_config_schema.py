"""rm_base.config.schema: one declaration validates a table and gives its reference rows."""

import dataclasses
import enum
import math
import re

import pytest
from rm_base.config.schema import (
    OPTIONAL,
    REQUIRED,
    InvalidValueError,
    Schema,
    boolean,
    booleans,
    build,
    choice,
    declare,
    group,
    integer,
    integers,
    mapping,
    number,
    numbers,
    one_of,
    rows,
    signs,
    string,
    strings,
    tables,
)
from rm_base.errors import ConfigError


class Shape(enum.Enum):
    ROUND = 1
    SQUARE = 2

SCHEMA = Schema((
    number('radius', REQUIRED, unit='m', gt=0.0, description='wheel radius'),
    integer('count', 4, ge=1, le=8, description='wheels'),
    boolean('enabled', False, description='on'),
    string('kind', 'mecanum', choices=('mecanum', 'omni'), lower=True, description='layout'),
    one_of('direction', (1, -1), 1, description='sign'),
    numbers('offset', (0.0, 0.0), unit='m', length=2, description='mount'),
    mapping('options', None, description='extra', parse=lambda table: tuple(sorted(table))),
    number('limit', None, unit='N', gt=0.0, description='optional clamp'),
    string('label', None, nonempty=True, description='a name, if any'),
))


class SchemaError(ConfigError):
    """The caller's own error type."""


def test_a_table_reads_typed_with_its_defaults():
    assert SCHEMA.read('wheel', {'radius': 1}) == {
        'radius': 1.0, 'count': 4, 'enabled': False, 'kind': 'mecanum', 'direction': 1,
        'offset': (0.0, 0.0), 'options': None, 'limit': None, 'label': None,
    }
    values = SCHEMA.read('wheel', {
        'radius': 0.076, 'count': 2, 'enabled': True, 'kind': 'OMNI', 'direction': -1,
        'offset': [1, 2.5], 'options': {'b': 1, 'a': 2}, 'limit': 3,
    })
    assert values['kind'] == 'omni' and values['offset'] == (1.0, 2.5)
    assert values['options'] == ('a', 'b') and values['limit'] == 3.0
    assert isinstance(values['radius'], float) and isinstance(values['count'], int)


@pytest.mark.parametrize(
    ('table', 'message'),
    [
        ({}, r'wheel\.radius is required \(double, m: wheel radius\)'),
        ({'radius': None}, r'wheel\.radius is required'),
        ({'radius': 'big'}, r"wheel\.radius must be double \[m\]; got str 'big'"),
        ({'radius': True}, r'wheel\.radius must be double \[m\]; got bool True'),
        ({'radius': math.nan}, r'wheel\.radius must be finite, got nan'),
        ({'radius': 0}, r'wheel\.radius must be > 0\.0, got 0\.0'),
        ({'radius': 1, 'count': 9}, r'wheel\.count must be <= 8, got 9'),
        ({'radius': 1, 'count': 2.0}, r'wheel\.count must be integer; got float 2\.0'),
        ({'radius': 1, 'enabled': 1}, r'wheel\.enabled must be bool; got int 1'),
        ({'radius': 1, 'kind': 'tank'}, r"wheel\.kind must be one of mecanum, omni, got 'tank'"),
        ({'radius': 1, 'kind': ''}, r"wheel\.kind must be one of mecanum, omni, got ''"),
        ({'radius': 1, 'label': ''}, r'wheel\.label must not be empty'),
        ({'radius': 1, 'direction': 2}, r'wheel\.direction must be one of 1, -1, got 2'),
        ({'radius': 1, 'direction': True}, r'wheel\.direction must be one of 1, -1, got True'),
        ({'radius': 1, 'offset': [1]}, r'wheel\.offset must have 2 entries, has 1'),
        ({'radius': 1, 'offset': [1, 'x']}, r'wheel\.offset must be double\[\] \[m\]; entry \[1\]'),
        ({'radius': 1, 'offset': 'ab'}, r'wheel\.offset must be double\[\]'),
        ({'radius': 1, 'options': [1]}, r'wheel\.options must be mapping; got list'),
        ({'radius': 1, 'limit': -1}, r'wheel\.limit must be > 0\.0, got -1\.0'),
        ({'radius': 1, 'wheels': 4}, r"wheel: unknown key\(s\) \['wheels'\]; allowed: "),
    ],
)
def test_a_bad_value_is_refused_naming_its_key(table, message):
    with pytest.raises(SchemaError, match=message):
        SCHEMA.read('wheel', table, SchemaError)


def test_not_a_mapping_is_refused():
    with pytest.raises(ConfigError, match=r'wheel must be a mapping, got list \[1\]'):
        SCHEMA.read('wheel', [1])


def test_an_open_table_hands_its_other_keys_back():
    open_schema = Schema(SCHEMA.keys, open=True)
    table = {'radius': 1, 'model': 'DM4310', 'limits': {'p_max': 12.5}}
    assert open_schema.read('joint', table)['radius'] == 1.0
    assert open_schema.extras(table) == {'model': 'DM4310', 'limits': {'p_max': 12.5}}


def test_the_reference_rows_come_from_the_same_declaration():
    rows = {row.key: row for row in SCHEMA.declared('chassis.<wheel>.')}
    assert list(rows) == [f'chassis.<wheel>.{k.name}' for k in SCHEMA.keys]
    radius = rows['chassis.<wheel>.radius']
    assert (radius.type_name, radius.unit, radius.default, radius.constraint) == (
        'double', 'm', None, '> 0.0')  # None: required
    assert rows['chassis.<wheel>.count'].constraint == '>= 1, <= 8'
    assert rows['chassis.<wheel>.kind'].constraint == 'one of: mecanum, omni'
    assert rows['chassis.<wheel>.offset'].constraint == 'length 2'
    assert rows['chassis.<wheel>.limit'].default is OPTIONAL  # optional, no default
    assert rows['chassis.<wheel>.direction'].type_name == 'integer'


LISTS = Schema((
    strings('motors', description='names'),
    signs('directions', None, description='per motor'),
    tables('wheels', (), description='one table each'),
))


def test_lists_of_names_signs_and_tables_read_as_tuples():
    values = LISTS.read('chassis', {
        'motors': ['fl', 'fr'], 'directions': [1, -1], 'wheels': [{'x': 1}, {'y': 2}],
    })
    assert values == {
        'motors': ('fl', 'fr'), 'directions': (1, -1), 'wheels': ({'x': 1}, {'y': 2}),
    }
    assert LISTS.read('chassis', {'motors': []})['directions'] is None


@pytest.mark.parametrize(
    ('table', 'message'),
    [
        ({'motors': 'fl'}, r"chassis\.motors must be string\[\]; got str 'fl'"),
        ({'motors': ['fl', '']}, r'chassis\.motors entry \[1\] must not be empty'),
        ({'motors': ['fl', 3]}, r'chassis\.motors must be string\[\]; entry \[1\] is int 3'),
        ({'motors': [], 'directions': [1, 0]},
         r'chassis\.directions entry \[1\] must be 1 or -1, got 0'),
        ({'motors': [], 'directions': [True]},
         r'chassis\.directions entry \[0\] must be 1 or -1, got True'),
        ({'motors': [], 'wheels': [{}, 'x']},
         r"chassis\.wheels must be mapping\[\]; entry \[1\] is str 'x'"),
    ],
)
def test_a_bad_list_names_its_entry(table, message):
    with pytest.raises(ConfigError, match=message):
        LISTS.read('chassis', table)


@pytest.mark.parametrize(
    ('key', 'value', 'expected'),
    [
        (integers('ids', description='d', ge=1), [1, 2], (1, 2)),
        (integers('ids', description='d', ge=1), [1, 0], 'entry [1] must be >= 1, got 0'),
        (numbers('gains', description='d', gt=0.0), [0.5, -1.0], 'entry [1] must be > 0.0'),
        (booleans('flags', description='d', length=2), [True, False], (True, False)),
        (booleans('flags', description='d', length=2), [True], 'must have 2 entries, has 1'),
        (strings('joints', description='d', unique=True), ['a', 'b'], ('a', 'b')),
        (strings('joints', description='d', unique=True), ['a', 'a'], 'duplicate entries: a'),
        (choice('shape', Shape, description='d'), 'ROUND', Shape.ROUND),
        (choice('shape', Shape, description='d'), 'oval', 'one of round, square'),
    ],
)
def test_the_array_and_choice_keys_convert_or_name_the_problem(key, value, expected):
    if isinstance(expected, str):
        with pytest.raises(InvalidValueError, match=re.escape(expected)):
            key.read({key.name: value})
    else:
        assert key.read({key.name: value}) == expected


@dataclasses.dataclass(frozen=True, kw_only=True)
class Motor:
    limit: float = declare(number, 2.0, description='effort limit', unit='N*m', gt=0.0)


@dataclasses.dataclass(frozen=True, kw_only=True)
class Arm:
    joints: tuple[str, ...] = declare(strings, description='joints', unique=True)
    motor: Motor = group(Motor)


def test_a_declared_set_builds_with_each_key_under_its_group_prefix():
    asked = []

    def value_of(prefix, key):
        asked.append(prefix + key.name)
        return key.read({'joints': ['j1']} if not prefix else {})

    assert build(Arm, value_of) == Arm(joints=('j1',), motor=Motor(limit=2.0))
    assert asked == ['joints', 'motor.limit']
    assert [(r.key, r.default, r.unit) for r in rows(Arm, 'arm.')] == [
        ('arm.joints', None, ''), ('arm.motor.limit', 2.0, 'N*m'),
    ]
    with pytest.raises(TypeError, match='not a declared parameter set'):
        build(int, value_of)
