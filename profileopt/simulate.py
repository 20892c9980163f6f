"""A quarter car driven over a route's own elevation samples: the forces a plan really causes.

The force models (:mod:`profileopt.forces`) predict a worst case from a statistic of the
terrain (the RI and a confidence level). This module measures instead: it drives the
linear quarter car of a :class:`~profileopt.vehicle.Vehicle` over the measured elevation
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
    removed each segment's trend line (:func:`profileopt.terrain.segment_roughness_index`),
    so here y is measured from the least-squares line of y over each segment's samples
    (``detrend=True``) or from the segment's mean (``detrend=False``). Then a constant grade
    causes no excitation force, as it causes no roughness.

Wheel geometry
--------------
The wheel does not follow the raw samples: a rigid wheel of radius r rolls over the
ground the route means, the straight lines between its samples (Fig. 2). Its centre above
s_j is the lowest that keeps the wheel out of that ground, w(s_j), the largest of the
circles of radius r about the samples within r and of the segments offset by r along their
normals (:func:`wheel_envelope_m` derives it); the base input is y(s_j) = w(s_j) - r. A
step of height e is climbed over the horizontal distance X_w = sqrt(2 e r - e^2) of
Eq. (2); on a straight incline of slope m, y = z + r (sqrt(1 + m^2) - 1) however the samples
are spaced. (Circles on the samples alone let the wheel sag between samples on a slope,
by up to r (sqrt(1 + m^2) - 1): 3.9 mm on washboard.csv's corrugation sampled every 5 cm,
which the damper made 8-10 % of the force at 20 m/s.) Between samples y is interpolated
with a monotone cubic (PCHIP, :class:`scipy.interpolate.PchipInterpolator`): its slope is
continuous and it never overshoots a step. Linear interpolation would not do: its slope
jumps at every sample, and the damper turns each jump into a force spike c v (change of
slope) that is an artefact of sampling (1.3 % of the transmitted force on a 10 m sinusoid
sampled every 2 cm at 2 m/s). A genuine jump of slope (where the wheel first touches an
edge) is spread over one sample interval instead; its full slope is still reached.

Integration
-----------
The speed profile (boundaries s_i and speeds v_i, constant acceleration inside a segment,
so v^2 is linear in s) gives the time of every position exactly; the motion is sampled on a
uniform time grid t_k = k dt, and y(t) is taken as linear between grid points (a
first-order hold). For such an input the linear ODE has an exact solution: in the relative
coordinate u = x - y, m u'' = -k u - c u' between grid points, and at each grid point u'
jumps by minus the jump of the input's slope. The transition matrix expm(A dt)
(:func:`scipy.linalg.expm`) makes this a discrete linear system, run with
:func:`scipy.signal.lfilter` in compiled code (a 5 km route sampled every 5 cm, driven at
10 m/s: 4e5 steps, 0.15 s). The relative coordinate keeps the numbers small (millimetres) even on routes at absolute elevations of
hundreds of metres.

Being exact for the held input, the only approximation is the hold itself: see
:func:`choose_time_step_s` for how dt is chosen.
"""

from __future__ import annotations

import dataclasses
import math
import time
from typing import TYPE_CHECKING

import numpy as np

from .errors import InputError
from .kinematics import segment_accel_mps2, segment_time_s
from .stations import segment_index, segment_samples
from .terrain import segment_line_fit
from .wheel import wheel_envelope_m

if TYPE_CHECKING:
    from .vehicle import Vehicle

__all__ = [
    "QuarterCarRun",
    "boundary_times_s",
    "position_at_time",
    "choose_time_step_s",
    "simulate_quarter_car",
    "STEPS_PER_SAMPLE",
    "MAX_STEPS",
]

#: Time steps per route sample interval at the profile's top speed (see choose_time_step_s).
STEPS_PER_SAMPLE = 4
#: Time steps per natural period of the suspension, at the least.
STEPS_PER_PERIOD = 200
#: Upper bound on the number of time steps (memory: about 15 arrays of this length).
MAX_STEPS = 20_000_000


@dataclasses.dataclass(frozen=True, eq=False)
class QuarterCarRun:
    """A simulated drive: time series on the uniform time grid and per-segment peaks.

    The held input's slope changes at every grid point by O(dt); forces are the central
    values (mean of the two one-sided limits), those of the smooth input to O(dt^2).

    Attributes
    ----------
    time_s : numpy.ndarray, shape (K+1,)
        Grid times t_k = k dt (s).
    s_m : numpy.ndarray, shape (K+1,)
        Position of the wheel at t_k (m).
    speed_mps : numpy.ndarray, shape (K+1,)
        Speed at t_k (m/s).
    base_m : numpy.ndarray, shape (K+1,)
        Base input y (wheel envelope minus r), in the route's elevation datum (m).
    mass_m : numpy.ndarray, shape (K+1,)
        Sprung-mass position x about static equilibrium, same datum as ``base_m`` (m).
    transmitted_n : numpy.ndarray, shape (K+1,)
        F_T = k (y - x) + c (y' - x') = m x'' (N).
    excitation_n : numpy.ndarray, shape (K+1,)
        F = k y + c y' with y measured from the segment's trend line or mean (N).
    boundaries_m : numpy.ndarray, shape (N+1,)
        Segment boundaries (m).
    transmitted_peak_n, excitation_peak_n : numpy.ndarray, shape (N,)
        Largest |F_T| and |F| while the wheel is in each segment (N).
    time_step_s : float
        dt (s).
    steps_per_sample : float
        Grid steps per route sample interval at the top speed (>= 4; a profile that would
        need more than :data:`MAX_STEPS` steps is refused).
    timings_s : dict
        Wall-clock seconds: ``envelope``, ``integrate``, ``total``.
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

    @property
    def steps(self) -> int:
        """Number of time steps K."""
        return int(self.time_s.size - 1)


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
    b = np.asarray(boundaries_m, dtype=float)
    v = np.asarray(speed_mps, dtype=float)
    t = np.asarray(time_s, dtype=float)
    seg = segment_index(t, times_s)
    length = np.diff(b)
    accel = segment_accel_mps2(v[:-1] ** 2, v[1:] ** 2, length)
    tau = t - times_s[seg]
    s = b[seg] + v[seg] * tau + 0.5 * accel[seg] * tau * tau
    speed = np.maximum(v[seg] + accel[seg] * tau, 0.0)
    return np.clip(s, b[seg], b[seg + 1]), speed


def choose_time_step_s(
    sample_spacing_m: float,
    peak_speed_mps: float,
    natural_frequency_radps: float,
    shortest_segment_time_s: float,
) -> float:
    """The time step dt (s) of the simulation, and why.

    The solution is exact for the held input (linear in time between grid points); what
    the hold approximates is the smooth input y(s(t)) (a cubic between route samples). The
    highest frequency the wheel passes is v_max / spacing samples per second, so

    * dt <= spacing / (4 v_max) (:data:`STEPS_PER_SAMPLE`): every cubic piece of the input
      is sampled at least 4 times even at top speed; the central slope of the held input
      then differs from y' by O(dt^2) (the closed-form checks in the tests agree to 1e-5);
    * dt <= 2 pi / (200 wn) (:data:`STEPS_PER_PERIOD`): the suspension's own swing is
      sampled 200 times per period, so a peak between grid points is missed by at most
      1 - cos(pi / 200) ~ 1.2e-4 of its amplitude;
    * dt <= (shortest segment time) / 4: every segment holds grid points.

    For a route sampled every 5 cm driven at up to 10 m/s that is dt = 1.25 ms.

    Parameters
    ----------
    sample_spacing_m : float
        Smallest distance between route samples (m).
    peak_speed_mps : float
        Top speed of the profile (m/s).
    natural_frequency_radps : float
        Suspension natural frequency wn (rad/s).
    shortest_segment_time_s : float
        Time spent in the shortest-lived segment (s).

    Returns
    -------
    float
        dt (s).
    """
    bounds = [2.0 * math.pi / (STEPS_PER_PERIOD * natural_frequency_radps), shortest_segment_time_s / 4.0]
    if peak_speed_mps > 0:
        bounds.append(sample_spacing_m / (STEPS_PER_SAMPLE * peak_speed_mps))
    return min(bounds)


def _segment_trend(s: np.ndarray, y: np.ndarray, boundaries: np.ndarray, detrend: bool
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Reference line y_ref = level + slope (s - s0) of each segment (datum of F = k y + c y').

    The segment's samples are those with s_i <= s < s_{i+1} (the last segment closed), as in
    :mod:`profileopt.stations`; the line is their least-squares fit
    (:func:`profileopt.terrain.segment_line_fit`, the fit the RI removes), or their mean
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
        Roll a rigid wheel over the samples (:func:`wheel_envelope_m`); False feeds the raw
        samples in as the base input (for checks against closed forms).
    detrend : bool, default True
        Measure y for the excitation force from each segment's least-squares line (True,
        as the RI does) or from its mean (False).
    time_step_s : float, optional
        dt (s); by default :func:`choose_time_step_s`.

    Returns
    -------
    QuarterCarRun
    """
    # scipy's submodules take 0.6 s to import: only when a simulation is run
    import scipy.interpolate
    import scipy.linalg
    import scipy.signal

    t_start = time.perf_counter()
    s = np.asarray(s_m, dtype=float)
    z = np.asarray(z_m, dtype=float)
    b = np.asarray(boundaries_m, dtype=float)
    v = np.asarray(speed_mps, dtype=float)
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

    y_samples = wheel_envelope_m(s, z, vehicle.wheel_radius_m) if envelope else z.copy()
    t_envelope = time.perf_counter()

    times = boundary_times_s(b, v)
    total = float(times[-1])
    spacing = float(np.min(np.diff(s)))
    if time_step_s is None:
        time_step_s = choose_time_step_s(
            spacing, float(np.max(v)), vehicle.natural_frequency_radps, float(np.min(np.diff(times)))
        )
    steps = max(int(math.ceil(total / time_step_s)), 1)
    if steps > MAX_STEPS:  # capping would break the step rules (and leave segments unsampled)
        slowest = int(np.argmax(np.diff(times)))
        raise InputError(
            f"speed profile: simulating it needs {steps:,} time steps of {time_step_s:.3g} s (at most "
            f"{MAX_STEPS:,}): it takes {total:.4g} s, the longest segment ({b[slowest]:g} to {b[slowest + 1]:g} m) "
            f"{times[slowest + 1] - times[slowest]:.4g} s; verify a profile that keeps moving"
        )
    dt = total / steps
    grid_t = np.linspace(0.0, total, steps + 1)
    grid_s, grid_v = position_at_time(grid_t, b, v, times)
    y = scipy.interpolate.PchipInterpolator(s, y_samples)(grid_s)
    y0 = y[0]
    yr = y - y0  # the ODE is shift-invariant; small numbers, no cancellation
    slope = np.diff(yr) / dt  # held input slope y' on [t_k, t_k+1], shape (K,)

    # Relative coordinate u = x - y: m u'' = -k u - c u' between grid points; at t_k the
    # input slope changes by (slope_k - slope_{k-1}) and u' jumps by minus that.
    k_spring, c_damp, m = vehicle.spring_n_per_m, vehicle.damping_ns_per_m, vehicle.quarter_mass_kg
    a_mat = np.array([[0.0, 1.0], [-k_spring / m, -c_damp / m]])
    phi = scipy.linalg.expm(a_mat * dt)
    kick = np.zeros(steps + 1)  # jump of u' at t_k; settled start: x'(0) = y'(0+)
    kick[1:-1] = -(slope[1:] - slope[:-1])
    # sigma_{k+1} = phi (sigma_k + e2 kick_k): a discrete LTI system with input kick.
    b_in = phi[:, 1:2]
    state = np.empty((steps + 1, 2))
    for row in range(2):
        num, den = scipy.signal.ss2tf(phi, b_in, np.eye(2)[row:row + 1], np.zeros((1, 1)))
        # sigma_k depends on kicks up to k-1: one sample of delay is in num (num[0] == 0).
        state[:, row] = scipy.signal.lfilter(num[0], den, kick)
    u, du_before = state[:, 0], state[:, 1]
    # The held input's slope jumps at each grid point by O(dt); the central value (mean of
    # the two one-sided limits) is the smooth input's force to O(dt^2).
    transmitted = -(k_spring * u + c_damp * (du_before + 0.5 * kick))

    # Excitation F = k y~ + c y~' with y~ = y - (level + trend slope * (s - s0)).
    s0, level, trend = _segment_trend(s, y_samples, b, detrend)
    n_seg = b.size - 1
    seg = segment_index(grid_s, b)
    y_tilde = y - (level[seg] + trend[seg] * (grid_s - s0[seg]))
    chord_speed = np.diff(grid_s) / dt  # consistent with the held y
    dy_central = np.empty(steps + 1)
    dy_central[1:-1] = 0.5 * (slope[1:] + slope[:-1]) - trend[seg[1:-1]] * 0.5 * (chord_speed[1:] + chord_speed[:-1])
    dy_central[0] = slope[0] - trend[seg[0]] * chord_speed[0]
    dy_central[-1] = slope[-1] - trend[seg[-1]] * chord_speed[-1]
    excitation = k_spring * y_tilde + c_damp * dy_central

    starts = np.searchsorted(seg, np.arange(n_seg), side="left")
    if np.any(np.diff(np.append(starts, seg.size)) <= 0):  # pragma: no cover - dt rules prevent it
        raise RuntimeError("a segment holds no time step; pass a smaller time_step_s")
    transmitted_peak = np.maximum.reduceat(np.abs(transmitted), starts)
    excitation_peak = np.maximum.reduceat(np.abs(excitation), starts)

    peak_v = float(np.max(v))
    t_end = time.perf_counter()
    return QuarterCarRun(
        time_s=grid_t,
        s_m=grid_s,
        speed_mps=grid_v,
        base_m=y,
        mass_m=y0 + yr + u,
        transmitted_n=transmitted,
        excitation_n=excitation,
        boundaries_m=b.copy(),
        transmitted_peak_n=transmitted_peak,
        excitation_peak_n=excitation_peak,
        time_step_s=dt,
        steps_per_sample=spacing / (peak_v * dt) if peak_v > 0 else math.inf,
        timings_s={
            "envelope": t_envelope - t_start,
            "integrate": t_end - t_envelope,
            "total": t_end - t_start,
        },
    )
