"""Simulated motor drivers on a CAN bus: the shared device base.

Each device owns a :class:`~rm_base.sim_devices.motor.MotorModel` and behaves on the bus like the
real driver, using the device side of its family's protocol for every byte; the devices
are in the family folders (``rm_base.motors.<family>.sim_device``), built from config
dicts by :mod:`rm_base.sim.device_config` through the family registry.

Frames a device cannot use (wrong length, remote/extended/FD frames, a control frame for
another mode, undecodable values) are ignored and counted in :attr:`SimDevice.stats`.

The public methods are on :class:`SimDevice` (``receive``, ``control``, ``step``, ``emit``,
``inject``/``clear_faults``); each family implements the protected hooks.
"""

from __future__ import annotations

import math
import random
from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import Any, ClassVar

from rm_base.hardware.errors import ProtocolError, ValueRangeError
from rm_base.sim_devices.faults import Fault, FaultKind
from rm_base.sim_devices.motor import MotorModel
from rm_base.sim_devices.motor_params import MotorType
from rm_base.sim_devices.schedule import RateSchedule

#: A frame a device sends: (11-bit arbitration id, data bytes).
Frame = tuple[int, bytes]

NS_PER_S = 1_000_000_000
STD_ID_MAX = 0x7FF  # largest 11-bit arbitration id


@dataclass
class DeviceStats:
    """Frame counters of one device (monotonic).

    Attributes:
        rx_frames: frames addressed to the device and used.
        ignored_frames: frames addressed to the device but unusable (malformed, wrong
            mode, remote/extended/FD, or a control frame while the motor cannot act on it).
        tx_frames: feedback and reply frames sent.
        garbage_frames: random frames sent by a GARBAGE fault.
        timeouts: times the command timeout cut the output.
    """

    rx_frames: int = 0
    ignored_frames: int = 0
    tx_frames: int = 0
    garbage_frames: int = 0
    timeouts: int = 0


class SimDevice(ABC):
    """One simulated motor with its driver, as seen on the CAN bus.

    Attributes:
        name: unique name in the world (``'wheel_fl'``).
        motor_type: the simulated motor type (``'m3508'``...; a MotorType for the
            built-in families).
        motor_id: the id set on the device (ESC id / CAN id).
        model: the physics.
        stats: frame counters.
        overtemp_c: winding temperature above which the driver cuts the output [°C], or
            None for no cut-out.
        powered: False while the supply port feeding it is off (the referee cut it): it
            neither receives nor sends and its rotor coasts (:meth:`set_powered`).
    """

    #: Several devices take their commands from one frame (DJI groups, a slot each).
    shares_command_frames: ClassVar[bool] = False

    def __init__(
        self,
        name: str,
        motor_type: MotorType | str,
        motor_id: int,
        model: MotorModel,
        *,
        seed: int = 0,
        overtemp_c: float | None = None,
    ):
        self.name = name
        self.motor_type = motor_type
        self.motor_id = motor_id
        self.model = model
        self.stats = DeviceStats()
        self.overtemp_c = overtemp_c
        self.powered = True
        #: The config dict the device was built from, if any.
        self.config: dict[str, Any] | None = None
        self._faults: dict[FaultKind, Fault] = {}
        self._garbage: RateSchedule | None = None
        self._rng = random.Random(seed)

    # -- routing -------------------------------------------------------------------------

    @property
    @abstractmethod
    def listen_ids(self) -> frozenset[int]:
        """Standard ids of the frames this device reads."""

    @property
    @abstractmethod
    def transmit_ids(self) -> frozenset[int]:
        """Standard ids of the frames this device sends (feedback / replies)."""

    # -- public API (called by the channel / world) --------------------------------------

    @property
    def faults(self) -> dict[FaultKind, Fault]:
        """Active faults by kind (a copy)."""
        return dict(self._faults)

    @property
    def online(self) -> bool:
        """False while unpowered or an OFFLINE fault is active."""
        return self.powered and FaultKind.OFFLINE not in self._faults

    def set_powered(self, on: bool) -> None:
        """Switch the device's supply; off, the winding carries no current."""
        self.powered = on
        if not on:
            self.model.command_current(0.0)

    def receive(
        self,
        arbitration_id: int,
        data: bytes,
        now_ns: int,
        *,
        is_extended_id: bool = False,
        is_remote_frame: bool = False,
        is_fd: bool = False,
    ) -> list[Frame]:
        """Hand the device a frame seen on the bus; return the frames it answers with.

        Args:
            arbitration_id: the frame's id.
            data: the frame's data bytes.
            now_ns: simulation time [ns].
            is_extended_id: 29-bit frame (the real drivers only read 11-bit frames).
            is_remote_frame: remote (RTR) frame.
            is_fd: CAN FD frame (the real drivers are classic CAN only).

        Returns:
            Reply frames, possibly none.
        """
        if (
            not self.powered
            or (self._faults and not self.online)
            or arbitration_id not in self.listen_ids
        ):
            return []
        if is_extended_id or is_remote_frame or is_fd:
            self.stats.ignored_frames += 1
            return []
        try:
            replies = self._on_frame(arbitration_id, bytes(data), now_ns)
        except ProtocolError:
            self.stats.ignored_frames += 1
            return []
        if replies is None:
            self.stats.ignored_frames += 1
            return []
        self.stats.rx_frames += 1
        self.stats.tx_frames += len(replies)
        return replies

    def control(self, now_ns: int, dt: float) -> None:
        """Run the driver's own logic before a physics step (timeouts, internal loops)."""
        if self.powered:
            self._control(now_ns, dt)

    def step(self, dt: float, stator_acceleration: float = 0.0) -> None:
        """Advance the physics by dt [s] (see :meth:`MotorModel.step`)."""
        self.model.step(dt, stator_acceleration=stator_acceleration)

    def emit(self, now_ns: int) -> list[Frame]:
        """Return the frames the device sends on its own at this tick (feedback, garbage)."""
        faults = self._faults  # usually empty: skip the enum lookups then
        if not self.powered or (faults and not self.online):
            return []
        frames = self._periodic(now_ns)
        if frames:
            self.stats.tx_frames += len(frames)
        garbage = faults.get(FaultKind.GARBAGE) if faults else None
        if garbage is not None and self._garbage is not None and self._garbage.due(now_ns):
            if garbage.can_id is not None:
                can_id = garbage.can_id
            elif garbage.random_ids:
                can_id = self._rng.randrange(STD_ID_MAX + 1)
            else:
                can_id = min(self.transmit_ids)
            frames.append((can_id, self._rng.randbytes(8)))
            self.stats.garbage_frames += 1
        return frames

    def inject(self, fault: Fault) -> None:
        """Activate a fault (replacing one of the same kind); it acts from the next tick."""
        self._faults[fault.kind] = fault
        if fault.kind is FaultKind.JAM:
            self.model.locked = fault.load_torque is None
            self.model.brake_torque = fault.load_torque or 0.0
        elif fault.kind is FaultKind.OVER_TEMPERATURE:
            self.model.temperature_override = fault.temperature
            self.model.temperature = fault.temperature
        elif fault.kind is FaultKind.GARBAGE:
            self._garbage = RateSchedule(fault.rate_hz)

    def clear_faults(self, kind: FaultKind | None = None) -> None:
        """Remove one kind of fault, or all of them (None).

        The temperature is not reset: after an over-temperature it cools down from the
        forced value through the thermal model.
        """
        kinds = list(self._faults) if kind is None else [kind]
        for k in kinds:
            self._faults.pop(k, None)
            if k is FaultKind.JAM:
                self.model.locked = False
                self.model.brake_torque = 0.0
            elif k is FaultKind.OVER_TEMPERATURE:
                self.model.temperature_override = None
            elif k is FaultKind.GARBAGE:
                self._garbage = None

    @property
    def overheated(self) -> bool:
        """True while the winding is above the driver's cut-out temperature."""
        return self.overtemp_c is not None and self.model.temperature > self.overtemp_c

    # -- hooks -----------------------------------------------------------------------------

    @abstractmethod
    def _on_frame(self, arbitration_id: int, data: bytes, now_ns: int) -> list[Frame] | None:
        """Use a frame on one of :attr:`listen_ids`; return replies, or None to ignore it.

        Raises:
            ProtocolError: the bytes cannot be decoded (the frame is then ignored).
        """

    def _control(self, now_ns: int, dt: float) -> None:  # noqa: B027 (optional hook)
        """Per-tick driver logic before the physics step; nothing by default."""

    @abstractmethod
    def _periodic(self, now_ns: int) -> list[Frame]:
        """Frames the device sends unasked at this tick."""



def require_finite(values: tuple[float, ...]) -> None:
    """Refuse a decoded command with a NaN or infinite value (the device ignores it)."""
    if not all(math.isfinite(v) for v in values):
        raise ValueRangeError(f'non-finite value in command {values!r}')
