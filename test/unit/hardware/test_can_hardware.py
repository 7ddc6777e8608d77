"""CanHardware end to end over python-can's virtual bus, the test playing the motors.

Why one module: every test drives one CanHardware through the same rig (a virtual bus,
the fake clock) and the same feedback helpers; split, they would be copied.
"""

import math
import threading

import can
import pytest
from rm_base.hardware import (
    MODE_EFFORT,
    MODE_OFF,
    CanHardware,
    CommandRejectedError,
    HardwareConfigError,
    HoldReason,
)
from rm_base.hardware.protocols import mit
from rm_base.hardware.protocols.mit import MitCommand, SystemCommand
from rm_base.motors.damiao import protocol as damiao
from rm_base.motors.dji import protocol as dji
from support.ros import wait_until

from rm_base import motors as motor_families

TIMEOUT = 10.0  # [s], condition waits only
DM4310 = damiao.dm_limits('DM4310')


def config(channel, **overrides):
    cfg = {
        'buses': {'can0': {'interface': 'virtual', 'channel': channel, 'receive_timeout_s': 0.01}},
        'joints': {
            'wheel': {'type': 'm3508', 'bus': 'can0', 'id': 1},
            'yaw': {'type': 'gm6020', 'bus': 'can0', 'id': 1},
            'arm': {'type': 'dm4310', 'bus': 'can0', 'id': 3, 'master_id': 0x13},
        },
    }
    cfg.update(overrides)
    return cfg


def dji_feedback(can_id, temperature=30):
    return can.Message(
        arbitration_id=can_id, data=dji.encode_feedback(0, 0, 0, temperature), is_extended_id=False
    )


def dm_feedback(state=damiao.DmState.ENABLED):
    data = damiao.encode_feedback(
        3, state, position=0.0, velocity=0.0, torque=0.0, t_mos=30, t_rotor=30, limits=DM4310
    )
    return can.Message(arbitration_id=0x13, data=data, is_extended_id=False)


def all_feedback(peer):
    peer.send(dji_feedback(0x201))
    peer.send(dji_feedback(0x205))
    peer.send(dm_feedback())


def frames(peer, n):
    out = {}
    for _ in range(n):
        msg = peer.recv(TIMEOUT)
        assert msg is not None, f'expected {n} frames, got {out}'
        out[msg.arbitration_id] = bytes(msg.data)
    return out


def slots(data):
    return dji.unpack_command(data)


@pytest.fixture
def rig(channel, clock):
    hw = CanHardware(
        config(channel), clock_ns=clock, receive_in_loop=False, families=motor_families,
    )
    peer = can.Bus(interface='virtual', channel=channel)
    hw.open()
    yield hw, peer, clock
    hw.shutdown()
    peer.shutdown()


def fed(hw, peer):
    """Send feedback for every motor and wait until it is stamped with the current time."""
    now = hw._clock_ns()
    all_feedback(peer)

    def fresh():
        return all(
            a.feedback is not None and a.feedback.stamp_ns >= now for a in hw.actuators.values()
        )

    assert wait_until(fresh, TIMEOUT)


def test_commands_reach_the_wire_in_shared_and_own_frames(rig):
    hw, peer, clock = rig
    fed(hw, peer)
    hw.set_command('wheel', MODE_EFFORT, effort=1.0)
    hw.set_command('yaw', MODE_EFFORT, effort=0.5)
    hw.set_command('arm', MODE_EFFORT, effort=2.0)
    assert hw.tick() == 3
    got = frames(peer, 3)
    # wheel: 1 N·m / 0.3 -> 3.333 A -> 2731 raw in 0x200 slot 0
    assert slots(got[0x200]) == (2731, 0, 0, 0)
    # yaw (voltage mode, at rest): 0.5/0.741 A * 1.8 ohm = 1.2146 V * 25000/24 -> 1265
    assert slots(got[0x1FF]) == (1265, 0, 0, 0)
    # arm: the first frame of a Damiao is ENABLE
    assert got[0x003] == mit.system_frame(SystemCommand.ENABLE)
    clock.advance_ms(1)
    all_feedback(peer)
    hw.tick()
    got = frames(peer, 3)
    cmd = mit.unpack_mit_command(got[0x003], DM4310)
    assert (cmd.kp, cmd.kd) == (0.0, 0.0)
    assert cmd.torque == pytest.approx(2.0, abs=20 / 4095)


def test_states_and_diagnostics(rig):
    hw, peer, _ = rig
    fed(hw, peer)
    hw.set_command('wheel', MODE_EFFORT, effort=1.0)
    hw.tick()
    states = hw.states()
    assert [s.name for s in states] == ['wheel', 'yaw', 'arm'] == hw.joint_names
    wheel = states[0]
    assert wheel.online and wheel.mode == MODE_EFFORT and wheel.temperature == 30.0
    assert wheel.command == pytest.approx(2731 * 20 / 16384 * 0.3)
    assert states[1].mode == MODE_OFF  # never commanded
    diag = hw.diagnostics()
    assert diag['buses']['can0'].frames_sent == 3
    assert diag['buses']['can0'].frames_received == 3
    assert diag['scheduler'].ticks == 1
    assert diag['joints']['yaw']['hold_reason'] == HoldReason.NO_COMMAND.value


def test_states_carry_their_feedback_time_or_the_stamp_asked_for(rig):
    hw, peer, _ = rig
    fed(hw, peer)
    hw.tick()
    received = hw.states()[0].stamp_ns
    assert received > 0
    assert [s.stamp_ns for s in hw.states(stamp_ns=123)] == [123, 123, 123]
    assert hw.states()[0].stamp_ns == received  # nothing kept


def test_command_timeout_ends_with_zero_current_on_the_wire(rig):
    hw, peer, clock = rig
    fed(hw, peer)
    hw.set_command('wheel', MODE_EFFORT, effort=1.0)
    hw.tick()
    assert slots(frames(peer, 3)[0x200])[0] == 2731
    clock.advance_ms(101)
    fed(hw, peer)
    hw.tick()
    assert slots(frames(peer, 3)[0x200]) == (0, 0, 0, 0)
    assert hw.actuators['wheel'].hold_reason is HoldReason.COMMAND_TIMEOUT


def test_when_a_command_arrives_late_expect_its_timeout_counted_from_its_stamp(rig):
    hw, peer, clock = rig
    fed(hw, peer)
    # issued 60 ms ago (it sat in queues): 40 ms of the 100 ms timeout left
    hw.set_command('wheel', MODE_EFFORT, effort=1.0, age_ns=60_000_000)
    clock.advance_ms(39)
    fed(hw, peer)
    hw.tick()
    assert slots(frames(peer, 3)[0x200])[0] == 2731
    clock.advance_ms(2)
    fed(hw, peer)
    hw.tick()
    assert slots(frames(peer, 3)[0x200]) == (0, 0, 0, 0)
    assert hw.actuators['wheel'].hold_reason is HoldReason.COMMAND_TIMEOUT


def test_offline_motor_gets_zero_on_the_wire(rig):
    hw, peer, clock = rig
    fed(hw, peer)
    clock.advance_ms(101)  # no feedback for 101 ms
    hw.set_command('wheel', MODE_EFFORT, effort=1.0)
    hw.set_command('arm', MODE_EFFORT, effort=1.0)
    hw.tick()
    got = frames(peer, 3)
    assert slots(got[0x200]) == (0, 0, 0, 0)
    assert not hw.states()[0].online


def test_over_temperature_ends_with_zero_current_on_the_wire(rig):
    hw, peer, _ = rig
    fed(hw, peer)
    for temperature in range(34, 86, 4):  # warming as a motor does, a few degC a frame
        peer.send(dji_feedback(0x201, temperature=temperature))
    assert wait_until(lambda: hw.actuators['wheel'].feedback.temperature >= 82, TIMEOUT)
    hw.set_command('wheel', MODE_EFFORT, effort=1.0)
    hw.tick()
    assert slots(frames(peer, 3)[0x200]) == (0, 0, 0, 0)
    assert hw.actuators['wheel'].hold_reason is HoldReason.OVER_TEMPERATURE


def test_nan_command_is_rejected_and_never_reaches_the_wire(rig):
    hw, peer, _ = rig
    fed(hw, peer)
    with pytest.raises(CommandRejectedError, match='effort is not a finite number: nan'):
        hw.set_command('wheel', MODE_EFFORT, effort=math.nan)
    hw.tick()
    assert slots(frames(peer, 3)[0x200]) == (0, 0, 0, 0)
    assert hw.diagnostics()['joints']['wheel']['commands_rejected'] == 1


def test_unknown_joint_is_rejected_and_counted(rig):
    hw, _, _ = rig
    with pytest.raises(CommandRejectedError, match="unknown joint 'whee'"):
        hw.set_command('whee', MODE_EFFORT, effort=1.0)
    assert hw.diagnostics()['unknown_joint_commands'] == 1


def test_shutdown_sends_zero_then_disable_and_is_idempotent(channel, clock):
    hw = CanHardware(
        config(channel), clock_ns=clock, receive_in_loop=False, families=motor_families,
    )
    with can.Bus(interface='virtual', channel=channel) as peer:
        hw.open()
        fed(hw, peer)
        hw.set_command('wheel', MODE_EFFORT, effort=1.0)
        hw.set_command('arm', MODE_EFFORT, effort=1.0)
        hw.tick()
        frames(peer, 3)
        hw.shutdown()
        hw.shutdown()
        got = [peer.recv(TIMEOUT) for _ in range(4)]
        assert peer.recv(0.05) is None
    by_id = [(m.arbitration_id, bytes(m.data)) for m in got]
    assert by_id[0] == (0x200, bytes(8))
    assert by_id[1] == (0x1FF, bytes(8))
    assert by_id[2] == (0x003, mit.pack_mit_command(MitCommand(0, 0, 0, 0, 0), DM4310))
    assert by_id[3] == (0x003, mit.system_frame(SystemCommand.DISABLE))
    assert all(b.state.value == 'closed' for b in hw.buses.values())


def test_system_commands_for_mit_joints_only(rig):
    hw, peer, _ = rig
    hw.request_system_command('arm', SystemCommand.SET_ZERO)
    hw.tick()
    assert frames(peer, 3)[0x003] == mit.system_frame(SystemCommand.SET_ZERO)
    with pytest.raises(CommandRejectedError, match='not an MIT-mode motor'):
        hw.request_system_command('wheel', SystemCommand.ENABLE)


# --- set_zero: the present position becomes the joint's zero ---
_YAW_TICKS = {}  # the ticks each CanHardware's yaw was last fed at


def yaw_at(hw, peer, ticks, rpm=0):
    """Turn the GM6020 yaw to encoder ticks (rotor rpm), tick, return its position.

    It moves there the short way round in steps of at most 500 ticks (0.38 rad), a frame
    each: a still shaft's angle that jumps further is implausible feedback.
    """
    yaw = hw.actuators['yaw']
    path = [ticks]
    if yaw.feedback is not None:
        last = _YAW_TICKS.get(id(hw), 0)  # fed() sends 0
        delta = (ticks - last + 4096) % 8192 - 4096
        n = max(1, -(-abs(delta) // 500))
        path = [(last + round(delta * k / n)) % 8192 for k in range(1, n + 1)]
    for step_ticks in path:
        hw._clock_ns.advance_ms(1)
        now = hw._clock_ns()
        peer.send(can.Message(arbitration_id=0x205,
                              data=dji.encode_feedback(step_ticks, rpm, 0, 30),
                              is_extended_id=False))
        assert wait_until(
            lambda now=now: yaw.feedback is not None and yaw.feedback.stamp_ns >= now, TIMEOUT
        )
        hw.tick()
        frames(peer, 2)
    _YAW_TICKS[id(hw)] = ticks
    return yaw.feedback.position


def test_set_zero_makes_the_present_position_zero_and_returns_the_offset(rig):
    hw, peer, _ = rig
    fed(hw, peer)
    hw.tick()
    frames(peer, 3)
    assert yaw_at(hw, peer, 3000) == pytest.approx(3000 / 8192 * math.tau)
    zero = hw.set_zero('yaw', max_speed=0.05)
    assert zero == pytest.approx(3000 / 8192 * math.tau)
    assert yaw_at(hw, peer, 3000) == pytest.approx(0.0, abs=1e-12)
    assert yaw_at(hw, peer, 3100) == pytest.approx(100 / 8192 * math.tau)
    assert hw.actuators['yaw'].zero_offset == zero


def test_a_zero_taken_after_whole_turns_reads_zero_after_a_restart(channel, clock):
    hw = CanHardware(
        config(channel), clock_ns=clock, receive_in_loop=False, families=motor_families,
    )
    peer = can.Bus(interface='virtual', channel=channel)
    hw.open()
    try:
        yaw_at(hw, peer, 8000)
        for ticks in (2000, 4000, 6000, 8000, 1000):  # on through 0: a turn and a bit
            yaw_at(hw, peer, ticks)
        zero = hw.set_zero('yaw', max_speed=0.05)
        assert yaw_at(hw, peer, 1000) == pytest.approx(0.0, abs=1e-12)
    finally:
        hw.shutdown()
    assert zero == pytest.approx(1000 / 8192 * math.tau)  # single-turn: what a restart reads
    restarted = config(channel)
    restarted['joints']['yaw']['zero_offset'] = zero
    hw = CanHardware(restarted, clock_ns=clock, receive_in_loop=False, families=motor_families)
    hw.open()
    try:
        assert yaw_at(hw, peer, 1000) == pytest.approx(0.0, abs=1e-12)
        assert yaw_at(hw, peer, 900) == pytest.approx(-100 / 8192 * math.tau)
    finally:
        hw.shutdown()
        peer.shutdown()


def test_set_zero_on_an_mit_motor_sends_its_set_zero_and_reads_from_zero_after(rig):
    hw, peer, _ = rig
    fed(hw, peer)
    hw.tick()
    frames(peer, 3)
    assert hw.set_zero('arm', max_speed=0.05) == 0.0
    hw.tick()
    assert frames(peer, 3)[0x003] == mit.system_frame(SystemCommand.SET_ZERO)
    fed(hw, peer)
    assert hw.actuators['arm'].zero_offset == 0.0


@pytest.mark.parametrize(
    ('setup', 'joint', 'message'),
    [
        ('none', 'yaw', 'yaw is offline: no position to take as zero'),
        ('fed', 'shoulder', "unknown joint 'shoulder'"),
        ('fed', 'wheel', 'wheel: its encoder turns 19.2032 times per output turn'),
        ('driven', 'yaw', 'yaw is driven: make the plugin that drives it PASSIVE first'),
        ('moving', 'yaw', r'yaw is moving \(0.105 rad/s, at rest below 0.05\): hold it still'),
    ],
    ids=['offline', 'unknown', 'geared', 'driven', 'moving'],
)
def test_set_zero_refuses_and_says_why(rig, setup, joint, message):
    hw, peer, _ = rig
    if setup != 'none':
        fed(hw, peer)
        hw.tick()
        frames(peer, 3)
    if setup == 'driven':
        hw.set_command('yaw', MODE_EFFORT, effort=0.1)
        hw.tick()
        frames(peer, 3)
    if setup == 'moving':
        yaw_at(hw, peer, 0, rpm=1)  # 1 rpm = 0.105 rad/s
    with pytest.raises(CommandRejectedError, match=message):
        hw.set_zero(joint, max_speed=0.05)
    assert hw.actuators['yaw'].zero_offset == 0.0


# --- bus error -> reopen -> zero until a fresh command ---
class FlakyFactory:
    """Virtual buses whose receive can be broken once (the adapter 'disappears')."""

    def __init__(self):
        self.break_next = threading.Event()
        self.opened = 0

    def __call__(self, interface, channel, **kwargs):
        factory = self
        self.opened += 1

        class Flaky(can.interfaces.virtual.VirtualBus):
            def _recv_internal(self, timeout):
                if factory.break_next.is_set():
                    factory.break_next.clear()
                    raise can.CanOperationError('USB adapter gone')
                return super()._recv_internal(timeout)

        kwargs.pop('ignore_config', None)
        kwargs.pop('bitrate', None)
        return Flaky(channel=channel, **kwargs)


def test_after_a_bus_error_the_bus_reopens_and_sends_zero_until_commanded(channel, clock):
    factory = FlakyFactory()
    cfg = config(channel)
    cfg['buses']['can0'].update(reconnect_initial_s=0.01, reconnect_max_s=0.02)
    hw = CanHardware(
        cfg, clock_ns=clock, bus_factory=factory, receive_in_loop=False, families=motor_families,
    )
    with hw, can.Bus(interface='virtual', channel=channel) as peer:
        hw.open()
        fed(hw, peer)
        hw.set_command('wheel', MODE_EFFORT, effort=1.0)
        hw.tick()
        assert slots(frames(peer, 3)[0x200])[0] == 2731
        factory.break_next.set()
        bus = hw.buses['can0']
        assert wait_until(lambda: bus.generation == 2, TIMEOUT)
        fed(hw, peer)  # feedback flows again; the wheel command is still fresh
        hw.tick()
        assert slots(frames(peer, 3)[0x200]) == (0, 0, 0, 0)
        assert hw.actuators['wheel'].hold_reason is HoldReason.BUS_RECOVERY
        clock.advance_ms(1)
        hw.set_command('wheel', MODE_EFFORT, effort=1.0)
        hw.tick()
        assert slots(frames(peer, 3)[0x200])[0] == 2731
        assert bus.stats().receive_errors == 1
        assert factory.opened == 2


# --- the real scheduler thread ---
@pytest.mark.realtime
def test_started_hardware_runs_at_its_rate_and_shuts_down_with_zero(channel):
    cfg = config(channel, safety={'command_timeout_s': 60.0})
    del cfg['joints']['arm']
    hw = CanHardware(cfg, families=motor_families)
    seen = []
    stop = threading.Event()

    def escs():  # answer every command frame with feedback, like the ESCs
        while not stop.is_set():
            msg = peer.recv(0.01)
            if msg is None:
                continue
            seen.append((msg.arbitration_id, bytes(msg.data)))
            if msg.arbitration_id == 0x200:
                peer.send(dji_feedback(0x201))
                peer.send(dji_feedback(0x205))

    with can.Bus(interface='virtual', channel=channel) as peer:
        thread = threading.Thread(target=escs, daemon=True)
        thread.start()
        hw.set_command('wheel', MODE_EFFORT, effort=1.0)
        hw.start()
        assert wait_until(lambda: (0x200, bytes.fromhex('0aab000000000000')) in seen, TIMEOUT)
        hw.shutdown()
        hw.shutdown()
        assert not hw.scheduler.running
        assert wait_until(lambda: seen and seen[-1][0] == 0x1FF, TIMEOUT)
        stop.set()
        thread.join(TIMEOUT)
    last_wheel = [d for i, d in seen if i == 0x200][-1]
    assert last_wheel == bytes(8)
    assert hw.scheduler.stats().ticks > 1


# --- config errors ---
@pytest.mark.parametrize(
    ('change', 'match'),
    [
        ({'wheel': {'type': 'm3509', 'bus': 'can0', 'id': 1}}, "type 'm3509' is unknown"),
        ({'wheel': {'type': 'm3508', 'bus': 'can9', 'id': 1}}, "bus 'can9' is not a configured"),
        ({'wheel': {'type': 'm3508', 'bus': 'can0', 'id': 5}}, 'share command frame 0x1FF'),
        (
            {'arm2': {'type': 'dm8009', 'bus': 'can0', 'id': 0x13, 'master_id': 0x13}},
            'both reply with master id 0x013 and id nibble 3 on can0',
        ),
        ({'arm2': {'type': 'dm8009', 'bus': 'can0', 'id': 3}}, 'both send frame 0x003'),
        (
            {'wheel': {'type': 'm3508', 'bus': 'can0', 'id': 1, 'direction': 2}},
            r'joints\.wheel\.direction must be one of 1, -1, got 2',
        ),
        (
            {'wheel': {'type': 'm3508', 'bus': 'can0', 'id': 1, 'velocity_pid': {'kp': -1}}},
            'velocity_pid',
        ),
    ],
)
def test_config_errors_name_the_culprit(channel, change, match):
    cfg = config(channel)
    cfg['joints'].update(change)
    with pytest.raises(HardwareConfigError, match=match):
        CanHardware(cfg, families=motor_families)


def test_joints_may_be_a_list_and_top_level_keys_are_checked(channel):
    cfg = config(channel)
    cfg['joints'] = [{'name': 'wheel', 'type': 'm3508', 'bus': 'can0', 'id': 2}]
    hw = CanHardware(cfg, families=motor_families)
    assert hw.joint_names == ['wheel']
    with pytest.raises(HardwareConfigError, match='duplicate name'):
        CanHardware(dict(cfg, joints=cfg['joints'] * 2), families=motor_families)
    with pytest.raises(HardwareConfigError, match=r"unknown key\(s\) \['scheduler_rate'\]"):
        CanHardware(dict(cfg, scheduler_rate=1), families=motor_families)
    with pytest.raises(HardwareConfigError, match=r'safety\.command_timeout_s must be > 0'):
        CanHardware(dict(cfg, safety={'command_timeout_s': 0}), families=motor_families)


def test_by_default_the_loop_takes_the_feedback_at_the_start_of_its_tick(channel, clock):
    hw = CanHardware(config(channel), clock_ns=clock, families=motor_families)
    peer = can.Bus(interface='virtual', channel=channel)
    try:
        hw.open()
        assert hw.receive_in_loop
        assert not [t for t in threading.enumerate() if t.name.startswith('canrx-')]
        all_feedback(peer)
        assert all(a.feedback is None for a in hw.actuators.values())  # nobody took it yet
        hw.tick()
        assert all(a.feedback is not None for a in hw.actuators.values())
        counts = {name: s.count for name, s in hw.scheduler.component_stats()}
        assert counts['feedback'] == 1
    finally:
        hw.shutdown()
        peer.shutdown()
