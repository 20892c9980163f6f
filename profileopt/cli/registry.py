"""The sub-commands of ``profileopt``: name -> (module, one-line help), importing none of them.

Each command is one module of :mod:`profileopt.cli` with two functions:
``arguments(parser)`` adds its options to an :class:`argparse.ArgumentParser` and
``run(args) -> int`` runs it on the parsed arguments and returns the exit status. A new
command is a new module and one entry here.
"""

from __future__ import annotations

import importlib
from types import ModuleType

__all__ = ["COMMANDS", "load_command"]

#: name on the command line -> (module that implements it, one-line help), in the order
#: ``profileopt --help`` lists them.
COMMANDS: dict[str, tuple[str, str]] = {
    "figures": ("profileopt.cli.figures",
                "write the paper's Figs. 1, 5 and 6 (PNG and CSV of the curves) into a folder"),
    "plan": ("profileopt.cli.plan",
             "plan the fastest speed profile along a route that keeps the terrain forces within limits"),
    "batch": ("profileopt.cli.batch",
              "plan many routes at once (a manifest or a list of route files), on a local or remote Dask cluster"),
    "drive": ("profileopt.cli.drive",
              "drive a route seeing only the terrain within the sensing range: the online speed selector, "
              "checked in simulation against the offline plan"),
    "route": ("profileopt.cli.route",
              "sample the ground under the wheels along a GPS track over a terrain map into a route CSV"),
    "export-c": ("profileopt.cli.export_c", "write C source, header and README for the force limits of a vehicle"),
    "verify": ("profileopt.cli.verify",
               "simulate the vehicle driving a planned profile and check the forces against the limits"),
    "compare": ("profileopt.cli.compare",
                "plan a route with each of the four force models and check each plan in simulation"),
}


def load_command(name: str) -> ModuleType:
    """The module of sub-command ``name`` (a key of :data:`COMMANDS`).

    Parameters
    ----------
    name : str
        The sub-command's name on the command line, e.g. ``"plan"``.

    Returns
    -------
    module
        The module, with ``arguments(parser)`` and ``run(args) -> int``.
    """
    return importlib.import_module(COMMANDS[name][0])
