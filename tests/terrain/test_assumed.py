"""Assumed roughness (issue 12): the expected RI of an ISO 8608 class, routes that carry an
assumed roughness, plans made with it and verify's synthetic roughness on such routes.

References are independent of the code under test: K against ``numpy.polyfit`` residuals of
sampled sinusoids, E[sigma^2] against seeded realisations of
:func:`profileopt.terrain.synthetic.iso8608_profile` measured by
:func:`profileopt.terrain.roughness.roughness_windows` (docs/paper-notes.md, "Assumed roughness: ISO
8608 classes").
"""

from __future__ import annotations

import math
import subprocess

import numpy as np
import pytest

from profileopt.io.profiles import write_profile
from profileopt.terrain.assumed import AssumedRoughness
from profileopt.errors import InputError
from profileopt.io import read_route
from profileopt.io.routes import route_metadata_lines
from profileopt.terrain.classes import (detrending_gain, iso8608_expected_rms_m, iso8608_expected_variance_m2,
                                          iso8608_ri)
from profileopt.terrain.synthetic import ISO8608_GD0_M3, iso8608_profile, iso8608_variance_m2
from profileopt.terrain.roughness import roughness_windows
from profileopt.io import read_profile
from profileopt.core.segments import segment_route
from profileopt.planning import plan
from profileopt.core.route import Route
from profileopt.physics.simulate import simulate_quarter_car
from profileopt.verification.verify import verify

from conftest import PROFILEOPT


def polyfit_gain(n_cpm: float, window_m: float, samples: int) -> float:
    """Phase-averaged mean square of a unit-variance sinusoid after numpy.polyfit's line,
    over ``samples`` points spanning [0, window_m]: the reference for K."""
    s = np.linspace(0.0, window_m, samples)
    residual = []
    for phase in np.linspace(0.0, 2.0 * np.pi, 64, endpoint=False):  # 64 phases average cos^2 exactly
        z = math.sqrt(2.0) * np.cos(2.0 * np.pi * n_cpm * s + phase)
        residual.append(np.mean((z - np.polyval(np.polyfit(s, z, 1), s)) ** 2))
    return float(np.mean(residual))


@pytest.mark.parametrize("n_cpm", [0.01, 0.05, 0.1, 0.2, 0.5, 1.0, 2.7])
def test_detrending_gain_matches_polyfit_residuals(n_cpm: float) -> None:
    # 20001 samples approximate the continuous window: a window of N samples measures like a
    # continuous one of N spacings (docs/paper-notes.md), W + W / 20000, so K at that length
    reference = polyfit_gain(n_cpm, 5.0, 20001)
    assert detrending_gain(n_cpm, window_m=5.0 + 5.0 / 20000) == pytest.approx(reference, rel=1e-6)


@pytest.mark.parametrize("n_cpm", [0.02, 0.1, 0.5])
def test_a_sampled_window_measures_like_a_continuous_one_a_spacing_longer(n_cpm: float) -> None:
    # 101 samples over 5 m: K at 5.05 m within 0.1 % (the rest is O(1/N^2)); at 5 m it is up to 4 % off
    reference = polyfit_gain(n_cpm, 5.0, 101)
    assert detrending_gain(n_cpm, window_m=5.05) == pytest.approx(reference, rel=1e-3)


def test_detrending_gain_series_and_closed_form_meet() -> None:
    # the series (below a = 0.3) and the closed form must agree where they meet, and K ~ a^4 / 45
    a = np.array([0.3 * (1 - 1e-12), 0.3 * (1 + 1e-12)])
    k = detrending_gain(a / (np.pi * 5.0), window_m=5.0)
    assert k[0] == pytest.approx(k[1], rel=1e-9)
    tiny = 1e-3
    assert detrending_gain(tiny / (np.pi * 5.0), window_m=5.0) == pytest.approx(tiny**4 / 45, rel=1e-6)


def test_without_detrending_power_the_integral_is_the_band_variance() -> None:
    # for a window far longer than every wave K -> 1 and E[sigma^2] tends to the band's whole
    # variance Gd(n0) n0^2 (1/n_min - 1/n_max) (iso8608_variance_m2, an independent formula);
    # K's ripples average out to within 1 % when the window is 100 times the longest wave
    whole = iso8608_variance_m2(ISO8608_GD0_M3["C"], 1.0, 4.0)
    assert iso8608_expected_variance_m2("C", window_m=100.0, n_min_cpm=1.0, n_max_cpm=4.0) == \
        pytest.approx(whole, rel=1e-2)


def starting_at_samples_ri(s_m: np.ndarray, z_m: np.ndarray, clearance_m: float, window_m: float) -> np.ndarray:
    """RI of the roughness windows the statistics here are about, N samples d apart over W
    (measuring like W + d): one starting at each sample, the last entry of each first sample
    (a window between samples, issue 29, holds one sample fewer and measures like W)."""
    windows = roughness_windows(s_m, z_m, clearance_m, window_m=window_m)
    return windows.ri[np.append(windows.first_sample[1:] != windows.first_sample[:-1], True)]


@pytest.mark.slow
@pytest.mark.parametrize("spacing_m", [0.05, 0.1])
def test_mean_window_variance_of_realisations_matches_the_expectation(spacing_m: float) -> None:
    # 24 independent seeded class C profiles of 2 km; each profile's mean of sigma^2 over its
    # windows is one independent draw, so the standard error of the grand mean is their
    # sample STD / sqrt(24) (about 0.07 % here). The reference is E[sigma^2] at W + spacing,
    # the continuous window a sampled one measures like (docs/paper-notes.md); the tolerance
    # is 4 standard errors plus 0.3 % for the O(1/N^2) rest of that equivalence at 51 samples.
    window_m, clearance_m = 5.0, 0.1
    means = []
    for seed in range(24):
        s, z = iso8608_profile("C", 2000.0, spacing_m, seed)
        means.append(np.mean(starting_at_samples_ri(s, z, clearance_m, window_m) ** 2) * clearance_m**2)
    means = np.array(means)
    standard_error = means.std(ddof=1) / math.sqrt(means.size)
    expected = iso8608_expected_variance_m2("C", window_m=window_m + spacing_m)
    assert standard_error < 0.005 * expected  # the test has the power to see a 1 % error
    assert abs(means.mean() - expected) < 4 * standard_error + 0.003 * expected
    # and the test can tell: the continuous window W alone is off by about spacing / W
    assert abs(means.mean() - iso8608_expected_variance_m2("C", window_m=window_m)) > 4 * standard_error


def test_class_ri_doubles_per_class_and_scales_with_clearance() -> None:
    # Gd(n0) quadruples per class (ISO 8608), so the RMS doubles; RI = RMS / h
    values = [iso8608_expected_rms_m(c, window_m=5.0) for c in "ABCDEFGH"]
    assert np.allclose(np.array(values[1:]) / values[:-1], 2.0, rtol=1e-12)
    assert iso8608_ri("c", window_m=5.0, clearance_m=0.2) == pytest.approx(values[2] / 0.2, rel=1e-12)
    # class C over 5 m: 4.025 mm (docs/paper-notes.md table)
    assert values[2] == pytest.approx(4.025e-3, rel=1e-3)


@pytest.mark.parametrize("bad", ["I", "", "CC", 3, None])
def test_unknown_class_is_one_line(bad) -> None:
    with pytest.raises(InputError, match="not an ISO 8608 class") as info:
        iso8608_ri(bad, window_m=5.0, clearance_m=0.1)
    assert "\n" not in str(info.value)


@pytest.mark.parametrize("window_m", [0.0, -1.0, math.inf, math.nan])
def test_bad_window_is_refused(window_m: float) -> None:
    with pytest.raises(InputError, match="window_m"):
        iso8608_expected_rms_m("C", window_m=window_m)


# --- the assumed roughness of a route -------------------------------------------------------



def test_assumed_roughness_gives_the_class_ri_or_the_given_one() -> None:
    by_class = AssumedRoughness(road_class="d")
    assert by_class.road_class == "D" and by_class.label == "ISO 8608 class D"
    assert by_class.ri_for(clearance_m=0.1, window_m=5.0) == iso8608_ri("D", window_m=5.0, clearance_m=0.1)
    given = AssumedRoughness(ri=0.05)
    assert given.label == "RI 0.05 given"
    assert given.ri_for(clearance_m=0.3, window_m=2.0) == 0.05


@pytest.mark.parametrize("fields", [{}, {"road_class": "C", "ri": 0.1}, {"road_class": "Z"}, {"ri": -0.01},
                                    {"ri": math.nan}, {"ri": math.inf}, {"ri": 2.5}, {"ri": "lots"}])
def test_assumed_roughness_refuses_bad_fields_in_one_line(fields: dict) -> None:
    with pytest.raises(InputError) as info:
        AssumedRoughness(**fields)
    assert "\n" not in str(info.value)


def write_route(tmp_path, comments: str, name: str = "route.csv"):
    path = tmp_path / name
    s = np.arange(0.0, 20.0001, 0.05)
    path.write_text(comments + "s,z\n" + "".join(f"{a:.2f},{0.01 * a:.4f}\n" for a in s), encoding="utf-8")
    return path


@pytest.mark.parametrize("assumed", [AssumedRoughness(road_class="C"), AssumedRoughness(ri=0.0123456789012),
                                     AssumedRoughness(ri=0.0)])
def test_route_files_carry_the_assumed_roughness_both_ways(tmp_path, assumed) -> None:
    lines = route_metadata_lines(assumed)
    assert len(lines) == 1
    path = write_route(tmp_path, "# from a DEM\n" + "\n".join(lines) + "\n# another comment\n")
    assert read_route(path).assumed_roughness == assumed


def test_route_file_reads_the_documented_spellings(tmp_path) -> None:
    assert read_route(write_route(tmp_path, "#roughness_class=e\n")).assumed_roughness == AssumedRoughness(road_class="E")
    assert read_route(write_route(tmp_path, "# roughness_ri = 0.05\n")).assumed_roughness == AssumedRoughness(ri=0.05)
    assert read_route(write_route(tmp_path, "# roughness classes are not measured here\n")).assumed_roughness is None
    assert route_metadata_lines(None) == []


@pytest.mark.parametrize("comments, line, says", [
    ("# a\n# roughness_class = Q\n", 2, "roughness_class = 'Q'"),
    ("# roughness_ri = 0.05 m\n", 1, "roughness_ri = '0.05 m'"),
    ("# roughness_ri = 20\n", 1, "roughness_ri = '20'"),
    ("# roughness_class = C\n# roughness_ri = 0.1\n", 2, "a second roughness line"),
])
def test_bad_roughness_lines_are_one_line_naming_file_and_line(tmp_path, comments, line, says) -> None:
    path = write_route(tmp_path, comments)
    with pytest.raises(InputError) as info:
        read_route(path)
    message = str(info.value)
    assert message.startswith(f"{path}: line {line}: ") and says in message and "\n" not in message


# --- planning with it ------------------------------------------------------------------------




#: a smooth DEM-like route: a constant 2 % grade, sampled at 0.05 m (its windows' RI is ~0)
SMOOTH_S_M = np.arange(0.0, 150.0001, 0.05)
SMOOTH_Z_M = 0.02 * SMOOTH_S_M


def smooth_route(assumed: AssumedRoughness | None) -> Route:
    return Route(SMOOTH_S_M, SMOOTH_Z_M, source="smooth.csv", assumed_roughness=assumed)


def test_every_window_gets_the_assumed_ri_in_the_measured_windows_places(atv) -> None:
    measured = segment_route(smooth_route(None), atv, roughness_window_m=4.0)
    assumed = segment_route(smooth_route(AssumedRoughness(road_class="D")), atv, roughness_window_m=4.0)
    ri = iso8608_ri("D", window_m=4.0, clearance_m=atv.ground_clearance_m)  # the window actually used
    assert np.all(assumed.windows.ri == ri) and np.all(assumed.ri == ri) and np.all(assumed.ri_min == ri)
    assert np.all(measured.windows.ri < 1e-6)  # the route itself measures nothing (rounding only)
    for field in ("start_m", "first_sample", "stop_sample"):
        assert np.array_equal(getattr(assumed.windows, field), getattr(measured.windows, field))


def test_a_route_shorter_than_the_window_uses_its_length(atv) -> None:
    route = Route(SMOOTH_S_M[:61], SMOOTH_Z_M[:61], assumed_roughness=AssumedRoughness(road_class="C"))  # 3 m
    seg = segment_route(route, atv, segment_length_m=1.0, roughness_window_m=5.0)
    assert seg.windows.window_m == pytest.approx(3.0)
    assert seg.ri[0] == pytest.approx(iso8608_ri("C", window_m=3.0, clearance_m=atv.ground_clearance_m), rel=1e-12)


def test_plan_says_the_roughness_was_assumed(atv) -> None:
    profile = plan(smooth_route(AssumedRoughness(road_class="F")), atv)
    ri = iso8608_ri("F", window_m=5.0, clearance_m=atv.ground_clearance_m)
    assert np.allclose(profile.ri, ri, rtol=0, atol=0)
    assert f"roughness assumed, not measured: ISO 8608 class F, RI {ri:.4g} over 5 m windows for this vehicle" \
        in profile.notes
    assert profile.summary()["roughness"] == {"source": "assumed", "label": "ISO 8608 class F", "ri": ri,
                                              "window_m": 5.0}
    # class F (RI 0.32) must slow the atv below what the bare smooth route allows
    assert profile.travel_time_s > 1.2 * plan(smooth_route(None), atv).travel_time_s


def test_a_measured_route_says_so_and_a_read_profile_keeps_the_label(atv, tmp_path) -> None:
    assert plan(smooth_route(None), atv).summary()["roughness"] == {"source": "measured"}
    path = tmp_path / "profile.csv"
    write_profile(plan(smooth_route(AssumedRoughness(ri=0.05)), atv), path)
    assert read_profile(path).summary()["roughness"] == {"source": "assumed", "label": "RI 0.05 given"}


# --- verify on such a route ------------------------------------------------------------------


def window_rms_m(s_m: np.ndarray, z_m: np.ndarray, window_m: float) -> float:
    return float(np.sqrt(np.mean(starting_at_samples_ri(s_m, z_m, 1.0, window_m) ** 2)))


@pytest.mark.parametrize("assumed, spacing_m", [(AssumedRoughness(road_class="C"), 0.05),
                                                (AssumedRoughness(ri=0.05), 0.05),
                                                (AssumedRoughness(road_class="C"), 0.25)])
def test_the_realisation_has_the_assumed_window_rms(assumed, spacing_m: float) -> None:
    # one 4 km realisation: the mean of sigma^2 over its windows scatters by about 0.3 % (see the
    # 24-seed test above: 0.07 % for 24 x 2 km), so 2 % holds it with room; the reference is
    # the assumed RMS^2 times the sampled-window factor E(W + d) / E(W) over the band used
    # (docs/paper-notes.md): 1 % at 0.05 m, 5 % at 0.25 m (where the band stops at 1.8 cycles/m
    # and the realisation is scaled up to the assumed RMS)
    s = np.arange(0.0, 4000.0001, spacing_m)
    z = assumed.realisation_m(s, clearance_m=0.1, window_m=5.0, seed=7)
    n_min, n_max = assumed.realisation_band_cpm(s)
    assert n_max == pytest.approx(min(4.0, 0.9 / (2 * spacing_m)))
    shape = assumed.road_class or "C"
    factor = (iso8608_expected_variance_m2(shape, window_m=5.0 + spacing_m, n_max_cpm=n_max)
              / iso8608_expected_variance_m2(shape, window_m=5.0, n_max_cpm=n_max))
    wanted = assumed.ri_for(clearance_m=0.1, window_m=5.0) * 0.1
    assert window_rms_m(s, z, 5.0) ** 2 == pytest.approx(wanted**2 * factor, rel=0.02)


def test_verify_drives_the_assumed_roughness_deterministically(atv) -> None:
    route = smooth_route(AssumedRoughness(road_class="E"))
    profile = plan(route, atv)
    first = verify(route, profile, atv, roughness_seed=5)
    again = verify(route, profile, atv, roughness_seed=5)
    other = verify(route, profile, atv, roughness_seed=6)
    note = [n for n in first.notes if n.startswith("roughness assumed (ISO 8608 class E)")]
    assert len(note) == 1 and "seed 5" in note[0]
    assert np.array_equal(first.transmitted_peak_n, again.transmitted_peak_n)
    assert not np.array_equal(first.transmitted_peak_n, other.transmitted_peak_n)
    # the bare route (a constant grade) excites almost nothing: the same drive over it stays
    # below 20 N (the speed changes on the grade), so a peak of hundreds of newtons is the
    # synthetic class E roughness
    bare = simulate_quarter_car(route.s_m, route.z_m, profile.s_m, profile.speed_mps, atv)
    assert np.max(bare.transmitted_peak_n) < 20.0
    assert np.max(first.transmitted_peak_n) > 10 * np.max(bare.transmitted_peak_n) + 100.0
    assert first.windows.count == segment_route(route, atv).windows.count


def test_verify_of_a_measured_route_is_unchanged_by_the_seed(atv) -> None:
    route = Route(SMOOTH_S_M, SMOOTH_Z_M + 0.01 * np.sin(2 * np.pi * SMOOTH_S_M / 3.0), source="bumpy.csv")
    profile = plan(route, atv)
    a, b = verify(route, profile, atv, roughness_seed=1), verify(route, profile, atv, roughness_seed=2)
    assert np.array_equal(a.transmitted_peak_n, b.transmitted_peak_n)
    assert not any("roughness assumed" in n for n in a.notes)


@pytest.mark.slow
def test_verify_command_reports_the_synthetic_roughness(tmp_path) -> None:
    route = write_route(tmp_path, "# from a DEM\n" + route_metadata_lines(AssumedRoughness(road_class="D"))[0] + "\n")
    profile = tmp_path / "profile.csv"
    done = subprocess.run([*PROFILEOPT, "plan", str(route), "--vehicle", "atv", "-o", str(profile)],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    outputs = []
    for seed in ("4", "4", "5"):
        done = subprocess.run([*PROFILEOPT, "verify", str(route), str(profile), "--seed", seed],
                              capture_output=True, text=True, timeout=300)
        assert done.returncode in (0, 4), done.stderr
        outputs.append(done.stdout)
    assert "note: roughness assumed (ISO 8608 class D): simulated on the route's elevation plus a random " \
           "ISO 8608 class D profile, seed 4," in outputs[0]
    assert outputs[0] == outputs[1] and outputs[0] != outputs[2]
    done = subprocess.run([*PROFILEOPT, "verify", str(route), str(profile), "--seed", "-3"],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 2 and "--seed" in done.stderr
