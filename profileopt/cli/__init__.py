"""The ``profileopt`` command: a thin layer that parses arguments, calls the library and formats its output.

:mod:`~profileopt.cli.app` holds :func:`~profileopt.cli.app.main` and the exit statuses;
:mod:`~profileopt.cli.registry` names the sub-commands, one module each
(:mod:`~profileopt.cli.plan`, :mod:`~profileopt.cli.verify`, :mod:`~profileopt.cli.compare`,
:mod:`~profileopt.cli.route`, :mod:`~profileopt.cli.figures`, :mod:`~profileopt.cli.export_c`).
"""

from __future__ import annotations

import sys
from typing import TYPE_CHECKING, Sequence

if TYPE_CHECKING:
    import argparse

__all__ = ["main", "build_parser"]


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line (:func:`profileopt.cli.app.main`); returns the exit status.

    The console script calls this first: the command line's own modules are imported here,
    so that Ctrl-C while they load is the command's one line and status 130, not a traceback.

    Parameters
    ----------
    argv : sequence of str, optional
        The arguments after the program name; None reads ``sys.argv[1:]``.

    Returns
    -------
    int
        The exit status (see :func:`profileopt.cli.app.main`).
    """
    try:
        from .app import main as run
    except KeyboardInterrupt:
        print("profileopt: interrupted", file=sys.stderr)
        return 130
    return run(argv)


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every registered sub-command (:func:`profileopt.cli.app.build_parser`)."""
    from .app import build_parser as build

    return build()

