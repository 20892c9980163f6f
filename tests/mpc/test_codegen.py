"""Generated C (``profileopt export-c``) against the Python Functions it was made from.

The reference is CasADi's own evaluation of the Python Functions (``force_function``,
``constraint_function`` and ``Function.jacobian()``); the C is compiled with the system
compiler and loaded through ``casadi.external``. Both evaluate the same expression graph,
so they must agree to rounding: within 1e-12 relative (1e-12 absolute near zero).
"""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

import casadi as ca
import numpy as np
import pytest

from profileopt import load_vehicle
from profileopt.cli import main
from profileopt.mpc.codegen import c_functions, export_c
from profileopt.mpc.constraints import constraint_function, force_function

CC = shutil.which("cc") or shutil.which("gcc") or shutil.which("clang")
needs_cc = pytest.mark.skipif(CC is None, reason="no C compiler (cc, gcc or clang) on PATH")

RTOL = 1e-12


def _compile_shared(source: Path, out: Path) -> Path:
    subprocess.run([CC, "-shared", "-fPIC", "-O2", str(source), "-lm", "-o", str(out)], check=True)
    return out


def _points(rng: np.random.Generator, terrain: str, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Random speeds (m/s) and terrain values, with the special points mixed in:
    smooth ground (0) and e_max around the wheel radius 0.1 m where X_w saturates (Eq. 2)."""
    speed = rng.uniform(0.0, 20.0, n)
    if terrain == "ri":
        value = rng.uniform(0.0, 1.5, n)
        value[:3] = [0.0, 0.1 / 0.47534243088162570, 0.21]  # e_max = 0, = r, just above r
    else:
        value = rng.uniform(0.0, 0.5, n)
        value[:3] = [0.0, 0.1, 0.1000001]
    speed[3] = 0.0
    return speed, value


def _close(actual: np.ndarray, expected: np.ndarray) -> None:
    np.testing.assert_allclose(actual, expected, rtol=RTOL, atol=RTOL, equal_nan=True)


def _check_library(so: Path, functions, vehicle, n_stages: int, rng: np.random.Generator) -> None:
    for e in functions:
        builder = force_function if e.kind == "force" else constraint_function
        py = builder(vehicle, model=e.model, terrain=e.terrain, n_stages=n_stages)
        py_jac = py.jacobian()  # CasADi's own Jacobian, not the exporter's wrapper
        c = ca.external(e.name, str(so))
        c_jac = ca.external(e.jacobian_name, str(so))
        assert c.name_in() == py.name_in() and c.name_out() == py.name_out()
        speed, value = _points(rng, e.terrain, 8 * n_stages)
        for i in range(8):
            s, t = speed[i * n_stages:(i + 1) * n_stages], value[i * n_stages:(i + 1) * n_stages]
            _close(np.asarray(c(s, t)), np.asarray(py(s, t)))
            jc, jp = c_jac(s, t), py_jac(s, t, 0)
            for k in range(2):
                assert jc[k].sparsity() == jp[k].sparsity(), e.jacobian_name
                _close(np.asarray(jc[k].nonzeros()), np.asarray(jp[k].nonzeros()))
        # many points at once through map
        speed, value = _points(rng, e.terrain, 64 * n_stages)
        shape = (n_stages, 64)
        s, t = speed.reshape(shape, order="F"), value.reshape(shape, order="F")
        _close(np.asarray(c.map(64)(s, t)), np.asarray(py.map(64)(s, t)))


@pytest.mark.slow
@pytest.mark.cc
@needs_cc
@pytest.mark.parametrize("name", ["atv", "atv-resonant"])
def test_generated_c_matches_python(tmp_path: Path, name: str) -> None:
    vehicle = load_vehicle(name)
    result = export_c(vehicle, tmp_path / "c")
    assert len(result.functions) == 14  # 4 models x (force, constraint) vs RI, 3 models vs e_max
    header = result.header.read_text()
    for e in result.functions:
        assert f"int {e.name}(const casadi_real** arg" in header
        assert f"int {e.jacobian_name}(const casadi_real** arg" in header
    so = _compile_shared(result.source, tmp_path / "libforces.so")
    _check_library(so, result.functions, vehicle, 1, np.random.default_rng(4))


@pytest.mark.slow
@pytest.mark.cc
@needs_cc
def test_command_line_export_with_stages_and_example_program(tmp_path: Path, capsys) -> None:
    out = tmp_path / "export"
    assert main(["export-c", "--vehicle", "atv-resonant", "-o", str(out), "--model", "sbem_tf", "--stages", "3"]) == 0
    files = sorted(p.name for p in out.iterdir())
    assert files == ["README.md", "example.c", "profileopt_atv_resonant.c", "profileopt_atv_resonant.h"]
    vehicle = load_vehicle("atv-resonant")
    functions = [t[0] for t in c_functions(vehicle, models=["sbem_tf"], n_stages=3)]
    so = _compile_shared(out / "profileopt_atv_resonant.c", tmp_path / "lib3.so")
    _check_library(so, functions, vehicle, 3, np.random.default_rng(5))

    # The example program of the README compiles, runs and prints what Python computes.
    exe = tmp_path / "example"
    subprocess.run([CC, "-O2", "example.c", "profileopt_atv_resonant.c", "-lm", "-o", str(exe)], cwd=out, check=True)
    printed = subprocess.run([str(exe)], check=True, capture_output=True, text=True).stdout
    number = r"([-+0-9.eE]+|nan|inf)"
    pattern = rf"speed {number} m/s, RI {number}: g {number}, dg/dspeed {number} s/m, dg/dRI {number}"
    rows = [list(map(float, re.fullmatch(pattern, line).groups())) for line in printed.strip().splitlines()]
    assert len(rows) == 3
    g = constraint_function(vehicle, model="sbem_tf")
    jac = g.jacobian()
    for speed, ri, g_c, dv_c, dri_c in rows:
        _close(np.array([g_c]), np.asarray(g(speed, ri)).ravel())
        _close(np.array([dv_c, dri_c]), np.array([float(j) for j in jac(speed, ri, 0)]))


@pytest.mark.parametrize(
    "argv, message",
    [
        (["--vehicle", "no-such-car"], "no bundled vehicle"),
        (["--vehicle", "atv", "--stages", "0"], "--stages = 0"),
    ],
)
def test_bad_input_is_one_line_and_writes_nothing(tmp_path: Path, capsys, argv, message) -> None:
    out = tmp_path / "c"
    assert main(["export-c", *argv, "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1
    assert not out.exists()


def test_output_that_is_a_file_is_refused(tmp_path: Path, capsys) -> None:
    target = tmp_path / "taken"
    target.write_text("keep me")
    assert main(["export-c", "--vehicle", "atv", "-o", str(target)]) == 2
    assert "is not a folder" in capsys.readouterr().err
    assert target.read_text() == "keep me"


# ------------------------------------------------------------------ one vocabulary (issue 9)


# ------------------------------------------------------------ not terrain: never admissible (issue 10)

#: Terrain values that are not terrain: negative (down to the smallest subnormal), NaN and
#: minus infinity. Each must give g > 0 or NaN, never g <= 0 ("admissible").
NOT_TERRAIN = [-0.1, -1e-300, -5e-324, -np.inf, np.nan]


def _never_admissible(values: np.ndarray, kind: str) -> None:
    values = np.asarray(values, dtype=float).ravel()
    ok = np.isnan(values) | (values > 0) if kind == "constraint" else np.isnan(values)
    assert np.all(ok), values


@pytest.mark.parametrize("name", ["atv", "atv-resonant"])
def test_functions_never_call_negative_or_nan_terrain_admissible(name: str) -> None:
    vehicle = load_vehicle(name)
    speeds = np.array([0.0, 0.3, 5.0, 20.0])
    for e, fn, _ in c_functions(vehicle, n_stages=1):
        for bad in NOT_TERRAIN:
            _never_admissible(fn.map(speeds.size)(speeds[None, :], np.full((1, speeds.size), bad)), e.kind)
        # smooth ground is terrain: no force, g = -1 (so the check above can tell the two apart)
        assert float(fn(5.0, 0.0)) == (-1.0 if e.kind == "constraint" else 0.0)
    for terrain in ("ri", "e_max"):  # the Functions of casadi_functions on their own, several stages
        g = constraint_function(vehicle, terrain=terrain, n_stages=3)
        _never_admissible(g([1.0, 2.0, 3.0], [-0.2, np.nan, -np.inf]), "constraint")


@pytest.mark.slow
@pytest.mark.cc
@needs_cc
@pytest.mark.parametrize("name", ["atv", "atv-resonant"])
def test_generated_c_never_calls_negative_or_nan_terrain_admissible(tmp_path: Path, name: str) -> None:
    vehicle = load_vehicle(name)
    result = export_c(vehicle, tmp_path / "c", n_stages=len(NOT_TERRAIN))
    assert "never a g <= 0" in result.readme.read_text() and "-ffast-math" in result.readme.read_text()
    so = _compile_shared(result.source, tmp_path / "lib.so")
    speeds = np.full(len(NOT_TERRAIN), 4.0)
    for e in result.functions:
        c = ca.external(e.name, str(so))
        _never_admissible(c(speeds, NOT_TERRAIN), e.kind)
        at_zero = np.asarray(c(speeds, np.zeros(len(NOT_TERRAIN)))).ravel()
        np.testing.assert_array_equal(at_zero, -1.0 if e.kind == "constraint" else 0.0)


def _random_inputs(fn: ca.Function, rng: np.random.Generator) -> list[np.ndarray]:
    """Inputs for the interval rows and the preview's envelopes: speeds 0-20 m/s, elevations
    0-0.3 m (e_min at most e_max), positions inside the horizon, coefficients of e_max (m),
    caps (m/s), |curvature| (0-0.5 1/m) and grades (-0.3-0.3 rad)."""
    names = fn.name_in()
    values = {}
    n = fn.size1_in(0)
    if names[0] == "v_start":
        values["v_start"], values["v_end"] = rng.uniform(0.0, 20.0, n), rng.uniform(0.0, 20.0, n)
        values["e_max_m"] = rng.uniform(0.0, 0.3, n)
        values["e_min_m"] = values["e_max_m"] * rng.uniform(0.0, 1.0, n)
    else:
        values["s_m"] = rng.uniform(0.0, 25.0, n)
        values["origin_m"] = np.array([0.0])
        k = fn.size1_in(2)
        low_high = {"e_coef": (0.0, 0.3), "cap_coef": (0.5, 20.0), "curvature_coef": (0.0, 0.5),
                    "grade_max_coef": (-0.3, 0.3), "grade_min_coef": (-0.3, 0.3)}[names[2]]
        values[names[2]] = rng.uniform(*low_high, k)
    return [values[name] for name in names]


@pytest.mark.slow
@pytest.mark.cc
@needs_cc
def test_interval_rows_and_preview_in_c_match_python(tmp_path: Path) -> None:
    # Issue 31: export-c covers the interval rows and the preview's envelopes (the terrain's
    # e_max and speed cap, the path's curvature and grades), not only point forces.
    from profileopt.mpc.functions import interval_constraint_function
    from profileopt.mpc.horizon import interval_force_constraints
    from profileopt.mpc.preview import TerrainPreview

    vehicle = load_vehicle("atv-resonant")
    out = tmp_path / "c"
    assert main(["export-c", "--vehicle", "atv-resonant", "-o", str(out), "--model", "sbem_tf", "--model", "iecm",
                 "--stages", "2", "--intervals", "--preview", "25", "--reach", "1.5"]) == 0
    preview = TerrainPreview(vehicle, horizon_m=25.0, reach_m=1.5)
    triples = c_functions(vehicle, models=["sbem_tf", "iecm"], n_stages=2, intervals=True, preview=preview)
    names = [e.name for e, _, _ in triples]
    assert "atv_resonant_sbem_tf_interval_constraint_of_e_max" in names
    assert "atv_resonant_iecm_interval_constraint_of_e_max" in names
    assert "atv_resonant_preview_e_max" in names and "atv_resonant_preview_speed_cap" in names
    path_names = ["atv_resonant_preview_curvature", "atv_resonant_preview_grade_max", "atv_resonant_preview_grade_min"]
    assert all(name in names for name in path_names)
    header = (out / "profileopt_atv_resonant.h").read_text()
    assert all(f"int {name}(const casadi_real** arg" in header for name in path_names)
    so = _compile_shared(out / "profileopt_atv_resonant.c", tmp_path / "lib.so")
    rng = np.random.default_rng(7)
    path_kinds = ("curvature", "grade_max", "grade_min")
    compared = set()
    for e, fn, jac in triples:
        if e.kind not in ("interval_constraint", "e_max", "speed_cap", *path_kinds):
            continue
        compared.add(e.kind)
        c, c_jac = ca.external(e.name, str(so)), ca.external(e.jacobian_name, str(so))
        assert c.name_in() == fn.name_in() and c.name_out() == fn.name_out()
        for _ in range(6):
            args = _random_inputs(fn, rng)
            _close(np.asarray(c(*args)), np.asarray(fn(*args)))
            for got, want in zip(c_jac(*args), jac(*args)):
                _close(np.asarray(ca.densify(got)), np.asarray(ca.densify(want)))
    # the exported rows are the Python helpers' own, evaluated independently of the export
    rows = interval_constraint_function(vehicle, model="sbem_tf", n_stages=2)
    v0, v1, e_hi, e_lo = np.array([0.2, 6.0]), np.array([3.0, 5.0]), np.array([0.05, 0.2]), np.array([0.0, 0.1])
    _close(np.asarray(rows(v0, v1, e_hi, e_lo)).ravel(),
           np.asarray(interval_force_constraints(v0, v1, e_hi, vehicle, e_min_m=e_lo).g).ravel())
    e_fn, cap_fn = preview.stage_functions(n_stages=2)
    coef = preview.coefficients(np.arange(0.0, 30.0, 0.05), 0.02 * np.sin(np.arange(0.0, 30.0, 0.05) * 7.0), 0.0)
    s = np.array([3.0, 11.5])
    _close(np.asarray(e_fn(s, coef.origin_m, coef.e_max)).ravel(),
           np.array([float(preview.e_max(x, coef.origin_m, coef.e_max)) for x in s]))
    assert set(path_kinds) <= compared
    readme = (out / "README.md").read_text()
    assert "interval_constraint_of_e_max" in readme
    assert all(f"`{name}` / `{name}_jac`" in readme for name in path_names)  # the README's table
    assert "TerrainPreview.path_coefficients" in readme
    # the compiled path envelopes against the scalar Python Functions a user calls
    # (preview.curvature, grade_max, grade_min), independently of the export, on the
    # coefficients of a real path: a 20 m radius arc on a 10 % climb, seen from 10 m on
    ds = 0.1
    s_path = np.arange(0.0, 60.0 + ds / 2, ds)
    heading = np.clip(s_path - 20.0, 0.0, 15.0) / 20.0  # the arc from 20 to 35 m
    x_path = np.concatenate([[0.0], np.cumsum(np.cos(heading[:-1]) * ds)])
    y_path = np.concatenate([[0.0], np.cumsum(np.sin(heading[:-1]) * ds)])
    z_path = 0.1 * np.maximum(s_path - 25.0, 0.0)
    path = preview.path_coefficients(s_path, z_path, 10.0, x_m=x_path, y_m=y_path, path_tolerance_m=0.05)
    stages = np.array([14.0, 31.25])
    for kind, scalar, coef in (("curvature", preview.curvature, path.curvature),
                               ("grade_max", preview.grade_max, path.grade_max),
                               ("grade_min", preview.grade_min, path.grade_min)):
        c = ca.external(f"atv_resonant_preview_{kind}", str(so))
        _close(np.asarray(c(stages, path.origin_m, coef)).ravel(),
               np.array([float(scalar(x, path.origin_m, coef)) for x in stages]))
    # the stage at 31.25 m is on the arc: the compiled envelope is not below its 1 / 20 m
    kappa = ca.external("atv_resonant_preview_curvature", str(so))
    assert float(np.asarray(kappa(stages, path.origin_m, path.curvature)).ravel()[1]) >= 0.05 * 0.97


@pytest.mark.parametrize("argv, message", [
    (["--reach", "2"], "--reach shape(s) the preview"),
    (["--preview", "-3"], "--preview -3: give a number of metres > 0"),
    (["--preview", "30", "--reach", "-1"], "--reach -1"),
    (["--preview", "30", "--unseen", "Q"], "not an ISO 8608 class"),
])
def test_preview_options_are_checked_in_one_line(tmp_path: Path, capsys, argv, message) -> None:
    out = tmp_path / "c"
    assert main(["export-c", "--vehicle", "atv", "-o", str(out), *argv]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1
    assert not out.exists()


@pytest.mark.parametrize("stem, slug", [("atv-resonant", "atv_resonant"), ("v__x", "v_x"), ("v\udcff", "v"),
                                        ("__", "vehicle"), ("4x4 car", "v_4x4_car")])
def test_vehicle_names_become_names_casadi_takes(stem: str, slug: str) -> None:
    from profileopt.mpc.codegen import vehicle_slug

    vehicle = load_vehicle("atv").replace(name=f"/some/folder/{stem}.toml")
    assert vehicle_slug(vehicle) == slug
    c_functions(vehicle, models=["iecm"])  # CasADi refused '__' in a Function's name


def test_the_size_estimate_covers_the_preview_it_exports(tmp_path: Path) -> None:
    # C_BYTES_PER_PREVIEW_KNOT is what export_c refuses by before any work: it must not be
    # below what the preview's envelopes (all five, with their Jacobians) actually write.
    from profileopt.mpc.codegen import C_BYTES_PER_PREVIEW_KNOT
    from profileopt.mpc.preview import TerrainPreview

    vehicle = load_vehicle("atv")
    preview = TerrainPreview(vehicle, horizon_m=20.0, reach_m=1.5)
    bare = export_c(vehicle, tmp_path / "bare", models=["prev_bem"], n_stages=2).source.stat().st_size
    full = export_c(vehicle, tmp_path / "full", models=["prev_bem"], n_stages=2, preview=preview)
    assert {e.kind for e in full.functions if e.model == "preview"} == {
        "e_max", "speed_cap", "curvature", "grade_max", "grade_min"}
    written = full.source.stat().st_size - bare
    assert written <= C_BYTES_PER_PREVIEW_KNOT * preview.n_intervals * 2
    assert written >= 0.5 * C_BYTES_PER_PREVIEW_KNOT * preview.n_intervals * 2  # and not far above it
