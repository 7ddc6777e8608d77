"""The kernel's view of a SocketCAN interface: up or down, controller state, counters.

What ``ip -details -statistics link show dev can0`` prints (docs/KERNEL_CAN.md, "What the
kernel counts"): whether the link is up, the controller's state (ERROR-ACTIVE,
ERROR-WARNING, ERROR-PASSIVE, BUS-OFF, STOPPED), its error counters, how often it went
bus-off and was restarted, and the interface's frame and drop counters. A vcan has no
controller: only the link and the counters. Read off the control loop (the diagnostics
publisher), at most once a second per interface.
"""

from __future__ import annotations

import json
import subprocess
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

# IFF_UP in /sys/class/net/<if>/flags: the administrator's "ip link set up".
_IFF_UP = 0x1
#: How often one interface is asked again [s].
READ_PERIOD_S = 1.0


@dataclass(frozen=True)
class LinkReport:
    """One reading of an interface.

    Attributes:
        exists: the interface exists.
        up: it is administratively up.
        kind: ``can``, ``vcan``, ``slcan``... ('' when the kernel does not say).
        can_state: the controller's state ('' without a controller, as on vcan).
        tx_error_counter, rx_error_counter: the controller's error counters, if reported.
        counters: the kernel's counters by name (rx/tx packets, errors, dropped,
            over_errors; bus_off, error_passive, error_warning, bus_error,
            arbitration_lost, restarts on a CAN controller).
        restart_ms: automatic restart after bus-off [ms], 0 = never; None if not a CAN
            controller.
        bitrate: the controller's bitrate, if it has one.
    """

    exists: bool
    up: bool = False
    kind: str = ''
    can_state: str = ''
    tx_error_counter: int | None = None
    rx_error_counter: int | None = None
    counters: dict[str, int] = field(default_factory=dict)
    restart_ms: int | None = None
    bitrate: int | None = None

    @property
    def healthy(self) -> bool:
        """Up, and its controller (if any) neither passive nor off the bus."""
        return self.exists and self.up and self.can_state in ('', 'ERROR-ACTIVE',
                                                              'ERROR-WARNING')


_STATS = ('packets', 'errors', 'dropped', 'over_errors')
_XSTATS = ('bus_off', 'error_passive', 'error_warning', 'bus_error', 'arbitration_lost',
           'restarts')


def parse_ip_link(text: str) -> LinkReport:
    """A LinkReport from ``ip -details -statistics -json link show dev X``'s output.

    Raises:
        ValueError: the text is not that command's JSON.
    """
    try:
        link: dict[str, Any] = json.loads(text)[0]
    except (ValueError, IndexError, KeyError, TypeError) as err:
        raise ValueError(f'not the JSON of `ip -json link show`: {err}') from err
    if not isinstance(link, dict):
        raise ValueError(f'not the JSON of `ip -json link show`: {link!r}')
    info = link.get('linkinfo') or {}
    data = info.get('info_data') or {}
    xstats = info.get('info_xstats') or {}
    berr = data.get('berr_counter') or {}
    stats = link.get('stats64') or link.get('stats') or {}
    counters: dict[str, int] = {}
    for direction in ('rx', 'tx'):
        for name in _STATS:
            value = (stats.get(direction) or {}).get(name)
            if isinstance(value, int):
                counters[f'{direction}_{name}'] = value
    for name in _XSTATS:
        if isinstance(xstats.get(name), int):
            counters[name] = xstats[name]
    bitrate = (data.get('bittiming') or {}).get('bitrate')
    restart = data.get('restart_ms')
    return LinkReport(
        exists=True,
        up='UP' in (link.get('flags') or []),
        kind=str(info.get('info_kind', '')),
        can_state=str(data.get('state', '')),
        tx_error_counter=berr.get('tx') if isinstance(berr.get('tx'), int) else None,
        rx_error_counter=berr.get('rx') if isinstance(berr.get('rx'), int) else None,
        counters=counters,
        restart_ms=restart if isinstance(restart, int) else None,
        bitrate=bitrate if isinstance(bitrate, int) else None,
    )


def read_link(interface: str) -> LinkReport | None:
    """Ask ``ip`` about interface now; None when ``ip`` cannot answer (missing, timed out)."""
    try:
        done = subprocess.run(
            ['ip', '-details', '-statistics', '-json', 'link', 'show', 'dev', interface],
            capture_output=True, text=True, timeout=2.0, check=False,
        )
    except (OSError, subprocess.SubprocessError):
        return None
    if done.returncode != 0:
        return LinkReport(exists=False) if 'does not exist' in done.stderr else None
    try:
        return parse_ip_link(done.stdout)
    except ValueError:
        return None


def link_is_up(interface: str, sys_net: Path = Path('/sys/class/net')) -> bool | None:
    """Whether interface is administratively up (sysfs, cheap).

    None if it does not exist or this system has no sysfs for it.
    """
    try:
        flags = int((sys_net / interface / 'flags').read_text(), 16)
    except (OSError, ValueError):
        return None
    return bool(flags & _IFF_UP)


class LinkReader:
    """The latest LinkReport of each interface, re-read at most every ``period_s``."""

    def __init__(self, read: Callable[[str], LinkReport | None] = read_link,
                 period_s: float = READ_PERIOD_S,
                 clock: Callable[[], float] = time.monotonic) -> None:
        self._read = read
        self._period_s = period_s
        self._clock = clock
        self._latest: dict[str, tuple[float, LinkReport | None]] = {}

    def report(self, interface: str) -> LinkReport | None:
        """The interface's report, read now unless read less than a period ago."""
        now = self._clock()
        cached = self._latest.get(interface)
        if cached is not None and now - cached[0] < self._period_s:
            return cached[1]
        report = self._read(interface)
        self._latest[interface] = (now, report)
        return report
