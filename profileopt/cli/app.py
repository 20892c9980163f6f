"""The ``profileopt`` command: a thin layer that parses arguments, calls the library and
formats its output.

Every user mistake surfaces as :class:`~profileopt.errors.InputError`: one line on stderr,
exit status 2, no traceback (``--debug`` shows one). Anything else is an internal error:
one line, exit status 1.

Exit statuses: 0 success, 1 internal error, 2 bad input, 130 interrupted. ``profileopt
verify`` is a gate and adds two: 3 when the profile breaks one of the vehicle's own limits
(speed, acceleration, jerk, predicted force) and 4 when the limits hold on paper but the
simulation puts a segment over the force limit; its 0 means the plan keeps every limit and
no simulated force exceeds the limit
(:data:`profileopt.cli.verify.VERIFY_EXIT_STATUSES`). ``compare`` is a report: 0.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import re
import signal
import sys
import traceback
from typing import NoReturn, Sequence

from .. import __version__
from ..errors import InputError
from .messages import flags_for_parameters
from .registry import COMMANDS, load_command

#: The command's mmap threshold (bytes): arrays and solver workspaces up to 1 GiB are taken from
#: the heap and reused once freed (:func:`keep_arrays_on_the_heap`).
MMAP_THRESHOLD_BYTES = 1024 * 1024 * 1024
#: A batch worker's (bytes): glibc's ceiling for its own dynamic threshold on 64-bit
#: (``DEFAULT_MMAP_THRESHOLD_MAX``); a long-lived worker returns freed memory above twice it.
WORKER_MMAP_THRESHOLD_BYTES = 32 * 1024 * 1024

__all__ = ["main", "build_parser"]

#: The arguments being parsed (:func:`_parse`), for :meth:`_Parser.error`'s hints.
_ARGV: list[str] = []


class _Parser(argparse.ArgumentParser):
    """An argument parser whose errors are one line (no usage block), exit status 2."""

    def error(self, message: str) -> NoReturn:
        # argparse's words for a value given to a switch (--refine=yes) read as if it ran on
        switch = re.fullmatch(r"argument (\S+?)(?:/(\S+))?: ignored explicit argument '(.*)'", message)
        if switch:
            names = [name for name in switch.groups()[:2] if name]
            message = f"{'/'.join(names)} takes no value ('{switch.group(3)}' given): write {' or '.join(names)}"
        missing = message.split(": ", 1)[1].split(", ") if message.startswith("the following arguments are") else []
        if any(not name.startswith("-") for name in missing) and any(
                word == "--terrain" or word.startswith("--terrain=") for word in _ARGV):
            # --terrain takes several files: a route after it is taken for one more
            message += "; --terrain takes one or more files, so give the route before it"
        choice = re.fullmatch(r"argument (.+): invalid choice: '(.*)' \(choose from (.*)\)", message)
        if choice:  # a misspelt sub-command or choice: the nearest, first
            offered = re.findall(r"'([^']*)'", choice.group(3))
            message += _did_you_mean(choice.group(2), offered)
        self.exit(2, f"{self.prog}: error: {message} (see '{self.prog} --help')\n")

    def unrecognized(self, extras: Sequence[str]) -> NoReturn:
        """Refuse the arguments this (sub-)command does not know, naming the nearest option."""
        options = [option for action in self._actions for option in action.option_strings]
        first = next((word for word in extras if word.startswith("-")), None)
        hint = _did_you_mean(first.split("=", 1)[0], options) if first is not None else ""
        self.error(f"unrecognized arguments: {' '.join(extras)}{hint}")


def _did_you_mean(word: str, offered: Sequence[str]) -> str:
    """``"; did you mean --segment-length?"`` for the offered word nearest ``word``, or ``""``."""
    import difflib

    nearest = difflib.get_close_matches(word, offered, n=1, cutoff=0.6)
    return f"; did you mean {nearest[0]}?" if nearest else ""


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every registered sub-command."""
    parser = _Parser(
        prog="profileopt",
        description="Terrain-force-limited, minimum-time speed profiles for ground vehicles.",
    )
    parser.add_argument("--debug", action="store_true", help="show a traceback on any error")
    parser.add_argument("--version", action="version", version=f"profileopt {__version__}",
                        help="print the version and exit")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for name, (_, help_text) in COMMANDS.items():
        p = sub.add_parser(name, help=help_text, description=help_text)
        load_command(name).arguments(p)
    return parser


def _parse(parser: argparse.ArgumentParser, argv: Sequence[str] | None) -> argparse.Namespace:
    """The arguments; what the sub-command does not know is refused by the sub-command, by
    name (``profileopt plan: error: unrecognized arguments: --segment-lenght; did you mean
    --segment-length?``), not by the top-level parser."""
    _ARGV[:] = sys.argv[1:] if argv is None else list(argv)  # for the parser's messages
    args, extras = parser.parse_known_args(argv)
    if extras:
        sub = next(action for action in parser._actions if isinstance(action, argparse._SubParsersAction))
        sub.choices[args.command].unrecognized(extras)
    return args


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the exit status (0 ok, 1 internal error, 2 bad input).

    Parameters
    ----------
    argv : sequence of str, optional
        The arguments after the program name, e.g. ``["plan", "route.csv"]``; None reads
        ``sys.argv[1:]``.

    Returns
    -------
    int
        The exit status: 0 success, 1 internal error (or a closed output pipe), 2 bad input
        (:class:`~profileopt.errors.InputError`, one line on stderr), 130 interrupted (Ctrl-C),
        143 terminated (SIGTERM); an interrupted or terminated run leaves no temporary file.
        ``verify`` also 3 (the profile breaks the vehicle's limits) and 4 (over the force
        limit in simulation only).
    """
    # IPOPT's linear solver (MUMPS) runs on CasADi's own OpenBLAS, loaded when the first
    # solver is built. Its extra threads spin on a second core for no gain in wall time on
    # these banded systems (measured: same wall time, half the CPU time), so one thread,
    # unless the user says otherwise.
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    # NumPy advises the kernel to back every array of 4 MB or more with huge pages; where the
    # kernel then compacts memory to find them (transparent huge pages with defrag=madvise, as
    # on the benchmark machine) a fresh array waits for it. Read by NumPy when it is imported,
    # which the command does after this line (tests/test_layout.py keeps it so). Measured on
    # that machine, the same bytes written: a plan of 10,000 segments 2.97 s against 3.15 s
    # (medians of 5), of 100,000 segments 31.8 s against 33.4 s (3 runs each; kernel time 3.3 s
    # against 5.5 s). A value the user sets is left to rule.
    os.environ.setdefault("NUMPY_MADVISE_HUGEPAGE", "0")

    try:
        args = _parse(build_parser(), argv)
    except KeyboardInterrupt:  # Ctrl-C while the command line is read: no traceback either
        print("profileopt: interrupted", file=sys.stderr)
        return 130
    if sys.stdout is None:  # started with standard output closed (>&-): refused before any work
        text = ("-o -: standard output is closed; give the path of a file to write"
                if getattr(args, "output", None) == "-" else
                "standard output is closed, and the command prints its summary there; run it with standard output "
                "open ('> /dev/null' discards it)")  # not lost silently
        print(f"profileopt {args.command}: error: {text}", file=sys.stderr)
        return 2
    keep_arrays_on_the_heap()
    previous = _catch_sigterm()
    try:
        status = load_command(args.command).run(args)
        _flush_stdout()
        return status
    except Terminated:  # SIGTERM: the same clean-up as Ctrl-C (no temporary file is left)
        print(f"profileopt {args.command}: terminated", file=sys.stderr)
        return 128 + signal.SIGTERM
    except InputError as exc:
        if args.debug:
            traceback.print_exc()
        _drop_unwritable_stdout()  # a full standard output: its buffer is not written again at exit
        print(f"profileopt {args.command}: error: {flags_for_parameters(str(exc))}", file=sys.stderr)
        return 2
    except BrokenPipeError:  # output piped into a reader that stopped early (e.g. head)
        _silence_stdout()
        # the status of a program ended by SIGPIPE in a shell (128 + 13), not 1 (an internal
        # error): the reader chose to stop, nothing went wrong here
        return 128 + getattr(signal, "SIGPIPE", 13)
    except OSError as exc:
        from ..io.atomic import WRITE_FAILURES

        if exc.errno not in WRITE_FAILURES:
            return _internal_error(args, exc)
        if args.debug:
            traceback.print_exc()
        # a full disk or device: the outputs' own failures are InputErrors naming them
        # (profileopt.io.atomic.OutputSet); what is left is a file named by the error, or
        # what the command printed (the summary, to a full standard output)
        if isinstance(exc, _StdoutFailed) or exc.filename is None:
            text = (f"standard output: cannot write ({exc.strerror}); free some space or send standard output "
                    "elsewhere")
        else:
            text = (f"{exc.filename}: cannot write ({exc.strerror}); nothing was written, free some space or "
                    "choose another output")
        _silence_stdout()
        print(f"profileopt {args.command}: error: {text}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"profileopt {args.command}: interrupted", file=sys.stderr)
        return 130
    except MemoryError:  # past the estimate (profileopt.cli.memory) or a limit set on the process
        if args.debug:
            traceback.print_exc()
        _silence_stdout()
        print(f"profileopt {args.command}: error: ran out of memory; nothing was written: split the route, give a "
              "coarser --spacing, or run it where more memory is free (plan and drive estimate their need before "
              "any work: --max-memory)", file=sys.stderr)
        return 2
    except Exception as exc:  # an internal error: still one line unless --debug
        return _internal_error(args, exc)
    finally:
        if previous is not _NO_HANDLER:
            signal.signal(signal.SIGTERM, signal.SIG_DFL if previous is None else previous)


def keep_arrays_on_the_heap(mmap_threshold_bytes: int = MMAP_THRESHOLD_BYTES) -> None:
    """Let glibc keep freed arrays of up to ``mmap_threshold_bytes`` for reuse in this process.

    A plan allocates and frees arrays of a few MB over and over (one per segment, window or
    sample), and IPOPT's linear solver a workspace at every iteration (302 MB at 100,000
    segments). glibc maps every allocation above its mmap threshold afresh from the kernel,
    page-faults it in and unmaps it when freed; its threshold starts at 128 kB and only rises
    as large blocks are freed, to 32 MiB at most. With the threshold at 32 MiB (trim above
    twice it) a 3 km plan on the command line took 3.5 s against 4.1 s (medians of 3, the same
    bytes written); at 1 GiB (the default, :data:`MMAP_THRESHOLD_BYTES`) a plan of 100,000
    segments took 37.3 s against 43.0 s (5.9 s in the kernel against 10.8; two runs each, the
    same bytes written; peak memory 3.75 GB against 3.62), and one of 10,000 the same time.
    Where a malloc threshold was set in the environment the dynamic rule is off altogether:
    Dask's nanny starts its workers with ``MALLOC_TRIM_THRESHOLD_=65536``
    (``distributed.nanny.pre-spawn-environ``), and a plan took 2-3 times the CPU in such a
    worker (``docs/guide/batch.md``), so :func:`profileopt.batch.plan_row` calls this too, with
    :data:`WORKER_MMAP_THRESHOLD_BYTES` (a long-lived worker should give memory back). Nothing
    is done off Linux or without glibc's ``mallopt``; no number planned depends on it.

    Each call sets the thresholds anew (the last call holds). glibc before 2.35 refuses an mmap
    threshold above 32 MiB; there :data:`WORKER_MMAP_THRESHOLD_BYTES` is set instead.

    Parameters
    ----------
    mmap_threshold_bytes : int, default :data:`MMAP_THRESHOLD_BYTES`
        Allocations above it are mapped from the kernel (bytes, in (0, 2**31)); freed memory
        at the top of the heap is returned above twice it (2**31 - 1 at most).

    Raises
    ------
    ValueError
        A threshold outside (0, 2**31) bytes (a C int).
    """
    threshold = int(mmap_threshold_bytes)
    if not 0 < threshold < 2**31:
        raise ValueError(f"mmap_threshold_bytes = {mmap_threshold_bytes!r}: must be in (0, 2**31) bytes (a C int)")
    if not sys.platform.startswith("linux"):
        return
    import ctypes

    try:
        mallopt = ctypes.CDLL(None).mallopt  # the process's own C library
    except (OSError, AttributeError):
        return
    m_trim_threshold, m_mmap_threshold = -1, -3  # <malloc.h>
    mallopt.argtypes, mallopt.restype = (ctypes.c_int, ctypes.c_int), ctypes.c_int
    # glibc before 2.35 refuses an mmap threshold above 32 MiB (it returns 0 and keeps its own);
    # the trim threshold is set only with an mmap threshold that held, since setting it turns
    # glibc's dynamic rule off
    for value in dict.fromkeys((threshold, min(threshold, WORKER_MMAP_THRESHOLD_BYTES))):
        if mallopt(m_mmap_threshold, value) == 1:
            mallopt(m_trim_threshold, min(2 * value, 2**31 - 1))
            return


def _internal_error(args: argparse.Namespace, exc: BaseException) -> int:
    if args.debug:
        traceback.print_exc()
    print(
        f"profileopt {args.command}: internal error: {type(exc).__name__}: {exc} "
        "(run again with --debug for a traceback and report it)",
        file=sys.stderr,
    )
    return 1


def _flush_stdout() -> None:
    """Write what the command printed now, so that a full standard output (``> /dev/full``)
    is an error of the command, not a message from the interpreter at exit."""
    if sys.stdout is None:  # started with standard output closed: what was printed went nowhere
        return
    try:
        sys.stdout.flush()
    except BrokenPipeError:
        raise
    except OSError as exc:
        raise _StdoutFailed(exc.errno, exc.strerror) from exc


class _StdoutFailed(OSError):
    """Standard output could not take what the command printed."""


def _drop_unwritable_stdout() -> None:
    """Write what is left in standard output's buffer, or, if it cannot take it (a full
    standard output, refused as bad input), point it at the null device, so that the
    interpreter's last flush does not add a second message at exit."""
    if sys.stdout is None:
        return
    try:
        sys.stdout.flush()
    except (OSError, ValueError):
        _silence_stdout()


def _silence_stdout() -> None:
    """Point standard output at the null device, so that the interpreter's last flush of what
    could not be written does not fail again at exit."""
    if sys.stdout is None:
        return
    with contextlib.suppress(OSError, ValueError):
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised where the program is, like Ctrl-C's KeyboardInterrupt: every
    ``finally`` and context manager runs (the atomic writers remove their temporary files)."""


def _terminate(signum: int, frame: object) -> None:
    raise Terminated


_NO_HANDLER = object()


def _catch_sigterm():  # noqa: ANN202
    """Turn SIGTERM into :class:`Terminated` while a command runs; returns the previous
    handler, or ``_NO_HANDLER`` when none can be set (not the main thread)."""
    try:
        return signal.signal(signal.SIGTERM, _terminate)
    except (ValueError, OSError):  # not the main thread of the main interpreter
        return _NO_HANDLER


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
