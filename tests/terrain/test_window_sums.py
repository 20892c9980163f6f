"""Roughness windows (issue 10): the RI of every window from prefix sums, the RI range each
segment meets, the force over a range of terrain, and plans that no longer depend on where
the segments fall (refined segments: tests/planning/test_refine.py)."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from conftest import direct_ri, window_sets
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
        assert xs[0] >= windows.start_m[k] - 1e-9 and xs[-1] <= windows.stop_m[k] + 1e-9


def test_windows_at_every_offset_match_a_direct_computation() -> None:
    s = np.cumsum(np.random.default_rng(2).uniform(0.02, 0.08, 3000))  # uneven spacing
    z = 0.05 * np.sin(1.3 * s) + 0.01 * np.cos(7.0 * s)
    windows = roughness_windows(s, z, 0.1, window_m=3.0)
    # conftest: the sets found from the offsets directly, their RI by two passes per window
    first, stop, a_lo, a_hi = window_sets(s, 3.0)
    np.testing.assert_array_equal(windows.first_sample, first)
    np.testing.assert_array_equal(windows.stop_sample, stop)
    np.testing.assert_allclose(windows.ri, direct_ri(s, z, first, stop, 0.1), rtol=1e-9, atol=1e-12)
    # the extent is the hull of the windows [a, a + W] holding the set
    np.testing.assert_allclose(windows.start_m, a_lo, rtol=0, atol=1e-9)
    np.testing.assert_allclose(windows.stop_m, a_hi + 3.0, rtol=0, atol=1e-9)
    # among them, the windows starting at every sample that leaves room and ending at every
    # sample after W
    held = set(zip(first.tolist(), stop.tolist()))
    for j in np.flatnonzero(s + 3.0 <= s[-1]):
        assert (j, int(np.searchsorted(s, s[j] + 3.0 + 1e-9, side="right"))) in held
    for k in np.flatnonzero(s - 3.0 >= s[0]):
        assert (int(np.searchsorted(s, s[k] - 3.0 - 1e-9, side="left")), k + 1) in held


def _offset_sets(s: np.ndarray, window_m: float) -> dict[tuple[int, int], tuple[float, float]]:
    """Brute force over offsets: every sample set j..k-1 a window [a, a + W] holds, for a
    at every breakpoint (a sample, or a sample less W) in [s_0, s_end - W] and between
    each two consecutive ones (the set is constant on each open interval), with the hull of
    the stretches [a, a + W] holding it."""
    points = np.concatenate([s, s - window_m, [s[0], s[-1] - window_m]])
    points = np.unique(points[(points >= s[0]) & (points <= s[-1] - window_m)])
    sets: dict[tuple[int, int], tuple[float, float]] = {}
    for a, lo, hi in [(p, p, p) for p in points] + [(0.5 * (p + q), p, q) for p, q in itertools.pairwise(points)]:
        inside = np.flatnonzero((s >= a) & (s <= a + window_m))
        key = (int(inside[0]), int(inside[-1]) + 1)
        old = sets.get(key, (math.inf, -math.inf))
        sets[key] = (min(old[0], lo), max(old[1], hi + window_m))
    return sets


@pytest.mark.parametrize("spacing", ["uniform", "uneven", "coarse"])
def test_windows_at_every_offset_are_every_distinct_sample_set_with_its_extent(spacing) -> None:
    # Issue 29: a window starting between two samples holds a set no window starting or
    # ending at a sample holds. The entries are every set a window [a, a + W] holds for
    # some real a, each once, with the hull of those windows as its extent; the reference
    # enumerates the offsets directly (_offset_sets) and fits each set with numpy.polyfit.
    rng = np.random.default_rng(11)
    if spacing == "uniform":  # W a whole number of spacings (0.5 m and 4 m: exact in binary)
        s, width = 0.5 * np.arange(60), 4.0
    elif spacing == "uneven":
        s, width = np.cumsum(rng.uniform(0.1, 0.5, 80)), 4.3
    else:  # spacing jumps: windows whose ends pass several samples while a passes one
        s, width = np.cumsum(np.repeat([0.05, 0.6, 0.1, 0.45], 20)), 5.0
    z = 0.02 * rng.standard_normal(s.size) + 0.03 * s
    windows = roughness_windows(s, z, 0.1, window_m=width)
    ref = _offset_sets(s, width)
    got = {(int(f), int(t)): (float(a), float(b))
           for f, t, a, b in zip(windows.first_sample, windows.stop_sample, windows.start_m, windows.stop_m)}
    assert len(got) == windows.count and set(got) == set(ref)
    for key, (lo, hi) in ref.items():
        assert got[key] == pytest.approx((lo, hi), abs=1e-12)
        xs, zs = s[key[0]:key[1]], z[key[0]:key[1]]
        ri = np.std(zs - np.polyval(np.polyfit(xs, zs, 1), xs)) / 0.1
        assert windows.ri[list(got).index(key)] == pytest.approx(ri, rel=1e-9)
    # sorted for the searches of overlapping(): both ends non-decreasing
    assert np.all(np.diff(windows.start_m) >= 0) and np.all(np.diff(windows.stop_m) >= 0)
    # about two sets per sample: one more than the windows starting at samples
    assert windows.count > 1.5 * np.count_nonzero(s <= s[-1] - width)
    # overlapping(): the entries whose extent shares a point with a stretch, against a loop
    lo, hi = np.sort(rng.uniform(s[0] - 1.0, s[-1] + 1.0, (2, 200)), axis=0)
    first, stop = windows.overlapping(lo, hi)
    for i in range(lo.size):
        meets = np.flatnonzero((windows.start_m <= hi[i]) & (windows.stop_m >= lo[i]))
        assert meets.tolist() == list(range(first[i], stop[i]))


def test_a_window_between_samples_can_be_rougher_than_every_window_at_a_sample() -> None:
    # Flat ground at 0, then 20 samples zigzagging +-1 cm, then flat again, every 0.25 m,
    # W = 5 m = 20 spacings. A window starting strictly between the sample before the zigzag
    # and its first holds exactly the zigzag; every window starting or ending at a sample
    # holds a flat sample as well, which lies near the zigzag's line (residual ~0), so its
    # population variance is the zigzag's sum of squares over one more sample: by hand,
    # RI_at_a_sample <= sqrt(20 / 21) RI_between (plus the flat sample's small residual).
    s = 0.25 * np.arange(81)
    z = np.where((s >= 10.0) & (s < 15.0), 0.01 * (-1.0) ** np.arange(81), 0.0)
    windows = roughness_windows(s, z, 0.1, window_m=5.0)
    zigzag = (40, 60)  # samples 40..59: 10 m to 14.75 m
    k = list(zip(windows.first_sample.tolist(), windows.stop_sample.tolist())).index(zigzag)
    xs, zs = s[40:60], z[40:60]
    ri_between = np.std(zs - np.polyval(np.polyfit(xs, zs, 1), xs)) / 0.1
    assert windows.ri[k] == pytest.approx(ri_between, rel=1e-9) and windows.ri.max() == windows.ri[k]
    assert windows.start_m[k] == 9.75 and windows.stop_m[k] == 15.0  # a in (9.75, 10)
    # the windows at samples, directly: [s_j, s_j + W] and [s_j - W, s_j]
    at_samples = []
    for a in np.concatenate([s[s <= 15.0], s[s >= 5.0] - 5.0]):
        inside = (s >= a - 1e-9) & (s <= a + 5.0 + 1e-9)
        at_samples.append(np.std(z[inside] - np.polyval(np.polyfit(s[inside], z[inside], 1), s[inside])) / 0.1)
    assert max(at_samples) < 0.99 * ri_between
    assert max(at_samples) == pytest.approx(math.sqrt(20 / 21) * ri_between, rel=0.01)


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


def test_a_gap_in_fine_samples_is_named_as_a_gap() -> None:
    # every 0.05 m but for 10 m missing after 49.95 m: the window is thin because of the gap,
    # not the spacing, and the line says where it is
    s = np.concatenate([np.arange(0.0, 49.97, 0.05), np.arange(60.0, 100.0 + 1e-9, 0.05)])
    with pytest.raises(InputError, match=r"holds 7 samples \(the samples jump from 49.95 to 60 m: a gap of 10 m\); "
                                         r"measuring roughness needs at least 8: fill the gap or sample"):
        roughness_windows(s, np.zeros_like(s), 0.1, window_m=5.0)
    # evenly sparse: no gap named
    sparse = np.arange(0.0, 50.0 + 1e-9, 1.0)
    with pytest.raises(InputError) as refused:
        roughness_windows(sparse, np.zeros_like(sparse), 0.1, window_m=5.0)
    assert "gap" not in str(refused.value)


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
