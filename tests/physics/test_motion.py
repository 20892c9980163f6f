"""The formulas of turns (profileopt.physics.motion): the speed a turn allows.

References, derived here by hand: v^2 kappa <= a_lat gives v <= sqrt(a_lat / kappa), so
sqrt(4 / 0.01) = 20 m/s and sqrt(4 / 10) = 0.632 m/s; a turn of radius 1 / kappa smaller than
the turning circle cannot be driven in one sweep: at most the crawl, 1 m/s
(profileopt.defaults.CRAWL_SPEED_MPS).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from profileopt.defaults import CRAWL_SPEED_MPS
from profileopt.physics.motion import lateral_speed_cap_mps, turn_speed_cap_mps


def test_the_speed_a_turn_allows() -> None:
    kappa = np.array([0.0, 0.01, 1 / 3.3, 1 / 3.2, 10.0])
    cap = turn_speed_cap_mps(4.0, kappa, 3.25)
    assert cap[0] == math.inf  # a straight
    assert cap[1] == pytest.approx(20.0, rel=1e-15)
    assert cap[2] == pytest.approx(math.sqrt(4.0 * 3.3), rel=1e-15)  # inside the turning circle: lateral
    assert CRAWL_SPEED_MPS == 1.0 and cap[3] == 1.0  # sharper than 3.25 m: the crawl (the lateral 3.58 m/s)
    assert cap[4] == pytest.approx(math.sqrt(0.4), rel=1e-15)  # the lateral cap, 0.632 m/s, below the crawl
    # without a turning circle it is the lateral cap alone
    np.testing.assert_array_equal(turn_speed_cap_mps(4.0, kappa), lateral_speed_cap_mps(4.0, kappa))
    # with no lateral limit (inf) only the crawl is left
    np.testing.assert_array_equal(turn_speed_cap_mps(math.inf, kappa, 3.25), [math.inf] * 3 + [1.0, 1.0])
