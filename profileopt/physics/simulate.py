"""A quarter car driven over a route's own elevation samples: the forces a plan really causes.

The force models (:mod:`profileopt.physics.forces`) predict a worst case from a statistic of the
terrain (the RI and a confidence level). This module measures instead: it drives the
linear quarter car of a :class:`~profileopt.core.vehicle.Vehicle` over the measured elevation
samples at the speeds of a profile and records the forces.

Model
-----
A sprung mass m on a spring k = m wn^2 and a damper c = 2 zeta m wn (docs/paper-notes.md), linear,
written about static equilibrium (gravity and the static spring force cancel and are left
out). The base input y is the height of the wheel's lowest point (its centre minus r), the
wheel being rigid, of radius r, and always in contact:

    m x'' = -k (x - y) - c (x' - y')                                    (Fig. 3)

Forces (N), both positive upwards:

``transmitted``
    F_T = k (y - x) + c (y' - x') = m x'', the force the suspension passes into the frame:
    the quantity of Eq. (13) (Inman, Engineering Vibration, section 2.4), limited by
    ``max_transmitted_force_n``.
``excitation``
    F = k y + c y', the base-excitation force of Eq. (9) (F = m x'' + c x' + k x in the
    paper's derivation: the equivalent force the moving ground applies to the oscillator),
    limited by ``max_excitation_force_n``. Its value depends on where y = 0 is. The model's
    e is measured from the terrain's mean (Eq. 8 assumes zero-mean elevations) after the RI
    removed each segment's trend line (:func:`profileopt.terrain.roughness.segment_roughness_index`),
    so here y is measured from the least-squares line of y over each segment's samples
    (``detrend=True``) or from the segment's mean (``detrend=False``). Then a constant grade
    causes no excitation force, as it causes no roughness.

Wheel geometry
--------------
The ground the route means is the polyline through its samples (straight lines between
them). A rigid wheel of radius r rolls on it, and the base input is the exact path of its
lowest point, :func:`profileopt.physics.wheel.wheel_path`: a chain of the segments offset by r
along their normals and of circular arcs of radius r about the convex vertices (Fig. 2), with
every kink (where the contact jumps from one piece to another: a concave vertex, the edge
of a step met ahead, a pothole bridged) located exactly. A step of height e < r is climbed
over X_w = sqrt(2 e r - e^2) (Eq. 2); on a straight incline of slope m,
y = z + r (sqrt(1 + m^2) - 1) however the samples are spaced.

A kink of the path, a jump dm of its slope, is a jump c v dm of the transmitted and of the
excitation force at speed v: the damper's velocity jumps. So a result depends on how the
route was sampled wherever the polyline through the samples differs from the ground: on
smooth ground sampled every h each concave vertex is a kink of about z'' h, and the forces
differ from those of the smooth ground by up to about c v |z''| h / 2 (first order in h);
a step is as steep as the samples make it (0.15 m between samples 5 cm apart is a ramp of
slope 3, whose top edge the wheel meets with a kink), and its force grows without bound as
the sampling around it gets finer (a vertical step has no finite answer for a rigid wheel).

Integration
-----------
The speed profile (boundaries s_i and speeds v_i, constant acceleration inside a segment,
so v^2 is linear in s) gives the time of every position exactly. Knots are placed at every
break of the wheel's path (kinks and the tangent joins of lines and arcs), along each arc
every :data:`MAX_ARC_STEP_RAD` of its angle, at every segment boundary and on a uniform
time grid of step dt (:func:`choose_time_step_s`). At each knot the path gives y and its
slope from both sides exactly; between knots the input is the quadratic in time with those
end slopes, exact on the path's lines (v linear in t), second order on its arcs. The linear
ODE is solved exactly for that input (:mod:`profileopt.physics.quarter_car`); nothing is smoothed.

The forces are recorded at every knot, from both sides at a kink, and between knots where
either force turns (its derivative changes sign: the stationary point is placed by the cubic
through the ends and evaluated exactly), so each segment's peak is the largest value the
forces take while the wheel is in it, not the largest at a grid point. The peaks converge as
dt shrinks; the tests compare them with an adaptive integrator at tight tolerances.
"""

from __future__ import annotations

import dataclasses
import math
import time
from typing import TYPE_CHECKING

import numpy as np

from ..core.kinematics import segment_accel_mps2, segment_time_s
from ..core.stations import segment_index, segment_samples
from ..core.vehicle import require_vehicle
from ..errors import InputError
from .quarter_car import hermite_extremum, knot_jumps, respond, transition
from .wheel import WheelPath, wheel_path
from ..terrain.roughness import segment_line_fit

if TYPE_CHECKING:
    from ..core.vehicle import Vehicle

__all__ = [
    "QuarterCarRun",
    "boundary_times_s",
    "position_at_time",
    "choose_time_step_s",
    "simulate_quarter_car",
    "STEPS_PER_SAMPLE",
    "STEPS_PER_PERIOD",
    "MAX_ARC_STEP_RAD",
    "MAX_STEPS",
    "TooLongToSimulate",
]

#: No longer a bound on dt (the path's kinks are knots); kept for callers that read it.
STEPS_PER_SAMPLE = 4
#: Time steps per natural period of the suspension, at the least.
STEPS_PER_PERIOD = 200
#: Largest angle of the wheel's arcs between two knots (rad).
MAX_ARC_STEP_RAD = 0.02
#: Upper bound on the number of time steps (memory: about 15 arrays of this length).
MAX_STEPS = 20_000_000
#: Knots whose forces are computed at once (the temporaries of one chunk fit in a cache).
CHUNK_KNOTS = 1 << 16


class TooLongToSimulate(InputError):
    """A speed profile that takes more than :data:`MAX_STEPS` time steps to simulate.

    Attributes
    ----------
    steps : int
        The time steps it needs.
    time_step_s : float
        Their length (s).
    total_s : float
        How long the profile takes (s).
    slowest : int
        Its slowest segment (the index of its first boundary), of ``segments``.
    segments : int
        The profile's segments.
    segment_m, speeds_mps, segment_s : tuple of float, tuple of float, float
        That segment's ends (m), the speeds there (m/s) and the time on it (s).
    """

    def __init__(self, message: str, *, steps: int, time_step_s: float, total_s: float, slowest: int, segments: int,
                 segment_m: tuple[float, float], speeds_mps: tuple[float, float], segment_s: float) -> None:
        super().__init__(message)
        self.steps, self.time_step_s, self.total_s = steps, time_step_s, total_s
        self.slowest, self.segments = slowest, segments
        self.segment_m, self.speeds_mps, self.segment_s = segment_m, speeds_mps, segment_s


@dataclasses.dataclass(frozen=True, eq=False)
class QuarterCarRun:
    """A simulated drive: forces at every knot and turning point, and per-segment peaks.

    The time series hold one row per knot of the input (path breaks, arc steps, segment
    boundaries, the uniform time grid), two rows with the same time at a kink of the
    wheel's path (the values just before and just after it: the forces jump there), and a
    row at every turning point of either force between knots.

    Attributes
    ----------
    time_s : numpy.ndarray, shape (K,)
        Time of each row (s), non-decreasing.
    s_m : numpy.ndarray, shape (K,)
        Position of the wheel (m).
    speed_mps : numpy.ndarray, shape (K,)
        Speed (m/s).
    base_m : numpy.ndarray, shape (K,)
        Base input y (the wheel's lowest point), in the route's elevation datum (m).
    mass_m : numpy.ndarray, shape (K,)
        Sprung-mass position x about static equilibrium, same datum as ``base_m`` (m).
    transmitted_n : numpy.ndarray, shape (K,)
        F_T = k (y - x) + c (y' - x') = m x'' (N).
    excitation_n : numpy.ndarray, shape (K,)
        F = k y + c y' with y measured from the segment's trend line or mean (N).
    boundaries_m : numpy.ndarray, shape (N+1,)
        Segment boundaries (m).
    transmitted_peak_n, excitation_peak_n : numpy.ndarray, shape (N,)
        Largest |F_T| and |F| while the wheel is in each segment (N), its ends included
        from inside.
    time_step_s : float
        dt of the uniform time grid (s).
    steps_per_sample : float
        Grid steps per route sample interval at the top speed (informative only).
    timings_s : dict
        Wall-clock seconds: ``envelope`` (the wheel's path), ``integrate``, ``total``.
    path : WheelPath
        The base input y(s) the wheel followed.
    """

    time_s: np.ndarray
    s_m: np.ndarray
    speed_mps: np.ndarray
    base_m: np.ndarray
    mass_m: np.ndarray
    transmitted_n: np.ndarray
    excitation_n: np.ndarray
    boundaries_m: np.ndarray
    transmitted_peak_n: np.ndarray
    excitation_peak_n: np.ndarray
    time_step_s: float
    steps_per_sample: float
    timings_s: dict
    path: WheelPath

    @property
    def steps(self) -> int:
        """Number of steps of the uniform time grid."""
        return int(round(float(self.time_s[-1]) / self.time_step_s))


def boundary_times_s(boundaries_m: np.ndarray, speed_mps: np.ndarray) -> np.ndarray:
    """Arrival time at each segment boundary (s), starting at 0.

    With constant acceleration inside a segment (v^2 linear in s) the time to cross it is
    exactly dt_i = 2 L_i / (v_i + v_{i+1}), which holds for a start or stop at rest too.

    Parameters
    ----------
    boundaries_m : numpy.ndarray, shape (N+1,)
        Segment boundaries (m), strictly increasing.
    speed_mps : numpy.ndarray, shape (N+1,)
        Speeds at the boundaries (m/s), >= 0, never 0 at both ends of a segment.

    Returns
    -------
    numpy.ndarray, shape (N+1,)
        Times (s).

    Raises
    ------
    InputError
        A negative speed, or a segment with zero speed at both ends (never crossed).
    """
    b = np.asarray(boundaries_m, dtype=float)
    v = np.asarray(speed_mps, dtype=float)
    if np.any(v < 0) or not np.all(np.isfinite(v)):
        raise InputError("speed profile: speeds must be finite and >= 0 m/s")
    both = v[:-1] + v[1:]
    stuck = np.flatnonzero(both <= 0)
    if stuck.size:
        i = stuck[0]
        raise InputError(
            f"speed profile: the segment from {b[i]:g} to {b[i + 1]:g} m has speed 0 at both ends, "
            "so the vehicle never crosses it; give it a speed > 0 at one end at least"
        )
    return np.concatenate([[0.0], np.cumsum(segment_time_s(v[:-1], v[1:], np.diff(b)))])


def position_at_time(
    time_s: np.ndarray, boundaries_m: np.ndarray, speed_mps: np.ndarray, times_s: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Position and speed at given times, exactly, for a constant-acceleration profile.

    Inside segment i (time tau since its start): s = s_i + v_i tau + a_i tau^2 / 2 and
    v = v_i + a_i tau, with a_i = (v_{i+1}^2 - v_i^2) / (2 L_i).

    Parameters
    ----------
    time_s : numpy.ndarray, shape (K,)
        Query times (s), within [0, times_s[-1]].
    boundaries_m, speed_mps : numpy.ndarray, shape (N+1,)
        The profile: boundaries (m) and boundary speeds (m/s).
    times_s : numpy.ndarray, shape (N+1,)
        Boundary times from :func:`boundary_times_s` (s).

    Returns
    -------
    s_m, speed_mps : numpy.ndarray, shape (K,)
        Position (m) and speed (m/s), clipped to the segment (rounding never leaves it).
    """
    t = np.asarray(time_s, dtype=float)
    b, v = np.asarray(boundaries_m, dtype=float), np.asarray(speed_mps, dtype=float)
    return _motion_in_segment(t, segment_index(t, times_s), b, v, np.asarray(times_s, dtype=float),
                              segment_accel_mps2(v[:-1] ** 2, v[1:] ** 2, np.diff(b)))


def _motion_in_segment(t: np.ndarray, seg: np.ndarray, b: np.ndarray, v: np.ndarray, times: np.ndarray,
                       accel: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Position and speed at times t, each inside the given segment (accel: each segment's, m/s^2)."""
    tau = np.maximum(t - times[seg], 0.0)
    s = b[seg] + v[seg] * tau + 0.5 * accel[seg] * tau * tau
    speed = np.maximum(v[seg] + accel[seg] * tau, 0.0)
    return np.clip(s, b[seg], b[seg + 1]), speed


def choose_time_step_s(natural_frequency_radps: float) -> float:
    """The step dt (s) of the simulation's uniform time grid, and why.

    Every break of the wheel's path is a knot whatever dt is, and the input between knots
    is exact on its lines and second order on its arcs (whose knots are at most
    :data:`MAX_ARC_STEP_RAD` apart), so dt no longer has to resolve the samples. What it
    resolves is the suspension's own motion, on which the turning points of the forces
    between knots are searched:

    * dt <= 2 pi / (200 wn) (:data:`STEPS_PER_PERIOD`): the swing is sampled 200 times per
      period, so the cubic that places a turning point is exact to about (pi / 100)^4;
    * dt <= (shortest segment time) / 4: every segment holds grid points. Only the
      segments that need it get them: a segment shorter in time than 4 dt gets 3 points
      of its own, at its quarters (:func:`simulate_quarter_car`), so one short, fast
      segment does not shrink the step over the whole route (a crawl over a refined
      route took 1.3 million steps instead of 160,000).

    For the bundled ``atv`` (wn = 3 rad/s) dt is 10.5 ms.

    Parameters
    ----------
    natural_frequency_radps : float
        Suspension natural frequency wn (rad/s).

    Returns
    -------
    float
        dt (s).
    """
    return 2.0 * math.pi / (STEPS_PER_PERIOD * natural_frequency_radps)


def _segment_trend(s: np.ndarray, y: np.ndarray, boundaries: np.ndarray, detrend: bool
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Reference line y_ref = level + slope (s - s0) of each segment (datum of F = k y + c y').

    The segment's samples are those with s_i <= s < s_{i+1} (the last segment closed), as in
    :mod:`profileopt.core.stations`; the line is their least-squares fit
    (:func:`profileopt.terrain.roughness.segment_line_fit`, the fit the RI removes), or their mean
    without detrending. A segment without samples gets the interpolated height at its
    middle, flat. Returns (s0, level, slope), each shape (N,).
    """
    starts, stops = segment_samples(s, boundaries)
    fit = segment_line_fit(s, y, starts, stops, detrend=detrend)
    s0, level, slope = fit.s0_m.copy(), fit.level_m.copy(), fit.slope.copy()
    empty = np.flatnonzero(fit.count == 0)
    if empty.size:
        middle = 0.5 * (boundaries[empty] + boundaries[empty + 1])
        s0[empty], level[empty], slope[empty] = middle, np.interp(middle, s, y), 0.0
    return s0, level, slope


def _knots_m(path: WheelPath, b: np.ndarray, max_arc_step_rad: float) -> np.ndarray:
    """Positions of the knots: segment boundaries, path breaks, steps along the arcs (m)."""
    lo, hi = b[0], b[-1]
    breaks = path.breaks_m
    arcs = np.flatnonzero(path.is_arc & (breaks[1:] > lo) & (breaks[:-1] < hi))
    r = path.wheel_radius_m
    centre = path.x_ref_m[arcs]
    angle = [np.arcsin(np.clip((centre - np.clip(breaks[arcs + side], lo, hi)) / r, -1.0, 1.0)) for side in (0, 1)]
    count = np.maximum(np.ceil(np.abs(angle[1] - angle[0]) / max_arc_step_rad), 1).astype(int)
    owner = np.repeat(np.arange(arcs.size), count - 1)
    step = np.arange(owner.size) - np.repeat(np.cumsum(count - 1) - (count - 1), count - 1) + 1
    theta = angle[0][owner] + (angle[1] - angle[0])[owner] * step / count[owner]
    along_arcs = centre[owner] - r * np.sin(theta)
    inner = breaks[(breaks > lo) & (breaks < hi)]
    knots = np.unique(np.concatenate([b, inner, along_arcs]))
    return knots[(knots >= lo) & (knots <= hi)]


def _validate(s, z, b, v) -> None:
    """The checks on the route and the profile (InputError with the fix)."""
    if s.ndim != 1 or z.shape != s.shape or s.size < 2:
        raise InputError("route: s and z must be 1-D arrays of the same length >= 2")
    if b.ndim != 1 or v.shape != b.shape or b.size < 2:
        raise InputError("speed profile: boundaries and speeds must be 1-D arrays of the same length >= 2")
    if np.any(np.diff(b) <= 0):
        raise InputError("speed profile: s_m must increase strictly")
    span = max(abs(s[0]), abs(s[-1]), 1.0) * 1e-9
    if b[0] < s[0] - span or b[-1] > s[-1] + span:
        raise InputError(
            f"speed profile: it covers {b[0]:g} to {b[-1]:g} m but the route only {s[0]:g} to {s[-1]:g} m; "
            "use the profile planned for this route"
        )
    with np.errstate(over="ignore"):
        too_fast = np.flatnonzero(np.isfinite(v) & np.isinf(v * v))  # NaN, inf: boundary_times_s
    if too_fast.size:
        i = too_fast[0]
        raise InputError(
            f"speed profile: the speed at s = {b[i]:g} m, {v[i]:g} m/s, is too large to simulate (its square "
            "overflows a float); no ground vehicle drives at it"
        )


def simulate_quarter_car(
    s_m: np.ndarray,
    z_m: np.ndarray,
    boundaries_m: np.ndarray,
    speed_mps: np.ndarray,
    vehicle: "Vehicle",
    *,
    envelope: bool = True,
    detrend: bool = True,
    time_step_s: float | None = None,
    max_arc_step_rad: float = MAX_ARC_STEP_RAD,
) -> QuarterCarRun:
    """Drive the vehicle's quarter car over sampled terrain at a speed profile.

    The vehicle starts settled on the ground (x = y, x' = y'), so on a route that begins
    with smooth ground it starts at static equilibrium.

    Parameters
    ----------
    s_m : numpy.ndarray, shape (M,)
        Distance along the route (m), strictly increasing.
    z_m : numpy.ndarray, shape (M,)
        Elevation of each sample (m).
    boundaries_m : numpy.ndarray, shape (N+1,)
        Segment boundaries of the speed profile (m), strictly increasing, inside
        [s_m[0], s_m[-1]].
    speed_mps : numpy.ndarray, shape (N+1,)
        Speed at each boundary (m/s); constant acceleration (v^2 linear in s) in between.
    vehicle : Vehicle
        Supplies m, wn, zeta (hence k and c) and the wheel radius r.
    envelope : bool, default True
        Roll a rigid wheel over the polyline of the samples (:func:`wheel_path`); False
        feeds the polyline itself in as the base input (a wheel of radius 0).
    detrend : bool, default True
        Measure y for the excitation force from each segment's least-squares line (True,
        as the RI does) or from its mean (False).
    time_step_s : float, optional
        dt of the uniform time grid (s); by default :func:`choose_time_step_s`.
    max_arc_step_rad : float, default MAX_ARC_STEP_RAD
        Largest angle of an arc of the wheel's path between two knots (rad), > 0.

    Returns
    -------
    QuarterCarRun

    Raises
    ------
    InputError
        Arrays of the wrong shape, a profile that does not lie on the route, a speed too
        large to simulate, a segment never crossed, or more than :data:`MAX_STEPS` steps.
    """
    t_start = time.perf_counter()
    vehicle = require_vehicle(vehicle, "simulate_quarter_car")
    s = np.asarray(s_m, dtype=float)
    z = np.asarray(z_m, dtype=float)
    b = np.asarray(boundaries_m, dtype=float)
    v = np.asarray(speed_mps, dtype=float)
    _validate(s, z, b, v)
    if not (max_arc_step_rad > 0):
        raise InputError(f"max_arc_step_rad = {max_arc_step_rad!r}: must be > 0 rad")
    b = np.clip(b, s[0], s[-1])
    path = wheel_path(s, z, vehicle.wheel_radius_m if envelope else 0.0)
    t_envelope = time.perf_counter()

    times = boundary_times_s(b, v)
    total = float(times[-1])
    spacing = float(np.min(np.diff(s)))
    if time_step_s is None:
        time_step_s = choose_time_step_s(vehicle.natural_frequency_radps)
    steps = max(int(math.ceil(total / time_step_s)), 1)
    if steps > MAX_STEPS:  # memory
        slowest = int(np.argmax(np.diff(times)))
        segment_s = float(times[slowest + 1] - times[slowest])
        raise TooLongToSimulate(
            f"speed profile: simulating it needs {steps:,} time steps of {time_step_s:.3g} s (at most "
            f"{MAX_STEPS:,}): it takes {total:.4g} s, the longest segment ({b[slowest]:g} to {b[slowest + 1]:g} m) "
            f"{segment_s:.4g} s; verify a profile that keeps moving",
            steps=steps, time_step_s=time_step_s, total_s=total, slowest=slowest, segments=b.size - 1,
            segment_m=(float(b[slowest]), float(b[slowest + 1])), speeds_mps=(float(v[slowest]), float(v[slowest + 1])),
            segment_s=segment_s)
    dt = total / steps
    knots = _Knots.build(path, b, v, times, steps, max_arc_step_rad)
    run = knots.drive(path, vehicle, _segment_trend(s, path.evaluate(s)[0], b, detrend))
    t_end = time.perf_counter()
    peak_v = float(np.max(v))
    return QuarterCarRun(
        **run,
        boundaries_m=b.copy(),
        time_step_s=dt,
        steps_per_sample=spacing / (peak_v * dt) if peak_v > 0 else math.inf,
        timings_s={"envelope": t_envelope - t_start, "integrate": t_end - t_envelope, "total": t_end - t_start},
        path=path,
    )


@dataclasses.dataclass(frozen=True, eq=False)
class _Knots:
    """The knots in time, with what the profile and the path are on either side of each."""

    t: np.ndarray  # (n,) times (s), strictly increasing
    s: np.ndarray  # (n,) positions (m)
    v: np.ndarray  # (n,) speeds (m/s)
    grid: np.ndarray  # (n,) bool: on the uniform grid
    piece: tuple[np.ndarray, np.ndarray]  # path piece before / after (n,)
    seg: tuple[np.ndarray, np.ndarray]  # profile segment before / after (n,)
    profile: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]  # b, v, times, accel

    @classmethod
    def build(cls, path: WheelPath, b: np.ndarray, v: np.ndarray, times: np.ndarray, steps: int,
              max_arc_step_rad: float) -> "_Knots":
        """Knots in s (boundaries, path breaks, arc steps), timed, merged with the grid."""
        accel = segment_accel_mps2(v[:-1] ** 2, v[1:] ** 2, np.diff(b))
        ks = _knots_m(path, b, max_arc_step_rad)
        seg_after = segment_index(ks, b)
        seg_before = np.clip(np.searchsorted(b, ks, side="left") - 1, 0, b.size - 2)
        i = seg_after
        v2 = np.maximum(v[i] ** 2 + 2.0 * accel[i] * (ks - b[i]), 0.0)
        kv = np.sqrt(v2)
        with np.errstate(invalid="ignore", divide="ignore"):
            kt = times[i] + np.where(ks > b[i], 2.0 * (ks - b[i]) / (v[i] + kv), 0.0)
        at_end = ks == b[-1]
        kt[at_end], kv[at_end] = times[-1], v[-1]
        kt = np.maximum.accumulate(kt)  # rounding never reorders them
        piece_after, piece_before = path.piece_index(ks, "right"), path.piece_index(ks, "left")
        # knots that rounding put at one time: one knot, left side of the first, right of the last
        first = np.concatenate([[True], kt[1:] != kt[:-1]])
        last = np.concatenate([kt[1:] != kt[:-1], [True]])
        group_first = np.flatnonzero(first)[np.cumsum(first) - 1]
        piece_before, seg_before = piece_before[group_first][last], seg_before[group_first][last]
        ks, kt, kv, piece_after, seg_after = ks[last], kt[last], kv[last], piece_after[last], seg_after[last]

        grid_t = np.linspace(0.0, times[-1], steps + 1)
        # a segment shorter in time than 4 steps gets points of its own at its quarters (off
        # the uniform grid, which the response runs on as one filter)
        duration = np.diff(times)
        short = np.flatnonzero(duration < 4.0 * times[-1] / steps)
        quarters = (times[short, None] + duration[short, None] * np.array([0.25, 0.5, 0.75])[None, :]).ravel()
        # the sorted union of three sorted arrays: a stable sort (a merge of sorted runs) and
        # the repeats dropped, what np.union1d gives by sorting afresh
        t = np.concatenate([kt, grid_t, quarters])
        t.sort(kind="stable")
        t = t[np.concatenate([[True], t[1:] != t[:-1]])]
        is_knot = np.zeros(t.size, dtype=bool)
        where_knot = np.searchsorted(t, kt)
        is_knot[where_knot] = True
        grid = np.zeros(t.size, dtype=bool)
        grid[np.searchsorted(t, grid_t)] = True
        # between knots the path piece and the profile segment are those after the last knot
        last_knot = np.cumsum(is_knot) - 1  # the first time, 0, is a knot: the start
        p_after, g_after = piece_after[last_knot], seg_after[last_knot]
        p_before, g_before = p_after.copy(), g_after.copy()
        p_before[where_knot], g_before[where_knot] = piece_before, seg_before
        s_t, v_t = np.empty(t.size), np.empty(t.size)
        for lo in range(0, t.size, CHUNK_KNOTS):  # elementwise: in chunks, as drive()
            hi = min(lo + CHUNK_KNOTS, t.size)
            s_t[lo:hi], v_t[lo:hi] = _motion_in_segment(t[lo:hi], g_after[lo:hi], b, v, times, accel)
        s_t[where_knot], v_t[where_knot] = ks, kv
        return cls(t=t, s=s_t, v=v_t, grid=grid, piece=(p_before, p_after), seg=(g_before, g_after),
                   profile=(b, v, times, accel))

    def on_path(self, path: WheelPath, side: int, lo: int, hi: int
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """y (m), dy/ds, d2y/ds2 (1/m) and y' = dy/ds v (m/s) on one side (0 before, 1 after)
        of knots lo to hi - 1."""
        y, ys, yss = path.evaluate(self.s[lo:hi], self.piece[side][lo:hi])
        return y, ys, yss, ys * self.v[lo:hi]

    def inputs(self, path: WheelPath, trend: tuple, lo: int, hi: int) -> dict[str, tuple[np.ndarray, np.ndarray]]:
        """y, y', y'' (from both sides) and the excitation's y~, y~', y~'' at knots lo to hi - 1."""
        accel = self.profile[3]
        s0, level, slope = trend
        s, v = self.s[lo:hi], self.v[lo:hi]
        out: dict[str, list] = {"y": [], "dy": [], "d2y": [], "yt": [], "dyt": [], "d2yt": []}
        for side in (0, 1):
            y, ys, yss, dy = self.on_path(path, side, lo, hi)
            seg = self.seg[side][lo:hi]
            a = accel[seg]
            out["y"].append(y)
            out["dy"].append(dy)
            out["d2y"].append(yss * v * v + ys * a)
            out["yt"].append(y - (level[seg] + slope[seg] * (s - s0[seg])))
            out["dyt"].append((ys - slope[seg]) * v)
            out["d2yt"].append(yss * v * v + (ys - slope[seg]) * a)
        return {key: (value[0], value[1]) for key, value in out.items()}

    def drive(self, path: WheelPath, vehicle: "Vehicle", trend: tuple) -> dict[str, np.ndarray]:
        """Run the quarter car over the knots; rows of the time series and segment peaks.

        The response is one recursion over all knots; everything else is elementwise, so it is
        done :data:`CHUNK_KNOTS` knots at a time (the same values as all at once: each row
        depends only on its knot and the next), which keeps the temporaries small.
        """
        wn, zeta = vehicle.natural_frequency_radps, vehicle.damping_ratio
        m, k, c = vehicle.quarter_mass_kg, vehicle.spring_n_per_m, vehicle.damping_ns_per_m
        n = self.t.size
        h = np.diff(self.t)
        # the base input, continuous (either side), and its slope from both sides
        y, dy_before, dy_after = np.empty(n), np.empty(n), np.empty(n)
        for lo in range(0, n, CHUNK_KNOTS):
            hi = min(lo + CHUNK_KNOTS, n)
            dy_before[lo:hi] = self.on_path(path, 0, lo, hi)[3]
            y[lo:hi], _, _, dy_after[lo:hi] = self.on_path(path, 1, lo, hi)
        g, u_star, jumps = knot_jumps(h, y, dy_before, dy_after, wn)
        del dy_before, dy_after  # the rows take the slopes from inputs(): not held through respond
        state = respond(self.t, jumps, self.grid, wn, zeta)
        del jumps
        g_last = g[-1] if g.size else 0.0

        def interval_terms(lo: int, end: int) -> tuple[tuple[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]:
            """g and u* of the interval before and after each of knots lo to end - 1 (before the
            first: g = 0 and its own u*; after the last: the last interval's g)."""
            g_before = g[lo - 1:end - 1] if lo > 0 else np.concatenate([[0.0], g[:end - 1]])
            g_after = g[lo:end] if end < n else np.append(g[lo:], g_last)
            u_before = u_star[lo - 1:end - 1] if lo > 0 else np.concatenate([u_star[:1], u_star[:end - 1]])
            return (g_before, g_after), (u_before, u_star[lo:end])

        b, v, times, accel = self.profile
        s0, level, slope = trend
        names = ("time_s", "s_m", "speed_mps", "base_m", "mass_m", "transmitted_n", "excitation_n")
        parts: dict[str, list] = {name: [] for name in names}
        n_seg = b.size - 1
        peaks = (np.zeros(n_seg), np.zeros(n_seg))
        for lo in range(0, n, CHUNK_KNOTS):
            hi = min(lo + CHUNK_KNOTS, n)  # the chunk's knots
            end = min(hi + 1, n)  # and the next knot, where its last interval ends
            q = self.inputs(path, trend, lo, end)
            st_before, st_after = state.before[lo:end], state.after[lo:end]
            g_side, u_side = interval_terms(lo, end)

            def forces(w, side):
                """F_T, its rate, and F, its rate, on one side of knots lo to end - 1."""
                ft = -k * w[:, 0] - c * w[:, 1] + 2.0 * m * g_side[side]
                ddw = -wn * wn * w[:, 0] - 2.0 * zeta * wn * w[:, 1]
                fe = k * q["yt"][side] + c * q["dyt"][side]
                return ft, -k * w[:, 1] - c * ddw, fe, k * q["dyt"][side] + c * q["d2yt"][side]

            before, after = forces(st_before, 0), forces(st_after, 1)
            # turning points inside the chunk's intervals (lo to end - 2), of either force
            hk = h[lo:end - 1]
            extra_j, extra_tau = [], []
            for col in (0, 2):
                tau = hermite_extremum(hk, after[col][:-1], before[col][1:], after[col + 1][:-1], before[col + 1][1:])
                hit = np.flatnonzero(np.isfinite(tau))
                extra_j.append(hit)
                extra_tau.append(tau[hit])
            jl = np.concatenate(extra_j)  # local to the chunk
            tau = np.concatenate(extra_tau)
            j = jl + lo
            seg = self.seg[1][j]
            te = self.t[j] + tau
            se, ve = _motion_in_segment(te, seg, b, v, times, accel)
            p11, p12, p21, p22 = transition(tau, wn, zeta)
            w0 = st_after[jl]
            w = np.stack([p11 * w0[:, 0] + p12 * w0[:, 1], p21 * w0[:, 0] + p22 * w0[:, 1]], axis=1)
            ye, yse, _ = path.evaluate(se, self.piece[1][j])
            ft_e = -k * w[:, 0] - c * w[:, 1] + 2.0 * m * g[j]
            fe_e = k * (ye - (level[seg] + slope[seg] * (se - s0[seg]))) + c * (yse - slope[seg]) * ve
            mass_e = ye + w[:, 0] + u_star[j]

            # rows: the left side at kinks and at the end, the right side elsewhere, turning points
            dy = q["dy"]
            count = hi - lo
            jump = np.abs(dy[1][:count] - dy[0][:count]) > 1e-12 * (1.0 + np.abs(dy[1][:count]))
            index = np.arange(lo, hi)
            left = np.flatnonzero(jump | (index == n - 1))
            left = left[left + lo > 0]  # local
            right = np.arange(min(hi, n - 1) - lo)  # local
            yc = y[lo:end]
            mass = (yc + st_before[:, 0] + u_side[0], yc + st_after[:, 0] + u_side[1])
            rows = {
                "time_s": (self.t[lo:end], te),
                "s_m": (self.s[lo:end], se),
                "speed_mps": (self.v[lo:end], ve),
                "base_m": (yc, ye),
                "mass_m": ((mass[0], mass[1]), mass_e),
                "transmitted_n": ((before[0], after[0]), ft_e),
                "excitation_n": ((before[2], after[2]), fe_e),
            }
            # left, right, inside: the order of the knots' times (2 j for the left side of knot
            # j, 2 j + 1 for its right side, between 2 j + 1 and 2 j + 2 inside its interval)
            key = np.concatenate([2.0 * (left + lo), 2.0 * (right + lo) + 1.0, 2.0 * j + 1.0 + 0.5 * tau / h[j]])
            order = np.argsort(key, kind="stable")
            for name, (at_knots, inside) in rows.items():
                sides = at_knots if isinstance(at_knots, tuple) else (at_knots, at_knots)
                parts[name].append(np.concatenate([sides[0][left], sides[1][right], inside])[order])
            # per-segment peaks: left values belong to the segment before, right and inside to the one after
            for peak, col in zip(peaks, (0, 2)):
                first = 1 if lo == 0 else 0  # knot 0 has no left side
                np.maximum.at(peak, self.seg[0][lo + first:hi], np.abs(before[col][first:count]))
                np.maximum.at(peak, self.seg[1][lo:min(hi, n - 1)], np.abs(after[col][:right.size]))
                np.maximum.at(peak, seg, np.abs(ft_e if col == 0 else fe_e))
        out = {name: np.concatenate(parts.pop(name)) for name in names}  # each column's chunks freed in turn
        out["transmitted_peak_n"], out["excitation_peak_n"] = peaks
        return out
