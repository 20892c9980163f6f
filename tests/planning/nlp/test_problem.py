"""The fast NLP builder (profileopt.planning.nlp.problem) against an independently written reference.

The reference below is the planner's NLP written straight from its definition (issue 3 and
the docstring of ``profileopt.planning.nlp.problem.build_nlp``) as one SX expression over all segments, the
way it was built before: y = b / b_ref at the N+1 boundaries, v = sqrt(b + eps^2),
a_i = (b_{i+1} - b_i) / (2 ds_i), travel time sum 2 ds_i / (v_i + v_{i+1}), smoothing
sum v_j (a_j - a_{j-1})^2 / dsm_j, jerk v_j (a_j - a_{j-1}) / dsm_j. Its derivatives come
from ``casadi.jacobian``/``casadi.hessian`` of the whole expression, so they are independent
of the stage-wise derivatives that build_nlp assembles. The Functions compared are the ones
IPOPT calls (``solver.get_function("nlp_grad_f")`` etc.), so a builder option that nlpsol
ignored would show up here.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from profileopt.planning.nlp import problem as _nlp
from profileopt.planning.options import DEFAULT_IPOPT_OPTIONS

EPS_MPS = 1e-3  # the speed that keeps sqrt(b) smooth at rest (NOTES: planner NLP)


def reference_nlp(n: int, with_jerk: bool, scaled: bool = False) -> dict:
    """The NLP as one SX expression: x, p, f, g (see the module docstring); with ``scaled``
    the variables are x = y / sigma, the N+1 scales sigma after the other parameters."""
    x = ca.SX.sym("x", n + 1)
    p = ca.SX.sym("p", n + 6 + (n + 1 if scaled else 0))
    ds_scaled = p[:n]
    b_ref, l_ref, a_ref, t_ref, weight, inv_jerk = (p[n + k] for k in range(6))
    y = p[n + 6:] * x if scaled else x
    ds = l_ref * ds_scaled
    b = b_ref * y
    v = ca.sqrt(b + EPS_MPS**2)
    travel = ca.sum1(2 * ds / (v[:-1] + v[1:]))
    accel = (b[1:] - b[:-1]) / (2 * ds)
    g = [accel / a_ref]
    smooth = 0
    if n >= 2:
        dsm = (ds[:-1] + ds[1:]) / 2
        da = accel[1:] - accel[:-1]
        smooth = ca.sum1(v[1:-1] * da**2 / dsm)
        if with_jerk:
            g.append(v[1:-1] * da / dsm * inv_jerk)
    return {"x": x, "p": p, "f": (travel + weight * smooth) / t_ref, "g": ca.vertcat(*g)}


def reference_functions(n: int, with_jerk: bool, scaled: bool = False) -> ca.Function:
    nlp = reference_nlp(n, with_jerk, scaled)
    x, p, f, g = nlp["x"], nlp["p"], nlp["f"], nlp["g"]
    lam_f, lam_g = ca.SX.sym("lam_f"), ca.SX.sym("lam_g", g.size1())
    hess = ca.hessian(lam_f * f + ca.dot(lam_g, g), x)[0]
    return ca.Function("ref", [x, p, lam_f, lam_g], [f, g, ca.gradient(f, x), ca.jacobian(g, x), hess])


def random_point(n: int, ng: int, rng: np.random.Generator) -> tuple:
    x = rng.uniform(0.02, 1.0, n + 1)
    x[rng.integers(0, n + 1)] = 0.0  # at rest somewhere: v = eps there
    p = np.concatenate([rng.uniform(0.3, 1.7, n),
                        [rng.uniform(20, 400), rng.uniform(1, 10), rng.uniform(0.5, 4), rng.uniform(5, 500),
                         rng.uniform(0, 2), rng.uniform(0.1, 2)]])
    return x, p, rng.uniform(0.1, 3), rng.normal(size=ng)


def dense(m) -> np.ndarray:
    return np.array(ca.DM(m).full())


@pytest.mark.parametrize("scaled", [False, True])
@pytest.mark.parametrize("n, with_jerk", [(1, True), (2, True), (2, False), (5, True), (5, False), (37, True),
                                          (130, True)])
def test_functions_ipopt_calls_equal_the_reference_derivatives(n: int, with_jerk: bool, scaled: bool) -> None:
    """With ``scaled`` (a scale per boundary, the IPOPT back end's form) the stage derivatives
    are carried over by the chain rule; the reference differentiates y = sigma x itself."""
    solver = _nlp.build_nlp(n, with_jerk, scaled=scaled)
    ref = reference_functions(n, with_jerk, scaled)
    ng = ref.size1_out(1)
    assert solver.size1_out("g") == ng and solver.size1_out("x") == n + 1
    assert solver.size1_in("p") == n + 6 + (n + 1 if scaled else 0)
    grad_f, jac_g, hess_l = (solver.get_function(name) for name in ("nlp_grad_f", "nlp_jac_g", "nlp_hess_l"))
    f_fun, g_fun = solver.get_function("nlp_f"), solver.get_function("nlp_g")
    rng = np.random.default_rng(n * 2 + with_jerk)
    for _ in range(5):
        x, p, lam_f, lam_g = random_point(n, ng, rng)
        if scaled:  # scales over four decades, as a crawl's boundaries beside the top speed's
            p = np.concatenate([p, 10.0 ** rng.uniform(-4, 0, n + 1)])
        f_ref, g_ref, grad_ref, jac_ref, hess_ref = (dense(o) for o in ref(x, p, lam_f, lam_g))
        f1, grad = grad_f(x, p)
        g1, jac = jac_g(x, p)
        hess = hess_l(x, p, lam_f, lam_g)
        assert hess.sparsity().is_triu()

        def close(value, reference) -> None:
            np.testing.assert_allclose(dense(value), reference, rtol=0,
                                       atol=1e-10 * max(np.abs(reference).max(), 1e-300))

        close(f_fun(x, p), f_ref)
        close(f1, f_ref)
        close(g_fun(x, p), g_ref)
        close(g1, g_ref)
        close(grad, grad_ref)
        close(jac, jac_ref)
        close(hess, np.triu(hess_ref))
        # every structural nonzero of the reference is in the supplied sparsity
        assert not np.any((np.abs(jac_ref) > 0) & (dense(ca.DM(jac.sparsity(), 1)) == 0))
        assert not np.any((np.abs(np.triu(hess_ref)) > 0) & (dense(ca.DM(hess.sparsity(), 1)) == 0))


def test_hessian_is_banded_so_the_build_does_not_grow_with_n() -> None:
    # bandwidth 2: stages couple at most three consecutive boundaries
    n = 50
    hess = _nlp.build_nlp(n, True).get_function("nlp_hess_l").sparsity_out(0)
    assert hess.nnz() == (n + 1) + n + (n - 1)
    jac = _nlp.build_nlp(n, True).get_function("nlp_jac_g").sparsity_out(1)
    assert jac.nnz() == 2 * n + 3 * (n - 1)


def random_problem(n: int, with_jerk: bool, seed: int) -> dict:
    """nlpsol arguments of a random feasible problem: random caps and lengths, stops at both
    ends, the greatest profile below the caps within the acceleration bounds as start."""
    rng = np.random.default_rng(seed)
    ds = rng.uniform(0.5, 1.5, n)
    l_ref, b_ref, a_ref, decel = 5.0, 100.0, 1.5, 2.0
    upper = rng.uniform(0.2, 1.0, n + 1)
    upper[0] = upper[-1] = 0.0
    b = upper * b_ref
    for i in range(n):
        b[i + 1] = min(b[i + 1], b[i] + 2 * a_ref * ds[i] * l_ref)
    for i in reversed(range(n)):
        b[i] = min(b[i], b[i + 1] + 2 * decel * ds[i] * l_ref)
    p = np.concatenate([ds, [b_ref, l_ref, a_ref, 30.0, 0.05, 1 / 1.5]])
    ng = n + (n - 1 if with_jerk and n >= 2 else 0)
    lbg = np.concatenate([np.full(n, -decel / a_ref), np.full(ng - n, -1.0)])
    return dict(x0=b / b_ref, lbx=np.zeros(n + 1), ubx=upper, lbg=lbg, ubg=np.ones(ng), p=p)


@pytest.mark.parametrize("n, with_jerk", [(1, True), (3, False), (37, True), (64, True), (150, True)])
def test_solution_equals_the_reference_nlpsol(n: int, with_jerk: bool) -> None:
    """Same IPOPT options on the reference NLP (symbolic derivatives of the whole
    expression): the same iterates, so the same b to rounding."""
    args = random_problem(n, with_jerk, 7 + n)
    reference = ca.nlpsol("reference", "ipopt", reference_nlp(n, with_jerk), dict(DEFAULT_IPOPT_OPTIONS))
    fast = _nlp.build_nlp(n, with_jerk)
    x_ref = dense(reference(**args)["x"]).ravel()
    x_new = dense(fast(**args)["x"]).ravel()
    assert reference.stats()["success"] and fast.stats()["success"]
    assert fast.stats()["iter_count"] == reference.stats()["iter_count"]
    np.testing.assert_allclose(x_new, x_ref, rtol=0, atol=1e-9 * np.abs(x_ref).max())


def test_rejects_an_empty_problem() -> None:
    with pytest.raises(ValueError, match="at least one segment"):
        _nlp.build_nlp(0, True)
