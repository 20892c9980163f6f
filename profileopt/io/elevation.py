"""Readers of measured longitudinal elevation profiles: OpenCRG road files and two-column
text profiles.

Both return an :class:`~profileopt.terrain.synthetic.ElevationProfile` (distance s and elevation z
in metres), the form that ``examples/routes/make_routes.py`` writes as a route CSV. A file
that cannot be read raises :class:`~profileopt.errors.InputError` whose one-line message
names the file (and the line), what is wrong and what would fix it.
"""

from __future__ import annotations

import dataclasses
import math
import os
import re
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..terrain.synthetic import ElevationProfile
from . import inputs
from .table import decimal_number, split_lines

__all__ = ["read_opencrg", "read_xy_profile", "parse_opencrg", "OpenCrgData"]

#: OpenCRG binary data formats this reader understands: numpy dtype of one value.
#: KRBI: 4-byte IEEE float, big-endian; KDBI: 8-byte IEEE float, big-endian.
_CRG_FORMATS = {"KRBI": ">f4", "KDBI": ">f8"}

#: OpenCRG binary data are padded with NaN to whole 80-byte records.
_CRG_RECORD_BYTES = 80

_HEADER_END = re.compile(rb"^\$\$\$\$+[ \t\r]*$", re.MULTILINE)


@dataclasses.dataclass(frozen=True, eq=False)
class OpenCrgData:
    """An OpenCRG file's header keys, column definitions and data, as stored.

    Attributes
    ----------
    path : pathlib.Path
        The file read.
    keys : dict of str to str
        The ``$ROAD_CRG`` block's ``key = value`` lines, keys in lower case.
    definitions : list of str
        The ``D:`` lines of the ``$KD_DEFINITION`` block without ``D:`` (e.g.
        ``"long section at v = -1.500,m"``), one per data column.
    data_format : str
        The ``#:`` line (``KRBI`` or ``KDBI``).
    u_m : numpy.ndarray, shape (rows,)
        Distance along the reference line of each data row (m):
        ``reference_line_start_u + i * reference_line_increment``.
    values : numpy.ndarray, shape (rows, len(definitions))
        The data, as floats (NaN where the file has no data).
    """

    path: Path
    keys: dict[str, str]
    definitions: list[str]
    data_format: str
    u_m: np.ndarray
    values: np.ndarray

    @property
    def columns(self) -> list[str]:
        """The name of each data column: its ``D:`` line up to the first comma."""
        return [text.split(",", 1)[0].strip() for text in self.definitions]

    def number(self, key: str, default: float | None = None) -> float:
        """A ``$ROAD_CRG`` key as a finite number.

        Parameters
        ----------
        key : str
            The key, lower case (``"reference_line_start_x"``).
        default : float, optional
            The value of a missing key; None makes a missing key an error.

        Returns
        -------
        float

        Raises
        ------
        InputError
            The key is missing (without a default), not a number, or not finite.
        """
        if key not in self.keys:
            if default is not None:
                return default
            raise InputError(f"{self.path}: header key {key!r} is missing; the reader needs it to place the samples")
        value = decimal_number(self.keys[key])  # ASCII decimal notation only
        if value is None:
            raise InputError(f"{self.path}: header key {key!r} = {self.keys[key]!r} is not a number")
        if not math.isfinite(value):
            raise InputError(f"{self.path}: header key {key!r} = {self.keys[key]!r} is not finite")
        return value


def parse_opencrg(path: str | os.PathLike) -> OpenCrgData:
    """Read an OpenCRG file (binary data formats): its header and its data grid.

    An OpenCRG file is a text header that ends in a line of ``$`` characters, followed by
    the data: one row per step along the reference line, one value per ``D:`` line of the
    ``$KD_DEFINITION`` block, as big-endian IEEE floats (format ``#:KRBI``, 4 bytes;
    ``#:KDBI``, 8 bytes), padded with NaN to whole 80-byte records. Distance along the
    reference line is ``reference_line_start_u + i * reference_line_increment``
    (``$ROAD_CRG`` block), up to ``reference_line_end_u``. The readers of profiles
    (:func:`read_opencrg`) and of surfaces
    (:func:`~profileopt.io.terrain_maps.read_crg_surface`) share it.

    Parameters
    ----------
    path : str or os.PathLike
        The ``.crg`` file.

    Returns
    -------
    OpenCrgData

    Raises
    ------
    InputError
        No header end line, a missing or non-numeric ``reference_line_*`` key, an
        unsupported data format, no ``D:`` lines, or too few data bytes.
    """
    path = Path(path)
    raw = inputs.read_input(path, "OpenCRG file", inputs.MAX_BINARY_BYTES)
    end = _HEADER_END.search(raw)
    if end is None:
        raise InputError(f"{path}: no line of '$' characters ends the header; is this an OpenCRG file?")
    header = split_lines(raw[: end.start()].decode("latin-1"))
    data_start = end.end() + 1  # the newline after the '$$$$' line

    keys: dict[str, str] = {}
    definitions: list[str] = []
    data_format = None
    block = ""
    for line in header:
        text = line.split("!", 1)[0].strip()  # '!' starts a comment in OpenCRG headers
        if text.startswith("$"):
            block = text[1:].strip().upper()  # "$ROAD_CRG", "$KD_DEFINITION", "$" ends one
        elif block == "ROAD_CRG" and "=" in text:
            key, _, value = text.partition("=")
            keys[key.strip().lower()] = value.strip()
        elif block == "KD_DEFINITION" and text.startswith("D:"):
            definitions.append(text[2:].strip())
        elif block == "KD_DEFINITION" and text.startswith("#:"):
            data_format = text[2:].strip().upper()
    crg = OpenCrgData(path, keys, definitions, data_format or "", np.empty(0), np.empty((0, 0)))

    start_u = crg.number("reference_line_start_u")
    end_u = crg.number("reference_line_end_u")
    step_u = crg.number("reference_line_increment")
    if not step_u > 0 or not end_u > start_u:
        raise InputError(
            f"{path}: reference_line_increment = {step_u:g} must be > 0 and reference_line_end_u = {end_u:g} "
            f"greater than reference_line_start_u = {start_u:g}"
        )
    if data_format not in _CRG_FORMATS:
        raise InputError(
            f"{path}: data format {data_format!r} (the '#:' line) is not supported; "
            f"only binary {', '.join(_CRG_FORMATS)} can be read, convert the file with OpenCRG's tools"
        )
    if not definitions:
        raise InputError(f"{path}: the $KD_DEFINITION block names no data columns ('D:' lines)")

    dtype = np.dtype(_CRG_FORMATS[data_format])
    available = max(len(raw) - data_start, 0)
    span = (end_u - start_u) / step_u  # inf for reference_line_end_u = 1e308 over a small increment
    if not span < available // (len(definitions) * dtype.itemsize):
        rows_text = f"{span + 1:.6g}" if math.isfinite(span) else "more than 1e308"
        raise InputError(
            f"{path}: reference_line_start_u = {start_u:g} to reference_line_end_u = {end_u:g} every "
            f"reference_line_increment = {step_u:g} m is {rows_text} rows of {len(definitions)} {data_format} "
            f"values, but the file holds {available} data bytes, enough for "
            f"{available // (len(definitions) * dtype.itemsize)} rows; the file is truncated or these keys are wrong"
        )
    rows = int(math.floor(span + 0.5)) + 1
    needed = rows * len(definitions) * dtype.itemsize
    if available < needed:
        raise InputError(
            f"{path}: {available} data bytes, but {rows} rows of {len(definitions)} "
            f"{data_format} values need {needed}; the file is truncated"
        )
    values = np.frombuffer(raw, dtype=dtype, count=rows * len(definitions), offset=data_start)
    return dataclasses.replace(crg, u_m=start_u + np.arange(rows) * step_u,
                               values=values.reshape(rows, len(definitions)).astype(float))


def read_opencrg(path: str | os.PathLike, track: int | None = None) -> ElevationProfile:
    """Read one longitudinal track of an OpenCRG road file (binary data formats).

    The file is read by :func:`parse_opencrg`: one row per step along the reference line,
    one value per ``D:`` line of the ``$KD_DEFINITION`` block (a lateral track, "long
    section i"); distance along the reference line is ``reference_line_start_u + i *
    reference_line_increment``, up to ``reference_line_end_u``.

    Parameters
    ----------
    path : str or os.PathLike
        The ``.crg`` file.
    track : int, optional
        Index (0-based) of the ``D:`` column to return; default the middle one (nearest
        the reference line for a symmetric grid).

    Returns
    -------
    ElevationProfile
        ``s_m`` shape (M,) distance along the reference line (m), ``z_m`` shape (M,)
        elevation of that track (m).

    Raises
    ------
    InputError
        No header end line, a missing or non-numeric ``reference_line_*`` key, an
        unsupported data format, too few data bytes, a track index out of range, or NaN
        (no data) on the chosen track.
    """
    crg = parse_opencrg(path)
    columns = crg.columns
    index = len(columns) // 2 if track is None else int(track)
    if not 0 <= index < len(columns):
        raise InputError(f"{crg.path}: track {track} does not exist; the file has tracks 0..{len(columns) - 1}")
    z = crg.values[:, index]
    if not np.all(np.isfinite(z)):
        bad = int(np.flatnonzero(~np.isfinite(z))[0])
        raise InputError(
            f"{crg.path}: track {index} ({columns[index]!r}) has no data (NaN) at row {bad} "
            f"(u = {crg.u_m[bad]:g} m); choose another track"
        )
    return ElevationProfile(crg.u_m.copy(), z.copy())


def read_xy_profile(path: str | os.PathLike) -> ElevationProfile:
    """Read a two-column text profile: distance (m) and elevation (m) per line.

    Columns are separated by whitespace or a comma; blank lines and lines starting with
    ``#`` are skipped; there is no header. Distances must increase strictly. Values are
    returned as they are in the file (a distance need not start at 0).

    Parameters
    ----------
    path : str or os.PathLike
        The text file.

    Returns
    -------
    ElevationProfile
        ``s_m`` shape (M,) distance (m), ``z_m`` shape (M,) elevation (m).

    Raises
    ------
    InputError
        A line without exactly two numbers, a non-finite value, fewer than 2 samples or a
        distance that does not increase (each names the line).
    """
    path = Path(path)
    try:
        text = inputs.read_input(path, "profile", inputs.MAX_TABLE_BYTES).decode("utf-8")
    except UnicodeDecodeError as exc:
        raise InputError(f"{path}: cannot read the profile ({exc})") from None
    text = text.replace("\r\n", "\n").replace("\r", "\n")  # as text mode reads it
    s: list[float] = []
    z: list[float] = []
    for number, line in enumerate(split_lines(text), start=1):
        stripped = line.strip()
        if not stripped or stripped.startswith("#"):
            continue
        fields = stripped.replace(",", " ").split()
        try:
            if len(fields) != 2:
                raise ValueError
            distance, elevation = (decimal_number(field) for field in fields)
            if distance is None or elevation is None:
                raise ValueError
        except ValueError:
            raise InputError(
                f"{path}, line {number}: expected two numbers 'distance elevation' (m), got {stripped[:60]!r}"
            ) from None
        if not (math.isfinite(distance) and math.isfinite(elevation)):
            raise InputError(f"{path}, line {number}: {stripped[:60]!r} is not finite; remove or fill that sample")
        if s and distance <= s[-1]:
            raise InputError(
                f"{path}, line {number}: distance {distance:g} m does not increase "
                f"(previous {s[-1]:g} m); sort the file or remove the duplicate"
            )
        s.append(distance)
        z.append(elevation)
    if len(s) < 2:
        raise InputError(f"{path}: {len(s)} sample(s); a profile needs at least 2 lines 'distance elevation'")
    return ElevationProfile(np.array(s), np.array(z))
