"""The friction circle: the tyres' longitudinal and lateral force within mu times the normal force.

(a + g sin theta)^2 + (v^2 kappa)^2 <= (mu g cos theta)^2 (:func:`profileopt.physics.motion.friction_usage`).
It couples the speed (through the lateral part) with the acceleration, so in general it is
a row of the NLP: in each segment at both ends (the lateral part grows with the speed) and
at both extremes of the segment's grade (the usage is a convex quadratic in sin theta, so
its largest value over the segment's grades is at one of them), with the segment's
largest |kappa|: four rows (:data:`profileopt.physics.rows.ROW_FAMILIES`, ``friction``).

Two consequences hold on their own and enter the exact forward-backward pass: a speed cap
v^2 kappa <= mu g cos theta (no acceleration at all) and the acceleration bounds
|a + g sin theta| <= mu g cos theta (no turn). Where the caps and bounds of every limit
already keep the usage within the circle (the largest drive or braking force with the
largest lateral acceleration), a segment needs no rows; where no segment needs them the plan
stays exact.
"""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING

import numpy as np

from ...core.path import SegmentPath
from ...physics.motion import (
    lateral_speed_cap_mps,
    segment_friction_radius_mps2,
    tyre_accel_mps2,
)
from ...physics.rows import friction_data, friction_rows_needed
from .base import PlanContext, RowLimit, worst_ratio

if TYPE_CHECKING:
    from ...core.profile import Profile

__all__ = ["FrictionLimit"]


@dataclasses.dataclass(frozen=True)
class FrictionLimit(RowLimit):
    """The friction circle at every speed, curvature and grade of every segment.

    Attributes
    ----------
    friction_coefficient : float
        mu (-).
    """

    friction_coefficient: float
    name = "friction"
    binding = "friction"
    family = "friction"

    def _radius(self, context: PlanContext) -> np.ndarray:
        """The smallest friction circle of each segment, mu g cos(max |theta|) (m/s^2), (N,)."""
        path = context.turns_and_slopes
        return segment_friction_radius_mps2(self.friction_coefficient, path.grade_lo_rad, path.grade_hi_rad)

    def speed_cap_mps(self, context: PlanContext) -> np.ndarray:
        """sqrt(mu g cos theta / kappa_max) per segment (m/s): all the grip used sideways.

        Parameters
        ----------
        context : PlanContext
            The route, vehicle and segments of the plan.

        Returns
        -------
        numpy.ndarray, shape (N,)
        """
        return lateral_speed_cap_mps(self._radius(context), context.turns_and_slopes.curvature_max_1pm)

    def accel_bounds_mps2(self, context: PlanContext) -> tuple[np.ndarray, np.ndarray]:
        """All the grip used along the path: -mu g cos theta <= a + g sin theta <= mu g cos theta
        at every grade of the segment (m/s^2).

        Parameters
        ----------
        context : PlanContext
            The route, vehicle and segments of the plan.

        Returns
        -------
        (decel_mps2, accel_mps2) : tuple of numpy.ndarray, shape (N,)
        """
        path = context.turns_and_slopes
        radius = self._radius(context)
        return tyre_accel_mps2(radius, path.grade_lo_rad), -tyre_accel_mps2(-radius, path.grade_hi_rad)

    def row_data(self, path: SegmentPath) -> np.ndarray:
        """Each segment's largest |curvature|, its grade range and mu, shape (N, 4).

        Parameters
        ----------
        path : SegmentPath
            Each segment's turns and slopes.

        Returns
        -------
        numpy.ndarray
        """
        return friction_data(path, self.friction_coefficient)

    def _needs_rows(self, context: PlanContext, cap_mps: np.ndarray, decel_mps2: np.ndarray,
                    accel_mps2: np.ndarray) -> np.ndarray:
        """Segments where the caps and bounds do not keep the usage within the circle, (N,)."""
        return friction_rows_needed(context.turns_and_slopes, self.friction_coefficient, cap_mps, decel_mps2,
                                    accel_mps2)

    def nlp_rows(self, context: PlanContext, cap_mps: np.ndarray, decel_mps2: np.ndarray,
                 accel_mps2: np.ndarray) -> tuple[str, np.ndarray] | None:
        """The ``friction`` rows, or None where no segment needs them.

        Parameters
        ----------
        context : PlanContext
            The route, vehicle and segments of the plan.
        cap_mps : numpy.ndarray, shape (N,)
            The lowest cap of each segment (m/s).
        decel_mps2, accel_mps2 : numpy.ndarray, shape (N,)
            The tightest acceleration bounds of each segment (m/s^2).

        Returns
        -------
        ("friction", data) or None
        """
        if not np.any(self._needs_rows(context, cap_mps, decel_mps2, accel_mps2)):
            return None
        return "friction", self.row_data(context.turns_and_slopes)

    def inner_bounds(self, context: PlanContext, cap_mps: np.ndarray, decel_mps2: np.ndarray,
                     accel_mps2: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        """Half the circle's square each way where rows are needed: v^2 kappa <= r / sqrt 2
        and |a + g sin theta| <= r / sqrt 2 give a usage of at most 1/2 + 1/2 = 1.

        Parameters
        ----------
        context : PlanContext
            The route, vehicle and segments of the plan.
        cap_mps : numpy.ndarray, shape (N,)
            The caps (m/s).
        decel_mps2, accel_mps2 : numpy.ndarray, shape (N,)
            The acceleration bounds (m/s^2).

        Returns
        -------
        (cap_mps, decel_mps2, accel_mps2) or None
        """
        need = self._needs_rows(context, cap_mps, decel_mps2, accel_mps2)
        if not np.any(need):
            return None
        path = context.turns_and_slopes
        share = self._radius(context) / math.sqrt(2.0)
        cap = np.where(need, np.minimum(cap_mps, lateral_speed_cap_mps(share, path.curvature_max_1pm)), cap_mps)
        decel = np.where(need, np.minimum(decel_mps2, tyre_accel_mps2(share, path.grade_lo_rad)), decel_mps2)
        accel = np.where(need, np.minimum(accel_mps2, -tyre_accel_mps2(-share, path.grade_hi_rad)), accel_mps2)
        return cap, decel, accel

    def margins(self, profile: "Profile") -> dict[str, dict]:
        """The largest share of the friction circle used (the tyre force over mu times the
        normal force, the square root of the usage), and where.

        Parameters
        ----------
        profile : Profile
            A planned profile.

        Returns
        -------
        dict
            ``{"friction": {...}}``.
        """
        return {"friction": worst_ratio(np.sqrt(np.maximum(self.row_values(profile), 0.0)), 1.0, profile.s_m[:-1])}
