"""rm_sim over a socket: the wire format, and a bus in this process on a world served here."""

from __future__ import annotations

import os
import struct
import tempfile

import can
import pytest
from hypothesis import given
from hypothesis import strategies as st
from rm_base.motors.dji import protocol as dji
from rm_base.sim import SimWorld, wire
from rm_base.sim.server import SimServer
from rm_base.sim.socket_bus import SimSocketBus
from support.ros import wait_until

from rm_base import motors as motor_families

WAIT = 5.0  # [s]


@given(
    st.lists(
        st.tuples(
            st.booleans(),
            st.integers(0, 0x1FFFFFFF),
            st.binary(max_size=8),
        ),
        max_size=20,
    ),
    st.floats(0.0, 2e9, allow_nan=False),
)
def test_frames_and_their_timestamp_survive_the_round_trip(frames, stamp):
    msgs = [
        can.Message(arbitration_id=i if ext else i & 0x7FF, is_extended_id=ext, data=d)
        for ext, i, d in frames
    ]
    back = wire.decode(wire.encode(msgs, stamp), 'can0')
    assert [(m.arbitration_id, m.is_extended_id, bytes(m.data)) for m in back] == [
        (m.arbitration_id, m.is_extended_id, bytes(m.data)) for m in msgs
    ]
    assert all(m.timestamp == stamp and m.channel == 'can0' for m in back)


def test_a_frame_is_a_socketcan_can_frame():
    msg = can.Message(arbitration_id=0x1FF, data=b'\x01\x02', is_extended_id=False)
    datagram = wire.encode([msg], 1.5)
    assert datagram[:8] == struct.pack('<d', 1.5)
    assert datagram[8:] == struct.pack('=IB3x8s', 0x1FF, 2, b'\x01\x02')


@pytest.mark.parametrize(
    ('datagram', 'message'),
    [
        (b'\x00' * 7, r'8 \+ n x 16 bytes; got 7'),
        (b'\x00' * 8 + b'\x00' * 15, r'got 23 bytes'),
        (b'\x00' * 8 + struct.pack('=IB3x8s', 0x200, 9, b''), 'length 9'),
    ],
)
def test_a_bad_datagram_is_refused_naming_what_is_wrong(datagram, message):
    with pytest.raises(wire.WireError, match=message):
        wire.decode(datagram)


def test_fd_frames_are_refused():
    with pytest.raises(wire.WireError, match='only classic CAN'):
        wire.encode([can.Message(arbitration_id=1, is_fd=True, data=bytes(12))], 0.0)


@pytest.fixture
def served():
    """A stepped world with one M3508 on channel 'can0', served on a socket."""
    folder = tempfile.mkdtemp(prefix='rm_sim_sock_')
    path = os.path.join(folder, 'can.sock')
    world = SimWorld(timing='stepped')
    world.add_channel('can0', [{'type': 'm3508', 'id': 1, 'name': 'wheel'}])
    server = SimServer(world, path)
    server.start()
    yield world, path, server
    server.stop()
    world.close()
    os.rmdir(folder)


def test_feedback_of_a_tick_arrives_on_the_bus(served):
    world, path, _ = served
    bus = SimSocketBus('can0', socket=path)
    try:
        assert wait_until(lambda: world.channel('can0').bus_count == 1, WAIT)
        world.step(1)
        msg = bus.recv(WAIT)
        assert msg is not None and msg.arbitration_id == 0x201  # the M3508 with id 1
        assert msg.timestamp == pytest.approx(world.timestamp())
    finally:
        bus.shutdown()


def test_a_current_command_turns_the_motor(served):
    world, path, _ = served
    bus = SimSocketBus('can0', socket=path)
    try:
        group, _ = dji.command_slot('c620', 1)  # 0x200, first slot
        frame = dji.pack_command([8000, 0, 0, 0])  # 8000 of 16384: about 10 A
        bus.send(can.Message(arbitration_id=group, data=frame, is_extended_id=False))
        assert wait_until(lambda: world.channel('can0').stats.sent == 1, WAIT)
        world.step(50)
        assert world.motor('wheel').model.velocity > 1.0
    finally:
        bus.shutdown()


def test_an_unknown_channel_is_refused_at_open(served):
    _, path, _ = served
    with pytest.raises(can.CanInitializationError, match='can9'):
        SimSocketBus('can9', socket=path)


def test_nobody_listening_is_refused_at_open(tmp_path):
    with pytest.raises(can.CanInitializationError, match='rm_sim at'):
        SimSocketBus('can0', socket=str(tmp_path / 'none.sock'))


def test_when_bus_off_is_injected_expect_send_to_fail_until_it_is_cleared(served):
    world, path, _ = served
    bus = SimSocketBus('can0', socket=path)
    try:
        world.channel('can0').set_state(can.BusState.ERROR)
        bus.send(can.Message(arbitration_id=0x200, data=bytes(8), is_extended_id=False))
        assert wait_until(lambda: bus.recv(0.0) is None and bus.state is can.BusState.ERROR, WAIT)
        with pytest.raises(can.CanOperationError, match='bus-off'):
            bus.send(can.Message(arbitration_id=0x200, data=bytes(8), is_extended_id=False))
        world.channel('can0').set_state(can.BusState.ACTIVE)
        world.step(1)  # the motor's feedback: the bus is back
        assert wait_until(lambda: bus.recv(0.0) is not None, WAIT)
        assert bus.state is can.BusState.ACTIVE
    finally:
        bus.shutdown()


def test_a_ticks_frames_go_to_rm_sim_in_one_datagram_per_bus(served):
    from rm_base.hardware import CanHardware

    world, path, server = served
    world.add_motor('can0', {'type': 'gm6020', 'id': 1, 'name': 'yaw'})
    hw = CanHardware({
        'buses': {'can0': {'interface': 'rm_sim_socket', 'channel': 'can0',
                           'options': {'socket': path}}},
        'joints': {'wheel': {'type': 'm3508', 'bus': 'can0', 'id': 1},
                   'yaw': {'type': 'gm6020', 'bus': 'can0', 'id': 1}},
    }, families=motor_families)
    try:
        hw.open()
        assert wait_until(lambda: world.channel('can0').bus_count == 1, WAIT)
        sent, datagrams = world.channel('can0').stats.sent, server.datagrams
        hw.tick()  # two frames: the C620 group (0x200) and the GM6020 group (0x1FF)
        assert wait_until(lambda: world.channel('can0').stats.sent == sent + 2, WAIT)
        assert server.datagrams == datagrams + 1
        assert hw.buses['can0'].stats().frames_sent == 2
    finally:
        hw.shutdown()
