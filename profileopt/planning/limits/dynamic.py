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

from .base import Limit
from .force import ForceLimit

__all__ = ["DynamicForceLimit"]


@dataclasses.dataclass(frozen=True)
class DynamicForceLimit(Limit):
    """The simulated transmitted force within the vehicle's limit (model ``dynamic``)."""

    name = "force"
    binding = "force"

    #: The largest force in the ``force_n`` column over its limit, and where: the column holds
    #: the simulated peaks here, the predicted ones for :class:`~.force.ForceLimit`.
    margins = ForceLimit.margins
