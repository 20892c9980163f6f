"""Benchmark of the dynamic model (issue 33): its plan time against SBEM:TF's on the same
route, at 10,000 segments.

Run by hand, never by the test suite (minutes; the numbers depend on the machine)::

    python benchmarks/bench_dynamic.py                       # 10 km, 10,000 segments of 1 m
    python benchmarks/bench_dynamic.py --length 2000 --repeats 1

The route: a seeded ISO 8608 profile whose class changes every kilometre (B, C, D, C, E, C,
B, D, C, B), sampled every 0.1 m, planned with ``--segment-length 1`` (10,000 segments for
10 km). Each vehicle's SBEM:TF plan and dynamic plan are timed in this process, alternately,
repeat by repeat (the imports and CasADi's first builds paid before the clock). Prints a
Markdown table: median seconds, the ratio dynamic / SBEM:TF, each plan's travel time and its
worst simulated |F_T| / limit.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time

CLASSES = "BCDCECBDCB"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--length", type=float, default=10_000.0, help="route length in m (default: 10000)")
    parser.add_argument("--segment-length", type=float, default=1.0, help="segment length in m (default: 1)")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args(argv)
    from profileopt import load_vehicle, plan
    from profileopt.core.route import Route
    from profileopt.studies.known_terrain import simulated_ratio
    from profileopt.terrain.synthetic import iso8608_sections

    piece = args.length / len(CLASSES)
    s_m, z_m = iso8608_sections([(c, piece) for c in CLASSES], 0.1, seed=0)
    route = Route(s_m, z_m, source=f"iso_sections_{args.length:g}m")
    warm = Route(s_m[:2001], z_m[:2001], source="warm")
    print("| vehicle | segments | SBEM:TF (s) | dynamic (s) | dynamic / SBEM:TF | travel time SBEM:TF / dynamic (s) "
          "| worst simulated / limit, SBEM:TF / dynamic |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    for name in ("atv", "atv-resonant"):
        vehicle = load_vehicle(name)
        plan(warm, vehicle, model="dynamic")
        times: dict[str, list[float]] = {"sbem_tf": [], "dynamic": []}
        plans = {}
        for _ in range(args.repeats):
            for model in ("sbem_tf", "dynamic"):
                started = time.perf_counter()
                plans[model] = plan(route, vehicle, model=model, segment_length_m=args.segment_length)
                times[model].append(time.perf_counter() - started)
        a, b = statistics.median(times["sbem_tf"]), statistics.median(times["dynamic"])
        ratios = [simulated_ratio(route, p.s_m, p.speed_mps, vehicle) for p in (plans["sbem_tf"], plans["dynamic"])]
        segments = int(round(route.length_m / args.segment_length))
        print(f"| {name} | {segments:,} | {a:.2f} | {b:.2f} | {b / a:.1f} "
              f"| {plans['sbem_tf'].travel_time_s:.0f} / {plans['dynamic'].travel_time_s:.0f} "
              f"| {ratios[0]:.3f} / {ratios[1]:.3f} |", flush=True)
    print(f"\nmedians of {args.repeats} repeats, alternating, in one process; route {route.length_m:g} m sampled every "
          "0.1 m")
    return 0


if __name__ == "__main__":
    sys.exit(main())
