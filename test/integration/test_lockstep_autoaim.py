"""Auto-aim on the standard robot in lockstep, at rm_sim's robot spinning at 2 rad/s.

The harness plays rm_auto_aim's tracker: it publishes the simulated target's truth on
/tracker/target at 100 Hz, stamped 10 ms old (a camera's and a detector's latency). The
AutoAim plugin aims the gimbal at the facing plate predicted over the latency and the
flight and fires one shot whenever the barrel is on it; rm_sim judges every projectile
against the spinning plates. rm_sim's projectiles fly without drag, so the robot's
solvers are told none. The plugins and the autoaim config are README's "Auto-aim".
"""

from __future__ import annotations

import math

import pytest
from auto_aim_interfaces.msg import Target
from support.lockstep import LockstepRobot
from support.user_session import readme_yaml

from rm_msgs.msg import GimbalCmd

pytestmark = [pytest.mark.ros]

README = readme_yaml('Auto-aim')['rm_robot']['ros__parameters']
NO_DRAG = {'gimbal.bullet_drag': 0.0, 'autoaim.bullet_drag': 0.0}


def robot(v_yaw: float) -> LockstepRobot:
    return LockstepRobot(plugins=README['plugins'], overrides={
        'rm_robot': {**NO_DRAG, **{f'autoaim.{k}': v for k, v in README['autoaim'].items()}},
        'can_bridge': {'sim.target.x': 4.0, 'sim.target.y': 0.5, 'sim.target.v_yaw': v_yaw,
                       'sim.target.z': 0.3},
    })


def track(r: LockstepRobot, age_s: float = 0.01) -> None:
    """Publish the target as a tracker would, age_s old."""
    def message() -> Target:
        truth = r.world.target.truth(r.world.time_ns - round(age_s * 1e9))
        msg = Target(tracking=True, id='3', armors_num=truth.armors_num, yaw=truth.yaw,
                     v_yaw=truth.v_yaw, radius_1=truth.radius_1, radius_2=truth.radius_2,
                     dz=truth.dz)
        msg.header.frame_id = 'odom'
        msg.position.x, msg.position.y = truth.center
        msg.position.z = truth.z
        msg.velocity.x, msg.velocity.y, msg.velocity.z = truth.velocity
        return msg

    r.publish('/tracker/target', message, rate_hz=100.0, age_s=age_s)


def test_a_target_spinning_at_2_rad_s_is_hit_on_its_plates():
    with robot(2.0) as r:
        track(r)
        r.run(10.0)  # from the start: friction wheels up, the gimbal on it, then fire
        # the barrel heat (100, 10 a shot, 10/s cooled) allows ~10 shots, then one a second
        target = r.world.target
        shots = target.shots
        hits = sum(target.hits.values())
        assert shots >= 12, shots
        assert hits >= 0.6 * shots, (hits, shots, dict(target.hits))
        assert len(target.hits) >= 3  # plate after plate as they come round


def test_a_spin_too_fast_to_follow_is_aimed_at_its_centre():
    with robot(8.0) as r:
        track(r)
        r.watch('/gimbal_state')
        r.run(2.0)
        assert r.plugin('autoaim').state.name == 'CENTRE'
        state = r.latest('/gimbal_state')
        assert state.yaw_target == pytest.approx(math.atan2(0.5, 4.0), abs=0.01)


def test_without_a_target_nothing_is_fired():
    with robot(2.0) as r:
        r.publish('/gimbal_cmd', GimbalCmd(mode=GimbalCmd.RATE), rate_hz=50.0)
        r.run(3.0)
        assert r.world.target.shots == 0
        assert r.plugin('autoaim').state.name == 'PASSIVE'
