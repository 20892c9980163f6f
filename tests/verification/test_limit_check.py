"""The vehicle's limits checked on paper (profileopt.verification.limit_check): turns.

References, derived here by hand: a reversal within the 0.1 m path tolerance is a U-turn of
radius 0.1 m (tests/terrain/test_geometry.py), so the bundled ATV may drive it at
sqrt(4 m/s^2 * 0.1 m) = 0.632 m/s (its lateral limit), and at most 1 m/s (the crawl through a
turn sharper than its 3.25 m turning circle); a profile that drives it at the top speed,
20 m/s, breaks both. The curvature verify finds is the planner's: the tolerance the profile
records, or estimated from the route as the planner estimates it.
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


def test_the_curvature_is_found_with_the_recorded_tolerance_or_estimated(atv) -> None:
    route = out_and_back()
    planned = plan(route, atv)
    # a profile that records no tolerance: estimated, as the planner did (0.1 m here)
    settings = {k: v for k, v in planned.settings.items() if not k.startswith("path_")}
    assert check_limits(route, dataclasses.replace(planned, settings=settings), atv).breaches == ()
    # a profile planned with a wide tolerance records it: a reversal is the sharpest turn
    # whatever the tolerance, so it is crawled and kept all the same
    wide = plan(route, atv, path_tolerance_m=5.0)
    assert wide.settings["path_tolerance_m"] == 5.0 and wide.settings["path_tolerance_source"] == "given"
    assert check_limits(route, wide, atv).breaches == ()
