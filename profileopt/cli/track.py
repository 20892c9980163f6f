"""What ``profileopt route`` and ``profileopt plan`` share about tracks and terrain maps:
their options, and the route they make of a track over a terrain."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from ..defaults import DEFAULT_CORRIDOR_M, DEFAULT_MAX_GAP_M, DEFAULT_TRACK_SPACING_M

if TYPE_CHECKING:
    from ..terrain.ground_track import TrackRoute

#: File name endings that are tracks, never route CSVs.
TRACK_SUFFIXES = (".gpx", ".geojson", ".json")
#: The ISO 8608 classes, for ``--roughness-class``.
ROAD_CLASSES = tuple("ABCDEFGH")


def number_argument(text: str) -> float:
    """An option's number, or argparse's one-line error."""
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"'{text}' is not a number") from None


def _index(text: str) -> int:
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"'{text}' is not a whole number") from None


def add_track_arguments(parser: argparse.ArgumentParser) -> None:
    """The options that turn a track and a terrain map into a route."""
    group = parser.add_argument_group("tracks and terrain maps (profileopt[geo])")
    group.add_argument("--terrain", metavar="FILE",
                       help="the ground under the track: a point cloud (.las, .laz), a DEM (.tif) or an OpenCRG "
                            "surface (.crg); without it, a track's own elevations (GPX <ele>)")
    group.add_argument("--spacing", type=number_argument, default=DEFAULT_TRACK_SPACING_M, metavar="M",
                       help=f"distance between route samples along the track in m (default: {DEFAULT_TRACK_SPACING_M:g}, "
                            "half the bundled vehicles' wheel radius)")
    group.add_argument("--corridor", type=number_argument, default=DEFAULT_CORRIDOR_M, metavar="M",
                       help="half-width in m of the strip around the wheel path whose ground points give the "
                            f"elevation (default: {DEFAULT_CORRIDOR_M:g}, about one tyre's width in all)")
    group.add_argument("--max-gap", type=number_argument, default=DEFAULT_MAX_GAP_M, metavar="M",
                       help="longest stretch without ground data bridged by a straight line, in m; a longer one "
                            f"is refused (default: {DEFAULT_MAX_GAP_M:g})")
    group.add_argument("--track-crs", metavar="CRS",
                       help="CRS of a CSV track's x,y, e.g. EPSG:32633 (GPX and GeoJSON are WGS 84); "
                            "default: the terrain's")
    group.add_argument("--terrain-crs", metavar="CRS", help="CRS of a terrain file that states none, e.g. EPSG:32633")
    group.add_argument("--track-index", type=_index, default=None, metavar="N",
                       help="use only track N (from 0) of a GPX file with several tracks")
    rough = group.add_mutually_exclusive_group()
    rough.add_argument("--roughness-class", choices=ROAD_CLASSES, type=str.upper, metavar="A-H",
                       help="assume this ISO 8608 road class's roughness where the terrain cannot measure it "
                            "(the terrain then gives the geometry and grade)")
    rough.add_argument("--ri", type=number_argument, metavar="VALUE",
                       help="assume this Roughness Index (RI = STD(e)/h over a roughness window) instead")


def is_track(path: str, args: argparse.Namespace) -> bool:
    """Whether a ``plan`` input is a track (to be sampled over a terrain) rather than a route CSV."""
    return args.terrain is not None or Path(path).suffix.lower() in TRACK_SUFFIXES


def track_inputs(args: argparse.Namespace) -> list[str]:
    """The files a track-reading command reads besides the track (for the output checks)."""
    return [args.terrain] if args.terrain is not None else []


def assumed_roughness(args: argparse.Namespace):  # noqa: ANN201  (AssumedRoughness | None)
    """The roughness the options assume (``--roughness-class`` or ``--ri``), or None."""
    if args.roughness_class is None and args.ri is None:
        return None
    from ..terrain.assumed import AssumedRoughness

    return AssumedRoughness(road_class=args.roughness_class, ri=args.ri)


def track_route(track_path: str, args: argparse.Namespace, prog: str) -> "TrackRoute":
    """Read the track and the terrain and sample the ground along the track; notes go to stderr.

    Parameters
    ----------
    track_path : str
        The track file (GPX, GeoJSON or CSV of x,y).
    args : argparse.Namespace
        The options of :func:`add_track_arguments`.
    prog : str
        The command's name for the notes ("profileopt route").

    Returns
    -------
    TrackRoute
    """
    from ..io.terrain_maps import read_terrain
    from ..io.tracks import read_track
    from ..terrain.ground_track import route_from_track

    terrain = read_terrain(args.terrain, terrain_crs=args.terrain_crs) if args.terrain is not None else None
    track = read_track(track_path, track_crs=args.track_crs, track_index=args.track_index)
    result = route_from_track(track, terrain, spacing_m=args.spacing, corridor_m=args.corridor,
                              max_gap_m=args.max_gap, assumed_roughness=assumed_roughness(args))
    from .messages import flags_for_parameters

    for note in (*track.notes, *getattr(terrain, "notes", ()), *result.notes):
        print(f"{prog}: note: {flags_for_parameters(note)}", file=sys.stderr)
    return result


def refuse_track_options(route_path: str, args: argparse.Namespace) -> None:
    """Refuse the options of a track over a terrain given with a route file, which has its samples.

    Raises
    ------
    InputError
        One of ``--spacing``, ``--corridor``, ``--max-gap``, ``--track-crs``, ``--terrain-crs``,
        ``--track-index`` differs from its default.
    """
    from ..errors import InputError

    defaults = {"spacing": DEFAULT_TRACK_SPACING_M, "corridor": DEFAULT_CORRIDOR_M, "max_gap": DEFAULT_MAX_GAP_M,
                "track_crs": None, "terrain_crs": None, "track_index": None}
    given = [name for name, default in defaults.items() if getattr(args, name) != default]
    if given:
        flags = ", ".join("--" + name.replace("_", "-") for name in given)
        raise InputError(f"{route_path}: {flags} apply to a track sampled over a terrain (--terrain TERRAIN); this is a route "
                         "file, already sampled: drop them, or give the track and --terrain")
