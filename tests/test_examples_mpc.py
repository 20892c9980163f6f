"""examples/mpc_terrain_preview.py runs, and its closed loop never breaks the force limit.

The check here is independent of the example's own report: it takes the closed-loop log
(state at each step and the acceleration applied over the next 0.25 s), replays the motion
densely, finds the planner's 5 m segment under every point, and evaluates the model's force
there with profileopt.forces, which must stay within the limit up to IPOPT's tolerance.
"""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from profileopt import load_vehicle
from profileopt.constraints import force_limit_n, force_n
from profileopt.planning import segment_route
from profileopt.io import read_route

from conftest import ROOT

EXAMPLES = ROOT / "examples"
DT = 0.25  # the example's control interval (s)


@pytest.mark.parametrize(
    "route, vehicle, options",
    [
        # the trail's rough classes D to F: the force limit binds again and again
        ("trail.csv", "atv", ["--from-m", "950", "--until-m", "300"]),
        # the washboard for the resonant vehicle: it must slow below resonance before it
        ("washboard.csv", "atv-resonant", ["--from-m", "100", "--until-m", "60", "--cruise", "8"]),
    ],
)
def test_mpc_example_keeps_the_force_limit(tmp_path: Path, route: str, vehicle: str, options: list[str]) -> None:
    run = subprocess.run(
        [sys.executable, str(EXAMPLES / "mpc_terrain_preview.py"), "--route", str(EXAMPLES / "routes" / route),
         "--vehicle", vehicle, "--out", str(tmp_path), *options],
        capture_output=True, text=True, timeout=120,
    )
    assert run.returncode == 0, run.stdout + run.stderr
    reported = float(re.search(r"worst force ratio met: ([0-9.]+)", run.stdout).group(1))
    assert "IPOPT failures: 0" in run.stdout
    assert (tmp_path / "mpc_terrain_preview.png").stat().st_size > 10_000

    log = np.genfromtxt(tmp_path / "mpc_closed_loop.csv", delimiter=",", names=True)
    veh = load_vehicle(vehicle)
    assert np.all(log["accel_mps2"] <= veh.max_accel_mps2) and np.all(log["accel_mps2"] >= -veh.max_decel_mps2)
    assert np.all(log["speed_mps"] >= 0) and np.all(log["speed_mps"] <= veh.max_speed_mps * (1 + 1e-9))
    # replay each interval at 200 instants (constant acceleration) on the real segments
    seg = segment_route(read_route(EXAMPLES / "routes" / route), veh, 5.0)
    tau = np.linspace(0.0, DT, 200)[None, :]
    s0, v0, a = (log[k][:, None] for k in ("s_m", "speed_mps", "accel_mps2"))
    s, v = s0 + v0 * tau + a * tau**2 / 2, v0 + a * tau
    np.testing.assert_allclose(s[:-1, -1], log["s_m"][1:], rtol=0, atol=1e-9)  # the log is consistent
    i = np.clip(np.searchsorted(seg.boundaries_m, s, side="right") - 1, 0, seg.count - 1)
    ratio = force_n(v, veh, e_max_m=seg.e_max_m[i], model="sbem_tf") / force_limit_n(veh, model="sbem_tf")
    assert ratio.max() <= 1 + 1e-6
    assert ratio.max() > 0.999  # the limit was met, so this run tested something
    assert reported <= 1 + 1e-6 and reported >= ratio.max() - 1e-9  # the example's exact check agrees
