"""The step limit of SBEM:TF: ramps of the wheel's path, their force bound, the cap, a plan."""

import dataclasses
import math

import casadi as ca
import numpy as np
import pytest
from scipy import signal

import profileopt
from profileopt.physics.steps import impulse_response_peak_s, ramp_force_n, ramp_speed_cap_mps
from profileopt.mpc.constraints import step_speed_envelope
from profileopt.planning.limits import StepLimit, default_limits
from profileopt.physics.steps import step_speed_cap_mps
from profileopt.physics.steps import wheel_ramps
from profileopt.physics.simulate import simulate_quarter_car
from profileopt.physics.wheel import wheel_path

from conftest import ROUTES


@pytest.fixture(scope="module", params=["atv", "atv-resonant"])
def vehicle(request):
    return profileopt.load_vehicle(request.param)


@pytest.mark.slow
@pytest.mark.parametrize("zeta", [0.05, 0.1, 0.5, 0.999, 1.0, 1.001, 2.0, 8.0])
def test_impulse_response_peak_matches_scipy(zeta):
    # Reference: scipy.signal.impulse of 1 / (s^2 + 2 zeta wn s + wn^2), the relative
    # displacement after a unit step of the base velocity, sampled finely; its largest value.
    vehicle = dataclasses.replace(profileopt.load_vehicle("atv"), damping_ratio=zeta)
    wn = vehicle.natural_frequency_radps
    t = np.linspace(0.0, 20.0 / wn, 400_001)
    _, phi = signal.impulse(([1.0], [1.0, 2.0 * zeta * wn, wn * wn]), T=t)
    assert impulse_response_peak_s(vehicle) == pytest.approx(float(np.max(phi)), rel=1e-6)


@pytest.mark.parametrize("rise_m, slope", [(0.15, 3.0), (0.05, 1.0), (0.3, 0.5), (0.02, 6.0)])
@pytest.mark.parametrize("speed_mps", [0.5, 2.0, 6.0, 15.0])
def test_ramp_force_bounds_the_simulated_ramp(vehicle, rise_m, slope, speed_mps):
    # Reference: the project's exact simulator on the bare polyline (envelope=False): flat
    # ground, a straight ramp down of the given slope and height, flat ground. The body starts
    # at rest; the largest |F_T| before and on the ramp (up to its foot, the landing) is
    # bounded by ramp_force_n (|phi| <= t, |phi'| <= 1 for the impulse response phi).
    dx = rise_m / slope
    s = np.concatenate([np.linspace(0.0, 5.0, 101), [5.0 + dx], 5.0 + dx + np.linspace(0.05, 1.0, 20)])
    z = np.where(s <= 5.0, rise_m, 0.0)
    run = simulate_quarter_car(s, z, np.array([0.0, s[-1]]), np.array([speed_mps, speed_mps]), vehicle,
                               envelope=False)
    on_ramp = run.s_m <= 5.0 + dx + 1e-12
    simulated = float(np.max(np.abs(run.transmitted_n[on_ramp])))
    bound = float(ramp_force_n(speed_mps, rise_m, slope, vehicle))
    assert simulated <= bound * (1 + 1e-6)
    if speed_mps * slope * impulse_response_peak_s(vehicle) >= 10 * rise_m:
        # a ramp too short for the body to follow: the bound is nearly what happens
        # (k d + c V s at the landing, the body barely moved)
        assert simulated >= 0.9 * bound


def test_ramp_speed_cap_is_the_inverse(vehicle):
    rng = np.random.default_rng(5)
    rise = rng.uniform(0.0, 0.3, 400)
    slope = rng.uniform(0.05, 8.0, 400)
    limit = vehicle.max_transmitted_force_n
    cap = ramp_speed_cap_mps(rise, slope, vehicle, limit)
    # the bound is V s (k phi_max + c) near V = 0: every ramp has a positive cap
    ok = cap > 0
    assert np.all(ok)
    force = ramp_force_n(cap[ok], rise[ok], slope[ok], vehicle)
    np.testing.assert_allclose(force, limit, rtol=1e-12)
    assert np.all(ramp_force_n(cap[ok] * 1.001, rise[ok], slope[ok], vehicle) > limit)
    assert np.isinf(ramp_speed_cap_mps(np.array([0.1]), np.array([0.0]), vehicle, limit)[0])


def test_wheel_ramps_of_a_sampled_drop_and_step():
    # A 0.15 m drop sampled every 0.05 m (a ramp of slope -3 from x0 = 10 to 10.05), a rigid
    # wheel of r = 0.1. Closed form of the landing: the centre, r above the floor, is r from
    # the line z = 0.15 - 3 (x - x0): 3 x_c + r - 3 x0 - 0.15 = r sqrt(10), so
    # x_c = x0 + (0.15 - r + r sqrt(10)) / 3. The path's slope before it is -3, the rise 0.15.
    r = 0.1
    s = np.round(np.arange(0.0, 20.0001, 0.05), 10)
    z = np.where(s > 10.0 + 1e-9, 0.0, 0.15)
    ramps = wheel_ramps(wheel_path(s, z, r))
    steep = ramps.slope > 1
    assert steep.sum() == 1 and ramps.landing[steep][0]
    kink = 10.0 + (0.15 - r + r * math.sqrt(10.0)) / 3.0
    assert ramps.kink_m[steep][0] == pytest.approx(kink, abs=1e-9)
    assert ramps.end_m[steep][0] == pytest.approx(kink, abs=1e-9)
    assert ramps.slope[steep][0] == pytest.approx(3.0, rel=1e-9)
    assert ramps.rise_m[steep][0] == pytest.approx(0.15, abs=1e-9)
    # the path's top: the wheel stands on the edge (its arc about the edge starts at x0)
    assert ramps.start_m[steep][0] == pytest.approx(10.0, abs=1e-9)
    # the same step climbed (a ramp from 9.95 to 10.0): the mirror image, the kink as far
    # before the foot as the landing was after it
    up = wheel_ramps(wheel_path(s, np.where(s < 9.95 + 1e-9, 0.0, 0.15), r))
    steep = up.slope > 1
    assert steep.sum() == 1 and not up.landing[steep][0]
    assert up.kink_m[steep][0] == pytest.approx(9.95 - (kink - 10.05), abs=1e-9)
    assert up.start_m[steep][0] == pytest.approx(up.kink_m[steep][0], abs=1e-12)
    assert up.rise_m[steep][0] == pytest.approx(0.15, abs=1e-9)


def test_no_cap_on_gentle_ground(vehicle):
    # a 10 m sinusoid of 2 cm: slopes up to 0.0126, below F / (V_top (k phi_max + c)) for
    # both vehicles (0.069 for atv-resonant), so no ramp can cap a speed
    s = np.linspace(0.0, 100.0, 2001)
    z = 0.02 * np.sin(2 * np.pi * s / 10.0)
    cap = step_speed_cap_mps(s, z, np.linspace(0.0, 100.0, 21), vehicle)
    assert np.all(np.isinf(cap))


def test_step_limit_only_with_sbem_tf():
    vehicle = profileopt.load_vehicle("atv")
    for model in ("sbem_tf", "sbem_ef", "iecm", "prev_bem"):
        has = any(isinstance(limit, StepLimit) for limit in default_limits(vehicle, model=model, max_jerk_mps3=5.0))
        assert has == (model == "sbem_tf")


def test_curb_drop_is_driven_within_the_limit():
    # curb.csv's 0.15 m drop with atv-resonant: without the step limit the plan crawled at
    # SBEM:TF's limit (1.45 m/s) and the simulated landing reached 1.007 x the limit (README,
    # safety study); with it the speed there is capped and no window is over in simulation.
    route = profileopt.read_route(ROUTES / "curb.csv")
    vehicle = profileopt.load_vehicle("atv-resonant")
    profile = profileopt.plan(route, vehicle)
    assert "step" in set(profile.binding)
    result = profileopt.verify(route, profile, vehicle)
    assert result.windows.over_count == 0
    assert result.windows.worst_ratio < 1.0


def _capping_ramps(route, vehicle):
    """The ramps of the wheel's path over the whole route that could cap a speed: steeper
    than G = F / (V_top (k phi_max + c)) against the trend (a gentler ramp's bound, at most
    V s (k phi_max + c), stays below F at every speed the vehicle can drive)."""
    k, c = vehicle.spring_n_per_m, vehicle.damping_ns_per_m
    gentlest = vehicle.max_transmitted_force_n / (vehicle.max_speed_mps * (k * impulse_response_peak_s(vehicle) + c))
    return wheel_ramps(wheel_path(route.s_m, route.z_m, vehicle.wheel_radius_m), min_slope=gentlest)


@pytest.mark.parametrize("name", ["curb.csv", "krc_rms_1in.csv", "krc_rms_4in.csv"])
def test_caps_from_stretches_equal_caps_from_the_whole_path(vehicle, name):
    # step_speed_cap_mps builds the wheel's path only around steep slopes; the reference
    # builds it over the whole route and caps every segment a ramp meets, by hand. Ramps no
    # steeper than G = F / (V_top (k phi_max + c)) cap nothing (their bound is at most
    # V s (k phi_max + c)); the caps ask only for steeper ones.
    route = profileopt.read_route(ROUTES / name)
    boundaries = np.arange(route.s_m[0], route.s_m[-1] + 1e-9, 2.5)
    ramps = _capping_ramps(route, vehicle)
    ramp_cap = ramp_speed_cap_mps(ramps.rise_m, ramps.slope, vehicle, vehicle.max_transmitted_force_n)
    expected = np.full(boundaries.size - 1, np.inf)
    for i in range(boundaries.size - 1):
        meets = (ramps.start_m <= boundaries[i + 1]) & (ramps.end_m >= boundaries[i])
        low = ramp_cap[meets & (ramp_cap < vehicle.max_speed_mps)]
        if low.size:
            expected[i] = low.min()
    cap = step_speed_cap_mps(route.s_m, route.z_m, boundaries, vehicle)
    np.testing.assert_array_equal(np.isfinite(cap), np.isfinite(expected))
    np.testing.assert_allclose(cap[np.isfinite(cap)], expected[np.isfinite(expected)], rtol=1e-9)


def test_a_sampled_drop_is_capped_at_the_hand_computed_speed():
    # A 0.15 m drop sampled every 0.05 m (slope 3) on flat ground, atv-resonant: k = 100 * 6^2
    # = 3600 N/m, c = 2 * 0.1 * 100 * 6 = 120 N s/m. At the cap V s phi_max > d (phi_max =
    # 0.1438 s), so k d + c V s = F: V = (1000 - 3600 * 0.15) / (120 * 3) = 1.2778 m/s; the
    # segment before the drop (where the wheel runs down from the edge) is held there.
    route = _drop_route()
    vehicle = profileopt.load_vehicle("atv-resonant")
    profile = profileopt.plan(route, vehicle)
    edge = int(np.searchsorted(profile.s_m, 50.0))  # the boundary at the edge
    held = profile.speed_cap_mps[edge - 1]  # the segment that ends at the edge
    assert held == pytest.approx((1000.0 - 3600.0 * 0.15) / (120.0 * 3.0), rel=1e-9)
    assert profile.binding[edge] == "step" and profile.speed_mps[edge] == pytest.approx(held, rel=1e-6)
    slowest = profile.summary()["slowest_segment"]
    assert "step limit" in slowest["reason"] and slowest["top_speed_mps"] == pytest.approx(held, rel=1e-9)


def _drop_route() -> profileopt.Route:
    """100 m of flat ground with a 0.15 m drop at 50 m, sampled every 0.05 m."""
    s = np.round(np.arange(0.0, 100.0001, 0.05), 10)
    return profileopt.Route(s_m=s, z_m=np.where(s > 50.0 + 1e-9, 0.0, 0.15), source="drop")


def _step_held_m(profile: profileopt.Profile) -> tuple[float, float, float]:
    """Where the step limit's cap holds the plan: the first and last point of the segments
    whose cap it sets and where the plan comes within 2 % of that cap, and their length (m)."""
    mine = [k for k, limit in enumerate(profile.limits) if isinstance(limit, StepLimit)][0]
    top = np.maximum(profile.speed_mps[:-1], profile.speed_mps[1:])
    held = np.flatnonzero((profile.cap_source == mine) & (top >= 0.98 * profile.speed_cap_mps))
    length = np.diff(profile.s_m)[held].sum()
    return float(profile.s_m[held[0]]), float(profile.s_m[held[-1] + 1]), float(length)


@pytest.mark.parametrize("segment_length_m", [2.5, 5.0, 10.0, 20.0])
def test_refining_keeps_a_steps_cap_to_the_samples_around_its_ramp(segment_length_m):
    # The drop's ramp runs from the edge at 50 m down to 50.122 m (step_caps). A segment
    # held by the cap is cut at the last sample before the ramp (49.95 m) and the first
    # after it (50.15 m). Where the grid has a boundary at the edge (2.5, 5 and 10 m
    # segments), the piece that ends there must keep MIN_SAMPLES_PER_SEGMENT = 2 samples, so
    # its cut moves out to 49.90 m; with 20 m segments (boundaries at 40 and 60 m) one piece
    # [49.95, 50.15] m holds the ramp. So the cap holds 0.20-0.25 m wherever the grid falls;
    # without refining it holds the whole segment that ends at the edge and the one that
    # starts there (or the one around it).
    from profileopt.core.segments import MIN_SAMPLES_PER_SEGMENT
    from profileopt.physics.steps import step_caps

    route, vehicle = _drop_route(), profileopt.load_vehicle("atv-resonant")
    caps = step_caps(route.s_m, route.z_m, vehicle)
    assert caps.start_m.tolist() == [50.0] and 50.1 < caps.end_m[0] < 50.15
    spacing = 0.05
    edge_on_grid = math.isclose(50.0 / segment_length_m, round(50.0 / segment_length_m))
    first, last, length = _step_held_m(profileopt.plan(route, vehicle, segment_length_m=segment_length_m))
    expected_first = 50.0 - (MIN_SAMPLES_PER_SEGMENT if edge_on_grid else 1) * spacing
    assert first == pytest.approx(expected_first, abs=1e-9)
    assert last == pytest.approx(50.15, abs=1e-9)  # the first sample after the ramp's end
    assert length == pytest.approx(50.15 - expected_first, abs=1e-9)
    first, last, length = _step_held_m(profileopt.plan(route, vehicle, segment_length_m=segment_length_m,
                                                       refine=False))
    around = (50.0 - segment_length_m, 50.0 + segment_length_m) if edge_on_grid else (40.0, 60.0)
    assert (first, last) == pytest.approx(around, abs=1e-9)


def test_stretch_cuts_by_hand():
    # Samples every 1 m from 0 to 30 m, segments [0, 10], [10, 20], [20, 30] m: segment 0
    # holds samples 0-9, segment 1 samples 10-19, segment 2 samples 20-30. Every segment is
    # held at 2 m/s, and each stretch below has that cap unless said otherwise.
    from profileopt.core.segments import segment_route
    from profileopt.planning.refine import stretch_cuts

    s = np.arange(0.0, 30.5, 1.0)
    route = profileopt.Route(s_m=s, z_m=np.zeros_like(s), source="by hand")
    seg = segment_route(route, profileopt.load_vehicle("atv"), 10.0, roughness_window_m=8.0)
    held = np.full(3, 2.0)

    def cuts(start_m, end_m, held_cap=held, cap_mps=2.0):
        return stretch_cuts(seg, s, held_cap, np.array([start_m]), np.array([end_m]), np.array([cap_mps])).tolist()

    # a stretch [14.5, 15.2] inside segment 1: the last sample before it (14) and the first
    # after it (16)
    assert cuts(14.5, 15.2) == [14, 16]
    # only segments held at the stretch's own cap are cut: not one that is not held (NaN),
    # nor one held at another cap (set by something else)
    assert cuts(14.5, 15.2, held_cap=np.array([2.0, np.nan, 2.0])) == []
    assert cuts(14.5, 15.2, cap_mps=3.0) == []
    # a stretch [11, 18.5]: the cuts at sample 10 (segment 1's first) and 19 (a piece [19,
    # 20] of one sample) cannot keep 2 samples a piece, and moving them away from the stretch
    # cannot help: none
    assert cuts(11.0, 18.5) == []
    # a stretch [19.6, 20] that ends on the boundary: the cut before it at sample 19 would
    # leave [19, 20] one sample, so it moves out to 18; the cut after it at sample 21 would
    # leave [20, 21] one, so it moves out to 22
    assert cuts(19.6, 20.0) == [18, 22]
    # at the route's start there is no sample before; at its end, none after (the last
    # segment holds the end sample 30, so [29, 30] keeps 2)
    assert cuts(0.0, 0.5) == [2]
    assert cuts(29.5, 30.0) == [29]


@pytest.mark.parametrize("segment_length_m", [5.0, 20.0])
def test_a_segment_a_steps_cap_held_is_also_cut_where_the_roughness_changes(segment_length_m):
    # Off the drop the ground is flat (RI 0, no force cap); only the 5 m roughness windows
    # that contain the edge (elevation changes between the samples at 50.00 and 50.05 m)
    # are rough, and they share points with [45.00, 55.05] m only. The step's cap hid the
    # force's cap of the segment around the edge; once refining frees the pieces off the
    # step, they are cut where the windows' roughness changes too, so the force holds the
    # plan only within one sample of that stretch (before, with 20 m segments, from 40 m on),
    # and the simulated vehicle keeps both limits.
    from profileopt.defaults import DEFAULT_ROUGHNESS_WINDOW_M

    route, vehicle = _drop_route(), profileopt.load_vehicle("atv-resonant")
    profile = profileopt.plan(route, vehicle, segment_length_m=segment_length_m)
    spacing = 0.05
    rough = (50.0 - DEFAULT_ROUGHNESS_WINDOW_M - spacing, 50.05 + DEFAULT_ROUGHNESS_WINDOW_M + spacing)
    held = profile.s_m[profile.binding == "force"]
    assert held.size and np.all((held >= rough[0]) & (held <= rough[1])), held
    result = profileopt.verify(route, profile, vehicle)
    assert result.windows.over_count == 0 and result.windows.worst_ratio < 1.0


# ------------------------------------------------------- the step limit in your own MPC

@pytest.mark.slow
@pytest.mark.parametrize("reach", [0.0, 1.3])
@pytest.mark.parametrize("name, vehicle_name", [("curb.csv", "atv-resonant"), ("curb.csv", "atv"),
                                                ("krc_rms_1in.csv", "atv-resonant")])
def test_step_speed_envelope_is_never_above_the_caps_it_must_keep(name, vehicle_name, reach):
    # Reference, by brute force: at each position x, the lowest ramp_speed_cap_mps of every
    # ramp whose [start, end] shares a point with [x, x + reach], or the top speed.
    route = profileopt.read_route(ROUTES / name)
    vehicle = profileopt.load_vehicle(vehicle_name)
    env = step_speed_envelope(route.s_m, route.z_m, vehicle, reach_m=reach)
    assert env.name_in() == ["s_m"] and env.name_out() == ["speed_cap_mps"]
    ramps = _capping_ramps(route, vehicle)
    cap = ramp_speed_cap_mps(ramps.rise_m, ramps.slope, vehicle, vehicle.max_transmitted_force_n)
    low = np.flatnonzero(cap < vehicle.max_speed_mps)
    assert low.size  # the test looks at routes where the step limit binds
    x = np.linspace(route.s_m[0], route.s_m[-1], 40001)

    def lowest_cap(a, b):  # the lowest cap of the ramps meeting [a, b] at each x, or the top speed
        need = np.full(x.size, vehicle.max_speed_mps)
        for r in low:
            meets = (ramps.start_m[r] <= b) & (ramps.end_m[r] >= a)
            need[meets] = np.minimum(need[meets], cap[r])
        return need

    need = lowest_cap(x, x + reach)
    value = np.asarray(env.map(x.size)(x[None, :])).ravel()
    assert np.all(value <= need), f"above by {np.max(value - need):.3g} m/s"
    # ... and not far below: at least the lowest cap within 4 knot intervals (h = 0.25 m)
    wider = lowest_cap(x - 1.0, x + reach + 1.0)
    assert np.all(value >= wider * (1 - 1e-9) - 1e-9)
    assert np.min(value) < 0.5 * vehicle.max_speed_mps  # the test saw a cap


def test_step_speed_envelope_is_smooth_and_works_on_sx_mx_dm():
    route = profileopt.read_route(ROUTES / "curb.csv")
    vehicle = profileopt.load_vehicle("atv-resonant")
    env = step_speed_envelope(route.s_m, route.z_m, vehicle, reach_m=0.5)
    x = ca.SX.sym("x")
    value = env(x)
    d = ca.Function("d", [x], [value, ca.gradient(value, x), ca.hessian(value, x)[0]])
    points = np.linspace(148.0, 158.0, 2001)
    v, d1, d2 = (np.asarray(o).ravel() for o in d.map(points.size)(points[None, :]))
    assert np.all(np.isfinite(d1)) and np.all(np.isfinite(d2)) and np.ptp(v) > 10  # it dips at the drop
    step = 1e-6  # the first derivative against central differences
    fd = (np.asarray(env.map(points.size)((points + step)[None, :])).ravel()
          - np.asarray(env.map(points.size)((points - step)[None, :])).ravel()) / (2 * step)
    np.testing.assert_allclose(d1, fd, rtol=1e-5, atol=1e-4)
    xm = ca.MX.sym("x")
    assert isinstance(env(xm), ca.MX)
    assert float(env(ca.DM(152.6))) == pytest.approx(float(env(152.6)))
    assert math.isnan(float(env(math.nan)))


@pytest.mark.parametrize("kwargs, message", [({"reach_m": -1.0}, "reach_m"), ({"knot_spacing_m": 0.0}, "knot_spacing_m"),
                                             ({"knot_spacing_m": 1e-4}, "knot intervals")])
def test_step_speed_envelope_bad_input_is_one_input_error(kwargs, message):
    route = profileopt.read_route(ROUTES / "curb.csv")
    with pytest.raises(profileopt.InputError, match=message):
        step_speed_envelope(route.s_m, route.z_m, profileopt.load_vehicle("atv"), **kwargs)


def test_an_opti_problem_keeps_the_step_limit_over_the_curb_drop():
    # Minimum time over 140-160 m of curb.csv (the 0.15 m drop at 152.5 m), stages of 0.5 m,
    # atv-resonant: with v_k, v_k+1 <= cap(s_k) (reach = the stage) no stage's speeds exceed
    # the cap of any ramp the stage meets, checked by brute force on every stage.
    route = profileopt.read_route(ROUTES / "curb.csv")
    vehicle = profileopt.load_vehicle("atv-resonant")
    keep = (route.s_m >= 140.0) & (route.s_m <= 160.0)
    s, z = route.s_m[keep], route.z_m[keep]
    ds = 0.5
    grid = np.arange(140.0, 160.0 + 1e-9, ds)
    cap_fn = step_speed_envelope(s, z, vehicle, reach_m=ds)
    opti = ca.Opti()
    b = opti.variable(grid.size)  # squared speeds
    opti.subject_to(opti.bounded(0.25, b, vehicle.max_speed_mps**2))
    opti.subject_to(opti.bounded(-2 * vehicle.max_decel_mps2 * ds, ca.diff(b), 2 * vehicle.max_accel_mps2 * ds))
    for k in range(grid.size - 1):
        c = cap_fn(grid[k])
        opti.subject_to(b[k] <= c**2)
        opti.subject_to(b[k + 1] <= c**2)
    opti.minimize(ca.sum1(2 * ds / (ca.sqrt(b[:-1]) + ca.sqrt(b[1:]))))
    opti.set_initial(b, 1.0)
    opti.solver("ipopt", {"print_time": False}, {"print_level": 0, "sb": "yes"})
    speed = np.sqrt(np.asarray(opti.solve().value(b)).ravel())
    ramps = _capping_ramps(profileopt.Route(s_m=s, z_m=z, source="curb 140-160 m"), vehicle)
    cap = ramp_speed_cap_mps(ramps.rise_m, ramps.slope, vehicle, vehicle.max_transmitted_force_n)
    for k in range(grid.size - 1):
        meets = (ramps.start_m <= grid[k + 1]) & (ramps.end_m >= grid[k])
        if np.any(meets):
            assert max(speed[k], speed[k + 1]) <= cap[meets].min() * (1 + 1e-6)
    assert speed.max() > 3.0  # it is not a crawl everywhere


def test_the_step_limit_reuses_a_routes_caps_only_for_that_route():
    # A refined plan asks the limit twice on one route; the limit keeps the route's caps
    # between the calls, and must not hand them to another route or vehicle.
    from profileopt.core.segments import segment_route
    from profileopt.planning.limits import PlanContext

    limit = StepLimit()
    curb = profileopt.read_route(ROUTES / "curb.csv")
    drop = _drop_route()
    resonant, atv = profileopt.load_vehicle("atv-resonant"), profileopt.load_vehicle("atv")
    for route, vehicle, length in ((curb, resonant, 5.0), (curb, resonant, 2.5), (drop, resonant, 5.0),
                                   (drop, atv, 5.0), (curb, resonant, 5.0)):
        seg = segment_route(route, vehicle, length)
        got = limit.speed_cap_mps(PlanContext(route=route, vehicle=vehicle, segments=seg))
        np.testing.assert_array_equal(got, step_speed_cap_mps(route.s_m, route.z_m, seg.boundaries_m, vehicle))


def _kerb_caps(grade: float, height_m: float, vehicle, shape: str = "grade"):
    """step_caps of a kerb (height_m > 0) or drop (< 0) at 100 m of 200 m of ground sampled
    every 0.05 m: on a steady grade, or at the top of a crest or the bottom of a dip whose
    grade reaches |grade| 50 m away (a road's vertical curve, of radius 50 / |grade| m)."""
    from profileopt.physics.steps import step_caps

    s = np.round(np.arange(0.0, 200.0001, 0.05), 10)
    curve = (s - 100.0) ** 2 * abs(grade) / 100.0
    ground = {"grade": grade * s, "crest": -curve, "dip": curve}
    return step_caps(s, ground[shape] + height_m * (s >= 100.0), vehicle)


@pytest.mark.parametrize(("shape", "grade"), [("grade", -0.15), ("grade", -0.05), ("grade", 0.05), ("grade", 0.15),
                                              ("crest", 0.05), ("crest", 0.15), ("dip", 0.05), ("dip", 0.15)])
@pytest.mark.parametrize("height_m", [0.08, -0.08])
def test_a_kerb_on_a_hill_is_capped_like_the_same_kerb_on_the_flat(vehicle, shape, grade, height_m):
    # Reference: the same kerb on flat ground. The quarter car is linear and a steady grade
    # loads its suspension not at all, so the ramp is the kerb measured against the grade it
    # interrupts: the same height, and a slope that differs from the flat kerb's only by the
    # wheel path's offset on an incline (r (sqrt(1 + g^2) - 1), 1 mm at 15 %) and the grade's
    # share of the sampled kerb's slope. Before issue 29 a climb's ramp ran up to the next
    # hilltop: an 8 cm kerb on a 5 % climb held 185 m of road at 6.5 m/s.
    flat = _kerb_caps(0.0, height_m, vehicle)
    caps = _kerb_caps(grade, height_m, vehicle, shape)
    assert flat.cap_mps.size == 1  # the reference is capped at all (0.05 m sampling)
    assert caps.cap_mps.size == 1
    assert caps.cap_mps[0] == pytest.approx(flat.cap_mps[0], rel=0.1)
    # the cap holds the ramp only: a few centimetres around 100 m, not the hill
    assert 99.8 <= caps.start_m[0] <= caps.end_m[0] <= 100.2


def test_a_trend_is_the_median_slope_of_the_path():
    # A 20 % grade with a 0.1 m kerb at 50 m: within 2.5 m of any point the kerb's ramp (a
    # few cm) is far less than half the path, so the median slope is the grade's, 0.2;
    # on a crest (slopes +0.1 before 50 m, -0.1 after) it is the slope of the longer side.
    from profileopt.physics.steps import trend_slope

    s = np.round(np.arange(0.0, 100.0001, 0.05), 10)
    path = wheel_path(s, 0.2 * s + 0.1 * (s >= 50.0), 0.1)
    np.testing.assert_allclose(trend_slope(path, np.array([10.0, 49.9, 50.0, 50.1, 90.0])), 0.2, atol=1e-12)
    crest = wheel_path(s, 0.1 * np.minimum(s, 100.0 - s), 0.1)
    np.testing.assert_allclose(trend_slope(crest, np.array([40.0, 48.0, 52.0, 60.0])), [0.1, 0.1, -0.1, -0.1],
                               atol=1e-12)


@pytest.mark.parametrize("grade", [-0.05, 0.05])
@pytest.mark.parametrize("height_m", [0.08, -0.08])
def test_a_kerb_on_a_grade_costs_what_it_costs_on_the_flat(grade, height_m):
    # Issue 29: an 8 cm kerb on a 5 % climb cost 1.9x the travel time of the climb without
    # it. Reference: the plan of the same kerb on flat ground, whose cost (its step cap,
    # 10.3 m/s for atv at this sampling, and the windows' RI around it) the grade should
    # not multiply; uphill the vehicle regains its speed a little more slowly after the cap.
    vehicle = profileopt.load_vehicle("atv")
    s = np.round(np.arange(0.0, 300.0001, 0.05), 10)
    kerb = height_m * (s >= 100.0)

    def travel_time_s(z):
        return profileopt.plan(profileopt.Route(s_m=s, z_m=z, source="kerb"), vehicle).travel_time_s

    flat_cost = travel_time_s(kerb) - travel_time_s(0.0 * s)
    plain = travel_time_s(grade * s)
    cost = travel_time_s(grade * s + kerb) - plain
    assert 0 < flat_cost < 0.12 * plain
    assert cost <= 1.1 * flat_cost
