"""How fast on known terrain: the dynamic model against the paper's and against references
computed from outside the planner (issue 33).

For each route and vehicle, :func:`known_terrain_row` plans with SBEM:TF (the paper's model,
the default) and with the ``dynamic`` model, drives each plan in the exact simulation (the one
``verify`` uses), and computes two references for "the fastest plan that stays within the
force limit in that same simulation", both from outside the planner:

- the fastest constant-speed drive (:func:`fastest_constant_speed`): the vehicle accelerates
  from rest at its ``max_accel_mps2`` to a constant speed and brakes at its
  ``max_decel_mps2`` to stop at the end, in closed form, for speeds every
  :data:`CONSTANT_SPEED_STEP_MPS` up to its top speed. It ignores the jerk bound and the
  turns, so at the same speed it is a little faster than any plan;
- the scaled limit (:func:`fastest_scaled_limit`): the public ``plan(route, vehicle)`` (SBEM:TF,
  default options, its simulation gate included) for the vehicle with its force limit
  scaled by a factor lam, each plan judged against the true limit, and the largest lam whose
  plan keeps it found by doubling and bisection.

``examples/known_terrain_study.py`` prints the table for the bundled routes (docs:
guide/known-terrain.md).
"""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING

import numpy as np

from ..errors import InfeasibleError, PlanningError
from ..physics.simulate import simulate_quarter_car

if TYPE_CHECKING:
    from ..core.route import Route
    from ..core.vehicle import Vehicle

__all__ = ["CONSTANT_SPEED_STEP_MPS", "SCALE_CAP", "SCALE_BRACKET", "KnownTerrainRow", "ScaledLimitReference",
           "simulated_ratio", "constant_speed_drive", "fastest_constant_speed", "scaled_limit_plan",
           "fastest_scaled_limit", "known_terrain_row"]

#: The constant speeds tried by :func:`fastest_constant_speed`: every 0.25 m/s (m/s).
CONSTANT_SPEED_STEP_MPS = 0.25
#: The largest factor tried on the force limit by :func:`fastest_scaled_limit` (dimensionless):
#: 64 times the limit lets both bundled ATVs drive every bundled route at the speed every
#: other limit allows.
SCALE_CAP = 64.0
#: :func:`fastest_scaled_limit` bisects until the factor that fails is at most this many times
#: the one that passes (dimensionless): 2 %.
SCALE_BRACKET = 1.02
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
        The terrain samples.
    vehicle : Vehicle
        The quarter car, its limit and its acceleration bounds.

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
class ScaledLimitReference:
    """The fastest SBEM:TF plan of a scaled force limit that keeps the true limit in simulation.

    Attributes
    ----------
    scale : float
        The factor lam on ``max_transmitted_force_n`` of the reference plan (dimensionless);
        nan when even lam = 1 does not keep the limit (or cannot be planned).
    travel_time_s : float
        Its travel time (s); inf when there is none.
    ratio : float
        Its worst simulated |F_T| / the true limit (dimensionless, at most 1).
    upper_scale : float
        The smallest factor tried above ``scale`` whose plan does not keep the true limit
        (dimensionless); inf when even :data:`SCALE_CAP` keeps it.
    upper_ratio : float
        That plan's worst simulated |F_T| / the true limit (> 1; inf when it could not be
        planned, nan when there is no such factor).
    plans : int
        How many plans were made.
    """

    scale: float
    travel_time_s: float
    ratio: float
    upper_scale: float
    upper_ratio: float
    plans: int


def scaled_limit_plan(route: "Route", vehicle: "Vehicle", scale: float) -> tuple[float, float]:
    """Plan ``route`` with SBEM:TF for ``vehicle`` with its force limit scaled by ``scale`` and
    judge the plan against the vehicle's true limit in the exact simulation.

    The plan is the public ``plan(route, vehicle.replace(max_transmitted_force_n=scale * L))``
    with default options, so its simulation gate lowers the speed where its own simulation
    goes over the scaled limit, as it would for a user with that vehicle.

    Parameters
    ----------
    route : Route
        The terrain samples.
    vehicle : Vehicle
        The vehicle with its true limit L (``max_transmitted_force_n``, N).
    scale : float
        The factor lam on the limit (dimensionless, > 0).

    Returns
    -------
    (travel_time_s, ratio)
        The plan's travel time (s) and its worst simulated |F_T| / L (dimensionless); (inf,
        inf) when the scaled vehicle cannot be planned (``InfeasibleError``, or the gate ran
        out of rounds: ``PlanningError``).
    """
    from ..planning import plan

    scaled = vehicle.replace(max_transmitted_force_n=float(scale) * vehicle.max_transmitted_force_n)
    try:
        profile = plan(route, scaled)
    except (InfeasibleError, PlanningError):
        return math.inf, math.inf
    return profile.travel_time_s, simulated_ratio(route, profile.s_m, profile.speed_mps, vehicle)


def fastest_scaled_limit(route: "Route", vehicle: "Vehicle", *, cap: float = SCALE_CAP,
                         bracket: float = SCALE_BRACKET) -> ScaledLimitReference:
    """The largest factor lam on the force limit whose SBEM:TF plan (:func:`scaled_limit_plan`)
    keeps the true limit in the exact simulation, and that plan's travel time.

    lam = 1 (the SBEM:TF plan itself) is tried first, then ``cap``: when that keeps the limit,
    it is the reference. Otherwise lam is doubled from 2 until a plan goes over the limit,
    and the bracket is bisected (geometric mean) until its ends are at most ``bracket`` times
    apart: 2 plans when ``cap`` keeps the limit, else 9 to 13 (``cap`` 64, ``bracket`` 1.02). The force is not monotone in the speed, so neither is the
    simulated force in lam; the bisection finds a lam that keeps the limit next to one that
    does not, and the reference is the fastest plan that kept it of all those made (almost
    always the last lam that kept it).

    Parameters
    ----------
    route : Route
        The terrain samples.
    vehicle : Vehicle
        The vehicle with its true limit.
    cap : float, default :data:`SCALE_CAP`
        The largest factor tried (dimensionless, >= 1).
    bracket : float, default :data:`SCALE_BRACKET`
        The bisection stops when the failing factor is at most this many times the passing one
        (dimensionless, > 1).

    Returns
    -------
    ScaledLimitReference
    """
    tried: dict[float, tuple[float, float]] = {}

    def passes(scale: float) -> bool:
        tried[scale] = scaled_limit_plan(route, vehicle, scale)
        return tried[scale][1] <= 1.0

    if not passes(1.0):
        return ScaledLimitReference(math.nan, math.inf, math.nan, 1.0, tried[1.0][1], len(tried))
    if cap > 1.0 and not passes(float(cap)):
        low, high = 1.0, float(cap)
        scale = 2.0
        while scale < high and passes(scale):
            low, scale = scale, 2.0 * scale
        high = min(scale, high)
        while high > bracket * low:
            middle = math.sqrt(low * high)
            if passes(middle):
                low = middle
            else:
                high = middle
    kept = [scale for scale, (_, ratio) in tried.items() if ratio <= 1.0]
    fastest_s = min(tried[scale][0] for scale in kept)
    # the largest factor of the fastest plans (plans whose force never binds differ by rounding)
    best = max(scale for scale in kept if tried[scale][0] <= fastest_s * (1.0 + 1e-9))
    failed = [scale for scale, (_, ratio) in tried.items() if ratio > 1.0 and scale > best]
    upper = min(failed, default=math.inf)
    return ScaledLimitReference(scale=best, travel_time_s=tried[best][0], ratio=tried[best][1], upper_scale=upper,
                                upper_ratio=tried[upper][1] if failed else math.nan, plans=len(tried))


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
    scaled : ScaledLimitReference
        The fastest SBEM:TF plan of a scaled limit within the true one
        (:func:`fastest_scaled_limit`).
    """

    route: str
    vehicle: str
    sbem_tf_s: float
    sbem_tf_ratio: float
    dynamic_s: float
    dynamic_ratio: float
    constant_mps: float
    constant_s: float
    scaled: ScaledLimitReference

    @property
    def fastest_other_s(self) -> float:
        """The faster of the two references (s): the constant speed's and the scaled limit's
        (which is never slower than SBEM:TF's own plan when that keeps the limit: lam = 1)."""
        return min(self.constant_s, self.scaled.travel_time_s)

    @property
    def over_fastest(self) -> float:
        """The dynamic plan's travel time over :attr:`fastest_other_s` (dimensionless; at most
        1.1 is the issue's target)."""
        return self.dynamic_s / self.fastest_other_s


def known_terrain_row(route: "Route", vehicle: "Vehicle") -> KnownTerrainRow:
    """Plan ``route`` with SBEM:TF and with the dynamic model, simulate both, and find the
    fastest constant-speed drive and the fastest scaled-limit SBEM:TF plan within the limit.

    Parameters
    ----------
    route : Route
        The terrain samples.
    vehicle : Vehicle
        The vehicle with its true limit.

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
        constant_mps=speed, constant_s=time_s, scaled=fastest_scaled_limit(route, vehicle))
