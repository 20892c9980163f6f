"""profileopt: terrain-force-limited, minimum-time speed profiles for ground vehicles.

The force models of Wilson et al. (University of Calgary) written once in CasADi, a
roughness index from elevation data, allowable speeds, a route-level minimum-time speed
planner solved with IPOPT, and a quarter-car simulation that checks every plan.

    >>> import profileopt
    >>> route = profileopt.read_route("examples/routes/trail.csv")  # doctest: +SKIP
    >>> profile = profileopt.plan(route, profileopt.load_vehicle("atv"))  # doctest: +SKIP
"""

from .errors import InfeasibleError, InputError, PlanningError
from .forces import MODELS, force_n, get_model
from .speeds import SpeedBands, allowable_speed, speed_bands
from .terrain import roughness_index, step_width, worst_case_elevation
from .vehicle import Vehicle, bundled_vehicles, load_vehicle
from .route import Route
from .io import read_profile, read_route
from .planning import Profile, SolverOptions, plan, summarize
from .simulate import QuarterCarRun, simulate_quarter_car
from .wheel import wheel_envelope_m
from .verification import Verification, verify
from .plots import plot_verification
from .study import ModelRun, SafetyStudy, compare_models, safety_study

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
