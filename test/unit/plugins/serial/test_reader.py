"""SerialReader on real pseudo-terminals and pyserial's loop://: frames, garbage, port loss."""

import math
import os
import threading

import pytest
import serial
from rm_base.hardware.protocols import hipnuc
from rm_base.hardware.protocols.hipnuc import HipnucParser
from rm_plugins.serial import SerialReader
from support.serial_port import Pty

WAIT = 10.0  # longest wait for a condition [s]; normally met within a few read timeouts


class Log:
    def __init__(self):
        self.lines = []

    def info(self, message):
        self.lines.append(('info', message))

    def warning(self, message):
        self.lines.append(('warning', message))


def frame(yaw=0.0, rate_z=0.0):
    q = (math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2))  # (w, x, y, z)
    return hipnuc.encode_frame(
        hipnuc.encode_imusol(
            acc=(0.0, 0.0, 9.80665),
            gyr=(0.0, 0.0, rate_z),
            mag=(0.0, 0.0, 0.0),
            euler=(0.0, 0.0, yaw),
            quat=q,
        )
    )


class Collector:
    def __init__(self):
        self.samples = []
        self.cond = threading.Condition()

    def __call__(self, sample):
        with self.cond:
            self.samples.append(sample)
            self.cond.notify_all()

    def wait_for(self, count, timeout=WAIT):
        with self.cond:
            return self.cond.wait_for(lambda: len(self.samples) >= count, timeout)


@pytest.fixture
def reader_factory():
    readers = []

    def make(url, on_sample, **kwargs):
        kwargs.setdefault('read_timeout', 0.01)
        kwargs.setdefault('backoff_min', 0.02)
        kwargs.setdefault('backoff_max', 0.05)
        reader = SerialReader(url, 115200, on_sample, Log(), parser=HipnucParser(), **kwargs)
        readers.append(reader)
        return reader

    yield make
    for reader in readers:
        assert reader.stop()


def wait(predicate, timeout=WAIT):
    event = threading.Event()
    for _ in range(int(timeout / 0.01)):
        if predicate():
            return True
        event.wait(0.01)
    return predicate()


def test_when_frames_arrive_on_a_pty_expect_each_decoded(tmp_path, reader_factory):
    port = Pty(str(tmp_path / 'imu'))
    got = Collector()
    reader = reader_factory(port.path, got)
    reader.start()
    assert wait(lambda: reader.stats().port_open)
    for i in range(5):
        port.write(frame(yaw=0.1 * i, rate_z=0.5))
    assert got.wait_for(5)
    # 0x91 carries float32 degrees: yaw 0.4 rad comes back within float precision.
    assert got.samples[4].euler[2] == pytest.approx(0.4, abs=1e-6)
    assert got.samples[4].gyr[2] == pytest.approx(0.5, abs=1e-6)
    stats = reader.stats()
    assert stats.frames_ok == 5 and stats.bad_frames == 0 and stats.bytes_discarded == 0
    assert stats.bytes_read == 5 * len(frame())
    port.close()


def test_when_garbage_and_broken_frames_come_between_good_ones_expect_them_skipped_and_counted(
    tmp_path, reader_factory
):
    port = Pty(str(tmp_path / 'imu'))
    got = Collector()
    reader = reader_factory(port.path, got)
    reader.start()
    assert wait(lambda: reader.stats().port_open)
    good = frame(yaw=0.2)
    corrupted = bytearray(good)
    corrupted[20] ^= 0xFF  # a payload byte: the CRC no longer matches
    truncated = good[:40]  # a frame cut short, the next frame follows at once
    garbage = b'\x00\x13\x11\xff' * 4  # 16 bytes, including XON/XOFF, which raw mode passes
    port.write(garbage + good + bytes(corrupted) + good + truncated + good)
    assert got.wait_for(3)
    stats = reader.stats()
    assert stats.frames_ok == 3
    # The corrupted frame fails its CRC; so does the truncated one, whose LEN swallows the
    # start of the next frame (the parser then rescans and still finds that frame).
    assert stats.crc_errors == 2
    assert stats.bytes_discarded >= len(garbage)
    assert [s.euler[2] for s in got.samples] == pytest.approx([0.2] * 3, abs=1e-6)
    port.close()


def test_when_the_port_is_missing_expect_retries_until_it_appears(tmp_path, reader_factory):
    path = str(tmp_path / 'imu')
    got = Collector()
    reader = reader_factory(path, got)
    reader.start()
    assert wait(lambda: reader.stats().open_failures >= 2)
    assert not reader.stats().port_open
    assert 'cannot open' in reader.stats().last_error
    port = Pty(path)
    assert wait(lambda: reader.stats().port_open)
    port.write(frame())
    assert got.wait_for(1)
    port.close()


def test_when_the_port_vanishes_expect_loss_counted_and_the_new_port_read(
    tmp_path, reader_factory
):
    path = str(tmp_path / 'imu')
    port = Pty(path)
    got = Collector()
    reader = reader_factory(path, got)
    reader.start()
    assert wait(lambda: reader.stats().port_open)
    port.write(frame())
    assert got.wait_for(1)

    port.close()  # the device goes away: reads fail with EIO, the symlink is gone
    assert wait(lambda: reader.stats().port_losses == 1 and not reader.stats().port_open)

    port = Pty(path)  # it comes back (a new pty, as when the simulator restarts)
    assert wait(lambda: reader.stats().port_open)
    assert reader.stats().opens == 2
    port.write(frame(yaw=0.3))
    assert got.wait_for(2)
    assert got.samples[-1].euler[2] == pytest.approx(0.3, abs=1e-6)
    port.close()


def test_when_the_port_goes_silent_expect_it_reopened(tmp_path, reader_factory):
    port = Pty(str(tmp_path / 'imu'))
    reader = reader_factory(port.path, Collector(), silence_reopen=0.1)
    reader.start()
    # Nothing is ever written: after 0.1 s of silence the reader closes and reopens.
    assert wait(lambda: reader.stats().opens >= 2)
    assert reader.stats().port_losses >= 1
    assert 'no byte' in reader.stats().last_error
    port.close()


def test_a_pyserial_url_is_read_too(reader_factory):
    # loop:// echoes what is written to it; the opener hands the reader a port that
    # already holds two frames.
    loop = serial.serial_for_url('loop://', timeout=0.01)
    loop.write(frame(yaw=0.1) + frame(yaw=0.2))
    got = Collector()
    reader = reader_factory('loop://', got, opener=lambda url, baud, timeout: loop)
    reader.start()
    assert got.wait_for(2)
    assert got.samples[1].euler[2] == pytest.approx(0.2, abs=1e-6)


def test_when_on_sample_raises_expect_it_counted_and_reading_to_go_on(tmp_path, reader_factory):
    port = Pty(str(tmp_path / 'imu'))
    calls = []

    def fussy(sample):
        calls.append(sample)
        if len(calls) == 1:
            raise ValueError('bad sample')

    reader = reader_factory(port.path, fussy)
    reader.start()
    assert wait(lambda: reader.stats().port_open)
    port.write(frame() + frame())
    assert wait(lambda: len(calls) == 2)
    assert reader.stats().sample_errors == 1
    port.close()


def test_stop_is_prompt_and_closes_the_port(tmp_path, reader_factory):
    port = Pty(str(tmp_path / 'imu'))
    reader = reader_factory(port.path, Collector())
    reader.start()
    assert wait(lambda: reader.stats().port_open)
    assert reader.stop(timeout=1.0)
    assert not reader.running and not reader.stats().port_open
    port.close()


class FakePort:
    """A port that never blocks: what is written waits in a buffer; reads are recorded."""

    def __init__(self):
        self.buffer = bytearray()
        self.reads = []
        self.lock = threading.Lock()

    def write(self, data):
        with self.lock:
            self.buffer += data

    @property
    def in_waiting(self):
        with self.lock:
            return len(self.buffer)

    def read(self, size):
        with self.lock:
            data = bytes(self.buffer[:size])
            del self.buffer[:size]
            self.reads.append(size)
            return data

    def close(self):
        pass


def test_a_polled_reader_reads_only_when_polled_and_in_the_polling_thread(reader_factory):
    port = FakePort()
    got = Collector()
    threads = []

    def on_sample(sample):
        threads.append(threading.current_thread())
        got(sample)

    reader = reader_factory('fake://', on_sample, opener=lambda *_: port, polled=True)
    reader.start()
    assert wait(lambda: reader.stats().port_open)
    for i in range(5):
        port.write(frame(yaw=0.1 * i))
    threading.Event().wait(0.05)  # the thread had time to read, and must not have
    assert got.samples == [] and port.reads == []
    reader.poll()  # what the loop's after-tick callback does
    assert len(got.samples) == 5 and threads == [threading.current_thread()] * 5
    # one read of what was waiting, never a blocking read for more
    assert port.reads == [len(frame()) * 5]
    reader.poll()  # nothing waits: no read at all
    stats = reader.stats()
    assert port.reads == [len(frame()) * 5] and stats.frames_ok == 5
    assert stats.bytes_read == len(frame()) * 5


def test_a_polled_reader_on_a_pty_reads_what_waits_without_blocking(tmp_path, reader_factory):
    port = Pty(str(tmp_path / 'imu'))
    got = Collector()
    reader = reader_factory(port.path, got, polled=True, read_timeout=1.0)
    reader.start()
    assert wait(lambda: reader.stats().port_open)
    reader.poll()  # nothing there: returns at once (a blocking read would wait 1 s)
    assert got.samples == []
    port.write(frame(yaw=0.1) + frame(yaw=0.2))
    assert wait(lambda: (reader.poll(), len(got.samples) == 2)[1])
    assert got.samples[1].euler[2] == pytest.approx(0.2, abs=1e-6)
    assert reader.stats().port_losses == 0
    port.close()


def test_a_polled_reader_loses_a_vanished_port_and_reads_the_new_one(tmp_path, reader_factory):
    path = str(tmp_path / 'imu')
    port = Pty(path)
    got = Collector()
    reader = reader_factory(path, got, polled=True)
    reader.start()
    assert wait(lambda: reader.stats().port_open)
    port.close()  # reads fail with EIO: the poll closes the port, the thread reopens
    reader.poll()
    assert reader.stats().port_losses == 1 and not reader.stats().port_open
    assert 'failed' in reader.stats().last_error
    port = Pty(path)
    assert wait(lambda: reader.stats().port_open)
    port.write(frame(yaw=0.3))
    assert wait(lambda: (reader.poll(), len(got.samples) == 1)[1])
    assert reader.stats().opens == 2
    port.close()


def test_a_polled_reader_reopens_a_silent_port(reader_factory):
    ports = []

    def opener(*_):
        ports.append(FakePort())
        return ports[-1]

    now = [0]
    reader = reader_factory(
        'fake://', Collector(), opener=opener, polled=True, clock_ns=lambda: now[0],
        silence_reopen=0.1,
    )
    reader.start()
    assert wait(lambda: reader.stats().port_open)
    now[0] += 50_000_000
    reader.poll()  # silent for 50 ms: kept
    assert reader.stats().port_losses == 0
    now[0] += 60_000_000
    reader.poll()  # silent for 110 ms: closed, and the thread opens it again
    assert reader.stats().port_losses == 1 and 'no byte' in reader.stats().last_error
    assert wait(lambda: reader.stats().opens == 2 and reader.stats().port_open)
    assert len(ports) == 2


def test_a_terminal_that_refuses_its_settings_is_retried_not_fatal(reader_factory):
    # pyserial's tcsetattr on a pseudo-terminal whose other side just closed raises
    # termios.error (not an OSError): the thread must count it and retry, not die.
    import termios

    attempts = []

    def opener(url, baudrate, timeout):
        attempts.append(url)
        if len(attempts) < 3:
            raise termios.error(22, 'Invalid argument')
        return serial.serial_for_url('loop://', baudrate=baudrate, timeout=timeout)

    collected = Collector()
    reader = reader_factory('/dev/pts/none', collected, opener=opener)
    reader.start()
    assert wait(lambda: reader.stats().port_open)
    assert reader.stats().open_failures == 2 and 'Invalid argument' in reader.stats().last_error


def test_a_device_with_parity_on_a_pseudo_terminal_is_reopened_without_it(tmp_path):
    # Linux refuses PARENB on a pty opened a second time (EINVAL); a pty has no wire.
    from types import SimpleNamespace

    from rm_plugins.serial.device import make_reader

    pty = Pty(str(tmp_path / 'dr16'))
    try:
        settings = SimpleNamespace(port=pty.path, baudrate=100000, read_timeout=0.01,
                                   backoff_min=0.01, backoff_max=0.02, silence_reopen=0.0)
        reader = make_reader(settings, lambda item: None, Log(), parser=HipnucParser(),
                             name='dr16', polled=False, parity=serial.PARITY_EVEN)
        for _ in range(3):
            port = reader._opener(pty.path, 100000, 0.01)
            port.close()
    finally:
        pty.close()


def test_write_reaches_the_device_and_never_blocks_on_a_full_buffer(tmp_path, reader_factory):
    port = Pty(str(tmp_path / 'referee'))
    reader = reader_factory(port.path, Collector())
    assert not reader.write(b'early')  # not open yet: refused, not queued
    reader.start()
    assert wait(lambda: reader.stats().port_open)
    assert reader.write(b'\xa5hello')
    assert wait(lambda: os.read(port.master, 64) == b'\xa5hello')
    # nobody reads the device side now: the buffer fills, and writes fail at once
    results = [reader.write(bytes(1000)) for _ in range(200)]
    assert not all(results) and results[-1] is False
    port.close()
