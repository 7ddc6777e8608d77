"""`make bench` writes docs/PERFORMANCE.md's table between its markers, nothing else."""

import pathlib

import pytest

from bench.doc_table import BEGIN, END, PAGES, MarkersMissingError, replace_table, write_table

ROOT = pathlib.Path(__file__).resolve().parents[2]


def test_the_table_between_the_markers_is_replaced_and_the_rest_kept():
    page = f'# Performance\n\nmethod\n\n{BEGIN}\n\nold table\n\n{END}\n\nfindings\n'
    new = replace_table(page, '| a | b |\n|---|---|\n| 1 | 2 |\n', 'bench of today, abc1234')
    assert new.startswith('# Performance\n\nmethod\n\n' + BEGIN)
    assert 'old table' not in new and '| 1 | 2 |' in new and 'bench of today, abc1234' in new
    assert new.endswith(f'{END}\n\nfindings\n')
    assert replace_table(new, '| a | b |\n|---|---|\n| 1 | 2 |\n', 'bench of today, abc1234') \
        == new  # a second write of the same run changes nothing


@pytest.mark.parametrize('page', ['no markers', f'{END}\n{BEGIN}', f'{BEGIN} only'])
def test_a_page_without_its_markers_is_refused(page):
    with pytest.raises(MarkersMissingError, match='needs the lines'):
        replace_table(page, '| x |', 'caption')


@pytest.mark.parametrize('name', PAGES)
def test_each_page_make_bench_writes_has_its_markers(tmp_path, name):
    page = (ROOT / name).read_text()
    copy = tmp_path / 'page.md'
    copy.write_text(page)
    write_table(copy, '| t |\n|---|\n| 1 |', 'caption')
    assert copy.read_text().count(BEGIN) == 1 and '| 1 |' in copy.read_text()
