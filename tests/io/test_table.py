"""The table reader's one-pass conversion of plain tables agrees with its line-by-line reading.

A plain table (every line after the header a data row with as many cells as the header) is
converted to numbers without splitting it into lines (:meth:`Table._plain_numbers`). The
reference is the general, line-by-line reading of the same text (``Table._general_numbers``,
which names the bad line of a bad file): for every text below both must give the same
floats, bit for bit, or the same one-line error, and the line numbers and comments must be
those of the lines as written.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from profileopt.errors import InputError
from profileopt.io.table import read_table

PLAIN = [
    "s,z\n0,0.5\n0.5,-1e-3\n1.0,2\n",
    "s,z\n0,0.5\n0.5,-1e-3\n1.0,2",  # no final newline
    "# a comment\n\ns,z\n 0 , 0.5\n0.5,\t-1e-3 \n",  # white space around cells and lines
    "s,z,speed_limit\n0,1_0,3\n1,+.5,4.\n",  # what Python's float() reads (underscores, signs)
    "s,z\n0,1e308\n1,-0.0\n",
]
NOT_PLAIN = [
    "s,z\n0,0.5\n\n1.0,2\n",  # a blank line
    "s,z\n\n0,0.5\n1.0,2\n",  # a blank line first
    "s,z\n0,0.5\n   \n1.0,2\n",  # a line of white space
    "s,z\n0,0.5\n# note\n1.0,2\n",  # a comment after the header
    "s,z\n0,0.5\n  # note\n1.0,2\n",  # an indented comment
]
BAD = [
    ("s,z\n0,0.5\n1,2,3\n2\n", "line 3: 3 cells but the header has 2"),  # misaligned, total matches
    ("s,z\n0,0.5\n1,abc\n", "line 3: z = 'abc' is not a number"),
    ("s,z\n0,0.5\n1,\n", "line 3: z = '' is not a number"),
    ("s,z\n0,nan\n1,2\n", "line 2: z = nan is not a finite number"),
    ("s,z\n0,0x10\n1,2\n", "line 2: z = '0x10' is not a number"),
    ("s,z\n0,0.5 # note\n1,2\n", "line 2: z = '0.5 # note' is not a number"),  # no comments after a cell
    ("# c\ns,z\n0,1\n\n1,inf\n", "line 5: z = inf is not a finite number"),
]


def _table(tmp_path: Path, text: str):
    path = tmp_path / "t.csv"
    path.write_text(text)
    return read_table(path, "route file", header_example="'s,z'", empty_fix="write one")


def _lines_as_written(text: str) -> tuple[list[int], list[tuple[int, str]]]:
    """Data line numbers and comments, counted by hand from the text (the reference)."""
    lines = [line.strip() for line in text.split("\n")]
    header = next(i for i, line in enumerate(lines) if line and not line.startswith("#"))
    data = [i + 1 for i, line in enumerate(lines) if i > header and line and not line.startswith("#")]
    comments = [(i + 1, line) for i, line in enumerate(lines) if line.startswith("#")]
    return data, comments


@pytest.mark.parametrize("text", PLAIN + NOT_PLAIN)
def test_numbers_line_numbers_and_comments_match_the_line_by_line_reading(tmp_path: Path, text: str) -> None:
    table = _table(tmp_path, text)
    width = len(table.header)
    reference = _table(tmp_path, text)._general_numbers(range(width))
    values = table.numbers(range(width))
    assert np.array_equal(values.view(np.int64), reference.view(np.int64))
    data, comments = _lines_as_written(text)
    assert table.line_numbers.tolist() == data
    assert table.row_count == len(data) == len(values)
    assert list(table.comments) == comments


@pytest.mark.parametrize("text", PLAIN)
def test_a_plain_table_is_converted_without_splitting_its_lines(tmp_path: Path, text: str) -> None:
    table = _table(tmp_path, text)
    assert table._plain_rows is not None
    table.numbers(range(len(table.header)))
    table.line_numbers, table.comments, table.row_count
    assert "_lines" not in vars(table)  # the line-by-line split was never made


@pytest.mark.parametrize("text", NOT_PLAIN)
def test_a_table_with_blank_or_comment_lines_is_not_plain(tmp_path: Path, text: str) -> None:
    assert _table(tmp_path, text)._plain_rows is None


@pytest.mark.parametrize(("text", "message"), BAD)
def test_a_bad_cell_is_named_by_its_line(tmp_path: Path, text: str, message: str) -> None:
    with pytest.raises(InputError, match=message):
        _table(tmp_path, text).numbers(range(2))
