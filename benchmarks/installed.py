"""Bytecode for profileopt's modules, as installing its wheel leaves them, before a benchmark
times any fresh process.

``pip install`` of a wheel compiles every module (``__pycache__/*.pyc``), so a user's command
imports bytecode. An editable install (``pip install -e .``, how the benchmarks are run from a
clone) compiles nothing, and where ``PYTHONDONTWRITEBYTECODE`` is set (as on the project's
development machines) no import writes it either: every process then compiles profileopt's
source afresh, about 0.15 s of each ``profileopt plan`` measured on the 2-core machine of
``results.md``. :func:`compile_package` writes the bytecode once, as pip would; Python
checks each file's modification time, so an edited module is compiled again in memory, never
run stale.
"""

from __future__ import annotations

import compileall
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "profileopt"


def compile_package() -> str:
    """Compile profileopt's modules into ``__pycache__`` (as ``pip install`` of the wheel does).

    Returns
    -------
    str
        A note for the benchmark's output: where, and whether every module compiled.
    """
    ok = compileall.compile_dir(str(PACKAGE), quiet=1)
    failed = "" if ok else ": some modules failed"
    return f"profileopt's bytecode compiled as a wheel install leaves it ({PACKAGE}){failed}"
