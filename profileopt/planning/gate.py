"""The planner's own gate: every plan driven in the exact simulation before it is returned.

The force models bound the force from a statistic of the terrain (the RI), and the step
limit bounds it on one ramp of the wheel's path met with the suspension at rest
(:mod:`profileopt.physics.steps`). Neither is proven sound everywhere: a block or a pit
shorter than the suspension's response, a ramp met before it settled from the last one, a
row of blocks that builds up resonance. ``verify`` judges a plan by the exact simulation of
the quarter car on the route's own samples (:mod:`profileopt.physics.simulate`); the planner
runs the same simulation before it returns a plan and, where the force the model limits
goes over the limit, caps the speed over the stretch that caused it and plans again
(:class:`~profileopt.planning.limits.simulated.SimulatedLimit`), until the simulation holds.
So a plan never fails the gate it is judged by.

Where a cap goes. The force at time t is the response to the input before t, and the
impulse response of the quarter car has its largest value within half a damped period
(:func:`profileopt.physics.steps.impulse_response_peak_s`) and then decays by
exp(-zeta wn t). A point over the limit at time t_p is charged to the route driven in the
``lookback`` before it, [s(t_p - tau), s(t_p)], tau = k 2 pi / wn in round k (one natural
period in the first round, longer each time the simulation is still over, for resonance
built over several blocks); overlapping stretches merge.

How low. A stretch's cap is the fastest speed driven in the natural period before its
worst point times min(:data:`GATE_SHRINK`, (1 - :data:`GATE_MARGIN`) / ratio), ratio the
largest simulated force over the limit there, so each round lowers the speed that met it: on a ramp the force grows about in proportion to the speed
(:func:`profileopt.physics.steps.ramp_force_n`), but it is not monotone in speed (a
resonant suspension), so the gate does not rely on it: it simulates again, and lowers
again, for at most :data:`MAX_GATE_ROUNDS` rounds. As the speed falls to 0 the force the
suspension transmits falls to 0 with it, so lowering always ends.

The gate checks the transmitted force F_T (the quantity of SBEM:TF, the default model). The
excitation force of Prev:BEM, IECM and SBEM:EF, k y + c y', keeps its k y term at any
speed, so lowering a speed cannot always bring it within its limit; for those models the
plan is returned unsimulated, as before. A route whose roughness is assumed (a track over a
DEM or a sparse cloud: its own samples cannot show wheel-scale roughness) is simulated as
``verify`` drives it by default: its elevation plus the seeded random profile of the
assumed class (:func:`profileopt.core.route.with_assumed_roughness`, seed 0).
"""

from __future__ import annotations

import dataclasses
import math
import time
from typing import TYPE_CHECKING

import numpy as np

from ..core.route import with_assumed_roughness
from ..physics.forces import get_model
from ..physics.motion import STANDARD_GRAVITY_MPS2
from ..physics.simulate import QuarterCarRun, simulate_quarter_car
from ..physics.steps import StepCaps
from ..progress import NO_PROGRESS, Progress
from .limits.simulated import SimulatedLimit

if TYPE_CHECKING:
    from typing import Callable

    from ..core.profile import Profile
    from ..core.route import Route
    from ..core.vehicle import Vehicle
    from .limits.base import Limit

__all__ = ["GATE_MARGIN", "GATE_SHRINK", "MAX_GATE_ROUNDS", "GateCheck", "GateRun", "gate_applies", "check_plan",
           "check_speeds", "gate_caps", "merged_caps", "covered_m", "segment_peaks_n", "run_gate", "gate_note"]

#: A simulated force above (1 - GATE_MARGIN) of the limit sends the plan back; a new cap aims
#: at that much below the limit, so the profile as written to a file (rounded speeds) and
#: verified again stays within it (dimensionless).
GATE_MARGIN = 1e-3
#: A stretch's new cap is at most this share of the fastest speed driven in it (dimensionless).
GATE_SHRINK = 0.9
#: Most rounds of simulating and capping before the planner gives up on a plan.
MAX_GATE_ROUNDS = 16


@dataclasses.dataclass(frozen=True)
class GateCheck:
    """The exact simulation of one plan, judged against the force limit.

    Attributes
    ----------
    run : QuarterCarRun
        The simulation of the plan on the route's samples.
    limit_n : float
        The force limit (N): the vehicle's ``max_transmitted_force_n``.
    worst_ratio : float
        Largest |F_T| / limit anywhere (dimensionless); with ``keep_contact``, or -F_T / m g
        where that is larger (over 1: the wheel leaves the ground).
    worst_s_m : float
        Where it occurs (m).
    ratio : numpy.ndarray, shape (K,)
        That ratio at each point of the run.
    """

    run: QuarterCarRun
    limit_n: float
    worst_ratio: float
    worst_s_m: float
    ratio: np.ndarray

    @property
    def passes(self) -> bool:
        """True when |F_T| stays within (1 - :data:`GATE_MARGIN`) of the limit everywhere."""
        return self.worst_ratio <= 1.0 - GATE_MARGIN


def gate_applies(model: str) -> bool:
    """Whether the gate checks plans of ``model``: those limiting the transmitted force, on
    every route (an assumed roughness is simulated as verify drives it; see the module's
    docstring).

    Parameters
    ----------
    model : str
        Force model key.

    Returns
    -------
    bool
    """
    return get_model(model).quantity == "transmitted"


def check_plan(route: "Route", profile: "Profile", vehicle: "Vehicle", *, window_m: float,
               force_margin: float = 0.0, keep_contact: bool = False) -> GateCheck:
    """Drive ``profile`` over ``route`` in the exact simulation (the one ``verify`` uses).

    Parameters
    ----------
    route : Route
        The route's samples; with an assumed roughness, driven with the seeded random
        profile ``verify`` adds by default (seed 0).
    profile : Profile
        The planned profile (boundaries ``s_m`` and speeds ``speed_mps``).
    vehicle : Vehicle
        The quarter car and ``max_transmitted_force_n``.
    window_m : float
        The roughness window the plan used (m): the band of an assumed roughness's profile.
    force_margin : float, default 0
        Share of the force limit kept in reserve (dimensionless, in [0, 1)): the limit
        judged is ``(1 - force_margin)`` times the vehicle's.
    keep_contact : bool, default False
        Also judge the wheel's contact: F_T >= -m g (m the quarter mass), where the linear
        simulation holds; below it the real wheel leaves the ground.

    Returns
    -------
    GateCheck
    """
    return check_speeds(route, profile.s_m, profile.speed_mps, vehicle, window_m=window_m,
                        force_margin=force_margin, keep_contact=keep_contact)


def check_speeds(route: "Route", s_m: np.ndarray, speed_mps: np.ndarray, vehicle: "Vehicle", *, window_m: float,
                 force_margin: float = 0.0, keep_contact: bool = False,
                 judged_m: tuple[float, float] | None = None) -> GateCheck:
    """:func:`check_plan` for speeds at boundaries, judged over the whole run or a stretch of it.

    Parameters
    ----------
    route : Route
        As for :func:`check_plan`.
    s_m, speed_mps : numpy.ndarray, shape (N+1,)
        Boundaries (m) and the speed at each (m/s), constant acceleration between them.
    vehicle, window_m, force_margin, keep_contact
        As for :func:`check_plan`.
    judged_m : (float, float), optional
        Only points of the run within [start, end] (m) are judged (their ratio elsewhere is
        0): the rest is driven for the suspension's state there only.

    Returns
    -------
    GateCheck
    """
    if route.assumed_roughness is not None:
        route, _ = with_assumed_roughness(route, vehicle, window_m=window_m, seed=0)
    run = simulate_quarter_car(route.s_m, route.z_m, s_m, speed_mps, vehicle)
    limit = float(vehicle.max_transmitted_force_n) * (1.0 - force_margin)
    ratio = np.abs(run.transmitted_n) / limit
    if keep_contact:
        ratio = np.maximum(ratio, -run.transmitted_n / (vehicle.quarter_mass_kg * STANDARD_GRAVITY_MPS2))
    if judged_m is not None:
        ratio = np.where((run.s_m >= judged_m[0]) & (run.s_m <= judged_m[1]), ratio, 0.0)
    worst = int(np.argmax(ratio))
    return GateCheck(run=run, limit_n=limit, worst_ratio=float(ratio[worst]), worst_s_m=float(run.s_m[worst]),
                     ratio=ratio)


def gate_caps(check: GateCheck, vehicle: "Vehicle", round_number: int, *, shrink: float = GATE_SHRINK) -> StepCaps:
    """The caps that take the plan of ``check`` back within the limit: one per stretch of
    route charged with a point over it (see the module's docstring).

    Parameters
    ----------
    check : GateCheck
        The simulation of a plan that did not pass.
    vehicle : Vehicle
        Supplies wn (rad/s).
    round_number : int
        1 for the first round of the gate, 2 for the second, ...: the lookback is that many
        natural periods.
    shrink : float, default :data:`GATE_SHRINK`
        A new cap is at most this share of the fastest speed driven before the worst point
        (dimensionless, in (0, 1)).

    Returns
    -------
    StepCaps
        Stretches (m) and caps (m/s), sorted by start; empty when nothing is over.
    """
    run = check.run
    ratio = check.ratio
    over = np.flatnonzero(ratio > 1.0 - GATE_MARGIN)
    if over.size == 0:
        return StepCaps(start_m=np.empty(0), end_m=np.empty(0), cap_mps=np.empty(0))
    period_s = 2.0 * math.pi / float(vehicle.natural_frequency_radps)
    start = np.interp(run.time_s[over] - round_number * period_s, run.time_s, run.s_m)
    end = run.s_m[over]
    # merge overlapping stretches (both start and end rise with the point's time)
    new = np.concatenate([[True], start[1:] > np.maximum.accumulate(end)[:-1]])
    heads = np.flatnonzero(new)
    lo = start[new]
    hi = np.maximum.reduceat(end, heads)
    # each stretch's worst point, and the fastest speed driven in the period before it
    worst = np.array([over[a + int(np.argmax(ratio[over[a:b]]))]
                      for a, b in zip(heads.tolist(), np.append(heads[1:], over.size).tolist())])
    first = np.searchsorted(run.time_s, run.time_s[worst] - period_s, side="left")
    fastest = np.array([float(np.max(run.speed_mps[a:b + 1])) for a, b in zip(first.tolist(), worst.tolist())])
    cut = np.minimum(shrink, (1.0 - GATE_MARGIN) / ratio[worst])
    return StepCaps(start_m=lo, end_m=hi, cap_mps=fastest * cut)


def segment_peaks_n(check: GateCheck, s_m: np.ndarray) -> np.ndarray:
    """The largest simulated |F_T| (N) inside each segment of boundaries ``s_m``, per row
    (the last row repeats the last segment's), as a profile's ``force_n`` column holds it.

    Parameters
    ----------
    check : GateCheck
        The simulation of the plan.
    s_m : numpy.ndarray, shape (N+1,)
        The plan's segment boundaries (m).

    Returns
    -------
    numpy.ndarray, shape (N+1,)
    """
    from ..core.stations import segment_index

    s = np.asarray(s_m, dtype=float)
    seg = segment_index(check.run.s_m, s)
    peaks = np.zeros(s.size - 1)
    np.maximum.at(peaks, seg, np.abs(check.run.transmitted_n))
    return np.append(peaks, peaks[-1])


def merged_caps(old: StepCaps | None, new: StepCaps) -> StepCaps:
    """Every stretch of ``old`` and ``new`` (a segment keeps the lowest cap it meets).

    Parameters
    ----------
    old : StepCaps or None
        The caps of the rounds before.
    new : StepCaps
        This round's.

    Returns
    -------
    StepCaps
    """
    if old is None:
        return new
    start = np.concatenate([old.start_m, new.start_m])
    order = np.argsort(start, kind="stable")
    return StepCaps(start_m=start[order], end_m=np.concatenate([old.end_m, new.end_m])[order],
                    cap_mps=np.concatenate([old.cap_mps, new.cap_mps])[order])


def covered_m(caps: StepCaps) -> float:
    """Length of route (m) that at least one stretch of ``caps`` covers (overlaps counted once).

    Parameters
    ----------
    caps : StepCaps
        Stretches (m).

    Returns
    -------
    float
    """
    if caps.start_m.size == 0:
        return 0.0
    order = np.argsort(caps.start_m, kind="stable")
    start, end = caps.start_m[order], np.maximum.accumulate(caps.end_m[order])
    new = np.concatenate([[True], start[1:] > end[:-1]])  # a stretch that starts past all before it
    heads = np.flatnonzero(new)
    tails = np.append(heads[1:], start.size) - 1
    return float(np.sum(end[tails] - start[heads]))


@dataclasses.dataclass(frozen=True)
class GateRun:
    """A plan driven through the simulation gate: the last profile, its simulation, the caps
    the gate set (None: none), and the first round's worst ratio and where (None: it passed at once)."""

    profile: Profile
    check: GateCheck
    caps: StepCaps | None
    first_ratio: float | None
    first_s_m: float | None
    rounds: int


def run_gate(profile: Profile, once: "Callable[[tuple[Limit, ...]], Profile]", limits: tuple[Limit, ...],
             route: "Route", vehicle: "Vehicle", window_m: float, timings: dict[str, float],
             progress: Progress = NO_PROGRESS, once_steps: int = 0, *, rounds: int = MAX_GATE_ROUNDS,
             shrink: float = GATE_SHRINK, force_margin: float = 0.0, keep_contact: bool = False) -> GateRun:
    """Simulate ``profile`` and, while it goes over the force limit, plan again with the
    gate's caps, for at most ``rounds`` rounds; the last plan and its simulation, passing or not.

    Parameters
    ----------
    profile : Profile
        The first plan.
    once : callable
        ``once(limits)``: a plan with these limits (the same segments and path).
    limits : tuple of Limit
        The plan's limits; each round adds a :class:`~profileopt.planning.limits.SimulatedLimit`
        holding every cap so far.
    route : Route
        The route (its samples are simulated).
    vehicle : Vehicle
        The quarter car and its limit.
    window_m : float
        The roughness window (m) (:func:`check_plan`).
    timings : dict
        Adds the simulation time (s) under ``"simulate"``.
    progress : Progress, optional
        Told each simulation.
    once_steps : int, default 0
        The progress steps of one plan.
    rounds : int, default :data:`MAX_GATE_ROUNDS`
        Most rounds of capping.
    shrink : float, default :data:`GATE_SHRINK`
        As :func:`gate_caps`'s.
    force_margin, keep_contact : float, bool
        As :func:`check_plan`'s.

    Returns
    -------
    GateRun
        ``check.passes`` says whether the last plan keeps the limit.
    """
    caps = None
    first_ratio = first_s = None
    for round_number in range(1, rounds + 1):
        t = time.perf_counter()
        progress.step("simulating the plan" if round_number == 1 else
                      f"simulating the plan again (round {round_number} of the simulation gate)")
        check = check_plan(route, profile, vehicle, window_m=window_m, force_margin=force_margin,
                           keep_contact=keep_contact)
        timings["simulate"] = timings.get("simulate", 0.0) + time.perf_counter() - t
        if check.passes:
            return GateRun(profile, check, caps, first_ratio, first_s, round_number)
        if first_ratio is None:
            first_ratio, first_s = check.worst_ratio, check.worst_s_m
        caps = merged_caps(caps, gate_caps(check, vehicle, round_number, shrink=shrink))
        progress.expect(once_steps + 1)  # plan again, simulate again
        profile = once((*limits, SimulatedLimit(caps=caps)))
    check = check_plan(route, profile, vehicle, window_m=window_m, force_margin=force_margin,
                       keep_contact=keep_contact)
    return GateRun(profile, check, caps, first_ratio, first_s, rounds)


def gate_note(run: GateRun) -> str | None:
    """What the gate did to a plan, one line.

    Parameters
    ----------
    run : GateRun
        A plan through the gate.

    Returns
    -------
    str or None
        None when it passed at once.
    """
    if run.caps is None:
        return None
    return (f"simulation gate: the plan went {run.first_ratio:.4g}x over the force limit in the exact simulation "
            f"(at s = {run.first_s_m:.6g} m); the speed was capped over {covered_m(run.caps):.3g} m of route "
            f"({run.caps.cap_mps.size} stretch(es)), until it held ({run.check.worst_ratio:.4g} of the limit)")
