"""Every way a user can hand the program something wrong fails clearly, and loses nothing.

Issue 5, "Every input path fails clearly, and nothing is lost": for each bad route, vehicle
file, option and profile the command exits with status 2, prints exactly one line on stderr
that names the file (or option, or key) and the problem, shows no traceback and leaves no
output file behind (nor replaces a good earlier one). The Python API raises
:class:`~profileopt.errors.InputError` (a ``ValueError``) with the same message. Also: every
output goes through :mod:`profileopt.io.atomic` (a failed or interrupted write leaves no temporary
file behind), and the same input gives the same output bytes.

Each case runs ``python -m profileopt`` in a subprocess (about 0.6 s each, mostly imports).
"""

from __future__ import annotations

import concurrent.futures
import contextlib
import dataclasses
import importlib
import json
import math
import os
import subprocess
import tomllib
from pathlib import Path

import numpy as np
import pytest

from profileopt.io.profiles import write_profile
from profileopt import cli
from profileopt.cli.messages import flags_for_parameters
from profileopt.io import atomic_path, atomic_write
from profileopt.errors import InfeasibleError, InputError
from profileopt import plan, read_profile
from profileopt.io import read_route
from profileopt.core.vehicle import load_vehicle

from conftest import PROFILEOPT, ROOT

ATV_TOML = ROOT / "models" / "atv.toml"

# --------------------------------------------------------------------------------------
# Inputs


def route_text(length_m: float = 50.0, spacing_m: float = 0.1, speed_limit_mps: float | None = None) -> str:
    """A valid route CSV: gentle 0.01 m sine bumps of 1.3 m wavelength, header ``s,z``."""
    s = np.round(np.arange(0.0, length_m + spacing_m / 2, spacing_m), 6)
    z = 0.01 * np.sin(2 * np.pi * s / 1.3)
    if speed_limit_mps is None:
        return "s,z\n" + "".join(f"{a:.6g},{b:.6g}\n" for a, b in zip(s, z))
    return "s,z,speed_limit\n" + "".join(f"{a:.6g},{b:.6g},{speed_limit_mps:g}\n" for a, b in zip(s, z))


GOOD_ROUTE = route_text()
GOOD_LINES = GOOD_ROUTE.splitlines(keepends=True)  # file line 1 is the header, line k + 2 is s = 0.1 k


def with_line(number: int, text: str, base: str = GOOD_ROUTE) -> str:
    """``base`` with file line ``number`` (1-based) replaced by ``text``."""
    lines = base.splitlines(keepends=True)
    lines[number - 1] = text + "\n"
    return "".join(lines)


def raised_from(number: int, by_m: float) -> str:
    """The good route with every elevation from file line ``number`` on raised by ``by_m``."""
    tail = []
    for line in GOOD_LINES[number - 1:]:
        s, z = line.strip().split(",")
        tail.append(f"{s},{float(z) + by_m:.6g}\n")
    return "".join(GOOD_LINES[:number - 1] + tail)


def rough_route_text() -> str:
    """A +-1.5 m zig-zag: RI = 15 with h = 0.1 m, so e_max = 4.7534 * 15 * 0.1 = 7.1 m (Eq. 8),
    and SBEM:EF's force at rest, k e_max = 900 N/m * 7.1 m = 6.4 kN, already exceeds the atv's
    5 kN: no speed is admissible (NOTES.md, Eq. 11 simplified: F grows with speed from k e)."""
    s = np.round(np.arange(0.0, 50.05, 0.1), 6)
    z = np.where(np.arange(s.size) % 2 == 0, 1.5, -1.5)
    return "s,z\n" + "".join(f"{a:.6g},{b:.6g}\n" for a, b in zip(s, z))


def toml_text(data: dict) -> str:
    def value(v: object) -> str:
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, str):
            return json.dumps(v)
        if isinstance(v, float) and math.isnan(v):
            return "nan"
        if isinstance(v, float) and math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)

    return "".join(f"{k} = {value(v)}\n" for k, v in data.items())


def vehicle_with(**changes: object) -> str:
    """The atv vehicle file with keys changed; a value of None removes the key."""
    data = tomllib.loads(ATV_TOML.read_text(encoding="utf-8"))
    for key, v in changes.items():
        if v is None:
            del data[key]
        else:
            data[key] = v
    return toml_text(data)


GOOD_PROFILE_HEADER = "s_m,speed_mps,accel_mps2,time_s,ri,e_max_m,force_n,force_limit_n"


def profile_text(*rows: str, comment: bool = True) -> str:
    head = "# profileopt profile: vehicle=atv model=sbem_tf\n" if comment else ""
    return head + GOOD_PROFILE_HEADER + "\n" + "".join(r + "\n" for r in rows)


# --------------------------------------------------------------------------------------
# The table: one case per bad input of issue 5.


@dataclasses.dataclass(frozen=True)
class Case:
    """One bad input: the files to create (name, text), the command line, the fragments its
    one-line message must contain (the file, option or key, and the problem), and the
    outputs the command was asked to write (none may exist afterwards)."""

    id: str
    argv: tuple[str, ...]
    fragments: tuple[str, ...]
    files: tuple[tuple[str, str], ...] = ()
    outputs: tuple[str, ...] = ("out.csv",)


def plan_case(id: str, fragments: tuple[str, ...], route: str | None = GOOD_ROUTE, vehicle: str | None = None,
              options: tuple[str, ...] = (), route_arg: str = "route.csv") -> Case:
    """``profileopt plan ROUTE --vehicle V -o out.csv --plot out.png OPTIONS``."""
    files = [] if route is None else [("route.csv", route)]
    vehicle_arg = "atv"
    if vehicle is not None:
        files.append(("vehicle.toml", vehicle))
        vehicle_arg = "vehicle.toml"
    argv = ("plan", route_arg, "--vehicle", vehicle_arg, "-o", "out.csv", "--plot", "out.png", *options)
    return Case(id, argv, fragments, tuple(files), ("out.csv", "out.png"))


ROUTE_CASES = [
    plan_case("route-empty", ("route.csv", "empty", "header line such as 's,z'"), route=""),
    plan_case("route-no-header", ("route.csv", "line 1", "not a header", "add a header"),
              route="".join(GOOD_LINES[1:])),
    plan_case("route-unknown-columns", ("route.csv", "line 1", "'dist,elev'", "rename the columns"),
              route="dist,elev\n" + "".join(GOOD_LINES[1:])),
    plan_case("route-missing-z-column", ("route.csv", "line 1", "lacks the columns", "'s,z'"),
              route="s,speed_limit\n0,1\n0.1,1\n0.2,1\n"),
    plan_case("route-missing-y-column", ("route.csv", "line 1", "lacks the columns", "'x,y,z'"),
              route="x,z\n0,0\n0.1,0\n0.2,0\n"),
    plan_case("route-duplicate-column", ("route.csv", "line 1", "'z' appears twice"),
              route="s,z,z\n0,0,0\n0.1,0,0\n0.2,0,0\n"),
    plan_case("route-non-numeric-cell", ("route.csv", "line 5", "'abc' is not a number"),
              route=with_line(5, "0.3,abc")),
    plan_case("route-missing-cell", ("route.csv", "line 7", "1 cells but the header has 2"),
              route=with_line(7, "0.5")),
    # one row with a cell too many next to one with a cell too few: the total count matches,
    # but the table must not be shifted silently
    plan_case("route-rows-misaligned", ("route.csv", "line 7", "3 cells but the header has 2"),
              route=with_line(8, "0.6", with_line(7, "0.5,0,0.01"))),
    plan_case("route-nan", ("route.csv", "line 6", "z = nan is not a finite number"),
              route=with_line(6, "0.4,nan")),
    plan_case("route-inf", ("route.csv", "line 9", "z = inf is not a finite number"),
              route=with_line(9, "0.7,inf")),
    plan_case("route-s-decreasing", ("route.csv", "line 12", "decreases", "sort the rows"),
              route=with_line(12, "0.85,0")),
    plan_case("route-s-duplicated", ("route.csv", "line 12", "repeats", "drop duplicates"),
              route=with_line(12, "0.9,0")),
    plan_case("route-xy-repeated-point", ("route.csv", "line 4", "repeats the previous x,y"),
              route="x,y,z\n0,0,0\n1,1,0\n1,1,0\n2,2,0\n"),
    plan_case("route-single-row", ("route.csv", "1 data row", "at least 2"), route="s,z\n0,0\n"),
    plan_case("route-too-sparse-for-windows",
              ("route.csv", "roughness window from 0 to 5 m", "holds 6 samples", "at least 8", "--roughness-window"),
              route=route_text(spacing_m=1.0)),
    plan_case("route-elevation-step-1km",
              ("route.csv", "line 101", "z jumps by 999.995 m", "steps above 100 m", "units"),
              route=raised_from(101, 1000.0)),
    plan_case("route-elevation-absurd", ("route.csv", "line 4", "z = 100000 m is beyond"),
              route=with_line(4, "0.2,1e5")),
    plan_case("route-speed-limit-zero", ("route.csv", "line 3", "speed_limit = 0 m/s must be > 0"),
              route=with_line(3, "0.1,0,0", route_text(speed_limit_mps=5.0))),
    plan_case("route-speed-limit-negative", ("route.csv", "line 8", "speed_limit = -2 m/s must be > 0"),
              route=with_line(8, "0.6,0,-2", route_text(speed_limit_mps=5.0))),
    plan_case("route-not-found", ("missing.csv", "not found", "check the path"), route_arg="missing.csv"),
    plan_case("route-is-a-folder", ("routes", "folder"), route_arg="routes",
              options=()),  # the folder is made by the test (see FOLDERS)
]

VEHICLE_CASES = [
    plan_case("vehicle-missing-key", ("vehicle.toml", "missing key 'damping_ratio'", "add"),
              vehicle=vehicle_with(damping_ratio=None)),
    plan_case("vehicle-unknown-key", ("vehicle.toml", "unknown key 'mass_kgs'", "has the keys", "optionally"),
              vehicle=vehicle_with(mass_kgs=100.0)),
    plan_case("vehicle-power-without-mass", ("vehicle.toml", "'max_power_w' needs key 'mass_kg'", "kg"),
              vehicle=vehicle_with(mass_kg=None)),
    plan_case("vehicle-track-without-cg", ("vehicle.toml", "'track_width_m' needs key 'cg_height_m'", "m"),
              vehicle=vehicle_with(cg_height_m=None)),
    plan_case("vehicle-mass-below-quarter", ("vehicle.toml", "'mass_kg' = 50 kg", "whole vehicle"),
              vehicle=vehicle_with(mass_kg=50.0)),
    plan_case("vehicle-friction-out-of-range", ("vehicle.toml", "'friction_coefficient' = 30", "outside"),
              vehicle=vehicle_with(friction_coefficient=30.0)),
    plan_case("vehicle-wrong-type-string", ("vehicle.toml", "'quarter_mass_kg'", "'heavy' is not a number", "kg"),
              vehicle=vehicle_with(quarter_mass_kg="heavy")),
    plan_case("vehicle-wrong-type-bool", ("vehicle.toml", "'max_speed_mps'", "is not a number", "m/s"),
              vehicle=vehicle_with(max_speed_mps=True)),
    plan_case("vehicle-zero", ("vehicle.toml", "'wheel_radius_m'", "> 0"), vehicle=vehicle_with(wheel_radius_m=0.0)),
    plan_case("vehicle-negative", ("vehicle.toml", "'max_decel_mps2'", "-4.0", "> 0"),
              vehicle=vehicle_with(max_decel_mps2=-4.0)),
    plan_case("vehicle-inf", ("vehicle.toml", "'max_speed_mps'", "not finite"),
              vehicle=vehicle_with(max_speed_mps=math.inf)),
    plan_case("vehicle-nan", ("vehicle.toml", "'ground_clearance_m'", "not finite"),
              vehicle=vehicle_with(ground_clearance_m=math.nan)),
    plan_case("vehicle-jerk-inf-in-file", ("vehicle.toml", "'max_jerk_mps3'", "not finite"),
              vehicle=vehicle_with(max_jerk_mps3=math.inf)),
    plan_case("vehicle-damping-zero", ("vehicle.toml", "'damping_ratio'", "> 0"),
              vehicle=vehicle_with(damping_ratio=0.0)),
    plan_case("vehicle-confidence-half", ("vehicle.toml", "'confidence'", "outside (0.5, 1)"),
              vehicle=vehicle_with(confidence=0.5)),
    plan_case("vehicle-confidence-one", ("vehicle.toml", "'confidence'", "outside (0.5, 1)"),
              vehicle=vehicle_with(confidence=1.0)),
    plan_case("vehicle-bad-toml", ("vehicle.toml", "not valid TOML", "line 2"),
              vehicle="quarter_mass_kg = 100.0\nground_clearance_m = = 0.1\n"),
    plan_case("vehicle-not-found", ("nope.toml", "not found"), options=("--vehicle", "nope.toml")),
    plan_case("vehicle-unknown-name", ("vehicle 'tank'", "atv-resonant"), options=("--vehicle", "tank")),
]

SHORT_ROUTE = route_text(length_m=10.0)
LIMITED_ROUTE = route_text(speed_limit_mps=5.0)

OPTION_CASES = [
    plan_case("segment-length-zero", ("--segment-length", "> 0"), options=("--segment-length", "0")),
    plan_case("segment-length-negative", ("--segment-length", "-5", "> 0"), options=("--segment-length", "-5")),
    plan_case("segment-length-longer-than-route",
              ("--segment-length = 60 m", "longer than the route", "route.csv", "50 m", "shorter"),
              options=("--segment-length", "60")),
    plan_case("segment-length-absurdly-small", ("--segment-length = 1e-09 m", "more segments", "at least"),
              options=("--segment-length", "1e-9")),
    plan_case("segment-length-not-a-number", ("--segment-length", "'abc' is not a number"),
              options=("--segment-length", "abc")),
    # a value given to a switch: argparse says "ignored explicit argument", which reads as if
    # the run went on; the message says the switch takes none and what to write
    plan_case("refine-with-a-value", ("--refine/--no-refine takes no value", "'yes' given",
                                      "write --refine or --no-refine"), options=("--refine=yes",)),
    plan_case("v0-negative", ("--v0", ">= 0"), options=("--v0", "-1")),
    plan_case("vend-negative", ("--vend", ">= 0"), options=("--vend", "-2")),
    plan_case("v0-above-max-speed", ("--v0 = 25 m/s", "max_speed_mps = 20"), options=("--v0", "25")),
    plan_case("vend-above-max-speed", ("--vend = 21 m/s", "max_speed_mps = 20"), options=("--vend", "21")),
    plan_case("v0-above-speed-limit", ("--v0 = 8 m/s", "allowable speed 5 m/s", "start slower"),
              route=LIMITED_ROUTE, options=("--v0", "8")),
    plan_case("vend-above-speed-limit", ("--vend = 8 m/s", "allowable speed 5 m/s", "end slower"),
              route=LIMITED_ROUTE, options=("--vend", "8")),
    # from 20 m/s, braking at 4 m/s^2 takes 20^2 / (2 * 4) = 50 m; the route is 10 m long
    plan_case("v0-cannot-stop-in-time", ("route.csv", "--v0 = 20 m/s", "cannot brake", "max_decel_mps2"),
              route=SHORT_ROUTE, options=("--v0", "20")),
    # from rest at 2.5 m/s^2 over 10 m: sqrt(2 * 2.5 * 10) = 7.07 m/s at most
    plan_case("vend-unreachable", ("route.csv", "--vend = 20 m/s", "only 7.07 m/s", "lower --vend"),
              route=SHORT_ROUTE, options=("--vend", "20")),
    plan_case("impassable-segment", ("route.csv", "segment 0 (0 to 5 m)", "at every speed"),
              route=rough_route_text(), options=("--model", "sbem_ef")),
    plan_case("smoothing-negative", ("--smoothing", ">= 0"), options=("--smoothing", "-1")),
    plan_case("max-jerk-zero", ("--max-jerk", "> 0"), options=("--max-jerk", "0")),
    plan_case("model-unknown", ("--model", "'tf'"), options=("--model", "tf")),
    plan_case("output-is-a-folder", ("routes", "folder"), options=("-o", "routes")),
    plan_case("output-folder-missing", ("nowhere", "does not exist"), options=("-o", "nowhere/out.csv")),
]

BAD_PROFILES = {
    "profile-empty": ("", ("profile.csv", "empty", "profileopt plan -o")),
    "profile-wrong-header": ("# c\ns,v\n0,1\n", ("profile.csv", "line 2", "header must be")),
    "profile-non-numeric": (profile_text("0,1,0,0,0,0,0,5000", "5,x,0,1,0,0,0,5000"),
                            ("profile.csv", "line 4", "speed_mps = 'x' is not a number")),
    "profile-short-row": (profile_text("0,1,0,0,0,0,0,5000", "5,1,0,1"), ("profile.csv", "line 4", "4 cells but the header has 8")),
    "profile-nan": (profile_text("0,1,0,0,0,0,0,5000", "5,nan,0,1,0,0,0,5000"),
                    ("profile.csv", "line 4", "speed_mps = nan is not a finite number")),
    "profile-one-row": (profile_text("0,1,0,0,0,0,0,5000"), ("profile.csv", "1 data row", "at least 2")),
    "profile-s-not-increasing": (profile_text("0,1,0,0,0,0,0,5000", "5,1,0,5,0,0,0,5000", "5,1,0,5,0,0,0,5000"),
                                 ("profile.csv", "line 5", "s_m = 5 m does not increase", "sort the rows")),
    "profile-negative-speed": (profile_text("0,1,0,0,0,0,0,5000", "5,-1,0,5,0,0,0,5000"),
                               ("profile.csv", "line 4", "speed_mps = -1 m/s is negative")),
    "profile-unknown-model": ("# profileopt profile: model=magic\n" + GOOD_PROFILE_HEADER + "\n0,1,0,0,0,0,0,5000\n"
                              "5,1,0,5,0,0,0,5000\n", ("profile.csv", "line 1", "model=magic")),
    "profile-off-the-route": (profile_text("0,1,0,0,0,0,0,5000", "900,1,0,900,0,0,0,5000"),
                              ("route.csv", "the profile covers")),
}

VERIFY_CASES = [
    Case(id, ("verify", "route.csv", "profile.csv", "--vehicle", "atv", "-o", "v.csv", "--plot", "v.png"),
         fragments, (("route.csv", GOOD_ROUTE), ("profile.csv", text)), ("v.csv", "v.png"))
    for id, (text, fragments) in BAD_PROFILES.items()
]

OTHER_CASES = [
    Case("figures-out-is-a-file", ("figures", "--out", "taken.txt"), ("--out taken.txt", "not a folder"),
         (("taken.txt", "precious\n"),), outputs=()),
    Case("export-c-bad-vehicle", ("export-c", "--vehicle", "vehicle.toml", "-o", "cout"),
         ("vehicle.toml", "'damping_ratio'", "> 0"), (("vehicle.toml", vehicle_with(damping_ratio=0.0)),),
         outputs=("cout",)),
]

CASES = ROUTE_CASES + VEHICLE_CASES + OPTION_CASES + VERIFY_CASES + OTHER_CASES
FOLDERS = ("routes",)  # made in every case's folder: a path that is a folder, not a file


def run_cli(cwd: Path, *argv: str) -> subprocess.CompletedProcess:
    env = dict(os.environ, MPLBACKEND="Agg")
    return subprocess.run([*PROFILEOPT, *argv], cwd=cwd, capture_output=True,
                          text=True, timeout=120, env=env)


def setup(case: Case, folder: Path) -> None:
    for name, text in case.files:
        (folder / name).write_text(text, encoding="utf-8")
    for name in FOLDERS:
        (folder / name).mkdir()


def assert_one_clean_line(done: subprocess.CompletedProcess, command: str, fragments: tuple[str, ...]) -> str:
    """Exit 2, exactly one line on stderr holding every fragment, no traceback; the message."""
    assert "Traceback" not in done.stderr + done.stdout
    assert done.returncode == 2, done.stderr
    lines = done.stderr.splitlines()
    assert len(lines) == 1 and done.stderr.endswith("\n"), done.stderr
    prefix = f"profileopt {command}: error: "
    assert lines[0].startswith(prefix), lines[0]
    for fragment in fragments:
        assert fragment in lines[0], f"{fragment!r} missing from: {lines[0]}"
    return lines[0][len(prefix):]


@dataclasses.dataclass(frozen=True)
class Outcome:
    folder: Path
    before: list[str]  # the folder's listing before the run
    done: subprocess.CompletedProcess


def _run_case(case: Case, folder: Path) -> Outcome:
    folder.mkdir(parents=True, exist_ok=True)
    setup(case, folder)
    before = sorted(p.name for p in folder.iterdir())
    return Outcome(folder, before, run_cli(folder, *case.argv))


#: The cases the Python API is also tried on (test_python_api_raises_input_error_with_the_same_message,
#: below). Their command-line runs are quick: ``-m "not slow"`` keeps them, the rest are slow.
API_CASES = ["route-non-numeric-cell", "route-s-duplicated", "route-elevation-step-1km", "vehicle-unknown-key",
             "vehicle-confidence-one", "v0-cannot-stop-in-time", "segment-length-longer-than-route",
             "impassable-segment", "profile-non-numeric"]


@pytest.fixture(scope="module")
def outcomes(request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory) -> dict[str, Outcome]:
    """The selected cases, each run once in its own folder, two subprocesses at a time (the
    runs are independent; this halves the wall time of the ~70 process starts)."""
    wanted = set()
    for item in request.session.items:
        params = getattr(item, "callspec", None) and item.callspec.params
        if params and item.module is request.module:
            wanted.add(params["case"].id if "case" in params else params.get("case_id"))
    selected = [case for case in CASES if case.id in wanted]
    root = tmp_path_factory.mktemp("cases")
    with concurrent.futures.ThreadPoolExecutor(max_workers=2) as pool:
        futures = {case.id: pool.submit(_run_case, case, root / case.id) for case in selected}
        return {key: future.result() for key, future in futures.items()}


@pytest.mark.parametrize("case", [pytest.param(c, id=c.id, marks=() if c.id in API_CASES else pytest.mark.slow(seconds=40))
                                  for c in CASES])  # the outcomes' fixture: about 40 s on one core, started early
def test_bad_input_is_one_line_exit_2_and_writes_nothing(case: Case, outcomes: dict[str, Outcome]) -> None:
    outcome = outcomes[case.id]
    assert_one_clean_line(outcome.done, case.argv[0], case.fragments)
    for name in case.outputs:
        assert not (outcome.folder / name).exists(), f"{name} was written by a failed run"
    assert sorted(p.name for p in outcome.folder.iterdir()) == outcome.before  # no stray temporary files


@pytest.mark.slow
def test_a_failed_run_keeps_a_good_earlier_output(tmp_path: Path) -> None:
    (tmp_path / "route.csv").write_text(SHORT_ROUTE)
    good = run_cli(tmp_path, "plan", "route.csv", "-o", "out.csv")
    assert good.returncode == 0, good.stderr
    earlier = (tmp_path / "out.csv").read_bytes()
    assert earlier.count(b"\n") > 2
    # the same output asked for by a run that fails (cannot stop from 20 m/s in 10 m)
    done = run_cli(tmp_path, "plan", "route.csv", "-o", "out.csv", "--v0", "20")
    assert_one_clean_line(done, "plan", ("--v0 = 20",))
    assert (tmp_path / "out.csv").read_bytes() == earlier
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.csv", "route.csv"]


def test_a_bad_plot_path_writes_no_csv(tmp_path: Path) -> None:
    (tmp_path / "route.csv").write_text(SHORT_ROUTE)
    done = run_cli(tmp_path, "plan", "route.csv", "-o", "out.csv", "--plot", "nowhere/p.png")
    assert_one_clean_line(done, "plan", ("nowhere", "does not exist"))
    assert not (tmp_path / "out.csv").exists()


# --------------------------------------------------------------------------------------
# The Python API raises InputError (a ValueError) with the command line's message (the cases
# of API_CASES, above).


def options_of(argv: list[str]) -> dict[str, str]:
    return {flag: value for flag, value in zip(argv, argv[1:]) if flag.startswith("-")}


def _api(case: Case) -> None:
    """What the command does, through the Python API."""
    argv = list(case.argv)
    if argv[0] == "verify":
        read_profile(argv[2])
        return
    vehicle = load_vehicle(options_of(argv)["--vehicle"])
    route = read_route(argv[1])
    options = options_of(argv)
    plan(route, vehicle, segment_length_m=float(options.get("--segment-length", 5.0)),
         model=options.get("--model", "sbem_tf"), v0_mps=float(options.get("--v0", 0.0)),
         vend_mps=float(options.get("--vend", 0.0)))


@pytest.mark.parametrize("case_id", API_CASES)
def test_python_api_raises_input_error_with_the_same_message(case_id: str, tmp_path: Path,
                                                             monkeypatch: pytest.MonkeyPatch,
                                                             outcomes: dict[str, Outcome]) -> None:
    case = next(c for c in CASES if c.id == case_id)
    setup(case, tmp_path)
    monkeypatch.chdir(tmp_path)  # relative names, as on the command line
    with pytest.raises(InputError) as raised:
        _api(case)
    assert isinstance(raised.value, ValueError)
    if case_id in ("v0-cannot-stop-in-time", "impassable-segment"):
        assert isinstance(raised.value, InfeasibleError)
    message = str(raised.value)
    assert "\n" not in message
    # the library names its parameters (segment_length_m), the command its flags (--segment-length)
    expected = flags_for_parameters(message)
    assert assert_one_clean_line(outcomes[case_id].done, case.argv[0], case.fragments) == expected


# --------------------------------------------------------------------------------------
# Internal errors: one line, exit 1 (a traceback only with --debug).


def test_internal_error_is_one_line_and_exit_1(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                               capsys: pytest.CaptureFixture) -> None:
    (tmp_path / "route.csv").write_text(SHORT_ROUTE)
    module = importlib.import_module("profileopt.planning")  # the plan command imports plan from it when run

    def broken(*args: object, **kwargs: object) -> None:
        raise ZeroDivisionError("a bug")

    monkeypatch.setattr(module, "plan", broken)
    out = tmp_path / "out.csv"
    assert cli.main(["plan", str(tmp_path / "route.csv"), "-o", str(out)]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "internal error: ZeroDivisionError: a bug" in err and "Traceback" not in err
    assert not out.exists()
    assert cli.main(["--debug", "plan", str(tmp_path / "route.csv"), "-o", str(out)]) == 1
    assert "Traceback" in capsys.readouterr().err


# --------------------------------------------------------------------------------------
# Atomic outputs: every writer goes through profileopt.io.atomic, and a failure mid-write leaves
# neither a partial file nor a temporary one.


WRITERS = ["plan -o", "plan --plot", "verify -o", "verify --plot", "figures", "export-c"]


def _write(writer: str, folder: Path) -> None:
    """What each command does to write its outputs into ``folder``."""
    from profileopt.mpc.codegen import export_c
    from profileopt.viz.figures import figure_1, write_figure
    from profileopt.viz.plots import plot_profile
    from profileopt import plot_verification, verify

    vehicle = load_vehicle("atv")
    route = read_route_text(folder, SHORT_ROUTE)
    profile = plan(route, vehicle)
    if writer == "plan -o":
        write_profile(profile, folder / "out.csv")
    elif writer == "plan --plot":
        plot_profile(profile, folder / "out.png")
    elif writer == "verify -o":
        verify(route, profile, vehicle).to_csv(folder / "v.csv")
    elif writer == "verify --plot":
        plot_verification(verify(route, profile, vehicle), folder / "v.png")
    elif writer == "figures":
        write_figure(figure_1(), folder)
    elif writer == "export-c":
        export_c(vehicle, folder)
    else:  # pragma: no cover
        raise AssertionError(writer)


@pytest.mark.slow
@pytest.mark.parametrize("writer", WRITERS)
def test_every_output_goes_through_a_temporary_file(writer: str, tmp_path: Path,
                                                    monkeypatch: pytest.MonkeyPatch) -> None:
    """Interrupt every writer at its last step (the rename of the finished temporary file):
    nothing may appear. A writer that wrote its file directly, not through profileopt.io.atomic,
    would leave it behind; one that did not clean up would leave the temporary file."""
    _write(writer, tmp_path)  # it works ...
    written = {p.name for p in tmp_path.iterdir()} - {"route.csv"}
    assert written
    for name in written:
        (tmp_path / name).unlink()

    def interrupted(src: object, dst: object, **dir_fds: int) -> None:  # os.replace (src_dir_fd=, dst_dir_fd=)
        raise KeyboardInterrupt

    monkeypatch.setattr(os, "replace", interrupted)
    with pytest.raises(KeyboardInterrupt):
        _write(writer, tmp_path)  # ... and interrupted, leaves nothing
    assert sorted(p.name for p in tmp_path.iterdir()) == ["route.csv"]


@pytest.mark.parametrize("error", [RuntimeError("disk full"), KeyboardInterrupt()], ids=["error", "interrupt"])
def test_failed_or_interrupted_write_leaves_nothing_behind(tmp_path: Path, error: BaseException) -> None:
    target = tmp_path / "out.csv"
    target.write_text("good earlier output\n")
    with pytest.raises(type(error)):
        with atomic_write(target) as handle:
            handle.write("half a line")
            handle.flush()
            raise error
    assert target.read_text() == "good earlier output\n"
    assert [p.name for p in tmp_path.iterdir()] == ["out.csv"]
    with pytest.raises(type(error)):
        with atomic_path(tmp_path / "new.png") as tmp:
            tmp.write_bytes(b"\x89PNG partial")
            raise error
    assert [p.name for p in tmp_path.iterdir()] == ["out.csv"]


def test_profile_to_csv_failing_mid_write_leaves_no_file(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from profileopt.io import profiles

    profile = plan(read_route_text(tmp_path, SHORT_ROUTE), load_vehicle("atv"))
    calls = []

    class FillsUp:
        """A file whose disk fills up while the table is written (the third write)."""

        def __init__(self, handle) -> None:  # noqa: ANN001
            self.handle = handle

        def write(self, text: str) -> int:
            calls.append(text)
            if len(calls) == 3:
                self.handle.write(text[: len(text) // 2])  # a partial table ...
                raise OSError("no space left on device")  # ... then the disk is full
            return self.handle.write(text)

    real = profiles.atomic_write

    @contextlib.contextmanager
    def filling_atomic_write(path):  # noqa: ANN001, ANN202
        with real(path) as handle:
            yield FillsUp(handle)

    monkeypatch.setattr(profiles, "atomic_write", filling_atomic_write)
    with pytest.raises(OSError):
        write_profile(profile, tmp_path / "out.csv")
    assert len(calls) == 3 and sorted(p.name for p in tmp_path.iterdir()) == ["route.csv"]


def read_route_text(folder: Path, text: str):  # noqa: ANN201
    (folder / "route.csv").write_text(text)
    return read_route(folder / "route.csv")


# --------------------------------------------------------------------------------------
# Determinism: the same input and options give the same output bytes.


@pytest.mark.slow
def test_plan_twice_gives_the_same_bytes(tmp_path: Path) -> None:
    (tmp_path / "route.csv").write_text(route_text(length_m=60.0))
    runs = []
    for name in ("a", "b"):
        csv_done = run_cli(tmp_path, "plan", "route.csv", "--vehicle", "atv-resonant", "-o", f"{name}.csv")
        json_done = run_cli(tmp_path, "plan", "route.csv", "--vehicle", "atv-resonant", "--json")
        assert csv_done.returncode == 0 and json_done.returncode == 0, csv_done.stderr + json_done.stderr
        summary = json.loads(json_done.stdout)
        del summary["solver"]["time_s"]  # wall-clock time, the one figure that may differ
        # the human summary, with the wall-clock time taken out
        text = [ln.split(", planned in")[0] for ln in csv_done.stdout.splitlines()]
        runs.append(((tmp_path / f"{name}.csv").read_bytes(), summary, [t.replace(f"{name}.csv", "X") for t in text]))
    assert runs[0][0] == runs[1][0]
    assert runs[0][1] == runs[1][1]
    assert runs[0][2] == runs[1][2]


@pytest.mark.slow
def test_a_reader_that_stops_early_ends_the_command_with_the_pipes_status() -> None:
    # `profileopt plan ... -o - | head -2`: the reader closes the pipe after a few bytes; the
    # command stops quietly with 128 + SIGPIPE (13) = 141, a shell's status for a program its
    # pipe ended, not 1 (an internal error) and not a traceback (the profile, about 300 kB, is
    # larger than a pipe's buffer, so writing it meets the closed pipe)
    import sys

    process = subprocess.Popen([sys.executable, "-m", "profileopt", "plan", str(ROOT / "examples" / "routes" / "trail.csv"),
                                "-o", "-"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=ROOT)
    assert process.stdout.read(100)  # the profile's header has started
    process.stdout.close()
    stderr = process.stderr.read().decode()
    assert process.wait(timeout=300) == 141
    assert "Traceback" not in stderr and "internal error" not in stderr
