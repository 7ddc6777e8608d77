import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from rm_base.errors import InputRejectedError
from rm_base.geometry import (
    Quaternion,
    normalize_quaternion,
    quaternion_from_rotation_matrix,
    quaternion_from_rpy,
    quaternion_from_yaw,
    quaternion_inverse,
    quaternion_multiply,
    rotation_matrix_from_quaternion,
    rotation_matrix_from_rpy,
    rpy_from_quaternion,
    yaw_from_quaternion,
)

SQRT_HALF = math.sqrt(0.5)


def test_when_default_quaternion_expect_identity_in_ros_order():
    assert tuple(Quaternion()) == (0.0, 0.0, 0.0, 1.0)


def test_when_yaw_quarter_turn_expect_z_w_half_angle():
    # q = (0, 0, sin(pi/4), cos(pi/4)) in (x, y, z, w) order
    assert quaternion_from_yaw(0.5 * math.pi) == pytest.approx((0.0, 0.0, SQRT_HALF, SQRT_HALF))


def test_when_yaw_quarter_turn_expect_x_axis_turned_to_y():
    # Positive yaw is counter-clockwise seen from above: x (forward) -> y (left)
    rotation = rotation_matrix_from_quaternion(quaternion_from_yaw(0.5 * math.pi))
    assert rotation @ [1.0, 0.0, 0.0] == pytest.approx([0.0, 1.0, 0.0])


def test_when_positive_pitch_expect_nose_down():
    # Right-hand rule about y (left): x (forward) turns towards -z
    rotation = rotation_matrix_from_rpy(0.0, 0.5 * math.pi, 0.0)
    assert rotation @ [1.0, 0.0, 0.0] == pytest.approx([0.0, 0.0, -1.0])


def test_when_positive_roll_expect_left_side_up():
    # Right-hand rule about x (forward): y (left) turns towards +z
    rotation = rotation_matrix_from_rpy(0.5 * math.pi, 0.0, 0.0)
    assert rotation @ [0.0, 1.0, 0.0] == pytest.approx([0.0, 0.0, 1.0])


def test_when_rpy_expect_fixed_axes_roll_then_pitch_then_yaw():
    # R = Rz(yaw) Ry(pitch) Rx(roll). roll = pitch = yaw = pi/2 applied to x:
    # Rx leaves x; Ry(pi/2) x -> -z; Rz(pi/2) leaves -z. So x -> -z.
    # And y: Rx(pi/2) y -> z; Ry(pi/2) z -> x; Rz(pi/2) x -> y. So y -> y.
    rotation = rotation_matrix_from_rpy(0.5 * math.pi, 0.5 * math.pi, 0.5 * math.pi)
    assert rotation @ [1.0, 0.0, 0.0] == pytest.approx([0.0, 0.0, -1.0], abs=1e-12)
    assert rotation @ [0.0, 1.0, 0.0] == pytest.approx([0.0, 1.0, 0.0], abs=1e-12)


def test_when_quaternion_has_yaw_expect_yaw_back():
    assert yaw_from_quaternion((0.0, 0.0, SQRT_HALF, SQRT_HALF)) == pytest.approx(0.5 * math.pi)


def test_when_quaternion_slightly_off_unit_expect_normalised():
    # float32 round-off from an IMU: |q|^2 = 1.0002, within tf2's 0.01
    q = normalize_quaternion((0.0, 0.0, 0.0, 1.0001))
    assert q == (0.0, 0.0, 0.0, 1.0)


@pytest.mark.parametrize(
    'q', [(0.0, 0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 2.0), (math.nan, 0.0, 0.0, 1.0), (0.0, 1.0)]
)
def test_when_quaternion_invalid_expect_rejected(q):
    with pytest.raises(InputRejectedError, match='quaternion'):
        normalize_quaternion(q)


def test_when_rpy_not_finite_expect_rejected():
    with pytest.raises(InputRejectedError, match='pitch'):
        quaternion_from_rpy(0.0, math.nan, 0.0)


def test_when_quaternions_multiplied_expect_yaws_add():
    # yaw pi/6 after yaw pi/3 is yaw pi/2
    product = quaternion_multiply(
        quaternion_from_yaw(math.pi / 6), quaternion_from_yaw(math.pi / 3)
    )
    assert yaw_from_quaternion(product) == pytest.approx(0.5 * math.pi)


def test_when_quaternion_times_inverse_expect_identity():
    q = quaternion_from_rpy(0.1, -0.2, 0.3)
    assert quaternion_multiply(q, quaternion_inverse(q)) == pytest.approx((0.0, 0.0, 0.0, 1.0))


def test_when_matrix_of_half_turn_about_x_expect_quaternion_x_axis():
    # 180° about x: q = (sin(pi/2), 0, 0, cos(pi/2)) = (1, 0, 0, 0); trace = -1 branch
    matrix = np.diag([1.0, -1.0, -1.0])
    assert quaternion_from_rotation_matrix(matrix) == pytest.approx((1.0, 0.0, 0.0, 0.0))


def test_when_matrix_is_reflection_expect_rejected():
    with pytest.raises(InputRejectedError, match='reflection'):
        quaternion_from_rotation_matrix(np.diag([1.0, 1.0, -1.0]))


def test_when_matrix_not_orthonormal_expect_rejected():
    with pytest.raises(InputRejectedError, match='orthonormal'):
        quaternion_from_rotation_matrix(np.diag([1.0, 2.0, 0.5]))


half_turn = st.floats(min_value=-math.pi, max_value=math.pi)
# Away from gimbal lock (pitch = ±pi/2), where roll and yaw are not separable.
pitch_away_from_lock = st.floats(min_value=-1.5, max_value=1.5)


@given(half_turn, pitch_away_from_lock, half_turn)
def test_when_rpy_round_trips_expect_same_rotation(roll, pitch, yaw):
    back = rpy_from_quaternion(quaternion_from_rpy(roll, pitch, yaw))
    # Compare rotations, not angles: roll = ±pi, yaw = ±pi are the same angle.
    assert rotation_matrix_from_rpy(*back) == pytest.approx(
        rotation_matrix_from_rpy(roll, pitch, yaw), abs=1e-9
    )
    assert back[1] == pytest.approx(pitch, abs=1e-9)


@given(half_turn, st.floats(min_value=-0.5 * math.pi, max_value=0.5 * math.pi), half_turn)
def test_when_matrix_round_trips_expect_same_quaternion_up_to_sign(roll, pitch, yaw):
    q = np.array(quaternion_from_rpy(roll, pitch, yaw))
    back = np.array(quaternion_from_rotation_matrix(rotation_matrix_from_quaternion(q)))
    # q and -q are the same rotation; the matrix route returns the one with w >= 0.
    assert back[3] >= 0.0
    assert np.allclose(back, q, atol=1e-9) or np.allclose(back, -q, atol=1e-9)
