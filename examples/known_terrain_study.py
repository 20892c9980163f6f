"""How fast on known terrain? The dynamic model beside the paper's SBEM:TF, on the bundled routes.

Run:  python examples/known_terrain_study.py [--out FILE.md] [--routes curb washboard ...]

Each bundled route (examples/routes/) is planned for both bundled ATVs with SBEM:TF (the
default) and with the dynamic model (profileopt plan --model dynamic), each plan is driven
in the exact simulation verify uses, and two references that stay within the force limit
there are found from outside the planner (profileopt.studies.known_terrain): the fastest
constant-speed drive, and the fastest SBEM:TF plan of the vehicle with its force limit
scaled by a factor lam (largest lam by bisection, each plan judged against the true limit).
The last column is the dynamic plan's time over the faster of the two. Prints a Markdown
table (and writes it to --out).

Runtime: about 4 minutes on 2 cores (7 routes x 2 vehicles; 3.6 min on 2026-11-28).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from profileopt import load_vehicle, read_route
from profileopt.io import atomic_write
from profileopt.studies.known_terrain import SCALE_CAP, KnownTerrainRow, known_terrain_row

ROUTES = Path(__file__).resolve().parent / "routes"
#: The bundled routes with measured or synthetic roughness (mojstrovka is a GPS track's
#: smoothed elevation, too steep for both ATVs' drive).
DEFAULT_ROUTES = ("curb", "washboard", "iri_road", "krc_rms_1in", "krc_rms_2in", "krc_rms_4in", "trail")


def _constant(row: KnownTerrainRow) -> str:
    """The constant-speed reference's cell: travel time and speed."""
    if row.constant_s == float("inf"):
        return "none"
    return f"{row.constant_s:.1f} s ({row.constant_mps:g} m/s)"


def _scaled(row: KnownTerrainRow) -> str:
    """The scaled-limit reference's cell: travel time and the factor lam on the limit."""
    ref = row.scaled
    if ref.travel_time_s == float("inf"):
        return "none"
    cap = ", the cap" if ref.scale >= SCALE_CAP and ref.upper_scale == float("inf") else ""
    return f"{ref.travel_time_s:.1f} s (lam {ref.scale:.3g}{cap})"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--routes", nargs="+", default=list(DEFAULT_ROUTES), metavar="NAME")
    parser.add_argument("--out", metavar="FILE.md")
    args = parser.parse_args(argv)
    lines = ["| route | vehicle | SBEM:TF (s) | its worst / limit | dynamic (s) | its worst / limit "
             "| fastest constant speed within the limit | fastest scaled limit within the limit "
             "| dynamic / fastest other |",
             "|---|---|---:|---:|---:|---:|---:|---:|---:|"]
    for name in args.routes:
        route = read_route(ROUTES / f"{name}.csv")
        for vehicle_name in ("atv", "atv-resonant"):
            row = known_terrain_row(route, load_vehicle(vehicle_name))
            lines.append(f"| {name} | {vehicle_name} | {row.sbem_tf_s:.1f} | {row.sbem_tf_ratio:.3f} "
                         f"| {row.dynamic_s:.1f} | {row.dynamic_ratio:.3f} | {_constant(row)} | {_scaled(row)} "
                         f"| {row.over_fastest:.2f} |")
            print(lines[-1], flush=True)
    text = "\n".join(lines) + "\n"
    if args.out:
        with atomic_write(args.out) as handle:
            handle.write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
