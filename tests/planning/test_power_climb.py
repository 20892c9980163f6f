"""A power-limited climb on segments too long for the forward pass to be exact.

Found by ``test_planner_properties.py::test_every_plan_keeps_every_limit`` (a random example
of the suite's default Hypothesis profile, 2026-11-28). The route (``data/power_climb_50m.csv``,
the example's samples: ISO 8608 class A ground on a 0.29 grade, with a step and a washboard
stretch) climbs 14.3 m in 50 m; the vehicle (the atv with 300 kg, 2 kW, 3 m/s top speed,
1 m/s^2 braking, 1 m/s^3 jerk; IECM) starts and stops at rest. On 10 m segments the forward
pass entered a segment above the steady climbing speed, where the power limit slows the
vehicle down all the way, and it stalled within the segment; the planner then refused the
route ("segments too long for the power-limited climb"), although entering slower climbs it.
The forward pass (``profileopt.planning.bands._forward_with_power``) now enters slower where
that is so.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from profileopt import load_vehicle, plan
from profileopt.core.route import Route
from profileopt.physics.motion import STANDARD_GRAVITY_MPS2
from profileopt.planning.bands import DrivePower, choose_bands, greatest_profile
from profileopt.verification.limit_check import check_limits

DATA = Path(__file__).resolve().parent / "data" / "power_climb_50m.csv"


def _problem() -> tuple[Route, object]:
    samples = np.loadtxt(DATA, delimiter=",", skiprows=1)
    route = Route(s_m=samples[:, 0], z_m=samples[:, 1], speed_limit_mps=None, source=DATA.name, x_m=None, y_m=None)
    vehicle = load_vehicle("atv").replace(
        quarter_mass_kg=100.0, ground_clearance_m=0.1, wheel_radius_m=0.1, natural_frequency_radps=3.0,
        damping_ratio=0.5, confidence=0.9, max_excitation_force_n=5000.0, max_transmitted_force_n=5000.0,
        max_speed_mps=3.0, max_accel_mps2=3.0, max_decel_mps2=1.0, max_jerk_mps3=1.0, max_lateral_accel_mps2=None,
        track_width_m=None, cg_height_m=None, friction_coefficient=None, mass_kg=300.0, max_power_w=2000.0)
    return route, vehicle


OPTIONS = dict(model="iecm", smoothing=0.0, v0_mps=0.0, vend_mps=0.0, band="all", method="auto", refine=False)


@pytest.mark.parametrize("segment_length_m", [1.5, 5.0, 10.0])
def test_the_climb_is_planned_and_keeps_every_limit(segment_length_m: float) -> None:
    """Planned on 1.5 m segments (exact there: no note) and on 5 and 10 m (a note names the
    1.67 m that plan it exactly); every plan passes the independent check of every limit."""
    route, vehicle = _problem()
    profile = plan(route, vehicle, segment_length_m=segment_length_m, **OPTIONS)
    assert profile.speed_mps[0] == 0.0 and profile.speed_mps[-1] == 0.0
    assert 0.0 < profile.travel_time_s < np.inf
    noted = any("power-limited climb" in note and "<= 1.67 m" in note for note in profile.notes)
    assert noted == (segment_length_m > 1.67)
    found = check_limits(route, profile, vehicle)
    assert not found.breaches, [breach.describe() for breach in found.breaches]


def test_a_stall_entering_fast_is_avoided_by_entering_at_the_steady_climbing_speed() -> None:
    """One 10 m segment with P/m = 2 W/kg and g sin(theta) = 1 m/s^2 (steady speed 2 m/s, b = 4),
    entered at b = 9 (hand calculation): at 3 m/s the power limit slows the vehicle all the way,
    to b = 9 + 2 * 10 * (2/3 - 1) = 2.33. That is kept when the next boundary asks for no more
    (it is the faster way over the segment: 20 / (3 + 1.53) = 4.42 s against 20 / (2 + 2) = 5 s);
    when it asks for b >= 3, the pass enters at the steady speed and leaves at it, b = 4."""
    power = DrivePower(power_per_mass_w_per_kg=2.0, grade_hi_rad=np.array([math.asin(1.0 / STANDARD_GRAVITY_MPS2)]))
    upper, ds = np.array([9.0, 100.0]), np.array([10.0])
    fast = greatest_profile(np.zeros(2), upper, ds, 10.0, 10.0, power)
    np.testing.assert_allclose(fast, [9.0, 9.0 + 20.0 * (2.0 / 3.0 - 1.0)], rtol=1e-12)
    slow = greatest_profile(np.array([0.0, 3.0]), upper, ds, 10.0, 10.0, power)
    np.testing.assert_allclose(slow, [4.0, 4.0], rtol=1e-12)


def test_a_slower_entry_keeps_the_boundarys_own_lower_bound() -> None:
    """A level 1 m segment at b = 9, then the 10 m climb above (P/m = 2 W/kg, g sin(theta) = 1
    m/s^2), whose exit must reach b = 2.5 while its entry must keep b >= 5 (the bands either
    side). Entering at 9 ends at 2.33 (short); the steady climbing speed b = 4 is below the
    entry's bound; entering at the bound, 5, ends at 5 + 20 (2 / sqrt 5 - 1) = 2.89 >= 2.5, so
    [9, 5, 2.5] keeps every limit (hand calculation). Found by review: the slower entry first
    ignored the boundary's own lower bound, and the band choice then refused such routes."""
    power = DrivePower(power_per_mass_w_per_kg=2.0,
                       grade_hi_rad=np.array([0.0, math.asin(1.0 / STANDARD_GRAVITY_MPS2)]))
    lower, upper = np.array([9.0, 5.0, 2.5]), np.array([9.0, 9.0, 2.5])
    found = greatest_profile(lower, upper, np.array([1.0, 10.0]), 10.0, 10.0, power)
    np.testing.assert_allclose(found, [9.0, 5.0, 2.5], rtol=1e-12)
    assert 5.0 + 20.0 * (2.0 / math.sqrt(5.0) - 1.0) >= 2.5


def test_a_coarse_climb_entered_at_v0_is_never_lowered_below_v0() -> None:
    """The 10 m climb entered at v0 = 3 m/s (b = 9), then a level 5 m segment with the bands
    [0, 1] and [sqrt 3, 10] m/s and 20 m to a stop. Entering at 9 ends at 2.33, short of the
    upper band's 3: the start cannot enter slower (v0 is given), so the band choice takes the
    lower band, [9, 1, 1, 0] (as before 21be0e0; 21be0e0 lowered the start below v0 and refused
    with "raise max_decel_mps2", found by review)."""
    power = DrivePower(power_per_mass_w_per_kg=2.0,
                       grade_hi_rad=np.array([math.asin(1.0 / STANDARD_GRAVITY_MPS2), 0.0, 0.0]))
    length = np.array([10.0, 5.0, 20.0])
    nan = np.nan
    lower = np.array([[0.0, nan], [0.0, math.sqrt(3.0)], [0.0, nan]])
    upper = np.array([[10.0, nan], [1.0, 10.0], [10.0, nan]])
    choice = choose_bands(lower, upper, np.array([1, 2, 1]), length, 10.0, 10.0, 3.0, 0.0,
                          np.concatenate([[0.0], np.cumsum(length)]), power)
    np.testing.assert_array_equal(choice.band, [0, 0, 0])
    np.testing.assert_allclose(choice.greatest_b, [9.0, 1.0, 1.0, 0.0], rtol=1e-12)
