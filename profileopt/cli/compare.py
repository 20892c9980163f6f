"""``profileopt compare``: plan a route with each of the four force models and check each plan.

It plans the route with each model, verifies each plan (as ``profileopt verify``) and prints
one table: the paper's claim (Prev:BEM is aggressive, the SBEM models are safe) put to a
test on real terrain. It prints only numbers that do not depend on the machine, so the same
input gives the same output bytes on every run.
"""

from __future__ import annotations

import argparse
import json

from .messages import flags_for_parameters

from ..defaults import DEFAULT_REFINE, MODEL_KEYS


def run(args: argparse.Namespace) -> int:
    """Run ``profileopt compare``: plan and verify with each model, print one table."""
    from ..core.vehicle import load_vehicle
    from ..io.routes import read_route
    from ..progress import terminal_progress
    from ..studies.compare import compare_models

    vehicle = load_vehicle(args.vehicle)
    route = read_route(args.route)
    with terminal_progress("profileopt compare", enabled=not args.quiet) as progress:
        runs = compare_models(route, vehicle, segment_length_m=args.segment_length,
                              roughness_window_m=args.roughness_window, refine=args.refine, progress=progress,
                              models=[*MODEL_KEYS, "dynamic"] if args.dynamic else None)
    rows = [run.to_dict() for run in runs]
    if args.json:
        print(json.dumps({"route": args.route, "vehicle": args.vehicle, "segment_length_m": args.segment_length,
                          "roughness_window_m": args.roughness_window, "refine": args.refine, "models": rows},
                         indent=2))
        return 0
    print(_table(args, route.length_m, rows))
    return 0


def _table(args: argparse.Namespace, length_m: float, rows: list[dict]) -> str:
    """A Markdown table (pastes into the README as it is)."""
    head = (f"`profileopt compare {args.route} --vehicle {args.vehicle} --segment-length {args.segment_length:g} "
            f"--roughness-window {args.roughness_window:g}` ({length_m:g} m)\n\n"
            "| model | travel time (s) | worst window simulated / limit | windows over the limit "
            "| worst segment simulated / limit | segments over the limit | worst F_T / F_T limit "
            "| windows simulated > predicted | wheel lift-off |\n"
            "|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    out = [head]
    notes = []
    for row in rows:
        if "travel_time_s" not in row:
            out.append(f"| {row['label']} | {row['status'].split(':')[0]} | | | | | | | |")
            notes.append(f"{row['label']}: {flags_for_parameters(row['status'])}")
            continue
        win = row["windows"]
        out.append(
            f"| {row['label']} | {row['travel_time_s']:.1f} | {win['worst']['ratio']:.2f} (at {win['worst']['start_m']:g} m) "
            f"| {win['over_count']} of {win['windows']} ({100 * win['over_count'] / win['windows']:.1f} %) "
            f"| {row['worst_ratio']:.2f} | {row['over_count']} of {row['segments']} "
            f"| {row['worst_transmitted_ratio']:.2f} | {win['underpredicted_count']} "
            f"| {row['lift_off_count']} |"
        )
        if row["status"] not in ("optimal", "exact"):
            notes.append(f"{row['label']}: planner status {row['status']}")
    out.append("")
    out.append("Simulated force: the one the model limits (F_T for SBEM:TF and dynamic, k y + c y' for the others), "
               f"its peak while the vehicle is inside each {args.roughness_window:g} m roughness window (y measured "
               "from the window's least-squares line, as its RI) and in each segment, against the limit; 'simulated "
               "> predicted': windows where it exceeds the model's own prediction for the window by more than 1 % "
               "of the limit; 'wheel lift-off': segments where F_T < -m g (the linear model keeps the wheel on "
               "the ground).")
    out += [f"note: {n}" for n in notes]
    return "\n".join(out)


def arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("route", help="route CSV")
    parser.add_argument("--vehicle", default="atv", metavar="NAME_OR_TOML",
                        help="bundled vehicle name or .toml file (default: atv)")
    parser.add_argument("--segment-length", type=float, default=5.0, metavar="M",
                        help="segment length in m (default: 5)")
    parser.add_argument("--refine", action=argparse.BooleanOptionalAction, default=DEFAULT_REFINE,
                        help="plan as 'profileopt plan' does, with segments cut where the plan meets the force's "
                             "speed cap and the roughness changes (default); --no-refine: uniform segments")
    parser.add_argument("--roughness-window", type=float, default=5.0, metavar="M",
                        help="roughness window length in m, for the plans and the checks (default: 5)")
    parser.add_argument("--dynamic", action="store_true",
                        help="add a row for the dynamic model (the quarter car's response simulated on the route's "
                             "own samples, for measured terrain): its plan beside the paper's models'")
    parser.add_argument("--json", action="store_true", help="print the results as JSON")
    parser.add_argument("-q", "--quiet", action="store_true", help="no progress display on stderr")
