"""The ``dynamic`` model: a plan held to the quarter car's own response on the route's samples.

The paper's models bound the force from the roughness index alone, the right thing for
terrain seen roughly from afar: SBEM:TF assumes the worst sinusoid of amplitude e_max at the
wavelength that makes the suspension resonate, in steady state. On terrain known sample by
sample (a survey, LiDAR, a test course) that is far more cautious than the vehicle needs: the
resonant ATV is told to crawl over ground it crosses at 10 m/s within its limit, because the
resonance band is crossed in less time than a resonance takes to build up, and a real
profile is no sinusoid.

The ``dynamic`` model holds the force that matters, the transmitted force F_T of the quarter
car driven over the route's own samples at the planned speeds, transients included, within
``max_transmitted_force_n``: the quantity ``verify`` judges by, computed by the same exact
simulation (:func:`profileopt.physics.simulate.simulate_quarter_car`). It is imposed as the
planner's simulation gate imposes it on SBEM:TF plans (:mod:`profileopt.planning.gate`), here
from the kinematic optimum instead of from the model's bands:

1. Plan with every limit but the force (top speed, speed limits, turns, grades, power,
   acceleration, jerk): the fastest profile the vehicle can drive at all.
2. Drive it in the exact simulation. Where |F_T| goes over the limit, cap the speed over
   the stretch of route driven in the natural periods before that point, at most
   :data:`DYNAMIC_GATE_SHRINK` of the fastest speed driven there (a finer step than the
   SBEM:TF gate's, which starts from a plan that is nearly right); plan again with the caps
   and repeat, for at most :data:`MAX_DYNAMIC_ROUNDS` rounds.
3. Unless the kinematic optimum kept the limit at once (nothing is faster), do the same
   starting from the plan with SBEM:TF's closed-form step caps
   (:class:`~profileopt.planning.limits.StepLimit`), which know how a kerb or a drop loads the
   suspension and so spare the gate many rounds there (but are cautious on some rough ground).
4. Return the fastest of the two plans that passed and, when the kinematic optimum did not
   pass at once, SBEM:TF's plan (itself gated) if it keeps the same limits in the simulation:
   the capping lowers whole stretches, and on a short block SBEM:TF's closed-form caps can be
   finer. Neither start passing (the gate ran out of rounds), return the SBEM:TF plan, with a
   note.

What it guarantees: the returned profile, driven at its own speeds over the route's samples
(the rigid-wheel quarter car with the profile's speeds interpolated exactly as ``verify``
drives them), keeps |F_T| within (1 - :data:`~profileopt.planning.gate.GATE_MARGIN`) x
(1 - ``force_margin``) of the limit everywhere; every other limit is kept as in any plan.
With ``keep_contact`` the simulated wheel also stays on the ground (F_T >= -m g, m the
quarter mass), where the linear model holds; without it (the default, as for SBEM:TF) the
plan may lift the wheel where F_T < -m g, which ``verify`` reports ("wheel lift-off"):
for the atv, whose force limit is five times its wheel load, often.
The guarantee is only as good as the route's samples: ground the samples miss is not
simulated (hence ``force_margin``, a share of the limit kept in reserve for measurement error,
and the refusal of routes whose roughness is assumed rather than measured). As speed falls
to 0 the transmitted force falls to 0, so the capping always ends; it is not an exact
optimum (a cap lowers a whole stretch), and the force is not monotone in speed (a resonant
suspension), so a slower plan is not always a safer one: each round is simulated again.
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING, Callable

from ..errors import InputError
from ..progress import NO_PROGRESS, Progress
from .gate import GateCheck, GateRun, check_plan, gate_note, run_gate, segment_peaks_n
from .limits import StepLimit

if TYPE_CHECKING:
    from ..core.profile import Profile
    from ..core.route import Route
    from ..core.vehicle import Vehicle
    from .limits.base import Limit

__all__ = ["DYNAMIC_GATE_SHRINK", "MAX_DYNAMIC_ROUNDS", "plan_dynamic", "check_dynamic_route"]

#: Each round lowers the speed over a stretch to at most this share of the fastest speed
#: driven there (dimensionless): finer than the SBEM:TF gate's 0.9, as the dynamic plan starts
#: from the kinematic optimum, far from the force limit's own shape.
DYNAMIC_GATE_SHRINK = 0.97
#: Most rounds of simulating and capping for each of the dynamic model's two starts.
MAX_DYNAMIC_ROUNDS = 60


def check_dynamic_route(route: "Route", simulation_gate: bool) -> None:
    """Refuse what the dynamic model cannot plan: a route whose roughness is assumed (its
    samples do not show the ground the wheel meets), or the simulation gate turned off (it
    is the model).

    Parameters
    ----------
    route : Route
        The route to plan.
    simulation_gate : bool
        The planner's ``simulation_gate`` argument.

    Raises
    ------
    InputError
        One line naming the route and the way out.
    """
    if route.assumed_roughness is not None:
        raise InputError(f"{route.source}: the dynamic model simulates the vehicle on the route's own samples, and "
                         f"this route's roughness is assumed ({route.assumed_roughness.label}), not measured; plan it "
                         "with the paper's model (--model sbem_tf), or give a terrain that measures it")
    if not simulation_gate:
        raise InputError("the dynamic model is the exact simulation of the quarter car: it cannot be planned with "
                         "the simulation gate off (simulation_gate=False); choose another model for that")


def plan_dynamic(first: "Profile", once: "Callable[[tuple[Limit, ...]], Profile]", limits: "tuple[Limit, ...]",
                 route: "Route", vehicle: "Vehicle", *, window_m: float, timings: dict[str, float],
                 fallback: "Callable[[], Profile]", force_margin: float = 0.0, keep_contact: bool = False,
                 progress: Progress = NO_PROGRESS, once_steps: int = 0) -> "Profile":
    """The dynamic model's plan (see the module's docstring for the method and its guarantee).

    Parameters
    ----------
    first : Profile
        The plan with ``limits`` (every limit but the force): the kinematic optimum.
    once : callable
        ``once(limits)``: a plan with other limits on the same segments and path.
    limits : tuple of Limit
        The plan's limits (:func:`~profileopt.planning.limits.default_limits` with model
        ``dynamic``, and the user's).
    route : Route
        The route (its own samples are simulated).
    vehicle : Vehicle
        The quarter car and ``max_transmitted_force_n``.
    window_m : float
        The roughness window (m), for the gate's bookkeeping.
    timings : dict
        Adds the simulation time (s) under ``"simulate"``.
    fallback : callable
        ``fallback()``: the SBEM:TF plan, returned when neither start passes.
    force_margin : float, default 0
        Share of the force limit kept in reserve (dimensionless, in [0, 1)).
    keep_contact : bool, default False
        Also keep the wheel on the ground in the simulation (F_T >= -m g).
    progress : Progress, optional
        Told each simulation.
    once_steps : int, default 0
        The progress steps of one plan.

    Returns
    -------
    Profile
        ``force_n`` holds each segment's largest simulated |F_T| (N); a note says which start
        won and how far the gate lowered the speed.
    """
    settings = {"rounds": MAX_DYNAMIC_ROUNDS, "shrink": DYNAMIC_GATE_SHRINK, "force_margin": force_margin,
                "keep_contact": keep_contact}
    kinematic = run_gate(first, once, limits, route, vehicle, window_m, timings, progress, once_steps, **settings)
    runs: list[tuple[str, GateRun]] = [("from the kinematic optimum", kinematic)]
    if kinematic.caps is not None or not kinematic.check.passes:  # else nothing is faster: done
        with_steps = (*limits, StepLimit())
        progress.expect(once_steps)
        runs.append(("from the plan with SBEM:TF's step caps",
                     run_gate(once(with_steps), once, with_steps, route, vehicle, window_m, timings, progress,
                              once_steps, **settings)))
    passed = [(how, run) for how, run in runs if run.check.passes]
    if not passed:
        worst = min(run.check.worst_ratio for _, run in runs)
        profile = fallback()
        note = (f"dynamic model: after {MAX_DYNAMIC_ROUNDS} rounds of lowering the speed the exact simulation was "
                f"still over the " + ("limits" if keep_contact else "force limit")
                + f" ({worst:.4g} of it at best); this is the SBEM:TF plan instead")
        if keep_contact or force_margin:  # say whether it keeps what was asked beyond SBEM:TF's own gate
            check = check_plan(route, profile, vehicle, window_m=window_m, force_margin=force_margin,
                               keep_contact=keep_contact)
            note += (", and it keeps them in the simulation too" if check.passes else
                     f", which does not keep them in the simulation ({check.worst_ratio:.4g} at s = "
                     f"{check.worst_s_m:.6g} m" + (": the wheel lifts" if keep_contact else "") + ")")
        return dataclasses.replace(profile, notes=(*profile.notes, note))
    how, run = min(passed, key=lambda item: item[1].profile.travel_time_s)
    if len(runs) > 1:  # the kinematic optimum did not pass at once: SBEM:TF's gated plan may be faster
        paper = _paper_if_faster(fallback, run.profile.travel_time_s, route, vehicle, window_m=window_m,
                                 force_margin=force_margin, keep_contact=keep_contact)
        if paper is not None:
            return paper
    profile = run.profile
    other = [f"{r.profile.travel_time_s:.4g} s {h}" for h, r in runs if r is not run and r.check.passes]
    note = (f"dynamic model: the exact simulation of the quarter car on the route's samples held within "
            f"{run.check.worst_ratio * (1 - force_margin):.4g} of the force limit"
            + (f" ({force_margin:g} of it kept in reserve)" if force_margin else "")
            + (" and of the wheel's load (F_T >= -m g: on the ground)" if keep_contact else "")
            + f"; planned {how}" + (f" (the other start: {'; '.join(other)})" if other else ""))
    gated = gate_note(run)
    return _as_dynamic(profile, run.check, (*([gated] if gated else []), note), force_margin=force_margin,
                       keep_contact=keep_contact)


def _as_dynamic(profile: "Profile", check: GateCheck, notes: tuple[str, ...], *, force_margin: float,
                keep_contact: bool) -> "Profile":
    """``profile`` as the dynamic model's plan: its simulated peaks in ``force_n``, the model
    and its options in the settings, ``notes`` added."""
    settings = {**profile.settings, "model": "dynamic",
                **({"force_margin": float(force_margin)} if force_margin else {}),
                **({"keep_contact": True} if keep_contact else {})}
    return dataclasses.replace(profile, model="dynamic", force_n=segment_peaks_n(check, profile.s_m),
                               notes=(*profile.notes, *notes), settings=settings)


def _paper_if_faster(fallback: "Callable[[], Profile]", travel_time_s: float, route: "Route", vehicle: "Vehicle", *,
                     window_m: float, force_margin: float, keep_contact: bool) -> "Profile | None":
    """SBEM:TF's gated plan as the dynamic model's (:func:`_as_dynamic`), when it is faster than
    ``travel_time_s`` and keeps the dynamic model's limits in the exact simulation; None
    otherwise, or when it cannot be planned."""
    from ..errors import InfeasibleError, PlanningError

    try:
        paper = fallback()
    except (InfeasibleError, PlanningError):
        return None
    if paper.travel_time_s >= travel_time_s:
        return None
    check = check_plan(route, paper, vehicle, window_m=window_m, force_margin=force_margin, keep_contact=keep_contact)
    if not check.passes:
        return None
    note = (f"dynamic model: the SBEM:TF plan ({paper.travel_time_s:.4g} s) was faster than the capped starts "
            f"({travel_time_s:.4g} s) and holds within {check.worst_ratio * (1 - force_margin):.4g} of the force "
            "limit" + (" and of the wheel's load" if keep_contact else "") + " in the exact simulation: it is the plan")
    return _as_dynamic(paper, check, (note,), force_margin=force_margin, keep_contact=keep_contact)
