"""The step limit of SBEM:TF: steps met and drops landed, where Eq. (13) falls short.

Eq. (13) is the steady response to a smooth quarter sine. A rigid wheel meeting a step, or
landing after a drop, runs a steep ramp of its path that starts or ends in a kink
(:func:`profileopt.ramps.wheel_ramps`), too fast for the body to follow; the force on it is
bounded by :func:`profileopt.ramp_force.ramp_force_n`, which rises with speed. Every segment that
shares a point with a ramp is capped at the speed where that bound meets the vehicle's
``max_transmitted_force_n`` (:func:`profileopt.ramp_force.ramp_speed_cap_mps`).

The wheel's path is built only around slopes of the route that could need a cap: the bound is
at most V s (k phi_max + c), and the path's slopes never exceed the route's (its pieces are
the route's lines, offset, and arcs between them), so a ramp can cap a speed the vehicle can
drive only next to a slope above F / (V_top (k phi_max + c)); on a route without one no path
is built at all.
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING

import numpy as np

from ...ramp_force import impulse_response_peak_s, ramp_speed_cap_mps
from ...ramps import wheel_ramps
from ...wheel_path import wheel_path
from .base import Limit, PlanContext

if TYPE_CHECKING:
    from ...vehicle import Vehicle
    from ..result import Profile

__all__ = ["StepLimit", "step_speed_cap_mps", "MAX_STRETCHES"]

#: Above this many steep stretches the wheel's path is built over the whole route at once.
MAX_STRETCHES = 16


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
    for lo, hi in _steep_stretches(s_m, z_m, vehicle):
        ramps = wheel_ramps(wheel_path(s_m[lo:hi], z_m[lo:hi], vehicle.wheel_radius_m))
        ramp_cap = ramp_speed_cap_mps(ramps.rise_m, ramps.slope, vehicle, vehicle.max_transmitted_force_n)
        binds = np.flatnonzero(ramp_cap < vehicle.max_speed_mps)
        # segment i covers [b_i, b_i+1]; it meets [start, end] when b_i <= end and b_i+1 >= start
        first = np.searchsorted(boundaries_m[1:], ramps.start_m[binds], side="left")
        stop = np.searchsorted(boundaries_m[:-1], ramps.end_m[binds], side="right")
        for j, a, b in zip(binds, first, stop):
            np.minimum(cap[a:b], float(ramp_cap[j]), out=cap[a:b])
    return cap


def _steep_stretches(s_m: np.ndarray, z_m: np.ndarray, vehicle: "Vehicle") -> list[tuple[int, int]]:
    """Sample ranges [lo, hi) whose wheel path holds every ramp that could cap a speed.

    Only a slope above F / (V_top (k phi_max + c)) can (module docstring). A ramp runs from
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
