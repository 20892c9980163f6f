"""The route planner: exact optima, band choice over resonance, constraint checks, CLI.

Every profile produced here is checked by ``check_profile`` (tests/conftest.py), an evaluation of every
constraint written independently of the planner: speeds against the caps, accelerations
recomputed from speed^2 differences, jerk v da/ds, and the model's force on a fine grid of
the speeds each segment passes through.
"""

from __future__ import annotations

import json
import math
import subprocess

import numpy as np
import pytest
from scipy.optimize import linprog

from profileopt.io.profiles import write_profile
from profileopt import InfeasibleError, InputError, Route, load_vehicle, read_profile, read_route
from profileopt.core.profile import PROFILE_COLUMNS
from profileopt.core.segments import segment_route
from profileopt.planning import greatest_profile, plan, planner

from conftest import PROFILEOPT, ROUTES


def flat_route(length_m=500.0, spacing_m=0.25, speed_limit=None):
    s = np.arange(0.0, length_m + 1e-9, spacing_m)
    return Route(s, np.zeros_like(s), speed_limit, source="flat")


def test_flat_route_matches_the_trapezoid_closed_form(check_profile, atv):
    # Flat ground: RI = 0, no force limit, so rest-to-rest at top speed V = 20 m/s with
    # a = 2.5, d = 4 m/s^2. Accelerating takes V^2/(2a) = 80 m (16 segments of 5 m) and
    # braking V^2/(2d) = 50 m (10 segments): the switches fall on boundaries, so the
    # piecewise-constant acceleration of the planner is exact. Trapezoid time:
    # t = L/V + V/(2a) + V/(2d) = 500/20 + 20/5 + 20/8 = 31.5 s.
    route = flat_route()
    profile = plan(route, atv, smoothing=0.0, max_jerk_mps3=math.inf)
    assert profile.status == "exact"
    assert profile.travel_time_s == pytest.approx(31.5, rel=1e-12)
    check_profile(profile, route, atv, jerk=math.inf)


def test_speed_limit_column_caps_the_profile(check_profile, atv):
    route = flat_route(speed_limit=np.where(np.arange(0, 500.0001, 0.25) < 250, 20.0, 8.0))
    profile = plan(route, atv)
    check_profile(profile, route, atv)
    assert profile.speed_mps[profile.s_m > 255].max() <= 8.0 + 1e-9


@pytest.mark.parametrize("refine", [True, False])
def test_refining_keeps_a_speed_limit_to_the_samples_around_its_zone(check_profile, atv, refine):
    # A zone of 8 m/s on the samples from 200.25 to 259.75 m (every 0.25 m), 15 m segments
    # (boundaries at 195 and 270 m around it): a segment's cap is the least limit of its
    # samples, so unrefined the plan is held from 195 to 270 m. Refining cuts the held
    # segments at the last sample before the zone (200.0 m) and the first after it (260.0
    # m): held from 200.0 to 260.0 m only, wherever the grid falls.
    s = np.arange(0.0, 500.0 + 1e-9, 0.25)
    route = flat_route(speed_limit=np.where((s > 200.1) & (s < 259.9), 8.0, 20.0))
    profile = plan(route, atv, segment_length_m=15.0, refine=refine)
    check_profile(profile, route, atv)
    mine = [k for k, limit in enumerate(profile.limits) if limit.binding == "speed_limit"][0]
    top = np.maximum(profile.speed_mps[:-1], profile.speed_mps[1:])
    held = np.flatnonzero((profile.cap_source == mine) & (profile.speed_cap_mps < 20.0) & (top >= 0.98 * 8.0))
    extent = (profile.s_m[held[0]], profile.s_m[held[-1] + 1])
    assert extent == pytest.approx((200.0, 260.0) if refine else (195.0, 270.0), abs=1e-9)


def test_greatest_profile_is_the_lp_optimum():
    # The greatest element of {b : b <= U, b_{j+1} - b_j <= 2 a ds, b_j - b_{j+1} <= 2 d ds}
    # maximises every positively weighted sum of b, so an LP (scipy's HiGHS) must agree.
    rng = np.random.default_rng(3)
    n = 40
    ds = rng.uniform(1.0, 6.0, n)
    upper = rng.uniform(0.0, 300.0, n + 1)
    upper[0] = upper[-1] = 0.0
    a, d = 2.0, 3.5
    rows, rhs = [], []
    for j in range(n):
        e = np.zeros(n + 1)
        e[j + 1], e[j] = 1.0, -1.0
        rows += [e, -e]
        rhs += [2 * a * ds[j], 2 * d * ds[j]]
    lp = linprog(-np.ones(n + 1), A_ub=np.array(rows), b_ub=np.array(rhs), bounds=list(zip(np.zeros(n + 1), upper)))
    assert lp.status == 0
    np.testing.assert_allclose(greatest_profile(np.zeros(n + 1), upper, ds, a, d), lp.x, atol=1e-7)


@pytest.mark.slow
@pytest.mark.parametrize("name,vehicle_name", [("trail.csv", "atv"), ("krc_rms_2in.csv", "atv"),
                                               ("washboard.csv", "atv-resonant")])
def test_pure_minimum_time_nlp_matches_the_exact_optimum(check_profile, name, vehicle_name):
    # With smoothing 0 and no jerk bound the forward-backward profile over the chosen bands
    # is the exact optimum; IPOPT, forced to solve the NLP, must agree within 1e-4.
    route = read_route(ROUTES / name)
    vehicle = load_vehicle(vehicle_name)
    exact = plan(route, vehicle, smoothing=0.0, max_jerk_mps3=math.inf)
    nlp = plan(route, vehicle, smoothing=0.0, max_jerk_mps3=math.inf, method="nlp")
    assert exact.status == "exact" and nlp.status == "optimal"
    assert nlp.travel_time_s == pytest.approx(exact.travel_time_s, rel=1e-4)
    assert nlp.travel_time_s >= exact.travel_time_s * (1 - 1e-9)  # nothing beats the optimum
    for profile in (exact, nlp):
        check_profile(profile, route, vehicle, jerk=math.inf)


@pytest.mark.slow
@pytest.mark.parametrize("name,vehicle_name", [("trail.csv", "atv"), ("curb.csv", "atv"),
                                               ("krc_rms_4in.csv", "atv"), ("iri_road.csv", "atv")])
def test_full_problem_keeps_every_limit(check_profile, name, vehicle_name):
    route = read_route(ROUTES / name)
    vehicle = load_vehicle(vehicle_name)
    profile = plan(route, vehicle)
    assert profile.success, profile.status
    check_profile(profile, route, vehicle)
    # smoothing and jerk cost time, but little
    exact = plan(route, vehicle, smoothing=0.0, max_jerk_mps3=math.inf)
    assert exact.travel_time_s <= profile.travel_time_s <= 1.15 * exact.travel_time_s


@pytest.mark.slow
def test_resonant_washboard_is_crossed_above_resonance(check_profile, atv_resonant):
    route = read_route(ROUTES / "washboard.csv")
    fast = plan(route, atv_resonant)
    safe = plan(route, atv_resonant, band="first")
    for profile in (fast, safe):
        assert profile.success
        check_profile(profile, route, atv_resonant)
    on_washboard = (fast.s_m > 155) & (fast.s_m < 295)
    first_cap = fast.allowable_first_mps.max(initial=0, where=(fast.s_m[:-1] > 155) & (fast.s_m[:-1] < 295))
    # the band reachable from rest ends at ~0.32 m/s; the plan holds the upper band (~3.4 m/s)
    assert first_cap < 0.4
    assert fast.speed_mps[on_washboard].min() > 3.0
    assert safe.speed_mps[on_washboard].max() < 0.4
    assert fast.travel_time_s < 0.4 * safe.travel_time_s
    # ... and slows below resonance again before the rougher stretch at 350-375 m, where only
    # the band from rest exists
    rough = np.flatnonzero((fast.s_m[:-1] >= 350) & (fast.s_m[:-1] < 375))
    top = np.maximum(fast.speed_mps[rough], fast.speed_mps[rough + 1])
    assert np.all(top <= fast.allowable_largest_mps[rough] + 1e-9)
    assert top.max() < 0.3
    summary = fast.summary()
    assert 350 <= summary["slowest_segment"]["s_start_m"] < 375
    assert "force limit" in summary["slowest_segment"]["reason"]


@pytest.mark.parametrize("end_m,above", [(320.0, True), (230.0, False)])
def test_band_choice_near_a_stop(check_profile, atv_resonant, end_m, above):
    # Cut the washboard route short. Ending on 20 m of smooth ground after the washboard
    # (320 m), the vehicle can brake from ~3.4 m/s within a segment, so it crosses above
    # resonance. Ending ON the washboard (230 m), it never can: leaving the upper band
    # [~0.53, ~3.4] m/s for the band from rest [0, ~0.32] m/s would pass through forbidden
    # speeds inside a washboard segment, so the whole washboard must be driven slowly.
    route = read_route(ROUTES / "washboard.csv")
    keep = route.s_m <= end_m
    short = Route(route.s_m[keep], route.z_m[keep], source="washboard-cut")
    profile = plan(short, atv_resonant)
    check_profile(profile, short, atv_resonant)
    assert profile.speed_mps[-1] == 0.0
    on_washboard = profile.speed_mps[(profile.s_m > 160) & (profile.s_m < 225)]
    if above:
        assert on_washboard.min() > 3.0
    else:
        assert on_washboard.max() < 0.33


@pytest.mark.slow
def test_fallback_keeps_every_limit_when_ipopt_fails(check_profile, monkeypatch, atv):
    route = read_route(ROUTES / "trail.csv")

    def failing(seg, chosen, decel, accel, smoothing, jerk, options, rows):
        return planner._NlpResult(chosen.greatest_b * 0.5, "Maximum_Iterations_Exceeded", 300, 1, {}, "ipopt")

    monkeypatch.setattr(planner, "_solve_nlp", failing)
    profile = plan(route, atv)
    assert not profile.success
    assert profile.status == "fallback: Maximum_Iterations_Exceeded"
    assert profile.pieces == 0  # no IPOPT solution is in it
    assert any("the NLP solver gave no usable solution" in note for note in profile.notes)
    check_profile(profile, route, atv)


def test_infeasible_stop_is_an_input_error(atv):
    route = flat_route(length_m=10.0)
    with pytest.raises(InfeasibleError, match="v0"):
        plan(route, atv, v0_mps=20.0)
    with pytest.raises(InputError, match="segment_length_m"):
        plan(route, atv, segment_length_m=20.0)


def test_short_tail_is_merged_and_noted(atv):
    # 10 segments of 5 m and a 0.03 m tail holding 1 sample (50.03 m): fewer than the 2 a
    # segment needs (MIN_SAMPLES_PER_SEGMENT), so it is merged into segment 9
    s = np.append(np.arange(0.0, 50.0 - 1e-9, 0.05), 50.03)
    route = Route(s, 0.01 * np.sin(s), source="tail")
    seg = segment_route(route, atv, 5.0)
    assert seg.count == 10 and seg.boundaries_m[-1] == 50.03
    assert seg.notes and "merged" in seg.notes[0]
    assert seg.samples.sum() == s.size


def test_profile_csv_round_trip(tmp_path, atv_resonant):
    route = read_route(ROUTES / "washboard.csv")
    profile = plan(route, atv_resonant, model="sbem_ef")
    path = tmp_path / "p.csv"
    write_profile(profile, path)
    lines = path.read_text().splitlines()
    assert lines[0].startswith("# profileopt profile:") and "model=sbem_ef" in lines[0]
    assert lines[1] == ",".join(PROFILE_COLUMNS)
    back = read_profile(path)
    assert back.model == "sbem_ef"
    # written rounded to what the numbers mean (profileopt.io.profiles.COLUMN_FORMATS): s_m
    # exactly, speeds to 12 significant digits, the rest to 9
    for name in PROFILE_COLUMNS:
        if name == "s_m" or not np.issubdtype(np.asarray(getattr(profile, name)).dtype, np.floating):
            np.testing.assert_array_equal(getattr(back, name), getattr(profile, name))
        else:
            rtol = 1e-11 if name == "speed_mps" else 1e-8
            np.testing.assert_allclose(getattr(back, name), getattr(profile, name), rtol=rtol, atol=1e-300)


def run_cli(*args, cwd=None):
    return subprocess.run([*PROFILEOPT, *args], capture_output=True, text=True, cwd=cwd)


@pytest.mark.slow
def test_cli_plan_end_to_end(check_profile, tmp_path):
    out, png = tmp_path / "profile.csv", tmp_path / "profile.png"
    done = run_cli("plan", str(ROUTES / "washboard.csv"), "--vehicle", "atv-resonant", "-o", str(out),
                   "--plot", str(png))
    assert done.returncode == 0, done.stderr
    assert "travel time" in done.stdout and "slowest" in done.stdout and "solver" in done.stdout
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    profile = read_profile(out)
    route = read_route(ROUTES / "washboard.csv")
    check_profile(profile, route, load_vehicle("atv-resonant"), written=True)
    done = run_cli("plan", str(ROUTES / "curb.csv"), "--json", "--max-jerk", "inf", "--smoothing", "0")
    assert done.returncode == 0, done.stderr
    summary = json.loads(done.stdout)
    assert summary["solver"]["status"] == "exact"
    assert summary["margins"]["jerk"]["ratio"] is None
    assert summary["distance_m"] == pytest.approx(200.0)


@pytest.mark.slow
def test_bands_first_still_reports_the_largest_allowable_speed(atv_resonant):
    # "first" restricts the plan, not the report: the washboard's upper band stays visible
    route = read_route(ROUTES / "washboard.csv")
    fast, safe = plan(route, atv_resonant), plan(route, atv_resonant, band="first")
    np.testing.assert_array_equal(safe.allowable_largest_mps, fast.allowable_largest_mps)
    np.testing.assert_array_equal(safe.allowable_first_mps, fast.allowable_first_mps)
    washboard = (safe.s_m[:-1] > 155) & (safe.s_m[:-1] < 295)
    assert np.all(safe.allowable_largest_mps[washboard] > 3.0)


def test_boundary_speed_between_two_bands_is_named_as_such(atv_resonant):
    route = read_route(ROUTES / "washboard.csv")
    keep = (route.s_m >= 160) & (route.s_m <= 260)  # washboard only: bands [0, ~0.32], [~0.53, ~3.4]
    washboard = Route(route.s_m[keep] - 160.0, route.z_m[keep], source="washboard-only")
    with pytest.raises(InfeasibleError, match=r"v0_mps = 0.4 m/s is not an admissible speed.*\[0, 0.3\d*\] and"):
        plan(washboard, atv_resonant, v0_mps=0.4)


def test_text_in_an_ignored_column_is_ignored(check_profile, tmp_path, atv):
    s = np.arange(0.0, 50.0 + 1e-9, 0.25)
    lines = ["s,z,comment"] + [f"{a:.2f},{0.01 * math.sin(a):.5f},note {k}" for k, a in enumerate(s)]
    (tmp_path / "r.csv").write_text("\n".join(lines) + "\n")
    route = read_route(tmp_path / "r.csv")
    assert route.notes and "comment" in route.notes[0]
    np.testing.assert_allclose(route.s_m, np.round(s, 2))
    check_profile(plan(route, atv), route, atv)


def _pothole_field_route():
    # flat ends, then potholes 0.6 m long every 3.1 m and rough ground between them: windows from
    # smooth to rough within one segment, where SBEM:TF's force is not monotone in the RI
    s = np.arange(0.0, 50.0 + 1e-9, 0.05)
    z = 0.004 * np.sin(2 * np.pi * s / 0.9) * ((s > 12) & (s < 38))
    for c in np.arange(15.0, 35.0, 3.1):
        inside = (s > c) & (s < c + 0.6)
        z[inside] -= 0.05 * np.sin(np.pi * (s[inside] - c) / 0.6)
    return Route(s, z, source="pothole field")


def _outside_segment_band(members, vehicle, band):
    """The band (lo, hi) of speeds admissible for every RI in ``members`` (brute force: a dense
    grid of the largest member force, the edges bisected), 'first' or 'largest'."""
    from profileopt import force_n

    limit = vehicle.max_transmitted_force_n

    def over(v):
        return bool(np.max(force_n(np.full(members.size, v), vehicle, ri=members)) > limit)

    grid = np.concatenate([np.linspace(0.0, 2.0, 801), np.linspace(2.0, vehicle.max_speed_mps, 181)[1:]])
    ok = np.max(force_n(grid[:, None], vehicle, ri=members[None, :]), axis=1) <= limit

    def edge(a, b):  # ok changes between grid speeds a < b: bisect to 1e-12 m/s
        want = over(a)
        while b - a > 1e-12:
            m = 0.5 * (a + b)
            a, b = (m, b) if over(m) == want else (a, m)
        return a if not want else b

    change = np.flatnonzero(ok[1:] != ok[:-1])
    edges = [edge(grid[j], grid[j + 1]) for j in change]
    points = ([0.0] if ok[0] else []) + edges + ([vehicle.max_speed_mps] if ok[-1] else [])
    runs = list(zip(points[0::2], points[1::2]))
    if band == "first":
        return runs[0] if runs and runs[0][0] == 0.0 else (0.0, 0.0)
    if band == "all":  # a relaxation: any speed up to the top of the highest band
        return 0.0, runs[-1][1]
    return runs[-1]


@pytest.mark.slow
@pytest.mark.parametrize("vehicle_name", ["atv", "atv-resonant"])
@pytest.mark.parametrize("band", ["first", "largest", "all"])
def test_sbem_tf_plans_are_exact_under_their_window_definition(vehicle_name, band):
    # Issue 33: each segment is held to every roughness window it meets, and to nothing more.
    # Reference, written here: each segment's band from a brute-force search over its windows'
    # RIs (every one of them: no range, no bound), and the exact minimum time over those bands
    # by the forward-backward passes (smoothing 0, no jerk bound), on the planner's own segments.
    # For band "all" the reference drops the lower edges (any speed up to the top of the highest
    # band): a lower bound on every band assignment's time, so a plan that reaches it is optimal
    # (here the resonant ATV crosses the potholes above resonance).
    from profileopt.terrain.roughness import roughness_windows

    route = _pothole_field_route()
    # without the optional keys (grades, turns, friction, power): the force and the bounds on a and d alone
    vehicle = load_vehicle(vehicle_name).replace(max_lateral_accel_mps2=None, track_width_m=None, cg_height_m=None,
                                                 friction_coefficient=None, mass_kg=None, max_power_w=None)
    profile = plan(route, vehicle, band=band, smoothing=0.0, max_jerk_mps3=math.inf, simulation_gate=False)
    assert profile.status == "exact"
    s = profile.s_m
    windows = roughness_windows(route.s_m, route.z_m, vehicle.ground_clearance_m, window_m=5.0)
    first, stop = windows.overlapping(s[:-1], s[1:])
    lower, upper = np.zeros(s.size - 1), np.zeros(s.size - 1)
    for i in range(s.size - 1):
        lower[i], upper[i] = _outside_segment_band(np.unique(windows.ri[first[i]:stop[i]]), vehicle, band)
    # v^2 at the boundaries: each boundary within both neighbours' bands, rest at both ends
    ub = np.minimum(np.append(upper, np.inf), np.insert(upper, 0, np.inf)) ** 2
    lb = np.maximum(np.append(lower, 0.0), np.insert(lower, 0, 0.0)) ** 2
    ub[0] = ub[-1] = 0.0
    length = np.diff(s)
    b = ub.copy()
    for i in range(length.size):
        b[i + 1] = min(b[i + 1], b[i] + 2 * vehicle.max_accel_mps2 * length[i])
    for i in range(length.size - 1, -1, -1):
        b[i] = min(b[i], b[i + 1] + 2 * vehicle.max_decel_mps2 * length[i])
    assert np.all(b >= lb * (1 - 1e-9))
    v = np.sqrt(b)
    exact = float(np.sum(2 * length / (v[:-1] + v[1:])))
    assert profile.travel_time_s == pytest.approx(exact, rel=1e-9)
