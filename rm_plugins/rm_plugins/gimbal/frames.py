"""The gimbal's frames: base_link -> yaw -> pitch from its joints, and what is mounted on it.

``base -> yaw_link`` is the yaw joint's rotation about z at the pivot (where the yaw and
pitch axes cross), ``yaw_link -> pitch_link`` the pitch joint's rotation about y (REP 103:
positive pitches the barrel down), both at the pivot. The muzzle sits ``barrel_length``
along pitch_link's x; other mounts (a camera, the IMU) are static transforms from the
config (``frames.mounts``). No ROS here beyond the parameters.
"""

from __future__ import annotations

from dataclasses import dataclass

from rm_base.geometry.transforms import SE3
from rm_base.plugin import PluginConfigError, PluginParams
from rm_base.plugin.frames import Link


@dataclass(frozen=True)
class Mount:
    """A frame fixed to another: child's pose in parent."""

    parent: str
    child: str
    transform: SE3


@dataclass(frozen=True)
class FramesConfig:
    """Names and mounts of the gimbal's frames.

    Attributes:
        base, yaw, pitch, muzzle: frame ids.
        rate: how often the joint frames are sent [Hz] (and at every TRACK command that
            names another frame of the tree).
        mounts: static frames, the muzzle first.
    """

    base: str
    yaw: str
    pitch: str
    muzzle: str
    rate: float
    mounts: tuple[Mount, ...]


def read_frames(p: PluginParams, base: str, barrel_length: float) -> FramesConfig:
    """Declare and read ``frames.*``.

    Raises:
        ParameterError: a value is missing or out of bounds.
        PluginConfigError: two frames share a name, or a mount's parent is unknown.
    """
    f = p.group('frames')
    yaw = f.string('yaw', 'yaw_link', description='frame of the yaw joint, at the pivot')
    pitch = f.string('pitch', 'pitch_link', description='frame of the pitch joint, at the pivot')
    muzzle = f.string('muzzle', 'muzzle', description='frame at the muzzle, barrel_length along x')
    rate = f.double('rate', 100.0, gt=0.0, unit='Hz', description='joint frames sent this often')
    names = f.string_array(
        'mounts', (), unique=True,
        description='static frames on the gimbal or chassis; each has frames.<name>.*',
    )
    mounts = [Mount(pitch, muzzle, SE3.from_translation_rpy((barrel_length, 0.0, 0.0), 0, 0, 0))]
    known = [base, yaw, pitch, muzzle]
    for name in names:
        m = f.group(name)
        parent = m.string('parent', description=f'frame {name} is fixed to')
        xyz = m.vector3('xyz', (0.0, 0.0, 0.0), unit='m', description=f'{name} in its parent')
        rpy = m.vector3('rpy', (0.0, 0.0, 0.0), unit='rad', description=f'{name} roll, pitch, yaw')
        if parent not in known:
            raise PluginConfigError(
                f'frames.{name}.parent is {parent!r}, not one of {", ".join(known)}'
            )
        known.append(name)
        mounts.append(Mount(parent, name, SE3.from_translation_rpy(xyz, *rpy)))
    if len(set(known)) != len(known):
        raise PluginConfigError(f'gimbal frames must have distinct names, got {", ".join(known)}')
    return FramesConfig(base, yaw, pitch, muzzle, rate, tuple(mounts))


def joint_links(
    frames: FramesConfig, pivot: tuple[float, float, float], yaw: float, pitch: float
) -> tuple[Link, Link]:
    """``base -> yaw`` and ``yaw -> pitch`` at joint angles yaw, pitch [rad]."""
    return (
        (frames.base, frames.yaw, SE3.from_translation_rpy(pivot, 0.0, 0.0, yaw)),
        (frames.yaw, frames.pitch, SE3.from_translation_rpy((0.0, 0.0, 0.0), 0.0, pitch, 0.0)),
    )


def mount_links(frames: FramesConfig) -> tuple[Link, ...]:
    """The static frames as links."""
    return tuple((m.parent, m.child, m.transform) for m in frames.mounts)
