"""Steps met and drops landed: the steep ramps of a rigid wheel's path, the force on them, and
the step limit of SBEM:TF.

A rigid wheel's path y(s) (:mod:`profileopt.physics.wheel`) kinks where its contact jumps from
one piece of the ground to another, and there its slope always rises (the path is an upper
envelope). Two kinds of kink start or end a ramp that the quarter car meets suddenly:

* a **landing**: the path runs down at slope -s and the kink takes at least half of that
  slope away at once (the wheel lands after a drop). The ramp runs from the path's last
  highest point before the kink down to the kink;
* a **climb**: the kink gives the path at least half of its following slope +s at once
  (the wheel meets a step ahead, or the foot of a steep ramp). The ramp runs from the kink
  up to the path's next highest point.

The rise d of a ramp is the height between its kink and that highest point. The step limit
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

__all__ = ["WheelRamps", "wheel_ramps", "SUDDEN_SHARE", "impulse_response_peak_s", "ramp_force_n",
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
        |dy/ds| of the path next to the kink on the ramp's side (dimensionless), > 0.
    rise_m : numpy.ndarray, shape (R,)
        Height between the kink and the ramp's highest end (m), >= 0.
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


def _landings(path: WheelPath) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Kink position, slope, rise and top position of every landing of ``path``."""
    inner = path.breaks_m[1:-1]
    piece = np.arange(path.pieces - 1)
    y_kink, before, _ = path.evaluate(inner, piece)
    after = path.evaluate(inner, piece + 1)[1]
    land = (before < 0) & (after - before >= -SUDDEN_SHARE * before)
    # the path's highest points: its breaks and the tops of its arcs are where it can turn
    s = np.unique(np.clip(np.concatenate([path.breaks_m, path.x_ref_m[path.is_arc]]),
                          path.breaks_m[0], path.breaks_m[-1]))
    y = path.evaluate(s)[0]
    top = np.concatenate([[True], (y[1:-1] >= y[:-2]) & (y[1:-1] >= y[2:]), [True]])
    last_top = np.maximum.accumulate(np.where(top, np.arange(s.size), 0))
    # the last highest point strictly before each kink
    at = np.searchsorted(s, inner[land], side="left") - 1
    j = last_top[np.maximum(at, 0)]
    return inner[land], -before[land], np.maximum(y[j] - y_kink[land], 0.0), s[j]


def _mirrored(path: WheelPath) -> WheelPath:
    """The same path driven the other way, on positions ``L - s`` (L = first + last break)."""
    total = path.breaks_m[0] + path.breaks_m[-1]
    return WheelPath(breaks_m=(total - path.breaks_m)[::-1].copy(), x_ref_m=(total - path.x_ref_m)[::-1].copy(),
                     z_ref_m=path.z_ref_m[::-1].copy(), slope=-path.slope[::-1].copy(),
                     is_arc=path.is_arc[::-1].copy(), wheel_radius_m=path.wheel_radius_m)


def wheel_ramps(path: WheelPath) -> WheelRamps:
    """Every landing and climb of a wheel's path (:class:`WheelRamps`), sorted by start.

    A climb is a landing of the path driven the other way, so both are found by one rule.

    Parameters
    ----------
    path : WheelPath
        The path of the wheel's lowest point (:func:`profileopt.physics.wheel.wheel_path`).

    Returns
    -------
    WheelRamps
    """
    total = path.breaks_m[0] + path.breaks_m[-1]
    kink_l, slope_l, rise_l, top_l = _landings(path)
    kink_c, slope_c, rise_c, top_c = _landings(_mirrored(path))
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

    The wheel's path is built only around slopes of the route that could need a cap: the
    bound is at most V s (k phi_max + c), and the path's slopes never exceed the route's (its
    pieces are the route's lines, offset, and arcs between them), so a ramp can cap a speed the
    vehicle can drive only next to a slope above F / (V_top (k phi_max + c)); on a route
    without one no path is built at all.

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
    for lo, hi in _steep_stretches(s_m, z_m, vehicle):
        ramps = wheel_ramps(wheel_path(s_m[lo:hi], z_m[lo:hi], vehicle.wheel_radius_m))
        cap = ramp_speed_cap_mps(ramps.rise_m, ramps.slope, vehicle, vehicle.max_transmitted_force_n)
        binds = cap < vehicle.max_speed_mps
        parts.append((ramps.start_m[binds], ramps.end_m[binds], cap[binds]))
    if not parts:
        return StepCaps(start_m=np.empty(0), end_m=np.empty(0), cap_mps=np.empty(0))
    return StepCaps(*(np.concatenate(column) for column in zip(*parts)))


def _steep_stretches(s_m: np.ndarray, z_m: np.ndarray, vehicle: "Vehicle") -> list[tuple[int, int]]:
    """Sample ranges [lo, hi) whose wheel path holds every ramp that could cap a speed.

    Only a slope above F / (V_top (k phi_max + c)) can (:func:`step_caps`). A ramp runs from
    its kink, next to such a slope, to the path's highest point beside it, which lies within
    r of a highest sample of the route (rolling a wheel over a falling polyline gives a
    falling path); each steep slope's stretch reaches from the highest sample before it to
    the one after it, and r and two samples beyond, so that the path there is the whole
    route's. Overlapping stretches are merged; more than :data:`MAX_STRETCHES` of them are
    one, the whole route (building the path is vectorised over its pieces, so one long call
    costs less than many short ones).
    """
    if s_m.size < 2:
        return []
    limit = vehicle.max_transmitted_force_n
    gentlest = limit / (vehicle.max_speed_mps * (vehicle.spring_n_per_m * impulse_response_peak_s(vehicle)
                                                 + vehicle.damping_ns_per_m))
    steep = np.flatnonzero(np.abs(np.diff(z_m)) > gentlest * np.diff(s_m))
    if steep.size == 0:
        return []
    m = s_m.size
    index = np.arange(m)
    top = np.ones(m, dtype=bool)
    top[1:-1] = (z_m[1:-1] >= z_m[:-2]) & (z_m[1:-1] >= z_m[2:])
    before = np.maximum.accumulate(np.where(top, index, 0))[steep]  # the highest sample at or before
    after = np.minimum.accumulate(np.where(top, index, m - 1)[::-1])[::-1][steep + 1]  # at or after
    reach = vehicle.wheel_radius_m
    lo = np.searchsorted(s_m, s_m[before] - reach, side="left") - 2
    hi = np.searchsorted(s_m, s_m[after] + reach, side="right") + 2
    lo, hi = np.clip(lo, 0, m), np.clip(hi, 0, m)
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
