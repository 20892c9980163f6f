"""The vehicle's motion along a 3-D path: turns, slopes, tyre friction and drive power.

Every formula of issue 11's limits is written here once, as plain arithmetic that works on
numbers, numpy arrays and CasADi symbols alike (as :mod:`profileopt.core.kinematics` does), so
the planner (:mod:`profileopt.planning.limits`) and the MPC constraints
(:mod:`profileopt.mpc.constraints`) evaluate the same expressions.

Conventions (SI units):

- ``speed_mps`` v along the path; ``accel_mps2`` a = dv/dt along the path;
- ``curvature_1pm`` kappa of the path in the horizontal plane (1/m; its sign, left or
  right, does not matter here: pass |kappa|);
- ``grade_rad`` theta, the path's inclination (positive uphill in the direction of travel).

Along the path, the tyres must supply a longitudinal force per unit mass
a + g sin(theta) (gravity's share is g sin(theta) uphill), and a lateral one v^2 kappa.
The friction circle bounds their vector sum by mu g cos(theta) (the normal force per unit
mass); the drive power bounds m (a + g sin(theta)) v (braking needs no power).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from ..core.vehicle import OPTIONAL_KEYS
from ..defaults import CRAWL_SPEED_MPS

if TYPE_CHECKING:
    from ..core.vehicle import Vehicle

__all__ = ["STANDARD_GRAVITY_MPS2", "lateral_accel_mps2", "rollover_threshold_mps2", "lateral_limit_mps2",
           "tyre_accel_mps2", "friction_radius_mps2", "friction_usage", "drive_power_w", "power_accel_mps2",
           "lateral_speed_cap_mps", "turn_speed_cap_mps", "plans_on_grades",
           "segment_friction_radius_mps2"]

#: Standard gravity g (m/s^2), ISO 80000-3.
STANDARD_GRAVITY_MPS2 = 9.80665


def lateral_accel_mps2(speed_mps: Any, curvature_1pm: Any) -> Any:
    """Lateral (centripetal) acceleration v^2 kappa of a turn (m/s^2).

    Parameters
    ----------
    speed_mps : array_like or CasADi
        Speed along the path (m/s).
    curvature_1pm : array_like or CasADi
        |kappa|, curvature of the path (1/m), >= 0.
    """
    return speed_mps**2 * curvature_1pm


def rollover_threshold_mps2(track_width_m: float, cg_height_m: float) -> float:
    """Static rollover threshold g t / (2 h_cg) (m/s^2): the lateral acceleration at which a
    rigid vehicle's inner wheels lift (Gillespie, Fundamentals of Vehicle Dynamics, 1992,
    section 9, "quasi-static rollover of a rigid vehicle").

    Parameters
    ----------
    track_width_m : float
        Track width t (m).
    cg_height_m : float
        Height of the centre of gravity h_cg (m).
    """
    return STANDARD_GRAVITY_MPS2 * track_width_m / (2.0 * cg_height_m)


def lateral_limit_mps2(vehicle: "Vehicle") -> float:
    """The vehicle's lateral acceleration limit (m/s^2): the smaller of
    ``max_lateral_accel_mps2`` and the rollover threshold; inf when it gives neither.

    Parameters
    ----------
    vehicle : Vehicle
        The vehicle.
    """
    limit = math.inf
    if vehicle.max_lateral_accel_mps2 is not None:
        limit = vehicle.max_lateral_accel_mps2
    if vehicle.track_width_m is not None and vehicle.cg_height_m is not None:
        limit = min(limit, rollover_threshold_mps2(vehicle.track_width_m, vehicle.cg_height_m))
    return limit


def lateral_speed_cap_mps(lateral_limit: Any, curvature_1pm: Any) -> Any:
    """The highest speed with v^2 kappa <= lateral_limit: sqrt(lateral_limit / kappa) (m/s);
    inf on a straight (kappa = 0). Numeric arguments only (numpy).

    Parameters
    ----------
    lateral_limit : float or numpy.ndarray
        Lateral acceleration limit (m/s^2).
    curvature_1pm : float or numpy.ndarray
        |kappa| (1/m), >= 0.
    """
    import numpy as np

    kappa = np.asarray(curvature_1pm, dtype=float)
    with np.errstate(divide="ignore"):
        return np.sqrt(np.where(kappa > 0, lateral_limit / np.where(kappa > 0, kappa, 1.0), np.inf))


def turn_speed_cap_mps(lateral_limit: Any, curvature_1pm: Any, min_turn_radius_m: float | None = None) -> Any:
    """The highest speed in a turn: sqrt(lateral_limit / kappa) (:func:`lateral_speed_cap_mps`),
    and at most :data:`~profileopt.defaults.CRAWL_SPEED_MPS` where the turn is sharper than the
    vehicle can steer, kappa > 1 / min_turn_radius_m: it is driven there in several moves, at a
    crawl. Numeric arguments only (numpy).

    Parameters
    ----------
    lateral_limit : float or numpy.ndarray
        Lateral acceleration limit (m/s^2).
    curvature_1pm : float or numpy.ndarray
        |kappa| (1/m), >= 0.
    min_turn_radius_m : float, optional
        The vehicle's turning circle (m); None: no turning circle (the lateral cap alone).

    Returns
    -------
    numpy.ndarray
        The cap (m/s), inf on a straight.
    """
    cap = lateral_speed_cap_mps(lateral_limit, curvature_1pm)
    if min_turn_radius_m is None:
        return cap
    return np.where(np.asarray(curvature_1pm, dtype=float) * min_turn_radius_m > 1.0,
                    np.minimum(cap, CRAWL_SPEED_MPS), cap)


def tyre_accel_mps2(accel_mps2: Any, grade_rad: Any) -> Any:
    """Longitudinal force per unit mass the tyres must supply: a + g sin(theta) (m/s^2).

    Parameters
    ----------
    accel_mps2 : array_like or CasADi
        Acceleration along the path (m/s^2).
    grade_rad : array_like or CasADi
        Grade theta (rad), positive uphill.
    """
    return accel_mps2 + STANDARD_GRAVITY_MPS2 * _sin(grade_rad)


def friction_radius_mps2(friction_coefficient: float, grade_rad: Any) -> Any:
    """Radius of the friction circle, mu g cos(theta) (m/s^2).

    Parameters
    ----------
    friction_coefficient : float
        mu (-).
    grade_rad : array_like or CasADi
        Grade theta (rad).
    """
    return friction_coefficient * STANDARD_GRAVITY_MPS2 * _cos(grade_rad)


def segment_friction_radius_mps2(friction_coefficient: float, grade_lo_rad: Any, grade_hi_rad: Any) -> Any:
    """The smallest friction circle over a segment's grades, mu g cos(max |theta|) (m/s^2).

    Parameters
    ----------
    friction_coefficient : float
        mu (-).
    grade_lo_rad, grade_hi_rad : array_like
        The least and the largest grade of each segment (rad).
    """
    return friction_radius_mps2(friction_coefficient, np.maximum(np.abs(grade_lo_rad), np.abs(grade_hi_rad)))


def friction_usage(speed_mps: Any, accel_mps2: Any, curvature_1pm: Any, grade_rad: Any,
                   friction_coefficient: float) -> Any:
    """Share of the friction circle used: ((a + g sin theta)^2 + (v^2 kappa)^2) / (mu g cos theta)^2.

    The friction limit is ``friction_usage <= 1``.

    Parameters
    ----------
    speed_mps, accel_mps2, curvature_1pm, grade_rad : array_like or CasADi
        v (m/s), a (m/s^2), |kappa| (1/m) and theta (rad).
    friction_coefficient : float
        mu (-).
    """
    along = tyre_accel_mps2(accel_mps2, grade_rad)
    across = lateral_accel_mps2(speed_mps, curvature_1pm)
    return (along**2 + across**2) / friction_radius_mps2(friction_coefficient, grade_rad) ** 2


def drive_power_w(mass_kg: float, speed_mps: Any, accel_mps2: Any, grade_rad: Any) -> Any:
    """Drive power m (a + g sin theta) v that the motion needs at the wheels (W); negative
    when braking (no power is needed then).

    Parameters
    ----------
    mass_kg : float
        Mass of the whole vehicle (kg).
    speed_mps, accel_mps2, grade_rad : array_like or CasADi
        v (m/s), a (m/s^2) and theta (rad).
    """
    return mass_kg * tyre_accel_mps2(accel_mps2, grade_rad) * speed_mps


def power_accel_mps2(max_power_w: float, mass_kg: float, speed_mps: Any, grade_rad: Any) -> Any:
    """The largest acceleration the drive power allows: P / (m v) - g sin(theta) (m/s^2).

    Parameters
    ----------
    max_power_w : float
        Largest drive power P (W).
    mass_kg : float
        Mass m of the whole vehicle (kg).
    speed_mps, grade_rad : array_like or CasADi
        v (m/s, > 0) and theta (rad).
    """
    return max_power_w / (mass_kg * speed_mps) - STANDARD_GRAVITY_MPS2 * _sin(grade_rad)


def _sin(x: Any) -> Any:
    """sin on numbers and numpy arrays (numpy) or on CasADi values (casadi)."""
    if type(x).__module__.startswith("casadi"):
        import casadi as ca

        return ca.sin(x)
    import numpy as np

    return np.sin(x)


def _cos(x: Any) -> Any:
    """cos on numbers and numpy arrays (numpy) or on CasADi values (casadi)."""
    if type(x).__module__.startswith("casadi"):
        import casadi as ca

        return ca.cos(x)
    import numpy as np

    return np.cos(x)


def plans_on_grades(vehicle: "Vehicle") -> bool:
    """Whether the grade enters ``vehicle``'s acceleration bounds: when its file gives any key
    of turns and hills (it then describes the vehicle's motion on 3-D routes; without any, a
    plan is exactly what it was before they existed).

    Parameters
    ----------
    vehicle : Vehicle
        The vehicle.

    Returns
    -------
    bool
    """
    return any(getattr(vehicle, key) is not None for key in OPTIONAL_KEYS)
