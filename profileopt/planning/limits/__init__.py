"""The kinds of limit a plan keeps, one module each, and the set every plan starts from.

- :class:`ForceLimit` (``force.py``): the terrain force model's admissible speed bands;
- :class:`DynamicForceLimit` (``dynamic.py``): the ``dynamic`` model's force, the simulated
  response (no bands; imposed by :mod:`profileopt.planning.dynamic`);
- :class:`StepLimit` (``step.py``): SBEM:TF's caps where the wheel meets a step or lands
  after a drop (with the ``sbem_tf`` model only);
- :class:`SpeedLimit` (``speed.py``): the vehicle's top speed and the route's speed limits;
- :class:`LateralLimit` (``lateral.py``): lateral acceleration in turns (and rollover);
- :class:`FrictionLimit` (``friction.py``): the friction circle;
- :class:`AccelLimit` (``accel.py``): acceleration and deceleration bounds, on grades;
- :class:`PowerLimit` (``power.py``): the drive power;
- :class:`JerkLimit` (``jerk.py``): the jerk bound;
- :class:`SimulatedLimit` (``simulated.py``): caps the planner's simulation gate lowers where
  the exact simulation went over the force limit (:mod:`profileopt.planning.gate`; not in
  :func:`default_limits`).

The limits of turns and hills (lateral, friction, power) are in a plan only when the vehicle
file gives their keys (:class:`profileopt.Vehicle`), and the grade enters the acceleration
bounds only when it gives any of them: a vehicle file without them plans exactly as before.

All follow :class:`Limit` (``base.py``). A new kind of limit is a new module with a
subclass of :class:`Limit`, registered in :func:`default_limits` below; a limit of your own
can also be passed to :func:`profileopt.plan` as ``extra_limits=`` without touching the
package.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from ...physics.motion import lateral_limit_mps2, plans_on_grades
from .accel import AccelLimit
from .base import Limit, PlanContext, worst_ratio
from .dynamic import DynamicForceLimit
from .force import ForceLimit
from .friction import FrictionLimit
from .jerk import JerkLimit
from .lateral import LateralLimit
from .power import PowerLimit
from .simulated import SimulatedLimit
from .speed import SpeedLimit
from .step import StepLimit

if TYPE_CHECKING:
    from ...core.vehicle import Vehicle

__all__ = ["Limit", "PlanContext", "worst_ratio", "ForceLimit", "DynamicForceLimit", "SpeedLimit", "AccelLimit", "JerkLimit",
           "LateralLimit", "FrictionLimit", "PowerLimit", "StepLimit", "SimulatedLimit",
           "default_limits"]


def default_limits(vehicle: "Vehicle", *, model: str, max_jerk_mps3: float) -> tuple[Limit, ...]:
    """The limits of a plan: force, speed caps, lateral, friction, acceleration, power, jerk
    (in this order, which is also the order of the summary's margins); lateral, friction and
    power only when the vehicle gives their keys; the step limit after the force with the
    ``sbem_tf`` model (it bounds the same transmitted force where Eq. 13 falls short). The
    ``dynamic`` model's force limit is the simulated response (:class:`DynamicForceLimit`,
    imposed by :mod:`profileopt.planning.dynamic`).

    Parameters
    ----------
    vehicle : Vehicle
        Supplies the top speed and the acceleration bounds.
    model : str
        Force model key.
    max_jerk_mps3 : float
        Jerk bound (m/s^3); inf turns it off.

    Returns
    -------
    tuple of Limit
    """
    limits: list[Limit] = [DynamicForceLimit() if model == "dynamic" else ForceLimit(model=model)]
    if model == "sbem_tf":
        limits.append(StepLimit())
    limits.append(SpeedLimit(max_speed_mps=vehicle.max_speed_mps))
    lateral = lateral_limit_mps2(vehicle)
    if math.isfinite(lateral):
        limits.append(LateralLimit(limit_mps2=lateral))
    if vehicle.friction_coefficient is not None:
        limits.append(FrictionLimit(friction_coefficient=vehicle.friction_coefficient))
    limits.append(AccelLimit(max_accel_mps2=vehicle.max_accel_mps2, max_decel_mps2=vehicle.max_decel_mps2,
                             grade=plans_on_grades(vehicle)))
    if vehicle.max_power_w is not None and vehicle.mass_kg is not None:
        limits.append(PowerLimit(mass_kg=vehicle.mass_kg, max_power_w=vehicle.max_power_w))
    limits.append(JerkLimit(max_jerk_mps3=max_jerk_mps3))
    return tuple(limits)
