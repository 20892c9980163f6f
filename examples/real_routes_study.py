"""Routes people drive, planned with default options and checked in simulation (issue 29).

Run:  python examples/real_routes_study.py [--out FILE.md] [--figures DIR] [--no-real] [--no-synthetic]
      python examples/real_routes_study.py --obstacles [--out FILE.md]

The real-route study (``profileopt.studies.real_routes``, beside the safety study): every
route below is planned with ``profileopt.plan(route, vehicle)`` (default options, nothing
tuned) for ``atv`` and ``atv-resonant``, and every plan is driven in the exact simulation
(``profileopt.verify``). The routes:

- the bundled GPS tracks (``data/real/gpx-tracks/``: Mojstrovka, a 2.7 km mountain trail,
  and korita-zbevnica's first drive, an 8.6 km loop), on their own smoothed GPS elevations
  with ISO 8608 class B roughness assumed, as ``profileopt plan TRACK --roughness-class B``;
- the LiDAR walk-through (``examples/geo/hexbin-track.gpx`` over PDAL's airborne cloud
  ``data/real/pdal-lidar/hexbin-crop.laz``, class C assumed, as the README);
- eleven hilly synthetic roads of 400 m sampled every 0.05 m: 8 cm kerbs and drops on grades
  of -15 % to +15 %, on a crest and in a dip, potholes on a 10 % climb, a washboard on a 5 %
  descent, a block field on an 8 % climb, rolling hills; each also planned without its
  obstacles, so that the table shows what they cost.

Both default vehicles stall on the GPS tracks' steepest climbs (33 % and 27 %; their drive
holds 26 %), so those tracks and the walk-through are driven by ``atv-low-range`` too.

It prints one Markdown table (a row per route and vehicle: travel time, what holds the
speed and where, the worst simulated roughness window, verify's verdict, what the planner's
simulation gate capped, the sharpest turn) and the plans' notes, writes them to ``--out``
(atomically) and draws one picture per route and vehicle into ``--figures``: the planned
speed under its caps, the roughness, the path's curvature, its grade and elevation, and
which limit holds the speed where, with the worst simulated window shaded.

``--obstacles`` runs issue 29's obstacle family instead: every block, pit, kerb and drop of
heights 0.02-0.3 m and widths 0.05-2 m sampled every 0.01, 0.05 and 0.2 m, on 60 m of flat
ground with the obstacle at 40 m, both vehicles (360 plans), and prints how many are over
the limit in simulation, how many the planner's simulation gate capped, and the slowest.

The GPS routes need the ``geo`` extra (``pip install -e '.[geo]'``); without it they are
skipped with one line. Runtime on 2 cores: 2-3 minutes for the routes, 4-6 minutes for
``--obstacles``.
"""

from __future__ import annotations

import argparse
import math
import re
import sys
import textwrap
import time
from pathlib import Path
from typing import Sequence

import numpy as np

from profileopt import InputError
from profileopt.io import atomic_path, atomic_write
from profileopt.studies.real_routes import (
    DEFAULT_VEHICLES,
    PairRun,
    StudyRoute,
    obstacle_study,
    real_route_study,
    study_track_route,
    synthetic_routes,
)
from profileopt.viz.plots import profile_figure

REPO = Path(__file__).resolve().parents[1]
GPX = REPO / "data" / "real" / "gpx-tracks"
COMMAND = "python examples/real_routes_study.py"
#: Drives the GPS tracks besides the default vehicles: the same ATV in low range, which
#: climbs their steepest stretches.
LOW_RANGE = "atv-low-range"


def real_routes() -> tuple[list[StudyRoute], list[str]]:
    """The bundled GPS tracks and the LiDAR walk-through, and a line for each one skipped."""
    specs = [
        ("Mojstrovka GPX", dict(track_path=GPX / "Mojstrovka.gpx", road_class="B"),
         "a GPS track of a mountain trail, up to a summit ridge and back (2.7 km as logged, points about 10 m "
         "apart), its own GPS elevations, class B assumed"),
        ("korita-zbevnica GPX", dict(track_path=GPX / "korita-zbevnica.gpx", track_index=1, road_class="B"),
         "the first drive of a GPS track (track 1: an 8.6 km loop, points about 11 m apart), class B assumed"),
        ("hexbin LiDAR", dict(track_path=REPO / "examples" / "geo" / "hexbin-track.gpx",
                              terrain_path=REPO / "data" / "real" / "pdal-lidar" / "hexbin-crop.laz", road_class="C"),
         "the README's walk-through: a GPX track drawn along a contour (points 5 m apart) over PDAL's airborne LiDAR "
         "cloud, class C assumed"),
    ]
    routes, skipped = [], []
    for name, options, description in specs:
        try:
            routes.append(study_track_route(name, description=description, extra_vehicles=(LOW_RANGE,), **options))
        except InputError as exc:
            skipped.append(f"{name}: skipped: {exc}")
    return routes, skipped


def _slug(text: str) -> str:
    """A file name of a route's name: "kerb+drop -5 %" -> "kerb-drop-minus-5-pct"."""
    text = re.sub(r"\+(?=\d)", "plus ", re.sub(r"-(?=\d)", "minus ", text.lower())).replace("%", "pct")
    return re.sub(r"[^a-z0-9]+", "-", text).strip("-")


def figure_path(folder: Path, route: str, vehicle: str) -> Path:
    """Where the picture of one (route, vehicle) pair goes."""
    return folder / f"{_slug(route)}__{vehicle}.png"


def draw_pair(run: PairRun, path: Path) -> None:
    """The project's profile picture (speed under its caps, RI, curvature, grade, what holds
    the speed) with the route's elevation and the worst simulated roughness window shaded.

    A straight ``s,z`` route has no turns, so its curvature panel would be an empty line at
    0: the elevation takes its place. A route with turns gets its elevation on a second axis
    of the grade panel.
    """
    result, profile = run.result, run.profile
    verdict = "passes verify" if result.passes else f"FAILS verify: {result.windows_over} windows over"
    title = (f"{result.route}, {result.vehicle}: {result.distance_m:.0f} m in {result.travel_time_s:.1f} s\n"
             f"worst simulated roughness window {result.worst_window_ratio:.3f} x the force limit ({verdict})")
    fig = profile_figure(profile, title=title)
    axes = {ax.get_ylabel().split(" ")[0]: ax for ax in fig.axes}
    speed, curvature, grade = axes.get("speed"), axes.get("curvature"), axes.get("grade")
    route = run.route.route
    if curvature is not None and result.sharpest_curvature_1pm == 0:
        curvature.clear()
        curvature.plot(route.s_m, route.z_m, color="0.25", linewidth=1.0)
        curvature.set_ylabel("elevation\n(m)")
        curvature.grid(True, alpha=0.3)
        curvature.tick_params(labelbottom=False)
    elif grade is not None:
        elevation = grade.twinx()
        elevation.plot(route.s_m, route.z_m, color="0.25", linewidth=1.0, linestyle=(0, (3, 1.5)))
        elevation.set_ylabel("elevation (m),\ndashed", color="0.25")
        grade.set_ylabel("grade (%), brown\nuphill +")
    if speed is not None and math.isfinite(result.worst_window_ratio):
        speed.axvspan(result.worst_window_start_m, result.worst_window_stop_m, color="tab:red", alpha=0.15, lw=0,
                      zorder=0)
        speed.annotate(f"worst window\n{result.worst_window_ratio:.3f} x limit", (result.worst_window_peak_s_m, 0),
                       xytext=(0, 6), textcoords="offset points", ha="center", va="bottom", fontsize="small",
                       color="tab:red", zorder=6, bbox=dict(boxstyle="round,pad=0.2", fc="white", ec="none", alpha=0.8))
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=90, format="png")


def draw_not_planned(run: PairRun, path: Path) -> None:
    """A route the planner refused for a vehicle: its elevation along s and, for a route with
    x, y, its plan view, with the place the planner's message names marked."""
    from matplotlib.figure import Figure

    result, route = run.result, run.route.route
    where = [float(x) for x in re.findall(r"\bs = ([0-9.]+) m", result.status)]
    plan_view = route.x_m is not None
    fig = Figure(figsize=(10, 7 if plan_view else 4), layout="constrained")
    axes = fig.subplots(2 if plan_view else 1, 1, height_ratios=[1, 2] if plan_view else None, squeeze=False)[:, 0]
    along = axes[0]
    along.plot(route.s_m, route.z_m, color="0.25", linewidth=1.0)
    along.set_xlabel("distance along the route s (m)")
    along.set_ylabel("elevation (m)")
    along.grid(True, alpha=0.3)
    along.set_xlim(route.s_m[0], route.s_m[-1])
    for k, s in enumerate(where):
        along.axvline(s, color="tab:red" if k == 0 else "tab:orange", linewidth=1.2, linestyle="--")
    if plan_view:
        top = axes[1]
        top.plot(route.x_m - route.x_m[0], route.y_m - route.y_m[0], color="0.25", linewidth=1.0)
        for k, s in enumerate(where):
            i = min(int(np.searchsorted(route.s_m, s)), route.s_m.size - 1)
            top.plot(route.x_m[i] - route.x_m[0], route.y_m[i] - route.y_m[0], "o",
                     color="tab:red" if k == 0 else "tab:orange", markersize=7)
        top.set_aspect("equal", adjustable="box")
        top.set_xlabel("x from the start (m, east)")
        top.set_ylabel("y from the start (m, north)")
        top.grid(True, alpha=0.3)
    reason = result.status.split("; ")[0]
    fig.suptitle(f"{result.route}, {result.vehicle}: not planned ({result.outcome})\n"
                 + textwrap.fill(reason, 110) + ("\n(red: where it stops; orange: where the climb starts)"
                                                 if len(where) > 1 else ""), fontsize="medium")
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=90, format="png")


def report(study, skipped: Sequence[str]) -> str:  # noqa: ANN001  (RealRouteStudy)
    """The Markdown for the docs: what was run, the table, what each route is, the notes."""
    lines = [
        f"`{COMMAND}`: {len(study.routes)} routes, each planned with default options for "
        f"{' and '.join(study.vehicles)} (the GPS routes for {LOW_RANGE} too) and driven in the exact simulation "
        "(`profileopt.verify`).",
        "",
        study.markdown(),
        "",
        "\"/ bare road\": travel time over that of the same road without its obstacles. \"gate capped\": how much of "
        "the route the planner's simulation gate slowed down. A turn radius is the sharpest the plan used.",
        "",
        "The routes:",
        "",
        *[f"- **{name}**: {study.descriptions[name]}" for name in study.routes],
        *([""] + [f"- {line}" for line in skipped] if skipped else []),
        "",
        "The plans' notes:",
        "",
        study.notes_markdown(),
    ]
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, help="also write the Markdown to this file (default: print it only)")
    parser.add_argument("--figures", type=Path, help="write one PNG per route and vehicle into this folder")
    parser.add_argument("--obstacles", action="store_true",
                        help="run issue 29's obstacle family (360 plans, 4-6 minutes) instead of the routes")
    parser.add_argument("--no-real", action="store_true", help="leave out the GPS routes")
    parser.add_argument("--no-synthetic", action="store_true", help="leave out the synthetic roads")
    args = parser.parse_args(argv)
    started = time.perf_counter()

    def progress(run: PairRun) -> None:
        r = run.result
        what = f"{r.travel_time_s:.1f} s, worst window {r.worst_window_ratio:.3f}" if r.planned else r.outcome
        print(f"  {r.route}, {r.vehicle}: {what} ({time.perf_counter() - started:.0f} s)", file=sys.stderr, flush=True)
        if args.figures is not None:
            (draw_pair if run.profile is not None else draw_not_planned)(run, figure_path(args.figures, r.route,
                                                                                          r.vehicle))

    if args.figures is not None:
        args.figures.mkdir(parents=True, exist_ok=True)
    if args.obstacles:
        study = obstacle_study(vehicles=DEFAULT_VEHICLES, on_pair=progress)
        text = (f"`{COMMAND} --obstacles`: issue 29's obstacle family, planned with default options and driven in "
                f"the exact simulation.\n\n{study.markdown()}")
    else:
        routes, skipped = ([], []) if args.no_real else real_routes()
        for line in skipped:
            print(line, file=sys.stderr)
        routes += [] if args.no_synthetic else synthetic_routes()
        study = real_route_study(routes, DEFAULT_VEHICLES, on_pair=progress)
        text = report(study, skipped)
    print(text)
    if args.out:
        with atomic_write(args.out) as handle:
            handle.write(text + "\n")
        print(f"wrote {args.out}")
    # on stderr, so that stdout is the same on every run
    print(f"done in {time.perf_counter() - started:.0f} s", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
