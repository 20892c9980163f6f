"""profileopt.cli.app: the command line's own errors (issue 30, items 2, 11 and 17).

A misspelt option is refused by the sub-command that was meant, naming the nearest option; a
write that finds no room, standard output full or closed, is one line and exit 2; Ctrl-C while
the command line is still being read is one line and 130, never a traceback.
"""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

import pytest

from profileopt import cli

from conftest import PROFILEOPT, ROUTES


def refusal(capsys: pytest.CaptureFixture, argv: list[str]) -> str:
    """The one line of a command line argparse refuses (exit status 2)."""
    with pytest.raises(SystemExit) as stop:
        cli.main(argv)
    assert stop.value.code == 2
    lines = capsys.readouterr().err.splitlines()
    assert len(lines) == 1, lines
    return lines[0]


@pytest.mark.parametrize("argv, words", [
    (["plan", "r.csv", "--segment-lenght", "2"],
     "profileopt plan: error: unrecognized arguments: --segment-lenght 2; did you mean --segment-length?"),
    (["verify", "r.csv", "p.csv", "--sed=3"], "profileopt verify: error: unrecognized arguments: --sed=3; did you "
                                              "mean --seed?"),
    (["plan", "r.csv", "--zzzz"], "profileopt plan: error: unrecognized arguments: --zzzz (see"),
    (["paln", "r.csv"], "did you mean plan?"),
    (["plan", "r.csv", "--model", "sbem_fT"], "did you mean sbem_tf?"),
    # --terrain takes several files (tiles): a route after them is taken for one more
    (["plan", "--terrain", "a.laz", "b.laz", "track.gpx"], "required: route; --terrain takes one or more files, so "
                                                             "give the route before it"),
    (["route", "--terrain", "tiles", "track.gpx", "-o", "r.csv"], "give the route before it"),
])
def test_a_misspelt_option_names_its_command_and_the_nearest_option(capsys: pytest.CaptureFixture,
                                                                   argv: list[str], words: str) -> None:
    assert words in refusal(capsys, argv)


def test_ctrl_c_while_the_command_line_is_read_is_one_line(capsys: pytest.CaptureFixture,
                                                         monkeypatch: pytest.MonkeyPatch) -> None:
    from profileopt.cli import app

    def interrupted() -> None:
        raise KeyboardInterrupt

    monkeypatch.setattr(app, "build_parser", interrupted)
    assert cli.main(["plan", "r.csv"]) == 130
    assert capsys.readouterr().err == "profileopt: interrupted\n"


def test_a_full_disk_while_an_output_is_written_is_exit_2_naming_it(tmp_path: Path, capsys: pytest.CaptureFixture,
                                                                    monkeypatch: pytest.MonkeyPatch) -> None:
    """The disk fills while the profile is written: one line naming the output, exit 2, and
    the earlier file there is kept (the outputs are all or none)."""
    from profileopt.io import atomic
    from profileopt.cli import plan as plan_command

    out = tmp_path / "out.csv"
    out.write_text("a good earlier profile\n")

    def disk_full(args) -> int:  # noqa: ANN001  (what write_profile meets on a full disk)
        with atomic.OutputSet([("-o", str(out), True)]):
            with atomic.atomic_write(out) as handle:
                handle.write("half")
                raise OSError(28, "No space left on device")

    monkeypatch.setattr(plan_command, "run", disk_full)
    assert cli.main(["plan", "r.csv"]) == 2
    assert capsys.readouterr().err == (f"profileopt plan: error: -o {out}: cannot write it (No space left on "
                                       "device); nothing was written, free some space or choose another output\n")
    assert out.read_text() == "a good earlier profile\n"


# --------------------------------------------------------------------------------------
# Standard output full or closed: the real command line, in a subprocess.


@pytest.fixture(scope="module")
def short_route(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The first 30 m of the bundled curb course (a plan in a fraction of a second)."""
    lines = (ROUTES / "curb.csv").read_text().splitlines()
    keep = [line for line in lines if not line[:1].isdigit() or float(line.split(",")[0]) <= 30.0]
    path = tmp_path_factory.mktemp("app") / "route.csv"
    path.write_text("\n".join(keep) + "\n")
    return path


@pytest.mark.slow
@pytest.mark.skipif(not Path("/dev/full").exists(), reason="needs /dev/full (Linux)")
def test_the_summary_to_a_full_standard_output_is_one_line(short_route: Path) -> None:
    with open("/dev/full", "w") as full:
        done = subprocess.run([*PROFILEOPT, "plan", str(short_route)], stdout=full, stderr=subprocess.PIPE,
                              text=True, timeout=120)
    assert done.returncode == 2, done.stderr
    errors = [line for line in done.stderr.splitlines() if "note:" not in line]
    assert errors == ["profileopt plan: error: standard output: cannot write (No space left on device); free some "
                      "space or send standard output elsewhere"]


@pytest.mark.slow
def test_the_profile_to_a_closed_standard_output_is_refused(short_route: Path) -> None:
    done = subprocess.run([*PROFILEOPT, "plan", str(short_route), "-o", "-"], stderr=subprocess.PIPE, text=True,
                          timeout=120, preexec_fn=lambda: os.close(1))
    assert done.returncode == 2, done.stderr
    assert done.stderr.splitlines() == ["profileopt plan: error: -o -: standard output is closed; give the path of "
                                        "a file to write"]


@pytest.mark.slow
def test_a_route_name_that_is_not_utf8_is_drawn(short_route: Path, tmp_path: Path,
                                               capsys: pytest.CaptureFixture) -> None:
    """A file name with bytes that are not UTF-8 (a lone surrogate to Python, which
    matplotlib's fonts refuse) is titled with U+FFFD, not an internal error."""
    name = tmp_path / os.fsdecode(b"r\xff\xfe.csv")
    name.write_bytes(short_route.read_bytes())
    picture = tmp_path / "plan.png"
    assert cli.main(["plan", str(name), "--plot", str(picture), "-q"]) == 0, capsys.readouterr().err
    assert picture.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_printable_replaces_only_what_is_not_utf8() -> None:
    from profileopt.cli.messages import printable

    assert printable(os.fsdecode(b"r\xff.csv")) == "r\ufffd.csv"
    assert printable("route é.csv") == "route é.csv"


@pytest.mark.parametrize("argv, words", [
    (["verify", "r.csv", "p.csv", "--seed", "\u0661"], "argument --seed: '\\u0661' is not a whole number (digits 0-9)"),
    (["verify", "r.csv", "p.csv", "--seed", "-1"], "argument --seed: -1: give a seed >= 0"),
    (["batch", "r.csv", "-o", "out", "--workers", "0"], "argument --workers: 0: give a number of workers >= 1"),
    (["plan", "r.csv", "--track-index", "1_0"], "argument --track-index: '1_0' is not a whole number"),
])
def test_whole_number_options_take_ascii_digits_only(capsys: pytest.CaptureFixture, argv: list[str],
                                                   words: str) -> None:
    assert words in refusal(capsys, argv)


def test_a_missing_route_without_terrain_gets_no_terrain_hint(capsys: pytest.CaptureFixture) -> None:
    assert refusal(capsys, ["plan"]) == ("profileopt plan: error: the following arguments are required: route "
                                         "(see 'profileopt plan --help')")


def test_names_that_are_not_utf8_are_written_with_u_fffd(short_route: Path, tmp_path: Path,
                                                        capsys: pytest.CaptureFixture) -> None:
    """issue 30, second round: every place a command writes a file name (CSV comment and
    header lines, a picture's title) takes one whose bytes are not UTF-8: before, route, verify
    -o and --plot and drive -o were internal errors (UnicodeEncodeError, matplotlib's
    TypeError)."""
    route = tmp_path / os.fsdecode(b"r\xff\xfe.csv")
    route.write_bytes(short_route.read_bytes())
    track = tmp_path / os.fsdecode(b"g\xff.gpx")
    track.write_text('<?xml version="1.0"?><gpx version="1.1" creator="t"><trk><trkseg><trkpt lat="46.0" '
                     'lon="13.0"><ele>100</ele></trkpt><trkpt lat="46.0005" lon="13.0"><ele>101</ele></trkpt>'
                     '</trkseg></trk></gpx>')
    made = tmp_path / "made.csv"
    assert cli.main(["route", str(track), "--roughness-class", "C", "-o", str(made), "-q"]) == 0, \
        capsys.readouterr().err
    assert "g\ufffd.gpx (2 points" in made.read_text(encoding="utf-8")
    profile = tmp_path / "p.csv"
    assert cli.main(["plan", str(route), "-o", str(profile), "-q"]) == 0
    table, picture = tmp_path / "v.csv", tmp_path / "v.png"
    assert cli.main(["verify", str(route), str(profile), "-o", str(table), "--plot", str(picture)]) == 0, \
        capsys.readouterr().err
    assert table.read_text(encoding="utf-8").startswith("# profileopt verify: route r\ufffd\ufffd.csv, vehicle atv")
    assert picture.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    driven = tmp_path / "d.csv"
    assert cli.main(["drive", str(route), "-o", str(driven), "-q"]) == 0, capsys.readouterr().err
    assert driven.read_text(encoding="utf-8").startswith("# drive: route=r\ufffd\ufffd.csv vehicle=atv")
    capsys.readouterr()
    # batch writes every name into its summary and cache keys: refused, one line
    assert cli.main(["batch", str(route), "-o", str(tmp_path / "out"), "--workers", "1"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "the name of a route has bytes that are not UTF-8" in err, err


def test_a_closed_standard_output_is_refused_before_any_work(short_route: Path, tmp_path: Path) -> None:
    # issue 30, second round: 'plan route.csv >&-' exited 0 and the summary was lost
    out = tmp_path / "p.csv"
    done = subprocess.run([*PROFILEOPT, "plan", str(short_route), "-o", str(out)], stderr=subprocess.PIPE, text=True,
                          timeout=120, preexec_fn=lambda: os.close(1))
    assert done.returncode == 2, done.stderr
    assert done.stderr.splitlines() == ["profileopt plan: error: standard output is closed, and the command prints "
                                        "its summary there; run it with standard output open ('> /dev/null' "
                                        "discards it)"]
    assert not out.exists()


def test_running_out_of_memory_is_one_line_exit_2(monkeypatch: pytest.MonkeyPatch,
                                                 capsys: pytest.CaptureFixture) -> None:
    # issue 30, second round: 'prlimit --as=4000000000 profileopt plan sz1250.csv' ended with
    # 'internal error: MemoryError' (exit 1) after 72 s; the estimate now refuses it before any
    # work, and whatever still runs out of memory is one line, exit 2
    from profileopt.cli import plan as command

    def exhausted(args):  # noqa: ANN001, ANN202
        raise MemoryError

    monkeypatch.setattr(command, "run", exhausted)
    assert cli.main(["plan", str(ROUTES / "curb.csv")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("profileopt plan: error: ran out of memory; nothing was written")


_REUSE_SCRIPT = """
import ctypes, resource, sys
from profileopt.cli.app import keep_arrays_on_the_heap
if sys.argv[1] != "default":
    keep_arrays_on_the_heap(int(sys.argv[1]))
libc = ctypes.CDLL(None)
libc.malloc.restype, libc.malloc.argtypes = ctypes.c_void_p, (ctypes.c_size_t,)
libc.free.argtypes = (ctypes.c_void_p,)
size = 100 * 2**20

def faults_to_fill_a_fresh_block():
    before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
    block = libc.malloc(size)
    ctypes.memset(block, 1, size)
    libc.free(block)
    return resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before

print(faults_to_fill_a_fresh_block(), faults_to_fill_a_fresh_block())
"""


@pytest.mark.skipif(not os.uname().sysname == "Linux" or os.confstr("CS_GNU_LIBC_VERSION") is None,
                    reason="glibc's mallopt")
def test_the_command_keeps_a_freed_100_mb_block_for_reuse_and_a_worker_does_not() -> None:
    """At the command's threshold (1 GiB) a freed 100 MB block (an IPOPT workspace at 100,000
    segments) is filled again without a page fault; at a worker's (32 MiB, glibc's own ceiling)
    it is mapped afresh and faulted in again, as with no setting at all."""
    import sys

    from profileopt.cli.app import MMAP_THRESHOLD_BYTES, WORKER_MMAP_THRESHOLD_BYTES

    def faults(threshold: str) -> tuple[int, int]:
        done = subprocess.run([sys.executable, "-c", _REUSE_SCRIPT, threshold], capture_output=True, text=True,
                              timeout=120, check=True)
        first, second = (int(word) for word in done.stdout.split())
        return first, second

    glibc = tuple(int(part) for part in os.confstr("CS_GNU_LIBC_VERSION").split()[1].split(".")[:2])
    first, second = faults(str(MMAP_THRESHOLD_BYTES))
    if glibc >= (2, 35):  # before, glibc refuses a threshold above 32 MiB: the worker's is set
        assert first > 0 and second <= 0.05 * first, (first, second)
    else:
        assert second > 0.5 * first > 0, (first, second)
    for threshold in (str(WORKER_MMAP_THRESHOLD_BYTES), "default"):
        first, second = faults(threshold)
        assert second > 0.5 * first > 0, (threshold, first, second)


@pytest.mark.parametrize("threshold", [0, -1, 2**31, 2**32 + 5])
def test_a_heap_threshold_that_is_no_c_int_is_refused(threshold: int) -> None:
    from profileopt.cli.app import keep_arrays_on_the_heap

    with pytest.raises(ValueError, match="mmap_threshold_bytes"):
        keep_arrays_on_the_heap(threshold)


@pytest.mark.parametrize("ceiling, expected", [
    (2**31, [(-3, 2**30), (-1, 2**31 - 1)]),  # glibc 2.35 and later: 1 GiB, trim above 2 GiB
    (2**25, [(-3, 2**30), (-3, 2**25), (-1, 2**26)]),  # before 2.35: 1 GiB refused, 32 MiB set
    (0, [(-3, 2**30), (-3, 2**25)]),  # nothing held: the trim threshold left alone
])
def test_a_refused_heap_threshold_falls_back_to_the_workers_and_never_sets_trim_alone(
        monkeypatch: pytest.MonkeyPatch, ceiling: int, expected: list) -> None:
    """glibc before 2.35 refuses an mmap threshold above 32 MiB; setting the trim threshold
    anyway would turn its dynamic rule off with the threshold stuck at 128 kB."""
    import ctypes

    from profileopt.cli import app

    calls = []

    class FakeMallopt:
        argtypes = restype = None

        def __call__(self, option: int, value: int) -> int:
            calls.append((option, value))
            return 1 if option == -1 or value <= ceiling else 0

    class FakeLibc:
        mallopt = FakeMallopt()

    monkeypatch.setattr(app.sys, "platform", "linux")
    monkeypatch.setattr(ctypes, "CDLL", lambda name: FakeLibc())
    app.keep_arrays_on_the_heap(app.MMAP_THRESHOLD_BYTES)
    assert calls == expected
