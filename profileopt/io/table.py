"""The one CSV table reader behind route and profile files.

A table file is UTF-8 text (a byte-order mark is allowed) with one header line of column
names, data rows of comma-separated cells, and comment lines starting with ``#`` and blank
lines anywhere. Lines end at ``\\n`` only (a ``\\r`` before it is dropped): a form feed,
vertical tab, NEL or U+2028 inside a comment is part of the comment, never a line break,
so it cannot turn the rest of a comment into a data row.

Every problem is one :class:`~profileopt.errors.InputError` line naming the file and the
line, what is wrong and how to fix it.
"""

from __future__ import annotations

import dataclasses
import itertools
import os
from typing import Sequence

import numpy as np

from ..errors import InputError
from . import inputs

__all__ = ["Table", "read_table", "split_lines", "read_text"]


def split_lines(text: str) -> list[str]:
    """Split ``text`` at ``\\n`` only, dropping one ``\\r`` before each (Unix and Windows files).

    Unlike :meth:`str.splitlines`, a form feed, vertical tab, NEL or U+2028 is kept inside its
    line.

    Parameters
    ----------
    text : str
        The whole file.

    Returns
    -------
    list of str
        The lines, without their line ends; no empty last line for a final newline.
    """
    lines = text.split("\n")
    if lines and lines[-1] == "":
        lines.pop()
    if "\r" not in text:  # a Unix file: nothing to drop (the common case, no pass over every line)
        return lines
    return [line[:-1] if line.endswith("\r") else line for line in lines]


def read_text(path: str | os.PathLike, what: str) -> str:
    """The text of a UTF-8 file (a byte-order mark is dropped), or one line saying why not.

    Parameters
    ----------
    path : str or os.PathLike
        The file.
    what : str
        What the file is, for messages ("route file", "profile file").

    Returns
    -------
    str

    Raises
    ------
    InputError
        The file is missing, a folder, not a regular file, larger than
        :data:`~profileopt.io.inputs.MAX_TABLE_BYTES`, unreadable or not UTF-8.
    """
    data = inputs.read_input(path, what, inputs.MAX_TABLE_BYTES)
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise InputError(f"{path}: cannot read the {what} ({exc})") from None
    # as a file opened in text mode reads it (universal newlines): \r\n and a lone \r end a line
    return text.replace("\r\n", "\n").replace("\r", "\n") if "\r" in text else text


@dataclasses.dataclass(frozen=True, eq=False)
class Table:
    """The lines of a table file, split into header, data rows and comments.

    Attributes
    ----------
    source : str
        The file's name, for messages.
    header : tuple of str
        Column names as written (stripped of white space).
    header_line : int
        File line number of the header (1-based).
    rows : list of str
        The data lines (stripped).
    line_numbers : numpy.ndarray of int, shape (M,)
        File line number of each data row.
    comments : tuple of (int, str)
        Line number and text of every comment line (``#`` included), in order.
    """

    source: str
    header: tuple[str, ...]
    header_line: int
    rows: list[str]
    line_numbers: np.ndarray
    comments: tuple[tuple[int, str], ...]

    def numbers(self, used: Sequence[int]) -> np.ndarray:
        """The cells of the columns ``used`` as finite floats, shape (M, len(header)).

        Every row must have exactly as many cells as the header (a row with one cell too
        many beside a row with one too few must not shift the table); only the columns in
        ``used`` must hold numbers (the others may hold text and are NaN in the result).

        Parameters
        ----------
        used : sequence of int
            Indices of the columns to convert.

        Returns
        -------
        numpy.ndarray, shape (M, len(header))

        Raises
        ------
        InputError
            A row with another number of cells, a cell that is not a number, or one that is
            NaN or infinite (the message names the line and the column).
        """
        width = len(self.header)
        rows = self.rows
        commas = np.array(list(map(str.count, rows, itertools.repeat(","))), dtype=np.int64)
        bad = np.flatnonzero(commas != width - 1)
        if bad.size:
            i = bad[0]
            raise InputError(f"{self.source}: line {self.line_numbers[i]}: {commas[i] + 1} cells but the header "
                             f"has {width}; make every row match the header")
        flat = ",".join(rows).split(",")
        table = None
        if len(used) == width:  # every column is used: one conversion of the whole table
            try:
                table = np.array(flat, dtype=float).reshape(len(rows), width)
            except ValueError:
                pass  # find the offending cell below
        if table is None:
            cells = np.array(flat, dtype=object).reshape(len(rows), width)
            table = np.full((len(rows), width), np.nan)
            for col in used:
                try:
                    table[:, col] = cells[:, col].astype(float)
                except ValueError:
                    i = next(i for i, cell in enumerate(cells[:, col]) if not _is_number(cell))
                    raise InputError(f"{self.source}: line {self.line_numbers[i]}: {self.header[col]} = "
                                     f"'{cells[i, col].strip()}' is not a number; every cell of that column must "
                                     "be a number in SI units") from None
        for col in used:
            bad = np.flatnonzero(~np.isfinite(table[:, col]))
            if bad.size:
                i = bad[0]
                raise InputError(f"{self.source}: line {self.line_numbers[i]}: {self.header[col]} = "
                                 f"{table[i, col]} is not a finite number; remove the row or give a number")
        return table


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def read_table(path: str | os.PathLike, what: str, *, header_example: str, empty_fix: str) -> Table:
    """Read a table file into its header, data rows and comments.

    Parameters
    ----------
    path : str or os.PathLike
        The file.
    what : str
        What the file is, for messages ("route file", "profile file").
    header_example : str
        A header to suggest when the first line is data (e.g. ``"'s,z' or 'x,y,z'"``).
    empty_fix : str
        What to do about an empty file, for its message.

    Returns
    -------
    Table

    Raises
    ------
    InputError
        The file cannot be read, is empty, or its first non-comment line is data.
    """
    source = str(path)
    text = read_text(path, what)
    stripped = [raw.strip() for raw in split_lines(text)]
    comments: list[tuple[int, str]] = []
    header: tuple[str, ...] | None = None
    header_line = 0
    start = len(stripped)
    for index, line in enumerate(stripped):  # comments and blank lines, up to the header
        if line.startswith("#"):
            comments.append((index + 1, line))
        elif line:
            header, header_line, start = tuple(c.strip() for c in line.split(",")), index + 1, index + 1
            break
    # after the header, in comprehensions (a 100,000-line route: 30 ms instead of 80)
    after = range(start, len(stripped))
    data = [i for i in after if stripped[i] and stripped[i][0] != "#"]
    comments += [(i + 1, stripped[i]) for i in after if stripped[i][:1] == "#"]
    rows = [stripped[i] for i in data]
    line_numbers = [i + 1 for i in data]
    if header is None:
        raise InputError(f"{source}: the {what} is empty; {empty_fix}")
    if all(_is_number(c) for c in header):
        raise InputError(f"{source}: line {header_line}: the first row is data, not a header; "
                         f"add a header line such as {header_example} above it")
    return Table(source=source, header=header, header_line=header_line, rows=rows,
                 line_numbers=np.asarray(line_numbers, dtype=np.int64), comments=tuple(comments))
