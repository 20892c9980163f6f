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
    "MODELS": "physics.forces", "force_n": "physics.forces", "get_model": "physics.forces",
    "SpeedBands": "physics.speeds", "allowable_speed": "physics.speeds", "speed_bands": "physics.speeds",
    "wheel_envelope_m": "physics.wheel",
    "roughness_index": "terrain.roughness", "step_width": "terrain.roughness",
    "worst_case_elevation": "terrain.roughness",
    "Vehicle": "core.vehicle", "bundled_vehicles": "core.vehicle", "load_vehicle": "core.vehicle",
    "Route": "core.route", "Profile": "core.profile",
    "read_profile": "io.profiles", "write_profile": "io.profiles", "read_route": "io.routes",
    "SolverOptions": "planning.options", "plan": "planning.planner",
    "QuarterCarRun": "physics.simulate", "simulate_quarter_car": "physics.simulate",
    "Verification": "verification.verify", "verify": "verification.verify",
    "plot_verification": "viz.plots",
    "ModelRun": "studies.compare", "compare_models": "studies.compare",
    "SafetyStudy": "studies.safety", "safety_study": "studies.safety",
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
    "write_profile",
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
