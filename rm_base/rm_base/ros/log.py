"""rclpy logging that is cheap enough for 1 kHz threads, and Python ``logging`` into it.

rclpy 7.1.6's ``RcutilsLogger.log()`` finds its caller with ``inspect.getframeinfo()``,
which reads the caller's source file (``findsource`` → ``getmodule`` → ``realpath`` over
``sys.modules``): about 400 µs per line on this machine, paid by every call that passes
the severity check, including the ones a ``throttle_duration_sec`` filter then drops. A
scheduler tick that logs nine "output held at zero" lines stalled for 3.6 ms.

``FastLogger`` wraps an rclpy logger and hands the message to the same rcutils call
(same output handlers: console, /rosout, log file) with the caller taken from the frame
(``sys._getframe``), which costs microseconds. It supports the filters this project uses
(``throttle_duration_sec``, ``once``) itself and passes any other keyword to rclpy's own
path. ``RosLogHandler`` forwards the hardware layer's Python ``logging`` records, with
their own caller information.

rcutils sends each line on /rosout in the thread that logs, and rclpy keeps the GIL for
the call; a send can block a third of a second while a /rosout subscriber joins
(docs/PERFORMANCE.md, "No DDS call from the loop"). So the call goes through
ctypes, which releases the GIL, and a control loop's thread
(:func:`rm_base.runtime.realtime.loop_thread`) does not make it at all: its lines wait in a
queue that a thread of their own writes, in order with every other thread's lines.
"""

from __future__ import annotations

import atexit
import collections
import ctypes
import logging
import sys
import threading
import time
from typing import Any, NamedTuple

from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.logging import LoggingSeverity

from rm_base.ros.publish import load_function
from rm_base.runtime.realtime import at_most_edge_priority, in_loop_thread

_OWN_FILTERS = frozenset({'throttle_duration_sec', 'once'})
#: Lines of a loop thread held at most while the writing thread is blocked.
MAX_QUEUED_LINES = 1000


class _Location(ctypes.Structure):
    """rcutils_log_location_t."""

    _fields_ = [
        ('function_name', ctypes.c_char_p),
        ('file_name', ctypes.c_char_p),
        ('line_number', ctypes.c_size_t),
    ]


# void rcutils_log(location, severity, name, format, ...): called with format "%s"
_rcutils_log = load_function(
    'librcutils.so', 'rcutils_log',
    (ctypes.POINTER(_Location), ctypes.c_int, ctypes.c_char_p, ctypes.c_char_p), None,
)
_rcutils_initialized = ctypes.c_bool.in_dll(ctypes.CDLL('librcutils.so'),
                                            'g_rcutils_logging_initialized')


class LogLine(NamedTuple):
    """One line for rcutils: its severity, logger name, text and caller."""

    severity: int
    name: str
    message: str
    function: str
    path: str
    line: int


def _encoded(text: str) -> bytes:
    return text.encode('utf-8', 'backslashreplace')


def write_line(line: LogLine) -> None:
    """Hand line to rcutils (console, /rosout, log file), the GIL released meanwhile."""
    if not _rcutils_initialized.value:  # rclpy's call initialises rcutils' logging first
        _rclpy.rclpy_logging_rcutils_log(*line)
        return
    location = _Location(_encoded(line.function), _encoded(line.path), max(line.line, 0))
    _rcutils_log(ctypes.byref(location), line.severity, _encoded(line.name), b'%s',
                 _encoded(line.message))


class LoopLines:
    """The log lines of control loop threads, written by a thread of their own.

    ``put`` never blocks (a deque append and an event). Lines of other threads go through
    ``write`` and come after the queued ones. Over ``max_lines`` queued, the oldest are
    dropped, counted, and reported by the next line written.
    """

    def __init__(self, max_lines: int = MAX_QUEUED_LINES, write: Any = write_line) -> None:
        self._lines: collections.deque[LogLine] = collections.deque(maxlen=max_lines)
        self._write = write
        self._wake = threading.Event()
        self._order = threading.Lock()  # one writer at a time, queued lines first
        self._start_lock = threading.Lock()
        self._thread: threading.Thread | None = None
        self._held = False
        self.dropped = 0
        self._reported = 0

    def put(self, line: LogLine) -> None:
        """Queue line for the writing thread (started with the first line)."""
        lines = self._lines
        if len(lines) == lines.maxlen:
            self.dropped += 1
        lines.append(line)
        if self._thread is None:
            self._start()
        self._wake.set()

    def write(self, line: LogLine) -> None:
        """Write line in the calling thread, after the lines queued before it."""
        with self._order:
            self._drain()
            self._write(line)

    def flush(self) -> None:
        """Write what is queued, in the calling thread."""
        with self._order:
            self._drain()

    def hold(self) -> None:
        """Write what is queued in the calling thread, then hold the writing thread.

        Its lines stay queued until :meth:`release`; other threads' lines are still
        written, after the queued ones.
        """
        with self._order:
            self._drain()
            self._held = True

    def release(self) -> None:
        """Let the writing thread write again, starting with the lines held back."""
        self._held = False
        self._wake.set()

    def _drain(self) -> None:
        # Caller holds self._order.
        lines = self._lines
        while lines:
            dropped = self.dropped - self._reported
            if dropped:  # said by the logger of the oldest line kept, in its place
                self._reported += dropped
                self._write(LogLine(
                    int(LoggingSeverity.WARN), lines[0].name,
                    f'{dropped} log line(s) of the control loop dropped: more than '
                    f'{lines.maxlen} waited to be written', '_drain', __file__, 0))
            self._write(lines.popleft())

    def _start(self) -> None:
        with self._start_lock:
            if self._thread is None:
                thread = threading.Thread(target=self._run, name='rm-log', daemon=True)
                thread.start()
                self._thread = thread

    def _run(self) -> None:
        try:
            at_most_edge_priority()  # started by the loop's thread: not at its priority
        except OSError:
            pass  # no right to change it: it runs as it is
        while True:
            self._wake.wait()
            self._wake.clear()
            try:
                with self._order:  # held is read under the lock hold() sets it under
                    if not self._held:  # else release() wakes the thread again
                        self._drain()
            except Exception as err:  # the thread must go on; rcutils is what failed
                sys.stderr.write(f'rm_base.ros.log: a log line was lost: {err!r}\n')


_LOOP_LINES = LoopLines()
atexit.register(_LOOP_LINES.flush)


def hold_loop_lines() -> None:
    """Write the control loops' queued lines now, then hold their thread's lines back.

    pytest captures output only while a test phase runs; a line written between phases
    goes to the terminal. test/conftest.py holds the lines between phases.
    """
    _LOOP_LINES.hold()


def release_loop_lines() -> None:
    """Undo :func:`hold_loop_lines`: the lines held back are written, then the new ones."""
    _LOOP_LINES.release()


def emit(line: LogLine) -> None:
    """Write line now, or from the writing thread if the caller runs a control loop."""
    if in_loop_thread():
        _LOOP_LINES.put(line)
    else:
        _LOOP_LINES.write(line)


class FastLogger:
    """An rclpy logger (``node.get_logger()``) with a cheap ``log()`` (see the module doc).

    Anything it does not define (``set_level``, ``get_effective_level``, ...) is the
    wrapped logger's.
    """

    def __init__(self, logger: Any) -> None:
        self._logger: Any = logger._logger if isinstance(logger, FastLogger) else logger
        self.name: str = logger.name
        self._filter_lock = threading.Lock()
        self._last: dict[tuple[Any, int], float] = {}  # caller -> last time it logged [s]

    def __getattr__(self, attribute: str) -> Any:
        return getattr(self._logger, attribute)

    def get_child(self, name: str) -> FastLogger:
        """The child logger ``<name>.<child>`` (a ``FastLogger`` too)."""
        return FastLogger(self._logger.get_child(name))

    def is_enabled_for(self, severity: LoggingSeverity) -> bool:
        """Whether a message at severity would go out (the rcutils level check)."""
        return bool(_rclpy.rclpy_logging_logger_is_enabled_for(self.name, severity))

    def log(self, message: str, severity: LoggingSeverity, **kwargs: Any) -> bool:
        """Log message at severity; True if it went out (as rclpy's ``log``)."""
        return self._log(sys._getframe(1), message, severity, kwargs)

    def debug(self, message: str, **kwargs: Any) -> bool:
        """Log at DEBUG."""
        return self._log(sys._getframe(1), message, LoggingSeverity.DEBUG, kwargs)

    def info(self, message: str, **kwargs: Any) -> bool:
        """Log at INFO."""
        return self._log(sys._getframe(1), message, LoggingSeverity.INFO, kwargs)

    def warning(self, message: str, **kwargs: Any) -> bool:
        """Log at WARN."""
        return self._log(sys._getframe(1), message, LoggingSeverity.WARN, kwargs)

    warn = warning

    def error(self, message: str, **kwargs: Any) -> bool:
        """Log at ERROR."""
        return self._log(sys._getframe(1), message, LoggingSeverity.ERROR, kwargs)

    def fatal(self, message: str, **kwargs: Any) -> bool:
        """Log at FATAL."""
        return self._log(sys._getframe(1), message, LoggingSeverity.FATAL, kwargs)

    def log_at(self, severity: LoggingSeverity, message: str, function: str, path: str,
               line: int) -> bool:
        """Log message with the given caller (for records that carry their own)."""
        if not self.is_enabled_for(severity):
            return False
        emit(LogLine(int(severity), self.name, message, function, path, line))
        return True

    def _log(self, frame: Any, message: str, severity: LoggingSeverity,
             kwargs: dict[str, Any]) -> bool:
        if not self.is_enabled_for(severity):
            return False
        if not kwargs.keys() <= _OWN_FILTERS:
            return bool(self._logger.log(message, severity, **kwargs))  # rclpy's filters
        if kwargs and not self._passes(frame, kwargs):
            return False
        code = frame.f_code
        emit(LogLine(int(severity), self.name, str(message), code.co_name, code.co_filename,
                     frame.f_lineno))
        return True

    def _passes(self, frame: Any, kwargs: dict[str, Any]) -> bool:
        """Once and throttle filters, per call site (as rclpy's, on the monotonic clock)."""
        caller = (frame.f_code, frame.f_lasti)
        now = time.monotonic()
        with self._filter_lock:
            last = self._last.get(caller)
            if kwargs.get('once') and last is not None:
                return False
            period = kwargs.get('throttle_duration_sec')
            if period is not None and last is not None and now - last < period:
                return False
            self._last[caller] = now
        return True


_SEVERITIES = (
    (logging.CRITICAL, LoggingSeverity.FATAL),
    (logging.ERROR, LoggingSeverity.ERROR),
    (logging.WARNING, LoggingSeverity.WARN),
    (logging.INFO, LoggingSeverity.INFO),
)


def ros_severity(levelno: int) -> LoggingSeverity:
    """The rclpy severity of a Python logging level."""
    for level, severity in _SEVERITIES:
        if levelno >= level:
            return severity
    return LoggingSeverity.DEBUG


class RosLogHandler(logging.Handler):
    """Forwards Python ``logging`` records (the hardware layer's) to a ``FastLogger``."""

    def __init__(self, logger: FastLogger) -> None:
        super().__init__()
        self._logger = logger
        self.setFormatter(logging.Formatter('%(name)s: %(message)s'))

    def emit(self, record: logging.LogRecord) -> None:
        """Log the record at the matching rclpy severity, with its own caller."""
        try:
            self._logger.log_at(ros_severity(record.levelno), self.format(record),
                                record.funcName, record.pathname, record.lineno)
        except Exception:
            self.handleError(record)


def forward_package_logging(ros_logger_name: str, package: str = 'rm_base') -> RosLogHandler:
    """Send package's Python log records (INFO and up) to the rclpy logger of that name.

    Returns the handler; ``logging.getLogger(package).removeHandler(handler)`` undoes it.
    """
    from rclpy.logging import get_logger

    handler = RosLogHandler(FastLogger(get_logger(ros_logger_name)))
    package_logger = logging.getLogger(package)
    package_logger.addHandler(handler)
    package_logger.setLevel(logging.INFO)
    package_logger.propagate = False
    return handler
