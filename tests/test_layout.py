"""The package layout stays readable (issue 9): small modules, no private names across modules.

A module over 600 lines holds more than one idea; a private name (``_check_ri``) imported
by another module, or by an example, is an interface nobody promised to keep. Modules whose
own name starts with an underscore (``_deprecation``) are the package's internal helpers and
may be imported inside the package, never from examples.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from conftest import ROOT

PACKAGE = ROOT / "profileopt"
MODULES = sorted(PACKAGE.rglob("*.py"))
MAX_LINES = 600


@pytest.mark.parametrize("path", MODULES, ids=[str(p.relative_to(ROOT)) for p in MODULES])
def test_no_module_is_over_600_lines(path: Path) -> None:
    lines = path.read_text(encoding="utf-8").count("\n")
    assert lines <= MAX_LINES, f"{path.relative_to(ROOT)} has {lines} lines; split it by idea"


def _private_imports(path: Path) -> list[str]:
    found = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom) and (node.level or (node.module or "").startswith("profileopt")):
            found += [f"{node.module}.{alias.name}" for alias in node.names
                      if alias.name.startswith("_") and alias.name != "__version__"]
    return found


@pytest.mark.parametrize("path", MODULES, ids=[str(p.relative_to(ROOT)) for p in MODULES])
def test_no_private_name_is_imported_across_modules(path: Path) -> None:
    assert _private_imports(path) == []


EXAMPLES = sorted((ROOT / "examples").rglob("*.py")) + sorted((ROOT / "benchmarks").glob("*.py"))


@pytest.mark.parametrize("path", EXAMPLES, ids=[str(p.relative_to(ROOT)) for p in EXAMPLES])
def test_examples_use_only_public_names(path: Path) -> None:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    private = [f"{node.module}.{alias.name}" for node in ast.walk(tree) if isinstance(node, ast.ImportFrom)
               and (node.module or "").startswith("profileopt") for alias in node.names
               if alias.name.startswith("_") or any(part.startswith("_") for part in node.module.split("."))]
    assert private == []


def test_the_check_finds_a_private_import(tmp_path: Path) -> None:
    bad = tmp_path / "bad.py"
    bad.write_text("from .terrain import _check_ri\nfrom profileopt.physics.forces import _of_e_max\n", encoding="utf-8")
    assert _private_imports(bad) == ["terrain._check_ri", "profileopt.physics.forces._of_e_max"]


def test_help_and_version_import_no_numerical_package() -> None:
    """``profileopt --help`` starts fast (issue 14: under 0.15 s, measured by
    benchmarks/bench_startup.py, not here): it imports none of CasADi, SciPy, matplotlib or
    numpy, nor the vehicle files' TOML reader or the output files' writer (25 ms of the
    0.15 s); each command imports them only when it runs."""
    import subprocess
    import sys

    probe = ("import sys\nfrom profileopt.cli import main\n"
             "for argv in (['--help'], ['--version'], ['plan', '--help'], ['verify', '--help'], ['export-c', '--help']):\n"
             "    try:\n        main(argv)\n    except SystemExit:\n        pass\n"
             "print(sorted(m for m in ('casadi', 'scipy', 'matplotlib', 'numpy', 'profileopt.core.vehicle', 'profileopt.io.atomic')\n"
             "             if m in sys.modules), file=sys.stderr)\n")
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stderr.strip().splitlines()[-1] == "[]"
