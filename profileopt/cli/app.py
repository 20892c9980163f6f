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

__all__ = ["main", "build_parser"]

class _Parser(argparse.ArgumentParser):
    """An argument parser whose errors are one line (no usage block), exit status 2."""

    def error(self, message: str) -> NoReturn:
        # argparse's words for a value given to a switch (--refine=yes) read as if it ran on
        switch = re.fullmatch(r"argument (\S+?)(?:/(\S+))?: ignored explicit argument '(.*)'", message)
        if switch:
            names = [name for name in switch.groups()[:2] if name]
            message = f"{'/'.join(names)} takes no value ('{switch.group(3)}' given): write {' or '.join(names)}"
        self.exit(2, f"{self.prog}: error: {message} (see '{self.prog} --help')\n")


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

    parser = build_parser()
    args = parser.parse_args(argv)
    previous = _catch_sigterm()
    try:
        return load_command(args.command).run(args)
    except Terminated:  # SIGTERM: the same clean-up as Ctrl-C (no temporary file is left)
        print(f"profileopt {args.command}: terminated", file=sys.stderr)
        return 128 + signal.SIGTERM
    except InputError as exc:
        if args.debug:
            traceback.print_exc()
        print(f"profileopt {args.command}: error: {flags_for_parameters(str(exc))}", file=sys.stderr)
        return 2
    except BrokenPipeError:  # output piped into a reader that stopped early (e.g. head)
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        # the status of a program ended by SIGPIPE in a shell (128 + 13), not 1 (an internal
        # error): the reader chose to stop, nothing went wrong here
        return 128 + getattr(signal, "SIGPIPE", 13)
    except KeyboardInterrupt:
        print(f"profileopt {args.command}: interrupted", file=sys.stderr)
        return 130
    except Exception as exc:  # an internal error: still one line unless --debug
        if args.debug:
            traceback.print_exc()
        print(
            f"profileopt {args.command}: internal error: {type(exc).__name__}: {exc} "
            "(run again with --debug for a traceback and report it)",
            file=sys.stderr,
        )
        return 1
    finally:
        if previous is not _NO_HANDLER:
            signal.signal(signal.SIGTERM, signal.SIG_DFL if previous is None else previous)


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
