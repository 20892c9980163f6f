"""The drive power limit: m (a + g sin theta) v <= P at every speed and grade of a segment.

In a segment of constant acceleration the power is largest at its higher speed and its
steepest grade, so a <= P / (m max(v_i, v_{i+1})) - g sin(theta_hi)
(:func:`profileopt.physics.motion.power_accel_mps2`). The exact forward-backward pass keeps it
(:class:`~profileopt.planning.bands.DrivePower`); in the NLP it is two rows per segment
(:data:`profileopt.physics.rows.ROW_FAMILIES`, ``power``), needed only where a speed the
caps allow, at the acceleration the bounds allow, would need more than P.
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING

import numpy as np

from ...core.path import SegmentPath
from ...physics.rows import power_data, power_rows_needed
from ..bands import DrivePower
from .base import PlanContext, RowLimit, worst_ratio

if TYPE_CHECKING:
    from ...core.profile import Profile

__all__ = ["PowerLimit"]


@dataclasses.dataclass(frozen=True)
class PowerLimit(RowLimit):
    """m (a + g sin theta) v <= max_power_w in every segment.

    Attributes
    ----------
    mass_kg : float
        Mass of the whole vehicle (kg).
    max_power_w : float
        Largest drive power at the wheels (W).
    """

    mass_kg: float
    max_power_w: float
    name = "power"
    binding = "power"
    family = "power"

    def drive_power(self, context: PlanContext) -> DrivePower:
        """P / m and each segment's steepest grade, for the forward pass.

        Parameters
        ----------
        context : PlanContext
            The route, vehicle and segments of the plan.

        Returns
        -------
        DrivePower
        """
        return DrivePower(self.max_power_w / self.mass_kg, context.turns_and_slopes.grade_hi_rad)

    def row_data(self, path: SegmentPath) -> np.ndarray:
        """Each segment's steepest grade, the mass and the power, shape (N, 3).

        Parameters
        ----------
        path : SegmentPath
            Each segment's turns and slopes.

        Returns
        -------
        numpy.ndarray
        """
        return power_data(path, self.mass_kg, self.max_power_w)

    def nlp_rows(self, context: PlanContext, cap_mps: np.ndarray, decel_mps2: np.ndarray,
                 accel_mps2: np.ndarray) -> tuple[str, np.ndarray] | None:
        """The ``power`` rows, or None where no segment can reach the power limit: the
        fastest speed its caps allow times the most drive force per unit mass its bounds
        allow, (a_max + g sin theta_hi) v_cap, is within P / m everywhere.

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
        ("power", data) or None
        """
        if not power_rows_needed(context.turns_and_slopes, self.mass_kg, self.max_power_w, cap_mps, accel_mps2):
            return None
        return "power", self.row_data(context.turns_and_slopes)

    def margins(self, profile: "Profile") -> dict[str, dict]:
        """The largest drive power over P, and where.

        Parameters
        ----------
        profile : Profile
            A planned profile.

        Returns
        -------
        dict
            ``{"power": {...}}``.
        """
        return {"power": worst_ratio(self.row_values(profile), 1.0, profile.s_m[:-1])}
