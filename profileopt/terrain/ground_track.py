"""A route from a track and a terrain map: the ground under the wheels, sampled along the track.

:func:`route_from_track` takes a :class:`~profileopt.io.tracks.Track` (GPX, GeoJSON or CSV)
and a terrain (a LAS/LAZ :class:`~profileopt.io.las.PointCloud`, a GeoTIFF
:class:`~profileopt.io.terrain_maps.ElevationGrid`, an OpenCRG
:class:`~profileopt.io.terrain_maps.CrgSurface`, or None: the track's own elevations) and
returns the :class:`~profileopt.core.route.Route` the planner reads:

1. The track is projected into the terrain's CRS (metres) and resampled every
   ``spacing_m`` along its horizontal length (straight lines between its points). Without a
   ``spacing_m``, the finest the terrain resolves is chosen, from half the wheel radius up to
   the wheel radius (:func:`supported_spacing_m`, :func:`cloud_spacing_m`), with a note.
2. Each sample's elevation:

   - point cloud: the ground points (class 2 where the cloud is classified) within
     ``corridor_m`` of the wheel path and nearest that sample give a robust statistic, the
     median (a stray point, a twig or a multipath echo does not move it). An unclassified
     cloud gives the 10th percentile instead (vegetation lies above the ground), with a note;
   - DEM and OpenCRG: bilinear interpolation between the cells;
   - no terrain: the track's own elevations, smoothed over about 50 m
     (:func:`smooth_track_elevations`).

3. Resolution. Roughness at wheel scale needs the terrain resolved at the spacing: a cloud
   with :data:`~profileopt.defaults.MIN_POINTS_PER_BIN` ground points expected per bin
   (density x 2 corridor x spacing), a grid whose cells are no larger than the spacing. A
   coarser terrain (airborne LiDAR at about one point per m^2, a 1 m DEM, a GPS track) is
   refused for roughness with one line giving the resolution found, the one needed and the
   spacing that would measure it (or that none up to the wheel radius does),
   unless an assumed roughness is given (an ISO 8608 class or an RI,
   :class:`~profileopt.terrain.assumed.AssumedRoughness`): then the terrain gives the
   route's geometry and grade, and the assumption its roughness. A sparse cloud then gives
   the elevation by linear interpolation over the triangulation of its ground points.
4. Gaps (samples without a ground point or without data) up to ``max_gap_m`` are bridged
   by straight lines and reported; a longer one is refused with its position.
"""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING, Any

import numpy as np

from ..core.route import Route, path_distance_m
from ..defaults import (
    DEFAULT_CORRIDOR_M,
    DEFAULT_MAX_GAP_M,
    DEFAULT_TRACK_SPACING_M,
    MAX_ROUGHNESS_CORRIDOR_M,
    MAX_ROUGHNESS_SPACING_M,
    MIN_POINTS_PER_BIN,
)
from ..errors import InputError
from ..io.inputs import max_route_samples

if TYPE_CHECKING:
    from ..io.tracks import Track

__all__ = ["TrackRoute", "route_from_track", "resample_polyline", "corridor_bins", "smooth_track_elevations",
           "supported_spacing_m", "cloud_spacing_m", "cloud_margin_m", "track_on_terrain_m", "GAP_RISK", "UNCLASSIFIED_QUANTILE", "GPS_ELEVATION_SCALE_M",
           "SPACING_STEP_M", "SPARSE_NEIGHBOURHOOD_M"]

#: Quantile of the points in a bin taken as the ground when the cloud is not classified:
#: vegetation and other objects lie above the ground, so a low quantile, not the median.
#: (Ground below the 10th percentile is not found: classify the cloud first, e.g. with
#: PDAL's filters.smrf, for a trustworthy profile.)
UNCLASSIFIED_QUANTILE = 0.1
#: Length (m) over which a GPS track's own elevations are smoothed (:func:`smooth_track_elevations`):
#: a consumer GPS's elevation errs by metres from fix to fix, about 10 m apart, so a few fixes
#: (50 m) are averaged; a hill's grade over 50 m survives, a 5 m error no longer reads as a 50 %
#: grade over the 10 m that the planner measures grades on.
GPS_ELEVATION_SCALE_M = 50.0
#: ASPRS class codes of ground (LAS 1.4 R15, Table 17).
_GROUND = 2
#: A spacing chosen for a terrain's resolution is rounded up to a whole number of these (m).
SPACING_STEP_M = 0.01
#: Expected number of stretches without ground points longer than ``max_gap_m`` (refused) that
#: a spacing chosen for a cloud may leave along the route (:func:`cloud_spacing_m`).
GAP_RISK = 0.05
#: Least distance (m) from the track of the ground points whose triangulation gives a sparse
#: cloud's elevations (at least 3 point spacings, 3 / sqrt(density), where that is more).
SPARSE_NEIGHBOURHOOD_M = 5.0


@dataclasses.dataclass(frozen=True, eq=False)
class TrackRoute:
    """A route sampled along a track over a terrain, with what was done to make it.

    Attributes
    ----------
    route : Route
        The samples: ``x_m``, ``y_m`` (m, in :attr:`crs_name`), ``z_m`` (m) and ``s_m``,
        the horizontal distance along the resampled track (m); its ``assumed_roughness``
        if one was given.
    crs_name : str
        The CRS of x and y ("WGS 84 / UTM zone 33N (EPSG:32633)"), or "" for a local frame.
    track_x_m, track_y_m : numpy.ndarray, shape (K,)
        The track's own points in that CRS (m), for maps.
    terrain_kind : str
        "point cloud", "DEM", "OpenCRG" or "track" (the track's own elevations).
    roughness_measured : bool
        Whether the terrain resolves the spacing (else the roughness must be assumed).
    density_per_m2 : float or None
        Ground points per m^2 within the corridor (point clouds only).
    resolution : str
        The terrain's resolution found and the one needed, in words.
    gaps_m : numpy.ndarray, shape (G, 2)
        Start and end (m along the route) of each stretch bridged by a straight line.
    comments : tuple of str
        The ``#`` lines a route file records: sources, CRS, sampling, gaps.
    notes : tuple of str
        Remarks for the user (decisions taken, gaps bridged).
    terrain : PointCloud, ElevationGrid, CrgSurface or None
        The terrain sampled (for maps).
    spacing_m : float or None
        The spacing the samples were taken at (m): the one given, or the one chosen
        (:func:`supported_spacing_m`).
    """

    route: Route
    crs_name: str
    track_x_m: np.ndarray
    track_y_m: np.ndarray
    terrain_kind: str
    roughness_measured: bool
    density_per_m2: float | None
    resolution: str
    gaps_m: np.ndarray
    comments: tuple[str, ...]
    notes: tuple[str, ...]
    terrain: Any = None
    spacing_m: float | None = None


def resample_polyline(x_m: np.ndarray, y_m: np.ndarray, spacing_m: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Samples every ``spacing_m`` along a polyline (straight lines between its points).

    Parameters
    ----------
    x_m, y_m : numpy.ndarray, shape (K,)
        The polyline's points (m), K >= 2, consecutive points distinct.
    spacing_m : float
        Distance between samples along the polyline (m), > 0. The last sample is the
        polyline's end: when the length is not a multiple of the spacing, the last step is
        the remainder if that is at least half a spacing, else the last regular sample moves
        to the end (a last step between 1 and 1.5 spacings).

    Returns
    -------
    s_m, xs_m, ys_m : numpy.ndarray, shape (M,)
        Horizontal distance along the polyline (m, from 0) and the samples' coordinates (m).

    Raises
    ------
    InputError
        More than :func:`profileopt.io.inputs.max_route_samples` samples (the memory of the
        largest route file).
    """
    x = np.asarray(x_m, dtype=float)
    y = np.asarray(y_m, dtype=float)
    along = path_distance_m(x, y)
    length = float(along[-1])
    count = int(math.floor(length / spacing_m + 1e-9)) + 1
    most = max_route_samples()
    if count > most:
        raise InputError(f"spacing_m = {spacing_m:g} m cuts the {length:.6g} m track into {count:.3g} samples, more "
                         f"than the {most:,} a route may have; give a larger spacing or a shorter track")
    s = spacing_m * np.arange(count)
    if length - s[-1] > 1e-9:
        if s.size > 1 and length - s[-1] < 0.5 * spacing_m:
            s[-1] = length  # a sliver of an end: the last sample moves to the end (a step below 1.5 spacings)
        else:
            s = np.append(s, length)
    return s, np.interp(s, along, x), np.interp(s, along, y)


def corridor_bins(points_xy_m: np.ndarray, stations_xy_m: np.ndarray, corridor_m: float
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Which sample's bin each point falls in: the nearest sample, if within the corridor.

    A point belongs to the bin of its nearest sample when its distance across the path
    (perpendicular to the path's direction at that sample) is at most ``corridor_m`` and
    its distance along it at most half the sample spacing.

    Parameters
    ----------
    points_xy_m : numpy.ndarray, shape (P, 2)
        Point coordinates x, y (m).
    stations_xy_m : numpy.ndarray, shape (M, 2)
        The samples along the path (m), M >= 2, evenly spaced except the last.
    corridor_m : float
        Half-width of the strip around the path (m), > 0.

    Returns
    -------
    kept : numpy.ndarray of int, shape (Q,)
        Indices of the points inside the strip.
    bins : numpy.ndarray of int, shape (Q,)
        Each kept point's sample index.
    """
    from scipy.spatial import cKDTree  # only when a cloud is sampled

    stations = np.asarray(stations_xy_m, dtype=float)
    points = np.asarray(points_xy_m, dtype=float)
    step = np.diff(stations, axis=0)
    half = 0.5 * float(np.max(np.hypot(step[:, 0], step[:, 1])))
    tangent = np.gradient(stations, axis=0)
    tangent /= np.hypot(tangent[:, 0], tangent[:, 1])[:, None]
    reach = math.hypot(corridor_m, half) * (1 + 1e-12)
    distance, nearest = cKDTree(stations).query(points, distance_upper_bound=reach)
    inside = np.flatnonzero(np.isfinite(distance))
    nearest = nearest[inside]
    offset = points[inside] - stations[nearest]
    along = np.einsum("ij,ij->i", offset, tangent[nearest])
    across = offset[:, 0] * tangent[nearest, 1] - offset[:, 1] * tangent[nearest, 0]
    keep = (np.abs(across) <= corridor_m) & (np.abs(along) <= half * (1 + 1e-12))
    return inside[keep], nearest[keep]


def supported_spacing_m(resolution_m: float) -> float | None:
    """The finest along-track spacing a terrain of the given resolution measures roughness at.

    The one rule shared by point clouds and grids: the spacing must be at least the terrain's
    resolution (a cloud's: the length of corridor that holds
    :data:`~profileopt.defaults.MIN_POINTS_PER_BIN` ground points; a grid's: its cell) and no
    coarser than :data:`~profileopt.defaults.MAX_ROUGHNESS_SPACING_M` (the wheel radius). It
    is :data:`~profileopt.defaults.DEFAULT_TRACK_SPACING_M` (half the wheel radius) when the
    terrain resolves that, else the resolution rounded up to :data:`SPACING_STEP_M`.

    Parameters
    ----------
    resolution_m : float
        The terrain's resolution along the track (m), > 0 (inf: none).

    Returns
    -------
    float or None
        The spacing (m), or None if no spacing up to the wheel radius is fine enough.
    """
    if not resolution_m <= MAX_ROUGHNESS_SPACING_M * (1 + 1e-9):
        return None
    if resolution_m <= DEFAULT_TRACK_SPACING_M * (1 + 1e-9):
        return DEFAULT_TRACK_SPACING_M
    steps = math.ceil(resolution_m / SPACING_STEP_M * (1 - 1e-9))
    return min(round(steps * SPACING_STEP_M, 10), MAX_ROUGHNESS_SPACING_M)


def cloud_spacing_m(density_per_m2: float, corridor_m: float, length_m: float,
                    max_gap_m: float = DEFAULT_MAX_GAP_M) -> float | None:
    """The finest along-track spacing a point cloud of this density measures roughness at.

    The spacings from :data:`~profileopt.defaults.DEFAULT_TRACK_SPACING_M` to
    :data:`~profileopt.defaults.MAX_ROUGHNESS_SPACING_M` (the wheel radius) in steps of
    :data:`SPACING_STEP_M` whose bins expect at least
    :data:`~profileopt.defaults.MIN_POINTS_PER_BIN` ground points (the rule of
    :func:`supported_spacing_m`, lambda = density x 2 corridor x spacing) are candidates.
    Empty bins are bridged, but a run of ``floor(max_gap_m / spacing)`` of them in a row is
    a gap longer than ``max_gap_m`` and is refused; with points scattered at random (Poisson)
    such runs are expected ``(length / spacing) exp(-lambda floor(max_gap_m / spacing))``
    times. The finest candidate that expects at most :data:`GAP_RISK` of them is chosen;
    if none does, the candidate that expects the fewest (the coarsest).

    Parameters
    ----------
    density_per_m2 : float
        Ground points per m^2 within the corridor.
    corridor_m : float
        The corridor's half-width (m).
    length_m : float
        The route's length (m).
    max_gap_m : float
        The longest stretch without data bridged (m).

    Returns
    -------
    float or None
        The spacing (m), or None if no spacing up to the wheel radius expects enough points.
    """
    finest = supported_spacing_m(_cloud_resolution_m(density_per_m2, corridor_m))
    if finest is None:
        return None
    steps = int(round((MAX_ROUGHNESS_SPACING_M - finest) / SPACING_STEP_M))
    candidates = [round(finest + k * SPACING_STEP_M, 10) for k in range(steps + 1)] or [finest]

    def risk(spacing: float) -> float:
        expected = _points_per_bin(density_per_m2, corridor_m, spacing)
        run = max(math.floor(max_gap_m / spacing + 1e-9), 1)
        return length_m / spacing * math.exp(-expected * run)

    return next((c for c in candidates if risk(c) <= GAP_RISK), min(candidates, key=risk))


def _points_per_bin(density_per_m2: float, corridor_m: float, spacing_m: float) -> float:
    """Points a bin expects: density x (2 corridor x spacing), the bin's area (m^2)."""
    return density_per_m2 * 2.0 * corridor_m * spacing_m


def _cloud_resolution_m(density_per_m2: float, corridor_m: float) -> float:
    """The length of a corridor ``corridor_m`` each side that holds MIN_POINTS_PER_BIN points
    at the density (m): the finest spacing such a cloud is binned at."""
    per_metre = _points_per_bin(density_per_m2, corridor_m, 1.0)
    return MIN_POINTS_PER_BIN / per_metre if per_metre > 0 else math.inf


def _sparse_neighbourhood_m(density_per_m2: float | None) -> float:
    """Distance (m) from the track of the ground points triangulated for a sparse cloud."""
    if not density_per_m2 or not density_per_m2 > 0:
        return SPARSE_NEIGHBOURHOOD_M
    return max(3.0 / math.sqrt(density_per_m2), SPARSE_NEIGHBOURHOOD_M)


def cloud_margin_m(density_per_m2: float | None, spacing_m: float | None = None,
                   corridor_m: float = DEFAULT_CORRIDOR_M) -> float:
    """How far from a track the points of a cloud are needed to sample it (m): those read
    (:func:`~profileopt.io.terrain_maps.read_terrain`'s ``track``) and no others.

    A cloud dense enough to measure roughness in the corridor is binned: it needs the points
    within ``corridor_m`` across and half a (last, up to 1.5 times longer) step along the
    path, all within ``corridor_m + spacing_m``. A sparser one is
    triangulated over its ground points within :data:`SPARSE_NEIGHBOURHOOD_M` (or 3 point
    spacings, judged from a quarter of the density: the ground's share is not known before
    the cloud is read). The margin is the larger of the two where the density (over the
    cloud's bounding box, which underestimates a strip's) might be sparse, plus 1 m for the
    track's own smoothing.

    Parameters
    ----------
    density_per_m2 : float or None
        The cloud's mean density (points per m^2), None if unknown.
    spacing_m : float, optional
        The sampling spacing (m); None: the coarsest chosen automatically
        (:data:`~profileopt.defaults.MAX_ROUGHNESS_SPACING_M`).
    corridor_m : float
        The corridor's half-width (m).

    Returns
    -------
    float
        The distance (m).
    """
    spacing = MAX_ROUGHNESS_SPACING_M if spacing_m is None else float(spacing_m)
    binned = corridor_m + spacing
    dense = density_per_m2 is not None and _cloud_resolution_m(0.5 * density_per_m2, corridor_m) <= spacing
    # a sparse cloud's neighbourhood is judged from its ground's density, unknown before it is
    # read: a quarter of the whole cloud's is assumed (a larger ground share needs less)
    sparse = _sparse_neighbourhood_m(None if density_per_m2 is None else 0.25 * density_per_m2)
    return (binned if dense else max(binned, sparse)) + 1.0


def smooth_track_elevations(s_m: np.ndarray, z_m: np.ndarray, *, scale_m: float = GPS_ELEVATION_SCALE_M) -> Any:
    """A smooth elevation curve through a GPS track's own elevations (noisy by metres).

    A smoothing spline of z over s (:func:`scipy.interpolate.make_smoothing_spline`) with
    lam = (n / L) scale^4, which smooths over about ``scale_m``. A reading equal to the one
    before it (to every digit the log keeps) is a frozen altimeter, not a measurement: it is
    left out (n counts the readings kept). Before the first reading kept and after the last
    the curve holds their values; with fewer than 5 readings kept it runs straight between them
    (one: a constant). (Weighing frozen readings 1e-6 instead, a track whose elevation never
    changes was left with one reading of weight 1 among hundreds of 1e-6: the spline's system
    was near singular and a constant 500 m read as 500-1020 m.)

    Parameters
    ----------
    s_m : numpy.ndarray, shape (K,)
        Distance along the track of its points (m), strictly increasing, K >= 5.
    z_m : numpy.ndarray, shape (K,)
        Their elevations (m).
    scale_m : float, default :data:`GPS_ELEVATION_SCALE_M`
        The length (m) over which the elevations are smoothed.

    Returns
    -------
    callable
        z(s) (m) for s (m) along the track: ``curve(s)``.
    """
    from scipy.interpolate import make_smoothing_spline

    s = np.asarray(s_m, dtype=float)
    z = np.asarray(z_m, dtype=float)
    read = np.concatenate([[True], np.diff(z) != 0])
    s_read, z_read = s[read], z[read]
    if s_read.size < 5:
        return lambda at_m: np.interp(at_m, s_read, z_read)
    spline = make_smoothing_spline(s_read, z_read, lam=s_read.size / (s[-1] - s[0]) * scale_m**4)
    return lambda at_m: spline(np.clip(at_m, s_read[0], s_read[-1]))


def _bin_quantile(bins: np.ndarray, z: np.ndarray, count: int, quantile: float) -> tuple[np.ndarray, np.ndarray]:
    """Per bin, the given quantile of its values (linear between order statistics, as
    numpy's default) and the number of values; NaN for an empty bin."""
    order = np.lexsort((z, bins))
    z_sorted = z[order]
    counts = np.bincount(bins, minlength=count)
    first = np.concatenate([[0], np.cumsum(counts)[:-1]])
    full = counts > 0
    position = quantile * (counts[full] - 1)
    low = np.floor(position).astype(int)
    high = np.minimum(low + 1, counts[full] - 1)
    frac = position - low
    values = np.full(count, np.nan)
    values[full] = (1 - frac) * z_sorted[first[full] + low] + frac * z_sorted[first[full] + high]
    return values, counts


def _fill_gaps(s: np.ndarray, z: np.ndarray, max_gap_m: float, source: str, what: str,
               xy: tuple[np.ndarray, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """Bridge each stretch without data no longer than ``max_gap_m``: between two samples
    with data by a straight line, at an end of the route by the nearest sample's elevation.
    A stretch is measured between the samples with data on either side (at an end, from the
    end's sample to the first with data). Returns z and the stretches bridged, shape (G, 2)."""
    missing = ~np.isfinite(z)
    if not missing.any():
        return z, np.zeros((0, 2))
    if missing.all():
        raise InputError(f"{source}: {what} anywhere along the track; check that the terrain covers the track "
                         "(and the CRS of both)")
    edges = np.flatnonzero(np.diff(np.concatenate([[0], missing.astype(np.int8), [0]])))
    gaps = []
    for first, stop in edges.reshape(-1, 2):  # [first missing, first present after] per run
        start_m = s[first - 1] if first > 0 else s[0]
        end_m = s[stop] if stop < s.size else s[-1]
        if end_m - start_m > max_gap_m * (1 + 1e-9):
            where = "at the start" if first == 0 else "at the end" if stop == s.size else "between samples with data"
            raise InputError(
                f"{source}: {what} from s = {s[first]:.2f} to {s[stop - 1]:.2f} m along the track "
                f"(x = {xy[0][first]:.2f}, y = {xy[1][first]:.2f}), a stretch of {end_m - start_m:.2f} m {where}, "
                f"longer than max_gap_m = {max_gap_m:g} m; cut the track there, give terrain that covers it, or raise "
                "max_gap_m (a straight line is then assumed across it)")
        gaps.append((start_m, end_m))
    filled = z.copy()
    filled[missing] = np.interp(s[missing], s[~missing], z[~missing])  # flat beyond the ends
    return filled, np.array(gaps)


def _check_options(spacing_m: float | None, corridor_m: float, max_gap_m: float) -> None:
    for name, value in (("spacing_m", DEFAULT_TRACK_SPACING_M if spacing_m is None else spacing_m),
                        ("corridor_m", corridor_m)):
        if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
            raise InputError(f"{name} = {value!r} m: must be a number > 0")
    if not (isinstance(max_gap_m, (int, float)) and math.isfinite(max_gap_m) and max_gap_m >= 0):
        raise InputError(f"max_gap_m = {max_gap_m!r} m: must be a number >= 0")


def _crs_label(crs: Any) -> str:
    if crs is None:
        return ""
    epsg = crs.to_epsg()
    return f"{crs.name} (EPSG:{epsg})" if epsg else crs.name


def _project(track: "Track", terrain: Any, terrain_source: str) -> tuple[np.ndarray, np.ndarray, Any, list[str]]:
    """The track's x, y in metres in the terrain's CRS (or a local one), that CRS and notes."""
    from ..io.tracks import local_projected_crs, project_track

    notes: list[str] = []
    if terrain is None:
        if track.crs is None:
            return track.x, track.y, None, notes
        target = local_projected_crs(track) if track.crs.is_geographic else track.crs
        moved = project_track(track, target)
        if not track.crs.is_geographic:
            notes += moved.notes[len(track.notes):]
        else:
            notes.append(f"{track.source}: projected into {_crs_label(target)}, the UTM zone of its mean position "
                         f"(longitude {np.mean(track.x):.4f}, latitude {np.mean(track.y):.4f})")
        return moved.x, moved.y, target, notes
    crs = getattr(terrain, "crs", None)
    if crs is None:
        if track.crs is not None:
            raise InputError(f"{terrain_source}: states no CRS, so the track ({track.source}, {_crs_label(track.crs)}) "
                             "cannot be placed on it; pass terrain_crs (e.g. EPSG:32633)")
        return track.x, track.y, None, notes
    if track.crs is None:
        from ..io.geo import length_units_m

        unit_m = length_units_m(crs, terrain_source)[0]
        notes.append(f"{track.source}: the track states no CRS; its x, y are taken in the terrain's "
                     f"({_crs_label(crs)}" + (f", in its unit of {unit_m:g} m" if unit_m != 1.0 else "")
                     + "); give track_crs if they are not")
        return track.x * unit_m, track.y * unit_m, crs, notes
    moved = project_track(track, crs)
    notes += moved.notes[len(track.notes):]
    return moved.x, moved.y, crs, notes


def track_on_terrain_m(track: "Track", crs: Any, source: str) -> tuple[np.ndarray, np.ndarray]:
    """The track's x, y (m) on a terrain in ``crs``, placed as :func:`route_from_track` places
    it (projected into the terrain's CRS; a track without a CRS taken in the terrain's).

    Parameters
    ----------
    track : Track
        The track (:func:`profileopt.io.read_track`).
    crs : pyproj.CRS or None
        The terrain's CRS (None: it states none).
    source : str
        The terrain file, for messages.

    Returns
    -------
    x_m, y_m : numpy.ndarray, shape (K,)
        The track's points (m).

    Raises
    ------
    InputError
        The track has a CRS and the terrain none.
    """
    from types import SimpleNamespace

    x, y, _, _ = _project(track, SimpleNamespace(crs=crs), source)
    return np.asarray(x, dtype=float), np.asarray(y, dtype=float)


def route_from_track(track: "Track", terrain: Any = None, *, spacing_m: float | None = None,
                     corridor_m: float = DEFAULT_CORRIDOR_M, max_gap_m: float = DEFAULT_MAX_GAP_M,
                     assumed_roughness: Any = None) -> TrackRoute:
    """The route a vehicle drives along ``track``: samples every ``spacing_m`` with the
    ground's elevation under the wheels.

    Parameters
    ----------
    track : Track
        The path (:func:`profileopt.io.read_track`).
    terrain : PointCloud, ElevationGrid, CrgSurface or None, default None
        The ground (:func:`profileopt.io.read_terrain`); None takes the track's own
        elevations (GPX ``<ele>``), which never measure roughness.
    spacing_m : float, optional
        Distance between samples along the track (m), > 0. None (the default) chooses the
        finest spacing the terrain resolves (:func:`supported_spacing_m`): a cloud's density
        in the corridor or a grid's cells, from
        :data:`~profileopt.defaults.DEFAULT_TRACK_SPACING_M` up to
        :data:`~profileopt.defaults.MAX_ROUGHNESS_SPACING_M` (the wheel radius), with a note
        when it is not the former; a terrain too coarse for any of them, and no terrain,
        get :data:`~profileopt.defaults.DEFAULT_TRACK_SPACING_M`.
    corridor_m : float, default :data:`~profileopt.defaults.DEFAULT_CORRIDOR_M`
        Half-width of the strip around the wheel path whose ground points a point cloud
        contributes (m), > 0.
    max_gap_m : float, default :data:`~profileopt.defaults.DEFAULT_MAX_GAP_M`
        Longest stretch without data that is bridged by a straight line (m), >= 0.
    assumed_roughness : AssumedRoughness, optional
        The roughness to plan with where the terrain cannot measure it (an ISO 8608 class
        or an RI); recorded on the route. Without it, a terrain too coarse for the spacing
        is refused.

    Returns
    -------
    TrackRoute

    Raises
    ------
    InputError
        A bad option; a track in another CRS than a terrain that states none; a track
        outside the terrain; a gap longer than ``max_gap_m``; a terrain too coarse to
        measure roughness at the spacing and no assumed roughness; a track without
        elevations and no terrain. Each is one line naming the file and the place.
    """
    _check_options(spacing_m, corridor_m, max_gap_m)
    terrain_source = getattr(terrain, "source", None) or getattr(getattr(terrain, "header", None), "path", "terrain")
    tx, ty, crs, notes = _project(track, terrain, terrain_source)
    chosen = spacing_m is None
    spacing_m = DEFAULT_TRACK_SPACING_M if chosen else float(spacing_m)
    s, x, y = resample_polyline(tx, ty, spacing_m)
    if s.size < 2:
        raise InputError(f"{track.source}: the track is {s[-1]:.3g} m long; a route needs at least two samples")
    if terrain is not None:
        _check_extent(terrain, terrain_source, track.source, s, x, y, crs,
                      track.crs is not None and track.crs.to_epsg() == 4326, max_gap_m)
        if chosen:
            spacing_m, note = _choose_spacing(terrain, terrain_source, s, x, y, corridor_m, max_gap_m)
            if note:
                notes.append(note)
                s, x, y = resample_polyline(tx, ty, spacing_m)
    frame = _crs_label(crs) or "the track's own frame (no CRS)"
    comments = [f"track: {track.source} ({tx.size} points, {s[-1]:.1f} m)", f"x, y: {frame}, in metres; z in metres"]
    density = None
    if terrain is None:
        kind = "track"
        if track.z_m is None:
            raise InputError(f"{track.source}: the track has no elevations (GPX <ele>, a z column); give a terrain "
                             "map (--terrain) for the ground's elevation")
        along = path_distance_m(tx, ty)
        if tx.size >= 5:
            z = smooth_track_elevations(along, track.z_m)(s)
            how = (f"smoothed over about {GPS_ELEVATION_SCALE_M:g} m (a spline; GPS elevations are noisy by metres; "
                   "repeated readings, a frozen altimeter, left out)")
        else:
            z = np.interp(s, along, track.z_m)
            how = "linear between them (too few to smooth)"
        measured = False
        resolution = (f"the track's own elevations, one every {along[-1] / max(tx.size - 1, 1):.3g} m: "
                      "they measure the grade, not the ground's roughness")
        comments.append(f"z: the track's own elevations, {how}")
    elif hasattr(terrain, "classification"):
        kind = "point cloud"
        z, measured, density, resolution, more = _sample_cloud(terrain, terrain_source, s, x, y, spacing_m,
                                                               corridor_m, assumed_roughness is not None, max_gap_m)
        comments += more
        if not terrain.is_classified:
            notes.append(f"{terrain_source}: the cloud is not classified (no ground class): each sample takes the "
                         f"{100 * UNCLASSIFIED_QUANTILE:g}th percentile of its points, as vegetation lies above the "
                         "ground; classify it (e.g. PDAL filters.smrf) for a trustworthy profile")
    else:
        kind = "OpenCRG" if hasattr(terrain, "u_m") else "DEM"
        z, measured, resolution, more = _sample_grid(terrain, terrain_source, kind, x, y, spacing_m)
        comments += more
    if not measured and assumed_roughness is None:
        raise InputError(f"{terrain_source if terrain is not None else track.source}: {resolution}; give an assumed "
                         "roughness, roughness_class A-H (ISO 8608) or ri VALUE (an RI), or a terrain that resolves it")
    if measured and assumed_roughness is not None:
        notes.append(f"{terrain_source}: the terrain measures the roughness at wheel scale, so the assumed "
                     f"{assumed_roughness.label} is not used (to plan with it anyway, plan the route file with "
                     + (f"roughness_class {assumed_roughness.road_class})" if assumed_roughness.road_class
                        else "ri VALUE)"))
        assumed_roughness = None
    if terrain is not None and track.z_m is not None:
        notes.append(f"{track.source}: the track's own elevations are ignored; the terrain gives z")
    what = "no ground points within the corridor" if kind == "point cloud" else "no terrain data"
    z, gaps = _fill_gaps(s, z, max_gap_m, terrain_source if terrain is not None else track.source, what, (x, y))
    if gaps.size:
        lengths = gaps[:, 1] - gaps[:, 0]
        worst = int(np.argmax(lengths))
        text = (f"{len(gaps)} gap(s) without data bridged by straight lines, {lengths.sum():.2f} m in all, the "
                f"longest {lengths[worst]:.2f} m at s = {gaps[worst, 0]:.2f} m")
        comments.append(f"gaps: {text}")
        notes.append(f"{terrain_source}: {text}")
    if assumed_roughness is not None:
        comments.append(f"roughness: assumed ({assumed_roughness.label}), not measured; {resolution}")
    limit = None
    if track.speed_limit_mps is not None:
        # a track point's limit holds to the next point; a sample on a piece of the track gets that
        # piece's limit, and a sample at a point the lower of the two pieces meeting there
        along = path_distance_m(tx, ty)
        piece = np.clip(np.searchsorted(along, s, side="right") - 1, 0, tx.size - 2)
        before = np.clip(np.searchsorted(along, s, side="left") - 1, 0, tx.size - 2)
        limit = np.minimum(track.speed_limit_mps[piece], track.speed_limit_mps[before])
        comments.append("speed_limit_mps: the track's speed_limit, each from its point to the next")
    # s as every x,y route has it (profileopt.io.read_route): the horizontal distance between the samples,
    # so that the route written and read back is this one, float for float
    s_route = path_distance_m(x, y)
    route = Route(s_m=s_route, z_m=z, x_m=x, y_m=y, speed_limit_mps=limit, source=track.source,
                  assumed_roughness=assumed_roughness)
    return TrackRoute(route=route, crs_name=_crs_label(crs), track_x_m=np.asarray(tx), track_y_m=np.asarray(ty),
                      terrain_kind=kind, roughness_measured=measured, density_per_m2=density, resolution=resolution,
                      gaps_m=gaps.reshape(-1, 2), comments=tuple(comments), notes=tuple(notes),
                      terrain=terrain, spacing_m=spacing_m)


def _extent(terrain: Any) -> tuple[float, float, float, float]:
    """(x min, x max, y min, y max) of a terrain's data in its file (m), also where only the
    part around the track was read."""
    whole = getattr(terrain, "file_extent_m", None)
    return tuple(float(v) for v in (whole if whole is not None else terrain.extent_m()))


def _choose_spacing(terrain: Any, source: str, s: np.ndarray, x: np.ndarray, y: np.ndarray,
                    corridor_m: float, max_gap_m: float) -> tuple[float, str | None]:
    """The spacing to sample a terrain at when none is given (:func:`supported_spacing_m`) and a
    note saying which when it is not the default."""
    if hasattr(terrain, "classification"):
        _, _, density = _corridor_points(terrain, source, s, x, y, DEFAULT_TRACK_SPACING_M, corridor_m)
        spacing = cloud_spacing_m(density, corridor_m, float(s[-1]), max_gap_m)
        if spacing is None or spacing == DEFAULT_TRACK_SPACING_M:
            return DEFAULT_TRACK_SPACING_M, None
        return spacing, (f"{source}: samples every {spacing:g} m, the finest spacing at which its {density:.3g} "
                         f"ground points per m^2 (within {corridor_m:g} m of the track) measure the roughness "
                         f"({MIN_POINTS_PER_BIN:g} or more per bin, few gaps over max_gap_m {max_gap_m:g}); "
                         "spacing_m sets another")
    if hasattr(terrain, "u_m"):
        resolution = float(terrain.u_m[1] - terrain.u_m[0])
        what = f"its cells ({resolution:g} m along the reference line)"
    else:
        resolution = float(max(terrain.cell_size_m))
        what = f"its cells ({terrain.cell_size_m[0]:g} m x {terrain.cell_size_m[1]:g} m)"
    spacing = supported_spacing_m(resolution)
    if spacing is None or spacing == DEFAULT_TRACK_SPACING_M:
        return DEFAULT_TRACK_SPACING_M, None
    return spacing, f"{source}: samples every {spacing:g} m, the finest spacing {what} resolve; spacing_m sets another"


def _check_extent(terrain: Any, source: str, track_source: str, s: np.ndarray, x: np.ndarray, y: np.ndarray,
                  crs: Any, track_is_wgs84: bool, max_gap_m: float) -> None:
    """Refuse a track that leaves the terrain's bounding box by more than ``max_gap_m`` + 1 m,
    naming where (a shorter excursion is a gap without data, bridged or refused as such)."""
    x0, x1, y0, y1 = _extent(terrain)
    pad = max_gap_m + 1.0
    outside = (x < x0 - pad) | (x > x1 + pad) | (y < y0 - pad) | (y > y1 + pad)
    if not outside.any():
        return
    box = f"x {x0:.1f} to {x1:.1f} m, y {y0:.1f} to {y1:.1f} m"
    if outside.all():
        raise InputError(
            f"{track_source}: the track (x {x.min():.1f} to {x.max():.1f} m, y {y.min():.1f} to {y.max():.1f} m"
            f"{', ' + _crs_label(crs) if crs is not None else ''}) lies outside the terrain {source} ({box}); "
            + ("is the terrain's CRS right (terrain_crs)?" if track_is_wgs84 else
               "are the CRS of the track and of the terrain right (track_crs, terrain_crs)?"))
    i = int(np.flatnonzero(outside)[0])
    stop = i + int(np.argmin(outside[i:])) if not outside[i:].all() else s.size
    raise InputError(
        f"{track_source}: the track leaves the terrain {source} ({box}) from s = {s[i]:.1f} to {s[stop - 1]:.1f} m "
        f"(x = {x[i]:.1f}, y = {y[i]:.1f}); cut the track to the terrain or give a terrain that covers it")


def _coarser_than_wheel_scale(spacing_m: float, corridor_m: float | None) -> str | None:
    """Why a route sampled so does not measure wheel-scale roughness, whatever the terrain (None if it does)."""
    reasons = []
    if spacing_m > MAX_ROUGHNESS_SPACING_M * (1 + 1e-9):
        reasons.append(f"samples every {spacing_m:g} m miss the bumps a wheel feels (roughness is measured at a "
                       f"spacing of at most {MAX_ROUGHNESS_SPACING_M:g} m)")
    if corridor_m is not None and corridor_m > MAX_ROUGHNESS_CORRIDOR_M * (1 + 1e-9):
        reasons.append(f"a corridor of {corridor_m:g} m each side averages ground the tyre does not touch (roughness "
                       f"is measured within at most {MAX_ROUGHNESS_CORRIDOR_M:g} m of the wheel path)")
    return "; ".join(reasons) or None


def _ground(cloud: Any, source: str) -> tuple[bool, np.ndarray, np.ndarray, np.ndarray]:
    """Whether the cloud is classified, and x, y, z (m) of its ground points (all its points
    if it is not classified)."""
    if len(cloud) == 0:
        within = getattr(cloud, "kept_within_m", None)
        raise InputError(f"{source}: the cloud has no points " + (f"within {within:.3g} m of the track" if within
                                                                   else "at all")
                         + "; check that it covers the track (and the CRS of both)")
    classified = bool(cloud.is_classified)
    ground = cloud.classification == _GROUND if classified else np.ones(len(cloud), dtype=bool)
    if classified and not ground.any():
        raise InputError(f"{source}: the cloud is classified but has no ground points (class 2); classify its ground "
                         "(e.g. PDAL filters.smrf)")
    return classified, cloud.x_m[ground], cloud.y_m[ground], cloud.z_m[ground]


def _corridor_points(cloud: Any, source: str, s: np.ndarray, x: np.ndarray, y: np.ndarray, spacing_m: float,
                     corridor_m: float) -> tuple[np.ndarray, np.ndarray, float]:
    """The ground points in each sample's bin: their z (m), their sample index, and the density
    of ground points within the corridor (per m^2)."""
    within = getattr(cloud, "kept_within_m", None)
    reach = corridor_m + spacing_m  # a bin's points lie within the corridor and half a (last, longer) step
    if within is not None and reach > within * (1 + 1e-9):
        raise InputError(f"{source}: only the points within {within:g} m of the track were read, and spacing_m "
                         f"{spacing_m:g} with corridor_m {corridor_m:g} needs more; read the terrain with the same "
                         "spacing_m and corridor_m (read_terrain)")
    _, gx, gy, gz = _ground(cloud, source)
    near = ((gx >= x.min() - reach) & (gx <= x.max() + reach) & (gy >= y.min() - reach) & (gy <= y.max() + reach))
    kept, bins = corridor_bins(np.column_stack([gx[near], gy[near]]), np.column_stack([x, y]), corridor_m)
    return gz[near][kept], bins, kept.size / (2.0 * corridor_m * s[-1])


def _sample_cloud(cloud: Any, source: str, s: np.ndarray, x: np.ndarray, y: np.ndarray, spacing_m: float,
                  corridor_m: float, assumed: bool, max_gap_m: float = DEFAULT_MAX_GAP_M
                  ) -> tuple[np.ndarray, bool, float, str, list[str]]:
    """Elevation of each sample from a point cloud: (z, roughness measured, density, resolution, comments)."""
    classified, gx, gy, gz = _ground(cloud, source)
    binned_z, bins, density = _corridor_points(cloud, source, s, x, y, spacing_m, corridor_m)
    stations = np.column_stack([x, y])
    needed = MIN_POINTS_PER_BIN / _points_per_bin(1.0, corridor_m, spacing_m)  # per m^2
    dense = _points_per_bin(density, corridor_m, spacing_m) >= MIN_POINTS_PER_BIN * (1 - 1e-12)
    coarse = _coarser_than_wheel_scale(spacing_m, corridor_m)
    measured = dense and coarse is None
    statistic = "median" if classified else f"{100 * UNCLASSIFIED_QUANTILE:g}th percentile"
    which = "ground points (class 2)" if classified else "points (the cloud is not classified)"
    found = (f"{density:.3g} {which} per m^2 within {corridor_m:g} m of the track; roughness at {spacing_m:g} m "
             f"needs {needed:.3g} per m^2 ({MIN_POINTS_PER_BIN:g} per {2 * corridor_m:g} m x {spacing_m:g} m bin)")
    if not dense:
        resolution_m = _cloud_resolution_m(density, corridor_m)
        works = cloud_spacing_m(density, corridor_m, float(s[-1]), max_gap_m)
        found += (f"; spacing_m {works:g} measures it" if works is not None else
                  f"; no spacing up to the wheel scale ({MAX_ROUGHNESS_SPACING_M:g} m) measures it ("
                  f"{MIN_POINTS_PER_BIN:g} points per bin would need bins {resolution_m:.2g} m long)")
    resolution = "; ".join(([] if dense else [found]) + ([coarse] if coarse else [])) or found
    if not measured and not assumed:  # refused by the caller with this resolution
        return np.full(s.size, np.nan), False, density, resolution, []
    if dense:
        quantile = 0.5 if classified else UNCLASSIFIED_QUANTILE
        z, _ = _bin_quantile(bins, binned_z, s.size, quantile)
        comments = [f"z: {statistic} of the {which} within {corridor_m:g} m of the wheel path, in bins of "
                    f"{spacing_m:g} m along it; {found}"]
        return z, measured, density, resolution, comments
    if not classified:
        raise InputError(f"{source}: the cloud is not classified and too sparse for roughness ({found}): a surface "
                         "through all its points would run over vegetation; classify its ground first (e.g. PDAL "
                         "filters.smrf)")
    # too sparse for roughness, which is assumed: the ground's shape from its triangulation
    from scipy.interpolate import LinearNDInterpolator
    from scipy.spatial import cKDTree

    # the ground points within a few point spacings (at least 5 m) of the track: enough to
    # surround every sample with triangles
    # (the density of the whole file's ground, the same whether or not only the points near
    # the track were read)
    whole = getattr(cloud, "ground_density_per_m2", None)
    spread = _sparse_neighbourhood_m(whole if whole is not None else gz.size / max(np.ptp(gx) * np.ptp(gy), 1e-9))
    kept = getattr(cloud, "kept_within_m", None)
    if kept is not None:  # no further than the points read (of a cloud whose ground is a small share)
        spread = min(spread, kept - 1.0)
    distance, _ = cKDTree(stations).query(np.column_stack([gx, gy]), distance_upper_bound=spread)
    wide = np.flatnonzero(np.isfinite(distance))
    if wide.size < 3:
        return np.full(s.size, np.nan), False, density, resolution, []
    surface = LinearNDInterpolator(np.column_stack([gx[wide], gy[wide]]), gz[wide])
    z = surface(x, y)
    comments = [f"z: linear over the triangulation of the {which} within {spread:.3g} m of the track"]
    return z, False, density, resolution, comments


def _sample_grid(grid: Any, source: str, kind: str, x: np.ndarray, y: np.ndarray, spacing_m: float
                 ) -> tuple[np.ndarray, bool, str, list[str]]:
    """Elevation of each sample from a DEM or an OpenCRG surface: (z, roughness measured,
    resolution, comments)."""
    z = grid.elevation_at(x, y)
    if kind == "OpenCRG":
        cell = float(grid.u_m[1] - grid.u_m[0])
        cell_text = f"{cell:g} m along its reference line"
    else:
        cell = float(max(grid.cell_size_m))
        cell_text = f"{grid.cell_size_m[0]:g} m x {grid.cell_size_m[1]:g} m"
    coarse = _coarser_than_wheel_scale(spacing_m, None)
    fine = cell <= spacing_m * (1 + 1e-9)
    measured = fine and coarse is None
    found = (f"the {kind}'s cells are {cell_text}: it has no data on ground features smaller than that, and "
             f"roughness at {spacing_m:g} m needs cells of at most {spacing_m:g} m")
    resolution = "; ".join(([] if fine else [found]) + ([coarse] if coarse else [])) or found
    comments = [f"z: bilinear between the {kind}'s cells ({cell_text})"]
    if not fine:
        comments[0] += f"; samples every {spacing_m:g} m interpolate between cells, no detail below the cell size"
    return z, measured, resolution, comments
