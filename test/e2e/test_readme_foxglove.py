"""README's "See it live in Foxglove": a WebSocket client sees the robot and tunes it.

The client speaks the Foxglove WebSocket protocol (foxglove.sdk.v1) itself, through
the websockets library: it reads the advertised channels, subscribes, decodes the CDR
messages of each kind with their ROS 2 classes, and gets and sets parameters.
"""

import json
import re
import struct
import time

import pytest
from diagnostic_msgs.msg import DiagnosticArray
from rclpy.serialization import deserialize_message
from sensor_msgs.msg import JointState
from std_msgs.msg import String
from support.user_session import UserSession, readme_blocks
from tf2_msgs.msg import TFMessage
from websockets.sync.client import connect

from rm_msgs.msg import ChassisState

pytestmark = [pytest.mark.ros, pytest.mark.slow, pytest.mark.realtime]

WAIT_S = 60.0  # the robot's start and discovery on a loaded 2-core machine: generous
KINDS = {
    '/joint_states': JointState,
    '/chassis_state': ChassisState,
    '/diagnostics': DiagnosticArray,
    '/tf': TFMessage,
    '/robot_description': String,
}


@pytest.fixture
def robot(tmp_path):
    """README's line, typed as written; yields the port it says it serves on."""
    (block,) = readme_blocks('See it live in Foxglove')
    command = ['bash', '-c', f'source scripts/env.sh && {block.strip()}']
    with UserSession(tmp_path, command=command) as user:
        said = user.status.wait_for(lambda line: 'Foxglove: ws://' in line, WAIT_S)
        assert said, user.log[-3000:]
        yield int(re.search(r'ws://127\.0\.0\.1:(\d+)', said).group(1))


def _json(ws, op, timeout):
    """The next JSON message of op (others skipped), or None."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        try:
            message = ws.recv(timeout=max(0.01, deadline - time.monotonic()))
        except TimeoutError:
            return None
        if isinstance(message, str) and json.loads(message).get('op') == op:
            return json.loads(message)
    return None


def test_a_client_gets_each_kind_of_message_live_and_sets_a_live_parameter(robot):
    with connect(f'ws://127.0.0.1:{robot}', subprotocols=['foxglove.sdk.v1']) as ws:
        channels = {}
        deadline = time.monotonic() + WAIT_S
        while set(KINDS) - set(channels) and time.monotonic() < deadline:
            advertised = _json(ws, 'advertise', deadline - time.monotonic())
            for channel in (advertised or {}).get('channels', ()):
                channels[channel['topic']] = channel
        assert set(KINDS) <= set(channels), sorted(channels)
        assert channels['/chassis_state']['schemaName'] == 'rm_msgs/msg/ChassisState'
        assert channels['/chassis_state']['encoding'] == 'cdr'
        assert channels['/chassis_state']['schemaEncoding'] == 'ros2msg'

        by_id = {i: topic for i, topic in enumerate(KINDS, start=1)}
        ws.send(json.dumps({'op': 'subscribe', 'subscriptions': [
            {'id': i, 'channelId': channels[topic]['id']} for i, topic in by_id.items()]}))
        got = {}
        deadline = time.monotonic() + WAIT_S
        while set(KINDS) - set(got) and time.monotonic() < deadline:
            try:
                message = ws.recv(timeout=1.0)
            except TimeoutError:
                continue
            if isinstance(message, bytes) and message[0] == 0x01:  # MessageData
                subscription, _stamp = struct.unpack_from('<IQ', message, 1)
                topic = by_id[subscription]
                got[topic] = deserialize_message(message[13:], KINDS[topic])
        assert set(KINDS) <= set(got), sorted(got)
        assert {'wheel_fl', 'yaw', 'pitch'} <= set(got['/joint_states'].name)
        assert got['/diagnostics'].status
        assert got['/tf'].transforms
        urdf = got['/robot_description'].data
        assert '<robot name="rm_robot">' in urdf and 'wheel_wheel_fl' in urdf and 'muzzle' in urdf

        def parameter(name, request_id, value=None):
            if value is None:
                ws.send(json.dumps({'op': 'getParameters', 'parameterNames': [name],
                                    'id': request_id}))
            else:
                ws.send(json.dumps({'op': 'setParameters', 'id': request_id,
                                    'parameters': [{'name': name, 'value': value}]}))
            answer = _json(ws, 'parameterValues', WAIT_S)
            assert answer is not None and answer.get('id') == request_id, answer
            return {p['name']: p.get('value') for p in answer['parameters']}[name]

        key = '/rm_robot.shooter.max_hz'
        before = parameter(key, 'get')
        assert parameter(key, 'set', 7.0) == 7.0  # a live key: the node took it
        assert parameter(key, 'bad', -1.0) == 7.0  # out of bounds: refused, unchanged
        assert parameter(key, 'no type', {'a': 1}) == 7.0  # no parameter holds it: unchanged
        # JSON's 8 for a double: the double 8.0 (rclpy refused an integer for a double)
        gain = '/can_bridge.joints.yaw.position_pid.kp'
        assert parameter(gain, 'whole', 8) == 8.0
        slots = '/rm_robot.shooter.slots'
        start = parameter(slots, 'slots')
        assert parameter(slots, 'set slots', start + 1) == start  # read at start-up: refused
        assert before != 7.0
