"""The progress display (issue 30, item 13): shown on a terminal for long work, never in a
file, silenced by --quiet; a missing tqdm is said once; the planner tells its steps."""

from __future__ import annotations

import builtins
import io
import sys

import pytest

import profileopt.progress as progress_module
from conftest import ROUTES
from profileopt import load_vehicle, plan, read_route
from profileopt.cli import main
from profileopt.progress import MISSING_TQDM, NO_PROGRESS, Progress, terminal_progress

CURB = str(ROUTES / "curb.csv")  # 200 m: a plan in a fraction of a second


class Terminal(io.StringIO):
    """A stderr that says it is a terminal."""

    def isatty(self) -> bool:
        return True


class Recorder(Progress):
    def __init__(self) -> None:
        self.expected = 0
        self.steps: list[str] = []

    def expect(self, steps: int) -> None:
        self.expected += steps

    def step(self, name: str) -> None:
        self.steps.append(name)


@pytest.fixture
def no_delay(monkeypatch: pytest.MonkeyPatch) -> None:
    """Show the display at once (the work of a test is shorter than the 2 s delay)."""
    monkeypatch.setattr(progress_module, "PROGRESS_DELAY_S", 0.0)
    monkeypatch.delenv(progress_module.PROGRESS_ENV, raising=False)


def test_the_planner_tells_its_steps_within_what_it_expects() -> None:
    seen = Recorder()
    plan(read_route(CURB), load_vehicle("atv"), progress=seen)
    # cutting, path, bands, refining, bands again, solving, simulating
    assert seen.steps[0].startswith("cutting 200 m") and seen.steps[-1] == "simulating the plan", seen.steps
    assert any("refined" in step for step in seen.steps) and any(s.startswith("solving") for s in seen.steps)
    assert len(seen.steps) <= seen.expected


def test_a_display_on_a_terminal_names_the_steps(no_delay: None) -> None:
    stream = Terminal()
    with terminal_progress("work", stream=stream) as shown:
        assert shown is not NO_PROGRESS
        shown.expect(2)
        shown.step("first thing")
        shown.step("second thing")
    text = stream.getvalue()
    assert "work: step" in text and "second thing" in text, text


def test_no_display_in_a_file_or_when_disabled(no_delay: None) -> None:
    for stream, enabled in ((io.StringIO(), True), (Terminal(), False)):
        with terminal_progress("work", stream=stream, enabled=enabled) as shown:
            assert shown is NO_PROGRESS
        assert stream.getvalue() == ""


def test_the_environment_forces_the_display_on_or_off(no_delay: None, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv(progress_module.PROGRESS_ENV, "1")
    with terminal_progress("work", stream=io.StringIO()) as shown:
        assert shown is not NO_PROGRESS
    monkeypatch.setenv(progress_module.PROGRESS_ENV, "0")
    with terminal_progress("work", stream=Terminal()) as shown:
        assert shown is NO_PROGRESS


def test_short_work_shows_nothing(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv(progress_module.PROGRESS_ENV, raising=False)
    stream = Terminal()
    with terminal_progress("work", stream=stream) as shown:  # the real 2 s delay
        shown.expect(1)
        shown.step("quick")
    assert "quick" not in stream.getvalue()


def test_a_missing_tqdm_is_said_once_and_the_work_goes_on(no_delay: None, monkeypatch: pytest.MonkeyPatch) -> None:
    real_import = builtins.__import__

    def without_tqdm(name, *args, **kwargs):  # noqa: ANN001, ANN002, ANN003, ANN202
        if name == "tqdm" or name.startswith("tqdm."):
            raise ImportError("No module named 'tqdm'")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", without_tqdm)
    monkeypatch.setattr(progress_module, "_said_missing", False)
    stream = Terminal()
    for _ in range(2):
        with terminal_progress("profileopt plan", stream=stream) as shown:
            assert shown is NO_PROGRESS
    assert stream.getvalue().splitlines() == [f"profileopt plan: {MISSING_TQDM}"]
    assert "pip install 'profileopt[progress]'" in MISSING_TQDM


def test_plan_shows_progress_on_a_terminal_and_quiet_silences_it(no_delay: None, monkeypatch: pytest.MonkeyPatch,
                                                                 capsys: pytest.CaptureFixture, tmp_path) -> None:
    # a boundary speed within rounding of the band edge: planned at the edge, with a note
    argv = ["plan", CURB, "--v0", "12.000005", "-o", str(tmp_path / "p.csv")]
    stderr = Terminal()
    monkeypatch.setattr(sys, "stderr", stderr)
    assert main(argv) == 0
    assert "profileopt plan: step" in stderr.getvalue() and "simulating the plan" in stderr.getvalue()
    # the note names the flag, not the library's parameter
    assert "note: --v0 = 12.000005 m/s" in stderr.getvalue() and "v0_mps" not in stderr.getvalue()

    quiet = Terminal()
    monkeypatch.setattr(sys, "stderr", quiet)
    assert main([*argv, "--quiet"]) == 0
    assert quiet.getvalue() == ""
    assert "travel time" in capsys.readouterr().out  # the summary is still printed


def test_plan_shows_no_progress_when_stderr_is_a_file(no_delay: None, capsys: pytest.CaptureFixture) -> None:
    assert main(["plan", CURB]) == 0
    assert "profileopt plan: step" not in capsys.readouterr().err


def test_verify_shows_progress_on_a_terminal_and_quiet_silences_it(no_delay: None, monkeypatch: pytest.MonkeyPatch,
                                                                   capsys: pytest.CaptureFixture, tmp_path) -> None:
    # issue 30, second round: verify of a big route worked for seconds showing nothing, and had
    # no --quiet (unrecognized)
    profile = tmp_path / "p.csv"
    assert main(["plan", CURB, "-o", str(profile), "-q"]) == 0
    stderr = Terminal()
    monkeypatch.setattr(sys, "stderr", stderr)
    # another vehicle than the one planned with: a note in the summary
    assert main(["verify", CURB, str(profile), "--vehicle", "atv-resonant"]) in (0, 3, 4)
    assert "profileopt verify: step" in stderr.getvalue() and "simulating the drive" in stderr.getvalue()
    assert "note:" in capsys.readouterr().out
    for flag in ("-q", "--quiet"):
        quiet = Terminal()
        monkeypatch.setattr(sys, "stderr", quiet)
        assert main(["verify", CURB, str(profile), "--vehicle", "atv-resonant", flag]) in (0, 3, 4)
        assert quiet.getvalue() == ""
        out = capsys.readouterr().out
        assert "verdict:" in out and "note:" not in out  # the verdict is still said, the notes are not


def _track_over_a_cloud(tmp_path):  # noqa: ANN001, ANN202
    pytest.importorskip("laspy")
    from geo_data import cloud_points, track_utm_m, write_gpx, write_laz

    cloud = write_laz(tmp_path / "cloud.laz", *cloud_points(density_per_m2=300.0))
    track = write_gpx(tmp_path / "track.gpx", *track_utm_m())
    return track, cloud


def test_route_and_plan_show_the_terrain_being_read_and_sampled(no_delay: None, monkeypatch: pytest.MonkeyPatch,
                                                                tmp_path) -> None:
    # issue 30, second round: route over a large cloud ran 21 s with no display, and plan's bar
    # started only once the terrain was sampled
    track, cloud = _track_over_a_cloud(tmp_path)
    for argv in (["route", str(track), "--terrain", str(cloud), "-o", str(tmp_path / "r.csv")],
                 ["plan", str(track), "--terrain", str(cloud), "-o", str(tmp_path / "p.csv")]):
        stderr = Terminal()
        monkeypatch.setattr(sys, "stderr", stderr)
        assert main(argv) == 0, stderr.getvalue()
        text = stderr.getvalue()
        prog = f"profileopt {argv[0]}: step"
        assert f"{prog}" in text and "reading the terrain (cloud.laz)" in text and \
            "sampling the ground along the track" in text, text
        # the notes are printed above the display, each on a line of its own
        notes = [line for line in text.replace("\r", "\n").splitlines() if "note:" in line]
        assert notes and all(line.startswith(f"profileopt {argv[0]}: note: ") for line in notes), notes
        quiet = Terminal()
        monkeypatch.setattr(sys, "stderr", quiet)
        assert main([*argv, "-q"]) == 0
        assert quiet.getvalue() == ""


def test_a_line_is_printed_above_a_shown_display(no_delay: None) -> None:
    from profileopt.progress import print_line

    stream = Terminal()
    with terminal_progress("work", stream=stream) as shown:
        shown.expect(2)
        shown.step("first thing")
        print_line(shown, "a note", stream)
        shown.step("second thing")
    text = stream.getvalue()
    before, after = text.split("a note\n")
    assert before.endswith("\r") and "first thing" in before and "second thing" in after, repr(text)
    plain = io.StringIO()
    print_line(NO_PROGRESS, "a note", plain)
    assert plain.getvalue() == "a note\n"
