"""``profileopt plan``: the minimum-time speed profile along a route."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from ..defaults import (
    DEFAULT_MODEL,
    DEFAULT_PATH_TOLERANCE_M,
    DEFAULT_REFINE,
    DEFAULT_ROUGHNESS_WINDOW_M,
    DEFAULT_SEGMENT_LENGTH_M,
    DEFAULT_SMOOTHING,
    PLAN_MODEL_KEYS,
    PLAN_BANDS,
    PLAN_METHODS,
    PLAN_SOLVERS,
)
from ..errors import InputError
from .memory import MAX_MEMORY_GB, MAX_MEMORY_HELP
from .paths import vehicle_input
from .route import PATH_TOLERANCE_HELP, smoothed_track_route
from .track import (
    add_track_arguments,
    assumed_roughness,
    is_track,
    number_argument,
    refuse_track_options,
    track_inputs,
)


def arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("route", help="route CSV: columns s,z or x,y,z (m), optional speed_limit (m/s); or a track "
                                      "(GPX, GeoJSON, CSV of x,y with --terrain), sampled as 'profileopt route' does")
    parser.add_argument("--vehicle", default="atv", metavar="NAME_OR_TOML",
                        help="bundled vehicle name or .toml file (default: atv)")
    parser.add_argument("-o", "--output", metavar="CSV",
                        help="write the profile CSV here ('-': standard output, the summary then goes to stderr)")
    parser.add_argument("--segment-length", type=number_argument, default=DEFAULT_SEGMENT_LENGTH_M, metavar="M",
                        help=f"segment length in m, the planning resolution (default: {DEFAULT_SEGMENT_LENGTH_M:g})")
    parser.add_argument("--refine", action=argparse.BooleanOptionalAction, default=DEFAULT_REFINE,
                        help="cut the segments where the minimum-time plan meets the force's speed cap wherever "
                             "the roughness changes, and those where it meets a step's or a speed limit's cap "
                             "just outside the step or zone, then plan, so that the travel time hardly depends on "
                             "--segment-length (default; 1-11 times the segments, 1-6 times the plan time); "
                             "--no-refine plans on the uniform segments")
    parser.add_argument("--roughness-window", type=number_argument, default=DEFAULT_ROUGHNESS_WINDOW_M, metavar="M",
                        help="roughness window in m: every stretch this long, wherever it starts, is driven at "
                             f"speeds admissible for its own RI (default: {DEFAULT_ROUGHNESS_WINDOW_M:g})")
    parser.add_argument("--path-tolerance", type=number_argument, default=DEFAULT_PATH_TOLERANCE_M, metavar="M",
                        help=PATH_TOLERANCE_HELP)
    parser.add_argument("--model", default=DEFAULT_MODEL, choices=list(PLAN_MODEL_KEYS),
                        help="force model: the paper's sbem_tf (default), sbem_ef, iecm, prev_bem, from the roughness "
                             "index; or dynamic, the quarter car's response simulated on the route's own samples "
                             "(measured terrain, offline)")
    parser.add_argument("--keep-contact", action="store_true",
                        help="with --model dynamic: also keep the simulated wheel on the ground (transmitted force "
                             ">= -m g); slower where the force limit exceeds the wheel load (the atv)")
    parser.add_argument("--force-margin", type=_share, default=0.0, metavar="SHARE",
                        help="with --model dynamic: share of the force limit kept in reserve for error in the "
                             "measured profile, e.g. 0.1 (default: 0)")
    parser.add_argument("--smoothing", type=number_argument, default=DEFAULT_SMOOTHING, metavar="W",
                        help="weight of the comfort term: objective = time + W * integral (jerk/(1 m/s^3))^2 dt "
                             f"(default: {DEFAULT_SMOOTHING}; 0 = pure minimum time)")
    parser.add_argument("--max-jerk", type=number_argument, default=None, metavar="MPS3",
                        help="jerk bound in m/s^3 (default: the vehicle file's; 'inf' turns it off)")
    parser.add_argument("--v0", type=number_argument, default=0.0, metavar="MPS", help="speed at the start, m/s (default: 0)")
    parser.add_argument("--vend", type=number_argument, default=0.0, metavar="MPS", help="speed at the end, m/s (default: 0)")
    parser.add_argument("--method", default="auto", choices=list(PLAN_METHODS),
                        help="'auto': exact forward-backward profile when it is optimal, else the NLP; "
                             "'nlp': always the NLP")
    parser.add_argument("--solver", default=PLAN_SOLVERS[0], choices=list(PLAN_SOLVERS),
                        help="the NLP's solver: 'ipopt' (IPOPT with MUMPS); 'fatrop' (FATROP on the NLP's stage "
                             "form, a long route in pieces); 'banded' (the banded interior point written here, "
                             "faster on long routes); IPOPT takes over where another stops "
                             f"(default: {PLAN_SOLVERS[0]})")
    parser.add_argument("--band", default="all", choices=list(PLAN_BANDS),
                        help="'all': any admissible speed band, chosen over the whole route (may cross "
                             "washboard above resonance); 'first': only speeds reachable from rest "
                             "without crossing a force peak; 'largest': only the highest band (default: all)")
    parser.add_argument("--json", action="store_true", help="print the summary as JSON")
    parser.add_argument("-q", "--quiet", action="store_true",
                        help="no notes and no progress display on stderr (errors are still said)")
    parser.add_argument("--plot", metavar="PNG",
                        help="draw speed, allowable speeds, RI, curvature, grade and the binding limit along the "
                             "route (PNG, or another format matplotlib writes by the extension: .jpg, .pdf, .svg)")
    parser.add_argument("--map", metavar="PNG",
                        help="draw the route over its terrain, coloured by the planned speed, marking where each "
                             "limit holds it (an x,y route or a track)")
    parser.add_argument("--max-memory", type=number_argument, default=MAX_MEMORY_GB, metavar="GB",
                        help=MAX_MEMORY_HELP)
    add_track_arguments(parser)


def run(args: argparse.Namespace) -> int:
    def report(summary: dict, outputs) -> None:  # noqa: ANN001  (OutputSet)
        # printed before the files are renamed into place: a full standard output replaces none
        out = sys.stderr if outputs.uses_stdout else sys.stdout  # standard output holds the profile
        if args.json:
            outputs.print(json.dumps(summary, indent=2), out)
        else:
            from .messages import printable

            outputs.print(printable(_human(summary, args)), out)  # a file name not in UTF-8: U+FFFD

    execute(args, report=report)
    return 0


def execute(args: argparse.Namespace, report=None, inputs=()) -> tuple[dict, bool]:  # noqa: ANN001
    """Plan as ``profileopt plan`` does and write its outputs, printing only notes (none with
    ``--quiet``): the work of :func:`run` without the summary (``profileopt batch`` runs it
    for each route).

    Parameters
    ----------
    args : argparse.Namespace
        ``profileopt plan``'s arguments.
    report : callable, optional
        ``report(summary, outputs)``, called once the outputs are written and before they are
        put in place, to print the summary with ``outputs.print``
        (:meth:`profileopt.io.atomic.OutputSet.print`): a stream that fails then leaves
        every file as it was.
    inputs : iterable of path, optional
        More files no output may replace, besides the route, the vehicle and the terrain
        (``profileopt batch``: its manifest and every route's inputs).

    Returns
    -------
    summary : dict
        :meth:`profileopt.Profile.summary` with the route and the vehicle first (and the
        track's smoothing, for a track).
    uses_stdout : bool
        Whether an output went to standard output (``-o -``).
    """
    from ..core.vehicle import load_vehicle
    from ..io.atomic import (
        OutputSet,  # imported when the command runs, not for --help (issue 14)
    )
    from ..io.profiles import write_profile
    from .messages import printable
    from ..progress import terminal_progress

    # first, before any work: every output checked (none may be an input, nor both the same
    # file); then written together, all or none
    _check_max_memory(args)
    outputs = OutputSet([("-o", args.output, True), ("--plot", args.plot), ("--map", args.map)],
                        inputs=[args.route, vehicle_input(args.vehicle), *track_inputs(args), *inputs])
    vehicle = load_vehicle(args.vehicle)
    from ..planning import SolverOptions, plan  # the numerical packages: imported only when planning

    made = track = None
    tolerance = args.path_tolerance
    route_name = printable(Path(args.route).name)  # for the pictures' titles and the progress display
    vehicle_name = printable(Path(vehicle.name).stem) if vehicle.name else None
    # the outputs are put in place when this block ends: after the progress display has
    # ended and the summary is printed (report), so a full standard output replaces no file
    with outputs:
        # the display starts before the route is read: a track over a large terrain takes
        # its time before the plan does (issue 30, item 13)
        with terminal_progress("profileopt plan", enabled=not args.quiet) as progress:
            say = _notes(args, progress)
            if is_track(args.route, args):
                made, track = smoothed_track_route(  # its notes: not with --quiet
                    args.route, args, "profileopt plan", progress=progress,
                    before_sampling=lambda found: _check_track_memory(args, found, vehicle))
                route = made.route
                if track.smoothing is not None and track.smoothing.smoothed:
                    tolerance = None  # the points are on the path smoothed within it; what is left is estimated
            else:
                refuse_track_options(args.route, args)
                progress.expect(1)
                progress.step(f"reading {route_name}")
                route = _route_file(args, say)
            if args.map is not None and route.x_m is None:
                raise InputError(f"{args.route}: --map draws a route's x,y (or a track's); this route has only s,z: "
                                 "drop --map or give an x,y,z route")
            say(route.notes)
            _check_memory(args, route, vehicle, None if made is None else made.spacing_m)
            profile = plan(
                route, vehicle, segment_length_m=args.segment_length, roughness_window_m=args.roughness_window,
                path_tolerance_m=tolerance, model=args.model, force_margin=args.force_margin,
                keep_contact=args.keep_contact, smoothing=args.smoothing,
                max_jerk_mps3=args.max_jerk, v0_mps=args.v0, vend_mps=args.vend, method=args.method,
                band=args.band, refine=args.refine, progress=progress,
                solver_options=SolverOptions(nlp_solver=args.solver),
            )
            progress.expect(sum(name is not None for name in (args.plot, args.map)))
            if args.output is not None:
                write_profile(profile, args.output, route=route)
            if args.plot is not None:
                from ..viz.plots import plot_profile

                progress.step(f"drawing {printable(args.plot)}")
                plot_profile(profile, args.plot, route=route_name, vehicle=vehicle_name)
            if args.map is not None:
                from ..viz.maps import plot_plan_map

                progress.step(f"drawing {printable(args.map)}")
                plot_plan_map(profile, made if made is not None else _plain_map(route), args.map,
                              route=route_name, vehicle=vehicle_name)
        # the route and the vehicle first, as compare's JSON names them
        summary = {"route": args.route, "vehicle": args.vehicle, **profile.summary()}
        say = _notes(args)  # the display has ended
        say(summary["notes"])  # the plan's, then each turn sharper than the turning circle
        smoothing = track.smoothing if track is not None else None
        if smoothing is not None:
            summary["track"] = {"smoothed": smoothing.smoothed, "tolerance_m": smoothing.tolerance_m,
                                "source": smoothing.tolerance_source, "noise_m": smoothing.noise.noise_m,
                                "points": smoothing.noise.points, "moved_max_m": smoothing.moved_max_m}
        if report is not None:
            report(summary, outputs)
    return summary, outputs.uses_stdout


def _route_file(args: argparse.Namespace, say):  # noqa: ANN001, ANN202  (Route)
    """A route CSV, with the roughness the options assume, if any, in place of the file's
    (``say`` prints the note that says so)."""
    import dataclasses

    from ..io.routes import read_route

    try:
        route = read_route(args.route)
    except InputError as exc:
        if "lacks the columns" not in str(exc):
            raise
        raise InputError(f"{exc}; a track of x,y points is planned with --terrain TERRAIN") from None
    assumed = assumed_roughness(args)
    if assumed is not None:
        if route.assumed_roughness is not None:
            say([f"{args.route}: its assumed roughness ({route.assumed_roughness.label}) is replaced by "
                          f"{assumed.label}"])
        route = dataclasses.replace(route, assumed_roughness=assumed)
    return route


def _notes(args: argparse.Namespace, progress=None):  # noqa: ANN001, ANN202  (Callable[[Iterable[str]], None])
    """What prints notes on stderr, in the command line's words (``--v0``, not ``v0_mps``),
    above the progress display if one is shown; nothing with ``--quiet``."""
    from ..progress import NO_PROGRESS, print_line
    from .messages import flags_for_parameters

    def say(notes) -> None:  # noqa: ANN001
        if not args.quiet:
            for note in notes:
                print_line(progress or NO_PROGRESS, f"profileopt plan: note: {flags_for_parameters(note)}")

    return say


def _check_max_memory(args: argparse.Namespace) -> None:
    """Refuse a --max-memory that is not a number > 0 (inf: no bound)."""
    if not args.max_memory > 0:
        raise InputError(f"--max-memory {args.max_memory:g}: must be a number > 0 in GB ('inf': no bound)")


def _check_memory(args: argparse.Namespace, route, vehicle, spacing_m: float | None) -> None:  # noqa: ANN001
    """Refuse, before planning, a route whose plan would need more than --max-memory
    (:func:`profileopt.cli.memory.check_plan_memory`); a bad --segment-length (not > 0, or
    more segments than samples) is left to the planner to refuse, naming it."""
    import math

    from .memory import PlanMemory, check_plan_memory

    if not (math.isfinite(args.segment_length) and args.segment_length > 0) or (
            route.length_m / args.segment_length > route.s_m.size):
        return  # more segments than samples: the planner refuses it, naming --segment-length
    check_plan_memory(args.route, PlanMemory(route.s_m.size, route.length_m, args.segment_length, args.refine,
                                             vehicle), args.max_memory, spacing_m=spacing_m)


def _check_track_memory(args: argparse.Namespace, track, vehicle) -> None:  # noqa: ANN001
    """The memory check of a track before it is sampled, where its spacing is known: given
    (--spacing) or the default of a track without a terrain (a terrain's is chosen as it is
    read, and checked once the route is made)."""
    import math

    from ..defaults import DEFAULT_TRACK_SPACING_M
    from ..io.tracks import track_length_m
    from .memory import PlanMemory, check_plan_memory

    spacing = args.spacing if args.spacing is not None else DEFAULT_TRACK_SPACING_M if args.terrain is None else None
    if spacing is None or not (math.isfinite(spacing) and spacing > 0) or not (
            math.isfinite(args.segment_length) and args.segment_length > 0):
        return  # the sampler or the planner refuses a bad one, naming it
    length = track_length_m(track)
    samples = int(length / spacing) + 1
    if length / args.segment_length > samples:
        return  # more segments than samples: the planner refuses it, naming --segment-length
    check_plan_memory(args.route, PlanMemory(samples, length, args.segment_length, args.refine, vehicle),
                      args.max_memory, spacing_m=spacing)


def _plain_map(route):  # noqa: ANN001, ANN202
    """A map without terrain of a route file's x, y."""
    import numpy as np

    from ..terrain.ground_track import TrackRoute

    return TrackRoute(route=route, crs_name="", track_x_m=route.x_m, track_y_m=route.y_m, terrain_kind="route file",
                      roughness_measured=route.assumed_roughness is None, density_per_m2=None, resolution="",
                      gaps_m=np.zeros((0, 2)), comments=(), notes=())


def _ratio(m: dict) -> str:
    return "off or unused" if m["ratio"] is None else f"{100 * m['ratio']:.1f} % of limit at s = {m['s_m']:g} m"


def _backend(backend: str | None) -> str:
    """The back end as the summary line names it ("" when no NLP was solved)."""
    return "" if backend is None else f"{backend}, "


def _human(summary: dict, args: argparse.Namespace) -> str:
    from ..io.atomic import STDOUT  # already imported by the run

    slow = summary["slowest_segment"]
    margins = summary["margins"]
    solver = summary["solver"]
    lines = [
        f"route {args.route}: {summary['distance_m']:.1f} m in {summary['segments']} segments, "
        f"vehicle {args.vehicle}, model {_label(summary['model'])}",
        f"  travel time  {summary['travel_time_s']:.2f} s   mean speed {summary['mean_speed_mps']:.2f} m/s",
        f"  slowest      {slow['s_start_m']:g}-{slow['s_end_m']:g} m at {slow['top_speed_mps']:.3g} m/s: "
        f"{slow['reason']}",
        f"  force        {_ratio(margins['force'])}",
        *([f"  roughness    assumed, not measured: {summary['roughness']['label']} (RI {summary['roughness']['ri']:.4g} "
           f"over {summary['roughness']['window_m']:g} m windows)"]
          if summary.get("roughness", {}).get("source") == "assumed" else []),
        *(f"  {name:<12} {_ratio(margins[key])}" for key, name in (("lateral", "lateral"), ("friction", "friction"))
          if key in margins),
        *([_path_line(summary)] if "path" in summary or "track" in summary else []),
        f"  acceleration {_ratio(margins['accel'])}",
        f"  deceleration {_ratio(margins['decel'])}",
        *([f"  power        {_ratio(margins['power'])}"] if "power" in margins else []),
        f"  jerk         {_ratio(margins['jerk'])}",
        "  binding      " + ", ".join(f"{name} {100 * share:.0f} %" for name, share in summary["binding"].items())
        + " of the distance",
        *([f"  limits off   {', '.join(summary['limits_off'])} (not in the vehicle file)"]
          if summary["limits_off"] else []),
        f"  solver       {solver['status']} ({_backend(solver['backend'])}{solver['iterations']} NLP iterations"
        + (f" over {solver['pieces']} pieces" if solver["pieces"] > 1 else "")
        + f"), planned in {solver['time_s']:.3f} s",
    ]
    if args.output is not None:
        lines.append("wrote the profile to standard output" if args.output == STDOUT else f"wrote {args.output}")
    for picture in (args.plot, args.map):
        if picture is not None:
            lines.append(f"wrote {picture}")
    return "\n".join(lines)




def _path_line(summary: dict) -> str:
    """The path tolerance the turns were found with, and why."""
    parts = []
    track = summary.get("track")
    if track is not None:
        why = "given" if track["source"] == "given" else (f"estimated: GPS noise {track['noise_m']:.3g} m over "
                                                           f"{track['points']} points, times sqrt(2 ln n)")
        parts.append(f"the track's points moved onto the smoothest path within {track['tolerance_m']:.3g} m ({why})"
                     if track["smoothed"] else f"the track's points kept (noise {track['noise_m']:.3g} m estimated)")
    path = summary.get("path")
    if path is not None:
        why = "given" if path["source"] == "given" else f"estimated from the x,y: noise {path['noise_m']:.3g} m"
        text = f"tolerance {path['tolerance_m']:.3g} m ({why})"
        if path.get("sharp_turns"):
            circle = path.get("min_turn_radius_m")
            text += (f", {path['sharp_turns']} turn(s) sharper than min_turn_radius_m {circle:g} m, crawled"
                     if circle is not None else f", {path['sharp_turns']} reversal(s)")
        parts.append(text)
    return "  path         " + "; ".join(parts)


def _label(model: str) -> str:
    from ..physics.forces import get_model

    return get_model(model).label


def _share(text: str) -> float:
    """A number in [0, 1) for --force-margin, or argparse's one-line error."""
    value = number_argument(text)
    if not 0.0 <= value < 1.0:
        raise argparse.ArgumentTypeError(f"{value:g}: give a share of the force limit, from 0 to below 1")
    return value
