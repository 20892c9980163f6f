"""The terrain measured so far: dense prefix only, frozen, forgotten behind (profileopt.online.sensed)."""

from __future__ import annotations

import numpy as np
import pytest

from profileopt.errors import InputError
from profileopt.online.sensed import SensedTerrain


def test_measured_stops_at_the_first_wide_gap_and_moves_on_when_it_is_filled():
    terrain = SensedTerrain(start_m=0.0, max_spacing_m=0.1)
    terrain.add(np.arange(0.0, 5.0001, 0.05), np.zeros(101))
    assert terrain.measured_to_m == pytest.approx(5.0)
    far = np.arange(6.0, 8.0001, 0.05)  # beyond a 1 m gap: sensed, not measured
    terrain.add(far, np.zeros(far.size))
    assert terrain.measured_to_m == pytest.approx(5.0)
    gap = np.arange(5.05, 5.96, 0.05)
    terrain.add(gap, np.ones(gap.size))
    assert terrain.measured_to_m == pytest.approx(8.0)


def test_measured_terrain_is_frozen_and_later_samples_there_are_ignored():
    terrain = SensedTerrain(start_m=0.0, max_spacing_m=0.1)
    s = np.arange(0.0, 2.0001, 0.05)
    terrain.add(s, np.zeros(s.size))
    terrain.add(s, np.full(s.size, 9.0))  # a noisy re-measurement of the same ground
    route = terrain.stretch(0.0, 2.0)
    assert np.all(route.z_m == 0.0)


def test_nothing_is_measured_until_a_sample_near_the_start():
    terrain = SensedTerrain(start_m=0.0, max_spacing_m=0.1)
    terrain.add([1.0, 1.05], [0.0, 0.0])
    assert terrain.stretch(0.0, 2.0) is None
    terrain.add(np.arange(0.0, 0.96, 0.05), np.zeros(20))
    assert terrain.measured_to_m == pytest.approx(1.05)


def test_forgetting_keeps_memory_bounded_however_long_the_route():
    terrain = SensedTerrain(start_m=0.0, max_spacing_m=0.1)
    for k in range(200):  # 200 m in 1 m pieces, forgetting what lies 10 m behind
        s = k + np.arange(0.0, 1.0, 0.05)
        terrain.add(s, np.zeros(s.size))
        terrain.forget_before(k - 10.0)
    assert terrain.sample_count < 12 * 20 + 5
    assert terrain.measured_to_m == pytest.approx(199.95)


@pytest.mark.parametrize("kwargs, words", [
    ({"s_m": [0.0, 0.05], "z_m": [0.0]}, "same length"),
    ({"s_m": [0.0, np.nan], "z_m": [0.0, 0.0]}, "not finite"),
    ({"s_m": [0.0, 0.05], "z_m": [0.0, 0.0], "x_m": [0.0, 0.1]}, "both x_m and y_m"),
])
def test_bad_samples_are_refused_in_one_line(kwargs, words):
    terrain = SensedTerrain(start_m=0.0)
    with pytest.raises(InputError, match=words):
        terrain.add(**kwargs)
