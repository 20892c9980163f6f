"""What every solver back end is given and what it returns.

The planner's NLP (:func:`profileopt.planning.nlp.problem.build_nlp`) is handed to a back end
as one :class:`NlpInstance`: its size, its rows and the numbers of one solve, all in the
scaled units the NLP is written in (y = b / b_ref). A back end (:class:`Backend`) solves it
and answers with a :class:`~profileopt.planning.nlp.problem.NlpResult` in the same terms, its
row multipliers in the order of :func:`~profileopt.planning.nlp.problem.row_bounds`, however
it wrote the problem for its solver. So the planner, the pieces of a long route and the
tests treat every back end alike.
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING, Protocol

import numpy as np

if TYPE_CHECKING:
    from ...options import SolverOptions
    from ..problem import NlpResult

__all__ = ["NlpInstance", "Backend"]


@dataclasses.dataclass(frozen=True)
class NlpInstance:
    """One solve of the planner's NLP, in scaled units.

    Attributes
    ----------
    n : int
        Number of segments N.
    with_jerk : bool
        Whether the NLP has jerk rows (only when N >= 2).
    families : tuple of str
        Row families (:data:`~profileopt.physics.rows.ROW_FAMILIES`), in the order of ``data``'s columns.
    x0, lbx, ubx : numpy.ndarray, shape (N+1,)
        Start point and bounds of y = b / b_ref (-).
    length_scaled : numpy.ndarray, shape (N,)
        Segment lengths / L_ref (-).
    lbg, ubg : numpy.ndarray, shape (R,)
        Bounds of the rows (:func:`~profileopt.planning.nlp.problem.row_bounds`).
    p_tail : numpy.ndarray, shape (6,)
        :meth:`~profileopt.planning.nlp.problem.Scaling.tail`.
    data : numpy.ndarray, shape (N, D), or None
        The row families' data.
    """

    n: int
    with_jerk: bool
    families: tuple[str, ...]
    x0: np.ndarray
    lbx: np.ndarray
    ubx: np.ndarray
    length_scaled: np.ndarray
    lbg: np.ndarray
    ubg: np.ndarray
    p_tail: np.ndarray
    data: np.ndarray | None = None

    @property
    def jerk_rows(self) -> bool:
        """Whether the NLP holds jerk rows (a bound, and N >= 2)."""
        return bool(self.with_jerk) and self.n >= 2

    def parameters(self) -> np.ndarray:
        """The NLP's parameter vector p: lengths, the families' data column after column, the tail.

        Returns
        -------
        numpy.ndarray, shape (N + N D + 6,)
        """
        middle = [] if self.data is None else [np.asarray(self.data, dtype=float).T.ravel()]
        return np.concatenate([self.length_scaled, *middle, self.p_tail])


class Backend(Protocol):
    """A solver back end: one module of :mod:`profileopt.planning.nlp.backends` each.

    Attributes
    ----------
    name : str
        What ``SolverOptions.nlp_solver`` and ``profileopt plan --solver`` call it.
    """

    name: str

    def solve(self, problem: NlpInstance, options: "SolverOptions", timings: dict[str, float]) -> "NlpResult":
        """Solve one instance of the NLP.

        Parameters
        ----------
        problem : NlpInstance
            The instance.
        options : SolverOptions
            Tolerance, iteration limit and the solver's own options.
        timings : dict
            ``build`` and ``solve`` seconds are added here.

        Returns
        -------
        NlpResult
            ``solver`` is the back end's name; ``lam_g`` in the order of ``row_bounds``.
        """
        ...
