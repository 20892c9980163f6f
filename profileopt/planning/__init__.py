"""Planning: the fastest speed profile along a route that keeps every limit.

Data flows route -> :mod:`.segments` (segments and their roughness) -> :mod:`.limits`
(what each kind of limit allows) -> :mod:`.bands` (one band per segment, exact
forward-backward profile) -> :mod:`.solve` (the NLP of :mod:`.nlp`, solved by
:mod:`.banded_ipm` or IPOPT, with IPOPT in :mod:`.pieces` on long routes) or
:mod:`.fallback` -> :mod:`.result` (the :class:`Profile`). :mod:`.planner` holds the
orchestration (:func:`plan`); :mod:`.options` the solver's tuning values.
"""

from __future__ import annotations

import warnings

from .bands import BandChoice, choose_bands, greatest_profile
from .limits import AccelLimit, ForceLimit, JerkLimit, Limit, PlanContext, SpeedLimit, default_limits
from .options import SolverOptions
from .planner import DEFAULT_SMOOTHING, PLAN_BANDS, plan
from .result import PROFILE_COLUMNS, Profile
from .segments import DEFAULT_SEGMENT_LENGTH_M, MIN_SAMPLES_PER_SEGMENT, Segments, route_roughness_windows, segment_route

__all__ = [
    "plan", "Profile", "PROFILE_COLUMNS", "SolverOptions", "DEFAULT_SMOOTHING", "PLAN_BANDS",
    "Segments", "segment_route", "route_roughness_windows", "MIN_SAMPLES_PER_SEGMENT", "DEFAULT_SEGMENT_LENGTH_M",
    "BandChoice", "choose_bands", "greatest_profile",
    "Limit", "PlanContext", "ForceLimit", "SpeedLimit", "AccelLimit", "JerkLimit", "default_limits",
    "summarize",
]


def summarize(profile: Profile) -> dict:
    """Deprecated: use :meth:`Profile.summary`.

    Parameters
    ----------
    profile : Profile
        A planned profile.

    Returns
    -------
    dict
    """
    warnings.warn("profileopt.summarize(profile) is deprecated; use profile.summary()", DeprecationWarning,
                  stacklevel=2)
    return profile.summary()
