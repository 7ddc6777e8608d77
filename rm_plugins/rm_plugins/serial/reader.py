"""SerialReader: reads frames from a serial port and hands out what they carry.

Why one module: the thread that opens the port and the poll that reads it share the port,
the lock that keeps them apart and the counters; split, each would reach into the other.

The port is any pyserial URL (``serial.serial_for_url``): a device (``/dev/ttyUSB0``), a
pseudo-terminal or a symlink to one (the simulator's IMU), ``loop://``, ``socket://h:p``.
A reader's thread opens the port, and reopens it with back-off when it fails. Who reads it:

- by default the thread, in reads that block for at most ``read_timeout`` (so ``stop()``
  is honoured quickly);
- a ``polled`` reader is read by :meth:`SerialReader.poll`, which the control loop calls at
  the start of every tick, before the plugins: one non-blocking read of what the port
  holds, decoded in the loop's thread, so the plugins of that tick see it. No thread is
  woken for it: a 400 Hz IMU costs no thread switch and never waits for the interpreter
  (docs/PERFORMANCE.md, "Serial ports are read by the loop").

Bytes go through the device's parser (``FrameStream``: the HiPNUC IMU's, the referee's...),
which resynchronises after garbage and counts what it skips; everything it decodes is
passed to ``on_sample`` in the reading thread.

A port that cannot be opened, fails while reading (unplugged, pty closed) or stays silent
for ``silence_reopen`` is closed and reopened with exponential back-off between
``backoff_min`` and ``backoff_max``. Nothing here raises to its caller: errors are
recorded in the statistics (``stats()``) and logged, rate-limited. No rclpy here.
"""

from __future__ import annotations

import dataclasses
import os
import termios
import threading
import time
from collections.abc import Callable
from typing import Any, Protocol

import serial

from rm_plugins.serial.descriptor import DescriptorReader

_NS_PER_S = 1_000_000_000
_LOG_PERIOD_NS = 5 * _NS_PER_S
_READ_CHUNK = 4096


class FrameStream(Protocol):
    """A device's byte-stream parser, as the reader drives it (counters since it began)."""

    @property
    def frames_ok(self) -> int:
        """Frames decoded."""

    @property
    def crc_errors(self) -> int:
        """Frames with a wrong CRC."""

    @property
    def length_errors(self) -> int:
        """Headers with an impossible length."""

    @property
    def decode_errors(self) -> int:
        """Frames with a good CRC but an undecodable payload."""

    @property
    def bytes_discarded(self) -> int:
        """Bytes skipped while looking for a frame."""

    def feed(self, data: bytes) -> list[Any]:
        """Add received bytes; return what the frames they completed carry."""


class Logger(Protocol):
    """The part of a logger the reader uses."""

    def info(self, message: str) -> Any:
        """Log at INFO."""

    def warning(self, message: str) -> Any:
        """Log at WARN."""


@dataclasses.dataclass(frozen=True)
class ReaderStats:
    """What the reader has seen since it was created (counters never go down).

    Attributes:
        port_open: the port is open now.
        opens: successful opens (1 after the first, +1 per reopen).
        open_failures: failed attempts to open.
        port_losses: times an open port failed or went silent and was closed.
        last_error: text of the last open/read problem, None if there was none.
        bytes_read: bytes received.
        frames_ok: frames decoded.
        crc_errors: frames with a wrong CRC.
        length_errors: headers with an impossible length.
        decode_errors: frames with a good CRC but an undecodable payload.
        bytes_discarded: bytes skipped while looking for a frame.
        sample_errors: samples the on_sample callback rejected (raised on).
    """

    port_open: bool = False
    opens: int = 0
    open_failures: int = 0
    port_losses: int = 0
    last_error: str | None = None
    bytes_read: int = 0
    frames_ok: int = 0
    crc_errors: int = 0
    length_errors: int = 0
    decode_errors: int = 0
    bytes_discarded: int = 0
    sample_errors: int = 0

    @property
    def bad_frames(self) -> int:
        """Frames lost to CRC, length or payload errors."""
        return self.crc_errors + self.length_errors + self.decode_errors


def open_serial(url: str, baudrate: int, timeout: float) -> Any:
    """Open url with pyserial (``serial_for_url``), non-exclusive, read timeout [s]."""
    return serial.serial_for_url(url, baudrate=baudrate, timeout=timeout)


def nonblocking_descriptor(port: Any) -> int | None:
    """The port's file descriptor if reading it never blocks, else None.

    pyserial opens a posix port (a tty, a pty) with O_NONBLOCK and waits with select()
    itself; a poll then needs a ``poll(0)`` and, when data waits, one ``read``
    (``DescriptorReader``, holding the GIL), not pyserial's ioctl + select + read.
    ``loop://``, ``socket://`` and the like have no descriptor of their own.
    """
    try:
        fd = port.fileno()
    except (AttributeError, OSError, ValueError):
        return None
    if not isinstance(fd, int) or os.get_blocking(fd):
        return None
    return fd


class SerialReader:
    """Reads one device's serial port in a background thread.

    Args:
        url: pyserial URL or device path (already expanded).
        baudrate: [bit/s].
        on_sample: called in the reading thread for each thing the parser decodes; an
            exception from it is counted as a sample error and logged (rate-limited).
        logger: receives open/lose/recover lines.
        read_timeout: longest blocking read [s] (also bounds how long stop() takes).
        backoff_min: first wait before reopening [s].
        backoff_max: longest wait between reopen attempts [s].
        silence_reopen: reopen an open port that delivered no byte for this long [s];
            0 disables.
        opener: ``(url, baudrate, timeout) -> port`` (pyserial by default).
        clock_ns: monotonic clock [ns].
        polled: the port is read by :meth:`poll` only (a stage of the control loop);
            the thread only opens and reopens it.
        parser: the device's frame parser.
        name: the device kind, for the thread's name (``<name> <url>``).
    """

    def __init__(
        self,
        url: str,
        baudrate: int,
        on_sample: Callable[[Any], None],
        logger: Logger,
        *,
        read_timeout: float = 0.02,
        backoff_min: float = 0.1,
        backoff_max: float = 2.0,
        silence_reopen: float = 1.0,
        opener: Callable[[str, int, float], Any] = open_serial,
        clock_ns: Callable[[], int] = time.monotonic_ns,
        polled: bool = False,
        parser: FrameStream,
        name: str = 'serial',
    ) -> None:
        if not 0.0 < read_timeout <= 1.0:
            raise ValueError(f'read_timeout must be in (0, 1] s, got {read_timeout}')
        if not 0.0 < backoff_min <= backoff_max:
            raise ValueError(
                f'need 0 < backoff_min <= backoff_max, got {backoff_min}, {backoff_max}'
            )
        if silence_reopen < 0.0:
            raise ValueError(f'silence_reopen must be >= 0 s, got {silence_reopen}')
        self.url = url
        self.baudrate = baudrate
        self._on_sample = on_sample
        self._logger = logger
        self._read_timeout = read_timeout
        self._backoff_min = backoff_min
        self._backoff_max = backoff_max
        self._silence_ns = round(silence_reopen * _NS_PER_S)
        self._opener = opener
        self._clock_ns = clock_ns
        self._polled = polled
        self._lost = threading.Event()  # a poll closed the port (or stop() was called)
        # poll() and closing never use the port together; poll() never waits for it.
        self._port_lock = threading.Lock()
        # A port read through its descriptor (libc poll and read, holding the GIL).
        self._descriptor: DescriptorReader | None = None
        self._parser = parser
        self._name = name
        self._lock = threading.Lock()
        self._stats = ReaderStats()  # the rare events; what every read counts is below
        self._bytes_read = 0  # written by whichever thread reads (the loop when polled)
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._port: Any = None
        self._last_byte_ns = 0
        self._next_log_ns = 0

    # -- public -----------------------------------------------------------------------------

    def start(self) -> None:
        """Start the reader thread (it opens the port). Does nothing if running."""
        if self._thread is not None and self._thread.is_alive():
            return
        self._stop.clear()
        self._thread = threading.Thread(
            target=self._run, name=f'{self._name} {self.url}', daemon=True
        )
        self._thread.start()

    def stop(self, timeout: float = 2.0) -> bool:
        """Stop the thread and close the port; return False if the thread did not end."""
        self._stop.set()
        self._lost.set()  # a polled reader's thread waits for a loss
        thread, self._thread = self._thread, None
        if thread is not None:
            thread.join(timeout)
            if thread.is_alive():
                return False
        self._close()
        return True

    @property
    def polled(self) -> bool:
        """Whether the port is read by :meth:`poll` (not by the thread)."""
        return self._polled

    def poll(self) -> bool:
        """Read and decode what the port holds, without blocking; return whether it held any.

        A polled reader's stage in the control loop: it returns at once when the port is
        not open or the thread is closing it. A failed read or a silence longer than
        ``silence_reopen`` closes the port, and the thread reopens it.
        """
        if self._port is None or not self._polled:
            return False
        if not self._port_lock.acquire(blocking=False):
            return False
        try:
            port = self._port
            if port is None:
                return False
            try:
                data = self._read_waiting(port)
            except (serial.SerialException, OSError, TypeError, ValueError,
                    termios.error) as err:
                problem: str | None = f'{self.url} failed: {err}'
                data = b''
            else:
                problem = self._take(data)
            if problem is not None:
                self._close_locked()
                self._note_loss(problem)
                self._lost.set()
            return bool(data)
        finally:
            self._port_lock.release()

    def write(self, data: bytes) -> bool:
        """Write data to the port without blocking; False if it is not open, busy or full.

        The port's output buffer full (nobody reads the other end) is a failed write, never
        a wait: the caller is the control loop. A descriptor that never blocks (a tty, a
        pty) is written directly: pyserial's own write with ``write_timeout=0`` spins
        while the buffer stays full.
        """
        if self._port is None or not self._port_lock.acquire(blocking=False):
            return False
        try:
            port = self._port
            if port is None:
                return False
            fd = nonblocking_descriptor(port)
            written = os.write(fd, data) if fd is not None else port.write(data)
            return bool(written == len(data))
        except (serial.SerialException, OSError, TypeError, ValueError, termios.error):
            return False  # BlockingIOError (the buffer full) among them
        finally:
            self._port_lock.release()

    @property
    def running(self) -> bool:
        """Whether the reader thread is alive."""
        return self._thread is not None and self._thread.is_alive()

    def stats(self) -> ReaderStats:
        """Return the counters, read together.

        The byte and frame counts are taken here, not copied on every read: they change
        hundreds of times a second in the control loop, and are read once a second.
        """
        parser = self._parser
        with self._lock:
            return dataclasses.replace(
                self._stats,
                bytes_read=self._bytes_read,
                frames_ok=parser.frames_ok,
                crc_errors=parser.crc_errors,
                length_errors=parser.length_errors,
                decode_errors=parser.decode_errors,
                bytes_discarded=parser.bytes_discarded,
            )

    # -- thread -----------------------------------------------------------------------------

    def _run(self) -> None:
        backoff = self._backoff_min
        while not self._stop.is_set():
            if self._port is None:
                if self._open():
                    backoff = self._backoff_min
                else:
                    self._stop.wait(backoff)
                    backoff = min(2.0 * backoff, self._backoff_max)
                    continue
            if self._polled:
                self._lost.wait()
                self._lost.clear()
            else:
                problem = self._read_blocking()
                if problem is None:
                    continue
                self._lose(problem)
            # Wait a little before reopening: a port that just vanished is rarely back
            # at once, and a device that keeps failing must not spin this thread.
            self._stop.wait(backoff)
            backoff = min(2.0 * backoff, self._backoff_max)
        self._close()

    def _open(self) -> bool:
        try:
            port = self._opener(self.url, self.baudrate, self._read_timeout)
        except (serial.SerialException, OSError, ValueError, termios.error) as err:
            message = f'cannot open {self.url}: {err}'
            with self._lock:
                first = self._stats.last_error != message
                self._update(open_failures=self._stats.open_failures + 1, last_error=message)
            if first:  # the same failure again and again is logged once
                self._logger.warning(f'{message}; retrying with back-off')
            return False
        fd = nonblocking_descriptor(port) if self._polled else None  # the thread uses pyserial
        self._descriptor = None if fd is None else DescriptorReader(fd, _READ_CHUNK)
        self._last_byte_ns = self._clock_ns()
        with self._lock:
            reopened = self._stats.opens > 0 or self._stats.open_failures > 0
            self._update(port_open=True, opens=self._stats.opens + 1)
        self._port = port  # last: a poll may read it from now on
        self._logger.info(f'{"reopened" if reopened else "opened"} {self.url}')
        return True

    def _read_blocking(self) -> str | None:
        """Read what is there (or wait up to read_timeout); return a problem or None."""
        try:
            waiting = self._port.in_waiting
            data = self._port.read(min(max(1, waiting), _READ_CHUNK))
        except (serial.SerialException, OSError, TypeError, ValueError, termios.error) as err:
            # pyserial raises TypeError/ValueError on some ports closed under its feet.
            return f'{self.url} failed: {err}'
        return self._take(data)

    def _read_waiting(self, port: Any) -> bytes:
        """What the port holds now, without blocking; b'' if nothing.

        Raises:
            OSError: the port failed, or it reports data and has none (a device that is
                gone, as pyserial reads it).
        """
        descriptor = self._descriptor
        if descriptor is None:
            waiting = port.in_waiting
            return port.read(min(waiting, _READ_CHUNK)) if waiting else b''
        return descriptor.read()

    def _take(self, data: bytes) -> str | None:
        """Decode data and hand out what it carries; return a problem (silence) or None."""
        now_ns = self._clock_ns()
        if not data:
            if self._silence_ns and now_ns - self._last_byte_ns > self._silence_ns:
                return f'no byte from {self.url} for {self._silence_ns / _NS_PER_S:.1f} s'
            return None
        self._last_byte_ns = now_ns
        samples = self._parser.feed(data)
        self._bytes_read += len(data)
        for sample in samples:
            try:
                self._on_sample(sample)
            except Exception as err:  # a bad sample never ends the reading
                with self._lock:
                    self._update(sample_errors=self._stats.sample_errors + 1)
                self._log_throttled(f'sample rejected: {type(err).__name__}: {err}')
        return None

    def _lose(self, problem: str) -> None:
        self._close()
        self._note_loss(problem)

    def _note_loss(self, problem: str) -> None:
        with self._lock:
            self._update(port_losses=self._stats.port_losses + 1, last_error=problem)
        self._logger.warning(f'{problem}; closed, reopening with back-off')

    def _close(self) -> None:
        with self._port_lock:
            self._close_locked()

    def _close_locked(self) -> None:
        # Caller holds self._port_lock.
        port, self._port, self._descriptor = self._port, None, None
        if port is not None:
            try:
                port.close()
            except Exception as err:  # closing a vanished device may fail; it is gone anyway
                self._logger.info(f'closing {self.url}: {err}')
        with self._lock:
            if self._stats.port_open:
                self._update(port_open=False)

    def _update(self, **changes: Any) -> None:
        # Caller holds self._lock.
        self._stats = dataclasses.replace(self._stats, **changes)

    def _log_throttled(self, message: str) -> None:
        now_ns = self._clock_ns()
        if now_ns >= self._next_log_ns:
            self._next_log_ns = now_ns + _LOG_PERIOD_NS
            self._logger.warning(message)
