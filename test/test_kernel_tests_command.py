"""scripts/kernel_tests.sh (make test-kernel): the pytest command it hands the guest.

The guest itself is the kernel tier's (test/kernel); here a stand-in for
scripts/kernel_run.sh prints the command, so the host checks its words: exactly the
kernel tests, and the caller's arguments as they were given.
"""

import pathlib
import shlex
import shutil
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]


@pytest.fixture
def scripts(tmp_path):
    """A copy of kernel_tests.sh beside a kernel_run.sh that prints its command."""
    (tmp_path / 'scripts').mkdir()
    shutil.copy(ROOT / 'scripts' / 'kernel_tests.sh', tmp_path / 'scripts')
    run = tmp_path / 'scripts' / 'kernel_run.sh'
    run.write_text('#!/usr/bin/env bash\nprintf "%s" "$1"\n')
    run.chmod(0o755)
    return tmp_path / 'scripts' / 'kernel_tests.sh'


def guest_pytest_words(script: pathlib.Path, *args: str) -> list[str]:
    done = subprocess.run([str(script), *args], capture_output=True, text=True, timeout=30,
                          check=True)
    words = shlex.split(done.stdout)
    return words[words.index('pytest') + 1:]


def test_without_arguments_the_guest_runs_the_kernel_tests_only(scripts):
    # an empty word here once made pytest collect the repository root: the whole suite
    # in the guest, where most of it fails and the rest ran past the timeout
    words = guest_pytest_words(scripts)
    assert words[-1] == 'test/kernel'
    assert '' not in words


def test_the_callers_arguments_reach_the_guest_word_for_word(scripts):
    words = guest_pytest_words(scripts, '-k', 'candump and not link', '-x')
    assert words[-4:] == ['test/kernel', '-k', 'candump and not link', '-x']
