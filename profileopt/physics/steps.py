"""Steps met and drops landed: the steep ramps of a rigid wheel's path, the force on them, and
the step limit of SBEM:TF.

A rigid wheel's path y(s) (:mod:`profileopt.physics.wheel`) kinks where its contact jumps from
one piece of the ground to another, and there its slope always rises (the path is an upper
envelope). A step sits on ground of some grade g, the trend it interrupts: the median
slope of the path within :data:`TREND_HALF_WIDTH_M` of the kink (:func:`trend_slope`). On a
steady grade the body follows the ground without moving on its suspension, and the quarter
car is linear, so what loads the suspension is the path measured against that trend,
y - g s. Two kinds of kink start or end a ramp that the quarter car meets suddenly:

* a **landing**: against the trend, the path runs down at slope -s and the kink takes at
  least half of that slope away at once (the wheel lands after a drop). The ramp runs from
  where the path's slope last was the trend's (walking back from the kink, at most
  :data:`MAX_RAMP_M`) down to the kink;
* a **climb**: against the trend, the kink gives the path at least half of its following
  slope +s at once (the wheel meets a step ahead, or the foot of a steep ramp). The ramp
  runs from the kink up to where the path's slope returns to the trend's.

So a kerb on a climb is a ramp of the kerb's height, not of the rest of the hill, and a
drop on a descent one of the drop's, never reaching to the next hilltop.

The rise d of a ramp is the height of y - g s between its two ends. The step limit
of SBEM:TF bounds the force on each ramp with :func:`ramp_force_n` and
caps the speed of every segment that shares a point with it.

Eq. (13) (:func:`profileopt.physics.forces.sbem_tf_force_n`) is the steady response to a smooth
quarter sine. Where the wheel meets a step or lands after a drop, its path runs a steep ramp
that starts or ends in a kink (:func:`wheel_ramps`), faster than the body can follow;
:func:`ramp_force_n` bounds the transmitted force there, from the quarter car's impulse
response, and :func:`ramp_speed_cap_mps` is the speed where that bound meets a limit. Like
the force models, the bound is one CasADi expression for numbers, arrays, DM, SX and MX.
Quarter-car constants: k = m wn^2, c = 2 zeta m wn (docs/paper-notes.md)."""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING, Any

import casadi as ca
import numpy as np

from ..core.symbolic import elementwise
from .wheel import WheelPath, wheel_path

if TYPE_CHECKING:
    from ..core.vehicle import Vehicle

__all__ = ["WheelRamps", "wheel_ramps", "trend_slope", "SUDDEN_SHARE", "TREND_HALF_WIDTH_M", "TREND_STEP_M",
           "MAX_RAMP_M", "SLOPE_TOLERANCE", "gentlest_capping_slope", "impulse_response_peak_s", "ramp_force_n",
           "ramp_speed_cap_mps", "StepCaps", "step_caps", "MAX_STRETCHES", "segment_step_caps_mps",
           "step_speed_cap_mps"]


#: A kink starts or ends a ramp when it takes away (landing) or brings (climb) at least this
#: share of the ramp's slope at once (dimensionless).
SUDDEN_SHARE = 0.5


@dataclasses.dataclass(frozen=True)
class WheelRamps:
    """R ramps of a wheel's path, each with a kink at one end.

    Attributes
    ----------
    start_m, end_m : numpy.ndarray, shape (R,)
        Where each ramp starts and ends along the route (m), start <= end.
    kink_m : numpy.ndarray, shape (R,)
        Where its kink is (m): ``end_m`` for a landing, ``start_m`` for a climb.
    slope : numpy.ndarray, shape (R,)
        |dy/ds - g| of the path next to the kink on the ramp's side, against the trend g
        (:func:`trend_slope`) (dimensionless), > 0.
    rise_m : numpy.ndarray, shape (R,)
        Height of y - g s between the kink and the ramp's other end (m), >= 0.
    landing : numpy.ndarray of bool, shape (R,)
        True for a landing, False for a climb.
    """

    start_m: np.ndarray
    end_m: np.ndarray
    kink_m: np.ndarray
    slope: np.ndarray
    rise_m: np.ndarray
    landing: np.ndarray

    @property
    def count(self) -> int:
        """Number of ramps R."""
        return int(self.slope.size)


#: Half-width (m) of the stretch around a kink whose median path slope is the grade it
#: interrupts: long beside a step or a pothole (a kerb's ramp is a few centimetres, a block or
#: a pit a fraction of a metre), so the median is the ground's grade, not the step's.
TREND_HALF_WIDTH_M = 2.5
#: Spacing (m) of the path's slopes whose median is the trend: the median needs the typical
#: slope of a few metres of path, not its detail.
TREND_STEP_M = 0.1
#: Longest a ramp reaches from its kink (m): where the path departs from the trend for longer,
#: the departure is a hill of its own, not a step.
MAX_RAMP_M = 5.0
#: A path slope within this of the trend (dimensionless) is the trend: rounding, not a ramp.
SLOPE_TOLERANCE = 1e-9


def trend_slope(path: WheelPath, at_m: np.ndarray) -> np.ndarray:
    """The grade a kink interrupts: the median slope of the path within
    :data:`TREND_HALF_WIDTH_M` of each position (dimensionless).

    The median over arc length (the path's slope every :data:`TREND_STEP_M`, clipped to the
    path's ends) is the slope of the ground the step
    sits on: a kerb, a block or a pothole occupies a small share of the stretch and moves it
    not at all, a steady grade is all of it.

    Parameters
    ----------
    path : WheelPath
        The path of the wheel's lowest point.
    at_m : numpy.ndarray, shape (K,)
        Positions (m).

    Returns
    -------
    numpy.ndarray, shape (K,)
    """
    at = np.asarray(at_m, dtype=float)
    h = TREND_STEP_M
    half = int(math.ceil(TREND_HALF_WIDTH_M / h))
    out = np.empty(at.size)
    first, last = float(path.breaks_m[0]), float(path.breaks_m[-1])
    offsets = h * np.arange(-half, half + 1)
    for chunk in range(0, at.size, 4096):  # bounded memory: 4096 x (2 half + 1) slopes at a time
        where = np.clip(at[chunk:chunk + 4096, None] + offsets[None, :], first, last)
        out[chunk:chunk + 4096] = np.median(path.evaluate(where.ravel())[1].reshape(where.shape), axis=1)
    return out


def _ramp_tops(path: WheelPath, kink_m: np.ndarray, trend: np.ndarray, gentle: float) -> np.ndarray:
    """Where each landing's ramp starts: walking back from its kink, the first position
    where the path's slope is back at the trend, or the end of the first line of the path
    whose slope is within ``gentle`` of it (at most :data:`MAX_RAMP_M` back).

    Along the path the slope is constant on a line, falls along an arc (the wheel rolling
    over a vertex) and jumps up at a kink, so walking back it never falls inside a piece:
    the walk stops in the first piece whose slope at its start reaches the trend, at its
    end if its slope there does, else inside the arc where the slope equals the trend g
    (d = -g r / sqrt(1 + g^2) from its vertex). It also stops at the end of a line whose
    slope is within ``gentle`` of the trend: the ground's own gentle slopes (the wall of a
    dip, a vertical curve) are not part of the sudden ramp, while the arcs where the wheel
    rolls over an edge are, all of them. There the path detrended by the trend,
    y - g s, has its last highest point before the kink.
    """
    r = path.wheel_radius_m
    breaks = path.breaks_m
    start_slope = path.evaluate(breaks[:-1], np.arange(path.pieces))[1]
    end_slope = path.evaluate(breaks[1:], np.arange(path.pieces))[1]
    floor = kink_m - MAX_RAMP_M
    piece = path.piece_index(kink_m, side="left")
    top = np.maximum(floor, breaks[0])
    active = np.arange(kink_m.size)
    while active.size:
        p, g = piece[active], trend[active] - SLOPE_TOLERANCE
        at_end = (end_slope[p] >= g) | (~path.is_arc[p] & (end_slope[p] >= g - gentle))
        inside = ~at_end & (start_slope[p] >= g)  # an arc whose slope passes the trend
        done = at_end | inside
        stop = np.where(at_end, breaks[p + 1], 0.0)
        if inside.any():
            gi = trend[active[inside]]  # the crossing of the trend itself
            stop[inside] = np.clip(path.x_ref_m[p[inside]] - gi * r / np.sqrt(1.0 + gi * gi),
                                   breaks[p[inside]], breaks[p[inside] + 1])
        top[active[done]] = np.maximum(stop[done], floor[active[done]])
        # the rest walk back one piece, unless the walk has reached its floor or the path's start
        on = ~done & (breaks[p] > floor[active]) & (p > 0)
        piece[active[on]] -= 1
        active = active[on]
    return np.minimum(top, kink_m)


def _landings(path: WheelPath, min_slope: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Kink position, slope, rise and top position of every landing of ``path`` whose slope
    exceeds ``min_slope``, all measured against the grade the kink interrupts
    (:func:`trend_slope`); the ramp ends where the path's slope is back at that grade, or at
    a line of the path within :data:`SUDDEN_SHARE` ``min_slope`` of it (a gentler slope is
    not sudden: a ramp of it could cap no speed, and the body follows it)."""
    inner = path.breaks_m[1:-1]
    piece = np.arange(path.pieces - 1)
    y_kink, before, _ = path.evaluate(inner, piece)
    after = path.evaluate(inner, piece + 1)[1]
    # a landing of slope > min_slope takes at least SUDDEN_SHARE of it away at once
    near = np.flatnonzero(after - before > max(SUDDEN_SHARE * min_slope, 0.0))
    trend = trend_slope(path, inner[near])
    fall, rise_after = before[near] - trend, after[near] - trend
    land = (fall < -min_slope) & (rise_after - fall >= -SUDDEN_SHARE * fall)
    at, g = near[land], trend[land]
    kink = inner[at]
    top = _ramp_tops(path, kink, g, SUDDEN_SHARE * min_slope)
    y_top = path.evaluate(top, path.piece_index(top, side="left"))[0]
    rise = np.maximum((y_top - g * top) - (y_kink[at] - g * kink), 0.0)
    return kink, -fall[land], rise, top


def _mirrored(path: WheelPath) -> WheelPath:
    """The same path driven the other way, on positions ``L - s`` (L = first + last break)."""
    total = path.breaks_m[0] + path.breaks_m[-1]
    return WheelPath(breaks_m=(total - path.breaks_m)[::-1].copy(), x_ref_m=(total - path.x_ref_m)[::-1].copy(),
                     z_ref_m=path.z_ref_m[::-1].copy(), slope=-path.slope[::-1].copy(),
                     is_arc=path.is_arc[::-1].copy(), wheel_radius_m=path.wheel_radius_m)


def wheel_ramps(path: WheelPath, *, min_slope: float = 0.0) -> WheelRamps:
    """Every landing and climb of a wheel's path (:class:`WheelRamps`), sorted by start.

    A climb is a landing of the path driven the other way, so both are found by one rule.

    Parameters
    ----------
    path : WheelPath
        The path of the wheel's lowest point (:func:`profileopt.physics.wheel.wheel_path`).
    min_slope : float, default 0
        Only ramps steeper than this, against the trend (dimensionless), each ending at the
        trend or at a line of the path within :data:`SUDDEN_SHARE` ``min_slope`` of it: a
        ramp's force bound is at most V s (k phi_max + c), so :func:`step_caps` needs no
        gentler ones (and the walk back to the trend stops on the wall of a dip).

    Returns
    -------
    WheelRamps
    """
    total = path.breaks_m[0] + path.breaks_m[-1]
    kink_l, slope_l, rise_l, top_l = _landings(path, min_slope)
    kink_c, slope_c, rise_c, top_c = _landings(_mirrored(path), min_slope)
    kink_c, top_c = total - kink_c, total - top_c
    start = np.concatenate([top_l, kink_c])
    order = np.argsort(start, kind="stable")
    return WheelRamps(start_m=start[order], end_m=np.concatenate([kink_l, top_c])[order],
                      kink_m=np.concatenate([kink_l, kink_c])[order],
                      slope=np.concatenate([slope_l, slope_c])[order],
                      rise_m=np.concatenate([rise_l, rise_c])[order],
                      landing=np.concatenate([np.ones(kink_l.size, bool), np.zeros(kink_c.size, bool)])[order])


#: Above this many steep stretches :func:`step_caps` builds the wheel's path over the whole
#: route at once.
MAX_STRETCHES = 16


def impulse_response_peak_s(vehicle: "Vehicle") -> float:
    """phi_max, the largest value of the quarter car's unit impulse response (s).

    phi solves phi'' + 2 zeta wn phi' + wn^2 phi = 0, phi(0) = 0, phi'(0) = 1: the relative
    displacement y - x (m) after the base velocity y' steps by 1 m/s. Its largest value is
    phi_max = exp(-zeta h(zeta)) / wn with h = arccos(zeta) / sqrt(1 - zeta^2) below critical
    damping (at t = arccos(zeta) / w_d, where tan(w_d t) = w_d / (zeta wn)), 1 at zeta = 1
    (phi = t exp(-wn t)) and arccosh(zeta) / sqrt(zeta^2 - 1) above it.

    Parameters
    ----------
    vehicle : Vehicle
        Supplies wn (rad/s) and zeta (dimensionless).
    """
    zeta, wn = float(vehicle.damping_ratio), float(vehicle.natural_frequency_radps)
    if abs(zeta - 1.0) < 1e-9:
        h = 1.0
    elif zeta < 1.0:
        h = math.acos(zeta) / math.sqrt(1.0 - zeta * zeta)
    else:
        h = math.acosh(zeta) / math.sqrt(zeta * zeta - 1.0)
    return math.exp(-zeta * h) / wn


@elementwise
def ramp_force_n(speed_mps: Any, rise_m: Any, slope: Any, vehicle: "Vehicle") -> Any:
    """Bound on |F_T| while a rigid wheel runs a steep ramp of its path from rest, in N.

    The step limit of SBEM:TF (docs: guide/steps.md, "Steps and drops"). Where the wheel's path (the base
    input y) runs at slope s for a height d and starts or ends with a kink (it climbs a step
    met ahead; it lands after a drop), y' = V s for the t_r = d / (V s) seconds of the ramp,
    too short for the body to follow at speed. From rest, the relative displacement is
    z = y - x = V s phi(t) and z' = V s phi'(t), with phi the unit impulse response
    (:func:`impulse_response_peak_s`), so F_T = k z + c z' obeys, for t <= t_r,

        |F_T| <= k min(d, V s phi_max) + c V s        (|phi(t)| <= t, |phi'(t)| <= 1).

    Eq. (13) is the steady response to a smooth quarter sine; it has neither the ramp's
    slope nor the kink where the two terms peak together (a drop: just before landing,
    spring and damper push the same way). The bound rises strictly with V, so a speed cap
    keeps it (:func:`ramp_speed_cap_mps`).

    Parameters
    ----------
    speed_mps : number, array, DM, SX or MX
        Forward speed V (m/s), >= 0.
    rise_m : number, array, DM, SX or MX
        Height d of the ramp (m), >= 0: the rise or fall of the path from its kink to its
        highest point next to it.
    slope : number, array, DM, SX or MX
        |dy/ds| of the path on the ramp's side of the kink (dimensionless), >= 0.
    vehicle : Vehicle
        Quarter-car constants k = m wn^2 (N/m), c = 2 zeta m wn (N s/m), wn, zeta.
    """
    k, c = vehicle.spring_n_per_m, vehicle.damping_ns_per_m
    rate = speed_mps * slope  # y' on the ramp (m/s)
    return k * ca.fmin(rise_m, rate * impulse_response_peak_s(vehicle)) + c * rate


def ramp_speed_cap_mps(rise_m: np.ndarray, slope: np.ndarray, vehicle: "Vehicle", limit_n: float) -> np.ndarray:
    """The largest speed at which :func:`ramp_force_n` stays within ``limit_n`` (m/s).

    The bound is k min(d, V s phi_max) + c V s, continuous and strictly rising in V, linear
    on either side of V s phi_max = d: below it V = F / (s (k phi_max + c)), above it
    V = (F - k d) / (c s). inf where the slope is 0.

    Parameters
    ----------
    rise_m, slope : numpy.ndarray, shape (R,)
        Height (m) and |slope| (dimensionless) of each ramp.
    vehicle : Vehicle
        Quarter-car constants.
    limit_n : float
        Force limit (N), > 0.

    Returns
    -------
    numpy.ndarray, shape (R,)
    """
    d = np.asarray(rise_m, dtype=float)
    s = np.asarray(slope, dtype=float)
    k, c, phi = vehicle.spring_n_per_m, vehicle.damping_ns_per_m, impulse_response_peak_s(vehicle)
    with np.errstate(divide="ignore", invalid="ignore"):
        steep = limit_n / (s * (k * phi + c))  # while the spring's term is V s phi_max
        long = (limit_n - k * d) / (c * s)  # once it is k d
        cap = np.where(steep * s * phi <= d, steep, long)
    return np.where(s > 0, cap, np.inf)


@dataclasses.dataclass(frozen=True)
class StepCaps:
    """The ramps of a route's wheel path whose cap lies below the vehicle's top speed.

    Attributes
    ----------
    start_m, end_m : numpy.ndarray, shape (R,)
        Where each ramp starts and ends along the route (m).
    cap_mps : numpy.ndarray, shape (R,)
        Its :func:`ramp_speed_cap_mps` at the vehicle's ``max_transmitted_force_n`` (m/s).
    """

    start_m: np.ndarray
    end_m: np.ndarray
    cap_mps: np.ndarray

    def lowest_over(self, lo_m: np.ndarray, hi_m: np.ndarray, fill: float) -> np.ndarray:
        """The lowest cap of the ramps that share a point with each interval [lo_m[k], hi_m[k]]
        (m/s), ``fill`` where none does.

        Parameters
        ----------
        lo_m, hi_m : numpy.ndarray, shape (K,)
            Interval ends (m), each non-decreasing in k.
        fill : float
            The value of an interval no ramp meets (m/s).

        Returns
        -------
        numpy.ndarray, shape (K,)
        """
        out = np.full(np.shape(lo_m), float(fill))
        # interval k meets [start, end] when lo_k <= end and hi_k >= start
        first = np.searchsorted(hi_m, self.start_m, side="left")
        stop = np.searchsorted(lo_m, self.end_m, side="right")
        for a, b, value in zip(first.tolist(), stop.tolist(), self.cap_mps.tolist()):
            np.minimum(out[a:b], value, out=out[a:b])
        return out


def step_caps(s_m: np.ndarray, z_m: np.ndarray, vehicle: "Vehicle") -> StepCaps:
    """The step limit's caps on a route: every ramp of the wheel's path
    (:func:`profileopt.physics.steps.wheel_ramps`) whose cap is below the top speed.

    The wheel's path is built only around the stretches of the route that could need a cap
    (:func:`_steep_stretches`); on a route without one no path is built at all.

    Parameters
    ----------
    s_m, z_m : numpy.ndarray, shape (M,)
        The route's samples: distance (m), increasing, and elevation (m).
    vehicle : Vehicle
        Supplies the quarter car, the wheel radius, the top speed and
        ``max_transmitted_force_n``.

    Returns
    -------
    StepCaps
    """
    parts = []
    gentlest = gentlest_capping_slope(vehicle)
    m, r = s_m.size, vehicle.wheel_radius_m
    for lo, hi in _steep_stretches(s_m, z_m, vehicle):
        ramps = wheel_ramps(wheel_path(s_m[lo:hi], z_m[lo:hi], r), min_slope=gentlest)
        cap = ramp_speed_cap_mps(ramps.rise_m, ramps.slope, vehicle, vehicle.max_transmitted_force_n)
        # within r of a cut end the stretch's path is not the route's: no kink of a ramp that
        # can cap lies there (each lies within r of a steep slope, far inside the stretch)
        inside = ((lo == 0) | (ramps.kink_m > s_m[lo] + r)) & ((hi == m) | (ramps.kink_m < s_m[hi - 1] - r))
        binds = (cap < vehicle.max_speed_mps) & inside
        parts.append((ramps.start_m[binds], ramps.end_m[binds], cap[binds]))
    if not parts:
        return StepCaps(start_m=np.empty(0), end_m=np.empty(0), cap_mps=np.empty(0))
    return StepCaps(*(np.concatenate(column) for column in zip(*parts)))


def gentlest_capping_slope(vehicle: "Vehicle") -> float:
    """G = F / (V_top (k phi_max + c)): a ramp no steeper than this (against the trend) caps
    no speed the vehicle can drive, its force bound being at most V s (k phi_max + c).

    Parameters
    ----------
    vehicle : Vehicle
        Supplies the quarter car, ``max_transmitted_force_n`` (N) and the top speed (m/s).

    Returns
    -------
    float
        G (dimensionless).
    """
    return vehicle.max_transmitted_force_n / (
        vehicle.max_speed_mps * (vehicle.spring_n_per_m * impulse_response_peak_s(vehicle) + vehicle.damping_ns_per_m))


def _steep_stretches(s_m: np.ndarray, z_m: np.ndarray, vehicle: "Vehicle") -> list[tuple[int, int]]:
    """Sample ranges [lo, hi) whose wheel path holds every ramp that could cap a speed.

    A ramp caps a speed only if its slope against the trend exceeds the gentlest capping
    slope G (:func:`gentlest_capping_slope`), and then its kink raises the path's slope by
    more than :data:`SUDDEN_SHARE` G at once. The path's slopes on either side of a kink at s
    are slopes of the route's segments within r of s, or lie between two of them (the arcs),
    so that kink lies within r of a segment whose neighbours within r differ from it in
    slope by more than SUDDEN_SHARE G. Each such segment's stretch reaches
    max(:data:`MAX_RAMP_M`, :data:`TREND_HALF_WIDTH_M`) + r and two samples beyond it on
    either side, so that the ramp's walk and its trend see the whole route's path.
    Overlapping stretches are merged; more than :data:`MAX_STRETCHES` of them are one, the
    whole route (building the path is vectorised over its pieces, so one long call costs
    less than many short ones).
    """
    from ..terrain.roughness import range_extremes

    m = s_m.size
    if m < 3:
        return [(0, m)] if m == 2 else []
    r = vehicle.wheel_radius_m
    slope = np.diff(z_m) / np.diff(s_m)
    # the segments within r of each segment (those whose span meets [s_i - r, s_i+1 + r])
    first = np.maximum(np.searchsorted(s_m, s_m[:-1] - r, side="left") - 1, 0)
    stop = np.minimum(np.searchsorted(s_m, s_m[1:] + r, side="right"), m - 1)
    least, largest = range_extremes(slope, first, np.maximum(stop, first + 1))
    steep = np.flatnonzero(largest - least > SUDDEN_SHARE * gentlest_capping_slope(vehicle))
    if steep.size == 0:
        return []
    reach = max(MAX_RAMP_M, TREND_HALF_WIDTH_M) + r
    lo = np.clip(np.searchsorted(s_m, s_m[steep] - reach, side="left") - 2, 0, m)
    hi = np.clip(np.searchsorted(s_m, s_m[steep + 1] + reach, side="right") + 2, 0, m)
    stretches: list[tuple[int, int]] = []
    for a, b in zip(lo.tolist(), np.maximum.accumulate(hi).tolist()):
        if stretches and a <= stretches[-1][1]:
            stretches[-1] = (stretches[-1][0], b)
        else:
            stretches.append((a, b))
    return stretches if len(stretches) <= MAX_STRETCHES else [(0, m)]


def segment_step_caps_mps(caps: StepCaps, boundaries_m: np.ndarray) -> np.ndarray:
    """Each segment's lowest cap of the ramps it shares a point with (m/s), inf where none.

    Parameters
    ----------
    caps : StepCaps
        The route's ramps below the top speed (:func:`profileopt.physics.steps.step_caps`).
    boundaries_m : numpy.ndarray, shape (N+1,)
        Segment boundaries (m), increasing.

    Returns
    -------
    numpy.ndarray, shape (N,)
    """
    return caps.lowest_over(boundaries_m[:-1], boundaries_m[1:], np.inf)  # segment i: [b_i, b_i+1]


def step_speed_cap_mps(s_m: np.ndarray, z_m: np.ndarray, boundaries_m: np.ndarray, vehicle: "Vehicle"
                       ) -> np.ndarray:
    """The step limit's cap on every speed driven in each segment (m/s), inf where none.

    Parameters
    ----------
    s_m, z_m : numpy.ndarray, shape (M,)
        The route's samples: distance (m), increasing, and elevation (m).
    boundaries_m : numpy.ndarray, shape (N+1,)
        Segment boundaries (m), increasing.
    vehicle : Vehicle
        Supplies the quarter car, the wheel radius, the top speed and
        ``max_transmitted_force_n``.

    Returns
    -------
    numpy.ndarray, shape (N,)
    """
    return segment_step_caps_mps(step_caps(s_m, z_m, vehicle), boundaries_m)
