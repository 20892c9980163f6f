"""The route's turns and slopes: curvature kappa(s) of the path in the horizontal plane and
grade theta(s) of the elevation, the inputs of the turn and hill limits of
:mod:`profileopt.physics.motion`.

Curvature comes from a smoothing fit, not from the samples directly: the second
differences of measured coordinates (LiDAR, RTK or GPS) are mostly noise. The fit is the
smoothest path whose deviation from every sample stays within a tolerance
(:func:`smooth_path`); that smoothed path is the one the vehicle is assumed to drive.

Grade is the slope of the least-squares line of z over a window longer than the roughness
windows (:func:`path_grade_rad`): the slope that the roughness windows detrend away,
measured at a scale longer than them, so a bump is roughness and not a hill.
"""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from ..core.route import Route
from ..defaults import DEFAULT_PATH_TOLERANCE_M  # why 0.1 m: see its comment there
from ..errors import InputError
from .window_sums import batched_window_moments

if TYPE_CHECKING:
    from scipy.interpolate import BSpline

__all__ = ["DEFAULT_PATH_TOLERANCE_M", "SmoothPath", "smooth_path", "path_grade_rad", "RouteGeometry",
           "route_geometry"]


#: Most points a smoothing spline is fitted to. scipy's make_smoothing_spline builds its
#: banded system in a Python loop (about 10 us a point); longer paths are fitted to the
#: means of consecutive runs of samples (weighted by their count), and the deviation is
#: still measured at every sample.
_MAX_FIT_POINTS = 10_000

#: The search for the smoothing scale stops when its bracket is this narrow (ratio).
_SCALE_RATIO_TOLERANCE = 1.01

#: Fewest samples scipy's make_smoothing_spline accepts.
_MIN_SMOOTHING_SAMPLES = 5


@dataclasses.dataclass(frozen=True, eq=False)
class SmoothPath:
    """The smoothed path in the horizontal plane and its curvature.

    Attributes
    ----------
    s_m : numpy.ndarray, shape (M,)
        Cumulative horizontal distance of the samples (m), from 0: the route's s.
    x_m, y_m : numpy.ndarray, shape (M,)
        The smoothed path at each sample's s (m).
    curvature_1pm : numpy.ndarray, shape (M,)
        Signed curvature kappa of the smoothed path (1/m), positive turning left
        (counter-clockwise in x, y); 0 on a straight.
    max_deviation_m : float
        Largest distance hypot(x_m - x, y_m - y) from a sample to its fitted point (m),
        <= tolerance_m.
    tolerance_m : float
        The deviation allowed (m).
    smoothing_scale_m : float
        The smoothing spline's length scale (lam / sample density)^(1/4) (m): turns much
        shorter than it are smoothed away. inf for fewer than 5 samples (no smoothing).
    """

    s_m: np.ndarray
    x_m: np.ndarray
    y_m: np.ndarray
    curvature_1pm: np.ndarray
    max_deviation_m: float
    tolerance_m: float
    smoothing_scale_m: float


def _check_tolerance(tolerance_m: float) -> float:
    tol = float(tolerance_m)
    if not (math.isfinite(tol) and tol > 0):
        raise InputError(f"path_tolerance_m = {tolerance_m!r} m: must be a finite number > 0 "
                         f"(e.g. {DEFAULT_PATH_TOLERANCE_M:g} m for LiDAR/RTK paths, a few metres for GPS)")
    return tol


def _curvature(d1: np.ndarray, d2: np.ndarray) -> np.ndarray:
    """Signed curvature (x' y'' - y' x'') / (x'^2 + y'^2)^(3/2) from first and second
    derivatives of (x, y)(s), shape (M, 2); 0 where the path stands still."""
    cross = d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]
    speed = np.hypot(d1[:, 0], d1[:, 1])
    ok = speed > 0
    return np.where(ok, cross / np.where(ok, speed, 1.0) ** 3, 0.0)


def smooth_path(x_m: ArrayLike, y_m: ArrayLike, *, tolerance_m: float = DEFAULT_PATH_TOLERANCE_M) -> SmoothPath:
    """The smoothest path within ``tolerance_m`` of every sample, and its curvature.

    x(s) and y(s), s the cumulative chord length, are fitted with penalised cubic
    smoothing splines (:func:`scipy.interpolate.make_smoothing_spline`, which minimises
    sum (y_i - f(s_i))^2 + lam int f''(s)^2 ds; one lam for both coordinates). lam is found
    by bisection on log(lam): the largest lam (the smoothest path) whose deviation
    hypot(x_fit - x, y_fit - y) from every sample is at most ``tolerance_m``. The least-squares
    line of each coordinate is taken out before the fit and put back after (a smoothing
    spline reproduces lines exactly), which keeps the banded system well conditioned for
    large lam. A path that is straight within the tolerance gets the largest lam tried
    (a smoothing scale of the route's length): curvature near 0.

    The curvature is kappa = (x' y'' - y' x'') / (x'^2 + y'^2)^(3/2) from the spline's
    derivatives. The splines are natural (zero second derivative at the ends), so the
    curvature falls to 0 over about one smoothing scale at the path's two ends.

    Paths of more than 10,000 samples are fitted to the means of runs of consecutive
    samples (10,000 runs, each weighted by its count), for speed; the deviation is measured
    at every sample all the same. Fewer than 5 samples are too few to smooth: the path is
    then the interpolating spline of degree M - 1 (a line for 2 samples).

    Parameters
    ----------
    x_m, y_m : array_like, shape (M,)
        The path in the horizontal plane (m), M >= 2, finite, no point repeating the one
        before it.
    tolerance_m : float, default DEFAULT_PATH_TOLERANCE_M
        Largest deviation allowed from any sample (m), > 0.

    Returns
    -------
    SmoothPath

    Raises
    ------
    InputError
        A tolerance that is not a finite number > 0, coordinates of different shapes, fewer
        than 2 samples, non-finite values or a repeated point.
    """
    # scipy.interpolate takes 0.4 s to import: only a route with turns pays it
    from scipy.interpolate import make_interp_spline, make_smoothing_spline

    tol = _check_tolerance(tolerance_m)
    x = np.asarray(x_m, dtype=float)
    y = np.asarray(y_m, dtype=float)
    if x.ndim != 1 or x.shape != y.shape:
        raise InputError(f"x_m and y_m must be 1-D arrays of the same length, got shapes {x.shape} and {y.shape}")
    if x.size < 2:
        raise InputError(f"a path needs at least 2 points, got {x.size}")
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
        raise InputError("x_m, y_m contain NaN or inf; remove or fill those points")
    step = np.hypot(np.diff(x), np.diff(y))
    bad = np.flatnonzero(step == 0)
    if bad.size:
        raise InputError(f"point {bad[0] + 1} repeats the previous x, y; remove duplicate points")
    s = np.concatenate([[0.0], np.cumsum(step)])
    xy = np.column_stack([x, y])
    m = s.size

    if m < _MIN_SMOOTHING_SAMPLES:
        if m == 2:
            return SmoothPath(s, x.copy(), y.copy(), np.zeros(2), 0.0, tol, math.inf)
        spline = make_interp_spline(s, xy, k=m - 1)
        return SmoothPath(s, x.copy(), y.copy(), _curvature(spline(s, 1), spline(s, 2)), 0.0, tol, math.inf)

    # least-squares line of x(s), y(s), taken out before fitting (centred s: no cancellation)
    sc = s - s.mean()
    slope = (sc @ (xy - xy.mean(axis=0))) / (sc @ sc)
    line = xy.mean(axis=0) + np.outer(sc, slope)
    residual = xy - line

    # fit points: every sample, or means of runs of `run` consecutive samples
    run = -(-m // _MAX_FIT_POINTS)
    if run > 1:
        group = np.arange(m) // run
        count = np.bincount(group).astype(float)
        s_fit = np.bincount(group, weights=sc) / count
        r_fit = np.column_stack([np.bincount(group, weights=residual[:, j]) / count for j in range(2)])
    else:
        count, s_fit, r_fit = np.ones(m), sc, residual
    density = m / s[-1]  # samples per metre: lam = density scale^4 smooths over about `scale`

    def fit(scale_m: float) -> tuple["BSpline", float]:
        spline = make_smoothing_spline(s_fit, r_fit, w=count, lam=density * scale_m**4)
        deviation = spline(sc) - residual
        return spline, float(np.max(np.hypot(deviation[:, 0], deviation[:, 1])))

    # bracket: from well below the spacing of the fit points (near interpolation) to the
    # route's length (near the least-squares line)
    lo_scale = 0.1 * float(np.min(np.diff(s_fit)))
    hi_scale = float(s[-1])
    best = fit(hi_scale)
    fit_hi_deviation = best[1]
    if best[1] <= tol:
        lo_scale = hi_scale
    else:
        best = fit(lo_scale)
        if best[1] > tol:
            if run > 1:  # the means of the runs cannot follow the samples closely enough
                count, s_fit, r_fit = np.ones(m), sc, residual
                lo_scale = 0.1 * float(np.min(step))
                best = fit(lo_scale)
            if best[1] > tol:  # only rounding can leave an interpolating spline this far
                raise InputError(f"path_tolerance_m = {tol:g} m is below what the path's numbers can resolve "
                                 f"(deviation {best[1]:.3g} m even without smoothing); raise path_tolerance_m")
        # the largest scale within the tolerance: regula falsi (Illinois) on
        # log(deviation / tol) against log(scale), each step kept inside the middle 96 % of
        # the bracket (so it never does worse than a slowed bisection): about 6 fits where
        # bisection took 11 to reach the same 1 % bracket
        g_lo = math.log(max(best[1], 1e-300) / tol)
        g_hi = math.log(max(fit_hi_deviation, 1e-300) / tol)
        u_lo, u_hi = math.log(lo_scale), math.log(hi_scale)
        side = 0
        while u_hi - u_lo > math.log(_SCALE_RATIO_TOLERANCE):
            u = u_lo - g_lo * (u_hi - u_lo) / (g_hi - g_lo) if g_hi > g_lo else 0.5 * (u_lo + u_hi)
            u = min(max(u, u_lo + 0.02 * (u_hi - u_lo)), u_hi - 0.02 * (u_hi - u_lo))
            trial = fit(math.exp(u))
            g = math.log(max(trial[1], 1e-300) / tol)
            if g <= 0:
                u_lo, g_lo, best = u, g, trial
                g_hi = g_hi / 2 if side == -1 else g_hi  # Illinois: halve the end kept twice
                side = -1
            else:
                u_hi, g_hi = u, g
                g_lo = g_lo / 2 if side == 1 else g_lo
                side = 1
        lo_scale = math.exp(u_lo)
    spline, deviation = best
    fitted = line + spline(sc)
    curvature = _curvature(spline(sc, 1) + slope, spline(sc, 2))  # the line adds slope to x', y'
    return SmoothPath(s, fitted[:, 0], fitted[:, 1], curvature, deviation, tol, lo_scale)


def _check_profile(s_m: ArrayLike, z_m: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    s = np.asarray(s_m, dtype=float)
    z = np.asarray(z_m, dtype=float)
    if s.ndim != 1 or z.shape != s.shape:
        raise InputError(f"s_m and z_m must be 1-D arrays of the same length, got shapes {s.shape} and {z.shape}")
    if s.size < 2:
        raise InputError(f"a grade needs at least 2 samples, got {s.size}")
    if not (np.all(np.isfinite(s)) and np.all(np.isfinite(z))):
        raise InputError("s_m, z_m contain NaN or inf; remove or fill those samples")
    if np.any(np.diff(s) <= 0):
        raise InputError("s_m must increase strictly; sort the samples or drop duplicates")
    return s, z


def path_grade_rad(s_m: ArrayLike, z_m: ArrayLike, *, scale_m: float) -> np.ndarray:
    """Grade theta = atan(dz/ds) of the least-squares line of z over a window of ``scale_m``.

    At each sample s_i the line is fitted to the samples in [s_i - scale_m / 2,
    s_i + scale_m / 2], clipped at the route's ends (and widened to the neighbouring sample
    when it would hold only s_i). The moments come from prefix sums in O(M)
    (:func:`profileopt.terrain.roughness.window_line_moments`, which restarts its sums every window
    length and shifts each window to its first sample, so kilometres of s and hundreds of
    metres of z lose no digits). A constant grade is returned exactly (to rounding); a
    kink in the grade spreads over ``scale_m``; undulations much shorter than ``scale_m``
    average out.

    Parameters
    ----------
    s_m : array_like, shape (M,)
        Horizontal distance along the path (m), strictly increasing, M >= 2.
    z_m : array_like, shape (M,)
        Elevation (m).
    scale_m : float
        Window length (m), > 0; the planner uses twice the roughness window, so that grade
        is the slope the roughness windows detrend away, measured at a longer scale.

    Returns
    -------
    numpy.ndarray, shape (M,)
        theta (rad), positive uphill in the direction of increasing s.

    Raises
    ------
    InputError
        A scale that is not a finite number > 0, arrays of different shapes, fewer than
        2 samples, non-finite values or s not strictly increasing.
    """
    scale = float(scale_m)
    if not (math.isfinite(scale) and scale > 0):
        raise InputError(f"grade scale_m = {scale_m!r} m: must be a finite number > 0 "
                         "(e.g. twice the roughness window)")
    s, z = _check_profile(s_m, z_m)
    m = s.size
    index = np.arange(m)
    tol = 1e-9 * max(scale, 1.0)
    first = np.searchsorted(s, s - scale / 2 - tol, side="left")
    stop = np.searchsorted(s, s + scale / 2 + tol, side="right")
    first = np.minimum(first, np.maximum(index - 1, 0))  # at least two samples per window
    stop = np.maximum(stop, np.minimum(index + 2, m))
    extent = float(np.max(s[stop - 1] - s[first]))
    var_s, cov, _ = batched_window_moments(s, z, first, stop, block_m=extent * (1 + 1e-6) + tol, with_var_z=False)
    return np.arctan(cov / var_s)


@dataclasses.dataclass(frozen=True, eq=False)
class RouteGeometry:
    """A route's turns and slopes at each sample, as the planner uses them.

    Attributes
    ----------
    curvature_1pm : numpy.ndarray, shape (M,)
        Signed curvature of the smoothed path (1/m), left positive; zeros for a route
        without x, y (a straight path).
    grade_rad : numpy.ndarray, shape (M,)
        Grade theta (rad), positive uphill in the direction of travel.
    max_deviation_m : float
        Largest distance from a sample to the smoothed path (m); 0 without x, y.
    tolerance_m : float
        The path tolerance used (m).
    grade_scale_m : float
        The window over which the grade was measured (m).
    curvature_reach_m : float
        How far (m) the smoothing spreads a change of curvature: twice the spline's
        smoothing scale (:attr:`SmoothPath.smoothing_scale_m`); 0 without x, y. A turn's
        smoothed curvature reaches its full value only this far inside the turn, so a
        limit that must hold where the route's own samples turn takes the largest
        curvature within this reach (:func:`profileopt.core.path.segment_path`).
    """

    curvature_1pm: np.ndarray
    grade_rad: np.ndarray
    max_deviation_m: float
    tolerance_m: float
    grade_scale_m: float
    curvature_reach_m: float = 0.0


def route_geometry(route: Route, *, tolerance_m: float = DEFAULT_PATH_TOLERANCE_M,
                   grade_scale_m: float) -> RouteGeometry:
    """Curvature (:func:`smooth_path`) and grade (:func:`path_grade_rad`) of a route.

    Parameters
    ----------
    route : Route
        The route; its x_m, y_m (if given) are the path in the horizontal plane.
    tolerance_m : float, default DEFAULT_PATH_TOLERANCE_M
        Largest deviation of the smoothed path from any sample (m), > 0.
    grade_scale_m : float
        Window of the grade's least-squares line (m), > 0.

    Returns
    -------
    RouteGeometry

    Raises
    ------
    InputError
        A tolerance or grade scale that is not a finite number > 0.
    """
    tol = _check_tolerance(tolerance_m)
    grade = path_grade_rad(route.s_m, route.z_m, scale_m=grade_scale_m)
    if route.x_m is None or route.y_m is None:
        curvature, deviation, reach = np.zeros(route.s_m.size), 0.0, 0.0
    else:
        path = smooth_path(route.x_m, route.y_m, tolerance_m=tol)
        curvature, deviation = path.curvature_1pm, path.max_deviation_m
        reach = 2.0 * path.smoothing_scale_m if math.isfinite(path.smoothing_scale_m) else 0.0
    return RouteGeometry(curvature_1pm=curvature, grade_rad=grade, max_deviation_m=deviation, tolerance_m=tol,
                         grade_scale_m=float(grade_scale_m), curvature_reach_m=reach)
