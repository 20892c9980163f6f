"""One solve of the planner's NLP: the banded interior-point method, IPOPT where it stops.

:func:`solve_nlp` is the one place that chooses the solver (:attr:`SolverOptions.nlp_solver`),
so the whole-route solve (:mod:`.planner`) and the pieces of a long route (:mod:`.pieces`)
are solved alike. The banded solver (:mod:`.banded_ipm`) and IPOPT solve the same NLP
(:mod:`.nlp`) from the same start point to the same tolerance; when the banded solver does
not converge, IPOPT solves the problem from the start and its iterations are added. The NLP
is not convex, so on a short route (:data:`CROSS_CHECK_MAX_SEGMENTS`), or where the banded
optimum crawls (:data:`CRAWL_RATIO`), IPOPT solves it too and the lower optimum is kept.
"""

from __future__ import annotations

import dataclasses
import math
import time

import casadi as ca
import numpy as np

from ..options import DEFAULT_IPOPT_OPTIONS, SolverOptions
from . import banded_ipm
from .banded_ipm import cached_banded_oracle
from .problem import NlpResult, cached_nlp

__all__ = ["solve_nlp", "solve_ipopt", "CROSS_CHECK_MAX_SEGMENTS", "CRAWL_RATIO", "CROSS_CHECK_RTOL"]

#: Routes of up to this many segments are also solved by IPOPT after the banded solver, and
#: the lower optimum is kept. The NLP is not convex (a jerk row is easier to keep at a lower
#: speed, where a segment takes longer), and the two interior-point methods, started alike,
#: can end in different local optima: at 0.5 m segments on krc_rms_1in.csv and curb.csv the
#: banded solver crawled through a rough spot at 0.4 m/s where IPOPT's optimum keeps 5 m/s,
#: 2.9 and 6 % more travel time. On 2,000 segments IPOPT adds about 0.25 s (0.1 s on 400);
#: on the long routes the banded solver is for (10,000 segments and more) no cross-check is
#: made unless the optimum crawls (:data:`CRAWL_RATIO`).
CROSS_CHECK_MAX_SEGMENTS = 2000
#: A longer route is cross-checked too when its banded optimum drives anywhere at less than
#: this fraction of the speed of its start, the exact optimum without jerk rows: the wrong
#: local optima seen crawl (0.00-0.08 of it, also on a 5,000-segment ISO class E route at
#: 0.5 m, 0.7 % slower), while every optimum that equals IPOPT's keeps at least 0.71 of it
#: (7 bundled routes x 2 vehicles x 5, 1 and 0.5 m, and 3 ISO routes of 5,000 segments).
#: Where it is wrong, the check costs an IPOPT solve and changes nothing.
CRAWL_RATIO = 0.3
#: IPOPT's optimum replaces the banded solver's only when lower by more than this, relative
#: (both stop at a tolerance of 1e-10 on the scaled problem; equal optima differ by less).
CROSS_CHECK_RTOL = 1e-6


def solve_nlp(n: int, with_jerk: bool, families: tuple[str, ...], options: SolverOptions, x0: np.ndarray,
              lbx: np.ndarray, ubx: np.ndarray, length_scaled: np.ndarray, lbg: np.ndarray, ubg: np.ndarray,
              p_tail: np.ndarray, data: np.ndarray | None = None, *, timings: dict[str, float] | None = None
              ) -> NlpResult:
    """Solve the planner's NLP for N = n segments, all in scaled units.

    Parameters
    ----------
    n : int
        Number of segments N.
    with_jerk : bool
        Whether the NLP has jerk rows.
    families : tuple of str
        Row families (:data:`~profileopt.physics.rows.ROW_FAMILIES`), in the order of ``data``'s columns.
    options : SolverOptions
        ``nlp_solver``, IPOPT's options, and the tolerance and iteration limit both use.
    x0, lbx, ubx : numpy.ndarray, shape (N+1,)
        Start point and bounds of y = b / b_ref.
    length_scaled : numpy.ndarray, shape (N,)
        Segment lengths / L_ref.
    lbg, ubg : numpy.ndarray
        Bounds of the rows (:func:`~.nlp.row_bounds`).
    p_tail : numpy.ndarray, shape (6,)
        :meth:`~.nlp.Scaling.tail`.
    data : numpy.ndarray, shape (N, D), optional
        The row families' data.
    timings : dict, optional
        ``build`` and ``solve`` seconds are added here.

    Returns
    -------
    NlpResult
        ``solver`` says which solver's answer it is (``"banded"``, ``"ipopt"``,
        ``"ipopt (the banded solver stopped: <why>)"``, or ``"ipopt (an optimum <x> % lower
        than the banded solver's)"`` after a cross-check); ``iterations`` counts both
        solvers' whenever both ran.
    """
    timings = {} if timings is None else timings
    for key in ("build", "solve"):
        timings.setdefault(key, 0.0)
    tol = float(options.ipopt.get("ipopt.tol", DEFAULT_IPOPT_OPTIONS["ipopt.tol"]))
    max_iter = int(options.ipopt.get("ipopt.max_iter", DEFAULT_IPOPT_OPTIONS["ipopt.max_iter"]))
    spent, stopped = 0, ""
    if options.nlp_solver == "banded":
        t = time.perf_counter()
        oracle = cached_banded_oracle(n, with_jerk, families)
        if n + 1 <= banded_ipm.LAPACK_ABOVE:
            banded_ipm.band_solve_functions(n + 1)  # the factorisations' analysis belongs to the build
        timings["build"] += time.perf_counter() - t
        t = time.perf_counter()
        middle = [] if data is None else [np.asarray(data, dtype=float).T.ravel()]
        p = np.concatenate([length_scaled, *middle, p_tail])
        result = banded_ipm.solve_banded(oracle, x0, lbx, ubx, lbg, ubg, p, tol=tol, max_iter=max_iter)
        timings["solve"] += time.perf_counter() - t
        if result.success and n > CROSS_CHECK_MAX_SEGMENTS and _slowest_ratio(x0, result.y) >= CRAWL_RATIO:
            return result
        if result.success:  # a short route, or a crawl: IPOPT's optimum too, and the lower of the two
            banded = result
            ipopt = _ipopt(n, with_jerk, families, options, x0, lbx, ubx, length_scaled, lbg, ubg, p_tail, data,
                           timings)
            iterations = banded.iterations + ipopt.iterations
            if ipopt.success:
                f_banded, f_ipopt = (float(oracle.values(r.y, p)[0]) for r in (banded, ipopt))  # the same f
                if f_ipopt < f_banded - CROSS_CHECK_RTOL * abs(f_banded):
                    return dataclasses.replace(ipopt, iterations=iterations, solver=(
                        f"ipopt (an optimum {100 * (f_banded - f_ipopt) / abs(f_banded):.2g} % lower than the banded solver's)"))
            return dataclasses.replace(banded, iterations=iterations)
        spent, stopped = result.iterations, f" (the banded solver stopped: {result.status})"
    result = _ipopt(n, with_jerk, families, options, x0, lbx, ubx, length_scaled, lbg, ubg, p_tail, data, timings)
    return dataclasses.replace(result, iterations=result.iterations + spent, solver=f"ipopt{stopped}")


def _slowest_ratio(x0: np.ndarray, y: np.ndarray) -> float:
    """The least ratio of the speed of y to that of the start x0 (both b / b_ref, (N+1,)),
    over the boundaries where the start moves (1 where it never does)."""
    moving = x0 > 1e-6 * float(np.max(x0, initial=0.0))
    if not np.any(moving):
        return 1.0
    return math.sqrt(max(float(np.min(y[moving] / x0[moving])), 0.0))


def _ipopt(n: int, with_jerk: bool, families: tuple[str, ...], options: SolverOptions, x0: np.ndarray,
           lbx: np.ndarray, ubx: np.ndarray, length_scaled: np.ndarray, lbg: np.ndarray, ubg: np.ndarray,
           p_tail: np.ndarray, data: np.ndarray | None, timings: dict[str, float]) -> NlpResult:
    """IPOPT from x0 on the cached NLP (:func:`solve_ipopt`), its build and solve timed."""
    t = time.perf_counter()
    solver = cached_nlp(n, with_jerk, options.ipopt_key(), families)
    timings["build"] += time.perf_counter() - t
    t = time.perf_counter()
    extra = () if data is None else (data,)
    result = solve_ipopt(solver, x0, lbx, ubx, length_scaled, lbg, ubg, p_tail, *extra)
    timings["solve"] += time.perf_counter() - t
    return result


def solve_ipopt(solver: ca.Function, x0: np.ndarray, lbx: np.ndarray, ubx: np.ndarray, length_scaled: np.ndarray,
                lbg: np.ndarray, ubg: np.ndarray, p_tail: np.ndarray, data: np.ndarray | None = None) -> NlpResult:
    """One IPOPT solve of a cached NLP, all in scaled units.

    Parameters
    ----------
    solver : casadi.Function
        From :func:`cached_nlp`.
    x0, lbx, ubx : numpy.ndarray, shape (N+1,)
        Start point and bounds of y = b / b_ref.
    length_scaled : numpy.ndarray, shape (N,)
        Segment lengths / L_ref.
    lbg, ubg : numpy.ndarray
        Bounds of the rows (:func:`row_bounds`).
    p_tail : numpy.ndarray, shape (6,)
        :meth:`Scaling.tail`.
    data : numpy.ndarray, shape (N, D), optional
        The row families' data, columns in the order the NLP was built with.

    Returns
    -------
    NlpResult
    """
    middle = [] if data is None else [np.asarray(data, dtype=float).T.ravel()]
    result = solver(x0=x0, lbx=lbx, ubx=ubx, lbg=lbg, ubg=ubg, p=np.concatenate([length_scaled, *middle, p_tail]))
    stats = solver.stats()
    success = bool(stats.get("success", False)) or _converged_but_stalled(stats)
    status = "optimal" if success else str(stats.get("return_status", "failed"))
    return NlpResult(np.asarray(result["x"]).ravel(), np.asarray(result["lam_g"]).ravel(), success, status,
                       int(stats.get("iter_count", 0)))


#: IPOPT's ``acceptable_tol`` in the planner's options: a final iterate whose scaled dual and
#: primal infeasibility and barrier parameter are all below it is a solution.
STALL_ACCEPTABLE_TOL = 1e-7


def _converged_but_stalled(stats: dict) -> bool:
    """IPOPT stopped with "Search_Direction_Becomes_Too_Small" at a solution: the last
    iterate's scaled dual and primal infeasibility and barrier parameter are all within
    :data:`STALL_ACCEPTABLE_TOL`. It happens when the dual infeasibility rounds at a few
    1e-10, just above ``tol``, for the last dozen steps of 1e-15 (a refined route with
    0.1 m and 5 m segments side by side); before, such a plan fell back to a crawl (138 s
    for 9.1 s). The planner still checks the solution against every limit itself."""
    if stats.get("return_status") != "Search_Direction_Becomes_Too_Small":
        return False
    iterations = stats.get("iterations") or {}
    last = [iterations.get(key) for key in ("inf_du", "inf_pr", "mu")]
    return all(values is not None and len(values) and float(values[-1]) <= STALL_ACCEPTABLE_TOL for values in last)
