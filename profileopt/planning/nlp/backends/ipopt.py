"""IPOPT (with MUMPS), through ``casadi.nlpsol``: the default back end.

The NLP is the one :func:`profileopt.planning.nlp.problem.build_nlp` writes, built once per
size and row families (:func:`~profileopt.planning.nlp.problem.cached_nlp`) and re-solved
with parameters. Options are :attr:`SolverOptions.ipopt
<profileopt.planning.options.SolverOptions.ipopt>`.
"""

from __future__ import annotations

import ctypes
import functools
import os
import re
import time
from pathlib import Path

import casadi as ca
import numpy as np

from ....errors import InputError
from ...options import SolverOptions
from ..problem import NlpResult, cached_nlp
from .base import NlpInstance

__all__ = ["BACKEND", "IpoptBackend", "solve_ipopt", "boundary_scales", "one_blas_thread", "STALL_ACCEPTABLE_TOL",
           "MIN_BOUNDARY_SCALE"]

#: The least scale of a boundary's variable (:func:`boundary_scales`), relative to b_ref.
MIN_BOUNDARY_SCALE = 1e-6

#: IPOPT's ``acceptable_tol`` in the planner's options: a final iterate whose scaled dual and
#: primal infeasibility and barrier parameter are all below it is a solution.
STALL_ACCEPTABLE_TOL = 1e-7


class IpoptBackend:
    """IPOPT on the NLP of :func:`~profileopt.planning.nlp.problem.build_nlp`."""

    name = "ipopt"

    def solve(self, problem: NlpInstance, options: SolverOptions, timings: dict[str, float]) -> NlpResult:
        """Solve one instance with IPOPT (see :class:`~.base.Backend`).

        Parameters
        ----------
        problem : NlpInstance
            The instance.
        options : SolverOptions
            ``ipopt``: IPOPT's options.
        timings : dict
            ``build`` and ``solve`` seconds are added here.

        Returns
        -------
        NlpResult
        """
        t = time.perf_counter()
        try:
            solver = cached_nlp(problem.n, problem.with_jerk, options.ipopt_key(), problem.families, scaled=True)
        except RuntimeError as exc:  # IPOPT checks its options when the solver is made
            text = str(exc)
            unknown = re.search(r"No such IPOPT option: (\S+)", text)
            if unknown:
                raise InputError(f"SolverOptions.ipopt: IPOPT has no option {unknown.group(1)!r}; check its "
                                 "spelling against IPOPT's list of options") from None
            if "Invalid options were detected" in text:
                raise InputError("SolverOptions.ipopt: IPOPT refused a value of its options as out of range "
                                 "(it printed which, and the range, above)") from None
            raise
        one_blas_thread()  # once IPOPT's plugin, and with it CasADi's OpenBLAS, is loaded
        timings["build"] = timings.get("build", 0.0) + time.perf_counter() - t
        t = time.perf_counter()
        result = solve_ipopt(solver, problem)
        timings["solve"] = timings.get("solve", 0.0) + time.perf_counter() - t
        return result


BACKEND = IpoptBackend()


def boundary_scales(problem: NlpInstance) -> np.ndarray:
    """A scale per boundary for IPOPT's variables x_j = y_j / sigma_j: each boundary's own
    upper bound on y (its cap squared over b_ref), at least :data:`MIN_BOUNDARY_SCALE`.

    With one scale for the route (y = b / b_ref) a crawl's boundaries sit at y ~ 2e-4 beside
    1 elsewhere, and IPOPT's barrier steps there are cut to 1e-2-1e-4 by the fraction to the
    boundary for a hundred iterations (189 on the trail with the resonant atv on the first
    band, docs' solver page); with its own scale every variable lies in [0, 1].

    Parameters
    ----------
    problem : NlpInstance
        The instance.

    Returns
    -------
    numpy.ndarray, shape (N+1,)
    """
    upper = np.asarray(problem.ubx, dtype=float)
    return np.where(np.isfinite(upper), np.clip(upper, MIN_BOUNDARY_SCALE, None), 1.0)


def solve_ipopt(solver: ca.Function, problem: NlpInstance) -> NlpResult:
    """One IPOPT solve of a cached NLP built with a scale per boundary
    (:func:`boundary_scales`); the result in the instance's scaled units (y = b / b_ref).

    Parameters
    ----------
    solver : casadi.Function
        From :func:`~profileopt.planning.nlp.problem.cached_nlp` with ``scaled=True``, of the
        instance's size and rows.
    problem : NlpInstance
        The instance.

    Returns
    -------
    NlpResult
    """
    sigma = boundary_scales(problem)
    result = solver(x0=problem.x0 / sigma, lbx=problem.lbx / sigma, ubx=problem.ubx / sigma, lbg=problem.lbg,
                    ubg=problem.ubg, p=np.concatenate([problem.parameters(), sigma]))
    stats = solver.stats()
    if stats.get("return_status") == "Invalid_Option":  # valid by name and range, not in this build
        raise InputError("SolverOptions.ipopt: IPOPT stopped at once with Invalid_Option: an option this build "
                         "of IPOPT cannot honour (CasADi's has no HSL, so no ma27/ma57 linear solvers and no "
                         "nlp_scaling_method equilibration-based); leave it out")
    success = bool(stats.get("success", False)) or _converged_but_stalled(stats)
    status = "optimal" if success else str(stats.get("return_status", "failed"))
    return NlpResult(sigma * np.asarray(result["x"]).ravel(), np.asarray(result["lam_g"]).ravel(), success, status,
                     int(stats.get("iter_count", 0)), "ipopt")


@functools.cache
def one_blas_thread() -> None:
    """IPOPT's linear solver on one thread, unless the environment chose (once per process).

    CasADi's IPOPT factorises with MUMPS on CasADi's own OpenBLAS (``libcasadi-tp-openblas``),
    which runs a thread per core. On the planner's banded systems the extra threads only spin:
    a 3 km plan in process took 1.54 s of wall time on two threads and 1.60 s on one, but 2.58 s
    of CPU time against 1.60 s, a core taken from whatever else runs (another plan, a batch's
    other worker, a controller). The command line sets ``OPENBLAS_NUM_THREADS=1`` before
    anything is loaded; this does the same for a Python program, through OpenBLAS's
    ``openblas_set_num_threads``, once the library is loaded. ``OPENBLAS_NUM_THREADS`` or
    ``OMP_NUM_THREADS`` in the environment is left to rule; a CasADi without that library (or
    a platform without ``RTLD_NOLOAD``) is left as it is.
    """
    if os.environ.get("OPENBLAS_NUM_THREADS") or os.environ.get("OMP_NUM_THREADS"):
        return
    no_load = getattr(os, "RTLD_NOLOAD", None)
    if no_load is None:
        return
    for path in sorted(Path(ca.__file__).parent.glob("libcasadi-tp-openblas*")):
        try:
            library = ctypes.CDLL(str(path), mode=no_load | os.RTLD_LAZY)  # only if already loaded
            library.openblas_set_num_threads(1)
        except (OSError, AttributeError):
            continue
        return


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
