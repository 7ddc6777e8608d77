"""What every serial-device plugin shares: its port settings, its link state, its report.

A plugin that owns a serial device (the Hi220 IMU, the referee system) declares the same
port parameters, decides its state from the reader's counters and the age of its last good
frame, and reports the same counters on /diagnostics; only what it does with a frame
differs.
"""

from __future__ import annotations

import os
import threading
from collections.abc import Callable
from dataclasses import dataclass
from enum import IntEnum
from typing import Any

import serial
from diagnostic_msgs.msg import DiagnosticStatus
from rm_base.plugin import PluginConfigError, PluginParams
from rm_base.ros.diagnostics import diagnostic_status

from rm_plugins.serial.reader import FrameStream, ReaderStats, SerialReader

_NS_PER_S = 1_000_000_000


class LinkState(IntEnum):
    """States of a serial-device plugin.

    PASSIVE: disabled, the port closed. NO_PORT: the port cannot be opened, or it failed or
    went silent and is being reopened with back-off. NO_DATA: the port is open but no good
    frame came within ``data_timeout`` (the link is lost). STREAMING: good frames arrive.
    """

    PASSIVE = 0
    NO_PORT = 1
    NO_DATA = 2
    STREAMING = 3


LEVELS = {
    LinkState.PASSIVE: DiagnosticStatus.OK,
    LinkState.NO_PORT: DiagnosticStatus.ERROR,
    LinkState.NO_DATA: DiagnosticStatus.WARN,
    LinkState.STREAMING: DiagnosticStatus.OK,
}


def expand_port(port: str) -> str:
    """Expand ``${VAR}`` (and ``~`` in a plain path) in a port name.

    Raises:
        PluginConfigError: the name is empty or uses an unset environment variable.
    """
    expanded = os.path.expandvars(port.strip())
    if '://' not in expanded:
        expanded = os.path.expanduser(expanded)
    if not expanded or '$' in expanded:
        raise PluginConfigError(f'port {port!r} is empty or uses an unset environment variable')
    return expanded


@dataclass(frozen=True)
class SerialSettings:
    """A serial device's port and how its reader treats it (see ``read_serial_settings``)."""

    port: str
    baudrate: int
    data_timeout: float
    read_timeout: float
    backoff_min: float
    backoff_max: float
    silence_reopen: float
    diagnostics_period: float


def read_serial_settings(
    p: PluginParams, *, baudrate: int, data_timeout: float, silence_reopen: float,
    port: str | None = None,
) -> SerialSettings:
    """Declare and read the port parameters (defaults as the device wants them).

    port: the port, when the plugin declared ``port`` itself (an optional device).

    Raises:
        ParameterError: a parameter is missing or out of bounds.
        PluginConfigError: the port name, or reopen_backoff_max below reopen_backoff_min.
    """
    if port is None:
        port = p.string(
            'port',
            description='serial port: device path or pyserial URL; ${VAR} and ~ are expanded',
        )
    port = expand_port(port)
    baud = p.integer('baudrate', baudrate, description='baud rate', unit='bit/s', gt=0)
    timeout = p.double(
        'data_timeout', data_timeout, unit='s', gt=0.0,
        description='no valid frame this long -> NO_DATA',
    )
    read_timeout = p.double(
        'read_timeout', 0.02, unit='s', gt=0.0, le=1.0,
        description='longest blocking read in the reader thread',
    )
    backoff_min = p.double(
        'reopen_backoff_min', 0.1, unit='s', gt=0.0,
        description='first wait before reopening a lost port',
    )
    backoff_max = p.double(
        'reopen_backoff_max', 2.0, unit='s', gt=0.0,
        description='longest wait between reopen attempts',
    )
    if backoff_max < backoff_min:
        raise PluginConfigError(
            f'reopen_backoff_max ({backoff_max} s) is below reopen_backoff_min ({backoff_min} s)'
        )
    silence = p.double(
        'silence_reopen', silence_reopen, unit='s', ge=0.0,
        description='reopen a port silent this long; 0 = never',
    )
    diagnostics_period = p.double(
        'diagnostics_period', 1.0, unit='s', gt=0.0,
        description='period of the /diagnostics status',
    )
    return SerialSettings(
        port, baud, timeout, read_timeout, backoff_min, backoff_max, silence, diagnostics_period
    )


def make_reader(
    settings: SerialSettings, on_item: Callable[[Any], None], logger: Any, *,
    parser: FrameStream, name: str, polled: bool, parity: str = serial.PARITY_NONE,
) -> SerialReader:
    """The reader of a device with these settings (not started).

    parity: pyserial's ``PARITY_*`` (the DR16 sends 8E1). A pseudo-terminal (the
    simulator's) has no wire to check parity on, and Linux refuses the setting when one is
    opened again: it is opened without.
    """
    def opener(url: str, baudrate: int, timeout: float) -> Any:
        wire = parity if not _is_pseudo_terminal(url) else serial.PARITY_NONE
        return serial.serial_for_url(url, baudrate=baudrate, timeout=timeout, parity=wire)

    return SerialReader(
        settings.port, settings.baudrate, on_item, logger,
        read_timeout=settings.read_timeout, backoff_min=settings.backoff_min,
        backoff_max=settings.backoff_max, silence_reopen=settings.silence_reopen,
        polled=polled, parser=parser, name=name, opener=opener,
    )


def _is_pseudo_terminal(url: str) -> bool:
    return os.path.realpath(url).startswith('/dev/pts/')


class DeviceLink:
    """A device plugin's reader and the time of its last good frame.

    The reader calls :meth:`received` for every good frame; the plugin's tick asks
    :meth:`decide` for the state. In the control loop the loop reads the port at the start
    of each tick, before the plugins run (``SerialReader.poll``), else the reader's thread does;
    ``polled=False`` keeps the thread reading in the loop too (a device framed by the
    silences between its bursts, the DR16, must be read as the bytes arrive).
    """

    def __init__(
        self, plugin: Any, settings: SerialSettings, on_item: Callable[[Any], None], *,
        parser: FrameStream, name: str, polled: bool | None = None,
        parity: str = serial.PARITY_NONE,
    ) -> None:
        self.settings = settings
        self._logger = plugin.logger
        self.reader = make_reader(
            settings, on_item, plugin.logger, parser=parser, name=name,
            polled=plugin.in_loop if polled is None else polled, parity=parity,
        )
        if self.reader.polled:
            plugin.loop_input(self.reader.poll, f'{plugin.name} port')
        self._lock = threading.Lock()
        self._last_ns: int | None = None

    def start(self) -> None:
        """Forget the last frame and start the reader (it opens the port)."""
        with self._lock:
            self._last_ns = None
        self.reader.start()

    def stop(self) -> None:
        """Stop the reader and close the port (logs if the thread does not end)."""
        if not self.reader.stop():
            self._logger.error(f'the reader of {self.settings.port} did not stop')

    def received(self, now_ns: int) -> None:
        """A good frame arrived now (the reading thread)."""
        with self._lock:
            self._last_ns = now_ns

    def decide(self, now_ns: int) -> tuple[LinkState, str, ReaderStats]:
        """The state, why, and the reader's counters (plugin tick)."""
        stats = self.reader.stats()
        with self._lock:
            last_ns = self._last_ns
        state, reason = decide_link(self.settings, stats, last_ns, now_ns)
        return state, reason, stats


def decide_link(
    settings: SerialSettings, stats: ReaderStats, last_ns: int | None, now_ns: int
) -> tuple[LinkState, str]:
    """The state of an enabled device and why, from the reader and its last good frame."""
    port = settings.port
    if not stats.port_open:
        return LinkState.NO_PORT, f'{stats.last_error or "opening"}; reopening with back-off'
    if last_ns is None:
        return LinkState.NO_DATA, f'{port} open, no valid frame yet'
    if now_ns - last_ns > settings.data_timeout * _NS_PER_S:
        return LinkState.NO_DATA, f'no valid frame from {port} within {settings.data_timeout:.3f} s'
    return LinkState.STREAMING, f'streaming from {port}'


def link_status(
    name: str, settings: SerialSettings, state: LinkState, stats: ReaderStats, *,
    reason: str, new_bad: int, values: dict[str, Any],
) -> DiagnosticStatus:
    """One /diagnostics status: the state, the reader's counters and the device's values.

    A device streaming with bad frames since the last report is a warning.
    """
    level = LEVELS[state]
    if level == DiagnosticStatus.OK and new_bad:
        level = DiagnosticStatus.WARN
    message = reason if not new_bad else f'{reason}; {new_bad} bad frame(s) skipped'
    return diagnostic_status(name, level, message, settings.port, {
        'state': state.name,
        'port': settings.port,
        'baudrate [bit/s]': settings.baudrate,
        **values,
        'frames_ok': stats.frames_ok,
        'crc_errors': stats.crc_errors,
        'length_errors': stats.length_errors,
        'decode_errors': stats.decode_errors,
        'sample_errors': stats.sample_errors,
        'bytes_read': stats.bytes_read,
        'bytes_discarded': stats.bytes_discarded,
        'opens': stats.opens,
        'open_failures': stats.open_failures,
        'port_losses': stats.port_losses,
        'last_error': stats.last_error or '',
    })
