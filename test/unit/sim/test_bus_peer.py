"""rm_sim's channels on python-can buses (socketcan on a robot's kernel; here python-can's
own virtual interface, which behaves as a kernel bus does for this: every other bus on the
channel hears a frame)."""

from __future__ import annotations

import can
import pytest
from rm_base.motors.dji import protocol as dji
from rm_base.sim import SimWorld
from rm_base.sim.bus_peer import BusPeer
from rm_base.sim_devices.errors import SimStateError
from support.ros import wait_until

from .helpers import unique_channel

WAIT = 5.0  # [s]


class _DownBus(can.BusABC):
    """A bus whose link is down for its first reads and sends (as `ip link set down`)."""

    def __init__(self, inner: can.BusABC, down_reads: int) -> None:
        super().__init__(channel=inner.channel_info)
        self.inner, self.down_reads = inner, down_reads

    def _recv_internal(self, timeout):
        if self.down_reads:
            self.down_reads -= 1
            raise can.CanOperationError('Error receiving: Network is down [Error Code 100]')
        return self.inner.recv(timeout), False

    def send(self, msg, timeout=None):
        self.inner.send(msg, timeout)

    def shutdown(self):
        self.inner.shutdown()
        super().shutdown()


def joined(*, stepped: bool, down_reads: int = 0):
    """A stepped world with one M3508 on channel 'can0', joined to a virtual bus whose
    link is down for its first down_reads reads; the peer stepped or with its threads."""
    wire = unique_channel('peer')
    world = SimWorld(timing='stepped')
    world.add_channel('can0', [{'type': 'm3508', 'id': 1, 'name': 'wheel'}])
    peer_bus = _DownBus(can.Bus(interface='virtual', channel=wire), down_reads=down_reads)
    peer = BusPeer(world, {'can0': peer_bus}, stepped=stepped)
    robot = can.Bus(interface='virtual', channel=wire)
    peer.start()
    yield world, peer, robot
    robot.shutdown()
    peer.stop()
    world.close()


@pytest.fixture
def peered():
    """The peer with its reader threads, the link down for its first three reads."""
    yield from joined(stepped=False, down_reads=3)


def test_the_motors_feedback_goes_out_on_the_bus(peered):
    world, peer, robot = peered
    world.step(1)
    msg = robot.recv(WAIT)
    assert msg is not None and msg.arbitration_id == 0x201  # the M3508 with id 1
    assert peer.endpoints['can0'].sent == 1


def test_a_command_from_the_bus_turns_the_motor_after_the_link_comes_back(peered):
    world, peer, robot = peered
    group, _ = dji.command_slot('c620', 1)
    robot.send(can.Message(arbitration_id=group, data=dji.pack_command([8000, 0, 0, 0]),
                           is_extended_id=False))
    endpoint = peer.endpoints['can0']
    assert wait_until(lambda: endpoint.received == 1, WAIT)
    assert endpoint.read_errors == 3  # the link was down for three reads, then read again
    world.step(50)
    assert world.motor('wheel').model.velocity > 1.0


def test_a_frame_the_bus_will_not_take_is_dropped_and_counted(peered):
    world, peer, _ = peered
    endpoint = peer.endpoints['can0']

    def refuse(msg, timeout=None):
        raise can.CanOperationError('Failed to transmit: No buffer space available')

    endpoint.bus.send = refuse
    world.step(3)
    assert (endpoint.sent, endpoint.dropped) == (0, 3)


@pytest.fixture
def stepped():
    """A stepped peer: no reader threads, the stepper settles each half tick."""
    yield from joined(stepped=True)


def command(current: int) -> can.Message:
    group, _ = dji.command_slot('c620', 1)
    return can.Message(arbitration_id=group, data=dji.pack_command([current, 0, 0, 0]),
                       is_extended_id=False)


def test_a_stepped_peer_reads_nothing_until_settled(stepped):
    world, peer, robot = stepped
    robot.send(command(8000))
    world.step(5)
    assert peer.endpoints['can0'].received == 0  # no thread took it
    assert world.motor('wheel').model.current == 0.0
    peer.settle({'can0': 1})
    assert peer.endpoints['can0'].received == 1
    world.step(50)
    assert world.motor('wheel').model.velocity > 1.0


def test_settle_takes_every_frame_waiting_not_only_the_robots_count(stepped):
    _, peer, robot = stepped
    for _ in range(3):
        robot.send(command(1000))
    peer.settle({'can0': 1})
    assert peer.endpoints['can0'].received == 3


def test_a_frame_sent_that_never_arrives_is_an_error_not_a_silent_loss(stepped):
    _, peer, robot = stepped
    robot.send(command(1000))
    with pytest.raises(SimStateError, match=r'rm_sim on can0: 1 of the robot.s frames did not '
                       r'arrive within 0.2 s'):
        peer.settle({'can0': 2}, timeout_s=0.2)


def test_settle_on_a_link_that_is_down_waits_for_nothing_and_counts_the_read_error():
    for world, peer, _ in joined(stepped=True, down_reads=1):
        peer.settle({'can0': 0})  # nothing was sent: returns at once
        assert peer.endpoints['can0'].read_errors == 1
        world.step(1)
        assert peer.endpoints['can0'].sent == 1
