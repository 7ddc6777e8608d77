"""``rmcli bag plot``: PNG plots of what a bag says about chassis, gimbal and shooter.

- ``chassis_velocity.png``: commanded vs measured chassis velocity (vx, vy [m/s],
  wz [rad/s]) from ``*/vel_cmd`` (geometry_msgs/Twist), ChassisState (``cmd_vel`` after
  ramps and limits, ``measured_vel``) and nav_msgs/Odometry, plus the chassis mode
  (ChassisCmd.mode, ChassisState.state).
- ``gimbal.png``: GimbalState yaw and pitch vs their targets [rad], and the gimbal state.
- ``shooter.png``: ShooterState shots fired, burst remaining and state; ShootCmd modes.

Plugin state topics are found by message type, not by name; several topics of one type
are all drawn, labelled by topic. Time is the receive time in seconds from the bag start.
Messages are decoded with the types the bag embeds (rosbags AnyReader).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .bag_io import open_bag, read_messages
from .bag_types import BagTypes, rm_bag_types
from .errors import BagError, CliError

TWIST = 'geometry_msgs/msg/Twist'
ODOMETRY = 'nav_msgs/msg/Odometry'
CHASSIS_CMD = 'rm_msgs/msg/ChassisCmd'
CHASSIS_STATE = 'rm_msgs/msg/ChassisState'
GIMBAL_CMD = 'rm_msgs/msg/GimbalCmd'
GIMBAL_STATE = 'rm_msgs/msg/GimbalState'
SHOOT_CMD = 'rm_msgs/msg/ShootCmd'
SHOOTER_STATE = 'rm_msgs/msg/ShooterState'
VEL_CMD_NAME = 'vel_cmd'  # a Twist topic is the velocity command when its last name is this


def _twist(prefix: str, twist) -> dict[str, float]:
    return {
        f'{prefix}vx': twist.linear.x,
        f'{prefix}vy': twist.linear.y,
        f'{prefix}wz': twist.angular.z,
    }


# msgtype -> message -> named values of one sample (rosbags' deserialised message classes
# are made at run time from the type definitions: Any)
EXTRACTORS: dict[str, Callable[[Any], dict[str, float]]] = {
    TWIST: lambda m: _twist('', m),
    ODOMETRY: lambda m: _twist('', m.twist.twist),
    CHASSIS_CMD: lambda m: {'mode': m.mode},
    CHASSIS_STATE: lambda m: {
        'state': m.state,
        **_twist('cmd_', m.cmd_vel),
        **_twist('measured_', m.measured_vel),
    },
    GIMBAL_STATE: lambda m: {
        'state': m.state,
        'yaw': m.yaw,
        'pitch': m.pitch,
        'yaw_target': m.yaw_target,
        'pitch_target': m.pitch_target,
    },
    SHOOTER_STATE: lambda m: {
        'state': m.state,
        'shots_fired': m.shots_fired,
        'burst_remaining': m.burst_remaining,
    },
    SHOOT_CMD: lambda m: {'mode': m.mode, 'burst_id': m.burst_id},
}

# Constants of those messages that name another field's values (ChassisCmd.speed_gear's
# GEAR_NORMAL = 0 would otherwise name mode 0).
NOT_STATES = ('GEAR_',)
# Which message's constants name the values of a state/mode column.
STATE_NAMES_FROM = {
    (CHASSIS_CMD, 'mode'): CHASSIS_CMD,
    (CHASSIS_STATE, 'state'): CHASSIS_CMD,
    (GIMBAL_STATE, 'state'): GIMBAL_CMD,
    (SHOOTER_STATE, 'state'): SHOOTER_STATE,
    (SHOOT_CMD, 'mode'): SHOOT_CMD,
}


@dataclass
class Track:
    """The samples of one topic: times [s from bag start] and named value columns."""

    topic: str
    msgtype: str
    t: list[float] = field(default_factory=list)
    columns: dict[str, list[float]] = field(default_factory=dict)

    def add(self, t: float, values: dict[str, float]) -> None:
        """Append one sample."""
        self.t.append(t)
        for name, value in values.items():
            self.columns.setdefault(name, []).append(float(value))


@dataclass
class PlotData:
    """Everything plottable in a bag."""

    tracks: list[Track]
    state_names: dict[str, dict[int, str]]  # msgtype -> value -> constant name
    skipped: dict[str, str] = field(default_factory=dict)  # topic -> why it is not plotted

    def of_type(self, msgtype: str) -> list[Track]:
        """Tracks of one message type, in topic order."""
        return [t for t in self.tracks if t.msgtype == msgtype]


def _wanted(topic: str, msgtype: str) -> bool:
    if msgtype == TWIST:
        return topic.rsplit('/', 1)[-1] == VEL_CMD_NAME
    return msgtype in EXTRACTORS


def read_plot_data(path: Path) -> PlotData:
    """Read the plottable topics of a bag.

    Raises:
        BagError: the bag cannot be read.
    """
    try:
        local = rm_bag_types()  # only used for bags that embed no definitions
    except BagError:
        local = BagTypes()
    with open_bag(path, typed=True, default_typestore=local.typestore) as reader:
        connections = [c for c in reader.connections if _wanted(c.topic, c.msgtype)]
        tracks: dict[str, Track] = {}
        skipped: dict[str, str] = {}
        if connections:
            start_ns = reader.start_time
            for connection, stamp_ns, raw in read_messages(reader, path, connections):
                try:
                    msg = reader.deserialize(raw, connection.msgtype)
                except Exception as err:
                    raise BagError(
                        f'cannot decode a {connection.msgtype} in {path}: {err}'
                    ) from None
                topic = connection.topic
                if topic in skipped:
                    continue
                values = EXTRACTORS[connection.msgtype](msg)
                odd = next(((k, v) for k, v in values.items()
                            if not isinstance(v, int | float)), None)
                if odd is not None:  # recorded in another definition of the type
                    skipped[topic] = (f'its {odd[0]} is {type(odd[1]).__name__} '
                                      f'{odd[1]!r}, not a number (recorded in another '
                                      f'definition of {connection.msgtype})')
                    tracks.pop(topic, None)
                    continue
                track = tracks.setdefault(topic, Track(topic, connection.msgtype))
                track.add((stamp_ns - start_ns) * 1e-9, values)
        bag_types = BagTypes(reader.typestore)
        names = {}
        for source in set(STATE_NAMES_FROM.values()):
            constants = bag_types.constants(source) or local.constants(source)
            names[source] = {int(v): k for k, v in constants.items()
                             if isinstance(v, int) and not k.startswith(NOT_STATES)}
    return PlotData(sorted(tracks.values(), key=lambda t: t.topic), names, skipped)


# ---------------------------------------------------------------------------------------------
# Drawing


def modes_seen(data: PlotData) -> list[str]:
    """Per state or mode column, the names of the values it took, in order of first use.

    ``/chassis_cmd mode: GYRO, POSITION``: what the plots' mode lanes show, said in words.
    """
    lines = []
    for track in data.tracks:
        for column, column_values in track.columns.items():
            source = STATE_NAMES_FROM.get((track.msgtype, column))
            if source is None:
                continue
            names = data.state_names.get(source, {})
            seen = list(dict.fromkeys(int(v) for v in column_values))
            lines.append(f'{track.topic} {column}: '
                         + ', '.join(names.get(v, str(v)) for v in seen))
    return lines


def _state_axis(ax, data: PlotData, sources: list[tuple[Track, str]], title: str) -> None:
    ticks: dict[int, str] = {}
    for track, column in sources:
        ax.step(track.t, track.columns[column], where='post', label=f'{track.topic} {column}')
        names = data.state_names.get(STATE_NAMES_FROM[(track.msgtype, column)], {})
        ticks.update(names)
    if ticks:
        ax.set_yticks(sorted(ticks), [ticks[v] for v in sorted(ticks)])
    ax.set_ylabel(title)
    ax.legend(loc='upper right', fontsize='small')
    ax.grid(True, alpha=0.3)


def _new_figure(rows: int, title: str):
    from matplotlib.figure import Figure

    fig = Figure(figsize=(11, 2.4 * rows + 0.6), layout='constrained')
    axes = fig.subplots(rows, 1, sharex=True, squeeze=False)[:, 0]
    fig.suptitle(title)
    axes[-1].set_xlabel('time since bag start [s]')
    return fig, list(axes)


def plot_chassis(data: PlotData, out: Path) -> Path | None:
    """Commanded vs measured chassis velocity, and the chassis mode; None if no data."""
    commands = data.of_type(TWIST)
    states = data.of_type(CHASSIS_STATE)
    odometry = data.of_type(ODOMETRY)
    modes = data.of_type(CHASSIS_CMD)
    velocity = bool(commands or states or odometry)
    if not (velocity or modes):
        return None
    rows = (3 if velocity else 0) + (1 if modes or states else 0)
    fig, axes = _new_figure(rows, 'Chassis: commanded vs measured velocity (base_link)')
    if velocity:
        for ax, (axis, unit) in zip(
            axes, (('vx', 'm/s'), ('vy', 'm/s'), ('wz', 'rad/s')), strict=False
        ):
            for track in commands:
                ax.step(
                    track.t, track.columns[axis], where='post', label=f'{track.topic} (command)'
                )
            for track in states:
                ax.plot(track.t, track.columns[f'cmd_{axis}'], label=f'{track.topic} cmd_vel')
                ax.plot(
                    track.t, track.columns[f'measured_{axis}'], label=f'{track.topic} measured_vel'
                )
            for track in odometry:
                ax.plot(track.t, track.columns[axis], '--', label=f'{track.topic} twist')
            ax.set_ylabel(f'{axis} [{unit}]')
            ax.legend(loc='upper right', fontsize='small')
            ax.grid(True, alpha=0.3)
    if modes or states:
        sources = [(t, 'mode') for t in modes] + [(t, 'state') for t in states]
        _state_axis(axes[-1], data, sources, 'mode / state')
    path = out / 'chassis_velocity.png'
    fig.savefig(path, dpi=100)
    return path


def plot_gimbal(data: PlotData, out: Path) -> Path | None:
    """Gimbal yaw and pitch vs targets, and the gimbal state; None if no GimbalState."""
    states = data.of_type(GIMBAL_STATE)
    if not states:
        return None
    fig, axes = _new_figure(3, 'Gimbal: measured vs target (world frame)')
    for ax, angle in zip(axes, ('yaw', 'pitch'), strict=False):
        for track in states:
            ax.plot(track.t, track.columns[angle], label=f'{track.topic} {angle}')
            ax.step(
                track.t,
                track.columns[f'{angle}_target'],
                where='post',
                linestyle='--',
                label=f'{track.topic} {angle}_target',
            )
        ax.set_ylabel(f'{angle} [rad]')
        ax.legend(loc='upper right', fontsize='small')
        ax.grid(True, alpha=0.3)
    _state_axis(axes[2], data, [(t, 'state') for t in states], 'state')
    path = out / 'gimbal.png'
    fig.savefig(path, dpi=100)
    return path


def plot_shooter(data: PlotData, out: Path) -> Path | None:
    """Shots fired, burst remaining and shooter state/commands; None if neither type."""
    states = data.of_type(SHOOTER_STATE)
    commands = data.of_type(SHOOT_CMD)
    if not (states or commands):
        return None
    rows = (2 if states else 0) + (1 if commands else 0)
    fig, axes = _new_figure(rows, 'Shooter: events over time')
    row = iter(axes)
    if states:
        ax = next(row)
        for track in states:
            ax.step(
                track.t,
                track.columns['shots_fired'],
                where='post',
                label=f'{track.topic} shots_fired',
            )
            ax.step(
                track.t,
                track.columns['burst_remaining'],
                where='post',
                linestyle='--',
                label=f'{track.topic} burst_remaining',
            )
        ax.set_ylabel('shots')
        ax.legend(loc='upper left', fontsize='small')
        ax.grid(True, alpha=0.3)
        _state_axis(next(row), data, [(t, 'state') for t in states], 'state')
    if commands:
        _state_axis(next(row), data, [(t, 'mode') for t in commands], 'command mode')
    path = out / 'shooter.png'
    fig.savefig(path, dpi=100)
    return path


PLOTS = (
    (
        plot_chassis,
        'chassis_velocity.png',
        f'*/{VEL_CMD_NAME} (Twist), ChassisCmd, ChassisState or Odometry',
    ),
    (plot_gimbal, 'gimbal.png', 'GimbalState'),
    (plot_shooter, 'shooter.png', 'ShooterState or ShootCmd'),
)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the options of ``bag plot``."""
    parser.add_argument('bag_path', help='Bag to open (folder, .mcap or .db3)')
    parser.add_argument(
        '-o', '--output', required=True, help='Folder for the PNG files (created if missing)'
    )


def run(args: argparse.Namespace) -> int:
    """Write the PNG files the bag has data for; fail if it has none."""
    import matplotlib

    matplotlib.use('Agg')  # files only; no display needed

    path = Path(args.bag_path)
    data = read_plot_data(path)
    for topic, why in sorted(data.skipped.items()):
        print(f'skipped {topic}: {why}', file=sys.stderr)
    if not data.tracks:
        wanted = '; '.join(needs for _, _, needs in PLOTS)
        raise CliError(f'nothing to plot in {path}: it has none of {wanted}')
    out = Path(args.output)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise CliError(f"cannot create output folder '{out}': {err}") from None
    for plot, name, needs in PLOTS:
        written = plot(data, out)
        if written is None:
            print(f'skipped {name}: the bag has no {needs}')
        else:
            print(f'wrote {written}')
    for line in modes_seen(data):
        print(line)
    return 0
