"""A known defect, kept failing on purpose until it is fixed: a climb from rest that the power
limit allows is refused on 10 m segments.

Found by ``test_planner_properties.py::test_every_plan_keeps_every_limit`` (a random example
of the suite's default Hypothesis profile, 2026-11-28; the same at commit 3727444, before that
session's changes). The route (``data/power_climb_50m.csv``, the example's samples: ISO 8608
class A ground on a 0.29 grade, with a step and a washboard stretch) climbs 14.3 m in 50 m;
the vehicle (the atv with 300 kg, 2 kW, 3 m/s top speed, 1 m/s^2 braking, 1 m/s^3 jerk) starts
and stops at rest. A crawl (v = 0 at both ends, a small speed at every interior boundary)
keeps every limit, the power limit too (P = m (a + g sin theta) v is small at small v), so a
profile exists; the planner says instead that the segments are too long for the
power-limited climb and asks for 1.67 m or less, and plans it on 1.5 m segments (24.96 s).
When the planner plans it on 10 m segments, this test fails (strict): remove the mark then.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from profileopt import load_vehicle, plan
from profileopt.core.route import Route

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


def test_the_climb_is_planned_on_short_segments() -> None:
    """The segment length the refusal names (1.67 m or less) plans it."""
    route, vehicle = _problem()
    profile = plan(route, vehicle, segment_length_m=1.5, **OPTIONS)
    assert profile.speed_mps[0] == 0.0 and profile.speed_mps[-1] == 0.0
    assert 0.0 < profile.travel_time_s < np.inf


@pytest.mark.xfail(strict=True, reason="known defect: a power-limited climb from rest refused on 10 m segments "
                                       "although a crawl keeps every limit (module docstring)")
def test_the_climb_is_planned_on_10_m_segments() -> None:
    route, vehicle = _problem()
    plan(route, vehicle, segment_length_m=10.0, **OPTIONS)
