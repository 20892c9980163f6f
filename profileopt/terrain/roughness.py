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
    """Every roughness window of a profile: its place, its samples and its RI (Eq. 1).

    A window of length W is a stretch [a, a + W] of the route. The windows kept are those
    that start at a sample and those that end at one (so the set is the same driven either
    way), sorted by start; each holds the samples a <= s <= a + W. Together they are every
    distinct set of samples that a window sliding continuously along the route covers
    when it has just taken in or is about to let go of a sample.

    Attributes
    ----------
    window_m : float
        The window length W (m).
    start_m : numpy.ndarray, shape (K,)
        Where each window starts (m), non-decreasing; it ends at ``start_m + window_m``.
    first_sample, stop_sample : numpy.ndarray of int, shape (K,)
        The window holds the samples ``first_sample[k] <= j < stop_sample[k]``.
    ri : numpy.ndarray, shape (K,)
        RI of each window's samples, detrended or not (dimensionless).
    """

    window_m: float
    start_m: np.ndarray
    first_sample: np.ndarray
    stop_sample: np.ndarray
    ri: np.ndarray

    @property
    def count(self) -> int:
        """Number of windows K."""
        return int(self.start_m.size)

    def overlapping(self, start_m: ArrayLike, stop_m: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """The windows that share a point with each stretch [start, stop] of the route.

        Parameters
        ----------
        start_m, stop_m : array_like, shape (N,)
            Ends of each stretch (m), start <= stop.

        Returns
        -------
        first, stop : numpy.ndarray of int, shape (N,)
            Stretch i meets the windows ``first[i] <= k < stop[i]`` (a window that only
            touches it at one end included: the vehicle is in both at that point).
        """
        tol = 1e-9 * max(self.window_m, 1.0)
        lo = np.searchsorted(self.start_m, np.asarray(start_m, dtype=float) - self.window_m - tol, side="left")
        hi = np.searchsorted(self.start_m, np.asarray(stop_m, dtype=float) + tol, side="right")
        return lo, hi


def roughness_windows(positions_m: ArrayLike, elevations_m: ArrayLike, clearance_m: float, *, window_m: float,
                      detrend: bool = True, source: str = "the route") -> RoughnessWindows:
    """The RI (Eq. 1) of every roughness window of a profile (:class:`RoughnessWindows`).

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
        A window length that is not a positive number, or a window with fewer than :data:`MIN_SAMPLES_PER_WINDOW` samples (the message says what
        sample spacing is needed).
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
    from_start = np.flatnonzero(s + width <= s[-1] + tol)  # windows [s_j, s_j + W]
    to_end = np.flatnonzero(s - width >= s[0] - tol)  # windows [s_k - W, s_k]
    first = np.concatenate([from_start, np.searchsorted(s, s[to_end] - width - tol, side="left")])
    stop = np.concatenate([np.searchsorted(s, s[from_start] + width + tol, side="right"), to_end + 1])
    start = np.concatenate([s[from_start], s[to_end] - width])
    order = np.lexsort((stop, first, start))
    first, stop, start = first[order], stop[order], start[order]
    # a window that both starts at one sample and ends at another is listed once
    same = (np.diff(start) <= tol) & (np.diff(first) == 0) & (np.diff(stop) == 0)
    keep = np.concatenate([[True], ~same])
    first, stop, start = first[keep], stop[keep], start[keep]
    count = stop - first
    thin = np.flatnonzero(count < MIN_SAMPLES_PER_WINDOW)
    if thin.size:
        k = thin[0]
        raise InputError(
            f"{source}: the roughness window from {start[k]:g} to {start[k] + width:g} m holds {count[k]} samples; "
            f"measuring roughness needs at least {MIN_SAMPLES_PER_WINDOW}: sample the route every "
            f"{width / MIN_SAMPLES_PER_WINDOW:.3g} m or closer, or raise roughness_window_m"
        )
    var_s, cov, var_z = batched_window_moments(s, z, first, stop, block_m=width * (1 + 1e-6) + 2 * tol)
    if detrend:
        ok = var_s > 0
        var_z = var_z - np.where(ok, cov * cov / np.where(ok, var_s, 1.0), 0.0)
    return RoughnessWindows(window_m=width, start_m=start, first_sample=first, stop_sample=stop,
                            ri=np.sqrt(np.maximum(var_z, 0.0)) / float(clearance_m))


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
    r = vehicle.wheel_radius_m
    e_c = ca.fmin(e_max_m, r)
    return ca.sqrt(e_c * (2.0 * r - e_c))
