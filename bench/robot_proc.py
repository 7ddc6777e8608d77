"""Child process of the bench: the whole standard robot in one process, instrumented.

Why one module: the instrumented robot and every measuring hook the bench asks it for; each
hook is short.

Exactly what ``bringup --robot standard --sim`` runs (can_bridge + rm_robot on one
EventsExecutor spun by the main thread, the 1 kHz loop running the plugins, the edge's
publisher and reader threads; rm_sim in a process of its own, or in this one for the split
robot's bridge), plus measuring hooks that cost nothing until a
phase uses them. The parent (:mod:`bench.robot`) drives it with one command per stdin line
and reads one ``@@BENCH {json}`` line per command from stdout:

* ``ready <timeout>``: wait until every joint reports feedback;
* ``wait_active <timeout> <joint>...``: wait until those joints are driven (not held);
* ``measure <name> <seconds>``: CPU per thread, scheduler period errors, frame rates,
  steal and load over a window;
* ``tap_on <joint>...`` / ``tap_off``: record, on CLOCK_MONOTONIC, every command frame of
  those (DJI) joints on the wire (a second rm_sim bus on the channel) and every joint
  target the bridge applies;
* ``profile <seconds> <dir>``: cProfile every robot thread (:mod:`bench.profiling`);
* ``quit``: shut down as bringup does (zero output first).

Run as ``python -m bench.robot_proc [--plugins a,b]`` from the repository root.
"""

from __future__ import annotations

import argparse
import array
import dataclasses
import json
import os
import pathlib
import resource
import shutil
import sys
import tempfile
import threading
import time
from typing import Any

from bench.protocol import reply, serve

#: How long a profiled thread may take to pass its check after the window [s].
_PROFILE_STOP_WAIT_S = 10.0


def make_tap_class():
    from rm_base.sim import SimBus

    class TapBus(SimBus):
        """A second rm_sim bus on a channel that keeps (t_ns, id, data) of some frames.

        The channel hands it every frame synchronously inside the sender's ``send``, so
        the stamp is the moment the bridge put the frame on the (simulated) wire.
        """

        def __init__(self, channel: str, world: Any, ids: set[int]) -> None:
            self.records: list[tuple[int, int, str]] = []
            self._ids = frozenset(ids)
            super().__init__(channel=channel, world=world)

        def _deliver(self, msg: Any) -> None:
            if msg.arbitration_id in self._ids:
                self.records.append((time.monotonic_ns(), msg.arbitration_id, msg.data.hex()))

    return TapBus


class _SendTap:
    """Keeps (t_ns, id, data) of some frames a ManagedBus sends (rm_sim in its process).

    Stamped when the bus has handed the tick's frames to its driver
    (``ManagedBus.observe_sent``): the moment they went on the socket, as the in-process
    tap stamps them on the simulated wire.
    """

    def __init__(self, bus: Any, channel: str, ids: set[int]) -> None:
        self.records: list[tuple[int, int, str]] = []
        self.channel_id = channel
        self._bus = bus
        wanted = frozenset(ids)

        def record(msgs: Any) -> None:
            now = time.monotonic_ns()
            for msg in msgs:
                if msg.arbitration_id in wanted:
                    self.records.append((now, msg.arbitration_id, msg.data.hex()))

        bus.observe_sent(record)

    def shutdown(self) -> None:
        self._bus.observe_sent(None)


class Robot:
    """The robot and its measuring hooks (see the module docstring)."""

    def __init__(self, plugins: list[str] | None, role: str = 'all', imu_dir: str = '') -> None:
        import rclpy
        from rclpy.experimental import EventsExecutor
        from rclpy.signals import SignalHandlerOptions
        from rm_base.bridge import CanBridgeNode
        from rm_base.host.node import RobotHost
        from rm_base.ros.env import prepare_ros_process
        from rm_bringup.bringup import parameter_files
        from rm_bringup.sim_process import SimProcess

        from bench.scheduler_timing import TickRecorder

        prepare_ros_process()
        self._tmp = tempfile.mkdtemp(prefix='rm_bench_')
        files = parameter_files('standard', None, True)
        # a private pty for the simulated IMU (the config's path has the domain id only);
        # with the robot split over two processes the parent names one for both
        overlay = pathlib.Path(self._tmp) / 'bench_overlay.yaml'
        imu = os.path.join(imu_dir or self._tmp, 'imu')
        host_params: dict[str, Any] = {'imu': {'port': imu}}
        if plugins:
            host_params['plugins'] = plugins
        overlay.write_text(
            json.dumps(
                {
                    'can_bridge': {'ros__parameters': {'sim.imu.path': imu}},
                    'rm_robot': {'ros__parameters': host_params},
                }
            )
        )
        files = [*files, overlay]
        # As make run and robot.launch.py split:=true lay it out: rm_sim (the motors) in a
        # process of its own, reached through the rm_sim_socket interface, so neither
        # layout's loop pays for the simulated motors' side of the bus.
        self.sim = None
        if role in ('all', 'bridge'):
            self.sim = SimProcess(files, pathlib.Path(self._tmp) / 'sim')
            files = [*files, self.sim.bridge_overlay]
        args = ['bench_robot', '--ros-args']
        for path in files:
            args += ['--params-file', str(path)]
        rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)
        self.rclpy = rclpy
        self.role = role
        self.bridge = CanBridgeNode() if role in ('all', 'bridge') else None
        # the one-process robot runs its plugins in the bridge's loop, as bringup does
        hardware = self.bridge.hardware if self.bridge is not None else None
        self.host = RobotHost(hardware=hardware) if role in ('all', 'host') else None
        self.executor = EventsExecutor()
        for node in (self.bridge, self.host):
            if node is not None:
                self.executor.add_node(node)
        from rm_base.runtime.realtime import prepare_loop_process

        owner = self.bridge if self.bridge is not None else self.host
        # as the executables do
        prepare_loop_process(owner.edge_priority, owner.cpu_index, owner.cpu_latency_us)
        self.hw = self.bridge.hardware if self.bridge is not None else None
        self.recorder = TickRecorder(self.hw.scheduler) if self.hw is not None else None
        self._sent_taps: list[Any] = []
        self.stop = threading.Event()
        self._taps: list[Any] = []
        self._applied: list[tuple[int, str, float, float]] = []
        self.profiles: Any = None

    # -- main thread ------------------------------------------------------------------
    def spin(self) -> None:
        while not self.stop.is_set() and self.rclpy.ok():
            self.executor.spin_once(timeout_sec=0.05)
            profiles = self.profiles
            if profiles is not None:
                profiles.check()

    def shutdown(self) -> None:
        for tap in self._taps:
            tap.shutdown()
        nodes = [n for n in (self.host, self.bridge) if n is not None]  # plugins first
        for node in nodes:
            node.shutdown()
        self.executor.shutdown()
        for node in nodes:
            node.destroy_node()
        self.rclpy.try_shutdown()
        if self.sim is not None:
            self.sim.stop()
        shutil.rmtree(self._tmp, ignore_errors=True)

    # -- commands (control thread) ------------------------------------------------------
    @property
    def _node(self) -> Any:
        return self.bridge if self.bridge is not None else self.host

    @property
    def _plugins(self) -> list[str]:
        return self.host.plugin_names if self.host is not None else []

    def ready(self, timeout: float) -> dict[str, Any]:
        if self.hw is None:
            return {'online': {}, 'plugins': self._plugins, 'joints': []}
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if all(s.online for s in self.hw.states()):
                break
            time.sleep(0.05)
        return {
            'online': {s.name: s.online for s in self.hw.states()},
            'plugins': self._plugins,
            'joints': self.hw.joint_names,
        }

    def wait_active(self, timeout: float, joints: list[str]) -> dict[str, Any]:
        deadline = time.monotonic() + timeout
        t0 = time.monotonic()
        while time.monotonic() < deadline:
            if all(self.hw.actuators[j].hold_reason.value == 'none' for j in joints):
                break
            time.sleep(0.02)
        holds = {j: self.hw.actuators[j].hold_reason.value for j in joints}
        return {
            'active': all(h == 'none' for h in holds.values()),
            'holds': holds,
            'waited_s': round(time.monotonic() - t0, 3),
        }

    def _frame_counts(self) -> dict[str, tuple[int, int]]:
        if self.hw is None:
            return {}
        return {
            name: (bus.stats().frames_received, bus.stats().frames_sent)
            for name, bus in self.hw.buses.items()
        }

    def _publishers(self, topic: str) -> list[str]:
        return sorted(i.node_name for i in self._node.get_publishers_info_by_topic(topic))

    def measure(self, name: str, seconds: float) -> dict[str, Any]:
        from bench.cpu import group_percent
        from bench.machine import Window, thread_cpu_percent, thread_cpu_snapshot
        from bench.stats import summary

        hw, host = self.hw, self.host
        plugins = self._plugins
        frames0 = self._frame_counts()
        overruns0 = {n: host.task(n).skipped for n in plugins}
        plugin_ticks0 = {n: host.task(n).ticks for n in plugins}
        world = self.bridge.sim_world if self.bridge is not None else None
        physics_ns = array.array('q')
        sim_time0 = world.time_ns if world is not None else 0
        ru0 = resource.getrusage(resource.RUSAGE_SELF)
        window = Window()
        threads0 = thread_cpu_snapshot()
        if world is not None:
            world._tick = _timed(type(world)._tick.__get__(world), physics_ns.append)
        if self.recorder is not None:
            self.recorder.start()
        time.sleep(seconds)
        sched = None
        if self.recorder is not None:
            sched = self.recorder.stop()
        if world is not None:
            world.__dict__.pop('_tick', None)
        threads1 = thread_cpu_snapshot()
        facts = window.close()
        ru1 = resource.getrusage(resource.RUSAGE_SELF)
        frames1 = self._frame_counts()
        elapsed = facts.elapsed_s
        per_thread = thread_cpu_percent(threads0, threads1, elapsed)
        # per loop: nominal rate, ticks, and the window they were counted in [s]
        loops: dict[str, tuple[float, int, float]] = {}
        feedback_hz: dict[str, float] = {}
        if hw is not None:
            loops['can-scheduler'] = (hw.config.rate_hz, sched['ticks'], sched['elapsed_s'])
        if world is not None:
            loops['rm_sim-physics'] = (
                1e9 / world.period_ns,
                (world.time_ns - sim_time0) // world.period_ns,
                elapsed,
            )
            feedback_hz = {
                bus: sum(1000.0 for a in hw.actuators.values() if a.bus_name == bus)
                for bus in hw.buses
            }  # every simulated DJI motor answers at 1 kHz
        for n in plugins:
            task = host.task(n)
            loops[f'plugin:{n}'] = (task.plugin.rate, task.ticks - plugin_ticks0[n], elapsed)
        process_pct = (
            100.0 * ((ru1.ru_utime - ru0.ru_utime) + (ru1.ru_stime - ru0.ru_stime)) / elapsed
        )
        return {
            'phase': name,
            'role': self.role,
            'window': facts.as_dict(),
            'threads': {k: round(v, 3) for k, v in sorted(per_thread.items())},
            'groups': {k: round(v, 3) for k, v in group_percent(per_thread).items()},
            'loops': loop_costs(loops, per_thread),
            'projected': project(per_thread, loops, frames0, frames1, feedback_hz, elapsed),
            'process_pct': round(process_pct, 3),
            'scheduler': sched,
            # the physics tick runs under the world lock, which every bus send waits for
            'sim_tick_us': summary(t / 1e3 for t in physics_ns) if world is not None else None,
            'frames_per_s': {
                bus: {
                    'received': (frames1[bus][0] - frames0[bus][0]) / elapsed,
                    'sent': (frames1[bus][1] - frames0[bus][1]) / elapsed,
                }
                for bus in frames1
            },
            'plugin_overruns': {n: host.task(n).skipped - overruns0[n] for n in plugins},
            # the loop's own timing of each component (since start), p50 / p99 / max
            'components': {
                name: dataclasses.asdict(summary)
                for name, summary in hw.scheduler.component_stats()
            } if hw is not None else {},
            'holds': {a.name: a.hold_reason.value for a in hw.actuators.values()} if hw else {},
            'publishers': {
                topic: self._publishers(topic)
                for topic in ('/chassis_cmd', '/gimbal_cmd', '/actuator_cmd')
            },
        }

    def tap_on(self, joints: list[str]) -> dict[str, Any]:
        tap_class = make_tap_class()
        slots: dict[str, Any] = {}
        ids: dict[str, set[int]] = {}
        for name in joints:
            actuator = self.hw.actuators[name]
            frame_id = actuator.command_frame_id  # DJI joints: their group's frame
            channel = str(self.hw.buses[actuator.bus_name].config.channel)
            ids.setdefault(channel, set()).add(frame_id)
            slots[name] = {'channel': channel, 'id': frame_id, 'slot': actuator.slot}
        world = self.bridge.sim_world
        if world is not None:
            self._taps = [
                tap_class(channel, world, frame_ids) for channel, frame_ids in ids.items()
            ]
        else:  # rm_sim in its own process: stamp the frames as the bridge hands them over
            self._taps = [
                _SendTap(bus, str(bus.config.channel), ids.get(str(bus.config.channel), set()))
                for bus in self.hw.buses.values()
            ]
        self._applied = []
        applied = self._applied
        original = type(self.hw).set_command.__get__(self.hw)

        def set_command(name: str, mode: int, **kwargs: Any) -> None:
            applied.append(
                (time.monotonic_ns(), name, kwargs.get('velocity', 0.0), kwargs.get('effort', 0.0))
            )
            original(name, mode, **kwargs)

        self.hw.set_command = set_command
        return {'slots': slots}

    def tap_off(self) -> dict[str, Any]:
        self.hw.__dict__.pop('set_command', None)
        frames: dict[str, list[tuple[int, int, str]]] = {}
        for tap in self._taps:
            frames[tap.channel_id] = tap.records
            tap.shutdown()
        self._taps = []
        return {'frames': frames, 'applied': self._applied}

    def profile(self, seconds: float, out_dir: str) -> dict[str, Any]:
        from bench.profiling import ThreadProfiles

        profiles = ThreadProfiles()
        targets: list[tuple[Any, str]] = []
        loops: list[Any] = []  # Schedulers: their thread checks after each tick
        # one method per thread, called once per wake-up of that thread
        if self.hw is not None:
            loops.append(self.hw.scheduler)
            targets.append((self.bridge, '_states_heard'))
            if self.bridge.sim_world is not None:  # rm_sim in this process (split layout)
                targets += [(self.bridge.sim_world, '_tick')]
        if self.host is not None:
            targets += [(self.host._outbox, 'flush')]
            if self.hw is None:  # rm_robot's own loop (split layout)
                loops.append(self.host.loop)
        for obj, attribute in targets:
            profiles.wrap(obj, attribute)
        for loop in loops:
            loop.add_after_tick(profiles.check)
        profiles.active = True
        self.profiles = profiles
        time.sleep(seconds)
        profiles.active = False
        # every thread passes its check and stops its profile; on a loaded machine a thread
        # behind the real-time loop may wait seconds for its next call
        deadline = time.monotonic() + _PROFILE_STOP_WAIT_S
        while not profiles.stopped() and time.monotonic() < deadline:
            time.sleep(0.05)
        self.profiles = None
        for obj, attribute in targets:
            obj.__dict__.pop(attribute, None)
        for loop in loops:
            loop.remove_after_tick(profiles.check)
        return {'profiles': profiles.report(pathlib.Path(out_dir))}


def loop_costs(
    loops: dict[str, tuple[float, int, float]], per_thread: dict[str, float]
) -> dict[str, Any]:
    """Per periodic thread: nominal and achieved rate, CPU per tick, CPU at full rate.

    Each loop's ticks count over their own window (the scheduler's recorder starts after
    the CPU snapshot and stops before the next one): the achieved rate is ticks over that
    window, and the CPU per tick is the thread's CPU rate over the achieved rate.
    """
    out = {}
    for thread, (rate_hz, ticks, seconds) in loops.items():
        cpu = per_thread.get(thread, 0.0)
        achieved_hz = ticks / seconds if seconds > 0 else 0.0
        us_per_tick = 1e4 * cpu / achieved_hz if achieved_hz > 0 else float('nan')
        out[thread] = {
            'rate_hz': rate_hz,
            'achieved_hz': achieved_hz,
            'cpu_pct': cpu,
            'us_per_tick': us_per_tick,
            'projected_pct': us_per_tick * rate_hz / 1e4,
        }
    return out


def project(
    per_thread: dict[str, float],
    loops: dict[str, tuple[float, int, float]],
    frames0: dict[str, tuple[int, int]],
    frames1: dict[str, tuple[int, int]],
    feedback_hz: dict[str, float],
    elapsed: float,
) -> dict[str, float]:
    """CPU groups with every loop at its nominal rate (what a quiet machine would see).

    On a loaded machine the loops skip deadlines and the simulator falls behind, so the
    measured CPU is too low. Here each periodic thread counts at its CPU per tick times
    its nominal rate, each receive thread at its CPU per frame times the motors' nominal
    feedback rate; the event-driven threads (executor, DDS, publisher) stay as measured,
    so the projection is still a lower bound.
    """
    from bench.cpu import group_percent

    scaled = dict(per_thread)
    costs = loop_costs(loops, per_thread)
    for thread, cost in costs.items():
        if cost['achieved_hz'] > 0:
            scaled[thread] = cost['projected_pct']
    for bus, nominal in feedback_hz.items():
        received = (frames1[bus][0] - frames0[bus][0]) / elapsed
        thread = f'canrx-{bus}'
        if received > 0 and thread in scaled:
            scaled[thread] = per_thread[thread] * nominal / received
    return {k: round(v, 3) for k, v in group_percent(scaled).items()}


def _timed(function: Any, record: Any) -> Any:
    clock = time.perf_counter_ns

    def timed(*args: Any) -> Any:
        t0 = clock()
        result = function(*args)
        record(clock() - t0)
        return result

    return timed


def control_loop(robot: Robot) -> None:
    try:
        _serve(robot)
    finally:
        robot.stop.set()


def _serve(robot: Robot) -> None:
    serve({
        'ready': lambda a: robot.ready(float(a[0])),
        'wait_active': lambda a: robot.wait_active(float(a[0]), a[1:]),
        'measure': lambda a: robot.measure(a[0], float(a[1])),
        'profile': lambda a: robot.profile(float(a[0]), a[1]),
        'tap_on': robot.tap_on,
        'tap_off': lambda a: robot.tap_off(),
    })


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog='bench.robot_proc')
    parser.add_argument('--plugins', default='', help='comma-separated plugin subset')
    parser.add_argument(
        '--role',
        choices=('all', 'bridge', 'host'),
        default='all',
        help='all: bridge + host (as bringup); bridge: can_bridge + rm_sim; host: rm_robot',
    )
    parser.add_argument('--imu-dir', default='', help="folder of the simulated IMU's pty")
    parser.add_argument(
        '--switch-interval-us',
        type=float,
        default=None,
        help='override the GIL switch interval after start-up (the executables set 500 us)',
    )
    args = parser.parse_args(argv)
    plugins = [p for p in args.plugins.split(',') if p] or None
    try:
        robot = Robot(plugins, args.role, args.imu_dir)
    except Exception as err:
        reply({'error': f'robot did not start: {type(err).__name__}: {err}'})
        return 1
    if args.switch_interval_us:
        sys.setswitchinterval(args.switch_interval_us / 1e6)
    reply({'started': True, 'pid': os.getpid(), 'switch_interval_s': sys.getswitchinterval()})
    control = threading.Thread(
        target=control_loop, args=(robot,), name='bench-control', daemon=True
    )
    control.start()
    try:
        robot.spin()
    except KeyboardInterrupt:
        pass
    finally:
        robot.shutdown()
    return 0


if __name__ == '__main__':
    sys.exit(main())
