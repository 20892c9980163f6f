"""The ``profileopt`` command: a thin layer that parses arguments, calls the library and formats its output.

:mod:`~profileopt.cli.app` holds :func:`~profileopt.cli.app.main` and the exit statuses;
:mod:`~profileopt.cli.registry` names the sub-commands, one module each
(:mod:`~profileopt.cli.plan`, :mod:`~profileopt.cli.verify`, :mod:`~profileopt.cli.compare`,
:mod:`~profileopt.cli.route`, :mod:`~profileopt.cli.figures`, :mod:`~profileopt.cli.export_c`).
"""

from .app import build_parser, main

__all__ = ["main", "build_parser"]
