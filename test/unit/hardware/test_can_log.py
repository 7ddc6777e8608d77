"""The bus's log_file writer: bounded, counted, and quick to stop (rm_base.hardware.can_log)."""

import logging
import threading
import time

import can
from rm_base.hardware.can_log import CanLog


class _StuckWriter:
    """A writer on a disk that does not keep up: each frame waits for release."""

    def __init__(self):
        self.release = threading.Event()
        self.written = 0

    def on_message_received(self, msg):
        self.release.wait()
        self.written += 1

    def stop(self):
        pass


def test_a_writer_that_falls_behind_drops_new_frames_counted_and_said_once(tmp_path, caplog):
    # The finding: 190 s behind on a starved CPU, the process grew from 104 to 497 MB
    # with no warning, and SIGINT took 9 s while the backlog was written.
    log = CanLog(str(tmp_path / 'can0.csv'), 'can0', max_queued=100)
    stuck = _StuckWriter()
    log._writer.stop()
    log._writer = stuck
    frame = can.Message(arbitration_id=0x201, data=bytes(8), is_extended_id=False)
    with caplog.at_level(logging.WARNING, logger='rm_base.hardware.bus'):
        log.wake()
        for _ in range(1000):
            log.received(frame)
        log.wake()
        time.sleep(0.05)  # the writer takes one frame and waits on it
        for _ in range(100):
            log.sent(frame, 'can0')
    assert len(log._queue) <= 100
    assert log.dropped >= 1000 - 100 - 1 + 100 - 1
    warnings = [r for r in caplog.records if 'CAN log writer' in r.getMessage()]
    assert len(warnings) == 1 and 'can0' in warnings[0].getMessage()
    stuck.release.set()
    start = time.monotonic()
    log.stop()
    assert time.monotonic() - start < 5.0
    assert stuck.written <= 101  # never more than the bound (+ the one in hand)


def test_a_log_is_candump_format_with_each_frames_direction(tmp_path):
    # socketcan marks a frame another local program sent is_rx=False; this bus received it
    path = tmp_path / 'can0.log'
    log = CanLog(str(path), 'can0')
    heard = can.Message(arbitration_id=0x201, data=b'\x01\x02', is_extended_id=False,
                        is_rx=False, channel='vcan0', timestamp=10.0)
    log.received(heard)
    log.sent(can.Message(arbitration_id=0x200, data=bytes(8), is_extended_id=False), 'vcan0')
    log.stop()
    lines = path.read_text().splitlines()
    assert lines[0] == '(10.000000) vcan0 201#0102 R'
    assert lines[1].split()[1:] == ['vcan0', '200#0000000000000000', 'T']
