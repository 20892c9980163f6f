"""Synthetic terrain (ISO 8608, washboard, step, ramp) and the bundled example routes (the
readers of the real data they come from: tests/io/test_elevation.py).

Reference values are closed forms derived in the comments (NOTES.md, "Terrain for examples
and tests: ISO 8608"), hand-built files, or numbers stated by the data's source.
"""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.signal import welch

from profileopt import load_vehicle, speed_bands
from profileopt.terrain.synthetic import (
    ISO8608_GD0_M3,
    iso8608_profile,
    iso8608_sections,
    iso8608_variance_m2,
    ramp,
    step,
    washboard,
)
from profileopt.terrain.roughness import roughness_index, segment_roughness_index

from conftest import REAL_DATA, ROUTES

N0 = 0.1  # ISO 8608 reference spatial frequency (cycles/m)


def closed_form_variance(gd0_m3: float, n_min: float, n_max: float) -> float:
    # integral of Gd(n0) (n/n0)^-2 dn from n_min to n_max = Gd(n0) n0^2 (1/n_min - 1/n_max)
    return gd0_m3 * N0**2 * (1.0 / n_min - 1.0 / n_max)


# ---------------------------------------------------------------------------- ISO 8608


def test_class_table_is_iso8608_geometric_means():
    # NOTES.md: A 16, B 64, ..., H 262144 (1e-6 m^3), a factor 4 per class
    expected = {"A": 16, "B": 64, "C": 256, "D": 1024, "E": 4096, "F": 16384, "G": 65536, "H": 262144}
    assert ISO8608_GD0_M3 == pytest.approx({k: v * 1e-6 for k, v in expected.items()}, rel=1e-12)


def test_notes_example_class_c_sigma_is_15_mm():
    # NOTES.md: class C over 0.011-2.83 cycles/m has sigma ~ 15 mm. By hand:
    # 256e-6 * 0.01 * (1/0.011 - 1/2.83) = 2.56e-6 * 90.556 = 2.318e-4 m^2 -> 15.2 mm
    assert math.sqrt(iso8608_variance_m2(256e-6, 0.011, 2.83)) == pytest.approx(0.01523, abs=1e-5)
    s, z = iso8608_profile("C", 20_000.0, 0.05, seed=11, n_max_cpm=2.83)
    assert np.std(z) == pytest.approx(0.0152, rel=0.03)


@pytest.mark.parametrize("road_class, n_min, n_max", [("C", 0.011, 4.0), ("E", 0.05, 2.0), ("A", 0.011, 9.0)])
def test_variance_matches_closed_form(road_class, n_min, n_max):
    reference = closed_form_variance(ISO8608_GD0_M3[road_class], n_min, n_max)
    variances = [np.var(iso8608_profile(road_class, 5_000.0, 0.05, seed, n_min, n_max).z_m) for seed in range(8)]
    # the amplitudes are fixed and the phases random, so each profile is close and the mean closer
    assert np.mean(variances) == pytest.approx(reference, rel=0.03)
    assert np.all(np.abs(np.array(variances) / reference - 1.0) < 0.10)


def test_short_profile_variance_over_seeds():
    # 300 m is shorter than the FFT period (8 / n_min = 727 m): the sample variance then
    # varies from seed to seed (by ~25 %, the few longest waves dominate it) but averages
    # to the closed form, less the little that the window's own mean takes out. Over 200
    # seeds the standard error of the mean is ~2 %.
    reference = closed_form_variance(ISO8608_GD0_M3["D"], 0.011, 4.0)
    variances = [np.var(iso8608_profile("D", 300.0, 0.05, seed).z_m) for seed in range(200)]
    assert 0.90 * reference < np.mean(variances) < 1.06 * reference


def test_psd_has_slope_minus_two_and_the_class_level():
    s, z = iso8608_profile("D", 20_000.0, 0.05, seed=3)
    n, psd = welch(z, fs=1.0 / 0.05, nperseg=4096)  # one-sided PSD, m^2 per (cycles/m)
    band = (n > 0.05) & (n < 3.0)
    slope, intercept = np.polyfit(np.log(n[band]), np.log(psd[band]), 1)
    assert slope == pytest.approx(-2.0, abs=0.05)
    # ISO 8608's Gd is one-sided: the fitted line at n0 is Gd(n0) of class D
    assert math.exp(intercept) * N0**slope == pytest.approx(1024e-6, rel=0.10)
    # nothing above n_max = 4 cycles/m (only the window's leakage, orders of magnitude down)
    above = (n > 5.0) & (n < 9.0)
    assert np.max(psd[above]) < 1e-4 * 1024e-6 * (N0 / 4.0) ** 2


def test_same_seed_same_profile_and_classes_scale():
    a = iso8608_profile("C", 1_000.0, 0.05, seed=5)
    b = iso8608_profile("C", 1_000.0, 0.05, seed=5)
    np.testing.assert_array_equal(a.z_m, b.z_m)
    np.testing.assert_array_equal(a.s_m, np.arange(20_001) * 0.05)
    assert not np.allclose(iso8608_profile("C", 1_000.0, 0.05, seed=6).z_m, a.z_m)
    # one class up is 4x Gd(n0), so the same phases give twice the elevation
    np.testing.assert_allclose(iso8608_profile("d", 1_000.0, 0.05, seed=5).z_m, 2.0 * a.z_m, rtol=1e-12)


def test_sections_scale_one_profile_and_join_smoothly():
    length = 500.0
    b_then_d = iso8608_sections([("B", length), ("D", length)], 0.05, seed=9, transition_m=10.0)
    unit = iso8608_profile("A", 2 * length, 0.05, seed=9).z_m / math.sqrt(16e-6)  # Gd(n0) = 1
    s = b_then_d.s_m
    before, after = s < length - 5.0, s > length + 5.0
    # away from the join the profile is the same random profile scaled to each class
    np.testing.assert_allclose(b_then_d.z_m[before], math.sqrt(64e-6) * unit[before], rtol=1e-12)
    np.testing.assert_allclose(b_then_d.z_m[after], math.sqrt(1024e-6) * unit[after], rtol=1e-12)
    # across the join no step: the largest sample-to-sample change there is no larger
    # than in the rough section itself
    join = (s > length - 6.0) & (s < length + 6.0)
    assert np.max(np.abs(np.diff(b_then_d.z_m[join]))) <= np.max(np.abs(np.diff(b_then_d.z_m[after])))


@pytest.mark.parametrize(
    "kwargs, words",
    [
        (dict(road_class="Z"), "road_class"),
        (dict(road_class=3), "road_class"),
        (dict(length_m=-1.0), "length_m"),
        (dict(length_m=float("nan")), "length_m"),
        (dict(spacing_m=0.0), "spacing_m"),
        (dict(spacing_m=200.0), "smaller than length_m"),
        (dict(n_max_cpm=10.0), "Nyquist"),
        (dict(n_min_cpm=5.0), "greater than n_min_cpm"),
        (dict(seed=-1), "seed"),
        (dict(seed=1.5), "seed"),
    ],
)
def test_bad_arguments_say_what_is_wrong(kwargs, words):
    args = dict(road_class="C", length_m=100.0, spacing_m=0.05, seed=0) | kwargs
    with pytest.raises(ValueError, match=words):
        iso8608_profile(**args)


def test_sections_refuse_bad_input():
    with pytest.raises(ValueError, match="empty"):
        iso8608_sections([], 0.05, seed=0)
    with pytest.raises(ValueError, match="transition_m"):
        iso8608_sections([("B", 100.0), ("C", 5.0), ("B", 100.0)], 0.05, seed=0, transition_m=10.0)
    with pytest.raises(ValueError, match="road_class"):
        iso8608_sections([("B", 100.0), ("Q", 100.0)], 0.05, seed=0)


# ------------------------------------------------------------- washboard, step, ramp


def test_washboard_ri_is_amplitude_over_sqrt2_h():
    # NOTES.md (Fig. 1): over whole periods a sinusoid of amplitude A has STD A / sqrt(2),
    # so RI = A / (sqrt(2) h). Sampled 10 times a period over 5 periods the sum is exact.
    s = np.arange(50) * 0.05
    z = washboard(s, amplitude_m=0.04, wavelength_m=0.5)
    assert roughness_index(z, 0.1, positions_m=s, detrend=False) == pytest.approx(0.04 / (math.sqrt(2) * 0.1), rel=1e-12)
    # With the segment's line removed (the default), part of a sine that starts at zero
    # height goes with the line: over n periods of length L, cov(s, A sin) = -A L / (2 pi n)
    # and var(s) = L^2 / 12, so the line takes 3 A^2 / (pi^2 n^2) of the A^2 / 2 variance:
    # RI = A / (sqrt(2) h) sqrt(1 - 6 / (pi^2 n^2)); the discrete sum differs by ~2e-4 here.
    s = np.arange(100) * 0.05
    z = washboard(s, amplitude_m=0.04, wavelength_m=1.0)
    expected = 0.04 / (math.sqrt(2) * 0.1) * math.sqrt(1.0 - 6.0 / (math.pi**2 * 5**2))
    assert roughness_index(z, 0.1, positions_m=s) == pytest.approx(expected, rel=1e-3)


def test_washboard_window_step_and_ramp():
    s = np.arange(0.0, 10.0, 0.25)
    z = washboard(s, 0.1, 2.0, start_m=2.0, end_m=6.0)
    assert np.all(z[(s < 2.0) | (s >= 6.0)] == 0.0)
    assert z[s == 2.25][0] == pytest.approx(0.1 * math.sin(math.pi / 4))  # 1/8 of the 2 m wave in
    assert z[s == 2.5][0] == pytest.approx(0.1)  # crest a quarter wavelength in
    assert z[s == 3.0][0] == pytest.approx(0.0, abs=1e-15)  # half a wavelength: back to zero
    np.testing.assert_array_equal(step(s, 5.0, 0.15), np.where(s >= 5.0, 0.15, 0.0))
    r = ramp(s, 2.0, 6.0, -0.4)  # a 10 % descent
    assert r[s == 1.0][0] == 0.0 and r[s == 4.0][0] == pytest.approx(-0.2) and r[s == 9.0][0] == pytest.approx(-0.4)
    with pytest.raises(ValueError, match="wavelength_m"):
        washboard(s, 0.1, 0.0)
    with pytest.raises(ValueError, match="end_m"):
        ramp(s, 3.0, 3.0, 1.0)


# ----------------------------------------------------------------- bundled routes


def read_csv(path: Path) -> tuple[list[str], np.ndarray]:
    lines = [ln for ln in path.read_text().splitlines() if not ln.startswith("#")]
    return lines[0].split(","), np.array([[float(x) for x in ln.split(",")] for ln in lines[1:]])


@pytest.mark.slow
def test_bundled_routes_are_what_make_routes_writes(tmp_path):
    subprocess.run(
        [sys.executable, str(ROUTES / "make_routes.py"), "--out", str(tmp_path), "--quiet", "--real", str(REAL_DATA)],
        check=True, capture_output=True, text=True, timeout=120,
    )
    synthetic = {"trail.csv", "washboard.csv", "curb.csv"}
    real_names = {"krc_rms_1in.csv", "krc_rms_2in.csv", "krc_rms_4in.csv", "iri_road.csv", "mojstrovka.csv"}
    made = {p.name for p in tmp_path.glob("*.csv")}
    assert made == synthetic | real_names
    for name in sorted(made):
        assert (tmp_path / name).read_bytes() == (ROUTES / name).read_bytes(), f"{name} differs: rerun make_routes.py"
    for name in synthetic | real_names:
        assert (ROUTES / name).is_file()
    assert sum((ROUTES / n).stat().st_size for n in synthetic | real_names) < 3e6


def test_washboard_route_has_an_above_resonance_band():
    columns, table = read_csv(ROUTES / "washboard.csv")
    assert columns == ["s", "z"]
    s, z = table[:, 0], table[:, 1]
    vehicle = load_vehicle("atv-resonant")
    edges = np.arange(0.0, s[-1], 5.0)
    ri = segment_roughness_index(s, z, np.searchsorted(s, edges), vehicle.ground_clearance_m)
    bands = speed_bands(ri, vehicle)
    wash = (edges >= 150.0) & (edges < 300.0)
    rough = (edges >= 350.0) & (edges < 375.0)
    smooth = ~(wash | rough)
    # washboard: RI ~ A / (sqrt(2) h) = 0.04 / 0.1414 = 0.283; a slow band from rest and a
    # fast one above resonance (NOTES.md, "Which root")
    assert np.all(np.abs(ri[wash] - 0.283) < 0.01)
    assert np.all(bands.count[wash] == 2)
    assert np.all((bands.first()[wash] > 0.25) & (bands.first()[wash] < 0.35))
    assert np.all((bands.largest()[wash] > 3.0) & (bands.largest()[wash] < 3.6))
    # rough corrugation: RI ~ 0.5, the upper band has closed (it closes near RI 0.45)
    assert np.all(ri[rough] > 0.47) and np.all(bands.count[rough] == 1)
    assert np.all(bands.largest()[rough] < 0.3)
    # smooth ground lets the vehicle reach any speed up to v_max
    assert np.all(bands.first()[smooth] == vehicle.max_speed_mps)


def test_curb_route_has_speed_limits_and_visible_curbs():
    columns, table = read_csv(ROUTES / "curb.csv")
    assert columns == ["s", "z", "speed_limit"]
    s, z, limit = table.T
    assert s[-1] == 200.0 and set(np.unique(limit)) == {8.0, 12.0}
    edges = np.arange(0.0, 200.0, 5.0)
    ri = segment_roughness_index(s, z, np.searchsorted(s, edges), 0.1)
    # a step H in the middle of a segment, least-squares line removed: residual STD H / 4
    # (var of the unit step 1/4 minus cov^2 / var(s) = (1/8)^2 * 12 = 3/16), so RI ~ 0.375
    curbs = np.isin(edges, [100.0, 150.0])
    assert np.all(np.abs(ri[curbs] - 0.375) < 0.02) and np.all(ri[~curbs] < 0.05)
