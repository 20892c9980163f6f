"""A primal-dual interior-point solver for the planner's chain-structured NLP: an opt-in back end.

The planner's NLP (:func:`profileopt.planning.nlp.problem.build_nlp`) is a chain: every term of
the objective and every row acts on at most three neighbouring variables. Its Newton
system, once the slacks and bound multipliers are eliminated, is therefore a symmetric
matrix of bandwidth 2, which a sparse Cholesky factorisation solves in time proportional to
N. IPOPT cannot know this and hands a sparse indefinite system five times that size to
MUMPS at every iteration, which is where 85 % of a 10,000-segment plan went. This module
solves the same problem, with the same exact derivatives (:func:`build_banded_oracle`:
the stage Functions of :mod:`~profileopt.planning.nlp.problem`, placed as bands), by the
same kind of method as IPOPT; the planner hands the problem to IPOPT whenever it does not
converge (:func:`profileopt.planning.nlp.solve.solve_nlp`), so it can make a plan faster
but never decide whether one is found.

Why it is kept, as ``SolverOptions(nlp_solver="banded")`` or ``profileopt plan --solver
banded`` and never by default: on the benchmark's long routes it is more than twice as
fast as IPOPT with the same optimum (the measurements are in ``benchmarks/results.md`` and
the docs' solver page). It is a solver this project owns, so the default is IPOPT.

The method (Nocedal and Wright, *Numerical Optimization*, 2nd ed., ch. 19; Wächter and
Biegler, Math. Program. 106 (2006) 25-57, for the safeguards):

* the problem  min f(y)  s.t.  y_L <= y <= y_U,  g_L <= g(y) <= g_U  is written with slacks
  s = g(y) and logarithmic barriers on every finite bound;
* each iteration solves the primal-dual Newton system condensed to
  (W + Sigma_y + J^T Sigma_s J) dy = r (W the Hessian of the Lagrangian, Sigma the barrier
  terms) on the band: a Cholesky factorisation, which fails unless the matrix is positive
  definite (the KKT matrix has the right inertia), and then a multiple of I is added, as
  IPOPT does. The factorisation is CasADi's (CSparse Cholesky, then LDL^T for the further
  solves of the iteration) up to :data:`LAPACK_ABOVE` boundaries and LAPACK's banded
  Cholesky (scipy.linalg) above, where its speed outweighs the cost of importing it;
* the barrier parameter follows Mehrotra's predictor-corrector rule, mu = (mu_aff / mu)^3 mu,
  with his second-order corrector;
* steps stay a fraction tau = max(0.99, 1 - mu) inside the bounds and are accepted by a
  backtracking Armijo search on the l1 merit function phi_mu + nu ||g(y) - s||_1, with a
  second-order correction when the full step fails; nu is 1.1 times the largest new row
  multiplier, set afresh at every iteration (a penalty kept from the wild first steps made
  the merit's curvature block all progress near the solution);
* bound multipliers start at the size of the objective's gradient;
* it stops when IPOPT's scaled optimality error is below ``tol`` and the total
  complementarity (the duality gap: how far f can still be above the optimum) is below
  ``tol`` times f, so that a long route's optimum is as exact as a short one's.

Variables whose two bounds are equal are fixed (IPOPT's default ``fixed_variable_treatment``);
rows whose two bounds are equal are not supported (the planner has none) and are reported
as a failed solve.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from typing import Callable

import time

import casadi as ca
import numpy as np

from ...options import SolverOptions
from ..problem import NlpResult, diagonal_matrix, nlp_parts
from .base import NlpInstance

__all__ = ["BACKEND", "BandedBackend", "BandedOracle", "build_banded_oracle", "cached_banded_oracle",
           "solve_banded", "LAPACK_ABOVE", "band_solve_functions"]

#: Largest multiple of I added to the condensed matrix before the solve gives up.
_MAX_REGULARISATION = 1e20
#: Armijo's sufficient-decrease fraction of the merit's directional derivative.
_ARMIJO = 1e-4
#: IPOPT's kappa_Sigma: bound multipliers stay within [mu / (k d), k mu / d] of their slack d.
_KAPPA_SIGMA = 1e10


@dataclasses.dataclass(frozen=True)
class BandedOracle:
    """The planner's NLP for N segments, evaluated as dense bands (:func:`build_banded_oracle`).

    Attributes
    ----------
    n : int
        Number of segments N; the variables are y (N+1,).
    values : casadi.Function
        (y, p) -> (f, g): objective and rows.
    derivatives : casadi.Function
        (y, p, lam_f, lam_g) -> (f, grad f (N+1,), g, one (count, width) Jacobian band per
        row block, then the Hessian of lam_f f + lam_g^T g as its diagonals at offsets 0, 1
        and 2 (N+1,), (N,), (N-1,)).
    widths : tuple of int
        Width of each row block (2: the rows of segment k act on y_k, y_{k+1}; 3: the jerk
        row of boundary k+1 acts on y_k .. y_{k+2}); row k of a block starts at column k.
    counts : tuple of int
        Rows in each block, in the order of g.
    """

    n: int
    values: ca.Function
    derivatives: ca.Function
    widths: tuple[int, ...]
    counts: tuple[int, ...]


def build_banded_oracle(n: int, with_jerk: bool, families: tuple[str, ...] = ()) -> "BandedOracle":
    """The planner's NLP for N = n segments as dense banded pieces, for :func:`solve_banded`.

    The same variables, parameters, objective and rows as :func:`~.nlp.build_nlp` (same stage
    Functions, same placement), but the Jacobian and the Hessian of the Lagrangian are
    returned as their bands (dense numpy arrays) rather than as sparse matrices: a solver
    that knows the chain structure factorises them in time proportional to N.

    Parameters
    ----------
    n : int
        Number of segments N >= 1.
    with_jerk : bool
        Whether g holds the jerk rows (only when N >= 2).
    families : tuple of str, default ()
        Row families (:data:`~profileopt.physics.rows.ROW_FAMILIES`).

    Returns
    -------
    BandedOracle
    """
    parts = nlp_parts(n, with_jerk, families)
    x, p = parts.x, parts.p
    values = ca.Function(f"{parts.name}_values", [x, p], [parts.f, parts.g])
    jac = [ca.horzcat(*block) for block in parts.jac_blocks]
    derivatives = ca.Function(f"{parts.name}_derivatives", [x, p, parts.lam_f, parts.lam_g],
                              [parts.f_d, parts.grad, parts.g_d, *jac, *parts.hess_diagonals])
    widths = tuple(len(block) for block in parts.jac_blocks)
    counts = tuple(block[0].size1() for block in parts.jac_blocks)
    return BandedOracle(n, values, derivatives, widths, counts)


@functools.lru_cache(maxsize=8)
def cached_banded_oracle(n: int, with_jerk: bool, families: tuple[str, ...] = ()) -> BandedOracle:
    """:func:`build_banded_oracle` for N = n segments, built once per size and cached.

    Parameters
    ----------
    n : int
        Number of segments.
    with_jerk : bool
        Whether the jerk rows are in g (only when n >= 2).
    families : tuple of str, default ()
        Row families (:data:`~profileopt.physics.rows.ROW_FAMILIES`).

    Returns
    -------
    BandedOracle
    """
    return build_banded_oracle(n, with_jerk and n >= 2, families)


class _Buffered:
    """A casadi.Function evaluated on persistent numpy arrays (``Function.buffer``): no
    conversion to and from DM at each call, which at 10,000 segments cost more than the
    evaluation itself."""

    def __init__(self, function: ca.Function) -> None:
        self.inputs = [np.zeros(function.nnz_in(i)) for i in range(function.n_in())]
        self.outputs = [np.zeros(function.nnz_out(i)) for i in range(function.n_out())]
        self.buffer, self.evaluate = function.buffer()
        for i, a in enumerate(self.inputs):
            self.buffer.set_arg(i, memoryview(a))
        for i, r in enumerate(self.outputs):
            self.buffer.set_res(i, memoryview(r))

    def __call__(self, *args: np.ndarray | float, copy: bool = True) -> list[np.ndarray]:
        """The outputs (dense, column-major) at ``args``: copies, safe to keep, or with
        ``copy=False`` the buffers themselves, overwritten by the next call (at 100,000
        segments the copies cost a tenth of the evaluation)."""
        for target, value in zip(self.inputs, args):
            target[:] = value
        self.evaluate()
        return [r.copy() for r in self.outputs] if copy else list(self.outputs)


class _Rows:
    """The Jacobian of g as dense bands: block b holds ``counts[b]`` rows, row k of it acting
    on columns k .. k + width - 1 (:class:`BandedOracle`)."""

    def __init__(self, oracle: BandedOracle, bands: list[np.ndarray]) -> None:
        self.bands = bands
        starts = np.cumsum((0,) + oracle.counts)
        self.slices = [slice(int(a), int(b)) for a, b in zip(starts[:-1], starts[1:])]

    def times(self, v: np.ndarray) -> np.ndarray:
        """J v, shape (M,)."""
        out = []
        for band in self.bands:
            count, width = band.shape
            out.append(sum(band[:, r] * v[r:r + count] for r in range(width)))
        return np.concatenate(out)

    def transpose_times(self, w: np.ndarray, n: int) -> np.ndarray:
        """J^T w, shape (n,)."""
        out = np.zeros(n)
        for band, rows in zip(self.bands, self.slices):
            count, width = band.shape
            for r in range(width):
                out[r:r + count] += band[:, r] * w[rows]
        return out

    def gram(self, d: np.ndarray, diagonals: list[np.ndarray]) -> None:
        """Add J^T diag(d) J to the upper diagonals (offsets 0, 1, 2), in place."""
        for band, rows in zip(self.bands, self.slices):
            count, width = band.shape
            weight = d[rows]
            for r1 in range(width):
                for r2 in range(r1, width):
                    diagonals[r2 - r1][r1:r1 + count] += band[:, r1] * band[:, r2] * weight


def _push(x: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """x moved strictly inside [lower, upper] as IPOPT's bound_push and bound_frac (0.01) do."""
    x = x.copy()
    has_l, has_u = np.isfinite(lower), np.isfinite(upper)
    both = has_l & has_u
    width = np.where(both, upper - np.where(has_l, lower, 0.0), np.inf)
    lo = np.where(has_l, lower, 0.0)
    up = np.where(has_u, upper, 0.0)
    p_lo = np.minimum(1e-2 * np.maximum(1.0, np.abs(lo)), 1e-2 * width)
    p_up = np.minimum(1e-2 * np.maximum(1.0, np.abs(up)), 1e-2 * width)
    x[has_l] = np.maximum(x[has_l], (lo + p_lo)[has_l])
    x[has_u] = np.minimum(x[has_u], (up - p_up)[has_u])
    return x


def _max_step(value: np.ndarray, step: np.ndarray, tau: float) -> float:
    """Largest alpha in (0, 1] with value + alpha step >= (1 - tau) value (value > 0; a
    zero step, as where a bound is absent, never limits)."""
    shrink = np.maximum(-step, 0.0)
    worst = float(np.max(shrink / value, initial=0.0))  # 1 / alpha of the tightest entry
    return 1.0 if worst <= tau else tau / worst


def solve_banded(oracle: BandedOracle, x0: np.ndarray, lbx: np.ndarray, ubx: np.ndarray, lbg: np.ndarray,
                 ubg: np.ndarray, p: np.ndarray, *, tol: float = 1e-10, max_iter: int = 300,
                 trace: Callable[[dict], None] | None = None) -> NlpResult:
    """Solve the banded NLP from ``x0`` (see the module docstring).

    Parameters
    ----------
    oracle : BandedOracle
        From :func:`build_banded_oracle` or :func:`cached_banded_oracle`.
    x0, lbx, ubx : numpy.ndarray, shape (N+1,)
        Start point and bounds of y = b / b_ref.
    lbg, ubg : numpy.ndarray, shape (M,)
        Bounds of the rows (may be infinite; not equal).
    p : numpy.ndarray
        The NLP's parameters (segment lengths, families' data, then the tail).
    tol : float, default 1e-10
        Tolerance on IPOPT's scaled optimality error.
    max_iter : int, default 300
        Most iterations.
    trace : callable, optional
        Called after every iteration with a dict of its numbers (error, mu, step sizes,
        regularisation, merit penalty): for studying a solve, never needed to plan.

    Returns
    -------
    NlpResult
        ``success`` False (status saying why) when it stops without converging.
    """
    n, m = x0.size, lbg.size
    if np.any(np.isfinite(lbg) & (lbg == ubg)):
        return NlpResult(x0.copy(), np.zeros(m), False, "equality rows are not supported", 0, "banded")
    if np.any(lbx > ubx):
        return NlpResult(x0.copy(), np.zeros(m), False, "a lower bound is above its upper bound", 0, "banded")
    free = lbx < ubx
    has_l, has_u = free & np.isfinite(lbx), free & np.isfinite(ubx)
    row_l, row_u = np.isfinite(lbg), np.isfinite(ubg)
    bounded_row = row_l | row_u
    x = np.where(free, _push(np.clip(x0, lbx, ubx), lbx, ubx), lbx)
    values, derivatives = _Buffered(oracle.values), _Buffered(oracle.derivatives)
    band = _BandSolver(n)

    _, g = values(x, p)
    s = _push(g, lbg, ubg)
    # bound multipliers start at the scale of the objective's gradient, not at IPOPT's 1:
    # the planner's f is a travel time over its whole-route scale, so its gradient entries
    # are about 1/N, and multipliers of 1 made the first steps' row multipliers, and with them
    # the Hessian's curvature, a thousand times too large on a route of 1,000 segments
    grad0 = derivatives(x, p, 1.0, np.zeros(m))[1]
    z0 = min(1.0, max(float(np.max(np.abs(grad0[free]), initial=0.0)), 1e-8))
    zl, zu = has_l * z0, has_u * z0
    vl, vu = row_l * z0, row_u * z0
    y = np.zeros(m)
    nu = 1.0  # merit penalty
    delta_last = 0.0
    # slack of each bound (1 where there is no bound, so that every division is defined)
    lo_x, up_x = np.where(has_l, lbx, 0.0), np.where(has_u, ubx, 0.0)
    lo_g, up_g = np.where(row_l, lbg, 0.0), np.where(row_u, ubg, 0.0)

    def slacks(x: np.ndarray, s: np.ndarray) -> tuple[np.ndarray, ...]:
        return (np.where(has_l, x - lo_x, 1.0), np.where(has_u, up_x - x, 1.0),
                np.where(row_l, s - lo_g, 1.0), np.where(row_u, up_g - s, 1.0))

    def log_sum(x: np.ndarray, s: np.ndarray) -> float:
        """The barrier's sum of log(slack) over every bound; -inf outside the bounds."""
        gaps = slacks(x, s)  # 1 where there is no bound: log 1 = 0
        if not all(np.all(d > 0) for d in gaps):
            return -math.inf
        return sum(float(np.sum(np.log(d))) for d in gaps)

    def merit(fx: float, gx: np.ndarray, logs: float, s: np.ndarray, mu: float) -> float:
        """phi_mu + nu ||g - s||_1 (``logs``: :func:`log_sum` of the point); +inf outside the
        bounds or where f or g is not finite."""
        if not (math.isfinite(fx) and math.isfinite(logs) and np.all(np.isfinite(gx))):
            return math.inf
        return float(fx - mu * logs + nu * np.sum(np.abs(gx - s)))

    # None: free mode (Mehrotra); a number: the fixed barrier parameter of the monotone mode
    # that a poor step (a short one, or one that needed the Hessian regularised: far from a
    # solution, in a nonconvex region) switches to for the rest of the solve
    logs_here: float | None = None  # log_sum at (x, s), known after an accepted step
    mu_fixed: float | None = None
    mu_solved: float | None = None  # the last fixed-mode barrier parameter whose problem was solved
    bound_mask = np.concatenate([has_l, has_u, row_l, row_u])
    bounds_count = int(bound_mask.sum())
    mu_floor = tol / (10.0 * max(bounds_count, 1))  # the gap test below needs mu * count < tol
    for iteration in range(max_iter + 1):
        out = derivatives(x, p, 1.0, y, copy=False)  # consumed within this iteration
        f, grad, g = float(out[0][0]), out[1], out[2]
        rows = _Rows(oracle, [b.reshape(w, -1).T for b, w in zip(out[3:-3], oracle.widths)])
        hess = out[-3:]
        s = np.where(bounded_row, s, g)  # a row without bounds keeps s = g
        dl, du, sl, su = slacks(x, s)
        grad_jty = grad + rows.transpose_times(y, n)  # grad f + J^T y, in r_d and every step's right-hand side
        r_d = np.where(free, grad_jty - zl + zu, 0.0)
        r_c = g - s
        compl = np.concatenate([dl * zl, du * zu, sl * vl, su * vu])  # 0 where there is no bound (z = 0)
        mu_now = float(compl.sum()) / bounds_count if bounds_count else 0.0
        # the slacks' stationarity, -y - v_l + v_u = 0 (y = 0 on a row without bounds): the
        # row multipliers returned are y, so it belongs to the dual infeasibility, as in IPOPT
        r_s = -y - vl + vu
        s_d = max(100.0, (np.abs(y).sum() + zl.sum() + zu.sum() + vl.sum() + vu.sum()) / max(n + m, 1)) / 100.0
        dual = max(float(np.max(np.abs(r_d))), float(np.max(np.abs(r_s), initial=0.0))) / s_d
        error = max(dual, float(np.max(np.abs(r_c), initial=0.0)), float(np.max(compl, initial=0.0)) / s_d)
        # IPOPT's test, and the total complementarity (the duality gap: how far f can be
        # above the optimum) within tol of f, so that a long route's optimum is as exact as a
        # short one's (the per-bound test alone left f 1.6e-6 high at 100,000 segments)
        if error <= tol and float(np.sum(compl)) <= tol * max(1.0, abs(f)):
            return NlpResult(x, y, True, "optimal", iteration, "banded")
        if not math.isfinite(error):
            return NlpResult(x, y, False, "the iterates are no longer finite", iteration, "banded")
        if iteration == max_iter:
            break

        sigma_x = np.where(has_l, zl / dl, 0.0) + np.where(has_u, zu / du, 0.0)
        sigma_s = np.where(row_l, vl / sl, 0.0) + np.where(row_u, vu / su, 0.0)
        diagonals = [hess[0] + sigma_x, hess[1], hess[2]]
        rows.gram(sigma_s, diagonals)
        # fixed variables: their rows and columns are those of the identity (dy = 0 there)
        diagonals[0] = np.where(free, diagonals[0], 1.0)
        diagonals[1] = np.where(free[:-1] & free[1:], diagonals[1], 0.0)
        diagonals[2] = np.where(free[:-2] & free[2:], diagonals[2], 0.0) if n > 2 else diagonals[2]
        delta = 0.0  # the multiple of I on the free variables (inertia correction, below)

        def direction(mu_l: np.ndarray, mu_u: np.ndarray, mu_sl: np.ndarray, mu_su: np.ndarray,
                      r_c: np.ndarray = r_c, first: bool = False):
            """The Newton step for complementarity targets mu_* (per bound) and constraint
            residual r_c (the second-order correction replaces it); ``first``: by Cholesky,
            None if the matrix (with the current delta) is not positive definite."""
            rt_x = grad_jty - np.where(has_l, mu_l / dl, 0.0) + np.where(has_u, mu_u / du, 0.0)
            rt_s = -y - np.where(row_l, mu_sl / sl, 0.0) + np.where(row_u, mu_su / su, 0.0)
            rhs = np.where(free, -rt_x - rows.transpose_times(sigma_s * r_c + rt_s, n), 0.0)
            a0 = diagonals[0] + np.where(free, delta, 0.0)
            dx = band.solve(a0, diagonals[1], diagonals[2], rhs, definite_only=first)
            if dx is None:
                return None
            dx = np.where(free, dx, 0.0)
            ds = rows.times(dx) + r_c
            dy = np.where(bounded_row, sigma_s * ds + rt_s, 0.0)
            dzl = np.where(has_l, (mu_l - dl * zl - zl * dx) / dl, 0.0)
            dzu = np.where(has_u, (mu_u - du * zu + zu * dx) / du, 0.0)
            dvl = np.where(row_l, (mu_sl - sl * vl - vl * ds) / sl, 0.0)
            dvu = np.where(row_u, (mu_su - su * vu + vu * ds) / su, 0.0)
            return dx, ds, dy, dzl, dzu, dvl, dvu

        def step_limits(dx, ds, dzl, dzu, dvl, dvu, tau):
            """Fraction-to-boundary step sizes (primal, dual); the multipliers of absent bounds
            are 0 and stay 0 (their steps are 0), so only the slacks need masking."""
            alpha_p = min(_max_step(dl, np.where(has_l, dx, 0.0), tau), _max_step(du, np.where(has_u, -dx, 0.0), tau),
                          _max_step(sl, np.where(row_l, ds, 0.0), tau), _max_step(su, np.where(row_u, -ds, 0.0), tau))
            alpha_d = min(_max_step(np.where(has_l, zl, 1.0), dzl, tau), _max_step(np.where(has_u, zu, 1.0), dzu, tau),
                          _max_step(np.where(row_l, vl, 1.0), dvl, tau), _max_step(np.where(row_u, vu, 1.0), dvu, tau))
            return alpha_p, alpha_d

        if mu_fixed is not None:
            barrier_error = max(dual, float(np.max(np.abs(r_c), initial=0.0)),
                                float(np.max(np.abs(compl - mu_fixed), initial=0.0, where=bound_mask)) / s_d)
            if barrier_error <= 10.0 * mu_fixed:  # its barrier problem solved: back to free mode
                mu_solved, mu_fixed = mu_fixed, None
        # the first step (Mehrotra's predictor, mu = 0, in free mode; the barrier step in fixed
        # mode), by Cholesky: where it fails, delta I is added as IPOPT does (first 1e-4, or a
        # third of the last delta; then x100 the first time, x8 after)
        first = (0.0,) * 4 if mu_fixed is None else (mu_fixed,) * 4
        while (step := direction(*(np.full(k, t) for k, t in zip((n, n, m, m), first)), first=True)) is None:
            if delta == 0.0:
                delta = 1e-4 if delta_last == 0.0 else max(1e-20, delta_last / 3.0)
            else:
                delta *= 100.0 if delta_last == 0.0 else 8.0
            if delta > _MAX_REGULARISATION:
                return NlpResult(x, y, False, "the Newton matrix could not be made positive definite", iteration,
                                 "banded")
        if delta > 0.0:
            delta_last = delta
        dx, ds, dy, dzl, dzu, dvl, dvu = step
        if mu_fixed is None:
            # free mode: the barrier target the predictor suggests, and the corrector (targets
            # mu minus the predictor's second-order complementarity terms)
            a_p, a_d = step_limits(dx, ds, dzl, dzu, dvl, dvu, 1.0)
            compl_aff = np.concatenate([(dl + a_p * dx) * (zl + a_d * dzl), (du - a_p * dx) * (zu + a_d * dzu),
                                        (sl + a_p * ds) * (vl + a_d * dvl), (su - a_p * ds) * (vu + a_d * dvu)])
            mu_aff = float(compl_aff.sum()) / bounds_count if bounds_count else 0.0
            mu = max(min((mu_aff / mu_now) ** 3, 1.0) * mu_now if mu_now > 0 else 0.0, mu_floor)
            targets = (mu - dx * dzl, mu + dx * dzu, mu - ds * dvl, mu + ds * dvu)
        else:
            # fixed mode (IPOPT's monotone strategy): plain Newton steps on the barrier problem
            # of mu_fixed until it is solved to 10 mu (IPOPT's kappa_epsilon), then free again
            mu = mu_fixed
            targets = (np.full(n, mu), np.full(n, mu), np.full(m, mu), np.full(m, mu))
        if mu_fixed is None:
            dx, ds, dy, dzl, dzu, dvl, dvu = direction(*targets)
        grad_phi_x = np.where(free, grad - np.where(has_l, mu / dl, 0.0) + np.where(has_u, mu / du, 0.0), 0.0)
        grad_phi_s = -np.where(row_l, mu / sl, 0.0) + np.where(row_u, mu / su, 0.0)
        violation = float(np.sum(np.abs(r_c)))
        nu = float(np.max(np.abs(y + dy), initial=0.0)) * 1.1 + 1e-8
        slope = float(grad_phi_x @ dx + grad_phi_s @ ds) - nu * violation
        if slope >= 0:  # the corrector spoilt descent: the plain barrier step for this mu
            targets = (np.full(n, mu), np.full(n, mu), np.full(m, mu), np.full(m, mu))
            dx, ds, dy, dzl, dzu, dvl, dvu = direction(*targets)
            nu = float(np.max(np.abs(y + dy), initial=0.0)) * 1.1 + 1e-8
            slope = float(grad_phi_x @ dx + grad_phi_s @ ds) - nu * violation
        tau = max(0.99, 1.0 - mu)
        alpha_p, alpha_d = step_limits(dx, ds, dzl, dzu, dvl, dvu, tau)
        if logs_here is None:
            logs_here = log_sum(x, s)
        phi0 = merit(f, g, logs_here, s, mu)
        alpha = alpha_p
        while True:
            x_t, s_t = x + alpha * dx, s + alpha * ds
            f_t, g_t = values(x_t, p, copy=False)
            s_t = np.where(bounded_row, s_t, g_t)
            logs_t = log_sum(x_t, s_t)
            phi = merit(float(f_t[0]), g_t, logs_t, s_t, mu)
            if not math.isfinite(logs_t) and alpha == alpha_p and tau > 0.99:
                # tau = 1 - mu left a slack at or below rounding (a bound that the step makes
                # active, near the end, where mu is tiny): step 0.99 of the way instead of half
                alpha_99 = step_limits(dx, ds, dzl, dzu, dvl, dvu, 0.99)[0]
                if alpha_99 < alpha:
                    alpha = alpha_99
                    continue
            if math.isfinite(phi) and phi <= phi0 + _ARMIJO * alpha * min(slope, 0.0):
                break
            if alpha == alpha_p and math.isfinite(phi):
                # second-order correction (Wächter and Biegler, sec. 2.4): the full step
                # failed, perhaps only for the curvature of g (the Maratos effect); correct
                # it for the residual the step leaves, with the same matrix
                soc = direction(*targets, r_c=alpha_p * r_c + (g_t - s_t))
                a_soc, _ = step_limits(soc[0], soc[1], *soc[3:], tau)
                x_c, s_c = x + a_soc * soc[0], s + a_soc * soc[1]
                f_c, g_c = values(x_c, p, copy=False)
                s_c = np.where(bounded_row, s_c, g_c)
                logs_c = log_sum(x_c, s_c)
                phi_c = merit(float(f_c[0]), g_c, logs_c, s_c, mu)
                if math.isfinite(phi_c) and phi_c <= phi0 + _ARMIJO * alpha_p * min(slope, 0.0):
                    x_t, s_t, alpha, logs_t = x_c, s_c, a_soc, logs_c
                    dx, ds, dy, dzl, dzu, dvl, dvu = soc
                    alpha_d = min(alpha_d, step_limits(*soc[:2], *soc[3:], tau)[1])
                    break
            alpha *= 0.5
            if alpha < 1e-14:
                return NlpResult(x, y, False, "the line search failed", iteration, "banded")
        if mu_fixed is None and (alpha < 0.1 or delta > 0.0):
            # back to fixed mode; below the last barrier parameter solved (IPOPT's monotone
            # decrease, 0.2 mu), or free and fixed mode can take turns at one mu for ever
            mu_fixed = max(mu_now, mu) if mu_solved is None else max(min(max(mu_now, mu), 0.2 * mu_solved), mu_floor)
        if trace is not None:
            trace({"mode": "free" if mu_fixed is None else "fixed", "iteration": iteration, "error": error, "mu_now": mu_now, "mu": mu, "delta": delta,
                   "violation": violation, "nu": nu, "alpha_max": alpha_p, "alpha": alpha, "alpha_dual": alpha_d,
                   "max_abs_y": float(np.max(np.abs(y + alpha * dy), initial=0.0))})
        x, s, logs_here = x_t, s_t, logs_t  # the barrier's logs of the new point, for the next phi0
        y = y + alpha * dy
        zl, zu = zl + alpha_d * dzl, zu + alpha_d * dzu
        vl, vu = vl + alpha_d * dvl, vu + alpha_d * dvu
        dl, du, sl, su = slacks(x, s)
        zl = np.where(has_l, np.clip(zl, mu / (_KAPPA_SIGMA * dl), _KAPPA_SIGMA * mu / dl), 0.0)
        zu = np.where(has_u, np.clip(zu, mu / (_KAPPA_SIGMA * du), _KAPPA_SIGMA * mu / du), 0.0)
        vl = np.where(row_l, np.clip(vl, mu / (_KAPPA_SIGMA * sl), _KAPPA_SIGMA * mu / sl), 0.0)
        vu = np.where(row_u, np.clip(vu, mu / (_KAPPA_SIGMA * su), _KAPPA_SIGMA * mu / su), 0.0)
    return NlpResult(x, y, False, "maximum iterations exceeded", max_iter, "banded")


@functools.lru_cache(maxsize=8)
def band_solve_functions(n: int) -> tuple[ca.Function, ca.Function]:
    """The two CasADi solvers of symmetric band systems of one size, built once per size.

    Both analyse the sparsity pattern once, here; at n = 10,000 a solve takes 1.6 and
    0.8 ms, against 1.0 ms for LAPACK's banded Cholesky and solve, without importing
    scipy.linalg, which alone took 0.19 s of a command's 1.1 s.

    Parameters
    ----------
    n : int
        Size of the matrix (the NLP's N+1 variables).

    Returns
    -------
    cholesky, ldl : casadi.Function
        ``(a0, a1, a2, r) -> x`` with A x = r, A symmetric with diagonals a0 (n,), a1 (n-1,)
        and a2 (n-2,) at offsets 0, 1, 2: by CSparse's Cholesky (which raises unless A is
        positive definite) and by CasADi's LDL^T.
    """
    a0, a1, a2, r = (ca.MX.sym(name, max(size, 0)) for name, size in (("a0", n), ("a1", n - 1), ("a2", n - 2),
                                                                     ("r", n)))

    upper = diagonal_matrix(a1, n, n, 1) + diagonal_matrix(a2, n, n, 2)
    matrix = diagonal_matrix(a0, n, n, 0) + upper + upper.T
    return tuple(ca.Function(f"band_{plugin}", [a0, a1, a2, r], [ca.solve(matrix, r, plugin)])
                 for plugin in ("csparsecholesky", "ldl"))


#: Boundaries above which the banded solver factorises with LAPACK (scipy.linalg) rather than
#: CasADi's CSparse: CSparse's Cholesky grows faster than N (1.6 ms at 10,000, 22 ms at
#: 100,000, against LAPACK's 1.0 and 9.5), while importing scipy.linalg costs a fixed 0.19 s,
#: 15 % of a 10,000-segment command. Both are exact Cholesky factorisations of the same
#: matrix; the threshold depends on the size only, so a plan never depends on what else a
#: process has imported.
LAPACK_ABOVE = 30_000


class _BandSolver:
    """Solves with symmetric band matrices of one size n (:func:`band_solve_functions`)."""

    def __init__(self, n: int) -> None:
        self.lapack = n > LAPACK_ABOVE
        if self.lapack:
            import scipy.linalg  # only for long routes (LAPACK_ABOVE)

            self.linalg, self.factor = scipy.linalg, None
        else:
            cholesky, ldl = band_solve_functions(n)
            self.cholesky, self.ldl = _Buffered(cholesky), _Buffered(ldl)

    def solve(self, a0: np.ndarray, a1: np.ndarray, a2: np.ndarray, rhs: np.ndarray, *, definite_only: bool
              ) -> np.ndarray | None:
        """x with A x = rhs (A by its diagonals a0 (n,), a1 (n-1,), a2 (n-2,)).

        ``definite_only``: factorise A by Cholesky, None unless A is positive definite;
        otherwise A is the matrix of the last such call (LAPACK reuses its factor, CasADi
        solves by LDL^T)."""
        if self.lapack:
            if definite_only:
                band = np.zeros((3, a0.size))
                band[2], band[1, 1:], band[0, 2:] = a0, a1, a2
                try:
                    self.factor = self.linalg.cholesky_banded(band, lower=False, check_finite=False)
                except np.linalg.LinAlgError:  # a pivot that is not positive
                    return None
            return self.linalg.cho_solve_banded((self.factor, False), rhs, check_finite=False)
        if not definite_only:
            return self.ldl(a0, a1, a2, rhs)[0]
        try:
            x = self.cholesky(a0, a1, a2, rhs)[0]
        except RuntimeError:  # CSparse found a pivot that is not positive
            return None
        return x if np.all(np.isfinite(x)) else None


class BandedBackend:
    """The banded interior-point method (:func:`solve_banded`) as a back end.

    Its tolerance is :meth:`SolverOptions.backend_tol
    <profileopt.planning.options.SolverOptions.backend_tol>`, its iteration limit IPOPT's
    (``"ipopt.max_iter"`` of
    :attr:`SolverOptions.ipopt <profileopt.planning.options.SolverOptions.ipopt>`).
    """

    name = "banded"

    def solve(self, problem: NlpInstance, options: SolverOptions, timings: dict[str, float]) -> NlpResult:
        """Solve one instance with the banded method (see :class:`~.base.Backend`).

        Parameters
        ----------
        problem : NlpInstance
            The instance.
        options : SolverOptions
            :meth:`~profileopt.planning.options.SolverOptions.backend_tol` and ``"ipopt.max_iter"``.
        timings : dict
            ``build`` and ``solve`` seconds are added here.

        Returns
        -------
        NlpResult
        """
        tol = options.backend_tol()
        max_iter = options.max_iter()
        t = time.perf_counter()
        oracle = cached_banded_oracle(problem.n, problem.with_jerk, problem.families)
        if problem.n + 1 <= LAPACK_ABOVE:
            band_solve_functions(problem.n + 1)  # the factorisations' analysis belongs to the build
        timings["build"] = timings.get("build", 0.0) + time.perf_counter() - t
        t = time.perf_counter()
        result = solve_banded(oracle, problem.x0, problem.lbx, problem.ubx, problem.lbg, problem.ubg,
                              problem.parameters(), tol=tol, max_iter=max_iter)
        timings["solve"] = timings.get("solve", 0.0) + time.perf_counter() - t
        return result


BACKEND = BandedBackend()
