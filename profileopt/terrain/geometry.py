"""The route's turns and slopes: curvature kappa(s) of the path in the horizontal plane and
grade theta(s) of the elevation, the inputs of the turn and hill limits of
:mod:`profileopt.physics.motion`.

Curvature comes from a smoothing fit, not from the samples directly: the second
differences of measured coordinates (LiDAR, RTK or GPS) are mostly noise. The fit is the
smoothest path whose deviation from every sample stays within a tolerance
(:func:`smooth_path`); that smoothed path is the one the vehicle is assumed to drive.

The tolerance is the user's (``path_tolerance_m``, ``--path-tolerance``) or, by default,
estimated from the path itself (:func:`estimate_path_noise`): the horizontal noise sigma of
its points (their spread about a quadratic through their neighbours), times sqrt(2 ln n),
the largest such noise reaches over n points, and never below
:data:`~profileopt.defaults.MIN_PATH_TOLERANCE_M`. A GPS track is smoothed so before it
becomes a route (:func:`smooth_track_points`, called by
:func:`profileopt.io.read_track`): its points are moved onto the smoothest path within the
tolerance, so that the route follows that path and its length is the path's, not the zigzag's
between noisy fixes (1.5 m of noise every 3 m adds 30 % to the length).

A reversal (the path turning back on itself: its heading turns by more than
:data:`REVERSAL_HEADING_CHANGE_RAD` within :data:`REVERSAL_LENGTH_M`) is a turn like any other
but the sharpest: where the smoothed path stops and goes back (a cusp, where its
x' and y' vanish together and the formula for curvature gives 0 / 0), or turns between two
samples by more than it can at the sharpest curvature read, the curvature is
:data:`MAX_CURVATURE_1PM`: a turn of radius :data:`~profileopt.defaults.MIN_PATH_TOLERANCE_M`,
the widest U-turn that stays within that tolerance of an out-and-back line. No turn is read
sharper than that. :func:`sharp_turns` names the turns sharper than a vehicle's turning
circle, and every reversal.

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
from ..defaults import DEFAULT_PATH_TOLERANCE_M, MIN_PATH_TOLERANCE_M
from ..errors import InputError
from .window_sums import batched_window_moments

if TYPE_CHECKING:
    from scipy.interpolate import BSpline

__all__ = [
    "DEFAULT_PATH_TOLERANCE_M",
    "MAX_CURVATURE_1PM",
    "MIN_PATH_TOLERANCE_M",
    "REVERSAL_HEADING_CHANGE_RAD",
    "REVERSAL_LENGTH_M",
    "TRACK_LENGTHENING_SHARE",
    "PathNoise",
    "RouteGeometry",
    "SharpTurn",
    "SmoothPath",
    "SmoothedTrack",
    "estimate_path_noise",
    "path_corners",
    "path_grade_rad",
    "route_geometry",
    "sharp_turns",
    "smooth_path",
    "smooth_track_points",
]


#: Most points a smoothing spline is fitted to. scipy's make_smoothing_spline builds its
#: banded system in a Python loop (about 10 us a point); longer paths are fitted to the
#: means of consecutive runs of samples (weighted by their count), and the deviation is
#: still measured at every sample.
_MAX_FIT_POINTS = 10_000

#: The search for the smoothing scale stops when its bracket is this narrow (ratio).
_SCALE_RATIO_TOLERANCE = 1.01

#: Fewest samples scipy's make_smoothing_spline accepts; fewer points are not smoothed and
#: their noise is not estimated.
_MIN_SMOOTHING_SAMPLES = 5

#: The sharpest curvature a path is read to have (1/m): a turn of radius
#: MIN_PATH_TOLERANCE_M (0.1 m). A U-turn of radius r keeps within r of an out-and-back
#: line's samples (its two legs r either side of the line), and none wider does: so 0.1 m is
#: the radius of a reversal within the smallest tolerance, and no path data resolve sharper.
MAX_CURVATURE_1PM = 1.0 / MIN_PATH_TOLERANCE_M

#: A turn whose heading changes by more than this (rad; 150 deg) within REVERSAL_LENGTH_M is
#: a reversal: the path turning back on itself (an out-and-back, a U-turn, a GPS track
#: doubling back).
REVERSAL_HEADING_CHANGE_RAD = math.radians(150.0)

#: The length (m) over which a reversal's heading change is measured: "within a few metres".
#: Turning 150 deg within 5 m is a radius of at most 5 / (150 pi / 180) = 1.9 m, inside the
#: turning circle of any road or off-road vehicle but a skid-steer robot's.
REVERSAL_LENGTH_M = 5.0

#: A sample within this distance (m) of the straight line through its two neighbours, and
#: between them, is an interpolated point of a straight piece (a polyline resampled, as
#: ``profileopt route`` and examples/routes/make_routes.py do), not a measured point: 1 mm,
#: ten times the rounding of coordinates written to 0.1 mm.
_COLLINEAR_M = 1e-3

#: Fewest consecutive samples on their neighbours' lines taken as interpolated, not measured
#: (a measured point with 1 cm of noise falls within 1 mm of that line 6 % of the time, three
#: in a row 0.03 % of the time; a polyline resampled at 5 cm has runs of tens).
_MIN_INTERPOLATED_RUN = 3

#: Variance of the cross-track residual of the five-point quadratic fit (in units of the
#: noise variance sigma^2 of each coordinate): the residual's weights (3, -12, 18, -12, 3) / 35
#: (one minus Savitzky and Golay's smoothing weights (-3, 12, 17, 12, -3) / 35) have
#: squares summing to 630 / 1225 = 18 / 35.
_RESIDUAL_VARIANCE = 18.0 / 35.0

#: Median of the chi-square distribution with one degree of freedom: the median of Z^2 for a
#: standard normal Z (the square of its upper quartile 0.6744897...).
_CHI2_1_MEDIAN = 0.454936423119572

#: Times a GPS track is fitted again with its parameter taken as the length along the path
#: just fitted, instead of the zigzag's between noisy points (the penalty on x'' and y'' is a
#: penalty on curvature only when the parameter is the path's own length).
_REPARAMETRISATIONS = 4

#: A track is smoothed before it becomes a route when its noise makes it longer than its path
#: by more than this share (:attr:`PathNoise.lengthens_share`): 1 %, a noise of a tenth of the
#: spacing (consumer GPS fixes 1.5 m apart every 3 m: 25 %); below it the route's own
#: geometry (:func:`smooth_path`) smooths the turns, and the ground is sampled where the
#: points say.
TRACK_LENGTHENING_SHARE = 0.01

#: Most reweightings of a track's fit (each one banded solve); each multiplies the weight of
#: every point farther than the tolerance by (distance / tolerance)^4.
_MAX_REWEIGHTINGS = 1000
_REWEIGHT_POWER = 4.0
_MAX_WEIGHT = 1e12


@dataclasses.dataclass(frozen=True)
class PathNoise:
    """The horizontal noise of a path's points, and the tolerance it gives.

    Attributes
    ----------
    noise_m : float
        sigma (m): the standard deviation of each coordinate's noise, estimated from the
        points' spread across the path; 0 when there are too few points to tell.
    points : int
        How many measured points it was estimated from (a resampled polyline's corners).
    tolerance_m : float
        max(MIN_PATH_TOLERANCE_M, sigma sqrt(2 ln n)) (m): a path within it of every point
        is, with high probability, within reach of the true path however the noise fell.
    spacing_m : float
        The median distance between consecutive measured points (m); 0 for fewer than 2.
    """

    noise_m: float
    points: int
    tolerance_m: float
    spacing_m: float = 0.0

    @property
    def lengthens_share(self) -> float:
        """How much longer the noise makes the polyline through the points than the path, as a
        share of its length: sigma^2 / h^2 for spacing h (each step's cross-track error has
        variance 2 sigma^2 and lengthens it by about its square over 2 h).

        Returns
        -------
        float
        """
        return (self.noise_m / self.spacing_m) ** 2 if self.spacing_m > 0 else 0.0


def _check_xy(x_m: ArrayLike, y_m: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """x, y as float arrays and the length of each step between them (m); InputError if bad."""
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
    return x, y, step


def path_corners(x_m: ArrayLike, y_m: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """The measured points of a path that may be a polyline resampled: its corners and ends.

    A sample within 1 mm of the straight line through its two neighbours, and between them,
    in a run of at least three such, is an interpolated point of a straight piece and is left
    out. Where a polyline was
    resampled at a fixed spacing from its start (``profileopt route``), its corners fall
    between two samples; a pair of consecutive non-straight samples with straight pieces on
    both sides is such a cut corner, and is taken at the pair's midpoint. A path measured
    point by point (a survey, a noisy path) keeps every sample.

    Parameters
    ----------
    x_m, y_m : array_like, shape (M,)
        The path (m), M >= 2, finite, no point repeating the one before it.

    Returns
    -------
    x_m, y_m : numpy.ndarray, shape (K,)
        The corners, in order, with the path's two ends (K <= M).
    """
    x, y, _ = _check_xy(x_m, y_m)
    p = np.column_stack([x, y])
    m = x.size
    if m < 3:
        return x.copy(), y.copy()
    chord = p[2:] - p[:-2]
    along = p[1:-1] - p[:-2]
    length2 = np.einsum("ij,ij->i", chord, chord)
    with np.errstate(divide="ignore", invalid="ignore"):
        off = np.abs(chord[:, 0] * along[:, 1] - chord[:, 1] * along[:, 0]) / np.sqrt(length2)
        share = np.einsum("ij,ij->i", along, chord) / length2
    straight = (length2 > 0) & (off <= _COLLINEAR_M) & (share > 0) & (share < 1)
    # interpolated points come in runs (a piece of a polyline resampled); a measured point
    # lies on its neighbours' line only by chance, alone: a run of fewer than 3 is measured
    edges = np.diff(np.concatenate([[0], straight.astype(np.int8), [0]]))
    starts, stops = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    for a, b in zip(starts, stops):
        if b - a < _MIN_INTERPOLATED_RUN:
            straight[a:b] = False
    corner = np.concatenate([[True], ~straight, [True]])
    # a cut corner: two corners side by side, straight samples before and after them
    pair = np.zeros(m, dtype=bool)
    pair[1:-2] = corner[1:-2] & corner[2:-1] & ~corner[:-3] & ~corner[3:]
    keep = corner & ~np.concatenate([[False], pair[:-1]])
    out = p[keep].copy()
    first = np.flatnonzero(pair)
    if first.size:
        where = np.searchsorted(np.flatnonzero(keep), first)
        out[where] = 0.5 * (p[first] + p[first + 1])
    return out[:, 0], out[:, 1]


def estimate_path_noise(x_m: ArrayLike, y_m: ArrayLike) -> PathNoise:
    """The horizontal noise of a path's points, and the path tolerance it gives.

    At each measured point (:func:`path_corners`) with two on either side, the quadratic
    least-squares fit of x and of y over the five (by point index) leaves the residual
    r_i = (3 p_{i-2} - 12 p_{i-1} + 18 p_i - 12 p_{i+1} + 3 p_{i+2}) / 35 (Savitzky and Golay's
    five-point quadratic, whose weights leave a quadratic, and by symmetry a cubic, unchanged:
    a path's turns barely enter it). Its component across the path, along the normal of the
    fit's tangent (-2 p_{i-2} - p_{i-1} + p_{i+1} + 2 p_{i+2}) / 10, is left: the along-track
    part also holds uneven spacing. The two sets of weights are orthogonal, so for Gaussian
    noise of standard deviation sigma in each coordinate the cross-track residual is
    N(0, 18/35 sigma^2) whatever the normal's own noise (a difference-based variance estimate,
    as Gasser, Sroka and Jennen-Steinmetz, Biometrika 73, 1986). sigma is taken from the
    median of the squared residuals, sigma^2 = median / (18/35 * 0.4549) (0.4549: the median of
    chi-square with one degree of freedom), so that the few points in sharp turns do not
    count. The tolerance is sigma sqrt(2 ln n) for n points, the largest distance n such
    errors reach with high probability (Donoho and Johnstone's universal threshold,
    Biometrika 81, 1994), and at least MIN_PATH_TOLERANCE_M.

    Parameters
    ----------
    x_m, y_m : array_like, shape (M,)
        The path (m), M >= 2, finite, no point repeating the one before it.

    Returns
    -------
    PathNoise
        sigma 0 and the smallest tolerance when there are fewer than 5 measured points.
    """
    cx, cy = path_corners(x_m, y_m)
    n = cx.size
    spacing = float(np.median(np.hypot(np.diff(cx), np.diff(cy))))
    if n < _MIN_SMOOTHING_SAMPLES:
        return PathNoise(noise_m=0.0, points=int(n), tolerance_m=MIN_PATH_TOLERANCE_M, spacing_m=spacing)
    p = np.column_stack([cx - cx.mean(), cy - cy.mean()])
    residual = (3 * p[:-4] - 12 * p[1:-3] + 18 * p[2:-2] - 12 * p[3:-1] + 3 * p[4:]) / 35.0
    tangent = (-2 * p[:-4] - p[1:-3] + p[3:-1] + 2 * p[4:]) / 10.0
    norm = np.hypot(tangent[:, 0], tangent[:, 1])
    ok = norm > 0
    if not np.any(ok):
        return PathNoise(noise_m=0.0, points=int(n), tolerance_m=MIN_PATH_TOLERANCE_M, spacing_m=spacing)
    across = (tangent[ok, 0] * residual[ok, 1] - tangent[ok, 1] * residual[ok, 0]) / norm[ok]
    sigma = math.sqrt(float(np.median(across**2)) / (_RESIDUAL_VARIANCE * _CHI2_1_MEDIAN))
    return PathNoise(noise_m=sigma, points=int(n),
                     tolerance_m=max(MIN_PATH_TOLERANCE_M, sigma * math.sqrt(2.0 * math.log(n))), spacing_m=spacing)


def _check_tolerance(tolerance_m: float) -> float:
    try:
        tol = float(tolerance_m)
    except (TypeError, ValueError):
        tol = math.nan
    if not (math.isfinite(tol) and tol > 0):
        raise InputError(f"path_tolerance_m = {tolerance_m!r} m: must be a finite number > 0 (or left out, to be "
                         f"estimated from the path's own noise; at least {MIN_PATH_TOLERANCE_M:g} m, a few metres for a "
                         "consumer GPS)")
    return tol


def _tolerance(x: np.ndarray, y: np.ndarray, tolerance_m: float | None) -> tuple[float, str, PathNoise]:
    """The tolerance to smooth within (m), where it came from ("given" or "estimated"), and
    the path's noise."""
    noise = estimate_path_noise(x, y)
    if tolerance_m is None:
        return noise.tolerance_m, "estimated", noise
    return _check_tolerance(tolerance_m), "given", noise


def _natural_smoothing_spline(t: np.ndarray, y: np.ndarray, w: np.ndarray, lam: float) -> np.ndarray:
    """Values at the knots of the natural cubic smoothing spline of (t, y), shape (n, 2).

    It minimises sum w_i |y_i - g(t_i)|^2 + lam int |g''(t)|^2 dt (the problem of
    :func:`scipy.interpolate.make_smoothing_spline`), by Reinsch's banded form (Green and
    Silverman, Nonparametric Regression and Generalized Linear Models, 1994, section 2.3.3):
    (R + lam Q^T W^-1 Q) gamma = Q^T y, g = y - lam W^-1 Q gamma, with Q (n x n-2) the second
    divided differences and R (n-2 x n-2) tridiagonal. Vectorised: one banded Cholesky solve.
    """
    from scipy.linalg import solveh_banded

    h = np.diff(t)
    a, c = 1.0 / h[:-1], 1.0 / h[1:]
    b = -a - c
    d = 1.0 / w
    band = np.zeros((3, t.size - 2))
    band[2] = (h[:-1] + h[1:]) / 3.0 + lam * (a**2 * d[:-2] + b**2 * d[1:-1] + c**2 * d[2:])
    band[1, 1:] = h[1:-1] / 6.0 + lam * (b[:-1] * a[1:] * d[1:-2] + c[:-1] * b[1:] * d[2:-1])
    band[0, 2:] = lam * c[:-2] * a[2:] * d[2:-2]
    gamma = solveh_banded(band, a[:, None] * y[:-2] + b[:, None] * y[1:-1] + c[:, None] * y[2:])
    q_gamma = np.zeros_like(y)
    q_gamma[:-2] += a[:, None] * gamma
    q_gamma[1:-1] += b[:, None] * gamma
    q_gamma[2:] += c[:, None] * gamma
    return y - lam * d[:, None] * q_gamma


def _fit_in_tube(t: np.ndarray, p: np.ndarray, tol: float, weights: np.ndarray | None = None
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Points of a smooth path x(t), y(t) within ``tol`` of every point p_i, shape (n, 2), and
    the weights that gave it, shape (n,) (the start of the next fit: ``weights``, default 1).

    A natural cubic smoothing spline with the penalty of a smoothing scale as long as the
    path (nearly the straightest path), reweighted: every point farther than ``tol`` from it
    has its weight multiplied by (distance / tol)^4 and the spline is fitted again, until
    none is. The weights grow only where the path must bend to keep within the tolerance (a
    turn), so the path is smooth where the points only scatter: a smoothing adapted to each
    stretch, where one smoothing scale for the whole path is set by its tightest turn and
    leaves the noise of its straights in.
    """
    n = t.size
    length = float(t[-1] - t[0])
    lam = (n / length) * length**4
    w = np.ones(n) if weights is None else weights.copy()
    for _ in range(_MAX_REWEIGHTINGS):
        fitted = _natural_smoothing_spline(t, p, w, lam)
        ratio = np.hypot(fitted[:, 0] - p[:, 0], fitted[:, 1] - p[:, 1]) / tol
        if ratio.max() <= 1.0:
            return fitted, w
        # at least doubled where outside, so that the last points come in at a steady pace
        w = np.minimum(w * np.where(ratio > 1.0, np.maximum(ratio**_REWEIGHT_POWER, 2.0), 1.0), _MAX_WEIGHT)
    # the last points still outside are taken as they are (their weight near interpolation)
    w = np.where(ratio > 1.0, _MAX_WEIGHT, w)
    fitted = _natural_smoothing_spline(t, p, w, lam)
    far = np.hypot(fitted[:, 0] - p[:, 0], fitted[:, 1] - p[:, 1]) > tol
    fitted[far] = p[far]
    return fitted, w


@dataclasses.dataclass(frozen=True, eq=False)
class SmoothedTrack:
    """A track's points moved onto the smoothest path within a tolerance of them.

    Attributes
    ----------
    x_m, y_m : numpy.ndarray, shape (M,)
        The points on the smoothed path (m), in the same order; the points as given when
        not smoothed.
    smoothed : bool
        Whether the points were moved: when their noise lengthens the polyline through them
        by more than TRACK_LENGTHENING_SHARE (a survey, a drawn line or a sparse track is kept
        as it is, and its turns are smoothed as a route's, :func:`smooth_path`).
    tolerance_m : float
        The tolerance (m): given, or estimated (:func:`estimate_path_noise`).
    tolerance_source : str
        ``"given"`` or ``"estimated"``.
    noise : PathNoise
        The points' noise, as estimated.
    moved_max_m : float
        The largest distance a point was moved (m), <= tolerance_m.
    """

    x_m: np.ndarray
    y_m: np.ndarray
    smoothed: bool
    tolerance_m: float
    tolerance_source: str
    noise: PathNoise
    moved_max_m: float

    def note(self, name: str) -> str:
        """One line for the user: what was estimated and done.

        Parameters
        ----------
        name : str
            The track's name, for the line.

        Returns
        -------
        str
        """
        noise = (f"noise {self.noise.noise_m:.3g} m (the spread of its {self.noise.points} points across the "
                 f"path, {self.noise.spacing_m:.3g} m apart)")
        if not self.smoothed:
            return (f"{name}: points kept as they are: {noise} lengthens it by "
                    f"{100 * self.noise.lengthens_share:.2g} %")
        why = "given" if self.tolerance_source == "given" else "estimated: the noise times sqrt(2 ln n)"
        return (f"{name}: {noise} lengthens it by {100 * self.noise.lengthens_share:.2g} %: its points moved onto the "
                f"smoothest path within {self.tolerance_m:.3g} m of them ({why}), by {self.moved_max_m:.3g} m at most")


def smooth_track_points(x_m: ArrayLike, y_m: ArrayLike, *, tolerance_m: float | None = None) -> SmoothedTrack:
    """A GPS track's points moved onto the smoothest path within the path tolerance.

    The path is fitted by :func:`_fit_in_tube` (a smoothing spline reweighted until it keeps
    within the tolerance of every point, smooth wherever the points only scatter), with the
    parameter the chord length between the points at first, then (four times) the length
    along the path just fitted, so that the bending penalty is one on curvature. Each point
    moves to the path's position at its own parameter. The route sampled along the moved
    points (:func:`profileopt.terrain.ground_track.route_from_track`) then follows the smoothed
    path, and is as long as it: between noisy points the polyline zigzags (1.5 m of noise
    every 3 m adds 30 % to its length, and as much to the time driven on it).

    Parameters
    ----------
    x_m, y_m : array_like, shape (M,)
        The track in the plane (m), M >= 2, finite, no point repeating the one before it.
    tolerance_m : float, optional
        Largest distance a point may move (m), > 0; None estimates it
        (:func:`estimate_path_noise`). Either way a track whose noise lengthens it by at most
        TRACK_LENGTHENING_SHARE is kept as it is.

    Returns
    -------
    SmoothedTrack

    Raises
    ------
    InputError
        A tolerance that is not a finite number > 0, coordinates of different shapes, fewer
        than 2 points, non-finite values or a repeated point.
    """
    from scipy.interpolate import CubicSpline

    x, y, step = _check_xy(x_m, y_m)
    tol, source, noise = _tolerance(x, y, tolerance_m)
    unchanged = SmoothedTrack(x_m=x.copy(), y_m=y.copy(), smoothed=False, tolerance_m=tol, tolerance_source=source,
                              noise=noise, moved_max_m=0.0)
    if x.size < _MIN_SMOOTHING_SAMPLES or noise.lengthens_share <= TRACK_LENGTHENING_SHARE:
        return unchanged
    centre = np.array([x.mean(), y.mean()])
    p = np.column_stack([x, y]) - centre
    chord = np.concatenate([[0.0], np.cumsum(step)])
    t = chord
    pieces = 8  # chords per interval for the length along the fitted path
    for k in range(_REPARAMETRISATIONS + 1):
        fitted, _ = _fit_in_tube(t, p, tol)
        if k == _REPARAMETRISATIONS:
            break
        spline = CubicSpline(t, fitted, bc_type="natural")
        fine = (t[:-1, None] + np.diff(t)[:, None] * np.arange(pieces) / pieces).ravel()
        at = spline(np.append(fine, t[-1]))
        along = np.hypot(np.diff(at[:, 0]), np.diff(at[:, 1])).reshape(-1, pieces).sum(axis=1)
        # where the fit stops and turns back (a reversal) its length barely grows: keep every
        # step at least a tenth of the chord's, so the parameter stays well spaced
        t = np.concatenate([[0.0], np.cumsum(np.maximum(along, 0.1 * step))])
    moved = float(np.max(np.hypot(fitted[:, 0] - p[:, 0], fitted[:, 1] - p[:, 1])))
    out = fitted + centre
    return SmoothedTrack(x_m=out[:, 0], y_m=out[:, 1], smoothed=True, tolerance_m=tol, tolerance_source=source,
                         noise=noise, moved_max_m=moved)


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
        (counter-clockwise in x, y); 0 on a straight; at most MAX_CURVATURE_1PM in size, which
        it is where the path stops and turns back (a cusp).
    max_deviation_m : float
        Largest distance hypot(x_m - x, y_m - y) from a sample to its fitted point (m),
        <= tolerance_m.
    tolerance_m : float
        The deviation allowed (m).
    smoothing_scale_m : float
        The smoothing spline's length scale (lam / sample density)^(1/4) (m): turns much
        shorter than it are smoothed away. inf for fewer than 5 samples (no smoothing).
    tolerance_source : str
        ``"given"`` (the caller's ``tolerance_m``) or ``"estimated"`` (from the path's noise).
    noise : PathNoise or None
        The path's noise as estimated (:func:`estimate_path_noise`).
    heading_rad : numpy.ndarray, shape (M,)
        Direction of travel along the smoothed path (rad, from +x towards +y), unwrapped
        along s: a reversal adds about pi.
    """

    s_m: np.ndarray
    x_m: np.ndarray
    y_m: np.ndarray
    curvature_1pm: np.ndarray
    max_deviation_m: float
    tolerance_m: float
    smoothing_scale_m: float
    tolerance_source: str = "given"
    noise: PathNoise | None = None
    heading_rad: np.ndarray | None = None


def _curvature(d1: np.ndarray, d2: np.ndarray, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Signed curvature of a path and its unwrapped heading, shape (M,) each, from the first
    and second derivatives of (x, y)(s) and its points, shape (M, 2).

    kappa = (x' y'' - y' x'') / (x'^2 + y'^2)^(3/2) at each point; where the path turns
    between two points by more than that gives (the heading's change over the length between
    them, |d theta| / |d p|: a cusp between them, where x' and y' vanish together, turns it
    by pi over almost no length), the larger; where x' and y' vanish at a point (0 / 0),
    the sharpest. All of it at most MAX_CURVATURE_1PM in size.
    """
    cross = d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]
    speed = np.hypot(d1[:, 0], d1[:, 1])
    stopped = speed <= 1e-12 * max(float(np.max(speed, initial=0.0)), 1e-300)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        kappa = np.where(stopped, 0.0, cross / np.where(stopped, 1.0, speed) ** 3)
    heading = np.arctan2(d1[:, 1], d1[:, 0])
    # a stopped point takes the direction it leaves in (or arrives from, at the end)
    if np.any(stopped) and not np.all(stopped):
        good = np.flatnonzero(~stopped)
        fill = good[np.minimum(np.searchsorted(good, np.flatnonzero(stopped)), good.size - 1)]
        heading[stopped] = heading[fill]
    turn = np.angle(np.exp(1j * np.diff(heading)))  # wrapped into (-pi, pi]
    step = np.hypot(np.diff(points[:, 0]), np.diff(points[:, 1]))
    with np.errstate(divide="ignore", invalid="ignore"):
        between = np.where(step > 0, np.abs(turn) / step, np.where(np.abs(turn) > 0, np.inf, 0.0))
    sign_between = np.where(turn >= 0, 1.0, -1.0)
    around = np.maximum(np.concatenate([[0.0], between]), np.concatenate([between, [0.0]]))
    which = np.where(np.concatenate([[0.0], between]) >= np.concatenate([between, [0.0]]),
                     np.concatenate([[1.0], sign_between]), np.concatenate([sign_between, [1.0]]))
    sharper = around > np.abs(kappa)
    kappa = np.where(sharper, which * around, kappa)
    kappa = np.where(stopped, MAX_CURVATURE_1PM, kappa)
    heading = np.concatenate([[heading[0]], heading[0] + np.cumsum(turn)])
    return np.clip(kappa, -MAX_CURVATURE_1PM, MAX_CURVATURE_1PM), heading


def smooth_path(x_m: ArrayLike, y_m: ArrayLike, *, tolerance_m: float | None = DEFAULT_PATH_TOLERANCE_M
                ) -> SmoothPath:
    """The smoothest path within the path tolerance of every sample, and its curvature.

    x(s) and y(s), s the cumulative chord length, are fitted with penalised cubic
    smoothing splines (:func:`scipy.interpolate.make_smoothing_spline`, which minimises
    sum (y_i - f(s_i))^2 + lam int f''(s)^2 ds; one lam for both coordinates). lam is found
    by a bracketing search on log(lam): the largest lam (the smoothest path) whose deviation
    hypot(x_fit - x, y_fit - y) from every sample is at most the tolerance. The least-squares
    line of each coordinate is taken out before the fit and put back after (a smoothing
    spline reproduces lines exactly), which keeps the banded system well conditioned for
    large lam. A path that is straight within the tolerance gets the largest lam tried
    (a smoothing scale of the route's length): curvature near 0.

    The tolerance is ``tolerance_m``, or, if None, estimated from the path's own noise
    (:func:`estimate_path_noise`): sigma sqrt(2 ln n), at least MIN_PATH_TOLERANCE_M.

    The curvature is kappa = (x' y'' - y' x'') / (x'^2 + y'^2)^(3/2) from the spline's
    derivatives, or the heading's change between two samples over their distance where that
    is sharper (a cusp between them), at most MAX_CURVATURE_1PM (a turn of radius
    MIN_PATH_TOLERANCE_M): an exact reversal, where x' and y' vanish together, is a turn of
    that radius, not a straight. The splines are natural (zero second derivative at the ends),
    so the curvature falls to 0 over about one smoothing scale at the path's two ends.

    Paths of more than 10,000 samples are fitted to the means of runs of consecutive
    samples (10,000 runs, each weighted by its count), for speed; the deviation is measured
    at every sample all the same. Fewer than 5 samples are too few to smooth: the path is
    then the interpolating spline of degree M - 1 (a line for 2 samples).

    Parameters
    ----------
    x_m, y_m : array_like, shape (M,)
        The path in the horizontal plane (m), M >= 2, finite, no point repeating the one
        before it.
    tolerance_m : float or None, default None (estimate it)
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

    x, y, step = _check_xy(x_m, y_m)
    tol, source, noise = _tolerance(x, y, tolerance_m)
    s = np.concatenate([[0.0], np.cumsum(step)])
    xy = np.column_stack([x, y])
    m = s.size
    extra = {"tolerance_source": source, "noise": noise}

    if m < _MIN_SMOOTHING_SAMPLES:
        if m == 2:
            heading = np.full(2, math.atan2(y[1] - y[0], x[1] - x[0]))
            return SmoothPath(s, x.copy(), y.copy(), np.zeros(2), 0.0, tol, math.inf, heading_rad=heading, **extra)
        spline = make_interp_spline(s, xy, k=m - 1)
        kappa, heading = _curvature(spline(s, 1), spline(s, 2), xy)
        return SmoothPath(s, x.copy(), y.copy(), kappa, 0.0, tol, math.inf, heading_rad=heading, **extra)

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

    def fit(scale_m: float) -> tuple[BSpline, float]:
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
    # the line adds slope to x', y'
    kappa, heading = _curvature(spline(sc, 1) + slope, spline(sc, 2), fitted)
    return SmoothPath(s, fitted[:, 0], fitted[:, 1], kappa, deviation, tol, lo_scale, heading_rad=heading, **extra)


@dataclasses.dataclass(frozen=True)
class SharpTurn:
    """A stretch of the path sharper than a turning circle, or a reversal.

    Attributes
    ----------
    s_m : float
        Where the stretch turns sharpest (m along the route).
    x_m, y_m : float
        The route's sample there (m).
    radius_m : float
        The smoothed path's tightest radius there, 1 / |kappa| (m).
    heading_change_rad : float
        How far the heading turns (rad, >= 0) over the stretch and REVERSAL_LENGTH_M / 2
        either side of it.
    reversal : bool
        Whether the heading turns by more than REVERSAL_HEADING_CHANGE_RAD within
        REVERSAL_LENGTH_M there.
    start_m, end_m : float
        The stretch's first and last sample (m along the route).
    """

    s_m: float
    x_m: float
    y_m: float
    radius_m: float
    heading_change_rad: float
    reversal: bool
    start_m: float
    end_m: float


def sharp_turns(s_m: ArrayLike, x_m: ArrayLike, y_m: ArrayLike, path: SmoothPath, *,
                min_turn_radius_m: float | None = None) -> list[SharpTurn]:
    """The stretches of a route sharper than a turning circle, and its reversals.

    A stretch is a run of consecutive samples whose smoothed curvature exceeds
    1 / ``min_turn_radius_m``, or whose heading turns by more than
    REVERSAL_HEADING_CHANGE_RAD between REVERSAL_LENGTH_M / 2 before and after them (a
    reversal). Each is reported once, at its sharpest sample.

    Parameters
    ----------
    s_m, x_m, y_m : array_like, shape (M,)
        The route's samples (m).
    path : SmoothPath
        Its smoothed path (:func:`smooth_path`).
    min_turn_radius_m : float, optional
        The vehicle's turning circle (m); None reports reversals only.

    Returns
    -------
    list of SharpTurn
        In order along the route.
    """
    s = np.asarray(s_m, dtype=float)
    kappa = np.abs(path.curvature_1pm)
    heading = path.heading_rad if path.heading_rad is not None else np.zeros(s.size)
    half = REVERSAL_LENGTH_M / 2
    change = np.abs(np.interp(s + half, s, heading) - np.interp(s - half, s, heading))
    reversal = change >= REVERSAL_HEADING_CHANGE_RAD * (1 - 1e-9)
    sharp = reversal.copy()
    if min_turn_radius_m is not None:
        sharp |= kappa > 1.0 / float(min_turn_radius_m)
    if not np.any(sharp):
        return []
    edges = np.diff(np.concatenate([[0], sharp.astype(np.int8), [0]]))
    starts, stops = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    # stretches less than REVERSAL_LENGTH_M apart are one turn
    join = s[starts[1:]] - s[stops[:-1] - 1] < REVERSAL_LENGTH_M
    starts = np.concatenate([starts[:1], starts[1:][~join]])
    stops = np.concatenate([stops[:-1][~join], stops[-1:]])
    x = np.asarray(x_m, dtype=float)
    y = np.asarray(y_m, dtype=float)
    turns = []
    for a, b in zip(starts, stops):
        i = a + int(np.argmax(kappa[a:b]))
        turned = abs(float(np.diff(np.interp([s[a] - half, s[b - 1] + half], s, heading))[0]))
        turns.append(SharpTurn(s_m=float(s[i]), x_m=float(x[i]), y_m=float(y[i]),
                               radius_m=float(1.0 / kappa[i]) if kappa[i] > 0 else math.inf,
                               heading_change_rad=turned, reversal=bool(np.any(reversal[a:b])),
                               start_m=float(s[a]), end_m=float(s[b - 1])))
    return turns


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
        The path tolerance used (m): given, or estimated from the route's x, y; for a route
        without x, y the one given, else MIN_PATH_TOLERANCE_M (unused).
    grade_scale_m : float
        The window over which the grade was measured (m).
    curvature_reach_m : float
        How far (m) the smoothing spreads a change of curvature: twice the spline's
        smoothing scale (:attr:`SmoothPath.smoothing_scale_m`); 0 without x, y. A turn's
        smoothed curvature reaches its full value only this far inside the turn, so a
        limit that must hold where the route's own samples turn takes the largest
        curvature within this reach (:func:`profileopt.core.path.segment_path`).
    tolerance_source : str
        ``"given"``, ``"estimated"`` (from the route's x, y), or ``""`` for a route without
        x, y.
    noise_m : float
        The horizontal noise estimated from the route's x, y (m; :func:`estimate_path_noise`);
        0 without x, y.
    noise_points : int
        How many measured points it was estimated from.
    turns : tuple of SharpTurn
        The stretches sharper than the vehicle's turning circle, and the reversals.
    min_turn_radius_m : float or None
        The turning circle they were judged against (m).
    """

    curvature_1pm: np.ndarray
    grade_rad: np.ndarray
    max_deviation_m: float
    tolerance_m: float
    grade_scale_m: float
    curvature_reach_m: float = 0.0
    tolerance_source: str = ""
    noise_m: float = 0.0
    noise_points: int = 0
    turns: tuple[SharpTurn, ...] = ()
    min_turn_radius_m: float | None = None

    @property
    def settings(self) -> dict[str, object]:
        """What a profile's settings record of the path: ``path_tolerance_m``, and for a route
        with x, y where it came from (``path_tolerance_source``) and the noise estimated
        (``path_noise_m``): a record for the reader (``verify`` estimates the tolerance
        again from the route and notes a recorded one that differs).

        Returns
        -------
        dict
        """
        out: dict[str, object] = {"path_tolerance_m": float(self.tolerance_m)}
        if self.tolerance_source:
            out["path_tolerance_source"] = self.tolerance_source
            out["path_noise_m"] = float(self.noise_m)
        return out


def route_geometry(route: Route, *, tolerance_m: float | None = DEFAULT_PATH_TOLERANCE_M,
                   grade_scale_m: float, min_turn_radius_m: float | None = None) -> RouteGeometry:
    """Curvature (:func:`smooth_path`) and grade (:func:`path_grade_rad`) of a route.

    Parameters
    ----------
    route : Route
        The route; its x_m, y_m (if given) are the path in the horizontal plane.
    tolerance_m : float or None, default None (estimate it from the route's x, y)
        Largest deviation of the smoothed path from any sample (m), > 0.
    grade_scale_m : float
        Window of the grade's least-squares line (m), > 0.
    min_turn_radius_m : float, optional
        The vehicle's turning circle (m): the turns sharper than it are listed
        (:func:`sharp_turns`, :attr:`RouteGeometry.turns`); reversals always are.

    Returns
    -------
    RouteGeometry

    Raises
    ------
    InputError
        A tolerance or grade scale that is not a finite number > 0.
    """
    tol = MIN_PATH_TOLERANCE_M if tolerance_m is None else _check_tolerance(tolerance_m)
    grade = path_grade_rad(route.s_m, route.z_m, scale_m=grade_scale_m)
    circle = None if min_turn_radius_m is None else float(min_turn_radius_m)
    if route.x_m is None or route.y_m is None:
        return RouteGeometry(curvature_1pm=np.zeros(route.s_m.size), grade_rad=grade, max_deviation_m=0.0,
                             tolerance_m=tol, grade_scale_m=float(grade_scale_m), min_turn_radius_m=circle)
    path = smooth_path(route.x_m, route.y_m, tolerance_m=tolerance_m)
    reach = 2.0 * path.smoothing_scale_m if math.isfinite(path.smoothing_scale_m) else 0.0
    turns = sharp_turns(route.s_m, route.x_m, route.y_m, path, min_turn_radius_m=min_turn_radius_m)
    noise = path.noise if path.noise is not None else PathNoise(0.0, 0, path.tolerance_m)
    return RouteGeometry(curvature_1pm=path.curvature_1pm, grade_rad=grade, max_deviation_m=path.max_deviation_m,
                         tolerance_m=path.tolerance_m, grade_scale_m=float(grade_scale_m), curvature_reach_m=reach,
                         tolerance_source=path.tolerance_source, noise_m=noise.noise_m, noise_points=noise.points,
                         turns=tuple(turns), min_turn_radius_m=circle)
