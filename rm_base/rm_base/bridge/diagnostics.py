"""The bridge's /diagnostics: a status per joint and bus, the scheduler and the commands.

Status names follow diagnostic_updater's ``"<node>: <task>"``: ``can_bridge: joint yaw``,
``can_bridge: bus can0``, ``can_bridge: scheduler``, ``can_bridge: commands``. Every value
is a ``KeyValue`` whose key carries its unit.

Levels:

* joint: OK while driven, commanded off or never commanded; WARN when held at zero by a
  command timeout or a bus recovery; ERROR when offline, over temperature, in a device
  fault or after an internal error. The message names the hold reason.
* bus: OK when up (WARN above 80 % load); ERROR when down (being reopened). A SocketCAN
  bus also carries the kernel's view (``ip -details -statistics link``: link up, the
  controller's state and error counters, bus-off and restart counts, frames dropped):
  WARN while its controller is ERROR-PASSIVE, ERROR when the link is down or BUS-OFF.
* scheduler: WARN when deadlines were missed since the previous report, ERROR when a
  tick raised since then.
* commands: WARN when /actuator_cmd messages were rejected since the previous report.
* simulator (a real-time simulated world only; ``rm_sim: simulator`` when the world runs in
  rm_sim's process): WARN when its simulated time slipped behind the wall clock since the
  previous report (a starved CPU): what is measured on it then runs slower than the wall
  clock says.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from typing import Any

from builtin_interfaces.msg import Time
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus

from rm_base.hardware import BusStats, HoldReason, JointState, Mode
from rm_base.hardware.can_link import LinkReport
from rm_base.loop import PeriodStats
from rm_base.loop.timing import HISTOGRAM_EDGES_US
from rm_base.ros.diagnostics import diagnostic_status

OK = DiagnosticStatus.OK
WARN = DiagnosticStatus.WARN
ERROR = DiagnosticStatus.ERROR

#: Level of a joint per hold reason.
HOLD_LEVELS: Mapping[str, bytes] = {
    HoldReason.NONE.value: OK,
    HoldReason.OFF.value: OK,
    HoldReason.NO_COMMAND.value: OK,
    HoldReason.SHUTDOWN.value: OK,
    HoldReason.COMMAND_TIMEOUT.value: WARN,
    HoldReason.BUS_RECOVERY.value: WARN,
    HoldReason.OFFLINE.value: ERROR,
    HoldReason.OVER_TEMPERATURE.value: ERROR,
    HoldReason.DEVICE_FAULT.value: ERROR,
    HoldReason.ERROR.value: ERROR,
}

#: Bus load above which a bus is reported WARN [fraction of the bitrate].
BUS_LOAD_WARN = 0.8


@dataclasses.dataclass(frozen=True)
class CommandStats:
    """Counters of the /actuator_cmd input (monotonic).

    Attributes:
        accepted: messages applied.
        rejected: messages rejected, by :class:`~rm_base.bridge.errors.Rejection` value.
        last_rejection: text of the last rejection, or None.
    """

    accepted: int = 0
    rejected: Mapping[str, int] = dataclasses.field(default_factory=dict)
    last_rejection: str | None = None

    @property
    def rejected_total(self) -> int:
        """All rejected messages."""
        return sum(self.rejected.values())


@dataclasses.dataclass(frozen=True)
class SimulatorStats:
    """How a real-time simulated world kept up with the wall clock (monotonic counters).

    Attributes:
        time_ns: simulated time since the world was made.
        slips: times it fell too far behind to catch up and skipped ahead.
        slipped_ns: the wall-clock time those skips left unsimulated.
    """

    time_ns: int
    slips: int
    slipped_ns: int


class SimulatorReporter:
    """The ``<node>: simulator`` status (the bridge's own world, or rm_sim's).

    Args:
        node_name: the node that reports it (prefix of the status name).
    """

    def __init__(self, node_name: str) -> None:
        self._name = f'{node_name}: simulator'
        self._last_slips = 0

    def status(self, stats: SimulatorStats) -> DiagnosticStatus:
        """The status now: WARN if it slipped since the previous one."""
        new_slips = stats.slips - self._last_slips
        self._last_slips = stats.slips
        if new_slips > 0:
            level, message = WARN, (
                f'simulated time slipped {new_slips} time(s) since the last report (CPU '
                'starved): it ran slower than the wall clock')
        else:
            level, message = OK, 'keeping up with the wall clock'
        values = {
            'time [s]': stats.time_ns / 1e9,
            'slips': stats.slips,
            'slipped [s]': stats.slipped_ns / 1e9,
        }
        return diagnostic_status(self._name, level, message, 'rm_sim', values)

    @staticmethod
    def stats(world: Any) -> SimulatorStats:
        """A real-time SimWorld's counters."""
        return SimulatorStats(world.time_ns, world.overruns, world.slipped_ns)


class DiagnosticsReporter:
    """Builds the DiagnosticArray; remembers counters to report what changed since last time.

    Args:
        node_name: prefix of every status name.
        hardware_ids: per joint, its ``hardware_id`` (default ``<bus>/<type>``).
    """

    def __init__(self, node_name: str, hardware_ids: Mapping[str, str] | None = None) -> None:
        self._prefix = f'{node_name}: '
        self._hardware_ids = dict(hardware_ids or {})
        self._last_overruns = 0
        self._last_errors = 0
        self._last_rejected = 0
        self._simulator = SimulatorReporter(node_name)

    def build(
        self,
        hardware: Mapping[str, Any],
        states: Sequence[JointState],
        commands: CommandStats,
        stamp: Time,
        simulator: SimulatorStats | None = None,
    ) -> DiagnosticArray:
        """One DiagnosticArray.

        Args:
            hardware: ``CanHardware.diagnostics()``.
            states: ``CanHardware.states()``.
            commands: the /actuator_cmd counters.
            stamp: header stamp.
            simulator: the real-time simulated world's clock, if the bridge runs one.
        """
        msg = DiagnosticArray()
        msg.header.stamp = stamp
        joints = hardware['joints']
        msg.status = [self._joint(s, joints[s.name]) for s in states]
        links = hardware.get('links', {})
        msg.status += [self._bus(stats, links.get(name))
                       for name, stats in hardware['buses'].items()]
        msg.status.append(self._scheduler(hardware['scheduler']))
        msg.status.append(self._commands(commands))
        if hardware.get('supercap') is not None:
            msg.status.append(self._supercap(hardware['supercap']))
        if simulator is not None:
            msg.status.append(self._simulator.status(simulator))
        return msg

    def _supercap(self, report: Mapping[str, Any]) -> DiagnosticStatus:
        state = report['state']
        if state in ('offline', 'fault'):
            why = f': {report["errors"]}' if report['errors'] else ''
            level, message = WARN, f'{state}{why}; the chassis keeps to the referee limit'
        else:
            level, message = OK, f'{state}, energy {100 * report["energy"]:.0f} %'
        values = {
            'state': state,
            'energy [%]': 100 * report['energy'],
            'chassis power [W]': report['chassis_power_w'],
            'board limit [W]': report['board_limit_w'],
            'referee limit [W]': report['referee_limit_w'],
            'requested [W]': report['request_w'],
            'errors': report['errors'],
            'frames_decoded': report['frames_decoded'],
            'decode_errors': report['decode_errors'],
        }
        return diagnostic_status(f'{self._prefix}supercap', level, message,
                                 f'{report["bus"]}/supercap', values)

    def _joint(self, state: JointState, diag: Mapping[str, Any]) -> DiagnosticStatus:
        hold = diag['hold_reason']
        level = HOLD_LEVELS.get(hold, ERROR)
        if hold == HoldReason.NONE.value:
            message = f'driven ({Mode(state.mode).name})'
        elif hold == HoldReason.NO_COMMAND.value:
            message = 'idle: no command yet'
        elif hold == HoldReason.OFF.value:
            message = 'off (commanded)'
        else:
            message = f'held at zero: {hold}'
        values = {
            'online': state.online,
            'hold_reason': hold,
            'temperature [degC]': state.temperature,
            'error_code': state.error_code,
            'mode': Mode(state.mode).name,
            'command [N*m]': state.command,
            'position [rad]': state.position,
            'velocity [rad/s]': state.velocity,
            'effort [N*m]': state.effort,
            'frames_decoded': diag['frames_decoded'],
            'decode_errors': diag['decode_errors'],
            'commands_accepted': diag['commands_accepted'],
            'commands_rejected': diag['commands_rejected'],
            'last_rejection': diag['last_rejection'] or '',
            'update_errors': diag['update_errors'],
            **diag.get('details', {}),
        }
        return diagnostic_status(
            f'{self._prefix}joint {state.name}',
            level,
            message,
            self._hardware_ids.get(state.name, f'{diag["bus"]}/{diag["type"]}'),
            values,
        )

    def _bus(self, stats: BusStats, link: LinkReport | None = None) -> DiagnosticStatus:
        load = stats.load_fraction
        if stats.state == 'up':
            level = WARN if load is not None and load > BUS_LOAD_WARN else OK
            message = 'up' if load is None or level == OK else f'up, load {100 * load:.0f} %'
        elif stats.state == 'down':
            level, message = ERROR, f'down, reopening: {stats.last_error or "unknown error"}'
        else:
            level, message = WARN, stats.state
        values = {
            'state': stats.state,
            'load [bit/s]': stats.load_bps,
            'load [%]': 100.0 * load if load is not None else 'unknown (no bitrate)',
            'frames_sent': stats.frames_sent,
            'frames_received': stats.frames_received,
            'frames_unmatched': stats.frames_unmatched,
            'send_errors': stats.send_errors,
            'receive_errors': stats.receive_errors,
            'error_frames': stats.error_frames,
            'handler_errors': stats.handler_errors,
            'reopen_count': stats.reopen_count,
            'open_failures': stats.open_failures,
            'log_dropped': stats.log_dropped,
            'last_error': stats.last_error or '',
            'bus_off': stats.bus_off,
            'last_error_frame': stats.last_error_frame or '',
        }
        if link is not None:
            level, message = _kernel_view(link, level, message)
            values.update(_link_values(link))
        return diagnostic_status(
            f'{self._prefix}bus {stats.name}', level, message, stats.name, values
        )

    def _scheduler(self, stats: PeriodStats) -> DiagnosticStatus:
        new_overruns = stats.overruns - self._last_overruns
        new_errors = stats.errors - self._last_errors
        self._last_overruns, self._last_errors = stats.overruns, stats.errors
        if new_errors > 0:
            level, message = ERROR, f'{new_errors} tick error(s) since the last report'
        elif new_overruns > 0:
            level, message = WARN, f'{new_overruns} overrun(s) since the last report'
        else:
            level, message = OK, 'on time'
        edges = [f'<{e}' for e in HISTOGRAM_EDGES_US] + [f'>={HISTOGRAM_EDGES_US[-1]}']
        values = {
            'rate [Hz]': 1e9 / stats.period_ns,
            'ticks': stats.ticks,
            'overruns': stats.overruns,
            'skipped_ticks': stats.skipped_ticks,
            'period_error_mean [us]': stats.mean_error_us,
            'period_error_max [us]': stats.max_error_us,
            'tick_max [us]': stats.max_tick_us,
            'errors': stats.errors,
        }
        values.update(
            {f'period_error {edge} [us]': n for edge, n in zip(edges, stats.histogram, strict=True)}
        )
        lateness = stats.lateness
        values.update({
            'lateness p50 [us]': lateness.p50_us,
            'lateness p99 [us]': lateness.p99_us,
            'lateness max [us]': lateness.max_us,
        })
        # Every component of the loop (feedback, each plugin, actuators, stages, pack,
        # send): how long it takes, since start.
        for name, summary in stats.components:
            values[f'{name} runs'] = summary.count
            values[f'{name} p50 [us]'] = summary.p50_us
            values[f'{name} p99 [us]'] = summary.p99_us
            values[f'{name} max [us]'] = summary.max_us
        return diagnostic_status(f'{self._prefix}scheduler', level, message, 'scheduler', values)

    def _commands(self, stats: CommandStats) -> DiagnosticStatus:
        total = stats.rejected_total
        new = total - self._last_rejected
        self._last_rejected = total
        if new > 0:
            level = WARN
            message = f'{new} /actuator_cmd message(s) rejected since the last report'
        else:
            level, message = OK, 'ok'
        values: dict[str, Any] = {'accepted': stats.accepted, 'rejected': total}
        values.update({f'rejected {reason}': n for reason, n in sorted(stats.rejected.items())})
        values['last_rejection'] = stats.last_rejection or ''
        return diagnostic_status(f'{self._prefix}commands', level, message, 'actuator_cmd', values)


def _kernel_view(link: LinkReport, level: bytes, message: str) -> tuple[bytes, str]:
    """The bus's level and message with what the kernel says of its interface."""
    if not link.exists:
        return ERROR, 'the interface does not exist'
    if not link.up:
        return ERROR, f'link down (kernel); {message}'
    if link.healthy:
        return level, message
    worst = ERROR if link.can_state == 'BUS-OFF' else max(level, WARN)
    return worst, f'controller {link.can_state}; {message}'


def _link_values(link: LinkReport) -> dict[str, Any]:
    values: dict[str, Any] = {
        'kernel link': 'up' if link.up else ('down' if link.exists else 'missing'),
        'kernel kind': link.kind or 'unknown',
    }
    if link.can_state:
        values['kernel can_state'] = link.can_state
    if link.tx_error_counter is not None:
        values['kernel tx_error_counter'] = link.tx_error_counter
        values['kernel rx_error_counter'] = link.rx_error_counter
    if link.restart_ms is not None:
        values['kernel restart_ms'] = link.restart_ms
    values.update({f'kernel {name}': n for name, n in link.counters.items()})
    return values
