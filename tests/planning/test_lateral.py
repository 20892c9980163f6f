"""Turns sharper than the vehicle can make, and reversals (profileopt.planning.limits.lateral).

References, derived here by hand:

* a reversal within the 0.1 m path tolerance is a U-turn of radius 0.1 m (its legs 0.1 m
  either side of the line: tests/terrain/test_geometry.py), so the bundled ATV's lateral
  limit, 4 m/s^2, allows sqrt(4 * 0.1) = 0.632 m/s there, below the 2 m/s a reversal may be
  driven at;
* a turn of radius 2 m is inside the ATV's 3.25 m turning circle: crawled, at most 1 m/s
  (the lateral limit alone would allow sqrt(4 * 2) = 2.83 m/s); one of radius 10 m is not:
  sqrt(4 * 10) = 6.32 m/s.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from profileopt import load_vehicle, plan
from profileopt.core.route import Route, path_distance_m

EXACT = {"smoothing": 0.0, "max_jerk_mps3": math.inf, "segment_length_m": 1.0}


def out_and_back(off_deg: float, offset_m: float = 0.0, leg_m: float = 60.0, step_m: float = 0.5) -> Route:
    """Out ``leg_m`` along +x and back, the return leg turned ``off_deg`` off the line and moved
    ``offset_m`` across it; a gentle wave in z (RI well below any limit)."""
    leg = np.arange(0.0, leg_m + step_m / 2, step_m)
    back = math.radians(180.0 - off_deg)
    x = np.concatenate([leg, leg_m + math.cos(back) * leg[1:]])
    y = np.concatenate([np.zeros(leg.size), math.sin(back) * leg[1:] + offset_m])
    s = path_distance_m(x, y)
    return Route(s_m=s, z_m=0.002 * np.sin(s), x_m=x, y_m=y, source=f"reversal {off_deg} deg")


def hairpin(radius_m: float, step_m: float = 0.05) -> Route:
    """40 m straight, a 180 degree left turn of ``radius_m``, 40 m straight back."""
    straight = np.arange(0.0, 40.0, step_m)
    angle = np.arange(0.0, math.pi, step_m / radius_m)
    x = np.concatenate([straight, 40.0 + radius_m * np.sin(angle), 40.0 - straight])
    y = np.concatenate([np.zeros(straight.size), radius_m * (1 - np.cos(angle)), np.full(straight.size, 2 * radius_m)])
    s = path_distance_m(x, y)
    return Route(s_m=s, z_m=np.zeros_like(s), x_m=x, y_m=y, source=f"hairpin {radius_m} m")


@pytest.fixture(scope="module")
def atv():
    return load_vehicle("atv")


@pytest.mark.parametrize("off_deg, offset_m", [(0.0, 0.0), (0.0, 1e-18), (2.0, 0.0), (30.0, 0.0)])
def test_a_reversal_is_crawled_and_named(atv, off_deg: float, offset_m: float) -> None:
    route = out_and_back(off_deg, offset_m)
    profile = plan(route, atv)
    turn = np.abs(profile.s_m - 60.0) <= 2.5
    assert profile.speed_mps[turn].max() == pytest.approx(math.sqrt(4.0 * 0.1), rel=1e-6)
    assert profile.speed_mps.max() > 10.0  # the legs are driven fast
    assert profile.path.curvature_max_1pm.max() == pytest.approx(10.0)
    summary = profile.summary()
    assert "sharper than the vehicle's min_turn_radius_m" in summary["slowest_segment"]["reason"]
    notes = [note for note in summary["notes"] if "reverses" in note]
    assert len(notes) == 1 and "s = 60" in notes[0] and f"turns {180 - off_deg:.0f} deg" in notes[0]
    assert summary["path"]["sharp_turns"] == 1 and summary["path"]["source"] == "estimated"
    assert profile.settings["path_tolerance_source"] == "estimated"


def test_a_turn_inside_the_turning_circle_is_crawled_and_a_wider_one_is_not(atv) -> None:
    tight = plan(hairpin(2.0), atv, **EXACT)
    middle = np.abs(tight.s_m - (40.0 + math.pi)) <= 1.0  # the middle of the 2 m turn
    assert tight.speed_mps[middle].max() == pytest.approx(1.0, rel=1e-9)  # the crawl, not 2.83 m/s
    wide = plan(hairpin(10.0), atv, **EXACT)
    middle = np.abs(wide.s_m - (40.0 + 5 * math.pi)) <= 3.0
    # the lateral limit on the smoothed path, whose radius is 10 m within a few per cent
    assert wide.speed_mps[middle].max() == pytest.approx(math.sqrt(40.0), rel=0.05)
    assert not wide.path.turns and not [n for n in wide.summary()["notes"] if "min_turn_radius_m" in n]
    # without a turning circle the lateral limit alone holds the tight turn
    free = plan(hairpin(2.0), atv.replace(min_turn_radius_m=None), **EXACT)
    middle = np.abs(free.s_m - (40.0 + math.pi)) <= 1.0
    assert free.speed_mps[middle].max() == pytest.approx(math.sqrt(8.0), rel=0.05)


def test_a_vehicle_without_a_limit_of_turns_says_the_reversal_is_not_slowed(atv) -> None:
    bare = atv.replace(max_lateral_accel_mps2=None, track_width_m=None, cg_height_m=None, friction_coefficient=None)
    profile = plan(out_and_back(0.0), bare)
    notes = [note for note in profile.summary()["notes"] if "reverses" in note]
    assert len(notes) == 1 and "not slowed there" in notes[0]


@pytest.mark.parametrize("route", [out_and_back(0.0), out_and_back(30.0), hairpin(2.0)], ids=["reversal",
                                                                                              "reversal-30", "hairpin-2m"])
def test_refining_holds_the_crawl_to_the_turn_not_to_the_segments_around_it(atv, route: Route) -> None:
    """With 5 m segments a crawl through a reversal or a hairpin inside the turning circle held
    every segment that reached the turn (10-15 m at walking pace). Refined, the crawl holds the
    sharp stretch (the samples sharper than the turning circle, or turning back, widened by the
    reach over which a segment takes its curvature) and at most a sample's spacing more on
    either side; the rest of those segments is driven faster."""
    refined = plan(route, atv)
    whole = plan(route, atv, refine=False)

    def crawled_m(profile):
        top = np.maximum(profile.speed_mps[:-1], profile.speed_mps[1:])
        return float(np.diff(profile.s_m)[top <= top.min() * (1 + 1e-9)].sum())

    turn = refined.path.turns[0]
    spacing = float(np.max(np.diff(route.s_m)))
    assert crawled_m(refined) <= turn.end_m - turn.start_m + 2 * refined.path.curvature_reach_m + 2 * spacing + 1e-9
    assert crawled_m(whole) >= 10.0 - 1e-9 and refined.travel_time_s < whole.travel_time_s - 3.0
    assert refined.speed_mps.max() > 9.0  # the 40 m legs are driven fast either way
    assert refined.summary()["margins"]["lateral"]["ratio"] <= 1.0 + 1e-9
