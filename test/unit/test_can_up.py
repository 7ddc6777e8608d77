"""scripts/can_up.sh: the commands that bring a robot's CAN interfaces up (--print).

On vcan, in the guest kernel, test/kernel runs it for real."""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest

SCRIPT = Path(__file__).resolve().parents[2] / 'scripts' / 'can_up.sh'


def can_up(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(['bash', str(SCRIPT), '--print', *args], capture_output=True,
                          text=True, timeout=30, check=False)


def test_a_controller_gets_its_bitrate_restart_and_queue_then_comes_up():
    done = can_up('--restart-ms', '50', 'can0', 'can1')
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines()[:4] == [
        '+ ip link set dev can0 down',
        '+ ip link set dev can0 type can bitrate 1000000 restart-ms 50',
        '+ ip link set dev can0 txqueuelen 1000',
        '+ ip link set dev can0 up',
    ]
    assert done.stdout.splitlines()[-1] == '+ ip link set dev can1 up'


def test_an_slcan_adapter_is_attached_with_slcands_bitrate_code():
    done = can_up('--slcan', '/dev/ttyACM0', '--bitrate', '500000', 'can0')
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines()[0] == '+ slcand -o -c -s6 /dev/ttyACM0 can0'


@pytest.mark.parametrize(('args', 'rc', 'says'), [
    ((), 2, 'name at least one interface'),
    (('--slcan', '/dev/ttyACM0', '--bitrate', '300000', 'can0'), 1, 'slcan has no bitrate'),
    (('--slcan', '/dev/ttyACM0', 'can0', 'can1'), 2, 'one interface name'),
    (('--bogus', 'can0'), 2, 'unknown option --bogus'),
])
def test_mistakes_are_one_line_and_do_nothing(args, rc, says):
    done = can_up(*args)
    assert done.returncode == rc and says in done.stderr
    assert '+ ip' not in done.stdout
