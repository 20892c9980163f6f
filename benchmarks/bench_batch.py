"""Benchmark of ``profileopt batch`` (issue 32): 40 routes on a local Dask cluster against the
same 40 planned one after another in one process, each timed as a user runs it.

Run by hand, never by the test suite (minutes; the numbers depend on the machine)::

    pip install -e '.[batch]'
    python benchmarks/bench_batch.py                 # 40 routes, 2 workers, 3 repeats
    python benchmarks/bench_batch.py --workers 2 --repeats 1 --separate
    python benchmarks/bench_batch.py --route-length-m 3000   # routes of 3 km

The routes: the bundled ones (``examples/routes/*.csv``) and seeded ISO 8608 profiles of
classes A-E (``--route-length-m`` long, default 300 m, sampled every 0.05 m) to make 40.
Each is planned with the vehicle ``atv`` and the default options. Each way is a fresh process started from the shell, so each pays its own
imports, and they alternate, repeat by repeat, in one run:

``serial``
    ``profileopt batch ROUTES --workers 1``: one route after another in the command's own
    process, without Dask;
``dask``
    ``profileopt batch ROUTES --workers N``: a ``LocalCluster`` of N single-thread worker
    processes, started, imported and closed within the time;
``separate`` (with ``--separate``, once)
    40 runs of ``profileopt plan ROUTE -o ID.csv``, one after another (a shell loop).

Every profile of the Dask batch (and of the separate runs) must be the same bytes as the
serial batch's. Prints a Markdown table: median seconds and the ratios.
"""

from __future__ import annotations

import argparse
import csv
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))  # the benchmarks' shared helper
from installed import compile_package  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


def make_routes(folder: Path, count: int, length_m: float) -> list[Path]:
    from profileopt.core.route import Route
    from profileopt.io.routes import write_route
    from profileopt.terrain.synthetic import iso8608_profile

    routes = sorted((ROOT / "examples" / "routes").glob("*.csv"))[:count]
    seed = 0
    while len(routes) < count:
        road_class = "ABCDE"[seed % 5]
        s_m, z_m = iso8608_profile(road_class, length_m, 0.05, seed)
        path = folder / f"iso_{road_class}_{seed}.csv"
        write_route(Route(s_m, z_m, source=path.name), path)
        routes.append(path)
        seed += 1
    return routes


def _run(argv: list[str], cwd: Path) -> float:
    started = time.perf_counter()
    done = subprocess.run(argv, cwd=cwd, capture_output=True, text=True)
    elapsed = time.perf_counter() - started
    if done.returncode not in (0, 5):  # 5: some routes refused by plan (the same in every way)
        raise SystemExit(f"{' '.join(argv[:4])} ...: exit {done.returncode}: {done.stderr[-400:]}")
    return elapsed


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--routes", type=int, default=40)
    parser.add_argument("--route-length-m", type=float, default=300.0, help="length of the generated routes (m)")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--separate", action="store_true", help="also time one 'profileopt plan' per route")
    args = parser.parse_args(argv)
    print(compile_package(), file=sys.stderr)
    command = [sys.executable, "-m", "profileopt"]
    env_note = "OPENBLAS_NUM_THREADS=1" if os.environ.get("OPENBLAS_NUM_THREADS") == "1" else ""
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        routes = make_routes(folder, args.routes, args.route_length_m)
        ids = [f"r{k:02d}_{path.stem}" for k, path in enumerate(routes)]
        for route, ident in zip(routes, ids):  # batch names each profile after its route file: copies
            (folder / f"{ident}.csv").write_bytes(route.read_bytes())
        names = [f"{ident}.csv" for ident in ids]
        times: dict[str, list[float]] = {"serial": [], "dask": [], "separate": []}
        for repeat in range(args.repeats):
            for name, workers in (("serial", 1), ("dask", args.workers)):
                times[name].append(_run([*command, "batch", *names, "--vehicle", "atv", "-o", f"{name}{repeat}",
                                         "--workers", str(workers), "-q"], folder))
        if args.separate:
            (folder / "separate").mkdir()
            started = time.perf_counter()
            for name in names:
                subprocess.run([*command, "plan", name, "--vehicle", "atv", "-o", f"separate/{name}", "-q"],
                               cwd=folder, capture_output=True)
            times["separate"].append(time.perf_counter() - started)
        summary = {row["id"]: row for row in csv.DictReader(open(folder / "serial0" / "summary.csv"))}
        failed = sorted(ident for ident, row in summary.items() if row["status"] != "ok")
        for ident in ids:
            if ident in failed:
                continue
            reference = (folder / "serial0" / f"{ident}.csv").read_bytes()
            others = [folder / f"dask{r}" / f"{ident}.csv" for r in range(args.repeats)]
            if args.separate:
                others.append(folder / "separate" / f"{ident}.csv")
            for other in others:
                if other.read_bytes() != reference:
                    print(f"{other}: differs from the serial batch's profile", file=sys.stderr)
                    return 1
    serial, dask = statistics.median(times["serial"]), statistics.median(times["dask"])
    print("| routes | generated routes (m) | workers | serial batch, one process (s) | Dask LocalCluster (s) | serial / Dask |"
          + (" 40 separate plans (s) | separate / Dask |" if args.separate else ""))
    print("|---|---|---|---|---|---|" + ("---|---|" if args.separate else ""))
    line = (f"| {args.routes} | {args.route_length_m:.0f} | {args.workers} | {serial:.1f} | {dask:.1f} "
            f"| {serial / dask:.2f} |")
    if args.separate:
        line += f" {times['separate'][0]:.1f} | {times['separate'][0] / dask:.2f} |"
    print(line)
    print(f"\nmedians of {args.repeats} repeats, each a fresh process {env_note}; every profile the same bytes in "
          f"every way; {len(failed)} of the routes refused by plan in every way ({', '.join(failed)})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
