import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from rm_base.errors import InputRejectedError
from rm_base.geometry import SE2, SE3, quaternion_from_yaw

coordinate = st.floats(min_value=-100.0, max_value=100.0)
angle = st.floats(min_value=-math.pi, max_value=math.pi)


def test_when_se2_applied_expect_rotate_then_translate():
    # Pose at (1, 2) heading +90°: the point 1 m ahead of it, (1, 0) in its frame, is
    # rotated to (0, 1) and moved to (1 + 0, 2 + 1) = (1, 3).
    transform = SE2.from_xy_yaw(1.0, 2.0, 0.5 * math.pi)
    assert transform.apply([1.0, 0.0]) == pytest.approx([1.0, 3.0])


def test_when_se2_applied_to_many_points_expect_one_row_each():
    transform = SE2.from_xy_yaw(1.0, 0.0, 0.0)
    # pure translation by +1 in x
    expected = np.array([[1.0, 0.0], [2.0, 1.0]])
    assert transform.apply([[0.0, 0.0], [1.0, 1.0]]) == pytest.approx(expected)


def test_when_se2_composed_expect_second_applied_in_first_frame():
    # T_a_b: b at (1, 0) heading +90° in a; T_b_c: c at (1, 0) in b, same heading.
    # c's origin in a: b's x axis points along a's y, so (1, 0) + (0, 1) = (1, 1);
    # heading 90° + 0 = 90°.
    t_a_c = SE2.from_xy_yaw(1.0, 0.0, 0.5 * math.pi) @ SE2.from_xy_yaw(1.0, 0.0, 0.0)
    assert t_a_c.to_xy_yaw() == pytest.approx((1.0, 1.0, 0.5 * math.pi))


def test_when_se2_inverted_expect_origin_back_to_origin():
    # Inverse of the pose (1, 2, 90°) maps the point (1, 2) in a back to b's origin.
    inverse = SE2.from_xy_yaw(1.0, 2.0, 0.5 * math.pi).inverse()
    assert inverse.apply([1.0, 2.0]) == pytest.approx([0.0, 0.0], abs=1e-12)


def test_when_se2_yaw_expect_wrapped():
    # 3pi/2 is reported as -pi/2
    assert SE2.from_xy_yaw(0.0, 0.0, 1.5 * math.pi).yaw == pytest.approx(-0.5 * math.pi)


def test_when_se2_matrix_not_rigid_expect_rejected():
    with pytest.raises(InputRejectedError, match='orthonormal'):
        SE2([[2.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])


def test_when_se2_last_row_wrong_expect_rejected():
    with pytest.raises(InputRejectedError, match='last row'):
        SE2([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 0.0, 1.0]])


def test_when_se2_value_nan_expect_rejected():
    with pytest.raises(InputRejectedError, match='finite'):
        SE2.from_xy_yaw(math.nan, 0.0, 0.0)


def test_when_se2_matrix_read_expect_read_only():
    with pytest.raises(ValueError, match='read-only'):
        SE2.identity().matrix[0, 2] = 1.0


def test_when_se2_built_from_array_expect_copy_not_view():
    source = np.eye(3)
    transform = SE2(source)
    source[0, 2] = 5.0
    assert transform.x == 0.0


def test_when_se3_from_translation_quaternion_expect_rotate_then_translate():
    # yaw +90° then translate (1, 2, 3): the point (1, 0, 0) -> (0, 1, 0) -> (1, 3, 3)
    transform = SE3.from_translation_quaternion([1.0, 2.0, 3.0], quaternion_from_yaw(0.5 * math.pi))
    assert transform.apply([1.0, 0.0, 0.0]) == pytest.approx([1.0, 3.0, 3.0])


def test_when_se3_from_rpy_expect_same_as_from_quaternion():
    # yaw 90° either way: q = (0, 0, sin 45°, cos 45°)
    half = math.sqrt(0.5)
    by_rpy = SE3.from_translation_rpy([1.0, 2.0, 3.0], 0.0, 0.0, 0.5 * math.pi)
    by_quaternion = SE3.from_translation_quaternion([1.0, 2.0, 3.0], (0.0, 0.0, half, half))
    assert by_rpy.matrix == pytest.approx(by_quaternion.matrix)


def test_when_se3_quaternion_read_back_expect_ros_order():
    # yaw 90°: (x, y, z, w) = (0, 0, sin 45°, cos 45°)
    transform = SE3.from_translation_rpy([0.0, 0.0, 0.0], 0.0, 0.0, 0.5 * math.pi)
    half = math.sqrt(0.5)
    assert transform.quaternion == pytest.approx((0.0, 0.0, half, half))


def test_when_se3_projected_to_se2_expect_x_y_yaw_kept():
    transform = SE3.from_translation_rpy([1.0, 2.0, 3.0], 0.1, -0.2, 0.3)
    assert transform.to_se2().to_xy_yaw() == pytest.approx((1.0, 2.0, 0.3))


def test_when_se2_lifted_to_se3_expect_same_planar_motion():
    planar = SE2.from_xy_yaw(1.0, 2.0, 0.5 * math.pi)
    # (1, 0) -> (1, 3) as in 2-D; z stays 0
    assert SE3.from_se2(planar).apply([1.0, 0.0, 0.0]) == pytest.approx([1.0, 3.0, 0.0])


def test_when_se3_quaternion_far_from_unit_expect_rejected():
    with pytest.raises(InputRejectedError, match='unit'):
        SE3.from_translation_quaternion([0.0, 0.0, 0.0], (0.0, 0.0, 1.0, 1.0))


def test_when_se3_translation_wrong_size_expect_rejected():
    with pytest.raises(InputRejectedError, match='translation'):
        SE3.from_translation_rpy([0.0, 0.0], 0.0, 0.0, 0.0)


def test_when_points_wrong_shape_expect_rejected():
    with pytest.raises(InputRejectedError, match='shape'):
        SE3.identity().apply([1.0, 2.0])


@given(coordinate, coordinate, angle, coordinate, coordinate, angle)
def test_when_se2_composed_with_inverse_expect_identity(x, y, yaw, px, py, _):
    transform = SE2.from_xy_yaw(x, y, yaw)
    assert (transform @ transform.inverse()).matrix == pytest.approx(np.eye(3), abs=1e-9)
    assert (transform.inverse() @ transform).matrix == pytest.approx(np.eye(3), abs=1e-9)
    assert transform.inverse().apply(transform.apply([px, py])) == pytest.approx([px, py], abs=1e-9)


@given(
    st.tuples(coordinate, coordinate, coordinate),
    angle,
    st.floats(min_value=-0.5 * math.pi, max_value=0.5 * math.pi),
    angle,
)
def test_when_se3_composed_with_inverse_expect_identity(translation, roll, pitch, yaw):
    transform = SE3.from_translation_rpy(translation, roll, pitch, yaw)
    assert (transform @ transform.inverse()).matrix == pytest.approx(np.eye(4), abs=1e-9)
    assert (transform.inverse() @ transform).matrix == pytest.approx(np.eye(4), abs=1e-9)


@given(coordinate, coordinate, angle, coordinate, coordinate, angle)
def test_when_se2_composed_expect_same_as_applying_in_turn(x1, y1, yaw1, x2, y2, yaw2):
    first = SE2.from_xy_yaw(x1, y1, yaw1)
    second = SE2.from_xy_yaw(x2, y2, yaw2)
    point = [0.3, -0.7]
    assert (first @ second).apply(point) == pytest.approx(
        first.apply(second.apply(point)), abs=1e-9
    )
