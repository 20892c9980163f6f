"""Planning: the fastest speed profile along a route that keeps every limit.

Data flows route -> :mod:`profileopt.core.segments` (segments and their roughness) ->
:mod:`.limits` (what each kind of limit allows, one module each) -> :mod:`.bands` (one band
per segment, exact forward-backward profile) -> :mod:`.nlp` (the NLP, solved by IPOPT or an
opt-in back end, FATROP or the banded interior point) or :mod:`.fallback` -> a
:class:`profileopt.core.profile.Profile`; :mod:`.refine` cuts segments where the first
profile meets a cap. :mod:`.planner` holds the orchestration (:func:`plan`);
:mod:`.options` the solver's tuning values.
"""

from __future__ import annotations

from .bands import BandChoice, choose_bands, greatest_profile
from .limits import (
    AccelLimit,
    ForceLimit,
    JerkLimit,
    Limit,
    PlanContext,
    SpeedLimit,
    default_limits,
)
from .options import SolverOptions
from .planner import DEFAULT_SMOOTHING, PLAN_BANDS, plan

__all__ = [
    "plan", "SolverOptions", "DEFAULT_SMOOTHING", "PLAN_BANDS",
    "BandChoice", "choose_bands", "greatest_profile",
    "Limit", "PlanContext", "ForceLimit", "SpeedLimit", "AccelLimit", "JerkLimit", "default_limits",
]
