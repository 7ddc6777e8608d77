"""docs/PARAMETERS.md is what the code declares (rm_bringup.param_reference)."""

import pathlib

import pytest
from rm_bringup.param_reference import collect, other_robots, render

pytestmark = [pytest.mark.ros, pytest.mark.realtime]

ROOT = pathlib.Path(__file__).resolve().parents[2]


def test_the_committed_parameter_reference_is_current():
    declared = collect()
    keys = {p.key for p in declared['rm_robot']}
    # the host's own keys and every plugin of the standard robot, required ones marked
    assert {'plugins', 'loop_rate', 'chassis.wheel_radius', 'gimbal.yaw_joint'} <= keys
    assert any(p.default is None for p in declared['rm_robot'])
    assert 'scheduler.rate_hz' in {p.key for p in declared['can_bridge']}
    others = other_robots(declared)
    assert 'chassis.steer_joints' in {p.key for p in others['swerve']}
    committed = (ROOT / 'docs' / 'PARAMETERS.md').read_text()
    assert render(declared, others) == committed, (
        'docs/PARAMETERS.md is stale: python -m rm_bringup.param_reference > docs/PARAMETERS.md'
    )
