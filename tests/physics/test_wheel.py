"""The exact path of a rigid wheel over the polyline of the samples (profileopt.physics.wheel).

References, each derived here by hand from the geometry (not from the module):

* Step of height e < r (paper's Fig. 2, Eq. 2): on flat ground the wheel's lowest point is
  at 0; the circle of radius r about the step's top edge (0, e) reaches y = 0 where
  e + sqrt(r^2 - s^2) - r = 0, i.e. s = -X_w with X_w = sqrt(2 e r - e^2). There the
  contact jumps from the ground to the edge: the slope jumps from 0 to the circle's,
  -s / sqrt(r^2 - s^2) = X_w / (r - e). The wheel then rolls over the edge on that circle
  until it stands on the top, at s = 0.
* Straight incline of slope m: the radius to the contact point is normal to the line, so
  the centre stands r / cos(atan m) = r sqrt(1 + m^2) above it, vertically; the lowest
  point r (sqrt(1 + m^2) - 1) above the ground below it, y = z + r (sqrt(1 + m^2) - 1).
* A step of 0.15 m > r = 0.1 m between two samples 5 cm apart is a ramp of slope
  m = 3 from B = (x0, 0) to T = (x0 + 0.05, 0.15). Its offset line,
  y = 3 (s - x0) + r (sqrt(10) - 1), holds for the centre positions whose contact point is
  on the ramp, s in [x0 - 3 r / sqrt(10), x0 + 0.05 - 3 r / sqrt(10)]; it meets the flat
  ground's y = 0 at s1 = x0 - r (sqrt(10) - 1) / 3 (inside that range: a kink of slope
  0 -> 3, the wheel meets the wall), and at its upper end s2 it runs tangentially onto the
  circle about T, which carries the wheel until it stands on the top at x0 + 0.05.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from profileopt.errors import InputError
from profileopt.io import read_route
from profileopt.terrain.roughness import step_width
from profileopt.core.vehicle import load_vehicle
from profileopt.physics.wheel import wheel_envelope_m
from profileopt.physics.wheel import wheel_path

from conftest import ROUTES

ATV = load_vehicle("atv")  # r = 0.1 m


def brute_force_path(s: np.ndarray, z: np.ndarray, r: float, query: np.ndarray) -> np.ndarray:
    """The definition: the highest centre over the polyline's points within r, minus r.

    The polyline (continued 2 r along its end chords) is cut every 2 um, vertices
    included; a tangent contact point is then missed by <= 1 um, which lowers the maximum
    by at most (1 + m^2)^1.5 / r * (1 um)^2 / 2 < 2e-10 m for slopes |m| <= 3.
    """
    head, tail = (z[1] - z[0]) / (s[1] - s[0]), (z[-1] - z[-2]) / (s[-1] - s[-2])
    xs = np.concatenate([[s[0] - 2 * r], s, [s[-1] + 2 * r]])
    zs = np.concatenate([[z[0] - 2 * r * head], z, [z[-1] + 2 * r * tail]])
    out = np.empty(query.size)
    for j, x in enumerate(query):
        xp = np.concatenate([np.arange(x - r, x + r, 2e-6), xs[np.abs(xs - x) <= r]])
        zp = np.interp(xp, xs, zs)
        out[j] = np.max(zp + np.sqrt(np.maximum(r * r - (xp - x) ** 2, 0.0))) - r
    return out


@pytest.mark.parametrize("e", [0.005, 0.02, 0.05, 0.09])
def test_a_step_lower_than_the_wheel_is_met_x_w_before_its_edge(e: float) -> None:
    r = ATV.wheel_radius_m
    s = np.array([-1.0, -1e-9, 0.0, 1.0])  # flat, a wall 1 nm wide, flat at e
    z = np.array([0.0, 0.0, e, e])
    path = wheel_path(s, z, r)
    x_w = math.sqrt(2 * e * r - e * e)
    assert x_w == pytest.approx(float(step_width(e, ATV)), rel=1e-12)  # Eq. 2 as the package has it
    kinks = path.kinks()
    where = np.flatnonzero(np.abs(kinks) > 1e-9)
    assert where.size == 1  # one kink: where the wheel meets the edge
    assert path.breaks_m[1 + where[0]] == pytest.approx(-x_w, abs=1e-12)
    assert kinks[where[0]] == pytest.approx(x_w / (r - e), rel=1e-9)
    # flat before, the circle about the edge from -X_w to 0, the top after
    q = np.linspace(-0.5, 0.5, 2001)
    expected = np.where(q < -x_w, 0.0, np.where(q < 0, e + np.sqrt(np.maximum(r * r - q * q, 0)) - r, e))
    assert np.max(np.abs(path.evaluate(q)[0] - expected)) < 1e-12
    arc = path.piece_index(np.array([-0.5 * x_w]))[0]
    assert path.is_arc[arc] and path.x_ref_m[arc] == 0.0 and path.z_ref_m[arc] == e


@pytest.mark.parametrize("grade", [-2.0, -0.3, 0.0, 0.05, 0.3, 3.0])
def test_a_straight_incline_is_the_line_raised_exactly_between_the_samples(grade: float) -> None:
    r = 0.1
    rng = np.random.default_rng(7)
    s = 3.0 + np.cumsum(rng.uniform(0.002, 0.3, 200))  # spacings from 2 mm to 3 r
    z = 250.0 + grade * s
    path = wheel_path(s, z, r)
    q = np.sort(rng.uniform(s[0], s[-1], 5000))  # anywhere, not only at the samples
    y, dy, d2y = path.evaluate(q)
    lift = r * (math.sqrt(1 + grade * grade) - 1)
    assert np.max(np.abs(y - (250.0 + grade * q + lift))) < 1e-12 * (1 + abs(grade) * s.max())
    assert np.allclose(dy, grade, rtol=0, atol=1e-9) and np.all(d2y == 0)
    assert np.max(np.abs(path.kinks()), initial=0.0) < 1e-9  # no kink anywhere


@pytest.mark.parametrize("down", [False, True], ids=["up", "down"])
def test_a_step_taller_than_the_wheel_sampled_every_5_cm_is_a_ramp_of_slope_3(down: bool) -> None:
    # curb.csv's 0.15 m curb, r = 0.1 m: the wheel follows the ramp the samples make.
    r, x0 = 0.1, 10.0
    s = np.round(np.arange(0.0, 20.0 + 1e-9, 0.05), 10)
    z = np.where(s > x0 + 1e-9, 0.15, 0.0)  # B = (10, 0), T = (10.05, 0.15)
    if down:  # the mirror image: the same path, read backwards
        s, z = np.round(20.0 - s[::-1], 10), z[::-1]
    path = wheel_path(s, z, r)
    root10 = math.sqrt(10.0)
    s1 = x0 - r * (root10 - 1) / 3  # the wheel meets the wall
    s2 = x0 + 0.05 - 3 * r / root10  # the contact reaches T
    q = np.linspace(9.5, 10.5, 4001)
    expected = np.where(q < s1, 0.0, np.where(q < s2, 3 * (q - x0) + r * (root10 - 1),
                        np.where(q < x0 + 0.05, 0.15 + np.sqrt(np.maximum(r * r - (q - x0 - 0.05) ** 2, 0)) - r, 0.15)))
    y = path.evaluate(20.0 - q if down else q)[0]
    assert np.max(np.abs(y - expected)) < 1e-12
    kinks = path.kinks()
    big = np.flatnonzero(np.abs(kinks) > 1e-9)
    assert big.size == 1  # the join at T is tangent: one kink
    assert path.breaks_m[1 + big[0]] == pytest.approx(20.0 - s1 if down else s1, abs=1e-12)
    assert abs(kinks[big[0]]) == pytest.approx(3.0, rel=1e-12)
    # at the samples alone the wheel's height would not show the ramp's full slope
    ramp = path.evaluate(np.array([20.0 - 0.5 * (s1 + s2) if down else 0.5 * (s1 + s2)]))[1][0]
    assert abs(ramp) == pytest.approx(3.0, rel=1e-12)


@pytest.mark.slow
def test_the_path_is_the_definition_at_any_point_of_rough_irregular_ground() -> None:
    r = 0.1
    rng = np.random.default_rng(3)
    s = np.cumsum(rng.uniform(0.01, 0.25, 120))
    z = 40.0 + np.cumsum(rng.uniform(-1.0, 1.0, s.size) * np.diff(s, prepend=s[0] - 0.1))
    path = wheel_path(s, z, r)
    q = np.concatenate([rng.uniform(s[0], s[-1], 300), path.breaks_m[1:-1]])
    reference = brute_force_path(s, z, r, q)
    y = path.evaluate(q)[0]
    assert np.all(reference <= y + 1e-11)  # nothing on the polyline sticks into the wheel
    assert np.max(y - reference) < 1e-9  # and the wheel touches it
    # continuous at every break; kinks only where the slope really jumps
    inner = np.arange(path.pieces - 1)
    assert np.max(np.abs(path.evaluate(path.breaks_m[1:-1], inner)[0]
                         - path.evaluate(path.breaks_m[1:-1], inner + 1)[0])) < 1e-12
    assert 0 < np.count_nonzero(np.abs(path.kinks()) > 1e-9) < path.pieces


def test_the_path_agrees_with_the_envelope_at_the_samples_of_the_krc_course() -> None:
    # wheel_envelope_m evaluates the same definition at the samples only, by another route
    # (every circle and offset line within r of each sample, no pieces).
    route = read_route(ROUTES / "krc_rms_1in.csv")
    path = wheel_path(route.s_m, route.z_m, 0.1)
    y = path.evaluate(route.s_m)[0]
    assert np.max(np.abs(y - wheel_envelope_m(route.s_m, route.z_m, 0.1))) < 1e-12
    assert path.breaks_m[0] == route.s_m[0] and path.breaks_m[-1] == route.s_m[-1]
    assert np.all(np.diff(path.breaks_m) > 0)


def test_a_wheel_of_radius_0_is_the_polyline() -> None:
    s = np.array([0.0, 1.0, 1.5, 3.0])
    z = np.array([0.0, 1.0, 0.0, 0.3])
    path = wheel_path(s, z, 0.0)
    assert np.array_equal(path.breaks_m, s)
    q = np.linspace(0.0, 3.0, 61)
    assert np.allclose(path.evaluate(q)[0], np.interp(q, s, z), atol=1e-15)
    assert np.allclose(path.kinks(), [-3.0, 2.2])


def test_a_fine_sinusoid_at_a_high_elevation_gives_a_piece_or_two_per_sample() -> None:
    # Nearly parallel offset lines (a slope change of 4e-5 per sample) 150 m up: rounding
    # must not invent crossings (before the local datum, each round found new ones).
    s = np.arange(0.0, 20.0 + 1e-9, 0.005)
    z = 150.0 + 0.02 * np.sin(2 * np.pi * s / 10.0)
    path = wheel_path(s, z, 0.1)
    assert path.pieces < 2 * s.size
    assert np.max(np.abs(path.evaluate(s)[0] - wheel_envelope_m(s, z, 0.1))) < 1e-12


def test_bad_input_is_refused() -> None:
    s = np.linspace(0.0, 1.0, 11)
    with pytest.raises(InputError, match="wheel radius"):
        wheel_path(s, 0 * s, -0.1)
    with pytest.raises(InputError, match="increase strictly"):
        wheel_path(s[::-1], 0 * s, 0.1)
    with pytest.raises(InputError, match="finite"):
        wheel_path(s, np.where(s > 0.5, np.nan, 0.0), 0.1)


def test_a_straight_vertex_leaves_no_gap_between_the_offset_lines() -> None:
    # Found by tests/planning/test_planner_properties.py (the step limit builds the path of
    # a route's first metres): two samples, r = 0.4 m. The chord continued beyond the first sample is
    # straight, but its offset line and the first segment's were computed with shifts an
    # ulp apart, and a slope comparison called the vertex concave: a 1-ulp interval with no
    # piece, and an IndexError. A vertex carries an arc wherever the spans leave a gap.
    s = np.array([-0.004180029166969869, 0.06192404104749893])
    z = np.array([0.09747487404780592, 0.09309106274632796])
    path = wheel_path(s, z, 0.4)
    assert path.breaks_m[0] == s[0] and path.breaks_m[-1] == s[-1]
    # a straight chord of slope m: the wheel rests on it, its lowest point r (sqrt(1 + m^2) - 1)
    # above it (the centre is r along the normal, r sqrt(1 + m^2) above the line)
    m = (z[1] - z[0]) / (s[1] - s[0])
    y = path.evaluate(s)[0]
    np.testing.assert_allclose(y, z + 0.4 * (math.sqrt(1 + m * m) - 1), rtol=0, atol=1e-12)
