"""``profileopt drive``: drive a route online, seeing it only within the sensing range.

The online selector (:mod:`profileopt.online`) chooses the speed every cycle from the terrain
revealed ahead; the vehicle follows; the driven speed is simulated on the real route; the
route's offline plan (``profileopt plan`` with its defaults) is the yardstick.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from ..defaults import DEFAULT_MODEL, DEFAULT_ROUGHNESS_WINDOW_M, MODEL_KEYS
from ..errors import InputError
from .memory import MAX_MEMORY_GB, MAX_MEMORY_HELP
from .paths import vehicle_input
from .track import number_argument

if TYPE_CHECKING:
    import numpy as np

#: Defaults of the online selector, repeated here so that ``--help`` needs no numerical
#: package; tests/cli/test_drive_command.py checks they equal :mod:`profileopt.online.selector`'s.
SENSOR_RANGE_M, CYCLE_S, SEGMENT_LENGTH_M, UNSEEN, UNSEEN_DESCENT = 50.0, 0.1, 1.0, "worst", 0.05


def arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("route", help="route CSV: columns s,z or x,y,z (m), optional speed_limit (m/s), measured "
                                      "terrain revealed to the vehicle only within --sensor-range")
    parser.add_argument("--vehicle", default="atv", metavar="NAME_OR_TOML",
                        help="bundled vehicle name or .toml file (default: atv)")
    parser.add_argument("-o", "--output", metavar="CSV",
                        help="write the driven profile here: time_s, s_m, speed_mps, accel_mps2, edge_m, "
                             "edge_speed_mps ('-': standard output, the summary then goes to stderr)")
    parser.add_argument("--sensor-range", type=number_argument, default=SENSOR_RANGE_M, metavar="M",
                        help=f"how far ahead the sensors measure, m (default: {SENSOR_RANGE_M:g})")
    parser.add_argument("--unseen", default=UNSEEN, metavar="CLASS_OR_RI",
                        help="what terrain not yet measured is assumed to be: 'worst' (ISO 8608 class H), a class "
                             "A-H, an RI (a number), or 'route' (the route's own roughest class, known only in an "
                             f"experiment) (default: {UNSEEN})")
    parser.add_argument("--unseen-descent", type=number_argument, default=UNSEEN_DESCENT, metavar="GRADE",
                        help="the steepest descent assumed on unseen ground, rise over run: the braking it leaves "
                             f"(default: {UNSEEN_DESCENT:g})")
    parser.add_argument("--cycle", type=number_argument, default=CYCLE_S, metavar="S",
                        help=f"control cycle, s (default: {CYCLE_S:g})")
    parser.add_argument("--sensor-noise", type=number_argument, default=0.0, metavar="M",
                        help="standard deviation of noise on each sensed elevation, m (default: 0)")
    parser.add_argument("--sensor-spacing", type=number_argument, default=None, metavar="M",
                        help="sense an elevation every this many m along the path (default: the route's samples); "
                             "terrain counts as measured only where samples are at most 0.1 m apart")
    parser.add_argument("--seed", type=int, default=0, help="seed of the sensor noise (default: 0)")
    parser.add_argument("--segment-length", type=number_argument, default=SEGMENT_LENGTH_M, metavar="M",
                        help=f"the selector's planning resolution, m (default: {SEGMENT_LENGTH_M:g})")
    parser.add_argument("--roughness-window", type=number_argument, default=DEFAULT_ROUGHNESS_WINDOW_M, metavar="M",
                        help=f"roughness window, m (default: {DEFAULT_ROUGHNESS_WINDOW_M:g})")
    parser.add_argument("--model", default=DEFAULT_MODEL, choices=list(MODEL_KEYS),
                        help="force model (default: sbem_tf)")
    parser.add_argument("--plot", metavar="PNG",
                        help="draw the driven speed beside the offline plan, how far ahead the selector had "
                             "planned, and the simulated force per roughness window")
    parser.add_argument("--json", action="store_true", help="print the results as JSON")
    parser.add_argument("-q", "--quiet", action="store_true", help="no notes or progress display on stderr")
    parser.add_argument("--max-memory", type=number_argument, default=MAX_MEMORY_GB, metavar="GB",
                        help=MAX_MEMORY_HELP.replace("whose plan", "whose offline plan"))


def run(args: argparse.Namespace) -> int:
    """Run ``profileopt drive``: drive online, plan offline, simulate, print the comparison."""
    from ..core.vehicle import load_vehicle
    from ..io.atomic import OutputSet
    from .messages import printable

    if not args.max_memory > 0:
        raise InputError(f"--max-memory {args.max_memory:g}: must be a number > 0 in GB ('inf': no bound)")
    if args.unseen.strip().lower() != "route":
        from ..terrain.assumed import unseen_roughness

        try:
            unseen_roughness(args.unseen)
        except InputError:
            raise InputError(f"--unseen {args.unseen!r} is not 'worst', 'route', an ISO 8608 class A-H or an RI from 0 "
                             "to 2 (the RMS roughness over the ground clearance, dimensionless)") from None
    outputs = OutputSet([("-o", args.output, True), ("--plot", args.plot)],
                        inputs=[args.route, vehicle_input(args.vehicle)])
    vehicle = load_vehicle(args.vehicle)
    if Path(args.route).suffix.lower() in (".gpx", ".geojson", ".json", ".las", ".laz", ".tif", ".tiff"):
        from ..io.inputs import check_regular_input

        check_regular_input(args.route, "route file")  # a path that is not there: not found, first
        raise InputError(f"{args.route}: drive takes a route CSV of measured terrain (s,z or x,y,z); make one from "
                         "a track and a terrain map with 'profileopt route' first")
    from ..io.routes import read_route
    from ..online import drive
    from ..terrain.assumed import unseen_roughness
    from ..planning import plan
    from ..progress import terminal_progress

    from ..defaults import DEFAULT_REFINE, DEFAULT_SEGMENT_LENGTH_M
    from .memory import PlanMemory, check_plan_memory

    route = read_route(args.route)
    # the offline plan (plan's defaults) and the drive beside it: refused before any work
    # when they would need more than --max-memory (measured: drive peaks 10-25 % above plan,
    # within plan's estimate)
    check_plan_memory(args.route, PlanMemory(route.s_m.size, route.length_m, DEFAULT_SEGMENT_LENGTH_M, DEFAULT_REFINE,
                                             vehicle), args.max_memory, what="driving and planning it")
    if not args.quiet:
        for note in route.notes:
            print(f"note: {printable(note)}", file=sys.stderr)
        blind = _never_measured(route.s_m, args.sensor_spacing)
        if blind:
            print(f"note: {blind}", file=sys.stderr)
    unseen = args.unseen
    if unseen.strip().lower() == "route":
        from ..core.segments import route_roughness_windows
        from ..terrain.classes import smoothest_class_covering

        windows = route_roughness_windows(route, vehicle, window_m=args.roughness_window)
        unseen = smoothest_class_covering(float(windows.ri.max()), window_m=windows.window_m,
                                          clearance_m=vehicle.ground_clearance_m)
    with terminal_progress("profileopt drive", enabled=not args.quiet) as progress:
        driven = drive(route, vehicle, sensor_range_m=args.sensor_range, unseen=unseen, model=args.model,
                       cycle_s=args.cycle, segment_length_m=args.segment_length,
                       roughness_window_m=args.roughness_window, sensor_noise_m=args.sensor_noise,
                       sensor_spacing_m=args.sensor_spacing, seed=args.seed, unseen_descent=args.unseen_descent,
                       progress=progress)
        offline = plan(route, vehicle, model=args.model, roughness_window_m=args.roughness_window, progress=progress)
        unseen_label = unseen_roughness(unseen).label
        # names as the summary prints them: a file name that is not UTF-8 with U+FFFD for its bytes
        settings = {"route": printable(Path(args.route).name), "vehicle": printable(args.vehicle), "model": args.model,
                    "sensor_range_m": args.sensor_range, "unseen": unseen_label, "cycle_s": args.cycle,
                    "sensor_noise_m": args.sensor_noise, "sensor_spacing_m": args.sensor_spacing,
                    "seed": args.seed, "segment_length_m": args.segment_length, "unseen_descent": args.unseen_descent,
                    "roughness_window_m": args.roughness_window}
    summary = {
        "route": args.route, "vehicle": args.vehicle, "model": args.model, "sensor_range_m": args.sensor_range,
        "unseen": unseen_label, "unseen_speed_mps": driven.unseen_speed_mps, "cycle_s": args.cycle,
        "travel_time_s": driven.travel_time_s, "offline_travel_time_s": offline.travel_time_s,
        "ratio_to_offline": driven.travel_time_s / offline.travel_time_s,
        "worst_window_ratio": driven.worst_window_ratio, "worst_window_s_m": driven.worst_s_m,
        "windows_over_limit": driven.windows_over, "emergency_cycles": driven.emergencies,
        "cycles": int(driven.cycle_s_m.size), "max_jerk_mps3": driven.max_jerk_mps3,
        "jerk_bound_mps3": vehicle.max_jerk_mps3,
        "cycle_compute_ms": driven.compute_ms(), "notes": list(driven.notes),
    }
    out = sys.stderr if outputs.uses_stdout else sys.stdout
    text = json.dumps(summary, indent=2) if args.json else printable(_human(summary, args))
    with outputs:
        if args.output is not None:
            from ..online.drive import write_drive

            write_drive(driven, args.output, settings=settings)
        if args.plot is not None:
            from ..viz.drives import plot_drive

            plot_drive(driven, offline, args.plot, sensor_range_m=args.sensor_range, unseen=unseen_label,
                       route=printable(Path(args.route).name),
                       vehicle=printable(Path(vehicle.name).stem) if vehicle.name else None)
        # printed before the files are renamed into place: a full standard output replaces none
        outputs.print(text, out)
    return 0


def _human(summary: dict, args: argparse.Namespace) -> str:
    ms = summary["cycle_compute_ms"]
    verdict = ("within the force limit in the exact simulation" if summary["windows_over_limit"] == 0 else
               f"OVER the force limit in {summary['windows_over_limit']} roughness windows of the exact simulation")
    lines = [
        f"drove {summary['route']} with {summary['sensor_range_m']:g} m of sensing, unseen terrain assumed "
        f"{summary['unseen']} ({summary['unseen_speed_mps']:.3g} m/s)",
        f"travel time {summary['travel_time_s']:.2f} s; offline plan {summary['offline_travel_time_s']:.2f} s; "
        f"ratio {summary['ratio_to_offline']:.3f}",
        f"worst simulated window {summary['worst_window_ratio']:.3f} of the limit (at "
        f"{summary['worst_window_s_m']:.6g} m): {verdict}",
        f"selector compute per cycle: median {ms['median']:.2f} ms, 99th percentile {ms['p99']:.2f} ms, worst "
        f"{ms['max']:.2f} ms over {summary['cycles']} cycles of {summary['cycle_s']:g} s",
        f"largest jerk of the commands: {summary['max_jerk_mps3']:.3g} m/s^3 (the vehicle's bound: "
        f"{summary['jerk_bound_mps3']:.3g} m/s^3)",
    ]
    if summary["emergency_cycles"]:
        count = summary["emergency_cycles"]
        lines.append(f"emergency braking in {count} cycle{'' if count == 1 else 's'}: the terrain was worse than "
                     "assumed where it came into view")
    for note in summary["notes"]:
        lines.append(f"note: {note}")
    for name in (args.output, args.plot):
        if name is not None and name != "-":
            lines.append(f"wrote {name}")
    return "\n".join(lines)


def _never_measured(s_m: np.ndarray, sensor_spacing_m: float | None) -> str:
    """Why no terrain of the drive can count as measured, said before the drive; '' if some can.

    Terrain counts as measured only where the sensed samples are at most
    :data:`~profileopt.defaults.MAX_ROUGHNESS_SPACING_M` apart (the drive's end note counts the
    metres that never were); a sensor spacing wider than that, or a route whose samples all are,
    leaves the whole route to the unseen assumption, which a user should know before waiting.

    Parameters
    ----------
    s_m : numpy.ndarray, shape (K,)
        The route's stations (m).
    sensor_spacing_m : float or None
        ``--sensor-spacing`` (m); None: the route's own samples are sensed.
    """
    import numpy as np

    from ..defaults import MAX_ROUGHNESS_SPACING_M as finest

    if sensor_spacing_m is not None:
        if not (np.isfinite(sensor_spacing_m) and sensor_spacing_m > finest * (1 + 1e-9)):
            return ""  # measurable, or a bad value that the drive refuses in one line
        cause = f"--sensor-spacing {sensor_spacing_m:g} m is wider than"
    else:
        gaps = np.diff(s_m)
        if gaps.size == 0 or not np.all(gaps > finest * (1 + 1e-9)):
            return ""
        cause = f"the route's samples are {float(np.min(gaps)):.3g} m apart or more, wider than"
    return (f"{cause} the {finest:g} m at which sensed terrain counts as measured: the whole route will be driven "
            f"as unseen terrain (--unseen); sense at most {finest:g} m apart to drive on what the sensor sees")
