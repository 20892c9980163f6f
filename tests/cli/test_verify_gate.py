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

import math
import os
import re
import subprocess
import sys
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
    # 1e-8: the profile's force_n carries 9 significant digits (issue 30), the table 10
    assert np.allclose(predicted, table(planned["krc"])["force_n"][:-1], rtol=1e-8)
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


# issue 30: verify must not trust or clobber what the profile names

def bumpy_route(path: Path) -> Path:
    """A 60 m s,z route with bumps 5 cm apart: planned in about a second."""
    s = np.arange(0.0, 60.001, 0.05)
    np.savetxt(path, np.column_stack([s, 0.01 * np.sin(2.0 * s) + 0.004 * np.sin(7.0 * s)]), delimiter=",",
               header="s,z", comments="", fmt="%.6f")
    return path


@pytest.fixture
def own_vehicle(tmp_path: Path, monkeypatch) -> dict[str, Path]:
    """A route, a vehicle file 'my veh.toml' (the atv's bytes) in folder 'a plans', and a
    profile planned there with --vehicle 'my veh.toml' (a relative name with a space)."""
    from profileopt import load_vehicle
    from profileopt.cli import main

    folder = tmp_path / "a plans"
    folder.mkdir()
    vehicle = folder / "my veh.toml"
    vehicle.write_bytes(Path(load_vehicle("atv").name).read_bytes())
    route = bumpy_route(tmp_path / "route.csv")
    monkeypatch.chdir(folder)
    assert main(["plan", str(route), "--vehicle", "my veh.toml", "-o", "p.csv"]) == 0
    return {"folder": folder, "vehicle": vehicle, "route": route, "profile": folder / "p.csv"}


def one_line_error(err: str) -> str:
    assert err.count("\n") == 1 and "Traceback" not in err, err
    return err


def test_an_output_naming_the_vehicle_the_profile_records_is_refused(own_vehicle, capsys) -> None:
    # Before: 'verify ROUTE PROFILE --plot veh.toml' replaced the vehicle file with a PNG (exit 0)
    from profileopt.cli import main

    vehicle, before = own_vehicle["vehicle"], own_vehicle["vehicle"].read_bytes()
    capsys.readouterr()
    for option in ("--plot", "-o"):
        for name in ("my veh.toml", str(vehicle), "../a plans/./my veh.toml"):
            assert main(["verify", str(own_vehicle["route"]), "p.csv", option, name]) == 2
            _, err = capsys.readouterr()
            assert "is the input" in one_line_error(err) and "my veh.toml" in err
    assert vehicle.read_bytes() == before


def test_the_vehicle_is_found_from_any_folder_and_a_changed_one_is_refused(own_vehicle, monkeypatch,
                                                                          capsys) -> None:
    # Before: the path was recorded relative to the folder plan ran in, with '_' for ' ':
    # 'my_veh.toml' from wherever verify ran, or nothing
    from profileopt.cli import main

    route, profile, vehicle = (str(own_vehicle[k]) for k in ("route", "profile", "vehicle"))
    elsewhere = own_vehicle["folder"].parent / "elsewhere"
    elsewhere.mkdir()
    (elsewhere / "my_veh.toml").write_text("not a vehicle")
    monkeypatch.chdir(elsewhere)
    capsys.readouterr()
    assert main(["verify", route, profile]) == 0
    out, err = capsys.readouterr()
    assert f"with vehicle {vehicle}," in out and err == ""
    # the file changed since the plan: refused, naming the file and what to do
    with open(vehicle, "a") as handle:
        handle.write("# tuned\n")
    assert main(["verify", route, profile]) == 2
    err = one_line_error(capsys.readouterr().err)
    assert vehicle in err and "not the one the profile was planned with" in err and "plan again" in err
    # ... unless the user names it: then it is used, with a note
    assert main(["verify", route, profile, "--vehicle", vehicle]) == 0
    assert "is not the vehicle the profile was planned with" in capsys.readouterr().out
    # an old profile (no hash) is verified with the file it names, with a note
    lines = Path(profile).read_text().splitlines()
    old = elsewhere / "old.csv"
    old.write_text("\n".join([re.sub(r" vehicle_sha256=\w+", "", lines[0]), *lines[1:]]) + "\n")
    assert main(["verify", route, str(old)]) == 0
    out = capsys.readouterr().out
    assert "records no SHA-256 of its vehicle" in out
    assert "relative path" not in out  # before: said of the absolute path recorded
    # a vehicle file that is gone: one line, what to do
    os.remove(vehicle)
    assert main(["verify", route, profile]) == 2
    assert "which is not there; pass --vehicle" in one_line_error(capsys.readouterr().err)


def test_verify_vehicle_is_matched_by_content_not_by_name(own_vehicle, capsys) -> None:
    # Before: --vehicle was matched by its file name: a byte-identical copy under another name
    # was refused, another file of the same name accepted; the refusal offered --vehicle FILE
    from profileopt.cli import main

    route, profile, vehicle = (str(own_vehicle[k]) for k in ("route", "profile", "vehicle"))
    folder = own_vehicle["folder"]
    copy = folder / "copy.toml"
    copy.write_bytes(Path(vehicle).read_bytes())
    other = folder / "other"
    other.mkdir()
    tuned = other / "my veh.toml"  # the same name, other content
    tuned.write_text(Path(vehicle).read_text().replace("mass_kg = 450.0", "mass_kg = 400.0"))
    assert tuned.read_bytes() != Path(vehicle).read_bytes()
    capsys.readouterr()
    # the same bytes under another name (or the bundled atv, whose bytes these are): that vehicle, no note
    for same in (str(copy), "atv"):
        assert main(["verify", route, profile, "--vehicle", same]) == 0
        out, err = capsys.readouterr()
        assert f"with vehicle {same}," in out and "note: --vehicle" not in out and err == ""
    # other bytes, under the same name or another: used as asked, with a note saying it is not that vehicle
    for different in (str(tuned), "atv-resonant"):
        status = main(["verify", route, profile, "--vehicle", different])
        out, err = capsys.readouterr()
        assert status in (0, 3, 4) and err == "", err
        assert f"with vehicle {different}," in out
        assert (f"note: --vehicle {different} is not the vehicle the profile was planned with ({vehicle}; its "
                "SHA-256 differs") in out
    # without --vehicle, the recorded file changed since the plan is refused, and the way the
    # refusal offers works
    Path(vehicle).write_bytes(tuned.read_bytes())
    assert main(["verify", route, profile]) == 2
    err = one_line_error(capsys.readouterr().err)
    assert "pass --vehicle FILE to verify against that file as it is now" in err
    assert main(["verify", route, profile, "--vehicle", vehicle]) == 0
    assert "is not the vehicle the profile was planned with" in capsys.readouterr().out


def test_verify_judges_the_jerk_by_the_vehicle_not_the_settings_line(tmp_path, capsys) -> None:
    # Before: a plan made with --max-jerk inf --smoothing 0 (jerk far above the vehicle's
    # 5 m/s^3) passed, "keeps every limit of the vehicle (... jerk ...)"
    from profileopt.cli import main

    route, free = bumpy_route(tmp_path / "route.csv"), tmp_path / "free.csv"
    assert main(["plan", str(route), "--max-jerk", "inf", "--smoothing", "0", "-o", str(free)]) == 0
    capsys.readouterr()
    assert main(["verify", str(route), str(free)]) == 3
    out = capsys.readouterr().out
    verdict = verdict_line(out)
    assert "breaks the vehicle's limits (jerk" in verdict and "jerk (the vehicle's 5 m/s^3)" in verdict
    assert "breaks the vehicle's jerk limit (5 m/s^3)" in out
    assert "note: the profile was planned with --max-jerk inf (its settings line); verified against the " \
           "vehicle's 5 m/s^3" in out
    # the user's own bound: not checked, and the verdict says so
    assert main(["verify", str(route), str(free), "--max-jerk", "inf"]) == 0
    verdict = verdict_line(capsys.readouterr().out)
    assert "not checked: jerk (--max-jerk inf)" in verdict and "jerk (" not in verdict.split("not checked")[0]
    # a second settings line is refused, naming the file and the line
    lines = free.read_text().splitlines()
    twice = tmp_path / "twice.csv"
    twice.write_text("\n".join([lines[0], lines[0], *lines[1:]]) + "\n")
    assert main(["verify", str(route), str(twice)]) == 2
    assert "twice.csv: line 2: a second settings line" in one_line_error(capsys.readouterr().err)
    # bounds that are not numbers > 0
    for option in (["--max-jerk", "0"], ["--path-tolerance", "inf"], ["--roughness-window", "-5"]):
        assert main(["verify", str(route), str(free), *option]) == 2
        assert f"{option[0]} " in one_line_error(capsys.readouterr().err)


def test_a_route_too_large_for_the_memory_allowed_is_refused_before_any_work(tmp_path, capsys) -> None:
    # issue 30 item 12: 2.9 GB for a 40 MB route. The estimate, derived here from its
    # documented parts: 160 MB + 1.4 kB x 1201 samples + 0.42 kB x steps
    from profileopt import load_vehicle
    from profileopt.cli import main
    from profileopt.cli.verify import MAX_MEMORY_GB
    from profileopt.io import read_profile, read_route
    from profileopt.physics.simulate import choose_time_step_s
    from profileopt.verification.verify import MAX_VERIFY_PEAK_BYTES, estimated_peak_bytes

    from profileopt.verification.verify import VERIFY_BASE_BYTES, VERIFY_BYTES_PER_SAMPLE, VERIFY_BYTES_PER_STEP

    assert MAX_MEMORY_GB * 1e9 == MAX_VERIFY_PEAK_BYTES
    # --help (which imports no numerical package) states the same numbers
    help_text = " ".join(subprocess.run([sys.executable, "-m", "profileopt", "verify", "--help"], capture_output=True,
                                        text=True, env=dict(os.environ, **WIDE_TERMINAL)).stdout.split())
    assert (f"about {VERIFY_BYTES_PER_SAMPLE / 1e3:g} kB per route sample and {VERIFY_BYTES_PER_STEP / 1e3:g} kB per "
            f"time step of the simulation, on top of {VERIFY_BASE_BYTES / 1e9:g} GB") in help_text
    assert f"default: {MAX_MEMORY_GB:g}," in help_text
    route_file, profile_file = bumpy_route(tmp_path / "route.csv"), tmp_path / "p.csv"
    assert main(["plan", str(route_file), "-o", str(profile_file)]) == 0
    route, profile, atv = read_route(route_file), read_profile(profile_file), load_vehicle("atv")
    steps = math.ceil(profile.travel_time_s / choose_time_step_s(atv.natural_frequency_radps))
    peak, found = estimated_peak_bytes(route, profile, atv)
    assert found == steps and peak == pytest.approx(160e6 + 1400 * 1201 + 420 * steps)
    capsys.readouterr()
    out = tmp_path / "v.csv"
    assert main(["verify", str(route_file), str(profile_file), "--max-memory", "0.1", "-o", str(out)]) == 2
    err = one_line_error(capsys.readouterr().err)
    assert "needs about 0.16 GB of memory (1,201 route samples" in err and "--max-memory" in err
    assert not out.exists()
