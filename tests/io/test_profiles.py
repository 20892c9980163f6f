"""Profile files (profileopt.io.profiles): what ``plan -o`` writes and ``verify`` reads (issue 30).

- Numbers rounded to what they mean, reading back to the same plan: the file's profile
  keeps every limit within verify's check tolerance and its travel time (from its speeds and
  its time_s column) is the plan's within 1e-8. The reference is the plan itself; speeds at
  9 significant digits do not keep it (shown here), hence 12.
- The route's x_m, y_m, z_m (z_m for an s,z route) at each boundary, which lies on a sample:
  the route's own values there.
- The settings line: the vehicle as an absolute path with spaces kept, and the SHA-256 of its
  bytes (computed here with hashlib); one settings line, each key once; old files still read.
"""

from __future__ import annotations

import dataclasses
import hashlib
import math
from pathlib import Path

import numpy as np
import pytest

from profileopt import load_vehicle, plan
from profileopt.core.route import Route
from profileopt.errors import InputError
from profileopt.io import read_profile, read_route
from profileopt.io.profiles import write_profile
from profileopt.physics.simulate import boundary_times_s
from profileopt.verification.limit_check import check_limits

from conftest import ROOT, ROUTES


@pytest.fixture(scope="module")
def washboard_plan(atv):
    route = read_route(ROUTES / "washboard.csv")
    return route, plan(route, atv)


def test_a_written_profile_reads_back_to_the_same_plan(washboard_plan, atv, tmp_path) -> None:
    route, planned = washboard_plan
    path = tmp_path / "p.csv"
    write_profile(planned, path, route=route)
    read = read_profile(path)
    assert check_limits(route, read, atv).breaches == ()
    assert "stale" not in " ".join(check_limits(route, read, atv).notes)
    from_speeds = boundary_times_s(read.s_m, read.speed_mps)[-1]
    assert from_speeds == pytest.approx(planned.travel_time_s, rel=1e-8)
    assert read.travel_time_s == pytest.approx(planned.travel_time_s, rel=1e-8)
    assert np.array_equal(read.s_m, planned.s_m)  # the boundaries exactly: they lie on the route's samples
    # rounded: no cell but s_m carries more than 12 significant digits
    body = [line.split(",") for line in path.read_text().splitlines()[2:]]
    digits = [len(cell.lstrip("-").split("e")[0].replace(".", "").lstrip("0")) for row in body for cell in row[1:]
              if cell[:1].isdigit() or cell[:1] == "-"]
    assert max(digits) <= 12
    # why 12 digits for the speeds: at 9, the jerk recomputed over this plan's 0.1 m segments
    # goes beyond the limit's tolerance
    nine = dataclasses.replace(read, speed_mps=np.array([float(f"{v:.9g}") for v in planned.speed_mps]))
    assert [b.quantity for b in check_limits(route, nine, atv).breaches] == ["jerk"]


def test_the_profile_carries_the_routes_coordinates(atv, tmp_path) -> None:
    s = np.arange(0.0, 40.01, 0.05)
    x, y = 3.0 + s / math.sqrt(2), -2.0 + s / math.sqrt(2)  # a straight line at 45 degrees
    xyz = Route(s_m=s, z_m=0.01 * np.sin(s), x_m=x, y_m=y, source="diagonal")
    planned = plan(xyz, atv)
    write_profile(planned, tmp_path / "xyz.csv", route=xyz)
    lines = (tmp_path / "xyz.csv").read_text().splitlines()
    assert lines[1].endswith(",binding,x_m,y_m,z_m")
    rows = np.array([[float(c) for c in line.split(",")[-3:]] for line in lines[2:]])
    k = np.searchsorted(s, planned.s_m)
    assert np.allclose(s[k], planned.s_m, atol=1e-9)  # every boundary is a sample here
    assert np.allclose(rows, np.column_stack([x[k], y[k], xyz.z_m[k]]), rtol=1e-8, atol=1e-9)
    assert np.allclose(read_profile(tmp_path / "xyz.csv").speed_mps, planned.speed_mps, rtol=1e-11, atol=0)
    sz = Route(s_m=s, z_m=xyz.z_m, source="s,z")
    write_profile(planned, tmp_path / "sz.csv", route=sz)
    assert (tmp_path / "sz.csv").read_text().splitlines()[1].endswith(",binding,z_m")
    read_profile(tmp_path / "sz.csv")


def test_the_vehicle_is_recorded_by_absolute_path_and_hash(atv, washboard_plan, tmp_path, monkeypatch) -> None:
    _, planned = washboard_plan
    folder = tmp_path / "my plans"
    folder.mkdir()
    vehicle_file = folder / "my veh.toml"
    vehicle_file.write_bytes((ROOT / "models" / "atv.toml").read_bytes())
    monkeypatch.chdir(folder)
    write_profile(dataclasses.replace(planned, settings=planned.settings | {"vehicle": "my veh.toml"}), "p.csv")
    monkeypatch.chdir(tmp_path)
    settings = read_profile(folder / "p.csv").settings
    assert settings["vehicle"] == str(vehicle_file)
    assert settings["vehicle_sha256"] == hashlib.sha256(vehicle_file.read_bytes()).hexdigest()
    # a bundled vehicle: its name, and the hash of the bundled file
    write_profile(planned, tmp_path / "bundled.csv")
    settings = read_profile(tmp_path / "bundled.csv").settings
    assert settings["vehicle"] == "atv"
    assert settings["vehicle_sha256"] == hashlib.sha256(Path(load_vehicle("atv").name).read_bytes()).hexdigest()
    # a value with a quote, a backslash and a line separator survives too
    odd = 'a "b"\\c\u2028d'
    write_profile(dataclasses.replace(planned, settings=planned.settings | {"note": odd}), tmp_path / "odd.csv")
    text = (tmp_path / "odd.csv").read_text()
    assert text.count("\n") == planned.s_m.size + 2 and "\u2028" not in text  # one line, escaped
    assert read_profile(tmp_path / "odd.csv").settings["note"] == odd


def test_a_read_profile_written_again_keeps_its_settings(washboard_plan, tmp_path) -> None:
    route, planned = washboard_plan
    write_profile(planned, tmp_path / "a.csv", route=route)
    write_profile(read_profile(tmp_path / "a.csv"), tmp_path / "b.csv")
    first, again = (tmp_path / "a.csv").read_text(), (tmp_path / "b.csv").read_text()
    assert again.splitlines()[0] == first.splitlines()[0]  # status=optimal, the vehicle and its hash


def test_a_second_settings_line_or_a_key_given_twice_is_refused(washboard_plan, tmp_path) -> None:
    _, planned = washboard_plan
    write_profile(planned, tmp_path / "p.csv")
    lines = (tmp_path / "p.csv").read_text().splitlines()
    twice = tmp_path / "twice.csv"
    twice.write_text("\n".join([lines[0], lines[0].replace("max_jerk_mps3=5.0", "max_jerk_mps3=inf"), *lines[1:]]))
    with pytest.raises(InputError, match=r"twice.csv: line 2: a second settings line .*the first is line 1"):
        read_profile(twice)
    key = tmp_path / "key.csv"
    key.write_text("\n".join([lines[0] + " max_jerk_mps3=inf", *lines[1:]]))
    with pytest.raises(InputError, match=r"key.csv: line 1: the settings line gives max_jerk_mps3 twice"):
        read_profile(key)


def test_files_of_older_versions_still_read(washboard_plan, tmp_path) -> None:
    _, planned = washboard_plan
    write_profile(planned, tmp_path / "p.csv")
    lines = (tmp_path / "p.csv").read_text().splitlines()
    old_settings = ("# profileopt profile: vehicle=my_veh.toml model=sbem_tf max_jerk_mps3=5.0 "
                    "status=fallback:_Maximum_Iterations_Exceeded")
    for columns in (11, 8):  # before the coordinates; before turns and hills
        old = tmp_path / f"old{columns}.csv"
        old.write_text("\n".join([old_settings, *(",".join(line.split(",")[:columns]) for line in lines[1:])]) + "\n")
        read = read_profile(old)
        assert read.settings["vehicle"] == "my_veh.toml" and read.settings["status"].startswith("fallback:_")
        assert np.allclose(read.speed_mps, planned.speed_mps, rtol=1e-11)
        assert (read.binding is not None) == (columns == 11)
