"""Config keys declared once: type, unit, bounds, default and description.

Why one module: the value converters, the key builders and the table reader are one
vocabulary; ROS parameters and config tables both speak it.

One declaration gives three things: the validation of a config value (an error naming the
key, its type and unit), the typed value, and the key's row in the generated parameter
reference (docs/PARAMETERS.md). Plugins declare theirs as ROS parameters
(:class:`rm_base.plugin.params.PluginParams`, which converts with the functions here);
tables of the robot config that are not flat ROS parameters (``buses.<bus>``,
``joints.<joint>``, the simulated world's ``sim.*`` groups) declare a :class:`Schema` of
:class:`Key` s and read their dicts through it. Pure: no ROS here.

Example:
    >>> SCHEMA = Schema((number('radius', REQUIRED, unit='m', gt=0.0, description='r'),))
    >>> SCHEMA.read('wheel', {'radius': 0.076}, ConfigError)
    {'radius': 0.076}
"""

from __future__ import annotations

import dataclasses
import difflib
import math
from collections.abc import Callable, Collection, Mapping, Sequence
from enum import Enum
from typing import Any, NamedTuple, TypeVar

from rm_base.errors import ConfigError

E = TypeVar('E', bound=Enum)
T = TypeVar('T')


class DeclaredParameter(NamedTuple):
    """One declared key, as the generated reference lists it.

    Attributes:
        key: full name (``chassis.wheel_radius``, ``buses.<bus>.bitrate``).
        type_name: ``double``, ``integer[]``...
        unit: SI unit, '' if none.
        default: the default, None if required.
        constraint: bounds, choices, length; '' if none.
        description: what it is.
        tunable: may be set while running.
    """

    key: str
    type_name: str
    unit: str
    default: Any
    constraint: str
    description: str
    tunable: bool = False


class _Required:
    """Marker for "no default: the config must set this key"."""

    def __repr__(self) -> str:
        return 'REQUIRED'


REQUIRED: Any = _Required()
"""Default of a key that has none: a missing value is a start-up error."""


class _Optional:
    """Marker for an optional key's default in the reference: none, or the type's own."""

    def __repr__(self) -> str:
        return 'OPTIONAL'


OPTIONAL: Any = _Optional()
"""An optional key's default as ``DeclaredParameter.default`` shows it (None is "required")."""


class InvalidValueError(Exception):
    """A value failed a check; the text completes "<key> ..." (``must be > 0, got -1``)."""


class WrongTypeError(InvalidValueError):
    """A value is of the wrong type; the text (optional) says which part."""


def describe_value(value: object) -> str:
    """``float 1.5``, ``str 'x'``, ``nothing``: a value for an error message."""
    if value is None:
        return 'nothing'
    return f'{type(value).__name__} {value!r}'


def as_sequence(value: object) -> list[Any] | None:
    """The value as a list, or None if it is no array (a str is not one here)."""
    # rclpy hands arrays over as list or array.array
    if isinstance(value, str | bytes) or value is None or isinstance(value, Mapping):
        return None
    try:
        return list(value)  # type: ignore[call-overload,no-any-return]
    except TypeError:
        return None


def to_float(value: object) -> float:
    """A finite number (an int is accepted, a bool is not) as a float."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise WrongTypeError()
    number = float(value)
    if not math.isfinite(number):
        raise InvalidValueError(f'must be finite, got {number}')
    return number


def to_int(value: object) -> int:
    """An int (a bool is not one)."""
    if not isinstance(value, int) or isinstance(value, bool):
        raise WrongTypeError()
    return int(value)


def to_bool(value: object) -> bool:
    """``true``/``false``; nothing else."""
    if not isinstance(value, bool):
        raise WrongTypeError()
    return value


def to_str(value: object) -> str:
    """A string."""
    if not isinstance(value, str):
        raise WrongTypeError()
    return value


def to_mapping(value: object) -> dict[str, Any]:
    """A mapping, as a plain dict."""
    if not isinstance(value, Mapping):
        raise WrongTypeError()
    return dict(value)


def array_of(
    convert_item: Callable[[object], Any], length: int | None = None
) -> Callable[[object], tuple[Any, ...]]:
    """A converter of arrays: each entry by convert_item; length entries if given."""

    def convert(value: object) -> tuple[Any, ...]:
        items = as_sequence(value)
        if items is None:
            raise WrongTypeError()
        if length is not None and len(items) != length:
            raise InvalidValueError(f'must have {length} entries, has {len(items)}')
        out = []
        for index, item in enumerate(items):
            try:
                out.append(convert_item(item))
            except WrongTypeError:
                raise WrongTypeError(f'entry [{index}] is {describe_value(item)}') from None
            except InvalidValueError as err:
                raise InvalidValueError(f'entry [{index}] {err}') from None
        return tuple(out)

    return convert


class Bounds:
    """Optional gt/ge/lt/le bounds of a number."""

    def __init__(
        self,
        gt: float | None = None,
        ge: float | None = None,
        lt: float | None = None,
        le: float | None = None,
    ) -> None:
        self._checks: list[tuple[float, str, Callable[[float, float], bool]]] = [
            (bound, op, test)
            for bound, op, test in (
                (gt, '>', lambda v, b: v > b),
                (ge, '>=', lambda v, b: v >= b),
                (lt, '<', lambda v, b: v < b),
                (le, '<=', lambda v, b: v <= b),
            )
            if bound is not None
        ]

    def text(self) -> str:
        """``> 0.0, <= 1000.0``; '' without bounds."""
        return ', '.join(f'{op} {bound}' for bound, op, _ in self._checks)

    def check(self, value: Any) -> Any:
        """value, if it keeps every bound.

        Raises:
            InvalidValueError: naming the bound it breaks.
        """
        for bound, op, test in self._checks:
            if not test(value, bound):
                raise InvalidValueError(f'must be {op} {bound}, got {value}')
        return value


@dataclasses.dataclass(frozen=True)
class Key:
    """One key of a config table.

    Attributes:
        name: the key (``bitrate``).
        type_name: as the reference shows it (``double``, ``integer``, ``string``, ``bool``,
            ``mapping``, ``double[]``...).
        convert: checks a present value and returns it typed; raises InvalidValueError.
        description: what it is.
        unit: SI unit, '' if none.
        default: value when absent; REQUIRED: must be given; None: optional (absent, or
            given as null, is None: "the type's default", "none").
        constraint: bounds or choices as the reference shows them.
        tunable: may change while the robot runs (a gain, a limit); else it is read at
            start-up and a change needs a restart (a joint name, a topic).
    """

    name: str
    type_name: str
    convert: Callable[[object], Any]
    description: str
    unit: str = ''
    default: Any = REQUIRED
    constraint: str = ''
    tunable: bool = False

    def read(self, data: Mapping[str, Any]) -> Any:
        """This key's typed value in data (or the default).

        Raises:
            InvalidValueError: missing while required, wrong type, or out of bounds; the
                text completes "<key> ...".
        """
        value = data.get(self.name)
        if value is None:
            if self.default is REQUIRED:
                unit = f', {self.unit}' if self.unit else ''
                raise InvalidValueError(
                    f'is required ({self.type_name}{unit}: {self.description})'
                )
            return self.default
        try:
            return self.convert(value)
        except WrongTypeError as err:
            unit = f' [{self.unit}]' if self.unit else ''
            got = str(err) or f'got {describe_value(value)}'
            raise InvalidValueError(f'must be {self.type_name}{unit}; {got}') from None

    def declared(self, prefix: str) -> DeclaredParameter:
        """This key's row of the reference, under prefix (``buses.<bus>.``)."""
        if self.default is REQUIRED:
            default = None
        else:
            default = OPTIONAL if self.default is None else self.default
        return DeclaredParameter(
            prefix + self.name, self.type_name, self.unit, default, self.constraint,
            self.description, self.tunable,
        )


def number(
    name: str,
    default: Any = REQUIRED,
    *,
    description: str,
    unit: str = '',
    gt: float | None = None,
    ge: float | None = None,
    lt: float | None = None,
    le: float | None = None,
) -> Key:
    """A finite floating-point key (an integer is accepted)."""
    bounds = Bounds(gt, ge, lt, le)
    return Key(name, 'double', lambda v: bounds.check(to_float(v)), description, unit,
               default, bounds.text())


def integer(
    name: str,
    default: Any = REQUIRED,
    *,
    description: str,
    unit: str = '',
    gt: int | None = None,
    ge: int | None = None,
    lt: int | None = None,
    le: int | None = None,
) -> Key:
    """An integer key."""
    bounds = Bounds(gt, ge, lt, le)
    return Key(name, 'integer', lambda v: bounds.check(to_int(v)), description, unit,
               default, bounds.text())


def boolean(name: str, default: Any = REQUIRED, *, description: str) -> Key:
    """A ``true``/``false`` key."""
    return Key(name, 'bool', to_bool, description, '', default)


def string(
    name: str,
    default: Any = REQUIRED,
    *,
    description: str,
    choices: Sequence[str] | None = None,
    lower: bool = False,
    nonempty: bool = False,
) -> Key:
    """A string key, optionally one of choices (compared in lower case if lower)."""

    def convert(value: object) -> str:
        text = to_str(value)
        if lower:
            text = text.lower()
        if nonempty and not text:
            raise InvalidValueError('must not be empty')
        if choices is not None and text not in choices:
            raise InvalidValueError(f'must be one of {", ".join(choices)}, got {text!r}')
        return text

    constraint = f'one of: {", ".join(choices)}' if choices else ''
    return Key(name, 'string', convert, description, '', default, constraint)


def one_of(name: str, choices: Sequence[Any], default: Any = REQUIRED, *, description: str) -> Key:
    """A key whose value must be one of choices (numbers or strings, compared exactly)."""

    def convert(value: object) -> Any:
        if isinstance(value, bool) or value not in choices:
            shown = ', '.join(str(c) for c in choices)
            raise InvalidValueError(f'must be one of {shown}, got {value!r}')
        return value

    type_name = 'integer' if all(isinstance(c, int) for c in choices) else 'string'
    constraint = f'one of: {", ".join(str(c) for c in choices)}'
    return Key(name, type_name, convert, description, '', default, constraint)


def mapping(
    name: str,
    default: Any = None,
    *,
    description: str,
    parse: Callable[[dict[str, Any]], Any] | None = None,
) -> Key:
    """A mapping key (``options``, a PID); parse(dict) may type it further."""

    def convert(value: object) -> Any:
        table = to_mapping(value)
        return table if parse is None else parse(table)

    return Key(name, 'mapping', convert, description, '', default)


def _array_constraint(bounds: Bounds, length: int | None, unique: bool = False) -> str:
    parts = [bounds.text(), f'length {length}' if length else '', 'unique' if unique else '']
    return '; '.join(p for p in parts if p)


def numbers(
    name: str,
    default: Any = REQUIRED,
    *,
    description: str,
    unit: str = '',
    length: int | None = None,
    gt: float | None = None,
    ge: float | None = None,
    lt: float | None = None,
    le: float | None = None,
) -> Key:
    """A list of finite numbers, of length entries if given, each within the bounds."""
    bounds = Bounds(gt, ge, lt, le)
    return Key(name, 'double[]', array_of(lambda v: bounds.check(to_float(v)), length),
               description, unit, default, _array_constraint(bounds, length))


def integers(
    name: str,
    default: Any = REQUIRED,
    *,
    description: str,
    unit: str = '',
    length: int | None = None,
    gt: int | None = None,
    ge: int | None = None,
    lt: int | None = None,
    le: int | None = None,
) -> Key:
    """A list of integers, of length entries if given, each within the bounds."""
    bounds = Bounds(gt, ge, lt, le)
    return Key(name, 'integer[]', array_of(lambda v: bounds.check(to_int(v)), length),
               description, unit, default, _array_constraint(bounds, length))


def booleans(
    name: str, default: Any = REQUIRED, *, description: str, length: int | None = None
) -> Key:
    """A list of ``true``/``false``, of length entries if given."""
    return Key(name, 'bool[]', array_of(to_bool, length), description, '', default,
               _array_constraint(Bounds(), length))


def choice(name: str, options: type[E], default: Any = REQUIRED, *, description: str) -> Key:
    """A string naming a member of the Enum options (any case); read as the member."""
    names = [member.name.lower() for member in options]
    by_name = {member.name.lower(): member for member in options}

    def convert(value: object) -> E:
        text = to_str(value)
        if text.lower() not in by_name:
            raise InvalidValueError(f'must be one of {", ".join(names)}, got {text!r}')
        return by_name[text.lower()]

    if isinstance(default, Enum):
        default = default.name.lower()
    return Key(name, 'string', convert, description, '', default, f'one of: {", ".join(names)}')


def strings(
    name: str,
    default: Any = REQUIRED,
    *,
    description: str,
    nonempty: bool = True,
    unique: bool = False,
    length: int | None = None,
) -> Key:
    """A list of strings (names: non-empty unless told), optionally unique; a tuple."""

    def item(value: object) -> str:
        text = to_str(value)
        if nonempty and not text:
            raise InvalidValueError('must not be empty')
        return text

    items = array_of(item, length)

    def convert(value: object) -> tuple[str, ...]:
        values = items(value)
        if unique and len(set(values)) != len(values):
            duplicates = sorted({v for v in values if values.count(v) > 1})
            raise InvalidValueError(f'has duplicate entries: {", ".join(duplicates)}')
        return values

    return Key(name, 'string[]', convert, description, '', default,
               _array_constraint(Bounds(), length, unique))


def signs(name: str, default: Any = REQUIRED, *, description: str) -> Key:
    """A list of directions, each 1 or -1; returned as a tuple of ints."""

    def item(value: object) -> int:
        if isinstance(value, bool) or value not in (1, -1):
            raise InvalidValueError(f'must be 1 or -1, got {value!r}')
        return 1 if value == 1 else -1

    return Key(name, 'integer[]', array_of(item), description, '', default, 'each 1 or -1')


def tables(name: str, default: Any = REQUIRED, *, description: str) -> Key:
    """A list of mappings (each read further by its own schema); returned as a tuple."""
    return Key(name, 'mapping[]', array_of(to_mapping), description, '', default)


def check_table(
    where: str,
    data: object,
    allowed: Collection[str] | None,
    error: type[ConfigError] = ConfigError,
) -> Mapping[str, Any]:
    """Data, if it is a mapping whose keys are all allowed (None: any); else raise error."""
    if not isinstance(data, Mapping):
        raise error(f'{where} must be a mapping, got {describe_value(data)}')
    if allowed is not None:
        unknown = set(data) - set(allowed)
        if unknown:
            raise error(unknown_keys_message(where, unknown, allowed))
    return data


def unknown_keys_message(where: str, unknown: Collection[str], allowed: Collection[str]) -> str:
    """``<where>: unknown key(s) [...] (did you mean ...?); allowed: [...]``."""
    hints = []
    for key in sorted(map(str, unknown)):
        close = difflib.get_close_matches(key, list(allowed), n=1)
        if close:
            hints.append(f'{close[0]!r} for {key!r}')
    hint = f' (did you mean {", ".join(hints)}?)' if hints else ''
    return f'{where}: unknown key(s) {sorted(map(str, unknown))}{hint}; allowed: {sorted(allowed)}'


def read_value(
    where: str, key: Key, data: Mapping[str, Any], error: type[ConfigError] = ConfigError
) -> Any:
    """One key's typed value in data; error names ``<where>.<key>``."""
    try:
        return key.read(data)
    except InvalidValueError as err:
        raise error(f'{where}.{key.name} {err}') from None


@dataclasses.dataclass(frozen=True)
class Schema:
    """The keys of one config table.

    Attributes:
        keys: in reference order.
        open: other keys are allowed (``read`` leaves them out; ``extras`` returns them),
            e.g. a joint's family options.
    """

    keys: tuple[Key, ...]
    open: bool = False

    @property
    def names(self) -> frozenset[str]:
        """The declared keys."""
        return frozenset(k.name for k in self.keys)

    def read(
        self, where: str, data: object, error: type[ConfigError] = ConfigError
    ) -> dict[str, Any]:
        """Every declared key's typed value (defaults filled in) from the table data.

        Args:
            where: the table's name in messages (``buses.can0``).
            data: the table.
            error: the error type to raise (the caller's layer's).

        Raises:
            error: data is not a mapping; an unknown key (unless open); a key missing,
                of the wrong type or out of bounds, named as ``<where>.<key>``.
        """
        table = check_table(where, data, None if self.open else self.names, error)
        return {key.name: read_value(where, key, table, error) for key in self.keys}

    def extras(self, data: Mapping[str, Any]) -> dict[str, Any]:
        """The keys of data this schema does not declare (an open table's rest)."""
        return {k: v for k, v in data.items() if k not in self.names}

    def declared(self, prefix: str) -> list[DeclaredParameter]:
        """The reference rows, each key under prefix."""
        return [key.declared(prefix) for key in self.keys]


# --- declared parameter sets (the generate_parameter_library idea) ---------------------

_KEY = 'rm_ros2.key'
_GROUP = 'rm_ros2.group'


def declare(
    make: Callable[..., Key], default: Any = REQUIRED, *, tunable: bool = False, **options: Any
) -> Any:
    """A field of a parameter set: the key ``make(<field name>, default=default, **options)``.

    In a ``@dataclass(frozen=True, kw_only=True)`` class, each field declared so is one
    key: its name, the field's; its type, unit, bounds, default and description, the
    key's. :func:`build` fills the class, :func:`rows` documents it, and a ROS node
    declares it (``PluginParams.read``): one declaration, four uses. ``tunable`` keys may
    change while the robot runs (:func:`with_values`).

    Example:
        >>> @dataclasses.dataclass(frozen=True, kw_only=True)
        ... class Wheel:
        ...     radius: float = declare(number, description='wheel radius', unit='m', gt=0.0)
        >>> build(Wheel, lambda prefix, key: key.read({'radius': 0.07}))
        Wheel(radius=0.07)
    """
    extra = {} if default is REQUIRED else {'default': default}
    return dataclasses.field(metadata={_KEY: (make, default, tunable, options)}, **extra)


def group(cls: type) -> Any:
    """A field holding a parameter set of its own, under ``<field name>.``."""
    return dataclasses.field(metadata={_GROUP: cls})


def _fields(cls: type) -> list[tuple[str, Key | type]]:
    """(field name, its key or its group's class) for each declared field of cls."""
    if not dataclasses.is_dataclass(cls):
        raise TypeError(f'{cls.__name__} is not a declared parameter set (a dataclass)')
    out: list[tuple[str, Key | type]] = []
    for field in dataclasses.fields(cls):
        if _KEY in field.metadata:
            make, default, tunable, options = field.metadata[_KEY]
            key = make(field.name, default=default, **options)
            out.append((field.name, dataclasses.replace(key, tunable=tunable)))
        elif _GROUP in field.metadata:
            out.append((field.name, field.metadata[_GROUP]))
    return out


def build(cls: type[T], value_of: Callable[[str, Key], Any], prefix: str = '') -> T:
    """An instance of the parameter set cls, each key's value from ``value_of(prefix, key)``.

    Groups recurse with ``prefix + '<group>.'``; cls's own checks (``__post_init__``) run
    last, on typed values.
    """
    values: dict[str, Any] = {}
    for name, item in _fields(cls):
        if isinstance(item, Key):
            values[name] = value_of(prefix, item)
        else:
            values[name] = build(item, value_of, f'{prefix}{name}.')
    return cls(**values)


def keys(cls: type, prefix: str = '') -> list[tuple[str, Key]]:
    """(prefix, key) of every key of cls, groups flattened, in declaration order."""
    out: list[tuple[str, Key]] = []
    for name, item in _fields(cls):
        if isinstance(item, Key):
            out.append((prefix, item))
        else:
            out += keys(item, f'{prefix}{name}.')
    return out


def rows(cls: type, prefix: str = '') -> list[DeclaredParameter]:
    """The reference rows of every key of cls under prefix (``chassis.``)."""
    return [key.declared(prefix + inner) for inner, key in keys(cls)]


def with_values(instance: T, changes: Mapping[str, object]) -> T:
    """A copy of the parameter set instance with the keys changes names set, checked.

    Args:
        instance: a filled parameter set (:func:`build`).
        changes: ``{inner key: raw value}``, inner keys as :func:`keys` names them
            (``heat.margin``); all applied together.

    Raises:
        InvalidValueError: a key that is not the set's, not tunable, or whose value its key
            refuses; the text starts with the key. ConfigError: the values do not fit
            together (the set's own checks).
    """
    declared = {prefix + key.name: key for prefix, key in keys(type(instance))}
    nested: dict[str, Any] = {}
    for name, raw in changes.items():
        key = declared.get(name)
        if key is None:
            raise InvalidValueError(f'{name} is not a parameter of {type(instance).__name__}')
        if not key.tunable:
            raise InvalidValueError(f'{name} is read at start-up: a change needs a restart')
        try:
            value = key.read({key.name: raw})
        except InvalidValueError as err:
            raise InvalidValueError(f'{name} {err}') from None
        *groups, leaf = name.split('.')
        level = nested
        for group_name in groups:
            level = level.setdefault(group_name, {})
        level[leaf] = value
    return _replace(instance, nested)


def _replace(instance: T, nested: Mapping[str, Any]) -> T:
    values = {
        name: _replace(getattr(instance, name), value) if isinstance(value, dict) else value
        for name, value in nested.items()
    }
    return dataclasses.replace(instance, **values)  # type: ignore[type-var]
