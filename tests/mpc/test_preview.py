"""The parametric terrain preview (profileopt.mpc.preview): one expression of fixed size, its
parameters set from the terrain measured so far, never below the requirement it bounds."""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import ROUTES

from profileopt.core.vehicle import load_vehicle
from profileopt.errors import InputError
from profileopt.io.routes import read_route
from profileopt.mpc.horizon import step_speed_envelope, terrain_envelope
from profileopt.mpc.preview import TerrainPreview
from profileopt.physics.steps import step_caps
from profileopt.terrain.classes import iso8608_ri
from profileopt.terrain.roughness import roughness_windows

ATV = load_vehicle("atv")
Z = 4.753424308816257  # sqrt(2) erfinv(2 Pe - 1) for Pe = 0.999999 (docs/paper-notes.md, Eq. 8)
W, REACH = 5.0, 5.0


def _piece(start_m: float, stop_m: float) -> tuple[np.ndarray, np.ndarray]:
    route = read_route(ROUTES / "curb.csv")
    keep = (route.s_m >= start_m) & (route.s_m <= stop_m)
    return route.s_m[keep], route.z_m[keep]


def _requirement(x: np.ndarray, s: np.ndarray, z: np.ndarray) -> np.ndarray:
    """Brute force: the largest e_max (Eq. 8: z RI h) of the windows sharing a point with
    [x, x + REACH], over the measured samples only."""
    win = roughness_windows(s, z, ATV.ground_clearance_m, window_m=W)
    e = Z * ATV.ground_clearance_m * win.ri
    meets = (win.start_m[None, :] <= x[:, None] + REACH + 1e-9) & (win.stop_m[None, :] >= x[:, None] - 1e-9)
    return np.max(np.where(meets, e[None, :], -np.inf), axis=1)


@pytest.mark.parametrize("origin", [60.0, 93.3, 140.7])
def test_never_below_any_window_it_can_reach_and_the_unseen_beyond_the_samples(origin):
    s, z = _piece(origin - 10.0, origin + 60.0)  # 60 m measured ahead, over the kerbs at 100 and 150 m
    preview = TerrainPreview(ATV, horizon_m=100.0, reach_m=REACH)
    coef = preview.coefficients(s, z, origin)
    x = np.linspace(origin, origin + 100.0, 801)
    value = np.array(preview.e_max.map(x.size)(x, coef.origin_m, coef.e_max)).ravel()
    measured = x + REACH <= s[-1] - preview.margin_m
    assert np.all(value[measured] >= _requirement(x[measured], s, z) * (1 - 1e-12))
    # past the samples: at least the e_max of class H, e = Z RI h with RI that of class H
    e_h = Z * ATV.ground_clearance_m * iso8608_ri("H", window_m=W, clearance_m=ATV.ground_clearance_m)
    assert preview.unseen_e_max_m == pytest.approx(e_h, rel=1e-9)
    assert np.all(value[~measured] >= e_h * (1 - 1e-12))


def test_where_its_knots_meet_a_fixed_envelopes_the_values_agree():
    """The preview is terrain_envelope with its coefficients as parameters: on knots that
    coincide (both 1 m apart, from integer positions) and inside the samples they are equal."""
    s, z = _piece(80.0, 180.0)
    preview = TerrainPreview(ATV, horizon_m=60.0, reach_m=REACH)
    fixed = terrain_envelope(s, z, ATV, window_m=W, reach_m=REACH, knot_spacing_m=1.0)
    coef = preview.coefficients(s, z, 100.0)
    x = np.linspace(100.0, 160.0, 241)
    ours = np.array(preview.e_max.map(x.size)(x, coef.origin_m, coef.e_max)).ravel()
    theirs = np.array(fixed.map(x.size)(x)).ravel()
    np.testing.assert_allclose(ours, theirs, rtol=1e-9)
    cap = step_speed_envelope(s, z, ATV, reach_m=REACH, knot_spacing_m=1.0)
    ours = np.array(preview.speed_cap.map(x.size)(x, coef.origin_m, coef.speed_cap)).ravel()
    np.testing.assert_allclose(ours, np.array(cap.map(x.size)(x)).ravel(), rtol=1e-9)


def test_the_step_cap_is_never_above_a_ramp_it_can_reach():
    s, z = _piece(60.0, 200.0)
    preview = TerrainPreview(ATV, horizon_m=120.0, reach_m=REACH)
    coef = preview.coefficients(s, z, 70.0)
    x = np.linspace(70.0, 190.0, 600)
    value = np.array(preview.speed_cap.map(x.size)(x, coef.origin_m, coef.speed_cap)).ravel()
    lowest = step_caps(s, z, ATV).lowest_over(x, x + REACH, ATV.max_speed_mps)
    assert np.all(value <= lowest * (1 + 1e-12))
    assert value.min() < 0.5 * ATV.max_speed_mps  # the kerbs are in it


def test_speed_limits_are_folded_into_the_cap():
    route = read_route(ROUTES / "curb.csv")
    keep = (route.s_m >= 0.0) & (route.s_m <= 120.0)
    s, z, limit = route.s_m[keep], route.z_m[keep], route.speed_limit_mps[keep]
    preview = TerrainPreview(ATV, horizon_m=100.0, reach_m=REACH)
    coef = preview.coefficients(s, z, 10.0, speed_limit_mps=limit)
    x = np.linspace(10.0, 110.0, 500)
    value = np.array(preview.speed_cap.map(x.size)(x, coef.origin_m, coef.speed_cap)).ravel()
    # never above the least limit of the samples an interval from x can reach
    for xi, vi in zip(x, value):
        reach = (s >= xi - 0.05) & (s <= xi + REACH + 0.05)
        assert vi <= limit[reach].min() * (1 + 1e-12)


def test_the_knots_stay_put_from_step_to_step():
    """The origin moves down to a multiple of the knot spacing, so the envelope at a position
    is the same whichever step computed it (a moving knot grid changed it between steps, and
    a controller's last plan could become infeasible)."""
    s, z = _piece(40.0, 200.0)
    preview = TerrainPreview(ATV, horizon_m=80.0, reach_m=REACH)
    x = np.linspace(100.0, 120.0, 81)
    values = []
    for origin in (95.0, 95.4, 96.7, 99.99):
        coef = preview.coefficients(s, z, origin)
        assert coef.origin_m == np.floor(origin) and coef.origin_m <= origin
        values.append(np.array(preview.e_max.map(x.size)(x, coef.origin_m, coef.e_max)).ravel())
    for other in values[1:]:
        np.testing.assert_allclose(other, values[0], rtol=1e-12)


def test_one_expression_for_any_route_length():
    """Built once: its size depends on the horizon and the knots, not on the route; the
    coefficients of any stretch fit it."""
    preview = TerrainPreview(ATV, horizon_m=80.0, reach_m=REACH)
    nodes = preview.e_max.n_nodes()
    for length in (20.0, 200.0):
        s, z = _piece(0.0, length)
        assert preview.coefficients(s, z, 0.0).e_max.shape == (preview.n_coefficients,)
    assert TerrainPreview(ATV, horizon_m=80.0, reach_m=REACH).e_max.n_nodes() == nodes
    assert TerrainPreview(ATV, horizon_m=160.0, reach_m=REACH).e_max.n_nodes() > nodes


@pytest.mark.parametrize("kwargs, words", [
    ({"horizon_m": -1.0}, "horizon_m"),
    ({"horizon_m": 10.0, "knot_spacing_m": 0.0}, "knot_spacing_m"),
    ({"horizon_m": 1e9, "knot_spacing_m": 1.0}, "knot intervals"),
    ({"horizon_m": 10.0, "unseen": "Q"}, "ISO 8608"),
])
def test_bad_options_are_one_line(kwargs, words):
    with pytest.raises(InputError, match=words):
        TerrainPreview(ATV, **kwargs)


def test_a_vehicle_name_is_refused_with_what_to_pass():
    with pytest.raises(InputError, match="load_vehicle"):
        TerrainPreview("atv", horizon_m=10.0)


def test_a_position_error_widens_the_preview_behind_and_ahead(atv_resonant) -> None:
    # Issue 31's back-off: a rough stretch ending 1.5 m behind s is met by a vehicle whose
    # position estimate is 2 m ahead of it; with position_error_m = 2 the envelope at s covers
    # it (from the windows' own e_max, computed here), without it it need not.
    from profileopt.terrain.roughness import roughness_windows, worst_case_elevation

    s = np.arange(0.0, 80.0 + 1e-9, 0.05)
    z = np.where((s > 10.0) & (s < 30.0), 0.03 * np.sin(2 * np.pi * s / 0.9), 0.0)
    windows = roughness_windows(s, z, atv_resonant.ground_clearance_m, window_m=5.0)
    e = np.asarray(worst_case_elevation(windows.ri, atv_resonant))
    at = 36.5  # the last rough window's extent ends near 35 m
    behind = e[(windows.stop_m >= at - 2.0) & (windows.start_m <= at)].max()
    plain = TerrainPreview(atv_resonant, horizon_m=40.0)
    backed = TerrainPreview(atv_resonant, horizon_m=40.0, position_error_m=2.0)
    got = {}
    for name, preview in (("plain", plain), ("backed", backed)):
        coef = preview.coefficients(s, z, 20.0)
        got[name] = float(preview.e_max(at, coef.origin_m, coef.e_max))
    assert got["backed"] >= behind * (1 - 1e-9)
    assert got["plain"] < behind  # the back-off is what covers it
    with pytest.raises(InputError, match="position_error_m"):
        TerrainPreview(atv_resonant, horizon_m=40.0, position_error_m=-1.0)


def _arc_on_a_climb():
    # straight 40 m, then an arc of radius 20 m for 30 m, then straight; a 10 % climb from 60 m on
    s = np.arange(0.0, 140.0 + 1e-9, 0.25)
    heading = np.where(s < 40.0, 0.0, np.minimum(s - 40.0, 30.0) / 20.0)
    x = np.concatenate([[0.0], np.cumsum(np.cos(heading[:-1]) * np.diff(s))])
    y = np.concatenate([[0.0], np.cumsum(np.sin(heading[:-1]) * np.diff(s))])
    z = 0.1 * np.maximum(s - 60.0, 0.0)
    return s, x, y, z


def test_path_preview_bounds_the_turn_and_the_climb(atv) -> None:
    # Issue 31: curvature and grade envelopes for lateral_constraints and friction_constraints.
    # References from the construction: |kappa| = 1 / 20 on the arc, grade atan(0.1) on the climb.
    s, x, y, z = _arc_on_a_climb()
    preview = TerrainPreview(atv, horizon_m=60.0, reach_m=3.0)
    coef = preview.path_coefficients(s, z, 20.0, x_m=x, y_m=y, path_tolerance_m=0.05)

    def at(fn, c, where):
        return float(fn(where, coef.origin_m, c))

    # a stage starting 2 m before the arc reaches into it: the envelope holds its curvature
    assert at(preview.curvature, coef.curvature, 38.0) >= (1 / 20.0) * 0.97
    assert at(preview.curvature, coef.curvature, 20.0) < 0.01  # far before it, the straight
    assert at(preview.grade_max, coef.grade_max, 58.0) >= math.atan(0.1) * 0.97
    assert at(preview.grade_min, coef.grade_min, 58.0) <= 1e-6
    assert at(preview.grade_max, coef.grade_max, 30.0) < 0.01
    # beyond the path given (the horizon reaches to 80 m, the path to 50 m): the vehicle's
    # tightest turn and the unseen grade are assumed
    short = s <= 50.0
    cut = preview.path_coefficients(s[short], z[short], 20.0, x_m=x[short], y_m=y[short], path_tolerance_m=0.05)
    assert float(preview.curvature(70.0, cut.origin_m, cut.curvature)) >= 1 / atv.min_turn_radius_m * (1 - 1e-9)
    assert float(preview.grade_min(70.0, cut.origin_m, cut.grade_min)) <= -math.atan(0.05) * (1 - 1e-9)
    with pytest.raises(InputError, match="min_turn_radius_m"):
        TerrainPreview(atv.replace(min_turn_radius_m=None, max_lateral_accel_mps2=None), horizon_m=60.0).path_coefficients(
            s[short], z[short], 20.0, x_m=x[short], y_m=y[short])


# ------------------------------------------------------------- the preview's reach, checked (issue 31)


def test_check_stages_holds_a_solved_horizon_to_the_preview_reach_and_horizon(atv) -> None:
    preview = TerrainPreview(atv, horizon_m=25.0, reach_m=1.5)
    assert preview.reach_m == 1.5 and preview.horizon_m == 25.0
    # lengths 1.5 (the reach), 1.0, 0.0: within the reach and inside [0, 25]
    np.testing.assert_allclose(preview.check_stages([3.0, 4.5, 5.5, 5.5], origin_m=0.0), [1.5, 1.0, 0.0])
    with pytest.raises(InputError) as caught:  # stage 1: 4.5 -> 6.5 m is 2 m, over the 1.5 m reach
        preview.check_stages([3.0, 4.5, 6.5, 7.0])
    message = str(caught.value)
    assert message.startswith("TerrainPreview.check_stages: stage 1 (from 4.5 to 6.5 m) is 2 m long")
    assert "reach 1.5 m" in message and "\n" not in message
    # a stage starting past origin + horizon_m (24.5 + 1 = 25.5 > 0 + 25) is outside what the envelopes bound
    with pytest.raises(InputError, match=r"stage 2 \(from 25.5 to 26 m\) starts outside the envelopes' horizon 0 to 25"):
        preview.check_stages([23.5, 24.5, 25.5, 26.0], origin_m=0.0)
    preview.check_stages([23.5, 24.5, 25.5, 26.0], origin_m=1.0)  # the next step's horizon covers it
    with pytest.raises(InputError, match="built with reach_m = 0"):
        TerrainPreview(atv, horizon_m=25.0).check_stages([0.0, 0.5])


def test_path_envelopes_at_every_stage_are_the_scalar_functions_and_the_b_spline(atv) -> None:
    """path_stage_functions evaluates curvature, grade_max and grade_min at n stages at once.
    References: the scalar Functions at each stage, and the uniform cubic B-spline's own
    values (de Boor, A Practical Guide to Splines, ch. IX; Piegl & Tiller, The NURBS Book,
    Eq. 2.5): on knot m the three basis functions that do not vanish are 1/6, 4/6, 1/6, so the
    value is (c_m + 4 c_m+1 + c_m+2) / 6; at the middle of knot interval m the four are 1/48,
    23/48, 23/48, 1/48. Knot m of a preview lies at origin + (m - 3) h (3 intervals of padding)."""
    preview = TerrainPreview(atv, horizon_m=20.0, reach_m=2.0, knot_spacing_m=1.0)
    kappa_fn, up_fn, down_fn = preview.path_stage_functions(n_stages=3, prefix="p")
    assert [f.name() for f in (kappa_fn, up_fn, down_fn)] == ["p_curvature", "p_grade_max", "p_grade_min"]
    assert kappa_fn.name_in() == ["s_m", "origin_m", "curvature_coef"] and kappa_fn.name_out() == ["curvature_1pm"]
    assert down_fn.name_in()[2] == "grade_min_coef" and up_fn.name_out() == ["grade_max_rad"]
    rng = np.random.default_rng(3)
    c = rng.uniform(-0.2, 0.2, preview.n_coefficients)
    origin, h = 40.0, 1.0
    m = np.array([5, 9, 14])  # on knots 5, 9, 14: 42, 46 and 51 m
    on_knots = origin + (m - 3) * h
    mid = on_knots + h / 2  # the middle of knot intervals 5, 9, 14
    expected_knot = (c[m] + 4 * c[m + 1] + c[m + 2]) / 6
    expected_mid = (c[m] + 23 * c[m + 1] + 23 * c[m + 2] + c[m + 3]) / 48
    for fn, scalar in ((kappa_fn, preview.curvature), (up_fn, preview.grade_max), (down_fn, preview.grade_min)):
        for x, expected in ((on_knots, expected_knot), (mid, expected_mid)):
            got = np.asarray(fn(x, origin, c)).ravel()
            np.testing.assert_allclose(got, expected, rtol=1e-12, atol=1e-15)
            np.testing.assert_array_equal(got, [float(scalar(xi, origin, c)) for xi in x])
    with pytest.raises(InputError, match="n_stages"):
        preview.path_stage_functions(n_stages=0)
