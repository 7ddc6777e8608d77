"""Test sessions on one machine never share a ROS domain (support.ros.claim_domain_id)."""

import os
import sys

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


def test_a_child_holds_the_sessions_domain_claim():
    child = ros.start_process([sys.executable, '-c', 'import time; time.sleep(60)'])
    try:
        fd_dir = f'/proc/{child.pid}/fd'
        files = [os.readlink(os.path.join(fd_dir, fd)) for fd in os.listdir(fd_dir)]
        claim = os.path.join(ros._CLAIMS, f'{os.environ["ROS_DOMAIN_ID"]}.lock')
        assert claim in files
    finally:
        child.kill()
        child.communicate()
