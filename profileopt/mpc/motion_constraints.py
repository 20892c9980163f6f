"""The limits of turns and hills as ``(g, lbg, ubg)`` constraints for your own CasADi problems.

Three functions put the vehicle's motion limits into a model-predictive controller (plain
``casadi.nlpsol``, ``casadi.Opti``, rockit, do-mpc, acados), in the style of
:func:`~profileopt.mpc.constraints.force_constraints`. Each row is normalised to order one and
``g <= 0`` means the limit holds:

:func:`lateral_constraints`
    v^2 |kappa| / a_lat - 1 <= 0, a_lat of :func:`~profileopt.physics.motion.lateral_limit_mps2`
    (``max_lateral_accel_mps2`` and the static rollover threshold, the smaller).
:func:`friction_constraints`
    :func:`~profileopt.physics.motion.friction_usage` - 1 <= 0: the friction circle
    (a + g sin theta)^2 + (v^2 kappa)^2 <= (mu g cos theta)^2.
:func:`power_constraints`
    :func:`~profileopt.physics.motion.drive_power_w` / P - 1 <= 0: m (a + g sin theta) v <= P
    (braking needs no power, so only the upper side binds).

No formula is written here: every row is an expression of :mod:`profileopt.physics.motion`, the
same one the planner evaluates. Arguments may be numbers, numpy arrays, ``DM``, ``SX`` or
``MX``; ``g`` is then a ``DM``, ``SX`` or ``MX`` column. The sign of the curvature does not
matter (left and right turns are alike): the rows use |kappa| (``casadi.fabs``, also for
symbols, whose derivative at kappa = 0 is taken as 0).

Stages and segments
-------------------
Each function accepts two layouts, as ``force_constraints`` does:

* *points*: N speeds and N values of each other argument (any of them, the speed too, may
  be one value for all stages): one row per stage;
* *segments*: N + 1 boundary speeds and N values of acceleration, curvature and grade
  (or one for all): segment i runs from v_i to v_{i+1} with a_i, kappa_i and theta_i, and
  both its entry and its exit speed are constrained (2 N rows, segment by segment).

In the planner a segment's speeds vary between its two boundary speeds, so the lateral and
power rows are tightest at the higher speed, and the friction row at the higher speed and
the larger |a + g sin theta|. With a, kappa and theta fixed over a segment, the lateral and
friction rows grow with v >= 0 and the power row is linear in v, so holding both ends holds
every speed in between: an MPC user who wants the limit between stages passes both stage
speeds (a ``(N + 1,)`` speed vector with N segment accelerations) and the segment's
largest |kappa| and its worst grade (the steepest climb for power). When every argument
but the speed has one value, the two layouts give the same rows (one per speed).

Units: speeds in m/s, accelerations in m/s^2, curvatures in 1/m, grades in rad (positive
uphill), powers in W; g is dimensionless.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import casadi as ca
import numpy as np

from ..core.symbolic import is_symbolic
from ..core.vehicle import Vehicle
from ..errors import InputError
from ..physics.motion import (
    drive_power_w,
    friction_usage,
    lateral_accel_mps2,
    lateral_limit_mps2,
)
from .horizon import ConstraintTriple

__all__ = ["MotionConstraints", "lateral_constraints", "friction_constraints", "power_constraints"]


@dataclasses.dataclass(frozen=True)
class MotionConstraints(ConstraintTriple):
    """Motion-limit constraints lbg <= g <= ubg (lateral, friction or power).

    Unpacks as the triple ``g, lbg, ubg = lateral_constraints(...)`` that
    ``casadi.nlpsol`` takes, indexes like it (``cons[0]`` is ``g``), and converts to the
    dict of the same three: ``dict(cons)``, ``{**cons}``, as
    :class:`~profileopt.mpc.constraints.ForceConstraints` does.

    Attributes
    ----------
    g : casadi.SX, casadi.MX or casadi.DM, shape (R, 1)
        The rows value / limit - 1 (dimensionless): R = N (points) or 2 N (segments).
    lbg, ubg : numpy.ndarray, shape (R,)
        Bounds: -inf and 0.
    value : casadi.SX, casadi.MX or casadi.DM, shape (R, 1)
        What each row constrains, for inspection: the lateral acceleration v^2 |kappa|
        (m/s^2), the share of the friction circle used (-) or the drive power (W).
    limit : float
        Its limit: a_lat (m/s^2), 1 (-) or P (W).
    name : str
        ``"lateral"``, ``"friction"`` or ``"power"``.
    """

    g: Any
    lbg: np.ndarray
    ubg: np.ndarray
    value: Any
    limit: float
    name: str



def lateral_constraints(speed_mps: Any, curvature_1pm: Any, vehicle: Vehicle) -> MotionConstraints:
    """The lateral acceleration limit in turns: v^2 |kappa| / a_lat - 1 <= 0.

    a_lat is :func:`~profileopt.physics.motion.lateral_limit_mps2` (vehicle): the smaller of
    ``max_lateral_accel_mps2`` and the static rollover threshold g t / (2 h_cg) (Gillespie,
    1992), whichever the vehicle gives.

    Parameters
    ----------
    speed_mps : SX, MX, DM, numpy array or number, shape (N,), (N + 1,) or scalar
        Stage speeds v (m/s), >= 0; N + 1 boundary speeds for the segments layout.
    curvature_1pm : SX, MX, DM, numpy array or number, shape (N,) or scalar
        Curvature kappa of each stage or segment (1/m); its sign does not matter.
    vehicle : Vehicle
        Gives ``max_lateral_accel_mps2``, or ``track_width_m`` and ``cg_height_m``, or both.

    Returns
    -------
    MotionConstraints
        Unpacks as ``g, lbg, ubg``: N rows (points) or 2 N (segments, entry and exit speed
        of each segment), ``lbg`` -inf, ``ubg`` 0; ``value`` is v^2 |kappa| (m/s^2) and
        ``limit`` a_lat.

    Raises
    ------
    InputError
        The vehicle gives no lateral limit, lengths that do not match, or a number that is
        NaN or infinite, or a negative speed.
    """
    where = "lateral_constraints"
    _check_vehicle(where, vehicle)
    limit = lateral_limit_mps2(vehicle)
    if not math.isfinite(limit):
        raise InputError(f"{where}: vehicle {_label(vehicle)} gives no lateral limit; add max_lateral_accel_mps2 "
                         "(m/s^2), or track_width_m and cg_height_m (m), to the vehicle file")
    v, (kappa,) = _stage_rows(where, speed_mps, curvature_1pm=curvature_1pm)
    value = lateral_accel_mps2(v, ca.fabs(kappa))
    return _normalised(value, limit, "lateral")


def friction_constraints(speed_mps: Any, accel_mps2: Any, curvature_1pm: Any, grade_rad: Any,
                         vehicle: Vehicle) -> MotionConstraints:
    """The friction circle: :func:`~profileopt.physics.motion.friction_usage` - 1 <= 0, that is
    (a + g sin theta)^2 + (v^2 kappa)^2 <= (mu g cos theta)^2.

    Parameters
    ----------
    speed_mps : SX, MX, DM, numpy array or number, shape (N,), (N + 1,) or scalar
        Stage speeds v (m/s), >= 0; N + 1 boundary speeds for the segments layout.
    accel_mps2 : SX, MX, DM, numpy array or number, shape (N,) or scalar
        Acceleration a along the path of each stage or segment (m/s^2).
    curvature_1pm : SX, MX, DM, numpy array or number, shape (N,) or scalar
        Curvature kappa (1/m); its sign does not matter.
    grade_rad : SX, MX, DM, numpy array or number, shape (N,) or scalar
        Grade theta (rad), positive uphill, in (-pi/2, pi/2).
    vehicle : Vehicle
        Gives ``friction_coefficient`` mu.

    Returns
    -------
    MotionConstraints
        Unpacks as ``g, lbg, ubg``: N rows (points) or 2 N (segments), ``lbg`` -inf,
        ``ubg`` 0; ``value`` is the share of the friction circle used and ``limit`` 1.

    Raises
    ------
    InputError
        The vehicle has no ``friction_coefficient``, lengths that do not match, a number
        that is NaN or infinite, a negative speed, or a grade outside (-pi/2, pi/2).
    """
    where = "friction_constraints"
    _check_vehicle(where, vehicle)
    if vehicle.friction_coefficient is None:
        raise InputError(f"{where}: vehicle {_label(vehicle)} has no friction_coefficient; add "
                         "friction_coefficient (the tyre-ground friction mu, -) to the vehicle file")
    v, (a, kappa, theta) = _stage_rows(where, speed_mps, accel_mps2=accel_mps2, curvature_1pm=curvature_1pm,
                                       grade_rad=grade_rad)
    value = friction_usage(v, a, ca.fabs(kappa), theta, vehicle.friction_coefficient)
    return _normalised(value, 1.0, "friction")


def power_constraints(speed_mps: Any, accel_mps2: Any, grade_rad: Any, vehicle: Vehicle) -> MotionConstraints:
    """The drive power limit: :func:`~profileopt.physics.motion.drive_power_w` / P - 1 <= 0, that is
    m (a + g sin theta) v <= P.

    Braking (a + g sin theta < 0) needs no power: its rows are below -1 and never bind.

    Parameters
    ----------
    speed_mps : SX, MX, DM, numpy array or number, shape (N,), (N + 1,) or scalar
        Stage speeds v (m/s), >= 0 (forward driving); N + 1 boundary speeds for the
        segments layout.
    accel_mps2 : SX, MX, DM, numpy array or number, shape (N,) or scalar
        Acceleration a along the path of each stage or segment (m/s^2).
    grade_rad : SX, MX, DM, numpy array or number, shape (N,) or scalar
        Grade theta (rad), positive uphill, in (-pi/2, pi/2).
    vehicle : Vehicle
        Gives ``mass_kg`` m and ``max_power_w`` P.

    Returns
    -------
    MotionConstraints
        Unpacks as ``g, lbg, ubg``: N rows (points) or 2 N (segments), ``lbg`` -inf,
        ``ubg`` 0; ``value`` is the drive power (W) and ``limit`` P.

    Raises
    ------
    InputError
        The vehicle has no ``mass_kg`` and ``max_power_w``, lengths that do not match, a
        number that is NaN or infinite, a negative speed, or a grade outside
        (-pi/2, pi/2).
    """
    where = "power_constraints"
    _check_vehicle(where, vehicle)
    if vehicle.mass_kg is None or vehicle.max_power_w is None:
        raise InputError(f"{where}: vehicle {_label(vehicle)} has no mass_kg and max_power_w; add mass_kg (the "
                         "mass of the whole vehicle, kg) and max_power_w (the drive power at the wheels, W) to the "
                         "vehicle file")
    v, (a, theta) = _stage_rows(where, speed_mps, accel_mps2=accel_mps2, grade_rad=grade_rad)
    value = drive_power_w(vehicle.mass_kg, v, a, theta)
    return _normalised(value, vehicle.max_power_w, "power")


# ---------------------------------------------------------------------------------------
# Helpers
# ---------------------------------------------------------------------------------------


def _check_vehicle(where: str, vehicle: Any) -> None:
    if not isinstance(vehicle, Vehicle):
        raise InputError(f"{where}: vehicle must be a Vehicle (profileopt.load_vehicle), got "
                         f"{type(vehicle).__name__}")


def _label(vehicle: Vehicle) -> str:
    return repr(vehicle.name) if vehicle.name else "(built in code)"


def _normalised(value: Any, limit: float, name: str) -> MotionConstraints:
    n = int(value.shape[0])
    return MotionConstraints(g=value / limit - 1.0, lbg=np.full(n, -np.inf), ubg=np.zeros(n), value=value,
                             limit=float(limit), name=name)


def _column(where: str, name: str, value: Any) -> Any:
    """``value`` as a column (SX, MX, DM reshaped; numbers and arrays as DM), its numbers
    checked: finite, speeds >= 0, grades inside (-pi/2, pi/2)."""
    if is_symbolic(value):
        return ca.vec(value)
    try:
        numbers = np.asarray(value.full() if isinstance(value, ca.DM) else value, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{where}: {name} = {value!r} is not numbers; give numbers, arrays or CasADi values") \
            from None
    if not np.all(np.isfinite(numbers)):
        raise InputError(f"{where}: {name} holds a NaN or infinite value; give finite numbers")
    if name == "speed_mps" and np.any(numbers < 0):
        raise InputError(f"{where}: speed_mps must be speeds >= 0 in m/s (forward driving)")
    if name == "grade_rad" and np.any(np.abs(numbers) >= math.pi / 2):
        raise InputError(f"{where}: grade_rad must lie in (-pi/2, pi/2) rad (a 10 % slope is atan(0.1) = 0.0997 rad)")
    return ca.DM(numbers.reshape(-1, 1))


def _stage_rows(where: str, speed: Any, **per_stage: Any) -> tuple[Any, list[Any]]:
    """Speeds and the per-stage arguments row by row for the points or segments layout
    (module docstring): N + 1 speeds and N values give 2 N rows, entry and exit of each
    segment, ordered segment by segment; an argument of one value (the speed too) applies
    to every stage."""
    v = _column(where, "speed_mps", speed)
    n_v = v.shape[0]
    if n_v == 0:
        raise InputError(f"{where}: no speeds were given; pass at least one stage speed")
    cols = {name: _column(where, name, value) for name, value in per_stage.items()}
    for name, col in cols.items():
        if col.shape[0] == 0:
            raise InputError(f"{where}: {name} is empty; give one value per stage or one for all")
    lengths = {name: col.shape[0] for name, col in cols.items() if col.shape[0] != 1}
    if len(set(lengths.values())) > 1:
        described = ", ".join(f"{name} has {n}" for name, n in lengths.items())
        raise InputError(f"{where}: {described} values; give the same number N for each (or one value for all)")
    n = next(iter(lengths.values()), n_v)
    if n_v == 1 and n > 1:  # one speed for every stage
        v, n_v = ca.repmat(v, n, 1), n
    if n == n_v:  # points
        return v, [col if col.shape[0] == n else ca.repmat(col, n, 1) for col in cols.values()]
    if n_v == n + 1:  # segments: both ends of segment i with the values of segment i
        v_rows = ca.vec(ca.horzcat(v[:-1], v[1:]).T)
        rows = []
        for col in cols.values():
            col = col if col.shape[0] == n else ca.repmat(col, n, 1)
            rows.append(ca.vec(ca.horzcat(col, col).T))
        return v_rows, rows
    name = next(iter(lengths))
    raise InputError(f"{where}: {n_v} speeds and {n} values of {name} do not match; give N speeds and N values "
                     "(points), N + 1 speeds and N values (segments), or one value for all")
