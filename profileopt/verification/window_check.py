"""A simulated drive judged by roughness windows (issue 10): in every window, the peak force
while the vehicle is inside it against that window's own prediction and the limit.

A profile keeps the force limit when, for every roughness window [a, a + W] of the route (a
anywhere in [s_0, s_end - W], W the profile's ``roughness_window_m``), every speed driven
while the vehicle is inside the window is admissible for the window's RI. The windows hold
finitely many distinct sets of samples; :func:`profileopt.terrain.roughness.roughness_windows`
lists each set once, with its extent [start, stop]: the union of the stretches of every
window [a, a + W] that holds it (issue 29: a window starting between two samples can hold a
set that no window starting or ending at a sample holds). Judging all the windows holding
one set is judging the speeds and the forces on its extent, so :func:`check_windows` puts each
entry to the simulation (:mod:`profileopt.physics.simulate`) over its extent:

*predicted*
    The model's largest force over the speeds driven inside the window, at the window's
    own RI (the planner holds a segment to each window it meets the same way). v^2 is
    linear in s inside each segment, so the speeds driven inside [start, stop] are the
    interval between the least and the largest of the speeds at start, at stop and at the
    segment boundaries between; the force over it is largest at one of its ends or at an interior
    maximum of the force in speed (only SBEM:TF has one, its resonance peak, whose frequency
    ratio depends on zeta alone: :func:`profileopt.physics.forces.force_peak_ratio`).
*simulated*
    The largest |F| of the simulation's rows whose position lies in [start, stop]. The
    extent is closed; where an end is open (no window holding the set reaches it, only
    windows arbitrarily close), the rows at that end are judged too: conservative by at
    most the jump of the force at a kink of the wheel's path exactly there.
*the datum of the excitation force*
    The transmitted force F_T = m x'' has none. The excitation force F = k y~ + c y~' is
    measured, in each window, from the window's own least-squares line of the base input y
    (the wheel's lowest point) over the window's samples: the samples and the fit of the
    window's RI (Eq. 1), so that a constant grade causes no excitation force. With
    ``detrend=False`` it is the mean of y over those samples. The simulator measures y from
    each segment's line instead; the two differ by a function of s and v alone:
    F_window = F_segment + k (L_seg(s) - L_win(s)) + c v (m_seg - m_win), L the lines and m
    their slopes, which is how the excitation series is moved to each window's datum.

Per window the excitation series is a different function of time, A(t) - C - m B(t) (A and B
the same for every window), so its peak is not a range maximum of one series. It is found
exactly by bounding: the rows are cut into blocks of :data:`BLOCK_ROWS`, each block's
extremes of A and B bound |F| over it, the rows of A's extremes give a lower bound, and only
the blocks whose bound reaches it are evaluated row by row.
"""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING

import numpy as np

from ..core.stations import segment_index, segment_samples
from ..physics.forces import force_peak_ratio, get_model
from ..terrain.roughness import (
    RoughnessWindows,
    range_extremes,
    segment_line_fit,
    step_width,
    window_line_moments,
    worst_case_elevation,
)

if TYPE_CHECKING:
    from ..core.route import Route
    from ..core.vehicle import Vehicle
    from ..physics.simulate import QuarterCarRun

__all__ = ["WindowCheck", "check_windows", "window_speed_range_mps", "window_predicted_force_n",
           "BLOCK_ROWS", "UNDERPREDICTION_TOLERANCE"]

#: Rows of the simulation per block of the bound on a window's excitation peak.
BLOCK_ROWS = 64
#: A simulated peak counts as above the prediction only beyond this share of the limit, so
#: that the ringing after a rough patch over smooth ground (prediction 0) is not counted.
UNDERPREDICTION_TOLERANCE = 0.01
#: Block-window pairs bounded at once (memory: about 12 arrays of this length).
_PAIRS_PER_CHUNK = 1 << 20


@dataclasses.dataclass(frozen=True, eq=False)
class WindowCheck:
    """Every roughness window of a route, its predicted and its simulated peak force.

    Attributes
    ----------
    window_m : float
        Window length W (m).
    start_m, stop_m : numpy.ndarray, shape (K,)
        Each entry's extent (m): every window [a, a + W] holding its samples lies in it
        (:class:`~profileopt.terrain.roughness.RoughnessWindows`); non-decreasing.
    ri : numpy.ndarray, shape (K,)
        Each window's detrended RI (Eq. 1, dimensionless).
    speed_low_mps, speed_high_mps : numpy.ndarray, shape (K,)
        The least and the largest speed driven inside each window (m/s).
    predicted_n : numpy.ndarray, shape (K,)
        The model's largest force over those speeds at the window's RI (N).
    simulated_n : numpy.ndarray, shape (K,)
        The simulated peak |F| of the model's force while the vehicle is inside (N).
    peak_s_m : numpy.ndarray, shape (K,)
        Where the vehicle is when it peaks (m).
    limit_n : float
        The vehicle's limit for the model's force (N).
    model : str
        Force model key.
    datum : str
        Datum of the excitation force: ``"window line"``, ``"window mean"``, or ``"none"``
        (the transmitted force).
    """

    window_m: float
    start_m: np.ndarray
    stop_m: np.ndarray
    ri: np.ndarray
    speed_low_mps: np.ndarray
    speed_high_mps: np.ndarray
    predicted_n: np.ndarray
    simulated_n: np.ndarray
    peak_s_m: np.ndarray
    limit_n: float
    model: str
    datum: str

    @property
    def count(self) -> int:
        """Number of windows K."""
        return int(self.start_m.size)

    @property
    def ratio(self) -> np.ndarray:
        """Simulated peak / limit of each window (dimensionless, shape (K,))."""
        return self.simulated_n / self.limit_n

    @property
    def over(self) -> np.ndarray:
        """Windows whose simulated peak exceeds the limit (bool, shape (K,))."""
        return self.ratio > 1.0

    @property
    def over_count(self) -> int:
        """Number of windows over the limit."""
        return int(np.count_nonzero(self.over))

    @property
    def underpredicted(self) -> np.ndarray:
        """Windows whose simulated peak exceeds the prediction by more than 1 % of the limit
        (bool, shape (K,))."""
        return self.simulated_n > self.predicted_n + UNDERPREDICTION_TOLERANCE * self.limit_n

    @property
    def worst(self) -> int:
        """Index of the window with the largest ratio.

        A peak lies in every window that holds its position, so many windows share the
        largest ratio; of those, the one with the least prediction (where the model is most
        wrong), and the first of those.
        """
        tied = np.flatnonzero(self.simulated_n == np.max(self.simulated_n))
        return int(tied[np.argmin(self.predicted_n[tied])])

    @property
    def worst_ratio(self) -> float:
        """Largest simulated peak / limit of any window (dimensionless)."""
        return float(self.simulated_n[self.worst] / self.limit_n)

    def describe(self, k: int) -> dict:
        """One window, JSON-ready (SI units in the key names).

        Parameters
        ----------
        k : int
            Index of the window.

        Returns
        -------
        dict
            ``start_m``, ``stop_m``, ``ri``, ``speed_low_mps``, ``speed_high_mps``,
            ``peak_s_m``, ``simulated_n``, ``predicted_n``, ``limit_n``, ``ratio``.
        """
        return {"start_m": float(self.start_m[k]), "stop_m": float(self.stop_m[k]),
                "ri": float(self.ri[k]), "speed_low_mps": float(self.speed_low_mps[k]),
                "speed_high_mps": float(self.speed_high_mps[k]), "peak_s_m": float(self.peak_s_m[k]),
                "simulated_n": float(self.simulated_n[k]), "predicted_n": float(self.predicted_n[k]),
                "limit_n": self.limit_n, "ratio": float(self.simulated_n[k] / self.limit_n)}

    def summary(self) -> dict:
        """The window counts and the worst window, JSON-ready.

        Returns
        -------
        dict
            ``window_m``, ``windows``, ``over_count``, ``underpredicted_count``, ``datum``
            and ``worst`` (:meth:`describe` of the worst window).
        """
        return {"window_m": self.window_m, "windows": self.count, "over_count": self.over_count,
                "underpredicted_count": int(np.count_nonzero(self.underpredicted)), "datum": self.datum,
                "worst": self.describe(self.worst)}

    def worst_meeting(self, boundaries_m: np.ndarray) -> np.ndarray:
        """For each segment, the worst of the windows that share a point with it.

        Parameters
        ----------
        boundaries_m : numpy.ndarray, shape (N+1,)
            Segment boundaries (m), increasing.

        Returns
        -------
        numpy.ndarray of int, shape (N,)
            Index of the window with the largest simulated peak among those meeting each
            segment (the first, if several).
        """
        b = np.asarray(boundaries_m, dtype=float)
        tol = 1e-9 * max(self.window_m, 1.0)
        lo = np.searchsorted(self.stop_m, b[:-1] - tol, side="left")
        hi = np.maximum(np.searchsorted(self.start_m, b[1:] + tol, side="right"), lo + 1)
        return _range_argmax(self.simulated_n, lo, np.minimum(hi, self.count))


def _range_argmax(values: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """The first index of the largest of ``values[lo[i]:hi[i]]`` for each non-empty range."""
    sizes = hi - lo
    owner = np.repeat(np.arange(lo.size), sizes)
    idx = np.repeat(lo - np.cumsum(sizes) + sizes, sizes) + np.arange(int(sizes.sum()))
    starts = np.cumsum(sizes) - sizes
    best = np.maximum.reduceat(values[idx], starts)
    return np.minimum.reduceat(np.where(values[idx] == best[owner], idx, values.size), starts)


def window_speed_range_mps(boundaries_m: np.ndarray, speed_mps: np.ndarray, start_m: np.ndarray,
                           stop_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The least and the largest speed driven inside each stretch [start, stop] of a profile.

    Inside a segment the acceleration is constant, so v^2 is linear in s and v monotone:
    the extremes over a stretch are among the speeds at its two ends (v^2 interpolated
    linearly, exact) and at the boundaries inside it.

    Parameters
    ----------
    boundaries_m, speed_mps : numpy.ndarray, shape (N+1,)
        The profile: segment boundaries (m) and the speeds there (m/s).
    start_m, stop_m : numpy.ndarray, shape (K,)
        The stretches (m), inside [boundaries_m[0], boundaries_m[-1]].

    Returns
    -------
    low, high : numpy.ndarray, shape (K,)
        Speeds (m/s).
    """
    b = np.asarray(boundaries_m, dtype=float)
    v = np.asarray(speed_mps, dtype=float)
    start, stop = np.asarray(start_m, dtype=float), np.asarray(stop_m, dtype=float)
    ends = np.sqrt(np.maximum(np.interp(np.stack([start, stop]), b, v * v), 0.0))
    low, high = ends.min(axis=0), ends.max(axis=0)
    first = np.searchsorted(b, start, side="left")
    stop_i = np.searchsorted(b, stop, side="right")
    inner = np.flatnonzero(stop_i > first)
    if inner.size:
        least, largest = range_extremes(v, first[inner], stop_i[inner])
        low[inner] = np.minimum(low[inner], least)
        high[inner] = np.maximum(high[inner], largest)
    return low, high


def window_predicted_force_n(model: str, vehicle: "Vehicle", ri: np.ndarray, speed_low_mps: np.ndarray,
                             speed_high_mps: np.ndarray) -> np.ndarray:
    """The model's largest force over every speed in [low, high], at each RI: exact.

    Prev:BEM, IECM and SBEM:EF grow with speed (Eq. 6, 11 and the reconstruction: e, X_w
    fixed, each a positive combination of 1 and V or V^2), so their largest force is at
    ``high``. SBEM:TF is largest at an end or at its resonance peak
    V = r_p 2 X_w wn / pi (:func:`profileopt.physics.forces.force_peak_ratio`) when that lies inside.

    Parameters
    ----------
    model : str
        Force model key.
    vehicle : Vehicle
        The quarter car (wn, zeta, r, h, Pe).
    ri : numpy.ndarray, shape (K,)
        RI of each window (dimensionless).
    speed_low_mps, speed_high_mps : numpy.ndarray, shape (K,)
        The speed interval of each window (m/s), low <= high.

    Returns
    -------
    numpy.ndarray, shape (K,)
        Force (N).
    """
    spec = get_model(model)
    ri = np.asarray(ri, dtype=float)
    low, high = np.asarray(speed_low_mps, dtype=float), np.asarray(speed_high_mps, dtype=float)
    candidates = [low, high]
    if spec.key == "sbem_tf":
        x_w = np.asarray(step_width(worst_case_elevation(ri, vehicle), vehicle), dtype=float)
        r_peak = force_peak_ratio(vehicle.damping_ratio)
        if r_peak is not None:
            peak = r_peak * 2.0 * x_w * vehicle.natural_frequency_radps / math.pi
            candidates.append(np.where((peak > low) & (peak < high), peak, low))
    speeds = np.stack(candidates)
    return np.asarray(spec.force_n(speeds, np.broadcast_to(ri, speeds.shape), vehicle), dtype=float).max(axis=0)


def _window_rows(run_s: np.ndarray, start: np.ndarray, stop: np.ndarray, tol: float
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Rows lo <= j < hi of the simulation with start <= s_j <= stop (at least one row)."""
    lo = np.searchsorted(run_s, start - tol, side="left")
    hi = np.searchsorted(run_s, stop + tol, side="right")
    lo = np.minimum(lo, run_s.size - 1)
    return lo, np.maximum(hi, lo + 1)


def _affine_peaks(a: np.ndarray, b: np.ndarray, lo: np.ndarray, hi: np.ndarray, slope: np.ndarray,
                  offset: np.ndarray, block: int = BLOCK_ROWS) -> tuple[np.ndarray, np.ndarray]:
    """max over lo_k <= j < hi_k of |a_j - offset_k - slope_k b_j| and its row, for every k.

    Exact: the bound of a block (from its extremes of a and b) is never below its values,
    so a block whose bound is below a value already found cannot hold the peak.
    """
    n = a.size
    blocks = -(-n // block)
    shape = (blocks, block)
    a_blk = np.pad(a, (0, blocks * block - n), mode="edge").reshape(shape)
    b_blk = np.pad(b, (0, blocks * block - n), mode="edge").reshape(shape)
    summary = (a_blk.max(1), a_blk.min(1), b_blk.max(1), b_blk.min(1))
    base = np.arange(blocks) * block
    reps = np.minimum(np.stack([base + a_blk.argmax(1), base + a_blk.argmin(1)]), n - 1)
    first_blk = lo // block
    per = (hi - 1) // block - first_blk + 1
    cum = np.cumsum(per)
    cuts = np.searchsorted(cum, np.arange(1, int(cum[-1]) // _PAIRS_PER_CHUNK + 1) * _PAIRS_PER_CHUNK, side="right")
    bounds = np.unique(np.concatenate([[0], cuts, [lo.size]]))
    peak, where = np.empty(lo.size), np.empty(lo.size, dtype=np.intp)
    for k0, k1 in zip(bounds[:-1], bounds[1:]):
        ks = slice(int(k0), int(k1))
        peak[ks], where[ks] = _affine_peaks_chunk(a, b, lo[ks], hi[ks], slope[ks], offset[ks], first_blk[ks],
                                                  per[ks], summary, reps, block)
    return peak, where


def _affine_peaks_chunk(a, b, lo, hi, slope, offset, first_blk, per, summary, reps, block):
    """:func:`_affine_peaks` for a chunk of windows (indices local to the chunk)."""
    a_max, a_min, b_max, b_min = summary
    starts = np.cumsum(per) - per
    owner = np.repeat(np.arange(lo.size), per)
    blk = np.repeat(first_blk - starts, per) + np.arange(int(per.sum()))
    m, c = slope[owner], offset[owner]
    mb_lo = np.minimum(m * b_min[blk], m * b_max[blk])
    mb_hi = np.maximum(m * b_min[blk], m * b_max[blk])
    bound = np.maximum(a_max[blk] - c - mb_lo, c + mb_hi - a_min[blk])
    # a lower bound: each window's first row and the rows of a's extremes inside it
    found_row = lo[owner].copy()
    found = np.abs(a[found_row] - c - m * b[found_row])
    for rows in reps[:, blk]:
        val = np.where((rows >= lo[owner]) & (rows < hi[owner]), np.abs(a[rows] - c - m * b[rows]), -np.inf)
        better = val > found
        found, found_row = np.where(better, val, found), np.where(better, rows, found_row)
    best = np.maximum.reduceat(found, starts)
    at = np.minimum.reduceat(np.where(found == best[owner], np.arange(found.size), found.size), starts)
    best_row = found_row[at]
    # row by row, the blocks that may hold more
    cand = np.flatnonzero(bound >= best[owner] * (1.0 - 1e-12))
    step = max(_PAIRS_PER_CHUNK // (4 * block), 1)
    for part in range(0, cand.size, step):
        pick = cand[part:part + step]
        who = owner[pick]
        rows = blk[pick, None] * block + np.arange(block)[None, :]
        inside = (rows >= lo[who, None]) & (rows < hi[who, None])
        rows = np.minimum(rows, a.size - 1)
        vals = np.where(inside, np.abs(a[rows] - offset[who, None] - slope[who, None] * b[rows]), -np.inf)
        col = vals.argmax(1)
        val, row = vals[np.arange(pick.size), col], rows[np.arange(pick.size), col]
        order = np.lexsort((-row, val, who))  # by window, the largest value last (the first row on ties)
        last = order[np.flatnonzero(np.append(who[order][1:] != who[order][:-1], True))]
        better = val[last] > best[who[last]]
        best[who[last][better]], best_row[who[last][better]] = val[last][better], row[last][better]
    return best, best_row


def _excitation_terms(route: "Route", run: "QuarterCarRun", k_spring: float, c_damp: float, detrend: bool
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray, float, float]:
    """The datum-free parts of the excitation force, and y at the route's samples.

    Returns A = k (y - y0) + c y' and B = k (s - s0) + c v at the rows, y at the samples,
    y0 and s0: a window with line y ~ level + m (s - s_mean) has F = A - C - m B with
    C = k (level - y0) - k m (s_mean - s0). A is the simulator's F plus its segment datum
    (:func:`profileopt.physics.simulate.simulate_quarter_car`: the least-squares line of y over each
    segment's samples, :func:`profileopt.terrain.roughness.segment_line_fit`).
    """
    s_row, v_row = run.s_m, run.speed_mps
    b = run.boundaries_m
    # y at the samples, from the simulation's own path (its rows are much finer than the samples)
    y_samples = np.interp(route.s_m, s_row, run.base_m)
    starts, stops = segment_samples(route.s_m, b)
    fit = segment_line_fit(route.s_m, y_samples, starts, stops, detrend=detrend)
    s0, level, trend = fit.s0_m.copy(), fit.level_m.copy(), fit.slope.copy()
    empty = np.flatnonzero(fit.count == 0)
    middle = 0.5 * (b[empty] + b[empty + 1])
    s0[empty], level[empty], trend[empty] = middle, np.interp(middle, route.s_m, y_samples), 0.0
    seg = segment_index(s_row, b)
    # a row on an interior boundary followed by a row at the same time is the value just
    # before a kink there: the simulator measured it from the segment before
    before = np.flatnonzero((seg > 0) & (s_row == b[seg]) & np.append(run.time_s[1:] == run.time_s[:-1], False))
    seg[before] -= 1
    y0, s_ref = float(y_samples[0]), float(route.s_m[0])
    line = (level[seg] - y0) + trend[seg] * (s_row - s0[seg])
    a_part = run.excitation_n + k_spring * line + c_damp * trend[seg] * v_row
    b_part = k_spring * (s_row - s_ref) + c_damp * v_row
    return a_part, b_part, y_samples, y0, s_ref


def check_windows(route: "Route", run: "QuarterCarRun", speed_mps: np.ndarray, vehicle: "Vehicle", *,
                  model: str, windows: RoughnessWindows, detrend: bool = True) -> WindowCheck:
    """Judge a simulated drive by roughness windows (module docstring).

    Parameters
    ----------
    route : Route
        The terrain (samples).
    run : QuarterCarRun
        The simulated drive of the profile over ``route``
        (:func:`profileopt.physics.simulate.simulate_quarter_car`).
    speed_mps : numpy.ndarray, shape (N+1,)
        The profile's speeds at ``run.boundaries_m`` (m/s).
    vehicle : Vehicle
        The quarter car and its limits.
    model : str
        Force model key: its force is simulated, predicted and limited.
    windows : RoughnessWindows
        The route's roughness windows, of the length the profile was planned with
        (:func:`profileopt.terrain.roughness.roughness_windows`; :attr:`profileopt.verification.limit_check.LimitCheck.windows`).
    detrend : bool, default True
        Datum of the excitation force: each window's least-squares line (True) or mean.

    Returns
    -------
    WindowCheck
    """
    spec = get_model(model)
    window_m = windows.window_m
    start, stop = windows.start_m, windows.stop_m
    low, high = window_speed_range_mps(run.boundaries_m, speed_mps, start, stop)
    # the dynamic model predicts by simulating: its prediction is the simulated peak (below)
    predicted = None if spec.key == "dynamic" else window_predicted_force_n(spec.key, vehicle, windows.ri, low, high)
    tol = 1e-9 * max(window_m, 1.0)
    lo, hi = _window_rows(run.s_m, start, stop, tol)
    zeros = np.zeros(windows.count)
    if spec.quantity == "transmitted":
        peak, row = _affine_peaks(run.transmitted_n, np.zeros_like(run.transmitted_n), lo, hi, zeros, zeros)
        datum = "none"
    else:
        k_spring, c_damp = vehicle.spring_n_per_m, vehicle.damping_ns_per_m
        a_part, b_part, y_samples, y0, s_ref = _excitation_terms(route, run, k_spring, c_damp, detrend)
        first, last = windows.first_sample, windows.stop_sample
        _, var_s, cov, _ = window_line_moments(route.s_m, y_samples, first, last,
                                               block_m=window_m * (1 + 1e-6) + 2 * tol, with_var_z=False)
        slope = np.where(var_s > 0, cov / np.where(var_s > 0, var_s, 1.0), 0.0) if detrend else zeros
        count = (last - first).astype(float)
        mean_s = _window_sums(route.s_m - s_ref, first, last) / count  # relative to s0 and y0
        mean_y = _window_sums(y_samples - y0, first, last) / count
        offset = k_spring * mean_y - k_spring * slope * mean_s
        peak, row = _affine_peaks(a_part, b_part, lo, hi, slope, offset)
        datum = "window line" if detrend else "window mean"
    return WindowCheck(window_m=window_m, start_m=start, stop_m=stop, ri=windows.ri, speed_low_mps=low,
                       speed_high_mps=high, predicted_n=peak if predicted is None else predicted, simulated_n=peak, peak_s_m=run.s_m[row],
                       limit_n=spec.limit_n(vehicle), model=spec.key, datum=datum)


def _window_sums(values: np.ndarray, first: np.ndarray, stop: np.ndarray) -> np.ndarray:
    """Sums of values[first:stop] from one running sum (values relative to the route's
    first sample, so that its rounding stays far below a millimetre)."""
    prefix = np.concatenate([[0.0], np.cumsum(values)])
    return prefix[stop] - prefix[first]
