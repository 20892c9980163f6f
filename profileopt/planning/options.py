"""The solver's tuning values: how the planner's NLP is split and how IPOPT is set.

None of these changes which profile is optimal; they change how fast it is found. They are
collected here, in one frozen dataclass passed to :func:`profileopt.plan`, rather than kept
as module globals, so that a test or a benchmark can change one for one call.
"""

from __future__ import annotations

import dataclasses
import math
import types
from typing import Any, Mapping

from ..defaults import LIMIT_RTOL, PLAN_SOLVERS
from ..errors import InputError

__all__ = ["SolverOptions", "DEFAULT_IPOPT_OPTIONS", "NLP_SOLVERS", "FATROP_PIECE_SEGMENTS", "FATROP_MAX_SEGMENTS",
           "BACKEND_TOL"]

#: Least tolerance of FATROP and the banded method: their optimality test at
#: max(``"ipopt.tol"``, BACKEND_TOL).
BACKEND_TOL = 1e-10

#: The NLP solvers :class:`SolverOptions` can choose (see ``nlp_solver``), the default first:
#: the back ends of :mod:`profileopt.planning.nlp.backends`.
NLP_SOLVERS = PLAN_SOLVERS

#: Most segments FATROP solves at once (its CasADi interface takes time growing faster than
#: N to set a problem up and at every iteration: 0.6 s to build 1,000 segments, 5.5 s 4,000,
#: 214 s 23,633); a longer route is solved in exact pieces of this size, chosen so that one
#: piece's set-up stays well under a second. Not tuned further (see the docs' solver page).
FATROP_PIECE_SEGMENTS = 500
#: Most segments FATROP is given at all: where a long route's pieces do not check out, the
#: planner solves it whole, which would take CasADi's FATROP interface minutes to set up;
#: the FATROP back end hands such a problem to IPOPT instead (with a note).
FATROP_MAX_SEGMENTS = 4000

#: IPOPT settings of the planner's NLP. ``mumps_mem_percent`` (IPOPT's default 1000) is the
#: extra working space MUMPS allocates, and clears, at every factorisation: 100 % is ample
#: for this banded KKT system (IPOPT doubles it and refactorises if it ever is not) and makes
#: a 10,000-segment solve 10 % faster, with the same iterates and solution. ``mu_oracle``
#: "loqo" (LOQO's centrality rule) instead of the default quality-function search, whose
#: extra linear solves took 60 % of a 10,000-segment solve: 20 % faster at 10,000 and
#: 100,000 segments, objective the same to 1e-10 on the bundled and benchmark routes.
#: ``tol`` 1e-13: IPOPT's test bounds each complementarity, not their sum, so at 1e-10 it
#: stopped with the objective up to 2.3e-7 above the optimum on the 10,000-segment benchmark
#: route (tens of thousands of bounds' small gaps add up); at 1e-13 within 1.2e-9 of the
#: duality-gap-closed optimum, in 46 iterations instead of 40 (1,000 segments: 36 and 33).
#: ``min_refinement_steps`` 0: iterative refinement of the KKT solves only when IPOPT's
#: residual test asks for it (it still may, up to ``max_refinement_steps``), not always once:
#: 15-20 % faster at 10,000 and 100,000 segments, same objective to 1e-16.
DEFAULT_IPOPT_OPTIONS: Mapping[str, Any] = types.MappingProxyType({
    "ipopt.print_level": 0,
    "ipopt.sb": "yes",
    "print_time": False,
    "ipopt.tol": 1e-13,
    "ipopt.acceptable_tol": 1e-7,
    "ipopt.max_iter": 300,
    "ipopt.mu_strategy": "adaptive",
    "ipopt.bound_relax_factor": 0.0,
    "ipopt.mumps_mem_percent": 100,
    "ipopt.mu_oracle": "loqo",
    "ipopt.min_refinement_steps": 0,
})


@dataclasses.dataclass(frozen=True)
class SolverOptions:
    """How the planner solves its NLP (not what it solves).

    Attributes
    ----------
    split_above_segments : int or None, default None
        A route of more segments than this is solved in exact pieces
        (:mod:`profileopt.planning.nlp.pieces`). None: the back end's own threshold
        (:meth:`split_threshold`): never for IPOPT and the banded method, whose time per
        segment hardly grows with N and whose iterations pieces only add to (IPOPT whole took
        42 iterations on the 100,000-segment jerk-limited benchmark route, refined to
        233,423 segments; its pieces' cuts did not check out there, and the whole route was
        solved after five rounds of them, 4 times as long), and :data:`FATROP_PIECE_SEGMENTS`
        for FATROP, whose CasADi interface takes time growing faster than N.
    piece_segments : int or None, default None
        Most segments in one piece; every piece is solved with the one NLP of this size
        (built once, padded with fixed variables). None: 4,000 (with IPOPT on the
        100,000-segment benchmark route, pieces of 3,000 to 6,000 segments took the same time
        within noise, pieces of 10,000 longer), or :data:`FATROP_PIECE_SEGMENTS` for FATROP.
    cut_rounds : int, default 5
        How many times the cuts that did not check out are replaced before the route is
        solved whole.
    check_rtol : float, default :data:`profileopt.defaults.LIMIT_RTOL` (1e-6)
        Relative tolerance of the independent check of every returned profile: a solution
        that breaks a limit by more is replaced by the fallback profile.
    ipopt : Mapping[str, Any], default :data:`DEFAULT_IPOPT_OPTIONS`
        Options of ``casadi.nlpsol`` for IPOPT (keys as CasADi spells them, ``"ipopt.tol"``).
        FATROP and the banded method take their iteration limit from ``"ipopt.max_iter"``
        and their tolerance from ``"ipopt.tol"`` or :data:`BACKEND_TOL`, whichever is
        larger (the banded method's test bounds the duality gap itself). An option IPOPT
        does not know, a value out of its range, or one its build cannot honour (HSL's
        solvers, which CasADi's IPOPT lacks) is an :class:`~profileopt.errors.InputError`
        when the plan solves.
    nlp_solver : {"ipopt", "fatrop", "banded"}, default "ipopt"
        The back end that solves the NLP (:mod:`profileopt.planning.nlp.backends`):
        ``"ipopt"``, IPOPT with MUMPS; ``"fatrop"``, FATROP on the NLP's stage form;
        ``"banded"``, the interior-point method written here, which factorises the
        chain-structured Newton system in time proportional to N (more than twice as fast as
        IPOPT on the benchmark's long routes). IPOPT takes over wherever FATROP or the banded
        method stops without converging.
    """

    split_above_segments: int | None = None
    piece_segments: int | None = None
    cut_rounds: int = 5
    check_rtol: float = LIMIT_RTOL
    ipopt: Mapping[str, Any] = dataclasses.field(default_factory=lambda: DEFAULT_IPOPT_OPTIONS)
    nlp_solver: str = "ipopt"

    def __post_init__(self) -> None:
        if self.nlp_solver not in NLP_SOLVERS:
            raise InputError(f"SolverOptions.nlp_solver = {self.nlp_solver!r}: choose one of {', '.join(NLP_SOLVERS)}")
        for name in ("split_above_segments", "piece_segments", "cut_rounds"):
            value = getattr(self, name)
            if name in ("split_above_segments", "piece_segments") and value is None:
                continue
            if isinstance(value, bool) or not isinstance(value, int) or value < (0 if name == "cut_rounds" else 1):
                raise InputError(f"SolverOptions.{name} = {value!r}: must be a whole number >= "
                                 f"{0 if name == 'cut_rounds' else 1}")
        if not (math.isfinite(self.check_rtol) and self.check_rtol > 0):
            raise InputError(f"SolverOptions.check_rtol = {self.check_rtol!r}: must be a finite number > 0")
        object.__setattr__(self, "ipopt", types.MappingProxyType(dict(self.ipopt)))

    def split_threshold(self) -> int | float:
        """Segments above which a route is solved in pieces (see ``split_above_segments``).

        Returns
        -------
        int or float
            ``split_above_segments``, or when it is None :data:`FATROP_PIECE_SEGMENTS` for
            FATROP and infinity for the other back ends.
        """
        if self.split_above_segments is not None:
            return self.split_above_segments
        return FATROP_PIECE_SEGMENTS if self.nlp_solver == "fatrop" else math.inf

    def piece_size(self) -> int:
        """Most segments in one piece (see ``piece_segments``).

        Returns
        -------
        int
            ``piece_segments``, or when it is None :data:`FATROP_PIECE_SEGMENTS` for FATROP
            and 4,000 for the other back ends.
        """
        if self.piece_segments is not None:
            return self.piece_segments
        return FATROP_PIECE_SEGMENTS if self.nlp_solver == "fatrop" else 4000

    def backend_tol(self) -> float:
        """The tolerance of FATROP and the banded method: max(``"ipopt.tol"``, :data:`BACKEND_TOL`).

        Returns
        -------
        float
        """
        return max(float(self.ipopt.get("ipopt.tol", DEFAULT_IPOPT_OPTIONS["ipopt.tol"])), BACKEND_TOL)

    def max_iter(self) -> int:
        """The iteration limit of every back end: ``"ipopt.max_iter"`` of ``ipopt``.

        Returns
        -------
        int
        """
        return int(self.ipopt.get("ipopt.max_iter", DEFAULT_IPOPT_OPTIONS["ipopt.max_iter"]))

    def ipopt_key(self) -> tuple:
        """The IPOPT options as a hashable, ordered key (for caching built solvers).

        Returns
        -------
        tuple of (str, object)
        """
        return tuple(sorted(self.ipopt.items()))
