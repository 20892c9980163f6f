"""``profileopt verify`` as a gate a script or CI can trust (issue 13).

A profile must cover its route exactly; every prediction is recomputed from the profile's
speeds; the vehicle's own limits (speed, acceleration, jerk, predicted force) are checked
before the simulation; and the exit status says which verdict it is:

- 0: the plan keeps every limit and no segment's simulated force exceeds the limit;
- 3: the profile breaks one of the vehicle's own limits;
- 4: the limits hold on paper, but the simulation puts a segment over the force limit;
- 2: bad input (one line), 1: internal error.

Each test edits a real profile (``profileopt plan`` on a bundled route) as a user would.
"""

from __future__ import annotations

import os
import re
import subprocess
from pathlib import Path

import numpy as np
import pytest

from conftest import ROUTES, WIDE_TERMINAL

KRC_1IN = ROUTES / "krc_rms_1in.csv"
CURB = ROUTES / "curb.csv"


def run(command: list[str], *args: str | Path, cwd: Path | None = None) -> subprocess.CompletedProcess:
    env = dict(os.environ, MPLBACKEND="Agg", **WIDE_TERMINAL)  # --help: no wrapping, whatever the terminal
    return subprocess.run([*command, *map(str, args)], capture_output=True, text=True, timeout=300,
                          env=env, cwd=cwd)


@pytest.fixture(scope="module")
def planned(profileopt_command, tmp_path_factory) -> dict[str, Path]:
    """SBEM:TF plans of krc_rms_1in and curb with the atv, and a Prev:BEM plan of krc_rms_1in."""
    folder = tmp_path_factory.mktemp("plans")
    plans = {"krc": (KRC_1IN, ()), "curb": (CURB, ()), "krc_prev_bem": (KRC_1IN, ("--model", "prev_bem"))}
    out = {}
    for name, (route, extra) in plans.items():
        path = folder / f"{name}.csv"
        done = run(profileopt_command, "plan", route, "--vehicle", "atv", *extra, "-o", path)
        assert done.returncode == 0, done.stderr
        out[name] = path
    return out


def edited(source: Path, target: Path, *, speed=None, rows: slice = slice(None), column: str | None = None,
           value: float | None = None) -> Path:
    """A copy of a profile CSV with its speeds mapped by ``speed(v)`` (row by row), only the
    rows ``rows`` kept, or one ``column`` set to ``value``: the edits a user makes by hand."""
    lines = source.read_text().splitlines()
    head, header, body = lines[0], lines[1], lines[2:]
    names = header.split(",")
    out = []
    for line in body[rows]:
        cells = line.split(",")
        if speed is not None:
            cells[1] = repr(float(speed(float(cells[1]))))
        if column is not None:
            cells[names.index(column)] = repr(float(value))
        out.append(",".join(cells))
    target.write_text("\n".join([head, header, *out]) + "\n")
    return target


def table(path: Path) -> dict[str, np.ndarray]:
    lines = path.read_text().splitlines()
    names = lines[1].split(",")
    numeric = [i for i, name in enumerate(names) if name != "binding"]  # the one text column
    values = np.array([[float(line.split(",")[i]) for i in numeric] for line in lines[2:]])
    return {names[i]: values[:, k] for k, i in enumerate(numeric)}


def verdict_line(stdout: str) -> str:
    """The first line after the header: the verdict."""
    return stdout.splitlines()[1]


@pytest.mark.slow
def test_a_planned_profile_passes_with_exit_0(profileopt_command, planned) -> None:
    done = run(profileopt_command, "verify", KRC_1IN, planned["krc"])
    assert done.returncode == 0, done.stdout + done.stderr
    assert "keeps every limit" in verdict_line(done.stdout)
    assert done.stderr == ""
    assert "stale" not in done.stdout  # a fresh plan's predictions are the recomputed ones


def test_a_profile_cut_short_is_refused_with_one_line(profileopt_command, planned, tmp_path) -> None:
    # 11 rows deleted at the end: the profile stops at 450 m of a 504.75 m route
    cut = edited(planned["krc"], tmp_path / "cut.csv", rows=slice(None, -11))
    out = tmp_path / "v.csv"
    done = run(profileopt_command, "verify", KRC_1IN, cut, "-o", out)
    assert done.returncode == 2, done.stdout + done.stderr
    assert done.stdout == "" and done.stderr.count("\n") == 1 and "Traceback" not in done.stderr
    assert "end" in done.stderr and "54.75 m" in done.stderr  # which end, and by how much
    assert not out.exists()


def test_a_profile_without_its_first_row_is_refused_with_one_line(profileopt_command, planned, tmp_path) -> None:
    # before: "internal error: ValueError: operands could not be broadcast together"
    headless = edited(planned["krc"], tmp_path / "headless.csv", rows=slice(1, None))
    done = run(profileopt_command, "verify", KRC_1IN, headless)
    assert done.returncode == 2, done.stdout + done.stderr
    assert done.stderr.count("\n") == 1 and "internal error" not in done.stderr
    assert "start" in done.stderr and "5 m" in done.stderr


@pytest.mark.slow
def test_speeds_raised_by_hand_break_the_vehicles_limits_exit_3(profileopt_command, planned, tmp_path) -> None:
    # 1.6 times the SBEM:TF plan on the KRC 1-inch course. Before: "1.225 times the limit in
    # simulation", exit 0. Exit 3, not 4: the plan breaks the vehicle's own limits on paper
    # already (the planned profile sits at the edge of the force, acceleration and jerk
    # limits, so 1.6 times its speeds predict more force than the limit and 2.56 times the
    # acceleration), which is the verdict that comes first; the simulation is reported
    # beside it. (Since every segment is planned for the windows it meets, issue 10, the
    # plan is slower, and 1.6 times it simulates 0.88 of the limit, not 1.225: the number
    # is the simulation's, what this test holds is that it is reported.)
    raised = edited(planned["krc"], tmp_path / "raised.csv", speed=lambda v: 1.6 * v)
    out = tmp_path / "v.csv"
    done = run(profileopt_command, "verify", KRC_1IN, raised, "-o", out)
    assert done.returncode == 3, done.stdout + done.stderr
    verdict = verdict_line(done.stdout)
    assert "breaks" in verdict
    for kind in ("acceleration", "jerk", "force"):
        assert kind in done.stdout
    # the simulation is still reported, by windows and by segments
    assert "roughness windows (5 m) over the limit:" in done.stdout and "worst window:" in done.stdout
    assert "worst segment, simulated / limit:" in done.stdout
    # the prediction follows the speeds: above the limit somewhere
    assert table(out)["predicted_force_n"].max() > 5000.0


@pytest.mark.slow
def test_a_profile_at_100_mps_for_a_20_mps_vehicle_breaks_the_top_speed(profileopt_command, planned,
                                                                           tmp_path) -> None:
    # Before: "0 of 40 over the limit", exit 0 (from rest to 100 m/s in 5 m is 1000 m/s^2)
    fast = edited(planned["curb"], tmp_path / "fast.csv", speed=lambda v: 100.0 if v > 0 else 0.0)
    done = run(profileopt_command, "verify", CURB, fast)
    assert done.returncode == 3, done.stdout + done.stderr
    assert "breaks" in verdict_line(done.stdout)
    first_breach = done.stdout.splitlines()[2]
    assert "top speed" in first_breach and "100 m/s" in first_breach and "20 m/s" in first_breach
    assert "1000 m/s^2" in done.stdout


@pytest.mark.slow
def test_a_stale_force_column_is_recomputed_and_noted(profileopt_command, planned, tmp_path) -> None:
    # the file's force_n says 1 N everywhere; the speeds are the plan's
    stale = edited(planned["krc"], tmp_path / "stale.csv", column="force_n", value=1.0)
    out = tmp_path / "v.csv"
    done = run(profileopt_command, "verify", KRC_1IN, stale, "-o", out)
    assert done.returncode == 0, done.stdout + done.stderr
    assert "stale" in done.stdout and "recomputed" in done.stdout
    predicted = table(out)["predicted_force_n"]
    assert np.allclose(predicted, table(planned["krc"])["force_n"][:-1], rtol=1e-9)
    # speeds lowered by hand: the prediction follows them (never above the plan's)
    slower = edited(planned["krc"], tmp_path / "slower.csv", speed=lambda v: 0.9 * v)
    done = run(profileopt_command, "verify", KRC_1IN, slower, "-o", out)
    assert done.returncode == 0, done.stdout + done.stderr
    assert "stale" in done.stdout
    recomputed, recorded = table(out)["predicted_force_n"], table(planned["krc"])["force_n"][:-1]
    assert np.all(recomputed <= recorded) and np.any(recomputed < 0.99 * recorded)


def test_speeds_of_1e155_break_the_top_speed_without_a_crash(profileopt_command, planned, tmp_path) -> None:
    # Before: "internal error: RuntimeError: a segment holds no time step" after 9 lines of warnings
    absurd = edited(planned["krc"], tmp_path / "absurd.csv", speed=lambda v: 1e155)
    out = tmp_path / "v.csv"
    done = run(profileopt_command, "verify", KRC_1IN, absurd, "-o", out)
    assert done.returncode == 3, done.stdout + done.stderr
    assert done.stderr == "" and "Traceback" not in done.stdout
    assert "breaks" in verdict_line(done.stdout) and "top speed" in done.stdout
    assert "not simulated" in done.stdout


@pytest.mark.slow
def test_a_plan_that_keeps_its_limits_but_not_in_simulation_exits_4(profileopt_command, planned) -> None:
    # Prev:BEM's plan keeps Prev:BEM's own prediction within the limit, but the simulated
    # excitation exceeds it in hundreds of the 19991 roughness windows (1471 measured) and on 7
    # segments (README, compare table). 19991 windows: every set of samples a 5 m window holds
    # at any offset; of the 10096 samples 5 cm apart, the 9996 with room each start one, and
    # each but the first one more starting just after the sample before it.
    done = run(profileopt_command, "verify", KRC_1IN, planned["krc_prev_bem"])
    assert done.returncode == 4, done.stdout + done.stderr
    verdict = verdict_line(done.stdout)
    over = re.search(r"in simulation (\d+) of 19991 roughness windows \(5 m\) and (\d+) of 101 segments", verdict)
    assert over and int(over.group(1)) >= 100 and int(over.group(2)) >= 5, verdict


def test_the_exit_statuses_are_documented_in_the_help(profileopt_command) -> None:
    done = run(profileopt_command, "verify", "--help")
    assert done.returncode == 0
    text = " ".join(done.stdout.split())
    for status in ("0:", "2:", "3:", "4:"):
        assert status in text


def test_the_simulator_refuses_a_speed_whose_square_overflows(atv) -> None:
    # Before: RuntimeWarnings, then "RuntimeError: a segment holds no time step"
    from profileopt.errors import InputError
    from profileopt.physics.simulate import simulate_quarter_car

    s = np.linspace(0.0, 10.0, 201)
    with pytest.raises(InputError, match="1e\\+155 m/s, is too large to simulate"):
        simulate_quarter_car(s, np.zeros_like(s), np.array([0.0, 5.0, 10.0]), np.full(3, 1e155), atv)


def test_a_reversal_is_crawled_by_plan_and_a_top_speed_one_fails_verify(tmp_path: Path, capsys) -> None:
    # issue 29: out 60 m and back along the same line was planned at top speed through the
    # U-turn and passed verify. A reversal within the 0.1 m tolerance is a U-turn of radius
    # 0.1 m: sqrt(4 m/s^2 * 0.1 m) = 0.632 m/s for the atv (tests/planning/test_lateral.py)
    from profileopt.cli import main
    from profileopt.io import read_profile

    leg = np.arange(0.0, 60.25, 0.5)
    x = np.concatenate([leg, leg[::-1][1:]])
    s = np.concatenate([[0.0], np.cumsum(np.abs(np.diff(x)))])
    z = 0.002 * np.sin(s)
    route, twin = tmp_path / "out-and-back.csv", tmp_path / "straight.csv"
    np.savetxt(route, np.column_stack([x, 0 * x, z]), delimiter=",", header="x,y,z", comments="", fmt="%.6f")
    np.savetxt(twin, np.column_stack([s, z]), delimiter=",", header="s,z", comments="", fmt="%.6f")
    planned, fast = tmp_path / "planned.csv", tmp_path / "fast.csv"
    assert main(["plan", str(route), "-o", str(planned)]) == 0
    out, err = capsys.readouterr()
    assert "path         tolerance 0.1 m (estimated from the x,y" in out
    note = [line for line in err.splitlines() if "reverses" in line]
    assert len(note) == 1 and "s = 60" in note[0] and "180 deg" in note[0] and "crawl" in note[0]
    profile = read_profile(planned)
    turn = np.abs(profile.s_m - 60.0) <= 2.5
    assert profile.speed_mps[turn].max() == pytest.approx(0.632, abs=0.001)  # at most 2 m/s: a crawl
    assert profile.settings["path_tolerance_source"] == "estimated"
    assert main(["verify", str(route), str(planned)]) == 0
    capsys.readouterr()
    # the speeds of the straight twin, driven through the U-turn near the top speed: exit 3
    assert main(["plan", str(twin), "-o", str(fast)]) == 0
    assert read_profile(fast).speed_mps[np.abs(read_profile(fast).s_m - 60.0) <= 5.0].min() > 15.0
    capsys.readouterr()
    assert main(["verify", str(route), str(fast)]) == 3
    out, _ = capsys.readouterr()
    assert "breaks the lateral acceleration limit in turns (0.6325 m/s) first in the segment from s = 5" in out
    assert "min_turn_radius_m (3.25 m)" in out
