"""The first band's top from a table (profileopt.online.band_table): never above the exact one,
and close to it."""

from __future__ import annotations

import numpy as np
import pytest

from profileopt import MODELS, force_n, load_vehicle
from profileopt.online.band_table import RI_GRID_HIGH, first_band_table
from profileopt.physics.speeds import speed_bands_of_sets

VEHICLES = ("atv", "atv-resonant")


def _random_sets(seed: int, high: float = RI_GRID_HIGH):
    """RIs from flat (0) to rough, log-uniform, with sets of 1-40 consecutive ones (a
    segment's windows)."""
    rng = np.random.default_rng(seed)
    values = np.exp(rng.uniform(np.log(1e-5), np.log(high), 1500))
    values[rng.uniform(size=values.size) < 0.05] = 0.0
    first = rng.integers(0, values.size - 1, 600)
    return values, first, np.minimum(first + rng.integers(1, 40, first.size), values.size)


@pytest.mark.parametrize("vehicle_name", VEHICLES)
@pytest.mark.parametrize("model", MODELS)
def test_the_table_is_never_above_the_exact_first_band_and_close_to_it(vehicle_name, model):
    # Reference: the exact bands of the sets (speed_bands_of_sets, itself checked against a
    # dense grid of forces in tests/physics/test_speeds.py); the first band's top of a set is
    # the least of its members'
    vehicle = load_vehicle(vehicle_name)
    values, first, stop = _random_sets(7, high=RI_GRID_HIGH * 1.5)  # some beyond the grid: found exactly
    table = first_band_table(vehicle, model).first_of_sets(values, first, stop)
    exact = speed_bands_of_sets(values, first, stop, vehicle, model=model)[0].first()
    assert np.all(table <= exact * (1 + 1e-12) + 1e-12)
    assert np.all(table >= exact - 0.06)
    if model == "sbem_tf":
        moving = exact > 0.3
        assert np.all(table[moving] >= 0.996 * exact[moving])
    beyond = np.array([values[a:b].max() > RI_GRID_HIGH for a, b in zip(first, stop)])
    assert beyond.any()
    np.testing.assert_allclose(table[beyond], exact[beyond], rtol=1e-12, atol=0)


@pytest.mark.parametrize("vehicle_name", VEHICLES)
def test_every_speed_up_to_the_table_top_keeps_every_member_within_the_limit(vehicle_name):
    # Reference: the SBEM:TF force of each member on a dense grid of speeds from 0 to the
    # table's top (brute force, no band finding)
    vehicle = load_vehicle(vehicle_name)
    values, first, stop = _random_sets(3, high=1.0)
    table = first_band_table(vehicle, "sbem_tf").first_of_sets(values, first[:25], stop[:25])
    for i, top in enumerate(table):
        speeds = np.linspace(0.0, top, 2001)
        for ri in values[first[i]:stop[i]]:
            force = np.asarray(force_n(speeds, vehicle, ri=np.full(speeds.size, ri))).ravel()
            assert np.all(force <= vehicle.max_transmitted_force_n * (1 + 1e-9))


def test_the_table_is_built_once_per_vehicle_and_model():
    vehicle = load_vehicle("atv")
    assert first_band_table(vehicle, "sbem_tf") is first_band_table(vehicle, "sbem_tf")
    assert first_band_table(vehicle, "iecm") is not first_band_table(vehicle, "sbem_tf")


def test_empty_sets_give_nothing():
    table = first_band_table(load_vehicle("atv"), "sbem_tf")
    assert table.first_of_sets(np.array([0.1]), np.empty(0, int), np.empty(0, int)).shape == (0,)
