"""What a newcomer and a controls engineer ran into (issue 13, "The newcomer's stumbles" and
"The controls engineer's stumbles"): each test failed before its fix."""

from __future__ import annotations

import importlib.util
import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import profileopt
from conftest import PROFILEOPT, ROOT, ROUTES, WIDE_TERMINAL, markdown_pages, markdown_section
from profileopt import load_vehicle, plan, read_route

CC = shutil.which("cc") or shutil.which("gcc") or shutil.which("clang")
needs_cc = pytest.mark.skipif(CC is None, reason="no C compiler (cc, gcc or clang) on PATH")
#: where the MPC walk-through lives (it was the README's section of that name)
MPC_PAGE, MPC_TITLE = "docs/guide/mpc.md", "Use the force limits in your own MPC"


def _env() -> dict[str, str]:
    """The environment of a child process: this checkout first on the path, no display, a
    terminal too wide for argparse to wrap a help line (a default path holds the clone's)."""
    path = os.pathsep.join([str(ROOT), *filter(None, [os.environ.get("PYTHONPATH")])])
    return {**os.environ, "PYTHONPATH": path, "MPLBACKEND": "Agg", **WIDE_TERMINAL}


# --- --version ------------------------------------------------------------------------


def test_version_prints_the_version_and_exits_0() -> None:
    result = subprocess.run([*PROFILEOPT, "--version"], capture_output=True, text=True, timeout=60, env=_env())
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == f"profileopt {profileopt.__version__}"


# --- the example scripts' options --------------------------------------------------------

#: each example script and defaults its --help must show
EXAMPLES = {
    "examples/paper_figures.py": ["figures"],
    "examples/safety_study.py": ["print"],
    "examples/lidar_roughness.py": ["hexbin-crop.las", "lidar_roughness.png", "10"],
    "examples/mpc_terrain_preview.py": ["trail.csv", "atv", "sbem_tf", "12", "mpc_out", "60", "worst"],
    "examples/mpc_dompc.py": ["atv", "trail.csv", "washboard.csv", "950"],
    "examples/mpc_rockit.py": ["atv", "trail.csv", "washboard.csv", "40"],
    "examples/routes/make_routes.py": ["beside this script"],
    "examples/geo_route.py": ["hexbin-track.gpx", "atv-low-range", "geo_route.png"],
    "examples/online_stream.py": ["trail.csv", "atv", "50", "worst", "0.1"],
}
#: the examples that import do-mpc or rockit before reading their options (the mpc extra)
MPC_EXAMPLES = {"examples/mpc_dompc.py", "examples/mpc_rockit.py"}
SCRIPTS = [pytest.param(script, marks=pytest.mark.mpc) if script in MPC_EXAMPLES else script for script in sorted(EXAMPLES)]


@pytest.mark.slow
@pytest.mark.parametrize("script", SCRIPTS)
def test_example_help_shows_defaults_and_writes_nothing(tmp_path: Path, script: str) -> None:
    result = subprocess.run([sys.executable, str(ROOT / script), "--help"], capture_output=True, text=True,
                            timeout=120, cwd=tmp_path, env=_env())
    assert result.returncode == 0, result.stderr
    assert result.stdout.startswith("usage:"), result.stdout
    text = " ".join(result.stdout.split())
    assert "default" in text
    for default in EXAMPLES[script]:
        assert default in text, (default, result.stdout)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.slow
@pytest.mark.parametrize("script", SCRIPTS)
def test_example_refuses_an_unknown_option_and_writes_nothing(tmp_path: Path, script: str) -> None:
    result = subprocess.run([sys.executable, str(ROOT / script), "--no-such-option"], capture_output=True,
                            text=True, timeout=120, cwd=tmp_path, env=_env())
    assert result.returncode == 2, (result.stdout, result.stderr)
    assert "--no-such-option" in result.stderr
    assert list(tmp_path.iterdir()) == []


# --- the online selector's loop ----------------------------------------------------------


def test_the_online_example_drives_a_route_to_its_end_in_its_cycles(tmp_path: Path) -> None:
    """examples/online_stream.py, the loop a robotics user adapts: it reaches the route's end
    at rest, and its clock agrees with the library's own closed loop (profileopt.online.drive)
    on the same route, to a cycle."""
    from profileopt.online import drive

    route = ROOT / "examples" / "routes" / "curb.csv"
    result = subprocess.run([sys.executable, str(ROOT / "examples" / "online_stream.py"), "--route", str(route),
                             "--every", "1000"], capture_output=True, text=True, timeout=300, cwd=tmp_path,
                            env=_env())
    assert result.returncode == 0, result.stderr
    arrived = float(result.stdout.split("arrived after ")[1].split(" s")[0])
    driven = drive(read_route(route), load_vehicle("atv"), sensor_range_m=50.0)
    assert abs(arrived - driven.travel_time_s) <= 0.1 + 1e-9
    assert list(tmp_path.iterdir()) == []


# --- generated C -----------------------------------------------------------------------


@pytest.mark.slow
@pytest.mark.cc
@needs_cc
@pytest.mark.parametrize("vehicle, n_stages", [("atv", 1), ("atv-resonant", 3)])
def test_generated_c_compiles_without_warnings(tmp_path: Path, vehicle: str, n_stages: int) -> None:
    from profileopt.mpc.codegen import export_c

    out = export_c(load_vehicle(vehicle), tmp_path / "c", n_stages=n_stages)
    for source in (out.source, out.example):
        result = subprocess.run([CC, "-std=c99", "-Wall", "-Wextra", "-Werror", "-c", source.name, "-o",
                                 str(tmp_path / (source.stem + ".o"))], cwd=out.directory,
                                capture_output=True, text=True, timeout=300)
        assert result.returncode == 0, result.stderr[:3000]


@pytest.mark.cc
@needs_cc
def test_mpc_guide_cc_line_works_from_the_repository_folder(tmp_path: Path) -> None:
    """The MPC guide's export and build commands (once the README's), run as written from a
    copy's top folder."""
    section = markdown_section(MPC_PAGE, MPC_TITLE)
    export = re.search(r"`(profileopt export-c [^`]*)`", section).group(1)
    build = re.search(r"`((?:cd \S+ && )?cc [^`]*)`", section).group(1)
    binary = re.search(r"-o (\S+)", build)
    assert binary, f"the cc line of {MPC_PAGE} names no binary: {build}"
    result = subprocess.run([*PROFILEOPT, *shlex.split(export)[1:]], cwd=tmp_path, capture_output=True,
                            text=True, timeout=300, env=_env())
    assert result.returncode == 0, result.stderr
    result = subprocess.run(build.replace("cc ", f"{CC} ", 1), shell=True, cwd=tmp_path, capture_output=True,
                            text=True, timeout=300)
    assert result.returncode == 0, result.stderr
    built = [p for p in tmp_path.rglob(Path(binary.group(1)).name) if p.is_file() and os.access(p, os.X_OK)]
    assert built, list(tmp_path.rglob("*"))
    run = subprocess.run([str(built[0])], capture_output=True, text=True, timeout=60)
    assert run.returncode == 0 and "speed" in run.stdout


# --- the constraints API -----------------------------------------------------------------


def test_force_constraints_with_e_max_and_vehicle_by_keyword(atv) -> None:
    import casadi as ca

    from profileopt.mpc.constraints import force_constraints

    v = ca.SX.sym("v", 4)
    g, lbg, ubg = force_constraints(v, e_max_m=0.05, vehicle=atv)
    assert g.shape == (4, 1) and lbg.shape == ubg.shape == (4,)


def test_force_constraints_converts_to_a_dict(atv) -> None:
    import casadi as ca

    from profileopt.mpc.constraints import force_constraints

    v = ca.SX.sym("v", 3)
    cons = force_constraints(v, atv, ri=0.2)
    d = dict(cons)
    assert set(d) == {"g", "lbg", "ubg"}
    assert d["g"] is cons.g and d["lbg"] is cons.lbg and d["ubg"] is cons.ubg
    g, lbg, ubg = cons  # still unpacks as the triple
    solver = ca.nlpsol("s", "ipopt", {"x": v, "f": -ca.sum1(v), "g": d["g"]},
                       {"print_time": False, "ipopt": {"print_level": 0, "sb": "yes"}})
    best = solver(x0=1, lbx=0, ubx=atv.max_speed_mps, lbg=d["lbg"], ubg=d["ubg"])["x"]
    assert np.all(np.asarray(best) > 0)


def test_plain_jacobian_is_public_and_takes_the_inputs_of_the_function(atv) -> None:
    from profileopt.mpc.constraints import force_function, jacobian_function

    fn = force_function(atv, n_stages=2)
    jac = jacobian_function(fn)
    assert jac.n_in() == 2 and [jac.name_in(i) for i in range(2)] == ["speed_mps", "ri"]
    out = jac(np.array([5.0, 8.0]), np.array([0.1, 0.2]))
    expected = fn.jacobian()(np.array([5.0, 8.0]), np.array([0.1, 0.2]), 0)
    np.testing.assert_allclose(np.asarray(out[0]), np.asarray(expected[0]))


def test_function_docs_hold_no_absolute_path(atv, tmp_path: Path) -> None:
    from profileopt.mpc.constraints import constraint_function, force_function

    own = tmp_path / "my_quad.toml"
    shutil.copyfile(ROOT / "models" / "atv.toml", own)
    for vehicle in (atv, load_vehicle(str(own))):
        assert Path(vehicle.name).is_absolute()  # what a loaded vehicle is named by
        for fn in (force_function(vehicle), constraint_function(vehicle, terrain="e_max")):
            assert str(Path(vehicle.name).parent) not in fn.__doc__, fn.__doc__
            assert Path(vehicle.name).stem in fn.__doc__


# --- files the documented commands write --------------------------------------------------


def _documented_outputs() -> set[str]:
    """Output paths named in the commands of the README and the documentation's pages (-o,
    --plot, --map, --out), placeholders aside."""
    names = set()
    lines = [line for page in markdown_pages() for line in page.read_text(encoding="utf-8").splitlines()]
    for line in lines:
        folder = re.search(r"\bcd (\S+) &&", line)  # a command run inside a folder writes there
        for match in re.finditer(r"(?:-o|--plot|--map|--out)\s+([\w./-]+)", line):
            name = match.group(1)
            if name.isupper() or name.split(".")[0].isupper() or name.startswith("/") or name == "-":
                continue
            names.add(folder.group(1).rstrip("/") + "/" + name if folder else name)
    return names


def test_gitignore_covers_what_the_documented_commands_write() -> None:
    if not (ROOT / ".git").exists():
        pytest.skip("not a git checkout")
    names = _documented_outputs() | {"mpc_out/"}  # mpc_terrain_preview.py's default folder
    assert {"profile.csv", "verify.csv", "verify.png", "forces_c/"} <= names, names
    for name in sorted(names):
        folder = name.endswith("/") or "." not in Path(name).name  # --out figures: a folder
        probe = name.rstrip("/") + "/x.c" if folder else name
        result = subprocess.run(["git", "check-ignore", "-q", "--no-index", probe], cwd=ROOT)
        assert result.returncode == 0, f"{name} is written by a documented command and not in .gitignore"


def test_bench_plan_does_not_overwrite_the_committed_results_by_default(tmp_path: Path, monkeypatch,
                                                                         capsys) -> None:
    spec = importlib.util.spec_from_file_location("bench_plan_under_test", ROOT / "benchmarks" / "bench_plan.py")
    bench = importlib.util.module_from_spec(spec)
    monkeypatch.setitem(sys.modules, spec.name, bench)  # its dataclasses look the module up
    spec.loader.exec_module(bench)
    (tmp_path / "benchmarks").mkdir()
    monkeypatch.setattr(bench, "REPO", tmp_path)
    monkeypatch.setattr(bench, "bench_size", lambda *args, **kwargs: [])
    monkeypatch.setattr(bench, "compile_package", lambda: "bytecode not compiled in the test")
    monkeypatch.chdir(tmp_path)
    assert bench.main(["--sizes", "2", "--repeats", "1", "--no-cli"]) == 0
    assert list((tmp_path / "benchmarks").iterdir()) == []
    assert list(tmp_path.iterdir()) == [tmp_path / "benchmarks"]
    assert "| method" in capsys.readouterr().out


# --- the MPC guide's first snippet (once the README's) ----------------------------------------


def test_mpc_guide_snippet_prints_only_its_answer(tmp_path: Path) -> None:
    section = markdown_section(MPC_PAGE, MPC_TITLE)
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300,
                            cwd=tmp_path, env=_env())
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert len(lines) == 1, result.stdout[:2000]
    assert lines[0].startswith("[") and lines[0].endswith("]"), lines
    assert "-0." not in lines[0], lines
    speeds = np.array(lines[0].strip("[]").split(), dtype=float)
    assert speeds.size == 11 and speeds[0] == 0
    assert "5.57" in section and np.isclose(speeds[5:].min(), 5.57, atol=0.01)


# --- pictures -----------------------------------------------------------------------------


@pytest.fixture(scope="module")
def curb_profile():
    route = read_route(ROUTES / "curb.csv")
    return plan(route, load_vehicle("atv"))


def _lines(ax) -> dict[str, object]:
    handles, labels = ax.get_legend_handles_labels()
    return dict(zip(labels, handles))


def test_plan_plot_names_route_and_vehicle_and_shows_the_speed_cap(curb_profile) -> None:
    from profileopt.viz.plots import profile_figure

    fig = profile_figure(curb_profile, route="curb.csv", vehicle="atv")
    ax = fig.axes[0]
    title = ax.get_title() + fig.texts[0].get_text() if fig.texts else ax.get_title()
    assert "curb.csv" in title and "atv" in title
    lines = _lines(ax)
    cap = [label for label in lines if "speed_limit" in label]
    assert len(cap) == 1 and "allowable" not in cap[0], list(lines)
    # the allowable lines show the force model alone: where the route's speed limit holds the
    # speed cap, they are not drawn at the cap
    route_cap = curb_profile.speed_cap_mps < load_vehicle("atv").max_speed_mps - 1e-9
    assert route_cap.any()
    for label, artist in lines.items():
        if "allowable" in label:
            values = np.asarray(artist.get_data().values, dtype=float)
            folded = route_cap & np.isclose(values, curb_profile.speed_cap_mps)
            assert not folded.any(), label


def test_plan_plot_draws_no_line_under_another(curb_profile) -> None:
    """Lines that can coincide (largest under first, either under the planned speed) are
    drawn wider underneath, so each stays visible around the one on top."""
    from profileopt.viz.plots import profile_figure

    fig = profile_figure(curb_profile)
    lines = _lines(fig.axes[0])
    by_kind = {kind: next(a for label, a in lines.items() if kind in label)
               for kind in ("largest", "first", "planned")}
    width = {k: a.get_linewidth() for k, a in by_kind.items()}
    z = {k: a.get_zorder() for k, a in by_kind.items()}
    assert width["largest"] > width["first"] and width["largest"] > width["planned"]
    assert z["largest"] < z["first"] and z["largest"] < z["planned"]
    for label, artist in lines.items():
        assert artist.get_visible() and artist.get_linewidth() > 0, label


def test_verification_plot_legends_sit_outside_the_data(tmp_path: Path) -> None:
    from profileopt import verify
    from profileopt.viz.plots import verification_figure

    route = read_route(ROUTES / "curb.csv")
    vehicle = load_vehicle("atv")
    result = verify(route, plan(route, vehicle), vehicle)
    fig = verification_figure(result)
    fig.canvas.draw()
    for ax in fig.axes:
        legend = ax.get_legend()
        if legend is None:
            continue
        box, area = legend.get_window_extent(), ax.get_window_extent()
        overlap_w = min(box.x1, area.x1) - max(box.x0, area.x0)
        overlap_h = min(box.y1, area.y1) - max(box.y0, area.y0)
        assert overlap_w <= 1 or overlap_h <= 1, (ax.get_ylabel(), box, area)


def test_figure_5_legend_cites_no_repository_file() -> None:
    from profileopt.viz.figures import figure_5

    data = figure_5(load_vehicle("atv"))
    for curve in data.curves:
        assert ".md" not in curve.label and "docs/" not in curve.label, curve.label
