"""A kind of limit defined outside the package plans like the built-in ones (issue 9).

The limit protocol (profileopt.planning.limits.base.Limit) is what the planner depends on:
a new kind of limit is one class. Here a speed cap over a stretch of the route is defined in
this file alone and passed to plan(); the plan must keep it at every speed driven inside
every segment that touches the stretch, keep every other limit, and be unchanged elsewhere
where the cap cannot reach.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from profileopt import plan, read_route
from profileopt.planning import Limit, PlanContext

from conftest import ROUTES


@dataclasses.dataclass(frozen=True)
class StretchCap(Limit):
    """No faster than ``cap_mps`` anywhere between ``start_m`` and ``end_m``."""

    start_m: float
    end_m: float
    cap_mps: float
    name = "stretch cap"

    def speed_cap_mps(self, context: PlanContext) -> np.ndarray:
        b = context.segments.boundaries_m
        touches = (b[1:] > self.start_m) & (b[:-1] < self.end_m)
        return np.where(touches, self.cap_mps, np.inf)

    def cap_reason(self, profile, segment: int) -> str:
        return f"the stretch cap ({self.cap_mps:g} m/s)"


@pytest.mark.parametrize("smoothing, jerk", [(0.0, math.inf), (0.01, None)])
def test_a_limit_defined_in_a_test_is_kept(atv, check_profile, smoothing, jerk):
    route = read_route(ROUTES / "curb.csv")
    cap = StretchCap(start_m=120.0, end_m=140.0, cap_mps=3.0)
    free = plan(route, atv, smoothing=smoothing, max_jerk_mps3=jerk)
    capped = plan(route, atv, smoothing=smoothing, max_jerk_mps3=jerk, extra_limits=[cap])
    check_profile(capped, route, atv, jerk=jerk)
    s, v = capped.s_m, capped.speed_mps
    inside = (s[1:] > cap.start_m) & (s[:-1] < cap.end_m)  # segments touching the stretch
    # every speed of those segments (both ends; v^2 is linear in between) within the cap
    assert np.all(np.maximum(v[:-1], v[1:])[inside] <= cap.cap_mps * (1 + 1e-9))
    assert free.speed_mps[(s > cap.start_m) & (s < cap.end_m)].max() > 2 * cap.cap_mps  # it binds
    assert capped.travel_time_s > free.travel_time_s
    # far before the stretch (beyond the braking distance from 20 m/s at 4 m/s^2, 50 m) the
    # exact plan is unchanged
    if smoothing == 0.0:
        early = s < cap.start_m - 60.0
        np.testing.assert_array_equal(capped.speed_mps[early], free.speed_mps[early])
    summary = capped.summary()
    assert summary["slowest_segment"]["reason"] == "the stretch cap (3 m/s)"
    assert set(summary["margins"]) == {"force", "lateral", "friction", "accel", "decel", "power", "jerk"}


def test_two_limits_giving_speed_bands_are_refused(atv):
    from profileopt.errors import InputError
    from profileopt.planning import ForceLimit

    route = read_route(ROUTES / "curb.csv")
    with pytest.raises(InputError, match="only one limit may give speed bands"):
        plan(route, atv, extra_limits=[ForceLimit(model="iecm")])
