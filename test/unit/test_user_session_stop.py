"""The e2e harness stops a typed script's whole process group, orphans included."""

import os
import signal
import subprocess
import time

from support.user_session import _signal_group, _stop


def _group_alive(pgid):
    try:
        os.killpg(pgid, 0)
    except ProcessLookupError:
        return False
    return True


def _typed(script):
    return subprocess.Popen(['bash', '-c', script], start_new_session=True)


def test_a_background_command_the_script_left_behind_is_stopped_with_it():
    # the script ends at once; its background job would run on, orphaned
    process = _typed('sleep 300 & echo started')
    process.wait(timeout=10)
    assert _group_alive(process.pid)
    _signal_group(process, signal.SIGTERM)
    _stop(process)
    assert not _group_alive(process.pid)


def test_a_command_that_will_not_end_is_killed_after_the_timeout():
    # ignores SIGTERM, as a process stuck in a teardown does
    process = _typed("trap '' TERM; sleep 300 & wait")
    time.sleep(0.3)
    _signal_group(process, signal.SIGTERM)
    started = time.monotonic()
    _stop(process, timeout_s=1.0)
    assert not _group_alive(process.pid)
    assert 1.0 <= time.monotonic() - started < 10.0
