"""The minimum-time speed profile along a route: the orchestration of one plan.

1. Cut the route into segments and measure each one's roughness (:mod:`.segments`).
2. Ask every limit (:mod:`.limits`) what it allows: speed bands and caps per segment,
   acceleration bounds, a jerk bound.
3. Choose one band per segment for the whole route and compute the exact minimum-time
   profile for it by a forward-backward pass (:mod:`.bands`); with smoothing and jerk off
   that is already the optimum (status ``exact``).
4. Otherwise polish it by solving the NLP in the squared speed b = v^2 (:mod:`.nlp`) with
   the back end the solver options name, IPOPT by default (:mod:`.nlp.backends`; with
   FATROP a long route in exact pieces, :mod:`.nlp.pieces`); check the solution independently and, if
   no solver gave a usable one, fall back to a slower profile that keeps every limit
   (:mod:`.fallback`).
5. Build the :class:`~.result.Profile` and check it once more against every limit.
6. Drive it in the exact simulation ``verify`` uses (:mod:`.gate`) and, where the force goes
   over the limit, plan again from step 2 with the gate's caps on the stretches that caused
   it, until the simulation holds: a plan is never returned that its own gate rejects.
"""

from __future__ import annotations

import dataclasses
import math
import time
from typing import TYPE_CHECKING, Callable, Sequence

import numpy as np

from ..core.binding import binding_labels
from ..core.kinematics import segment_accel_mps2, segment_time_s
from ..core.path import SegmentPath, segment_path
from ..core.profile import Profile
from ..core.segments import (
    DEFAULT_ROUGHNESS_WINDOW_M,
    DEFAULT_SEGMENT_LENGTH_M,
    Segments,
    roughness_source,
    segment_route,
)
from ..core.vehicle import PLAUSIBLE_RANGES, require_vehicle, vehicle_reference
from ..defaults import (
    DEFAULT_PATH_TOLERANCE_M,
    DEFAULT_REFINE,
    DEFAULT_SIMULATION_GATE,
    DEFAULT_SMOOTHING,
    PLAN_BANDS,
    PLAN_METHODS,
)
from ..errors import InfeasibleError, InputError, PlanningError
from ..physics.forces import DEFAULT_MODEL, get_model
from ..physics.simulate import MAX_STEPS, TooLongToSimulate
from ..physics.speeds import SpeedBands
from ..progress import NO_PROGRESS, Progress
from .bands import BandChoice, DrivePower, choose_bands, snap_to_band
from .fallback import fallback_choice
from .gate import MAX_GATE_ROUNDS, gate_applies, gate_note, run_gate
from .limits import Limit, PlanContext, default_limits
from .nlp.pieces import choose_cuts, cut_scores, solve_pieces
from .nlp.problem import Scaling, family_rows, objective_s, row_bounds
from .nlp.solve import solve_nlp
from .options import SolverOptions
from .refine import REFINE_AT_CAP, SPLIT_MAX_FACTOR, can_split_to, refined_segments, split_long_segments

if TYPE_CHECKING:
    from ..core.route import Route
    from ..core.vehicle import Vehicle
    from ..terrain.geometry import RouteGeometry

__all__ = ["plan", "DEFAULT_SMOOTHING", "PLAN_BANDS", "MIN_JERK_MPS3", "REFINE_AT_CAP"]

#: The smallest jerk bound (m/s^3) a plan accepts: the smallest a vehicle file may give
#: (:data:`profileopt.core.vehicle.PLAUSIBLE_RANGES`). Below it the jerk-limited profile crawls (a
#: bound of 1e-13 left no usable profile at all, 1e-50 one standing still for ever).
MIN_JERK_MPS3 = PLAUSIBLE_RANGES["max_jerk_mps3"][0]


def _validate_options(vehicle: "Vehicle", smoothing: float, max_jerk_mps3: float, v0_mps: float,
                      vend_mps: float, method: str, band: str, refine: bool) -> None:
    if not (math.isfinite(smoothing) and smoothing >= 0):
        raise InputError(f"smoothing = {smoothing!r}: must be a finite number >= 0 (0 is pure minimum time)")
    if math.isnan(max_jerk_mps3) or not max_jerk_mps3 > 0:
        raise InputError(f"max_jerk_mps3 = {max_jerk_mps3!r} m/s^3: must be > 0 ('inf' turns the jerk limit off)")
    if max_jerk_mps3 < MIN_JERK_MPS3:
        raise InputError(f"max_jerk_mps3 = {max_jerk_mps3:g} m/s^3 is too small to move the vehicle in a useful time; "
                         f"give at least {MIN_JERK_MPS3:g} m/s^3 ('inf' turns the jerk limit off)")
    for name, value in (("v0_mps", v0_mps), ("vend_mps", vend_mps)):
        if not (math.isfinite(value) and value >= 0):
            raise InputError(f"{name} = {value!r} m/s: must be a finite speed >= 0")
        if value > vehicle.max_speed_mps:
            raise InputError(f"{name} = {value:g} m/s is above the vehicle's max_speed_mps = "
                             f"{vehicle.max_speed_mps:g} m/s; give a lower boundary speed")
    if method not in PLAN_METHODS:
        raise InputError(f"method = {method!r}: choose {' or '.join(repr(m) for m in PLAN_METHODS)}")
    if band not in PLAN_BANDS:
        raise InputError(f"band = {band!r}: choose one of {', '.join(repr(b) for b in PLAN_BANDS)}")
    if not isinstance(refine, (bool, np.bool_)):  # "no" would be true
        raise InputError(f"refine = {refine!r}: must be True or False")


def plan(
    route: "Route",
    vehicle: "Vehicle",
    *,
    segment_length_m: float = DEFAULT_SEGMENT_LENGTH_M,
    roughness_window_m: float = DEFAULT_ROUGHNESS_WINDOW_M,
    path_tolerance_m: float | None = DEFAULT_PATH_TOLERANCE_M,
    model: str = DEFAULT_MODEL,
    smoothing: float = DEFAULT_SMOOTHING,
    max_jerk_mps3: float | None = None,
    v0_mps: float = 0.0,
    vend_mps: float = 0.0,
    method: str = "auto",
    band: str = "all",
    extra_limits: Sequence[Limit] = (),
    solver_options: SolverOptions | None = None,
    refine: bool = DEFAULT_REFINE,
    simulation_gate: bool = DEFAULT_SIMULATION_GATE,
    force_margin: float = 0.0,
    keep_contact: bool = False,
    progress: Progress = NO_PROGRESS,
) -> Profile:
    """The fastest smooth speed profile along ``route`` that keeps every limit.

    Parameters
    ----------
    route : Route
        The terrain samples (and speed limits) of the route.
    vehicle : Vehicle
        The vehicle: quarter car, force limits, top speed, acceleration and jerk bounds.
    segment_length_m : float, default 5
        Length of the segments (m): the planning resolution. Each segment's speeds are
        admissible for every roughness window that shares a point with it, so where the
        segments fall does not decide what is safe.
    roughness_window_m : float, default 5
        Roughness window length W (m): the force limit holds, for every stretch [a, a + W]
        of the route (a at every sample), at every speed driven inside it, for that
        stretch's own RI (docs/paper-notes.md, "Roughness windows"). The grade is measured
        over twice this length (:mod:`profileopt.terrain.geometry`).
    path_tolerance_m : float or None, default None (:data:`~profileopt.defaults.DEFAULT_PATH_TOLERANCE_M`)
        How far (m) the smoothed path whose curvature limits the speed in turns may stray
        from the route's x, y samples (:func:`profileopt.terrain.geometry.smooth_path`). None
        estimates it from the route's own x, y: their noise sigma times sqrt(2 ln n), at least
        :data:`~profileopt.defaults.MIN_PATH_TOLERANCE_M`
        (:func:`profileopt.terrain.geometry.estimate_path_noise`); the profile's settings and
        summary say which it was. Ignored for an ``s,z`` route. A turn sharper than the
        vehicle's ``min_turn_radius_m`` (a reversal always is) is planned at a crawl, with a
        note naming where.
    model : str, default :data:`~profileopt.physics.forces.DEFAULT_MODEL` (``"sbem_tf"``)
        Force model: ``"sbem_tf"``, ``"sbem_ef"``, ``"iecm"`` or ``"prev_bem"`` (the paper's,
        from the roughness index), or ``"dynamic"``: the transmitted force of the quarter car
        simulated on the route's own samples held within the limit, for offline plans over
        measured terrain (:mod:`profileopt.planning.dynamic`).
    smoothing : float, default :data:`DEFAULT_SMOOTHING` (0.01)
        Weight w of the comfort term: the objective is travel time + w * integral of
        (jerk / 1 m/s^3)^2 dt, both in seconds. 0 is pure minimum time.
    max_jerk_mps3 : float, optional
        Jerk bound (m/s^3); ``None`` takes the vehicle's ``max_jerk_mps3``, ``inf`` turns
        it off.
    v0_mps, vend_mps : float, default 0
        Speed at the start and at the end of the route (m/s).
    method : {"auto", "nlp"}, default "auto"
        ``"auto"`` returns the exact forward-backward profile without solving the NLP when
        it is provably optimal (smoothing 0, no jerk bound, no friction rows), else solves
        the NLP; ``"nlp"`` always solves the NLP (for benchmarks and tests of the NLP
        itself). Which solver solves it is ``solver_options.nlp_solver``.
    band : {"all", "first", "largest"}, default "all"
        Which admissible speed bands each segment may use: ``"all"``, any band, chosen
        over the whole route (a resonant vehicle may cross washboard above resonance);
        ``"first"``, only the band that starts at rest (docs/paper-notes.md, "Which root":
        safe for a vehicle that may have to slow down anywhere); ``"largest"``, only the
        highest band (a vehicle that stays above resonance).
    extra_limits : sequence of Limit, default ()
        Limits of your own, kept beside the default ones (force, speed caps, acceleration,
        jerk; :func:`profileopt.planning.limits.default_limits`).
    solver_options : SolverOptions, optional
        How the NLP is solved (pieces, IPOPT options); default ``SolverOptions()``.
    refine : bool, default True (:data:`profileopt.defaults.DEFAULT_REFINE`)
        Choose the bands, then cut every segment where the minimum-time profile comes within
        :data:`REFINE_AT_CAP` of its band's top, set by the force, wherever its windows'
        roughness changes (:func:`profileopt.planning.refine.refine_segments`), and every
        segment where it comes that close to a step's cap, a speed limit or a sharp turn's crawl
        just outside the step's ramp, the limit's zone or the turn
        (:func:`profileopt.planning.refine.stretch_cuts`), choose the bands again on those
        segments, and solve once.
        A segment is held to every window that shares a point with it, so without this the
        travel time converges only to first order in ``segment_length_m``; with it, it hardly
        depends on it (docs: guide/planning.md, "Choosing --segment-length"), for more segments. False plans
        on the uniform segments asked for (one band choice; the profile has exactly their
        boundaries).
    simulation_gate : bool, default True (:data:`profileopt.defaults.DEFAULT_SIMULATION_GATE`)
        Drive the plan in the exact simulation ``verify`` uses and, where the force goes over
        the limit, plan again with lower caps there (:mod:`profileopt.planning.gate`; model
        ``sbem_tf``). False returns the model's plan as it is: for studies of the force
        models themselves (:func:`profileopt.studies.safety.safety_study`). The ``dynamic``
        model is the simulation: it refuses False.
    force_margin : float, default 0
        Share of the force limit kept in reserve by the ``dynamic`` model (dimensionless, in
        [0, 1)): its simulated force is held within (1 - force_margin) of the limit, for
        error in the measured profile. Other models refuse a margin other than 0.
    keep_contact : bool, default False
        With the ``dynamic`` model, also keep the simulated wheel on the ground
        (F_T >= -m g, where the linear quarter car holds); other models refuse True.
    progress : Progress, default :data:`profileopt.progress.NO_PROGRESS`
        Told the steps of the plan as they start (cutting the route, the path, the speed
        bands, refining, solving, each round of the simulation gate): for a display of
        progress (:func:`profileopt.progress.terminal_progress`).

    Returns
    -------
    Profile
        ``status`` says how it was obtained; a profile is never returned that breaks a
        force, speed, acceleration or jerk limit, nor (model ``sbem_tf``) one whose exact
        simulation goes over the force limit (:mod:`profileopt.planning.gate`; on an assumed
        roughness, the ground ``verify`` drives by default; a note says where the gate
        lowered the speed).

    Raises
    ------
    InputError
        Bad options or a route too sparsely sampled for its segments.
    InfeasibleError
        No profile keeps every limit (an impassable segment, unreachable boundary speeds).
    PlanningError
        The NLP could not be solved and no limit-keeping fallback profile exists, or the
        simulation gate could not bring the plan within the force limit in
        :data:`~profileopt.planning.gate.MAX_GATE_ROUNDS` rounds (please report it).
    """
    t_start = time.perf_counter()
    vehicle = require_vehicle(vehicle, "plan")
    jerk = vehicle.max_jerk_mps3 if max_jerk_mps3 is None else float(max_jerk_mps3)
    limits = (*default_limits(vehicle, model=model, max_jerk_mps3=jerk), *extra_limits)  # refuses a bad model
    _validate_options(vehicle, smoothing, jerk, v0_mps, vend_mps, method, band, refine)
    options = SolverOptions() if solver_options is None else solver_options
    timings: dict[str, float] = {}
    dynamic = model == "dynamic"
    if not (isinstance(force_margin, (int, float)) and 0.0 <= force_margin < 1.0):
        raise InputError(f"force_margin = {force_margin!r}: must be a number from 0 to below 1 (a share of the force "
                         "limit)")
    if force_margin and not dynamic:
        raise InputError(f"force_margin = {force_margin:g} applies to the dynamic model (model='dynamic'); the "
                         f"{get_model(model).label} model has its own margins in its force formula")
    if keep_contact and not dynamic:
        raise InputError(f"keep_contact applies to the dynamic model (model='dynamic'), not {get_model(model).label}")
    if dynamic:
        from .dynamic import check_dynamic_route

        check_dynamic_route(route, simulation_gate)
    gate = simulation_gate and gate_applies(model)
    once_steps = 4 if refine else 2  # the speed bands (again after refining), refining, solving
    progress.expect(2 + once_steps + (1 if gate else 0))
    progress.step(f"cutting {route.length_m:.0f} m into segments, measuring their roughness")
    seg = segment_route(route, vehicle, segment_length_m, roughness_window_m=roughness_window_m)
    timings["segment"] = time.perf_counter() - t_start

    t = time.perf_counter()
    progress.step("finding the path's turns and grades")
    from ..terrain.geometry import route_geometry  # scipy: only when a plan is made

    geometry = route_geometry(route, tolerance_m=path_tolerance_m, grade_scale_m=2.0 * seg.roughness_window_m,
                              min_turn_radius_m=vehicle.min_turn_radius_m)
    timings["path"] = time.perf_counter() - t

    def once(limits: tuple[Limit, ...]) -> Profile:
        return _plan_once(route, vehicle, limits, seg=seg, geometry=geometry, options=options, jerk=jerk,
                          model=model, smoothing=smoothing, v0_mps=v0_mps, vend_mps=vend_mps, method=method,
                          band=band, refine=refine, segment_length_m=segment_length_m,
                          roughness_window_m=roughness_window_m, path_tolerance_m=path_tolerance_m,
                          timings=timings, progress=progress)

    profile = once(limits)
    try:
        if dynamic:  # the force is the simulated response: gate the kinematic optimum (and a second start)
            from .dynamic import plan_dynamic

            def sbem_tf() -> Profile:
                return plan(route, vehicle, segment_length_m=segment_length_m, roughness_window_m=roughness_window_m,
                            path_tolerance_m=path_tolerance_m, model="sbem_tf", smoothing=smoothing,
                            max_jerk_mps3=max_jerk_mps3, v0_mps=v0_mps, vend_mps=vend_mps, method=method, band=band,
                            extra_limits=extra_limits, solver_options=solver_options, refine=refine,
                            simulation_gate=True, progress=progress)

            profile = plan_dynamic(profile, once, limits, route, vehicle, window_m=seg.roughness_window_m,
                                   timings=timings, fallback=sbem_tf, force_margin=float(force_margin),
                                   keep_contact=bool(keep_contact), progress=progress, once_steps=once_steps)
        elif gate:  # drive it in the exact simulation; cap where it goes over
            profile = _gate(profile, once, limits, route, vehicle, seg.roughness_window_m, timings, progress,
                            once_steps)
    except TooLongToSimulate as exc:  # the gate cannot check it: say why in the plan's terms
        raise InfeasibleError(_too_slow_message(route.source, exc)) from None
    timings["total"] = time.perf_counter() - t_start
    return dataclasses.replace(profile, timings_s=dict(timings))


def _too_slow_message(source: str, exc: TooLongToSimulate) -> str:
    """Why a plan too slow for the exact simulation is refused, in the plan's terms: how long
    it takes, its slowest segment, and what to change."""
    (a, b), (va, vb) = exc.segment_m, exc.speeds_mps
    i = exc.slowest
    ends = [name for name, here in (("v0_mps", i == 0), ("vend_mps", i == exc.segments - 1)) if here]
    if ends and min(va, vb) <= 1e-3 * max(va, vb):  # from or to (almost) a standstill at an end: 2 L / v
        remedy = f"raise {' or '.join(ends)} or use shorter segments (segment_length_m)"
    elif min(va, vb) <= 1e-3 * max(va, vb):
        remedy = "use shorter segments (segment_length_m): the plan comes almost to a standstill there"
    else:
        remedy = "the limits allow almost no speed there: check the route's samples and the vehicle's limits"
    return (f"{source}: the plan takes {exc.total_s:.4g} s, {exc.segment_s:.4g} s of it on segment {i} ({a:g} to "
            f"{b:g} m, {va:.3g} to {vb:.3g} m/s): too slow for the exact simulation that checks every plan (at most "
            f"{MAX_STEPS:,} steps of {exc.time_step_s:.3g} s); {remedy}")


def _gate(profile: Profile, once: "Callable[[tuple[Limit, ...]], Profile]", limits: tuple[Limit, ...],
          route: "Route", vehicle: "Vehicle", window_m: float, timings: dict[str, float],
          progress: Progress = NO_PROGRESS, once_steps: int = 0) -> Profile:
    """Simulate ``profile`` and, while it goes over the force limit, plan again with the
    gate's caps (:mod:`.gate`); the last profile, with a note when the gate capped anything.
    ``progress`` is told each simulation; ``once_steps``: the steps of one plan."""
    run = run_gate(profile, once, limits, route, vehicle, window_m, timings, progress, once_steps)
    if not run.check.passes:
        raise PlanningError(
            f"{route.source}: after {MAX_GATE_ROUNDS} rounds of lowering the speed, the exact simulation is "
            f"still over the force limit ({run.check.worst_ratio:.4g} of it at s = {run.check.worst_s_m:.6g} m); "
            "please report this with the route and vehicle")
    note = gate_note(run)
    return run.profile if note is None else dataclasses.replace(run.profile, notes=(*run.profile.notes, note))


def _plan_once(route: "Route", vehicle: "Vehicle", limits: tuple[Limit, ...], *, seg: Segments,
               geometry: "RouteGeometry", options: SolverOptions, jerk: float, model: str, smoothing: float,
               v0_mps: float, vend_mps: float, method: str, band: str, refine: bool, segment_length_m: float,
               roughness_window_m: float, path_tolerance_m: float | None, timings: dict[str, float],
               progress: Progress = NO_PROGRESS) -> Profile:
    """One plan with ``limits`` on the segments ``seg`` (refined inside) and the route's
    ``geometry``: the steps of :func:`plan` after the route was cut and its geometry found;
    the other arguments as :func:`plan`'s. Adds to ``timings`` (s) and tells ``progress``
    its steps."""
    v0_requested, vend_requested = v0_mps, vend_mps
    refine_note = split_note = ""
    split_asked = not refine  # with refine, segments too long for a power-limited climb are cut first
    while True:  # twice with refine: on the segments asked for, then on the refined ones
        t = time.perf_counter()
        progress.step(f"speed bands of {seg.count} segments" + (" (refined)" if refine_note else ""))
        path = segment_path(route, seg, geometry)
        timings["path"] = timings.get("path", 0.0) + time.perf_counter() - t

        t = time.perf_counter()
        context = PlanContext(route=route, vehicle=vehicle, segments=seg, path=path)
        speed_sets, band_source = _speed_bands(limits, context)
        cap, cap_source = _speed_caps(limits, context)
        all_bands = speed_sets.capped(cap)  # every band, for reports and messages
        if band == "first":
            usable = speed_sets.first_band_only().capped(cap)
        elif band == "largest":
            usable = speed_sets.largest_band_only().capped(cap)
        else:
            usable = all_bands
        timings["bands"] = timings.get("bands", 0.0) + time.perf_counter() - t

        t = time.perf_counter()
        decel, accel, decel_source, accel_source = _accel_bounds(limits, context)
        _check_grades(route.source, seg, path, decel, accel, limits, accel_source, decel_source)
        rows = _nlp_rows(limits, context, cap, decel, accel)
        # the forward pass keeps the power limit only where it can bind (it then has NLP rows);
        # elsewhere the acceleration bounds imply it and the vectorised pass stays exact
        power = _drive_power(limits, context) if "power" in rows else None
        jerk_bound = min(limit.jerk_bound_mps3(context) for limit in limits)
        notes = list(seg.notes)
        v0_mps, note_v0 = snap_to_band(v0_requested, usable.lower_mps[0], usable.upper_mps[0],
                                       int(usable.count[0]), "v0_mps")
        vend_mps, note_vend = snap_to_band(vend_requested, usable.lower_mps[-1], usable.upper_mps[-1],
                                           int(usable.count[-1]), "vend_mps")
        notes += [note for note in (note_v0, note_vend) if note]
        coarse = _coarse_power_segments(power, seg)
        if coarse and not split_asked:
            split_asked = True
            budget = SPLIT_MAX_FACTOR * max(seg.count, math.ceil(route.length_m / DEFAULT_SEGMENT_LENGTH_M))
            finer = split_long_segments(seg, power.longest_exact_segment_m(), route.s_m, vehicle,
                                        max_segments=budget)
            if finer is not seg:
                split_note = (f"the power-limited climb {coarse} planned on shorter segments "
                              f"({seg.count} -> {finer.count} segments)")
                seg = finer
                progress.expect(1)  # the speed bands again, on the shorter segments
                continue
        try:
            chosen = choose_bands(usable.lower_mps, usable.upper_mps, usable.count, seg.length_m, accel, decel,
                                  v0_mps, vend_mps, seg.boundaries_m, power)
        except InfeasibleError as exc:  # name the route, as every input message does
            if coarse and can_split_to(seg, power.longest_exact_segment_m(), route.s_m):
                raise InfeasibleError(f"{route.source}: no profile found, but the segments are too long for the "
                                      f"power-limited climb {coarse}: use segment_length_m <= "
                                      f"{_shortest_exact(power, seg):.3g} m there and plan again") from None
            grip = _grip_holds(limits, accel_source)
            stall = _stall_message(exc, seg, path, accel, grip)
            if stall:  # a climb the drive cannot hold explains it: say that, not the generic bound
                raise InfeasibleError(f"{route.source}: {stall}") from None
            raise InfeasibleError(f"{route.source}: {exc}{_grade_hint(exc, seg, path, decel, accel, grip)}") from None
        timings["choose"] = timings.get("choose", 0.0) + time.perf_counter() - t
        if not refine or refine_note:
            break
        # cut where the profile meets the force's cap and the roughness changes, or a step's,
        # a speed limit's or a sharp turn's cap (refine.py); then the bands are chosen again
        t = time.perf_counter()
        progress.step("refining the segments where the plan meets a cap")
        band_top = usable.upper_mps[np.arange(seg.count), chosen.band]
        finer = refined_segments(limits, context, chosen.greatest_b, band_top, cap, cap_source)
        timings["refine"] = time.perf_counter() - t
        if finer is seg:
            break
        refine_note = (f"refined: {finer.count - seg.count} segments added where the plan meets the force's cap "
                       f"and the roughness changes, or a step's, a speed limit's or a sharp turn's cap "
                       f"({seg.count} -> {finer.count})")
        seg = finer
    if split_note:
        notes.append(split_note + ("" if coarse else ", which plan it exactly"))
    if refine_note:
        notes.append(refine_note)
    if coarse:
        exact = _shortest_exact(power, seg)
        if can_split_to(seg, power.longest_exact_segment_m(), route.s_m):
            fix = f"segment_length_m <= {exact:.3g} m plans it exactly"
        else:
            fix = f"the route's samples are too far apart there for segments that plan it exactly ({exact:.3g} m)"
        notes.append(f"the segments are longer than the power-limited climb {coarse} resolves exactly: the plan "
                     f"keeps every limit but may be slower than the optimum; {fix}")

    iterations = pieces = 0
    solver = ""
    progress.step(f"solving the plan on {seg.count} segments")
    if method == "auto" and smoothing == 0 and not math.isfinite(jerk_bound) and "friction" not in rows:
        b, status, success = chosen.greatest_b, "exact", True
    else:
        result = _solve_nlp(seg, chosen, decel, accel, smoothing, jerk_bound, options, rows)
        b, status, iterations, pieces = result.b, result.status, result.iterations, result.pieces
        solver = result.solver
        timings.update(result.timings)
        if result.solver.startswith("ipopt (") and status == "optimal":  # IPOPT took over: worth knowing
            notes.append(f"IPOPT solved the NLP{result.solver.removeprefix('ipopt')}")
        success = status == "optimal"
        if success:
            worst = {"speed": chosen.violation(b)}
            for limit in limits:
                worst[limit.name] = max(worst.get(limit.name, 0.0), limit.violation(context, b))
            if max(worst.values()) > options.check_rtol:
                status, success = f"solution breaks a limit ({max(worst, key=worst.get)})", False
        if not success:
            notes.append(f"the NLP solver gave no usable solution ({status}); returning a slower profile that keeps "
                         "every limit")
            inner_cap, inner_decel, inner_accel = cap, decel, accel
            for limit in limits:  # tighten the caps and bounds until no NLP row is needed
                inner = limit.inner_bounds(context, inner_cap, inner_decel, inner_accel)
                if inner is not None:
                    inner_cap, inner_decel, inner_accel = inner
            inner_usable = usable.capped(inner_cap)
            chosen = fallback_choice(inner_usable, seg.length_m, seg.boundaries_m, inner_decel, inner_accel,
                                     jerk_bound, v0_mps, vend_mps, power)
            b = chosen.greatest_b
            status, pieces = f"fallback: {status}", 0
    b = np.clip(b, chosen.lower_b, chosen.upper_b) if success else b
    settings = {
        "vehicle": vehicle_reference(vehicle) or "unnamed", "model": model,
        "segment_length_m": float(segment_length_m), "roughness_window_m": float(roughness_window_m),
        **geometry.settings, "smoothing": float(smoothing),
        "max_speed_mps": vehicle.max_speed_mps, "max_accel_mps2": vehicle.max_accel_mps2,
        "max_decel_mps2": vehicle.max_decel_mps2, "max_jerk_mps3": jerk,
        # "bands" is the profile file's key for the band option (kept so files stay readable)
        "v0_mps": float(v0_mps), "vend_mps": float(vend_mps), "method": method, "bands": band,
    }
    settings["refine"] = bool(refine)
    roughness = roughness_source(route, seg.windows)
    if roughness["source"] == "assumed":  # only then: a measured route's file keeps its bytes
        settings["roughness"] = roughness["label"]
    profile = _assemble(seg, b, vehicle, model, all_bands, usable, chosen, cap,
                        force_of=lambda speed: _predicted_force(limits, context, speed))
    row_values = {family: family_rows(family, b, seg.length_m, data) for family, data in rows.items()}
    cap_label = _cap_labels(limits, context, cap, cap_source)
    band_top = usable.upper_mps[np.arange(seg.count), chosen.band]
    seg_label = np.where(band_top >= cap * (1 - 1e-9), cap_label, "force").astype(object)
    binding = binding_labels(
        b, seg.length_m, upper_b=chosen.upper_b,
        upper_label=_boundary_labels(seg_label, chosen.upper_b, band_top),
        accel_mps2=accel, accel_label=np.array([limits[k].binding for k in accel_source], dtype=object),
        decel_mps2=decel,
        decel_label=np.array(["decel" if limits[k].binding == "accel" else limits[k].binding for k in decel_source],
                             dtype=object),
        rows=row_values, jerk_mps3=jerk_bound,
    )
    profile = dataclasses.replace(
        profile, status=status, success=success, objective=objective_s(b, seg.length_m, smoothing),
        iterations=iterations, pieces=pieces, solver=solver, notes=tuple(notes), settings=settings,
        limits=limits, cap_source=cap_source, band_source=band_source, path=path,
        curvature_1pm=path.curvature_1pm, grade_rad=path.grade_rad, binding=binding, roughness=roughness,
    )
    for limit in limits:  # the bands promise every limit; never hand back a breach
        breach = limit.check(profile)
        if breach > options.check_rtol:
            raise PlanningError(
                f"{route.source}: the planned profile breaks the {limit.name} limit (by {breach:.4g} of it) "
                "although every speed was taken from the admissible bands; please report this with the route "
                "and vehicle"
            )
    return profile


def _speed_bands(limits: Sequence[Limit], context: PlanContext) -> tuple[SpeedBands, int]:
    """The one limit's speed bands (or [0, inf) everywhere) and its index in ``limits``."""
    found: list[tuple[int, SpeedBands]] = []
    for k, limit in enumerate(limits):
        sets = limit.speed_bands(context)
        if sets is not None:
            found.append((k, sets))
    if len(found) > 1:
        names = ", ".join(limits[k].name for k, _ in found)
        raise InputError(f"extra_limits: only one limit may give speed bands, but {names} do; "
                         "give the others' limits as speed caps")
    if found:
        return found[0][1], found[0][0]
    n = context.segments.count
    return SpeedBands(lower_mps=np.zeros((n, 1)), upper_mps=np.full((n, 1), np.inf), count=np.ones(n, dtype=int),
                      peaks_mps=np.full((n, 1), np.nan)), -1


def _speed_caps(limits: Sequence[Limit], context: PlanContext) -> tuple[np.ndarray, np.ndarray]:
    """The lowest cap of each segment (m/s) and the index in ``limits`` of the limit giving it."""
    n = context.segments.count
    caps = [(k, cap) for k, limit in enumerate(limits) if (cap := limit.speed_cap_mps(context)) is not None]
    if not caps:
        return np.full(n, np.inf), np.full(n, -1)
    stack = np.vstack([np.broadcast_to(np.asarray(cap, dtype=float), (n,)) for _, cap in caps])
    which = np.argmin(stack, axis=0)
    return stack[which, np.arange(n)], np.array([k for k, _ in caps])[which]


def _accel_bounds(limits: Sequence[Limit], context: PlanContext
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The tightest deceleration (positive on the level) and acceleration bound of each
    segment (m/s^2), and the index in ``limits`` of the limit giving each."""
    n = context.segments.count
    decel, accel = np.full(n, np.inf), np.full(n, np.inf)
    decel_source, accel_source = np.zeros(n, dtype=int), np.zeros(n, dtype=int)
    for k, limit in enumerate(limits):
        bounds = limit.accel_bounds_mps2(context)
        if bounds is not None:
            tighter_d, tighter_a = bounds[0] < decel, bounds[1] < accel
            decel, accel = np.where(tighter_d, bounds[0], decel), np.where(tighter_a, bounds[1], accel)
            decel_source[tighter_d], accel_source[tighter_a] = k, k
    if not (np.all(np.isfinite(decel)) and np.all(np.isfinite(accel))):
        raise InputError("extra_limits: the plan needs finite acceleration and deceleration bounds")
    return decel, accel, decel_source, accel_source


def _check_grades(source: str, seg: Segments, path: SegmentPath, decel: np.ndarray, accel: np.ndarray,
                  limits: Sequence[Limit], accel_source: np.ndarray, decel_source: np.ndarray) -> None:
    """Refuse a segment whose bounds leave no acceleration at all (-decel > accel)."""
    bad = np.flatnonzero(-decel > accel + 1e-12 * np.maximum(np.abs(accel), 1.0))
    if bad.size:
        i = int(bad[0])
        raise InfeasibleError(
            f"{source}: segment {i} ({seg.boundaries_m[i]:g} to {seg.boundaries_m[i + 1]:g} m): its grade changes "
            f"from {math.tan(path.grade_lo_rad[i]):.1%} to {math.tan(path.grade_hi_rad[i]):.1%}, so no acceleration "
            f"keeps both the {limits[accel_source[i]].name} bound ({accel[i]:.3g} m/s^2 at most) and the "
            f"{limits[decel_source[i]].name} bound ({-decel[i]:.3g} m/s^2 at least); use shorter segments "
            "(segment_length_m) or a route with gentler slopes"
        )


def _grip_holds(limits: Sequence[Limit], accel_source: np.ndarray) -> np.ndarray:
    """Per segment, whether the tyres' grip (the friction limit), not the drive, gives the
    acceleration bound, shape (N,)."""
    friction = np.array([limit.name == "friction" for limit in limits], dtype=bool)
    return friction[accel_source]


def _raise_drive(grip: np.ndarray) -> str:
    """What to raise where a climb is steeper than the acceleration bound allows: the grip's
    key where ``grip`` holds anywhere in the stretch, else the drive's."""
    if np.any(grip):
        return "raise friction_coefficient (the grip holds the drive there: a climb of grade G needs mu >= G)"
    return "raise max_accel_mps2 (a climb of grade G needs g sin(atan G))"


def _stall_message(exc: Exception, seg: Segments, path: SegmentPath, accel: np.ndarray, grip: np.ndarray) -> str:
    """"the vehicle stalls at s = ... m on the climb ...", when the profile fell short of 0 m/s
    after a climb the drive (or the grip: ``grip``, per segment) cannot hold ("" otherwise)."""
    at = getattr(exc, "position_m", None)
    if at is None or "must be at least 0 m/s" not in str(exc):
        return ""
    climb = np.flatnonzero((accel < 0) & (seg.boundaries_m[:-1] < at))
    if not climb.size:
        return ""
    last = int(climb[-1])
    first = last
    while first > 0 and accel[first - 1] < 0:
        first -= 1
    holder = "grip" if np.any(grip[first:last + 1]) else "drive"
    return (f"the vehicle stalls at s = {at:g} m on the climb from s = {seg.boundaries_m[first]:g} m (grade up to "
            f"{math.tan(path.grade_hi_rad[first:last + 1].max()):.1%}), steeper than its {holder} can hold: there it "
            f"loses up to {-accel[first:last + 1].min():.3g} m/s^2 at full {holder} and no speed it can reach before "
            f"carries it over; {_raise_drive(grip[first:last + 1])} or choose a gentler route")


def _grade_hint(exc: Exception, seg: Segments, path: SegmentPath, decel: np.ndarray, accel: np.ndarray,
                grip: np.ndarray) -> str:
    """Where the grade makes a route impassable: a climb the drive (or the grip: ``grip``, per
    segment) cannot hold, a descent the brakes cannot hold; appended to an infeasibility
    message ("" if neither)."""
    parts = []
    at = getattr(exc, "position_m", None)
    climb = np.flatnonzero(accel < 0)
    if at is not None:  # the climbs before the place where the profile fell short
        climb = climb[seg.boundaries_m[climb] < at]
    if climb.size:
        i = int(climb[-1]) if at is not None else int(climb[np.argmin(accel[climb])])
        parts.append(f"the climb at s = {seg.boundaries_m[i]:g} m (grade {math.tan(path.grade_hi_rad[i]):.1%}) "
                     f"is steeper than the drive can hold (it slows the vehicle by {-accel[i]:.3g} m/s^2 at full "
                     f"drive; {_raise_drive(grip[i:i + 1])} or choose a gentler route)")
    descent = np.flatnonzero(decel < 0)
    if at is not None and parts:  # a climb explains it; name a descent only when none does
        descent = descent[:0]
    if descent.size:
        i = int(descent[np.argmin(decel[descent])])
        parts.append(f"the descent at s = {seg.boundaries_m[i]:g} m (grade {math.tan(path.grade_lo_rad[i]):.1%}) "
                     f"is steeper than the brakes can hold (the vehicle speeds up by {-decel[i]:.3g} m/s^2 at full "
                     "braking)")
    return ("; " + " and ".join(parts)) if parts else ""


def _coarse_power_segments(power: DrivePower | None, seg: Segments) -> str:
    """Where segments are too long for the power forward pass to be exact ("at s = a to b m"),
    or "" (:meth:`DrivePower.longest_exact_segment_m`)."""
    if power is None:
        return ""
    coarse = np.flatnonzero(seg.length_m > power.longest_exact_segment_m())
    if not coarse.size:
        return ""
    return f"at s = {seg.boundaries_m[coarse[0]]:g} to {seg.boundaries_m[coarse[-1] + 1]:g} m"


def _shortest_exact(power: DrivePower, seg: Segments) -> float:
    """The longest segment length (m) that keeps the power forward pass exact everywhere."""
    return float(np.min(power.longest_exact_segment_m()))


def _drive_power(limits: Sequence[Limit], context: PlanContext) -> DrivePower | None:
    """The one drive power limit of the plan, or None."""
    found = [p for limit in limits if (p := limit.drive_power(context)) is not None]
    if len(found) > 1:
        raise InputError("extra_limits: only one limit may give a drive power limit")
    return found[0] if found else None


def _nlp_rows(limits: Sequence[Limit], context: PlanContext, cap: np.ndarray, decel: np.ndarray,
              accel: np.ndarray) -> dict[str, np.ndarray]:
    """The row families the NLP needs, with their per-segment data, in the limits' order."""
    rows: dict[str, np.ndarray] = {}
    for limit in limits:
        found = limit.nlp_rows(context, cap, decel, accel)
        if found is not None:
            family, data = found
            if family in rows:
                raise InputError(f"extra_limits: two limits give NLP rows of the family {family!r}")
            rows[family] = data
    return rows


def _cap_labels(limits: Sequence[Limit], context: PlanContext, cap: np.ndarray, cap_source: np.ndarray
                ) -> np.ndarray:
    """The ``binding`` name of each segment's lowest cap, shape (N,)."""
    labels = np.full(cap.shape, "top_speed", dtype=object)
    for k in np.unique(cap_source):
        if k >= 0:
            where = cap_source == k
            labels[where] = limits[int(k)].cap_binding(context, cap)[where]
    return labels


def _boundary_labels(seg_label: np.ndarray, upper_b: np.ndarray, band_top_mps: np.ndarray) -> np.ndarray:
    """The ``binding`` name of each boundary's upper bound: that of the segment beside it
    whose band top is the lower, shape (N+1,)."""
    top2 = band_top_mps**2
    left = np.concatenate([[seg_label[0]], seg_label])
    right = np.concatenate([seg_label, [seg_label[-1]]])
    left_top = np.concatenate([[np.inf], top2])
    right_top = np.concatenate([top2, [np.inf]])
    return np.where(left_top <= right_top, left, right).astype(object)


@dataclasses.dataclass(frozen=True)
class _NlpResult:
    b: np.ndarray  # (N+1,) squared speeds, m^2/s^2
    status: str
    iterations: int  # NLP solver iterations, all solves together
    pieces: int  # NLP solves whose solutions make up b
    timings: dict[str, float]
    solver: str  # NlpResult.solver of a whole-route solve; for pieces, the same form


def _accel_scale(accel: np.ndarray, decel: np.ndarray) -> float:
    """The NLP's acceleration scale (m/s^2): the largest acceleration bound, or, where a climb
    leaves none positive, the largest bound in size (a scale must be > 0)."""
    top = float(accel.max())
    return top if top > 0 else max(float(np.max(np.abs(accel))), float(np.max(np.abs(decel))), 1e-9)


def _solve_nlp(seg: Segments, chosen: BandChoice, decel: np.ndarray, accel: np.ndarray, smoothing: float,
               jerk: float, options: SolverOptions, rows: dict[str, np.ndarray]) -> _NlpResult:
    """The NLP's optimum over the chosen bands (:func:`~.solve.solve_nlp`): in pieces on a long
    route when the back end asks for them (exact, checked), else whole."""
    n = seg.count
    with_jerk = math.isfinite(jerk)
    scaling = Scaling(b_ref=max(float(chosen.upper_b.max()), 1e-6), l_ref=float(seg.length_m.mean()),
                      a_ref=_accel_scale(accel, decel), weight=smoothing, inv_jerk=1.0 / jerk if with_jerk else 0.0,
                      t_whole=max(objective_s(chosen.greatest_b, seg.length_m, 0.0), 1e-6))
    timings = {"build": 0.0, "solve": 0.0}
    iterations = 0
    if n > max(options.split_threshold(), options.piece_size()):
        score = cut_scores(chosen.upper_b, chosen.greatest_b, seg.length_m)
        cuts = choose_cuts(score, options.piece_size())
        if cuts.size:
            b, iterations, pieces, taken_over = solve_pieces(seg.length_m, chosen, decel, accel, scaling, with_jerk,
                                                             score, cuts, options, timings, rows)
            if b is not None:
                solver = (f"ipopt (the {options.nlp_solver} solver stopped on {taken_over} of {pieces} pieces)"
                          if taken_over else options.nlp_solver)
                return _NlpResult(b, "optimal", iterations, pieces, timings, solver)

    families = tuple(rows)
    b_ref = scaling.b_ref
    lbg, ubg = row_bounds(with_jerk and n >= 2, decel, accel, scaling.a_ref, families)
    data = np.column_stack(list(rows.values())) if rows else None  # the row families' data
    result = solve_nlp(n, with_jerk, families, options, chosen.greatest_b / b_ref, chosen.lower_b / b_ref,
                       chosen.upper_b / b_ref, seg.length_m / scaling.l_ref, lbg, ubg, scaling.tail(scaling.t_whole),
                       data, timings=timings)
    return _NlpResult(result.y * b_ref, result.status, iterations + result.iterations, 1, timings, result.solver)


def _predicted_force(limits: Sequence[Limit], context: PlanContext, speed_mps: np.ndarray) -> np.ndarray:
    """The largest force predicted over each segment (N): the limit's that predicts one, else 0
    (the dynamic model's force is simulated once the plan is made, planning.dynamic)."""
    for limit in limits:
        force = limit.predicted_force_n(context, speed_mps)
        if force is not None:
            return force
    return np.zeros(context.segments.count)


def _assemble(seg: Segments, b: np.ndarray, vehicle: "Vehicle", model: str, all_bands: SpeedBands,
              usable: SpeedBands, chosen: BandChoice, cap: np.ndarray, *,
              force_of: Callable[[np.ndarray], np.ndarray]) -> Profile:
    """The Profile of squared speeds b: per-row arrays, the largest force per segment
    (``force_of(speed)``), and the allowable speeds under both semantics from ``all_bands``
    (every band, capped)."""
    speed = np.sqrt(np.maximum(b, 0.0))
    accel = segment_accel_mps2(b[:-1], b[1:], seg.length_m)
    dt = segment_time_s(speed[:-1], speed[1:], seg.length_m)
    time_s = np.concatenate([[0.0], np.cumsum(dt)])
    force = force_of(speed)
    rows = np.arange(seg.count)

    def per_row(x: np.ndarray) -> np.ndarray:
        return np.append(x, x[-1])

    return Profile(
        s_m=seg.boundaries_m,
        speed_mps=speed,
        accel_mps2=per_row(accel),
        time_s=time_s,
        ri=per_row(seg.ri),
        e_max_m=per_row(seg.e_max_m),
        force_n=per_row(force),
        force_limit_n=np.full(seg.count + 1, get_model(model).limit_n(vehicle)),
        model=model,
        allowable_first_mps=all_bands.first(),
        allowable_largest_mps=all_bands.largest(),
        speed_cap_mps=cap,
        band_lower_mps=usable.lower_mps[rows, chosen.band],
        band_upper_mps=usable.upper_mps[rows, chosen.band],
    )
