"""The kinds of limit a plan keeps, one module each, and the set every plan starts from.

- :class:`ForceLimit` (``force.py``): the terrain force model's admissible speed bands;
- :class:`SpeedLimit` (``speed.py``): the vehicle's top speed and the route's speed limits;
- :class:`AccelLimit` (``accel.py``): acceleration and deceleration bounds;
- :class:`JerkLimit` (``jerk.py``): the jerk bound.

All follow :class:`Limit` (``base.py``). A new kind of limit is a new module with a
subclass of :class:`Limit`, registered in :func:`default_limits` below; a limit of your own
can also be passed to :func:`profileopt.plan` as ``extra_limits=`` without touching the
package.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .accel import AccelLimit
from .base import Limit, PlanContext, worst_ratio
from .force import ForceLimit
from .jerk import JerkLimit
from .speed import SpeedLimit

if TYPE_CHECKING:
    from ...vehicle import Vehicle

__all__ = ["Limit", "PlanContext", "worst_ratio", "ForceLimit", "SpeedLimit", "AccelLimit", "JerkLimit",
           "default_limits"]


def default_limits(vehicle: "Vehicle", *, model: str, max_jerk_mps3: float) -> tuple[Limit, ...]:
    """The limits every plan keeps: force, speed caps, acceleration, jerk (in this order,
    which is also the order of the summary's margins).

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
    return (
        ForceLimit(model=model),
        SpeedLimit(max_speed_mps=vehicle.max_speed_mps),
        AccelLimit(max_accel_mps2=vehicle.max_accel_mps2, max_decel_mps2=vehicle.max_decel_mps2),
        JerkLimit(max_jerk_mps3=max_jerk_mps3),
    )
