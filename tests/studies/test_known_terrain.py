"""The scaled-limit reference of the known-terrain study (profileopt.studies.known_terrain, issue 33).

The reference is "the fastest SBEM:TF plan, for the vehicle with its force limit scaled by
lam, that keeps the true limit in the exact simulation". It is checked here from outside
the study, by planning again with the public ``plan`` and simulating with
:func:`~profileopt.physics.simulate.simulate_quarter_car` directly: the returned lam's plan
keeps the limit, the bracket's upper end's plan and lam * 1.05's do not, and the bracket is
within 2 %. The route is short (two 0.08 m kerbs on 60 m of flat ground), so a plan takes a
fraction of a second.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import profileopt
from profileopt.core.route import Route
from profileopt.physics.simulate import simulate_quarter_car
from profileopt.studies.known_terrain import (SCALE_BRACKET, SCALE_CAP, fastest_constant_speed,
                                              fastest_scaled_limit, known_terrain_row)
from profileopt.terrain.synthetic import iso8608_profile, step


def kerbs_route() -> Route:
    """60 m of flat ground sampled every 0.05 m, up 0.08 m at s = 20.5 m and down at 40.5 m."""
    s_m = np.arange(0.0, 60.0 + 1e-9, 0.05)
    return Route(s_m, step(s_m, 20.5, 0.08) - step(s_m, 40.5, 0.08), source="kerbs")


def replanned(route: Route, vehicle: profileopt.Vehicle, scale: float) -> tuple[float, float]:
    """Travel time (s) and worst simulated |F_T| / the true limit of the default plan for the
    vehicle with its limit scaled by ``scale``, computed here without the study's helpers."""
    limit_n = vehicle.max_transmitted_force_n
    profile = profileopt.plan(route, vehicle.replace(max_transmitted_force_n=scale * limit_n))
    run = simulate_quarter_car(route.s_m, route.z_m, profile.s_m, profile.speed_mps, vehicle)
    return profile.travel_time_s, float(np.max(np.abs(run.transmitted_n))) / limit_n


@pytest.mark.slow
@pytest.mark.parametrize("vehicle_name", ["atv", "atv-resonant"])
def test_the_largest_scale_keeps_the_limit_and_a_little_more_does_not(vehicle_name: str) -> None:
    route = kerbs_route()
    vehicle = profileopt.load_vehicle(vehicle_name)
    ref = fastest_scaled_limit(route, vehicle)
    # a bracket was bisected: the cap goes over the limit on a kerb
    assert 1.0 <= ref.scale < ref.upper_scale <= SCALE_BRACKET * ref.scale
    assert ref.plans <= 13
    time_s, ratio = replanned(route, vehicle, ref.scale)
    assert ratio <= 1.0
    assert ref.ratio == pytest.approx(ratio, rel=1e-9)
    assert ref.travel_time_s == pytest.approx(time_s, rel=1e-9)
    assert replanned(route, vehicle, ref.upper_scale)[1] > 1.0
    assert ref.upper_ratio > 1.0
    assert replanned(route, vehicle, 1.05 * ref.scale)[1] > 1.0
    # lam = 1 is SBEM:TF's own plan, which keeps the limit: the reference is never slower
    sbem_tf_s, sbem_tf_ratio = replanned(route, vehicle, 1.0)
    assert sbem_tf_ratio <= 1.0
    assert ref.travel_time_s <= sbem_tf_s


def test_where_even_the_cap_keeps_the_limit_the_cap_is_the_reference() -> None:
    """ISO 8608 class D ground: the resonant ATV keeps its limit at 64 times the limit."""
    route = Route(*iso8608_profile("D", 60.0, 0.05, 1), source="iso_D")
    vehicle = profileopt.load_vehicle("atv-resonant")
    ref = fastest_scaled_limit(route, vehicle)
    assert (ref.scale, ref.upper_scale, ref.plans) == (SCALE_CAP, math.inf, 2)
    time_s, ratio = replanned(route, vehicle, SCALE_CAP)
    assert ratio <= 1.0 and ref.travel_time_s == pytest.approx(time_s, rel=1e-9)


@pytest.mark.slow
def test_the_row_compares_the_dynamic_plan_with_the_faster_reference() -> None:
    route = kerbs_route()
    vehicle = profileopt.load_vehicle("atv-resonant")
    row = known_terrain_row(route, vehicle)
    constant_s = fastest_constant_speed(route, vehicle)[1]
    assert row.constant_s == constant_s
    assert row.fastest_other_s == min(constant_s, row.scaled.travel_time_s)
    assert row.over_fastest == pytest.approx(row.dynamic_s / row.fastest_other_s, rel=1e-12)
    assert row.dynamic_ratio <= 1.0
