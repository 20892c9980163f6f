"""The refine round of a plan: which segments to cut after the first choice of bands, and where.

A segment is held to every roughness window and every ramp of the wheel's path that shares a
point with it, so a long segment that reaches into a rough stretch or touches a step is held
to its speeds over its whole length. After the bands are chosen once, the planner cuts

- the segments where the minimum-time profile meets its band's top, set by the force, where
  the roughness of their windows changes (:func:`refine_segments`);
- the segments where it meets a cap set on stretches of the route (a step's, a speed-limit
  zone's, a sharp turn's or a reversal's crawl; :meth:`.limits.Limit.cap_stretches_m`) just outside the stretch that sets it
  (:func:`stretch_cuts`), and where their roughness changes as well: the cap hid
  their band's top, which the pieces off the stretch meet once they are free of it;

then chooses the bands again on the finer segments and solves once. Before the first choice,
it cuts the segments too long for a drive power limit's climb to be planned exactly
(:func:`split_long_segments`, with :meth:`.bands.DrivePower.longest_exact_segment_m`).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Sequence

import numpy as np

from ..core.segments import MIN_SAMPLES_PER_SEGMENT, Segments, segments_at
from ..core.stations import segment_samples
from ..errors import InputError
from ..terrain.roughness import range_extremes
from .limits.base import Limit, PlanContext

if TYPE_CHECKING:
    from ..core.vehicle import Vehicle

__all__ = ["refined_segments", "refine_segments", "stretch_cuts", "at_force_cap", "at_cap", "split_long_segments",
           "can_split_to", "REFINE_RI_TOLERANCE", "REFINE_AT_CAP", "SPLIT_MAX_FACTOR"]

#: :func:`refine_segments` cuts a segment where the RI range of the windows met between two
#: samples departs by more than this fraction from the range where the piece began.
REFINE_RI_TOLERANCE = 0.02
#: With ``refine``, the segments whose minimum-time speed comes within this fraction of
#: their band's top, where the force sets it, are the ones cut (where the speed is below
#: it, or a speed cap holds it, the roughness does not decide the plan there).
REFINE_AT_CAP = 0.02


def refined_segments(limits: Sequence[Limit], context: PlanContext, greatest_b: np.ndarray, band_top_mps: np.ndarray,
                     cap_mps: np.ndarray, cap_source: np.ndarray) -> Segments:
    """The plan's segments cut where the first minimum-time profile meets a cap.

    Parameters
    ----------
    limits : sequence of Limit
        The plan's limits.
    context : PlanContext
        The route, vehicle and segments of the first round.
    greatest_b : numpy.ndarray, shape (N+1,)
        The first round's minimum-time profile, v^2 at the boundaries (m^2/s^2).
    band_top_mps : numpy.ndarray, shape (N,)
        Top of each segment's chosen band (m/s), speed caps included.
    cap_mps : numpy.ndarray, shape (N,)
        Each segment's lowest cap (m/s).
    cap_source : numpy.ndarray of int, shape (N,)
        The index in ``limits`` of the limit giving that cap (-1: none).

    Returns
    -------
    Segments
        ``context.segments`` itself when nothing is cut.
    """
    seg, s_m = context.segments, context.route.s_m
    at = at_cap(greatest_b, cap_mps)
    cuts = []
    for k, limit in enumerate(limits):
        mine = at & (cap_source == k)
        if mine.any() and (stretches := limit.cap_stretches_m(context)) is not None:
            cuts.append(stretch_cuts(seg, s_m, np.where(mine, cap_mps, np.nan), *stretches))
    # refine_segments walks a segment cut at a stretch for roughness changes too (the cap
    # hid its band top)
    return refine_segments(seg, s_m, context.vehicle, at_force_cap(greatest_b, band_top_mps, cap_mps),
                           cut_at=np.concatenate(cuts) if cuts else None)


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
        The route's segments (:func:`profileopt.core.segments.segment_route`).
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


#: Most segments the planner lets :func:`split_long_segments` leave, per segment of the
#: plan's grid or of the default 5 m grid, whichever has more: enough for a 20 % climb with
#: 2.2 W/kg (0.69 m pieces), and a bound on a plan's size where the exact length is
#: centimetres (20 km of a 25 % climb with 1 W/kg: 0.07 m, 70 times the 5 m grid). The
#: command line's memory estimate assumes 4 per segment of the plan's grid
#: (``profileopt.cli.memory``): a plan cut more than that needs more memory than it estimates
#: for its segments.
SPLIT_MAX_FACTOR = 8


def split_long_segments(segments: Segments, longest_m: np.ndarray, s: np.ndarray, vehicle: "Vehicle", *,
                        max_segments: int) -> Segments:
    """The segments with each one longer than its ``longest_m`` cut at samples into pieces of
    about equal length, no longer than it where the samples allow (every piece keeps
    :data:`~profileopt.core.segments.MIN_SAMPLES_PER_SEGMENT` samples).

    At most ``max_segments`` result: where cutting every long segment would leave more, only
    the first of each run of long segments is cut (where a climb is entered, maybe faster
    than it can be held), and where that too would leave more, none.

    Parameters
    ----------
    segments : Segments
        The plan's segments.
    longest_m : numpy.ndarray, shape (N,)
        The longest each segment may be (m); inf: any.
    s : numpy.ndarray, shape (M,)
        The route's sample positions (m).
    vehicle : Vehicle
        As for :func:`~profileopt.core.segments.segments_at`.
    max_segments : int
        Most segments to leave (the planner: :data:`SPLIT_MAX_FACTOR` per segment of its grid
        or of the default grid).

    Returns
    -------
    Segments
        ``segments`` itself when none is cut.
    """
    long = segments.length_m > longest_m
    first_of_run = long & ~np.concatenate([[False], long[:-1]])
    for chosen in (long, first_of_run):
        cuts = _split_cuts(segments, longest_m, s, np.flatnonzero(chosen))
        if segments.count + len(cuts) <= max_segments:
            break
    else:
        return segments
    if not cuts:
        return segments
    bounds = np.union1d(segments.boundaries_m, s[np.asarray(cuts, dtype=np.intp)])
    starts, stops = segment_samples(s, bounds)
    return segments_at(bounds, segments.windows, vehicle, starts=starts, stops=stops, notes=segments.notes)


def can_split_to(segments: Segments, longest_m: np.ndarray, s: np.ndarray) -> bool:
    """Whether every segment longer than its ``longest_m`` could be cut into pieces no longer
    than it, each with :data:`~profileopt.core.segments.MIN_SAMPLES_PER_SEGMENT` samples: the
    samples there at most that many times closer than it (:func:`split_long_segments`).

    Parameters
    ----------
    segments : Segments
        The plan's segments.
    longest_m : numpy.ndarray, shape (N,)
        The longest each segment may be (m); inf: any.
    s : numpy.ndarray, shape (M,)
        The route's sample positions (m).

    Returns
    -------
    bool
    """
    return all(MIN_SAMPLES_PER_SEGMENT * _widest_spacing_m(segments, int(k), s) <= longest_m[k]
               for k in np.flatnonzero(segments.length_m > longest_m))


def _widest_spacing_m(segments: Segments, k: int, s: np.ndarray) -> float:
    """The widest spacing (m) of the samples ``s`` in segment k, to the next segment's first."""
    a = int(segments.first_sample[k])
    b = a + int(segments.samples[k])
    return float(np.max(np.diff(s[a:min(b + 1, s.size)]), initial=0.0))


def _split_cuts(segments: Segments, longest_m: np.ndarray, s: np.ndarray, which: np.ndarray) -> list[int]:
    """The samples where :func:`split_long_segments` cuts the segments ``which``."""
    least = MIN_SAMPLES_PER_SEGMENT
    cuts: list[int] = []
    for k in which:
        a = int(segments.first_sample[k])
        b = a + int(segments.samples[k])  # samples a .. b-1
        # cut at the last sample at or before each target: a piece is then shorter than the
        # targets' spacing plus the samples' widest spacing here, so the targets are that much closer
        spacing = _widest_spacing_m(segments, int(k), s)
        target_m = max(float(longest_m[k]) - spacing, spacing, 1e-9)
        pieces = min(int(math.ceil(segments.length_m[k] / target_m)), (b - a) // least)
        if pieces < 2:
            continue
        targets = segments.boundaries_m[k] + segments.length_m[k] * np.arange(1, pieces) / pieces
        last = a
        for j in (np.searchsorted(s[a:b], targets, side="right") - 1 + a).tolist():
            if j - last >= least and b - j >= least:
                cuts.append(j)
                last = j
    return cuts
