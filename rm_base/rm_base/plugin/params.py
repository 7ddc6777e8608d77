"""Typed ROS parameters under a plugin's dotted prefix (``chassis.wheel_radius``).

Why one module: one typed accessor per ROS parameter type, each with its descriptor and the
checks that name the key.

Each accessor declares one parameter on the host node with a ``ParameterDescriptor``
(description, unit, constraints, read-only), takes its value from the robot config
(``--params-file`` or ``parameter_overrides``) or the typed default, checks type and range,
and returns a plain Python value. A parameter without a default is *required*: a config that
omits it fails at start-up with a ``ParameterError`` naming the plugin, the key, the expected
type and unit; so does a value of the wrong type or out of range.

Parameters are read once, at init, and declared read-only so ``ros2 param set`` is refused
with a reason instead of silently doing nothing.
"""

from __future__ import annotations

import math
import weakref
from collections.abc import Callable, Sequence
from enum import Enum
from typing import Any, NamedTuple, TypeVar

from rcl_interfaces.msg import ParameterDescriptor

from rm_base.plugin.errors import ParameterError

E = TypeVar('E', bound=Enum)


class DeclaredParameter(NamedTuple):
    """One parameter as declared (for the generated reference, docs/PARAMETERS.md).

    Attributes:
        key: full name (``chassis.wheel_radius``).
        type_name: ``double``, ``integer[]``...
        unit: SI unit, '' if none.
        default: the default, None if required.
        constraint: bounds, choices, length; '' if none.
        description: what it is.
    """

    key: str
    type_name: str
    unit: str
    default: Any
    constraint: str
    description: str


# Every declaration through PluginParams, per node, in declaration order.
_DECLARED: weakref.WeakKeyDictionary[Any, list[DeclaredParameter]] = weakref.WeakKeyDictionary()


def declared_parameters(node: Any) -> list[DeclaredParameter]:
    """The parameters declared on node through PluginParams, in declaration order."""
    return list(_DECLARED.get(node, ()))


class _Required:
    """Marker for "no default: the config must set this parameter"."""

    def __repr__(self) -> str:
        return 'REQUIRED'


REQUIRED: Any = _Required()
"""Default of a parameter that has none: a missing value is a start-up error."""


def _is_number(value: object) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def _as_sequence(value: object) -> list | None:
    # rclpy hands arrays over as list or array.array; a str is not an array here.
    if isinstance(value, str | bytes) or value is None:
        return None
    try:
        return list(value)  # type: ignore[call-overload]
    except TypeError:
        return None


def _describe_value(value: object) -> str:
    if value is None:
        return 'nothing'
    return f'{type(value).__name__} {value!r}'


class PluginParams:
    """Typed parameter access for one plugin instance.

    Args:
        node: the node the parameters are declared on (the host node).
        plugin: instance name from the robot config, e.g. ``chassis``; also the prefix.
        plugin_type: plugin type for messages, e.g. ``rm_plugins/StandChassis``.
        prefix: parameter prefix; defaults to ``'<plugin>.'``; ``''`` for node-level keys.

    Example:
        >>> radius = params.double('wheel_radius', description='wheel radius', unit='m', gt=0.0)
        >>> kind = params.choice('kinematics', Kinematics, Kinematics.MECANUM,
        ...                      description='wheel layout')
    """

    def __init__(
        self, node: Any, plugin: str, plugin_type: str = '', *, prefix: str | None = None
    ) -> None:
        self._node = node
        self.plugin = plugin
        self.plugin_type = plugin_type
        self.prefix = f'{plugin}.' if prefix is None else prefix

    def key(self, name: str) -> str:
        """Return the full parameter name of name (``'chassis.' + name``)."""
        return self.prefix + name

    def group(self, name: str) -> PluginParams:
        """The parameters under ``<prefix><name>.`` (a device's own port settings)."""
        return PluginParams(self._node, self.plugin, self.plugin_type, prefix=self.key(name + '.'))

    # -- scalars ------------------------------------------------------------------------

    def double(
        self,
        name: str,
        default: float = REQUIRED,
        *,
        description: str,
        unit: str = '',
        gt: float | None = None,
        ge: float | None = None,
        lt: float | None = None,
        le: float | None = None,
    ) -> float:
        """Declare and read a floating-point parameter.

        An integer in the config is accepted (``1`` for ``1.0``); NaN and inf are not.

        Args:
            name: key below the prefix, e.g. ``wheel_radius``.
            default: value when the config has none; omit for a required parameter.
            description: what it is, for ``ros2 param describe``.
            unit: SI unit, e.g. ``m``, ``rad/s``, ``s``.
            gt: exclusive lower bound.
            ge: inclusive lower bound.
            lt: exclusive upper bound.
            le: inclusive upper bound.

        Returns:
            The value [unit].

        Raises:
            ParameterError: missing, not a number, not finite, or out of bounds.
        """
        bounds = _Bounds(gt, ge, lt, le)
        return self._declare(
            name, default=default, type_name='double', description=description, unit=unit,
            constraint=bounds.text(), convert=lambda v: bounds.check(self._to_float(v)),
        )

    def integer(
        self,
        name: str,
        default: int = REQUIRED,
        *,
        description: str,
        unit: str = '',
        gt: int | None = None,
        ge: int | None = None,
        lt: int | None = None,
        le: int | None = None,
    ) -> int:
        """Declare and read an integer parameter (see ``double`` for the arguments)."""
        bounds = _Bounds(gt, ge, lt, le)
        return self._declare(
            name, default=default, type_name='integer', description=description, unit=unit,
            constraint=bounds.text(), convert=lambda v: bounds.check(self._to_int(v)),
        )

    def boolean(self, name: str, default: bool = REQUIRED, *, description: str) -> bool:
        """Declare and read a boolean parameter (``true``/``false`` in YAML)."""
        return self._declare(
            name, default=default, type_name='bool', description=description, unit='',
            constraint='', convert=self._to_bool,
        )

    def string(
        self,
        name: str,
        default: str = REQUIRED,
        *,
        description: str,
        choices: Sequence[str] | None = None,
    ) -> str:
        """Declare and read a string parameter, optionally one of choices."""
        constraint = f'one of: {", ".join(choices)}' if choices else ''

        def convert(value: object) -> str:
            text = self._to_str(value)
            if choices is not None and text not in choices:
                raise _InvalidValueError(f'must be one of {", ".join(choices)}, got {text!r}')
            return text

        return self._declare(
            name, default=default, type_name='string', description=description, unit='',
            constraint=constraint, convert=convert,
        )

    def choice(
        self, name: str, options: type[E], default: E = REQUIRED, *, description: str
    ) -> E:
        """Declare a string parameter naming a member of the Enum options; return the member.

        Matching is case-insensitive on the member name: ``mecanum`` selects
        ``Kinematics.MECANUM``.
        """
        names = [member.name.lower() for member in options]
        by_name = {member.name.lower(): member for member in options}

        def convert(value: object) -> E:
            text = self._to_str(value)
            if text.lower() not in by_name:
                raise _InvalidValueError(f'must be one of {", ".join(names)}, got {text!r}')
            return by_name[text.lower()]

        default_text = default if default is REQUIRED else default.name.lower()
        return self._declare(
            name, default=default_text, type_name='string', description=description, unit='',
            constraint=f'one of: {", ".join(names)}', convert=convert,
        )

    # -- arrays -------------------------------------------------------------------------

    def double_array(
        self,
        name: str,
        default: Sequence[float] = REQUIRED,
        *,
        description: str,
        unit: str = '',
        length: int | None = None,
        gt: float | None = None,
        ge: float | None = None,
        lt: float | None = None,
        le: float | None = None,
    ) -> tuple[float, ...]:
        """Declare and read an array of floats; bounds apply to every element."""
        bounds = _Bounds(gt, ge, lt, le)
        return self._declare_array(
            name, default=default, type_name='double[]', description=description, unit=unit,
            length=length, constraint=bounds.text(),
            convert_item=lambda v: bounds.check(self._to_float(v)),
        )

    def vector3(
        self,
        name: str,
        default: tuple[float, float, float] | None = None,
        *,
        description: str,
        unit: str = '',
    ) -> tuple[float, float, float]:
        """Declare and read three floats (a position, a set of angles); None: required."""
        x, y, z = self.double_array(
            name, REQUIRED if default is None else default, description=description,
            unit=unit, length=3,
        )
        return x, y, z

    def integer_array(
        self,
        name: str,
        default: Sequence[int] = REQUIRED,
        *,
        description: str,
        unit: str = '',
        length: int | None = None,
        gt: int | None = None,
        ge: int | None = None,
        lt: int | None = None,
        le: int | None = None,
    ) -> tuple[int, ...]:
        """Declare and read an array of integers; bounds apply to every element."""
        bounds = _Bounds(gt, ge, lt, le)
        return self._declare_array(
            name, default=default, type_name='integer[]', description=description, unit=unit,
            length=length, constraint=bounds.text(),
            convert_item=lambda v: bounds.check(self._to_int(v)),
        )

    def string_array(
        self,
        name: str,
        default: Sequence[str] = REQUIRED,
        *,
        description: str,
        length: int | None = None,
        unique: bool = False,
    ) -> tuple[str, ...]:
        """Declare and read an array of strings (e.g. joint names), optionally unique."""
        values = self._declare_array(
            name, default=default, type_name='string[]', description=description, unit='',
            length=length, constraint='unique' if unique else '', convert_item=self._to_str,
        )
        if unique and len(set(values)) != len(values):
            duplicates = sorted({v for v in values if values.count(v) > 1})
            raise self._error(name, f'has duplicate entries: {", ".join(duplicates)}')
        return values

    def boolean_array(
        self,
        name: str,
        default: Sequence[bool] = REQUIRED,
        *,
        description: str,
        length: int | None = None,
    ) -> tuple[bool, ...]:
        """Declare and read an array of booleans."""
        return self._declare_array(
            name, default=default, type_name='bool[]', description=description, unit='',
            length=length, constraint='', convert_item=self._to_bool,
        )

    # -- machinery ----------------------------------------------------------------------

    def _declare_array(
        self,
        name: str,
        *,
        default: object,
        type_name: str,
        description: str,
        unit: str,
        length: int | None,
        constraint: str,
        convert_item: Callable[[object], Any],
    ) -> tuple:
        constraints = [c for c in (constraint, f'length {length}' if length else '') if c]

        def convert(value: object) -> tuple:
            items = _as_sequence(value)
            if items is None:
                raise _WrongTypeError()
            if length is not None and len(items) != length:
                raise _InvalidValueError(f'must have {length} entries, has {len(items)}')
            out = []
            for index, item in enumerate(items):
                try:
                    out.append(convert_item(item))
                except _WrongTypeError:
                    raise _WrongTypeError(f'entry [{index}] is {_describe_value(item)}') from None
                except _InvalidValueError as err:
                    raise _InvalidValueError(f'entry [{index}] {err}') from None
            return tuple(out)

        if default is not REQUIRED:
            default = list(default)  # type: ignore[call-overload]
        return self._declare(
            name, default=default, type_name=type_name, description=description, unit=unit,
            constraint='; '.join(constraints), convert=convert,
        )

    def _declare(
        self,
        name: str,
        *,
        default: object,
        type_name: str,
        description: str,
        unit: str,
        constraint: str,
        convert: Callable[[object], Any],
    ) -> Any:
        key = self.key(name)
        required = default is REQUIRED
        if not required:
            # A wrong default is a bug in the plugin, not in the config.
            try:
                convert(default)
            except _InvalidValueError as err:
                raise TypeError(
                    f'default of parameter {key!r} is not a valid {type_name}: {default!r} {err}'
                ) from None
        constraints = [f'type: {type_name}']
        if unit:
            constraints.append(f'unit: {unit}')
        if constraint:
            constraints.append(constraint)
        if required:
            constraints.append('required')
        _DECLARED.setdefault(self._node, []).append(
            DeclaredParameter(
                key, type_name, unit, None if required else default, constraint, description
            )
        )
        descriptor = ParameterDescriptor(
            name=key,
            description=f'{description} [{unit}]' if unit else description,
            additional_constraints='; '.join(constraints),
            # Typed by convert() below, so an int given for a double is accepted and every
            # type error gets a message naming the plugin and key.
            dynamic_typing=True,
            # Read once at init; refuse `ros2 param set` rather than ignore it.
            read_only=True,
        )
        try:
            parameter = self._node.declare_parameter(
                key, None if required else default, descriptor
            )
        except Exception as err:  # rclpy raises several unrelated exception types here
            raise self._error(name, f'cannot be declared: {err}') from err
        value = parameter.value
        if value is None:
            raise self._error(
                name,
                f'is required but not set ({type_name}'
                f'{", " + unit if unit else ""}: {description})',
            )
        try:
            return convert(value)
        except _WrongTypeError as err:
            unit_text = f' [{unit}]' if unit else ''
            got = str(err) or f'got {_describe_value(value)}'
            raise self._error(name, f'must be {type_name}{unit_text}; {got}') from None
        except _InvalidValueError as err:
            raise self._error(name, str(err)) from None

    def _error(self, name: str, problem: str) -> ParameterError:
        key = self.key(name)
        if self.plugin:
            kind = f' ({self.plugin_type})' if self.plugin_type else ''
            where = f"plugin '{self.plugin}'{kind}"
            message = f"{where}: parameter '{key}' {problem}"
        else:
            message = f"parameter '{key}' {problem}"
        return ParameterError(message, plugin=self.plugin, key=key)

    @staticmethod
    def _to_float(value: object) -> float:
        if not _is_number(value):
            raise _WrongTypeError()
        number = float(value)  # type: ignore[arg-type]
        if not math.isfinite(number):
            raise _InvalidValueError(f'must be finite, got {number}')
        return number

    @staticmethod
    def _to_int(value: object) -> int:
        if not isinstance(value, int) or isinstance(value, bool):
            raise _WrongTypeError()
        return int(value)

    @staticmethod
    def _to_bool(value: object) -> bool:
        if not isinstance(value, bool):
            raise _WrongTypeError()
        return value

    @staticmethod
    def _to_str(value: object) -> str:
        if not isinstance(value, str):
            raise _WrongTypeError()
        return value


class _InvalidValueError(Exception):
    """A value failed a check; the text completes "parameter 'x' ..."."""


class _WrongTypeError(_InvalidValueError):
    """A value is of the wrong type; the text (optional) says which part."""


class _Bounds:
    """Optional gt/ge/lt/le bounds of a number."""

    def __init__(self, gt: float | None, ge: float | None, lt: float | None, le: float | None):
        self._checks = [
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
        return ', '.join(f'{op} {bound}' for bound, op, _ in self._checks)

    def check(self, value: float) -> Any:
        for bound, op, test in self._checks:
            if not test(value, bound):
                raise _InvalidValueError(f'must be {op} {bound}, got {value}')
        return value
