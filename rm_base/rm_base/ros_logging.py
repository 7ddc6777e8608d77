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
"""

from __future__ import annotations

import logging
import sys
import threading
import time
from typing import Any

from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.logging import LoggingSeverity

_OWN_FILTERS = frozenset({'throttle_duration_sec', 'once'})


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
        return _rclpy.rclpy_logging_logger_is_enabled_for(self.name, severity)

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
        _rclpy.rclpy_logging_rcutils_log(severity, self.name, message, function, path, line)
        return True

    def _log(self, frame: Any, message: str, severity: LoggingSeverity,
             kwargs: dict[str, Any]) -> bool:
        if not self.is_enabled_for(severity):
            return False
        if not kwargs.keys() <= _OWN_FILTERS:
            return self._logger.log(message, severity, **kwargs)  # rclpy's filters
        if kwargs and not self._passes(frame, kwargs):
            return False
        code = frame.f_code
        _rclpy.rclpy_logging_rcutils_log(
            severity, self.name, str(message), code.co_name, code.co_filename, frame.f_lineno)
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
