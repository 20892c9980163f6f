"""Terrain roughness: the Roughness Index (Eq. 1), worst-case elevation (Eq. 8) and the
width of a step the wheel rolls over (Eq. 2).

Equation numbers are those of Wilson et al., "Velocity Selection for High-Speed UGVs in
Rough Unknown Terrains using Force Prediction" (see ``shared/paper``), with the project's
errata in ``docs/paper-notes.md``.
"""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING, Any

import casadi as ca
import numpy as np
from numpy.typing import ArrayLike

from ..core.symbolic import elementwise, is_symbolic
from ..core.vehicle import require_vehicle
from ..errors import InputError
from .window_sums import (  # window_line_moments: re-exported
    batched_window_moments,
    window_line_moments,
)

if TYPE_CHECKING:
    from ..core.vehicle import Vehicle

__all__ = [
    "roughness_index",
    "segment_roughness_index",
    "SegmentLineFit",
    "segment_line_fit",
    "RoughnessWindows",
    "roughness_windows",
    "window_line_moments",
    "range_extremes",
    "MIN_SAMPLES_PER_WINDOW",
    "elevation_z_score",
    "worst_case_elevation",
    "step_width",
    "check_ri",
    "check_e_max",
]


def roughness_index(
    elevations_m: ArrayLike,
    clearance_m: float,
    *,
    positions_m: ArrayLike | None = None,
    detrend: bool = True,
) -> float:
    """Roughness Index RI = STD(e / h) of a terrain patch (Eq. 1).

    The population standard deviation (ddof = 0) of the elevations divided by the
    vehicle's ground clearance. RI = 0 is perfectly smooth ground; it grows without bound
    with roughness.

    With ``detrend=True`` (the default) the least-squares line (profile) or plane (point
    cloud) is removed first, because a constant grade is not roughness: a vehicle climbing
    a smooth 10 % slope feels no bumps. ``detrend=False`` is the paper's raw definition
    (only the mean is removed, as the standard deviation does).

    Parameters
    ----------
    elevations_m : array_like, shape (M,) or (M, 3)
        A longitudinal profile of elevations e (m), or a point cloud of rows (x, y, z) (m).
    clearance_m : float
        Ground clearance h (m), > 0.
    positions_m : array_like, shape (M,), optional
        Distance along the profile of each elevation (m), used to fit the trend of a 1-D
        profile. If omitted, the samples are taken as evenly spaced. Not used for clouds.
    detrend : bool, default True
        Remove the least-squares line (profile) or plane (cloud) before taking the STD.

    Returns
    -------
    float
        RI (dimensionless).

    Raises
    ------
    InputError
        Non-finite values, fewer than 2 samples (3 points for a cloud), mismatched shapes
        or a clearance that is not > 0.
    """
    h = float(clearance_m)
    if not (math.isfinite(h) and h > 0):
        raise InputError(f"clearance_m = {clearance_m!r} m: must be a finite number > 0")
    e = np.asarray(elevations_m, dtype=float)
    if not np.all(np.isfinite(e)):
        raise InputError("elevations_m contain NaN or inf; remove or fill those samples")
    if e.ndim == 2 and e.shape[1] == 3:
        if e.shape[0] < 3:
            raise InputError(f"a point cloud needs at least 3 points, got {e.shape[0]}")
        z = e[:, 2]
        if detrend:
            design = np.column_stack([np.ones(len(z)), e[:, 0] - e[:, 0].mean(), e[:, 1] - e[:, 1].mean()])
            coef, *_ = np.linalg.lstsq(design, z, rcond=None)
            z = z - design @ coef
        return float(np.std(z / h))
    if e.ndim != 1:
        raise InputError(f"elevations_m must have shape (M,) or (M, 3), got {e.shape}")
    if e.size < 2:
        raise InputError(f"a profile needs at least 2 samples, got {e.size}")
    s = np.arange(e.size, dtype=float) if positions_m is None else np.asarray(positions_m, dtype=float)
    if s.shape != e.shape:
        raise InputError(f"positions_m have shape {s.shape} but elevations_m {e.shape}")
    if not np.all(np.isfinite(s)):
        raise InputError("positions_m contain NaN or inf")
    return float(segment_roughness_index(s, e, np.array([0]), h, detrend=detrend)[0])


def segment_roughness_index(
    positions_m: np.ndarray,
    elevations_m: np.ndarray,
    starts: np.ndarray,
    clearance_m: float,
    detrend: bool = True,
) -> np.ndarray:
    """RI (Eq. 1) of many consecutive segments of one profile at once.

    Segment i holds the samples ``starts[i] <= j < starts[i+1]`` (the last runs to the end).
    The STD of the residual of a least-squares line is computed from the segment's moments,
    var(e) - cov(s, e)^2 / var(s), with each segment shifted to its first sample so that
    absolute elevations (hundreds of metres) lose no precision.

    Parameters
    ----------
    positions_m, elevations_m : numpy.ndarray, shape (M,)
        Distance along the profile (m) and elevation (m), finite.
    starts : numpy.ndarray of int, shape (N,)
        Index of the first sample of each segment, strictly increasing, ``starts[0] == 0``.
    clearance_m : float
        Ground clearance h (m).
    detrend : bool, default True
        Remove each segment's least-squares line (else only its mean).

    Returns
    -------
    numpy.ndarray, shape (N,)
        RI of each segment (dimensionless).
    """
    starts = np.asarray(starts, dtype=np.intp)
    fit = segment_line_fit(positions_m, elevations_m, starts, np.append(starts[1:], np.size(positions_m)),
                           detrend=detrend)
    return np.sqrt(fit.residual_variance_m2) / clearance_m


@dataclasses.dataclass(frozen=True)
class SegmentLineFit:
    """The least-squares line z ~ level_m + slope (s - s0_m) of each segment's samples.

    Attributes
    ----------
    s0_m, level_m : numpy.ndarray, shape (N,)
        A point of each line: at distance s0_m (the segment's first sample) it is at
        level_m (m).
    slope : numpy.ndarray, shape (N,)
        Its slope dz/ds (dimensionless); 0 without detrending or with fewer than two
        distinct positions.
    residual_variance_m2 : numpy.ndarray, shape (N,)
        Population variance of the samples about the line (m^2), >= 0.
    count : numpy.ndarray of int, shape (N,)
        Samples in each segment; a segment without samples has NaN in the other fields.
    """

    s0_m: np.ndarray
    level_m: np.ndarray
    slope: np.ndarray
    residual_variance_m2: np.ndarray
    count: np.ndarray


def segment_line_fit(positions_m: ArrayLike, elevations_m: ArrayLike, starts: ArrayLike, stops: ArrayLike,
                     detrend: bool = True) -> SegmentLineFit:
    """Least-squares line of the samples ``starts[i] <= j < stops[i]`` of each segment i.

    Computed from the segment's moments: slope = cov(s, z) / var(s), residual variance
    var(z) - cov(s, z)^2 / var(s), with each segment shifted to its first sample so that
    absolute positions and elevations (kilometres, hundreds of metres) lose no precision.
    With ``detrend=False`` the line is flat at the mean (slope 0). The RI of Eq. (1)
    (:func:`segment_roughness_index`) and the simulator's excitation datum use this one fit.

    Parameters
    ----------
    positions_m, elevations_m : array_like, shape (M,)
        Distance (m) and elevation (m) of the samples, s increasing.
    starts, stops : array_like of int, shape (N,)
        Sample ranges of the segments, non-decreasing (a segment may be empty).
    detrend : bool, default True

    Returns
    -------
    SegmentLineFit
    """
    s = np.asarray(positions_m, dtype=float)
    z = np.asarray(elevations_m, dtype=float)
    starts = np.asarray(starts, dtype=np.intp)
    stops = np.asarray(stops, dtype=np.intp)
    n = starts.size
    count = stops - starts
    has = count > 0
    idx = np.flatnonzero(has)
    nan = np.full(n, np.nan)
    s0, level, slope, variance = nan.copy(), nan.copy(), nan.copy(), nan.copy()
    if idx.size:
        seg = np.repeat(np.arange(idx.size), count[idx])
        take = np.concatenate([np.arange(a, b) for a, b in zip(starts[idx], stops[idx])]) \
            if idx.size < n or stops[-1] != s.size or np.any(starts[1:] != stops[:-1]) else np.arange(s.size)
        first = starts[idx]
        ds = s[take] - s[first][seg]
        dz = z[take] - z[first][seg]
        cnt = count[idx].astype(float)

        def mean(x: np.ndarray) -> np.ndarray:
            return np.bincount(seg, weights=x, minlength=idx.size) / cnt

        ms, mz = mean(ds), mean(dz)
        var_z = mean(dz * dz) - mz * mz
        b = np.zeros(idx.size)
        if detrend:
            var_s = mean(ds * ds) - ms * ms
            cov = mean(ds * dz) - ms * mz
            ok = var_s > 0
            safe_var_s = np.where(ok, var_s, 1.0)
            b = np.where(ok, cov / safe_var_s, 0.0)
            var_z = var_z - np.where(ok, cov * cov / safe_var_s, 0.0)
        s0[idx] = s[first]
        level[idx] = z[first] + mz - b * ms
        slope[idx] = b
        variance[idx] = np.maximum(var_z, 0.0)
    return SegmentLineFit(s0_m=s0, level_m=level, slope=slope, residual_variance_m2=variance, count=count)


#: A window's RI is a standard deviation: with fewer samples it means little.
MIN_SAMPLES_PER_WINDOW = 8


@dataclasses.dataclass(frozen=True)
class RoughnessWindows:
    """Every roughness window of a profile: the stretch it covers, its samples and its RI (Eq. 1).

    A roughness window of length W is a stretch [a, a + W] of the route, for every real
    offset a in [s_0, s_end - W]; it holds the samples a <= s <= a + W (a sample within
    1e-9 W of an end counts as inside). As a slides along the route, the samples it holds
    change only where an end passes a sample, so the windows hold finitely many distinct
    sample sets: those are the entries kept, one per distinct set j..k, sorted by place.
    They are of three kinds: the set of a window that starts at a sample, that of a window
    that ends at one, and the set of a window strictly between (a in (s_{j-1}, s_j) and
    a + W in (s_k, s_{k+1})), which can be none of the first two and have a larger RI
    (the detrended STD is not monotone under taking a subset of the samples).

    Each entry stands for *all* the windows [a, a + W] that hold its set: the offsets
    a in (s_{j-1}, s_j] (first sample j) and in [s_k - W, s_{k+1} - W) (last sample k),
    an interval. Its extent [start_m, stop_m] is the union of those windows' stretches,
    closed:

        start_m = max(s_{j-1}, s_k - W),   stop_m = min(s_j + W, s_{k+1})

    (s_0 for j = 0, s_end for the last sample), at least W long and at most W plus one
    sample spacing (the one before its first sample, or after its last). "Every speed driven inside every window holding the set
    is admissible for its RI" is exactly "every speed driven on [start_m, stop_m] is": the
    closure adds only limit points, where the speed is the limit of speeds driven inside.

    Attributes
    ----------
    window_m : float
        The window length W (m).
    start_m, stop_m : numpy.ndarray, shape (K,)
        The extent of each entry (m): every window holding its samples lies in
        [start_m, stop_m], and every point of it lies in one of them or is a limit of such
        points. Both are non-decreasing; stop_m - start_m >= W (to rounding).
    first_sample, stop_sample : numpy.ndarray of int, shape (K,)
        The entry's samples are ``first_sample[k] <= j < stop_sample[k]``.
    ri : numpy.ndarray, shape (K,)
        RI of each entry's samples, detrended or not (dimensionless).
    """

    window_m: float
    start_m: np.ndarray
    stop_m: np.ndarray
    first_sample: np.ndarray
    stop_sample: np.ndarray
    ri: np.ndarray

    @property
    def count(self) -> int:
        """Number of entries K (distinct sample sets)."""
        return int(self.start_m.size)

    def overlapping(self, start_m: ArrayLike, stop_m: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """The entries whose extent shares a point with each stretch [start, stop] of the route.

        Parameters
        ----------
        start_m, stop_m : array_like, shape (N,)
            Ends of each stretch (m), start <= stop.

        Returns
        -------
        first, stop : numpy.ndarray of int, shape (N,)
            Stretch i meets the entries ``first[i] <= k < stop[i]`` (an extent that only
            touches it at one end included: the vehicle is in both at that point, or
            arbitrarily close to it).
        """
        tol = 1e-9 * max(self.window_m, 1.0)
        lo = np.searchsorted(self.stop_m, np.asarray(start_m, dtype=float) - tol, side="left")
        hi = np.searchsorted(self.start_m, np.asarray(stop_m, dtype=float) + tol, side="right")
        return lo, hi


def roughness_windows(positions_m: ArrayLike, elevations_m: ArrayLike, clearance_m: float, *, window_m: float,
                      detrend: bool = True, source: str = "the route") -> RoughnessWindows:
    """The RI (Eq. 1) of every roughness window of a profile, at any offset (:class:`RoughnessWindows`).

    The windows holding samples j..k are those with a in (s_{j-1}, s_j] and a + W in
    [s_k, s_{k+1}): for first sample j, the last sample k runs from the last one a window
    starting just after s_{j-1} holds, K(j - 1), to the last one a window starting at s_j
    holds, K(j), with K(j) the last sample <= s_j + W. Every such pair is a distinct set;
    there are about two per sample (one more than the start-anchored window for each
    sample a + W passes while a moves from s_{j-1} to s_j). Their moments come from prefix
    sums (:func:`~profileopt.terrain.window_sums.batched_window_moments`).

    Parameters
    ----------
    positions_m, elevations_m : array_like, shape (M,)
        Samples: distance along the route (m), increasing, and elevation (m), finite.
    clearance_m : float
        Ground clearance h (m), > 0.
    window_m : float
        Window length W (m), > 0; a route shorter than W is one window, the whole route
        (``RoughnessWindows.window_m`` is then the route's length).
    detrend : bool, default True
        Remove each window's least-squares line before taking the STD (else only its mean).
    source : str, default "the route"
        Names the profile in messages.

    Returns
    -------
    RoughnessWindows

    Raises
    ------
    InputError
        A window length that is not a positive number, or a window starting or ending at a
        sample with fewer than :data:`MIN_SAMPLES_PER_WINDOW` samples (the message says what
        sample spacing is needed). A window between samples holds at most one sample fewer
        than the one starting at the sample before it; it is not refused for that.
    """
    s = np.asarray(positions_m, dtype=float)
    z = np.asarray(elevations_m, dtype=float)
    width = float(window_m)
    if not (math.isfinite(width) and width > 0):
        raise InputError(f"roughness_window_m = {window_m!r} m: must be a number > 0")
    total = float(s[-1] - s[0])
    tol = 1e-9 * max(width, 1.0)
    if width > total:  # a route shorter than the window is one window: the whole route
        width = total
    _check_window_samples(s, width, tol, source)
    reach = width + tol  # a sample within tol of a window's end counts as inside
    m = s.size
    # K(j): the last sample a window starting at s_j holds; first samples j up to the one
    # at or after s_end - W (a window cannot start later)
    j_end = int(np.searchsorted(s, s[-1] - reach, side="left")) + 1
    last = np.searchsorted(s, s[:j_end] + reach, side="right") - 1
    k_lo = np.concatenate([last[:1], last[:-1]])  # K(j - 1): a = s_0 only for j = 0
    per = last - k_lo + 1
    first = np.repeat(np.arange(j_end), per)
    offsets = np.cumsum(per) - per
    k = np.repeat(k_lo - offsets, per) + np.arange(int(per.sum()))
    # the extent: the union of [a, a + W] over the offsets a holding j..k (the class docstring)
    start = np.where(first > 0, np.maximum(s[np.maximum(first - 1, 0)], s[k] - width), s[0])
    stop = np.minimum(np.minimum(s[first] + width, s[np.minimum(k + 1, m - 1)]), s[-1])
    stop_sample = k + 1
    var_s, cov, var_z = batched_window_moments(s, z, first, stop_sample, block_m=width * (1 + 1e-6) + 2 * tol)
    if detrend:
        ok = var_s > 0
        var_z = var_z - np.where(ok, cov * cov / np.where(ok, var_s, 1.0), 0.0)
    return RoughnessWindows(window_m=width, start_m=start, stop_m=stop, first_sample=first,
                            stop_sample=stop_sample, ri=np.sqrt(np.maximum(var_z, 0.0)) / float(clearance_m))


def _check_window_samples(s: np.ndarray, width: float, tol: float, source: str) -> None:
    """Refuse a profile whose windows starting or ending at a sample hold fewer than
    :data:`MIN_SAMPLES_PER_WINDOW` samples, naming the first such window (by start)."""
    from_start = np.flatnonzero(s + width <= s[-1] + tol)  # windows [s_j, s_j + W]
    to_end = np.flatnonzero(s - width >= s[0] - tol)  # windows [s_k - W, s_k]
    first = np.concatenate([from_start, np.searchsorted(s, s[to_end] - width - tol, side="left")])
    stop = np.concatenate([np.searchsorted(s, s[from_start] + width + tol, side="right"), to_end + 1])
    start = np.concatenate([s[from_start], s[to_end] - width])
    thin = np.flatnonzero(stop - first < MIN_SAMPLES_PER_WINDOW)
    if thin.size:
        k = thin[np.lexsort((stop[thin], first[thin], start[thin]))[0]]
        # a gap: the widest step between the samples around the window, if it is several times
        # the route's usual spacing (a route sampled finely elsewhere)
        lo, hi = max(int(first[k]) - 1, 0), min(int(stop[k]), s.size - 1)
        steps = np.diff(s[lo:hi + 1])
        gap = ""
        if steps.size and steps.max() > 4.0 * float(np.median(np.diff(s))):
            j = lo + int(np.argmax(steps))
            gap = f" (the samples jump from {s[j]:g} to {s[j + 1]:g} m: a gap of {s[j + 1] - s[j]:.3g} m)"
        raise InputError(
            f"{source}: the roughness window from {start[k]:g} to {start[k] + width:g} m holds {stop[k] - first[k]} "
            f"samples{gap}; measuring roughness needs at least {MIN_SAMPLES_PER_WINDOW}: "
            f"{'fill the gap or ' if gap else ''}sample the route every "
            f"{width / MIN_SAMPLES_PER_WINDOW:.3g} m or closer, or raise roughness_window_m"
        )


def range_extremes(values: ArrayLike, first: ArrayLike, stop: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Least and largest of ``values[first[i]:stop[i]]`` for many ranges, in O(K log L).

    A sparse table built one level at a time (level k holds the extremes of runs of 2^k
    values), answering each range at its own level from two overlapping runs; only one
    level is kept, so memory stays O(K).

    Parameters
    ----------
    values : array_like, shape (K,)
    first, stop : array_like of int, shape (N,)
        Non-empty ranges ``first < stop``.

    Returns
    -------
    least, largest : numpy.ndarray, shape (N,)
    """
    v = np.asarray(values, dtype=float)
    lo = np.asarray(first, dtype=np.intp)
    hi = np.asarray(stop, dtype=np.intp)
    length = hi - lo
    if np.any(length < 1):
        raise ValueError("range_extremes: every range must hold at least one value")
    level = np.floor(np.log2(length)).astype(np.intp)
    least, largest = np.empty(lo.size), np.empty(lo.size)
    small, big = v.copy(), v.copy()
    for k in range(int(level.max()) + 1):
        if k:
            half = 1 << (k - 1)
            small = np.minimum(small[:-half], small[half:])
            big = np.maximum(big[:-half], big[half:])
        at = np.flatnonzero(level == k)
        if at.size:
            other = hi[at] - (1 << k)
            least[at] = np.minimum(small[lo[at]], small[other])
            largest[at] = np.maximum(big[lo[at]], big[other])
    return least, largest


def elevation_z_score(confidence: float) -> float:
    """The factor sqrt(2) erfinv(2 Pe - 1) of Eq. (8) (dimensionless).

    The z-score below which a zero-mean normal elevation stays with probability Pe;
    4.7534 for Pe = 0.999999 (docs/paper-notes.md).

    Parameters
    ----------
    confidence : float
        The probability Pe in (0, 1), e.g. ``vehicle.confidence``.
    """
    return math.sqrt(2.0) * float(ca.erfinv(2.0 * confidence - 1.0))


def check_ri(ri: Any) -> None:
    """Raise :class:`~profileopt.errors.InputError` unless every roughness index is >= 0.

    Parameters
    ----------
    ri : float, array_like, casadi.DM, SX or MX
        Roughness index (dimensionless). Symbols (SX, MX) are not checked.

    Raises
    ------
    InputError
        A NaN or negative value.
    """
    _check_not_negative(ri, "RI must be a number >= 0 (NaN or a negative RI was given)")


def check_e_max(e_max_m: Any) -> None:
    """Raise :class:`~profileopt.errors.InputError` unless every worst-case elevation is >= 0.

    Parameters
    ----------
    e_max_m : float, array_like, casadi.DM, SX or MX
        Worst-case elevation e_max (m) of Eq. (8). Symbols (SX, MX) are not checked.

    Raises
    ------
    InputError
        A NaN or negative value.
    """
    _check_not_negative(e_max_m, "e_max_m must be a number >= 0 in metres (NaN or a negative value was given)")


def _check_not_negative(value: Any, message: str) -> None:
    """Raise InputError(message) if a numeric ``value`` holds a NaN or a negative entry."""
    if is_symbolic(value):
        return
    values = np.asarray(value.full() if isinstance(value, ca.DM) else value, dtype=float)
    if np.any(np.isnan(values)) or np.any(values < 0):
        raise InputError(message)


def worst_case_elevation(ri: Any, vehicle: "Vehicle") -> Any:
    """Worst-case elevation e_max = sqrt(2) erfinv(2 Pe - 1) RI h (Eq. 8), in metres.

    Parameters
    ----------
    ri : float, numpy.ndarray, casadi.DM, SX or MX
        Roughness index (dimensionless), >= 0. Any shape.
    vehicle : Vehicle
        Supplies the confidence Pe and the ground clearance h (m).

    Returns
    -------
    Same kind and shape as ``ri``: e_max (m).
    """
    vehicle = require_vehicle(vehicle, "worst_case_elevation")
    check_ri(ri)
    return elevation_z_score(vehicle.confidence) * vehicle.ground_clearance_m * ri


@elementwise
def step_width(e_max_m: Any, vehicle: "Vehicle") -> Any:
    """Horizontal distance X_w over which the wheel climbs a step of height e (Eq. 2), in m.

    X_w = sqrt(2 e r - e^2), saturated at the wheel radius r once e >= r (docs/paper-notes.md),
    written as sqrt(e_c (2 r - e_c)) with e_c = min(e, r) so that it is continuous.

    Parameters
    ----------
    e_max_m : float, array_like, casadi.DM, SX or MX
        Step height e (m), >= 0, usually the worst-case elevation e_max of Eq. (8). Any
        shape.
    vehicle : Vehicle
        Supplies the wheel radius r (m).

    Returns
    -------
    Same kind and shape as ``e_max_m``: X_w (m).
    """
    r = require_vehicle(vehicle, "step_width").wheel_radius_m
    e_c = ca.fmin(e_max_m, r)
    return ca.sqrt(e_c * (2.0 * r - e_c))
