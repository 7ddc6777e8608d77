"""Tunable parameters set on the running robot: checked, all of a call or none, between runs.

Through the host node's parameter services' own path (``Node.set_parameters`` runs the
set-parameters callback exactly as ``ros2 param set`` does), in lockstep.
"""

from __future__ import annotations

import pytest
from geometry_msgs.msg import Twist, Vector3
from rclpy.parameter import Parameter
from rm_plugins.chassis.commands import SpeedGear
from support.lockstep import LockstepRobot

from rm_msgs.msg import ChassisCmd, ShootCmd

pytestmark = [pytest.mark.ros]

HZ = 20.0


def _set(r, **values):
    """Set host parameters (``heat__margin`` for ``shooter.heat.margin``); one result."""
    params = [Parameter(k.replace('__', '.'), value=v) for k, v in values.items()]
    return r.host.set_parameters_atomically(params)


def test_a_tunable_key_changes_between_runs_and_the_others_refuse_with_the_reason():
    with LockstepRobot('standard', plugins=('shooter',)) as r:
        shooter = r.plugin('shooter')
        r.publish('/shoot_cmd', ShootCmd(mode=ShootCmd.READY, speed=15.0), rate_hz=HZ)
        r.run(0.5)
        assert shooter.config.max_hz != 7.5

        result = _set(r, shooter__max_hz=7.5, shooter__jam__time=0.3)
        assert result.successful, result.reason
        # not in the middle of a run: the plugin has the old set until its next run
        assert shooter.config.max_hz != 7.5
        r.run(0.05)
        assert (shooter.config.max_hz, shooter.config.jam.time) == (7.5, 0.3)
        assert r.host.get_parameter('shooter.max_hz').value == 7.5

        # out of bounds: refused, naming key and bound; nothing of the call applied
        result = _set(r, shooter__max_hz=9.0, shooter__jam__effort=-1.0)
        assert not result.successful
        assert result.reason == 'shooter.jam.effort must be > 0.0, got -1.0'
        r.run(0.05)
        assert shooter.config.max_hz == 7.5
        assert r.host.get_parameter('shooter.max_hz').value == 7.5

        # the wrong type: refused, and the parameter still describes itself as a double
        result = _set(r, shooter__max_hz='fast')
        assert not result.successful and 'max_hz must be double' in result.reason
        assert r.host.describe_parameter('shooter.max_hz').type == Parameter.Type.DOUBLE.value

        # the set's own checks: a step tolerance over half a slot
        result = _set(r, shooter__step_tolerance=3.0)
        assert not result.successful and 'below half a slot' in result.reason

        # start-up keys are read-only: refused, and their description says why
        for key, value in (('shooter.trigger_joint', 'x'), ('shooter.rate', 50.0),
                           ('plugins', ['shooter'])):
            result = r.host.set_parameters_atomically([Parameter(key, value=value)])
            assert not result.successful
            assert result.reason == f'Trying to set a read-only parameter: {key}.'
            assert r.host.describe_parameter(key).additional_constraints.endswith(
                'read at start-up: a change needs a restart')


def test_a_joints_loop_gains_change_at_the_next_tick_and_the_rest_of_its_table_refuses():
    with LockstepRobot('standard', plugins=('chassis',)) as r:
        wheel = r.bridge.hardware.actuators['wheel_fl']
        velocity, _ = wheel.loop_gains
        result = r.bridge.set_parameters_atomically([
            Parameter('joints.wheel_fl.velocity_pid.kp', value=velocity.kp * 2),
            Parameter('joints.wheel_fl.velocity_pid.ki', value=0.0),
        ])
        assert result.successful, result.reason
        assert wheel.loop_gains[0] == velocity  # not before a tick
        r.step()
        new, _ = wheel.loop_gains
        assert (new.kp, new.ki, new.output_limit) == (velocity.kp * 2, 0.0, velocity.output_limit)
        bad = r.bridge.set_parameters_atomically(
            [Parameter('joints.wheel_fl.velocity_pid.kp', value=-1.0)])
        assert not bad.successful and 'joints.wheel_fl.velocity_pid' in bad.reason
        fixed = r.bridge.set_parameters_atomically([Parameter('joints.wheel_fl.id', value=3)])
        assert not fixed.successful
        assert fixed.reason.startswith(
            'joints.wheel_fl.id: read at start-up: a change needs a restart'), fixed.reason
        flat = r.bridge.set_parameters_atomically([Parameter('publish_rate', value=50.0)])
        assert flat.reason == 'Trying to set a read-only parameter: publish_rate.'
        r.step()
        assert wheel.loop_gains[0] == new


def test_a_gain_written_as_a_whole_number_takes_a_fraction_and_an_unwritten_field_is_live():
    # a team's config writes `kp: 20`; rclpy declared it an integer, which refused 20.5
    overrides = {'can_bridge': {'joints.yaw.position_pid.kp': 20}}
    with LockstepRobot('standard', plugins=('gimbal',), overrides=overrides) as r:
        yaw = r.bridge.hardware.actuators['yaw']
        assert r.bridge.get_parameter('joints.yaw.position_pid.kp').value == 20.0
        result = r.bridge.set_parameters_atomically(
            [Parameter('joints.yaw.position_pid.kp', value=20.5)])
        assert result.successful, result.reason
        # a field the config leaves out is declared with the value in use, and is live
        assert r.bridge.get_parameter('joints.yaw.position_pid.deadband').value == 0.0
        result = r.bridge.set_parameters_atomically(
            [Parameter('joints.yaw.position_pid.deadband', value=0.001)])
        assert result.successful, result.reason
        r.step()
        position = yaw.loop_gains[1]
        assert (position.kp, position.deadband) == (20.5, 0.001)
        # a whole number for a double (ros2 param set's `30`, a Foxglove client's JSON)
        for node, name in ((r.bridge, 'joints.yaw.position_pid.kp'),
                           (r.host, 'gimbal.yaw_pid.kp')):
            (result,) = node.set_parameters([Parameter(name, value=30)])
            assert result.successful, (name, result.reason)
            held = node.get_parameter(name)
            assert (held.type_, held.value) == (Parameter.Type.DOUBLE, 30.0), name
        r.step()
        assert yaw.loop_gains[1].kp == 30.0
        described = r.bridge.describe_parameter('joints.yaw.position_pid.kd')
        assert described.additional_constraints == 'type: double; set while running'
        # a joint's loop the config does not give stays undeclared (the wheels' position)
        assert not r.bridge.has_parameter('joints.wheel_fl.position_pid.kp')


def test_the_gimbals_loop_gains_are_live_and_its_frames_are_not():
    with LockstepRobot('standard', plugins=('imu', 'gimbal')) as r:
        gimbal = r.plugin('gimbal')
        kp = gimbal.config.yaw.angle_pid.kp
        result = r.host.set_parameters_atomically([
            Parameter('gimbal.yaw_pid.kp', value=kp + 5.0),
            Parameter('gimbal.pitch_pid.max_rate', value=4.0),
        ])
        assert result.successful, result.reason
        r.run(0.05)
        assert gimbal.config.yaw.angle_pid.kp == kp + 5.0
        assert gimbal.config.pitch.angle_pid.output_limit == 4.0
        assert gimbal.config.yaw.angle_pid.angle_mode  # the loop's own settings stay
        refused = r.host.set_parameters_atomically([Parameter('gimbal.yaw_pid.kp', value=-1.0)])
        assert refused.reason == 'gimbal.yaw_pid.kp must be >= 0.0, got -1.0'
        frames = r.host.set_parameters_atomically([Parameter('gimbal.pitch_joint', value='x')])
        assert frames.reason == 'Trying to set a read-only parameter: gimbal.pitch_joint.'


def test_the_chassis_gears_and_default_power_limit_are_live():
    with LockstepRobot('standard', plugins=('chassis',)) as r:
        chassis = r.plugin('chassis')
        result = r.host.set_parameters_atomically([
            Parameter('chassis.gears.slow.linear', value=0.3),
            Parameter('chassis.power.default_limit', value=45.0),
        ])
        assert result.successful, result.reason
        r.run(0.05)
        assert chassis.config.gears[SpeedGear.SLOW][0] == 0.3
        assert chassis.config.power_limit == 45.0
        refused = r.host.set_parameters_atomically(
            [Parameter('chassis.gears.fast.angular', value=0.0)])
        assert refused.reason == 'chassis.gears.fast.angular must be > 0.0, got 0.0'
        wheels = r.host.set_parameters_atomically([Parameter('chassis.wheel_radius', value=0.1)])
        assert wheels.reason == 'Trying to set a read-only parameter: chassis.wheel_radius.'


def _speed_after(r, seconds):
    """The body's forward speed [m/s] seconds after a RAW 2 m/s command from rest."""
    r.publish('/chassis_cmd', ChassisCmd(mode=ChassisCmd.RAW), rate_hz=HZ)
    r.publish('/vel_cmd', Twist(linear=Vector3(x=2.0)), rate_hz=HZ)
    r.run(seconds)
    return r.world.body.twist[0]


def test_the_chassis_ramps_and_power_model_are_live():
    with LockstepRobot('standard', plugins=('chassis',)) as r:
        # the default ramp (launch 4, normal 6 m/s^2): 0.82 m/s after 0.3 s (lockstep)
        assert _speed_after(r, 0.3) > 0.7
    with LockstepRobot('standard', plugins=('chassis',)) as r:
        result = r.host.set_parameters_atomically([
            Parameter(f'chassis.ramp.linear.{key}_acceleration', value=1.0)
            for key in ('launch', 'normal')
        ] + [Parameter('chassis.power.k1', value=3.5),
             Parameter('chassis.power.static_power', value=4.0)])
        assert result.successful, result.reason
        assert _speed_after(r, 0.3) < 0.3  # 1 m/s^2 for 0.3 s, and the wheels' lag
        stage = r.bridge.hardware.power_limits['chassis']
        assert (stage.model.k1, stage.model.k2, stage.model.static_power_w) == (3.5, 3.08e-3,
                                                                                 4.0)
        refused = r.host.set_parameters_atomically(
            [Parameter('chassis.power.k2', value=-1.0)])
        assert refused.reason == 'chassis.power.k2 must be >= 0.0, got -1.0'


def test_the_chassis_modes_loops_are_live_gyro_spins_at_the_new_rate():
    with LockstepRobot('standard', plugins=('chassis',)) as r:
        chassis = r.plugin('chassis')
        r.publish('/chassis_cmd', ChassisCmd(mode=ChassisCmd.GYRO, follow_source='base_link'),
                  rate_hz=HZ)
        r.publish('/vel_cmd', Twist(), rate_hz=HZ)
        r.run(1.5)
        assert r.world.body.twist[2] > 4.5  # 6 rad/s asked, within the default 60 W
        result = r.host.set_parameters_atomically([
            Parameter('chassis.gyro.spin_rate', value=3.0),
            Parameter('chassis.follow.pid.kp', value=6.0),
            Parameter('chassis.twist.amplitude', value=0.4),
        ])
        assert result.successful, result.reason
        r.run(1.5)
        assert r.world.body.twist[2] == pytest.approx(3.0, abs=0.3)
        modes = chassis.config.modes
        assert (modes.follow.gains.kp, modes.twist.amplitude) == (6.0, 0.4)
        waveform = r.host.set_parameters_atomically(
            [Parameter('chassis.twist.waveform', value='triangle')])
        assert waveform.reason == 'Trying to set a read-only parameter: chassis.twist.waveform.'
