"""Every command block of README runs in a user-path test: an untested example is a defect.

Each README section with a bash block must be read by a test of test/e2e through
``readme_blocks('<section>')`` (which runs README's own text, never a copy), except the
two commands of "Two commands": ``make test`` is what CI runs (.ci/run) and ``make run``
with ``source scripts/env.sh`` start every user session (support/user_session.py); and
"The kernel's CAN"'s ``make test-kernel``, which ``make test`` itself runs where it can.
"""

import pathlib
import re

from support.user_session import ROOT, readme_blocks

E2E = pathlib.Path(__file__).resolve().parent


def sections_with_blocks() -> list[str]:
    text = (ROOT / 'README.md').read_text(encoding='utf-8')
    names = re.findall(r'^## (.+)$', text, flags=re.M)
    return [name for name in names if readme_blocks(name)]


def test_every_readme_block_is_run_by_a_user_path_test():
    claimed = set()
    for path in E2E.glob('test_*.py'):
        source = path.read_text(encoding='utf-8')
        claimed |= set(re.findall(r"readme_blocks\((?:'([^']+)'|SECTION)\)", source))
        claimed |= set(re.findall(r"^SECTION = '([^']+)'", source, flags=re.M))
    run_by_make_test = ('Two commands', "The kernel's CAN")
    missing = [s for s in sections_with_blocks() if s not in claimed and s not in run_by_make_test]
    assert not missing, f'README sections whose commands no test runs: {missing}'


def test_the_two_commands_are_what_ci_and_every_session_run():
    (block, env) = readme_blocks('Two commands')
    assert 'make run' in block and 'make test' in block
    assert 'make test' in (ROOT / '.ci' / 'run').read_text()
    session = (E2E.parent / 'support' / 'user_session.py').read_text()
    assert "['make', '-s', 'run']" in session and env.split('#')[0].strip() in session


def test_make_test_kernel_is_what_make_test_runs():
    (block,) = readme_blocks("The kernel's CAN")
    assert block.split('#')[0].strip() == 'make test-kernel'
    runner = (ROOT / 'scripts' / 'run_tests.sh').read_text()
    assert 'make --no-print-directory test-kernel' in runner
