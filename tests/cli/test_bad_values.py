"""Values a user may give that used to end in exit 1 or a message naming the wrong cause (issue 13).

Each case: one line on stderr that names the file or option and the real cause, exit 2, no
traceback, nothing written. Plus the library-level behaviour behind them: boundary speeds a
rounding error outside a band are planned from the band's edge, with a note.
"""

from __future__ import annotations

import math
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest

from profileopt.io.profiles import write_profile
from profileopt import InputError, Route, load_vehicle, plan, read_route
from profileopt.core.segments import segment_route
from profileopt.physics.speeds import speed_bands
from profileopt.core.vehicle import PLAUSIBLE_RANGES

from conftest import ROOT, ROUTES

ATV_TOML = ROOT / "models" / "atv.toml"


def run(argv: list[str], cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "profileopt", *argv], cwd=cwd, capture_output=True, text=True,
                          timeout=300)


def one_line(done: subprocess.CompletedProcess, *fragments: str) -> str:
    assert done.returncode == 2, done.stderr
    assert "Traceback" not in done.stderr + done.stdout
    lines = done.stderr.splitlines()
    assert len(lines) == 1, done.stderr
    for fragment in fragments:
        assert fragment in lines[0], lines[0]
    return lines[0]


def vehicle_file(tmp_path: Path, key: str, value: str) -> Path:
    """The atv's file with one key's value replaced by ``value`` (TOML text, written as is)."""
    text = "".join(f"{k} = {value if k == key else repr(v)}\n" for k, v in
                   tomllib.loads(ATV_TOML.read_text(encoding="utf-8")).items())
    path = tmp_path / "vehicle.toml"
    path.write_text(text, encoding="utf-8")
    return path


ABSURD = [
    ("max_speed_mps", "1e200", "m/s"),
    ("natural_frequency_radps", "1e200", "rad/s"),
    ("quarter_mass_kg", "1" + "0" * 400, "401-digit"),
    ("max_transmitted_force_n", "1e-300", "N"),
    ("max_accel_mps2", "1e-12", "m/s^2"),
]


@pytest.mark.slow
@pytest.mark.parametrize("key, value, unit", ABSURD, ids=[a[0] for a in ABSURD])
@pytest.mark.parametrize("command", ["plan", "compare", "export-c", "figures"])
def test_absurd_vehicle_values_are_one_line_in_every_command(tmp_path, command, key, value, unit):
    vehicle = vehicle_file(tmp_path, key, value)
    argv = {
        "plan": ["plan", str(ROUTES / "curb.csv"), "--vehicle", str(vehicle), "-o", "out.csv"],
        "compare": ["compare", str(ROUTES / "curb.csv"), "--vehicle", str(vehicle)],
        "export-c": ["export-c", "--vehicle", str(vehicle), "-o", "forces_c"],
        "figures": ["figures", "--out", "figs", "--vehicle", str(vehicle)],
    }[command]
    one_line(run(argv, tmp_path), "vehicle.toml", f"'{key}'", "outside", unit)
    # before: OverflowError (exit 1) and, for figures, a folder left behind; a RuntimeWarning
    # printed before the error for 1e-300 N
    assert sorted(p.name for p in tmp_path.iterdir()) == ["vehicle.toml"]


def test_plausible_ranges_hold_the_bundled_vehicles():
    for name in ("atv", "atv-resonant"):
        vehicle = load_vehicle(name)
        for key, (lo, hi) in PLAUSIBLE_RANGES.items():
            assert lo <= getattr(vehicle, key) <= hi, (name, key)


@pytest.mark.parametrize("jerk", ["1e-13", "1e-50"])
def test_a_jerk_bound_too_small_to_move_is_refused_with_the_smallest_that_can(tmp_path, jerk):
    # before: 1e-13 ended in "internal error ... no jerk-limited fallback exists" (exit 1) and
    # 1e-50 returned status optimal with every speed 0 and travel time inf (Infinity in --json)
    done = run(["plan", str(ROUTES / "curb.csv"), "--max-jerk", jerk, "-o", "out.csv"], tmp_path)
    line = one_line(done, "--max-jerk", "too small to move the vehicle", "at least 0.001 m/s^3")
    assert "max_jerk_mps3" not in line  # the command names its own option
    assert not (tmp_path / "out.csv").exists()


def test_the_smallest_accepted_jerk_bound_plans(atv):
    route = read_route(ROUTES / "curb.csv")
    profile = plan(route, atv, max_jerk_mps3=PLAUSIBLE_RANGES["max_jerk_mps3"][0])
    assert profile.success and math.isfinite(profile.travel_time_s) and profile.speed_mps.max() > 0.1


def _washboard_only() -> Route:
    route = read_route(ROUTES / "washboard.csv")
    keep = (route.s_m >= 160) & (route.s_m <= 260)  # bands [0, ~0.32] and [~0.53, ~3.4]
    return Route(route.s_m[keep] - 160.0, route.z_m[keep], source="washboard-only")


@pytest.mark.parametrize("smoothing", [0.01, 0.0])
def test_a_boundary_speed_a_rounding_error_outside_a_band_starts_at_its_edge(atv_resonant, smoothing):
    route = _washboard_only()
    seg = segment_route(route, atv_resonant)
    edge = float(speed_bands(seg.ri[:1], atv_resonant).upper_mps[0, 0])  # top of the band from rest
    v0 = edge + 3e-9  # outside the band by 3e-9 m/s, e.g. a band edge printed by another tool
    # before: with smoothing, IPOPT stopped on "LBX <= UBX was violated" (exit 1); without, the
    # start speed was moved silently
    profile = plan(route, atv_resonant, v0_mps=v0, smoothing=smoothing,
                   max_jerk_mps3=None if smoothing else math.inf)
    assert profile.speed_mps[0] == edge
    assert any("v0_mps" in note and "outside the admissible band" in note for note in profile.notes)


def test_a_boundary_speed_clearly_outside_every_band_is_still_refused(atv_resonant):
    route = _washboard_only()
    with pytest.raises(InputError, match=r"v0_mps = 0.4 m/s is not an admissible speed"):
        plan(route, atv_resonant, v0_mps=0.4)


def _route_file(tmp_path: Path, s: np.ndarray, z: np.ndarray, limit: np.ndarray | None = None) -> Path:
    path = tmp_path / "route.csv"
    with open(path, "w", encoding="utf-8") as handle:
        handle.write("s,z" + (",speed_limit" if limit is not None else "") + "\n")
        for k in range(s.size):
            handle.write(f"{float(s[k])!r},{float(z[k])!r}" + (f",{float(limit[k])!r}" if limit is not None else "") + "\n")
    return path


@pytest.mark.slow
def test_a_speed_limit_slower_than_any_vehicle_names_itself(tmp_path):
    s = np.round(np.arange(0.0, 50.05, 0.1), 6)
    limit = np.full(s.size, 8.0)
    limit[100] = 5e-4  # before: "segment 0 would have to start and end at 0 m/s; use shorter segments"
    path = _route_file(tmp_path, s, 0.01 * np.sin(s), limit)
    line = one_line(run(["plan", str(path)], tmp_path), "route.csv", "line 102", "speed_limit = 0.0005 m/s")
    assert "shorter segments" not in line


@pytest.mark.slow
def test_distances_beyond_double_precision_are_named_as_such(tmp_path):
    s = 1e15 + np.arange(0.0, 50.0, 0.1)  # 1e15 keeps steps of 0.125 m only: rows repeat
    path = _route_file(tmp_path, s, 0.01 * np.sin(np.arange(s.size)))
    line = one_line(run(["plan", str(path)], tmp_path), "route.csv", "double precision", "subtract the first value")
    assert "drop duplicates" not in line


# --------------------------------------------------------------------------------------
# Silent misreading: a comment ends only where its line does; a byte-order mark is accepted in every file


@pytest.mark.parametrize("separator", ["\u2028", "\u2029", "\x0c", "\x0b", "\x85", "\x1c"])
def test_a_line_separator_inside_a_comment_stays_in_the_comment(tmp_path, separator):
    s = np.round(np.arange(0.0, 10.05, 0.1), 6)
    rows = "".join(f"{a:.6g},{0.01 * math.sin(3 * a):.6g}\n" for a in s)
    clean = tmp_path / "clean.csv"
    clean.write_text("# a comment\ns,z\n" + rows, encoding="utf-8")
    # before: str.splitlines split the comment, "5,3" became a data row and changed the RI
    tricky = tmp_path / "tricky.csv"
    tricky.write_text(f"# a comment{separator}5,3\ns,z\n" + rows, encoding="utf-8")
    a, b = read_route(clean), read_route(tricky)
    np.testing.assert_array_equal(a.s_m, b.s_m)
    np.testing.assert_array_equal(a.z_m, b.z_m)


@pytest.mark.parametrize(("comment", "line"), [("# note\r10.025,5", 203), ("# x\r# roughness_class = H", 1)],
                         ids=["data after a CR", "roughness after a CR"])
def test_a_lone_carriage_return_in_a_comment_is_refused_by_plan(tmp_path, capsys, comment, line):
    # issue 30 item 3: before, "10.025,5" became a data row (a 5 m step: 5.2 s of travel became
    # 108 s) and the second comment set an assumed roughness of class H; both exit 0
    from profileopt.cli import main

    rows = [f"{a:.3f},0" for a in np.arange(0.0, 20.001, 0.05)]
    lines = ["s,z", *rows]
    if comment.startswith("# note"):
        lines.insert(lines.index("10.000,0") + 1, comment)
    else:
        lines.insert(0, comment)
    route = tmp_path / "cr.csv"
    route.write_bytes(("\n".join(lines) + "\n").encode())
    out = tmp_path / "p.csv"
    assert main(["plan", str(route), "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"cr.csv: line {line}: a carriage return (\\r) inside the line" in err[0], err
    assert not out.exists()


def test_a_byte_order_mark_is_accepted_in_route_and_profile_files(tmp_path, atv):
    route = read_route(ROUTES / "curb.csv")
    profile = plan(route, atv)
    write_profile(profile, tmp_path / "profile.csv")
    (tmp_path / "bom.csv").write_bytes(b"\xef\xbb\xbf" + (tmp_path / "profile.csv").read_bytes())
    from profileopt import read_profile

    np.testing.assert_array_equal(read_profile(tmp_path / "bom.csv").speed_mps,
                                  read_profile(tmp_path / "profile.csv").speed_mps)
    (tmp_path / "route.csv").write_bytes(b"\xef\xbb\xbf" + (ROUTES / "curb.csv").read_bytes())
    np.testing.assert_array_equal(read_route(tmp_path / "route.csv").z_m, route.z_m)


def test_a_byte_order_mark_is_accepted_in_vehicle_files(tmp_path):
    # before: the vehicle reader decoded plain UTF-8 and refused the file with a TOML error
    (tmp_path / "bom.toml").write_bytes(b"\xef\xbb\xbf" + ATV_TOML.read_bytes())
    assert load_vehicle(tmp_path / "bom.toml") == load_vehicle("atv")
