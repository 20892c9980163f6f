"""Routes: the longitudinal terrain profile along the path a vehicle will drive.

A route file is a CSV with a header row; lines starting with ``#`` are comments. Columns:

``s,z``
    distance along the path and elevation (m), or
``x,y,z``
    a 3-D polyline (m); s is then the cumulative horizontal distance.
``speed_limit`` (optional)
    a legal or operational speed cap at that sample (m/s), > 0.

The unit-suffixed names ``s_m``, ``x_m``, ``y_m``, ``z_m`` and ``speed_limit_mps`` are
accepted as well. Other columns are ignored with a note. Every problem is reported as one
:class:`~profileopt.errors.InputError` line naming the file, the line and what to fix.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from .errors import InputError

__all__ = ["Route", "read_route", "MAX_ABS_ELEVATION_M", "MAX_ELEVATION_STEP_M"]

#: Elevations beyond this (m) are not on the Earth's surface: almost surely a unit mistake.
MAX_ABS_ELEVATION_M = 10_000.0
#: A jump between consecutive samples larger than this (m) is not terrain a vehicle drives.
MAX_ELEVATION_STEP_M = 100.0

_ALIASES = {
    "s": "s", "s_m": "s",
    "x": "x", "x_m": "x",
    "y": "y", "y_m": "y",
    "z": "z", "z_m": "z",
    "speed_limit": "speed_limit", "speed_limit_mps": "speed_limit",
}


@dataclasses.dataclass(frozen=True, eq=False)
class Route:
    """A validated longitudinal terrain profile.

    Attributes
    ----------
    s_m : numpy.ndarray, shape (M,)
        Distance along the path (m), strictly increasing, M >= 2.
    z_m : numpy.ndarray, shape (M,)
        Elevation (m).
    speed_limit_mps : numpy.ndarray, shape (M,), or None
        Speed cap at each sample (m/s), > 0; None if the file has none.
    source : str
        Where the route came from (file name), used in messages.
    notes : tuple of str
        Remarks made while reading (ignored columns), for the user to see.
    """

    s_m: np.ndarray
    z_m: np.ndarray
    speed_limit_mps: np.ndarray | None = None
    source: str = "route"
    notes: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        s = np.ascontiguousarray(self.s_m, dtype=float)
        z = np.ascontiguousarray(self.z_m, dtype=float)
        object.__setattr__(self, "s_m", s)
        object.__setattr__(self, "z_m", z)
        if s.ndim != 1 or z.shape != s.shape:
            raise InputError(f"{self.source}: s and z must be 1-D arrays of the same length")
        if s.size < 2:
            raise InputError(f"{self.source}: a route needs at least 2 samples, got {s.size}; add rows")
        limit = None
        if self.speed_limit_mps is not None:
            limit = np.ascontiguousarray(self.speed_limit_mps, dtype=float)
            if limit.shape != s.shape:
                raise InputError(f"{self.source}: speed_limit_mps has shape {limit.shape} but s has {s.shape}; "
                                 "give one speed limit per sample")
            object.__setattr__(self, "speed_limit_mps", limit)
        lines = np.arange(s.size)  # sample indices, used when no file lines are known
        _check_route_arrays(self.source, s, z, limit, lines, "sample")

    @property
    def length_m(self) -> float:
        """Length of the route s[-1] - s[0] (m)."""
        return float(self.s_m[-1] - self.s_m[0])


def _check_route_arrays(source: str, s: np.ndarray, z: np.ndarray, limit: np.ndarray | None,
                        where: np.ndarray, what: str) -> None:
    """Validate route arrays; ``where[i]`` is the line (or sample) number of row i."""
    for name, col in (("s", s), ("z", z)) + ((("speed_limit", limit),) if limit is not None else ()):
        bad = np.flatnonzero(~np.isfinite(col))
        if bad.size:
            i = bad[0]
            raise InputError(f"{source}: {what} {where[i]}: {name} = {col[i]} is not a finite number; "
                             "remove the row or give a number")
    ds = np.diff(s)
    bad = np.flatnonzero(ds <= 0)
    if bad.size:
        i = bad[0] + 1
        kind = "repeats" if ds[i - 1] == 0 else "decreases"
        raise InputError(f"{source}: {what} {where[i]}: s = {s[i]:g} m {kind} (previous {s[i - 1]:g} m); "
                         "s must increase strictly, so sort the rows or drop duplicates")
    bad = np.flatnonzero(np.abs(z) > MAX_ABS_ELEVATION_M)
    if bad.size:
        i = bad[0]
        raise InputError(f"{source}: {what} {where[i]}: z = {z[i]:g} m is beyond +-{MAX_ABS_ELEVATION_M:g} m; "
                         "elevations are in metres (were they given in millimetres?)")
    dz = np.abs(np.diff(z))
    bad = np.flatnonzero(dz > MAX_ELEVATION_STEP_M)
    if bad.size:
        i = bad[0] + 1
        raise InputError(f"{source}: {what} {where[i]}: z jumps by {dz[i - 1]:g} m from the previous sample; "
                         f"steps above {MAX_ELEVATION_STEP_M:g} m are not drivable terrain (check the units)")
    if limit is not None:
        bad = np.flatnonzero(limit <= 0)
        if bad.size:
            i = bad[0]
            raise InputError(f"{source}: {what} {where[i]}: speed_limit = {limit[i]:g} m/s must be > 0; "
                             "give a positive limit in m/s")


def read_route(path: str | Path) -> Route:
    """Read and validate a route CSV.

    Parameters
    ----------
    path : str or pathlib.Path
        CSV file with columns ``s,z`` or ``x,y,z`` (m) and optional ``speed_limit`` (m/s).

    Returns
    -------
    Route

    Raises
    ------
    InputError
        Empty file, no header, missing or unusable columns, a non-numeric, NaN or infinite
        cell, s not strictly increasing, a single row, absurd magnitudes or a speed limit
        <= 0. The message names the file and line.
    """
    path = Path(path)
    name = str(path)
    try:
        text = path.read_text(encoding="utf-8-sig")
    except FileNotFoundError:
        raise InputError(f"{name}: route file not found; check the path") from None
    except IsADirectoryError:
        raise InputError(f"{name}: is a folder, not a route CSV file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"{name}: cannot read the route file ({exc})") from None

    rows: list[str] = []
    line_numbers: list[int] = []
    header: list[str] | None = None
    header_line = 0
    for number, raw in enumerate(text.splitlines(), start=1):
        line = raw.strip()
        if not line or line.startswith("#"):
            continue
        if header is None:
            header = [c.strip().lower() for c in line.split(",")]
            header_line = number
            continue
        rows.append(line)
        line_numbers.append(number)
    if header is None:
        raise InputError(f"{name}: the file is empty; a route CSV starts with a header line such as 's,z'")
    if all(_is_number(c) for c in header):
        raise InputError(f"{name}: line {header_line}: the first row is data, not a header; "
                         "add a header line such as 's,z' or 'x,y,z' above it")

    columns: dict[str, int] = {}
    ignored = []
    for i, col in enumerate(header):
        key = _ALIASES.get(col)
        if key is None:
            ignored.append(col or f"(empty name, column {i + 1})")
        elif key in columns:
            raise InputError(f"{name}: line {header_line}: column '{col}' appears twice; keep one")
        else:
            columns[key] = i
    if "z" not in columns or not ("s" in columns or ("x" in columns and "y" in columns)):
        raise InputError(f"{name}: line {header_line}: header {','.join(header)!r} lacks the columns "
                         "'s,z' (distance, elevation in m) or 'x,y,z' (a polyline in m); rename the columns")
    if "s" in columns and ("x" in columns or "y" in columns):
        raise InputError(f"{name}: line {header_line}: give either 's' or 'x,y', not both")
    notes = tuple(f"{name}: ignoring column '{c}'" for c in ignored)
    if len(rows) < 2:
        raise InputError(f"{name}: {len(rows)} data row(s); a route needs at least 2 (better: many, "
                         "dense enough to measure roughness)")

    table = _parse_table(name, rows, line_numbers, len(header), sorted(columns.values()), header)
    where = np.asarray(line_numbers)
    z = table[:, columns["z"]]
    limit = table[:, columns["speed_limit"]] if "speed_limit" in columns else None
    if "s" in columns:
        s = table[:, columns["s"]]
    else:
        x, y = table[:, columns["x"]], table[:, columns["y"]]
        for label, col in (("x", x), ("y", y)):
            bad = np.flatnonzero(~np.isfinite(col))
            if bad.size:
                raise InputError(f"{name}: line {where[bad[0]]}: {label} = {col[bad[0]]} is not a finite number; "
                                 "remove the row or give a number")
        step = np.hypot(np.diff(x), np.diff(y))
        bad = np.flatnonzero(step == 0)
        if bad.size:
            raise InputError(f"{name}: line {where[bad[0] + 1]}: the point repeats the previous x,y; "
                             "remove duplicate points")
        s = np.concatenate([[0.0], np.cumsum(step)])
    _check_route_arrays(name, s, z, limit, where, "line")
    return Route(s_m=s, z_m=z, speed_limit_mps=limit, source=name, notes=notes)


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _parse_table(name: str, rows: list[str], line_numbers: list[int], width: int,
                 used: list[int], header: list[str]) -> np.ndarray:
    """Parse the used columns of the data rows into an (M, width) float array.

    Every row must have exactly ``width`` cells (a row with one cell too many next to a row
    with one too few must not shift the table); only the columns in ``used`` must be
    numbers (ignored columns may hold text). Columns not used are NaN. One line's error if
    anything is wrong.
    """
    commas = np.fromiter((row.count(",") for row in rows), dtype=np.int64, count=len(rows))
    bad = np.flatnonzero(commas != width - 1)
    if bad.size:
        i = bad[0]
        raise InputError(f"{name}: line {line_numbers[i]}: {commas[i] + 1} cells but the header has {width}; "
                         "make every row match the header")
    flat = ",".join(rows).split(",")
    if len(used) == width:  # every column is used: one conversion of the whole table
        try:
            return np.array(flat, dtype=float).reshape(len(rows), width)
        except ValueError:
            pass  # find the offending cell below
    cells = np.array(flat, dtype=object).reshape(len(rows), width)
    table = np.full((len(rows), width), np.nan)
    for col in used:
        try:
            table[:, col] = cells[:, col].astype(float)
        except ValueError:
            for i, cell in enumerate(cells[:, col]):
                if not _is_number(cell):
                    raise InputError(f"{name}: line {line_numbers[i]}: {header[col]} = '{cell.strip()}' is not a "
                                     "number; every cell of that column must be a number in SI units") from None
            raise  # pragma: no cover - astype failed on a column every cell of which parses
    return table
