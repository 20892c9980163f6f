"""Outputs that never destroy data, inputs that cannot exhaust the machine (issue 13).

Every command checks all its outputs before any work (an output that is one of its inputs, two
outputs that are the same file, an empty path, a name too long) and writes them all or none;
an output that is not a regular file (``/dev/null``, a FIFO, standard output) is written into,
never replaced; SIGTERM cleans up like Ctrl-C; a route, profile or vehicle path that is not a
regular file, or a file above the size cap, is refused with one line.
"""

from __future__ import annotations

import errno
import io
import os
import resource
import signal
import stat
import subprocess
import sys
import textwrap
import threading
import time
from pathlib import Path

import pytest

from conftest import PROFILEOPT, ROOT, ROUTES

ROUTE = ROUTES / "curb.csv"  # 200 m: a plan takes a fraction of a second
VEHICLE = ROOT / "models" / "atv.toml"


def _limit_memory() -> None:  # a run that reads /dev/zero must fail, not take the machine's memory
    resource.setrlimit(resource.RLIMIT_AS, (4 << 30, 4 << 30))


def run(cwd: Path, *argv: str, timeout: float = 120) -> subprocess.CompletedProcess:
    env = dict(os.environ, MPLBACKEND="Agg")
    return subprocess.run([*PROFILEOPT, *argv], cwd=cwd, capture_output=True, text=True, timeout=timeout,
                          env=env, preexec_fn=_limit_memory)


def one_line_exit_2(done: subprocess.CompletedProcess, *fragments: str) -> str:
    assert done.returncode == 2, (done.returncode, done.stdout, done.stderr)
    lines = done.stderr.splitlines()
    assert len(lines) == 1, done.stderr
    for fragment in fragments:
        assert fragment in lines[0], (fragment, lines[0])
    assert "travel time" not in done.stdout  # refused before any work
    return lines[0]


@pytest.fixture
def folder(tmp_path: Path) -> Path:
    (tmp_path / "route.csv").write_bytes(ROUTE.read_bytes())
    (tmp_path / "my.toml").write_bytes(VEHICLE.read_bytes())
    (tmp_path / "sub").mkdir()
    return tmp_path


@pytest.fixture(scope="module")
def profile_text(tmp_path_factory: pytest.TempPathFactory) -> bytes:
    where = tmp_path_factory.mktemp("profile")
    done = run(where, "plan", str(ROUTE), "-o", "profile.csv")
    assert done.returncode == 0, done.stderr
    return (where / "profile.csv").read_bytes()


def snapshot(folder: Path) -> dict[str, bytes]:
    return {p.name: (p.read_bytes() if p.is_file() else b"<dir>") for p in sorted(folder.iterdir())}


# --------------------------------------------------------------------------------------
# An output that is an input, two outputs that are one file: refused before any work.

SAME_AS_INPUT = {
    "plan -o route": ("plan", "route.csv", "-o", "route.csv"),
    "plan -o ./route": ("plan", "route.csv", "-o", "./route.csv"),
    "plan -o sub/../route": ("plan", "route.csv", "-o", "sub/../route.csv"),
    "plan --plot route": ("plan", "route.csv", "--plot", "route.csv"),
    "plan -o vehicle": ("plan", "route.csv", "--vehicle", "my.toml", "-o", "my.toml"),
    "plan -o hard link of route": ("plan", "route.csv", "-o", "hard.csv"),
    "plan -o symlink to route": ("plan", "route.csv", "-o", "soft.csv"),
    "verify -o profile": ("verify", "route.csv", "profile.csv", "-o", "profile.csv"),
    "verify -o route": ("verify", "route.csv", "profile.csv", "-o", "./route.csv"),
    "verify --plot profile": ("verify", "route.csv", "profile.csv", "--plot", "sub/../profile.csv"),
    "verify -o vehicle": ("verify", "route.csv", "profile.csv", "--vehicle", "my.toml", "-o", "my.toml"),
    "export-c README.md is the vehicle": ("export-c", "--vehicle", "cout/README.md", "-o", "cout"),
}


@pytest.mark.slow
@pytest.mark.parametrize("argv", SAME_AS_INPUT.values(), ids=SAME_AS_INPUT.keys())
def test_an_output_that_is_an_input_is_refused(argv: tuple[str, ...], folder: Path, profile_text: bytes) -> None:
    (folder / "profile.csv").write_bytes(profile_text)
    os.link(folder / "route.csv", folder / "hard.csv")
    os.symlink("route.csv", folder / "soft.csv")
    (folder / "cout").mkdir()
    (folder / "cout" / "README.md").write_bytes(VEHICLE.read_bytes())
    before = snapshot(folder)
    one_line_exit_2(run(folder, *argv), "is the input", "choose another output path")
    assert snapshot(folder) == before
    assert (folder / "soft.csv").is_symlink()


SAME_OUTPUTS = {
    "plan -o p --plot p": ("plan", "route.csv", "-o", "p.csv", "--plot", "p.csv"),
    "plan -o p --plot ./p": ("plan", "route.csv", "-o", "p.csv", "--plot", "./p.csv"),
    "plan -o p --plot sub/../p (existing)": ("plan", "route.csv", "-o", "old.csv", "--plot", "sub/../old.csv"),
    "verify -o v --plot v": ("verify", "route.csv", "profile.csv", "-o", "v.csv", "--plot", "v.csv"),
}


@pytest.mark.parametrize("argv", SAME_OUTPUTS.values(), ids=SAME_OUTPUTS.keys())
def test_two_outputs_that_are_one_file_are_refused(argv: tuple[str, ...], folder: Path, profile_text: bytes) -> None:
    (folder / "profile.csv").write_bytes(profile_text)
    (folder / "old.csv").write_text("a good earlier output\n")
    before = snapshot(folder)
    one_line_exit_2(run(folder, *argv), "is also the output of", "its own path")
    assert snapshot(folder) == before


# --------------------------------------------------------------------------------------
# Several outputs: all checked first, then all written, or none.


def test_figures_checks_every_file_before_writing_one(folder: Path) -> None:
    out = folder / "figs"
    out.mkdir()
    (out / "fig5_allowable_speed.csv").write_text("a good earlier fig5\n")
    (out / "fig6_resonance.png").mkdir()  # the last output cannot be written
    before = snapshot(out)
    one_line_exit_2(run(folder, "figures", "--out", "figs"), "fig6_resonance.png", "is a folder")
    assert snapshot(out) == before


def test_a_plot_name_too_long_keeps_the_earlier_profile(folder: Path) -> None:
    (folder / "out.csv").write_text("a good earlier profile\n")
    before = snapshot(folder)
    long_png = "p" * 252 + ".png"  # 256 bytes: longer than a name may be
    one_line_exit_2(run(folder, "plan", "route.csv", "-o", "out.csv", "--plot", long_png), "--plot", "name")
    assert snapshot(folder) == before


def test_a_failing_second_output_leaves_the_first_untouched(folder: Path, monkeypatch: pytest.MonkeyPatch,
                                                           capsys: pytest.CaptureFixture) -> None:
    """The disk fills up while the plot is written: the profile written just before it must
    not have replaced the earlier one (the pair would no longer match)."""
    from profileopt import cli
    from profileopt.viz import plots

    def disk_full(profile, path, **labels):  # noqa: ANN001, ANN202  (route=, vehicle= for the title)
        with plots.atomic_path(path) as tmp:
            tmp.write_bytes(b"\x89PNG half")
            raise OSError(28, "No space left on device")

    monkeypatch.setattr(plots, "plot_profile", disk_full)
    (folder / "out.csv").write_text("a good earlier profile\n")
    (folder / "out.png").write_bytes(b"a good earlier plot")
    before = snapshot(folder)
    status = cli.main(["plan", str(folder / "route.csv"), "-o", str(folder / "out.csv"),
                       "--plot", str(folder / "out.png")])
    assert status == 2  # the user's to fix (issue 30): one line naming the output
    assert "--plot" in (err := capsys.readouterr().err) and "No space left on device" in err
    assert snapshot(folder) == before


class _FullStdout(io.StringIO):
    """Standard output on a full disk (``> /dev/full``): what is printed cannot be flushed."""

    def flush(self) -> None:
        raise OSError(errno.ENOSPC, "No space left on device")


FULL_STDOUT = {
    "plan --json": ("plan", "route.csv", "-q", "-o", "old.csv", "--plot", "old.png", "--json"),
    "plan": ("plan", "route.csv", "-q", "-o", "old.csv", "--plot", "old.png"),
    "verify": ("verify", "route.csv", "profile.csv", "-o", "old.csv", "--plot", "old.png"),
    "verify --json": ("verify", "route.csv", "profile.csv", "-o", "old.csv", "--json"),
}


@pytest.mark.parametrize("argv", FULL_STDOUT.values(), ids=FULL_STDOUT.keys())
def test_a_full_standard_output_replaces_no_file(argv: tuple[str, ...], folder: Path, profile_text: bytes,
                                                 monkeypatch: pytest.MonkeyPatch,
                                                 capsys: pytest.CaptureFixture) -> None:
    # Before (issue 30, item 2): `plan ... -o old.csv --plot old.png > /dev/full` said exit 2
    # but had replaced both files: the summary was printed after they were renamed into place
    from profileopt import cli

    (folder / "profile.csv").write_bytes(profile_text)
    (folder / "old.csv").write_text("OLDCSV\n")
    (folder / "old.png").write_text("OLDPNG\n")
    before = snapshot(folder)
    monkeypatch.chdir(folder)
    monkeypatch.setattr(sys, "stdout", _FullStdout())
    assert cli.main(list(argv)) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    assert ("standard output: cannot write (No space left on device); no file output was written" in err), err
    assert snapshot(folder) == before


@pytest.mark.slow
@pytest.mark.skipif(not Path("/dev/full").exists(), reason="needs /dev/full (Linux)")
def test_a_summary_to_dev_full_replaces_no_file(folder: Path) -> None:
    # the tester's case, as typed: `profileopt plan ... --json > /dev/full`
    (folder / "old.csv").write_text("OLDCSV\n")
    (folder / "old.png").write_text("OLDPNG\n")
    before = snapshot(folder)
    with open("/dev/full", "w") as full:
        done = subprocess.run([*PROFILEOPT, "plan", "route.csv", "-q", "-o", "old.csv", "--plot", "old.png", "--json"],
                              cwd=folder, stdout=full, stderr=subprocess.PIPE, text=True, timeout=120,
                              env=dict(os.environ, MPLBACKEND="Agg"))
    assert done.returncode == 2 and done.stderr.count("\n") == 1, done.stderr
    assert "standard output: cannot write" in done.stderr
    assert snapshot(folder) == before


# --------------------------------------------------------------------------------------
# Outputs that are not regular files are written into, never replaced; '-' is stdout.


@pytest.mark.slow
def test_output_to_standard_output(folder: Path) -> None:
    done = run(folder, "plan", "route.csv", "-o", "-")
    assert done.returncode == 0, done.stderr
    assert run(folder, "plan", "route.csv", "-o", "file.csv").returncode == 0
    assert done.stdout == (folder / "file.csv").read_text()  # the CSV alone; the summary on stderr
    assert "travel time" in done.stderr and "standard output" in done.stderr
    assert not (folder / "-").exists()


def test_a_png_cannot_go_to_standard_output(folder: Path) -> None:
    before = snapshot(folder)
    one_line_exit_2(run(folder, "plan", "route.csv", "--plot", "-"), "--plot -", "standard output")
    assert snapshot(folder) == before


@pytest.mark.slow
def test_a_fifo_output_is_written_into_not_replaced(folder: Path) -> None:
    fifo = folder / "pipe"
    os.mkfifo(fifo)
    received: list[bytes] = []

    def reader() -> None:
        with open(fifo, "rb") as handle:
            received.append(handle.read())

    thread = threading.Thread(target=reader, daemon=True)
    thread.start()
    try:
        done = run(folder, "plan", "route.csv", "-o", "pipe", timeout=60)
    finally:
        if thread.is_alive() and stat.S_ISFIFO(os.lstat(fifo).st_mode):
            os.close(os.open(fifo, os.O_WRONLY | os.O_NONBLOCK))  # release the reader
        thread.join(10)
    assert done.returncode == 0, done.stderr
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)  # still the FIFO
    assert run(folder, "plan", "route.csv", "-o", "file.csv").returncode == 0
    assert received == [(folder / "file.csv").read_bytes()]


@pytest.mark.slow
def test_a_symlink_to_standard_output_is_written_through(folder: Path) -> None:
    os.symlink("/proc/self/fd/1", folder / "out")
    done = run(folder, "plan", "route.csv", "-o", "out")
    assert done.returncode == 0, done.stderr
    assert (folder / "out").is_symlink()
    assert done.stdout.startswith("# profileopt profile:")


@pytest.mark.slow
def test_dev_null_is_written_into_not_replaced(folder: Path) -> None:
    before = os.stat(os.devnull)
    assert stat.S_ISCHR(before.st_mode)
    done = run(folder, "plan", "route.csv", "-o", os.devnull)
    assert done.returncode == 0, done.stderr
    after = os.stat(os.devnull)
    assert stat.S_ISCHR(after.st_mode) and (after.st_ino, after.st_rdev) == (before.st_ino, before.st_rdev)


# --------------------------------------------------------------------------------------
# Empty paths and long names.

EMPTY = {
    "plan -o": ("plan", "route.csv", "-o", ""),
    "plan --plot": ("plan", "route.csv", "--plot", ""),
    "verify -o": ("verify", "route.csv", "profile.csv", "-o", ""),
    "verify --plot": ("verify", "route.csv", "profile.csv", "--plot", ""),
    "export-c -o": ("export-c", "--vehicle", "atv", "-o", ""),
    "figures --out": ("figures", "--out", ""),
}


@pytest.mark.slow
@pytest.mark.parametrize("argv", EMPTY.values(), ids=EMPTY.keys())
def test_an_empty_output_path_is_refused(argv: tuple[str, ...], folder: Path, profile_text: bytes) -> None:
    (folder / "profile.csv").write_bytes(profile_text)
    before = snapshot(folder)
    one_line_exit_2(run(folder, *argv), "''", "empty")
    assert snapshot(folder) == before


@pytest.mark.slow
def test_the_longest_legal_names_are_written(folder: Path) -> None:
    csv, png = "c" * 251 + ".csv", "p" * 251 + ".png"  # 255 bytes each, the limit
    done = run(folder, "plan", "route.csv", "-o", csv, "--plot", png)
    assert done.returncode == 0, done.stderr
    assert (folder / csv).read_text().startswith("# profileopt profile:")
    assert (folder / png).read_bytes().startswith(b"\x89PNG")
    assert sorted(snapshot(folder)) == sorted([csv, png, "my.toml", "route.csv", "sub"])


def test_a_name_too_long_is_one_line(folder: Path) -> None:
    before = snapshot(folder)
    one_line_exit_2(run(folder, "plan", "route.csv", "-o", "c" * 252 + ".csv"), "-o", "too long")
    assert snapshot(folder) == before


# --------------------------------------------------------------------------------------
# SIGTERM: the same clean-up as Ctrl-C.

SLOW_WRITER = textwrap.dedent("""
    import sys, time
    from profileopt import cli
    from profileopt.cli.registry import COMMANDS
    from profileopt.io import atomic_write

    def arguments(parser):
        parser.add_argument("path")

    def run(args):
        with atomic_write(args.path) as handle:
            handle.write("half a file\\n")
            handle.flush()
            open(args.path + ".started", "w").close()
            time.sleep(60)
        return 0

    COMMANDS["slow-write"] = ("__main__", "test")
    sys.exit(cli.main(["slow-write", sys.argv[1]]))
""")


def test_sigterm_while_writing_leaves_no_temporary_file(tmp_path: Path) -> None:
    target = tmp_path / "out.csv"
    target.write_text("a good earlier output\n")
    process = subprocess.Popen([sys.executable, "-c", SLOW_WRITER, str(target)], cwd=tmp_path,
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 60
    while not (tmp_path / "out.csv.started").exists():
        assert process.poll() is None, process.communicate()
        assert time.monotonic() < deadline
        time.sleep(0.05)
    process.send_signal(signal.SIGTERM)
    out, err = process.communicate(timeout=30)
    assert process.returncode == 143, (process.returncode, err)
    assert err.splitlines() == ["profileopt slow-write: terminated"]
    assert target.read_text() == "a good earlier output\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.csv", "out.csv.started"]


# --------------------------------------------------------------------------------------
# Inputs that are not regular files, or too large: one line, exit 2, no hang.

NOT_REGULAR = {
    "route /dev/zero": (("plan", "/dev/zero"), "/dev/zero"),
    "route /dev/urandom": (("plan", "/dev/urandom"), "/dev/urandom"),
    "vehicle /dev/zero": (("plan", "route.csv", "--vehicle", "/dev/zero"), "/dev/zero"),
    "profile /dev/zero": (("verify", "route.csv", "/dev/zero", "--vehicle", "atv"), "/dev/zero"),
    "route FIFO": (("plan", "fifo"), "fifo"),
    "vehicle FIFO": (("plan", "route.csv", "--vehicle", "sub/fifo.toml"), "fifo.toml"),
    "compare route FIFO": (("compare", "fifo"), "fifo"),
}


@pytest.mark.slow
@pytest.mark.parametrize("argv,name", NOT_REGULAR.values(), ids=NOT_REGULAR.keys())
def test_an_input_that_is_not_a_regular_file_is_refused(argv: tuple[str, ...], name: str, folder: Path) -> None:
    os.mkfifo(folder / "fifo")  # no writer: reading it would block for ever
    os.mkfifo(folder / "sub" / "fifo.toml")
    one_line_exit_2(run(folder, *argv, timeout=60), name, "not a regular file")


@pytest.mark.parametrize("what", ["route", "profile", "vehicle"])
def test_an_input_above_the_size_cap_is_refused_before_reading(what: str, folder: Path) -> None:
    from profileopt.io.inputs import MAX_TABLE_BYTES, MAX_VEHICLE_BYTES

    big = folder / ("big.toml" if what == "vehicle" else "big.csv")
    with open(big, "wb") as handle:  # sparse: no disk space, no time; read, it is all zero bytes
        handle.truncate((MAX_VEHICLE_BYTES if what == "vehicle" else MAX_TABLE_BYTES) + 1)
    argv = {"route": ("plan", "big.csv"), "profile": ("verify", "route.csv", "big.csv", "--vehicle", "atv"),
            "vehicle": ("plan", "route.csv", "--vehicle", "big.toml")}[what]
    one_line_exit_2(run(folder, *argv, timeout=60), "big.", "MB", "larger than", "split it")


# --------------------------------------------------------------------------------------
# export-c: the size of the C files is capped and said before any work.


def test_export_c_refuses_a_huge_horizon_saying_its_size(folder: Path) -> None:
    started = time.monotonic()
    line = one_line_exit_2(run(folder, "export-c", "--vehicle", "atv", "-o", "cout", "--stages", "100000"),
                           "--stages = 100000", "MB", "at most")
    assert time.monotonic() - started < 30
    assert "2,368 MB" in line  # 23.7 kB per stage for the four models
    assert not (folder / "cout").exists()


def test_export_c_within_the_cap_still_works(folder: Path) -> None:
    done = run(folder, "export-c", "--vehicle", "atv", "-o", "cout", "--stages", "3", "--model", "prev_bem")
    assert done.returncode == 0, done.stderr
    assert sorted(p.name for p in (folder / "cout").iterdir()) == ["README.md", "example.c", "profileopt_atv.c",
                                                                   "profileopt_atv.h"]


# --------------------------------------------------------------------------------------
# Output people read (issue 30, items 14 and 17): plan's JSON names the route and the
# vehicle; a .jpg plot is a JPEG; make_routes.py --out creates its folder as figures does.


def test_plan_json_names_route_and_vehicle(capsys: pytest.CaptureFixture) -> None:
    import json

    from profileopt.cli import main

    assert main(["plan", str(ROUTE), "--vehicle", "atv", "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert (summary["route"], summary["vehicle"]) == (str(ROUTE), "atv")
    assert list(summary)[:2] == ["route", "vehicle"]  # first, as compare's JSON
    assert all(m["ratio"] is None or m["ratio"] <= 1.0 for m in summary["margins"].values())


@pytest.mark.slow  # a plan and a picture
def test_a_jpg_plot_is_a_jpeg(tmp_path: Path) -> None:
    from profileopt.cli import main

    assert main(["plan", str(ROUTE), "--quiet", "--plot", str(tmp_path / "plan.jpg")]) == 0
    assert (tmp_path / "plan.jpg").read_bytes()[:3] == b"\xff\xd8\xff"  # before: PNG bytes


def _make_routes(monkeypatch: pytest.MonkeyPatch):  # noqa: ANN202  (the script's module)
    import importlib.util

    spec = importlib.util.spec_from_file_location("make_routes", ROUTES / "make_routes.py")
    module = importlib.util.module_from_spec(spec)
    monkeypatch.setitem(sys.modules, "make_routes", module)  # its dataclasses look themselves up there
    spec.loader.exec_module(module)
    return module


def test_make_routes_creates_its_out_folder(tmp_path: Path, capsys: pytest.CaptureFixture,
                                            monkeypatch: pytest.MonkeyPatch) -> None:
    out = tmp_path / "new" / "routes"  # before: refused, "not a folder; create it"
    make_routes = _make_routes(monkeypatch)
    assert make_routes.main(["--out", str(out), "--no-real", "--quiet"]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["curb.csv", "trail.csv", "washboard.csv"]
    (tmp_path / "taken").write_text("x")
    assert make_routes.main(["--out", str(tmp_path / "taken"), "--no-real", "--quiet"]) == 2
    assert capsys.readouterr().err.splitlines() == [f"error: --out {tmp_path / 'taken'}: exists and is not a folder; "
                                                    "give a folder path"]
