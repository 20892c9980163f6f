"""One solve of the planner's NLP, by the back end :attr:`SolverOptions.nlp_solver` names.

:func:`solve_nlp` is the one place that calls a back end
(:mod:`profileopt.planning.nlp.backends`), so the whole-route solve (:mod:`..planner`) and
the pieces of a long route (:mod:`.pieces`) are solved alike. Every back end solves the same
NLP (:mod:`.problem`) from the same start point to the same tolerance. When an opt-in back
end (FATROP, the banded method) stops without converging, IPOPT solves the problem from the
start and its iterations are added; a back end that converged is never solved again.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..options import SolverOptions
from .backends import NlpInstance, get_backend
from .problem import NlpResult

__all__ = ["solve_nlp"]


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
        ``nlp_solver`` (the back end), IPOPT's options, and the tolerance and iteration limit
        every back end uses.
    x0, lbx, ubx : numpy.ndarray, shape (N+1,)
        Start point and bounds of y = b / b_ref.
    length_scaled : numpy.ndarray, shape (N,)
        Segment lengths / L_ref.
    lbg, ubg : numpy.ndarray
        Bounds of the rows (:func:`~.problem.row_bounds`).
    p_tail : numpy.ndarray, shape (6,)
        :meth:`~.problem.Scaling.tail`.
    data : numpy.ndarray, shape (N, D), optional
        The row families' data.
    timings : dict, optional
        ``build`` and ``solve`` seconds are added here.

    Returns
    -------
    NlpResult
        ``solver`` names the back end whose answer it is (``"ipopt"``, ``"fatrop"``,
        ``"banded"``, or ``"ipopt (the <name> solver stopped: <why>)"`` when IPOPT took
        over); ``iterations`` counts both solvers' when both ran.
    """
    timings = {} if timings is None else timings
    for key in ("build", "solve"):
        timings.setdefault(key, 0.0)
    problem = NlpInstance(n, with_jerk, tuple(families), x0, lbx, ubx, length_scaled, lbg, ubg, p_tail, data)
    backend = get_backend(options.nlp_solver)
    result = backend.solve(problem, options, timings)
    if result.success or backend.name == "ipopt":
        return result
    ipopt = get_backend("ipopt").solve(problem, options, timings)
    return dataclasses.replace(ipopt, iterations=ipopt.iterations + result.iterations,
                               solver=f"ipopt (the {backend.name} solver stopped: {result.status})")
