"""How often does a plan really exceed the force limit? The four models on a fixed route set.

Run:  python examples/safety_study.py [--out FILE.md] [--no-refine]

Every route of a fixed, seeded set, and copies of it shifted against the segment grid, is
planned with each of the four force models for each bundled vehicle, every plan is driven
by the simulated quarter car (profileopt.verify), and the roughness windows (and the
segments) whose simulated force exceeds the limit are counted. The result is Markdown
(printed, and written to --out if given): per model, the share of all windows over the
limit, pooled over the whole set, and where they are.

Runtime: about 2 minutes on 2 cores (2 x 56 routes x 4 models = 448 plans and simulations).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import Sequence

import numpy as np

from profileopt import get_model, load_vehicle
from profileopt.defaults import DEFAULT_REFINE
from profileopt.io import atomic_write, read_route
from profileopt.core.route import Route
from profileopt.studies.safety import SafetyStudy, safety_study
from profileopt.progress import NO_PROGRESS, Progress, terminal_progress
from profileopt.terrain.synthetic import iso8608_profile, step

ROUTES = Path(__file__).resolve().parent / "routes"
COMMAND = "python examples/safety_study.py"

# The route set. First the bundled routes (examples/routes/make_routes.py says what each
# one is): a 2 km ISO 8608 trail (classes B to F), a curb (0.15 m up and down, each in the
# middle of a 5 m segment), the three measured KRC ride courses, a measured road, and a
# washboard made for the resonant vehicle.
BUNDLED = ["trail.csv", "curb.csv", "krc_rms_1in.csv", "krc_rms_2in.csv", "krc_rms_4in.csv",
           "iri_road.csv", "washboard.csv"]
# Then six random ISO 8608 profiles of 300 m, sampled every 0.05 m like the bundled
# synthetic routes, from class C (a rough road) to class F (rocky track), with fixed seeds,
# so that the rough end (where the force limits bind) is not one single random draw.
SYNTHETIC = [("C", 101), ("D", 102), ("E", 103), ("F", 104), ("E", 105), ("F", 106)]
SYNTHETIC_LENGTH_M = 300.0
SYNTHETIC_SPACING_M = 0.05
# Kerbs on flat ground, 0.05 m high, two exactly on a 5 m segment boundary and two 2.5 m off
# one (issue 10: a kerb on a boundary was invisible to the per-segment RI, planned at full
# speed, and simulated 1.13 times the limit).
KERB_HEIGHT_M = 0.05
KERBS_M = [(50.0, KERB_HEIGHT_M), (100.0, -KERB_HEIGHT_M), (152.5, KERB_HEIGHT_M), (202.5, -KERB_HEIGHT_M)]
KERB_ROUTE_LENGTH_M = 250.0
# Each route is also driven with 1/4, 1/2 and 3/4 of a segment removed from its start, so
# that every feature meets the segment grid at four places (a copy keeps the original
# positions: it starts at the shift, and its segments are cut from there).
SHIFT_FRACTIONS = [0.0, 0.25, 0.5, 0.75]
SHIFT_MARK = "+"  # a shifted copy's source: the route's, then "+1.25m"
# Both bundled vehicles drive every route. The well-damped Table 1 "atv" (limits 5000 N)
# and the lightly damped "atv-resonant" (wn = 6 rad/s, zeta = 0.1, limits 1000 N): the
# second is the harder test, because its transmitted force peaks at resonance. Where a model
# says a route cannot be driven at all (atv-resonant on the rough KRC courses), the study
# records it as not drivable: that is a (very) conservative answer, not a failure.
VEHICLES = ["atv", "atv-resonant"]
# The planner's default 5 m segments and default options.
SEGMENT_LENGTH_M = 5.0


def kerb_route() -> Route:
    """Flat ground with the kerbs of KERBS_M, sampled like the synthetic routes."""
    s_m = SYNTHETIC_SPACING_M * np.arange(round(KERB_ROUTE_LENGTH_M / SYNTHETIC_SPACING_M) + 1)
    z_m = sum(step(s_m, where, height) for where, height in KERBS_M)
    return Route(s_m, z_m, source="kerbs_0.05m")


def shifted(route: Route, shift_m: float) -> Route:
    """``route`` without its first ``shift_m`` metres (at least one sample kept per segment)."""
    if shift_m == 0:
        return route
    keep = route.s_m >= route.s_m[0] + shift_m - 1e-9
    limit = None if route.speed_limit_mps is None else route.speed_limit_mps[keep]
    return Route(route.s_m[keep], route.z_m[keep], speed_limit_mps=limit,
                 source=f"{route.source}{SHIFT_MARK}{shift_m:g}m")


def base_routes() -> list[Route]:
    """The bundled routes, the kerbs, then the synthetic ones."""
    routes = [read_route(ROUTES / name) for name in BUNDLED] + [kerb_route()]
    for road_class, seed in SYNTHETIC:
        s_m, z_m = iso8608_profile(road_class, SYNTHETIC_LENGTH_M, SYNTHETIC_SPACING_M, seed)
        routes.append(Route(s_m, z_m, source=f"iso8608_{road_class}_seed{seed}"))
    return routes


def route_set() -> list[Route]:
    """The fixed, seeded route set: every base route shifted by each of SHIFT_FRACTIONS."""
    return [shifted(route, fraction * SEGMENT_LENGTH_M) for route in base_routes() for fraction in SHIFT_FRACTIONS]


def run_study(*, refine: bool = DEFAULT_REFINE, progress: Progress = NO_PROGRESS) -> SafetyStudy:
    """Plan, simulate and pool (the expensive part: about 2 minutes on 2 cores); ``refine``:
    every plan with refined segments (the default, as ``profileopt plan``), or False for
    uniform segments (``profileopt plan --no-refine``); ``progress``: told of each run."""
    return safety_study(route_set(), [load_vehicle(name) for name in VEHICLES],
                        segment_length_m=SEGMENT_LENGTH_M, refine=refine, progress=progress)


def report(study: SafetyStudy) -> str:
    """The Markdown for the docs (docs/guide/verify.md): the pooled table, then where the exceedances are."""
    shifts = ", ".join(f"{f:g}" for f in SHIFT_FRACTIONS)
    return "\n".join([
        f"`{COMMAND}{'' if study.refine else ' --no-refine'}`: {len(study.pairs())} route-vehicle pairs "
        f"({len(BUNDLED)} bundled routes, a route of "
        f"{KERB_HEIGHT_M:g} m kerbs on and off the segment grid and {len(SYNTHETIC)} seeded ISO 8608 routes of "
        f"{SYNTHETIC_LENGTH_M:g} m, classes {'-'.join(sorted({c for c, _ in SYNTHETIC}))}, each shifted by "
        f"{shifts} of a segment, each driven by {' and '.join(VEHICLES)}), {study.segment_length_m:g} m "
        f"segments{', refined' if study.refine else ' (not refined)'}, {study.roughness_window_m:g} m roughness "
        f"windows, default planner options{'' if study.refine else ' otherwise'}.",
        "",
        study.markdown(),
        "",
        _same_windows(study),
        "",
        "Where the windows over the limit are (routes with a window over the limit for some model; windows "
        f"over / windows, summed over the {len(SHIFT_FRACTIONS)} shifted copies (worst window's simulated / "
        "limit over the copies)):",
        "",
        by_base_route(study),
    ])


def base_name(source: str) -> str:
    """The route a (shifted) copy was made from: its file name without the shift."""
    return Path(source.split(SHIFT_MARK)[0]).name


def by_base_route(study: SafetyStudy) -> str:
    """The windows over the limit per route (its shifted copies pooled), vehicle and model."""
    labels = {key: get_model(key).label for key in study.models}
    groups: dict[tuple[str, str], list] = {}
    for run in study.runs:
        groups.setdefault((base_name(run.route), run.vehicle), []).append(run)
    lines = ["| route | vehicle | " + " | ".join(labels.values()) + " |", "|---|---|" + "---:|" * len(labels)]
    for (route, vehicle), runs in groups.items():
        if not any(r.planned and r.windows_over for r in runs):
            continue
        cells = []
        for key in study.models:
            mine = [r for r in runs if r.model == key]
            done = [r for r in mine if r.planned]
            if not done:
                cells.append("not drivable")
                continue
            over, windows = sum(r.windows_over for r in done), sum(r.windows["windows"] for r in done)
            worst = max(r.worst_window_ratio for r in done)
            text = f"**{over}**" if over else "0"
            cells.append(f"{text} / {windows} ({worst:.2f})" + ("" if len(done) == len(mine) else " (some not drivable)"))
        lines.append(f"| {route} | {vehicle} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def _same_windows(study: SafetyStudy) -> str:
    """One sentence: the pooled fractions on the pairs that every model could drive."""
    common = study.totals_where_all_planned()
    pairs = common[0].runs
    shares = ", ".join(f"{t.label} {t.windows_over} ({100 * t.window_over_fraction:.2f} %)" for t in common)
    return (f"On the {pairs} pairs that every model can drive ({common[0].windows} windows each), "
            f"windows over the limit: {shares}.")


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, help="also write the Markdown to this file (default: print it only)")
    parser.add_argument("--refine", action=argparse.BooleanOptionalAction, default=DEFAULT_REFINE,
                        help="plan with refined segments, as 'profileopt plan' does (default; the figures of docs/guide/verify.md); "
                             "--no-refine: uniform segments")
    args = parser.parse_args(argv)
    started = time.perf_counter()
    with terminal_progress("safety study") as progress:  # on stderr, when it is a terminal
        study = run_study(refine=args.refine, progress=progress)
    text = report(study)
    print(text)
    if args.out:
        with atomic_write(args.out) as handle:
            handle.write(text + "\n")
        print(f"wrote {args.out}")
    # on stderr, so that stdout is the same on every run
    print(f"{len(study.runs)} plans and simulations in {time.perf_counter() - started:.1f} s", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
