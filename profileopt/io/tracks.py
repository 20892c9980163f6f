"""GPS tracks: GPX, GeoJSON and CSV polylines in plan view, and their projection to metres.

:func:`read_track` reads the line a vehicle will follow (x, y and, where the file has it for
every point, elevation) with the coordinate reference system the file states;
:func:`project_track` takes it to a projected CRS in metres (the terrain's), and
:func:`local_projected_crs` picks the UTM zone for a track used without a terrain map.

Every problem is one :class:`~profileopt.errors.InputError` line naming the file, the point
(its index or CSV line) or key, what is wrong and how to fix it. gpxpy and pyproj (the
``geo`` extra) are imported only when needed.

GPS noise
---------
A GPS track's points are noisy by metres (a consumer receiver's fixes scatter by 1 to 5 m):
between them the polyline zigzags, reads its corners as sharp turns, and is longer than the
path driven (1.5 m of noise every 3 m adds 30 %). :func:`read_track` therefore returns the
points moved onto the smoothest path within the path tolerance of them
(:func:`profileopt.terrain.geometry.smooth_track_points`): the tolerance given
(``path_tolerance_m``, ``--path-tolerance``), or estimated from the points' own spread,
sigma sqrt(2 ln n) (:func:`profileopt.terrain.geometry.estimate_path_noise`). A track whose
estimated noise stays within :data:`~profileopt.defaults.MIN_PATH_TOLERANCE_M` (a survey, a
drawn line) is kept as it is. A note says what was estimated and how far the points moved.

Joining GPX pieces
------------------
A GPX file may hold several tracks, each of several segments (a receiver starts a new one
when it loses the fix or the logging is paused). They are joined in file order when each
starts within :data:`JOIN_GAP_M` (50 m) of the previous end: a consumer receiver's position
error is 5 to 10 m (95 %) and its points are a few to 10 m apart, so a gap of a few tens of
metres is a pause in logging on the same way (the bundled ``korita-zbevnica.gpx`` resumes
20 m on after a five-minute stop), while a longer gap is a stretch whose path is unknown and
a straight joint could cut through a hillside. A longer gap is refused, naming the gap and
the tracks to choose from with ``track_index`` (``--track-index``). A joint's start that
repeats the previous end exactly (the split point written twice) is dropped with a note.
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
import sys
from pathlib import Path
from typing import Any, Callable

import numpy as np

from ..core.route import path_distance_m
from ..errors import InputError
from . import inputs
from .geo import crs_label, length_units_m, parse_crs, require_geo
from .table import read_table, read_text

__all__ = ["Track", "read_track", "project_track", "local_projected_crs", "track_length_m", "check_track_samples",
           "check_not_degrees", "degrees_like_extent", "JOIN_GAP_M", "TRACK_SUFFIXES", "DEGREES_EXTENT"]

#: What a terrain file given as a track is, by its ending (the endings of
#: :data:`profileopt.io.terrain_maps.TERRAIN_SUFFIXES`), for the message saying to give it as
#: ``--terrain``.
_TERRAIN_FILES = {".las": "a point cloud (LAS)", ".laz": "a point cloud (LAZ)", ".tif": "a terrain map (GeoTIFF DEM)",
                  ".tiff": "a terrain map (GeoTIFF DEM)", ".crg": "a terrain surface (OpenCRG)"}

#: Largest gap (m) between the end of one GPX track or segment and the start of the next
#: that is joined (see the module's notes).
JOIN_GAP_M = 50.0

#: File name endings :func:`read_track` accepts, and the reader of each.
TRACK_SUFFIXES = {".gpx": "GPX", ".geojson": "GeoJSON", ".json": "GeoJSON", ".csv": "CSV"}

#: A track without a CRS whose x all lie within +-180 and y within +-90, and whose bounding box
#: is smaller than this across (its diagonal, in the file's units), is taken to be longitude
#: and latitude in degrees, not metres (:func:`degrees_like_extent`): 2 degrees is about 200 km,
#: while 2 m is too short a route to plan a speed along (a few wheel turns).
DEGREES_EXTENT = 2.0

_CSV_COLUMNS = {"x": "x", "x_m": "x", "y": "y", "y_m": "y", "z": "z", "z_m": "z",
                "speed_limit": "speed_limit", "speed_limit_mps": "speed_limit"}


@dataclasses.dataclass(frozen=True, eq=False)
class Track:
    """A track in plan view: the points a vehicle drives through, in order.

    Attributes
    ----------
    x : numpy.ndarray, shape (N,)
        Easting (m) in a projected CRS, longitude (deg) in a geographic one, or as the file
        gives it when ``crs`` is None.
    y : numpy.ndarray, shape (N,)
        Northing (m) or latitude (deg).
    z_m : numpy.ndarray, shape (N,), or None
        Elevation (m) from the track itself (GPX ``<ele>``, a GeoJSON third coordinate, a
        CSV z column) if every point has one, else None.
    crs : pyproj.CRS or None
        The coordinate reference system of x and y; None when the file states none (a CSV
        without ``track_crs``: the caller takes it to be in the terrain's CRS, in metres).
    source : str
        The file read, for messages.
    notes : tuple of str
        What was done on the way (joints, dropped repeats, ignored items), one line each.
    speed_limit_mps : numpy.ndarray, shape (N,), or None
        A speed cap (m/s, > 0) at each point, from a CSV ``speed_limit`` column: it holds
        from that point to the next. None if the file gives none.
    smoothing : SmoothedTrack or None
        How the points were moved onto the smoothest path within the path tolerance (see
        "GPS noise" above): the tolerance, where it came from, the noise estimated; None for
        a track made otherwise than by :func:`read_track`.
    """

    x: np.ndarray
    y: np.ndarray
    z_m: np.ndarray | None
    crs: Any
    source: str
    notes: tuple[str, ...] = ()
    speed_limit_mps: np.ndarray | None = None
    smoothing: Any = None

    def __len__(self) -> int:
        return int(self.x.size)


@dataclasses.dataclass
class _Points:
    """Points as read, before the checks: coordinates, times (s, NaN if none) and labels."""

    x: list[float]
    y: list[float]
    z: list[float | None]
    t: list[float]
    label: Callable[[int], str]
    limit: list[float] | None = None


def read_track(path: str | os.PathLike, *, track_crs: str | None = None,
               track_index: int | None = None, path_tolerance_m: float | None = None,
               smooth: bool = True) -> Track:
    """Read a track from a GPX, GeoJSON or CSV file (chosen by the file name's ending).

    * GPX (``.gpx``): the points of its tracks and their segments, or, in a file without
      track points, of its routes; several are joined in file order when each starts within
      :data:`JOIN_GAP_M` of the previous end (see the module's notes), else refused unless
      ``track_index`` picks one. CRS: WGS 84 longitude/latitude (EPSG:4326), always.
    * GeoJSON (``.geojson``, ``.json``): a LineString geometry, a Feature of one, or a
      FeatureCollection with exactly one LineString. CRS: WGS 84 (RFC 7946), or the legacy
      ``"crs"`` member if the file has one.
    * CSV (``.csv``): a header with ``x,y`` or ``x_m,y_m`` and optionally ``z`` or ``z_m``
      (m) and ``speed_limit`` or ``speed_limit_mps`` (m/s, from that point to the next),
      ``#`` comment lines. CRS: ``track_crs``, else None (not stated). The x, y values
      are in the unit of that CRS's axes (a GIS writes them so) and are converted to metres
      here; ``x_m, y_m`` columns with a CRS not in metres are refused as contradictory.

    In a geographic CRS, x is the longitude and y the latitude (degrees), whatever the CRS's
    own axis order. In a projected CRS they are converted to metres. Consecutive repeats of
    a point are refused, unless both points carry times and the times differ (the vehicle
    stood still): then the repeat is dropped with a note. Points are counted from 0.

    The points are then moved onto the smoothest path within the path tolerance of them
    (see "GPS noise" above; in metres: a geographic track on the plane tangent to the Earth
    at its mean position, WGS 84 radii of curvature there, which is within millimetres of
    exact over tens of kilometres for moves of metres). Elevations and speed limits stay
    with their points.

    Parameters
    ----------
    path : str or os.PathLike
        The track file.
    track_crs : str, optional
        The CRS of the coordinates (``EPSG:32633``, WKT, PROJ): required for a CSV not in
        the terrain's CRS; overrides a GeoJSON file's; not allowed for GPX (always WGS 84).
    track_index : int, optional
        Which GPX track to read (0-based, in file order; the routes in a file without track
        points); its segments are joined as above. None reads them all.
    path_tolerance_m : float, optional
        How far (m) a point may be moved onto the smoothed path, > 0; None estimates it from
        the track (and keeps a track whose noise is within MIN_PATH_TOLERANCE_M as it is).
    smooth : bool, default True
        False returns the points as the file gives them (no smoothing, no ``smoothing``).

    Returns
    -------
    Track

    Raises
    ------
    InputError
        An unknown file ending, malformed XML or JSON, no track points, a single point,
        a non-finite coordinate, a latitude or longitude out of range, an unknown CRS, a
        gap too long to join, a repeated point, a path tolerance that is not a number > 0, or
        gpxpy/pyproj missing (each one line).
    """
    path = Path(path)
    kind = TRACK_SUFFIXES.get(path.suffix.lower())
    if kind is None:
        what = _TERRAIN_FILES.get(path.suffix.lower())
        if what is not None:
            inputs.check_regular_input(path, "track file")  # a path that is not there: not found, first
            raise InputError(f"{path}: is {what}, not a track; give it as --terrain with the track to drive over it "
                             f"(profileopt route TRACK.gpx --terrain {path.name} -o route.csv)")
        raise InputError(f"{path}: a track file must end in {', '.join(TRACK_SUFFIXES)} "
                         f"(GPX, GeoJSON or CSV), not {path.suffix or 'no ending'!r}; rename or convert it")
    if track_index is not None and kind != "GPX":
        raise InputError(f"{path}: track_index (--track-index) picks a track of a GPX file; a {kind} file holds one")
    crs = None if track_crs is None else parse_crs(track_crs, str(path), "--track-crs")
    notes: list[str] = []
    metres_named = False
    if kind == "GPX":
        if track_crs is not None:
            raise InputError(f"{path}: GPX coordinates are WGS 84 latitude/longitude by definition; "
                             "drop --track-crs")
        points, crs = _read_gpx(path, track_index, notes), parse_crs("EPSG:4326", str(path), "GPX")
    elif kind == "GeoJSON":
        points, stated = _read_geojson(path, notes)
        crs = crs if crs is not None else stated
    else:
        points, metres_named = _read_csv(path, notes)
    track = _finish(path, points, crs, notes, metres_named)
    return _smoothed(track, path_tolerance_m) if smooth else track


def _smoothed(track: Track, path_tolerance_m: float | None) -> Track:
    """The track with its points moved onto the smoothest path within the path tolerance."""
    # scipy: only when a track is read
    from ..terrain.geometry import smooth_track_points

    geographic = track.crs is not None and _is_geographic(track.crs)
    if geographic:
        # east and north (m) on the plane tangent at the mean position: the meridional and
        # prime-vertical radii of curvature of the WGS 84 ellipsoid there
        a, f = 6378137.0, 1 / 298.257223563
        e2 = f * (2 - f)
        lat0 = math.radians(float(np.mean(track.y)))
        lon0 = float(np.degrees(np.angle(np.mean(np.exp(1j * np.radians(track.x))))))
        w = 1.0 - e2 * math.sin(lat0) ** 2
        north_m = a * (1 - e2) / w**1.5 * math.pi / 180  # per degree of latitude
        east_m = a / math.sqrt(w) * math.cos(lat0) * math.pi / 180  # per degree of longitude
        x = ((track.x - lon0 + 180.0) % 360.0 - 180.0) * east_m
        y = (track.y - float(np.degrees(lat0))) * north_m
    else:
        x, y = track.x, track.y
    done = smooth_track_points(x, y, tolerance_m=path_tolerance_m)
    if not done.smoothed:
        return dataclasses.replace(track, smoothing=done)
    note = done.note(Path(track.source).name)
    if geographic:
        new_x, new_y = track.x + (done.x_m - x) / east_m, track.y + (done.y_m - y) / north_m
    else:
        new_x, new_y = done.x_m, done.y_m
    return dataclasses.replace(track, x=new_x, y=new_y, notes=(*track.notes, note), smoothing=done)


def _finish(path: Path, points: _Points, crs: Any, notes: list[str], metres_named: bool) -> Track:
    """The checks every track passes, then the Track."""
    x = np.asarray(points.x, dtype=float)
    y = np.asarray(points.y, dtype=float)
    t = np.asarray(points.t, dtype=float)
    bad = np.flatnonzero(~(np.isfinite(x) & np.isfinite(y)))
    if bad.size:
        i = int(bad[0])
        raise InputError(f"{path}: {points.label(i)}: coordinate ({x[i]}, {y[i]}) is not finite; "
                         "remove the point or give numbers")
    geographic = crs is not None and _is_geographic(crs)
    if geographic:
        bad = np.flatnonzero((np.abs(y) > 90) | (np.abs(x) > 180))
        if bad.size:
            i = int(bad[0])
            raise InputError(f"{path}: {points.label(i)}: longitude {x[i]:g}, latitude {y[i]:g} out of range "
                             "(longitude -180..180, latitude -90..90 degrees); are x and y swapped or not degrees?")
    elif crs is not None:
        unit_m = length_units_m(crs, str(path))[0]
        if unit_m != 1.0:
            if metres_named:
                raise InputError(f"{path}: columns x_m,y_m say metres but {crs_label(crs)} is in units of "
                                 f"{unit_m:g} m; rename them x,y (values in the CRS's unit) or convert them")
            x, y = x * unit_m, y * unit_m
            notes.append(f"{path.name}: x, y converted from the CRS's unit ({unit_m:g} m) to metres")
    z_values = points.z
    z = None
    if z_values and all(v is not None for v in z_values):
        z = np.asarray(z_values, dtype=float)
        bad = np.flatnonzero(~np.isfinite(z))
        if bad.size:
            raise InputError(f"{path}: {points.label(int(bad[0]))}: elevation {z[bad[0]]} is not finite; "
                             "remove the point or give a number")
    elif any(v is not None for v in z_values):
        missing = sum(v is None for v in z_values)
        notes.append(f"{path.name}: {missing} of {len(z_values)} points have no elevation; the track's own "
                     "elevations are not used")
    limit = None if points.limit is None else np.asarray(points.limit, dtype=float)
    if limit is not None:
        bad = np.flatnonzero(~(np.isfinite(limit) & (limit > 0)))
        if bad.size:
            i = int(bad[0])
            raise InputError(f"{path}: {points.label(i)}: speed_limit = {limit[i]:g} m/s must be a number > 0; "
                             "give the limit in m/s")
    keep = np.ones(x.size, dtype=bool)
    repeat = np.flatnonzero((np.diff(x) == 0) & (np.diff(y) == 0)) + 1
    for i in repeat:
        if np.isfinite(t[i - 1]) and np.isfinite(t[i]) and t[i] != t[i - 1]:
            keep[i] = False
            continue
        raise InputError(f"{path}: {points.label(int(i))} repeats the previous point ({x[i]:.9g}, {y[i]:.9g}) "
                         "without a later time; remove the duplicate point")
    if not keep.all():
        dropped = np.flatnonzero(~keep)
        notes.append(f"{path.name}: dropped {dropped.size} repeated point(s) where the vehicle stood still "
                     f"(first: {points.label(int(dropped[0]))})")
        x, y = x[keep], y[keep]
        z = None if z is None else z[keep]
        limit = None if limit is None else limit[keep]
    if x.size < 2:
        raise InputError(f"{path}: the track has {x.size} point; a track needs at least 2 distinct points")
    return Track(x=x, y=y, z_m=z, crs=crs, source=str(path), notes=tuple(notes), speed_limit_mps=limit)


def _is_geographic(crs: Any) -> bool:
    parts = list(crs.sub_crs_list) if crs.is_compound else [crs]
    return any(p.is_geographic for p in parts) and not any(p.is_projected for p in parts)


# ----------------------------------------------------------------------------------- GPX


def _read_gpx(path: Path, track_index: int | None, notes: list[str]) -> _Points:
    gpxpy = require_geo("gpxpy", "reading GPX")
    data = inputs.read_input(path, "GPX file", inputs.MAX_TABLE_BYTES)
    try:
        gpx = gpxpy.parse(data)
    except (gpxpy.gpx.GPXException, ValueError, UnicodeDecodeError) as exc:
        reason = " ".join(str(exc).split())[:160]
        raise InputError(f"{path}: is not a readable GPX file ({reason}); check that it is GPX XML") from None
    kind = "track"
    items = [(trk.name, [seg.points for seg in trk.segments]) for trk in gpx.tracks]
    if not any(points for _, segments in items for points in segments):
        kind, items = "route", [(rte.name, [rte.points]) for rte in gpx.routes]
    _check_gpx_numbers(path, data, kind)
    filled = [i for i, (_, segments) in enumerate(items) if any(segments)]
    if not filled:
        raise InputError(f"{path}: the GPX file has no track or route points; export the track with its "
                         "points (<trkpt> or <rtept>)")
    listing = "; ".join(f"{i} {items[i][0] or ''!r} {sum(map(len, items[i][1]))} points" for i in filled)
    if track_index is not None:
        if not 0 <= track_index < len(items) or track_index not in filled:
            raise InputError(f"{path}: {kind} {track_index} does not exist or has no points; choose "
                             f"--track-index from the {kind}s with points: {listing}")
        chosen = [track_index]
    else:
        chosen = filled
        empty = [i for i in range(len(items)) if i not in filled]
        if empty:
            notes.append(f"{path.name}: skipped {kind}(s) without points: {', '.join(map(str, empty))}")
    if gpx.waypoints:
        notes.append(f"{path.name}: ignored {len(gpx.waypoints)} waypoint(s) (only {kind} points are read)")
    routes = sum(1 for rte in gpx.routes if rte.points)
    if kind == "track" and routes:
        notes.append(f"{path.name}: ignored {routes} route(s) with points (<rte>): a GPX file with track points is "
                     "read for its tracks; to drive a route, save it in a file of its own")

    pieces = [(i, j, segment) for i in chosen for j, segment in enumerate(items[i][1]) if segment]
    labels: list[tuple[int, int, int]] = []
    out = _Points([], [], [], [], lambda k: "")
    geod = None
    for number, (i, j, segment) in enumerate(pieces):
        start = 0
        if number:
            previous = pieces[number - 1]
            end, first = previous[2][-1], segment[0]
            for p in (end, first):
                _check_lonlat(path, p, _gpx_label(kind, *labels[-1]) if p is end else _gpx_label(kind, i, j, 0))
            if geod is None:
                geod = require_geo("pyproj", "reading GPX").Geod(ellps="WGS84")
            gap = float(geod.inv(end.longitude, end.latitude, first.longitude, first.latitude)[2])
            where = f"{kind} {previous[0]} segment {previous[1]} to {kind} {i} segment {j}"
            if gap > JOIN_GAP_M:
                raise InputError(f"{path}: {kind} {previous[0]} segment {previous[1]} ends {gap:.0f} m from the start "
                                 f"of {kind} {i} segment {j}, more than the {JOIN_GAP_M:g} m joined; read one "
                                 f"{kind} with --track-index ({kind}s with points: {listing})")
            if gap == 0.0:
                start = 1
                notes.append(f"{path.name}: joined {where} (its first point repeats the joint, dropped)")
            else:
                notes.append(f"{path.name}: joined {where} across a gap of {gap:.1f} m")
        for k, p in enumerate(segment[start:], start=start):
            out.x.append(p.longitude)
            out.y.append(p.latitude)
            out.z.append(p.elevation)
            out.t.append(p.time.timestamp() if p.time is not None else math.nan)
            labels.append((i, j, k))
    out.label = lambda n: _gpx_label(kind, *labels[n])
    return out


def _gpx_label(kind: str, i: int, j: int, k: int) -> str:
    return f"{kind} {i} segment {j} point {k}"


#: White space XML allows around an attribute's or an element's text.
_XML_SPACE = " \t\r\n"


def _check_gpx_numbers(path: Path, data: bytes, kind: str) -> None:
    """Refuse a ``lat``, ``lon`` or ``<ele>`` of the points read (``kind``: track or route
    points) that is not a number in ASCII decimal notation, as every number the project reads
    (:func:`profileopt.io.table.is_decimal`): gpxpy reads them with ``float()``, which also
    takes ``1_00``, Arabic-Indic and full-width digits. One line naming the file, the line,
    the point and the value."""
    from xml.parsers import expat

    from .table import is_decimal, quoted

    point_tag = "trkpt" if kind == "track" else "rtept"
    counters = {"trk": -1, "trkseg": -1, "rte": -1, "point": -1}
    state: dict[str, Any] = {"point": None, "ele": None, "depth": 0, "point_depth": None}
    parser = expat.ParserCreate()

    def refuse(line: int, what: str, value: str) -> None:
        raise InputError(f"{path}: line {line} ({state['point']}): {what} = {quoted(value)} is not a number; write it "
                         "with the ASCII digits 0-9, '.' and an optional exponent (e.g. 45.00005)")

    def number(text: str) -> bool:
        text = text.strip(_XML_SPACE)
        return not text or is_decimal(text)

    def start(name: str, attributes: dict[str, str]) -> None:
        local = name.rsplit(":", 1)[-1]
        state["depth"] += 1
        if local in ("trk", "rte"):
            counters[local] += 1
            counters["trkseg"] = -1 if local == "trk" else 0
            counters["point"] = -1
        elif local == "trkseg":
            counters["trkseg"] += 1
            counters["point"] = -1
        elif local == point_tag:
            counters["point"] += 1
            i = counters["trk" if kind == "track" else "rte"]
            state["point"] = _gpx_label(kind, max(i, 0), max(counters["trkseg"], 0), counters["point"])
            state["point_depth"] = state["depth"]
            for key in ("lat", "lon"):
                value = attributes.get(key)
                if value is not None and not number(value):
                    refuse(parser.CurrentLineNumber, key, value)
        elif local == "ele" and state["point_depth"] is not None and state["depth"] == state["point_depth"] + 1:
            state["ele"] = (parser.CurrentLineNumber, [])

    def end(name: str) -> None:
        local = name.rsplit(":", 1)[-1]
        if local == "ele" and state["ele"] is not None:
            line, parts = state["ele"]
            state["ele"] = None
            text = "".join(parts)
            if not number(text):
                refuse(line, "<ele>", text.strip(_XML_SPACE))
        elif local == point_tag and state["depth"] == state["point_depth"]:
            state["point"] = state["point_depth"] = None
        state["depth"] -= 1

    def characters(text: str) -> None:
        if state["ele"] is not None:
            state["ele"][1].append(text)

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    parser.CharacterDataHandler = characters
    try:
        parser.Parse(data, True)
    except expat.ExpatError:  # gpxpy read it, expat does not: its numbers were checked as far as expat got
        pass


def _check_lonlat(path: Path, point: Any, label: str) -> None:
    lon, lat = point.longitude, point.latitude
    if not (math.isfinite(lon) and math.isfinite(lat) and abs(lon) <= 180 and abs(lat) <= 90):
        raise InputError(f"{path}: {label}: longitude {lon:g}, latitude {lat:g} is not a position "
                         "(longitude -180..180, latitude -90..90 degrees); fix or remove the point")


# ------------------------------------------------------------------------------- GeoJSON


def _read_geojson(path: Path, notes: list[str]) -> tuple[_Points, Any]:
    text = read_text(path, "GeoJSON file", line_ends=False)  # JSON: a \r is white space
    try:
        root = json.loads(text)
    except json.JSONDecodeError as exc:
        raise InputError(f"{path}: line {exc.lineno}: not valid JSON ({exc.msg}); check the file") from None
    except RecursionError:
        raise InputError(f"{path}: the JSON is nested deeper than it can be read (about {sys.getrecursionlimit()} "
                         "levels); a GeoJSON track is a LineString of positions [[x, y], ...], a few levels "
                         "deep") from None
    except ValueError:  # an integer of more digits than Python converts (sys.get_int_max_str_digits)
        raise InputError(f"{path}: holds a number of more than {sys.get_int_max_str_digits():,} digits, too large "
                         "for any coordinate; fix it") from None
    if not isinstance(root, dict):
        raise InputError(f"{path}: the JSON is not a GeoJSON object; give a LineString, a Feature or a "
                         "FeatureCollection")
    geometry, where = _one_linestring(path, root, notes)
    coordinates = geometry.get("coordinates")
    if not isinstance(coordinates, list):
        raise InputError(f"{path}: {where}: 'coordinates' is not a list of positions; give [[x, y], ...]")
    out = _Points([], [], [], [], lambda k: f"{where} coordinate {k}")
    for k, position in enumerate(coordinates):
        if (not isinstance(position, list) or len(position) not in (2, 3)
                or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in position)):
            raise InputError(f"{path}: {where} coordinate {k}: {_json_excerpt(position)} is not a position "
                             "[x, y] or [x, y, z] of numbers; fix it")
        try:
            values = [float(v) for v in position]
        except OverflowError:  # an integer of hundreds of digits
            raise InputError(f"{path}: {where} coordinate {k}: a number of "
                             f"{max(len(str(abs(v))) for v in position if isinstance(v, int))} digits, too large for "
                             "any coordinate; fix it") from None
        out.x.append(values[0])
        out.y.append(values[1])
        out.z.append(values[2] if len(values) == 3 else None)
        out.t.append(math.nan)
    crs = parse_crs("EPSG:4326", str(path), "GeoJSON")  # RFC 7946, section 4
    member = root.get("crs")
    if member is not None:  # the 2008 GeoJSON specification's named CRS
        properties = member.get("properties", {}) if isinstance(member, dict) else {}
        name = properties.get("name") if isinstance(properties, dict) else None
        if not isinstance(name, str):
            raise InputError(f"{path}: key 'crs' is not a named CRS {{\"type\": \"name\", \"properties\": "
                             "{\"name\": \"EPSG:32633\"}}; fix it or remove it (RFC 7946: WGS 84)")
        crs = parse_crs(name, str(path), "the file's 'crs' member")
        notes.append(f"{path.name}: CRS {crs_label(crs)} from the file's legacy 'crs' member")
    return out, crs


def _json_excerpt(value: Any, limit: int = 60) -> str:
    """The start of ``value`` written as JSON, for a message (a value nested too deep to write
    is described instead)."""
    try:
        return json.dumps(value)[:limit]
    except (RecursionError, ValueError):
        return f"a {type(value).__name__} nested too deep"


def _one_linestring(path: Path, root: dict, notes: list[str]) -> tuple[dict, str]:
    kind = root.get("type")
    if kind == "FeatureCollection":
        features = root.get("features")
        if not isinstance(features, list):
            raise InputError(f"{path}: key 'features' of the FeatureCollection is not a list; fix the file")
        found = []
        for i, feature in enumerate(features):
            geometry = feature.get("geometry") if isinstance(feature, dict) else None
            gtype = geometry.get("type") if isinstance(geometry, dict) else None
            if gtype == "MultiLineString":
                raise InputError(_multi(path, f"feature {i}"))
            if gtype == "LineString":
                found.append((geometry, f"feature {i}"))
        if len(found) != 1:
            raise InputError(f"{path}: the FeatureCollection holds {len(found)} LineStrings; a track file needs "
                             "exactly one, save the one to drive on its own")
        if len(features) > 1:
            notes.append(f"{path.name}: ignored {len(features) - 1} feature(s) that are not the LineString")
        return found[0]
    if kind == "Feature":
        geometry = root.get("geometry")
        gtype = geometry.get("type") if isinstance(geometry, dict) else None
        if gtype == "MultiLineString":
            raise InputError(_multi(path, "the Feature"))
        if gtype != "LineString":
            raise InputError(f"{path}: the Feature's geometry is {gtype!r}, not a LineString; give the track as "
                             "a LineString")
        return geometry, "the Feature"
    if kind == "MultiLineString":
        raise InputError(_multi(path, "the geometry"))
    if kind == "LineString":
        return root, "the LineString"
    raise InputError(f"{path}: key 'type' is {kind!r}; a track is a GeoJSON LineString, a Feature of one or a "
                     "FeatureCollection with one")


def _multi(path: Path, where: str) -> str:
    return (f"{path}: {where} is a MultiLineString; join its parts into one LineString (or save the part to "
            "drive) so that the order of the parts is yours, not a guess")


# ----------------------------------------------------------------------------------- CSV


def _read_csv(path: Path, notes: list[str]) -> tuple[_Points, bool]:
    table = read_table(path, "track file", header_example="'x,y' or 'x_m,y_m'",
                       empty_fix="a track CSV starts with a header line such as 'x,y'")
    columns: dict[str, int] = {}
    names: dict[str, str] = {}
    for i, name in enumerate(table.header):
        key = _CSV_COLUMNS.get(name.lower())
        if key is None:
            notes.append(f"{path.name}: ignoring column {name!r}")
        elif key in columns:
            raise InputError(f"{path}: line {table.header_line}: columns {names[key]!r} and {name!r} both give "
                             f"{key}; keep one")
        else:
            columns[key], names[key] = i, name.lower()
    if "x" not in columns or "y" not in columns:
        raise InputError(f"{path}: line {table.header_line}: header {','.join(table.header)!r} lacks the columns "
                         "'x,y' (or 'x_m,y_m'); rename the columns")
    if not table.row_count:
        raise InputError(f"{path}: no data rows after the header; a track needs at least 2 points")
    values = table.numbers(sorted(columns.values()))
    lines = table.line_numbers
    out = _Points(list(values[:, columns["x"]]), list(values[:, columns["y"]]),
                  list(values[:, columns["z"]]) if "z" in columns else [None] * len(values),
                  [math.nan] * len(values), lambda k: f"line {lines[k]}",
                  list(values[:, columns["speed_limit"]]) if "speed_limit" in columns else None)
    return out, names["x"].endswith("_m") or names["y"].endswith("_m")


# ---------------------------------------------------------------------------- projection


def project_track(track: Track, crs: Any) -> Track:
    """The track in a projected CRS, x and y in metres.

    A track without a CRS (``crs`` None) is taken to be in ``crs`` already, in metres (the
    caller's rule for a CSV without ``--track-crs``), and gets a note saying so. Otherwise
    pyproj transforms it (``always_xy``: x is easting or longitude), from the track's unit
    into the target's, and the result is converted to metres by the target's axis unit
    (a CRS in US survey feet gives metres all the same). Elevations are kept as they are.

    Parameters
    ----------
    track : Track
        The track, as :func:`read_track` returns it.
    crs : pyproj.CRS
        The target: a projected CRS whose axes are in a length unit (the terrain's).

    Returns
    -------
    Track
        ``x``, ``y`` in metres, ``crs`` the target, a note added.

    Raises
    ------
    InputError
        The target is geographic, or a point cannot be projected (outside the projection's
        domain), or pyproj is missing.
    """
    pyproj = require_geo("pyproj", "projecting a track")
    target_m = length_units_m(crs, track.source)[0]
    if track.crs is None:
        note = f"{Path(track.source).name}: states no CRS; taken to be in {crs_label(crs)} (metres)"
        return dataclasses.replace(track, crs=crs, notes=track.notes + (note,))
    if track.crs == crs:
        return dataclasses.replace(track, crs=crs)
    source_m = 1.0 if _is_geographic(track.crs) else length_units_m(track.crs, track.source)[0]
    transformer = pyproj.Transformer.from_crs(track.crs, crs, always_xy=True)
    x, y = transformer.transform(track.x / source_m, track.y / source_m)
    x, y = np.asarray(x, dtype=float) * target_m, np.asarray(y, dtype=float) * target_m
    bad = np.flatnonzero(~(np.isfinite(x) & np.isfinite(y)))
    if bad.size:
        i = int(bad[0])
        raise InputError(f"{track.source}: point {i} ({track.x[i]:.9g}, {track.y[i]:.9g}) cannot be projected to "
                         f"{crs_label(crs)}; is the track far outside the area of that CRS?")
    note = f"{Path(track.source).name}: projected from {crs_label(track.crs)} to {crs_label(crs)} (metres)"
    return dataclasses.replace(track, x=x, y=y, crs=crs, notes=track.notes + (note,))


def local_projected_crs(track: Track) -> Any:
    """The WGS 84 UTM zone of the track's mean position, for a track used without a terrain map.

    The zone is ``floor((longitude + 180) / 6) + 1`` of the mean longitude (a circular mean,
    so a track across the 180th meridian is placed right), EPSG:326zz north of the equator
    and EPSG:327zz south of it (the mean latitude's sign). The special zones of Norway and
    Svalbard are not used: the regular zone is a valid projection there too.

    Parameters
    ----------
    track : Track
        A track with a CRS.

    Returns
    -------
    pyproj.CRS
        WGS 84 / UTM zone zz N or S.

    Raises
    ------
    InputError
        The track states no CRS, its mean latitude is outside UTM's 80 deg S to 84 deg N,
        or pyproj is missing.
    """
    pyproj = require_geo("pyproj", "choosing a map projection")
    if track.crs is None:
        raise InputError(f"{track.source}: states no CRS, so its position on Earth is unknown; pass --track-crs "
                         "(e.g. EPSG:32633)")
    lon, lat = track.x, track.y
    if not _is_geographic(track.crs):
        unit_m = length_units_m(track.crs, track.source)[0]
        to_wgs84 = pyproj.Transformer.from_crs(track.crs, "EPSG:4326", always_xy=True)
        lon, lat = (np.asarray(v, dtype=float) for v in to_wgs84.transform(track.x / unit_m, track.y / unit_m))
    radians = np.radians(lon)
    mean_lon = math.degrees(math.atan2(float(np.mean(np.sin(radians))), float(np.mean(np.cos(radians)))))
    mean_lat = float(np.mean(lat))
    if not -80.0 <= mean_lat <= 84.0:
        raise InputError(f"{track.source}: mean latitude {mean_lat:.2f} deg is outside the UTM zones (80 S to 84 N); "
                         "pass a projected CRS for polar regions (e.g. EPSG:3413 or EPSG:3031)")
    zone = int((mean_lon + 180.0) // 6.0) % 60 + 1
    return pyproj.CRS.from_epsg((32600 if mean_lat >= 0 else 32700) + zone)


# ------------------------------------------------------------------------------ checks


def track_length_m(track: Track) -> float:
    """The length of the track's polyline (m).

    Along the WGS 84 ellipsoid (geodesics between the points) for a geographic track; in the
    plane for a projected one (x, y in metres) and for one without a CRS (its units taken
    as metres, as a track used without a terrain map is).

    Parameters
    ----------
    track : Track
        As :func:`read_track` returns it.

    Returns
    -------
    float
    """
    if track.crs is not None and _is_geographic(track.crs):
        geod = require_geo("pyproj", "measuring a track").Geod(ellps="WGS84")
        return float(geod.line_length(track.x, track.y))
    return float(path_distance_m(track.x, track.y)[-1])


def check_track_samples(track: Track, spacing_m: float) -> None:
    """Refuse, before sampling, a track that would make more route samples than a route may have.

    A route made from a track has about length / spacing samples; more than
    :func:`profileopt.io.inputs.max_route_samples` would need more memory than the largest
    route file (see :mod:`profileopt.io.inputs`). A spacing that is not a number > 0 is left
    to the sampler to refuse.

    Parameters
    ----------
    track : Track
        As :func:`read_track` returns it.
    spacing_m : float
        Distance between the route's samples along the track (m).

    Raises
    ------
    InputError
        Too many samples; the message names the track's length and the smallest spacing
        that fits (two significant digits, rounded up).
    """
    if not (math.isfinite(spacing_m) and spacing_m > 0):
        return
    cap = inputs.max_route_samples()
    length = track_length_m(track)
    count = length / spacing_m + 1
    if count <= cap:
        return
    least = length / (cap - 1)
    step = 10.0 ** (math.floor(math.log10(least)) - 1)
    fit = math.ceil(least / step) * step
    raise InputError(f"{track.source}: the track is {length / 1000:.4g} km long: at spacing_m {spacing_m:g} m it makes "
                     f"{count:.3g} route samples, more than the {cap:,} a route may have (the memory of the "
                     f"largest route file; see profileopt.io.inputs); give spacing_m {fit:.2g} or more, or split the "
                     "track")


def degrees_like_extent(x: np.ndarray, y: np.ndarray) -> float | None:
    """The extent of x, y that look like longitude and latitude in degrees, else None.

    They look so when every x lies within +-180, every y within +-90, and their bounding
    box is less than :data:`DEGREES_EXTENT` across (its diagonal).

    Parameters
    ----------
    x, y : numpy.ndarray, shape (N,)
        Coordinates as a file gives them.

    Returns
    -------
    float or None
        The bounding box's diagonal (in the file's units) when they look like degrees.
    """
    if x.size == 0:
        return None
    extent = math.hypot(float(np.ptp(x)), float(np.ptp(y)))
    if extent < DEGREES_EXTENT and np.all(np.abs(x) <= 180.0) and np.all(np.abs(y) <= 90.0):
        return extent
    return None


def check_not_degrees(track: Track) -> None:
    """Refuse a track without a CRS whose x, y look like longitude and latitude in degrees.

    Used where the track's x, y would be taken as metres (no terrain map): a track in
    degrees would be planned as a route some millimetres long (:func:`degrees_like_extent`).

    Parameters
    ----------
    track : Track
        As :func:`read_track` returns it.

    Raises
    ------
    InputError
        The track states no CRS and its x, y look like degrees.
    """
    extent = None if track.crs is not None else degrees_like_extent(track.x, track.y)
    if extent is not None:
        raise InputError(f"{track.source}: states no CRS and its x, y look like longitude, latitude in degrees (within "
                         f"+-180, +-90 and {extent:.3g} across: as metres, a route {extent:.3g} m across); give "
                         "track_crs EPSG:4326 (or the CRS they are in)")
