"""The force limit of the ``dynamic`` model: the quarter car's own simulated response.

Where the paper's models bound the force from the RI of each roughness window, the
``dynamic`` model holds the transmitted force that the exact simulation of the quarter car
on the route's own samples gives (:func:`profileopt.physics.simulate.simulate_quarter_car`,
the one ``verify`` judges by) within ``max_transmitted_force_n``. It has no speed bands: the
planner imposes it by simulating each plan and capping the speed where it goes over
(:mod:`profileopt.planning.dynamic`). After that, the profile's ``force_n`` holds each
segment's largest simulated |F_T|, which this limit reports as the force margin.
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING

import numpy as np

from .base import Limit

if TYPE_CHECKING:
    from ...core.profile import Profile

__all__ = ["DynamicForceLimit"]


@dataclasses.dataclass(frozen=True)
class DynamicForceLimit(Limit):
    """The simulated transmitted force within the vehicle's limit (model ``dynamic``)."""

    name = "force"
    binding = "force"

    def margins(self, profile: "Profile") -> dict[str, dict]:
        """The largest simulated force over its limit, and where.

        Parameters
        ----------
        profile : Profile
            A planned profile whose ``force_n`` holds each segment's largest simulated |F_T| (N).

        Returns
        -------
        dict
            ``{"force": {"ratio": float, "s_m": float}}``.
        """
        ratio = profile.force_n[:-1] / profile.force_limit_n[:-1]
        k = int(np.argmax(ratio))
        return {"force": {"ratio": float(ratio[k]), "s_m": float(profile.s_m[k])}}
