"""rm_sim's channels on python-can buses (socketcan on a robot's kernel; here python-can's
own virtual interface, which behaves as a kernel bus does for this: every other bus on the
channel hears a frame)."""

from __future__ import annotations

import can
import pytest
from rm_base.motors.dji import protocol as dji
from rm_base.sim import SimWorld
from rm_base.sim.bus_peer import BusPeer
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


@pytest.fixture
def peered():
    """A stepped world with one M3508 on channel 'can0', joined to a virtual bus."""
    wire = unique_channel('peer')
    world = SimWorld(timing='stepped')
    world.add_channel('can0', [{'type': 'm3508', 'id': 1, 'name': 'wheel'}])
    peer_bus = _DownBus(can.Bus(interface='virtual', channel=wire), down_reads=3)
    peer = BusPeer(world, {'can0': peer_bus})
    robot = can.Bus(interface='virtual', channel=wire)
    peer.start()
    yield world, peer, robot
    robot.shutdown()
    peer.stop()
    world.close()


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
