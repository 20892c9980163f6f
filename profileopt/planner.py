"""Deprecated module: the planner is the package :mod:`profileopt.planning` now.

``from profileopt.planner import plan`` keeps working for one release, with a
``DeprecationWarning`` naming the new place of each name.
"""

from __future__ import annotations

import warnings

_MOVED = {
    "plan": "profileopt.planning", "Profile": "profileopt.planning", "PROFILE_COLUMNS": "profileopt.planning",
    "DEFAULT_SMOOTHING": "profileopt.planning", "Segments": "profileopt.planning",
    "segment_route": "profileopt.planning", "MIN_SAMPLES_PER_SEGMENT": "profileopt.planning",
    "BandChoice": "profileopt.planning", "choose_bands": "profileopt.planning",
    "greatest_profile": "profileopt.planning", "summarize": "profileopt.planning",
    "read_profile": "profileopt.io", "PlanningError": "profileopt.errors",
}


def __getattr__(name: str) -> object:
    if name not in _MOVED:
        raise AttributeError(f"module 'profileopt.planner' has no attribute {name!r}")
    import importlib

    where = _MOVED[name]
    warnings.warn(f"profileopt.planner.{name} is deprecated; use {where}.{name}", DeprecationWarning, stacklevel=2)
    return getattr(importlib.import_module(where), name)
