"""profileopt: terrain-force-limited, minimum-time speed profiles for ground vehicles.

The force models of Wilson et al. (University of Calgary) written once in CasADi, a
roughness index from elevation data, allowable speeds, and (in later modules) a route-level
speed planner solved with IPOPT.
"""

from .errors import InfeasibleError, InputError
from .forces import MODELS, force_n, get_model
from .speeds import SpeedBands, allowable_speed, speed_bands
from .terrain import roughness_index, step_width, worst_case_elevation
from .vehicle import Vehicle, bundled_vehicles, load_vehicle
from .simulate import QuarterCarRun, simulate_quarter_car, wheel_envelope_m
# Note: this makes the name profileopt.verify the function, as the issue asks for
# (profileopt.verify(route, profile, vehicle)); the module stays importable with
# "from profileopt.verify import ...".
from .verify import Verification, plot_verification, verify

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
    "QuarterCarRun",
    "simulate_quarter_car",
    "wheel_envelope_m",
    "Verification",
    "plot_verification",
    "verify",
]

__version__ = "0.1.0"
