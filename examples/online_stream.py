"""Online speed selection in a control loop: terrain points and odometry in, a speed command out,
every cycle.

Run:  python examples/online_stream.py [--route ROUTE.csv] [--vehicle atv] [--sensor-range 50]
                                       [--cycle 0.1] [--unseen worst] [--noise 0.005]
                                       [--realtime] [--every 10]

Adapt it to your robot: replace ``sensor_stream`` by your drivers. Each cycle they give the
vehicle's odometry (distance along the path in m, speed in m/s) and the ground points the
perception stack measured since the last cycle near the wheel track, as (s along the path, z)
in m, with their own noise and density. This script stands in for them with a generator that
reveals a bundled route within the sensing range and adds Gaussian noise, and a vehicle that
does exactly what it is told.

The loop is the whole API (docs: guide/online.md):

    selector = SpeedSelector(vehicle, sensor_range_m=50, unseen="worst", end_m=path_length)
    every cycle:
        selector.sense(s_m, z_m)                  # what was measured since the last cycle
                                                  # (speed_limit_mps=... from a map, if any)
        command = selector.update(position, speed)
        send command.accel_mps2 (or command.speed_mps) to the drive

Points closer than 0.1 m apart along the path count as measured; a wider gap makes what lies
beyond it unseen until it is filled, and unseen ground is driven as the ``unseen`` assumption
allows. The printout: one line every ``--every`` cycles with the command, how far ahead the
plan reaches, and the time the selector took.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import Iterator

import numpy as np

from profileopt import load_vehicle, read_route
from profileopt.online import SpeedSelector

ROUTES = Path(__file__).resolve().parent / "routes"


def sensor_stream(route, sensor_range_m: float, noise_m: float, seed: int = 0
                  ) -> Iterator[tuple[np.ndarray, np.ndarray, np.ndarray | None]]:
    """Stands in for the perception stack and the map: given the vehicle's position (sent in),
    the route's samples newly within range, with noise on z (m), and the map's speed limits
    there (m/s; None without). A generator: ``stream.send(position_m)``."""
    rng = np.random.default_rng(seed)
    revealed = 0
    position = yield np.empty(0), np.empty(0), None
    while True:
        upto = int(np.searchsorted(route.s_m, position + sensor_range_m, side="right"))
        s = route.s_m[revealed:upto]
        z = route.z_m[revealed:upto] + rng.normal(0.0, noise_m, size=s.size)
        limits = None if route.speed_limit_mps is None else route.speed_limit_mps[revealed:upto]
        revealed = max(revealed, upto)
        position = yield s, z, limits


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    parser.add_argument("--route", type=Path, default=ROUTES / "trail.csv", help="route CSV revealed as it is driven")
    parser.add_argument("--vehicle", default="atv", help="bundled vehicle name or .toml file")
    parser.add_argument("--sensor-range", type=float, default=50.0, help="sensing range (m)")
    parser.add_argument("--cycle", type=float, default=0.1, help="control cycle (s)")
    parser.add_argument("--unseen", default="worst", help="assumption for unseen terrain: worst, a class A-H or an RI")
    parser.add_argument("--noise", type=float, default=0.0, help="standard deviation of the sensed elevations (m)")
    parser.add_argument("--realtime", action="store_true", help="wait for each cycle, as a robot's loop does")
    parser.add_argument("--every", type=int, default=10, help="print one line every this many cycles")
    args = parser.parse_args(argv)

    route = read_route(args.route)
    vehicle = load_vehicle(args.vehicle)
    selector = SpeedSelector(vehicle, sensor_range_m=args.sensor_range, unseen=args.unseen, cycle_s=args.cycle,
                             start_m=float(route.s_m[0]), end_m=float(route.s_m[-1]))
    stream = sensor_stream(route, args.sensor_range, args.noise)
    next(stream)
    position, speed, clock = float(route.s_m[0]), 0.0, 0.0
    compute_ms = []
    print(f"{'t (s)':>8} {'s (m)':>9} {'v (m/s)':>8} {'a cmd (m/s^2)':>14} {'plan ahead (m)':>15} {'ms':>6}")
    for cycle in range(10_000_000):
        if position >= route.s_m[-1] - 0.01 and speed <= 0:
            break
        started = time.perf_counter()
        s_new, z_new, limits = stream.send(position)  # the drivers' new points, the map's limits
        selector.sense(s_new, z_new, speed_limit_mps=limits)
        command = selector.update(position, speed)
        compute_ms.append((time.perf_counter() - started) * 1e3)
        if cycle % args.every == 0 or command.emergency:
            print(f"{clock:8.1f} {position:9.2f} {speed:8.2f} {command.accel_mps2:14.2f} "
                  f"{command.edge_m - position:15.1f} {compute_ms[-1]:6.2f}"
                  + (f"  EMERGENCY: {command.note}" if command.emergency else ""))
        if args.realtime:
            time.sleep(max(args.cycle - (time.perf_counter() - started), 0.0))
        # the vehicle does what it is told: the command's acceleration for one cycle
        position, speed = command.position_next_m, command.speed_mps
        clock += args.cycle
    print(f"arrived after {clock:.1f} s; selector per cycle: median {np.median(compute_ms):.2f} ms, 99th percentile "
          f"{np.percentile(compute_ms, 99):.2f} ms")
    return 0


if __name__ == "__main__":
    sys.exit(main())
