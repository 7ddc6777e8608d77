"""The standard robot with a super-capacitor board, against the simulated referee, in lockstep.

rm_sim's board (rm_base.sim.supercap) draws from the referee's chassis output no more than
the limit the robot sends it and gives the wheels the rest from its capacitor; the referee
measures what the board draws. A burst (a /chassis_cmd power_limit above the referee's)
drives the wheels beyond the referee's 60 W from the capacitor, down to its reserve, and
then refills it; the referee sees no more than its limit throughout. A board that reports
an error, or goes silent, leaves the chassis on the referee's own budget (the buffer rule).
The board's config is README's "Super-capacitor" example, read from README.
"""

from __future__ import annotations

import pytest
from geometry_msgs.msg import Twist
from rm_base.hardware.protocols.supercap import CapError
from support.lockstep import LockstepRobot
from support.user_session import readme_yaml

from rm_msgs.msg import ChassisCmd, GimbalCmd, ShootCmd

pytestmark = [pytest.mark.ros]

COMMAND_HZ = 50.0
POWER_LIMIT = 60.0  # [W] standard_sim.yaml sim.referee
BUFFER_RESERVE = 20.0  # [J] standard.yaml chassis.power.buffer_reserve
RESERVE = 0.3  # README's supercap.reserve
BURST_W = 100.0  # README's supercap.burst_w
SNAPPY = {
    f'chassis.ramp.linear.{kind}_acceleration': 30.0 for kind in ('launch', 'normal', 'brake')
}
def readme_supercap() -> dict[str, object]:
    """README's "Super-capacitor" config, as flat can_bridge parameters."""
    table = readme_yaml('Super-capacitor')['can_bridge']['ros__parameters']['supercap']
    return {f'supercap.{key}': value for key, value in table.items()}


# README's board with a small capacitor: a burst reaches the reserve in about three seconds
CAP = {**readme_supercap(), 'sim.supercap.capacity_j': 200.0, 'sim.supercap.energy': 0.8}


def test_the_readme_config_is_the_one_tested():
    assert (CAP['supercap.bus'], CAP['supercap.reserve'], CAP['supercap.burst_w']) == (
        'can0', RESERVE, BURST_W)


def robot() -> LockstepRobot:
    r = LockstepRobot(overrides={'rm_robot': SNAPPY, 'can_bridge': CAP})
    r.publish('/gimbal_cmd', GimbalCmd(mode=GimbalCmd.RATE), rate_hz=COMMAND_HZ)
    r.publish('/shoot_cmd', ShootCmd(mode=ShootCmd.PASSIVE), rate_hz=COMMAND_HZ)
    r.publish('/chassis_cmd', ChassisCmd(mode=ChassisCmd.PASSIVE), rate_hz=COMMAND_HZ)
    r.run(1.5)  # the board's feedback clean for fault_clear_s (0.5 s)
    return r


def full_stick(r: LockstepRobot, power_limit: float) -> None:
    def stick() -> Twist:
        msg = Twist()
        msg.linear.x = 3.5 if int(r.t) % 2 == 0 else -3.5
        return msg

    r.publish('/chassis_cmd', ChassisCmd(mode=ChassisCmd.RAW, power_limit=power_limit),
              rate_hz=COMMAND_HZ)
    r.publish('/vel_cmd', stick, rate_hz=COMMAND_HZ)


class Meter:
    """Per 100 ms (the referee's period): the wheels' power, the referee's, the energy."""

    def __init__(self, r: LockstepRobot) -> None:
        self.r, self.cap, self.rules = r, r.world.supercap, r.world.referee.rules
        self.wheels: list[float] = []
        self.referee: list[float] = []
        self.energy: list[float] = []
        self.lowest_buffer = self.rules.buffer_j
        self._sum, self._n = 0.0, 0

    def tick(self) -> None:
        self._sum += self.cap.chassis_power_w
        self._n += 1
        self.lowest_buffer = min(self.lowest_buffer, self.rules.buffer_j)
        if self._n == 100:
            self.wheels.append(self._sum / 100)
            self.referee.append(self.rules.power_w)
            self.energy.append(self.cap.energy)
            self._sum, self._n = 0.0, 0

    def run(self, seconds: float) -> None:
        self.r.run(seconds, self.tick)


def test_a_burst_spends_the_capacitor_to_its_reserve_within_the_referees_limit():
    with robot() as r:
        state = r.bridge.hardware.supercap
        full_stick(r, power_limit=250.0)
        meter = Meter(r)
        meter.run(6.0)
        rules = r.world.referee.rules
        # the wheels drew well beyond the referee's limit, from the capacitor ...
        assert max(meter.wheels[:15]) > POWER_LIMIT + 0.5 * BURST_W, meter.wheels
        assert max(meter.wheels) < POWER_LIMIT + BURST_W + 15.0, meter.wheels  # model error
        # ... down to its reserve, then refilled it, drawing less than the limit
        low = min(meter.energy)
        assert RESERVE - 0.05 < low < RESERVE + 0.02, meter.energy
        assert meter.energy[-1] > low + 0.02, meter.energy
        after = meter.energy.index(low) + 3  # the next second: the referee's limit - 15 W
        assert max(meter.wheels[after:after + 10]) < POWER_LIMIT - 10.0, meter.wheels
        # and the referee saw no more than its limit: the buffer untouched, nothing cut
        assert max(meter.referee) <= POWER_LIMIT + 0.5, meter.referee
        assert meter.lowest_buffer >= 59.0
        assert (rules.chassis_cuts, rules.hp) == (0, 200)
        assert state.frames_decoded > 7000  # the board's 1 kHz, since the start


def test_without_a_request_above_the_limit_the_capacitor_is_kept():
    with robot() as r:
        full_stick(r, power_limit=0.0)  # the configured limit: the referee's
        meter = Meter(r)
        meter.run(3.0)
        assert min(meter.energy) >= 0.79, meter.energy
        assert max(meter.referee) <= POWER_LIMIT + 0.5, meter.referee


@pytest.mark.parametrize('fault', ['under_voltage', 'silent'])
def test_a_faulty_or_silent_board_leaves_the_chassis_on_the_referees_budget(fault):
    with robot() as r:
        cap = r.world.supercap
        if fault == 'silent':
            cap.online = False
        else:
            cap.errors = CapError.UNDER_VOLTAGE
        full_stick(r, power_limit=250.0)
        meter = Meter(r)
        meter.run(4.0)
        rules = r.world.referee.rules
        hardware = r.bridge.hardware
        assert hardware.supercap.state(r.world.time_ns).value == (
            'offline' if fault == 'silent' else 'fault')
        # the board passes the chassis' power through; the robot keeps to the buffer rule
        # (a burst's 160 W would empty the 60 J buffer in half a second: a chassis cut)
        assert meter.lowest_buffer >= BUFFER_RESERVE, meter.lowest_buffer
        assert rules.chassis_cuts == 0
        assert sum(meter.referee[-20:]) / 20 < POWER_LIMIT + 5.0, meter.referee
        # the fault gone, the capacitor is used again only after clean feedback
        cap.online, cap.errors = True, 0
        meter.run(0.3)
        assert hardware.supercap.state(r.world.time_ns).value == 'fault'
        meter.run(1.5)
        assert max(meter.wheels[-10:]) > POWER_LIMIT + 0.5 * BURST_W, meter.wheels
