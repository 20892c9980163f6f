"""numpy_evaluator runs a CasADi Function's own instructions on arrays: CasADi's values, bitwise.

The reference is CasADi's own evaluation of the same Function (``Function.map``), so any
operation that numpy computes differently from CasADi's virtual machine fails here. The
speed bands are checked the same way: once with the numpy evaluator (the default) and
once with CasADi evaluating every point, on many random RI values for every model and
both bundled vehicles. Every public physics function, which evaluates arrays of numbers
through numpy_evaluator, is checked against CasADi's evaluation too.
"""

from __future__ import annotations

import inspect

import casadi as ca
import numpy as np
import pytest

from profileopt.core import symbolic as _casadi
from profileopt.physics import forces, speeds
from profileopt.terrain import roughness as terrain
from profileopt.physics.forces import MODELS
from profileopt.core.vehicle import load_vehicle

VEHICLES = ("atv", "atv-resonant")
SPECIAL = np.array([0.0, -0.0, 1.0, -1.0, 0.5, 2.0, 1e-300, -1e300, np.inf, -np.inf, np.nan])


def casadi_values(fun: ca.Function, *arrays: np.ndarray) -> list[np.ndarray]:
    shape = np.broadcast_shapes(*(a.shape for a in arrays))
    flat = [np.broadcast_to(a, shape).ravel()[None, :] for a in arrays]
    out = fun.map(int(np.prod(shape)))(*flat)
    out = out if isinstance(out, (list, tuple)) else [out]
    return [np.asarray(o).reshape(shape) for o in out]


def assert_bitwise(actual, expected) -> None:
    assert len(actual) == len(expected)
    for a, e in zip(actual, expected):
        assert a.shape == e.shape
        # same bits, NaN included (signed zeros compare equal, which is all CasADi promises)
        np.testing.assert_array_equal(a, e)


@pytest.mark.parametrize("op", sorted(_casadi._NUMPY_OPS))
def test_every_supported_operation_matches_casadi_on_special_values(op: int) -> None:
    x, y = ca.SX.sym("x"), ca.SX.sym("y")
    expr = ca.SX.binary(op, x, y) if op in _casadi._BINARY_OPS else ca.SX.unary(op, x)
    fun = ca.Function("f", [x, y], [expr])
    if op != ca.OP_ASSIGN:  # x itself: CasADi compiles the assignment away
        assert op in {fun.instruction_id(k) for k in range(fun.n_instructions())}
    assert _casadi._numpy_program(fun) is not None
    a, b = np.meshgrid(SPECIAL, SPECIAL)
    rng = np.random.default_rng(op)
    a = np.concatenate([a.ravel(), rng.normal(scale=10, size=500)])
    b = np.concatenate([b.ravel(), rng.normal(scale=10, size=500)])
    assert_bitwise(_casadi.numpy_evaluator(fun)(a, b), casadi_values(fun, a, b))


@pytest.mark.parametrize("vehicle_name", VEHICLES)
@pytest.mark.parametrize("model", sorted(MODELS))
def test_speed_band_functions_run_as_numpy_programs_bitwise(model: str, vehicle_name: str) -> None:
    vehicle = load_vehicle(vehicle_name)
    rng = np.random.default_rng(len(model))
    speed = np.concatenate([[0.0, vehicle.max_speed_mps], rng.uniform(0, 1.2 * vehicle.max_speed_mps, 3000)])
    ri = np.concatenate([[0.0, 0.0], rng.uniform(0, 2.0, 3000)])
    ri[::50] = 0.0  # smooth ground: the models' if_else branch
    for fun in speeds._constraint_derivatives(model, vehicle):
        evaluate = _casadi.numpy_evaluator(fun)
        # a Function the speed bands use must not silently take the slow path
        assert _casadi._numpy_program(fun) is not None, fun.name()
        assert_bitwise(evaluate(speed, ri), casadi_values(fun, speed, ri))
        # broadcasting (grid of speeds x column of RI), sliced into cache-sized chunks
        grid, column = speed[None, :100], ri[:400, None]
        assert_bitwise(evaluate(grid, column), casadi_values(fun, grid, column))


def test_unsupported_functions_fall_back_to_casadi() -> None:
    x, y = ca.SX.sym("x"), ca.SX.sym("y")
    transcendental = ca.Function("f", [x, y], [ca.exp(x) * y, ca.sin(y)])
    vector = ca.Function("g", [ca.SX.sym("v", 2), y], [y * 2])
    xm, ym = ca.MX.sym("x"), ca.MX.sym("y")
    mx = ca.Function("h", [xm, ym], [xm * ym])
    assert _casadi._numpy_program(transcendental) is None
    assert _casadi._numpy_program(vector) is None
    assert _casadi._numpy_program(mx) is None
    a, b = np.linspace(-2, 2, 7)[:, None], np.linspace(0, 1, 5)[None, :]
    assert_bitwise(_casadi.numpy_evaluator(transcendental)(a, b), casadi_values(transcendental, a, b))
    assert _casadi.numpy_evaluator(transcendental)(np.empty(0), np.empty(0))[0].shape == (0,)


def test_structurally_zero_output_is_zero() -> None:
    x, y = ca.SX.sym("x"), ca.SX.sym("y")
    fun = ca.Function("f", [x, y], [x * y, ca.jacobian(x * 3.0, x) * 0 + ca.SX(1, 1)])
    assert fun.nnz_out(1) == 0
    value, zero = _casadi.numpy_evaluator(fun)(np.arange(4.0), 2.0)
    np.testing.assert_array_equal(value, 2.0 * np.arange(4.0))
    np.testing.assert_array_equal(zero, np.zeros(4))


@pytest.mark.parametrize("vehicle_name", VEHICLES)
@pytest.mark.parametrize("model", sorted(MODELS))
def test_speed_bands_unchanged_by_the_numpy_evaluator(model: str, vehicle_name: str, monkeypatch) -> None:
    vehicle = load_vehicle(vehicle_name)
    rng = np.random.default_rng(3 + len(model) + len(vehicle_name))
    # RI from smooth to impassable, a dense sweep through the resonant vehicle's band changes
    ri = np.concatenate([[0.0], rng.uniform(0, 0.05, 100), rng.uniform(0, 1.5, 300),
                         np.linspace(0.1, 0.6, 200)])
    ri_min = ri * rng.uniform(0.0, 1.0, ri.size)  # RI ranges too (roughness windows)
    fast = speeds.speed_bands(ri, vehicle, model=model)
    fast_range = speeds.speed_bands(ri, vehicle, model=model, ri_min=ri_min)
    if model == "sbem_tf" and vehicle_name == "atv-resonant":  # the multi-band path is exercised
        assert fast.count.max() >= 2 and np.isfinite(fast.peaks_mps).any()

    def casadi_evaluators(model_: str, vehicle_: object, envelope: bool = False) -> tuple:
        return tuple(lambda *a, f=f: casadi_values(f, *np.broadcast_arrays(*map(np.asarray, a)))
                     for f in speeds._constraint_derivatives(model_, vehicle_, envelope))

    monkeypatch.setattr(speeds, "_constraint_evaluators", casadi_evaluators)
    slow = speeds.speed_bands(ri, vehicle, model=model)
    slow_range = speeds.speed_bands(ri, vehicle, model=model, ri_min=ri_min)
    for one, other in ((fast, slow), (fast_range, slow_range)):
        np.testing.assert_array_equal(one.count, other.count)
        for name in ("lower_mps", "upper_mps", "peaks_mps"):
            a, b = getattr(one, name), getattr(other, name)
            assert a.shape == b.shape
            np.testing.assert_allclose(a, b, rtol=1e-12, atol=0, equal_nan=True)


def test_speed_bands_in_row_blocks_equal_all_at_once(monkeypatch) -> None:
    # rows are independent, so splitting a long RI array into blocks changes nothing
    vehicle = load_vehicle("atv-resonant")
    ri = np.concatenate([np.linspace(0.0, 0.6, 150), [0.0, 5.0]])  # one band and two bands
    whole = speeds.speed_bands(ri, vehicle, model="sbem_tf")
    monkeypatch.setattr(speeds, "_BLOCK_ROWS", 7)
    blocks = speeds.speed_bands(ri, vehicle, model="sbem_tf")
    assert set(whole.count) == {1, 2}
    for name in ("lower_mps", "upper_mps", "count", "peaks_mps"):
        np.testing.assert_array_equal(getattr(blocks, name), getattr(whole, name))


ELEMENTWISE = [forces.base_frequency_radps, forces.iecm_force_n, forces.sbem_ef_force_n, forces.sbem_tf_force_n,
               forces.prev_bem_force_n, terrain.step_width] + [m.of_ri for m in MODELS.values()]


@pytest.mark.parametrize("vehicle_name", VEHICLES)
@pytest.mark.parametrize("public", ELEMENTWISE, ids=lambda f: f.__name__)
def test_numeric_model_evaluation_is_casadis_bitwise(public, vehicle_name: str) -> None:
    # every physics function evaluates arrays of numbers with numpy_evaluator (bitwise
    # CasADi's own evaluation of the very same Function)
    vehicle = load_vehicle(vehicle_name)
    builder = public.symbolic
    n_inputs = len(inspect.signature(builder).parameters) - 1
    fun = _casadi.scalar_function(builder, n_inputs, vehicle, builder.__name__)
    assert _casadi._numpy_program(fun) is not None
    rng = np.random.default_rng(11)
    # speeds (column) against RI or elevation (row), up to past the wheel radius (the
    # saturated step width), zeros included (the smooth-ground branch)
    terrain_values = np.concatenate([[0.0, 0.0], rng.uniform(0, 2 * vehicle.wheel_radius_m, 28)])
    if n_inputs == 2:
        args = [rng.uniform(0, vehicle.max_speed_mps, size=(40, 1)), terrain_values[None, :]]
    else:
        args = [np.tile(terrain_values, (3, 1))]
    value = public(*args, vehicle)
    assert value.shape == np.broadcast_shapes(*(a.shape for a in args))
    assert_bitwise([value], casadi_values(fun, *args))


def test_mx_replay_is_the_function_on_every_entry_bitwise() -> None:
    # one MX vector operation per instruction: the stage Functions of the NLP, a
    # parameter-only entry (stays a scalar) and a structural zero (None)
    z, q = ca.SX.sym("z", 2), ca.SX.sym("q")
    expr = ca.sqrt(z[0] + 1e-6) * z[1] / (q + 2.0) - ca.fmin(z[0], q) ** 2
    fun = ca.Function("stage", [z, q], [ca.vertcat(expr, 2.0 * q, ca.SX(1, 1)), ca.gradient(expr, z)])
    rng = np.random.default_rng(5)
    a, b, qq = rng.uniform(0, 2, 50), rng.normal(size=50), 0.7
    za, zb, qm = ca.MX.sym("a", 50), ca.MX.sym("b", 50), ca.MX.sym("q")
    (value, only_q, zero), gradient = _casadi.mx_replay(fun, [[za, zb], [qm]])
    assert zero is None and only_q.size1() == 1
    replayed = ca.Function("r", [za, zb, qm], [value, only_q, gradient[0], gradient[1]])
    got = [np.asarray(o).ravel() for o in replayed(a, b, qq)]
    reference = fun.map(50)(np.stack([a, b]), qq)
    ref_value = np.asarray(reference[0])  # 3 x 50
    ref_grad = np.asarray(reference[1])  # 2 x 50
    np.testing.assert_array_equal(got[0], ref_value[0])
    np.testing.assert_array_equal(got[1], [2.0 * qq])
    np.testing.assert_array_equal(got[2], ref_grad[0])
    np.testing.assert_array_equal(got[3], ref_grad[1])
