"""Route files: the CSV a user writes to describe the path a vehicle will drive.

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

One comment line may record an assumed roughness (issue 12), for a route whose elevation
comes from a terrain model too coarse to measure wheel-scale roughness:

``# roughness_class = C``
    an ISO 8608 class, one letter A to H (case-insensitive): every roughness window gets
    the class's expected RI (:mod:`profileopt.terrain.classes`), or
``# roughness_ri = 0.05``
    the RI (dimensionless, 0 to :data:`~profileopt.terrain.assumed.MAX_ASSUMED_RI`) of
    every roughness window.

Blanks around ``=`` are optional. At most one such line; a bad value or a second line is
one InputError naming the file and the line. Every other ``#`` line stays a comment.
:func:`route_metadata_lines` writes the line.
"""

from __future__ import annotations

import os
import re
from pathlib import Path
from typing import Sequence

import numpy as np

from ..core.route import Route, path_distance_m, validate_route_arrays
from ..errors import InputError
from ..terrain.assumed import MAX_ASSUMED_RI, AssumedRoughness
from .atomic import atomic_write
from .table import Table, decimal_number, read_table
from .tracks import degrees_like_extent

__all__ = ["read_route", "write_route", "route_metadata_lines", "ROUTE_COLUMN_ALIASES", "ROUGHNESS_KEYS"]

#: The keys of a route file's assumed-roughness comment line and the AssumedRoughness field each sets.
ROUGHNESS_KEYS = {"roughness_class": "road_class", "roughness_ri": "ri"}
_ROUGHNESS_LINE = re.compile(r"#\s*(roughness_class|roughness_ri)\s*=(.*)$", re.IGNORECASE)

#: Accepted column names (lower case) and the quantity each one gives.
ROUTE_COLUMN_ALIASES = {
    "s": "s", "s_m": "s",
    "x": "x", "x_m": "x",
    "y": "y", "y_m": "y",
    "z": "z", "z_m": "z",
    "speed_limit": "speed_limit", "speed_limit_mps": "speed_limit",
}


def read_route(path: str | os.PathLike) -> Route:
    """Read and validate a route CSV.

    Parameters
    ----------
    path : str or os.PathLike
        CSV file with columns ``s,z`` or ``x,y,z`` (m) and optional ``speed_limit`` (m/s).

    Returns
    -------
    Route

    Raises
    ------
    InputError
        Empty file, no header, missing or unusable columns, a non-numeric, NaN or infinite
        cell (numbers in ASCII decimal notation only), s not strictly increasing, a single
        row, absurd magnitudes or a speed limit <= 0; x, y that look like longitude and
        latitude in degrees (:func:`~profileopt.io.tracks.degrees_like_extent`); a terrain
        file (``.las``, ``.laz``, ``.tif``, ``.tiff``, ``.crg``) given as the route. The message
        names the file and line.
    """
    _refuse_terrain_file(path)
    table = read_table(path, "route file", header_example="'s,z' or 'x,y,z'",
                       empty_fix="a route CSV starts with a header line such as 's,z'")
    name = table.source
    header = [c.lower() for c in table.header]
    header_line = table.header_line
    columns: dict[str, int] = {}
    ignored = []
    for i, col in enumerate(header):
        key = ROUTE_COLUMN_ALIASES.get(col)
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
    if table.row_count < 2:
        raise InputError(f"{name}: {table.row_count} data row(s); a route needs at least 2 (better: many, "
                         "dense enough to measure roughness)")

    values = table.numbers(sorted(columns.values()))
    where = table.line_numbers
    z = values[:, columns["z"]]
    limit = values[:, columns["speed_limit"]] if "speed_limit" in columns else None
    x = y = None
    if "s" in columns:
        s = values[:, columns["s"]]
    else:
        x, y = values[:, columns["x"]], values[:, columns["y"]]
        s = path_distance_m(x, y)
        bad = np.flatnonzero(np.diff(s) == 0)
        if bad.size:
            raise InputError(f"{name}: line {where[bad[0] + 1]}: the point repeats the previous x,y; "
                             "remove duplicate points")
        extent = degrees_like_extent(x, y)
        if extent is not None:
            raise InputError(f"{name}: x, y look like longitude, latitude in degrees (within +-180, +-90 and "
                             f"{extent:.3g} across), but a route file's are metres; make a route of them as a track "
                             f"(profileopt route {Path(name).name} --track-crs EPSG:4326 -o route.csv) or convert "
                             "them to metres in a projected CRS")
    validate_route_arrays(name, s, z, limit, where, "line")
    return Route(s_m=s, z_m=z, speed_limit_mps=limit, source=name, notes=notes, x_m=x, y_m=y,
                 assumed_roughness=_assumed_roughness(table))


#: What each kind of terrain file (:data:`profileopt.io.terrain_maps.TERRAIN_SUFFIXES`) is, for
#: the message when one is given as a route.
_TERRAIN_KINDS = {"LAS": "a point cloud (LAS)", "LAZ": "a point cloud (LAZ)", "GeoTIFF": "a terrain map (GeoTIFF DEM)",
                  "OpenCRG": "a terrain surface (OpenCRG)"}


def _refuse_terrain_file(path: str | os.PathLike) -> None:
    """Refuse a terrain file given where a route file belongs, saying how to use it.

    Raises
    ------
    InputError
        ``path`` ends in a terrain file's ending (``.las``, ``.laz``, ``.tif``, ``.tiff``, ``.crg``)
        (or, so ending, is not there: not found).
    """
    from .terrain_maps import TERRAIN_SUFFIXES  # its endings (no geo package is imported)

    suffix = os.path.splitext(str(path))[1].lower()
    if suffix in TERRAIN_SUFFIXES:
        from .inputs import check_regular_input

        check_regular_input(path, "route file")  # a path that is not there is not found, whatever its ending
        kind = _TERRAIN_KINDS[TERRAIN_SUFFIXES[suffix]]
        raise InputError(f"{path}: is {kind}, not a route file; give it as --terrain with the track to drive over it "
                         f"(profileopt plan TRACK.gpx --terrain {os.path.basename(str(path))}, or make a route first "
                         "with profileopt route)")


def _assumed_roughness(table: Table) -> AssumedRoughness | None:
    """The assumed roughness a route file's comment lines record (module docstring), if any.

    Parameters
    ----------
    table : Table
        The route file, read by :func:`~profileopt.io.table.read_table`.

    Returns
    -------
    AssumedRoughness or None

    Raises
    ------
    InputError
        A second roughness line, or a value that is not a class A to H (``roughness_class``)
        or a number in range (``roughness_ri``); the message names the file and the line.
    """
    found: AssumedRoughness | None = None
    first = 0
    for number, line in table.comments:
        match = _ROUGHNESS_LINE.match(line)
        if match is None:
            continue
        key, value = match.group(1).lower(), match.group(2).strip()
        if found is not None:
            raise InputError(f"{table.source}: line {number}: a second roughness line ('{line}'; the first is line "
                             f"{first}); keep one of them")
        try:
            found = AssumedRoughness(**{ROUGHNESS_KEYS[key]: value if key == "roughness_class" else _number(value)})
        except InputError as exc:
            fix = ("give one ISO 8608 class letter A to H, e.g. '# roughness_class = C'" if key == "roughness_class"
                   else f"give the RI (RMS roughness / ground clearance) as a number in [0, {MAX_ASSUMED_RI:g}], "
                   "e.g. '# roughness_ri = 0.05'")
            raise InputError(f"{table.source}: line {number}: {key} = '{value}' is not usable "
                             f"({_reason(exc)}); {fix}") from None
        first = number
    return found


def _number(text: str) -> float:
    """The RI a roughness line writes, in ASCII decimal notation (:func:`~profileopt.io.table.decimal_number`)."""
    value = decimal_number(text)
    if value is None:
        raise InputError(f"assumed roughness: {text!r} is not a number written in ASCII digits")
    return value


def _reason(exc: InputError) -> str:
    """The part of an AssumedRoughness message that says what is wrong."""
    return str(exc).removeprefix("assumed roughness: ").split("; ")[0]


def route_metadata_lines(assumed: AssumedRoughness | None) -> list[str]:
    """The comment lines a route file needs to carry ``assumed`` (none for None).

    Parameters
    ----------
    assumed : AssumedRoughness or None
        The route's assumed roughness.

    Returns
    -------
    list of str
        ``["# roughness_class = C"]``, ``["# roughness_ri = 0.05"]`` (the RI's shortest
        repr, read back to the same float) or ``[]``; without line ends.
    """
    if assumed is None:
        return []
    if assumed.road_class is not None:
        return [f"# roughness_class = {assumed.road_class}"]
    return [f"# roughness_ri = {assumed.ri!r}"]


def write_route(route: Route, path: str | os.PathLike, *, comments: Sequence[str] = ()) -> None:
    """Write a route CSV atomically, in the form :func:`read_route` reads back exactly.

    Columns ``x_m,y_m,z_m`` (a route with a path in the plane) or ``s_m,z_m``, then
    ``speed_limit_mps`` if the route has one; each number as the shortest decimal that reads
    back as the same float, so that the route read back is this one, float for float. The comment lines come first, each
    prefixed with ``#`` and a space, then the assumed roughness's metadata line, if any.

    Parameters
    ----------
    route : Route
        The route to write.
    path : str or os.PathLike
        The output file; it appears only when the whole file is written.
    comments : sequence of str, default ()
        Lines recording where the route came from (sources, CRS, what was done), without
        the ``#``; each must be a single line.
    """
    names = ["x_m", "y_m", "z_m"] if route.x_m is not None else ["s_m", "z_m"]
    columns = [getattr(route, name) for name in names]
    if route.speed_limit_mps is not None:
        names.append("speed_limit_mps")
        columns.append(route.speed_limit_mps)
    lines = [f"# {line}" for line in comments]
    lines += route_metadata_lines(route.assumed_roughness)
    with atomic_write(path) as handle:
        for line in lines:
            handle.write(line.replace("\n", " ") + "\n")
        handle.write(",".join(names) + "\n")
        # repr: the shortest decimal that reads back as the same float (300.437, not 300.43700000000001)
        handle.writelines(",".join(map(repr, row)) + "\n" for row in np.column_stack(columns).tolist())
