"""Where `profileopt plan`'s wall time goes at 10,000 segments, stage by stage, and what each
stage could reach (issue 28).

The route is bench_plan.py's (10,000 segments of 5 m, ISO 8608 sections, sampled every
0.5 m, the bundled atv without the keys of turns and hills). For each stage: its median time
over the repeats, a *limit* (the time of the smallest work that stage cannot avoid, done by
a well-kept library: reading the same file with pyarrow, a prefix sum over the samples, the
fastest back end's solve) and the gap between them. The process itself is timed from
outside; start-up is the process's wall time less everything measured inside it.

    python benchmarks/bench_cli_stages.py [--repeats 5]

Run by hand: the machines are shared and noisy, so no test times anything.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import bench_plan  # noqa: E402  (the benchmark's route and vehicle)
from installed import compile_package  # noqa: E402

from profileopt.io import read_route  # noqa: E402
from profileopt.io.profiles import write_profile  # noqa: E402
from profileopt.planning import SolverOptions, plan  # noqa: E402


def _median(times: list[float]) -> float:
    return statistics.median(times)


def _timed(fn) -> float:
    start = time.perf_counter()
    fn()
    return time.perf_counter() - start


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=5, help="timed runs of each stage (default 5)")
    parser.add_argument("--segments", type=int, default=10_000, help="5 m segments (default 10,000)")
    args = parser.parse_args()
    print(compile_package(), file=sys.stderr)
    with tempfile.TemporaryDirectory(prefix="bench_cli_") as tmp:
        work = Path(tmp)
        route_path = work / "route.csv"
        bench_plan.write_route(route_path, args.segments, 0.5, 8608)
        bench_plan.write_level_atv(work / bench_plan.LEVEL_VEHICLE_FILE)
        vehicle = bench_plan.level_atv()
        command = [sys.executable, "-m", "profileopt", "plan", str(route_path), "--vehicle",
                   str(work / bench_plan.LEVEL_VEHICLE_FILE), "-o", str(work / "cli.csv"), "--json", "--quiet",
                   "--max-memory", "inf"]  # large routes are above the 1.5 GB default estimate
        process, inside, startup_floor, import_times = [], [], [], []
        stages: dict[str, list[float]] = {}
        limits: dict[str, list[float]] = {"read": [], "write": [], "windows": [], "solve": []}
        for _ in range(args.repeats):
            start = time.perf_counter()
            done = subprocess.run(command, capture_output=True, text=True, check=True)
            process.append(time.perf_counter() - start)
            inside.append(json.loads(done.stdout)["solver"]["time_s"])
            startup_floor.append(_timed(lambda: subprocess.run([sys.executable, "-c", "import numpy, casadi"],
                                                               check=True)))
            import_times.append(_timed(lambda: subprocess.run(
                [sys.executable, "-c", "import profileopt.cli.app, profileopt.planning, profileopt.io"], check=True)))
            # in process, as the command does it
            t = time.perf_counter()
            route = read_route(route_path)
            stages.setdefault("read and validate the CSV", []).append(time.perf_counter() - t)
            profile = plan(route, vehicle, segment_length_m=bench_plan.SEGMENT_LENGTH_M, model=bench_plan.MODEL)
            for key, value in profile.timings_s.items():
                if key != "total":
                    stages.setdefault(f"plan: {key}", []).append(value)
            stages.setdefault("plan: the rest (assembly, checks, gate)", []).append(
                profile.timings_s["total"] - sum(v for k, v in profile.timings_s.items() if k != "total"))
            stages.setdefault("write the profile CSV", []).append(
                _timed(lambda: write_profile(profile, work / "inproc.csv", route=route)))
            # the limits
            try:
                import pyarrow.csv as pacsv

                limits["read"].append(_timed(lambda: [c.to_numpy() for c in pacsv.read_csv(
                    route_path, parse_options=pacsv.ParseOptions(), read_options=pacsv.ReadOptions(skip_rows=1)
                ).columns]))
                import pyarrow as pa

                columns = profile.columns()
                table = pa.table({k: np.asarray(v, dtype=float) for k, v in columns.items()
                                  if np.asarray(v).dtype.kind == "f"})
                limits["write"].append(_timed(lambda: pacsv.write_csv(table, work / "arrow.csv")))
            except ImportError:
                pass
            z = route.z_m
            # a window's RI needs its samples' sums: two prefix sums over the samples at least
            limits["windows"].append(_timed(lambda: (np.cumsum(z), np.cumsum(z * z))))
            banded = plan(route, vehicle, segment_length_m=bench_plan.SEGMENT_LENGTH_M, model=bench_plan.MODEL,
                          solver_options=SolverOptions(nlp_solver="banded"))
            limits["solve"].append(banded.timings_s.get("solve", math.nan))
    rows = [("process start-up and imports (outside `plan`)", _median(process) - _median(inside)
             - _median(stages["read and validate the CSV"]) - _median(stages["write the profile CSV"]),
             _median(startup_floor), "`python -c 'import numpy, casadi'`")]
    rows.append(("  of which importing profileopt's modules", _median(import_times), _median(startup_floor),
                 "the same"))
    rows.append(("read and validate the CSV", _median(stages.pop("read and validate the CSV")),
                 _median(limits["read"]) if limits["read"] else math.nan, "pyarrow.csv.read_csv of the same file"))
    limit_of = {"plan: segment": (limits["windows"], "two prefix sums over the samples (numpy)"),
                "plan: solve": (limits["solve"], "the banded back end's solve (same NLP, same optimum)"),
                "plan: build": ([0.0], "nothing (built once per size)")}
    write = stages.pop("write the profile CSV")
    for name, times in stages.items():
        limit, what = limit_of.get(name, ([], ""))
        rows.append((name, _median(times), _median(limit) if limit else math.nan, what))
    rows.append(("write the profile CSV", _median(write), _median(limits["write"]) if limits["write"] else math.nan,
                 "pyarrow.csv.write_csv of its float columns"))
    print(f"`profileopt plan` at {args.segments:,} segments: process {_median(process):.3f} s "
          f"(min {min(process):.3f}, max {max(process):.3f}), medians of {args.repeats}; "
          f"`plan` itself {_median(inside):.3f} s.\n")
    print("| stage | time (s) | limit (s) | the limit | gap (x) |")
    print("|---|---:|---:|---|---:|")
    for name, value, limit, what in rows:
        gap = f"{value / limit:.1f}" if limit and math.isfinite(limit) and limit > 0 else ""
        lim = f"{limit:.3f}" if math.isfinite(limit) else ""
        print(f"| {name} | {value:.3f} | {lim} | {what} | {gap} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
