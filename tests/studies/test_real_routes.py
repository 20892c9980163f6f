"""The real-route study (profileopt.studies.real_routes, examples/real_routes_study.py).

The fast tests plan two short synthetic roads (60 m: potholes on a 10 % climb, a washboard on
a 5 % descent) for both bundled vehicles and check the study's numbers against
independent computations from the plan and the simulation it reports on: the travel time
from the profile's s and speed columns (constant acceleration per segment), the binding
shares from the ``binding`` column, the worst window from a fresh ``profileopt.verify``, the
baseline's travel time from a fresh plan of the bare road; and one table row per pair. The
route builders are checked against their construction. The GPS routes need the geo extra.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

import profileopt
from profileopt.studies.real_routes import (
    OBSTACLE_FAMILY,
    PLANNED,
    PairRun,
    RealRouteStudy,
    graded_road_m,
    obstacle_route,
    real_route_study,
    study_track_route,
    synthetic_routes,
)

from conftest import ROOT

VEHICLES = ("atv", "atv-resonant")


@pytest.fixture(scope="module")
def short_study() -> tuple[RealRouteStudy, list[PairRun]]:
    routes = {r.name: r for r in synthetic_routes(length_m=60.0)}
    # two roads the planner solves without IPOPT (fast): potholes with its bare road, a washboard alone
    chosen = [routes["potholes +10 %"], dataclasses.replace(routes["washboard -5 %"], baseline=None)]
    runs: list[PairRun] = []
    return real_route_study(chosen, VEHICLES, on_pair=runs.append), runs


def test_one_result_and_one_table_row_per_route_and_vehicle(short_study) -> None:
    study, runs = short_study
    assert [(r.route, r.vehicle) for r in study.results] == [
        (route, vehicle) for route in ("potholes +10 %", "washboard -5 %") for vehicle in VEHICLES]
    assert all(run.result is result for run, result in zip(runs, study.results, strict=True))
    table = study.markdown().splitlines()
    assert len(table) == 2 + len(study.results)
    columns = table[0].count("|")
    for line, result in zip(table[2:], study.results):
        assert line.startswith(f"| {result.route} | {result.vehicle} |") and line.count("|") == columns
    assert study.notes_markdown().count("- **") == len(study.results)


def test_travel_time_and_binding_shares_from_the_profile_columns(short_study) -> None:
    _, runs = short_study
    for run in runs:
        result, profile = run.result, run.profile
        assert result.outcome == PLANNED
        s, v = profile.s_m, profile.speed_mps
        # constant acceleration per segment: the mean speed over a segment is (v_i + v_{i+1}) / 2
        time_s = float(np.sum(2.0 * np.diff(s) / (v[:-1] + v[1:])))
        assert result.travel_time_s == pytest.approx(time_s, rel=1e-9)
        assert result.distance_m == pytest.approx(60.0, abs=1e-9)
        assert result.mean_speed_mps == pytest.approx(60.0 / time_s, rel=1e-9)
        # each boundary stands for the half segments on either side of it
        half = np.diff(s) / 2
        weight = np.concatenate([half, [0.0]]) + np.concatenate([[0.0], half])
        for name, share in result.binding.items():
            assert share == pytest.approx(weight[profile.binding == name].sum() / 60.0, rel=1e-9)
        assert sum(result.binding.values()) == pytest.approx(1.0)
        # the stretches cover the route once, in order, and add up to the shares
        runs_m = result.binding_runs
        assert runs_m[0][1] == 0.0 and runs_m[-1][2] == pytest.approx(60.0)
        assert all(a[2] == b[1] for a, b in zip(runs_m[:-1], runs_m[1:]))
        for name, share in result.binding.items():
            assert sum(b - a for n, a, b in runs_m if n == name) == pytest.approx(60.0 * share, rel=1e-9)
        assert result.sharpest_curvature_1pm == 0.0 and result.min_turn_radius_m == math.inf  # an s,z road


def test_worst_window_and_verdict_are_verifys(short_study) -> None:
    _, runs = short_study
    for run in runs:
        check = profileopt.verify(run.route.route, run.profile, run.vehicle)
        result = run.result
        assert result.worst_window_ratio == check.windows.worst_ratio
        worst = check.windows.describe(check.windows.worst)
        assert (result.worst_window_start_m, result.worst_window_stop_m) == (worst["start_m"], worst["stop_m"])
        assert result.worst_window_start_m <= result.worst_window_peak_s_m <= result.worst_window_stop_m
        assert result.passes == check.passes and result.windows == check.windows.count
        assert result.windows_over == check.windows.over_count
        assert result.gated == any(note.startswith("simulation gate:") for note in run.profile.notes)


def test_the_baseline_is_the_bare_road_planned_alone(short_study) -> None:
    _, runs = short_study
    for run in runs:
        result = run.result
        if run.route.baseline is None:
            assert math.isnan(result.baseline_time_s) and math.isnan(result.time_ratio)
            continue
        bare = profileopt.plan(run.route.baseline, run.vehicle)
        assert result.baseline_time_s == pytest.approx(bare.travel_time_s, rel=1e-12)
        assert result.time_ratio == pytest.approx(result.travel_time_s / bare.travel_time_s, rel=1e-12)


def test_the_synthetic_roads_are_what_they_say() -> None:
    routes = synthetic_routes()
    assert 8 <= len(routes) <= 12 and len({r.name for r in routes}) == len(routes)
    for r in routes:
        s = r.route.s_m
        assert s[0] == 0.0 and s[-1] == pytest.approx(400.0) and np.allclose(np.diff(s), 0.05)
        assert np.array_equal(r.baseline.s_m, s)
    by_name = {r.name: r for r in routes}
    kerbs = by_name["kerb+drop +5 %"]
    obstacle = kerbs.route.z_m - kerbs.baseline.z_m
    assert np.allclose(obstacle, np.where(s >= 150.0, 0.08, 0.0) - np.where(s >= 250.0, 0.08, 0.0))
    middle = (s > 60) & (s < 340)  # the road's grade between its level ends
    assert np.allclose(np.polyfit(s[middle], kerbs.baseline.z_m[middle], 1)[0], 0.05, atol=2e-3)


def test_graded_road_has_its_grades_and_a_continuous_slope() -> None:
    s = np.arange(0.0, 300.0001, 0.05)
    z = graded_road_m(s, [0.0, 0.15, -0.10], [100.0, 200.0], 40.0)
    slope = np.gradient(z, s)
    assert z[0] == 0.0
    assert np.allclose(slope[s < 79], 0.0) and np.allclose(slope[(s > 121) & (s < 179)], 0.15)
    assert np.allclose(slope[s > 221], -0.10)
    assert np.max(np.abs(np.diff(slope))) < 0.25 * 0.05 / 40.0 * 1.01 + 1e-12  # grade changes linearly, 0.25 over 40 m
    assert z[-1] == pytest.approx(0.15 * 100.0 - 0.10 * 100.0)  # the curves are symmetric about their joins


def test_obstacle_family_and_routes() -> None:
    assert len(OBSTACLE_FAMILY) == 180  # 2 x 5 x 5 x 3 blocks and pits, 2 x 5 x 3 kerbs and drops
    route = obstacle_route("block", 0.15, 0.4, 0.05)
    inside = (route.s_m >= 40.0) & (route.s_m < 40.4)
    assert route.s_m[-1] == pytest.approx(60.0) and np.count_nonzero(inside) == 8
    assert np.array_equal(route.z_m, np.where(inside, 0.15, 0.0))
    assert route.source == "block 0.15 m x 0.4 m every 0.05 m"
    assert np.array_equal(obstacle_route("drop", 0.1, 0.0, 0.2).z_m, np.where(np.arange(301) * 0.2 >= 40.0, -0.1, 0.0))


@pytest.mark.geo
def test_the_walk_through_is_a_route_of_the_assumed_class() -> None:
    route = study_track_route("hexbin", ROOT / "examples" / "geo" / "hexbin-track.gpx",
                              terrain_path=ROOT / "data" / "real" / "pdal-lidar" / "hexbin-crop.laz", road_class="C")
    assert route.route.x_m is not None and route.route.assumed_roughness.road_class == "C"
    assert route.route.length_m == pytest.approx(279.3, rel=0.05)  # the README's 279 m
