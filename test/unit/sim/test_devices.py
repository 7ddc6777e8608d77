"""Simulated drivers on the bus: DJI ESCs, Damiao and Cheetah motors (stepped, through SimBus).

Why one module: the three families' simulated drivers share the SimBus fixtures and the
cross-family checks.
"""

import itertools
import math

import can
import pytest
from rm_base.hardware.protocols import mit
from rm_base.motors.cheetah import protocol as cheetah
from rm_base.motors.damiao import protocol as damiao
from rm_base.motors.dji import protocol as dji
from rm_base.sim import DriveMode, Fault, SimConfigError, SimWorld

from .helpers import drain, send, unique_channel

DM4310 = damiao.dm_limits('DM4310')


def frames_on(frames, can_id):
    return [f for f in frames if f.arbitration_id == can_id]


# -- DJI ---------------------------------------------------------------------------------------


def test_when_stepped_expect_one_dji_feedback_frame_per_tick_per_motor(make_bus):
    bus = make_bus([{'type': 'm3508', 'id': 1}, {'type': 'gm6020', 'id': 2}])
    bus.sim.step(100)
    frames = drain(bus)
    c620 = frames_on(frames, 0x201)
    gm6020 = frames_on(frames, 0x206)  # 0x204 + 2
    assert len(c620) == 100
    assert len(gm6020) == 100
    assert len(frames) == 200
    # Stepped timestamps advance with the simulation clock: 1 ms per tick (an epoch-based
    # float timestamp resolves about 0.2 µs).
    for a, b in itertools.pairwise(c620):
        assert b.timestamp - a.timestamp == pytest.approx(0.001, abs=1e-6)


def test_when_feedback_rate_configured_expect_that_rate(make_bus):
    # 250 Hz on a 1 kHz world: every 4th tick, so 25 frames in 100 ms.
    bus = make_bus([{'type': 'm2006', 'id': 3, 'feedback_rate_hz': 250}])
    bus.sim.step(100)
    assert len(frames_on(drain(bus), 0x203)) == 25


@pytest.mark.parametrize(
    ('motor', 'frame_id', 'slot'),
    [
        ({'type': 'm3508', 'id': 1}, 0x200, 0),
        ({'type': 'm3508', 'id': 3}, 0x200, 2),
        ({'type': 'm3508', 'id': 6}, 0x1FF, 1),
        ({'type': 'm2006', 'id': 8}, 0x1FF, 3),
        ({'type': 'gm6020', 'id': 1}, 0x1FF, 0),
        ({'type': 'gm6020', 'id': 7}, 0x2FF, 2),
        ({'type': 'gm6020', 'id': 2, 'control': 'current'}, 0x1FE, 1),
        ({'type': 'gm6020', 'id': 5, 'control': 'current'}, 0x2FE, 0),
    ],
)
def test_dji_motor_takes_its_slot_of_the_group_frame(make_bus, motor, frame_id, slot):
    bus = make_bus([motor])
    device = bus.sim.motor(f'{motor["type"]}_{motor["id"]}')
    raws = [111, 222, 333, 444]
    send(bus, frame_id, dji.pack_command(raws))
    assert device.command_raw == raws[slot]
    assert device.stats.rx_frames == 1


@pytest.mark.parametrize('other', [0x200, 0x1FF, 0x2FF, 0x1FE, 0x2FE])
def test_dji_motor_ignores_the_other_group_frames(make_bus, other):
    bus = make_bus([{'type': 'm3508', 'id': 2}])  # listens on 0x200 only
    device = bus.sim.motor('m3508_2')
    send(bus, other, dji.pack_command([1000, 1000, 1000, 1000]))
    assert device.command_raw == (1000 if other == 0x200 else 0)


def test_when_c620_current_commanded_expect_that_current():
    # C620: 16384 raw = 20 A, so 4096 raw = 5 A; the rotor is locked so back-EMF is 0.
    with SimWorld(timing='stepped') as world:
        world.add_channel(unique_channel(), [{'type': 'm3508', 'id': 1, 'name': 'w'}])
        device = world.motor('w')
        world.inject('w', Fault.jam())
        device.receive(0x200, dji.pack_command([4096]), world.time_ns)
        world.step()
        assert device.model.current == pytest.approx(5.0)


def test_when_gm6020_voltage_commanded_expect_ohmic_current():
    # 2500 raw * 24 V / 25000 = 2.4 V over 1.8 Ω, rotor locked: 1.333 A (< 3 A limit).
    with SimWorld(timing='stepped') as world:
        world.add_channel(unique_channel(), [{'type': 'gm6020', 'id': 1, 'name': 'yaw'}])
        device = world.motor('yaw')
        world.inject('yaw', Fault.jam())
        device.receive(0x1FF, dji.pack_command([2500]), world.time_ns)
        world.step()
        assert device.model.mode is DriveMode.VOLTAGE
        assert device.model.current == pytest.approx(2.4 / 1.8)


def test_when_command_above_raw_limit_expect_saturated(make_bus):
    bus = make_bus([{'type': 'm3508', 'id': 1}])
    send(bus, 0x200, dji.pack_command([30000]))
    assert bus.sim.motor('m3508_1').command_raw == 16384


def test_dji_feedback_carries_rotor_angle_rpm_current_and_temperature(make_bus):
    bus = make_bus([{'type': 'm3508', 'id': 1, 'coulomb_friction': 0.0, 'viscous_friction': 0.0}])
    device = bus.sim.motor('m3508_1')
    # 1 rad/s at the output is 3591/187 rad/s at the rotor = 183.4 rpm.
    device.model.reset(angle=1.0, velocity=1.0)
    device.model.temperature = 47.4
    bus.sim.step()
    fb = dji.decode_feedback(frames_on(drain(bus), 0x201)[-1].data)
    assert fb.angle_ticks == device.model.encoder_count
    assert fb.rotor_rpm == round(3591 / 187 * 60 / (2 * math.pi))
    assert fb.current_raw == 0
    assert fb.temperature_c == 47


def test_when_c610_expect_temperature_byte_zero_even_when_hot(make_bus):
    bus = make_bus([{'type': 'm2006', 'id': 1}, {'type': 'm3508', 'id': 2}])
    bus.sim.inject('m2006_1', Fault.over_temperature(60.0))
    bus.sim.inject('m3508_2', Fault.over_temperature(60.0))
    bus.sim.step()
    frames = drain(bus)
    assert frames_on(frames, 0x201)[-1].data[6] == 0
    assert frames_on(frames, 0x202)[-1].data[6] == 60


def test_when_no_command_for_timeout_expect_zero_current(make_bus):
    bus = make_bus([{'type': 'm3508', 'id': 1, 'command_timeout': 0.02}])
    device = bus.sim.motor('m3508_1')
    device.model.locked = True
    send(bus, 0x200, dji.pack_command([4096]))
    bus.sim.step(20)  # 20 ms: still inside the timeout
    assert device.model.current == pytest.approx(5.0)
    bus.sim.step(2)  # the command is now 21 ms old
    assert device.model.current == 0.0
    assert device.stats.timeouts == 1
    send(bus, 0x200, dji.pack_command([4096]))  # a new command revives it
    bus.sim.step()
    assert device.model.current == pytest.approx(5.0)


def test_default_command_timeout_is_100_ms(make_bus):
    bus = make_bus([{'type': 'm3508', 'id': 1}])
    device = bus.sim.motor('m3508_1')
    device.model.locked = True
    send(bus, 0x200, dji.pack_command([4096]))
    bus.sim.step(100)
    assert device.model.current == pytest.approx(5.0)
    bus.sim.step(2)
    assert device.model.current == 0.0


def test_when_command_timeout_disabled_expect_command_holds(make_bus):
    bus = make_bus([{'type': 'm3508', 'id': 1, 'command_timeout': 0}])
    device = bus.sim.motor('m3508_1')
    device.model.locked = True
    send(bus, 0x200, dji.pack_command([4096]))
    bus.sim.step(1000)
    assert device.model.current == pytest.approx(5.0)


@pytest.mark.parametrize(
    'message',
    [
        can.Message(arbitration_id=0x200, data=b'\x10\x00\x00\x00', is_extended_id=False),
        can.Message(arbitration_id=0x200, is_remote_frame=True, dlc=8, is_extended_id=False),
        can.Message(arbitration_id=0x200, data=bytes(8), is_extended_id=True),
        can.Message(arbitration_id=0x200, data=bytes(8), is_fd=True, is_extended_id=False),
    ],
    ids=['short', 'remote', 'extended', 'fd'],
)
def test_when_malformed_command_expect_ignored_and_counted(make_bus, message):
    bus = make_bus([{'type': 'm3508', 'id': 1}])
    device = bus.sim.motor('m3508_1')
    send(bus, 0x200, dji.pack_command([1000]))
    bus.send(message)
    assert device.command_raw == 1000
    assert device.stats.ignored_frames == 1
    assert device.stats.rx_frames == 1


def test_when_frame_for_nobody_expect_counted_unclaimed(make_bus):
    bus = make_bus([{'type': 'm3508', 'id': 1}])
    send(bus, 0x123, b'\x01')
    assert bus.sim_channel.stats.unclaimed == 1
    assert bus.sim.motor('m3508_1').stats.ignored_frames == 0


# -- Damiao ------------------------------------------------------------------------------------


def dm_bus(make_bus, **extra):
    motor = {'type': 'dm4310', 'id': 1, 'name': 'pitch', 'master_id': 0x11, **extra}
    bus = make_bus([motor])
    return bus, bus.sim.motor('pitch')


def mit_frame(p=0.0, v=0.0, kp=0.0, kd=0.0, t=0.0):
    return mit.pack_mit_command(mit.MitCommand(p, v, kp, kd, t), DM4310)


def dm_replies(bus):
    return [damiao.decode_feedback(f.data, DM4310) for f in frames_on(drain(bus), 0x11)]


def test_when_damiao_disabled_expect_no_reply_to_mit_command(make_bus):
    bus, device = dm_bus(make_bus)
    send(bus, 0x001, mit_frame(t=1.0))
    assert dm_replies(bus) == []
    assert device.stats.ignored_frames == 1
    bus.sim.step(10)
    assert device.model.current == 0.0  # and it did not act on it


def test_when_damiao_enabled_expect_one_reply_per_command(make_bus):
    bus, _ = dm_bus(make_bus)
    send(bus, 0x001, mit.system_frame(mit.SystemCommand.ENABLE))
    (enable_reply,) = dm_replies(bus)
    assert enable_reply.state == damiao.DmState.ENABLED
    assert enable_reply.motor_id == 1
    for _ in range(3):
        send(bus, 0x001, mit_frame())
    assert len(dm_replies(bus)) == 3
    bus.sim.step(10)
    assert dm_replies(bus) == []  # no unsolicited feedback


def test_when_damiao_disabled_again_expect_replies_stop(make_bus):
    bus, device = dm_bus(make_bus)
    send(bus, 0x001, mit.system_frame(mit.SystemCommand.ENABLE))
    send(bus, 0x001, mit.system_frame(mit.SystemCommand.DISABLE))
    replies = dm_replies(bus)
    assert [r.state for r in replies] == [damiao.DmState.ENABLED, damiao.DmState.DISABLED]
    send(bus, 0x001, mit_frame(t=1.0))
    assert dm_replies(bus) == []
    assert not device.enabled


def test_damiao_computes_the_mit_law_on_the_motor(make_bus):
    bus, _ = dm_bus(make_bus)
    send(bus, 0x001, mit.system_frame(mit.SystemCommand.ENABLE))
    send(bus, 0x001, mit_frame(p=1.0, kp=20.0, kd=1.0))
    bus.sim.step(2000)
    send(bus, 0x001, mit_frame(p=1.0, kp=20.0, kd=1.0))
    reply = dm_replies(bus)[-1]
    # Error budget: Coulomb friction 0.05 N·m / kp 20 = 2.5 mrad dead band, the target's
    # 16-bit field truncates by up to 0.4 mrad and the reply's by another 0.4 mrad.
    assert reply.position == pytest.approx(1.0, abs=3.3e-3 + 1e-4)
    assert reply.velocity == pytest.approx(0.0, abs=0.02)


def test_when_set_zero_expect_position_reads_zero_there(make_bus):
    bus, device = dm_bus(make_bus, initial_position=0.7)
    send(bus, 0x001, mit.system_frame(mit.SystemCommand.ENABLE))
    send(bus, 0x001, mit.system_frame(mit.SystemCommand.SET_ZERO))
    send(bus, 0x001, mit_frame())
    reply = dm_replies(bus)[-1]
    assert reply.position == pytest.approx(0.0, abs=4e-4)
    assert device.model.angle == pytest.approx(0.7)


def test_damiao_position_wraps_within_pmax(make_bus):
    # 12.6 rad is beyond PMAX 12.5: it reads 12.6 - 25 = -12.4 rad.
    bus, _ = dm_bus(make_bus, initial_position=12.6, enabled=True)
    send(bus, 0x001, mit_frame())
    assert dm_replies(bus)[-1].position == pytest.approx(-12.4, abs=4e-4)


def test_when_damiao_overheats_expect_error_state_and_limp(make_bus):
    bus, device = dm_bus(make_bus, enabled=True)
    bus.sim.inject('pitch', Fault.over_temperature(130.0))  # cut-out default 120 °C
    send(bus, 0x001, mit_frame(t=2.0))
    bus.sim.step()  # the driver checks its temperature once per tick
    send(bus, 0x001, mit_frame(t=2.0))
    reply = dm_replies(bus)[-1]
    assert reply.state == damiao.DmState.COIL_OVER_TEMPERATURE
    assert reply.t_rotor == 130
    assert device.model.current == 0.0


def test_when_damiao_error_cleared_while_hot_expect_error_stays(make_bus):
    bus, device = dm_bus(make_bus, enabled=True)
    bus.sim.inject('pitch', Fault.over_temperature(130.0))
    bus.sim.step()
    send(bus, 0x001, mit.system_frame(mit.SystemCommand.CLEAR_ERROR))
    assert dm_replies(bus)[-1].state == damiao.DmState.COIL_OVER_TEMPERATURE
    bus.sim.clear_faults('pitch')
    device.model.temperature = 60.0  # cooled down
    send(bus, 0x001, mit.system_frame(mit.SystemCommand.CLEAR_ERROR))
    assert dm_replies(bus)[-1].state == damiao.DmState.DISABLED
    send(bus, 0x001, mit.system_frame(mit.SystemCommand.ENABLE))
    assert dm_replies(bus)[-1].state == damiao.DmState.ENABLED


def test_when_damiao_command_timeout_expect_communication_lost(make_bus):
    bus, device = dm_bus(make_bus, enabled=True, command_timeout=0.05)
    send(bus, 0x001, mit_frame(t=1.0))
    bus.sim.step(60)
    send(bus, 0x001, mit_frame(t=1.0))
    assert dm_replies(bus)[-1].state == damiao.DmState.COMMUNICATION_LOST
    assert device.stats.timeouts == 1
    assert device.model.current == 0.0


@pytest.mark.parametrize('system_id', [0x101, 0x001])
def test_damiao_pos_vel_mode_reaches_position_within_speed_limit(make_bus, system_id):
    bus, device = dm_bus(make_bus, mode='pos_vel')
    # System frames are taken on id + 0x100 and on the bare id (the SDKs disagree).
    send(bus, system_id, mit.system_frame(mit.SystemCommand.ENABLE))
    send(bus, 0x101, damiao.pack_pos_vel(1.0, 2.0))
    assert len(dm_replies(bus)) == 2
    peak = 0.0
    for _ in range(1500):
        bus.sim.step()
        peak = max(peak, abs(device.model.velocity))
    assert device.position == pytest.approx(1.0, abs=2e-3)
    assert peak < 2.0 * 1.1  # the velocity limit, with the loop's small overshoot


def test_damiao_vel_mode_reaches_velocity(make_bus):
    bus, device = dm_bus(make_bus, mode='vel')
    send(bus, 0x201, mit.system_frame(mit.SystemCommand.ENABLE))
    send(bus, 0x201, damiao.pack_vel(3.0))
    bus.sim.step(1000)
    assert device.model.velocity == pytest.approx(3.0, rel=1e-3)


def test_when_damiao_control_frame_on_other_mode_id_expect_ignored(make_bus):
    bus, device = dm_bus(make_bus, mode='vel', enabled=True)
    send(bus, 0x001, mit_frame(t=1.0))  # an MIT frame to a VEL-mode motor
    assert dm_replies(bus) == []
    assert device.stats.ignored_frames == 1


def test_when_damiao_vel_frame_is_nan_expect_ignored(make_bus):
    bus, device = dm_bus(make_bus, mode='vel', enabled=True)
    send(bus, 0x201, b'\x00\x00\xc0\x7f')  # float32 NaN
    assert dm_replies(bus) == []
    assert device.stats.ignored_frames == 1


# -- Cheetah -----------------------------------------------------------------------------------


def test_cheetah_replies_six_bytes_to_master_zero_when_enabled(make_bus):
    bus = make_bus([{'type': 'cheetah', 'id': 3, 'name': 'leg'}])
    limits = cheetah.CHEETAH_DEFAULT_LIMITS
    command = mit.pack_mit_command(mit.MitCommand(0.0, 0.0, 0.0, 0.0, 0.0), limits)
    send(bus, 0x003, command)
    assert drain(bus) == []  # disabled: no reply
    send(bus, 0x003, cheetah.cheetah_system_frame(mit.SystemCommand.ENABLE))
    send(bus, 0x003, command)
    replies = drain(bus)
    assert [r.arbitration_id for r in replies] == [0x000, 0x000]
    assert all(len(r.data) == 6 for r in replies)
    assert cheetah.decode_reply(replies[-1].data, limits).motor_id == 3


def test_cheetah_with_voltage_reply_sends_seven_bytes(make_bus):
    bus = make_bus([{'type': 'cheetah', 'id': 1, 'reply_voltage': True, 'master_id': 0x40}])
    send(bus, 0x001, cheetah.cheetah_system_frame(mit.SystemCommand.ENABLE))
    (reply,) = drain(bus)
    assert reply.arbitration_id == 0x40
    decoded = cheetah.decode_reply(reply.data)
    assert decoded.bus_voltage == pytest.approx(24.0, abs=40 / 255)


def test_cheetah_treats_ff_fb_as_an_mit_command_like_its_firmware(make_bus):
    # The Cheetah firmware knows no clear-error: FF..FB unpacks as an MIT command.
    bus = make_bus([{'type': 'cheetah', 'id': 1, 'enabled': True}])
    device = bus.sim.motor('cheetah_1')
    send(bus, 0x001, mit.system_frame(mit.SystemCommand.CLEAR_ERROR))
    assert len(drain(bus)) == 1
    assert device.command.kp == pytest.approx(500.0)


# -- configuration -----------------------------------------------------------------------------


@pytest.mark.parametrize(
    ('motors', 'message'),
    [
        ([{'type': 'm3509', 'id': 1}], "unknown motor type 'm3509'"),
        ([{'type': 'm3508'}], r'motor\.id is required'),
        ([{'type': 'm3508', 'id': 1, 'load_inertia': -1}],
         r'm3508_1\.load_inertia must be >= 0\.0, got -1'),
        ([{'type': 'm3508', 'id': 1, 'feedback_rate_hz': 0}],
         r'm3508_1\.feedback_rate_hz must be > 0\.0, got 0'),
        ([{'type': 'dm4310', 'id': 1, 'name': 'j', 'limits': {'p_max': 'far'}}],
         "j: MIT limit p_max must be a number, got 'far'"),
        ([{'type': 'dm4310', 'id': 1, 'enabled': 'yes'}], r'dm4310_1\.enabled must be bool'),
        ([{'type': 'm3508', 'id': 9}], 'out of range 1..8'),
        ([{'type': 'gm6020', 'id': 8}], 'out of range 1..7'),
        ([{'type': 'm3508', 'id': 1, 'friction': 0.1}], r"unknown key\(s\) \['friction'\]"),
        ([{'type': 'm3508', 'id': 1, 'control': 'current'}], 'only the GM6020'),
        ([{'type': 'dm4310', 'id': 1, 'mode': 'pos_force'}], 'mode must be one of'),
        ([{'type': 'dm4310', 'id': 17}], 'Damiao id must be 0..15'),
        ([{'type': 'm3508', 'id': 5}, {'type': 'gm6020', 'id': 1}], 'share command frame'),
        ([{'type': 'm3508', 'id': 1}, {'type': 'm3508', 'id': 1, 'name': 'b'}], 'share'),
        (
            [{'type': 'm3508', 'id': 1}, {'type': 'dm4310', 'id': 2, 'master_id': 0x201}],
            'both send on id 0x201',
        ),
        (
            [{'type': 'm3508', 'id': 1}, {'type': 'dm4310', 'id': 1, 'mode': 'vel'}],
            'listens on 0x201',
        ),
        ([{'type': 'm3508', 'id': 1}, {'type': 'm3508', 'id': 2, 'name': 'm3508_1'}], 'named'),
    ],
)
def test_when_bad_motor_config_expect_config_error(motors, message):
    with SimWorld(timing='stepped') as world, pytest.raises(SimConfigError, match=message):
        world.add_channel(unique_channel(), motors)


def test_motor_parameters_are_overridable_from_config(make_bus):
    bus = make_bus([{'type': 'm3508', 'id': 1, 'load_inertia': 0.5, 'max_current': 10.0}])
    params = bus.sim.motor('m3508_1').model.params
    assert params.load_inertia == 0.5
    assert params.max_current == 10.0
    assert params.torque_constant == 0.3  # the rest keeps the M3508 defaults


def test_when_dji_cut_out_configured_expect_zero_current_while_hot(make_bus):
    bus = make_bus([{'type': 'm3508', 'id': 1, 'overtemp_c': 100.0, 'command_timeout': 0}])
    device = bus.sim.motor('m3508_1')
    device.model.locked = True
    send(bus, 0x200, dji.pack_command([4096]))
    bus.sim.step()
    assert device.model.current == pytest.approx(5.0)
    bus.sim.inject('m3508_1', Fault.over_temperature(101.0))
    bus.sim.step()
    assert device.model.current == 0.0
    bus.sim.clear_faults('m3508_1')
    device.model.temperature = 90.0
    bus.sim.step()
    assert device.model.current == pytest.approx(5.0)  # the held command comes back
