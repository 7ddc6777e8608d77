"""SimBus: the python-can BusABC contract on a simulated channel shared by several buses."""

import json
import time

import can
import pytest
from rm_base.motors.dji import protocol as dji
from rm_base.sim import SimBus, SimStateError, SimWorld, find_channel
from support.ros import wait_until

from .helpers import drain, send, unique_channel

MOTOR = {'type': 'm3508', 'id': 1, 'name': 'wheel'}


def entry_point_installed() -> bool:
    from can.interfaces import BACKENDS

    return BACKENDS.get('rm_sim') == ('rm_base.sim.bus', 'SimBus')


@pytest.mark.skipif(
    not entry_point_installed(),
    reason="rm_base's can.interface entry point 'rm_sim' is not installed in this "
    'environment; run scripts/setup.sh and test under scripts/with_env.sh (make test)',
)
def test_can_bus_opens_rm_sim_through_the_entry_point():
    channel = unique_channel()
    with can.Bus(interface='rm_sim', channel=channel, motors=[MOTOR], timing='stepped') as bus:
        assert isinstance(bus, SimBus)
        assert bus.channel_info == f'rm_sim channel {channel}'
        bus.sim.step(5)
        assert len(drain(bus)) == 5


def test_buses_on_one_channel_see_each_others_frames(make_bus):
    a = make_bus()
    b = make_bus(channel=a.channel_id)
    send(a, 0x123, b'\x01\x02')
    (got,) = drain(b)
    assert (got.arbitration_id, bytes(got.data), got.is_rx) == (0x123, b'\x01\x02', True)
    assert got.channel == a.channel_id
    assert drain(a) == []  # receive_own_messages is off


def test_when_receive_own_messages_expect_echo_marked_tx(make_bus):
    a = make_bus(receive_own_messages=True)
    send(a, 0x123, b'\x01')
    (echo,) = drain(a)
    assert echo.arbitration_id == 0x123
    assert echo.is_rx is False


def test_every_bus_on_the_channel_gets_the_motor_feedback(make_bus):
    a = make_bus([MOTOR])
    b = make_bus(channel=a.channel_id)
    a.sim.step(3)
    assert len(drain(a)) == 3
    assert len(drain(b)) == 3


def test_buses_on_other_channels_see_nothing(make_bus):
    a = make_bus([MOTOR])
    b = make_bus()
    send(a, 0x200, dji.pack_command([1000]))
    a.sim.step(3)
    assert drain(b) == []


def test_when_filters_set_expect_only_matching_frames(make_bus):
    a = make_bus([MOTOR, {'type': 'm3508', 'id': 2}])
    b = make_bus(channel=a.channel_id, can_filters=[{'can_id': 0x202, 'can_mask': 0x7FF}])
    a.sim.step(4)
    assert {f.arbitration_id for f in drain(b)} == {0x202}
    b.set_filters(None)
    a.sim.step(1)
    assert {f.arbitration_id for f in drain(b)} == {0x201, 0x202}


def test_when_shut_down_twice_expect_no_error_and_closed_bus(make_bus):
    bus = make_bus([MOTOR])
    bus.shutdown()
    bus.shutdown()
    with pytest.raises(can.CanOperationError, match='closed'):
        send(bus, 0x200, bytes(8))
    with pytest.raises(can.CanOperationError, match='closed'):
        bus.recv(timeout=0)


def test_when_last_bus_of_a_bus_built_world_shuts_down_expect_world_closed():
    channel = unique_channel()
    a = SimBus(channel, motors=[MOTOR], timing='stepped')
    b = SimBus(channel)
    world = a.sim
    a.shutdown()
    assert not world.closed
    b.shutdown()
    assert world.closed
    assert find_channel(channel) is None


def test_when_bus_joins_an_explicit_world_expect_world_outlives_it():
    with SimWorld(timing='stepped') as world:
        channel = unique_channel()
        with SimBus(channel, world=world, motors=[MOTOR]) as bus:
            assert bus.sim is world
            world.step()
            assert len(drain(bus)) == 1
        assert not world.closed
        assert world.motor('wheel').name == 'wheel'


def test_when_bus_off_injected_expect_send_error_and_silence(make_bus):
    bus = make_bus([MOTOR])
    bus.sim_channel.set_state(can.BusState.ERROR)
    assert bus.state is can.BusState.ERROR
    with pytest.raises(can.CanOperationError, match='bus-off'):
        send(bus, 0x200, dji.pack_command([1000]))
    bus.sim.step(5)
    assert drain(bus) == []
    assert bus.sim.motor('wheel').command_raw == 0
    bus.sim_channel.set_state(can.BusState.ACTIVE)
    assert bus.state is can.BusState.ACTIVE
    send(bus, 0x200, dji.pack_command([1000]))
    bus.sim.step(1)
    assert len(drain(bus)) == 1
    assert bus.sim_channel.stats.lost == 6  # one refused send and five feedback frames


def test_when_error_passive_injected_expect_state_but_traffic(make_bus):
    bus = make_bus([MOTOR])
    bus.sim_channel.set_state(can.BusState.PASSIVE)
    assert bus.state is can.BusState.PASSIVE
    bus.sim.step(2)
    assert len(drain(bus)) == 2


def test_bus_state_cannot_be_set_on_the_bus(make_bus):
    bus = make_bus()
    with pytest.raises(NotImplementedError, match='set_state'):
        bus.state = can.BusState.PASSIVE


def test_when_receive_queue_full_expect_new_frames_dropped_and_counted(make_bus):
    bus = make_bus([MOTOR], rx_queue_size=10)
    bus.sim.step(25)
    assert len(drain(bus)) == 10
    assert bus.rx_overflows == 15


FOUR_MOTORS = [{'type': 'm3508', 'id': i, 'name': f'wheel{i}'} for i in (1, 2, 3, 4)]


def test_when_queue_fills_within_one_tick_expect_the_first_frames_kept_in_order(make_bus):
    # Four feedback frames a tick (0x201..0x204) into room for six: the second tick's
    # first two fit, its last two are dropped.
    bus = make_bus(FOUR_MOTORS, rx_queue_size=6)
    bus.sim.step(2)
    ids = [f.arbitration_id for f in drain(bus)]
    assert ids == [0x201, 0x202, 0x203, 0x204, 0x201, 0x202]
    assert bus.rx_overflows == 2


def test_when_a_subclass_overrides_deliver_expect_every_motor_frame_through_it(make_bus):
    seen = []

    class Tap(SimBus):
        def _deliver(self, msg):
            seen.append(msg.arbitration_id)

    bus = make_bus(FOUR_MOTORS)
    tap = Tap(bus.channel_id, world=bus.sim)
    try:
        bus.sim.step(1)
    finally:
        tap.shutdown()
    assert seen == [0x201, 0x202, 0x203, 0x204]


def test_when_a_tick_delivers_four_frames_expect_one_notify_waking_four_readers(make_bus):
    bus = make_bus(FOUR_MOTORS)
    wakes = []
    condition = bus._queue.not_empty
    notify = condition.notify
    condition.notify = lambda n=1: (wakes.append(n), notify(n))
    bus.sim.step(2)
    assert wakes == [4, 4]  # as four put()s would wake up to four readers, once a tick


def test_detect_available_configs_lists_open_channels(make_bus):
    bus = make_bus()
    configs = SimBus._detect_available_configs()
    assert {'interface': 'rm_sim', 'channel': bus.channel_id} in configs


def test_when_same_motor_list_passed_again_expect_shared_motor(make_bus):
    a = make_bus([MOTOR])
    b = make_bus([MOTOR], channel=a.channel_id)
    assert len(b.sim_channel.devices) == 1


def test_when_conflicting_motor_passed_expect_initialization_error(make_bus):
    a = make_bus([MOTOR])
    with pytest.raises(can.CanInitializationError, match="already named 'wheel'"):
        SimBus(a.channel_id, motors=[{**MOTOR, 'id': 2}])


def test_when_conflicting_timing_expect_initialization_error(make_bus):
    a = make_bus()
    with pytest.raises(can.CanInitializationError, match='timing stepped'):
        SimBus(a.channel_id, timing='realtime')


def test_when_preserve_timestamps_expect_sender_stamp(make_bus):
    a = make_bus(preserve_timestamps=True)
    b = make_bus(channel=a.channel_id)
    a.send(can.Message(arbitration_id=1, data=b'', timestamp=12.5, is_extended_id=False))
    assert drain(b)[0].timestamp == 12.5


def test_when_world_config_file_given_expect_buses_share_one_world(tmp_path):
    can0, can1 = unique_channel(), unique_channel()
    config = {
        'timing': 'stepped',
        'channels': {can0: [MOTOR], can1: [{'type': 'gm6020', 'id': 1, 'name': 'yaw'}]},
    }
    path = tmp_path / 'world.json'
    path.write_text(json.dumps(config))
    a = SimBus(can0, world=str(path))
    b = SimBus(can1, world=str(path))
    try:
        assert a.sim is b.sim
        a.sim.step(2)
        assert {f.arbitration_id for f in drain(a)} == {0x201}
        assert {f.arbitration_id for f in drain(b)} == {0x205}
    finally:
        a.shutdown()
        b.shutdown()
    assert a.sim.closed


@pytest.mark.realtime
def test_realtime_bus_receives_feedback_from_the_physics_thread():
    with SimBus(unique_channel(), motors=[MOTOR]) as bus:
        assert bus.sim.running
        with pytest.raises(SimStateError, match='owns the clock'):
            bus.sim.step()
        frames = []
        # Generous: 20 frames take 20 ms on an idle machine.
        assert wait_until(lambda: frames.extend(drain(bus)) or len(frames) >= 20, timeout=10.0)
        assert all(f.arbitration_id == 0x201 for f in frames)
        stamps = [f.timestamp for f in frames]
        assert stamps == sorted(stamps)
        assert abs(stamps[-1] - time.time()) < 10.0  # wall-clock stamps in real time
        world = bus.sim
    assert not world.running
    assert world.closed
