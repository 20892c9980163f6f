"""The profile's summary (issue 30, item 14): a ratio at the limit reads at most 1."""

from __future__ import annotations

import dataclasses

import numpy as np

from conftest import ROUTES
from profileopt import load_vehicle, plan, read_route
from profileopt.core.profile import at_limit
from profileopt.defaults import LIMIT_RTOL


def test_a_ratio_within_the_check_tolerance_reads_at_the_limit() -> None:
    assert at_limit({"ratio": 1.0000000002, "s_m": 5.0}) == {"ratio": 1.0, "s_m": 5.0}
    assert at_limit({"ratio": 1.0 + LIMIT_RTOL, "s_m": 5.0})["ratio"] == 1.0
    # beyond the tolerance a breach reads as one; below 1 and None stay as they are
    assert at_limit({"ratio": 1.0 + 2 * LIMIT_RTOL, "s_m": 5.0})["ratio"] == 1.0 + 2 * LIMIT_RTOL
    assert at_limit({"ratio": 0.97, "s_m": 1.0})["ratio"] == 0.97
    assert at_limit({"ratio": None, "s_m": None}) == {"ratio": None, "s_m": None}


class _Over:
    """A limit whose margin is a hair over 1, as rounding leaves it."""

    name = "jerk"

    def __init__(self, ratio: float) -> None:
        self.ratio = ratio

    def margins(self, profile: object) -> dict:
        return {"jerk": {"ratio": self.ratio, "s_m": 5.0}}


def test_the_summary_reads_a_rounding_over_the_limit_as_1() -> None:
    profile = plan(read_route(ROUTES / "curb.csv"), load_vehicle("atv"))
    for ratio, shown in ((1.0000000002, 1.0), (1.01, 1.01)):
        limits = tuple(_Over(ratio) if limit.name == "jerk" else limit for limit in profile.limits)
        margins = dataclasses.replace(profile, limits=limits).summary()["margins"]
        assert margins["jerk"]["ratio"] == shown
    # every margin of a real plan is at most 1
    assert all(m["ratio"] is None or m["ratio"] <= 1.0 for m in profile.summary()["margins"].values())
    assert np.isfinite(profile.travel_time_s)
