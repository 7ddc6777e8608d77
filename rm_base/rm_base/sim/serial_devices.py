"""The simulated world's devices on serial ports: IMUs, the referee, the DR16, the image link.

Each tick the world asks them for their due frames (:meth:`SerialDevices.tick`, under the
world's lock: the IMUs and the referee read the body), then writes what was collected
after releasing the lock (:meth:`SerialDevices.take`, :meth:`SerialDevices.write`): a
terminal write is a system call that can take milliseconds on a loaded machine, and every
bus send waits for that lock. A ``sink`` takes the frames instead of the terminals
(lockstep: a terminal delivers to its reader asynchronously).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any

from rm_base.sim.body import RobotBody
from rm_base.sim.image_link import SimImageLink
from rm_base.sim.imu import SimImu, imu_from_config
from rm_base.sim.launcher import Shot
from rm_base.sim.operator_link import link_from_config
from rm_base.sim.referee import SimReferee, referee_from_config
from rm_base.sim.remote import SimRemote
from rm_base.sim_devices.errors import SimConfigError, SimLookupError, SimStateError

#: A simulated device on a serial port.
SerialDevice = SimImu | SimReferee | SimRemote | SimImageLink


class SerialDevices:
    """What the world has on serial ports (see the module docstring).

    Attributes:
        imus: IMUs by name.
        referee: the referee system, or None.
        remote: the DR16 receiver, or None.
        image_link: the image link (keyboard and mouse), or None.
        sink: None: every frame goes to its terminal; else ``sink(device, frame)``.
    """

    def __init__(self) -> None:
        self.imus: dict[str, SimImu] = {}
        self.referee: SimReferee | None = None
        self.remote: SimRemote | None = None
        self.image_link: SimImageLink | None = None
        self.sink: Callable[[SerialDevice, bytes], object] | None = None
        self._frames: list[tuple[SerialDevice, bytes]] = []

    # -- building (the world holds its lock) -----------------------------------------------

    def add_imu(self, config: Mapping[str, Any], body: RobotBody) -> SimImu:
        """An IMU (:func:`~rm_base.sim.imu.imu_from_config`) on the body.

        Raises:
            SimConfigError: invalid config or a name already used.
        """
        name = config.get('name', 'imu') if isinstance(config, Mapping) else None
        if name in self.imus:
            raise SimConfigError(f'two IMUs are named {name!r}')
        imu = imu_from_config(config, body)
        self.imus[imu.name] = imu
        return imu

    def imu(self, name: str) -> SimImu:
        """The IMU of that name. Raises: SimLookupError: none."""
        try:
            return self.imus[name]
        except KeyError:
            raise SimLookupError(f'no IMU {name!r}; IMUs: {sorted(self.imus)}') from None

    def set_body(self, body: RobotBody) -> None:
        """Mount the IMUs on a new body. Raises: SimStateError: a referee judges the old one."""
        if self.referee is not None:
            raise SimStateError('set the body before the referee (it judges the body)')
        for imu in self.imus.values():
            imu.body = body

    def set_referee(self, config: Mapping[str, Any], body: RobotBody) -> SimReferee:
        """The referee (:func:`~rm_base.sim.referee.referee_from_config`), judging body.

        The body's wheels are its chassis output, yaw and pitch its gimbal output, its
        shooter its shooter output.

        Raises:
            SimConfigError: invalid config.
            SimStateError: a referee exists already.
        """
        if self.referee is not None:
            raise SimStateError('the world has a referee already')
        gimbal = [j.device for j in (body.yaw_joint, body.pitch_joint) if j is not None]
        self.referee = referee_from_config(
            config, chassis=body.chassis.motors if body.chassis is not None else (),
            gimbal=gimbal, launcher=body.launcher,
        )
        return self.referee

    def set_remote(self, config: Mapping[str, Any]) -> SimRemote:
        """The DR16 receiver, ``{path}``. Raises: SimConfigError, SimStateError (a second)."""
        if self.remote is not None:
            raise SimStateError('the world has a DR16 receiver already')
        self.remote = link_from_config(SimRemote, config, 'remote')
        return self.remote

    def set_image_link(self, config: Mapping[str, Any]) -> SimImageLink:
        """The image link, ``{path}``. Raises: SimConfigError, SimStateError (a second)."""
        if self.image_link is not None:
            raise SimStateError('the world has an image link already')
        self.image_link = link_from_config(SimImageLink, config, 'image_link')
        return self.image_link

    # -- a tick ------------------------------------------------------------------------------

    def tick(self, now_ns: int, device_ns: int, dt: float, shots: Sequence[Shot]) -> None:
        """Collect the frames due at now_ns (the world's lock held).

        device_ns: the devices' own clock (the IMU's counter); shots: the projectiles
        the launcher fired this tick.
        """
        frames = self._frames
        for imu in self.imus.values():
            frame = imu.poll(now_ns, device_ns)
            if frame is not None:
                frames.append((imu, frame))
        referee = self.referee
        if referee is not None:
            for frame in referee.tick(now_ns, dt, shots):
                frames.append((referee, frame))
        for operator in (self.remote, self.image_link):
            if operator is not None:
                for frame in operator.tick(now_ns):
                    frames.append((operator, frame))

    def take(self) -> list[tuple[SerialDevice, bytes]]:
        """The frames collected so far (the world's lock held)."""
        frames, self._frames = self._frames, []
        return frames

    def write(self, frames: list[tuple[SerialDevice, bytes]]) -> None:
        """Write taken frames to their terminals, or hand them to the sink (lock released)."""
        sink = self.sink
        for device, frame in frames:
            if sink is None:
                device.write(frame)
            else:
                sink(device, frame)

    def close(self) -> None:
        """Close every terminal (idempotent)."""
        for imu in self.imus.values():
            imu.close()
        for device in (self.referee, self.remote, self.image_link):
            if device is not None:
                device.close()
