"""The step limit of SBEM:TF: steps met and drops landed, where Eq. (13) falls short.

Eq. (13) is the steady response to a smooth quarter sine. A rigid wheel meeting a step, or
landing after a drop, runs a steep ramp of its path that starts or ends in a kink
(:func:`profileopt.physics.steps.wheel_ramps`), too fast for the body to follow; the force on it is
bounded by :func:`profileopt.physics.steps.ramp_force_n`, which rises with speed. Every segment that
shares a point with a ramp is capped at the speed where that bound meets the vehicle's
``max_transmitted_force_n`` (:func:`profileopt.physics.steps.step_caps`, which builds the
wheel's path only where a cap can bind); where a plan meets that cap, refining cuts the
segment just outside the ramp (:meth:`StepLimit.cap_stretches_m`), so the cap holds metres
around a step, not the whole segment.
"""

from __future__ import annotations

import dataclasses
import weakref
from typing import TYPE_CHECKING

import numpy as np

from ...physics.steps import StepCaps, segment_step_caps_mps, step_caps
from .base import Limit, PlanContext, own_cap_excess

if TYPE_CHECKING:
    from ...core.profile import Profile

__all__ = ["StepLimit"]


@dataclasses.dataclass(frozen=True)
class StepLimit(Limit):
    """Steps met and drops landed by the rigid wheel: SBEM:TF's transmitted force on them.

    Part of every plan with the ``sbem_tf`` model (:func:`profileopt.planning.limits.default_limits`).
    """

    name = "step"
    binding = "step"
    #: The route's caps, kept for the next call on the same route and vehicle (a refined plan
    #: asks twice, on the segments asked for and on the refined ones): (route ref, vehicle, caps).
    _last: list = dataclasses.field(default_factory=list, init=False, repr=False, compare=False)

    def speed_cap_mps(self, context: PlanContext) -> np.ndarray:
        """:func:`profileopt.physics.steps.step_speed_cap_mps` of the plan's route and segments (m/s), shape (N,).

        Parameters
        ----------
        context : PlanContext
            The route, vehicle and segments of the plan.

        Returns
        -------
        numpy.ndarray
        """
        return segment_step_caps_mps(self._caps(context), context.segments.boundaries_m)

    def cap_stretches_m(self, context: PlanContext) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The ramps whose cap lies below the top speed: where each starts and ends (m), and
        its cap (m/s).

        Parameters
        ----------
        context : PlanContext
            The route, vehicle and segments of the plan.

        Returns
        -------
        (start_m, end_m, cap_mps) : tuple of numpy.ndarray, shape (R,)
        """
        caps = self._caps(context)
        return caps.start_m, caps.end_m, caps.cap_mps

    def _caps(self, context: PlanContext) -> StepCaps:
        """The route's :func:`step_caps`, found once per route and vehicle."""
        route, vehicle = context.route, context.vehicle
        if not (self._last and self._last[0]() is route and self._last[1] is vehicle):
            self._last[:] = [weakref.ref(route), vehicle, step_caps(route.s_m, route.z_m, vehicle)]
        return self._last[2]

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
