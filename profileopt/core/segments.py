"""A route cut into segments: stations, the samples of each segment and its terrain numbers.

Segment i covers s_i <= s < s_{i+1} (the last one closed); which samples that is, is
decided in one place, :mod:`profileopt.core.stations`. Segments are the planning resolution
only: the roughness is measured over sliding *roughness windows* [a, a + W] of a fixed
length W at every offset a (:func:`profileopt.terrain.roughness.roughness_windows`: each
distinct set of samples a window can hold, with the extent over which the windows holding
it lie), wherever the segments fall, and a segment's admissible speeds are those admissible
for every window that shares a point with it, i.e. every entry whose extent does. So each
segment carries the least and the largest RI (Eq. 1, detrended) of those windows, and the
worst-case elevation e_max of Eq. (8) of the largest. A route with an
assumed roughness (:attr:`profileopt.core.route.Route.assumed_roughness`) keeps its windows'
places but every window gets the assumed RI (:func:`route_roughness_windows`).
"""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING

import numpy as np

from ..defaults import DEFAULT_ROUGHNESS_WINDOW_M, DEFAULT_SEGMENT_LENGTH_M
from ..errors import InputError
from ..terrain.roughness import (
    RoughnessWindows,
    range_extremes,
    roughness_windows,
    worst_case_elevation,
)
from .stations import segment_samples

if TYPE_CHECKING:
    from .route import Route
    from .vehicle import Vehicle

__all__ = ["Segments", "segment_route", "segments_at", "route_roughness_windows", "roughness_source",
           "MIN_SAMPLES_PER_SEGMENT", "DEFAULT_SEGMENT_LENGTH_M", "DEFAULT_ROUGHNESS_WINDOW_M"]

#: Samples a segment must hold: the roughness comes from the windows, but the simulator
#: (verify) measures each segment's own samples.
MIN_SAMPLES_PER_SEGMENT = 2

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
        segment, at any offset (dimensionless).
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

    def window_ranges(self) -> tuple[np.ndarray, np.ndarray]:
        """The roughness windows each segment meets: segment i meets ``windows`` entries
        ``first[i] <= k < stop[i]``.

        Returns
        -------
        first, stop : numpy.ndarray of int, shape (N,)
        """
        return self.windows.overlapping(self.boundaries_m[:-1], self.boundaries_m[1:])


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
        needs :data:`profileopt.terrain.roughness.MIN_SAMPLES_PER_WINDOW` samples.

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
    # a boundary that lands on a sample but for rounding (0.1 x 3 = 0.30000000000000004 against
    # a sample at 0.3) is that sample: a segment holds the samples from its start up to its end,
    # excluded, and rounding must not move a sample to the segment before
    nearest = np.clip(np.searchsorted(s, bounds), 1, s.size - 1)
    nearest = np.where(np.abs(s[nearest - 1] - bounds) < np.abs(s[nearest] - bounds), nearest - 1, nearest)
    snap = np.abs(s[nearest] - bounds) <= 1e-9 * np.maximum(np.abs(bounds), 1.0)
    bounds[snap] = s[nearest[snap]]
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
    """The route's roughness windows (:func:`profileopt.terrain.roughness.roughness_windows`) with the
    RI the planner uses: the measured one, or for a route with an assumed roughness, the
    assumed RI in every window (the windows' places and extents stay those of the route's
    samples).

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
    """Where a plan's roughness comes from, for :meth:`profileopt.core.profile.Profile.summary`.

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

    A segment [s_i, s_i+1] meets an entry of ``windows`` when it shares a point with the
    entry's extent [start_m, stop_m] (:meth:`RoughnessWindows.overlapping`): then some window
    [a, a + W] holding the entry's samples shares a point with it, or comes arbitrarily
    close (an open end of the extent), where the speed is the limit of speeds inside.

    Parameters
    ----------
    boundaries_m : numpy.ndarray, shape (N+1,)
        Segment boundaries (m), increasing, within the route.
    windows : RoughnessWindows
        The route's roughness windows (:func:`profileopt.terrain.roughness.roughness_windows`).
    vehicle : Vehicle
        Supplies Pe and h (for e_max).
    starts, stops : numpy.ndarray of int, shape (N,)
        Each segment's route samples (:func:`profileopt.core.stations.segment_samples`).
    notes : tuple of str, default ()

    Returns
    -------
    Segments
    """
    bounds = np.asarray(boundaries_m, dtype=float)
    window_first, window_stop = windows.overlapping(bounds[:-1], bounds[1:])  # as Segments.window_ranges
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
