"""Benchmark of ``profileopt batch`` (issue 32): a batch of 40 routes on a local Dask cluster
against the same 40 planned one after another in one process.

Run by hand, never by the test suite (minutes; the numbers depend on the machine)::

    pip install -e '.[batch]'
    python benchmarks/bench_batch.py                 # 40 routes, 2 workers, 3 repeats
    python benchmarks/bench_batch.py --workers 2 --repeats 1

The routes: the bundled ones (``examples/routes/*.csv``) and seeded ISO 8608 profiles of
classes A-E (300 m at 0.05 m) to make 40. Each is planned with the vehicle ``atv`` and the
default options. Timed side by side, repeat by repeat, in one run:

``serial``
    :func:`profileopt.batch.plan_many` with ``workers=1``: one route after another in this
    process (the imports paid once, before the clock starts);
``dask``
    the same rows on a ``LocalCluster`` of ``--workers`` processes, one thread each, from
    the cluster's start to the last result (workers start and import within the time).

Every profile of the Dask batch must be the same bytes as the serial batch's. Prints a
Markdown table: median seconds and the ratio serial / dask.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def make_routes(folder: Path, count: int) -> list[Path]:
    from profileopt.core.route import Route
    from profileopt.io.routes import write_route
    from profileopt.terrain.synthetic import iso8608_profile

    routes = sorted((ROOT / "examples" / "routes").glob("*.csv"))[:count]
    seed = 0
    while len(routes) < count:
        road_class = "ABCDE"[seed % 5]
        s_m, z_m = iso8608_profile(road_class, 300.0, 0.05, seed)
        path = folder / f"iso_{road_class}_{seed}.csv"
        write_route(Route(s_m, z_m, source=path.name), path)
        routes.append(path)
        seed += 1
    return routes


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--routes", type=int, default=40)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args(argv)
    from profileopt.batch import BatchRow, plan_many

    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        rows = [BatchRow(f"r{k:02d}_{path.stem}", str(path), (("vehicle", "atv"),))
                for k, path in enumerate(make_routes(folder, args.routes))]
        plan_many(rows[:1], folder / "warm", workers=1)  # imports, once
        times: dict[str, list[float]] = {"serial": [], "dask": []}
        for repeat in range(args.repeats):
            for name, workers in (("serial", 1), ("dask", args.workers)):
                out = folder / f"{name}{repeat}"
                started = time.perf_counter()
                result = plan_many(rows, out, workers=workers)
                times[name].append(time.perf_counter() - started)
                failed = {r["id"]: r["error"] for r in result if r["status"] != "ok"}
            for row in rows:
                if row.id in failed:  # refused by plan (a track without terrain, ...): the same in both
                    continue
                if (folder / f"serial{repeat}" / f"{row.id}.csv").read_bytes() != \
                        (folder / f"dask{repeat}" / f"{row.id}.csv").read_bytes():
                    print(f"{row.id}: the Dask batch's profile differs from the serial one", file=sys.stderr)
                    return 1
    serial, dask = statistics.median(times["serial"]), statistics.median(times["dask"])
    print("| routes | workers | serial, one process (s) | Dask LocalCluster (s) | serial / Dask |")
    print("|---|---|---|---|---|")
    print(f"| {args.routes} | {args.workers} | {serial:.1f} | {dask:.1f} | {serial / dask:.2f} |")
    print(f"\nmedians of {args.repeats} repeats; every profile the same bytes in both; {len(failed)} of the routes "
          f"refused by plan in both ({', '.join(sorted(failed))})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
