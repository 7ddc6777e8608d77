"""CAN test rigs without ROS: the standard robot's hardware, or N synthetic motors, on
rm_sim channels that have no simulated motors, fed by a paced feedback generator.

Why no physics here: measurements 4 and 5 are about the bridge's own cost (update, pack,
send, decode, dispatch). With an empty rm_sim channel a sent frame is only counted, and
:class:`FeedbackFeeder` puts pre-built feedback frames straight into each bus's receive
queue (``SimBus._deliver``, what the channel does for a motor's frame), so neither motor
physics nor frame construction runs in the measured process beyond the feeder thread,
which is named ``bench-feeder`` and counted apart.
"""

from __future__ import annotations

import itertools
import logging
import struct
import threading
import time
from pathlib import Path
from typing import Any

import can

from rm_base import motors as motor_families

ROOT = Path(__file__).resolve().parents[1]
CONFIG_DIR = ROOT / 'rm_bringup' / 'config'
_channel_ids = itertools.count()


def quiet_logs() -> None:
    """Hold-at-zero and offline warnings of rigs are expected; keep them off the table."""
    logging.getLogger('rm_base').setLevel(logging.ERROR)


def standard_hardware() -> dict[str, Any]:
    """The standard robot's CanHardware config dict (standard.yaml + standard_sim.yaml)."""
    from rm_base.bridge.params import settings_from_parameters
    from rm_base.bridge.sim_process import TYPED, bridge_parameters

    flat = bridge_parameters(CONFIG_DIR / name for name in ('standard.yaml', 'standard_sim.yaml'))
    typed = {k: v for k, v in flat.items() if k in TYPED}
    settings = settings_from_parameters(typed, {k: v for k, v in flat.items() if k not in typed})
    return dict(settings.hardware)


def synthetic_hardware(motors: int, buses: int) -> dict[str, Any]:
    """``motors`` M3508 in velocity mode spread evenly over ``buses`` (<= 8 per bus)."""
    per_bus = -(-motors // buses)
    if per_bus > 8:
        raise ValueError(f'{motors} DJI C620 motors need at least {-(-motors // 8)} buses')
    joints = {}
    for i in range(motors):
        bus, esc_id = divmod(i, per_bus)
        joints[f'm{i}'] = {
            'type': 'm3508',
            'bus': f'can{bus}',
            'id': esc_id + 1,
            'velocity_pid': {'kp': 0.6, 'ki': 4.0, 'output_limit': 4.0, 'integral_limit': 1.5},
        }
    return {
        'buses': {f'can{b}': {'interface': 'rm_sim', 'bitrate': 1_000_000} for b in range(buses)},
        'joints': joints,
        'scheduler': {'rate_hz': 1000.0},
    }


class Rig:
    """A CanHardware whose buses sit on empty rm_sim channels of one stepped world."""

    def __init__(self, hardware: dict[str, Any]) -> None:
        from rm_base.hardware import CanHardware
        from rm_base.sim import SimWorld

        quiet_logs()
        self.world = SimWorld(timing='stepped')
        config = dict(hardware)
        buses = {}
        for name, bus in hardware['buses'].items():
            # channel names are process-wide: a fresh one per rig
            channel = f'bench{next(_channel_ids)}-{name}'
            self.world.add_channel(channel)
            options = {**bus.get('options', {}), 'world': self.world}
            buses[name] = {**bus, 'interface': 'rm_sim', 'channel': channel, 'options': options}
        config['buses'] = buses
        self.hw = CanHardware(config, families=motor_families)
        self.feeder: FeedbackFeeder | None = None

    def sim_bus(self, name: str) -> Any:
        """The python-can bus under a ManagedBus (opened)."""
        return self.hw.buses[name]._bus

    def feedback_frames(self, variants: int = 16) -> dict[str, list[list[can.Message]]]:
        """Per bus, per joint: ``variants`` realistic feedback frames (angle moving)."""
        out: dict[str, list[list[can.Message]]] = {}
        for actuator in self.hw.actuators.values():
            frames = []
            for k in range(variants):
                data = struct.pack('>HhhBx', (k * 511) % 8192, 300 + k, 200 - k, 35)
                frames.append(
                    can.Message(
                        arbitration_id=actuator.feedback_id,
                        data=data,
                        is_extended_id=False,
                        is_rx=True,
                    )
                )
            out.setdefault(actuator.bus_name, []).append(frames)
        return out

    def command_all(self, velocity: float = 5.0) -> None:
        """Velocity targets on every joint (they time out after the safety timeout)."""
        for name in self.hw.joint_names:
            self.hw.set_command(name, 2, velocity=velocity)

    def close(self) -> None:
        self.hw.shutdown()
        self.world.close()


class FeedbackFeeder:
    """Puts feedback frames into the rig's receive queues at a total rate, every 1 ms.

    Frames go round-robin over the joints (each joint its own frames, angle moving), so
    every joint sees ``rate / joints`` frames per second; every ``command_period_s`` the
    feeder also refreshes the joints' velocity targets (as /actuator_cmd would).
    """

    def __init__(self, rig: Rig, rate_hz: float, command_period_s: float = 0.01) -> None:
        self._rig = rig
        self.rate_hz = rate_hz
        self._command_period_s = command_period_s
        self.sent = 0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name='bench-feeder', daemon=True)

    def start(self) -> None:
        self._thread.start()

    def stop(self) -> None:
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join(timeout=5.0)

    def _run(self) -> None:
        frames = self._rig.feedback_frames()
        streams = []  # (deliver, frames of one joint)
        for bus, per_joint in frames.items():
            deliver = self._rig.sim_bus(bus)._deliver
            streams += [(deliver, joint_frames) for joint_frames in per_joint]
        n_streams = len(streams)
        t0 = time.perf_counter_ns()
        next_tick = t0
        next_command = t0
        while not self._stop.is_set():
            now = time.perf_counter_ns()
            due = int(self.rate_hz * (now - t0) / 1e9)
            sent = self.sent
            while sent < due:
                deliver, joint_frames = streams[sent % n_streams]
                deliver(joint_frames[(sent // n_streams) % len(joint_frames)])
                sent += 1
            self.sent = sent
            if now >= next_command:
                self._rig.command_all()
                next_command += int(self._command_period_s * 1e9)
            next_tick += 1_000_000
            delay = next_tick - time.perf_counter_ns()
            if delay > 0:
                time.sleep(delay / 1e9)
            elif delay < -50_000_000:
                next_tick = time.perf_counter_ns()
