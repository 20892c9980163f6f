"""The planner's simulation gate: a plan is driven in the exact simulation before it is
returned, and capped where it goes over the force limit (profileopt.planning.gate)."""

import math
import types

import numpy as np
import pytest

import profileopt
from profileopt.physics.simulate import simulate_quarter_car
from profileopt.planning.gate import GATE_MARGIN, GATE_SHRINK, check_plan, gate_caps
from profileopt.planning.limits import SimulatedLimit
from profileopt.studies.real_routes import OBSTACLE_FAMILY, obstacle_route

from conftest import ROUTES


def test_gate_caps_by_hand():
    # A constant 3 m/s over a 0.15 m block 0.4 m long sampled every 0.05 m, atv-resonant
    # (wn = 6 rad/s): the simulated landing off its trailing edge goes over the 1000 N limit.
    # At constant speed V the lookback of round k, k natural periods 2 pi / wn, is k V 2 pi /
    # wn metres before the first point over the limit; the cap is V times
    # min(GATE_SHRINK, (1 - GATE_MARGIN) / ratio) (hand computation from the gate's rule).
    vehicle = profileopt.load_vehicle("atv-resonant")
    route = obstacle_route("block", 0.15, 0.4, 0.05)
    speed = 3.0
    run = simulate_quarter_car(route.s_m, route.z_m, np.array([0.0, 60.0]), np.array([speed, speed]), vehicle)
    force = np.abs(run.transmitted_n) / vehicle.max_transmitted_force_n
    over = np.flatnonzero(force > 1.0 - GATE_MARGIN)
    assert over.size  # the test needs a plan over the limit
    profile = types.SimpleNamespace(s_m=np.array([0.0, 60.0]), speed_mps=np.array([speed, speed]))
    check = check_plan(route, profile, vehicle, window_m=5.0)
    assert check.worst_ratio == pytest.approx(force.max(), rel=1e-12) and not check.passes
    period_m = speed * 2.0 * math.pi / 6.0
    for round_number in (1, 2):
        caps = gate_caps(check, vehicle, round_number)
        assert caps.cap_mps.size == 1  # every point over the limit lies within one lookback of the next
        assert caps.start_m[0] == pytest.approx(run.s_m[over[0]] - round_number * period_m, abs=1e-9)
        assert caps.end_m[0] == pytest.approx(run.s_m[over[-1]], abs=1e-12)
        assert caps.cap_mps[0] == pytest.approx(speed * min(GATE_SHRINK, (1 - GATE_MARGIN) / force.max()), rel=1e-12)


def test_a_plan_the_models_let_over_the_limit_comes_back_within_it():
    # Issue 29: a 0.40 m x 0.15 m block sampled every 0.05 m, atv-resonant. The step limit
    # caps it at 1.27 m/s, where the exact simulation (the landing off its trailing edge) is
    # 1.34 x the limit; verify rejected the plan (exit 4). Reference: profileopt.verify, the
    # same exact simulation, run independently of the planner.
    vehicle = profileopt.load_vehicle("atv-resonant")
    route = obstacle_route("block", 0.15, 0.4, 0.05)
    ungated = profileopt.plan(route, vehicle, simulation_gate=False)  # the plan as it was
    assert profileopt.verify(route, ungated, vehicle).worst_ratio > 1.3
    profile = profileopt.plan(route, vehicle)
    result = profileopt.verify(route, profile, vehicle)
    assert result.passes and result.worst_ratio <= 1.0 - GATE_MARGIN
    assert any(note.startswith("simulation gate:") for note in profile.notes)
    assert "simulated" in set(profile.binding)
    assert any(isinstance(limit, SimulatedLimit) for limit in profile.limits)
    # slower only around the block: the run-up is driven as fast as without the gate
    before = profile.s_m <= 35.0
    np.testing.assert_allclose(profile.speed_mps[before], np.interp(profile.s_m[before], ungated.s_m,
                                                                    ungated.speed_mps), rtol=1e-6)


def test_a_plan_within_the_limit_is_returned_as_planned():
    # curb.csv with atv: the exact simulation stays within the limit (0.86 of it), so the gate
    # simulates once and changes nothing.
    vehicle = profileopt.load_vehicle("atv")
    route = profileopt.read_route(ROUTES / "curb.csv")
    ungated = profileopt.plan(route, vehicle, simulation_gate=False)
    profile = profileopt.plan(route, vehicle)
    np.testing.assert_array_equal(profile.speed_mps, ungated.speed_mps)
    assert not any("simulation gate" in note for note in profile.notes)
    assert "simulate" in profile.timings_s


def test_the_gate_leaves_the_excitation_models_alone():
    # their force keeps its k y term at any speed: a lower speed cannot always help
    from profileopt.planning.gate import gate_applies

    assert gate_applies("sbem_tf")
    assert not any(gate_applies(model) for model in ("sbem_ef", "iecm", "prev_bem"))


def test_an_assumed_roughness_is_gated_on_the_ground_verify_drives():
    # A route whose roughness is assumed (class D) over a 0.15 m drop sampled every 0.05 m,
    # atv-resonant: verify drives its elevation plus a seeded class-D profile (seed 0), and
    # the plan must pass that very check (reference: profileopt.verify, run independently).
    from profileopt.terrain.assumed import AssumedRoughness

    route = obstacle_route("drop", 0.15, 0.0, 0.05)
    route = profileopt.Route(s_m=route.s_m, z_m=route.z_m, source="drop, class D assumed",
                             assumed_roughness=AssumedRoughness(road_class="D"))
    vehicle = profileopt.load_vehicle("atv-resonant")
    profile = profileopt.plan(route, vehicle)
    result = profileopt.verify(route, profile, vehicle)
    assert result.passes, result.worst_ratio


# The family of issue 29 (profileopt.studies.real_routes.OBSTACLE_FAMILY): every block, pit,
# kerb and drop of 0.02-0.3 m height and 0.05-2 m width, sampled every 0.01-0.2 m, both
# bundled vehicles, within the limit in the exact simulation. A few corners run in the fast
# suite, every twelfth case of the grid (a different twelfth for each vehicle) in the slow
# one; the whole grid, 360 plans, is run by examples/real_routes_study.py --obstacles (about 5
# minutes) and summarised in docs/guide/real-routes.md.
CORNERS = [("block", 0.15, 0.4, 0.05), ("block", 0.1, 0.5, 0.05), ("pit", 0.3, 2.0, 0.01), ("drop", 0.3, 0.0, 0.05)]


def _keeps_the_limit_in_simulation(kind, height_m, width_m, spacing_m, vehicle_name):
    vehicle = profileopt.load_vehicle(vehicle_name)
    route = obstacle_route(kind, height_m, width_m, spacing_m)
    profile = profileopt.plan(route, vehicle)
    result = profileopt.verify(route, profile, vehicle)
    assert result.passes, f"{route.source}, {vehicle_name}: {result.worst_ratio:.4f} of the limit"


@pytest.mark.parametrize("vehicle_name", ["atv", "atv-resonant"])
@pytest.mark.parametrize("kind, height_m, width_m, spacing_m", CORNERS)
def test_obstacles_are_planned_within_the_limit_in_simulation(kind, height_m, width_m, spacing_m, vehicle_name):
    _keeps_the_limit_in_simulation(kind, height_m, width_m, spacing_m, vehicle_name)


@pytest.mark.slow
@pytest.mark.parametrize("kind, height_m, width_m, spacing_m, vehicle_name",
                         [(*case, "atv") for case in OBSTACLE_FAMILY[0::12]]
                         + [(*case, "atv-resonant") for case in OBSTACLE_FAMILY[6::12]])
def test_obstacles_of_the_family_are_planned_within_the_limit(kind, height_m, width_m, spacing_m, vehicle_name):
    _keeps_the_limit_in_simulation(kind, height_m, width_m, spacing_m, vehicle_name)


def test_covered_length_counts_overlaps_once():
    # by hand: [0, 2] and [1, 3] cover 3 m, [5, 6] one more, [5.5, 5.7] nothing new
    from profileopt.physics.steps import StepCaps
    from profileopt.planning.gate import covered_m

    caps = StepCaps(start_m=np.array([5.0, 0.0, 1.0, 5.5]), end_m=np.array([6.0, 2.0, 3.0, 5.7]),
                    cap_mps=np.ones(4))
    assert covered_m(caps) == pytest.approx(4.0, abs=1e-12)


def test_a_plan_too_slow_for_the_simulation_is_refused_in_one_line_naming_its_slowest_segment(tmp_path):
    """One 50 m segment from rest to vend = 4.8e-5 m/s takes 2 L / (v0 + vend) = 100 / 4.8e-5 =
    2.083e6 s (hand calculation), more than the simulation's MAX_STEPS steps (a random example of
    the suite's property test, 2026-11-28, that plan() let out as the simulation's own "verify a
    profile that keeps moving"). On 5 m segments the same ends plan (the last segment, from
    about 3 m/s down to 4.8e-5 m/s, takes 10 / 3 s)."""
    from profileopt.core.route import Route
    from profileopt.terrain.synthetic import iso8608_profile

    ground = iso8608_profile("A", 50.0, 0.05, seed=0)
    route = Route(s_m=ground.s_m, z_m=ground.z_m, source="slow.csv")
    vehicle = profileopt.load_vehicle("atv").replace(max_speed_mps=3.0, max_accel_mps2=1.0, max_decel_mps2=1.0)
    ends = dict(smoothing=0.0, v0_mps=0.0, vend_mps=4.8e-5, refine=False)
    with pytest.raises(profileopt.InfeasibleError) as refused:
        profileopt.plan(route, vehicle, segment_length_m=50.0, **ends)
    message = str(refused.value)
    assert message.startswith("slow.csv: the plan takes 2.083e+06 s") and "segment 0 (0 to 50 m" in message
    assert "vend_mps" in message and "segment_length_m" in message and "\n" not in message
    assert profileopt.plan(route, vehicle, segment_length_m=5.0, **ends).travel_time_s < 100.0
