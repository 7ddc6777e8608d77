"""scripts/run_tests.sh (make test): each selected test in exactly one of its two passes."""

import os
import pathlib
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
KINDS = 'test/fixtures/two_passes/test_kinds.py'
PASS_2 = '[test] pass 2 of 2'


def _collect(*args):
    """(exit code, node names pass 1 collected, node names pass 2 collected)."""
    command = [str(ROOT / 'scripts' / 'run_tests.sh'), '--co', '-q', '-p', 'no:cacheprovider']
    done = subprocess.run(
        [*command, KINDS, *args],
        cwd=ROOT,
        env={**os.environ, 'TEST_WORKERS': '0'},
        capture_output=True,
        text=True,
        timeout=120,
        check=False,  # the exit code is one of the results
    )
    first, _, second = done.stdout.partition(PASS_2)
    assert second, done.stdout + done.stderr

    def names(text):
        return {line.split('::')[1] for line in text.splitlines() if '::' in line}

    return done.returncode, names(first), names(second)


@pytest.mark.parametrize(
    ('args', 'first', 'second'),
    [
        ((), {'test_plain', 'test_plain_slow'}, {'test_realtime', 'test_realtime_slow'}),
        # the caller's marker expression narrows both passes, in each spelling; a pass
        # left empty by the selection is no error
        (('-m', 'slow', '-k', 'plain'), {'test_plain_slow'}, set()),
        (('-mnot slow',), {'test_plain'}, {'test_realtime'}),
        (('--markexpr=slow', '-k', 'realtime'), set(), {'test_realtime_slow'}),
    ],
)
def test_each_test_is_in_one_pass_the_realtime_ones_in_the_second(args, first, second):
    code, collected_first, collected_second = _collect(*args)
    assert (collected_first, collected_second) == (first, second)
    assert code == 0


def test_a_selection_of_nothing_is_pytests_no_tests_exit():
    code, first, second = _collect('-k', 'no_such_test')
    assert (first, second) == (set(), set())
    assert code == 5
