"""A route cut into segments: stations, the samples of each segment and its terrain numbers.

Segment i covers s_i <= s < s_{i+1} (the last one closed); which samples that is, is
decided in one place, :mod:`profileopt.stations`. Segments are the planning resolution
only: the roughness is measured over sliding *roughness windows* of a fixed length W
(:func:`profileopt.terrain.roughness_windows`), wherever the segments fall, and a
segment's admissible speeds are those admissible for every window that shares a point
with it. So each segment carries the least and the largest RI (Eq. 1, detrended) of those
windows, and the worst-case elevation e_max of Eq. (8) of the largest. A route with an
assumed roughness (:attr:`profileopt.route.Route.assumed_roughness`) keeps its windows'
places but every window gets the assumed RI (:func:`route_roughness_windows`).
"""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING

import numpy as np

from ..defaults import DEFAULT_ROUGHNESS_WINDOW_M, DEFAULT_SEGMENT_LENGTH_M
from ..errors import InputError
from ..stations import segment_samples
from ..terrain import RoughnessWindows, range_extremes, roughness_windows, worst_case_elevation

if TYPE_CHECKING:
    from ..route import Route
    from ..vehicle import Vehicle

__all__ = ["Segments", "segment_route", "segments_at", "refine_segments", "route_roughness_windows",
           "roughness_source", "MIN_SAMPLES_PER_SEGMENT", "DEFAULT_SEGMENT_LENGTH_M", "DEFAULT_ROUGHNESS_WINDOW_M",
           "REFINE_RI_TOLERANCE", "REFINE_AT_CAP", "at_force_cap", "at_cap", "stretch_cuts"]

#: Samples a segment must hold: the roughness comes from the windows, but the simulator
#: (verify) measures each segment's own samples.
MIN_SAMPLES_PER_SEGMENT = 2

#: :func:`refine_segments` cuts a segment where the RI range of the windows met between two
#: samples departs by more than this fraction from the range where the piece began.
REFINE_RI_TOLERANCE = 0.02
#: With ``refine``, the segments whose minimum-time speed comes within this fraction of
#: their band's top, where the force sets it, are the ones cut (where the speed is below
#: it, or a speed cap holds it, the roughness does not decide the plan there).
REFINE_AT_CAP = 0.02


@dataclasses.dataclass(frozen=True, eq=False)
class Segments:
    """A route cut into segments, with each segment's samples and roughness.

    Attributes
    ----------
    boundaries_m : numpy.ndarray, shape (N+1,)
        Segment boundaries s_i (m); segment i covers s_i <= s < s_{i+1}, the last one closed.
    length_m : numpy.ndarray, shape (N,)
        Segment lengths (m).
    ri : numpy.ndarray, shape (N,)
        The largest detrended RI of the roughness windows that share a point with each
        segment (dimensionless).
    ri_min : numpy.ndarray, shape (N,)
        The least RI of those windows (dimensionless).
    e_max_m : numpy.ndarray, shape (N,)
        Worst-case elevation of Eq. (8) of ``ri`` (m).
    first_sample : numpy.ndarray of int, shape (N,)
        Index of each segment's first route sample.
    samples : numpy.ndarray of int, shape (N,)
        Number of route samples in each segment.
    windows : RoughnessWindows
        Every roughness window of the route, with its RI (``windows.overlapping(
        boundaries_m[:-1], boundaries_m[1:])`` gives the ones each segment meets).
    notes : tuple of str
        Decisions taken while segmenting (e.g. a short tail merged into its neighbour).
    """

    boundaries_m: np.ndarray
    length_m: np.ndarray
    ri: np.ndarray
    ri_min: np.ndarray
    e_max_m: np.ndarray
    first_sample: np.ndarray
    samples: np.ndarray
    windows: RoughnessWindows
    notes: tuple[str, ...] = ()

    @property
    def roughness_window_m(self) -> float:
        """The roughness window length W (m)."""
        return self.windows.window_m

    @property
    def count(self) -> int:
        """Number of segments N."""
        return int(self.length_m.size)


def segment_route(route: "Route", vehicle: "Vehicle", segment_length_m: float = DEFAULT_SEGMENT_LENGTH_M,
                  *, roughness_window_m: float = DEFAULT_ROUGHNESS_WINDOW_M) -> Segments:
    """Cut a route into segments of ``segment_length_m`` and find the roughness windows
    each one meets.

    Parameters
    ----------
    route : Route
        The terrain samples.
    vehicle : Vehicle
        Supplies h (for the RI) and Pe (for e_max).
    segment_length_m : float, default 5
        Segment length (m), > 0 and at most the route's length: the planning resolution.
        The last segment takes what is left; if that tail holds fewer than
        ``MIN_SAMPLES_PER_SEGMENT`` samples it is merged into the segment before it (noted
        in ``Segments.notes``).
    roughness_window_m : float, default 5
        Roughness window length W (m), > 0 and at most the route's length; each window
        needs :data:`profileopt.terrain.MIN_SAMPLES_PER_WINDOW` samples.

    Returns
    -------
    Segments

    Raises
    ------
    InputError
        A bad segment or window length, or a segment or window with too few samples (the
        message says what sample spacing is needed).
    """
    length = float(segment_length_m)
    total = route.length_m
    if not (math.isfinite(length) and length > 0):
        raise InputError(f"segment_length_m = {segment_length_m!r} m: must be a number > 0")
    if length > total * (1 + 1e-12):
        raise InputError(
            f"segment_length_m = {length:g} m is longer than the route {route.source} ({total:g} m); "
            "choose a shorter segment length"
        )
    s = route.s_m
    notes: tuple[str, ...] = ()
    windows = route_roughness_windows(route, vehicle, window_m=roughness_window_m)
    if windows.window_m < float(roughness_window_m):
        notes = (f"the route ({total:g} m) is shorter than the {float(roughness_window_m):g} m roughness window: its "
                 "RI is that of the whole route",)
    source = roughness_source(route, windows)
    if route.assumed_roughness is not None and route.assumed_roughness.road_class is None:
        notes += (f"roughness assumed, not measured: RI {source['ri']:.4g} given for every {windows.window_m:g} m "
                  "window",)
    elif route.assumed_roughness is not None:
        notes += (f"roughness assumed, not measured: {source['label']}, RI {source['ri']:.4g} over "
                  f"{windows.window_m:g} m windows for this vehicle",)
    if total / length > s.size:  # more segments than samples: refuse before allocating them
        raise InputError(
            f"segment_length_m = {length:g} m cuts {route.source} ({total:g} m, {s.size} samples) into more "
            f"segments than it can fill with {MIN_SAMPLES_PER_SEGMENT} samples each; use at least "
            f"{MIN_SAMPLES_PER_SEGMENT * total / s.size:.3g} m"
        )
    n_full = max(int(math.floor(total / length + 1e-9)), 1)
    bounds = s[0] + length * np.arange(n_full + 1)
    if total - n_full * length > 1e-9 * max(total, 1.0):
        bounds = np.append(bounds, s[-1])
    bounds[-1] = s[-1]
    starts, stops = segment_samples(s, bounds)
    counts = stops - starts
    if counts.size > 1 and counts[-1] < MIN_SAMPLES_PER_SEGMENT:
        notes += (
            f"the last {bounds[-1] - bounds[-2]:.3g} m hold only {counts[-1]} samples; "
            "merged into the segment before them",
        )
        bounds = np.delete(bounds, -2)
        starts, stops = segment_samples(s, bounds)
        counts = stops - starts
    thin = np.flatnonzero(counts < MIN_SAMPLES_PER_SEGMENT)
    if thin.size:
        i = thin[0]
        raise InputError(
            f"{route.source}: segment {i} ({bounds[i]:g} to {bounds[i + 1]:g} m) holds {counts[i]} samples; "
            f"a segment must hold at least {MIN_SAMPLES_PER_SEGMENT}: raise segment_length_m above the "
            "route's sample spacing"
        )
    return segments_at(bounds, windows, vehicle, starts=starts, stops=stops, notes=notes)


def route_roughness_windows(route: "Route", vehicle: "Vehicle", *, window_m: float) -> RoughnessWindows:
    """The route's roughness windows (:func:`profileopt.terrain.roughness_windows`) with the
    RI the planner uses: the measured one, or for a route with an assumed roughness, the
    assumed RI in every window (the windows' places stay those of the route's samples).

    Parameters
    ----------
    route : Route
        The terrain samples, and ``assumed_roughness`` if any.
    vehicle : Vehicle
        Supplies the ground clearance h (m).
    window_m : float
        Roughness window length W (m), > 0; a route shorter than W is one window.

    Returns
    -------
    RoughnessWindows
    """
    windows = roughness_windows(route.s_m, route.z_m, vehicle.ground_clearance_m, window_m=window_m,
                                source=route.source)
    if route.assumed_roughness is None:
        return windows
    ri = route.assumed_roughness.ri_for(clearance_m=vehicle.ground_clearance_m, window_m=windows.window_m)
    return dataclasses.replace(windows, ri=np.full(windows.count, ri))


def roughness_source(route: "Route", windows: RoughnessWindows) -> dict:
    """Where a plan's roughness comes from, for :meth:`profileopt.planning.Profile.summary`.

    Parameters
    ----------
    route : Route
        The route planned.
    windows : RoughnessWindows
        Its windows as planned (:func:`route_roughness_windows`).

    Returns
    -------
    dict
        ``{"source": "measured"}``, or ``{"source": "assumed", "label": ..., "ri": ...,
        "window_m": ...}`` with the assumed roughness's label, the RI every window got
        (dimensionless) and the window length W (m).
    """
    if route.assumed_roughness is None:
        return {"source": "measured"}
    return {"source": "assumed", "label": route.assumed_roughness.label, "ri": float(windows.ri[0]),
            "window_m": float(windows.window_m)}


def segments_at(boundaries_m: np.ndarray, windows: RoughnessWindows, vehicle: "Vehicle", *, starts: np.ndarray,
                stops: np.ndarray, notes: tuple[str, ...] = ()) -> Segments:
    """The segments between given boundaries, with the RI range of the windows each meets.

    Parameters
    ----------
    boundaries_m : numpy.ndarray, shape (N+1,)
        Segment boundaries (m), increasing, within the route.
    windows : RoughnessWindows
        The route's roughness windows (:func:`profileopt.terrain.roughness_windows`).
    vehicle : Vehicle
        Supplies Pe and h (for e_max).
    starts, stops : numpy.ndarray of int, shape (N,)
        Each segment's route samples (:func:`profileopt.stations.segment_samples`).
    notes : tuple of str, default ()

    Returns
    -------
    Segments
    """
    bounds = np.asarray(boundaries_m, dtype=float)
    window_first, window_stop = windows.overlapping(bounds[:-1], bounds[1:])
    ri_min, ri = range_extremes(windows.ri, window_first, window_stop)
    return Segments(
        boundaries_m=bounds,
        length_m=np.diff(bounds),
        ri=ri,
        ri_min=ri_min,
        e_max_m=worst_case_elevation(ri, vehicle),
        first_sample=starts,
        samples=stops - starts,
        windows=windows,
        notes=notes,
    )


def at_force_cap(greatest_b: np.ndarray, band_top_mps: np.ndarray, cap_mps: np.ndarray) -> np.ndarray:
    """The segments ``refine`` cuts: where the minimum-time profile comes within
    :data:`REFINE_AT_CAP` of the band's top and the force, not a speed cap, sets that top.

    Parameters
    ----------
    greatest_b : numpy.ndarray, shape (N+1,)
        The minimum-time profile's v^2 at the boundaries (m^2/s^2).
    band_top_mps : numpy.ndarray, shape (N,)
        Top of each segment's chosen band (m/s), speed caps included.
    cap_mps : numpy.ndarray, shape (N,)
        Each segment's speed cap (m/s): top speed, speed limits, turns.

    Returns
    -------
    numpy.ndarray of bool, shape (N,)
    """
    return at_cap(greatest_b, band_top_mps) & (band_top_mps < cap_mps * (1.0 - 1e-9))


def at_cap(greatest_b: np.ndarray, cap_mps: np.ndarray) -> np.ndarray:
    """The segments where the minimum-time profile comes within :data:`REFINE_AT_CAP` of
    ``cap_mps`` at either boundary.

    Parameters
    ----------
    greatest_b : numpy.ndarray, shape (N+1,)
        The minimum-time profile's v^2 at the boundaries (m^2/s^2).
    cap_mps : numpy.ndarray, shape (N,)
        A speed cap of each segment (m/s).

    Returns
    -------
    numpy.ndarray of bool, shape (N,)
    """
    top_b = np.maximum(greatest_b[:-1], greatest_b[1:])
    return top_b >= (1.0 - REFINE_AT_CAP) ** 2 * np.asarray(cap_mps, dtype=float) ** 2


def stretch_cuts(segments: Segments, positions_m: np.ndarray, held_cap_mps: np.ndarray, start_m: np.ndarray,
                 end_m: np.ndarray, cap_mps: np.ndarray) -> np.ndarray:
    """The samples at which to cut the held segments so that only one piece of each shares a
    point with the stretch [start_m, end_m] that sets its cap: the last sample before each
    stretch and the first after it, where that sample lies inside a segment held at that
    stretch's cap, moved away from the stretch as far as both pieces need to keep
    :data:`MIN_SAMPLES_PER_SEGMENT` samples.

    A cap that holds every segment sharing a point with a stretch (the step limit's, around a
    ramp of the wheel's path; a speed-limit zone's) then holds that piece only, not the whole
    segment.

    Parameters
    ----------
    segments : Segments
        The route's segments.
    positions_m : numpy.ndarray, shape (M,)
        The route's sample positions s (m), those ``segments`` was cut from.
    held_cap_mps : numpy.ndarray, shape (N,)
        The cap each segment is held at (m/s), NaN where it may not be cut (the planner's:
        where the plan meets a cap of the limit giving the stretches).
    start_m, end_m : numpy.ndarray, shape (R,)
        The stretches' ends (m), start_m <= end_m.
    cap_mps : numpy.ndarray, shape (R,)
        Each stretch's cap (m/s): it cuts only segments held at that cap.

    Returns
    -------
    numpy.ndarray of int, shape (C,)
        Sample indices, increasing, for :func:`refine_segments`' ``cut_at``.
    """
    s = np.asarray(positions_m, dtype=float)
    held_cap = np.asarray(held_cap_mps, dtype=float)
    if held_cap.shape != (segments.count,):
        raise ValueError(f"held_cap_mps has shape {held_cap.shape}; expected ({segments.count},)")
    cap = np.asarray(cap_mps, dtype=float)
    first, count = segments.first_sample, segments.samples

    def within(j: np.ndarray, outward: int) -> np.ndarray:
        # the segment holding sample j (segment k holds samples first_k .. first_k + count_k
        # - 1), held at the stretch's cap; j moved away from the stretch (outward -1: towards
        # the start) until both pieces keep MIN_SAMPLES_PER_SEGMENT samples, dropped where
        # that is impossible
        ok = (j > 0) & (j < s.size)
        j, c = j[ok], cap[ok]
        k = np.searchsorted(first, j, side="right") - 1
        j, c, k = j[k >= 0], c[k >= 0], k[k >= 0]
        a, b = first[k], first[k] + count[k]
        j = np.minimum(j, b - MIN_SAMPLES_PER_SEGMENT) if outward < 0 else np.maximum(j, a + MIN_SAMPLES_PER_SEGMENT)
        sets = np.abs(held_cap[k] - c) <= 1e-12 * c  # NaN (not held) compares false
        return j[sets & (j - a >= MIN_SAMPLES_PER_SEGMENT) & (b - j >= MIN_SAMPLES_PER_SEGMENT)]

    before = np.searchsorted(s, np.asarray(start_m, dtype=float), side="left") - 1  # last s_j < start
    after = np.searchsorted(s, np.asarray(end_m, dtype=float), side="right")  # first s_j > end
    return np.unique(np.concatenate([within(before, -1), within(after, +1)]))


def refine_segments(segments: Segments, positions_m: np.ndarray, vehicle: "Vehicle", marked: np.ndarray, *,
                    tolerance: float = REFINE_RI_TOLERANCE, cut_at: np.ndarray | None = None) -> Segments:
    """Cut the marked segments where the roughness of their windows changes, and every
    segment at the samples ``cut_at``.

    A segment's speeds are held to every window that shares a point with it, so a segment
    that reaches into a rough stretch is held to the rough stretch's speeds over its whole
    length: the travel time converges only to first order in the segment length. Cutting
    a segment where the roughness changes (between two samples, the windows met change)
    lets each piece keep only its own windows. Each marked segment is walked sample by
    sample; a new piece starts at a sample where the least or the largest RI of the windows
    met between it and the next sample departs from the values where the current piece
    began by more than ``tolerance`` (relative), as long as both pieces keep
    :data:`MIN_SAMPLES_PER_SEGMENT` samples. Unmarked segments are kept whole.

    Parameters
    ----------
    segments : Segments
        The route's segments (:func:`segment_route`).
    positions_m : numpy.ndarray, shape (M,)
        The route's sample positions s (m), those ``segments`` was cut from.
    vehicle : Vehicle
        Supplies Pe and h (for e_max).
    marked : numpy.ndarray of bool, shape (N,)
        The segments to cut (the planner marks those where its plan meets the speed cap).
    tolerance : float, default :data:`REFINE_RI_TOLERANCE`
        Relative change of the RI range that starts a new piece, > 0.
    cut_at : numpy.ndarray of int, optional
        Sample indices where a piece starts as well (the planner's :func:`stretch_cuts`),
        where both pieces keep :data:`MIN_SAMPLES_PER_SEGMENT` samples; a segment holding one
        is walked for roughness changes too, marked or not.

    Returns
    -------
    Segments
        The same boundaries and more (every new one at a sample), with each segment's
        windows and RI range found afresh (:func:`segments_at`); ``notes`` unchanged.
    """
    s = np.asarray(positions_m, dtype=float)
    marked = np.asarray(marked, dtype=bool)
    if marked.shape != (segments.count,):
        raise ValueError(f"marked has shape {marked.shape}; expected ({segments.count},)")
    if not (math.isfinite(tolerance) and tolerance > 0):
        raise InputError(f"tolerance = {tolerance!r}: must be a number > 0")
    # the RI range of the windows met between consecutive samples j and j + 1
    first, stop = segments.windows.overlapping(s[:-1], s[1:])
    least_all, largest_all = range_extremes(segments.windows.ri, first, stop)
    del first, stop
    low, high = 1.0 - tolerance, 1.0 + tolerance
    forced = set() if cut_at is None else set(np.asarray(cut_at, dtype=np.intp).tolist())
    marked = marked.copy()
    if forced:  # the segments holding a forced cut
        holder = np.searchsorted(segments.first_sample, sorted(forced), side="right") - 1
        marked[holder[holder >= 0]] = True
    cuts: list[int] = []
    for k in np.flatnonzero(marked):
        a = int(segments.first_sample[k])
        b = a + int(segments.samples[k])  # samples a .. b-1; a piece from sample j holds j .. next-1
        # one segment's values as Python floats (fast to index; the whole route's would take
        # 64 bytes a sample at the peak, a third of a long route's plan)
        least, largest = least_all[a:b].tolist(), largest_all[a:b].tolist()
        start = a
        base_lo, base_hi = least[0], largest[0]
        for j in range(a + MIN_SAMPLES_PER_SEGMENT, b - MIN_SAMPLES_PER_SEGMENT + 1):
            if j - start < MIN_SAMPLES_PER_SEGMENT:
                continue
            lo, hi = least[j - a], largest[j - a]
            if j in forced or hi > base_hi * high or hi < base_hi * low or lo > base_lo * high or lo < base_lo * low:
                cuts.append(j)
                start, base_lo, base_hi = j, lo, hi
    if not cuts:
        return segments
    bounds = np.union1d(segments.boundaries_m, s[np.asarray(cuts, dtype=np.intp)])
    starts, stops = segment_samples(s, bounds)
    return segments_at(bounds, segments.windows, vehicle, starts=starts, stops=stops, notes=segments.notes)
