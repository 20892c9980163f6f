"""profileopt: terrain-force-limited, minimum-time speed profiles for ground vehicles.

The force models of Wilson et al. (University of Calgary) written once in CasADi, a
roughness index from elevation data, allowable speeds, a route-level minimum-time speed
planner solved with IPOPT, and a quarter-car simulation that checks every plan.

    >>> import profileopt
    >>> route = profileopt.read_route("examples/routes/trail.csv")  # doctest: +SKIP
    >>> profile = profileopt.plan(route, profileopt.load_vehicle("atv"))  # doctest: +SKIP
"""

import importlib
from typing import Any

from .errors import InfeasibleError, InputError, PlanningError

# Everything else is imported when first used (PEP 562), so that ``profileopt --help`` and
# commands that need neither CasADi nor SciPy start in a fraction of a second: name -> module.
_LAZY = {
    "MODELS": "forces", "force_n": "forces", "get_model": "forces",
    "SpeedBands": "speeds", "allowable_speed": "speeds", "speed_bands": "speeds",
    "roughness_index": "terrain", "step_width": "terrain", "worst_case_elevation": "terrain",
    "Vehicle": "vehicle", "bundled_vehicles": "vehicle", "load_vehicle": "vehicle",
    "Route": "route",
    "read_profile": "io", "read_route": "io",
    "Profile": "planning", "SolverOptions": "planning", "plan": "planning", "summarize": "planning",
    "QuarterCarRun": "simulate", "simulate_quarter_car": "simulate",
    "wheel_envelope_m": "wheel",
    "Verification": "verification", "verify": "verification",
    "plot_verification": "plots",
    "ModelRun": "study", "SafetyStudy": "safety", "compare_models": "study", "safety_study": "safety",
}


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        value = getattr(importlib.import_module(f".{_LAZY[name]}", __name__), name)
        globals()[name] = value  # once imported, a plain attribute
        return value
    raise AttributeError(f"module 'profileopt' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))


__all__ = [
    "InputError",
    "InfeasibleError",
    "MODELS",
    "force_n",
    "get_model",
    "SpeedBands",
    "allowable_speed",
    "speed_bands",
    "roughness_index",
    "step_width",
    "worst_case_elevation",
    "Vehicle",
    "bundled_vehicles",
    "load_vehicle",
    "Route",
    "read_route",
    "PlanningError",
    "Profile",
    "SolverOptions",
    "plan",
    "read_profile",
    "summarize",
    "QuarterCarRun",
    "simulate_quarter_car",
    "wheel_envelope_m",
    "Verification",
    "plot_verification",
    "verify",
    "ModelRun",
    "SafetyStudy",
    "compare_models",
    "safety_study",
]

__version__ = "0.1.0"
