"""A URDF of the robot built from its config, for Foxglove's 3D panel (/robot_description).

Boxes and cylinders where the config puts them: the chassis spanning its wheels, each wheel
at its position with its radius, the gimbal's yaw and pitch links at the pivot and the
barrel to the muzzle. The links carry the frame ids the robot publishes on /tf (the joints'
angles come from there); the wheels are fixed links of their own. Pure: no ROS here.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any
from xml.sax.saxutils import quoteattr

_WHEEL_WIDTH = 0.04  # [m]
_BODY_HEIGHT = 0.08  # [m]


@dataclass(frozen=True)
class WheelPlace:
    """One wheel (or swerve module): its joint, position in base_link [m] and radius [m]."""

    joint: str
    x: float
    y: float
    radius: float


@dataclass(frozen=True)
class GimbalPlace:
    """The gimbal: its frame ids, pivot in base_link [m] and barrel length [m]."""

    yaw_frame: str
    pitch_frame: str
    muzzle_frame: str
    pivot: tuple[float, float, float]
    barrel_length: float


def _xyz(x: float, y: float, z: float) -> str:
    return f'{x:.4f} {y:.4f} {z:.4f}'


def _link(name: str, geometry: str, origin: str = '0 0 0', rpy: str = '0 0 0',
          colour: str = '0.5 0.5 0.5 1') -> str:
    return (
        f'  <link name={quoteattr(name)}><visual><origin xyz="{origin}" rpy="{rpy}"/>'
        f'<geometry>{geometry}</geometry><material name={quoteattr(name + "_colour")}>'
        f'<color rgba="{colour}"/></material></visual></link>'
    )


def _joint(name: str, kind: str, parent: str, child: str, origin: str, *,
           axis: str | None = None) -> str:
    axis_tag = f'<axis xyz="{axis}"/>' if axis else ''
    # URDF asks a revolute joint for limits; the TF the robot sends moves it anyway
    limit = '<limit lower="-1.57" upper="1.57" effort="0" velocity="0"/>' if (
        kind == 'revolute') else ''
    return (
        f'  <joint name={quoteattr(name)} type="{kind}"><parent link={quoteattr(parent)}/>'
        f'<child link={quoteattr(child)}/><origin xyz="{origin}"/>{axis_tag}{limit}</joint>'
    )


def robot_description(
    name: str,
    wheels: Sequence[WheelPlace],
    gimbal: GimbalPlace | None,
    base_frame: str = 'base_link',
) -> str:
    """The URDF text of the robot (see the module docstring).

    Raises:
        ValueError: no wheels (a chassis spans its wheels).
    """
    if not wheels:
        raise ValueError('a robot description needs the chassis wheels')
    radius = max(w.radius for w in wheels)
    length = 2 * max(abs(w.x) for w in wheels)
    width = 2 * max(abs(w.y) for w in wheels) - _WHEEL_WIDTH
    lines = [
        '<?xml version="1.0"?>',
        f'<robot name={quoteattr(name)}>',
        _link(base_frame, f'<box size="{_xyz(length, max(width, 0.05), _BODY_HEIGHT)}"/>',
              origin=_xyz(0.0, 0.0, radius)),
    ]
    for wheel in wheels:
        link = f'wheel_{wheel.joint}'
        lines.append(_link(
            link, f'<cylinder radius="{wheel.radius:.4f}" length="{_WHEEL_WIDTH}"/>',
            rpy='1.5708 0 0', colour='0.1 0.1 0.1 1',
        ))
        lines.append(_joint(f'{link}_mount', 'fixed', base_frame, link,
                            _xyz(wheel.x, wheel.y, wheel.radius)))
    if gimbal is not None:
        px, py, pz = gimbal.pivot
        lines.append(_link(gimbal.yaw_frame, '<cylinder radius="0.06" length="0.04"/>',
                           colour='0.8 0.3 0.1 1'))
        lines.append(_joint('yaw', 'continuous', base_frame, gimbal.yaw_frame,
                            _xyz(px, py, pz), axis='0 0 1'))
        barrel = max(gimbal.barrel_length, 0.05)
        lines.append(_link(gimbal.pitch_frame, f'<box size="{_xyz(barrel, 0.03, 0.03)}"/>',
                           origin=_xyz(barrel / 2, 0.0, 0.0), colour='0.8 0.3 0.1 1'))
        lines.append(_joint('pitch', 'revolute', gimbal.yaw_frame, gimbal.pitch_frame,
                            '0 0 0', axis='0 1 0'))
        lines.append(f'  <link name={quoteattr(gimbal.muzzle_frame)}/>')
        lines.append(_joint('muzzle', 'fixed', gimbal.pitch_frame, gimbal.muzzle_frame,
                            _xyz(gimbal.barrel_length, 0.0, 0.0)))
    lines.append('</robot>')
    return '\n'.join(lines) + '\n'


def describe_host(host: Any) -> str | None:
    """The URDF of the robot a RobotHost runs, from its plugins' configs; None without a chassis.

    The chassis is the plugin whose config has wheel joints and their kinematics (wheels
    or swerve modules); the gimbal, the one with a pivot and frames.
    """
    wheels: list[WheelPlace] = []
    gimbal = None
    for name in host.plugin_names:
        config: Any = getattr(host.plugin(name), 'config', None)
        kinematics = getattr(config, 'wheels', None)
        if kinematics is not None and hasattr(config, 'wheel_joints'):
            places: Sequence[Any] = (
                getattr(kinematics, 'wheels', ()) or getattr(kinematics, 'modules', ()))
            wheels = [WheelPlace(joint, w.x, w.y, w.radius)
                      for joint, w in zip(config.wheel_joints, places, strict=False)]
        elif hasattr(config, 'pivot') and hasattr(config, 'frames'):
            frames = config.frames
            gimbal = GimbalPlace(frames.yaw, frames.pitch, frames.muzzle, tuple(config.pivot),
                                 config.barrel_length)
    if not wheels:
        return None
    return robot_description(host.get_name(), wheels, gimbal)
