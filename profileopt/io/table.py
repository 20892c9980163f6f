"""The one CSV table reader behind route and profile files.

A table file is UTF-8 text (a byte-order mark is allowed) with one header line of column
names, data rows of comma-separated cells, and comment lines starting with ``#`` and blank
lines anywhere.

Line ends
---------
A line ends at ``\\n`` or ``\\r\\n`` (any ``\\r`` just before a ``\\n`` is dropped), or, in a
file with no ``\\n`` at all (classic Mac OS), at every ``\\r``. A lone ``\\r`` inside a line of a
file whose lines end at ``\\n`` is refused, naming the line: some programs show it as a line
break (an editor would show ``# note\\r10.025,5`` as a comment and a data row) and others
not (``cat`` draws the text after it over the comment), so reading it either way could
silently read something else than what its author saw. A form feed, vertical tab, NEL or
U+2028 inside a line is part of it, never a line break, so it cannot turn the rest of a
comment into a data row; a comment ends only where its line does.

Numbers
-------
A cell is a number only in ASCII decimal notation: an optional sign, digits ``0-9`` with
an optional ``.``, an optional exponent (``e`` or ``E``, sign, digits), or ``inf``/``nan``
(refused as not finite, with their own message). What Python's ``float()`` reads besides
(``1_0``, an Arabic-Indic digit ``\\u0661``, full-width ``\\uff11\\uff10``) is refused, naming
the line and the column.

Every problem is one :class:`~profileopt.errors.InputError` line naming the file and the
line, what is wrong and how to fix it.
"""

from __future__ import annotations

import dataclasses
import functools
import itertools
import os
import re
from typing import Sequence

import numpy as np

from ..errors import InputError
from . import inputs

__all__ = ["Table", "read_table", "split_lines", "read_text", "normalise_line_ends", "is_decimal", "decimal_number",
           "quoted"]

#: One number in ASCII decimal notation (module notes), white space around it allowed.
_DECIMAL = re.compile(r"[ \t]*[+-]?(?:(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?|inf|infinity|nan)[ \t]*",
                      re.IGNORECASE)
#: The characters of cells of ASCII decimal numbers, their commas and line ends (the quick
#: check of a whole table's text).
_NUMBER_BYTES = b"0123456789.eE+-,\n \tinfatyINFATY"
#: Carriage returns just before a line feed: part of the line end.
_CR_BEFORE_LF = re.compile(r"\r+\n")


def is_decimal(text: str) -> bool:
    """Whether ``text`` is one number in ASCII decimal notation (module notes; ``inf`` and
    ``nan`` included, white space around it allowed).

    Parameters
    ----------
    text : str
        A cell or a value.

    Returns
    -------
    bool
    """
    return _DECIMAL.fullmatch(text) is not None


def decimal_number(text: str) -> float | None:
    """The float ``text`` writes in ASCII decimal notation, or None when it is not one.

    Parameters
    ----------
    text : str
        A cell or a value.

    Returns
    -------
    float or None
        ``float(text)`` (``inf`` and ``nan`` included), or None for anything else
        (``1_0``, ``\\u0661``, ``\\uff11``, ``0x10``, text).
    """
    return float(text) if is_decimal(text) else None


def _ascii_decimals(text: str) -> bool:
    """Whether ``text`` (cells joined by commas and line ends) holds only the characters of
    ASCII decimal numbers: then ``float()`` reads each cell in that notation or refuses it."""
    # bytes.translate deleting the allowed characters: a C loop (0.04 s for 16 MB; a regex takes 0.3 s)
    return text.isascii() and not text.encode("ascii").translate(None, _NUMBER_BYTES)


def normalise_line_ends(text: str, source: str, what: str) -> str:
    """``text`` with every line ending at ``\\n`` (module notes, "Line ends").

    Parameters
    ----------
    text : str
        The whole file.
    source : str
        The file's name, for messages.
    what : str
        What the file is, for messages ("route file").

    Returns
    -------
    str

    Raises
    ------
    InputError
        A lone ``\\r`` inside a line of a file whose lines end at ``\\n`` (the message names
        the line).
    """
    if "\r" not in text:
        return text
    if "\n" not in text:  # classic Mac OS: every \r ends a line
        return text.replace("\r", "\n")
    feeds = text.count("\n")
    windows = len(_CR_BEFORE_LF.findall(text))  # lines ending at \r\n
    text = text.replace("\r\n", "\n")
    if "\r" in text:
        text = _CR_BEFORE_LF.sub("\n", text)
    lone = text.find("\r")
    if lone >= 0:
        line = text.count("\n", 0, lone) + 1
        lones = text.count("\r")
        if lones > feeds:  # mostly classic Mac OS line ends, with a few \n among them
            raise InputError(f"{source}: the {what} ends {lones} lines at a lone carriage return (\\r, classic Mac "
                             f"OS) and {feeds} at \\n, so where its lines end is ambiguous; convert every line end "
                             "to \\n (e.g. mac2unix) or to \\r")
        ends = "\\r\\n" if windows == feeds else "\\n" if not windows else "\\n and \\r\\n"
        raise InputError(f"{source}: line {line}: a carriage return (\\r) inside the line, in a {what} whose lines "
                         f"end at {ends}: some programs show it as a line break and others do not, so what follows it "
                         "is ambiguous; replace it with a line break or remove it")
    return text


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


def read_text(path: str | os.PathLike, what: str, *, max_bytes: int | None = None, line_ends: bool = True) -> str:
    """The text of a UTF-8 file (a byte-order mark is dropped), or one line saying why not.

    Parameters
    ----------
    path : str or os.PathLike
        The file.
    what : str
        What the file is, for messages ("route file", "profile file").
    max_bytes : int, optional
        The largest size read (default: :data:`~profileopt.io.inputs.MAX_TABLE_BYTES`).
    line_ends : bool, default True
        Make every line end ``\\n`` by :func:`normalise_line_ends` (module notes); False
        returns the text as it is (JSON, where a ``\\r`` is white space).

    Returns
    -------
    str

    Raises
    ------
    InputError
        The file is missing, a folder, not a regular file, larger than ``max_bytes``,
        unreadable or not UTF-8, or (``line_ends``) has a lone ``\\r`` inside a line.
    """
    data = inputs.read_input(path, what, inputs.MAX_TABLE_BYTES if max_bytes is None else max_bytes)
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise InputError(f"{path}: cannot read the {what} ({exc})") from None
    return normalise_line_ends(text, str(path), what) if line_ends else text


@dataclasses.dataclass(frozen=True, eq=False)
class Table:
    """The lines of a table file, split into header, data rows and comments.

    The lines after the header are split only when something asks for them: a plain table
    (every line after the header a data row with as many cells as the header, as every file
    ``profileopt`` writes is) is converted to numbers in one pass over its text.

    Attributes
    ----------
    source : str
        The file's name, for messages.
    header : tuple of str
        Column names as written (stripped of white space).
    header_line : int
        File line number of the header (1-based).
    head_comments : tuple of (int, str)
        Line number and text of the comment lines above the header.
    body : str
        The text after the header line.
    """

    source: str
    header: tuple[str, ...]
    header_line: int
    head_comments: tuple[tuple[int, str], ...]
    body: str

    @functools.cached_property
    def _lines(self) -> tuple[list[str], np.ndarray, tuple[tuple[int, str], ...]]:
        """The data rows (stripped), their file line numbers, and the comments after the header."""
        stripped = [raw.strip() for raw in split_lines(self.body)]
        first = self.header_line + 1
        # in comprehensions (a 100,000-line route: 30 ms instead of 80)
        data = [i for i, line in enumerate(stripped) if line and line[0] != "#"]
        comments = tuple((i + first, line) for i, line in enumerate(stripped) if line[:1] == "#")
        return ([stripped[i] for i in data], np.asarray(data, dtype=np.int64) + first, comments)

    @functools.cached_property
    def _plain_rows(self) -> int | None:
        """The number of data rows when every line after the header is one, else None.

        Plain means: no comment, no blank line, and exactly ``len(header) - 1`` commas on
        every line (so no line is blank or only white space either). Checked on the bytes
        in a few vectorised passes; a one-column table is never plain.
        """
        body, width = self.body, len(self.header)
        if width < 2 or not body or "#" in body or body[0] == "\n" or "\n\n" in body:
            return None
        text = body[:-1] if body[-1] == "\n" else body
        n_rows = text.count("\n") + 1
        if text.count(",") != n_rows * (width - 1):
            return None
        raw = np.frombuffer(text.encode("utf-8"), dtype=np.uint8)
        commas_before_line_end = np.searchsorted(np.flatnonzero(raw == ord(",")), np.flatnonzero(raw == ord("\n")))
        if np.any(np.diff(commas_before_line_end, prepend=0) != width - 1):
            return None  # the last line's count follows from the total
        return n_rows

    @property
    def rows(self) -> list[str]:
        """The data lines (stripped), in order."""
        return self._lines[0]

    @property
    def row_count(self) -> int:
        """The number of data rows (without splitting a plain table into lines)."""
        plain = self._plain_rows
        return plain if plain is not None else len(self.rows)

    @property
    def line_numbers(self) -> np.ndarray:
        """File line number of each data row, shape (M,)."""
        plain = self._plain_rows
        if plain is not None:
            return np.arange(self.header_line + 1, self.header_line + 1 + plain, dtype=np.int64)
        return self._lines[1]

    @property
    def comments(self) -> tuple[tuple[int, str], ...]:
        """Line number and text of every comment line (``#`` included), in order."""
        if "#" not in self.body:
            return self.head_comments
        return self.head_comments + self._lines[2]

    def _plain_numbers(self) -> np.ndarray | None:
        """Every cell of a plain table as floats in one conversion, or None (not plain, or a
        cell that is not a number: the general path then finds and names it)."""
        n_rows = self._plain_rows
        if n_rows is None:
            return None
        body = self.body[:-1] if self.body[-1] == "\n" else self.body
        if not _ascii_decimals(body):
            return None
        try:
            return np.array(body.replace("\n", ",").split(","), dtype=float).reshape(n_rows, len(self.header))
        except ValueError:
            return None

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
        table = self._plain_numbers() if len(used) == width else None
        if table is None:
            table = self._general_numbers(used)
        for col in used:
            bad = np.flatnonzero(~np.isfinite(table[:, col]))
            if bad.size:
                i = bad[0]
                raise InputError(f"{self.source}: line {self.line_numbers[i]}: {self.header[col]} = "
                                 f"{table[i, col]} is not a finite number; remove the row or give a number")
        return table

    def _general_numbers(self, used: Sequence[int]) -> np.ndarray:
        """:meth:`numbers` line by line, for any table (the one that names a bad line)."""
        width = len(self.header)
        rows = self.rows
        commas = np.array(list(map(str.count, rows, itertools.repeat(","))), dtype=np.int64)
        bad = np.flatnonzero(commas != width - 1)
        if bad.size:
            i = bad[0]
            raise InputError(f"{self.source}: line {self.line_numbers[i]}: {commas[i] + 1} cells but the header "
                             f"has {width}; make every row match the header")
        joined = ",".join(rows)
        flat = joined.split(",")
        if len(used) == width and _ascii_decimals(joined):  # every column is used: one conversion
            try:
                return np.array(flat, dtype=float).reshape(len(rows), width)
            except ValueError:
                pass  # find the offending cell below
        cells = np.array(flat, dtype=object).reshape(len(rows), width)
        table = np.full((len(rows), width), np.nan)
        for col in used:
            column = cells[:, col]
            try:
                if not _ascii_decimals("\n".join(column)):
                    raise ValueError
                table[:, col] = column.astype(float)
            except ValueError:
                i = next(i for i, cell in enumerate(column) if not is_decimal(cell))
                raise InputError(f"{self.source}: line {self.line_numbers[i]}: {self.header[col]} = "
                                 f"{quoted(column[i])} is not a number; every cell of that column must be a number "
                                 "in SI units, written with the ASCII digits 0-9, '.' and an optional exponent "
                                 "(e.g. 12.5 or -1.2e-3)") from None
        return table


def quoted(cell: str, limit: int = 40) -> str:
    """A cell or an option's value as a message quotes it: stripped, at most ``limit``
    characters, anything but printable ASCII escaped (``'\\u0661'``), so that the message
    stays one readable line.

    Parameters
    ----------
    cell : str
        The text as read.
    limit : int, default 40
        The most characters shown (then ``...``).

    Returns
    -------
    str
        The text in single quotes.
    """
    text = cell.strip()
    text = text if len(text) <= limit else text[:limit] + "..."
    if not (text.isascii() and text.isprintable()):
        text = text.encode("unicode_escape").decode("ascii")
    return f"'{text}'"


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
    comments: list[tuple[int, str]] = []
    header: tuple[str, ...] | None = None
    header_line = 0
    start = 0
    while start < len(text):  # comments and blank lines, up to the header (the rest is split lazily)
        end = text.find("\n", start)
        end = len(text) if end < 0 else end
        line, header_line, start = text[start:end].strip(), header_line + 1, end + 1
        if line.startswith("#"):
            comments.append((header_line, line))
        elif line:
            header = tuple(c.strip() for c in line.split(","))
            break
    if header is None:
        raise InputError(f"{source}: the {what} is empty; {empty_fix}")
    if all(is_decimal(c) for c in header):
        raise InputError(f"{source}: line {header_line}: the first row is data, not a header; "
                         f"add a header line such as {header_example} above it")
    return Table(source=source, header=header, header_line=header_line, head_comments=tuple(comments),
                 body=text[start:])
