"""The frame tap behind ~/frames."""

import can
from rm_base.bridge.frames import FrameTap

from .helpers import unique_name


def test_tapped_bus_records_sent_and_received_frames():
    channel = unique_name()
    tap = FrameTap({('virtual', channel): 'can0'})
    bus = tap.factory(interface='virtual', channel=channel)
    peer = can.Bus(interface='virtual', channel=channel)
    try:
        sent = can.Message(arbitration_id=0x200, data=bytes(8), is_extended_id=False)
        bus.send(sent)
        peer.send(can.Message(arbitration_id=0x201, data=b'\x01', is_extended_id=False))
        received = bus.recv(1.0)
        assert received.arbitration_id == 0x201
        assert bus.recv(0.0) is None  # nothing else, and a timeout records nothing
        frames = tap.drain()
        assert [(f.bus, f.frame.arbitration_id, f.is_rx) for f in frames] == [
            ('can0', 0x200, False),
            ('can0', 0x201, True),
        ]
        assert frames[0].frame is sent
        assert tap.drain() == []
        assert bus.channel_info  # other attributes reach the real bus
    finally:
        bus.shutdown()
        peer.shutdown()


def test_when_the_queue_is_full_expect_oldest_dropped_and_counted():
    tap = FrameTap({}, max_frames=2)
    for i in range(5):
        tap.record('can0', can.Message(arbitration_id=i), False)
    assert [f.frame.arbitration_id for f in tap.drain()] == [3, 4]
    assert tap.dropped == 3
