"""Acceleration and deceleration bounds along the path.

Inside a segment the acceleration is constant, a = (b_{i+1} - b_i) / (2 ds) in the squared
speed b = v^2, so the bounds are linear rows of the NLP and slopes of the exact
forward-backward pass.
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING

import numpy as np

from ...kinematics import segment_accel_mps2
from .base import Limit, PlanContext, worst_ratio

if TYPE_CHECKING:
    from ..result import Profile

__all__ = ["AccelLimit"]


@dataclasses.dataclass(frozen=True)
class AccelLimit(Limit):
    """-max_decel_mps2 <= a <= max_accel_mps2 in every segment.

    Attributes
    ----------
    max_accel_mps2 : float
        Largest acceleration (m/s^2), > 0.
    max_decel_mps2 : float
        Largest deceleration (m/s^2, a positive number).
    """

    max_accel_mps2: float
    max_decel_mps2: float
    name = "accel"

    def accel_bounds_mps2(self, context: PlanContext) -> tuple[np.ndarray, np.ndarray]:
        """The same bounds for every segment (m/s^2).

        Parameters
        ----------
        context : PlanContext
            The route, vehicle and segments of the plan.

        Returns
        -------
        (decel_mps2, accel_mps2) : tuple of numpy.ndarray, shape (N,)
        """
        n = context.segments.count
        return np.full(n, self.max_decel_mps2), np.full(n, self.max_accel_mps2)

    def violation(self, context: PlanContext, b: np.ndarray) -> float:
        """Largest acceleration or deceleration beyond its bound, over max_accel_mps2.

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
        a = segment_accel_mps2(b[:-1], b[1:], context.segments.length_m)
        over = max(np.max(a - self.max_accel_mps2), np.max(-self.max_decel_mps2 - a), 0.0)
        return float(over) / self.max_accel_mps2

    def margins(self, profile: "Profile") -> dict[str, dict]:
        """The largest acceleration and deceleration over their bounds, and where.

        Parameters
        ----------
        profile : Profile
            A planned profile.

        Returns
        -------
        dict
            ``{"accel": {...}, "decel": {...}}``.
        """
        accel = profile.accel_mps2[:-1]
        where = profile.s_m[:-1]
        return {"accel": worst_ratio(accel, self.max_accel_mps2, where),
                "decel": worst_ratio(-accel, self.max_decel_mps2, where)}
