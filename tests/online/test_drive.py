"""Driving a route seen only within the sensing range (profileopt.online.drive): safe on surprises,
never faster than the whole route's own plan, an emergency said when the assumption fails."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from conftest import ROUTES

from profileopt.core.route import Route
from profileopt.errors import InputError
from profileopt.io.routes import read_route
from profileopt.online import drive
from profileopt.planning import plan
from profileopt.terrain.synthetic import iso8608_profile, step

SPACING_M = 0.05


def _kerb_route(length_m: float = 120.0, kerb_at_m: float = 70.0, height_m: float = 0.08) -> Route:
    """Smooth ISO 8608 class B ground with a kerb up: a surprise that the class-H assumption
    does not describe (a step), met at speed."""
    ground = iso8608_profile("B", length_m, SPACING_M, seed=3)
    return Route(s_m=ground.s_m, z_m=ground.z_m + step(ground.s_m, kerb_at_m, height_m), source="kerb")


def _class_h_route(length_m: float = 100.0, start_m: float = 60.0, stretch_m: float = 6.0) -> Route:
    """Class B ground with a stretch of class H: rough ground just beyond the sensing range."""
    smooth = iso8608_profile("B", length_m, SPACING_M, seed=4)
    rough = iso8608_profile("H", length_m, SPACING_M, seed=5)
    inside = (smooth.s_m >= start_m) & (smooth.s_m <= start_m + stretch_m)
    return Route(s_m=smooth.s_m, z_m=np.where(inside, rough.z_m, smooth.z_m), source="class H stretch")


@pytest.mark.parametrize("vehicle_name, sensor_range_m", [
    ("atv", 20.0),
    pytest.param("atv", 50.0, marks=pytest.mark.slow),
    pytest.param("atv_resonant", 20.0, marks=pytest.mark.slow),
    pytest.param("atv_resonant", 50.0, marks=pytest.mark.slow),
    pytest.param("atv", 100.0, marks=pytest.mark.slow),
    pytest.param("atv_resonant", 100.0, marks=pytest.mark.slow),
])
@pytest.mark.parametrize("make_route", [_kerb_route, _class_h_route])
def test_surprises_beyond_the_sensing_range_stay_within_the_force_limit(make_route, vehicle_name, sensor_range_m,
                                                                         request):
    """The exact simulation of the driven speed (the one verify uses) has no roughness window
    over the force limit, and the selector never had to break its promise (no emergency). The
    surprise lies beyond the sensing range at the start: at 70 m, or 20 m past the range. (At
    100 m the class H stretch at 120 m ends in a 0.79 m step onto the class B ground, which the
    resonant atv crawls over at the step limit's cap with its body still moving: without the
    selector's simulation gate, 1.28 times the limit in simulation.)"""
    vehicle = request.getfixturevalue(vehicle_name)
    at_m = max(70.0, sensor_range_m + 20.0)
    route = (_kerb_route(length_m=at_m + 50.0, kerb_at_m=at_m) if make_route is _kerb_route
             else _class_h_route(length_m=at_m + 40.0, start_m=at_m))
    driven = drive(route, vehicle, sensor_range_m=sensor_range_m)
    assert driven.windows_over == 0, driven.worst_window_ratio
    assert driven.worst_window_ratio <= 1.0
    assert driven.emergencies == 0
    assert driven.max_jerk_mps3 <= vehicle.max_jerk_mps3 * (1 + 1e-9)


def test_never_faster_than_the_plan_that_knows_the_whole_route(atv):
    """Knowing less can only slow the vehicle: the driven speed is nowhere above the exact
    minimum-time profile of the whole route (plan() with the first band, 1 m segments, no
    jerk bound or smoothing: the greatest profile under the same caps), here on the bundled
    kerbs with speed limits."""
    vehicle = dataclasses.replace(atv, max_lateral_accel_mps2=None, track_width_m=None, cg_height_m=None,
                                  friction_coefficient=None, mass_kg=None, max_power_w=None,
                                  min_turn_radius_m=None)
    route = read_route(ROUTES / "curb.csv")
    known = plan(route, vehicle, segment_length_m=1.0, refine=False, smoothing=0.0, max_jerk_mps3=float("inf"),
                 band="first", simulation_gate=False)
    driven = drive(route, vehicle, sensor_range_m=50.0)
    allowed_b = np.interp(driven.s_m, known.s_m, known.speed_mps ** 2)  # v^2 linear in s inside segments
    assert np.all(driven.speed_mps ** 2 <= allowed_b + 1e-9)
    assert driven.travel_time_s > known.travel_time_s
    # and the knots are a real drive: times from the speeds, ending at rest at the route's end
    assert driven.s_m[-1] == route.s_m[-1] and driven.speed_mps[-1] == 0.0
    assert driven.time_s[-1] == pytest.approx(driven.travel_time_s)


def test_an_assumption_that_fails_is_said_not_hidden(atv):
    """Assuming class A (20 m/s) on unseen ground with 10 m of sensing, a kerb (capped at
    8.5 m/s) comes into view too late to brake for within the jerk bound: the drive counts
    emergencies and says where and why."""
    driven = drive(_kerb_route(kerb_at_m=80.0, height_m=0.09), atv, sensor_range_m=10.0, unseen="A")
    assert driven.emergencies > 0
    assert ("came into view after the vehicle was there" in driven.notes[0]
            or "keeps the limits of the terrain ahead; braking as hard as the vehicle may" in driven.notes[0])


def test_terrain_measured_after_the_vehicle_drove_it_is_said(atv):
    """Terrain that the sensors deliver only after the vehicle has driven over it (here by
    hand: 0-50 m measured, the vehicle at 51.5 m at 17 m/s, then 50-70 m with a 9 cm kerb at
    51.2 m) is worse than the class A assumed: the command that finds it says where and how
    fast."""
    from profileopt.online.selector import SpeedSelector

    ground = _kerb_route(length_m=150.0, kerb_at_m=51.2, height_m=0.09)
    selector = SpeedSelector(atv, sensor_range_m=10.0, unseen="A", start_m=0.0, end_m=150.0)
    seen = ground.s_m <= 50.0
    later = (ground.s_m > 50.0) & (ground.s_m <= 70.0)
    selector.sense(ground.s_m[seen], ground.z_m[seen])
    for position_m in (40.0, 45.0, 51.5):
        command = selector.update(position_m, 17.0, 0.0)
        assert not command.emergency
    selector.sense(ground.s_m[later], ground.z_m[later])
    commands = [selector.update(position_m, 17.0, 0.0) for position_m in (53.0, 54.7)]  # the work's two stages
    assert commands[-1].emergency
    assert "came into view after the vehicle was there at 17 m/s" in commands[-1].note
    assert "worse than the unseen assumption (ISO 8608 class A)" in commands[-1].note


@pytest.mark.parametrize("kwargs, words", [
    ({"cycle_s": float("nan")}, "cycle_s"),
    ({"cycle_s": 1e-9}, "cycles even at the top speed"),
    ({"sensor_noise_m": -1.0}, "sensor_noise_m"),
    ({"sensor_spacing_m": 0.0}, "sensor_spacing_m"),
])
def test_bad_options_are_refused_in_one_line(atv, kwargs, words):
    with pytest.raises(InputError, match=words):
        drive(_kerb_route(length_m=20.0, kerb_at_m=10.0), atv, **kwargs)


def test_a_route_of_assumed_roughness_has_nothing_to_sense(atv):
    from profileopt.terrain.assumed import AssumedRoughness

    route = dataclasses.replace(_kerb_route(length_m=20.0, kerb_at_m=10.0),
                                assumed_roughness=AssumedRoughness(road_class="C"))
    with pytest.raises(InputError, match="nothing for a sensor to see"):
        drive(route, atv)


@pytest.mark.parametrize("grade", [0.30, -0.50])  # a climb the drive cannot hold, a descent too steep to brake on
def test_a_grade_the_vehicle_cannot_drive_is_refused_not_reported_as_a_bug(atv, grade):
    s = np.arange(0.0, 80.0001, 0.05)
    z = np.where(s > 40.0, grade * (s - 40.0), 0.0)
    with pytest.raises(InputError, match="a climb steeper than its drive can hold, a descent too steep"):
        drive(Route(s_m=s, z_m=z, source="grade"), atv, sensor_range_m=30.0)


@pytest.mark.parametrize("route_name, vehicle_name", [("curb.csv", "atv-resonant"), ("washboard.csv", "atv")])
def test_a_one_second_cycle_creeps_on_and_reaches_the_end(route_name, vehicle_name):
    """With 1 s cycles (the longest taken) the command's acceleration comes from 21 candidates
    0.5 m/s^2 apart: before, the resonant atv stopped at the curb's crawl (0.11 m/s cap) for good
    at 147 m, the smallest positive candidate overshooting it in one cycle, and the atv stopped
    2.6 cm before the washboard's end; both drives failed with 'no command moved it on'. The
    tracker now looks between the best candidate and the next larger one when the best leaves
    the vehicle where it is. Both reach the end, within the force limit in simulation."""
    from profileopt import load_vehicle

    route = read_route(ROUTES / route_name)
    driven = drive(route, load_vehicle(vehicle_name), cycle_s=1.0)
    assert driven.s_m[-1] == pytest.approx(route.s_m[-1], abs=0.011)  # END_TOLERANCE_M
    assert driven.windows_over == 0 and driven.emergencies == 0
