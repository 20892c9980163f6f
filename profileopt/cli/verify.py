"""``profileopt verify``: check a planned profile against a simulated vehicle.

It checks a profile against the vehicle's own limits, drives the vehicle's quarter car over
the route at its speeds and judges the drive by roughness windows: in every window
[a, a + W] of the route, the simulated peak force while the vehicle is inside it beside the
window's own prediction (recomputed from the speeds) and the limit; the same per segment.
Its exit status is a verdict a script or CI can gate on (:data:`VERIFY_EXIT_STATUSES`). It
prints only numbers that do not depend on the machine, so the same input gives the same
output bytes on every run.

It trusts nothing the profile says of itself (issue 30). The bounds are the vehicle's and the
project's defaults (:mod:`profileopt.defaults`), or verify's own ``--max-jerk``,
``--path-tolerance`` and ``--roughness-window`` (as plan's); where the profile's settings line
records others, a note says so, and the verdict names every bound checked, with its value and
source, and every bound not checked. The vehicle is the one the settings line records (an
absolute path or a bundled name), refused when its bytes are not the ones planned with
(``vehicle_sha256``), and counted among the inputs no output may replace. Memory grows with
the route (:func:`profileopt.verification.verify.estimated_peak_bytes`: about 1.4 kB per route
sample and 0.42 kB per time step of the simulation, on top of 0.16 GB); a route that would
need more than ``--max-memory`` (1.5 GB by default) is refused before any work.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import os
import sys
from pathlib import Path

from ..defaults import DEFAULT_PATH_TOLERANCE_M, DEFAULT_ROUGHNESS_WINDOW_M, PLAN_MODEL_KEYS
from ..errors import InputError
from .messages import printable
from .paths import vehicle_input
from .route import PATH_TOLERANCE_HELP
from .track import number_argument, whole_number_argument


def _vehicle_files(args: argparse.Namespace, profile) -> list[str]:
    """Every vehicle file verify may read: --vehicle's, and the one the profile records (a
    bundled name's file too), whether or not it is then used or refused."""
    files = [vehicle_input(args.vehicle)]
    recorded = str(profile.settings.get("vehicle", ""))
    if recorded not in ("", "unnamed"):
        if vehicle_input(recorded) is not None:
            files.append(recorded)
        else:
            from ..core.vehicle import load_vehicle

            try:
                files.append(load_vehicle(recorded).name)
            except InputError:
                pass  # no such bundled vehicle: refused when it is looked for
    return files


def _vehicle_of(args: argparse.Namespace, profile) -> tuple[str, str | None, list[str]]:
    """The vehicle to verify with, the file it reads, and notes.

    Without --vehicle: the one the profile records (an absolute path or a bundled name, with
    the SHA-256 of the file planned with: a file there whose bytes differ is refused). With
    --vehicle: that one, as asked; the same bytes under any name are the vehicle planned
    with, other bytes are used with a note saying so (compared by path for an older profile
    that records no SHA-256).
    """
    from ..io.profiles import vehicle_file_sha256

    recorded = str(profile.settings.get("vehicle", ""))
    digest = profile.settings.get("vehicle_sha256")
    notes = []
    if recorded in ("", "unnamed"):
        if args.vehicle is None:
            raise InputError(f"{args.profile}: the profile does not record its vehicle; pass --vehicle")
        return args.vehicle, vehicle_input(args.vehicle), notes
    if args.vehicle is not None:
        found, sha = vehicle_file_sha256(args.vehicle)
        if digest is not None:
            same, how = sha == digest, "its SHA-256 differs from the vehicle_sha256 the profile records"
        else:
            same, how = _same_vehicle(args.vehicle, recorded), ("another file; the profile records no SHA-256 of "
                                                                "its vehicle")
        if not same:
            notes.append(f"--vehicle {args.vehicle} is not the vehicle the profile was planned with ({recorded}; "
                         f"{how}): verified against --vehicle {args.vehicle}, as asked")
        return args.vehicle, found, notes
    if vehicle_input(recorded) is not None and not Path(recorded).exists():
        raise InputError(f"{args.profile}: the profile was planned with the vehicle file {recorded}, which is not "
                         "there; pass --vehicle FILE with that vehicle, or plan again")
    found, sha = vehicle_file_sha256(recorded)
    if digest is None:
        where = "" if Path(found).is_absolute() or vehicle_input(recorded) is None else \
            " (a relative path, from the current folder)"
        notes.append(f"the profile records no SHA-256 of its vehicle (written by an older profileopt): {found} is "
                     f"used as found{where}; pass --vehicle to choose another")
    elif sha != digest:
        raise InputError(f"{args.profile}: the vehicle file {found} is not the one the profile was planned with "
                         "(its SHA-256 differs from the vehicle_sha256 its settings line records: it was changed "
                         "or replaced since); plan again, or pass --vehicle FILE to verify against that file as it "
                         "is now")
    args.vehicle = recorded
    return recorded, found, notes


def _same_vehicle(given: str, recorded: str) -> bool:
    """Whether --vehicle names the vehicle an older profile (no SHA-256) records: the same
    bundled name, or the same file (a relative recorded path taken from the current folder)."""
    if vehicle_input(given) is None or vehicle_input(recorded) is None:
        return given == recorded
    try:
        return os.path.samefile(given, recorded)
    except OSError:  # one of them is not there
        return os.path.abspath(given) == os.path.abspath(recorded)


#: The default of ``--max-memory`` (GB): :data:`profileopt.verification.verify.MAX_VERIFY_PEAK_BYTES`,
#: written here so that ``--help`` imports no numerical package (a test holds them equal).
MAX_MEMORY_GB = 1.5

#: The exit status of ``profileopt verify``: the plan keeps every limit of the vehicle and no
#: roughness window's (nor segment's) simulated force exceeds the limit.
EXIT_PASSES = 0
#: The profile breaks one of the vehicle's own limits (speed, acceleration, jerk, predicted force).
EXIT_BREAKS_LIMITS = 3
#: The limits hold on paper, but the simulation puts a roughness window (or a segment) over
#: the force limit.
EXIT_OVER_IN_SIMULATION = 4
#: Every exit status of ``profileopt verify`` and its meaning (also in its ``--help``).
VERIFY_EXIT_STATUSES = {
    EXIT_PASSES: "the plan keeps every limit checked (the verdict names each, with its value: the vehicle's, or "
                 "an option of verify's) and no roughness window's (nor segment's) simulated force exceeds the "
                 "force limit",
    1: "internal error",
    2: "bad input (one line on stderr), e.g. a profile that does not cover its route exactly",
    EXIT_BREAKS_LIMITS: "the profile breaks one of the vehicle's own limits (speed, acceleration, jerk or "
                        "predicted force); the simulation is still reported when it can be run",
    EXIT_OVER_IN_SIMULATION: "the limits hold on paper, but the simulation puts a roughness window (or a segment) "
                             "over the force limit",
}


def _verdict(check, result=None) -> tuple[int, str]:
    """The exit status and the verdict line (``result`` None: not simulated)."""
    unchecked = f"; not checked: {', '.join(check.unchecked)}" if check.unchecked else ""
    if check.breaches:
        kinds = ", ".join(dict.fromkeys(b.quantity for b in check.breaches))
        return EXIT_BREAKS_LIMITS, (f"  verdict: the profile breaks the vehicle's limits ({kinds}); checked: "
                                    f"{', '.join(check.checked)}{unchecked}; exit {EXIT_BREAKS_LIMITS}")
    if result is not None and not result.passes:
        win = result.windows
        return EXIT_OVER_IN_SIMULATION, (
            f"  verdict: the profile keeps every limit checked on paper ({', '.join(check.checked)}), but in "
            f"simulation {win.over_count} of {win.count} roughness windows ({win.window_m:g} m) and "
            f"{result.over_count} of {result.ratio.size} segments exceed the force limit{unchecked}; "
            f"exit {EXIT_OVER_IN_SIMULATION}")
    return EXIT_PASSES, (f"  verdict: the profile keeps every limit checked ({', '.join(check.checked)}) and no "
                         f"roughness window or segment exceeds the force limit in simulation{unchecked}; "
                         f"exit {EXIT_PASSES}")


def run(args: argparse.Namespace) -> int:
    """Run ``profileopt verify``; returns the verdict's status (:data:`VERIFY_EXIT_STATUSES`)."""
    from ..core.vehicle import load_vehicle
    from ..io import read_profile, read_route
    from ..io.atomic import OutputSet  # imported when the command runs, not for --help (issue 14)
    from ..physics.forces import get_model
    from ..verification.limit_check import check_limits
    from ..verification.verify import check_memory, estimated_peak_bytes, verify
    from ..io.atomic import STDOUT
    from ..progress import terminal_progress
    from ..viz.plots import plot_verification

    from .track import TRACK_SUFFIXES

    _check_bounds(args)
    if Path(args.route).suffix.lower() in TRACK_SUFFIXES:
        from ..io.inputs import check_regular_input

        check_regular_input(args.route, "route file")  # a path that is not there: not found, first
        raise InputError(f"{args.route}: verify drives a route file, not a track: make one with 'profileopt route "
                         f"{args.route} --terrain TERRAIN -o route.csv' (or '--roughness-class CLASS' without a "
                         "terrain map), plan and verify that")
    # the profile first (small beside the route): it names the vehicle file, which is an input
    # as much as one typed on the command line
    profile = read_profile(args.profile)
    # then, before any other check or work: every output checked (none may be an input, nor
    # both the same file); then written together, all or none
    outputs = OutputSet([("-o", args.output, True), ("--plot", args.plot)],
                        inputs=[args.route, args.profile, *_vehicle_files(args, profile)])
    reference, _, vehicle_notes = _vehicle_of(args, profile)
    unsimulated = None
    # the outputs are put in place when this block ends: after the progress display has ended
    # and the summary is printed, so a full standard output replaces no file
    with outputs:
        with terminal_progress("profileopt verify", enabled=not args.quiet) as progress:
            progress.expect(3 + (args.output is not None) + (args.plot is not None))
            progress.step(f"reading {printable(Path(args.route).name)}")
            route = read_route(args.route)
            vehicle = load_vehicle(reference)
            check_memory(route, profile, vehicle, None if math.isinf(args.max_memory) else args.max_memory * 1e9,
                         fix=f"pass --max-memory GB (about "
                             f"{math.ceil(estimated_peak_bytes(route, profile, vehicle)[0] / 1e8) / 10:g})")
            progress.step("checking the limits on paper")
            check = check_limits(route, profile, vehicle, model=args.model, max_jerk_mps3=args.max_jerk,
                                 path_tolerance_m=args.path_tolerance, roughness_window_m=args.roughness_window)
            check = dataclasses.replace(check, notes=(*vehicle_notes, *check.notes))
            model = get_model(check.model)
            header = (f"verified {args.profile} on {args.route} with vehicle {args.vehicle}, "
                      f"model {model.label} ({model.quantity} force, limit {check.limit_n:g} N)")
            progress.step("simulating the drive")
            try:
                result = verify(route, profile, vehicle, model=args.model, check=check, roughness_seed=args.seed,
                                max_peak_bytes=None)  # checked above
            except InputError as exc:
                if not check.breaches:
                    raise
                # a profile so far beyond the vehicle's limits that it cannot be simulated (1e155 m/s):
                # reported once the display has ended, nothing written
                unsimulated = str(exc)
            if unsimulated is None:
                # the names written into the CSV's header and the picture's title: a file name that
                # is not UTF-8 with U+FFFD for its bytes, as in the summary (matplotlib refuses the rest)
                named = dataclasses.replace(result, route=printable(str(result.route)),
                                            vehicle=printable(str(result.vehicle)))
                if args.output is not None:
                    progress.step("writing the table" if args.output == STDOUT else
                                  f"writing {printable(args.output)}")
                    named.to_csv(args.output)
                if args.plot is not None:
                    progress.step(f"drawing {printable(args.plot)}")
                    plot_verification(named, args.plot)
        if unsimulated is None:
            out = sys.stderr if outputs.uses_stdout else sys.stdout  # standard output holds the table
            status, verdict = _verdict(check, result)
            # the summary is printed before the files are renamed into place (OutputSet.print): a
            # full standard output replaces none of them
            if args.json:
                text = json.dumps(result.summary(timings=False) | {"exit_status": status}, indent=2)
            else:  # a file name not in UTF-8: U+FFFD
                text = printable(_summary_text(args, check, result, header, verdict))
            outputs.print(text, out)
    if unsimulated is not None:
        return _report_unsimulated(args, check, header, unsimulated)
    return status


def _summary_text(args: argparse.Namespace, check, result, header: str, verdict: str) -> str:  # noqa: ANN001
    """The lines verify prints after a simulation."""
    from ..io.atomic import STDOUT

    i = result.worst_segment
    win = result.windows
    worst = win.describe(win.worst)
    lines = [
        header,
        verdict,
        *(f"  {breach.describe()}" for breach in check.breaches),
        f"  roughness windows ({win.window_m:g} m) over the limit: {win.over_count} of {win.count} "
        f"({100 * win.over_count / win.count:.1f} %)",
        f"  worst window: {worst['start_m']:g} to {worst['stop_m']:g} m (RI {worst['ri']:.3f}, speeds "
        f"{worst['speed_low_mps']:.3g} to {worst['speed_high_mps']:.3g} m/s): {_ratio_text(worst['ratio'])} of the "
        f"limit, {worst['simulated_n']:.0f} N simulated at s = {worst['peak_s_m']:.2f} m, "
        f"{worst['predicted_n']:.0f} N predicted, limit {worst['limit_n']:g} N",
        f"  windows where the simulation exceeds the prediction by > 1 % of the limit: "
        f"{int(win.underpredicted.sum())}",
        f"  segments over the limit: {result.over_count} of {result.ratio.size} "
        f"({100 * result.over_fraction:.1f} %, {result.over_length_m:g} m)",
        f"  worst segment, simulated / limit: {_ratio_text(result.worst_ratio)} in the segment from s = {result.s_m[i]:g} m "
        f"({result.simulated_n[i]:.0f} N simulated, {result.predicted_n[i]:.0f} N predicted)",
        f"  segments where the simulation exceeds the prediction by > 1 % of the limit: "
        f"{int(result.underpredicted.sum())}",
        f"  segments where the wheel would leave the ground (F_T < -m g = {-result.weight_n:.0f} N): "
        f"{int(result.lift_off.sum())}",
        f"  simulated {result.travel_time_s:.2f} s of driving in {result.run.steps} steps of "
        f"{1e3 * result.run.time_step_s:.4f} ms",
    ]
    lines += [] if args.quiet else [f"  note: {note}" for note in result.notes]
    if args.output is not None:
        lines.append("wrote the table to standard output" if args.output == STDOUT else f"wrote {args.output}")
    if args.plot is not None:
        lines.append(f"wrote {args.plot}")
    return "\n".join(lines)


def _check_bounds(args: argparse.Namespace) -> None:
    """Refuse a bound option that is not a number > 0 (finite, but for --max-jerk inf)."""
    for flag, value, unit, finite in (("--max-jerk", args.max_jerk, "m/s^3", False),
                                      ("--max-memory", args.max_memory, "GB", False),
                                      ("--path-tolerance", args.path_tolerance, "m", True),
                                      ("--roughness-window", args.roughness_window, "m", True)):
        if value is not None and not (value > 0 and (math.isfinite(value) or not finite)):
            also = " ('inf' turns the check off)" if flag == "--max-jerk" else ""
            raise InputError(f"{flag} {value:g}: must be a number > 0 in {unit}{also}")


def _report_unsimulated(args: argparse.Namespace, check, header: str, reason: str) -> int:
    """The verdict of a profile that breaks the limits and cannot be simulated; nothing is written."""
    status, verdict = _verdict(check)
    unwritten = [name for name in (args.output, args.plot) if name]
    if args.json:
        print(json.dumps({"route": str(args.route), "vehicle": str(args.vehicle), "model": check.model,
                          "segments": int(check.predicted_n.size), "keeps_limits": False,
                          "checked": list(check.checked), "not_checked": list(check.unchecked),
                          "breaches": [b.to_dict() for b in check.breaches], "simulated": False,
                          "not_simulated": reason, "notes": list(check.notes), "exit_status": status}, indent=2))
        return status
    lines = [header, verdict, *(f"  {breach.describe()}" for breach in check.breaches),
             f"  not simulated: {reason}"]
    lines += [] if args.quiet else [f"  note: {note}" for note in check.notes]
    if unwritten:
        lines.append(f"not written (there is no simulation to write): {', '.join(unwritten)}")
    print(printable("\n".join(lines)))
    return status


def arguments(parser: argparse.ArgumentParser) -> None:
    parser.epilog = "exit status: " + "; ".join(f"{code}: {text}" for code, text in
                                                sorted(VERIFY_EXIT_STATUSES.items())) + "."
    parser.add_argument("route", help="route CSV (the terrain the profile was planned on)")
    parser.add_argument("profile", help="profile CSV written by 'profileopt plan -o'")
    parser.add_argument("--vehicle", default=None, metavar="NAME_OR_TOML",
                        help="bundled vehicle name or .toml file (default: the vehicle the profile "
                             "records; another one is used as asked, with a note that it is not the one planned "
                             "with)")
    parser.add_argument("--model", default=None, choices=list(PLAN_MODEL_KEYS),
                        help="force model to check against (default: the model the profile records)")
    # the bounds are verify's own, never read from the profile's settings line (a note says
    # where that differs): the vehicle's and the project's defaults unless given here
    parser.add_argument("--max-jerk", type=number_argument, default=None, metavar="MPS3",
                        help="jerk bound in m/s^3 to check (default: the vehicle file's; 'inf': not checked)")
    parser.add_argument("--path-tolerance", type=number_argument, default=DEFAULT_PATH_TOLERANCE_M, metavar="M",
                        help=PATH_TOLERANCE_HELP + "; as plan's")
    parser.add_argument("--roughness-window", type=number_argument, default=DEFAULT_ROUGHNESS_WINDOW_M, metavar="M",
                        help="roughness window in m: the segments' RI and the windows judged (default: "
                             f"{DEFAULT_ROUGHNESS_WINDOW_M:g}, as plan's)")
    parser.add_argument("-o", "--output", metavar="CSV",
                        help="write one row per segment to this CSV, with the worst roughness window that meets "
                             "it ('-': standard output, the summary then goes to stderr)")
    parser.add_argument("--plot", metavar="PNG", help="write forces along s and simulated vs predicted per window")
    parser.add_argument("--json", action="store_true", help="print the summary as JSON")
    parser.add_argument("-q", "--quiet", action="store_true",
                        help="no notes and no progress display (the verdict and errors are still said)")
    parser.add_argument("--max-memory", type=number_argument, default=MAX_MEMORY_GB, metavar="GB",
                        help="refuse, before any work, a route whose verification needs more memory than this, in "
                             "GB ('inf': no bound; default: %(default)g, what planning the largest route needs). "
                             "It needs about 1.4 kB per route sample and 0.42 kB per time step of the simulation, "
                             "on top of 0.16 GB: 1 GB for about 550,000 samples (a 10 MB s,z file), 3.5 GB for 40 MB")
    parser.add_argument("--seed", type=_seed, default=0, metavar="N",
                        help="for a route with an assumed roughness (a '# roughness_class' or '# roughness_ri' "
                             "line): the seed of the random ISO 8608 profile added to its elevation for the "
                             "simulation (default: 0); unused for other routes")


def _seed(text: str) -> int:
    """A whole number >= 0 for --seed, or argparse's one-line error."""
    return whole_number_argument(text, minimum=0, what="a seed")


def _ratio_text(ratio: float) -> str:
    """A force ratio with 3 decimals, or 3 significant digits when it is absurdly large."""
    return f"{ratio:.3f}" if ratio < 1e6 else f"{ratio:.3g}"
