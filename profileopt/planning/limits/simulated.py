"""Caps learned from the exact simulation: where the planner's gate found the force over the limit.

The force models and the step limit bound the force from the terrain's statistics and from
single ramps met at rest; on short blocks, pits and rows of them the quarter car can still
respond more than they allow. The planner drives every plan in the exact simulation before
returning it (:mod:`profileopt.planning.gate`) and, where the force it limits goes over,
caps the speed over the stretch of route that caused it: a :class:`SimulatedLimit` holding
those stretches and caps, which the next round of planning keeps like any other cap.
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING

import numpy as np

from ...physics.steps import StepCaps, segment_step_caps_mps
from .base import Limit, PlanContext, own_cap_excess

if TYPE_CHECKING:
    from ...core.profile import Profile

__all__ = ["SimulatedLimit"]


@dataclasses.dataclass(frozen=True)
class SimulatedLimit(Limit):
    """Speed caps over stretches of the route where the exact simulation went over the limit.

    Made by the planner's gate (:func:`profileopt.planning.gate.gate_caps`), not by a user.

    Attributes
    ----------
    caps : StepCaps
        The stretches (``start_m``, ``end_m``, m) and their caps (``cap_mps``, m/s); a
        segment that shares a point with a stretch is held to its cap.
    """

    caps: StepCaps
    name = "simulated"
    binding = "simulated"

    def speed_cap_mps(self, context: PlanContext) -> np.ndarray:
        """The lowest cap of the stretches each segment shares a point with (m/s), inf where none.

        Parameters
        ----------
        context : PlanContext
            The route, vehicle and segments of the plan.

        Returns
        -------
        numpy.ndarray, shape (N,)
        """
        return segment_step_caps_mps(self.caps, context.segments.boundaries_m)

    def cap_stretches_m(self, context: PlanContext) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The stretches and their caps, so that refining cuts segments just outside them.

        Parameters
        ----------
        context : PlanContext
            The route, vehicle and segments of the plan.

        Returns
        -------
        (start_m, end_m, cap_mps) : tuple of numpy.ndarray, shape (R,)
        """
        return self.caps.start_m, self.caps.end_m, self.caps.cap_mps

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
        return own_cap_excess(self, profile)

    def cap_reason(self, profile: "Profile", segment: int) -> str:
        """"the exact simulation of the quarter car went over the force limit here at a higher speed".

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
        return (f"the exact simulation of the quarter car went over the force limit here at a higher speed "
                f"({profile.speed_cap_mps[segment]:.3g} m/s, the planner's simulation gate)")
