"""The step limit of SBEM:TF: steps met and drops landed, where Eq. (13) falls short.

Eq. (13) is the steady response to a smooth quarter sine. A rigid wheel meeting a step, or
landing after a drop, runs a steep ramp of its path that starts or ends in a kink
(:func:`profileopt.ramps.wheel_ramps`), too fast for the body to follow; the force on it is
bounded by :func:`profileopt.forces.ramp_force_n`, which rises with speed. Every segment that
shares a point with a ramp is capped at the speed where that bound meets the vehicle's
``max_transmitted_force_n`` (:func:`profileopt.forces.ramp_speed_cap_mps`).

The wheel's path is built only when some slope of the route could need a cap: the bound is
at most V s (k phi_max + c), and the path's slopes never exceed the route's (its pieces are
the route's lines, offset, and arcs between them), so a route whose every slope is below
F / (V_top (k phi_max + c)) has no ramp that caps a speed the vehicle can drive.
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING

import numpy as np

from ...forces import impulse_response_peak_s, ramp_speed_cap_mps
from ...ramps import wheel_ramps
from ...wheel_path import wheel_path
from .base import Limit, PlanContext

if TYPE_CHECKING:
    from ...vehicle import Vehicle
    from ..result import Profile

__all__ = ["StepLimit", "step_speed_cap_mps"]


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
    n = boundaries_m.size - 1
    cap = np.full(n, np.inf)
    limit = vehicle.max_transmitted_force_n
    gentlest = limit / (vehicle.max_speed_mps * (vehicle.spring_n_per_m * impulse_response_peak_s(vehicle)
                                                 + vehicle.damping_ns_per_m))
    if s_m.size < 2 or not np.any(np.abs(np.diff(z_m)) > gentlest * np.diff(s_m)):
        return cap
    ramps = wheel_ramps(wheel_path(s_m, z_m, vehicle.wheel_radius_m))
    ramp_cap = ramp_speed_cap_mps(ramps.rise_m, ramps.slope, vehicle, limit)
    binds = np.flatnonzero(ramp_cap < vehicle.max_speed_mps)
    # segment i covers [b_i, b_i+1]; it shares a point with [start, end] when b_i <= end and b_i+1 >= start
    first = np.searchsorted(boundaries_m[1:], ramps.start_m[binds], side="left")
    stop = np.searchsorted(boundaries_m[:-1], ramps.end_m[binds], side="right")
    for j, a, b in zip(binds, first, stop):
        np.minimum(cap[a:b], max(float(ramp_cap[j]), 0.0), out=cap[a:b])
    return cap


@dataclasses.dataclass(frozen=True)
class StepLimit(Limit):
    """Steps met and drops landed by the rigid wheel: SBEM:TF's transmitted force on them.

    Part of every plan with the ``sbem_tf`` model (:func:`profileopt.planning.limits.default_limits`).
    """

    name = "step"
    binding = "step"

    def speed_cap_mps(self, context: PlanContext) -> np.ndarray:
        """:func:`step_speed_cap_mps` of the plan's route and segments (m/s), shape (N,).

        Parameters
        ----------
        context : PlanContext
            The route, vehicle and segments of the plan.

        Returns
        -------
        numpy.ndarray
        """
        route = context.route
        return step_speed_cap_mps(route.s_m, route.z_m, context.segments.boundaries_m, context.vehicle)

    def check(self, profile: "Profile") -> float:
        """How far a speed in a segment this limit caps exceeds the cap (relative).

        Parameters
        ----------
        profile : Profile
            The profile about to be returned.

        Returns
        -------
        float
        """
        mine = [k for k, limit in enumerate(profile.limits) if limit is self]
        if not mine or profile.cap_source is None:
            return 0.0
        where = np.flatnonzero(profile.cap_source == mine[0])
        if where.size == 0:
            return 0.0
        top = np.maximum(profile.speed_mps[where], profile.speed_mps[where + 1])
        return max(float(np.max(top / profile.speed_cap_mps[where])) - 1.0, 0.0)

    def cap_reason(self, profile: "Profile", segment: int) -> str:
        """"a step or drop of the ground (the wheel's path runs a steep ramp from a kink)".

        Parameters
        ----------
        profile : Profile
            A planned profile.
        segment : int
            Index of the segment.

        Returns
        -------
        str
        """
        return (f"a step or drop of the ground, where the wheel meets a steep ramp suddenly "
                f"({profile.speed_cap_mps[segment]:.3g} m/s, the step limit)")
