"""``profileopt verify`` and ``profileopt compare``: check plans against a simulated vehicle.

``verify`` drives the vehicle's quarter car over the route at a profile's speeds and reports
the simulated peak forces per segment beside the model's prediction and the limit.
``compare`` plans the route with each of the four force models, verifies each plan and
prints one table: the paper's claim (Prev:BEM is aggressive, the SBEM models are safe) put
to a test on real terrain.

Both print only numbers that do not depend on the machine, so the same input gives the same
output bytes on every run.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from ..io.atomic import STDOUT, OutputSet
from ..cli import command
from ..errors import InputError
from ..forces import MODELS, get_model
from ..vehicle import load_vehicle
from ._paths import vehicle_input


def _vehicle_of(args: argparse.Namespace, profile) -> str:
    """The vehicle to verify with: the one the profile records, unless --vehicle names it."""
    recorded = str(profile.settings.get("vehicle", ""))
    if recorded in ("", "unnamed"):
        if args.vehicle is None:
            raise InputError(f"{args.profile}: the profile does not record its vehicle; pass --vehicle")
        return args.vehicle
    if args.vehicle is not None and Path(args.vehicle).stem != Path(recorded).stem:
        raise InputError(f"{args.profile}: the profile was planned for vehicle '{recorded}' but --vehicle is "
                         f"'{args.vehicle}'; pass --vehicle {recorded} (or leave it out), or plan again")
    args.vehicle = args.vehicle or recorded
    return args.vehicle


def _verify(args: argparse.Namespace) -> int:
    """Run ``profileopt verify``; returns 0 (also when segments are over the limit)."""
    from ..io import read_profile, read_route
    from ..plots import plot_verification
    from ..verification import verify

    # first, before any work: every output checked (none may be an input, nor both the same
    # file); then written together, all or none
    outputs = OutputSet([("-o", args.output, True), ("--plot", args.plot)],
                        inputs=[args.route, args.profile, vehicle_input(args.vehicle)])
    route = read_route(args.route)
    profile = read_profile(args.profile)
    vehicle = load_vehicle(_vehicle_of(args, profile))
    result = verify(route, profile, vehicle, model=args.model)
    with outputs:
        if args.output is not None:
            result.to_csv(args.output)
        if args.plot is not None:
            plot_verification(result, args.plot)
    out = sys.stderr if outputs.uses_stdout else sys.stdout  # standard output holds the table
    if args.json:
        print(result.to_json(timings=False), file=out)
        return 0
    model = get_model(result.model)
    i = result.worst_segment
    lines = [
        f"verified {args.profile} on {args.route} with vehicle {args.vehicle}, "
        f"model {model.label} ({result.quantity} force, limit {result.limit_n[i]:g} N)",
        f"  segments over the limit: {result.over_count} of {result.ratio.size} "
        f"({100 * result.over_fraction:.1f} %, {result.over_length_m:g} m)",
        f"  worst simulated / limit: {result.worst_ratio:.3f} in the segment from s = {result.s_m[i]:g} m "
        f"({result.simulated_n[i]:.0f} N simulated, {result.predicted_n[i]:.0f} N predicted)",
        f"  segments where the simulation exceeds the prediction by > 1 % of the limit: "
        f"{int(result.underpredicted.sum())}",
        f"  segments where the wheel would leave the ground (F_T < -m g = {-result.weight_n:.0f} N): "
        f"{int(result.lift_off.sum())}",
        f"  simulated {result.travel_time_s:.2f} s of driving in {result.run.steps} steps of "
        f"{1e3 * result.run.time_step_s:.4f} ms",
    ]
    lines += [f"  note: {note}" for note in result.notes]
    if args.output is not None:
        lines.append("wrote the table to standard output" if args.output == STDOUT else f"wrote {args.output}")
    if args.plot is not None:
        lines.append(f"wrote {args.plot}")
    print("\n".join(lines), file=out)
    return 0


def _verify_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("route", help="route CSV (the terrain the profile was planned on)")
    parser.add_argument("profile", help="profile CSV written by 'profileopt plan -o'")
    parser.add_argument("--vehicle", default=None, metavar="NAME_OR_TOML",
                        help="bundled vehicle name or .toml file (default: the vehicle the profile "
                             "records; a different one is refused)")
    parser.add_argument("--model", default=None, choices=list(MODELS),
                        help="force model to check against (default: the model the profile records)")
    parser.add_argument("-o", "--output", metavar="CSV",
                        help="write one row per segment to this CSV ('-': standard output, the summary then "
                             "goes to stderr)")
    parser.add_argument("--plot", metavar="PNG", help="write forces along s and simulated vs predicted")
    parser.add_argument("--json", action="store_true", help="print the summary as JSON")


_verify.arguments = _verify_arguments  # type: ignore[attr-defined]
command("verify", "simulate the vehicle driving a planned profile and check the forces against the limits")(_verify)


def _compare(args: argparse.Namespace) -> int:
    """Run ``profileopt compare``: plan and verify with each model, print one table."""
    from ..io.routes import read_route
    from ..study import compare_models

    vehicle = load_vehicle(args.vehicle)
    route = read_route(args.route)
    rows = [run.to_dict() for run in compare_models(route, vehicle, segment_length_m=args.segment_length)]
    if args.json:
        print(json.dumps({"route": args.route, "vehicle": args.vehicle,
                          "segment_length_m": args.segment_length, "models": rows}, indent=2))
        return 0
    print(_table(args, route.length_m, rows))
    return 0


def _table(args: argparse.Namespace, length_m: float, rows: list[dict]) -> str:
    """A Markdown table (pastes into the README as it is)."""
    head = (f"`profileopt compare {args.route} --vehicle {args.vehicle} --segment-length {args.segment_length:g}` "
            f"({length_m:g} m)\n\n"
            "| model | travel time (s) | worst simulated / limit | segments over the limit | length over (m) "
            "| worst F_T / F_T limit | simulated > predicted | wheel lift-off |\n"
            "|---|---:|---:|---:|---:|---:|---:|---:|")
    out = [head]
    notes = []
    for row in rows:
        if "travel_time_s" not in row:
            out.append(f"| {row['label']} | {row['status'].split(':')[0]} | | | | | | |")
            notes.append(f"{row['label']}: {row['status']}")
            continue
        out.append(
            f"| {row['label']} | {row['travel_time_s']:.1f} | {row['worst_ratio']:.2f} "
            f"| {row['over_count']} of {row['segments']} ({100 * row['over_fraction']:.1f} %) "
            f"| {row['over_length_m']:g} | {row['worst_transmitted_ratio']:.2f} "
            f"| {row['underpredicted_count']} | {row['lift_off_count']} |"
        )
        if row["status"] not in ("optimal", "exact"):
            notes.append(f"{row['label']}: planner status {row['status']}")
    out.append("")
    out.append("Simulated force: the one the model limits (F_T for SBEM:TF, k y + c y' for the others); "
               "'simulated > predicted': segments where it exceeds the model's own prediction by more than "
               "1 % of the limit; 'wheel lift-off': segments where F_T < -m g (the linear model keeps the "
               "wheel on the ground).")
    out += [f"note: {n}" for n in notes]
    return "\n".join(out)


def _compare_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("route", help="route CSV")
    parser.add_argument("--vehicle", default="atv", metavar="NAME_OR_TOML",
                        help="bundled vehicle name or .toml file (default: atv)")
    parser.add_argument("--segment-length", type=float, default=5.0, metavar="M",
                        help="segment length in m (default: 5)")
    parser.add_argument("--json", action="store_true", help="print the results as JSON")


_compare.arguments = _compare_arguments  # type: ignore[attr-defined]
command("compare", "plan a route with each of the four force models and check each plan in simulation")(_compare)

