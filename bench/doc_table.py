"""The latest table of README.md and docs/PERFORMANCE.md, written by `make bench`.

Each page holds the table between two marker comments; a full run (every measurement, the
runs it was asked for, not --quick) replaces what is between them with its own target
table and one line saying when, where and on which commit it was measured. The page is
reference: it shows the latest run only, and git keeps the ones before.
"""

from __future__ import annotations

from pathlib import Path

#: the pages that show the latest table (README's Performance and the reference page)
PAGES = ('README.md', 'docs/PERFORMANCE.md')
BEGIN = '<!-- make bench writes the table below -->'
END = '<!-- end of the table make bench writes -->'


class MarkersMissingError(ValueError):
    """The page has not both markers, in order."""


def replace_table(page: str, table: str, caption: str) -> str:
    """page with what lies between the markers replaced by caption and table.

    Raises:
        MarkersMissingError: a marker missing, or END before BEGIN.
    """
    start, end = page.find(BEGIN), page.find(END)
    if start < 0 or end < 0 or end < start:
        raise MarkersMissingError(
            f'the page needs the lines {BEGIN!r} and then {END!r} around its table'
        )
    body = f'\n\n{caption}\n\n{table.strip()}\n\n'
    return page[: start + len(BEGIN)] + body + page[end:]


def write_table(path: Path, table: str, caption: str) -> None:
    """Replace the table of the page at path (see :func:`replace_table`)."""
    path.write_text(replace_table(path.read_text(encoding='utf-8'), table, caption),
                    encoding='utf-8')
