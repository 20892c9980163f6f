"""Roughness Index of real 3-D terrain: airborne LiDAR of a steep mountain slope, in patches.

Run:  python examples/lidar_roughness.py [LAS_FILE] [--out PNG] [--tile-m 10] [--vehicle atv]

The paper defines the RI on a point cloud (Eq. 1: RI = STD(e / h) of a terrain patch). Here
the patches are real: the ground points of an airborne LiDAR survey, tiled into squares.
For each square the least-squares plane is removed (a constant slope is not roughness), the
RI is taken with h = the vehicle's ground clearance, and the RI is turned into the SBEM:TF
allowable speed from rest ('first'). Two maps (RI, allowable speed) are written to --out
and a summary is printed.

Data: ``hexbin-crop.las`` from PDAL (https://github.com/PDAL/PDAL,
``test/data/filters/hexbin-crop.las``), BSD licence (``LICENSE.txt`` beside the copy in
``data/real/pdal-lidar/`` of this repository). LAS 1.2, point format 1, WGS 84 / UTM zone 42N
(EPSG:32642) in metres: 38,367 points over 293 x 201 m, 35,318 of them classified ground.

Runtime: about 1 s.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
from matplotlib import patheffects
from matplotlib.colors import LogNorm
from matplotlib.figure import Figure

from profileopt import InputError, allowable_speed, load_vehicle, roughness_index
from profileopt.io import atomic_path
from profileopt.io import LAS_GROUND, read_las

DEFAULT_LAS = Path(__file__).resolve().parents[1] / "data" / "real" / "pdal-lidar" / "hexbin-crop.las"

# Patch size. The ground points here are about 0.9 m apart (median distance to the nearest
# neighbour), roughly 1 point per m^2. A 5 m square (the planner's segment length) would hold
# about 25 points, too few for a plane fit plus a spread; a 10 m square holds about 100.
# So 10 m squares, and a square needs at least MIN_POINTS ground points to get an RI (the
# squares cut by the edge of the surveyed area get fewer and are left blank).
TILE_M = 10.0
MIN_POINTS = 30
SLOW_MPS = 5.0  # the summary counts the patches whose allowable speed is below this


def tile_points(xyz_m: np.ndarray, tile_m: float) -> tuple[np.ndarray, np.ndarray, list[np.ndarray]]:
    """Group points into tile_m squares of a grid aligned to multiples of tile_m.

    Returns the (column, row) index of each occupied square, shape (T, 2), the grid's
    south-west corner (m), shape (2,), and the points of each square, a list of (M_t, 3).
    """
    origin = np.floor(xyz_m[:, :2].min(axis=0) / tile_m) * tile_m
    cell = np.floor((xyz_m[:, :2] - origin) / tile_m).astype(int)
    cells, which = np.unique(cell, axis=0, return_inverse=True)
    order = np.argsort(which.ravel(), kind="stable")
    groups = np.split(xyz_m[order], np.cumsum(np.bincount(which.ravel()))[:-1])
    return cells, origin, groups


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("las", nargs="?", type=Path, default=DEFAULT_LAS, help="LAS point cloud (default: %(default)s)")
    parser.add_argument("--out", type=Path, default=Path("figures") / "lidar_roughness.png", help="PNG to write (default: %(default)s)")
    parser.add_argument("--tile-m", type=float, default=TILE_M, help="side of a square patch in m (default: %(default)s)")
    parser.add_argument("--vehicle", default="atv", help="bundled vehicle name or .toml file (default: %(default)s)")
    args = parser.parse_args(argv)
    if not args.las.is_file():
        print(f"{args.las}: LiDAR data not found; pass the path of hexbin-crop.las "
              "(PDAL's test/data/filters/hexbin-crop.las)", file=sys.stderr)
        return 2
    try:
        cloud = read_las(args.las)
        vehicle = load_vehicle(args.vehicle)
    except InputError as exc:
        print(exc, file=sys.stderr)
        return 2
    label = Path(vehicle.name).stem or args.vehicle  # "atv" for the bundled file atv.toml

    # 1. The ground points (class 2), in metres (read_las applies scale, offset and units).
    ground = cloud.xyz_m(LAS_GROUND)

    # 2. Square patches, and the RI of each (Eq. 1, least-squares plane removed) with h = the
    #    vehicle's ground clearance (0.1 m for the Table 1 ATV).
    cells, origin, groups = tile_points(ground, args.tile_m)
    counts = np.array([len(g) for g in groups])
    used = counts >= MIN_POINTS
    ri = np.array([roughness_index(g, vehicle.ground_clearance_m) for g, ok in zip(groups, used) if ok])

    # 3. The allowable speed from rest of each patch under SBEM:TF ('first': every speed from
    #    0 up to it keeps the transmitted force within the limit; NOTES.md "Which root").
    speed_mps = np.asarray(allowable_speed(ri, vehicle, model="sbem_tf", band="first"), dtype=float)

    # 4. Summary. What to expect: the slope here is steep (the fitted planes tilt 15-40
    #    degrees) and a 10 m plane leaves the curvature of ridges and gullies in the residual,
    #    plus the LiDAR's own vertical noise (centimetres to a decimetre). Against a 0.1 m
    #    clearance that is a large RI (median ~1.8, i.e. a residual spread of ~0.18 m), and
    #    SBEM:TF allows only walking to jogging speeds almost everywhere.
    pct = np.percentile(ri, [5, 25, 50, 75, 95])
    print(f"{args.las.name}: {len(cloud)} points, {len(ground)} ground (class {LAS_GROUND}), "
          f"CRS {cloud.header.crs or 'not named'}")
    print(f"{len(groups)} squares of {args.tile_m:g} m with ground points, {used.sum()} with >= {MIN_POINTS} "
          f"points (median {np.median(counts[used]):.0f} points)")
    print(f"RI (h = {vehicle.ground_clearance_m:g} m, plane removed) percentiles 5/25/50/75/95: "
          + " / ".join(f"{p:.2f}" for p in pct))
    print(f"SBEM:TF allowable speed from rest for {label}: median {np.median(speed_mps):.2f} m/s, "
          f"{np.mean(speed_mps < SLOW_MPS):.0%} of patches below {SLOW_MPS:g} m/s")

    # 5. Two maps on the tile grid (blank: outside the survey or too few points).
    shape = tuple(cells.max(axis=0) + 1)
    ri_map = np.full(shape, np.nan)
    speed_map = np.full(shape, np.nan)
    height_map = np.full(shape, np.nan)  # mean ground elevation of each patch (m), for contours
    ri_map[tuple(cells[used].T)] = ri
    speed_map[tuple(cells[used].T)] = speed_mps
    height_map[tuple(cells[used].T)] = [g[:, 2].mean() for g, ok in zip(groups, used) if ok]
    edges_x = origin[0] + args.tile_m * np.arange(shape[0] + 1)
    edges_y = origin[1] + args.tile_m * np.arange(shape[1] + 1)
    # Axes in metres from the grid's south-west corner; the corner's UTM coordinates in the title.
    east, north = edges_x - origin[0], edges_y - origin[1]

    centres_x = 0.5 * (east[:-1] + east[1:])
    centres_y = 0.5 * (north[:-1] + north[1:])
    levels = np.arange(np.floor(np.nanmin(height_map) / 10) * 10, np.nanmax(height_map) + 10, 10.0)

    fig = Figure(figsize=(12, 5.0), layout="constrained")
    ax_ri, ax_v = fig.subplots(1, 2, sharex=True, sharey=True)
    mesh = ax_ri.pcolormesh(east, north, ri_map.T, cmap="magma_r", norm=LogNorm(vmin=max(ri.min(), 0.1), vmax=ri.max()))
    fig.colorbar(mesh, ax=ax_ri, shrink=0.8, label=f"RI (h = {vehicle.ground_clearance_m:g} m), log scale")
    ax_ri.set_title(f"Roughness Index of {args.tile_m:g} m patches (plane removed)")
    # The speed scale tops out at SLOW_MPS: yellow patches allow that speed or more.
    mesh = ax_v.pcolormesh(east, north, speed_map.T, cmap="viridis", vmin=0.0, vmax=SLOW_MPS)
    fig.colorbar(mesh, ax=ax_v, shrink=0.8, extend="max", label="allowable speed from rest (m/s)")
    ax_v.set_title(f"SBEM:TF allowable speed from rest, {label}")
    # each label has a halo of the opposite shade, so it reads on dark and light patches alike
    for ax, colour, halo in ((ax_ri, "0.1", "white"), (ax_v, "0.95", "black")):
        contours = ax.contour(centres_x, centres_y, height_map.T, levels=levels, colors=colour, linewidths=0.7)
        labels = ax.clabel(contours, levels[::2], fontsize=7, fmt="%.0f m")
        for text in labels:
            text.set_path_effects([patheffects.withStroke(linewidth=2.0, foreground=halo)])
        ax.set_aspect("equal")
        ax.set_facecolor("0.85")
        ax.set_xlabel(f"easting - {origin[0]:.0f} m (m)")
    ax_ri.set_ylabel(f"northing - {origin[1]:.0f} m (m)")
    fig.suptitle(f"{args.las.name} (PDAL, BSD licence), {cloud.header.crs or 'CRS not named'}: "
                 f"{used.sum()} patches of ground points\ncontours: mean elevation of the patches, every 10 m; "
                 f"grey: outside the survey or < {MIN_POINTS} points")
    args.out.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(args.out) as tmp:
        fig.savefig(tmp, dpi=110, format="png")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
