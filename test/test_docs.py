"""The repo explains itself: every document a file cites is in the repo."""

import pathlib
import re
import subprocess

ROOT = pathlib.Path(__file__).resolve().parents[1]
# an upper-case Markdown file name, with docs/ or ../ before it or not
_CITED = re.compile(r'(?<![\w.])((?:\.\./|docs/)*[A-Z][A-Z_]+\.md)\b')
# the notes kept outside the repo (built here, so that this file does not name it itself)
_OUTSIDE = '/'.join(('..', 'shared'))
_TEXT = ('.py', '.md', '.yaml', '.yml', '.sh', '.toml', '.ini', '.txt', '.xml', '.launch.py')


def _tracked_text_files():
    names = subprocess.run(
        ['git', 'ls-files'], cwd=ROOT, capture_output=True, text=True, check=True
    ).stdout.split()
    return [ROOT / n for n in names if n.endswith(_TEXT) or n in ('Makefile', '.ci/run')]


def test_every_cited_document_is_in_the_repo():
    missing = []
    for path in _tracked_text_files():
        text = path.read_text(encoding='utf-8', errors='replace')
        for cited in set(_CITED.findall(text)):
            name = cited.split('/')[-1]
            here = (path.parent / cited).resolve()
            if not (here.exists() or (ROOT / 'docs' / name).exists() or (ROOT / name).exists()):
                missing.append(f'{path.relative_to(ROOT)}: {cited}')
    assert not missing, 'documents cited but not in the repo:\n' + '\n'.join(sorted(missing))


def test_nothing_points_outside_the_repo():
    outside = [
        str(path.relative_to(ROOT))
        for path in _tracked_text_files()
        if _OUTSIDE in path.read_text(encoding='utf-8', errors='replace')
    ]
    assert not outside, f'files that refer to {_OUTSIDE}: {outside}'
