"""Benchmark of the online speed selector (issue 31): its compute time per cycle, and how much
slower driving with only the sensed terrain is than the offline plan.

Run by hand, never by the test suite (minutes; the numbers depend on the machine and on what
else runs on it)::

    python benchmarks/bench_online.py                     # bundled courses, both vehicles
    python benchmarks/bench_online.py --routes trail --vehicles atv --ranges 50

For each bundled route and vehicle: the offline plan (``plan`` with its defaults) once, then
``drive`` (the closed loop of ``profileopt drive``, 0.1 s cycle) at each sensing range with
``unseen`` set to the route's own roughest ISO 8608 class (the Done-when of issue 31) and with
``"worst"`` (class H, the default). Each drive times every cycle of the selector (sensing and
update, ``time.perf_counter``), in this process, after one warm-up drive that pays the imports
and CasADi's first builds. Prints a Markdown table: the per-cycle median, 99th percentile and
worst (ms), the driven travel time, the offline plan's, their ratio, the worst simulated
roughness window over the limit and the emergencies. Beside the offline plan, the offline plan
with ``band="first"``: the selector keeps to the first band (it must be able to slow down
anywhere), so the second ratio is the cost of seeing only so far, the first that and the band.
"""

from __future__ import annotations

import argparse
import sys
import time

ROUTES = ("trail", "washboard", "krc_rms_1in", "krc_rms_2in", "krc_rms_4in", "curb")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--routes", default=",".join(ROUTES), help="bundled route names, comma-separated")
    parser.add_argument("--vehicles", default="atv,atv-resonant", help="bundled vehicles, comma-separated")
    parser.add_argument("--ranges", default="20,50,100", help="sensing ranges in m, comma-separated")
    parser.add_argument("--unseen", default="route,worst",
                        help="assumptions for unseen terrain, comma-separated: 'route' (the route's roughest class), "
                             "'worst', a class or an RI")
    args = parser.parse_args(argv)
    from pathlib import Path

    from profileopt import load_vehicle, plan, read_route
    from profileopt.core.segments import route_roughness_windows
    from profileopt.online import drive
    from profileopt.terrain.classes import smoothest_class_covering

    folder = Path(__file__).resolve().parents[1] / "examples" / "routes"
    warm = read_route(folder / "curb.csv")
    drive(warm, load_vehicle("atv"), sensor_range_m=50.0)  # imports, CasADi's first builds
    print("| route | vehicle | unseen | range (m) | cycles | median (ms) | p99 (ms) | worst (ms) | driven (s) "
          "| offline (s) | driven / offline | offline, first band (s) | driven / that | worst window / limit "
          "| emergencies | max jerk (m/s^3) |")
    print("|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for name in args.routes.split(","):
        route = read_route(folder / f"{name}.csv")
        for vehicle_name in args.vehicles.split(","):
            vehicle = load_vehicle(vehicle_name)
            offline = plan(route, vehicle).travel_time_s
            first = plan(route, vehicle, band="first").travel_time_s  # as the selector: slow down anywhere
            windows = route_roughness_windows(route, vehicle, window_m=5.0)
            own = smoothest_class_covering(float(windows.ri.max()), window_m=windows.window_m,
                                           clearance_m=vehicle.ground_clearance_m)
            for unseen in args.unseen.split(","):
                assumed = own if unseen == "route" else unseen
                label = f"{assumed} (route's)" if unseen == "route" else assumed
                for sensing in (float(r) for r in args.ranges.split(",")):
                    started = time.perf_counter()
                    driven = drive(route, vehicle, sensor_range_m=sensing, unseen=assumed)
                    ms = driven.compute_ms()
                    print(f"| {name} | {vehicle_name} | {label} | {sensing:g} | {driven.cycle_s_m.size:,} "
                          f"| {ms['median']:.2f} | {ms['p99']:.2f} | {ms['max']:.2f} | {driven.travel_time_s:.1f} "
                          f"| {offline:.1f} | {driven.travel_time_s / offline:.3f} | {first:.1f} "
                          f"| {driven.travel_time_s / first:.3f} | {driven.worst_window_ratio:.3f} "
                          f"| {driven.emergencies} | {driven.max_jerk_mps3:.2f} |", flush=True)
                    print(f"  {name} {vehicle_name} {label} {sensing:g} m: {time.perf_counter() - started:.0f} s",
                          file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
