"""Test sessions on one machine never share a ROS domain (support.ros.claim_domain_id)."""

import os

from support import ros


def test_a_domain_another_session_holds_is_not_claimed_again():
    mine = int(os.environ['ROS_DOMAIN_ID'])  # claimed by this session's conftest
    seed = mine - 1  # the seed whose first choice is this session's domain
    assert ros.pick_domain_id(seed) == mine
    other = ros.claim_domain_id(seed)
    try:
        assert other != mine and 1 <= other <= 102 and other != 42
    finally:
        ros._CLAIMED.pop().close()  # give the extra domain back
