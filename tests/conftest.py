"""Shared fixtures and constants of the test suite.

Paths: everything the tests read is inside the repository (``data/real/`` holds the measured
terrain, ``examples/routes/`` the bundled routes), so a fresh clone runs every test with
nothing beside it. Test modules that need a path at import time (in a ``parametrize`` list,
say) import the constant (``from conftest import ROUTES``); tests use the fixtures.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

from profileopt import force_n, load_vehicle

#: the repository (this file is tests/conftest.py)
ROOT = Path(__file__).resolve().parents[1]
#: the bundled example routes
ROUTES = ROOT / "examples" / "routes"
#: the measured terrain bundled with the repository (sources and licences: data/README.md)
REAL_DATA = ROOT / "data" / "real"

#: the ``profileopt`` command, run by the interpreter that runs the tests (``python -m
#: profileopt`` is the console script's entry point, profileopt.cli:main)
PROFILEOPT = (sys.executable, "-m", "profileopt")


@pytest.fixture(scope="session")
def atv():
    """The bundled ``atv`` (the paper's Table 1)."""
    return load_vehicle("atv")


@pytest.fixture(scope="session")
def atv_resonant():
    """The bundled ``atv-resonant`` (the lightly damped ATV of the paper's Fig. 6)."""
    return load_vehicle("atv-resonant")


@pytest.fixture(scope="session")
def profileopt_command() -> list[str]:
    """The argv prefix that runs the ``profileopt`` command: ``[*profileopt_command, "plan", ...]``."""
    return list(PROFILEOPT)


@pytest.fixture(scope="session")
def check_profile():
    """``check_profile(profile, route, vehicle, *, jerk=None, rtol=1e-6, grid=64)``: assert
    that a planned profile keeps every limit (see :func:`_check_profile`)."""
    return _check_profile


def _check_profile(profile, route, vehicle, *, jerk=None, rtol=1e-6, grid=64):
    """Assert that ``profile`` keeps every limit (independent of the planner's own check).

    An evaluation of every constraint written independently of the planner: speeds against
    the caps, accelerations recomputed from speed^2 differences, jerk v da/ds, and the
    model's force on a fine grid of the speeds each segment passes through.
    """
    s, v = profile.s_m, profile.speed_mps
    vmax = vehicle.max_speed_mps
    assert np.all(v >= 0) and np.all(v <= vmax * (1 + rtol))
    if route.speed_limit_mps is not None:
        # every sample inside a segment caps both of the segment's boundary speeds
        seg = np.searchsorted(s, route.s_m, side="right") - 1
        seg = np.clip(seg, 0, s.size - 2)
        cap = np.full(s.size - 1, np.inf)
        np.minimum.at(cap, seg, route.speed_limit_mps)
        assert np.all(np.maximum(v[:-1], v[1:]) <= cap * (1 + rtol))
    ds = np.diff(s)
    accel = (v[1:] ** 2 - v[:-1] ** 2) / (2 * ds)  # constant acceleration in s: v^2 linear
    assert np.all(accel <= vehicle.max_accel_mps2 * (1 + rtol))
    assert np.all(-accel <= vehicle.max_decel_mps2 * (1 + rtol))
    np.testing.assert_allclose(profile.accel_mps2[:-1], accel, rtol=1e-9, atol=1e-9)
    j_max = vehicle.max_jerk_mps3 if jerk is None else jerk
    if math.isfinite(j_max) and ds.size >= 2:
        jerk_values = v[1:-1] * np.diff(accel) / (0.5 * (ds[:-1] + ds[1:]))
        assert np.all(np.abs(jerk_values) <= j_max * (1 + rtol))
    # each segment's RI again, from the route's own samples: Eq. (1) on the residual of a
    # least-squares line (numpy.polyfit), population std over the clearance h
    seg_of_sample = np.clip(np.searchsorted(s, route.s_m, side="right") - 1, 0, s.size - 2)
    ri_route = np.empty(s.size - 1)
    for i in range(s.size - 1):
        xs, zs = route.s_m[seg_of_sample == i], route.z_m[seg_of_sample == i]
        residual = zs - np.polyval(np.polyfit(xs - xs[0], zs, 1), xs - xs[0])
        ri_route[i] = np.std(residual) / vehicle.ground_clearance_m
    np.testing.assert_allclose(profile.ri[:-1], ri_route, rtol=1e-6, atol=1e-9)
    # the force over every speed between the two boundary speeds of each segment
    frac = np.linspace(0.0, 1.0, grid)
    speeds = v[:-1, None] + (v[1:] - v[:-1])[:, None] * frac[None, :]
    ri = ri_route[:, None] * np.ones_like(frac)[None, :]
    forces = force_n(speeds, vehicle, ri=ri, model=profile.model)
    limit = profile.force_limit_n[0]
    assert np.all(forces <= limit * (1 + rtol)), f"force ratio {forces.max() / limit}"
    # the reported force is at least what the grid sees, and within the limit
    assert np.all(profile.force_n[:-1] >= forces.max(axis=1) * (1 - 1e-9))
    assert np.all(profile.force_n <= limit * (1 + rtol))
    # time: dt = 2 ds / (v_i + v_{i+1}) for constant acceleration
    np.testing.assert_allclose(np.diff(profile.time_s), 2 * ds / (v[:-1] + v[1:]), rtol=1e-12)
