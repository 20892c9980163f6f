"""Speed caps: the vehicle's top speed and the route's own ``speed_limit`` column.

A segment's cap is the smallest of the vehicle's ``max_speed_mps`` and the route's speed
limit at any of the segment's samples, so it holds for every speed driven inside it; where
a plan meets a speed limit, refining cuts the segment just outside the run of samples that
sets it (:meth:`SpeedLimit.cap_stretches_m`).
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING

import numpy as np

from .base import Limit, PlanContext

if TYPE_CHECKING:
    from ...core.profile import Profile

__all__ = ["SpeedLimit"]


@dataclasses.dataclass(frozen=True)
class SpeedLimit(Limit):
    """min(top speed, the route's speed_limit over each segment's samples).

    Attributes
    ----------
    max_speed_mps : float
        The vehicle's top speed (m/s).
    """

    max_speed_mps: float
    name = "speed cap"
    binding = "speed_limit"

    def cap_binding(self, context: PlanContext, cap_mps: np.ndarray) -> np.ndarray:
        """``top_speed`` where the cap is the vehicle's top speed, else ``speed_limit`` (the
        route's own), shape (N,).

        Parameters
        ----------
        context : PlanContext
            The route, vehicle and segments of the plan.
        cap_mps : numpy.ndarray, shape (N,)
            This limit's caps (m/s).

        Returns
        -------
        numpy.ndarray of str
        """
        return np.where(cap_mps >= self.max_speed_mps, "top_speed", "speed_limit").astype(object)

    def speed_cap_mps(self, context: PlanContext) -> np.ndarray:
        """The cap of each segment (m/s), shape (N,).

        Parameters
        ----------
        context : PlanContext
            The route, vehicle and segments of the plan.

        Returns
        -------
        numpy.ndarray
        """
        cap = np.full(context.segments.count, self.max_speed_mps)
        limit = context.route.speed_limit_mps
        if limit is not None:
            cap = np.minimum(cap, np.minimum.reduceat(limit, context.segments.first_sample))
        return cap

    def cap_stretches_m(self, context: PlanContext) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        """Each run of samples with one speed limit below the top speed: its first and last
        sample (m) and that limit (m/s); None without a ``speed_limit`` column.

        Parameters
        ----------
        context : PlanContext
            The route, vehicle and segments of the plan.

        Returns
        -------
        (start_m, end_m, cap_mps) : tuple of numpy.ndarray, shape (R,), or None
        """
        limit = context.route.speed_limit_mps
        if limit is None:
            return None
        s = context.route.s_m
        starts = np.concatenate([[0], np.flatnonzero(np.diff(limit) != 0) + 1])
        stops = np.append(starts[1:], limit.size) - 1
        low = limit[starts] < self.max_speed_mps
        return s[starts[low]], s[stops[low]], limit[starts[low]]

    def check(self, profile: "Profile") -> float:
        """How far the fastest speed of any segment exceeds its cap (relative).

        Parameters
        ----------
        profile : Profile
            The profile about to be returned.

        Returns
        -------
        float
        """
        if profile.speed_cap_mps is None:
            return 0.0
        top = np.maximum(profile.speed_mps[:-1], profile.speed_mps[1:])
        return max(float(np.max(top / profile.speed_cap_mps)) - 1.0, 0.0)

    def cap_reason(self, profile: "Profile", segment: int) -> str:
        """"the vehicle's top speed" or "the route's speed_limit (... m/s)".

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
        cap = float(profile.speed_cap_mps[segment])
        tol = 1e-6 * max(float(profile.speed_mps.max()), 1.0)
        if cap >= self.max_speed_mps - tol:
            return "the vehicle's top speed"
        return f"the route's speed_limit ({cap:.3g} m/s)"
