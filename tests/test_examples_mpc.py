"""The MPC examples run, and their trajectories keep the force limit in every roughness window,
between their grid points.

The check here is independent of the examples' own (examples/mpc_window_check.py, which
solves for the times the vehicle enters and leaves each window and takes the force's
peaks from profileopt.physics.speeds): it replays each logged interval at 400 instants with its
constant acceleration, finds by comparison every roughness window that contains the
position at each instant, and evaluates the model's force (profileopt.physics.forces.force_n) at
that instant's speed for each of those windows' RI. The largest ratio must be within the
limit and must agree with the example's report (the report is exact, so it may only be
slightly higher than this sampled one).
"""

from __future__ import annotations

import importlib.util
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from profileopt import load_vehicle
from profileopt.mpc.constraints import add_force_constraints, force_limit_n, force_n
from profileopt.io import read_route
from profileopt.terrain.roughness import roughness_windows

from conftest import ROOT, markdown_section

EXAMPLES = ROOT / "examples"
ROUTES = EXAMPLES / "routes"
W = 5.0
needs_mpc_extra = pytest.mark.skipif(
    importlib.util.find_spec("do_mpc") is None or importlib.util.find_spec("rockit") is None,
    reason="the 'mpc' extra (do-mpc, rockit-meco) is not installed: pip install 'profileopt[mpc]'")


def _run(script: str, *argv: str, env: dict | None = None) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, str(EXAMPLES / script), *argv], capture_output=True, text=True,
                          timeout=300, env=env)


def _sampled_worst(route_name: str, vehicle, t, s, v, a) -> float:
    """Largest F / F_limit over 400 instants of every interval, against every window that
    contains the position at that instant."""
    route = read_route(ROUTES / route_name)
    win = roughness_windows(route.s_m, route.z_m, vehicle.ground_clearance_m, window_m=W)
    tau = np.linspace(0.0, 1.0, 400)[None, :] * np.diff(t)[:, None]
    pos = (s[:-1, None] + v[:-1, None] * tau + a[:, None] * tau**2 / 2).ravel()
    speed = np.abs(v[:-1, None] + a[:, None] * tau).ravel()
    # the replay ends where the log says: the intervals are what was driven
    np.testing.assert_allclose(s[:-1] + v[:-1] * np.diff(t) + a * np.diff(t) ** 2 / 2, s[1:], atol=1e-7)
    limit = force_limit_n(vehicle, model="sbem_tf")
    worst = 0.0
    near = np.flatnonzero((win.start_m <= pos.max()) & (win.stop_m >= pos.min()))
    starts, stops, ri = win.start_m[near], win.stop_m[near], win.ri[near]
    for i in range(0, pos.size, 200):
        p, sp = pos[i:i + 200, None], speed[i:i + 200, None]
        inside = (starts[None, :] <= p + 1e-9) & (stops[None, :] >= p - 1e-9)
        assert np.all(inside.any(axis=1))
        forces = force_n(np.broadcast_to(sp, inside.shape), vehicle, ri=np.broadcast_to(ri, inside.shape))
        worst = max(worst, float(np.max(np.where(inside, forces, 0.0))) / limit)
    return worst


def _reported(stdout: str) -> tuple[float, int]:
    match = re.search(r"worst window force over the limit: ([0-9.]+) .*windows over the limit: (\d+) of", stdout)
    assert match, stdout
    return float(match.group(1)), int(match.group(2))


def _check_log(path: Path, route_name: str, vehicle_name: str, stdout: str) -> float:
    log = np.genfromtxt(path, delimiter=",", names=True)
    vehicle = load_vehicle(vehicle_name)
    t, s, v, a = log["time_s"], log["s_m"], log["speed_mps"], log["accel_mps2"][:-1]
    assert np.all(a <= vehicle.max_accel_mps2 + 1e-7) and np.all(a >= -vehicle.max_decel_mps2 - 1e-7)
    assert np.all(v >= -1e-7) and np.all(v <= vehicle.max_speed_mps + 1e-7)
    sampled = _sampled_worst(route_name, vehicle, t, s, v, a)
    reported, over = _reported(stdout)
    assert over == 0 and reported <= 1.0
    assert sampled <= 1.0
    assert sampled <= reported + 1e-9  # the example's exact check is never below the samples ...
    assert reported - sampled <= 1e-3  # ... and close to them
    return sampled


def _hidden_route(folder: Path) -> Path:
    """A route the controller has never seen: class B ground with a kerb block (8 cm up at
    30 m, down at 45 m), 30 m of washboard (3 cm, 0.8 m waves) from 60 m and a pothole (8 cm
    deep, 0.8 m wide) at 120 m, sampled every 0.05 m."""
    from profileopt.terrain.synthetic import iso8608_profile, step, washboard

    ground = iso8608_profile("B", 170.0, 0.05, seed=11)
    s = ground.s_m
    z = (ground.z_m + step(s, 30.0, 0.08) - step(s, 45.0, 0.08) + washboard(s, 0.03, 0.8, 60.0, 90.0)
         - 0.08 * ((s >= 120.0) & (s <= 120.8)))
    path = folder / "hidden.csv"
    np.savetxt(path, np.column_stack([s, z]), delimiter=",", fmt="%.10g", header="s,z", comments="")
    return path


@pytest.mark.slow(seconds=110)  # the module's example runs, about 110 s in all on one core: started first
@pytest.mark.mpc
@needs_mpc_extra
@pytest.mark.parametrize("vehicle, cruise", [("atv", "12"), ("atv-resonant", "8")])
def test_dompc_example_converges_every_step_on_hidden_terrain(tmp_path: Path, vehicle: str, cruise: str) -> None:
    """Issue 31: the do-mpc controller of the docs, over a route it sees only 60 m ahead with a
    kerb, a washboard and a pothole, converges at every step with both vehicles and keeps
    every window within the limit (checked here at 400 instants of every interval)."""
    route = _hidden_route(tmp_path)
    run = _run("mpc_dompc.py", "--vehicle", vehicle, "--route", str(route), "--from-m", "0", "--distance-m", "150",
               "--cruise", cruise, "--max-steps", "2000", "--out", str(tmp_path))
    assert run.returncode == 0, run.stdout + run.stderr
    assert "IPOPT failures: 0" in run.stdout
    _check_log(tmp_path / f"mpc_dompc_{vehicle}.csv", route, vehicle, run.stdout)
    log = np.genfromtxt(tmp_path / f"mpc_dompc_{vehicle}.csv", delimiter=",", names=True)
    assert log["s_m"][-1] >= 150.0  # it got there


@pytest.mark.slow
@pytest.mark.mpc
@needs_mpc_extra
@pytest.mark.parametrize("vehicle", ["atv", "atv-resonant"])
def test_dompc_example_keeps_every_window_within_the_limit(tmp_path: Path, vehicle: str) -> None:
    run = _run("mpc_dompc.py", "--vehicle", vehicle, "--out", str(tmp_path))
    assert run.returncode == 0, run.stdout + run.stderr
    assert "IPOPT failures: 0" in run.stdout
    route = "washboard.csv" if vehicle == "atv-resonant" else "trail.csv"
    sampled = _check_log(tmp_path / f"mpc_dompc_{vehicle}.csv", route, vehicle, run.stdout)
    assert sampled > 0.999  # the limit bound somewhere: the run tested something


@pytest.mark.slow
@pytest.mark.mpc
@needs_mpc_extra
@pytest.mark.parametrize("vehicle", ["atv", "atv-resonant"])
def test_rockit_example_keeps_every_window_within_the_limit(tmp_path: Path, vehicle: str) -> None:
    run = _run("mpc_rockit.py", "--vehicle", vehicle, "--stages", "30", "--out", str(tmp_path))
    assert run.returncode == 0, run.stdout + run.stderr
    route = "washboard.csv" if vehicle == "atv-resonant" else "trail.csv"
    sampled = _check_log(tmp_path / f"mpc_rockit_{vehicle}.csv", route, vehicle, run.stdout)
    assert sampled > 0.999
    assert float(re.search(r"minimum time: ([0-9.]+) s", run.stdout).group(1)) > 0


@pytest.mark.slow
@pytest.mark.mpc
@needs_mpc_extra
def test_the_examples_check_finds_the_pointwise_constraint_unsafe(tmp_path: Path) -> None:
    """The constraint issue 10 found unsafe (the force at the grid points only, on the terrain
    under them): the washboard's resonant vehicle goes over the limit between them, and the
    example's own check says so and exits 1."""
    run = _run("mpc_rockit.py", "--vehicle", "atv-resonant", "--stages", "30", "--pointwise", "--out", str(tmp_path))
    assert run.returncode == 1, run.stdout + run.stderr
    reported, over = _reported(run.stdout)
    assert reported > 1.05 and over > 0
    log = np.genfromtxt(tmp_path / "mpc_rockit_atv-resonant.csv", delimiter=",", names=True)
    sampled = _sampled_worst("washboard.csv", load_vehicle("atv-resonant"), log["time_s"], log["s_m"],
                             log["speed_mps"], log["accel_mps2"][:-1])
    assert sampled > 1.05 and sampled <= reported + 1e-9


def test_without_the_extra_an_example_says_which_to_install(tmp_path: Path) -> None:
    """do-mpc and rockit hidden by modules that fail to import: one line naming the extra."""
    for name in ("do_mpc", "rockit"):
        (tmp_path / f"{name}.py").write_text("raise ImportError('not installed')\n", encoding="utf-8")
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(tmp_path), os.environ.get("PYTHONPATH", "")]))
    for script in ("mpc_dompc.py", "mpc_rockit.py"):
        run = _run(script, env=env)
        assert run.returncode == 1
        assert run.stderr.strip().count("\n") == 0 and "pip install 'profileopt[mpc]'" in run.stderr, run.stderr


@pytest.mark.slow(seconds=20)
@pytest.mark.parametrize(
    "route, vehicle, options",
    [
        # the trail's rough classes D to F: the force limit binds again and again
        ("trail.csv", "atv", ["--from-m", "950", "--until-m", "150"]),
        # the washboard for the resonant vehicle: it must slow to its upper band before it
        ("washboard.csv", "atv-resonant", ["--from-m", "100", "--until-m", "60", "--cruise", "8"]),
    ],
)
def test_preview_example_keeps_every_window_within_the_limit(tmp_path: Path, route: str, vehicle: str,
                                                             options: list[str]) -> None:
    run = _run("mpc_terrain_preview.py", "--route", str(ROUTES / route), "--vehicle", vehicle, "--out",
               str(tmp_path), *options)
    assert run.returncode == 0, run.stdout + run.stderr
    assert "IPOPT failures: 0" in run.stdout
    assert (tmp_path / "mpc_terrain_preview.png").stat().st_size > 10_000
    log = np.genfromtxt(tmp_path / "mpc_closed_loop.csv", delimiter=",", names=True)
    # one row per step (state, then the acceleration applied): the last state is the next
    # step's, so the replay covers every interval but the last
    t, s, v, a = log["time_s"], log["s_m"], log["speed_mps"], log["accel_mps2"]
    dt = np.diff(t)
    np.testing.assert_allclose(dt, 0.25, rtol=1e-12)
    veh = load_vehicle(vehicle)
    sampled = _sampled_worst(route, veh, t, s, v, a[:-1])
    reported, over = _reported(run.stdout)
    assert over == 0 and reported <= 1.0 and sampled <= reported + 1e-9
    assert sampled > 0.999


def test_mpc_guide_between_the_grid_points_snippet_runs_and_prints_its_answer() -> None:
    """The MPC guide's second snippet (once the README's), run as written from the
    repository's top folder: it ends in the washboard's upper band
    (examples/routes/washboard.csv: [0.53, 3.4] m/s)."""
    section = markdown_section("docs/guide/mpc.md", "Between the grid points")
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")])))
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300, cwd=ROOT, env=env)
    assert run.returncode == 0, run.stderr
    assert run.stdout.strip() == "3.37" and "3.37" in code


@pytest.mark.slow
@pytest.mark.mpc
@needs_mpc_extra
def test_add_force_constraints_works_on_a_rockit_ocp() -> None:
    """add_force_constraints takes any problem with subject_to: a rockit Ocp, minimum time
    over 50 m from rest. The fastest speed is the allowable speed of the RI (profileopt.physics.speeds,
    bracketing Newton) where that is below sqrt(2 a_max 50 m), the acceleration-limited one."""
    from rockit import FreeTime, MultipleShooting, Ocp

    from profileopt import allowable_speed

    vehicle = load_vehicle("atv")
    for ri in (0.05, 0.3):
        ocp = Ocp(T=FreeTime(5.0))
        s, v, a = ocp.state(), ocp.state(), ocp.control()
        ocp.set_der(s, v)
        ocp.set_der(v, a)
        ocp.add_objective(ocp.T)
        cons = add_force_constraints(ocp, v, vehicle, ri=ri, accel_mps2=a)
        assert cons.n_force == 1
        ocp.subject_to(v >= 0)
        ocp.subject_to(ocp.at_t0(s) == 0)
        ocp.subject_to(ocp.at_t0(v) == 0)
        ocp.subject_to(ocp.at_tf(s) == 50)
        ocp.solver("ipopt", {"print_time": False, "ipopt.print_level": 0, "ipopt.sb": "yes"})
        ocp.method(MultipleShooting(N=20))
        sol = ocp.solve()
        speeds, accels = sol.sample(v, grid="control")[1], sol.sample(a, grid="control")[1]
        expected = min(float(allowable_speed(ri, vehicle)), np.sqrt(2 * vehicle.max_accel_mps2 * 50.0))
        assert speeds.max() == pytest.approx(expected, rel=1e-5)
        assert accels.max() <= vehicle.max_accel_mps2 + 1e-6
