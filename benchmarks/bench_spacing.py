"""Travel time and solve time of the bundled routes at segment lengths 5, 2, 1 and 0.5 m.

Issue 10: with roughness windows the segment length is only the planning resolution, so
the travel time must converge as it shrinks. This prints a markdown table (run by hand;
the numbers in docs/guide/planning.md's "Choosing `--segment-length`" come from it):

    python benchmarks/bench_spacing.py

Each route is planned with its usual vehicle, default options (smoothing 0.01, the
vehicle's jerk bound) and pure minimum time (smoothing 0, no jerk bound: the exact
forward-backward optimum), the default 5 m roughness window, each on uniform segments
(``refine=False``, ``--no-refine``) and refined (``refine=True``, the default: segments cut
where the plan meets its cap and the roughness changes). Solve time is plan()'s own
``timings_s["total"]``, median of 3, on this machine, and the table gives the number of
segments planned after it.
"""

from __future__ import annotations

import argparse
import math
import statistics
from pathlib import Path

from profileopt.io.routes import read_route
from profileopt.planning import plan
from profileopt.core.vehicle import load_vehicle

ROUTES = Path(__file__).resolve().parent.parent / "examples" / "routes"
CASES = [("trail.csv", "atv"), ("krc_rms_1in.csv", "atv"), ("krc_rms_2in.csv", "atv"), ("krc_rms_4in.csv", "atv"),
         ("curb.csv", "atv"), ("iri_road.csv", "atv"), ("washboard.csv", "atv-resonant")]
LENGTHS_M = (5.0, 2.0, 1.0, 0.5)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    head = " | ".join(f"{length:g} m" for length in LENGTHS_M)
    print(f"| route | vehicle | options | {head} | 1 m vs 0.5 m |")
    print("|---|---|---|" + "---|" * len(LENGTHS_M) + "---|")
    for name, vehicle_name in CASES:
        route, vehicle = read_route(ROUTES / name), load_vehicle(vehicle_name)
        cases = [("default", {}), ("min time", {"smoothing": 0.0, "max_jerk_mps3": math.inf})]
        cases = [(f"{label}{suffix}", {**options, "refine": refine})
                 for label, options in cases for suffix, refine in ((", uniform", False), (", refined", True))]
        for label, options in cases:
            cells, times = [], []
            for length in LENGTHS_M:
                runs = [plan(route, vehicle, segment_length_m=length, **options) for _ in range(args.repeats)]
                travel = runs[0].time_s[-1]
                solve = statistics.median(run.timings_s["total"] for run in runs)
                times.append(travel)
                count = f", {runs[0].s_m.size - 1} seg."
                cells.append(f"{travel:.2f} s ({solve:.2f} s{count})")
            gap = 100 * (times[-2] - times[-1]) / times[-1]
            print(f"| {name} | {vehicle_name} | {label} | " + " | ".join(cells) + f" | {gap:.1f} % |")


if __name__ == "__main__":
    main()
