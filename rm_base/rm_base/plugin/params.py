"""Typed ROS parameters under a plugin's dotted prefix (``chassis.wheel_radius``).

Every parameter is a key of :mod:`rm_base.config.schema` (the one vocabulary of type,
unit, bounds, default and description): a plugin reads a declared parameter set with
:meth:`PluginParams.read`, or one key at a time with the typed accessors (``double``,
``string_array``...), which build the same keys. Each key is declared on the host node
with a ``ParameterDescriptor`` (description, unit, constraints, when it may change), takes its value
from the robot config (``--params-file`` or ``parameter_overrides``) or the default, and is
checked and returned as a plain Python value. A parameter without a default is *required*:
a config that omits it fails at start-up with a ``ParameterError`` naming the plugin, the
key, the expected type and unit; so does a value of the wrong type or out of range.

A key the schema marks ``tunable`` may be set while the robot runs (the host takes it
through the parameter services, ``ros2 param set``, and hands it to the plugin between two
runs); the others are read once, at init, and declared read-only: a set is refused.
"""

from __future__ import annotations

import weakref
from collections.abc import Callable, Sequence
from enum import Enum
from typing import Any, TypeVar, cast

from rcl_interfaces.msg import ParameterDescriptor

from rm_base.config import schema
from rm_base.config.schema import (
    OPTIONAL,
    REQUIRED,
    DeclaredParameter,
    InvalidValueError,
    Key,
    WrongTypeError,
    describe_value,
)
from rm_base.plugin.errors import ParameterError

E = TypeVar('E', bound=Enum)
T = TypeVar('T')


def _listed(default: object) -> Any:
    """An array default as the list a ROS parameter takes (REQUIRED as it is)."""
    return default if default is REQUIRED else list(default)  # type: ignore[call-overload]


# Every declaration through PluginParams, per node, in declaration order.
_DECLARED: weakref.WeakKeyDictionary[Any, list[DeclaredParameter]] = weakref.WeakKeyDictionary()


def declared_parameters(node: Any) -> list[DeclaredParameter]:
    """The parameters declared on node through PluginParams, in declaration order."""
    return list(_DECLARED.get(node, ()))


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
        return cast(float, self.declare_key(schema.number(
            name, default, description=description, unit=unit, gt=gt, ge=ge, lt=lt, le=le
        )))

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
        return cast(int, self.declare_key(schema.integer(
            name, default, description=description, unit=unit, gt=gt, ge=ge, lt=lt, le=le
        )))

    def boolean(self, name: str, default: bool = REQUIRED, *, description: str) -> bool:
        """Declare and read a boolean parameter (``true``/``false`` in YAML)."""
        return cast(bool, self.declare_key(schema.boolean(name, default, description=description)))

    def string(
        self,
        name: str,
        default: str = REQUIRED,
        *,
        description: str,
        choices: Sequence[str] | None = None,
    ) -> str:
        """Declare and read a string parameter, optionally one of choices."""
        return cast(str, self.declare_key(
            schema.string(name, default, description=description, choices=choices)
        ))

    def choice(
        self, name: str, options: type[E], default: E = REQUIRED, *, description: str
    ) -> E:
        """Declare a string parameter naming a member of the Enum options; return the member.

        Matching is case-insensitive on the member name: ``mecanum`` selects
        ``Kinematics.MECANUM``.
        """
        return cast(E, self.declare_key(
            schema.choice(name, options, default, description=description)
        ))

    def declare_key(self, key: Key) -> Any:
        """Declare and read a key of a config schema (:mod:`rm_base.config.schema`).

        The parameter takes the key's type, unit, bounds, default and description, which
        are declared once, in the schema. An optional key (default None) may stay unset:
        its value is then None.
        """
        return self._declare(
            key.name, default=key.default, type_name=key.type_name,
            description=key.description, unit=key.unit, constraint=key.constraint,
            convert=key.convert, tunable=key.tunable,
        )

    def read(self, cls: type[T]) -> T:
        """Declare every key of the parameter set cls under the prefix; return it filled.

        cls is a dataclass of :func:`rm_base.config.schema.declare` fields (groups under
        ``<group>.``): its fields are the typed values, its keys the ROS parameters.
        """
        return schema.build(cls, lambda inner, key: self.nested(inner).declare_key(key))

    def nested(self, inner: str) -> PluginParams:
        """The parameters under ``<prefix><inner>`` (inner: '' or ``group.``)."""
        if not inner:
            return self
        return PluginParams(self._node, self.plugin, self.plugin_type, prefix=self.key(inner))

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
        return cast(tuple[float, ...], self.declare_key(schema.numbers(
            name, _listed(default), description=description, unit=unit, length=length,
            gt=gt, ge=ge, lt=lt, le=le,
        )))

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
        return cast(tuple[int, ...], self.declare_key(schema.integers(
            name, _listed(default), description=description, unit=unit, length=length,
            gt=gt, ge=ge, lt=lt, le=le,
        )))

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
        return cast(tuple[str, ...], self.declare_key(schema.strings(
            name, _listed(default), description=description, nonempty=False, unique=unique,
            length=length,
        )))

    def boolean_array(
        self,
        name: str,
        default: Sequence[bool] = REQUIRED,
        *,
        description: str,
        length: int | None = None,
    ) -> tuple[bool, ...]:
        """Declare and read an array of booleans."""
        return cast(tuple[bool, ...], self.declare_key(schema.booleans(
            name, _listed(default), description=description, length=length,
        )))

    # -- machinery ----------------------------------------------------------------------

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
        tunable: bool = False,
    ) -> Any:
        key = self.key(name)
        required = default is REQUIRED
        if not required and default is not None:
            # A wrong default is a bug in the plugin, not in the config.
            try:
                convert(default)
            except InvalidValueError as err:
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
        constraints.append(
            'set while running' if tunable else 'read at start-up: a change needs a restart'
        )
        shown = None if required else OPTIONAL if default is None else default
        _DECLARED.setdefault(self._node, []).append(
            DeclaredParameter(key, type_name, unit, shown, constraint, description, tunable)
        )
        descriptor = ParameterDescriptor(
            name=key,
            description=f'{description} [{unit}]' if unit else description,
            additional_constraints='; '.join(constraints),
            # Typed by convert() below, so an int given for a double is accepted and every
            # type error gets a message naming the plugin and key.
            dynamic_typing=True,
            # Start-up keys refuse `ros2 param set` rather than ignore it; the host's
            # set-parameters callback takes the tunable ones to the plugin.
            read_only=not tunable,
        )
        try:
            parameter = self._node.declare_parameter(
                key, None if required else default, descriptor
            )
        except Exception as err:  # rclpy raises several unrelated exception types here
            raise self.error(name, f'cannot be declared: {err}') from err
        value = parameter.value
        if value is None and not required:
            return None  # an optional key left unset
        if value is None:
            raise self.error(
                name,
                f'is required but not set ({type_name}'
                f'{", " + unit if unit else ""}: {description})',
            )
        try:
            return convert(value)
        except WrongTypeError as err:
            unit_text = f' [{unit}]' if unit else ''
            got = str(err) or f'got {describe_value(value)}'
            raise self.error(name, f'must be {type_name}{unit_text}; {got}') from None
        except InvalidValueError as err:
            raise self.error(name, str(err)) from None

    def error(self, name: str, problem: str) -> ParameterError:
        """The error for a problem with key name, naming the plugin and the full key."""
        key = self.key(name)
        if self.plugin:
            kind = f' ({self.plugin_type})' if self.plugin_type else ''
            where = f"plugin '{self.plugin}'{kind}"
            message = f"{where}: parameter '{key}' {problem}"
        else:
            message = f"parameter '{key}' {problem}"
        return ParameterError(message, plugin=self.plugin, key=key)
