"""CanHardware against the simulator's CAN interface (rm_sim), stepped in lockstep.

The same bus config works with ``can.Bus(interface='rm_sim')`` once rm_base is installed
(entry point); here the SimBus class is handed in through ``bus_factory`` so the test does
not depend on the installed entry points, and the world is stepped by the test.
"""

import pytest
from rm_base.hardware import MODE_EFFORT, MODE_MIT, CanHardware
from rm_base.sim.world import SimWorld
from support.hardware import FakeClock, sim_factory, wait_fresh

from rm_base import motors as motor_families


@pytest.fixture
def world(channel):
    w = SimWorld(timing='stepped')
    w.add_channel(
        channel,
        [{'type': 'm3508', 'id': 1, 'name': 'wheel'}, {'type': 'dm4310', 'id': 2, 'name': 'arm'}],
    )
    yield w
    w.close()


def test_effort_and_native_mit_against_simulated_motors(channel, world):
    clock = FakeClock()
    cfg = {
        'buses': {
            'can0': {
                'interface': 'rm_sim',
                'channel': channel,
                'options': {'world': world},
                'receive_timeout_s': 0.01,
            }
        },
        'joints': {
            'wheel': {'type': 'm3508', 'bus': 'can0', 'id': 1},
            'arm': {'type': 'dm4310', 'bus': 'can0', 'id': 2},  # master id 0x12 in both
        },
    }
    hw = CanHardware(
        cfg, clock_ns=clock, bus_factory=sim_factory, receive_in_loop=False,
        families=motor_families,
    )
    with hw:
        hw.open()
        world.step(1)
        for _ in range(1000):  # 1 s at 1 kHz
            now = clock.advance_ms(1)
            hw.set_command('wheel', MODE_EFFORT, effort=0.3)
            hw.set_command('arm', MODE_MIT, position=0.5, kp=5.0, kd=0.3)
            hw.tick(now)
            world.step(1)
            wait_fresh(hw, now)
        wheel, arm = hw.states()
    # the wheel turns forward under a constant forward effort
    assert wheel.online and wheel.velocity > 1.0 and wheel.position > 0.5
    assert wheel.effort == pytest.approx(0.3, abs=0.05)
    # the Damiao was enabled by the layer and holds the MIT target on its own
    assert arm.online and arm.error_code == 0
    assert arm.position == pytest.approx(0.5, abs=0.05)
    diag = hw.diagnostics()
    assert diag['buses']['can0'].send_errors == 0
    assert diag['joints']['arm']['decode_errors'] == 0


def _velocity_run(channel, world, velocity_pid):
    """A wheel in velocity mode at 10 rad/s for 0.6 s; (velocity at 0.1 s, at the end)."""
    from rm_base.hardware import MODE_VELOCITY

    clock = FakeClock()
    cfg = {
        'buses': {'can0': {'interface': 'rm_sim', 'channel': channel,
                           'options': {'world': world}, 'receive_timeout_s': 0.01}},
        'joints': {'wheel': {'type': 'm3508', 'bus': 'can0', 'id': 1,
                             'velocity_pid': velocity_pid}},
    }
    hw = CanHardware(
        cfg, clock_ns=clock, bus_factory=sim_factory, receive_in_loop=False,
        families=motor_families,
    )
    early = None
    with hw:
        hw.open()
        world.step(1)
        for tick in range(600):
            now = clock.advance_ms(1)
            hw.set_command('wheel', MODE_VELOCITY, velocity=10.0)
            hw.tick(now)
            world.step(1)
            wait_fresh(hw, now)
            if tick == 100:
                early = hw.states()[0].velocity
        return early, hw.states()[0].velocity


def test_a_joint_can_run_its_velocity_loop_as_an_incremental_pid_with_a_td(channel, world):
    positional = _velocity_run(channel, world, {'kp': 0.3, 'ki': 2.0, 'output_limit': 3.0})
    world.motor('wheel').model.reset()
    incremental = _velocity_run(channel, world, {
        'form': 'incremental', 'kp': 0.3, 'ki': 2.0, 'output_limit': 3.0,
        'td_acceleration_limit': 500.0,  # the setpoint: 10 rad/s in 0.28 s, 2.5 at 0.1 s
    })
    # both forms settle on the target
    assert positional[1] == pytest.approx(10.0, abs=0.3)
    assert incremental[1] == pytest.approx(10.0, abs=0.3)
    # the TD makes the incremental loop's start a ramp: at 0.1 s about a quarter of the way
    assert positional[0] > 8.0
    assert 1.0 < incremental[0] < 5.0
