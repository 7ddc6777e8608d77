"""RefereeWatch: when the simulated referee had which joints unpowered, for the soak.

A bus-off while the trigger pushes leaves its ESC on the last current for the ESC's
command timeout, and the trigger then coasts: it fires shots nobody commanded, the referee
locks the launcher and may take all the HP (docs/RELIABILITY.md, "Shots nobody
commanded"). A destroyed robot, or a launcher locked for the match, would stay so for the
rest of a soak, with every later fault on it undetectable. The watch revives it at once
and keeps, per joint, when its output was off, so that faults then are not judged.
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable, Iterable, Mapping
from typing import Any

from rm_base.runtime.realtime import outside_robot


class RefereeWatch:
    """Samples the referee's power outputs of a real-time world; revives a destroyed robot.

    Args:
        world: a SimWorld with a referee.
        output_joints: the joints on each output (``chassis``, ``gimbal``, ``shooter``).
        period_s: how often the thread samples [s].
    """

    def __init__(
        self,
        world: Any,
        output_joints: Mapping[str, tuple[str, ...]],
        period_s: float = 0.02,
    ) -> None:
        if world.referee is None:
            raise ValueError('the world has no referee')
        self.world = world
        self.referee = world.referee
        self.output_joints = dict(output_joints)
        self.events: list[str] = []
        # joint -> [start, end] wall times its output was off (end inf: still off)
        self.off: dict[str, list[list[float]]] = {
            joint: [] for joints in self.output_joints.values() for joint in joints
        }
        self._period_s = period_s
        self._t0 = time.time()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name='soak-referee', daemon=True)

    def start(self) -> None:
        """Sample in a thread from now on."""
        self._thread.start()

    def stop(self) -> None:
        """Stop sampling; a window still open ends now."""
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join(timeout=5.0)
        now = time.time()
        for windows in self.off.values():
            if windows and windows[-1][1] == math.inf:
                windows[-1][1] = now

    def _run(self) -> None:
        with outside_robot():  # the test's, not the robot's (rm_base.runtime.realtime)
            while not self._stop.wait(self._period_s):
                self.sample(time.time())

    def sample(self, now: float) -> None:
        """Note which outputs are off at wall time now; revive a destroyed robot."""
        with self.world.lock:
            rules = self.referee.rules
            outputs = rules.outputs
            revive = rules.destroyed or rules.locked_for_match
            why = 'destroyed' if rules.destroyed else 'launcher locked for the match'
            heat, shots = rules.heat, rules.shots
            if revive:
                self.referee.revive()
        for port, joints in self.output_joints.items():
            off = not getattr(outputs, port)
            for joint in joints:
                windows = self.off[joint]
                is_open = bool(windows) and windows[-1][1] == math.inf
                if off and not is_open:
                    windows.append([now, math.inf])
                    is_open = True
                if is_open and (revive or not off):
                    windows[-1][1] = now
        if revive:
            self.events.append(
                f'{now - self._t0:.1f} s: {why} (heat {heat:.0f}, {shots} shots); revived'
            )
            print(f'[soak] referee: {self.events[-1]}', flush=True)

    def was_off(
        self, joints: tuple[str, ...], start: float, end: float, settle_s: float = 0.0
    ) -> bool:
        """Whether the referee had any of joints unpowered between start and end, or
        less than settle_s before start (they come back online after their output)."""
        return any(
            a <= end and start <= b + settle_s
            for joint in joints
            for a, b in self.off.get(joint, ())
        )

    def set_aside(
        self, records: Iterable[Any], joints_of: Callable[[str], tuple[str, ...]], settle_s: float
    ) -> None:
        """Turn each missed fault whose joints the referee had unpowered into not judged.

        An unpowered motor shows no temperature, no jam and no garbage. records: the soak's
        fault records (``target``, ``start``, ``end``, ``detected``, ``note``); joints_of:
        the joints a target stands for (a bus: its joints).
        """
        for rec in records:
            if rec.detected is False and self.was_off(
                joints_of(rec.target), rec.start, rec.end, settle_s
            ):
                rec.detected = None
                rec.note = 'its output was off by the referee (see referee in the report)'

    def summary(self) -> dict[str, Any]:
        """The report's ``referee`` section."""
        rules = self.referee.rules
        return {
            'revivals': rules.revivals,
            'events': self.events,
            'launcher_locks': rules.launcher_locks,
            'chassis_cuts': rules.chassis_cuts,
            'shots': rules.shots,
            'hp_at_end': rules.hp,
            'output_off_s': {
                joint: round(sum(b - a for a, b in windows), 1)
                for joint, windows in self.off.items()
                if windows
            },
        }
