"""The force on a steep ramp of a rigid wheel's path: the step limit of SBEM:TF.

Eq. (13) (:func:`profileopt.forces.sbem_tf_force_n`) is the steady response to a smooth
quarter sine. Where the wheel meets a step or lands after a drop, its path runs a steep ramp
that starts or ends in a kink (:mod:`profileopt.ramps`), faster than the body can follow;
:func:`ramp_force_n` bounds the transmitted force there, from the quarter car's impulse
response, and :func:`ramp_speed_cap_mps` is the speed where that bound meets a limit. Like
the force models, the bound is one CasADi expression for numbers, arrays, DM, SX and MX.
Quarter-car constants: k = m wn^2, c = 2 zeta m wn (docs/paper-notes.md).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import casadi as ca
import numpy as np

from .symbolic import elementwise

if TYPE_CHECKING:
    from .vehicle import Vehicle

__all__ = ["impulse_response_peak_s", "ramp_force_n", "ramp_speed_cap_mps"]


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

    The step limit of SBEM:TF (README, "Steps and drops"). Where the wheel's path (the base
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
