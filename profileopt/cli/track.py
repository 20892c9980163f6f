"""What ``profileopt route`` and ``profileopt plan`` share about tracks and terrain maps: their
options and the checks of them (the route they make of a track over a terrain:
:func:`profileopt.cli.route.smoothed_track_route`)."""

from __future__ import annotations

import argparse
from pathlib import Path

from ..defaults import DEFAULT_CORRIDOR_M, DEFAULT_MAX_GAP_M, DEFAULT_TRACK_SPACING_M, MAX_ROUGHNESS_SPACING_M

#: File name endings that are tracks, never route CSVs.
TRACK_SUFFIXES = (".gpx", ".geojson", ".json")
#: The ISO 8608 classes, for ``--roughness-class``.
ROAD_CLASSES = tuple("ABCDEFGH")
#: The longest stretch without ground points the default ``--max-gap`` of a point cloud
#: bridges (m): five wheel radii of the bundled vehicles. A missing strip of ground (a hole in
#: the scan, a lake, a shadow) longer than this is refused however dense the cloud.
MAX_DEFAULT_GAP_M = 0.5
#: The expected number of stretches without ground points longer than the default
#: ``--max-gap`` that a point cloud's random scatter leaves along a route (a false refusal
#: once in a hundred routes).
DEFAULT_GAP_RISK = 0.01


def number_argument(text: str) -> float:
    """An option's number in ASCII decimal notation (``inf`` and ``nan`` too, which the options
    refuse or allow themselves), or argparse's one-line error."""
    from ..io.table import decimal_number, quoted  # when an option is parsed, not for --help

    value = decimal_number(text)
    if value is None:
        raise argparse.ArgumentTypeError(f"{quoted(text)} is not a number (digits 0-9, '.', an optional exponent)")
    return value


def whole_number_argument(text: str, *, minimum: int | None = None, what: str = "") -> int:
    """An option's whole number in ASCII digits (not ``1_0`` or an Arabic-Indic digit, which
    ``int()`` reads), at least ``minimum`` if given, or argparse's one-line error naming
    ``what`` it counts (``"a seed"``)."""
    from ..io.table import quoted  # when an option is parsed, not for --help

    digits = text.strip()
    if not (digits.isascii() and digits.removeprefix("-").removeprefix("+").isdigit()):
        raise argparse.ArgumentTypeError(f"{quoted(text)} is not a whole number (digits 0-9)"
                                         + (f"; give {what} >= {minimum}" if minimum is not None else ""))
    value = int(digits)
    if minimum is not None and value < minimum:
        raise argparse.ArgumentTypeError(f"{value}: give {what or 'a number'} >= {minimum}")
    return value


def add_track_arguments(parser: argparse.ArgumentParser) -> None:
    """The options that turn a track and a terrain map into a route."""
    group = parser.add_argument_group("tracks and terrain maps (profileopt[geo])")
    group.add_argument("--terrain", metavar="FILE", nargs="+", action="extend",
                       help="the ground under the track: a point cloud (.las, .laz), a DEM (.tif) or an OpenCRG "
                            "surface (.crg); or tiles: several LAS/LAZ or GeoTIFF files, or a folder of them (only "
                            "those near the track are read); without it, a track's own elevations (GPX <ele>)")
    group.add_argument("--spacing", type=number_argument, default=None, metavar="M",
                       help="distance between route samples along the track in m (default: the finest the terrain "
                            f"resolves, from {DEFAULT_TRACK_SPACING_M:g}, half the bundled vehicles' wheel radius, up "
                            f"to {MAX_ROUGHNESS_SPACING_M:g}, their wheel radius; {DEFAULT_TRACK_SPACING_M:g} without "
                            "a terrain)")
    group.add_argument("--corridor", type=number_argument, default=DEFAULT_CORRIDOR_M, metavar="M",
                       help="half-width in m of the strip around the wheel path whose ground points give the "
                            f"elevation (default: {DEFAULT_CORRIDOR_M:g}, about one tyre's width in all)")
    group.add_argument("--max-gap", type=number_argument, default=None, metavar="M",
                       help="longest stretch without ground data bridged by a straight line, in m; a longer one "
                            "is refused (default: for a point cloud that measures roughness, the shortest from "
                            f"{DEFAULT_MAX_GAP_M:g} up to {MAX_DEFAULT_GAP_M:g} that its density leaves by chance "
                            f"less than once in {1 / DEFAULT_GAP_RISK:g} routes, with a note; else "
                            f"{DEFAULT_MAX_GAP_M:g})")
    group.add_argument("--track-crs", metavar="CRS",
                       help="CRS of a CSV track's x,y, e.g. EPSG:32633 (GPX and GeoJSON are WGS 84); "
                            "default: the terrain's")
    group.add_argument("--terrain-crs", metavar="CRS", help="CRS of a terrain file that states none, e.g. EPSG:32633")
    group.add_argument("--track-index", type=whole_number_argument, default=None, metavar="N",
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
    """The files a track-reading command reads besides the track (for the output checks): the
    terrain files, a folder of tiles as its files."""
    if args.terrain is None:
        return []
    from ..io.tiles import terrain_files

    return [str(path) for path in terrain_files(args.terrain)]


def terrain_words(args: argparse.Namespace) -> str:
    """The ``--terrain`` files as typed, for a title or a summary (empty without one)."""
    return " ".join(args.terrain) if args.terrain else ""


def assumed_roughness(args: argparse.Namespace):  # noqa: ANN201  (AssumedRoughness | None)
    """The roughness the options assume (``--roughness-class`` or ``--ri``), or None."""
    if args.roughness_class is None and args.ri is None:
        return None
    from ..terrain.assumed import AssumedRoughness

    return AssumedRoughness(road_class=args.roughness_class, ri=args.ri)


def default_max_gap_m(track, terrain, args: argparse.Namespace) -> tuple[float, str | None]:  # noqa: ANN001
    """The longest stretch without ground points bridged when ``--max-gap`` is not given,
    and a note saying which.

    A point cloud's ground points lie at random: in a corridor of width w = 2 ``--corridor``
    with rho ground points per m^2, a stretch of length g holds none with probability
    exp(-rho w g), so a route of length L sampled every h (each of its L / h bins a place
    such a stretch may begin) meets about (L / h) exp(-rho w h floor(g / h)) of them. The
    default is the shortest g from :data:`~profileopt.defaults.DEFAULT_MAX_GAP_M` up in
    steps of 0.1 m that expects at most :data:`DEFAULT_GAP_RISK` of them, at the spacing the
    cloud is sampled at for that g (``--spacing``, or the one
    :func:`profileopt.terrain.ground_track.cloud_spacing_m` chooses); at most
    :data:`MAX_DEFAULT_GAP_M`, so that a real hole, a strip of missing ground, is still
    refused. Measured: 135 ground points per m^2 (UAV LiDAR) give 0.4 m on a 1 km strip,
    100 per m^2 0.5 m. A DEM, an OpenCRG surface, a cloud too sparse to measure roughness (the
    ground then comes from the triangulation of its points) and no terrain get
    :data:`~profileopt.defaults.DEFAULT_MAX_GAP_M`.

    Parameters
    ----------
    track : Track
        The track (:func:`profileopt.io.read_track`).
    terrain : PointCloud, ElevationGrid, CrgSurface or None
        The terrain read around it.
    args : argparse.Namespace
        The options of :func:`add_track_arguments` (``--spacing``, ``--corridor``).

    Returns
    -------
    max_gap_m : float
        The longest stretch bridged (m).
    note : str or None
        What was chosen and why, for a point cloud.
    """
    if terrain is None or not hasattr(terrain, "classification") or len(terrain) == 0:
        return DEFAULT_MAX_GAP_M, None
    import math

    import numpy as np

    from ..errors import InputError
    from ..terrain.ground_track import cloud_spacing_m, corridor_bins, resample_polyline, track_on_terrain_m

    corridor = args.corridor
    if not (math.isfinite(corridor) and corridor > 0) or (args.spacing is not None and not (
            math.isfinite(args.spacing) and args.spacing > 0)):
        return DEFAULT_MAX_GAP_M, None  # refused by the sampler, naming the option
    source = getattr(terrain, "source", None) or getattr(getattr(terrain, "header", None), "path", "terrain")
    try:
        tx, ty = track_on_terrain_m(track, terrain.crs, str(source))
    except InputError:
        return DEFAULT_MAX_GAP_M, None  # the sampler says why
    s, x, y = resample_polyline(tx, ty, DEFAULT_TRACK_SPACING_M)
    length = float(s[-1])
    if x.size < 2 or not length > 0:
        return DEFAULT_MAX_GAP_M, None
    ground = terrain.classification == 2 if terrain.is_classified else np.ones(len(terrain), dtype=bool)
    gx, gy = terrain.x_m[ground], terrain.y_m[ground]
    reach = corridor + DEFAULT_TRACK_SPACING_M
    near = (gx >= x.min() - reach) & (gx <= x.max() + reach) & (gy >= y.min() - reach) & (gy <= y.max() + reach)
    kept, _ = corridor_bins(np.column_stack([gx[near], gy[near]]), np.column_stack([x, y]), corridor)
    density = kept.size / (2.0 * corridor * length)
    if cloud_spacing_m(density, corridor, length) is None:  # too sparse to measure roughness: triangulated
        return DEFAULT_MAX_GAP_M, None
    steps = int(round((MAX_DEFAULT_GAP_M - DEFAULT_MAX_GAP_M) / 0.1))
    for k in range(steps + 1):
        gap = round(DEFAULT_MAX_GAP_M + 0.1 * k, 10)
        spacing = args.spacing if args.spacing is not None else cloud_spacing_m(density, corridor, length, gap)
        run = max(math.floor(gap / spacing + 1e-9), 1)
        expected = length / spacing * math.exp(-density * 2.0 * corridor * spacing * run)
        if expected <= DEFAULT_GAP_RISK:
            break
    if gap == DEFAULT_MAX_GAP_M:
        return gap, None  # dense enough for the fixed default: nothing to say
    return gap, (f"{source}: --max-gap {gap:g} m: stretches without ground points up to {gap:g} m are bridged, "
                 f"as its {density:.3g} ground points per m^2 within {corridor:g} m of the track leave such gaps by "
                 f"chance (a longer one expected {expected:.2g} times over {length / 1000:.3g} km at {spacing:g} m "
                 "spacing); a longer stretch is refused; --max-gap sets another")


def refuse_terrain_options(args: argparse.Namespace) -> None:
    """Refuse the options of a terrain without ``--terrain``: ``--terrain-crs`` has no
    terrain file to apply to, ``--corridor`` and ``--max-gap`` no terrain to take points
    from (a track's own elevations are used, every one of them).

    Parameters
    ----------
    args : argparse.Namespace
        The options of :func:`add_track_arguments`.

    Raises
    ------
    InputError
        ``--terrain-crs``, ``--corridor`` or ``--max-gap`` given (not at its default) and
        ``--terrain`` not.
    """
    if args.terrain is not None:
        return
    from ..errors import InputError

    if args.terrain_crs is not None:
        from ..io.table import quoted

        raise InputError(f"--terrain-crs {quoted(args.terrain_crs)[1:-1]} sets the CRS of a terrain file, and no --terrain "
                         "is given; drop it, or give the terrain (--terrain FILE); the track's CRS is --track-crs")
    given = [flag for flag, value, default in (("--corridor", args.corridor, DEFAULT_CORRIDOR_M),
                                               ("--max-gap", args.max_gap, None)) if value != default]
    if given:
        verb, them = ("applies", "it") if len(given) == 1 else ("apply", "them")
        raise InputError(f"{' and '.join(given)} {verb} to the ground points of a terrain (--terrain TERRAIN), and no "
                         f"--terrain is given: the track's own elevations are used; drop {them}, or give the terrain")


def refuse_track_options(route_path: str, args: argparse.Namespace) -> None:
    """Refuse the options of a track over a terrain given with a route file, which has its samples.

    Raises
    ------
    InputError
        One of ``--spacing``, ``--corridor``, ``--max-gap``, ``--track-crs``, ``--terrain-crs``,
        ``--track-index`` differs from its default.
    """
    from ..errors import InputError

    defaults = {"spacing": None, "corridor": DEFAULT_CORRIDOR_M, "max_gap": None,
                "track_crs": None, "terrain_crs": None, "track_index": None}
    given = [name for name, default in defaults.items() if getattr(args, name) != default]
    if given:
        flags = ", ".join("--" + name.replace("_", "-") for name in given)
        verb, them = ("applies", "it") if len(given) == 1 else ("apply", "them")
        raise InputError(f"{route_path}: {flags} {verb} to a track sampled over a terrain (--terrain TERRAIN); this is a "
                         f"route file, already sampled: drop {them}, or give the track and --terrain")
