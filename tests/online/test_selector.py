"""The online speed selector (profileopt.online.selector): the offline planner's limits on what is
measured, the unseen assumption beyond, never faster than what is known allows."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from conftest import ROUTES

from profileopt.errors import InputError
from profileopt.io.routes import read_route
from profileopt.online.band_table import first_band_table
from profileopt.online.selector import SpeedSelector, unseen_speed_mps
from profileopt.physics.speeds import allowable_speed, speed_bands_of_sets
from profileopt.planning import plan
from profileopt.terrain.classes import iso8608_ri


def _level(vehicle):
    """The vehicle without the keys of turns and hills, so that the offline plan is the exact
    forward-backward profile (no friction rows for an NLP)."""
    return dataclasses.replace(vehicle, max_lateral_accel_mps2=None, track_width_m=None, cg_height_m=None,
                               friction_coefficient=None, mass_kg=None, max_power_w=None, min_turn_radius_m=None)


class _ExactFirstBand:
    """The exact first band of sets of RIs, where the selector uses its table (the table's
    highest bands, for the upper band, as they are)."""

    def __init__(self, vehicle):
        self.vehicle = vehicle
        self.highest_of_sets = first_band_table(vehicle, "sbem_tf").highest_of_sets

    def first_of_sets(self, values, first, stop):
        return speed_bands_of_sets(values, first, stop, self.vehicle)[0].first()


@pytest.mark.parametrize("name", ["curb.csv", pytest.param("washboard.csv", marks=pytest.mark.slow)])
def test_with_the_whole_route_measured_the_plan_is_the_offline_exact_plan(name, atv_resonant):
    """Every segment's speeds are computed on the measured stretch around it only (a window
    and a step's ramp either side): if that stretch were too short, a kerb's or a window's cap
    would differ from the offline planner's, which sees the whole route. The route is revealed a
    metre at a time, so that its segments are computed in chunks. Reference: plan() with
    the first band, 1 m uniform segments, no smoothing or jerk: the exact forward-backward
    profile (status "exact") on the same segments. The selector's force bands come from a
    table that is conservative by a grid step (tests/online/test_band_table.py); here it is
    replaced by the exact bands, so that what is compared is the measured stretch alone."""
    route = read_route(ROUTES / name)
    vehicle = _level(atv_resonant)
    offline = plan(route, vehicle, segment_length_m=1.0, refine=False, smoothing=0.0, max_jerk_mps3=float("inf"),
                   band="first", simulation_gate=False)
    assert offline.status == "exact"
    selector = SpeedSelector(vehicle, sensor_range_m=50.0, start_m=route.s_m[0], end_m=route.s_m[-1])
    selector._band_table = _ExactFirstBand(vehicle)
    revealed = 0
    for ahead in np.arange(route.s_m[0] + 1.0, route.s_m[-1] + 1.0, 1.0):  # 1 m more at a time
        upto = int(np.searchsorted(route.s_m, ahead, side="right"))
        part = slice(revealed, upto)
        limit = None if route.speed_limit_mps is None else route.speed_limit_mps[part]
        selector.sense(route.s_m[part], route.z_m[part], speed_limit_mps=limit)
        revealed = upto
        for _ in range(2):  # the two stages of the work, one per cycle, standing at the start
            selector.update(route.s_m[0], 0.0)
    assert selector.planned_to_m == route.s_m[-1]
    command = selector.update(route.s_m[0], 0.0)
    np.testing.assert_allclose(command.horizon_s_m, offline.s_m, rtol=0, atol=1e-9)
    np.testing.assert_allclose(command.horizon_speed_mps, offline.speed_mps, rtol=1e-9, atol=1e-9)


def test_unseen_worst_is_the_first_band_at_class_h(atv):
    """'worst' is ISO 8608 class H; for the atv, whose force grows with speed, the first band
    over RIs up to H's is the allowable speed at H's RI (Eq. 13, solved by allowable_speed)."""
    ri = iso8608_ri("H", window_m=5.0, clearance_m=atv.ground_clearance_m)
    assert unseen_speed_mps("worst", atv) == pytest.approx(float(allowable_speed(ri, atv)), rel=1e-9)
    assert unseen_speed_mps("worst", atv) == unseen_speed_mps("H", atv)
    assert unseen_speed_mps("A", atv) > unseen_speed_mps("E", atv) > unseen_speed_mps("H", atv)
    assert unseen_speed_mps(0.0, atv) == atv.max_speed_mps


def test_nothing_measured_means_the_unseen_speed_and_no_faster(atv):
    selector = SpeedSelector(atv, sensor_range_m=50.0, unseen="F")
    speed = 0.0
    position = 0.0
    for _ in range(100):  # 10 s on ground never measured
        command = selector.update(position, speed)
        position, speed = command.position_next_m, command.speed_mps
        assert speed <= selector.unseen_speed_mps * (1 + 1e-9)
    assert speed == pytest.approx(selector.unseen_speed_mps, rel=1e-3)


@pytest.mark.parametrize("kwargs, words", [
    ({"sensor_range_m": 7.0}, "7.5 m of measured terrain"),
    ({"segment_length_m": 1e-9}, "at least 0.1 m"),
    ({"model": "dynamic"}, "dynamic model simulates the whole route"),
    ({"unseen": "Q"}, "ISO 8608 class"),
    ({"unseen": "fast"}, "'worst', an ISO 8608 class"),
    ({"cycle_s": 0.0}, "cycle_s"),
    ({"cycle_s": 2.0}, "cycle_s = 2.0: must be at most 1 s"),
    ({"max_jerk_mps3": -1.0}, "max_jerk_mps3"),
    ({"end_m": -5.0}, "end_m"),
    ({"unseen_descent": 2.0}, "unseen_descent"),
])
def test_bad_options_are_refused_in_one_line(atv, kwargs, words):
    with pytest.raises(InputError, match=words):
        SpeedSelector(atv, **kwargs)


def test_a_vehicle_name_is_refused_with_what_to_pass():
    with pytest.raises(InputError, match="load_vehicle"):
        SpeedSelector("atv")


def test_a_blind_spot_is_driven_as_unseen_and_the_terrain_beyond_it_is_planned(atv):
    """Samples missing over 1 m (a puddle without returns): the selector slows to the unseen
    speed there, and plans the ground beyond it again instead of treating the rest of the
    route as unseen."""
    s = np.arange(0.0, 200.0001, 0.05)
    z = 0.002 * np.sin(2 * np.pi * s / 7.0)
    seen = (s < 100.0) | (s > 101.0)
    selector = SpeedSelector(atv, sensor_range_m=50.0, start_m=0.0, end_m=200.0)
    position, speed, revealed = 0.0, 0.0, 0
    path = []
    for _ in range(5000):
        if position >= 199.99 and speed <= 0:
            break
        upto = int(np.searchsorted(s, position + 50.0, side="right"))
        part = slice(revealed, upto)
        selector.sense(s[part][seen[part]], z[part][seen[part]])
        revealed = upto
        command = selector.update(position, speed)
        path.append((position, speed))
        position, speed = command.position_next_m, command.speed_mps
    at, v = np.array(path).T
    near = (at > 100.0 - selector.margin_m) & (at < 101.0 + selector.margin_m)
    assert v[near].max() <= selector.unseen_speed_mps * (1 + 1e-9)
    assert v[(at > 130.0) & (at < 150.0)].min() > 3 * selector.unseen_speed_mps
    assert selector.blind_m == pytest.approx(1.0, abs=0.11)


def test_samples_that_start_a_little_after_the_path_are_planned(atv):
    """A sensor whose first sample is 5 cm after the path's start (within the 0.1 m rule):
    the first segments are planned, not left unseen for ever."""
    s = np.arange(0.05, 100.0001, 0.05)
    selector = SpeedSelector(atv, sensor_range_m=50.0, start_m=0.0, end_m=100.0)
    selector.sense(s[s <= 50.0], np.zeros(np.count_nonzero(s <= 50.0)))
    for _ in range(30):
        command = selector.update(0.0, 0.0)
    assert selector.planned_to_m >= 40.0
    assert command.edge_m >= 40.0


def test_a_position_that_jitters_back_keeps_the_caps_and_one_far_back_is_refused(atv):
    """Localisation jitter: a position a little behind the last one still sees the caps ahead
    (here a speed limit of 0.5 m/s from 10.5 m); one behind all that is kept is refused."""
    s = np.arange(0.0, 60.0001, 0.05)
    limit = np.where(s >= 10.5, 0.5, 20.0)
    selector = SpeedSelector(atv, sensor_range_m=50.0, start_m=0.0, end_m=60.0)
    selector.sense(s, np.zeros(s.size), speed_limit_mps=limit)
    for _ in range(30):
        selector.update(0.0, 0.0)
    for position in (10.001, 9.999, 9.5):
        command = selector.update(position, 0.5, 0.0)
        assert command.edge_m > 40.0  # the terrain planned ahead is still known
        inside = command.horizon_s_m >= 10.0  # the segments holding the limit's samples
        assert np.all(command.horizon_speed_mps[inside] <= 0.5 + 1e-9)
    with pytest.raises(InputError, match="behind the earliest position still planned"):
        selector.update(0.0, 0.5, 0.0)


def test_samples_with_columns_of_the_wrong_length_are_one_line_and_change_nothing(atv):
    selector = SpeedSelector(atv, sensor_range_m=50.0)
    with pytest.raises(InputError, match="x_m has shape"):
        selector.sense([0.0, 0.05, 0.1], [0.0, 0.0, 0.0], x_m=[0.0, 0.05], y_m=[0.0, 0.0])
    with pytest.raises(InputError, match="speed_limit_mps has shape"):
        selector.sense([0.0, 0.05, 0.1], [0.0, 0.0, 0.0], speed_limit_mps=[1.0, 2.0])
    selector.sense([0.0, 0.05, 0.1], [0.0, 0.0, 0.0])  # refused calls left no trace
    assert selector.terrain.measured_to_m == pytest.approx(0.1)
