"""Acceleration and deceleration bounds along the path, on the level and on grades.

The vehicle's ``max_accel_mps2`` and ``max_decel_mps2`` bound the force the drive and the
brakes put on the ground per unit mass, F / m = a + g sin(theta)
(:func:`profileopt.physics.motion.tyre_accel_mps2`). Along the path, then,
-max_decel - g sin(theta) <= a <= max_accel - g sin(theta): a climb takes acceleration
away, a descent braking. Over a segment whose grade ranges over [theta_lo, theta_hi] the
bounds that hold for every grade of it are a <= max_accel - g sin(theta_hi) and
a >= -max_decel - g sin(theta_lo). Either may change sign: a climb steeper than the drive
can hold must be entered fast enough to carry over it, a descent steeper than the brakes
can hold slowly enough.

Inside a segment the acceleration is constant, a = (b_{i+1} - b_i) / (2 ds) in the squared
speed b = v^2, so the bounds are linear rows of the NLP and slopes of the exact
forward-backward pass.
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING

import numpy as np

from ...core.kinematics import segment_accel_mps2
from ...physics.motion import tyre_accel_mps2
from .base import Limit, PlanContext, worst_ratio

if TYPE_CHECKING:
    from ...core.profile import Profile

__all__ = ["AccelLimit"]


@dataclasses.dataclass(frozen=True)
class AccelLimit(Limit):
    """-max_decel_mps2 <= a + g sin(theta) <= max_accel_mps2 at every grade of every segment.

    Attributes
    ----------
    max_accel_mps2 : float
        Largest acceleration (m/s^2), > 0.
    max_decel_mps2 : float
        Largest deceleration (m/s^2, a positive number).
    grade : bool, default True
        Whether the grade enters the bounds; off, they bound a itself (on the level, the
        same), as before turns and hills (:func:`~profileopt.planning.limits.default_limits`
        turns it on for a vehicle that gives any key of turns and hills).
    """

    max_accel_mps2: float
    max_decel_mps2: float
    grade: bool = True
    name = "accel"
    binding = "accel"

    def accel_bounds_mps2(self, context: PlanContext) -> tuple[np.ndarray, np.ndarray]:
        """The bounds of each segment along the path at its grades (m/s^2).

        Parameters
        ----------
        context : PlanContext
            The route, vehicle and segments of the plan.

        Returns
        -------
        (decel_mps2, accel_mps2) : tuple of numpy.ndarray, shape (N,)
            max_decel + g sin(theta_lo) and max_accel - g sin(theta_hi); either may be
            negative on a steep grade.
        """
        n = context.segments.count
        if not self.grade:
            return np.full(n, self.max_decel_mps2), np.full(n, self.max_accel_mps2)
        path = context.turns_and_slopes
        decel = tyre_accel_mps2(self.max_decel_mps2, path.grade_lo_rad)
        accel = -tyre_accel_mps2(-self.max_accel_mps2, path.grade_hi_rad)
        return decel, accel

    def violation(self, context: PlanContext, b: np.ndarray) -> float:
        """Largest acceleration or deceleration beyond its bound at the segment's grades,
        over max_accel_mps2.

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
        decel, accel = self.accel_bounds_mps2(context)
        over = max(np.max(a - accel), np.max(-decel - a), 0.0)
        return float(over) / self.max_accel_mps2

    def _tyre(self, profile: "Profile") -> tuple[np.ndarray, np.ndarray]:
        """Each segment's largest drive and braking force per unit mass (m/s^2), (N,) each."""
        accel = profile.accel_mps2[:-1]
        path = profile.path if self.grade else None
        drive = accel if path is None else tyre_accel_mps2(accel, path.grade_hi_rad)
        brake = -(accel if path is None else tyre_accel_mps2(accel, path.grade_lo_rad))
        return drive, brake

    def check(self, profile: "Profile") -> float:
        """How far the drive or braking force per unit mass of any segment exceeds its bound,
        over max_accel_mps2 (0 if none).

        Parameters
        ----------
        profile : Profile
            The profile about to be returned.

        Returns
        -------
        float
        """
        drive, brake = self._tyre(profile)
        over = max(float(np.max(drive - self.max_accel_mps2)), float(np.max(brake - self.max_decel_mps2)), 0.0)
        return over / self.max_accel_mps2

    def margins(self, profile: "Profile") -> dict[str, dict]:
        """The largest drive and braking force per unit mass, a + g sin(theta) at the
        segment's steepest grade either way, over their bounds, and where.

        Parameters
        ----------
        profile : Profile
            A planned profile.

        Returns
        -------
        dict
            ``{"accel": {...}, "decel": {...}}``.
        """
        where = profile.s_m[:-1]
        drive, brake = self._tyre(profile)
        return {"accel": worst_ratio(drive, self.max_accel_mps2, where),
                "decel": worst_ratio(brake, self.max_decel_mps2, where)}
