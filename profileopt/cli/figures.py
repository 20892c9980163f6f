"""``profileopt figures``: reproduce the paper's Figs. 1, 5 and 6 as PNG + CSV files."""

from __future__ import annotations

import argparse

from ..errors import InputError
from .paths import check_folder, folder_outputs, vehicle_input


def run(args: argparse.Namespace) -> int:
    """Write the figures into ``args.out`` (created if missing); print ``wrote PATH`` for each
    file written, as ``plan`` does."""
    from ..core.vehicle import load_vehicle
    from ..progress import terminal_progress
    from ..viz.figures import (  # matplotlib: only when drawing (0.3 s)
        paper_figure_paths,
        write_paper_figures,
    )

    out = check_folder("--out", args.out)
    inputs = [vehicle_input(args.vehicle), vehicle_input(args.resonant_vehicle)]
    # every file checked before any work (a fig6 path that is a folder must not let fig5 be
    # replaced); the six are then written together, all or none
    outputs = folder_outputs("--out", paper_figure_paths(out), inputs)
    vehicle = load_vehicle(args.vehicle)
    resonant = load_vehicle(args.resonant_vehicle)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError(f"--out {out}: cannot create the folder ({exc.strerror}); choose another path") from None
    if outputs is None:
        outputs = folder_outputs("--out", paper_figure_paths(out), inputs)
    with outputs:
        with terminal_progress("profileopt figures", enabled=not args.quiet) as progress:
            written = write_paper_figures(out, vehicle, resonant, progress=progress)
        # printed before the files are renamed into place: a full standard output replaces none
        outputs.print("\n".join(f"wrote {path}" for path in written))
    return 0


def arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--out", required=True, metavar="DIR",
                        help="folder for the figures (created if missing)")
    parser.add_argument("--vehicle", default="atv", metavar="NAME_OR_TOML",
                        help="vehicle of Fig. 5: a bundled name or a .toml file (default: atv, Table 1)")
    parser.add_argument("--resonant-vehicle", default="atv-resonant", metavar="NAME_OR_TOML",
                        help="vehicle of Fig. 6: a bundled name or a .toml file (default: atv-resonant)")
    parser.add_argument("-q", "--quiet", action="store_true", help="no progress display on stderr")


# cli.command reads run.arguments when it registers run, so set it first, then register.
