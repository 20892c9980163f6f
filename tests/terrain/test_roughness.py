"""Terrain: the roughness index (Eq. 1), worst-case elevation (Eq. 8) and step width (Eq. 2)."""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
import pytest
import scipy.special
import scipy.stats
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from profileopt import InputError, load_vehicle, roughness_index, step_width, worst_case_elevation
from profileopt.terrain.roughness import elevation_z_score, segment_roughness_index

from conftest import REAL_DATA

ATV = load_vehicle("atv")
REAL_PROFILE = REAL_DATA / "iri-road-profile" / "profile_1.txt"


def cosine_profile(amplitude_m: float, frequency_cpm: float, periods: int, per_period: int):
    """A cos(2 pi f s) at the midpoints of a whole number of periods.

    Midpoint sampling makes the profile even about the window's centre while s - centre is
    odd, so its sample covariance with s is exactly 0: the least-squares line is flat and
    both detrend settings have the same closed form, RI = A / (sqrt(2) h).
    """
    s = (np.arange(periods * per_period) + 0.5) / (per_period * frequency_cpm)
    return s, amplitude_m * np.cos(2 * math.pi * frequency_cpm * s)


@pytest.mark.parametrize("detrend", [False, True])
@pytest.mark.parametrize("amplitude_m, frequency_cpm, h", [(0.05, 1.5, 0.1), (0.1, 1.0, 0.1), (0.02, 0.3, 0.25)])
def test_ri_of_sinusoid_whole_periods_is_closed_form(amplitude_m, frequency_cpm, h, detrend):
    s, z = cosine_profile(amplitude_m, frequency_cpm, periods=7, per_period=40)
    # population variance of A cos over whole periods = A^2 / 2, so RI = A / (sqrt(2) h)
    expected = amplitude_m / (math.sqrt(2) * h)
    assert roughness_index(z, h, positions_m=s, detrend=detrend) == pytest.approx(expected, rel=1e-12)


def test_sine_over_whole_periods_raw_ri_and_detrend_effect():
    # A sine (not cosine) correlates with s over a finite window: the raw RI is still exact,
    # detrending removes a little (continuous limit: var drops by 3 A^2 / (pi^2 n^2), n periods).
    n, per = 10, 200
    s = np.arange(n * per) / per
    z = 0.08 * np.sin(2 * math.pi * s)
    raw = roughness_index(z, 0.1, positions_m=s, detrend=False)
    assert raw == pytest.approx(0.08 / (math.sqrt(2) * 0.1), rel=1e-12)
    detrended = roughness_index(z, 0.1, positions_m=s, detrend=True)
    expected = math.sqrt(0.08**2 / 2 - 3 * 0.08**2 / (math.pi**2 * n**2)) / 0.1
    assert detrended == pytest.approx(expected, rel=1e-3)
    assert detrended < raw


def test_population_std_ddof_0():
    # e / h = [0, 1]: population STD = 0.5 (ddof = 1 would give 0.7071)
    assert roughness_index([0.0, 0.1], 0.1, detrend=False) == pytest.approx(0.5, rel=1e-14)
    # [1, 2, 3, 4] / 1: mean 2.5, squared deviations 2.25 + 0.25 + 0.25 + 2.25 = 5, / 4 -> 1.25
    assert roughness_index([1.0, 2.0, 3.0, 4.0], 1.0, detrend=False) == pytest.approx(math.sqrt(1.25), rel=1e-14)


def test_detrend_removes_a_constant_grade_of_a_profile():
    rng = np.random.default_rng(1)
    s = np.sort(rng.uniform(0, 20, 300))
    z = 0.03 * rng.standard_normal(300)
    graded = z + 582.0 + 0.12 * s  # a 12 % climb at absolute altitude
    assert roughness_index(graded, 0.1, positions_m=s) == pytest.approx(roughness_index(z, 0.1, positions_m=s), rel=1e-9)
    # without detrend the grade counts as roughness: STD of 0.12 s on [0, 20] ~ 0.12 * 20 / sqrt(12)
    assert roughness_index(graded, 0.1, positions_m=s, detrend=False) > 5.0
    # a pure line is perfectly smooth
    assert roughness_index(3.0 - 0.5 * s, 0.1, positions_m=s) == pytest.approx(0.0, abs=1e-9)


def test_detrend_removes_a_plane_of_a_point_cloud():
    rng = np.random.default_rng(2)
    x, y = rng.uniform(0, 10, 500), rng.uniform(-3, 3, 500)
    bumps = 0.02 * rng.standard_normal(500)
    plane = 120.0 + 0.1 * x - 0.3 * y
    flat = np.column_stack([x, y, bumps])
    tilted = np.column_stack([x, y, bumps + plane])
    assert roughness_index(tilted, 0.1) == pytest.approx(roughness_index(flat, 0.1), rel=1e-9)
    # independent: STD of the residual of numpy's least-squares plane
    design = np.column_stack([np.ones(500), x, y])
    resid = tilted[:, 2] - design @ np.linalg.lstsq(design, tilted[:, 2], rcond=None)[0]
    assert roughness_index(tilted, 0.1) == pytest.approx(np.std(resid) / 0.1, rel=1e-9)
    # raw: plain population STD of z / h
    assert roughness_index(tilted, 0.1, detrend=False) == pytest.approx(np.std(tilted[:, 2] / 0.1), rel=1e-12)


@pytest.mark.parametrize("detrend", [True, False])
def test_segment_ri_of_real_road_profile_matches_lstsq_residual(detrend):
    # michalsorel/iri profile_1.txt (MIT): 544 m of road at 0.25 m, absolute elevations ~582 m
    data = np.loadtxt(REAL_PROFILE)
    s, z = data[:, 0], data[:, 1]
    assert z.min() > 500  # absolute elevations: the precision trap this test is about
    starts = np.arange(0, s.size, 20)  # 5 m segments; the last one is shorter
    got = segment_roughness_index(s, z, starts, 0.1, detrend=detrend)
    bounds = np.append(starts, s.size)
    expected = []
    for a, b in zip(bounds[:-1], bounds[1:]):
        if detrend:
            design = np.column_stack([np.ones(b - a), s[a:b]])
            resid = z[a:b] - design @ np.linalg.lstsq(design, z[a:b], rcond=None)[0]
        else:
            resid = z[a:b] - z[a:b].mean()
        expected.append(np.std(resid) / 0.1)
    expected = np.array(expected)
    assert got.shape == (starts.size,)
    assert np.all(expected > 1e-4)  # real roughness, not a degenerate zero
    np.testing.assert_allclose(got, expected, rtol=1e-7)
    # roughness_index of one segment agrees too
    a, b = bounds[3], bounds[4]
    assert roughness_index(z[a:b], 0.1, positions_m=s[a:b], detrend=detrend) == pytest.approx(expected[3], rel=1e-7)


@pytest.mark.parametrize(
    "bad, match",
    [([0.0, np.nan, 1.0], "NaN"), ([1.0], "at least 2"), (np.zeros((4, 2)), "shape"), (np.zeros((2, 3)), "at least 3")],
)
def test_roughness_index_rejects_bad_input(bad, match):
    with pytest.raises(ValueError, match=match):
        roughness_index(bad, 0.1)


@pytest.mark.parametrize("h", [0.0, -0.1, math.nan])
def test_roughness_index_rejects_bad_clearance(h):
    with pytest.raises(ValueError, match="clearance"):
        roughness_index([0.0, 1.0], h)


def test_e_max_factor_for_pe_0999999():
    # NOTES.md: sqrt(2) erfinv(2 * 0.999999 - 1) = 4.7534; independently the standard normal
    # quantile, since Phi(z) = (1 + erf(z / sqrt(2))) / 2 = Pe  <=>  z = sqrt(2) erfinv(2 Pe - 1)
    assert elevation_z_score(0.999999) == pytest.approx(4.7534, abs=5e-5)
    assert elevation_z_score(0.999999) == pytest.approx(scipy.stats.norm.ppf(0.999999), rel=1e-9)
    assert elevation_z_score(0.975) == pytest.approx(1.959963984540054, rel=1e-9)  # the familiar 1.96
    # Eq. (8): e_max = 4.7534 * RI * h; RI = 0.5, h = 0.1 -> 0.23767 m
    assert worst_case_elevation(0.5, ATV) == pytest.approx(math.sqrt(2) * scipy.special.erfinv(0.999998) * 0.05, rel=1e-9)
    assert worst_case_elevation(0.5, ATV) == pytest.approx(0.23767, abs=1e-5)
    np.testing.assert_allclose(worst_case_elevation(np.array([0.0, 0.2]), ATV), [0.0, 0.2 * 0.1 * 4.753424], rtol=1e-6)


@pytest.mark.parametrize("ri", [math.nan, -0.1, np.array([0.1, np.nan]), np.array([-1e-9])])
def test_worst_case_elevation_rejects_nan_and_negative_ri(ri):
    with pytest.raises(ValueError, match="RI"):
        worst_case_elevation(ri, ATV)


def test_step_width_eq2_and_saturation():
    # Eq. (2) with r = 0.1 m: e = 0.02 -> sqrt(2 * 0.02 * 0.1 - 0.02^2) = sqrt(0.0036) = 0.06
    assert step_width(0.02, ATV) == pytest.approx(0.06, rel=1e-14)
    # e = 0.05 -> sqrt(0.01 - 0.0025) = sqrt(0.0075)
    assert step_width(0.05, ATV) == pytest.approx(math.sqrt(0.0075), rel=1e-14)
    # saturated at r once e >= r
    np.testing.assert_allclose(step_width(np.array([0.1, 0.1 + 1e-12, 0.3, 5.0]), ATV), 0.1, rtol=1e-12)
    assert step_width(0.0, ATV) == 0.0
    # continuous at e = r from below: X_w(r - d) = sqrt(r^2 - d^2) -> r
    assert step_width(0.1 - 1e-6, ATV) == pytest.approx(0.1, abs=1e-10)
    # symbolic: the same expression, with a kink (not a jump) at r
    e = ca.SX.sym("e")
    fun = ca.Function("xw", [e], [step_width(e, ATV)])
    assert float(fun(0.02)) == pytest.approx(0.06, rel=1e-14)
    assert float(fun(0.4)) == pytest.approx(0.1, rel=1e-14)


# ---------------------------------------------------------------- property tests (hypothesis)

# Elevations of 0 or between 1 um and 1 m in size: hypothesis otherwise finds values like
# 1e-157 whose squares are subnormal (1e-314), where the variance loses its relative
# precision however it is summed; such elevations are not terrain.
finite = st.one_of(st.just(0.0), st.floats(1e-6, 1.0), st.floats(-1.0, -1e-6))


@settings(deadline=None)  # examples: the profile's (tests/conftest.py)
@given(
    z=arrays(np.float64, st.integers(3, 60), elements=finite),
    spacing=st.floats(0.05, 2.0),
    offset=st.floats(-1000.0, 1000.0),
    grade=st.floats(-0.5, 0.5),
    scale=st.one_of(st.floats(1e-3, 50.0), st.floats(-50.0, -1e-3)),  # no underflow to subnormals
)
def test_ri_invariant_to_offset_and_grade_and_linear_in_amplitude(z, spacing, offset, grade, scale):
    s = np.arange(z.size) * spacing
    h = 0.1
    base = roughness_index(z, h, positions_m=s)
    # tolerance from rounding: the moments of O(offset + grade * length) numbers lose about
    # eps * size^2 in the variance, i.e. sqrt of that in the STD
    size = abs(offset) + abs(grade) * s[-1] + np.abs(z).max()
    atol = 1e-6 * size / h
    assert roughness_index(z + offset + grade * s, h, positions_m=s) == pytest.approx(base, rel=1e-9, abs=atol)
    # linear in amplitude, both definitions (STD scales with |scale|)
    assert roughness_index(scale * z, h, positions_m=s) == pytest.approx(abs(scale) * base, rel=1e-9, abs=1e-6 * abs(scale) * np.abs(z).max() / h)
    raw = roughness_index(z, h, positions_m=s, detrend=False)
    assert roughness_index(scale * z, h, positions_m=s, detrend=False) == pytest.approx(abs(scale) * raw, rel=1e-9, abs=1e-12)
    # raw RI is invariant to the offset only
    assert roughness_index(z + offset, h, positions_m=s, detrend=False) == pytest.approx(raw, rel=1e-9, abs=1e-6 * (abs(offset) + 1) / h)


# ------------------------------------------------------------------ deprecated forms (issue 9)


def test_input_errors_name_the_parameters():
    with pytest.raises(InputError, match="clearance_m"):
        roughness_index([0.0, 1.0], 0.0)
    with pytest.raises(InputError, match="positions_m"):
        roughness_index([0.0, 1.0, 2.0], 0.1, positions_m=[0.0, 1.0])
    with pytest.raises(TypeError):
        roughness_index([0.0, 1.0], 0.1, position_m=[0.0, 1.0])  # a misspelt keyword
