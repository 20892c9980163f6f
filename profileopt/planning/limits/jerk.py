"""The jerk bound at the interior segment boundaries.

Between two segments of constant acceleration the acceleration changes at the boundary;
the planner bounds jerk = v da/ds there (:func:`profileopt.core.kinematics.boundary_jerk_mps3`),
a nonlinear row of the NLP.
"""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING

import numpy as np

from ...core.kinematics import boundary_jerk_mps3, segment_accel_mps2
from .base import Limit, PlanContext, worst_ratio

if TYPE_CHECKING:
    from ...core.profile import Profile

__all__ = ["JerkLimit"]


@dataclasses.dataclass(frozen=True)
class JerkLimit(Limit):
    """|v da/ds| <= max_jerk_mps3 at every interior boundary.

    Attributes
    ----------
    max_jerk_mps3 : float
        Jerk bound (m/s^3), > 0; inf turns it off.
    """

    max_jerk_mps3: float
    name = "jerk"
    binding = "jerk"

    def jerk_bound_mps3(self, context: PlanContext) -> float:
        """The bound (m/s^3).

        Parameters
        ----------
        context : PlanContext
            The route, vehicle and segments of the plan.

        Returns
        -------
        float
        """
        return self.max_jerk_mps3

    def violation(self, context: PlanContext, b: np.ndarray) -> float:
        """Largest |jerk| beyond the bound, over the bound.

        Parameters
        ----------
        context : PlanContext
            The route, vehicle and segments of the plan.
        b : numpy.ndarray, shape (N+1,)
            Squared speeds at the boundaries (m^2/s^2).

        Returns
        -------
        float
        """
        length = context.segments.length_m
        if not math.isfinite(self.max_jerk_mps3) or length.size < 2:
            return 0.0
        a = segment_accel_mps2(b[:-1], b[1:], length)
        j = boundary_jerk_mps3(np.sqrt(np.maximum(b[1:-1], 0.0)), a[:-1], a[1:], length[:-1], length[1:])
        return float(max(np.max(np.abs(j)) - self.max_jerk_mps3, 0.0)) / self.max_jerk_mps3

    def margins(self, profile: "Profile") -> dict[str, dict]:
        """The largest |jerk| over the bound, and where.

        Parameters
        ----------
        profile : Profile
            A planned profile.

        Returns
        -------
        dict
            ``{"jerk": {...}}``.
        """
        return {"jerk": worst_ratio(np.abs(profile.jerk_mps3()), self.max_jerk_mps3, profile.s_m[1:-1])}
