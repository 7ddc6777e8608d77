"""Test sessions on one machine never share a ROS domain (support.ros.claim_domain_id)."""

import contextlib
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
        files = []
        for fd in os.listdir(fd_dir):
            # the starting interpreter opens and closes files of its own meanwhile
            with contextlib.suppress(FileNotFoundError):
                files.append(os.readlink(os.path.join(fd_dir, fd)))
        claim = os.path.join(ros._CLAIMS, f'{os.environ["ROS_DOMAIN_ID"]}.lock')
        assert claim in files
    finally:
        child.kill()
        child.communicate()


def test_a_pytest_xdist_worker_claims_a_domain_of_its_own_and_its_children_keep_it():
    mine = os.environ['ROS_DOMAIN_ID']
    owner = os.environ['RM_TEST_DOMAIN_OWNER']  # this process's: a worker's name, or ''
    inherited = {'RM_TEST_DOMAIN_ID': mine, 'RM_TEST_DOMAIN_OWNER': owner, 'ROS_DOMAIN_ID': mine}
    if owner:
        inherited['PYTEST_XDIST_WORKER'] = owner
    # a process this session starts keeps the session's domain
    assert ros.isolate_ros_environment(dict(inherited)) == int(mine)
    worker = {**inherited, 'PYTEST_XDIST_WORKER': owner + 'x'}  # a worker of this session
    try:
        other = ros.isolate_ros_environment(worker)
        assert other != int(mine)
        assert worker['ROS_DOMAIN_ID'] == worker['RM_TEST_DOMAIN_ID'] == str(other)
        # and a process the worker starts keeps the worker's
        child = dict(worker)
        assert ros.isolate_ros_environment(child) == other
    finally:
        ros._CLAIMED.pop().close()  # give the extra domain back
