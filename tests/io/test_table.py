"""The table reader: its one-pass conversion of plain tables agrees with its line-by-line
reading; only ASCII decimal notation is a number; lines end at one kind of line end.

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
from profileopt.io import read_route
from profileopt.io.table import decimal_number, is_decimal, read_table

PLAIN = [
    "s,z\n0,0.5\n0.5,-1e-3\n1.0,2\n",
    "s,z\n0,0.5\n0.5,-1e-3\n1.0,2",  # no final newline
    "# a comment\n\ns,z\n 0 , 0.5\n0.5,\t-1e-3 \n",  # white space around cells and lines
    "s,z,speed_limit\n0,+1e1,3\n1,+.5,4.\n",  # signs, a bare point, exponents
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


# ------------------------------------------------------------------ numbers (issue 30 item 8)

#: Cells Python's float() reads that are not ASCII decimal notation (before: read as 10, 1, 10),
#: and others that are not numbers either.
NOT_DECIMAL = ["1_0", "\u0661", "\uff11\uff10", "\u00bd", "2\u00b2", "\u0661.5", "0x10", "1e", "--1", "1.2.3", ""]
#: Cells in ASCII decimal notation and their values, written out by hand.
DECIMAL = [("0", 0.0), ("+.5", 0.5), ("5.", 5.0), ("-1.5E+3", -1500.0), (" 7\t", 7.0), ("1e-3", 0.001),
           ("-0", -0.0), ("12345.678", 12345.678)]


@pytest.mark.parametrize("cell", NOT_DECIMAL)
@pytest.mark.parametrize("shape", ["plain", "comment", "text column"])
def test_only_ascii_decimal_notation_is_a_number(tmp_path: Path, cell: str, shape: str) -> None:
    # plain: the one-pass conversion; comment: the line-by-line one; text column: column by column
    head = {"plain": "s,z\n", "comment": "s,z\n# a note\n", "text column": "s,z,name\n"}[shape]
    tail = ",x" if shape == "text column" else ""
    text = head + f"0,0{tail}\n1,{cell}{tail}\n2,0{tail}\n"
    line = 4 if shape == "comment" else 3
    with pytest.raises(InputError, match=rf"t\.csv: line {line}: z = '.*' is not a number;.*ASCII digits"):
        _table(tmp_path, text).numbers([0, 1])
    assert not is_decimal(cell) and decimal_number(cell) is None


@pytest.mark.parametrize(("cell", "value"), DECIMAL)
def test_ascii_decimal_numbers_are_read(tmp_path: Path, cell: str, value: float) -> None:
    for text in (f"s,z\n0,0\n1,{cell}\n", f"s,z\n# note\n0,0\n1,{cell}\n"):
        values = _table(tmp_path, text).numbers([0, 1])
        assert values[1, 1] == value and np.signbit(values[1, 1]) == np.signbit(value)
    assert decimal_number(cell) == value


def test_a_non_ascii_cell_in_a_column_not_used_is_fine(tmp_path: Path) -> None:
    values = _table(tmp_path, "s,z,name\n0,1,\u010cezso\u010da\n2,3,\u0661\n").numbers([0, 1])
    assert values[:, :2].tolist() == [[0.0, 1.0], [2.0, 3.0]]


def test_the_message_escapes_what_it_cannot_show(tmp_path: Path) -> None:
    with pytest.raises(InputError) as caught:
        _table(tmp_path, "s,z\n0,\uff11\uff10\n").numbers([0, 1])
    assert "'\\uff11\\uff10'" in str(caught.value) and str(caught.value).isascii()


# ---------------------------------------------------------------- line ends (issue 30 item 3)

LINES = ["# a comment", "s,z", "0,0.5", "# another", "1,2", "2,-1"]


@pytest.mark.parametrize("end", ["\n", "\r\n", "\r", "\r\r\n"], ids=["LF", "CRLF", "CR", "CRCRLF"])
def test_every_kind_of_line_end_reads_the_same_table(tmp_path: Path, end: str) -> None:
    path = tmp_path / "t.csv"
    path.write_bytes(end.join(LINES).encode() + end.encode())
    table = read_table(path, "route file", header_example="'s,z'", empty_fix="write one")
    assert table.numbers([0, 1]).tolist() == [[0.0, 0.5], [1.0, 2.0], [2.0, -1.0]]
    assert table.line_numbers.tolist() == [3, 5, 6]
    assert list(table.comments) == [(1, "# a comment"), (4, "# another")]


@pytest.mark.parametrize(("text", "line"), [
    # before: the lone CR ended the comment and "10.025,5" became a data row (a 5 m step)
    ("s,z\n10,0\n# note\r10.025,5\n10.05,0\n", 3),
    # before: the second comment was obeyed as an assumed roughness
    ("# x\r# roughness_class = H\ns,z\n0,0\n1,0\n", 1),
    ("s,z\r\n0,0\r\n1,0\r2,0\r\n", 3),  # in a CRLF file as well
])
def test_a_lone_carriage_return_in_a_file_of_lf_lines_is_refused(tmp_path: Path, text: str, line: int) -> None:
    path = tmp_path / "r.csv"
    path.write_bytes(text.encode())
    with pytest.raises(InputError, match=rf"r\.csv: line {line}: a carriage return \(\\r\) inside the line"):
        read_route(path)


@pytest.mark.parametrize(("text", "words"), [
    ("s,z\n0,0\n1,0\r2,0\n", r"line 3: a carriage return \(\\r\) inside the line, in a route file whose lines end "
                              r"at \\n:"),
    # before: a CRLF file was said to end its lines at \n
    ("s,z\r\n0,0\r\n1,0\r2,0\r\n", r"line 3: .* in a route file whose lines end at \\r\\n:"),
    ("s,z\n0,0\r\n1,0\r2,0\n", r"line 3: .* in a route file whose lines end at \\n and \\r\\n:"),
    # a classic Mac OS file (lines end at \r) with a \n in it: not a lone \r in a file of \n lines
    ("s,z\r0,0\r1,0\n2,0\r3,0\r", r"r\.csv: the route file ends 4 lines at a lone carriage return \(\\r, classic "
                                   r"Mac OS\) and 1 at \\n"),
])
def test_the_refusal_of_a_lone_carriage_return_says_what_the_lines_end_with(tmp_path: Path, text: str,
                                                                            words: str) -> None:
    path = tmp_path / "r.csv"
    path.write_bytes(text.encode())
    with pytest.raises(InputError, match=words) as raised:
        read_route(path)
    assert "\n" not in str(raised.value)
