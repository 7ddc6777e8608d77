"""Calibration services in lockstep: gimbal zeros set from the present pose, kept in a file.

The standard robot on rm_sim turns its gimbal away from its start, goes PASSIVE and sets
the yaw zero there (can_bridge's ``<joint>/set_zero``): the joint then reads 0, the
calibration file holds the offset, and a robot started again from that file reads the
start pose where the zero-less one did, less the offset. A driven joint, a moving one
(the limp pitch sinks under its own weight: it must be held) and a geared wheel are
refused, each saying why.
"""

from __future__ import annotations

import pytest
from rm_base.config.calibration import CalibrationFile, joint_zero_offsets
from rm_base.geometry import wrap_to_pi
from support.lockstep import LockstepRobot

from rm_msgs.msg import ChassisCmd, GimbalCmd

pytestmark = [pytest.mark.ros]

GIMBAL = ('imu', 'gpio', 'chassis', 'gimbal')


def robot(path) -> LockstepRobot:
    return LockstepRobot(
        plugins=GIMBAL, overrides={'can_bridge': {'calibration.file': str(path)}}
    )


def positions(r: LockstepRobot) -> dict[str, float]:
    return {j: r.bridge.hardware.actuators[j].feedback.position for j in ('yaw', 'pitch')}


def test_gimbal_zeros_are_set_where_it_stands_and_kept_for_the_next_start(tmp_path):
    path = tmp_path / 'calibration.yaml'
    with robot(path) as r:
        r.publish('/chassis_cmd', ChassisCmd(mode=ChassisCmd.PASSIVE), rate_hz=50)
        r.run(0.05)
        start = positions(r)
        r.publish('/gimbal_cmd', GimbalCmd(mode=GimbalCmd.RATE, rate_yaw=1.5, rate_pitch=-0.4),
                  rate_hz=50)
        r.run(0.5)
        ok, message = r.bridge.set_zero('yaw')
        assert not ok and message == (
            'refused: yaw is driven: make the plugin that drives it PASSIVE first'
        )
        r.publish('/gimbal_cmd', GimbalCmd(mode=GimbalCmd.PASSIVE), rate_hz=50)
        r.run(0.5)
        turned = positions(r)
        assert abs(turned['yaw'] - start['yaw']) > 0.4
        ok, message = r.bridge.set_zero('pitch')
        assert not ok and message.startswith('refused: pitch is moving (')
        ok, message = r.bridge.set_zero('yaw')
        assert ok, message
        assert message.startswith('yaw: zero set at the present position (zero_offset ')
        assert message.endswith(f'saved to {path}')
        r.run(0.01)
        assert positions(r)['yaw'] == pytest.approx(0.0, abs=1e-3)
        ok, message = r.bridge.set_zero('wheel_fl')
        assert not ok and 'wheel_fl: its encoder turns' in message
    zeros = joint_zero_offsets(CalibrationFile(str(path)))
    assert set(zeros) == {'yaw'}
    with robot(path) as again:
        again.run(0.05)
        assert again.bridge.hardware.actuators['yaw'].zero_offset == zeros['yaw']
        expected = wrap_to_pi(start['yaw'] - turned['yaw'])
        assert positions(again)['yaw'] == pytest.approx(expected, abs=2e-3)
