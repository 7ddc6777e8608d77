"""Soak: the standard robot on rm_sim for minutes under a command mix and random faults.

Why one module: a standalone script whose parts (processes, command mix, faults, report) run
as one timed schedule.

    make soak                            # 10 minutes
    make soak SOAK_ARGS='--minutes 2 --seed 7 --report soak.json'

Processes: this one runs can_bridge (CanBridgeNode on rm_sim, standard.yaml and
standard_sim.yaml), the unsafe-frame checker on both simulated buses
(test/reliability/wire.py, fed in a thread) and the commander; rm_robot runs as its own
process (console script, the same two files), so it can be killed and restarted, and so
does rm_manual (rm_robot's executable as the operator's node, its DR16 on rm_sim's pty).

Every few seconds the commander picks a new mix (chassis RAW/FOLLOW/TWIST/GYRO/PASSIVE
with a random twist, gimbal RATE or TRACK, shooter READY and PUSH bursts, now and then
silence) and the injector a random fault: a motor offline, jammed, over temperature or
sending garbage on its feedback id, garbage on the feedback id of a motor held for
over-temperature, noise bursts into the silent DR16 port, a bus in bus-off, or rm_robot
killed (SIGKILL) and restarted. Each fault has a detection rule (what the robot must show
within a deadline, see ``FaultInjector``); the checker keeps its own record of each
motor's injected faults (``WireChecker.note_fault``), so no frame on the wire can talk it
out of a fault. The report counts faults injected and detected, unsafe frames
on the wire (the checker, by rule; must be 0), crashes (must be 0: the bridge's threads,
scheduler errors, rm_robot exits not caused here), the scheduler's timing, the
resident memory of both processes at the start (after warm-up) and the end, and what the
simulated referee did (``reliability.referee_watch``: a robot it destroyed is revived, and
a fault missed while it had the joint unpowered is not judged).

Network rule: ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST and a private ROS_DOMAIN_ID are set
before rclpy is imported, and passed to rm_robot.
"""

from __future__ import annotations

import argparse
import json
import logging
import math
import os
import pathlib
import random
import signal
import subprocess
import sys
import tempfile
import threading
import time
from dataclasses import dataclass, field
from typing import Any

TEST_ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(TEST_ROOT))

from support.ros import domain_claim_fds, isolate_ros_environment  # noqa: E402

# Network rule, before anything imports rclpy.
isolate_ros_environment(os.environ)

import rclpy  # noqa: E402
from geometry_msgs.msg import Twist  # noqa: E402
from rclpy.context import Context  # noqa: E402
from rclpy.experimental import EventsExecutor  # noqa: E402
from rclpy.parameter import Parameter  # noqa: E402
from rclpy.qos import qos_profile_sensor_data  # noqa: E402
from reliability.jam_watch import FeedSpan, JamWatch, power_scale  # noqa: E402
from reliability.referee_watch import RefereeWatch  # noqa: E402
from reliability.rigs import WireWatch, hardware_config  # noqa: E402
from reliability.wire import check_actuator_states, max_efforts  # noqa: E402
from rm_base.bridge import CanBridgeNode  # noqa: E402
from rm_base.ros.publish import publish  # noqa: E402
from rm_base.runtime.realtime import (  # noqa: E402
    children_start_normal,
    outside_robot,
    prepare_loop_process,
)
from rm_base.sim import Fault, FaultKind  # noqa: E402
from support.robot import CONFIG_DIR, load_parameters  # noqa: E402

from rm_msgs.msg import (  # noqa: E402
    ActuatorState,
    ChassisCmd,
    ChassisState,
    GimbalCmd,
    GimbalState,
    ShootCmd,
    ShooterState,
)

CONFIG_FILES = [CONFIG_DIR / 'standard.yaml', CONFIG_DIR / 'standard_sim.yaml']
WARM_UP_S = 20.0  # [s] before the first fault and the start RSS
GRACE_S = 0.05  # [s] the checker's timing grace (see reliability.wire)
DETECT_S = 1.0  # [s] deadline of most detection rules
RECONTROL_S = 20.0  # [s] a restarted rm_robot must drive again within this
WHEELS = ('wheel_fl', 'wheel_fr', 'wheel_rl', 'wheel_rr')
MOTORS = (*WHEELS, 'yaw', 'pitch', 'friction_l', 'friction_r', 'trigger')
# the joints on each output of the referee's power management module
OUTPUT_JOINTS = {
    'chassis': WHEELS,
    'gimbal': ('yaw', 'pitch'),
    'shooter': ('friction_l', 'friction_r', 'trigger'),
}
REFEREE_SETTLE_S = 1.0  # [s] after an output is back, its joints still resynchronise


def rss_kib(pid: int) -> int:
    """Resident set size of a process [KiB] (0 if it is gone)."""
    try:
        for line in pathlib.Path(f'/proc/{pid}/status').read_text().splitlines():
            if line.startswith('VmRSS:'):
                return int(line.split()[1])
    except OSError:
        pass
    return 0


# --- the robot ---------------------------------------------------------------------------------


class Robot:
    """can_bridge in this process, rm_robot as a child, the commander's node."""

    def __init__(self, workdir: pathlib.Path) -> None:
        self.workdir = workdir
        params = load_parameters(CONFIG_FILES)['can_bridge']
        params = {k: os.path.expandvars(v) if isinstance(v, str) else v for k, v in params.items()}
        self.bridge_parameters = params
        self.context = Context()
        rclpy.init(context=self.context, domain_id=int(os.environ['ROS_DOMAIN_ID']))
        self.bridge = CanBridgeNode(
            context=self.context,
            parameter_overrides=[Parameter(k, value=v) for k, v in params.items()],
        )
        self.world = self.bridge.sim_world
        self.hardware = self.bridge.hardware
        self.watch = WireWatch(
            self.world, hardware_config(params), grace_s=GRACE_S, track_commands=True
        )
        self.watch.checker._keep = 10_000  # kept for the report's attribution
        self.watch.watch_commands(self.hardware)
        self.node = rclpy.create_node('soak_commander', context=self.context)
        self._lock = threading.Lock()
        self.latest: dict[str, Any] = {}
        for topic, cls in (
            ('chassis_state', ChassisState),
            ('gimbal_state', GimbalState),
            ('shooter_state', ShooterState),
        ):
            self.node.create_subscription(
                cls, topic, lambda m, t=topic: self._store(t, m), qos_profile_sensor_data
            )
        # every /actuator_states: no NaN, nothing beyond a limit, MODE_OFF means 0
        limits = max_efforts(hardware_config(params))
        self.state_problems: list[str] = []
        self.node.create_subscription(
            ActuatorState,
            'actuator_states',
            lambda m: self.state_problems.extend(check_actuator_states(m, limits)),
            50,
        )
        self.executor = EventsExecutor(context=self.context)
        self.executor.add_node(self.bridge)
        # the soak's own subscriptions (states, every /actuator_states checked) are not the
        # robot's: another executor, in a thread outside it (rm_base.runtime.realtime)
        self.soak_executor = EventsExecutor(context=self.context)
        self.soak_executor.add_node(self.node)
        self._cpus = os.sched_getaffinity(0)  # rm_robot's, before this process is pinned
        prepare_loop_process(
            self.bridge.edge_priority, self.bridge.cpu_index, self.bridge.cpu_latency_us
        )  # as can_bridge
        self._stop = threading.Event()
        self._spinner = threading.Thread(
            target=self._spin, args=(self.executor,), name='soak-spin', daemon=True
        )
        self._listener = threading.Thread(target=self._listen, name='soak-listen', daemon=True)
        self._spinner.start()
        self._listener.start()
        self.host: subprocess.Popen | None = None
        self.host_log = open(workdir / 'rm_robot.log', 'ab')
        self.manual: subprocess.Popen | None = None
        # what the operator's node publishes: with the remote silent, nothing at all
        self.manual_messages = 0
        self.node.create_subscription(ChassisCmd, '/manual/chassis_cmd',
                                      self._count_manual, qos_profile_sensor_data)
        self.host_exits: list[int] = []  # exits not caused by the soak (crashes)

    def _spin(self, executor: EventsExecutor) -> None:
        while not self._stop.is_set():
            executor.spin_once(timeout_sec=0.05)

    def _listen(self) -> None:
        with outside_robot():
            self._spin(self.soak_executor)

    def _count_manual(self, msg: ChassisCmd) -> None:
        with self._lock:
            self.manual_messages += 1

    def _store(self, topic: str, msg: Any) -> None:
        with self._lock:
            self.latest[topic] = msg

    def state(self, topic: str) -> Any:
        with self._lock:
            return self.latest.get(topic)

    def _start_robot_exe(self, *remap: str) -> subprocess.Popen:
        from ament_index_python.packages import get_package_prefix

        exe = pathlib.Path(get_package_prefix('rm_base')) / 'lib' / 'rm_base' / 'rm_robot'
        args = [str(exe), '--ros-args', *remap]
        for path in CONFIG_FILES:
            args += ['--params-file', str(path)]
        env = dict(os.environ)
        isolate_ros_environment(env)
        with children_start_normal():  # not at this thread's real-time priority
            process = subprocess.Popen(
                args, env=env, stdout=self.host_log, stderr=self.host_log,
                pass_fds=domain_claim_fds(),  # an rm_robot left over keeps its domain
            )
        # It inherited this thread's CPU; it picks its own for its Python threads, and its
        # middleware's threads run anywhere, as when started from a shell.
        try:
            os.sched_setaffinity(process.pid, self._cpus)
        except ProcessLookupError:  # it died at once: the soak counts its exit
            pass
        return process

    def start_host(self) -> None:
        self.host = self._start_robot_exe()

    def start_manual(self) -> None:
        self.manual = self._start_robot_exe('-r', '__node:=rm_manual')

    def kill_host(self) -> None:
        if self.host is not None and self.host.poll() is None:
            os.kill(self.host.pid, signal.SIGKILL)
            self.host.wait(timeout=10)

    def check_host(self) -> None:
        """Count an rm_robot that exited by itself (a crash) and start it again."""
        if self.host is not None and self.host.poll() is not None:
            self.host_exits.append(self.host.returncode)
            self.start_host()

    def close(self) -> None:
        for process in (self.manual, self.host):
            if process is not None and process.poll() is None:
                process.send_signal(signal.SIGINT)
                try:
                    process.wait(timeout=15)
                except subprocess.TimeoutExpired:
                    process.kill()
        self._stop.set()
        self._spinner.join(timeout=5.0)
        self._listener.join(timeout=5.0)
        self.executor.shutdown()
        self.soak_executor.shutdown()
        self.bridge.destroy_node()
        self.node.destroy_node()
        self.watch.close()
        self.context.try_shutdown()
        self.host_log.close()

    # --- what the robot shows ---
    def joint(self, name: str):
        return self.hardware.actuators[name]

    def driven(self, names=WHEELS) -> bool:
        return all(self.joint(n).state().command != 0.0 for n in names)

    def all_zero(self) -> bool:
        return all(s.command == 0.0 for s in self.hardware.states())

    def threads_alive(self) -> bool:
        return self.hardware.scheduler.running and self.bridge._publisher_thread.is_alive()


# --- commands ----------------------------------------------------------------------------------


class Commander:
    """Publishes a command mix at 50 Hz; a new mix every few seconds."""

    def __init__(self, robot: Robot, rng: random.Random) -> None:
        self.robot = robot
        self.rng = rng
        node = robot.node
        self.pubs = {
            'chassis': node.create_publisher(ChassisCmd, 'chassis_cmd', 10),
            'vel': node.create_publisher(Twist, 'vel_cmd', 10),
            'gimbal': node.create_publisher(GimbalCmd, 'gimbal_cmd', 10),
            'shoot': node.create_publisher(ShootCmd, 'shoot_cmd', 10),
        }
        self.burst_id = 0
        self.mixes = 0
        self.silent_until = 0.0
        self.mix: dict[str, Any] = {}
        self._next_mix = 0.0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name='soak-commander', daemon=True)

    def start(self) -> None:
        self._thread.start()

    def stop(self) -> None:
        self._stop.set()
        self._thread.join(timeout=5.0)

    def new_mix(self) -> None:
        rng = self.rng
        self.mixes += 1
        mode = rng.choice([ChassisCmd.RAW, ChassisCmd.FOLLOW, ChassisCmd.TWIST, ChassisCmd.GYRO, 0])
        vel = Twist()
        vel.linear.x, vel.linear.y = rng.uniform(-1.5, 1.5), rng.uniform(-1.0, 1.0)
        vel.angular.z = rng.uniform(-3.0, 3.0)
        if rng.random() < 0.5:
            gimbal = GimbalCmd(
                mode=GimbalCmd.RATE, rate_yaw=rng.uniform(-2, 2), rate_pitch=rng.uniform(-1, 1)
            )
        else:
            gimbal = GimbalCmd(mode=GimbalCmd.TRACK, bullet_speed=rng.choice([0.0, 15.0]))
            gimbal.target.header.frame_id = rng.choice(['odom', 'base_link'])
            gimbal.target.point.x = rng.uniform(1.0, 6.0)
            gimbal.target.point.y = rng.uniform(-3.0, 3.0)
            gimbal.target.point.z = rng.uniform(0.0, 1.0)
        if rng.random() < 0.5:
            self.burst_id += 1
            shoot = ShootCmd(
                mode=ShootCmd.PUSH,
                speed=rng.choice([15.0, 18.0, 25.0]),
                hz=rng.uniform(2.0, 10.0),
                num=rng.randint(1, 5),
                burst_id=self.burst_id,
            )
        else:
            shoot = ShootCmd(mode=rng.choice([ShootCmd.READY, ShootCmd.PASSIVE]), speed=15.0)
        self.mix = {'chassis': ChassisCmd(mode=mode), 'vel': vel, 'gimbal': gimbal, 'shoot': shoot}
        # now and then the operator goes quiet: every plugin must time out to safe
        if rng.random() < 0.1:
            self.silent_until = time.monotonic() + rng.uniform(0.5, 2.0)

    def _run(self) -> None:
        with outside_robot():  # the operator, not the robot (rm_base.runtime.realtime)
            self._publish_mixes()

    def _publish_mixes(self) -> None:
        clock = self.robot.node.get_clock()
        while not self._stop.wait(0.02):
            now = time.monotonic()
            if now >= self._next_mix:
                self.new_mix()
                self._next_mix = now + self.rng.uniform(2.0, 6.0)
            if now < self.silent_until:
                continue
            stamp = clock.now().to_msg()
            for key, msg in self.mix.items():
                if hasattr(msg, 'header'):
                    msg.header.stamp = stamp
                publish(self.pubs[key], msg)  # as the bridge's threads: DDS without the GIL


# --- faults ------------------------------------------------------------------------------------


@dataclass
class FaultRecord:
    """One injected fault and whether the robot showed it was handled."""

    kind: str
    target: str
    start: float  # wall time [s]
    end: float = math.inf  # wall time the fault was cleared [s]
    detected: bool | None = None  # None: could not be judged (see note)
    note: str = ''
    latency_ms: float | None = None


@dataclass
class Tally:
    records: list[FaultRecord] = field(default_factory=list)

    def summary(self) -> dict[str, Any]:
        out: dict[str, Any] = {}
        for r in self.records:
            row = out.setdefault(
                r.kind, {'injected': 0, 'detected': 0, 'missed': 0, 'not_judged': 0}
            )
            row['injected'] += 1
            if r.detected is True:
                row['detected'] += 1
            elif r.detected is False:
                row['missed'] += 1
            else:
                row['not_judged'] += 1
        return out


def wait_for(predicate, timeout: float, period: float = 0.005) -> float | None:
    """Seconds until predicate() held, or None after timeout."""
    start = time.monotonic()
    while time.monotonic() - start < timeout:
        if predicate():
            return time.monotonic() - start
        time.sleep(period)
    return None


class FaultInjector:
    """Injects one random fault at a time and judges its detection (see each method)."""

    def __init__(self, robot: Robot, rng: random.Random, host_restarts: bool) -> None:
        self.robot = robot
        self.rng = rng
        self.tally = Tally()
        shooter = load_parameters(CONFIG_FILES)['rm_robot']
        # The shooter counts a jam after the trigger stalled, pushing harder than this, this
        # long while feeding; its state reaches the soak up to two state periods late.
        self.trigger_jam_effort = float(shooter['shooter.jam.effort'])
        self.trigger_jam_s = (
            float(shooter['shooter.jam.time']) + 2.0 / float(shooter['shooter.state_rate'])
        )
        kinds = ['offline', 'jam', 'over_temperature', 'garbage', 'garbage_hot', 'dr16_noise',
                 'bus_off']
        weights = [3, 2, 2, 2, 2, 1, 1]
        if host_restarts:
            kinds.append('host_restart')
            weights.append(1)
        self.kinds, self.weights = kinds, weights

    def inject_one(self) -> FaultRecord:
        kind = self.rng.choices(self.kinds, self.weights)[0]
        return getattr(self, f'_{kind}')()

    def _inject(self, joint: str, fault: Fault) -> None:
        """Inject into rm_sim, and tell the checker (its own record, not the wire's)."""
        self.robot.world.inject(joint, fault)
        temperature = fault.temperature if fault.kind is FaultKind.OVER_TEMPERATURE else None
        self.robot.watch.checker.note_fault(joint, fault.kind.value, time.time(),
                                            temperature=temperature)

    def _clear(self, joint: str, kind: FaultKind) -> None:
        self.robot.world.clear_faults(joint, kind)
        self.robot.watch.checker.note_fault(joint, kind.value, time.time(), active=False)

    def _record(self, kind: str, target: str) -> FaultRecord:
        rec = FaultRecord(kind, target, time.time())
        self.tally.records.append(rec)
        return rec

    def _offline(self) -> FaultRecord:
        """Detected: the bridge reports the joint offline within DETECT_S."""
        joint = self.rng.choice(MOTORS)
        rec = self._record('offline', joint)
        self._inject(joint, Fault.offline())
        lat = wait_for(lambda: not self.robot.joint(joint).state().online, DETECT_S)
        rec.detected, rec.latency_ms = lat is not None, None if lat is None else 1e3 * lat
        time.sleep(self.rng.uniform(0.2, 1.5))
        self._clear(joint, FaultKind.OFFLINE)
        rec.end = time.time()
        return rec

    def _over_temperature(self) -> FaultRecord:
        """Detected: the joint held OVER_TEMPERATURE within DETECT_S (at 130 °C)."""
        joint = self.rng.choice(MOTORS)
        rec = self._record('over_temperature', joint)
        self._inject(joint, Fault.over_temperature(130.0))
        lat = wait_for(
            lambda: self.robot.joint(joint).hold_reason.value == 'over_temperature', DETECT_S
        )
        if lat is not None:
            rec.detected, rec.latency_ms = True, 1e3 * lat
        elif getattr(getattr(self.robot.joint(joint), 'spec', None), 'has_temperature', True):
            rec.detected = False
        else:
            rec.note = 'its ESC reports no temperature (C610): invisible to the bridge'

        time.sleep(self.rng.uniform(0.3, 1.5))
        self._inject(joint, Fault.over_temperature(50.0))  # cooled down
        time.sleep(0.2)
        self._clear(joint, FaultKind.OVER_TEMPERATURE)
        rec.end = time.time()
        return rec

    def _garbage_hot(self) -> FaultRecord:
        """Detected: a motor held for over-temperature stays held while random frames
        (some of them cool and plausible) come on its feedback id: its hold never lifts."""
        joint = self.rng.choice([m for m in MOTORS if m != 'trigger'])  # the C610 has no °C
        rec = self._record('garbage_hot', joint)
        actuator = self.robot.joint(joint)
        self._inject(joint, Fault.over_temperature(123.0))
        held = wait_for(lambda: actuator.hold_reason.value == 'over_temperature', DETECT_S)
        self._inject(joint, Fault.garbage(rate_hz=1000.0))
        lifted = wait_for(lambda: actuator.hold_reason.value == 'none',
                          self.rng.uniform(1.0, 2.5))
        rec.detected = held is not None and lifted is None
        rec.latency_ms = None if held is None else 1e3 * held
        if lifted is not None:
            rec.note = f'the hold lifted {1e3 * lifted:.0f} ms into the garbage'
        self._clear(joint, FaultKind.GARBAGE)
        self._inject(joint, Fault.over_temperature(50.0))
        time.sleep(0.2)
        self._clear(joint, FaultKind.OVER_TEMPERATURE)
        rec.end = time.time()
        return rec

    def _dr16_noise(self) -> FaultRecord:
        """Detected: random 18-byte bursts into the silent DR16 port, 7 ms apart for 1-3 s,
        make rm_manual publish nothing (no /manual/chassis_cmd)."""
        rec = self._record('dr16_noise', 'rm_manual')
        remote = self.robot.world.remote
        before = self.robot.manual_messages
        deadline = time.monotonic() + self.rng.uniform(1.0, 3.0)
        while time.monotonic() < deadline:
            remote.write(self.rng.randbytes(18))
            time.sleep(0.007)
        time.sleep(0.3)  # what a believed frame would have made it publish
        published = self.robot.manual_messages - before
        rec.detected = published == 0
        if published:
            rec.note = f'rm_manual published {published} command(s) on noise'
        rec.end = time.time()
        return rec

    def _jam(self) -> FaultRecord:
        """Detected: trigger -> the shooter counts a jam or blocks; any other joint -> its
        output reaches its clamp (the loop pushes against the stall). Not judged: a trigger
        that did not push past the jam effort while feeding for as long as the shooter's
        jam rule needs (it may wait for the friction wheels, at rest), or another joint
        whose commands never asked its loop for a push that reaches the clamp against a
        stall (reliability.jam_watch)."""
        joint = self.rng.choice(('trigger', 'trigger', 'friction_l', 'wheel_fl', 'yaw'))
        rec = self._record('jam', joint)
        before = self.robot.state('shooter_state')
        jams = before.jam_count if before is not None else 0
        self._inject(joint, Fault.jam())
        fed = FeedSpan(self.trigger_jam_effort)  # trigger: how long it pushed while jammed
        trigger = self.robot.joint('trigger')
        watch = JamWatch(self.robot.joint(joint), power_scale(self.robot.hardware, joint))

        def shown() -> bool:
            if joint != 'trigger':
                return watch.sample()
            s = self.robot.state('shooter_state')
            feeding = s is not None and s.state in (ShooterState.FEED, ShooterState.PUSH)
            fed.sample(feeding, trigger.state().effort, time.monotonic())
            return s is not None and (s.jam_count > jams or s.state == ShooterState.BLOCK)

        lat = wait_for(shown, 3.0)
        if lat is not None:
            rec.detected, rec.latency_ms = True, 1e3 * lat
        elif joint == 'trigger' and fed.longest < self.trigger_jam_s:
            rec.note = (
                f'fed for {1e3 * fed.longest_fed:.0f} ms while jammed, pushing past the jam '
                f'effort for {1e3 * fed.longest:.0f} ms of it, under the '
                f'{1e3 * self.trigger_jam_s:.0f} ms the shooter needs to see a jam'
            )
        elif joint != 'trigger' and not watch.judged:
            rec.note = f'never asked for a push that reaches the clamp: {watch.note()}'
        else:
            rec.detected = False
            if joint != 'trigger':
                gimbal = self.robot.state('gimbal_state')
                rec.note = (
                    f'{watch.note()}, gimbal state '
                    f'{gimbal.state if gimbal is not None else None}'
                )
        time.sleep(self.rng.uniform(0.2, 1.0))
        self._clear(joint, FaultKind.JAM)
        rec.end = time.time()
        return rec

    def _garbage(self) -> FaultRecord:
        """Detected: the joint's refused frames rise (random bytes on a DJI feedback id:
        about half have an angle above 8191, and most others are implausible)."""
        joint = self.rng.choice(MOTORS)
        rec = self._record('garbage', joint)
        actuator = self.robot.joint(joint)
        before = actuator.decode_errors + actuator.implausible_frames
        self._inject(joint, Fault.garbage(rate_hz=self.rng.choice([100.0, 1000.0])))
        lat = wait_for(lambda: actuator.decode_errors + actuator.implausible_frames > before,
                       3.0)
        rec.detected, rec.latency_ms = lat is not None, None if lat is None else 1e3 * lat
        time.sleep(self.rng.uniform(0.3, 1.0))
        self._clear(joint, FaultKind.GARBAGE)
        rec.end = time.time()
        return rec

    def _bus_off(self) -> FaultRecord:
        """Detected: every joint on the bus offline (held at zero) within DETECT_S."""
        import can

        bus = self.rng.choice(['can0', 'can1'])
        rec = self._record('bus_off', bus)
        channel = self.robot.bridge_parameters[f'buses.{bus}.channel']
        sim_channel = self.robot.world.channel(channel)
        members = [a for a in self.robot.hardware.actuators.values() if a.bus_name == bus]
        sim_channel.set_state(can.BusState.ERROR)
        lat = wait_for(lambda: not any(a.state().online for a in members), DETECT_S)
        rec.detected, rec.latency_ms = lat is not None, None if lat is None else 1e3 * lat
        time.sleep(self.rng.uniform(0.0, 0.8))
        sim_channel.set_state(can.BusState.ACTIVE)
        rec.end = time.time()
        return rec

    def _host_restart(self) -> FaultRecord:
        """Detected: every joint at zero output within the command timeout (+ 0.2 s) of
        the SIGKILL, and the wheels driven again after the restart."""
        rec = self._record('host_restart', 'rm_robot')
        self.robot.kill_host()
        lat = wait_for(self.robot.all_zero, 0.1 + 0.2)
        rec.latency_ms = None if lat is None else 1e3 * lat
        time.sleep(self.rng.uniform(0.5, 2.0))
        self.robot.start_host()
        rec.end = time.time()
        back = wait_for(self.robot.driven, RECONTROL_S, period=0.05)
        rec.detected = lat is not None and (back is not None or not self._wheels_commanded())
        if back is None:
            rec.note = 'wheels not driven again (the mix may be PASSIVE)'
        return rec

    def _wheels_commanded(self) -> bool:
        s = self.robot.state('chassis_state')
        return s is not None and s.state != 0


# --- the run -----------------------------------------------------------------------------------


def attribute(
    violations, records: list[FaultRecord], bus_of: dict[str, str]
) -> dict[str, int]:
    """Count the kept violations by the fault active on their joint (or bus: bus_of, joint
    -> bus) at the time, up to 0.5 s after it was cleared; 'none' when no fault was."""
    out: dict[str, int] = {}
    for v in violations:
        kind = 'none'
        for r in records:
            if r.start <= v.time <= r.end + 0.5 and r.target in (
                v.joint,
                bus_of.get(v.joint),
                'rm_robot',
            ):
                kind = r.kind
                break
        out[kind] = out.get(kind, 0) + 1
    return out


def main(argv: list[str] | None = None) -> int:
    """Run the soak; print the report; exit 1 on an unsafe frame or a crash."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--minutes', type=float, default=10.0, help='duration [min] (10)')
    parser.add_argument('--seed', type=int, default=1, help='random seed of mix and faults')
    parser.add_argument('--report', type=pathlib.Path, help='write the report as JSON here')
    parser.add_argument('--no-host-restart', action='store_true', help='never kill rm_robot')
    args = parser.parse_args(argv)
    rng = random.Random(args.seed)
    workdir = pathlib.Path(tempfile.mkdtemp(prefix='rm_soak_'))
    print(
        f'[soak] {args.minutes:g} min, seed {args.seed}, domain {os.environ["ROS_DOMAIN_ID"]}, '
        f'logs in {workdir}',
        flush=True,
    )
    # the hardware layer's log lines go to a file, not the terminal
    handler = logging.FileHandler(workdir / 'can_bridge.log')
    handler.setFormatter(logging.Formatter('%(asctime)s %(name)s: %(message)s'))
    logging.getLogger('rm_base').addHandler(handler)
    logging.getLogger('rm_base').setLevel(logging.INFO)
    logging.getLogger('rm_base').propagate = False
    robot = Robot(workdir)
    referee = RefereeWatch(robot.world, OUTPUT_JOINTS)
    referee.start()
    commander = Commander(robot, rng)
    injector = FaultInjector(robot, rng, host_restarts=not args.no_host_restart)
    rss: dict[str, Any] = {'bridge': [], 'rm_robot': []}
    robot.start_host()
    robot.start_manual()
    commander.start()
    t0 = time.monotonic()
    end = t0 + 60.0 * args.minutes
    next_sample = t0
    try:
        while time.monotonic() < t0 + WARM_UP_S:
            robot.check_host()
            time.sleep(0.5)
        rss['bridge'].append(rss_kib(os.getpid()))
        rss['rm_robot'].append(rss_kib(robot.host.pid))
        while time.monotonic() < end:
            robot.check_host()
            if not robot.threads_alive():
                print('[soak] a bridge thread died', flush=True)
                break
            rec = injector.inject_one()
            print(
                f'[soak] {time.monotonic() - t0:7.1f} s  {rec.kind:16s} {rec.target:10s} '
                f'detected={rec.detected} {rec.note}',
                flush=True,
            )
            time.sleep(rng.uniform(1.0, 5.0))  # let the robot settle between faults
            if time.monotonic() >= next_sample:
                next_sample += 30.0
                rss['bridge'].append(rss_kib(os.getpid()))
                if robot.host is not None:
                    rss['rm_robot'].append(rss_kib(robot.host.pid))
    finally:
        rss['bridge'].append(rss_kib(os.getpid()))
        if robot.host is not None:
            rss['rm_robot'].append(rss_kib(robot.host.pid))
        commander.stop()
        referee.stop()
        alive = robot.threads_alive()
        robot.close()
    bus_of = {name: a.bus_name for name, a in robot.hardware.actuators.items()}

    def joints_of(target: str) -> tuple[str, ...]:
        if target == 'rm_robot':  # judged by the wheels being driven again
            return WHEELS
        if target in MOTORS:
            return (target,)
        return tuple(j for j, bus in bus_of.items() if bus == target)

    referee.set_aside(injector.tally.records, joints_of, REFEREE_SETTLE_S)
    checker = robot.watch.checker
    during = attribute(checker.violations, injector.tally.records, bus_of)
    sched = robot.hardware.scheduler.stats()
    crashes = {
        'rm_robot_exits': robot.host_exits,
        'bridge_threads_alive_at_end': alive,
        'scheduler_errors': sched.errors,
        'update_errors': sum(a.update_errors for a in robot.hardware.actuators.values()),
        'handler_errors': sum(b.stats().handler_errors for b in robot.hardware.buses.values()),
    }
    crash_count = (
        len(robot.host_exits)
        + (0 if alive else 1)
        + crashes['scheduler_errors']
        + crashes['update_errors']
        + crashes['handler_errors']
    )
    report = {
        'minutes': args.minutes,
        'seed': args.seed,
        'faults': injector.tally.summary(),
        'faults_injected': len(injector.tally.records),
        'faults_detected': sum(r.detected is True for r in injector.tally.records),
        'faults_missed': [
            (r.kind, r.target, r.note) for r in injector.tally.records if r.detected is False
        ],
        'detection_latency_ms_max': {
            kind: round(
                max(
                    r.latency_ms
                    for r in injector.tally.records
                    if r.kind == kind and r.latency_ms is not None
                ),
                1,
            )
            for kind in {r.kind for r in injector.tally.records if r.latency_ms is not None}
        },
        'unsafe_frames': checker.violation_count,
        'unsafe_by_rule': checker.violations_by_rule,
        'unsafe_after_stall': checker.violations_after_stall,
        'unsafe_during_fault': during,
        'actuator_states_problems': len(robot.state_problems),
        'actuator_states_examples': robot.state_problems[:5],
        'unsafe_examples': [str(v) for v in checker.violations[:10]],
        'wire': checker.summary(),
        'crashes': crash_count,
        'crash_detail': crashes,
        'command_mixes': commander.mixes,
        'referee': referee.summary(),
        'scheduler': {
            'ticks': sched.ticks,
            # ticks run per second of loop time (every deadline is a tick run or skipped)
            'ticks_per_s': round(
                sched.ticks / max(sched.ticks + sched.skipped_ticks, 1) * 1e9 / sched.period_ns,
                1,
            ),
            'overruns': sched.overruns,
            'skipped_ticks': sched.skipped_ticks,
            'max_error_ms': round(sched.max_error_us / 1e3, 1),
            'max_tick_ms': round(sched.max_tick_us / 1e3, 1),
        },
        'rss_kib': {
            name: {
                'start': values[0] if values else None,
                'end': values[-1] if values else None,
                'samples': values,
            }
            for name, values in rss.items()
        },
        'host_log': str(workdir / 'rm_robot.log'),
    }
    text = json.dumps(report, indent=2)
    print(text, flush=True)
    if args.report is not None:
        args.report.write_text(text + '\n')
    ok = report['unsafe_frames'] == 0 and crash_count == 0 and not robot.state_problems
    print(
        f'[soak] {"PASS" if ok else "FAIL"}: unsafe frames {report["unsafe_frames"]}, '
        f'crashes {crash_count}',
        flush=True,
    )
    return 0 if ok else 1


if __name__ == '__main__':
    sys.exit(main())
