"""The route's turns and slopes (profileopt.terrain.geometry).

References, each derived here by hand, not from the module:

* a circle of radius R has curvature 1/R; a straight line 0;
* the lateral limit of the bundled ATV, 4 m/s^2 at its top speed 20 m/s, is inactive
  where v^2 |kappa| <= 4, i.e. |kappa| <= 4 / 20^2 = 0.01 1/m;
* the least-squares line of samples of a line is that line: a ramp z = g s gives
  theta = atan(g) for any window;
* a kink z = a u (u < 0), b u (u > 0) about the window's centre is (a + b)/2 u plus
  (b - a)/2 |u|, and |u| is even, so over a symmetric window the slope is (a + b)/2;
* the least-squares slope of sin(w s) over [c - h, c + h] (continuous) is
  cov / var = 3 cos(w c) / h^3 (sin(w h) / w^2 - h cos(w h) / w), whose magnitude is at
  most 3 (1 / (h^2 w) + 1 / (h^3 w^2)).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from profileopt.errors import InputError
from profileopt.terrain.geometry import (DEFAULT_PATH_TOLERANCE_M, RouteGeometry, SmoothPath, path_grade_rad,
                                 route_geometry, smooth_path)
from profileopt.core.route import Route

SPACING_M = 0.05
#: |kappa| above which the bundled ATV's lateral limit (4 m/s^2) binds at 20 m/s: 4 / 20^2.
ATV_LATERAL_KAPPA_1PM = 4.0 / 20.0**2


def arc_between_straights(radius_m: float, straight_m: float, noise_m: float,
                          seed: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray, float, float]:
    """A straight along +x, a 90 degree left arc, a straight along +y, every SPACING_M of
    path length, with Gaussian noise on x and y. Returns (s, x, y, arc start, arc end) (m)."""
    arc_m = radius_m * math.pi / 2
    s = np.arange(int(round((2 * straight_m + arc_m) / SPACING_M)) + 1) * SPACING_M
    a = np.clip(s - straight_m, 0.0, arc_m) / radius_m  # angle turned so far (rad)
    x = np.minimum(s, straight_m) + radius_m * np.sin(a)
    y = radius_m * (1 - np.cos(a)) + np.maximum(s - straight_m - arc_m, 0.0)
    rng = np.random.default_rng(seed)
    return (s, x + noise_m * rng.standard_normal(s.size), y + noise_m * rng.standard_normal(s.size),
            straight_m, straight_m + arc_m)


@pytest.mark.slow
def test_noisy_straight_line_leaves_the_lateral_limit_inactive() -> None:
    # 200 m every 5 cm, 1 cm Gaussian noise on x and y: the samples' own second differences
    # read curvatures of order 0.01 * 2 / 0.05^2 = 8 1/m; the fit must read a straight line.
    rng = np.random.default_rng(11)
    s = np.arange(4001) * SPACING_M
    path = smooth_path(s + 0.01 * rng.standard_normal(s.size), 0.01 * rng.standard_normal(s.size))
    assert isinstance(path, SmoothPath)
    assert path.tolerance_m == DEFAULT_PATH_TOLERANCE_M
    assert path.max_deviation_m <= DEFAULT_PATH_TOLERANCE_M
    # inactive with a margin of 1000: measured max |kappa| ~ 1e-6 1/m (a radius of 1000 km)
    assert np.max(np.abs(path.curvature_1pm)) < ATV_LATERAL_KAPPA_1PM / 1000


@pytest.mark.parametrize("noise_m", [0.0, 0.01])
def test_25_m_arc_is_found_within_10_percent(noise_m: float) -> None:
    radius = 25.0
    s, x, y, start, end = arc_between_straights(radius, 50.0, noise_m)
    path = smooth_path(x, y)
    kappa = path.curvature_1pm
    assert path.max_deviation_m <= DEFAULT_PATH_TOLERANCE_M
    middle = np.argmin(np.abs(s - (start + end) / 2))
    # issue text: the arc's curvature 1/R within 10 %; measured 1.4 % (noiseless) and 0.5 %
    assert kappa[middle] == pytest.approx(1 / radius, rel=0.10)
    # a left turn is positive
    assert np.all(kappa[(s > start + 5) & (s < end - 5)] > 0)
    # The fit smears the curvature's jump at the joins over a smoothing scale of about 3.5 m
    # (measured): within 10 % of 1/R only from 5.5 m inside the arc; on the straights |kappa|
    # is 0.018 1/m 0.5 m from a join, 0.004 at 5 m, 0.0013 at 10 m (both noise levels). So
    # on the straights from 10 m beyond the joins (and 10 m from the path's ends) it must be
    # below 0.1 / R = 0.004 1/m, a tenth of the arc's.
    straight = ((s > 10) & (s < start - 10)) | ((s > end + 10) & (s < s[-1] - 10))
    assert np.max(np.abs(kappa[straight])) < 0.1 / radius
    arc_inside = (s > start + 6) & (s < end - 6)
    assert np.max(np.abs(kappa[arc_inside] * radius - 1)) < 0.10


def test_full_circle_curvature_is_one_over_r() -> None:
    radius = 25.0
    angle = np.arange(0.0, 2 * math.pi, SPACING_M / radius)
    # clockwise, to check the sign as well: kappa = -1/R
    path = smooth_path(radius * np.cos(angle), -radius * np.sin(angle))
    # the splines are natural (kappa -> 0 at the path's two ends): 0.5 rad (12.5 m) away from
    # them the curvature is the circle's, measured within 0.2 %
    inside = (angle > 0.5) & (angle < 2 * math.pi - 0.5)
    np.testing.assert_allclose(path.curvature_1pm[inside], -1 / radius, rtol=0.01)


def test_straight_and_tiny_paths_do_not_fail() -> None:
    s = np.arange(1000) * 0.1
    path = smooth_path(3.0 + 0.6 * s, -2.0 + 0.8 * s)  # exactly straight
    assert np.max(np.abs(path.curvature_1pm)) < 1e-9
    np.testing.assert_allclose(path.s_m, s, atol=1e-9)  # s is the chord length
    for n in (2, 3, 4):  # too few to smooth: interpolated, straight stays straight
        path = smooth_path(np.arange(n) * 1.0, np.arange(n) * 2.0)
        assert path.max_deviation_m == 0.0
        assert np.max(np.abs(path.curvature_1pm)) < 1e-12
    # three points on a circle of radius 1 turn left
    path = smooth_path([1.0, 0.0, -1.0], [0.0, 1.0, 0.0])
    assert path.curvature_1pm[1] > 0


@st.composite
def wavy_paths(draw: st.DrawFn) -> tuple[np.ndarray, np.ndarray, float]:
    """A path heading along x that wanders in y (a few sinusoids), sampled unevenly, with
    noise on both coordinates, and a tolerance."""
    seed = draw(st.integers(0, 2**16))
    rng = np.random.default_rng(seed)
    n = draw(st.integers(5, 2000))
    spacing = draw(st.sampled_from([0.05, 0.5, 5.0, 15.0]))
    t = np.cumsum(rng.uniform(0.5, 1.5, n)) * spacing
    y = sum(rng.uniform(0, 0.2) * t[-1] * np.sin(2 * math.pi * t / (t[-1] * rng.uniform(0.1, 2.0)) + rng.uniform(0, 6))
            for _ in range(draw(st.integers(0, 3))))
    noise = draw(st.sampled_from([0.0, 0.01, 0.1, 3.0]))
    x = t + noise * rng.standard_normal(n)
    y = y + noise * rng.standard_normal(n)
    tolerance = draw(st.sampled_from([0.02, 0.1, 0.5, 3.0]))
    return x, y, tolerance


@pytest.mark.slow
@settings(deadline=None, suppress_health_check=[HealthCheck.too_slow])  # examples: the profile's
@given(wavy_paths())
def test_the_deviation_never_exceeds_the_tolerance(case: tuple[np.ndarray, np.ndarray, float]) -> None:
    x, y, tolerance = case
    path = smooth_path(x, y, tolerance_m=tolerance)
    deviation = np.max(np.hypot(path.x_m - x, path.y_m - y))  # recomputed here
    assert deviation <= tolerance
    # the same to the rounding of the coordinates: a few ulps of the largest (3.6e-12 m at 25 km,
    # where a straight path's deviations are themselves rounding)
    ulps = 8 * np.spacing(max(np.max(np.abs(x)), np.max(np.abs(y)), 1.0))
    assert deviation == pytest.approx(path.max_deviation_m, abs=1e-12 + ulps)
    assert np.all(np.isfinite(path.curvature_1pm))


def test_grade_of_a_ramp_is_exact() -> None:
    rng = np.random.default_rng(3)
    s = np.cumsum(rng.uniform(0.02, 0.08, 5000))  # uneven, about 250 m
    s += 1234.0  # far from 0, and a high elevation: no lost digits
    grade = path_grade_rad(s, 1500.0 + 0.15 * s, scale_m=10.0)
    # the least-squares line of a line is the line: atan(0.15) in every window, even clipped
    np.testing.assert_allclose(grade, math.atan(0.15), rtol=0, atol=1e-12)


def test_short_undulations_average_out_to_the_ramp() -> None:
    s = np.arange(4001) * SPACING_M
    amplitude, wavelength, scale = 0.1, 0.5, 10.0
    omega, half = 2 * math.pi / wavelength, scale / 2
    grade = path_grade_rad(s, 0.05 * s + amplitude * np.sin(omega * s), scale_m=scale)
    full = (s >= half) & (s <= s[-1] - half)  # windows not clipped
    # continuous bound (module docstring): 0.1 * 3 (1/(25 * 4 pi) + 1/(125 * 16 pi^2)) = 9.7e-4,
    # against the undulation's own slope amplitude A w = 1.26; 10 % more for 10 samples a
    # wavelength (the midpoint sum differs from the integral by about (w ds)^2 / 24 = 1.6 %).
    bound = amplitude * 3 * (1 / (half**2 * omega) + 1 / (half**3 * omega**2))
    assert np.max(np.abs(grade[full] - math.atan(0.05))) <= 1.1 * bound
    assert 1.1 * bound < amplitude * omega / 1000  # averaged out: a thousandth of it is left


def test_a_kink_moves_the_grade_over_the_scale() -> None:
    s = np.arange(4001) / 20.0  # 0..200 m, s = 100 exactly a sample
    before, after, scale = 0.05, 0.20, 10.0
    z = np.where(s < 100, before * s, before * 100 + after * (s - 100))
    grade = path_grade_rad(s, z, scale_m=scale)
    # windows on one side of the kink see one line (the kink itself lies on both)
    np.testing.assert_allclose(grade[s <= 100 - scale / 2], math.atan(before), rtol=0, atol=1e-12)
    np.testing.assert_allclose(grade[s >= 100 + scale / 2], math.atan(after), rtol=0, atol=1e-12)
    # centred on the kink: (a + b) / 2 (module docstring)
    assert grade[s == 100][0] == pytest.approx(math.atan((before + after) / 2), abs=1e-12)
    across = grade[(s >= 100 - scale / 2) & (s <= 100 + scale / 2)]
    assert np.all(np.diff(across) > 0)  # and it rises steadily between


@pytest.mark.slow
def test_route_geometry() -> None:
    s, x, y, start, end = arc_between_straights(25.0, 50.0, 0.0)
    z = 0.1 * s
    geometry = route_geometry(Route(s_m=s, z_m=z, x_m=x, y_m=y), grade_scale_m=10.0)
    assert isinstance(geometry, RouteGeometry)
    np.testing.assert_array_equal(geometry.curvature_1pm, smooth_path(x, y).curvature_1pm)
    np.testing.assert_allclose(geometry.grade_rad, math.atan(0.1), atol=1e-12)
    assert 0 < geometry.max_deviation_m <= geometry.tolerance_m == DEFAULT_PATH_TOLERANCE_M
    assert geometry.grade_scale_m == 10.0
    flat = route_geometry(Route(s_m=s, z_m=z), tolerance_m=2.0, grade_scale_m=20.0)  # no x, y: straight
    np.testing.assert_array_equal(flat.curvature_1pm, np.zeros(s.size))
    assert flat.max_deviation_m == 0.0 and flat.tolerance_m == 2.0


@pytest.mark.parametrize("tolerance", [0.0, -0.1, math.nan, math.inf])
def test_bad_tolerance_is_an_input_error(tolerance: float) -> None:
    s = np.arange(10.0)
    with pytest.raises(InputError, match="tolerance_m"):
        smooth_path(s, s**2 / 20, tolerance_m=tolerance)
    with pytest.raises(InputError, match="tolerance_m"):
        route_geometry(Route(s_m=s, z_m=0 * s), tolerance_m=tolerance, grade_scale_m=10.0)


@pytest.mark.parametrize("scale", [0.0, -10.0, math.nan])
def test_bad_grade_scale_is_an_input_error(scale: float) -> None:
    s = np.arange(10.0)
    with pytest.raises(InputError, match="scale_m"):
        path_grade_rad(s, 0 * s, scale_m=scale)
    with pytest.raises(InputError, match="scale_m"):
        route_geometry(Route(s_m=s, z_m=0 * s), grade_scale_m=scale)


def test_bad_paths_are_input_errors() -> None:
    with pytest.raises(InputError, match="repeats"):
        smooth_path([0.0, 1.0, 1.0, 2.0], [0.0, 0.0, 0.0, 0.0])
    with pytest.raises(InputError, match="NaN"):
        smooth_path([0.0, 1.0, math.nan], [0.0, 0.0, 0.0])
    with pytest.raises(InputError, match="same length"):
        smooth_path([0.0, 1.0, 2.0], [0.0, 0.0])
    with pytest.raises(InputError, match="increase"):
        path_grade_rad([0.0, 2.0, 1.0], [0.0, 0.0, 0.0], scale_m=1.0)
