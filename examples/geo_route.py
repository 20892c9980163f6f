"""From a GPS track and a LiDAR cloud to a verified plan, in Python (the walk-through of docs/guide/data-sources.md).

Run:  python examples/geo_route.py [--track GPX] [--terrain LAZ] [--road-class C]
                                   [--vehicle atv-low-range] [--out PNG]

``profileopt route`` and ``profileopt plan TRACK --terrain TERRAIN`` do this on the command
line; here are the same steps through the library, for a program of your own:

1. read the track (GPX, in WGS 84) and the terrain (a LAZ cloud, in UTM): ``read_track``,
   ``read_terrain``;
2. sample the ground under the wheels along the track: ``route_from_track``. This airborne
   cloud has about one ground point per m^2, far too sparse for wheel-scale roughness, so a
   roughness is assumed (an ISO 8608 class): the cloud gives the geometry and the grade;
3. plan the route (``plan``) and check it in simulation (``verify``: the route's elevation
   plus a random profile of the assumed class);
4. draw the plan over the terrain (``plot_plan_map``).

Data: PDAL's ``hexbin-crop.las`` (BSD licence, ``data/real/pdal-lidar/``), compressed to LAZ,
and a track drawn along one of its contours (``examples/geo/hexbin-track.gpx``). Needs the
``geo`` extra (``pip install -e '.[geo]'``). Runtime: a few seconds.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from profileopt import InputError, load_vehicle, plan, verify
from profileopt.terrain.assumed import AssumedRoughness
from profileopt.terrain.ground_track import route_from_track
from profileopt.io import read_terrain, read_track
from profileopt.viz.maps import plot_plan_map

REPO = Path(__file__).resolve().parents[1]
DEFAULT_TRACK = REPO / "examples" / "geo" / "hexbin-track.gpx"
DEFAULT_TERRAIN = REPO / "data" / "real" / "pdal-lidar" / "hexbin-crop.laz"
# The GPX points are 5 m apart along a drawn contour: a path tolerance of 2 m lets the smoothed
# path cut the polyline's corners as a driver would (the default, 0.1 m, suits a surveyed path).
PATH_TOLERANCE_M = 2.0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description="plan a GPS track over a LiDAR cloud and check it in simulation")
    parser.add_argument("--track", type=Path, default=DEFAULT_TRACK, help="GPX track (default: examples/geo/hexbin-track.gpx)")
    parser.add_argument("--terrain", type=Path, default=DEFAULT_TERRAIN, help="LAS/LAZ cloud (default: data/real/pdal-lidar/hexbin-crop.laz)")
    parser.add_argument("--road-class", default="C", help="assumed ISO 8608 class A-H (default: %(default)s)")
    parser.add_argument("--vehicle", default="atv-low-range", help="bundled vehicle (default: %(default)s)")
    parser.add_argument("--out", type=Path, default=Path("geo_route.png"), help="map PNG (default: %(default)s)")
    args = parser.parse_args(argv)
    try:
        vehicle = load_vehicle(args.vehicle)
        # 1. the track and the ground
        track = read_track(args.track)
        cloud = read_terrain(args.terrain)
        # 2. the route under the wheels: too sparse to measure roughness, so a class is assumed
        made = route_from_track(track, cloud, assumed_roughness=AssumedRoughness(road_class=args.road_class))
        print(f"route: {made.route.length_m:.1f} m, {made.route.s_m.size} samples in {made.crs_name}; "
              f"roughness assumed ({made.route.assumed_roughness.label}): {made.resolution}")
        # 3. the plan, and the plan driven in simulation over ground of the assumed roughness
        profile = plan(made.route, vehicle, path_tolerance_m=PATH_TOLERANCE_M)
        check = verify(made.route, profile, vehicle, path_tolerance_m=PATH_TOLERANCE_M)  # as planned
        print(f"plan: {profile.travel_time_s:.2f} s; simulated: {check.windows.over_count} of "
              f"{check.windows.count} roughness windows over the force limit")
        # 4. the map
        plot_plan_map(profile, made, args.out, route=args.track.name, vehicle=args.vehicle)
    except InputError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
