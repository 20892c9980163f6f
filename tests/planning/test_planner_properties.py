"""Property-based tests (hypothesis) of the planner over random routes and random vehicles.

Issue 5, "Tests": over random routes (ISO 8608 classes, steps, washboard, constant grades)
and random valid vehicles, every plan satisfies every constraint under a check written here,
independently of the planner:

- the segment boundaries cover the route, and each segment's RI, recomputed from the route
  samples s_i <= s < s_{i+1} with :func:`profileopt.terrain.roughness.roughness_index`, is the one the
  profile reports;
- speeds lie in [0, v_max], and at every route sample the speed, from v(s)^2 linear in s
  between boundaries (constant acceleration), is within that sample's speed_limit;
- accelerations (v_{i+1}^2 - v_i^2) / (2 ds_i) lie in [-max_decel, max_accel];
- the jerk v da/ds = v_j (a_j - a_{j-1}) / ((ds_{j-1} + ds_j) / 2) is within the bound;
- the model's force (:mod:`profileopt.physics.forces`), evaluated over the speeds each segment passes
  through (a fine grid between its two boundary speeds, refined twice around the largest
  value, plus both ends), is within the limit (relative tolerance 1e-6), and the profile's
  reported force_n is not below it;
- the boundary speeds are v0 and vend, and the arrival times are the integral of ds / v.

When the planner says the problem is infeasible, the message must name an option or a
segment; and with v0 = vend = 0 it may say so only when some segment forbids standing still
(force at rest above the limit), since otherwise "stay at rest" keeps every limit.

Each example plans a route of 50-500 m (up to ~150 segments); the ``dev`` and ``ci``
Hypothesis profiles' 30 examples per property keep the file within a few tens of seconds
(the properties that plan are marked ``slow``); ``--hypothesis-profile thorough`` runs 2000
(tests/conftest.py).
"""

from __future__ import annotations

import dataclasses
import math
import re

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, event, given, settings
from hypothesis import strategies as st

from profileopt.terrain import synthetic
from profileopt.errors import InfeasibleError
from profileopt.physics.speeds import allowable_speed
from profileopt.physics.forces import MODELS, get_model
from profileopt.core.segments import MIN_SAMPLES_PER_SEGMENT, segment_route
from profileopt.planning import plan
from profileopt.core.route import Route
from profileopt.terrain.roughness import MIN_SAMPLES_PER_WINDOW, segment_roughness_index
from profileopt.core.vehicle import OPTIONAL_KEYS
from conftest import G, check_turns_and_hills, grade_direct, window_ri, window_speeds
from profileopt.core.vehicle import Vehicle, load_vehicle

RTOL = 1e-6
# The number of examples is the Hypothesis profile's (tests/conftest.py): 30 per property
# by default, ``--hypothesis-profile thorough`` (2000) for a long hunt.
PLANS = settings(deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
BASES = {name: load_vehicle(name) for name in ("atv", "atv-resonant")}

# ------------------------------------------------------------------------------ strategies


@st.composite
def routes(draw: st.DrawFn) -> Route:
    """A random route: ISO 8608 ground, optionally with a step, a washboard stretch or a
    constant grade, and optionally a piecewise-constant speed_limit column."""
    spacing = draw(st.sampled_from([0.05, 0.1, 0.2, 0.25, 0.5]))
    length = draw(st.floats(50.0, 500.0))
    seed = draw(st.integers(0, 2**16))
    road_class = draw(st.sampled_from("ABCDE"))
    n_max = min(4.0, 0.45 / spacing)  # below the Nyquist frequency 1 / (2 spacing)
    s, z = synthetic.iso8608_profile(road_class, length, spacing, seed, n_max_cpm=n_max)
    feature = draw(st.sampled_from(["none", "step", "washboard", "grade", "all"]))
    if feature in ("step", "all"):
        z = z + synthetic.step(s, draw(st.floats(0.1, 0.9)) * s[-1], draw(st.floats(-0.3, 0.3)))
    if feature in ("washboard", "all"):
        start = draw(st.floats(0.0, 0.7)) * s[-1]
        z = z + synthetic.washboard(s, draw(st.floats(0.002, 0.06)), draw(st.floats(0.3, 3.0)),
                                    start, start + draw(st.floats(0.1, 0.3)) * s[-1])
    if feature in ("grade", "all"):
        z = z + draw(st.floats(-0.3, 0.3)) * s + draw(st.floats(-500.0, 500.0))
    if draw(st.booleans()):  # uneven sampling (as from an x,y polyline), still increasing
        s = s + np.random.default_rng(seed).uniform(-0.3, 0.3, s.size) * spacing
    s = s + draw(st.sampled_from([0.0, 1234.5]))  # a route need not start at s = 0
    x = y = None
    if draw(st.booleans()):  # turns: arcs of random radius and side between straights
        turns = draw(st.lists(st.tuples(st.floats(0.0, 1.0), st.floats(8.0, 200.0), st.sampled_from([-1, 1])),
                              min_size=1, max_size=3))
        kappa = np.zeros(s.size)
        for where, radius, side in turns:
            start = s[0] + where * 0.8 * (s[-1] - s[0])
            kappa[(s >= start) & (s < start + radius * math.pi / 3)] = side / radius
        heading = np.concatenate([[0.0], np.cumsum(0.5 * (kappa[1:] + kappa[:-1]) * np.diff(s))])
        step = np.diff(s)
        x = np.concatenate([[0.0], np.cumsum(step * np.cos(0.5 * (heading[1:] + heading[:-1])))])
        y = np.concatenate([[0.0], np.cumsum(step * np.sin(0.5 * (heading[1:] + heading[:-1])))])
        s = s[0] + np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(x), np.diff(y)))])  # s is the chord length
    limit = None
    if draw(st.booleans()):
        pieces = draw(st.lists(st.floats(1.0, 25.0), min_size=1, max_size=3))
        where = (s - s[0]) / (s[-1] - s[0]) * len(pieces)
        limit = np.asarray(pieces)[np.minimum(where.astype(int), len(pieces) - 1)]
    return Route(s_m=s, z_m=z, speed_limit_mps=limit, source=f"random-{road_class}-{feature}-{seed}", x_m=x, y_m=y)


@st.composite
def vehicles(draw: st.DrawFn) -> Vehicle:
    """The atv or atv-resonant with every parameter perturbed within sane ranges."""
    base = BASES[draw(st.sampled_from(sorted(BASES)))]
    factor = st.floats(0.5, 2.0)
    return base.replace(
        quarter_mass_kg=base.quarter_mass_kg * draw(factor),
        ground_clearance_m=base.ground_clearance_m * draw(factor),
        wheel_radius_m=base.wheel_radius_m * draw(st.floats(0.5, 4.0)),
        natural_frequency_radps=base.natural_frequency_radps * draw(factor),
        damping_ratio=draw(st.floats(0.05, 0.9)),
        confidence=draw(st.sampled_from([0.9, 0.99, 0.9999, 0.999999])),
        max_excitation_force_n=base.max_excitation_force_n * draw(st.floats(0.3, 3.0)),
        max_transmitted_force_n=base.max_transmitted_force_n * draw(st.floats(0.3, 3.0)),
        max_speed_mps=draw(st.floats(3.0, 25.0)),
        max_accel_mps2=draw(st.floats(0.5, 4.0)),
        max_decel_mps2=draw(st.floats(1.0, 8.0)),
        max_jerk_mps3=draw(st.floats(1.0, 20.0)),
        # turns and hills: each limit on or off (all off: no grade in the acceleration bounds)
        max_lateral_accel_mps2=draw(st.one_of(st.none(), st.floats(1.0, 8.0))),
        track_width_m=(track := draw(st.one_of(st.none(), st.floats(0.6, 2.0)))),
        cg_height_m=None if track is None else draw(st.floats(0.3, 1.5)),
        friction_coefficient=draw(st.one_of(st.none(), st.floats(0.2, 1.0))),
        mass_kg=(mass := draw(st.one_of(st.none(), st.floats(300.0, 2000.0)))),
        max_power_w=None if mass is None else draw(st.floats(2000.0, 100000.0)),
    )


@st.composite
def problems(draw: st.DrawFn) -> dict:
    route = draw(routes())
    vehicle = draw(vehicles())
    spacing = float(np.diff(route.s_m).max())
    # at least MIN_SAMPLES_PER_SEGMENT samples per segment, at most ~150 segments
    shortest = max(MIN_SAMPLES_PER_SEGMENT * spacing * 1.01, route.length_m / 150)
    segment = draw(st.one_of(st.floats(shortest, max(shortest, min(20.0, route.length_m))),
                             st.just(route.length_m)))  # or one segment for the whole route
    boundary = st.one_of(st.just(0.0), st.floats(0.0, 1.0).map(lambda f: f * vehicle.max_speed_mps))
    return {
        "route": route,
        "vehicle": vehicle,
        "options": {
            "segment_length_m": segment,
            "model": draw(st.sampled_from(sorted(MODELS))),
            "smoothing": draw(st.sampled_from([0.0, 0.01, 1.0])),
            "max_jerk_mps3": draw(st.one_of(st.sampled_from([None, math.inf]), st.floats(0.3, 30.0))),
            "v0_mps": draw(boundary),
            "vend_mps": draw(boundary),
            "band": draw(st.sampled_from(["all", "first"])),
            "method": draw(st.sampled_from(["auto", "nlp"])),
            "refine": draw(st.booleans()),
        },
    }


# ------------------------------------------------------------------------------ the check


def max_force_between(model: str, v_a: np.ndarray, v_b: np.ndarray, ri: np.ndarray, vehicle: Vehicle,
                      points: int = 129, refinements: int = 2) -> np.ndarray:
    """The largest force of ``model`` over the speeds between v_a[i] and v_b[i] (N), shape (N,):
    a uniform grid, then twice a finer grid over the two grid cells around the largest value
    (a resonance peak is narrower than a coarse grid cell), the ends always included."""
    spec = get_model(model)
    lo, hi = np.minimum(v_a, v_b)[:, None], np.maximum(v_a, v_b)[:, None]
    frac = np.linspace(0.0, 1.0, points)[None, :]
    grid = lo + (hi - lo) * frac
    rr = np.broadcast_to(ri[:, None], grid.shape)
    forces = np.asarray(spec.force_n(grid, rr, vehicle))
    best = forces.max(axis=1)
    for _ in range(refinements):
        k = np.argmax(forces, axis=1)
        rows = np.arange(grid.shape[0])
        left = grid[rows, np.maximum(k - 1, 0)][:, None]
        right = grid[rows, np.minimum(k + 1, grid.shape[1] - 1)][:, None]
        grid = left + (right - left) * frac
        forces = np.asarray(spec.force_n(grid, rr, vehicle))
        best = np.maximum(best, forces.max(axis=1))
    return best


def check_plan(profile, route: Route, vehicle: Vehicle, options: dict) -> None:
    """Assert every constraint of the planning problem on ``profile``, independently."""
    s, v = np.asarray(profile.s_m), np.asarray(profile.speed_mps)
    n = s.size - 1
    assert n >= 1 and s[0] == route.s_m[0] and s[-1] == route.s_m[-1]
    ds = np.diff(s)
    assert np.all(ds > 0)
    # segments cut where asked, except a merged short tail; refined, some of them cut again
    # at samples, every piece keeping MIN_SAMPLES_PER_SEGMENT of them
    asked = segment_route(route, vehicle, options["segment_length_m"]).boundaries_m
    if options["refine"]:  # every caller says (plan refines by default)
        assert np.all(np.isin(asked, s)) and np.all(np.isin(s, asked) | np.isin(s, route.s_m))
        counts = np.diff(np.searchsorted(route.s_m, s, side="left"))
        assert counts[:-1].min(initial=MIN_SAMPLES_PER_SEGMENT) >= MIN_SAMPLES_PER_SEGMENT
    else:
        np.testing.assert_array_equal(s, asked)
        assert np.all(ds[:-1] == pytest.approx(options["segment_length_m"], rel=1e-9))
        assert ds[-1] < 2 * options["segment_length_m"] * (1 + 1e-9)
    # every roughness window, its RI recomputed directly (conftest.window_ri), and the
    # largest of those a segment meets is its ri column
    window_m = float(profile.settings["roughness_window_m"])
    start_m, ri_w = window_ri(route, window_m, vehicle.ground_clearance_m)
    first = np.searchsorted(start_m, s[:-1] - window_m * (1 + 1e-9), side="left")
    stop = np.searchsorted(start_m, s[1:] + 1e-9 * window_m, side="right")
    np.testing.assert_allclose(profile.ri[:-1], [ri_w[a:b].max() for a, b in zip(first, stop)], rtol=1e-6,
                               atol=1e-6)  # atol: see conftest's check_profile

    # speeds
    vmax = vehicle.max_speed_mps
    assert np.all(v >= 0) and np.all(v <= vmax * (1 + RTOL))
    assert v[0] == pytest.approx(options["v0_mps"], rel=RTOL, abs=1e-9 * vmax)
    assert v[-1] == pytest.approx(options["vend_mps"], rel=RTOL, abs=1e-9 * vmax)
    if route.speed_limit_mps is not None:
        # v(s)^2 linear in s between boundaries, evaluated at every route sample
        v2_at_samples = np.interp(route.s_m, s, v**2)
        assert np.all(v2_at_samples <= route.speed_limit_mps**2 * (1 + RTOL) ** 2)

    # acceleration from the squared speeds (constant acceleration within a segment), within
    # its bounds at the segment's grades (conftest.check_turns_and_hills recomputes the
    # grade directly), and the lateral, friction and power limits at every speed and grade
    accel = (v[1:] ** 2 - v[:-1] ** 2) / (2 * ds)
    np.testing.assert_allclose(profile.accel_mps2[:-1], accel, rtol=1e-9, atol=1e-9)
    check_turns_and_hills(profile, route, vehicle, accel, RTOL)

    # jerk = v da/ds at the interior boundaries
    jerk_bound = vehicle.max_jerk_mps3 if options["max_jerk_mps3"] is None else options["max_jerk_mps3"]
    if math.isfinite(jerk_bound) and n >= 2:
        jerk = v[1:-1] * np.diff(accel) / (0.5 * (ds[:-1] + ds[1:]))
        assert np.all(np.abs(jerk) <= jerk_bound * (1 + RTOL)), np.abs(jerk).max()

    # the force over every speed driven inside each window, at that window's own RI
    model = options["model"]
    limit = get_model(model).limit_n(vehicle)
    v_lo, v_hi = window_speeds(s, v, start_m, window_m)
    worst = max_force_between(model, v_lo, v_hi, ri_w, vehicle)
    assert np.all(worst <= limit * (1 + RTOL)), f"force / limit = {worst.max() / limit}"
    assert np.all(profile.force_limit_n == limit)
    assert np.all(profile.force_n <= limit * (1 + RTOL))

    # time: dt = ds / mean speed for constant acceleration
    with np.errstate(divide="ignore"):
        dt = 2 * ds / (v[:-1] + v[1:])
    np.testing.assert_allclose(np.diff(profile.time_s), dt, rtol=1e-9)


#: An infeasibility message names its cause: the end speeds, a segment, or a place (s = 12 m, or
#: a stretch: s = 0 to 48 m, as the power-limited climb's message gives it).
NAMES_THE_CAUSE = re.compile(r"v0_mps|vend_mps|segment \d+|s = [-0-9.e+]+( to [-0-9.e+]+)? m")


@pytest.mark.slow(seconds=12)
@PLANS
@given(problem=problems())
def test_every_plan_keeps_every_limit(problem: dict) -> None:
    route, vehicle, options = problem["route"], problem["vehicle"], problem["options"]
    try:
        profile = plan(route, vehicle, **options)
    except InfeasibleError as exc:
        event("infeasible")
        message = str(exc)
        assert "\n" not in message and NAMES_THE_CAUSE.search(message), message
        # Rest to rest, a crawl (v = 0 at both ends, a tiny speed at every interior boundary)
        # keeps every speed, acceleration and jerk bound; it keeps the force limit iff every
        # segment admits standing still and some speed above it ("first" > 0), and it exists
        # only with at least two segments (one segment from rest to rest never moves). So
        # the planner may then call the problem infeasible only if one of these fails.
        at_rest = dict(options, v0_mps=0.0, vend_mps=0.0)
        boundaries = segment_route(route, vehicle, options["segment_length_m"]).boundaries_m  # where they are
        _, ri = window_ri(route, 5.0, vehicle.ground_clearance_m)  # every window (plan's default W)
        force_at_rest = np.asarray(get_model(options["model"]).force_n(np.zeros_like(ri), ri, vehicle))
        rest_is_admissible = bool(np.all(force_at_rest <= get_model(options["model"]).limit_n(vehicle)))
        crawl_exists = boundaries.size >= 3 and bool(np.all(allowable_speed(ri, vehicle, model=options["model"]) > 0))
        if any(getattr(vehicle, key) is not None for key in OPTIONAL_KEYS):
            # on grades a crawl needs to climb the steepest grade from rest and hold the
            # steepest descent: g sin(theta) within max_accel and max_decel (and within the grip
            # mu g cos(theta)); the grade over twice the roughness window, recomputed directly
            grade = grade_direct(route, 10.0)
            grip = math.inf if vehicle.friction_coefficient is None else vehicle.friction_coefficient
            climb, descent = G * np.sin(grade.max()), -G * np.sin(grade.min())
            crawl_exists = crawl_exists and climb < min(vehicle.max_accel_mps2, grip * G * math.cos(grade.max())) \
                and descent < min(vehicle.max_decel_mps2, grip * G * math.cos(grade.min()))
        try:
            profile = plan(route, vehicle, **at_rest)
        except InfeasibleError as again:
            assert not (rest_is_admissible and crawl_exists), f"infeasible although a crawl keeps every limit: {again}"
            event("infeasible also at rest")
            return
        check_plan(profile, route, vehicle, at_rest)
        return
    event(f"planned: {profile.status.split(':')[0]}")
    assert profile.status in ("exact", "optimal") or profile.status.startswith("fallback"), profile.status
    check_plan(profile, route, vehicle, options)


@pytest.mark.slow
@PLANS
@given(problem=problems(), fraction=st.floats(0.2, 1.0))
def test_braking_further_than_the_route_is_always_infeasible(problem: dict, fraction: float) -> None:
    """The obvious case: from v0 the vehicle needs v0^2 / (2 d) to stop. On the first stretch
    of the route shorter than that, no profile ends at rest (whatever the terrain, vehicle
    and options), so the planner must refuse and say that v0_mps is the cause."""
    route, vehicle, options = problem["route"], problem["vehicle"], dict(problem["options"])
    # on the level (a vehicle without the keys of turns and hills: no grade helps the brakes)
    vehicle = vehicle.replace(max_lateral_accel_mps2=None, track_width_m=None, cg_height_m=None,
                              friction_coefficient=None, mass_kg=None, max_power_w=None)
    decel, spacing = vehicle.max_decel_mps2, float(np.diff(route.s_m).max())
    # the longest stretch from which max_speed / 1.05 can still not stop
    cut = fraction * (vehicle.max_speed_mps / 1.05) ** 2 / (2 * decel)
    assume(cut >= 2 * MIN_SAMPLES_PER_WINDOW * spacing)
    keep = route.s_m <= route.s_m[0] + cut
    limit = None if route.speed_limit_mps is None else route.speed_limit_mps[keep]
    short = Route(route.s_m[keep], route.z_m[keep], limit, source="stretch")
    v0 = 1.05 * math.sqrt(2 * decel * short.length_m)
    options.update(v0_mps=v0, vend_mps=0.0, segment_length_m=short.length_m / 2)
    with pytest.raises(InfeasibleError) as raised:
        plan(short, vehicle, **options)
    # (or, as the planner checks first, a segment that no speed at all may cross)
    assert "v0_mps" in str(raised.value) or "at every speed" in str(raised.value), str(raised.value)


# ------------------------------------------------------------------------------ RI


@settings(deadline=None)
@given(
    seed=st.integers(0, 2**16),
    spacing=st.sampled_from([0.05, 0.1, 0.25]),
    n_segments=st.integers(1, 12),
    offset=st.floats(-1000.0, 1000.0),
    grade=st.floats(-0.5, 0.5),
    scale=st.floats(0.01, 20.0),
)
def test_segment_ri_ignores_offset_and_grade_and_is_linear_in_amplitude(seed, spacing, n_segments, offset, grade,
                                                                        scale):
    """The per-segment RI the planner uses (tests/terrain/test_roughness.py checks the
    one-segment function): adding a constant and a constant grade to the whole route changes
    no segment's RI, and scaling the elevations by c scales every RI by c (Eq. 1 is a
    standard deviation of the detrended elevations over h)."""
    s, z = synthetic.iso8608_profile("C", 10.0 * n_segments, spacing, seed, n_max_cpm=min(4.0, 0.45 / spacing))
    starts = np.searchsorted(s, 10.0 * np.arange(n_segments))
    h = 0.1
    base = segment_roughness_index(s, z, starts, h)
    assert np.all(base > 0)
    np.testing.assert_allclose(segment_roughness_index(s, z + offset + grade * s, starts, h), base, rtol=1e-6)
    np.testing.assert_allclose(segment_roughness_index(s, scale * z, starts, h), scale * base, rtol=1e-9)


# ------------------------------------------------------------------------------ the check itself


@pytest.mark.slow
def test_the_independent_check_catches_broken_plans() -> None:
    """check_plan must be able to fail: a good plan passes; the same plan checked against a
    vehicle with lower limits, or with one speed raised, does not."""
    s, z = synthetic.iso8608_profile("C", 100.0, 0.1, seed=5)
    route = Route(s, z, source="check")
    vehicle = BASES["atv-resonant"].replace(max_lateral_accel_mps2=None, track_width_m=None, cg_height_m=None,
                                            friction_coefficient=None, mass_kg=None, max_power_w=None)
    options = {"segment_length_m": 5.0, "model": "sbem_tf", "smoothing": 0.01, "max_jerk_mps3": None,
               "v0_mps": 0.0, "vend_mps": 0.0, "band": "all", "method": "auto", "refine": True}
    profile = plan(route, vehicle, **options)
    check_plan(profile, route, vehicle, options)
    force_ratio = profile.force_n[:-1].max() / vehicle.max_transmitted_force_n
    accel = np.diff(profile.speed_mps**2) / (2 * np.diff(profile.s_m))
    stricter = [
        vehicle.replace(max_transmitted_force_n=vehicle.max_transmitted_force_n * force_ratio * 0.99),
        vehicle.replace(max_accel_mps2=accel.max() * 0.99),
        vehicle.replace(max_decel_mps2=-accel.min() * 0.99),
        vehicle.replace(max_speed_mps=profile.speed_mps.max() * 0.99),
        vehicle.replace(max_jerk_mps3=vehicle.max_jerk_mps3 * 0.5),
    ]
    for other, what in zip(stricter, ["force / limit", None, None, None, None]):
        with pytest.raises(AssertionError, match=re.escape(what) if what else None):
            check_plan(profile, route, other, options)
    with pytest.raises(AssertionError):
        check_plan(profile, route, vehicle, dict(options, v0_mps=0.5))
    faster = profile.speed_mps.copy()
    faster[len(faster) // 2] *= 1.05
    with pytest.raises(AssertionError):
        check_plan(dataclasses.replace(profile, speed_mps=faster), route, vehicle, options)
    limited = Route(s, z, np.full(s.size, profile.speed_mps.max() * 0.99), source="check")
    with pytest.raises(AssertionError):
        check_plan(profile, limited, vehicle, options)
    # turns and hills: a plan on a 20 % climb with a bend, checked against lower power,
    # grip and lateral limits than it was planned with, and against the flat acceleration bound
    theta = np.arange(0.0, 1.0, 0.1 / 20.0)
    x = np.concatenate([np.arange(0.0, 40.0, 0.1), 40 + 20 * np.sin(theta), 40 + 20 * np.sin(1.0) + np.arange(0.1, 40, 0.1) * np.cos(1.0)])
    y = np.concatenate([np.zeros(400), 20 * (1 - np.cos(theta)), 20 * (1 - np.cos(1.0)) + np.arange(0.1, 40, 0.1) * np.sin(1.0)])
    s3 = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(x), np.diff(y)))])
    hill = Route(s3, 0.2 * s3, source="hill", x_m=x, y_m=y)
    full = BASES["atv"].replace(max_power_w=4000.0)  # binds above P / (m a_max) = 3.6 m/s
    options = dict(options, smoothing=0.0, max_jerk_mps3=math.inf)
    profile = plan(hill, full, **options)
    check_plan(profile, hill, full, options)
    for other in (full.replace(max_power_w=full.max_power_w * 0.9), full.replace(friction_coefficient=0.2),
                  full.replace(max_lateral_accel_mps2=1.0), full.replace(max_accel_mps2=1.0)):
        with pytest.raises(AssertionError):
            check_plan(profile, hill, other, options)
