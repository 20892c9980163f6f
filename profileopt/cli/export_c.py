"""``profileopt export-c``: C source and header for the force limits of one vehicle."""

from __future__ import annotations

import argparse
import contextlib

from ..defaults import MAX_C_BYTES, MODEL_KEYS
from .paths import check_folder, folder_outputs, vehicle_input


def arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--vehicle", required=True, help="bundled vehicle name (atv, atv-resonant) or a .toml file")
    parser.add_argument("-o", "--output", required=True, metavar="DIR", help="folder for the C files (created if missing)")
    parser.add_argument(
        "--model",
        action="append",
        choices=list(MODEL_KEYS),
        help="force model to export (repeat for several); default all four",
    )
    parser.add_argument(
        "--stages", type=int, default=1, metavar="N",
        help="length of every input and output vector, one horizon at once (default 1; the code grows "
             f"with it, about 24 kB per stage for all four models; at most {MAX_C_BYTES // 1_000_000} MB is "
             "written)",
    )


def run(args: argparse.Namespace) -> int:
    from ..core.vehicle import (
        load_vehicle,  # imported when the command runs, not for --help (issue 14)
    )

    out = check_folder("-o", args.output)
    vehicle = load_vehicle(args.vehicle)
    # the four files checked before any work (none may be the vehicle file), written all or none
    from ..mpc.codegen import (  # CasADi: imported only when exporting
        export_c,
        export_c_paths,
    )

    outputs = folder_outputs("-o", export_c_paths(vehicle, out), [vehicle_input(args.vehicle)])
    with outputs or contextlib.nullcontext():
        result = export_c(vehicle, out, models=args.model, n_stages=args.stages)
        text = "\n".join([*(str(path) for path in (result.source, result.header, result.example, result.readme)),
                          f"{len(result.functions)} functions, each with its Jacobian (*_jac); see README.md there"])
        if outputs is not None:  # printed before the files are renamed into place: a full standard output
            outputs.print(text)  # replaces none of them
    if outputs is None:  # a new folder: no file there to replace
        print(text)
    return 0


# cli.command reads run.arguments when it registers run, so set it first, then register.
