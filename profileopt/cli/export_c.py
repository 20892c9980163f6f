"""``profileopt export-c``: C source and header for the force limits of one vehicle."""

from __future__ import annotations

import argparse
import contextlib
import math

from ..defaults import MAX_C_BYTES, MODEL_KEYS
from ..errors import InputError
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
    parser.add_argument("--intervals", action="store_true",
                        help="also the interval rows (the limit at every speed between two stages' speeds) of each "
                             "model defined on e_max")
    parser.add_argument("--preview", type=float, metavar="HORIZON_M",
                        help="also a TerrainPreview's five envelopes (e_max, the step speed cap, |curvature|, the "
                             "steepest and least grade) over a horizon of this length (m), with --reach, "
                             "--knot-spacing and --unseen")
    parser.add_argument("--reach", type=float, default=0.0, metavar="M",
                        help="with --preview: how far beyond its position a stage can take the vehicle (m, default 0)")
    parser.add_argument("--knot-spacing", type=float, default=None, metavar="M",
                        help="with --preview: the envelopes' knot spacing (m, default 1)")
    parser.add_argument("--unseen", default="worst", metavar="CLASS_OR_RI",
                        help="with --preview: terrain not measured is this ISO 8608 class (A-H), an RI, or 'worst' "
                             "(class H; the default)")


def run(args: argparse.Namespace) -> int:
    from ..core.vehicle import (
        load_vehicle,  # imported when the command runs, not for --help (issue 14)
    )

    out = check_folder("-o", args.output)
    vehicle = load_vehicle(args.vehicle)
    preview = None
    if args.preview is None:
        given = [flag for flag, value, default in (("--reach", args.reach, 0.0), ("--knot-spacing", args.knot_spacing, None),
                                                    ("--unseen", args.unseen, "worst")) if value != default]
        if given:
            raise InputError(f"{', '.join(given)} shape(s) the preview: give --preview HORIZON_M as well, or leave "
                             f"{'it' if len(given) == 1 else 'them'} out")
    else:
        from ..mpc.preview import DEFAULT_PREVIEW_KNOT_SPACING_M, TerrainPreview

        spacing = DEFAULT_PREVIEW_KNOT_SPACING_M if args.knot_spacing is None else args.knot_spacing
        for flag, value, least in (("--preview", args.preview, "> 0"), ("--reach", args.reach, ">= 0"),
                                   ("--knot-spacing", spacing, "> 0")):
            if not (math.isfinite(value) and (value >= 0 if least == ">= 0" else value > 0)):
                raise InputError(f"{flag} {value:g}: give a number of metres {least}")
        unseen: str | float = args.unseen
        try:
            unseen = float(args.unseen)
        except ValueError:
            pass
        try:
            preview = TerrainPreview(vehicle, horizon_m=args.preview, reach_m=args.reach, unseen=unseen,
                                     knot_spacing_m=spacing)
        except InputError as exc:
            raise InputError(f"--preview {args.preview:g} --knot-spacing {spacing:g} --unseen {args.unseen}: "
                             f"{exc}") from None
    # the four files checked before any work (none may be the vehicle file), written all or none
    from ..mpc.codegen import (  # CasADi: imported only when exporting
        export_c,
        export_c_paths,
    )

    outputs = folder_outputs("-o", export_c_paths(vehicle, out), [vehicle_input(args.vehicle)])
    with outputs or contextlib.nullcontext():
        result = export_c(vehicle, out, models=args.model, n_stages=args.stages, intervals=args.intervals,
                          preview=preview)
        text = "\n".join([*(str(path) for path in (result.source, result.header, result.example, result.readme)),
                          f"{len(result.functions)} functions, each with its Jacobian (*_jac); see README.md there"])
        if outputs is not None:  # printed before the files are renamed into place: a full standard output
            outputs.print(text)  # replaces none of them
    if outputs is None:  # a new folder: no file there to replace
        print(text)
    return 0


# cli.command reads run.arguments when it registers run, so set it first, then register.
