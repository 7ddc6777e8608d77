"""State and frame messages built from the hardware layer's values."""

import math

import can
import pytest
from rm_base.bridge.messages import (
    actuator_state_msg,
    can_frame_msg,
    joint_state_msg,
    state_msgs,
    time_msg,
)
from rm_base.hardware import JointState

STATES = [
    JointState('wheel', 1.5, 20.0, 0.3, 41.0, True, 0, 2, 0.35),
    JointState('pitch', -0.2, 0.0, 0.0, math.nan, False, 5, 0, 0.0),
]


def test_joint_state_holds_position_velocity_effort_per_joint():
    msg = joint_state_msg(STATES, time_msg(1_500_000_000))
    assert msg.header.stamp.sec == 1 and msg.header.stamp.nanosec == 500_000_000
    assert list(msg.name) == ['wheel', 'pitch']
    assert list(msg.position) == [1.5, -0.2]
    assert list(msg.velocity) == [20.0, 0.0]
    assert list(msg.effort) == [0.3, 0.0]


def test_actuator_state_holds_every_field():
    msg = actuator_state_msg(STATES, time_msg(0))
    assert list(msg.name) == ['wheel', 'pitch']
    assert list(msg.position) == [1.5, -0.2]
    assert list(msg.velocity) == [20.0, 0.0]
    assert list(msg.effort) == [0.3, 0.0]
    assert msg.temperature[0] == 41.0 and math.isnan(msg.temperature[1])
    assert list(msg.online) == [True, False]
    assert list(msg.error_code) == [0, 5]
    assert list(msg.mode) == [2, 0]
    assert list(msg.command) == [0.35, 0.0]


def test_state_msgs_build_both_messages_alike():
    stamp = time_msg(2_000_000_001)
    joint, actuator = state_msgs(STATES, stamp)
    expected_joint = joint_state_msg(STATES, stamp)
    expected_actuator = actuator_state_msg(STATES, stamp)
    assert joint == expected_joint
    # NaN != NaN: the temperature column apart
    assert actuator.temperature[0] == 41.0 and math.isnan(actuator.temperature[1])
    actuator.temperature = expected_actuator.temperature = [0.0, 0.0]
    assert actuator == expected_actuator


def test_when_no_joints_expect_empty_state_messages():
    joint, actuator = state_msgs([], time_msg(0))
    assert list(joint.name) == [] and list(joint.position) == []
    assert list(actuator.online) == [] and list(actuator.error_code) == []


def test_when_an_error_code_exceeds_a_byte_expect_its_low_byte():
    (state,) = STATES[:1]
    msg = actuator_state_msg([state._replace(error_code=0x1F3)], time_msg(0))
    assert list(msg.error_code) == [0xF3]


@pytest.mark.parametrize('is_rx', [True, False])
def test_can_frame_copies_the_frame(is_rx):
    frame = can.Message(arbitration_id=0x1FF, data=b'\x01\x02\x03', is_extended_id=False)
    msg = can_frame_msg('can1', frame, is_rx, time_msg(7))
    assert (msg.bus, msg.is_rx, msg.id) == ('can1', is_rx, 0x1FF)
    assert not msg.is_extended and not msg.is_fd
    assert bytes(msg.data) == b'\x01\x02\x03'
    assert msg.header.stamp.nanosec == 7
