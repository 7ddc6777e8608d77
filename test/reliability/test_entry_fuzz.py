"""The referee and image-link decoders and every command entry, against arbitrary input.

test_decoder_fuzz.py does the motors', the IMU's and the DR16's decoders. Here the rule is
the same for the rest of what comes from outside: any input is either taken, with every
value it yields finite and inside its limit, or refused with the entry's own error (a
``ProtocolError`` for bytes, an ``InputRejectedError`` for a command); nothing else may
escape, since anything else would be a traceback in the loop instead of one counted
rejection.
"""

import math
from types import SimpleNamespace

from geometry_msgs.msg import Twist
from hypothesis import given, settings
from hypothesis import strategies as st
from rm_base.bridge.commands import parse_actuator_cmd
from rm_base.bridge.errors import ActuatorCmdRejectedError
from rm_base.errors import InputRejectedError
from rm_base.hardware.errors import ProtocolError
from rm_base.hardware.protocols import referee as ref
from rm_base.hardware.protocols.referee.status import LAYOUTS
from rm_base.joints import check_target
from rm_plugins.chassis import parse_chassis_cmd, parse_vel_cmd
from rm_plugins.chassis.commands import MAX_MOVE
from rm_plugins.gpio.pins import PinKind, PinSpec, check_command
from rm_plugins.shooter.command import parse_shoot_cmd

from rm_msgs.msg import ShootCmd

FUZZ = settings(max_examples=200, deadline=None)
numbers = st.floats(allow_nan=True, allow_infinity=True) | st.integers(-2**63, 2**63 - 1)
small_ints = st.integers(-300, 300)


def finite(*values):
    return all(math.isfinite(v) for v in values)


# --- bytes -----------------------------------------------------------------------------------

@FUZZ
@given(st.lists(st.binary(max_size=64), max_size=20), st.booleans())
def test_any_bytes_in_any_split_into_the_referee_parser_never_raise(chunks, image_link):
    parser = ref.FrameParser(image_link=image_link)
    for chunk in chunks:
        for frame in parser.feed(chunk):
            assert isinstance(frame, ref.RawFrame)


KNOWN = sorted({(cmd_id, length) for layouts in LAYOUTS.values()
                for cmd_id, by_length in layouts.items() for length in by_length})


@FUZZ
@given(st.sampled_from(KNOWN), st.data(), st.sampled_from(list(ref.ProtocolVersion)))
def test_a_crc_valid_referee_frame_with_any_payload_decodes_or_is_counted(known, data, version):
    cmd_id, length = known
    payload = data.draw(st.binary(min_size=length, max_size=length))
    decoder = ref.StatusDecoder(version)
    raw = ref.decode_frame(ref.encode_frame(cmd_id, payload))
    record = decoder.decode(raw)  # never raises: a record, or None counted by kind
    counted = (sum(decoder.decoded.values()) + sum(decoder.wrong_length.values())
               + sum(decoder.ignored.values()) + sum(decoder.rejected.values()))
    assert counted == 1
    assert (record is None) == (sum(decoder.decoded.values()) == 0)


@FUZZ
@given(st.binary(min_size=17, max_size=17))
def test_any_image_link_remote_payload_decodes_in_range_or_is_a_protocol_error(payload):
    try:
        frame = ref.decode_remote_payload(payload)
    except ProtocolError:
        return
    sticks = (frame.right_x, frame.right_y, frame.left_x, frame.left_y, frame.dial)
    assert all(abs(v) <= 660 for v in sticks), sticks


# --- commands --------------------------------------------------------------------------------

@FUZZ
@given(small_ints, st.sampled_from(['', 'base_link', 'odom', 'gimbal', '\0']), small_ints,
       st.lists(numbers, min_size=7, max_size=7), st.integers(0, 2**32 - 1))
def test_any_chassis_cmd_is_taken_within_limits_or_refused(mode, source, gear, values, move_id):
    msg = SimpleNamespace(
        mode=mode, follow_source=source, speed_gear=gear,
        accel=SimpleNamespace(linear=SimpleNamespace(x=values[0], y=values[1]),
                              angular=SimpleNamespace(z=values[2])),
        power_limit=values[3], move_x=values[4], move_y=values[5], move_yaw=values[6],
        move_id=move_id,
    )
    try:
        request = parse_chassis_cmd(msg)
    except InputRejectedError:
        return
    assert request.mode == mode and request.gear == gear
    assert all(a is None or (finite(a) and a > 0) for a in request.accel)
    assert request.power_limit is None or (finite(request.power_limit) and request.power_limit > 0)
    assert all(finite(m) and abs(m) <= limit for m, limit in zip(request.move, MAX_MOVE,
                                                                  strict=True))


@FUZZ
@given(st.lists(st.floats(allow_nan=True, allow_infinity=True), min_size=6, max_size=6))
def test_any_twist_is_taken_finite_or_refused(values):
    twist = Twist()
    (twist.linear.x, twist.linear.y, twist.linear.z,
     twist.angular.x, twist.angular.y, twist.angular.z) = values
    try:
        vx, vy, wz = parse_vel_cmd(twist)
    except InputRejectedError:
        return
    assert finite(vx, vy, wz)


@FUZZ
@given(small_ints, numbers, numbers, st.integers(0, 2**31), st.integers(0, 2**32 - 1))
def test_any_shoot_cmd_is_taken_finite_or_refused(mode, speed, hz, num, burst_id):
    msg = SimpleNamespace(mode=mode, speed=speed, hz=hz, num=num, burst_id=burst_id)
    try:
        command = parse_shoot_cmd(msg)
    except InputRejectedError:
        return
    assert finite(command.speed, command.hz) and command.speed >= 0 and command.hz >= 0
    assert command.mode in (ShootCmd.PASSIVE, ShootCmd.READY, ShootCmd.PUSH)


PINS = {
    'laser': PinSpec('laser', PinKind.OUTPUT),
    'servo': PinSpec('servo', PinKind.PWM),
    'switch': PinSpec('switch', PinKind.INPUT),
}


@FUZZ
@given(st.lists(st.sampled_from([*PINS, 'x', '']), max_size=5),
       st.lists(st.floats(allow_nan=True, allow_infinity=True), max_size=5))
def test_any_gpio_cmd_is_applied_within_range_or_refused_whole(names, values):
    try:
        writes = check_command(PINS, names, values)
    except InputRejectedError:
        return
    for name, value in writes.items():
        assert PINS[name].kind is not PinKind.INPUT
        assert finite(value) and 0.0 <= value <= 1.0
        assert PINS[name].kind is not PinKind.OUTPUT or value in (0.0, 1.0)


@FUZZ
@given(small_ints, st.lists(numbers, min_size=5, max_size=5))
def test_any_joint_target_is_taken_finite_or_refused(mode, values):
    position, velocity, effort, kp, kd = values
    try:
        target = check_target(mode, position=position, velocity=velocity, effort=effort,
                              kp=kp, kd=kd)
    except InputRejectedError:
        return
    assert finite(target.position, target.velocity, target.effort, target.kp, target.kd)
    assert target.kp >= 0.0 and target.kd >= 0.0


@FUZZ
@given(st.lists(st.sampled_from(['wheel', 'yaw', 'nope']), max_size=4), st.data())
def test_any_actuator_cmd_is_taken_whole_and_finite_or_refused_whole(names, data):
    def column(elements):
        return data.draw(st.lists(elements, min_size=len(names), max_size=len(names) + 1))

    msg = SimpleNamespace(name=names, mode=column(small_ints), position=column(numbers),
                          velocity=column(numbers), effort=column(numbers), kp=column(numbers),
                          kd=column(numbers))
    try:
        targets = parse_actuator_cmd(msg, {'wheel', 'yaw'})
    except ActuatorCmdRejectedError:
        return
    assert [name for name, _ in targets] == names
    for _, t in targets:
        assert finite(t.position, t.velocity, t.effort, t.kp, t.kd)
