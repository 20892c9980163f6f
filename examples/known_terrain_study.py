"""How fast on known terrain? The dynamic model beside the paper's SBEM:TF, on the bundled routes.

Run:  python examples/known_terrain_study.py [--out FILE.md] [--routes curb washboard ...] [--hidden]

Each bundled route (examples/routes/) is planned for both bundled ATVs with SBEM:TF (the
default) and with the dynamic model (profileopt plan --model dynamic), each plan is driven
in the exact simulation verify uses, and two references that stay within the force limit
there are found from outside the planner (profileopt.studies.known_terrain): the fastest
constant-speed drive, and the fastest SBEM:TF plan of the vehicle with its force limit
scaled by a factor lam (largest lam by bisection, each plan judged against the true limit).
The last column is the dynamic plan's time over the faster of the two. Prints a Markdown
table (and writes it to --out).

With --hidden it studies instead routes of the kinds issue 33 measured, built here (not
bundled): ISO 8608 class E (two seeds) and D, 200 m; a washboard entered at rest; repeated
potholes; class E with a few heavy-tailed bumps; kerbs and a block (every 0.05 m).

Runtime: about 4 minutes on 2 cores (7 routes x 2 vehicles; 3.6 min on 2026-11-28).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from profileopt import Route, load_vehicle, read_route
from profileopt.io import atomic_write
from profileopt.studies.known_terrain import SCALE_CAP, KnownTerrainRow, known_terrain_row
from profileopt.terrain.synthetic import iso8608_profile

ROUTES = Path(__file__).resolve().parent / "routes"
#: The bundled routes with measured or synthetic roughness (mojstrovka is a GPS track's
#: smoothed elevation, too steep for both ATVs' drive).
DEFAULT_ROUTES = ("curb", "washboard", "iri_road", "krc_rms_1in", "krc_rms_2in", "krc_rms_4in", "trail")


SPACING_M = 0.05


def _stations(length_m: float) -> np.ndarray:
    return np.arange(0.0, length_m + SPACING_M / 2, SPACING_M)


def _iso(road_class: str, seed: int, length_m: float = 200.0) -> Route:
    profile = iso8608_profile(road_class, length_m, SPACING_M, seed)
    return Route(profile.s_m, profile.z_m, source=f"ISO 8608 class {road_class} (seed {seed})")


def _bumps(s_m: np.ndarray, starts_m, widths_m, heights_m) -> np.ndarray:
    """Half-sine bumps (negative heights: potholes) of the given starts, widths and heights (m)."""
    z = np.zeros_like(s_m)
    for start, width, height in zip(starts_m, widths_m, heights_m):
        inside = (s_m > start) & (s_m < start + width)
        z[inside] += height * np.sin(np.pi * (s_m[inside] - start) / width)
    return z


def hidden_routes() -> list[Route]:
    """Routes of the kinds issue 33 measured, built here from their description."""
    s = _stations(150.0)
    washboard = Route(s, 0.02 * np.sin(2 * np.pi * s / 0.7) * (s < 120.0), source="washboard entered at rest")
    starts = np.arange(10.0, 140.0, 4.0)
    potholes = Route(s, _bumps(s, starts, np.full(starts.size, 0.8), np.full(starts.size, -0.06)),
                     source="repeated potholes (0.8 m x 6 cm every 4 m)")
    rough = _iso("E", 5)
    rng = np.random.default_rng(5)
    centres = rng.uniform(10.0, 190.0, 8)
    heavy = Route(rough.s_m, rough.z_m + _bumps(rough.s_m, centres, rng.uniform(0.3, 1.0, 8),
                                                 0.03 * rng.standard_t(2, 8)),
                  source="class E with heavy-tailed bumps")
    s = _stations(120.0)
    kerbs = Route(s, 0.08 * (s > 30.0) - 0.08 * (s > 60.0) + 0.12 * ((s > 85.0) & (s < 85.5)),
                  source="kerbs (8 cm up and down) and a block (0.5 m x 12 cm)")
    return [_iso("E", 11), _iso("E", 12), _iso("D", 13), washboard, potholes, heavy, kerbs]


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
    parser.add_argument("--hidden", action="store_true", help="the issue's kinds of route, built here")
    args = parser.parse_args(argv)
    lines = ["| route | vehicle | SBEM:TF (s) | its worst / limit | dynamic (s) | its worst / limit "
             "| fastest constant speed within the limit | fastest scaled limit within the limit "
             "| dynamic / fastest other |",
             "|---|---|---:|---:|---:|---:|---:|---:|---:|"]
    routes = (hidden_routes() if args.hidden else [read_route(ROUTES / f"{name}.csv") for name in args.routes])
    for route in routes:
        name = Path(route.source).stem if not args.hidden else route.source
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
