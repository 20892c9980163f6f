"""Roughness windows (issue 10): the RI of every window from prefix sums, the RI range each
segment meets, the force over a range of terrain, and plans that no longer depend on where
the segments fall (refined segments: tests/planning/test_refine.py)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from conftest import window_ri
from profileopt.errors import InputError
from profileopt.physics.forces import (envelope_force_n, force_n, sbem_tf_envelope_force_n, sbem_tf_force_n,
                               transmissibility_peak_ratio)
from profileopt.planning import plan
from profileopt.core.route import Route
from profileopt.physics.speeds import speed_bands
from profileopt.terrain.synthetic import iso8608_profile
from profileopt.terrain.roughness import range_extremes, roughness_windows


@pytest.mark.slow
def test_window_ri_matches_polyfit_on_a_100_km_route() -> None:
    # 100 km at 0.05 m (2,000,001 samples), 300 m above the datum on a 3 % grade: running
    # sums from the start would lose every digit of a 5 m window's variance out here.
    rng = np.random.default_rng(10)
    s = np.arange(2_000_001) * 0.05
    z = 300.0 + 0.03 * s + 0.02 * np.sin(s / 7.0) + 0.01 * rng.standard_normal(s.size)
    windows = roughness_windows(s, z, 0.1, window_m=5.0)
    assert windows.count > 1_999_000
    picks = np.concatenate([rng.integers(0, windows.count, 150), np.arange(windows.count - 5, windows.count)])
    for k in picks:
        a, b = windows.first_sample[k], windows.stop_sample[k]
        xs, zs = s[a:b], z[a:b]
        # the reference: numpy.polyfit's line through the window, on its own raw coordinates
        residual = zs - np.polyval(np.polyfit(xs, zs, 1), xs)
        assert windows.ri[k] == pytest.approx(np.std(residual) / 0.1, rel=1e-8)
        assert xs[0] >= windows.start_m[k] - 1e-9 and xs[-1] <= windows.start_m[k] + 5.0 + 1e-9


def test_windows_start_and_end_at_every_sample_and_match_a_direct_computation() -> None:
    s = np.cumsum(np.random.default_rng(2).uniform(0.02, 0.08, 3000))  # uneven spacing
    z = 0.05 * np.sin(1.3 * s) + 0.01 * np.cos(7.0 * s)
    route = Route(s, z, source="uneven")
    windows = roughness_windows(s, z, 0.1, window_m=3.0)
    start_ref, ri_ref = window_ri(route, 3.0, 0.1)  # conftest: a padded two-pass computation
    # every window of the reference is in the package's set (same start within 1e-9 m)
    k = np.searchsorted(windows.start_m, start_ref - 1e-9)
    assert np.all(np.abs(windows.start_m[np.minimum(k, windows.count - 1)] - start_ref) <= 1e-9)
    np.testing.assert_allclose(windows.ri[k], ri_ref, rtol=1e-9, atol=1e-12)
    # windows start at every sample that leaves room, and end at every sample after W
    assert set(np.round(s[s + 3.0 <= s[-1]], 9)) <= set(np.round(windows.start_m, 9))
    assert set(np.round(s[s - 3.0 >= s[0]], 9)) <= set(np.round(windows.start_m + 3.0, 9))


def test_range_extremes_against_a_loop() -> None:
    rng = np.random.default_rng(4)
    values = rng.standard_normal(5000)
    first = rng.integers(0, 4900, 2000)
    stop = first + rng.integers(1, 100, 2000)
    least, largest = range_extremes(values, first, stop)
    np.testing.assert_array_equal(least, [values[a:b].min() for a, b in zip(first, stop)])
    np.testing.assert_array_equal(largest, [values[a:b].max() for a, b in zip(first, stop)])


def test_a_window_too_sparse_is_one_line_naming_the_spacing() -> None:
    s = np.arange(0.0, 50.0 + 1e-9, 1.0)
    with pytest.raises(InputError, match=r"holds 6 samples.*every 0.625 m or closer"):
        roughness_windows(s, np.zeros_like(s), 0.1, window_m=5.0)


def test_transmissibility_peak_ratio_is_the_peak() -> None:
    for zeta in (0.05, 0.1, 0.3, 0.5, 0.7):
        r = np.linspace(0.01, 3.0, 300001)
        a = 4 * zeta**2
        t2 = (1 + a * r**2) / ((1 - r**2) ** 2 + a * r**2)  # Eq. (13)'s transmissibility squared
        assert transmissibility_peak_ratio(zeta) == pytest.approx(r[np.argmax(t2)], abs=2e-5)


@pytest.mark.parametrize("vehicle_name", ["atv", "atv-resonant"])
def test_sbem_tf_envelope_bounds_every_elevation_of_the_range(vehicle_name) -> None:
    from profileopt.core.vehicle import load_vehicle

    vehicle = load_vehicle(vehicle_name)
    speeds = np.linspace(0.0, 20.0, 801)[:, None]
    e = np.geomspace(1e-4, 0.4, 240)[None, :]
    force = sbem_tf_force_n(speeds, e, vehicle)  # (speeds, elevations)
    # the speed above which even the widest step (X_w = r) is crossed above resonance
    exact_above = 2 * vehicle.natural_frequency_radps * vehicle.wheel_radius_m * transmissibility_peak_ratio(
        vehicle.damping_ratio) / math.pi
    for i in range(0, 240, 17):
        for j in range(i, 240, 23):
            bound = sbem_tf_envelope_force_n(speeds[:, 0], e[0, i], e[0, j], vehicle)
            worst = force[:, i:j + 1].max(axis=1)
            assert np.all(bound >= worst * (1 - 1e-12))
            fast = speeds[:, 0] >= exact_above
            np.testing.assert_allclose(bound[fast], sbem_tf_force_n(speeds[fast, 0], e[0, j], vehicle), rtol=1e-12)
    # a range of one value is the model itself
    np.testing.assert_allclose(sbem_tf_envelope_force_n(speeds, e, e, vehicle), force, rtol=1e-13)


def test_monotone_models_envelope_is_the_top_and_bad_terrain_is_nan(atv) -> None:
    for model in ("iecm", "sbem_ef", "prev_bem"):
        got = envelope_force_n(3.0, atv, ri_range=(0.01, 0.2), model=model)
        assert got == pytest.approx(force_n(3.0, atv, ri=0.2, model=model), rel=1e-14)
    with pytest.raises(InputError, match="ri_min must not exceed ri_max"):
        envelope_force_n(3.0, atv, ri_range=(0.3, 0.2))
    import casadi as ca

    ri = ca.SX.sym("ri")
    for model in ("iecm", "sbem_ef", "sbem_tf", "prev_bem"):
        f = ca.Function("f", [ri], [force_n(3.0, atv, ri=ri, model=model)])
        # never "admissible"; -5e-324 would round to e_max = -0.0 if only e_max were tested
        assert math.isnan(float(f(-0.1))) and math.isnan(float(f(math.nan))) and math.isnan(float(f(-5e-324)))


def test_speed_bands_of_a_range_are_admissible_for_every_ri_in_it(atv_resonant) -> None:
    ri_min = np.array([0.05, 0.1, 0.2, 0.0])
    ri_max = np.array([0.3, 0.12, 0.6, 0.28])
    bands = speed_bands(ri_max, atv_resonant, ri_min=ri_min)
    limit = atv_resonant.max_transmitted_force_n
    for row in range(4):
        for ri in np.linspace(ri_min[row], ri_max[row], 41):
            for k in range(int(bands.count[row])):
                v = np.linspace(bands.lower_mps[row, k], bands.upper_mps[row, k], 201)
                assert np.all(force_n(v, atv_resonant, ri=np.full_like(v, ri)) <= limit * (1 + 1e-9))


def test_a_kerb_on_a_segment_boundary_is_seen_wherever_the_grid_falls(atv) -> None:
    # Issue 10: a 0.05 m kerb exactly on a 5 m boundary detrended to flat in both segments
    # and was planned at full speed. With windows its RI is the same wherever it lies, so
    # the plan slows for it by the same amount on the boundary and 2.5 m off it.
    s = np.arange(0.0, 200.0 + 1e-9, 0.05)
    base = iso8608_profile("A", 200.0, 0.05, 7).z_m
    times = []
    for kerb_m in (100.0, 102.5):
        z = base + np.where(s >= kerb_m, 0.05, 0.0)
        profile = plan(Route(s, z, source="kerb"), atv, smoothing=0.0, max_jerk_mps3=math.inf)
        at = np.searchsorted(profile.s_m, kerb_m, side="right") - 1
        # a step of height H in a window's middle leaves a detrended residual of about H / 4
        # (the line halves the step; RI ~ 0.0125 / 0.1 m), far above the class A ground's
        assert profile.ri[at] > 0.1 > 5 * profile.ri[0]
        times.append(profile.time_s[-1])
        flat = plan(Route(s, base, source="flat"), atv, smoothing=0.0, max_jerk_mps3=math.inf)
        assert profile.time_s[-1] > flat.time_s[-1] + 0.5  # it slows down for the kerb
    assert times[0] == pytest.approx(times[1], rel=0.02)


def test_travel_time_converges_as_the_segments_shrink(atv) -> None:
    from conftest import ROUTES
    from profileopt.io.routes import read_route

    route = read_route(ROUTES / "krc_rms_2in.csv")
    times = [plan(route, atv, segment_length_m=length, smoothing=0.0, max_jerk_mps3=math.inf).time_s[-1]
             for length in (2.0, 1.0, 0.5)]
    # each halving moves the time less, and 1 m and 0.5 m agree within 2 % (issue 10)
    assert times[0] > times[1] > times[2]
    assert times[0] - times[1] > times[1] - times[2]
    assert times[1] == pytest.approx(times[2], rel=0.02)


def test_batches_change_no_bit(monkeypatch) -> None:
    # the moments are formed in batches of windows (cache); every batch must give the very
    # bits of one pass over the whole route
    import profileopt.terrain.window_sums as window_sums

    rng = np.random.default_rng(3)
    s = np.cumsum(rng.uniform(0.02, 0.08, 20000))
    z = 0.01 * rng.standard_normal(s.size) + 0.001 * s
    whole = roughness_windows(s, z, 0.1, window_m=5.0).ri
    monkeypatch.setattr(window_sums, "WINDOW_BATCH", 997)
    np.testing.assert_array_equal(roughness_windows(s, z, 0.1, window_m=5.0).ri, whole)


def test_grade_batches_change_no_bit(monkeypatch) -> None:
    # path_grade_rad forms its windows' moments in batches too (cache, at a million samples)
    import profileopt.terrain.geometry as geometry
    import profileopt.terrain.window_sums as window_sums

    rng = np.random.default_rng(4)
    s = 1000.0 + np.cumsum(rng.uniform(0.02, 0.08, 20000))
    z = 300.0 + 0.01 * rng.standard_normal(s.size) + 0.05 * np.sin(s / 40.0) * s / 10.0
    whole = geometry.path_grade_rad(s, z, scale_m=10.0)
    monkeypatch.setattr(window_sums, "WINDOW_BATCH", 997)
    np.testing.assert_array_equal(geometry.path_grade_rad(s, z, scale_m=10.0), whole)
    monkeypatch.setattr(window_sums, "WINDOW_BATCH", 10**9)  # one pass over the whole route
    np.testing.assert_array_equal(geometry.path_grade_rad(s, z, scale_m=10.0), whole)


@pytest.mark.parametrize("vehicle_name", ["atv", "atv-resonant"])
def test_crawl_bound_bounds_every_force_below_the_ridge_speed(vehicle_name) -> None:
    # sbem_tf_crawl_bound_n: no elevation in [0, e_max] gives more SBEM:TF force at any speed
    # up to 2 wn r_w r_p / pi (checked on a dense grid of both)
    from profileopt.physics.forces import sbem_tf_crawl_bound_n
    from profileopt.core.vehicle import load_vehicle

    vehicle = load_vehicle(vehicle_name)
    ridge = 2 * vehicle.natural_frequency_radps * vehicle.wheel_radius_m * transmissibility_peak_ratio(
        vehicle.damping_ratio) / math.pi
    speeds = np.linspace(0.0, ridge, 401)[:, None]
    for e_max in (0.01, 0.05, 0.1, 0.3):
        e = np.linspace(1e-6, e_max, 801)[None, :]
        assert sbem_tf_force_n(speeds, e, vehicle).max() <= sbem_tf_crawl_bound_n(e_max, vehicle) * (1 + 1e-12)


def test_bands_of_a_range_for_a_vehicle_that_cannot_reach_its_limit_crawling_are_the_tops(atv) -> None:
    # for atv the crawl bound (276 N at RI 0.6) is far below the 5000 N limit, so a range's
    # bands are exactly those of its largest RI
    rng = np.random.default_rng(5)
    ri = rng.uniform(0.0, 0.6, 500)
    top = speed_bands(ri, atv)
    ranged = speed_bands(ri, atv, ri_min=ri * rng.uniform(0.0, 1.0, 500))
    np.testing.assert_array_equal(ranged.upper_mps, top.upper_mps)
    np.testing.assert_array_equal(ranged.count, top.count)
