"""``profileopt route``: the route a vehicle drives along a GPS track over a terrain map."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from .. import __version__
from .track import (
    add_track_arguments,
    assumed_roughness,
    default_max_gap_m,
    number_argument,
    refuse_terrain_options,
    terrain_words,
    track_inputs,
)

if TYPE_CHECKING:
    from typing import Callable

    from ..io.tracks import Track
    from ..progress import Progress
    from ..terrain.ground_track import TrackRoute

#: ``--path-tolerance``'s help, shared with ``profileopt plan``.
PATH_TOLERANCE_HELP = ("how far in m the smoothed path, whose curvature limits the speed in turns, may stray from "
                       "a track's points (which are moved onto it) or an x,y,z route's (default: estimated from "
                       "the points' own scatter, their noise times sqrt(2 ln n), at least 0.1)")


def arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("track", help="the track: GPX (tracks or routes), a GeoJSON LineString, or a CSV of x,y")
    parser.add_argument("-o", "--output", required=True, metavar="CSV",
                        help="write the route CSV (x_m,y_m,z_m) here ('-': standard output)")
    parser.add_argument("--plot", metavar="PNG", help="draw the track over the terrain and the route's elevation")
    parser.add_argument("--path-tolerance", type=number_argument, default=None, metavar="M", help=PATH_TOLERANCE_HELP)
    parser.add_argument("-q", "--quiet", action="store_true",
                        help="no notes and no progress display on stderr (errors are still said)")
    add_track_arguments(parser)


def run(args: argparse.Namespace) -> int:
    from ..io.atomic import (  # imported when the command runs, not for --help (issue 14)
        STDOUT,
        OutputSet,
    )
    from ..progress import terminal_progress

    outputs = OutputSet([("-o", args.output, True), ("--plot", args.plot)], inputs=[args.track, *track_inputs(args)])
    from ..io.routes import write_route
    from .messages import printable

    # the outputs are put in place when this block ends: after the progress display has ended
    # and the summary is printed, so a full standard output replaces no file
    with outputs:
        with terminal_progress("profileopt route", enabled=not args.quiet) as progress:
            result, track = smoothed_track_route(args.track, args, "profileopt route", progress=progress)
            name = Path(args.output).name if args.output != STDOUT else "route"
            made = (f"profileopt {__version__} route {args.track}"
                    + (f" --terrain {terrain_words(args)}" if args.terrain else ""))
            # a file name that is not UTF-8 is written with U+FFFD for its bytes, as in the summary
            comments = [printable(line) for line in (
                f"{name}: the ground under the wheels along a track, made by `{made}`", *result.comments,
                *([f"x, y: {track.smoothing.note(Path(args.track).name)}"] if track.smoothing is not None else []),
                f"options: spacing {result.spacing_m:g} m, corridor {args.corridor:g} m, max gap {args.max_gap:g} m")]
            progress.expect(1 + (args.plot is not None))
            progress.step("writing the route" if args.output == STDOUT else f"writing {printable(args.output)}")
            write_route(result.route, args.output, comments=comments)
            if args.plot is not None:
                from ..viz.maps import plot_route_map

                progress.step(f"drawing {printable(args.plot)}")
                plot_route_map(result, args.plot, title=printable(f"{Path(args.track).name}"
                                                                  + (f" over {_terrain_name(args)}" if args.terrain
                                                                     else "")))
        # printed before the files are renamed into place: a full standard output replaces none
        out = sys.stderr if outputs.uses_stdout else sys.stdout
        outputs.print(printable(_human(result, args)), out)  # a file name not in UTF-8: U+FFFD
    return 0


def smoothed_track_route(track_path: str, args: argparse.Namespace, prog: str, *, progress: Progress | None = None,
                         before_sampling: Callable[[Track], None] | None = None) -> tuple[TrackRoute, Track]:
    """Read the track and the terrain and sample the ground along the track; notes go to stderr.

    The track's points are moved onto the smoothest path within ``--path-tolerance`` of them
    (or within the noise estimated from them: :func:`profileopt.io.read_track`). Before the
    terrain is read and the track sampled, the options and the track are checked: no
    ``--terrain-crs`` without ``--terrain``; without a terrain, no track in degrees taken as
    metres (:func:`profileopt.io.tracks.check_not_degrees`); no more samples than a route may
    have (:func:`profileopt.io.tracks.check_track_samples`). Without ``--max-gap``, the
    longest gap bridged follows from a point cloud's density (:func:`default_max_gap_m`);
    ``args.max_gap`` is then set to the one chosen.

    Parameters
    ----------
    track_path : str
        The track file (GPX, GeoJSON or CSV of x,y).
    args : argparse.Namespace
        The options of :func:`profileopt.cli.track.add_track_arguments` and ``path_tolerance``.
    prog : str
        The command's name for the notes ("profileopt route").
    progress : Progress, optional
        Told each step (reading the track, the terrain, sampling); notes are printed above
        its display (:func:`profileopt.progress.print_line`).
    before_sampling : callable, optional
        Called with the track once it is read and checked, before the terrain is read and
        the track sampled (``profileopt plan``'s memory check).

    Returns
    -------
    tuple of (TrackRoute, Track)
    """
    from ..defaults import DEFAULT_TRACK_SPACING_M
    from ..io.tiles import read_tiles
    from ..io.tracks import check_not_degrees, check_track_samples, read_track
    from ..progress import NO_PROGRESS, print_line
    from ..terrain.ground_track import route_from_track
    from .messages import flags_for_parameters, printable

    progress = NO_PROGRESS if progress is None else progress
    refuse_terrain_options(args)
    progress.expect(2 + (args.terrain is not None))
    progress.step(f"reading {printable(Path(track_path).name)}")
    track = read_track(track_path, track_crs=args.track_crs, track_index=args.track_index,
                       path_tolerance_m=args.path_tolerance)
    if args.terrain is None:
        check_not_degrees(track)
    if before_sampling is not None:
        before_sampling(track)
    # the finest spacing a terrain supports is at least the default: the count is an upper bound
    check_track_samples(track, DEFAULT_TRACK_SPACING_M if args.spacing is None else args.spacing)
    terrain = None
    if args.terrain is not None:
        progress.step(f"reading the terrain ({printable(_terrain_name(args))})")
        terrain = read_tiles(args.terrain, terrain_crs=args.terrain_crs, track=track, spacing_m=args.spacing,
                             corridor_m=args.corridor)
    progress.step("sampling the ground along the track")
    gap_notes = []
    if args.max_gap is None:
        args.max_gap, gap_note = default_max_gap_m(track, terrain, args)
        gap_notes = [gap_note] if gap_note else []
    result = route_from_track(track, terrain, spacing_m=args.spacing, corridor_m=args.corridor,
                              max_gap_m=args.max_gap, assumed_roughness=assumed_roughness(args))
    if not getattr(args, "quiet", False):
        for note in (*track.notes, *getattr(terrain, "notes", ()), *gap_notes, *result.notes):
            print_line(progress, f"{prog}: note: {flags_for_parameters(note)}")
    return result, track


def _terrain_name(args: argparse.Namespace) -> str:
    """The terrain in a title: its file's name, or the first tile's and how many more."""
    names = [Path(path).name or str(path) for path in args.terrain]
    return names[0] if len(names) == 1 else f"{names[0]} and {len(names) - 1} more"


def _human(result: object, args: argparse.Namespace) -> str:
    from ..io.atomic import STDOUT  # already imported by the run

    route = result.route
    z = route.z_m
    roughness = (f"assumed, {route.assumed_roughness.label} ({result.resolution})" if route.assumed_roughness
                 else f"measured ({result.resolution})" if result.terrain_kind != "track" else "")
    frame = result.crs_name or "the track's own frame (no CRS)"
    terrain = terrain_words(args) or "none (the track's own elevations)"
    lines = [
        f"route {args.track}: {route.length_m:.1f} m, {route.s_m.size} samples every {result.spacing_m:g} m, "
        f"x, y in {frame}",
        f"  terrain    {terrain} ({result.terrain_kind})",
        f"  roughness  {roughness}",
        f"  elevation  {z.min():.2f} to {z.max():.2f} m",
        "  gaps       " + (f"{len(result.gaps_m)} bridged by straight lines, the longest "
                           f"{(result.gaps_m[:, 1] - result.gaps_m[:, 0]).max():.2f} m" if len(result.gaps_m) else "none"),
    ]
    lines.append("wrote the route to standard output" if args.output == STDOUT else f"wrote {args.output}")
    if args.plot is not None:
        lines.append(f"wrote {args.plot}")
    return "\n".join(lines)


