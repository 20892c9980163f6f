"""Progress of long work: what the planner and the studies report, and its display on stderr.

The library reports progress through :class:`Progress`: the work says how many steps it
expects (:meth:`Progress.expect`) and names each step as it starts (:meth:`Progress.step`).
The base class does nothing (:data:`NO_PROGRESS`, every function's default), so the library
knows nothing of terminals. The command line passes :func:`terminal_progress`: a tqdm bar
on stderr, shown only when stderr is a terminal and only once the work has taken
:data:`PROGRESS_DELAY_S` (short work prints nothing). tqdm is the ``progress`` extra
(``pip install 'profileopt[progress]'``) and is imported only when a bar may be shown; when it
is missing, one line says so, once, and the work goes on without a display.
"""

from __future__ import annotations

import contextlib
import os
import sys
import threading
import time
from typing import IO, Iterator

__all__ = ["Progress", "NO_PROGRESS", "terminal_progress", "print_line", "PROGRESS_DELAY_S", "PROGRESS_ENV",
           "MISSING_TQDM"]

#: Seconds of work before a display appears (work shorter than this prints nothing).
PROGRESS_DELAY_S = 2.0
#: Seconds between refreshes of a shown display while one step runs (its clock keeps moving).
REFRESH_S = 0.5
#: Environment variable: ``1`` shows the display whether or not stderr is a terminal (for a
#: log a person watches), ``0`` never shows it; unset: only on a terminal.
PROGRESS_ENV = "PROFILEOPT_PROGRESS"
#: The one line said when a display is wanted and tqdm is not installed.
MISSING_TQDM = ("note: install the progress display with pip install 'profileopt[progress]' (tqdm); "
                "going on without it")
_said_missing = False  # the line above is said once per process


class Progress:
    """What long work reports as it goes: this base ignores it (the library's default).

    Subclass it to show progress in your own program; the planner
    (:func:`profileopt.plan`) and the studies call :meth:`expect` and :meth:`step`.
    """

    def expect(self, steps: int) -> None:
        """More steps are expected (added to those expected before).

        Parameters
        ----------
        steps : int
            How many more steps the work will report.
        """

    def step(self, name: str) -> None:
        """A step starts (the one before it, if any, is done).

        Parameters
        ----------
        name : str
            What the step does, in a few words ("simulating the plan").
        """


#: The progress that reports nothing: every function's default.
NO_PROGRESS = Progress()


def wanted(stream: IO[str], force: bool | None = None) -> bool:
    """Whether a display on ``stream`` is wanted: ``force`` if given, else
    :data:`PROGRESS_ENV` if set to 0 or 1, else whether ``stream`` is a terminal.

    Parameters
    ----------
    stream : file object
        Where the display would go (stderr).
    force : bool, optional
        True: as if ``stream`` were a terminal; False: never.

    Returns
    -------
    bool
    """
    if force is not None:
        return bool(force)
    env = os.environ.get(PROGRESS_ENV, "").strip()
    if env in ("0", "1"):
        return env == "1"
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError, OSError):  # no isatty, or a closed stream
        return False


class _TqdmProgress(Progress):
    """A tqdm bar of steps, shown after :data:`PROGRESS_DELAY_S`; a thread refreshes it while
    a long step runs (tqdm itself redraws only when a step starts)."""

    def __init__(self, tqdm_class: type, label: str, stream: IO[str], delay_s: float) -> None:
        self._lock = threading.Lock()
        self._stream = stream
        self._started = False
        self._bar = tqdm_class(total=0, desc=label, file=stream, delay=delay_s, leave=False, mininterval=0.0,
                               miniters=1, dynamic_ncols=True,
                               bar_format="{desc}: step {n_fmt}/{total_fmt} |{bar}| {elapsed}{postfix}")
        self._shown_after = time.monotonic() + delay_s
        self._stop = threading.Event()
        self._ticker = threading.Thread(target=self._tick, name="profileopt-progress", daemon=True)
        self._ticker.start()

    def _tick(self) -> None:
        while not self._stop.wait(REFRESH_S):
            if time.monotonic() >= self._shown_after:
                with self._lock:
                    if not self._stop.is_set():
                        self._bar.refresh()

    def expect(self, steps: int) -> None:
        with self._lock:
            self._bar.total += int(steps)

    def step(self, name: str) -> None:
        with self._lock:
            if self._started:
                self._bar.update(1)
            self._started = True
            if self._bar.n >= self._bar.total:  # more steps than expected: never above 100 %
                self._bar.total = self._bar.n + 1
            self._bar.set_postfix_str(name, refresh=False)
            if time.monotonic() >= self._shown_after:
                self._bar.refresh()

    def write(self, text: str, stream: IO[str]) -> None:
        """Print a line on ``stream`` above the display: the bar is cleared first and drawn
        again after it, so that the line does not run into the bar."""
        with self._lock:
            shown = time.monotonic() >= self._shown_after and stream is self._stream
            if shown:
                self._bar.clear()
            print(text, file=stream, flush=True)
            if shown:
                self._bar.refresh()

    def close(self) -> None:
        self._stop.set()
        self._ticker.join()
        with self._lock:
            self._bar.close()


def print_line(progress: Progress, text: str, stream: IO[str] | None = None) -> None:
    """Print a line (a note) on ``stream`` while ``progress`` may be shown there: above the
    display, which is cleared and drawn again, instead of running into it.

    Parameters
    ----------
    progress : Progress
        The display the work reports to (:func:`terminal_progress`'s, or any other).
    text : str
        The line, without its end.
    stream : file object, optional
        Where; default ``sys.stderr`` at the time of the call.
    """
    stream = sys.stderr if stream is None else stream
    if isinstance(progress, _TqdmProgress):
        progress.write(text, stream)
    else:
        print(text, file=stream)


@contextlib.contextmanager
def terminal_progress(label: str, *, enabled: bool = True, stream: IO[str] | None = None,
                      force: bool | None = None) -> Iterator[Progress]:
    """A progress display on stderr for the work inside the ``with`` block.

    It is shown when ``enabled``, and stderr is a terminal (or ``force``, or
    :data:`PROGRESS_ENV` says so), and the work takes more than :data:`PROGRESS_DELAY_S`;
    it is cleared when the block ends. Otherwise the block gets :data:`NO_PROGRESS`. When a
    display is wanted and tqdm is missing, :data:`MISSING_TQDM` is said once on stderr.

    Parameters
    ----------
    label : str
        What the work is, shown before the bar ("profileopt plan").
    enabled : bool, default True
        False (``--quiet``): no display at all.
    stream : file object, optional
        Where the display goes; default ``sys.stderr`` at the time of the call.
    force : bool, optional
        True: as if ``stream`` were a terminal; False: never (:func:`wanted`).

    Yields
    ------
    Progress
    """
    global _said_missing
    stream = sys.stderr if stream is None else stream
    if not (enabled and wanted(stream, force)):
        yield NO_PROGRESS
        return
    try:
        from tqdm import tqdm
    except ImportError:
        if not _said_missing:
            _said_missing = True
            print(f"{label}: {MISSING_TQDM}", file=stream)
        yield NO_PROGRESS
        return
    shown = _TqdmProgress(tqdm, label, stream, PROGRESS_DELAY_S)
    try:
        yield shown
    finally:
        shown.close()
