"""FrameTree: lookups through common ancestors, stamps, and the links it refuses."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from rm_base.errors import InputRejectedError
from rm_base.geometry.frame_tree import FrameLookupError, FrameTree
from rm_base.geometry.transforms import SE3


def robot_tree(yaw=0.3, pitch=-0.2, x=1.0, y=2.0, heading=0.5):
    """odom -> base_link -> yaw_link -> pitch_link -> {muzzle, camera}, as the robot has it."""
    tree = FrameTree()
    tree.set('odom', 'base_link', SE3.from_translation_rpy((x, y, 0.0), 0.0, 0.0, heading), 10)
    tree.set('base_link', 'yaw_link', SE3.from_translation_rpy((0.0, 0.0, 0.4), 0, 0, yaw), 20)
    tree.set('yaw_link', 'pitch_link', SE3.from_translation_rpy((0, 0, 0), 0, pitch, 0), 30)
    tree.set('pitch_link', 'muzzle', SE3.from_translation_rpy((0.2, 0, 0), 0, 0, 0), 0,
             static=True)
    tree.set('pitch_link', 'camera', SE3.from_translation_rpy((0.1, 0, 0.05), 0, 0, 0), 0,
             static=True)
    return tree


def test_the_muzzle_in_odom_is_the_chain_of_every_link():
    tree = robot_tree(yaw=0.3, pitch=0.0, x=1.0, y=2.0, heading=0.5)
    found = tree.lookup('odom', 'muzzle')
    # level barrel: 0.2 m along heading + yaw, 0.4 m up
    expected = (1.0 + 0.2 * math.cos(0.8), 2.0 + 0.2 * math.sin(0.8), 0.4)
    np.testing.assert_allclose(found.transform.translation, expected, atol=1e-12)
    assert found.transform.rpy[2] == pytest.approx(0.8)
    assert found.stamp_ns == 10  # the oldest dynamic link on the path


def test_between_siblings_the_path_goes_through_their_parent_only():
    tree = robot_tree()
    found = tree.lookup('camera', 'muzzle')
    np.testing.assert_allclose(found.transform.translation, (0.1, 0.0, -0.05), atol=1e-12)
    assert found.stamp_ns is None  # two static links: nothing ages


def test_a_lookup_and_its_reverse_are_inverses():
    tree = robot_tree()
    there = tree.lookup('odom', 'camera').transform
    back = tree.lookup('camera', 'odom').transform
    np.testing.assert_allclose((there @ back).matrix, np.eye(4), atol=1e-12)


def test_a_frame_in_itself_is_the_identity_even_if_unknown():
    assert np.array_equal(FrameTree().lookup('x', 'x').transform.matrix, np.eye(4))


@pytest.mark.parametrize(
    ('target', 'source', 'message'),
    [
        ('odom', 'turret', "unknown frame 'turret'"),
        ('map', 'base_link', "unknown frame 'map'"),
    ],
)
def test_unknown_frames_are_named(target, source, message):
    with pytest.raises(FrameLookupError, match=message):
        robot_tree().lookup(target, source)


def test_frames_of_two_trees_are_not_connected():
    tree = robot_tree()
    tree.set('map', 'landmark', SE3.identity(), 1)
    with pytest.raises(FrameLookupError, match="'odom' and 'landmark' are not connected"):
        tree.lookup('odom', 'landmark')


@pytest.mark.parametrize(
    ('parent', 'child', 'message'),
    [
        ('', 'base_link', 'must not be empty'),
        ('base_link', 'base_link', 'its own parent'),
        ('muzzle', 'odom', 'would close a loop'),
    ],
)
def test_links_that_break_the_tree_are_refused(parent, child, message):
    tree = robot_tree()
    with pytest.raises(InputRejectedError, match=message):
        tree.set(parent, child, SE3.identity(), 100)


def test_an_older_transform_does_not_replace_a_newer_one():
    tree = robot_tree(heading=0.5)
    assert tree.set('odom', 'base_link', SE3.identity(), 5) is False
    assert tree.lookup('odom', 'base_link').transform.rpy[2] == pytest.approx(0.5)
    assert tree.set('odom', 'base_link', SE3.identity(), 11) is True
    assert tree.lookup('odom', 'base_link').transform.rpy[2] == pytest.approx(0.0)


def test_a_leading_slash_names_the_same_frame():
    tree = robot_tree()
    np.testing.assert_allclose(
        tree.lookup('/odom', '/base_link').transform.matrix,
        tree.lookup('odom', 'base_link').transform.matrix,
    )
    assert {'odom', 'base_link', 'muzzle'} <= tree.frames()


angle = st.floats(-math.pi, math.pi)


@settings(max_examples=50, deadline=None)
@given(yaw=angle, pitch=st.floats(-1.0, 1.0), heading=angle)
def test_a_point_maps_through_the_tree_as_through_the_chain_by_hand(yaw, pitch, heading):
    tree = robot_tree(yaw=yaw, pitch=pitch, heading=heading)
    by_hand = (
        SE3.from_translation_rpy((1.0, 2.0, 0.0), 0, 0, heading)
        @ SE3.from_translation_rpy((0, 0, 0.4), 0, 0, yaw)
        @ SE3.from_translation_rpy((0, 0, 0), 0, pitch, 0)
        @ SE3.from_translation_rpy((0.1, 0, 0.05), 0, 0, 0)
    )
    point = (3.0, -1.0, 0.5)
    np.testing.assert_allclose(
        tree.lookup('odom', 'camera').transform.apply(point), by_hand.apply(point), atol=1e-9
    )
