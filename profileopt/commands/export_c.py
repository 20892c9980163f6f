"""``profileopt export-c``: C source and header for the force limits of one vehicle."""

from __future__ import annotations

import argparse

from ..cli import command
from ..codegen import export_c
from ..forces import MODELS
from ..vehicle import load_vehicle


def _arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--vehicle", required=True, help="bundled vehicle name (atv, atv-resonant) or a .toml file")
    parser.add_argument("-o", "--output", required=True, metavar="DIR", help="folder for the C files (created if missing)")
    parser.add_argument(
        "--model",
        action="append",
        choices=list(MODELS),
        help="force model to export (repeat for several); default all four",
    )
    parser.add_argument(
        "--stages", type=int, default=1, metavar="N",
        help="length of every input and output vector, one horizon at once (default 1)",
    )


def run(args: argparse.Namespace) -> int:
    vehicle = load_vehicle(args.vehicle)
    result = export_c(vehicle, args.output, models=args.model, n_stages=args.stages)
    for path in (result.source, result.header, result.example, result.readme):
        print(path)
    print(f"{len(result.functions)} functions, each with its Jacobian (*_jac); see README.md there")
    return 0


# cli.command reads run.arguments when it registers run, so set it first, then register.
run.arguments = _arguments  # type: ignore[attr-defined]
command("export-c", "write C source, header and README for the force limits of a vehicle")(run)
