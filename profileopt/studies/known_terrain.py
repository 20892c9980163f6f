"""How fast on known terrain: the dynamic model against the paper's and against references
computed from outside the planner (issue 33).

For each route and vehicle, :func:`known_terrain_row` plans with SBEM:TF (the paper's model,
the default) and with the ``dynamic`` model, drives each plan in the exact simulation (the one
``verify`` uses), and computes the fastest constant-speed drive that stays within the force
limit in that same simulation (:func:`fastest_constant_speed`): the vehicle accelerates from
rest at its ``max_accel_mps2`` to a constant speed and brakes at its ``max_decel_mps2`` to stop
at the end, in closed form, for speeds every :data:`CONSTANT_SPEED_STEP_MPS` up to its top
speed. That reference ignores the jerk bound and the turns, so at the same speed it is a
little faster than any plan; it knows nothing of the planner. ``examples/known_terrain_study.py``
prints the table for the bundled routes (docs: guide/known-terrain.md).
"""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING

import numpy as np

from ..physics.simulate import simulate_quarter_car

if TYPE_CHECKING:
    from ..core.route import Route
    from ..core.vehicle import Vehicle

__all__ = ["CONSTANT_SPEED_STEP_MPS", "KnownTerrainRow", "simulated_ratio", "constant_speed_drive",
           "fastest_constant_speed", "known_terrain_row"]

#: The constant speeds tried by :func:`fastest_constant_speed`: every 0.25 m/s (m/s).
CONSTANT_SPEED_STEP_MPS = 0.25
#: Stations of a constant-speed drive every 0.5 m (m).
_STATION_M = 0.5


def simulated_ratio(route: "Route", s_m: np.ndarray, speed_mps: np.ndarray, vehicle: "Vehicle") -> float:
    """Largest |F_T| / ``max_transmitted_force_n`` when the quarter car drives ``speed_mps`` at
    stations ``s_m`` over the route's own samples (the exact simulation ``verify`` uses).

    Parameters
    ----------
    route : Route
        The terrain samples.
    s_m, speed_mps : numpy.ndarray, shape (K,)
        Stations (m) and the speeds there (m/s), as a profile's boundaries.
    vehicle : Vehicle
        The quarter car and its limit.

    Returns
    -------
    float
        Dimensionless; within the limit when at most 1.
    """
    run = simulate_quarter_car(route.s_m, route.z_m, s_m, speed_mps, vehicle)
    return float(np.max(np.abs(run.transmitted_n)) / vehicle.max_transmitted_force_n)


def constant_speed_drive(route: "Route", speed_mps: float, vehicle: "Vehicle"
                         ) -> tuple[np.ndarray, np.ndarray, float]:
    """From rest at ``max_accel_mps2`` up to ``speed_mps``, held, then braking at
    ``max_decel_mps2`` to rest at the route's end.

    Parameters
    ----------
    route : Route
        The route (its length).
    speed_mps : float
        The constant speed (m/s), > 0.
    vehicle : Vehicle
        Supplies the acceleration bounds.

    Returns
    -------
    (s_m, speed_mps, travel_time_s)
        Stations every 0.5 m (m), their speeds (m/s), and the travel time (s): each step's
        time is its length over the mean of its two speeds (exact for constant acceleration).
    """
    length = float(route.s_m[-1] - route.s_m[0])
    x = np.linspace(0.0, length, max(int(math.ceil(length / _STATION_M)), 1) + 1)
    v = np.minimum.reduce([np.full_like(x, float(speed_mps)), np.sqrt(2.0 * vehicle.max_accel_mps2 * x),
                           np.sqrt(2.0 * vehicle.max_decel_mps2 * np.maximum(length - x, 0.0))])
    time_s = float(np.sum(2.0 * np.diff(x) / np.maximum(v[1:] + v[:-1], 1e-12)))
    return route.s_m[0] + x, v, time_s


def fastest_constant_speed(route: "Route", vehicle: "Vehicle") -> tuple[float, float]:
    """The constant-speed drive (:func:`constant_speed_drive`) of least travel time that stays
    within the force limit in the exact simulation, of the speeds tried every
    :data:`CONSTANT_SPEED_STEP_MPS` up to the top speed.

    Parameters
    ----------
    route : Route
    vehicle : Vehicle

    Returns
    -------
    (speed_mps, travel_time_s)
        (nan, inf) when none of them stays within it.
    """
    best = (math.nan, math.inf)
    for speed in np.arange(CONSTANT_SPEED_STEP_MPS, vehicle.max_speed_mps + 1e-9, CONSTANT_SPEED_STEP_MPS):
        s, v, time_s = constant_speed_drive(route, float(speed), vehicle)
        if time_s < best[1] and simulated_ratio(route, s, v, vehicle) <= 1.0:
            best = (float(speed), time_s)
    return best


@dataclasses.dataclass(frozen=True)
class KnownTerrainRow:
    """One route and vehicle: travel times (s) and worst simulated |F_T| / limit of each plan.

    Attributes
    ----------
    route, vehicle : str
        Names.
    sbem_tf_s, sbem_tf_ratio : float
        The SBEM:TF plan (default options).
    dynamic_s, dynamic_ratio : float
        The dynamic plan (default options).
    constant_mps, constant_s : float
        The fastest constant-speed drive within the limit (:func:`fastest_constant_speed`).
    """

    route: str
    vehicle: str
    sbem_tf_s: float
    sbem_tf_ratio: float
    dynamic_s: float
    dynamic_ratio: float
    constant_mps: float
    constant_s: float

    @property
    def over_fastest(self) -> float:
        """The dynamic plan's travel time over the faster of SBEM:TF's and the constant
        speed's (dimensionless; at most 1.1 is the issue's target)."""
        return self.dynamic_s / min(self.sbem_tf_s, self.constant_s)


def known_terrain_row(route: "Route", vehicle: "Vehicle") -> KnownTerrainRow:
    """Plan ``route`` with SBEM:TF and with the dynamic model, simulate both, and find the
    fastest constant-speed drive within the limit.

    Parameters
    ----------
    route : Route
    vehicle : Vehicle

    Returns
    -------
    KnownTerrainRow
    """
    from ..planning import plan

    paper = plan(route, vehicle)
    dynamic = plan(route, vehicle, model="dynamic")
    speed, time_s = fastest_constant_speed(route, vehicle)
    return KnownTerrainRow(
        route=str(route.source), vehicle=vehicle.name or "vehicle",
        sbem_tf_s=paper.travel_time_s, sbem_tf_ratio=simulated_ratio(route, paper.s_m, paper.speed_mps, vehicle),
        dynamic_s=dynamic.travel_time_s,
        dynamic_ratio=simulated_ratio(route, dynamic.s_m, dynamic.speed_mps, vehicle),
        constant_mps=speed, constant_s=time_s)
