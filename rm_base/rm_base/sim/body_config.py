"""The simulated body's config, declared once: the ``body`` of a world (``sim.body``).

Each table (the body, the chassis of each ``type``, a wheel, the gimbal's joints, the
launcher) is a :class:`~rm_base.config.schema.Schema`: reading a config through it gives
errors naming the key (``body.chassis.wheelbase must be > 0.0, got -0.4``), and the same
schemas print the ``sim.body`` rows of docs/PARAMETERS.md (:data:`BODY_TABLES`). Motors
are named, not configured, here: each name must be a motor of the world.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, NamedTuple

from rm_base.config.schema import (
    REQUIRED,
    Schema,
    boolean,
    integer,
    mapping,
    number,
    numbers,
    one_of,
    signs,
    string,
    strings,
    tables,
)
from rm_base.errors import ConfigError
from rm_base.geometry import (
    SwerveKinematics,
    Wheel,
    WheelKinematics,
    mecanum_wheels,
    omni_wheels,
    square_modules,
)
from rm_base.sim.body import Chassis, RobotBody
from rm_base.sim.joint import Joint
from rm_base.sim.launcher import CALIBRES, Launcher
from rm_base.sim_devices.device import SimDevice
from rm_base.sim_devices.errors import SimConfigError

#: ``body``: every part is optional (a world may be a bare bench of motors).
BODY_SCHEMA = Schema((
    numbers('initial_pose', (0.0, 0.0, 0.0), unit='m, m, rad', length=3,
            description='chassis x, y and heading in the world at the start'),
    mapping('chassis', None, description='the wheels and their kinematics (body.chassis)'),
    mapping('gimbal', None, description='the yaw and pitch joints (body.gimbal)'),
    mapping('shooter', None, description='the launcher (body.shooter)'),
))

_MOTOR = string('motor', nonempty=True, description='the motor that drives it (its name)')
_DIRECTION = one_of('direction', (1, -1), 1,
                    description='sign of the joint angle against the motor angle')
_ZERO = number('zero', 0.0, unit='rad', description='motor angle at which the joint reads 0')

#: ``body.gimbal``.
GIMBAL_SCHEMA = Schema((
    mapping('yaw', None, description='the yaw joint (body.gimbal.yaw)'),
    mapping('pitch', None, description='the pitch joint (body.gimbal.pitch)'),
))
#: ``body.gimbal.yaw``.
YAW_SCHEMA = Schema((
    _MOTOR, _DIRECTION, _ZERO,
    boolean('world_frame_inertia', True,
            description="the load keeps its inertia in the world: the chassis' yaw "
            'acceleration is fed to the yaw motor'),
))
#: ``body.gimbal.pitch``.
PITCH_SCHEMA = Schema((
    _MOTOR, _DIRECTION, _ZERO,
    number('gravity_torque', 0.0, unit='N·m',
           description='gravity torque at 0 pitch, times cos(pitch) (nose-heavy > 0)'),
    numbers('end_stops', None, unit='rad', length=2,
            description='the mechanical stops [low, high] of the joint: a limp barrel rests '
            'there (none if unset)'),
))

_CHASSIS_TYPES = ('mecanum', 'omni', 'swerve', 'wheels')
_TYPE = string('type', choices=_CHASSIS_TYPES, description='the wheel layout')
_MOTORS = strings('motors', description="the wheel motors, in the layout's order")
_DIRECTIONS = signs('directions', None,
                    description='wheel speed = direction x motor speed; default all 1')
_WHEEL_RADIUS = number('wheel_radius', unit='m', gt=0.0, description='wheel radius')

#: ``body.chassis``, by its ``type``.
CHASSIS_SCHEMAS: Mapping[str, Schema] = {
    'mecanum': Schema((
        _TYPE, _MOTORS, _DIRECTIONS,
        number('wheelbase', unit='m', gt=0.0, description='front to rear axle'),
        number('track', unit='m', gt=0.0, description='left to right wheel centres'),
        _WHEEL_RADIUS,
        signs('roller_signs', None,
              description='roller direction per wheel (FL, FR, RL, RR); default the X layout'),
    )),
    'omni': Schema((
        _TYPE, _MOTORS, _DIRECTIONS,
        numbers('mounting_angles', unit='rad',
                description='angle of each wheel from the chassis x axis'),
        number('centre_distance', unit='m', gt=0.0, description='centre to each wheel'),
        _WHEEL_RADIUS,
    )),
    'swerve': Schema((
        _TYPE, _MOTORS, _DIRECTIONS,
        strings('steer_motors', description='the steering motors, one per drive motor'),
        signs('steer_directions', None,
              description='module angle = direction x (motor angle - zero); default all 1'),
        numbers('steer_zeros', None, unit='rad',
                description='steering motor angle at which a module points along x; '
                'default all 0'),
        number('wheelbase', unit='m', gt=0.0, description='front to rear modules'),
        number('track', unit='m', gt=0.0, description='left to right modules'),
        _WHEEL_RADIUS,
    )),
    'wheels': Schema((
        _TYPE,
        tables('wheels', description='one table per wheel (body.chassis.wheels[i])'),
    )),
}
#: ``body.chassis.wheels[i]`` of a ``wheels`` chassis.
WHEEL_SCHEMA = Schema((
    _MOTOR,
    number('x', unit='m', description='wheel centre, chassis frame'),
    number('y', unit='m', description='wheel centre, chassis frame'),
    number('radius', unit='m', gt=0.0, description='wheel radius'),
    number('rolling_direction', 0.0, unit='rad',
           description='direction the wheel rolls, from the chassis x axis'),
    number('roller_angle', 0.0, unit='rad', description='roller angle (0: a plain wheel)'),
    one_of('direction', (1, -1), 1, description='wheel speed sign against the motor speed'),
))

#: ``body.shooter``.
LAUNCHER_SCHEMA = Schema((
    mapping('trigger', REQUIRED, description='the trigger joint (body.shooter.trigger)'),
    strings('friction_motors', description='the friction wheels'),
    signs('friction_directions', None,
          description='launch direction per friction wheel; default all 1'),
    integer('slots', ge=1, description='pockets per trigger turn'),
    number('fire_phase', unit='rad', ge=0.0,
           description='where in a slot a ball leaves for the wheels (< 2*pi/slots)'),
    number('speed_ratio', unit='m/s per rad/s', ge=0.0,
           description='muzzle speed per friction wheel speed'),
    number('min_speed', 5.0, unit='m/s', ge=0.0,
           description='slower balls stay in the barrel (duds)'),
    one_of('calibre', CALIBRES, 17, description='projectile calibre [mm]'),
))
#: ``body.shooter.trigger``.
TRIGGER_SCHEMA = Schema((_MOTOR, _DIRECTION, _ZERO))


class BodyTable(NamedTuple):
    """One table of the body config, as docs/PARAMETERS.md lists it.

    Attributes:
        key: where it is below ``body`` ('' for the body itself).
        note: what it is.
        schema: its keys.
        variant: which form of the table (a chassis ``type``), '' if it has one form.
    """

    key: str
    note: str
    schema: Schema
    variant: str = ''


_LAYOUTS = {
    'mecanum': 'four mecanum wheels on a rectangle (FL, FR, RL, RR)',
    'omni': 'omni wheels on a circle, each rolling tangentially',
    'swerve': 'four steered wheels on a rectangle (FL, FR, RL, RR)',
    'wheels': 'any wheels, one table each',
}

#: Every table, in reference order (keys below ``body``).
BODY_TABLES: tuple[BodyTable, ...] = (
    BodyTable('', 'the robot the motors move', BODY_SCHEMA),
    *(BodyTable('chassis', _LAYOUTS[kind], CHASSIS_SCHEMAS[kind], f'type {kind}')
      for kind in _CHASSIS_TYPES),
    BodyTable('chassis.wheels[i]', 'a wheel of a type wheels chassis', WHEEL_SCHEMA),
    BodyTable('gimbal', 'its joints', GIMBAL_SCHEMA),
    BodyTable('gimbal.yaw', 'the yaw joint', YAW_SCHEMA),
    BodyTable('gimbal.pitch', 'the pitch joint', PITCH_SCHEMA),
    BodyTable('shooter', 'the launcher: which trigger pushes are shots', LAUNCHER_SCHEMA),
    BodyTable('shooter.trigger', 'the trigger joint', TRIGGER_SCHEMA),
)


def _read(schema: Schema, where: str, data: object) -> dict[str, Any]:
    return schema.read(where, data, SimConfigError)


def _motor(devices: Mapping[str, SimDevice], name: str, where: str) -> SimDevice:
    if name not in devices:
        raise SimConfigError(f'{where} is {name!r}, which is not a configured motor')
    return devices[name]


def _joint(values: Mapping[str, Any], devices: Mapping[str, SimDevice], where: str) -> Joint:
    return Joint(
        _motor(devices, values['motor'], f'{where}.motor'),
        float(values['direction']),
        values['zero'],
    )


def _signs(values: tuple[int, ...] | None, count: int, where: str) -> list[float]:
    """One direction per wheel (default all 1)."""
    if values is None:
        return [1.0] * count
    if len(values) != count:
        raise SimConfigError(f'{where} must have one entry per wheel ({count}), has {len(values)}')
    return [float(v) for v in values]


def _chassis(data: Mapping[str, Any], devices: Mapping[str, SimDevice]) -> Chassis:
    where = 'body.chassis'
    kind = _read(Schema((_TYPE,), open=True), where, data)['type']
    values = _read(CHASSIS_SCHEMAS[kind], where, data)
    if kind == 'wheels':
        wheels, motors, directions = [], [], []
        for i, entry in enumerate(values['wheels']):
            wheel = _read(WHEEL_SCHEMA, f'{where}.wheels[{i}]', entry)
            wheels.append(Wheel(
                wheel['x'], wheel['y'], wheel['radius'],
                rolling_direction=wheel['rolling_direction'],
                roller_angle=wheel['roller_angle'],
            ))
            motors.append(_motor(devices, wheel['motor'], f'{where}.wheels[{i}].motor'))
            directions.append(float(wheel['direction']))
        return Chassis(WheelKinematics(wheels), motors, directions)
    if kind == 'swerve':
        return _swerve(values, devices, where)
    if kind == 'mecanum':
        extra = {} if values['roller_signs'] is None else {'roller_signs': values['roller_signs']}
        layout = mecanum_wheels(
            values['wheelbase'], values['track'], values['wheel_radius'], **extra
        )
    else:
        layout = omni_wheels(
            values['mounting_angles'], values['centre_distance'], values['wheel_radius']
        )
    return Chassis(
        WheelKinematics(layout),
        _motors(values['motors'], len(layout), devices, f'{where}.motors'),
        _signs(values['directions'], len(layout), f'{where}.directions'),
    )


def _motors(
    names: tuple[str, ...], count: int, devices: Mapping[str, SimDevice], where: str
) -> list[SimDevice]:
    if len(names) != count:
        raise SimConfigError(f'{where} must name {count} motors, got {list(names)}')
    return [_motor(devices, name, where) for name in names]


def _swerve(values: Mapping[str, Any], devices: Mapping[str, SimDevice], where: str) -> Chassis:
    modules = square_modules(values['wheelbase'], values['track'], values['wheel_radius'])
    count = len(modules)
    zeros = values['steer_zeros']
    if zeros is not None and len(zeros) != count:
        raise SimConfigError(
            f'{where}.steer_zeros must have one entry per module ({count}), has {len(zeros)}'
        )
    steering = [
        Joint(device, direction, zero)
        for device, direction, zero in zip(
            _motors(values['steer_motors'], count, devices, f'{where}.steer_motors'),
            _signs(values['steer_directions'], count, f'{where}.steer_directions'),
            zeros if zeros is not None else [0.0] * count,
            strict=True,
        )
    ]
    return Chassis(
        SwerveKinematics(modules),
        _motors(values['motors'], count, devices, f'{where}.motors'),
        _signs(values['directions'], count, f'{where}.directions'),
        steering,
    )


def launcher_from_config(data: object, devices: Mapping[str, SimDevice]) -> Launcher:
    """The launcher of a ``body.shooter`` table (:data:`LAUNCHER_SCHEMA`).

    Raises:
        SimConfigError: a missing, unknown or bad key, or an unknown motor.
    """
    where = 'body.shooter'
    values = _read(LAUNCHER_SCHEMA, where, data)
    motors = values['friction_motors']
    directions = _signs(values['friction_directions'], len(motors), f'{where}.friction_directions')
    friction = [
        Joint(_motor(devices, name, f'{where}.friction_motors'), direction)
        for name, direction in zip(motors, directions, strict=True)
    ]
    trigger = _read(TRIGGER_SCHEMA, f'{where}.trigger', values['trigger'])
    return Launcher(
        _joint(trigger, devices, f'{where}.trigger'),
        friction,
        slots=values['slots'],
        fire_phase=values['fire_phase'],
        speed_ratio=values['speed_ratio'],
        min_speed=values['min_speed'],
        calibre=values['calibre'],
    )


def body_from_config(data: object, devices: Mapping[str, SimDevice]) -> RobotBody:
    """Build the body from its config (:data:`BODY_TABLES`); motors are named.

    Args:
        data: the ``body`` table of a world config.
        devices: every configured motor by name.

    Raises:
        SimConfigError: an unknown key, a missing or unknown motor, bad geometry.
    """
    values = _read(BODY_SCHEMA, 'body', data)
    try:
        chassis = None if values['chassis'] is None else _chassis(values['chassis'], devices)
        gimbal = _read(GIMBAL_SCHEMA, 'body.gimbal', values['gimbal'] or {})
        yaw = pitch = stops = None
        world_frame, gravity = True, 0.0
        if gimbal['yaw'] is not None:
            settings = _read(YAW_SCHEMA, 'body.gimbal.yaw', gimbal['yaw'])
            yaw = _joint(settings, devices, 'body.gimbal.yaw')
            world_frame = settings['world_frame_inertia']
        if gimbal['pitch'] is not None:
            settings = _read(PITCH_SCHEMA, 'body.gimbal.pitch', gimbal['pitch'])
            pitch = _joint(settings, devices, 'body.gimbal.pitch')
            gravity = settings['gravity_torque']
            stops = settings['end_stops']
            if stops is not None and not stops[0] < stops[1]:
                raise SimConfigError(
                    f'body.gimbal.pitch.end_stops must be [low, high], low < high, got {stops}'
                )
        shooter = values['shooter']
        return RobotBody(
            chassis=chassis,
            yaw=yaw,
            pitch=pitch,
            initial_pose=values['initial_pose'],
            pitch_gravity_torque=gravity,
            pitch_end_stops=stops,
            yaw_world_frame_inertia=world_frame,
            launcher=None if shooter is None else launcher_from_config(shooter, devices),
        )
    except SimConfigError:
        raise
    except ConfigError as err:  # the geometry's own checks
        raise SimConfigError(f'body: {err}') from err
