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
  most 3 (1 / (h^2 w) + 1 / (h^3 w^2));
* the noise estimate is checked against the noise put in: Gaussian, of standard deviation
  sigma in each coordinate, drawn here with a seed; the median of n >= 500 squared
  residuals is within a few per cent of its expectation (its relative standard error is
  about 1.6 / sqrt(n)), so sigma within 10 %;
* a polyline resampled along its pieces has its corners where the pieces meet: the corner
  points given;
* a U-turn of radius r keeps within r of an out-and-back line's points (its legs r either
  side of the line): the radius of a reversal within the 0.1 m tolerance is 0.1 m, a
  curvature of 10 1/m; a heading turned back by 180, 178 or 150 degrees is how the two legs
  were drawn;
* the length of a path of straights and arcs is the sum of the straights and of radius times
  angle of the arcs.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from profileopt.errors import InputError
from profileopt.core.route import Route, path_distance_m
from profileopt.terrain.geometry import (
    MAX_CURVATURE_1PM,
    MIN_PATH_TOLERANCE_M,
    RouteGeometry,
    SmoothPath,
    estimate_path_noise,
    path_corners,
    path_grade_rad,
    route_geometry,
    sharp_turns,
    smooth_path,
    smooth_track_points,
)
from profileopt.terrain.ground_track import resample_polyline

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
    assert path.tolerance_m == MIN_PATH_TOLERANCE_M
    assert path.max_deviation_m <= MIN_PATH_TOLERANCE_M
    # inactive with a margin of 1000: measured max |kappa| ~ 1e-6 1/m (a radius of 1000 km)
    assert np.max(np.abs(path.curvature_1pm)) < ATV_LATERAL_KAPPA_1PM / 1000


@pytest.mark.parametrize("noise_m", [0.0, 0.01])
def test_25_m_arc_is_found_within_10_percent(noise_m: float) -> None:
    radius = 25.0
    s, x, y, start, end = arc_between_straights(radius, 50.0, noise_m)
    path = smooth_path(x, y)
    kappa = path.curvature_1pm
    assert path.max_deviation_m <= MIN_PATH_TOLERANCE_M
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
    assert 0 < geometry.max_deviation_m <= geometry.tolerance_m == MIN_PATH_TOLERANCE_M
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


def known_path(step_m: float) -> tuple[np.ndarray, np.ndarray, float, float]:
    """Straights, two 40 m arcs (90 deg) and an 8 m hairpin (180 deg), every ``step_m`` of
    length: x, y (m), the length (m) and the sharpest curvature, 1/8 (1/m)."""
    pieces = [(150.0, 0.0), (40.0, math.pi / 2), (100.0, 0.0), (8.0, -math.pi), (100.0, 0.0), (40.0, math.pi / 2),
              (150.0, 0.0)]
    lengths = [r * abs(a) if a else r for r, a in pieces]
    total = float(sum(lengths))
    s = np.arange(0.0, total, step_m)
    heading = np.zeros(s.size)
    x, y = np.zeros(s.size), np.zeros(s.size)
    start, h0, x0, y0 = 0.0, 0.0, 0.0, 0.0
    for (r, a), length in zip(pieces, lengths):
        inside = (s >= start) & (s < start + length)
        u = s[inside] - start
        if a == 0:
            x[inside], y[inside], heading[inside] = x0 + u * math.cos(h0), y0 + u * math.sin(h0), h0
            x0, y0 = x0 + length * math.cos(h0), y0 + length * math.sin(h0)
        else:
            turn = math.copysign(1.0, a)  # +1 left
            cx, cy = x0 - turn * r * math.sin(h0), y0 + turn * r * math.cos(h0)
            h = h0 + turn * u / r
            x[inside], y[inside] = cx + turn * r * np.sin(h), cy - turn * r * np.cos(h)
            h_end = h0 + a
            x0, y0 = cx + turn * r * math.sin(h_end), cy - turn * r * math.cos(h_end)
            h0 = h_end
        start += length
    return x, y, total, 1.0 / 8.0


@pytest.mark.parametrize("sigma_m, uneven", [(0.5, False), (1.5, False), (1.5, True)])
def test_the_noise_estimate_finds_the_noise_put_in(sigma_m: float, uneven: bool) -> None:
    # points every 3 m (or 2 to 4 m) on a 40 m circle, Gaussian noise of sigma in x and y
    rng = np.random.default_rng(29)
    n = 1500
    step = rng.uniform(2.0, 4.0, n) if uneven else np.full(n, 3.0)
    angle = np.cumsum(step) / 40.0
    x = 40 * np.cos(angle) + sigma_m * rng.standard_normal(n)
    y = 40 * np.sin(angle) + sigma_m * rng.standard_normal(n)
    noise = estimate_path_noise(x, y)
    assert noise.noise_m == pytest.approx(sigma_m, rel=0.10)
    assert noise.points >= n - 2  # a measured point on its neighbours' line is dropped only in a run of 3
    # the universal threshold: sigma sqrt(2 ln n)
    assert noise.tolerance_m == pytest.approx(noise.noise_m * math.sqrt(2 * math.log(n)), rel=1e-12)


def test_a_clean_path_gets_the_smallest_tolerance_and_keeps_its_turns() -> None:
    # a surveyed arc (1 cm of noise, every 5 cm): sigma sqrt(2 ln n) = 0.01 * 4.3 < 0.1 m
    s, x, y, start, end = arc_between_straights(25.0, 50.0, 0.01)
    noise = estimate_path_noise(x, y)
    assert noise.noise_m == pytest.approx(0.01, rel=0.10)
    path = smooth_path(x, y)
    assert path.tolerance_m == MIN_PATH_TOLERANCE_M and path.tolerance_source == "estimated"
    middle = np.argmin(np.abs(s - (start + end) / 2))
    assert path.curvature_1pm[middle] == pytest.approx(1 / 25.0, rel=0.10)  # the real turn stays
    given = smooth_path(x, y, tolerance_m=0.5)
    assert given.tolerance_m == 0.5 and given.tolerance_source == "given"


def test_corners_of_a_resampled_polyline_are_its_points() -> None:
    corners_x = np.array([0.0, 10.013, 10.013, 25.37, 30.0])
    corners_y = np.array([0.0, 0.0, 7.021, 7.021, -3.3])
    _, x, y = resample_polyline(corners_x, corners_y, 0.05)
    cx, cy = path_corners(x, y)
    assert cx.size == corners_x.size
    # a corner falls between two samples 5 cm apart: their midpoint, within 2.5 cm of it
    np.testing.assert_allclose(cx, corners_x, atol=0.025)
    np.testing.assert_allclose(cy, corners_y, atol=0.025)
    # a path measured point by point keeps every point
    rng = np.random.default_rng(1)
    px, py = np.arange(50.0), 0.01 * rng.standard_normal(50)
    assert path_corners(px, py)[0].size == 50


def out_and_back(off_deg: float, offset_m: float = 0.0, step_m: float = 0.5) -> tuple[np.ndarray, np.ndarray]:
    """Out 50 m along +x and back, the return leg turned ``off_deg`` off the line (a heading
    change of 180 - off_deg degrees) and moved ``offset_m`` across it."""
    leg = np.arange(0.0, 50.0 + step_m / 2, step_m)
    back = math.radians(180.0 - off_deg)
    x = np.concatenate([leg, 50.0 + math.cos(back) * leg[1:]])
    y = np.concatenate([np.zeros(leg.size), math.sin(back) * leg[1:] + offset_m])
    return x, y


@pytest.mark.parametrize("off_deg, offset_m", [(0.0, 0.0), (0.0, 1e-18), (2.0, 0.0), (30.0, 0.0)])
def test_a_reversal_is_the_sharpest_turn_not_a_straight(off_deg: float, offset_m: float) -> None:
    x, y = out_and_back(off_deg, offset_m)
    path = smooth_path(x, y)
    s = path.s_m
    kappa = np.abs(path.curvature_1pm)
    turn = np.abs(s - 50.0) <= 1.0
    # the U-turn within the 0.1 m tolerance: radius 0.1 m (module docstring)
    assert kappa[turn].max() == pytest.approx(MAX_CURVATURE_1PM, rel=1e-12) == 1 / MIN_PATH_TOLERANCE_M
    assert kappa.max() <= MAX_CURVATURE_1PM
    assert np.all(kappa[np.abs(s - 50.0) >= 10.0] < 1e-3)  # the legs stay straight
    turns = sharp_turns(s, x, y, path, min_turn_radius_m=3.25)
    assert len(turns) == 1
    turn = turns[0]
    assert turn.s_m == pytest.approx(50.0, abs=1.0) and turn.radius_m == pytest.approx(0.1)
    assert math.degrees(turn.heading_change_rad) == pytest.approx(180.0 - off_deg, abs=1.0)
    assert turn.reversal  # 150 degrees and more within 5 m


def test_a_gentle_turn_is_no_sharp_turn() -> None:
    s, x, y, _, _ = arc_between_straights(25.0, 50.0, 0.0)
    path = smooth_path(x, y)
    assert sharp_turns(s, x, y, path, min_turn_radius_m=3.25) == []
    assert sharp_turns(s, x, y, path, min_turn_radius_m=30.0)[0].radius_m == pytest.approx(25.0, rel=0.05)


@pytest.mark.parametrize("sigma_m", [1.0, 1.5])
def test_a_noisy_track_is_moved_onto_a_path_as_long_as_the_true_one(sigma_m: float) -> None:
    true_x, true_y, length, sharpest = known_path(3.0)
    rng = np.random.default_rng(3)
    x = true_x + sigma_m * rng.standard_normal(true_x.size)
    y = true_y + sigma_m * rng.standard_normal(true_y.size)
    raw_length = path_distance_m(x, y)[-1]
    # the zigzag between noisy points: about sigma^2 / h^2 longer (PathNoise.lengthens_share)
    assert raw_length > length * (1 + 0.5 * (sigma_m / 3.0) ** 2)
    done = smooth_track_points(x, y)
    assert done.smoothed and done.tolerance_source == "estimated"
    assert done.noise.noise_m == pytest.approx(sigma_m, rel=0.15)
    moved = np.hypot(done.x_m - x, done.y_m - y)
    assert moved.max() <= done.tolerance_m * (1 + 1e-12) and done.moved_max_m == pytest.approx(moved.max())
    # the smoothed polyline is as long as the path (its last point is up to 3 m short of the end)
    assert path_distance_m(done.x_m, done.y_m)[-1] == pytest.approx(length - 1.5, rel=0.03)
    # and the route's turns: none sharper than half the sharpest true turn's radius
    _, rx, ry = resample_polyline(done.x_m, done.y_m, 0.25)
    assert np.abs(smooth_path(rx, ry).curvature_1pm).max() < 2 * sharpest


def test_a_clean_track_is_kept_and_a_given_tolerance_bounds_the_moves() -> None:
    x, y, _, _ = known_path(3.0)
    done = smooth_track_points(x, y)
    assert not done.smoothed and done.moved_max_m == 0.0
    np.testing.assert_array_equal(done.x_m, x)
    rng = np.random.default_rng(4)
    nx, ny = x + 1.5 * rng.standard_normal(x.size), y + 1.5 * rng.standard_normal(y.size)
    given = smooth_track_points(nx, ny, tolerance_m=2.0)
    assert given.smoothed and given.tolerance_m == 2.0 and given.tolerance_source == "given"
    assert np.hypot(given.x_m - nx, given.y_m - ny).max() <= 2.0 * (1 + 1e-12)
    with pytest.raises(InputError, match="path_tolerance_m"):
        smooth_track_points(nx, ny, tolerance_m=-1.0)


def test_route_geometry_records_the_tolerance_and_why() -> None:
    x, y = out_and_back(0.0)
    s = path_distance_m(x, y)
    geometry = route_geometry(Route(s_m=s, z_m=0 * s, x_m=x, y_m=y), grade_scale_m=10.0, min_turn_radius_m=3.25)
    assert geometry.settings == {"path_tolerance_m": 0.1, "path_tolerance_source": "estimated", "path_noise_m": 0.0}
    assert len(geometry.turns) == 1 and geometry.min_turn_radius_m == 3.25
    # a straight route records the tolerance it was given (or the smallest) and nothing else
    assert route_geometry(Route(s_m=s, z_m=0 * s), grade_scale_m=10.0).settings == {"path_tolerance_m": 0.1}
    assert route_geometry(Route(s_m=s, z_m=0 * s), tolerance_m=2.0,
                          grade_scale_m=10.0).settings == {"path_tolerance_m": 2.0}
