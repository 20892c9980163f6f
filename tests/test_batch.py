"""profileopt.batch and ``profileopt batch``: many routes, each planned as ``profileopt plan``
plans it (issue 32).

The reference for every profile is ``profileopt plan`` itself: a batch's ``ID.csv`` must be
the same bytes as the plan command's ``-o`` of that route with the row's options. Broken
rows fail alone, with the one line ``plan`` would say; a batch run again plans only what is
missing, failed or changed; a batch stopped by SIGTERM resumes where it stopped.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from profileopt import cli
from profileopt.batch import BatchRow, plan_many, read_manifest
from profileopt.errors import InputError

from conftest import PROFILEOPT, ROUTES


def short_route(folder: Path, name: str, length_m: float, source: Path = ROUTES / "curb.csv") -> Path:
    """The first ``length_m`` of a bundled route (a plan in a fraction of a second)."""
    lines = source.read_text().splitlines()
    keep = [line for line in lines if not line[:1].isdigit() or float(line.split(",")[0]) <= length_m]
    path = folder / name
    path.write_text("\n".join(keep) + "\n")
    return path


@pytest.fixture
def folder(tmp_path: Path) -> Path:
    short_route(tmp_path, "kerb.csv", 120.0)  # the curb's step at 102.5 m
    short_route(tmp_path, "board.csv", 60.0, ROUTES / "washboard.csv")
    (tmp_path / "coarse.csv").write_text("s,z\n0,0\n10,0.1\n20,0\n30,0.1\n")  # too coarse to measure roughness
    return tmp_path


def alone(folder: Path, *argv: str) -> bytes:
    """The profile ``profileopt plan ARGV -o`` writes, in this process, run in ``folder``."""
    import contextlib

    out = folder / "alone.csv"
    with contextlib.chdir(folder):
        assert cli.main(["plan", *argv, "-o", str(out), "-q"]) == 0
    data = out.read_bytes()
    out.unlink()
    return data


def summary(out: Path) -> dict[str, dict[str, str]]:
    import csv

    with open(out / "summary.csv", newline="") as handle:
        return {row["id"]: row for row in csv.DictReader(handle)}


# --------------------------------------------------------------------------------------
# The manifest


def test_a_manifest_reads_paths_relative_to_itself_and_plan_options(tmp_path: Path) -> None:
    (tmp_path / "m").mkdir()
    (tmp_path / "m" / "runs.csv").write_text("id,route,vehicle,segment_length,refine,terrain\n"
                                             "a,../r.csv,atv-resonant,2,false,\n"
                                             "b,/abs/r.csv,my.toml,,true,cloud.laz\n")
    a, b = read_manifest(tmp_path / "m" / "runs.csv")
    assert a == BatchRow("a", str(tmp_path / "m" / "../r.csv"),
                         (("vehicle", "atv-resonant"), ("segment_length", "2"), ("refine", "false")))
    assert b.route == "/abs/r.csv" and ("vehicle", str(tmp_path / "m" / "my.toml")) in b.options
    assert ("terrain", str(tmp_path / "m" / "cloud.laz")) in b.options
    assert a.argv("o.csv") == [a.route, "-o", "o.csv", "--quiet", "--vehicle=atv-resonant", "--segment-length=2",
                               "--no-refine"]
    (tmp_path / "runs.json").write_text(json.dumps([{"id": "j", "route": "r.csv", "v0": 1.5, "refine": True}]))
    (j,) = read_manifest(tmp_path / "runs.json")
    assert j.argv("o.csv")[4:] == ["--v0=1.5", "--refine"]


@pytest.mark.parametrize("text, words", [
    ("id,route,segment_lenght\na,r.csv,2\n", "column 'segment_lenght' is no option of profileopt plan"),
    ("id,route,segment_lenght\na,r.csv,2\n", "did you mean 'segment_length'?"),
    ("id,route,plot\na,r.csv,p.png\n", "column 'plot' is no option"),
    ("id,route\na,r.csv\na,s.csv\n", "line 3: id 'a' is also the id of line 2"),
    ("id,route\n../x,r.csv\n", "id '../x' must be a file name"),
    ("id,route\nsummary,r.csv\n", "(not 'summary')"),
    ("id,route\na,\n", "line 2: no route"),
    ("id,route\n", "the manifest has no rows"),
])
def test_a_bad_manifest_is_one_line(tmp_path: Path, text: str, words: str) -> None:
    (tmp_path / "m.csv").write_text(text)
    with pytest.raises(InputError) as raised:
        read_manifest(tmp_path / "m.csv")
    assert words in str(raised.value) and "\n" not in str(raised.value) and "m.csv" in str(raised.value)


# --------------------------------------------------------------------------------------
# Planning: the same bytes as `profileopt plan`, failures alone, resumed


@pytest.mark.slow
def test_one_worker_plans_each_route_as_plan_does_and_fails_alone(folder: Path) -> None:
    (folder / "runs.csv").write_text("id,route,vehicle,model,segment_length\n"
                                     "kerb,kerb.csv,atv,,\n"
                                     "board,board.csv,atv-resonant,sbem_ef,2\n"
                                     "missing,nowhere.csv,,,\n"
                                     "badveh,kerb.csv,no-such-vehicle,,\n"
                                     "coarse,coarse.csv,,,\n")
    out = folder / "out"
    rows = read_manifest(folder / "runs.csv")
    result = plan_many(rows, out, workers=1)
    assert [r["id"] for r in result] == ["kerb", "board", "missing", "badveh", "coarse"]
    assert (out / "kerb.csv").read_bytes() == alone(folder, str(folder / "kerb.csv"), "--vehicle", "atv")
    assert (out / "board.csv").read_bytes() == alone(folder, str(folder / "board.csv"), "--vehicle", "atv-resonant",
                                                     "--model", "sbem_ef", "--segment-length", "2")
    table = summary(out)
    assert [table[k]["status"] for k in table] == ["ok", "ok", "failed", "failed", "failed"]
    assert "nowhere.csv: route file not found" in table["missing"]["error"]
    assert "no bundled vehicle" in table["badveh"]["error"]
    assert "coarse.csv" in table["coarse"]["error"] and "\n" not in table["coarse"]["error"]
    assert not (out / "missing.csv").exists() and table["missing"]["profile"] == ""
    assert float(table["kerb"]["travel_time_s"]) == pytest.approx(json.loads(_plan_json(folder / "kerb.csv"))[
        "travel_time_s"], rel=1e-12)
    _same_as_parquet(out, table)
    # run again: only the failed rows are tried again, the profiles planned stay as they are
    stamp = (out / "kerb.csv").stat().st_mtime_ns
    again = plan_many(rows, out, workers=1)
    assert (out / "kerb.csv").stat().st_mtime_ns == stamp and again[0] == result[0]
    # a changed route is planned again
    short_route(folder, "kerb.csv", 110.0)
    third = plan_many(rows, out, workers=1)
    assert third[0]["input_sha256"] != result[0]["input_sha256"]
    assert (out / "kerb.csv").read_bytes() == alone(folder, str(folder / "kerb.csv"), "--vehicle", "atv")


def _same_as_parquet(out: Path, table: dict[str, dict[str, str]]) -> None:
    """summary.parquet (with pyarrow) holds the CSV's rows, numbers typed, empty cells null;
    without pyarrow there is none."""
    import importlib.util

    if importlib.util.find_spec("pyarrow") is None:
        assert not (out / "summary.parquet").exists()
        return
    import pyarrow.parquet as pq

    rows = pq.read_table(out / "summary.parquet").to_pylist()
    assert [row["id"] for row in rows] == list(table)
    for row in rows:
        csv_row = table[row["id"]]
        assert row["status"] == csv_row["status"] and row["error"] == (csv_row["error"] or None)
        assert row["travel_time_s"] == (float(csv_row["travel_time_s"]) if csv_row["travel_time_s"] else None)
        assert row["segments"] == (int(csv_row["segments"]) if csv_row["segments"] else None)


def test_a_parquet_summary_behind_the_csv_is_written_again(folder: Path) -> None:
    """summary.parquet is written once, as a batch ends: one killed between its last
    summary.csv and the Parquet table leaves it missing (or older), and the next run, with
    nothing left to plan, writes it."""
    pytest.importorskip("pyarrow")
    short_route(folder, "kerb.csv", 60.0)
    rows = [BatchRow("kerb", str(folder / "kerb.csv"), (("vehicle", "atv"),))]
    out = folder / "out"
    plan_many(rows, out, workers=1)
    (out / "summary.parquet").unlink()  # as if killed after the CSV
    stamp = (out / "kerb.csv").stat().st_mtime_ns
    plan_many(rows, out, workers=1)
    assert (out / "kerb.csv").stat().st_mtime_ns == stamp  # nothing planned again
    _same_as_parquet(out, summary(out))


def test_the_parquet_summary_keeps_text_that_looks_like_a_null(folder: Path) -> None:
    """An id "NA" (a valid id) and an error line with commas and quotes stay text in
    summary.parquet, not nulls or split cells."""
    pytest.importorskip("pyarrow")
    rows = [BatchRow("NA", str(folder / 'no, "such".csv'), (("vehicle", "atv"),))]
    out = folder / "out"
    plan_many(rows, out, workers=1)
    table = summary(out)
    assert list(table) == ["NA"] and 'no, "such".csv' in table["NA"]["error"]
    _same_as_parquet(out, table)


def _plan_json(route: Path) -> str:
    done = subprocess.run([*PROFILEOPT, "plan", str(route), "--json", "-q"], capture_output=True, text=True,
                          check=True, timeout=120)
    return done.stdout


@pytest.mark.slow
def test_the_command_on_a_local_cluster_exits_5_with_the_failures(folder: Path) -> None:
    """Two worker processes (a Dask LocalCluster): the same profiles as one after another."""
    pytest.importorskip("distributed")
    out = folder / "out"
    done = subprocess.run([*PROFILEOPT, "batch", "kerb.csv", "board.csv", "coarse.csv", "--vehicle", "atv",
                           "-o", "out", "--workers", "2", "-q"], cwd=folder, capture_output=True, text=True,
                          timeout=300)
    assert done.returncode == 5, done.stderr
    assert done.stdout.strip() == "planned 2 of 3 routes into out (out/summary.csv); 1 failed"
    assert [line for line in done.stderr.splitlines() if line.startswith("profileopt batch: coarse:")]
    assert (out / "kerb.csv").read_bytes() == alone(folder, "kerb.csv", "--vehicle", "atv")
    assert (out / "board.csv").read_bytes() == alone(folder, "board.csv", "--vehicle", "atv")


@pytest.mark.slow
def test_a_batch_stopped_by_sigterm_resumes_where_it_stopped(folder: Path) -> None:
    names = [f"r{k}" for k in range(6)]
    for k, name in enumerate(names):
        short_route(folder, f"{name}.csv", 40.0 + 10 * k)
    # the third route is the bundled 2 km trail (seconds to plan, where the others take a tenth
    # of one), so the signal sent when two are done lands while the batch is still at work
    (folder / "r2.csv").write_bytes((ROUTES / "trail.csv").read_bytes())
    batch = subprocess.Popen([*PROFILEOPT, "batch", *(f"{n}.csv" for n in names), "-o", "out", "--workers", "1"],
                             cwd=folder, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and len(summary(folder / "out") if (folder / "out" / "summary.csv").exists()
                                               else {}) < 2:
        time.sleep(0.05)
    batch.send_signal(signal.SIGTERM)
    _, err = batch.communicate(timeout=60)
    assert batch.returncode == 143, err
    first = summary(folder / "out")
    assert 2 <= len(first) < len(names) and all(row["status"] == "ok" for row in first.values())
    assert not list((folder / "out").glob(".po-*"))  # no half-written file
    _same_as_parquet(folder / "out", first)  # written once, as the batch stopped
    stamps = {name: (folder / "out" / f"{name}.csv").stat().st_mtime_ns for name in first}
    done = subprocess.run([*PROFILEOPT, "batch", *(f"{n}.csv" for n in names), "-o", "out", "--workers", "1"],
                          cwd=folder, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert {name: (folder / "out" / f"{name}.csv").stat().st_mtime_ns for name in first} == stamps
    assert len(summary(folder / "out")) == len(names)
    _same_as_parquet(folder / "out", summary(folder / "out"))


@pytest.mark.slow
def test_a_batch_on_a_running_cluster_gives_the_same_profiles(folder: Path) -> None:
    """A scheduler and two workers started as their own processes, addresses on localhost."""
    pytest.importorskip("distributed")
    info = folder / "scheduler.json"
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1")
    dask = [sys.executable, "-m", "distributed.cli.dask_scheduler"]
    scheduler = subprocess.Popen([*dask, "--scheduler-file", str(info), "--host", "127.0.0.1", "--port", "0",
                                  "--dashboard-address", ":0"], cwd=folder, env=env,
                                 stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    workers = []
    try:
        deadline = time.monotonic() + 60
        while not info.exists() and time.monotonic() < deadline:
            time.sleep(0.1)
        address = json.loads(info.read_text())["address"]
        for _ in range(2):
            workers.append(subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_worker", address,
                                             "--nthreads", "1", "--no-dashboard"], cwd=folder, env=env,
                                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        done = subprocess.run([*PROFILEOPT, "batch", "kerb.csv", "board.csv", "--vehicle", "atv-resonant", "-o",
                               "out", "-q"], cwd=folder, capture_output=True, text=True, timeout=300,
                              env=dict(env, DASK_SCHEDULER_ADDRESS=address))
        assert done.returncode == 0, done.stderr
    finally:
        for process in (*workers, scheduler):
            process.terminate()
        for process in (*workers, scheduler):
            process.wait(30)
    for name in ("kerb", "board"):
        assert (folder / "out" / f"{name}.csv").read_bytes() == alone(folder, f"{name}.csv", "--vehicle",
                                                                      "atv-resonant")


def test_the_command_refuses_a_manifest_and_routes_together(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    (tmp_path / "m.csv").write_text("id,route\na,r.csv\n")
    assert cli.main(["batch", "r.csv", "--manifest", str(tmp_path / "m.csv"), "-o", str(tmp_path / "o")]) == 2
    assert capsys.readouterr().err == ("profileopt batch: error: give either --manifest FILE or route files, not "
                                       "both and not neither\n")


def test_several_workers_without_dask_say_which_extra(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import builtins

    real_import = builtins.__import__

    def no_dask(name, *args, **kwargs):  # noqa: ANN001, ANN202
        if name.startswith(("dask", "distributed")):
            raise ImportError(name)
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_dask)
    with pytest.raises(InputError, match=r"pip install 'profileopt\[batch\]'"):
        plan_many([BatchRow("a", "r.csv")], tmp_path / "o", workers=2)


def test_a_terrain_column_takes_tiles_separated_by_semicolons_or_a_json_list(tmp_path: Path) -> None:
    (tmp_path / "runs.json").write_text('[{"id": "a", "route": "t.gpx", "terrain": ["tiles/sw.laz", "/abs/ne.laz"]},'
                                        ' {"id": "b", "route": "t.gpx", "terrain": "tiles"}]')
    a, b = read_manifest(tmp_path / "runs.json")
    assert a.options == (("terrain", f"{tmp_path / 'tiles/sw.laz'};/abs/ne.laz"),)
    assert a.argv("o.csv")[-2:] == [f"--terrain={tmp_path / 'tiles/sw.laz'}", "--terrain=/abs/ne.laz"]
    assert b.argv("o.csv")[-1] == f"--terrain={tmp_path / 'tiles'}"


@pytest.mark.slow
def test_tracks_over_a_folder_of_tiles_plan_as_plan_does(tmp_path: Path) -> None:
    """Two GPX tracks over a folder of four LAZ tiles (and one far away), each route reading the
    tiles near it: the profiles are plan's bytes."""
    pytest.importorskip("laspy")
    import numpy as np

    import geo_data as g

    x, y, z, c = g.cloud_points(density_per_m2=400.0)
    (tmp_path / "tiles").mkdir()
    mid_x, mid_y = float(np.median(x)), float(np.median(y))
    for name, keep in (("sw", (x < mid_x) & (y < mid_y)), ("se", (x >= mid_x) & (y < mid_y)),
                       ("nw", (x < mid_x) & (y >= mid_y)), ("ne", (x >= mid_x) & (y >= mid_y))):
        g.write_laz(tmp_path / "tiles" / f"{name}.laz", x[keep], y[keep], z[keep], c[keep])
    g.write_laz(tmp_path / "tiles" / "far.laz", x[:500] + 900.0, y[:500], z[:500], c[:500])
    tx, ty = g.track_utm_m(2.0)
    g.write_gpx(tmp_path / "arc.gpx", tx, ty)
    g.write_gpx(tmp_path / "back.gpx", tx[::-1], ty[::-1])
    import contextlib

    with contextlib.chdir(tmp_path):
        assert cli.main(["batch", "arc.gpx", "back.gpx", "--terrain", "tiles", "-o", "out", "--workers", "1", "-q",
                         "--vehicle", "atv"]) == 0
    for name in ("arc", "back"):
        assert (tmp_path / "out" / f"{name}.csv").read_bytes() == alone(
            tmp_path, f"{name}.gpx", "--terrain", "tiles", "--vehicle", "atv")


# --------------------------------------------------------------------------------------
# Issue 30, items 1 and 7: no output of a batch replaces a file it reads


def _snapshot(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir()) if p.is_file()}


@pytest.mark.parametrize("case", ["manifest named ID.csv", "manifest named summary.csv",
                                  "summary.csv a link to the manifest", "ID.csv another row's route"])
def test_no_output_of_a_batch_replaces_its_manifest_or_a_route(tmp_path: Path, case: str,
                                                               capsys: pytest.CaptureFixture) -> None:
    # Before: the manifest (or a route) was replaced by a profile or the summary, exit 0
    out = tmp_path / "b"
    out.mkdir()
    short_route(out, "r.csv", 30.0)
    manifest, text = out / "man.csv", "id,route,vehicle\nrr,r.csv,atv\n"
    if case == "manifest named ID.csv":
        manifest = out / "rr.csv"
    elif case == "manifest named summary.csv":
        manifest = out / "summary.csv"
    elif case == "summary.csv a link to the manifest":
        (out / "summary.csv").symlink_to("man.csv")
    else:
        text = "id,route,vehicle\nr,r.csv,atv\nq,r.csv,atv\n"  # row r's profile r.csv is row q's route
    manifest.write_text(text)
    before = _snapshot(out)
    assert cli.main(["batch", "--manifest", str(manifest), "-o", str(out), "--workers", "1", "-q"]) == 2
    captured = capsys.readouterr()
    err = captured.err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    named = {"manifest named ID.csv": ("b/rr.csv: the profile of row 'rr' would replace the manifest", "rr.csv"),
             "manifest named summary.csv": ("b/summary.csv: the batch's summary would replace the manifest",
                                            "summary.csv"),
             "summary.csv a link to the manifest": ("b/summary.csv: the batch's summary would replace the manifest",
                                                    "man.csv"),
             "ID.csv another row's route": ("b/r.csv: the profile of row 'r' would replace the route of row 'q'",
                                            "r.csv")}[case]
    assert named[0] in err and f"b/{named[1]})" in err, err
    assert captured.out == "" and _snapshot(out) == before
    assert not list(out.glob(".po-*.tmp"))


def test_a_row_whose_profile_is_its_own_route_fails_alone(tmp_path: Path) -> None:
    # as profileopt plan refuses `-o` naming its route: that row fails, the others are planned
    short_route(tmp_path, "r.csv", 30.0)
    short_route(tmp_path, "k.csv", 30.0)
    (tmp_path / "m.csv").write_text("id,route\nr,r.csv\nk2,k.csv\n")
    before = (tmp_path / "r.csv").read_bytes()
    result = plan_many(read_manifest(tmp_path / "m.csv"), tmp_path, workers=1, inputs=[tmp_path / "m.csv"])
    assert [row["status"] for row in result] == ["failed", "ok"]
    assert "is the input" in result[0]["error"]
    assert (tmp_path / "r.csv").read_bytes() == before


def test_an_output_folder_swapped_during_a_batch_replaces_no_input(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                                   capsys: pytest.CaptureFixture) -> None:
    # Before: with the output folder swapped for a link to the inputs' folder after the first
    # route, the summary was written through the link over the manifest (named summary.csv)
    from profileopt import batch

    inputs, out = tmp_path / "in", tmp_path / "out"
    inputs.mkdir()
    out.mkdir()
    short_route(inputs, "r.csv", 30.0)
    short_route(inputs, "s.csv", 30.0)
    manifest = inputs / "summary.csv"
    manifest.write_text("id,route\nr2,r.csv\ns2,s.csv\n")
    before = _snapshot(inputs)
    planned = batch.plan_row

    def plan_then_swap(*args, **kwargs):  # noqa: ANN002, ANN003, ANN202
        result = planned(*args, **kwargs)
        if not (tmp_path / "out.old").exists():  # after the first route: out/ becomes a link to in/
            out.rename(tmp_path / "out.old")
            out.symlink_to(inputs)
        return result

    monkeypatch.setattr(batch, "plan_row", plan_then_swap)
    assert cli.main(["batch", "--manifest", str(manifest), "-o", str(out), "--workers", "1", "-q"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "is now the input" in err and str(manifest) in err, err
    assert _snapshot(inputs) == before
    assert not list(tmp_path.rglob(".po-*.tmp"))


_FAULTS_PER_ALLOCATION = """
import resource, sys
import numpy as np
from profileopt.batch import plan_row
if sys.argv[1] == "planning":
    assert plan_row(["--no-such-option"])["status"] == "failed"  # a row, planned or not
np.ones(1 << 17)  # 1 MiB, allocated and freed
before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
for _ in range(50):
    np.ones(1 << 17)
print((resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before) / 50)
"""


@pytest.mark.slow
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="glibc's malloc")
def test_a_worker_started_as_dask_starts_it_reuses_freed_arrays_once_it_plans() -> None:
    """Dask's nanny starts workers with MALLOC_TRIM_THRESHOLD_=65536, which makes glibc map
    every array over 128 kB afresh: a 1 MiB array is 256 pages faulted in each time. Once a
    process has planned a route (plan_row), freed arrays are reused: no page faults."""
    env = {**os.environ, "MALLOC_TRIM_THRESHOLD_": "65536"}
    faults = {}
    for mode in ("idle", "planning"):
        done = subprocess.run([sys.executable, "-c", _FAULTS_PER_ALLOCATION, mode], env=env, capture_output=True,
                              text=True, check=True)
        faults[mode] = float(done.stdout)
    assert faults["idle"] >= 200  # the reason for the fix: 256 pages of 4 kB per MiB
    assert faults["planning"] < 5
