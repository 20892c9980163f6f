"""FATROP on the NLP's stage form (profileopt.planning.nlp.backends.fatrop).

References, independent of the stage form: IPOPT on the whole NLP written as one SX
expression (``reference_nlp`` of tests/planning/nlp/test_problem.py), and the exact
forward-backward profile where the NLP is convex.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

import profileopt
from profileopt import load_vehicle, read_route
from profileopt.planning import SolverOptions
from profileopt.planning.nlp.backends import BACKENDS, NlpInstance, get_backend
from profileopt.planning.nlp.backends.fatrop import StageInstance
from profileopt.planning.options import DEFAULT_IPOPT_OPTIONS, NLP_SOLVERS

from conftest import ROUTES
from planning.nlp.test_problem import dense, random_problem, reference_nlp

FATROP = SolverOptions(nlp_solver="fatrop")


def instance(n: int, with_jerk: bool, seed: int) -> tuple[NlpInstance, dict]:
    """A random feasible problem (test_problem.random_problem) as an instance, and its nlpsol arguments."""
    args = random_problem(n, with_jerk, seed)
    p = args["p"]
    problem = NlpInstance(n, with_jerk, (), args["x0"], args["lbx"], args["ubx"], p[:n], args["lbg"], args["ubg"],
                          p[n:])
    return problem, args


def objective(n: int, with_jerk: bool) -> ca.Function:
    """The reference NLP's objective as a Function of (y, p)."""
    nlp = reference_nlp(n, with_jerk)
    return ca.Function("f", [nlp["x"], nlp["p"]], [nlp["f"]])


# Random problems of test_problem's family: FATROP converges on about half of them and
# reaches its iteration limit on the rest (measured; the docs' solver page says so).
FAMILY = [(n, True, seed) for n in (2, 5, 20, 37, 80, 150) for seed in range(3)] + [(3, False, 1), (12, False, 0)]


def test_fatrop_reaches_ipopts_optimum_of_the_reference_nlp_where_it_converges() -> None:
    converged = 0
    for n, with_jerk, seed in FAMILY:
        problem, args = instance(n, with_jerk, seed)
        reference = ca.nlpsol("reference", "ipopt", reference_nlp(n, with_jerk), dict(DEFAULT_IPOPT_OPTIONS))
        x_ref = dense(reference(**args)["x"]).ravel()
        assert reference.stats()["success"]
        result = get_backend("fatrop").solve(problem, FATROP, {})
        assert result.solver == "fatrop" and result.iterations > 0
        if not result.success:
            assert result.status == "the iteration limit (300)"
            continue
        converged += 1
        f = objective(n, with_jerk)
        f_ref, f_new = (float(f(x, args["p"])) for x in (x_ref, result.y))
        # the same local optimum (the NLP is not convex; both start from the same point)
        assert f_new == pytest.approx(f_ref, rel=1e-6), (n, with_jerk, seed)
        np.testing.assert_allclose(result.y, x_ref, rtol=0, atol=1e-4)
        # within the bounds (FATROP relaxes them by 1e-8; the back end gives it bounds moved in by that)
        assert np.all(result.y >= args["lbx"]) and np.all(result.y <= args["ubx"]), (n, seed)
    assert converged >= len(FAMILY) // 3, converged


@pytest.mark.parametrize("n, seed", [(2, 1), (20, 0), (37, 1), (150, 0)])
def test_where_fatrop_stops_ipopt_takes_over(n: int, seed: int) -> None:
    """Problems of the same family on which FATROP reaches its iteration limit (measured):
    solve_nlp hands them to IPOPT, says so, and counts both solvers' iterations."""
    from profileopt.planning.nlp.solve import solve_nlp

    problem, args = instance(n, True, seed)
    alone = get_backend("fatrop").solve(problem, FATROP, {})
    ipopt = get_backend("ipopt").solve(problem, SolverOptions(), {})
    result = solve_nlp(n, True, (), FATROP, problem.x0, problem.lbx, problem.ubx, problem.length_scaled,
                       problem.lbg, problem.ubg, problem.p_tail)
    assert ipopt.success
    if alone.success:  # FATROP converged after all: its own answer, IPOPT not run
        assert result.solver == "fatrop" and result.iterations == alone.iterations
    else:
        assert result.success and result.solver == f"ipopt (the fatrop solver stopped: {alone.status})"
        assert result.iterations == alone.iterations + ipopt.iterations
        np.testing.assert_array_equal(result.y, ipopt.y)


def test_fatrop_multipliers_come_back_in_the_order_of_the_rows() -> None:
    """The acceleration rows' multipliers are the bounds' on u_k, the jerk rows' the stage
    rows': in the order of row_bounds they equal IPOPT's on the reference NLP (same KKT point,
    unique multipliers where the active rows are independent)."""
    n = 80
    problem, args = instance(n, True, 1)
    reference = ca.nlpsol("reference", "ipopt", reference_nlp(n, True), dict(DEFAULT_IPOPT_OPTIONS))
    out = reference(**args)
    lam_ref = dense(out["lam_g"]).ravel()
    result = get_backend("fatrop").solve(problem, FATROP, {})
    assert result.success and result.lam_g.shape == lam_ref.shape
    scale = np.abs(lam_ref).max()
    assert scale > 0
    np.testing.assert_allclose(result.lam_g, lam_ref, rtol=0, atol=1e-4 * scale)


def test_the_stage_form_holds_the_same_bounds_and_rows() -> None:
    """The stage instance's bounds on y are the problem's, on u the acceleration rows', and
    its start satisfies the dynamics exactly."""
    problem, _ = instance(12, True, 3)
    stage = StageInstance(problem)
    # moved in by FATROP's bound relaxation, 1e-8 max(1, |bound|), except fixed speeds (the stops)
    relax = 1e-8 * np.maximum(1.0, np.abs(problem.ubx))
    fixed = problem.lbx == problem.ubx
    np.testing.assert_allclose(stage.lbx[stage.y_index], np.where(fixed, problem.lbx, problem.lbx + relax),
                               rtol=0, atol=1e-15)
    np.testing.assert_allclose(stage.ubx[stage.y_index], np.where(fixed, problem.ubx, problem.ubx - relax),
                               rtol=0, atol=1e-15)
    accel_relax = 1e-8 * np.maximum(1.0, np.maximum(np.abs(problem.lbg[:12]), np.abs(problem.ubg[:12])))
    np.testing.assert_allclose(stage.lbx[stage.w_index], problem.lbg[:12] + accel_relax, rtol=0, atol=1e-15)
    np.testing.assert_allclose(stage.ubx[stage.w_index], problem.ubg[:12] - accel_relax, rtol=0, atol=1e-15)
    b_ref, l_ref, a_ref = problem.p_tail[:3]
    y, w = stage.x0[stage.y_index], stage.x0[stage.w_index]
    np.testing.assert_allclose(y[1:], y[:-1] + 2 * l_ref * problem.length_scaled * a_ref * w / b_ref, atol=1e-7)
    assert stage.jerk_rows.size == 11 and np.all(stage.ubg[stage.jerk_rows] == 1.0)


def test_every_back_end_is_named_and_chosen_by_its_name() -> None:
    assert tuple(BACKENDS) == NLP_SOLVERS
    assert all(get_backend(name).name == name for name in NLP_SOLVERS)


@pytest.mark.parametrize("name", ["curb", "washboard"])
def test_a_plan_with_fatrop_reaches_ipopts_travel_time(name: str) -> None:
    """Whole routes through plan(): FATROP (or IPOPT where it stops, with a note) to the same
    travel time as IPOPT's own plan, and the convex problem to the exact optimum."""
    route, vehicle = read_route(ROUTES / f"{name}.csv"), load_vehicle("atv")
    ipopt = profileopt.plan(route, vehicle)
    fatrop = profileopt.plan(route, vehicle, solver_options=FATROP)
    assert ipopt.solver == "ipopt" and fatrop.status == "optimal"
    assert fatrop.solver == "fatrop" or fatrop.solver.startswith("ipopt (the fatrop solver stopped")
    assert fatrop.objective == pytest.approx(ipopt.objective, rel=1e-6)
    convex = dict(smoothing=0.0, max_jerk_mps3=float("inf"))
    exact = profileopt.plan(route, vehicle, **convex)
    solved = profileopt.plan(route, vehicle, method="nlp", solver_options=FATROP, **convex)
    assert exact.status == "exact" and solved.status == "optimal"
    assert solved.travel_time_s == pytest.approx(exact.travel_time_s, rel=1e-8)
