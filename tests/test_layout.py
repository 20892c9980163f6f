"""The package's layout keeps its promises (issue 27): a house a newcomer can read.

- no import loop, counting every import of a module by another, at module level, inside a
  function or under ``TYPE_CHECKING``;
- at most 8 modules directly under ``profileopt/``: the rest live in sub-packages by role;
- physics knows nothing of the planner, verification nothing of the planner (it checks the
  planner, so it must not share its numbers), the core nothing of anything above it;
- the CLI is thin: its registry imports none of the commands, and each command is one module
  with ``arguments`` and ``run``;
- each kind of limit is one module under ``planning/limits/``;
- no private name (``_check_ri``) crosses a module boundary, and examples and benchmarks use
  only public names.

The import graph is read from the source (:mod:`ast`), so a test fails by naming the loop or
the import that breaks a rule, not by an ImportError somewhere else.
"""

from __future__ import annotations

import ast
import importlib
import os
import subprocess
import tempfile
import sys
from pathlib import Path

import pytest

from conftest import ROOT

PACKAGE = ROOT / "profileopt"


def _module_name(path: Path, package: Path) -> tuple[str, bool]:
    """Dotted name of a source file of ``package`` and whether it is a package's ``__init__``."""
    parts = list(path.relative_to(package.parent).with_suffix("").parts)
    is_init = parts[-1] == "__init__"
    return ".".join(parts[:-1] if is_init else parts), is_init


def import_graph(package: Path = PACKAGE) -> dict[str, set[str]]:
    """Module -> the package's modules it imports anywhere in its source (absolute names).

    ``from . import x`` counts as importing module ``x`` where ``x`` is a module, else the
    package it comes from; ``importlib.import_module`` calls are not imports of the source.
    """
    files = {name: (path, is_init) for path in package.rglob("*.py")
             for name, is_init in [_module_name(path, package)]}
    graph: dict[str, set[str]] = {}
    for name, (path, is_init) in files.items():
        here = name if is_init else name.rpartition(".")[0]
        found: set[str] = set()
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ImportFrom):
                if node.level:
                    base = here.split(".")[: len(here.split(".")) - node.level + 1]
                    module = ".".join(base + ([node.module] if node.module else []))
                else:
                    module = node.module or ""
                for alias in node.names:
                    candidate = f"{module}.{alias.name}"
                    found.add(candidate if candidate in files else module)
            elif isinstance(node, ast.Import):
                found.update(alias.name for alias in node.names)
        graph[name] = {m for m in found if m in files and m != name}
    return graph


def import_loops(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan), each sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    loops: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                loops.append(sorted(component))

    sys.setrecursionlimit(max(sys.getrecursionlimit(), 10_000))
    for v in sorted(graph):
        if v not in index:
            visit(v)
    return loops


def reachable(graph: dict[str, set[str]], start: str) -> set[str]:
    """Every module ``start`` imports, directly or through others."""
    seen, todo = set(), [start]
    while todo:
        for w in graph[todo.pop()]:
            if w not in seen:
                seen.add(w)
                todo.append(w)
    return seen


GRAPH = import_graph()


def test_no_import_loop() -> None:
    assert import_loops(GRAPH) == []


def test_the_loop_finder_finds_a_loop(tmp_path: Path) -> None:
    package = tmp_path / "profileopt"
    (package / "sub").mkdir(parents=True)
    (package / "__init__.py").write_text("")
    (package / "sub" / "__init__.py").write_text("")
    (package / "a.py").write_text("from .sub import b\n")
    (package / "sub" / "b.py").write_text("def f():\n    from ..a import g\n")
    (package / "c.py").write_text("from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from .a import x\n")
    graph = import_graph(package)
    assert import_loops(graph) == [["profileopt.a", "profileopt.sub.b"]]
    assert reachable(graph, "profileopt.c") == {"profileopt.a", "profileopt.sub.b"}


def test_at_most_eight_modules_directly_under_the_package() -> None:
    top = sorted(p.name for p in PACKAGE.glob("*.py"))
    assert len(top) <= 8, top


@pytest.mark.parametrize(("package", "forbidden"), [
    ("profileopt.core", ("planning", "verification", "studies", "mpc", "viz", "cli", "physics")),
    ("profileopt.terrain", ("planning", "verification", "studies", "mpc", "viz", "cli")),
    ("profileopt.physics", ("planning", "verification", "studies", "mpc", "viz", "cli")),
    ("profileopt.verification", ("planning", "studies", "mpc", "viz", "cli")),
    ("profileopt.planning", ("verification", "studies", "mpc", "viz", "cli")),
    ("profileopt.io", ("planning", "verification", "studies", "mpc", "viz", "cli")),
    ("profileopt.mpc", ("planning", "verification", "studies", "viz", "cli", "online")),
    ("profileopt.online", ("studies", "mpc", "viz", "cli")),
])
def test_each_package_imports_only_what_lies_below_it(package: str, forbidden: tuple[str, ...]) -> None:
    """Directly or through other modules: verification judges a plan from physics and core
    alone, physics knows nothing of the NLP, the core nothing of what is built on it."""
    bad = {}
    for module in (m for m in GRAPH if m == package or m.startswith(package + ".")):
        hits = sorted(m for m in reachable(GRAPH, module) if m.split(".")[1] in forbidden)
        if hits:
            bad[module] = hits
    assert bad == {}


def test_the_cli_registry_imports_no_command_and_every_command_has_arguments_and_run() -> None:
    from profileopt.cli.registry import COMMANDS

    assert GRAPH["profileopt.cli.registry"] == set()
    assert {m for m in GRAPH["profileopt.cli.app"] if m.startswith("profileopt.cli.")} <= {
        "profileopt.cli.registry", "profileopt.cli.messages"}
    for name, (module, help_text) in COMMANDS.items():
        loaded = importlib.import_module(module)
        assert callable(loaded.arguments) and callable(loaded.run), name
        assert help_text and "issue" not in help_text.lower(), name


def test_each_kind_of_limit_is_one_module_under_planning_limits(atv) -> None:
    from profileopt.planning.limits import Limit, default_limits

    modules = [type(limit).__module__ for limit in default_limits(atv, model="sbem_tf", max_jerk_mps3=5.0)]
    assert len(set(modules)) == len(modules), modules
    for module in modules:
        assert module.startswith("profileopt.planning.limits."), module
        defined = [obj for obj in vars(importlib.import_module(module)).values()
                   if isinstance(obj, type) and issubclass(obj, Limit) and obj.__module__ == module]
        assert len(defined) == 1, (module, defined)


def _private_imports(path: Path) -> list[str]:
    found = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom) and (node.level or (node.module or "").startswith("profileopt")):
            found += [f"{node.module}.{alias.name}" for alias in node.names
                      if alias.name.startswith("_") and alias.name != "__version__"]
    return found


def test_no_private_name_is_imported_across_modules() -> None:
    found = {str(p.relative_to(ROOT)): hits for p in sorted(PACKAGE.rglob("*.py")) if (hits := _private_imports(p))}
    assert found == {}


def test_the_check_finds_a_private_import(tmp_path: Path) -> None:
    bad = tmp_path / "bad.py"
    bad.write_text("from .terrain import _check_ri\nfrom profileopt.physics.forces import _of_e_max\n",
                   encoding="utf-8")
    assert _private_imports(bad) == ["terrain._check_ri", "profileopt.physics.forces._of_e_max"]


def test_examples_and_benchmarks_use_only_public_names() -> None:
    private = {}
    for path in sorted((ROOT / "examples").rglob("*.py")) + sorted((ROOT / "benchmarks").glob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        hits = [f"{node.module}.{alias.name}" for node in ast.walk(tree) if isinstance(node, ast.ImportFrom)
                and (node.module or "").startswith("profileopt") for alias in node.names
                if alias.name.startswith("_") or any(part.startswith("_") for part in node.module.split("."))]
        if hits:
            private[str(path.relative_to(ROOT))] = hits
    assert private == {}


def test_help_and_version_import_no_numerical_package() -> None:
    """``profileopt --help`` starts fast (under 0.15 s, measured by
    benchmarks/bench_startup.py, not here): it imports none of CasADi, SciPy, matplotlib or
    numpy, nor the vehicle files' TOML reader or the output files' writer; each command
    imports them only when it runs."""
    probe = ("import sys\nfrom profileopt.cli import main\n"
             "for argv in (['--help'], ['--version'], ['plan', '--help'], ['verify', '--help'], ['export-c', '--help']):\n"
             "    try:\n        main(argv)\n    except SystemExit:\n        pass\n"
             "print(sorted(m for m in ('casadi', 'scipy', 'matplotlib', 'numpy', 'profileopt.core.vehicle', 'profileopt.io.atomic')\n"
             "             if m in sys.modules), file=sys.stderr)\n")
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stderr.strip().splitlines()[-1] == "[]"


def test_planning_a_profile_route_imports_no_scipy() -> None:
    """``profileopt plan`` of a profile route (s,z: no turns to fit) imports no SciPy: its
    linear algebra took 0.24 s to import, a fifth of a 10 km plan and of each batch worker's
    first plan (the exact simulation's grid recursion is numpy since). SciPy stays for what
    needs it (x,y routes' curvature, tracks, point clouds)."""
    probe = ("import sys\nfrom profileopt.cli import main\n"
             f"status = main(['plan', {str(ROOT / 'examples' / 'routes' / 'trail.csv')!r}, '-o', sys.argv[1], "
             "'--quiet'])\n"
             "print(status, sorted(m for m in sys.modules if m == 'scipy' or m.startswith('scipy.'))[:5], "
             "file=sys.stderr)\n")
    with tempfile.TemporaryDirectory() as tmp:
        done = subprocess.run([sys.executable, "-c", probe, str(Path(tmp) / "trail-profile.csv")],
                              capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert done.stderr.strip().splitlines()[-1] == "0 []"


@pytest.mark.parametrize("user_value, advised", [(None, "False"), ("1", "True")])
def test_the_command_turns_numpys_hugepage_advice_off_unless_the_user_set_it(user_value: str | None,
                                                                             advised: str) -> None:
    """``profileopt`` sets NUMPY_MADVISE_HUGEPAGE=0 before NumPy is imported (profileopt.cli
    imports no NumPy; see profileopt.cli.app.main): NumPy reads it only when it is imported,
    so the setting fails silently if NumPy comes in first. A value the user set rules."""
    probe = ("import sys\nimport profileopt.cli\nprint('numpy' in sys.modules, file=sys.stderr)\n"
             "try:\n    profileopt.cli.main(['--version'])\nexcept SystemExit:\n    pass\n"
             "import numpy\nprint(numpy._core.multiarray._get_madvise_hugepage(), file=sys.stderr)\n")
    env = {key: value for key, value in os.environ.items() if key != "NUMPY_MADVISE_HUGEPAGE"}
    if user_value is not None:
        env["NUMPY_MADVISE_HUGEPAGE"] = user_value
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=120, env=env)
    assert done.returncode == 0, done.stderr
    assert done.stderr.strip().splitlines()[-2:] == ["False", advised]
