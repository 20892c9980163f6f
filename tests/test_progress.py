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
