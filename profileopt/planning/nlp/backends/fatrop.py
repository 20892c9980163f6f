"""FATROP, the structure-exploiting interior-point solver of optimal-control problems, through
``casadi.nlpsol("fatrop")``: an opt-in back end.

FATROP factorises the Newton system stage by stage (a Riccati recursion), so it needs the
NLP written as an optimal-control problem: a state per stage, controls, dynamics that carry
the state to the next stage, and path constraints on one stage's state and controls only.
The planner's NLP (:func:`profileopt.planning.nlp.problem.build_nlp`, variables y = b / b_ref
at the boundaries) is rewritten here in that *stage form*, with the same formulas:

* stage k = boundary k, state x_k = (y_k, p_k) (x_0 = y_0), control u_k = w_k, the
  acceleration of segment k over a_ref; the dynamics are the kinematics of a segment,
  y_{k+1} = y_k + 2 ds_k a_k / b_ref, with w_k carried to the next stage as its copy
  p_{k+1}, so that the jerk at boundary k+1 sees it;
* path constraints of stage k: the jerk row at boundary k (v_k (a_k - a_{k-1}) / dsm_k / J)
  and the row families of segment k, its far end's speed from the dynamics;
* the acceleration rows a_k / a_ref of :func:`~profileopt.planning.nlp.problem.row_bounds`
  become bounds on u_k;
* the objective: each segment's travel time and each boundary's smoothing term.

This is the same problem (at a feasible point b_{k+1} = b_k + 2 ds_k a_k exactly), so the
back end answers in the terms of the other back ends: y, and the row multipliers in the
order of ``row_bounds`` (the acceleration rows' multipliers are the bounds' on u).

CasADi 3.8's FATROP interface takes time growing faster than N to set a problem up, and at
every iteration (measured: a 4,000-segment NLP took 5.5 s to build, 23,633 segments 214 s),
so a route is solved in exact pieces of at most
:data:`~profileopt.planning.options.FATROP_PIECE_SEGMENTS` segments
(:mod:`profileopt.planning.nlp.pieces`); see the docs' solver page for the measurements.
"""

from __future__ import annotations

import functools
import time

import casadi as ca
import numpy as np

from ....core.kinematics import boundary_jerk_mps3, jerk_squared_time, segment_time_s
from ....physics.rows import ROW_FAMILIES
from ...options import FATROP_MAX_SEGMENTS, SolverOptions
from ..problem import PARAMETERS, NlpResult, speed_mps
from .base import NlpInstance

#: How far FATROP relaxes a bound, relative to max(1, |bound|) (measured: answers up to
#: 9.96e-9 above an upper bound of about 0.5).
BOUND_RELAX = 1e-8

__all__ = ["BACKEND", "BOUND_RELAX", "FatropBackend", "build_stage_nlp", "cached_stage_nlp",
           "StageInstance"]



def _family_count(families: tuple[str, ...]) -> tuple[int, int]:
    """(rows, data columns) of the row families together."""
    return (sum(ROW_FAMILIES[f].count for f in families), sum(len(ROW_FAMILIES[f].data) for f in families))


def build_stage_nlp(n: int, with_jerk: bool, families: tuple[str, ...], fatrop_options: dict) -> ca.Function:
    """FATROP's solver of the planner's NLP for N = n segments, in stage form.

    Parameters
    ----------
    n : int
        Number of segments N >= 1.
    with_jerk : bool
        Whether stages 1..N-1 hold a jerk row (only when N >= 2).
    families : tuple of str
        Row families (:data:`~profileopt.physics.rows.ROW_FAMILIES`), in this order.
    fatrop_options : dict
        Options of FATROP itself (``tol``, ``max_iter``, ...).

    Returns
    -------
    casadi.Function
        ``casadi.nlpsol(..., "fatrop")`` with variables, shape (3N + 1,), [y_0, w_0, then
        (y_k, p_k, w_k) for k = 1..N-1, then (y_N, p_N)]: the state x_k = (y_k, p_k) holds
        the copy p_k of w_{k-1}, and u_k = w_k. The parameters p are those of
        :func:`~profileopt.planning.nlp.problem.build_nlp`
        (:meth:`~.base.NlpInstance.parameters`). Rows, stage after stage: the two dynamics
        rows carrying x_k, u_k to x_{k+1} (= 0), then stage k's path rows: its jerk row
        (1 <= k <= N-1) and the family rows of segment k.
    """
    n = int(n)
    if n < 1:
        raise ValueError(f"the NLP needs at least one segment, got n = {n}")
    jerk = bool(with_jerk) and n >= 2
    n_rows, n_data = _family_count(families)
    q = ca.SX.sym("q", len(PARAMETERS))
    b_ref, l_ref, a_ref, t_ref, weight, inv_jerk = (q[k] for k in range(len(PARAMETERS)))
    y, w_prev, w, ds, ds_prev = (ca.SX.sym(name) for name in ("y", "w_prev", "w", "ds", "ds_prev"))
    d = ca.SX.sym("d", n_data)
    b0, accel, length = b_ref * y, a_ref * w, l_ref * ds
    b1 = b0 + 2.0 * length * accel  # segment k's far end, by the dynamics
    # The speeds are taken at max(b, 0), the same at every point the problem allows: FATROP
    # keeps a fixed variable (a standstill at either end) only within a few 1e-9 of its value,
    # and b1 is below 0 where an iterate's dynamics do not yet hold.
    v0, v1 = speed_mps(ca.fmax(b0, 0.0)), speed_mps(ca.fmax(b1, 0.0))
    travel = segment_time_s(v0, v1, length) / t_ref
    family_rows, start = [], 0
    for family in families:
        width = len(ROW_FAMILIES[family].data)
        family_rows += ROW_FAMILIES[family].rows((v0, v1), accel, [d[start + k] for k in range(width)])
        start += width
    dynamics = ca.vertcat(b1 / b_ref, w)  # x_{k+1} from x_k, u_k
    first = ca.Function("stage0", [y, w, ds, d, q], [travel, dynamics, ca.vertcat(*family_rows)])
    accel_prev, length_prev = a_ref * w_prev, l_ref * ds_prev
    smooth = weight * jerk_squared_time(v0, accel_prev, accel, length_prev, length) / t_ref
    path = ([boundary_jerk_mps3(v0, accel_prev, accel, length_prev, length) * inv_jerk] if jerk else []) + family_rows
    inner = ca.Function("stage", [y, w_prev, w, ds, ds_prev, d, q], [travel + smooth, dynamics, ca.vertcat(*path)])

    nw = 3 * n + 1
    W = ca.MX.sym("w", nw)
    P = ca.MX.sym("p", n + n * n_data + len(PARAMETERS))
    Q = P[n + n * n_data:]
    lengths = P[:n]
    data = ca.reshape(P[n:n + n * n_data], n, n_data).T if n_data else ca.MX(0, n)  # column k: segment k
    x_last = W[nw - 2:nw]
    f, next0, rows0 = first(W[0], W[1], lengths[0], data[:, 0], Q)
    if n > 1:
        middle = ca.reshape(W[2:2 + 3 * (n - 1)], 3, n - 1)  # columns (y_k, p_k, w_k), k = 1..N-1
        fk, nextk, rowsk = inner.map(n - 1)(middle[0, :], middle[1, :], middle[2, :], lengths[1:].T,
                                             lengths[:-1].T, data[:, 1:], Q)
        states = ca.horzcat(middle[:2, :], x_last)  # x_1 .. x_N
        g = ca.vertcat(states[:, 0] - next0, rows0, ca.reshape(ca.vertcat(states[:, 1:] - nextk, rowsk), -1, 1))
        f = f + ca.sum2(fk)
    else:
        g = ca.vertcat(x_last - next0, rows0)
    path_rows = (1 if jerk else 0) + n_rows
    options = {
        "expand": True, "print_time": False,
        "structure_detection": "manual", "N": n, "nx": [1] + [2] * n, "nu": [1] * n + [0],
        "ng": [n_rows] + [path_rows] * (n - 1) + [0],
        "fatrop": dict(fatrop_options),
    }
    name = f"profileopt_stage_n{n}_{'jerk' if jerk else 'nojerk'}" + "".join(f"_{f}" for f in families)
    return ca.nlpsol(name, "fatrop", {"x": W, "p": P, "f": f, "g": g}, options)


@functools.lru_cache(maxsize=4)
def cached_stage_nlp(n: int, with_jerk: bool, families: tuple[str, ...], options_key: tuple) -> ca.Function:
    """:func:`build_stage_nlp`, built once per size, rows and options and cached.

    Parameters
    ----------
    n : int
        Number of segments.
    with_jerk : bool
        Whether the NLP has jerk rows.
    families : tuple of str
        Row families.
    options_key : tuple of (str, object)
        FATROP's options, sorted.

    Returns
    -------
    casadi.Function
    """
    return build_stage_nlp(n, with_jerk, families, dict(options_key))


class StageInstance:
    """An :class:`~.base.NlpInstance` in stage form: the start, bounds and row bounds of
    :func:`build_stage_nlp`'s variables and rows, and the way back.

    Parameters
    ----------
    problem : NlpInstance
        The instance in the planner's terms.
    """

    def __init__(self, problem: NlpInstance) -> None:
        n = problem.n
        self.problem = problem
        self.jerk = problem.jerk_rows
        self.n_rows, _ = _family_count(problem.families)
        b_ref, l_ref, a_ref = (float(problem.p_tail[k]) for k in range(3))
        # w_k of the start: the acceleration the start's squared speeds give each segment
        w0 = (problem.x0[1:] - problem.x0[:-1]) * b_ref / (2.0 * l_ref * problem.length_scaled) / a_ref
        middle = 3 * np.arange(n - 1)
        self.y_index = np.concatenate([[0], 2 + middle, [3 * n - 1]]).astype(int)
        self.w_index = np.concatenate([[1], 4 + middle]).astype(int)
        prev_index = np.concatenate([3 + middle, [3 * n]]).astype(int)  # p_k = w_{k-1}, k = 1..N
        self.x0, self.lbx, self.ubx = (np.empty(3 * n + 1) for _ in range(3))
        for target, y_values, w_values, prev_values in (
                (self.x0, problem.x0, w0, w0),
                (self.lbx, problem.lbx, problem.lbg[:n], np.full(n, -np.inf)),
                (self.ubx, problem.ubx, problem.ubg[:n], np.full(n, np.inf))):
            target[self.y_index] = y_values
            target[self.w_index] = w_values
            target[prev_index] = prev_values
        # FATROP relaxes every bound by 1e-8 max(1, |bound|) (IPOPT's default bound_relax_factor,
        # which it cannot be told to drop): the bounds it is given are moved in by that much, so
        # that its answer keeps the true ones and the planner's clip to them changes nothing
        lower, upper = np.isfinite(self.lbx), np.isfinite(self.ubx)
        size = np.maximum(np.where(lower, np.abs(self.lbx), 0.0), np.where(upper, np.abs(self.ubx), 0.0))
        relax = BOUND_RELAX * np.maximum(1.0, size)
        width = np.where(lower & upper, self.ubx - np.where(lower, self.lbx, 0.0), np.inf)
        movable = width > 4.0 * relax  # a fixed variable (a standstill) stays where it is
        self.lbx[lower & movable] += relax[lower & movable]
        self.ubx[upper & movable] -= relax[upper & movable]
        self.x0 = np.clip(self.x0, self.lbx, self.ubx)
        jerk_count = n - 1 if self.jerk else 0
        jerk_width = 1 if self.jerk else 0
        family_lb = problem.lbg[n + jerk_count:].reshape(self.n_rows, n)
        family_ub = problem.ubg[n + jerk_count:].reshape(self.n_rows, n)
        jerk_lb = problem.lbg[n:n + jerk_count].reshape(jerk_width, n - 1)
        jerk_ub = problem.ubg[n:n + jerk_count].reshape(jerk_width, n - 1)
        zeros = np.zeros((2, n - 1))
        self.lbg = np.concatenate([np.zeros(2), family_lb[:, 0], np.vstack([zeros, jerk_lb, family_lb[:, 1:]]).T.ravel()])
        self.ubg = np.concatenate([np.zeros(2), family_ub[:, 0], np.vstack([zeros, jerk_ub, family_ub[:, 1:]]).T.ravel()])
        # where each of the planner's jerk and family rows sits among the stage rows
        stage_start = 2 + self.n_rows + (2 + jerk_width + self.n_rows) * np.arange(n - 1)  # stages 1..N-1
        self.jerk_rows = stage_start + 2 if self.jerk else np.zeros(0, dtype=int)
        family = np.empty((self.n_rows, n), dtype=int)
        family[:, 0] = 2 + np.arange(self.n_rows)
        family[:, 1:] = stage_start[None, :] + 2 + jerk_width + np.arange(self.n_rows)[:, None]
        self.family_rows = family.ravel()

    def result(self, w: np.ndarray, lam_x: np.ndarray, lam_g: np.ndarray, success: bool, status: str,
               iterations: int) -> NlpResult:
        """The stage solution in the planner's terms (y, and multipliers in ``row_bounds`` order).

        Parameters
        ----------
        w : numpy.ndarray, shape (3N + 1,)
            The stage variables.
        lam_x : numpy.ndarray, shape (3N + 1,)
            Their bound multipliers.
        lam_g : numpy.ndarray
            The stage rows' multipliers.
        success : bool
            Whether FATROP converged.
        status : str
            ``"optimal"`` or why it stopped.
        iterations : int
            FATROP's iterations.

        Returns
        -------
        NlpResult
        """
        lam = np.concatenate([lam_x[self.w_index], lam_g[self.jerk_rows], lam_g[self.family_rows]])
        # a fixed speed (a standstill) comes back within rounding of its value, maybe below 0
        y = np.clip(np.asarray(w)[self.y_index], self.problem.lbx, self.problem.ubx)
        return NlpResult(y, lam, success, status, iterations, "fatrop")


class FatropBackend:
    """FATROP on the stage form of the NLP (see the module docstring).

    Its tolerance is :meth:`SolverOptions.backend_tol
    <profileopt.planning.options.SolverOptions.backend_tol>`, its iteration limit IPOPT's
    (``"ipopt.max_iter"`` of
    :attr:`SolverOptions.ipopt <profileopt.planning.options.SolverOptions.ipopt>`).
    """

    name = "fatrop"

    def solve(self, problem: NlpInstance, options: SolverOptions, timings: dict[str, float]) -> NlpResult:
        """Solve one instance with FATROP (see :class:`~.base.Backend`).

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
        if problem.n > FATROP_MAX_SEGMENTS:  # never the whole of a long route: see FATROP_MAX_SEGMENTS
            return NlpResult(problem.x0.copy(), np.zeros(problem.lbg.size), False,
                             f"{problem.n} segments, more than the {FATROP_MAX_SEGMENTS:,} FATROP is given at once",
                             0, "fatrop")
        tol = options.backend_tol()
        max_iter = options.max_iter()
        fatrop_options = {"tol": tol, "max_iter": max_iter, "print_level": 0}
        t = time.perf_counter()
        solver = cached_stage_nlp(problem.n, problem.jerk_rows, problem.families, tuple(sorted(fatrop_options.items())))
        stage = StageInstance(problem)
        timings["build"] = timings.get("build", 0.0) + time.perf_counter() - t
        t = time.perf_counter()
        out = solver(x0=stage.x0, lbx=stage.lbx, ubx=stage.ubx, lbg=stage.lbg, ubg=stage.ubg, p=problem.parameters())
        timings["solve"] = timings.get("solve", 0.0) + time.perf_counter() - t
        stats = solver.stats()
        success = bool(stats.get("success", False))
        iterations = int(stats.get("iter_count", 0))
        status = ("optimal" if success else f"the iteration limit ({max_iter})" if iterations >= max_iter
                  else f"FATROP's return flag {stats.get('return_status', '?')}")
        return stage.result(np.asarray(out["x"]).ravel(), np.asarray(out["lam_x"]).ravel(),
                            np.asarray(out["lam_g"]).ravel(), success, status, iterations)


BACKEND = FatropBackend()
