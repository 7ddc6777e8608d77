"""Linters run as tests: ruff (pyflakes, pycodestyle, isort, pydocstyle/Google, ...)."""

import pathlib
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent


def test_ruff_finds_no_problems():
    result = subprocess.run(
        [sys.executable, '-m', 'ruff', 'check', '--no-cache', '--output-format', 'concise', '.'],
        cwd=ROOT, capture_output=True, text=True, check=False,
    )
    assert result.returncode == 0, result.stdout + result.stderr


MODULE_LINES = 400  # the habit (docs/DEVELOPING.md); a longer module says why at its top


def test_every_long_module_says_why_it_is_one_module():
    tracked = subprocess.run(
        ['git', 'ls-files', '*.py'], cwd=ROOT, capture_output=True, text=True, check=True
    ).stdout.split()
    unexplained = []
    for name in tracked:
        text = (ROOT / name).read_text(encoding='utf-8')
        head = text[:1500]
        if text.count('\n') > MODULE_LINES and 'Why one module:' not in head:
            unexplained.append(f'{name} ({text.count(chr(10))} lines)')
    assert not unexplained, (
        f'modules over {MODULE_LINES} lines without "Why one module:" in their docstring: '
        + ', '.join(unexplained)
    )
