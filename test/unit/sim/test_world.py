"""SimWorld: building from config, the clock, the registry, the real-time thread."""

import threading
import time

import can
import pytest
from rm_base.motors.dji import protocol as dji
from rm_base.sim import (
    SimBus,
    SimConfigError,
    SimLookupError,
    SimStateError,
    SimWorld,
    Timing,
    channel_names,
    find_channel,
    load_config,
)
from support.ros import wait_until

from .helpers import drain, unique_channel


def test_from_config_builds_channels_and_motors(make_world):
    can0, can1 = unique_channel(), unique_channel()
    world = make_world(
        {
            'tick_rate_hz': 500,
            'channels': {
                can0: [{'type': 'm3508', 'id': 1, 'name': 'wheel_fl'}],
                can1: [{'type': 'gm6020', 'id': 1, 'name': 'yaw'}],
            },
        }
    )
    assert world.timing is Timing.STEPPED
    assert world.period == pytest.approx(0.002)
    assert set(world.motors) == {'wheel_fl', 'yaw'}
    assert world.channel(can0).devices == [world.motor('wheel_fl')]
    assert find_channel(can1) is world.channel(can1)
    assert {can0, can1} <= set(channel_names())


def test_when_world_closed_expect_channel_names_released(make_world):
    name = unique_channel()
    world = make_world({'channels': {name: []}})
    world.close()
    world.close()  # idempotent
    assert find_channel(name) is None
    with pytest.raises(SimStateError, match='closed'):
        world.step()


def test_when_channel_owned_by_another_world_expect_config_error(make_world):
    name = unique_channel()
    make_world({'channels': {name: []}})
    with pytest.raises(SimConfigError, match='belongs to another simulated world'):
        make_world({'channels': {name: []}})


def test_when_config_fails_expect_partial_world_released():
    name = unique_channel()
    with pytest.raises(SimConfigError, match='unknown motor type'):
        SimWorld.from_config({'channels': {name: [{'type': 'nope', 'id': 1}]}})
    assert find_channel(name) is None


@pytest.mark.parametrize(
    ('config', 'message'),
    [
        ({'channel': {}}, r"unknown key\(s\) \['channel'\]"),
        ({'timing': 'fast'}, "timing must be 'realtime' or 'stepped'"),
        ({'tick_rate_hz': 1}, 'tick_rate_hz must be 10..100000'),
        ({'seed': 1.5}, 'seed must be an int'),
        ({'channels': ['can0']}, 'channels must map names'),
        ({'imus': {'path': '/tmp/x'}}, 'imus must be a list'),
    ],
)
def test_when_bad_world_config_expect_config_error(config, message):
    with pytest.raises(SimConfigError, match=message):
        SimWorld.from_config(config)


def test_step_and_advance_move_the_clock_in_ticks(make_world):
    world = make_world({})
    world.step(3)
    assert world.time_ns == 3_000_000
    world.advance(0.0104)  # rounds to 10 ticks
    assert world.time == pytest.approx(0.013)
    with pytest.raises(ValueError, match='n must be an int >= 0'):
        world.step(-1)
    with pytest.raises(ValueError, match='seconds must be finite'):
        world.advance(float('nan'))


def test_lookups_name_what_exists(make_world):
    world = make_world({'channels': {unique_channel(): [{'type': 'm3508', 'id': 1}]}})
    with pytest.raises(SimLookupError, match=r"no motor 'x'.*\['m3508_1'\]"):
        world.motor('x')
    with pytest.raises(SimLookupError, match="no channel 'x'"):
        world.channel('x')
    with pytest.raises(SimLookupError, match="no IMU 'imu'"):
        world.imu()


def test_stepped_world_has_no_physics_thread(make_world):
    with pytest.raises(SimStateError, match='no physics thread'):
        make_world({}).start()


@pytest.mark.realtime
def test_when_physics_raises_expect_on_error_hook_decides():
    errors = []

    def on_error(error):
        errors.append(error)
        return len(errors) < 3  # go on twice, then stop

    with SimWorld(on_error=on_error) as world:
        world.add_channel(unique_channel(), [{'type': 'm3508', 'id': 1, 'name': 'w'}])
        device = world.motor('w')

        def broken(now_ns, dt):
            raise RuntimeError('boom')

        device.control = broken
        world.start()
        assert wait_until(lambda: not world.running, timeout=10.0)
        assert len(errors) == 3
        assert isinstance(world.error, RuntimeError)


@pytest.mark.realtime
def test_realtime_world_advances_with_the_wall_clock():
    with SimWorld() as world:
        world.start()
        world.start()  # no-op while running
        assert wait_until(lambda: world.time >= 0.05, timeout=10.0)
        world.stop()
        stopped_at = world.time_ns
        world.step()  # stepping is allowed again once the thread is stopped
        assert world.time_ns == stopped_at + world.period_ns


@pytest.mark.realtime
def test_a_starved_realtime_world_lets_its_time_slip_and_counts_it():
    # Held off the CPU (here: the world lock, taken from outside) for 0.3 s, far beyond
    # the 50 ticks it catches up, the world skips ahead instead of bursting 300 ticks.
    with SimWorld() as world:
        world.start()
        assert wait_until(lambda: world.time_ns > 0, timeout=10.0)
        slips, slipped = world.overruns, world.slipped_ns
        with world.lock:
            time.sleep(0.3)
        assert wait_until(lambda: world.overruns > slips, timeout=10.0)
        assert world.slipped_ns - slipped >= 250_000_000  # the 0.3 s less its 50 ticks


@pytest.mark.realtime
def test_when_the_physics_tick_holds_the_lock_expect_send_not_to_wait():
    # A sender waiting for the world lock gives up the GIL and has to win it back; the
    # CAN scheduler lost most of its deadlines that way (bench/). The frame is handed to
    # the tick, which puts it on the bus before it releases the lock.
    channel = unique_channel()
    world = SimWorld()
    world.add_channel(channel, [{'type': 'm3508', 'id': 1, 'name': 'wheel'}])
    armed, in_tick, release = threading.Event(), threading.Event(), threading.Event()
    apply_loads = world.body.apply_loads

    def slow_apply_loads():
        if armed.is_set():
            in_tick.set()
            release.wait(5.0)
        apply_loads()

    world.body.apply_loads = slow_apply_loads
    sender = SimBus(channel, world=world)  # starts the physics thread
    listener = SimBus(channel, world=world, can_filters=[{'can_id': 0x200, 'can_mask': 0x7FF}])
    command = can.Message(
        arbitration_id=0x200, data=dji.pack_command([1000, 0, 0, 0]), is_extended_id=False
    )
    try:
        armed.set()
        assert in_tick.wait(5.0)  # the physics thread is in a tick, holding the lock
        started = time.monotonic()
        sent_at = time.time()
        sender.send(command)
        send_took = time.monotonic() - started
        on_bus_during_tick = listener.recv(timeout=0)
        time.sleep(0.3)  # the tick goes on (it lost the CPU)
        released_at = time.time()
        release.set()
        on_bus_after_tick = listener.recv(timeout=5.0)
    finally:
        release.set()
        listener.shutdown()
        sender.shutdown()
        world.close()
    assert send_took < 1.0  # the tick holds the lock for 5 s
    assert on_bus_during_tick is None
    assert on_bus_after_tick is not None and on_bus_after_tick.arbitration_id == 0x200
    # on the wire when it was sent, not when the tick let it go
    assert sent_at <= on_bus_after_tick.timestamp < released_at
    assert world.motor('wheel').command_raw == 1000


def test_same_config_gives_the_same_frames(make_world):
    def run():
        name = unique_channel()
        world = make_world(
            {
                'channels': {
                    name: [
                        {'type': 'm3508', 'id': 1, 'initial_velocity': 3.0},
                        {'type': 'dm4310', 'id': 2, 'enabled': True, 'initial_position': 0.3},
                    ]
                }
            }
        )
        with SimBus(name, world=world) as bus:
            world.step(50)
            return [(f.arbitration_id, bytes(f.data)) for f in drain(bus)]

    assert run() == run()


def test_load_config_reads_yaml(tmp_path):
    path = tmp_path / 'world.yaml'
    path.write_text('timing: stepped\nchannels:\n  can9: []\n')
    assert load_config(path) == {'timing': 'stepped', 'channels': {'can9': []}}
    (tmp_path / 'list.yaml').write_text('- 1\n')
    with pytest.raises(SimConfigError, match='does not hold a mapping'):
        load_config(tmp_path / 'list.yaml')
    with pytest.raises(SimConfigError, match='cannot read world config'):
        load_config(tmp_path / 'missing.yaml')
