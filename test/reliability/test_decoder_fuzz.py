"""Every byte decoder against arbitrary, truncated and corrupted input (hypothesis).

The rule for each decoder: any input either decodes to finite values inside the field's
physical range, or raises a ``ProtocolError`` (the hardware layer counts those and drops
the frame); nothing else may escape, because anything else would count as a bug in the
receive thread and a NaN would travel up to a plugin. The HiPNUC stream parser must never
raise at all, must find exactly the complete frames of a truncated stream, and — through
the IMU plugin's conversion — a frame with a valid CRC but NaN/inf floats must be
rejected, never published.

Vectors and round trips of each protocol are in test/unit/hardware/test_protocols_*.py;
garbage into HipnucParser.feed is test_protocols_hipnuc.py::test_parser_never_raises_on_garbage.
"""

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from rm_base.errors import InputRejectedError
from rm_base.hardware.errors import ProtocolError
from rm_base.hardware.protocols import dbus, hipnuc, mit
from rm_base.motors.cheetah import protocol as cheetah
from rm_base.motors.damiao import protocol as damiao
from rm_base.motors.dji import protocol as dji
from rm_base.motors.piper import protocol as piper
from rm_plugins.imu.conversion import Mounting, reading_from_sample

DM4310 = damiao.dm_limits('DM4310')
frames = st.binary(min_size=0, max_size=20)
FUZZ = settings(max_examples=200, deadline=None)  # per decoder: ~0.1-0.5 s
STREAMS = settings(max_examples=60, deadline=None)  # frames of ~80 bytes: slower


def finite(*values):
    return all(math.isfinite(v) for v in values)


def within(value, limit):
    # decoded MIT fields may sit a rounding step outside the nominal range
    return abs(value) <= limit * (1 + 1e-6)


def _dji(data):
    fb = dji.decode_feedback(data)
    assert 0 <= fb.angle_ticks < dji.ENCODER_TICKS_PER_REV
    assert -(2**15) <= fb.rotor_rpm < 2**15 and -(2**15) <= fb.current_raw < 2**15
    assert 0 <= fb.temperature_c <= 255


def _dji_command(data):
    assert all(-(2**15) <= raw < 2**15 for raw in dji.unpack_command(data))


def _damiao(data):
    fb = damiao.decode_feedback(data, DM4310)
    assert finite(fb.position, fb.velocity, fb.torque)
    assert within(fb.position, DM4310.p_max) and within(fb.velocity, DM4310.v_max)
    assert within(fb.torque, DM4310.t_max)


def _cheetah(data):
    reply = cheetah.decode_reply(data)
    limits = cheetah.CHEETAH_DEFAULT_LIMITS
    assert finite(reply.position, reply.velocity, reply.torque)
    assert within(reply.position, limits.p_max) and within(reply.torque, limits.t_max)


def _mit_command(data):
    if mit.parse_system_frame(data) is not None:
        return
    cmd = mit.unpack_mit_command(data, DM4310)
    assert finite(*cmd)
    assert cmd.kp >= 0.0 and cmd.kd >= 0.0 and within(cmd.torque, DM4310.t_max)


def _damiao_modes(data):
    for decode in (damiao.unpack_pos_vel, damiao.unpack_vel, damiao.unpack_pos_force):
        try:
            values = decode(data)
        except ProtocolError:
            continue
        values = values if isinstance(values, tuple) else (values,)
        # float32 fields may carry NaN/inf: the motor side (simulator) must reject them
        assert all(isinstance(v, float) for v in values)


def _piper(data):
    for can_id in (0x2A5, 0x2A6, 0x2A7, 0x251, 0x256, 0x15A, 0x123):
        for decode in (piper.decode_joint_feedback, piper.decode_high_speed_feedback):
            try:
                values = decode(can_id, data)
            except ProtocolError:
                continue
            assert finite(*(v for v in values if isinstance(v, float)))
        try:
            cmd = piper.unpack_joint_mit(can_id, data)
        except ProtocolError:
            continue
        assert finite(*(v for v in cmd if isinstance(v, float)))


def _dbus(data):
    frame = dbus.decode(data)
    assert all(abs(c) <= 660 for c in (*frame.channels, frame.wheel))


def _hipnuc_frame(data):
    sample = hipnuc.decode_payload(hipnuc.decode_frame(data))
    assert isinstance(sample, hipnuc.ImuSample)


DECODERS = {
    'dji feedback': _dji,
    'dji command': _dji_command,
    'damiao feedback': _damiao,
    'damiao pos/vel/force': _damiao_modes,
    'cheetah reply': _cheetah,
    'mit command': _mit_command,
    'piper': _piper,
    'dbus': _dbus,
    'hipnuc frame': _hipnuc_frame,
}


@pytest.mark.parametrize('name', list(DECODERS))
def test_any_bytes_decode_to_values_in_range_or_a_protocol_error(name):
    decode = DECODERS[name]

    @FUZZ
    @given(
        st.one_of(frames, st.binary(min_size=8, max_size=8), st.binary(min_size=18, max_size=18))
    )
    def run(data):
        try:
            decode(data)
        except ProtocolError:
            pass

    run()


# --- HiPNUC streams -------------------------------------------------------------------------

VEC = st.tuples(*[st.floats(-1e3, 1e3, allow_nan=False)] * 3)


def imusol_frame(acc, gyr, t_ms):
    payload = hipnuc.encode_imusol(
        acc=acc,
        gyr=gyr,
        mag=(0.0, 0.0, 0.0),
        euler=(0.0, 0.0, 0.0),
        quat=(1.0, 0.0, 0.0, 0.0),
        temperature=25,
        pressure=101325.0,
        system_time_ms=t_ms,
    )
    return hipnuc.encode_frame(payload)


streams = st.lists(st.tuples(VEC, VEC), min_size=1, max_size=8).map(
    lambda items: [imusol_frame(a, g, i) for i, (a, g) in enumerate(items)]
)


@STREAMS
@given(streams, st.data())
def test_a_truncated_stream_yields_exactly_its_complete_frames_in_order(frames_, data):
    stream = b''.join(frames_)
    cut = data.draw(st.integers(0, len(stream)))
    chunks = data.draw(st.lists(st.integers(1, 64), max_size=10))
    parser = hipnuc.HipnucParser()
    got, pos = [], 0
    for size in [*chunks, len(stream)]:
        got += parser.feed(stream[pos : min(pos + size, cut)])
        pos = min(pos + size, cut)
    complete = 0
    total = 0
    for frame in frames_:
        total += len(frame)
        complete += total <= cut
    assert [s.system_time_ms for s in got] == list(range(complete))
    assert parser.crc_errors == 0


@settings(max_examples=100, deadline=None, derandomize=True)
@given(streams, st.integers(0, 10_000), st.binary(min_size=1, max_size=2))
def test_a_corrupted_stream_yields_only_intact_frames(frames_, where, burst):
    # One burst of up to 16 bits: CRC-16 detects every such error in a frame, so what comes
    # out must be frames exactly as sent (derandomized: a CRC collision after a corrupted
    # length, ~2**-16 per frame, would fail the same way every run, not now and then).
    originals = {s.system_time_ms: s for s in hipnuc.HipnucParser().feed(b''.join(frames_))}
    stream = bytearray(b''.join(frames_))
    at = where % len(stream)
    stream[at : at + len(burst)] = burst
    parser = hipnuc.HipnucParser()
    got = parser.feed(bytes(stream))
    assert len(got) <= len(frames_)
    for sample in got:
        assert sample == originals.get(sample.system_time_ms), sample


@STREAMS
@given(st.lists(st.floats(width=32), min_size=17, max_size=17), st.integers(0, 2**32 - 1))
def test_a_crc_valid_frame_with_any_floats_is_converted_or_rejected_never_nan(values, t_ms):
    # A 0x91 item packed by hand, so NaN and inf get in (the encoder refuses them):
    # tag, status, temperature, pressure, time, then acc, gyr, mag, euler, quat.
    payload = hipnuc._IMUSOL.pack(hipnuc.TAG_IMUSOL, 0, 25, values[0], t_ms, *values[1:])
    samples = hipnuc.HipnucParser().feed(hipnuc.encode_frame(payload))
    assert len(samples) == 1
    try:
        reading = reading_from_sample(samples[0], Mounting())
    except InputRejectedError:
        return
    for part in (reading.orientation, reading.angular_velocity, reading.linear_acceleration):
        assert part is None or finite(*part)
