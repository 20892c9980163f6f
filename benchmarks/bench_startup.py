"""How long `profileopt --help` takes, process start to exit (issue 14: target < 0.15 s).

Runs the installed command (or ``python -m profileopt`` when none is on PATH) --repeats
times and prints the median and the range. Run by hand: the machines are shared and noisy,
so no test times anything.

    python benchmarks/bench_startup.py [--repeats 15]
"""

from __future__ import annotations

import argparse
import shutil
import statistics
import subprocess
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))  # the benchmarks' shared helper
from installed import compile_package  # noqa: E402


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    parser.add_argument("--repeats", type=int, default=15, help="timed runs of each command")
    args = parser.parse_args()
    print(compile_package(), file=sys.stderr)
    exe = shutil.which("profileopt")
    command = [exe] if exe else [sys.executable, "-m", "profileopt"]
    print("| command | median (s) | min-max (s) | target |")
    print("|---|---:|---:|---|")
    for argv, target in ((["--help"], "< 0.15 s"), (["--version"], ""), (["plan", "--help"], "")):
        times = []
        for _ in range(args.repeats):
            start = time.perf_counter()
            subprocess.run(command + argv, check=True, capture_output=True)
            times.append(time.perf_counter() - start)
        print(f"| `profileopt {' '.join(argv)}` | {statistics.median(times):.3f} | {min(times):.3f}-{max(times):.3f} "
              f"| {target} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
