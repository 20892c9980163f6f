"""The vehicle's limits checked on paper (profileopt.verification.limit_check): turns.

References, derived here by hand: a reversal within the 0.1 m path tolerance is a U-turn of
radius 0.1 m (tests/terrain/test_geometry.py), so the bundled ATV may drive it at
sqrt(4 m/s^2 * 0.1 m) = 0.632 m/s (its lateral limit), and at most 1 m/s (the crawl through a
turn sharper than its 3.25 m turning circle); a profile that drives it at the top speed,
20 m/s, breaks both. The curvature verify finds is the planner's by default: estimated from
the route as the planner estimates it, or the tolerance given to check_limits; never the one the
profile's settings line records (issue 30: an edited path_tolerance_m=1e6 hid a lateral
breach). On an arc of radius 10 m the ATV may drive sqrt(4 m/s^2 x 10 m) = 6.32 m/s.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from profileopt import load_vehicle, plan
from profileopt.core.route import Route, path_distance_m
from profileopt.verification.limit_check import check_limits


def out_and_back(step_m: float = 0.5) -> Route:
    leg = np.arange(0.0, 60.0 + step_m / 2, step_m)
    x = np.concatenate([leg, leg[::-1][1:]])
    s = path_distance_m(x, np.zeros_like(x))
    return Route(s_m=s, z_m=0.002 * np.sin(s), x_m=x, y_m=np.zeros_like(x), source="out and back")


@pytest.fixture(scope="module")
def atv():
    return load_vehicle("atv")


def test_a_top_speed_reversal_breaks_the_limits_of_turns_and_a_planned_one_does_not(atv) -> None:
    route = out_and_back()
    planned = plan(route, atv)
    assert planned.settings["path_tolerance_source"] == "estimated"
    assert check_limits(route, planned, atv).breaches == ()
    # the same speeds as on a straight line (what the planner gave before reversals were turns)
    straight = plan(Route(s_m=route.s_m, z_m=route.z_m, source="straight"), atv)
    assert straight.speed_mps[np.abs(straight.s_m - 60.0) <= 5.0].min() > 15.0  # the turn near the top speed
    breaches = {b.limit_name: b for b in check_limits(route, straight, atv).breaches}
    lateral = breaches["the lateral acceleration limit in turns"]
    assert lateral.limit == pytest.approx(math.sqrt(0.4)) and abs(lateral.s_m - 60.0) <= 5.0
    crawl = next(b for name, b in breaches.items() if "min_turn_radius_m (3.25 m)" in name)
    assert crawl.limit == 1.0 and crawl.value > 15.0


def test_the_curvature_is_found_with_the_tolerance_given_or_estimated(atv) -> None:
    route = out_and_back()
    planned = plan(route, atv)
    # a profile that records no tolerance: estimated, as the planner did (0.1 m here)
    settings = {k: v for k, v in planned.settings.items() if not k.startswith("path_")}
    assert check_limits(route, dataclasses.replace(planned, settings=settings), atv).breaches == ()
    # a profile planned with a wide tolerance: a reversal is the sharpest turn whatever the
    # tolerance, so it is crawled and kept all the same, with the estimate or the same tolerance
    wide = plan(route, atv, path_tolerance_m=5.0)
    assert wide.settings["path_tolerance_m"] == 5.0 and wide.settings["path_tolerance_source"] == "given"
    assert check_limits(route, wide, atv).breaches == ()
    assert check_limits(route, wide, atv, path_tolerance_m=5.0).breaches == ()


def arc_route(radius_m: float = 10.0, step_m: float = 0.05) -> Route:
    """30 m straight, a quarter circle of radius_m, 30 m straight (x, y, and a small ripple in z)."""
    straight = np.arange(0.0, 30.0, step_m)
    angle = np.arange(0.0, math.pi / 2, step_m / radius_m)
    x = np.concatenate([straight, 30.0 + radius_m * np.sin(angle), np.full(straight.size, 30.0 + radius_m)])
    y = np.concatenate([np.zeros(straight.size), radius_m * (1 - np.cos(angle)), radius_m + straight])
    s = path_distance_m(x, y)
    return Route(s_m=s, z_m=0.002 * np.sin(s), x_m=x, y_m=y, source="arc")


def test_a_path_tolerance_in_the_settings_line_is_reported_not_obeyed(atv) -> None:
    # issue 30: planned (or edited) with path_tolerance_m=1e6, the path is a straight line and
    # the arc is driven far above its 6.32 m/s; verify read the tolerance and passed it
    route = arc_route()
    wide = plan(route, atv, path_tolerance_m=1e6)
    arc = (wide.s_m > 32.0) & (wide.s_m < 44.0)
    assert wide.speed_mps[arc].max() > 1.2 * math.sqrt(40.0)  # the turn unseen
    found = check_limits(route, wide, atv)
    lateral = [b for b in found.breaches if b.limit_name == "the lateral acceleration limit in turns"]
    # in the arc itself the cap is sqrt(4 m/s^2 x 10 m): the worst breach is at least that one
    assert lateral and lateral[0].worst_ratio >= 0.95 * wide.speed_mps[arc].max() / math.sqrt(40.0)
    assert any("planned with a path tolerance of 1000000.0 m" in note and "estimated from the route" in note
               for note in found.notes)
    # the user's own choice is obeyed, as plan's
    assert check_limits(route, wide, atv, path_tolerance_m=1e6).breaches == ()
    assert not any("path tolerance" in note for note in check_limits(route, plan(route, atv), atv).notes)


def test_a_roughness_window_in_the_settings_line_is_reported_not_obeyed(atv) -> None:
    route = arc_route()
    planned = plan(route, atv, roughness_window_m=10.0)
    found = check_limits(route, planned, atv)
    assert found.windows.window_m == 5.0
    assert any("planned with --roughness-window 10.0 m" in note and "not compared" in note for note in found.notes)
    own = check_limits(route, planned, atv, roughness_window_m=10.0)
    assert own.windows.window_m == 10.0 and own.breaches == () and not own.notes
    # the bounds checked, in words with their values and where they come from
    assert "jerk (the vehicle's 5 m/s^3)" in own.checked and own.unchecked == ()
    assert any(words.startswith("speed (the vehicle's top speed 20 m/s") and "turns" in words
               for words in own.checked)
    assert check_limits(route, planned, atv, max_jerk_mps3=math.inf).unchecked == ("jerk (--max-jerk inf)",)
