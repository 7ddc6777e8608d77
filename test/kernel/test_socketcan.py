"""The project on the kernel's CAN stack: rm_sim, the managed bus, can-utils as the peer.

Each test has a vcan interface of its own (conftest). can-utils are the kernel's own
tools: candump's log and the project's bus log must agree frame for frame, canplayer must
replay a log, cangen's flood must be counted and harmless, and a link taken down and up
must be survived as python-can reports it (CanOperationError, errno 100).
"""

from __future__ import annotations

import re
import subprocess
import time

import can
import pytest
from rm_base.hardware.bus import ManagedBus
from rm_base.hardware.can_link import LinkReport, read_link
from rm_base.hardware.config import BusConfig
from rm_base.motors.dji import protocol as dji
from rm_base.sim import SimWorld
from rm_base.sim.bus_peer import BusPeer
from support.ros import wait_until

from .conftest import ip

# The guest runs Python ~25x slower than a host (docs/KERNEL_CAN.md): generous waits.
WAIT = 60.0  # [s]
CANDUMP_LINE = re.compile(r'\((\d+\.\d+)\) (\S+) ([0-9A-F]+)#([0-9A-F]*)')


def frames_of_log(text: str) -> list[tuple[int, bytes]]:
    """(id, data) of each line of a candump -L log (python-can's .log is the same)."""
    return [(int(m.group(3), 16), bytes.fromhex(m.group(4)))
            for m in map(CANDUMP_LINE.match, text.splitlines()) if m]


def managed(channel: str, **options) -> ManagedBus:
    return ManagedBus(BusConfig(name='test', interface='socketcan', channel=channel,
                                bitrate=None, **options))


def test_rm_sim_answers_on_vcan_as_the_motors_do(vcan):
    world = SimWorld(timing='stepped')
    world.add_channel(vcan, [{'type': 'm3508', 'id': 1, 'name': 'wheel'}])
    peer = BusPeer(world, {vcan: can.Bus(interface='socketcan', channel=vcan)})
    robot = can.Bus(interface='socketcan', channel=vcan)
    peer.start()
    try:
        group, _ = dji.command_slot('c620', 1)
        robot.send(can.Message(arbitration_id=group, data=dji.pack_command([8000, 0, 0, 0]),
                               is_extended_id=False))
        assert wait_until(lambda: peer.endpoints[vcan].received == 1, WAIT)
        world.step(50)
        assert world.motor('wheel').model.velocity > 1.0
        feedback = robot.recv(WAIT)
        assert feedback is not None and feedback.arbitration_id == 0x201
    finally:
        robot.shutdown()
        peer.stop()
        world.close()


def test_candump_and_the_bus_log_agree_frame_for_frame(vcan, tmp_path):
    log = tmp_path / 'bus.log'
    dump = subprocess.Popen(['candump', '-L', vcan], stdout=subprocess.PIPE, text=True)
    bus = managed(vcan, log_file=str(log))
    other = can.Bus(interface='socketcan', channel=vcan)
    try:
        bus.start()
        time.sleep(1.0)  # candump is listening
        for i in range(20):
            assert bus.send(can.Message(arbitration_id=0x200 + i % 3, data=bytes([i] * 8),
                                        is_extended_id=False))
            other.send(can.Message(arbitration_id=0x201, data=bytes([i, 0xA5]),
                                   is_extended_id=False))
        assert wait_until(lambda: bus.stats().frames_received == 20, WAIT)
    finally:
        other.shutdown()
        bus.shutdown()
        time.sleep(0.5)
        dump.terminate()
    dumped = frames_of_log(dump.communicate(timeout=WAIT)[0])
    logged = list(can.LogReader(str(log)))
    assert len(dumped) == 40 and len(logged) == 40
    assert {m.channel for m in logged} == {vcan}  # named as candump names them
    # Each direction in the order it was on the bus. (The log's writer takes what the
    # loop sent and what the receive thread got from two queues, so the two directions
    # interleave by when each thread ran, not by bus order.)
    sent = [(m.arbitration_id, bytes(m.data)) for m in logged if not m.is_rx]
    received = [(m.arbitration_id, bytes(m.data)) for m in logged if m.is_rx]
    assert sent == [f for f in dumped if len(f[1]) == 8]
    assert received == [f for f in dumped if len(f[1]) == 2]


def test_canplayer_replays_a_candump_log_into_another_bus(vcan2, tmp_path):
    source, target = vcan2
    frames = [(0x200, bytes([i, 2, 3, 4])) for i in range(10)]
    log = tmp_path / 'robot.log'
    log.write_text(''.join(f'({1.0 + i * 0.001:.6f}) {source} {f:03X}#{d.hex().upper()}\n'
                           for i, (f, d) in enumerate(frames)))
    checker = can.Bus(interface='socketcan', channel=target)
    try:
        subprocess.run(['canplayer', '-I', str(log), f'{target}={source}'], check=True,
                       timeout=WAIT)
        got = []
        while (msg := checker.recv(2.0)) is not None:
            got.append((msg.arbitration_id, bytes(msg.data)))
    finally:
        checker.shutdown()
    assert got == frames


def test_a_cangen_flood_is_counted_and_harmless(vcan):
    bus = managed(vcan)
    matched = []
    bus.add_handler(0x201, lambda msg, now_ns: matched.append(msg) or True)
    other = can.Bus(interface='socketcan', channel=vcan)
    try:
        bus.start()
        # random ids, lengths and data, back to back: more than the receiver can take
        subprocess.run(['cangen', vcan, '-g', '0', '-n', '5000', '-I', 'r', '-L', 'r',
                        '-D', 'r'], check=True, timeout=300)
        assert wait_until(lambda: bus.stats().frames_received >= 100, WAIT)
        # then a frame for the handler: the bus still takes and sorts what comes
        marker = bytes([0xEE] * 8)
        other.send(can.Message(arbitration_id=0x201, data=marker, is_extended_id=False))
        assert wait_until(lambda: any(bytes(m.data) == marker for m in matched), WAIT)
        stats = bus.stats()
        assert stats.frames_unmatched == stats.frames_received - len(matched)
        assert stats.state == 'up' and stats.receive_errors == 0, stats
        assert stats.handler_errors == 0
    finally:
        other.shutdown()
        bus.shutdown()


def test_a_link_down_mid_run_is_reported_and_the_same_bus_works_after_up(vcan):
    bus = managed(vcan, reconnect_initial_s=0.05, reconnect_max_s=0.2)
    frame = can.Message(arbitration_id=0x1FF, data=bytes(8), is_extended_id=False)
    try:
        bus.start()
        assert bus.send(frame)
        ip('link', 'set', 'down', vcan)
        assert wait_until(lambda: not bus.send(frame), WAIT)  # nothing goes out while down
        assert wait_until(lambda: bus.stats().state == 'down', WAIT)
        down = bus.stats()
        assert down.send_errors + down.receive_errors >= 1
        # python-can's words while the link is down, then the bus's own on reopening
        assert wait_until(lambda: f'link {vcan} is down' in (bus.stats().last_error or ''),
                          WAIT), bus.stats().last_error
        assert bus.stats().state == 'down'  # not reopened onto a link that is down
        ip('link', 'set', 'up', vcan)
        other = can.Bus(interface='socketcan', channel=vcan)
        try:
            assert wait_until(lambda: bus.send(frame), WAIT)
            seen = other.recv(WAIT)
            assert seen is not None and seen.arbitration_id == 0x1FF
        finally:
            other.shutdown()
        assert bus.stats().state == 'up' and bus.stats().reopen_count >= 1
    finally:
        bus.shutdown()


def test_a_bus_on_a_link_that_is_down_waits_for_up(vcan):
    ip('link', 'set', 'down', vcan)
    bus = managed(vcan, reconnect_initial_s=0.05, reconnect_max_s=0.2)
    try:
        bus.start()
        stats = bus.stats()
        assert stats.state == 'down' and stats.open_failures >= 1
        assert f'link {vcan} is down' in stats.last_error
        ip('link', 'set', 'up', vcan)
        assert wait_until(lambda: bus.stats().state == 'up', WAIT)
    finally:
        bus.shutdown()


def test_the_kernels_error_frames_are_decoded_and_counted(vcan):
    bus = managed(vcan)
    other = can.Bus(interface='socketcan', channel=vcan)
    try:
        bus.start()
        # what a controller's driver sends on bus-off, with its counters (tx 255, rx 0)
        other.send(can.Message(arbitration_id=0x240, is_error_frame=True, is_extended_id=False,
                               data=bytes([0, 0, 0, 0, 0, 0, 255, 0])))
        assert wait_until(lambda: bus.stats().error_frames == 1, WAIT)
        stats = bus.stats()
        assert stats.bus_off == 1 and stats.frames_received == 0
        assert stats.last_error_frame == 'bus-off counters, counters tx 255 rx 0'
    finally:
        other.shutdown()
        bus.shutdown()


def test_the_kernels_link_report_reads_a_vcan(vcan):
    report = read_link(vcan)
    assert report is not None and (report.exists, report.up, report.kind) == (True, True, 'vcan')
    assert 'tx_packets' in report.counters
    ip('link', 'set', 'down', vcan)
    assert read_link(vcan).up is False
    assert read_link('vtnone1') == LinkReport(exists=False)


def test_a_bus_on_a_missing_interface_fails_to_open_with_no_such_device():
    with pytest.raises(OSError) as err:
        can.Bus(interface='socketcan', channel='vtnone0')
    assert err.value.errno == 19


def test_can_up_makes_a_vcan_with_a_deep_queue():
    name = 'vtcanup0'
    try:
        subprocess.run(['bash', 'scripts/can_up.sh', '--vcan', name], check=True,
                       capture_output=True, timeout=WAIT)
        shown = subprocess.run(['ip', '-json', 'link', 'show', 'dev', name], check=True,
                               capture_output=True, text=True).stdout
        assert '"txqlen":1000' in shown.replace(' ', '')
        report = read_link(name)
        assert report is not None and report.up and report.kind == 'vcan'
    finally:
        subprocess.run(['ip', 'link', 'del', name], check=False, capture_output=True)
