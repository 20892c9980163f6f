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

from ..defaults import LIMIT_RTOL
from ..errors import InputError

__all__ = ["SolverOptions", "DEFAULT_IPOPT_OPTIONS", "NLP_SOLVERS"]

#: The NLP solvers :class:`SolverOptions` can choose (see ``nlp_solver``).
NLP_SOLVERS = ("banded", "ipopt")

#: IPOPT settings of the planner's NLP. ``mumps_mem_percent`` (IPOPT's default 1000) is the
#: extra working space MUMPS allocates, and clears, at every factorisation: 100 % is ample
#: for this banded KKT system (IPOPT doubles it and refactorises if it ever is not) and makes
#: a 10,000-segment solve 10 % faster, with the same iterates and solution. ``mu_oracle``
#: "loqo" (LOQO's centrality rule) instead of the default quality-function search, whose
#: extra linear solves took 60 % of a 10,000-segment solve: 20 % faster at 10,000 and
#: 100,000 segments, objective the same to 1e-10 on the bundled and benchmark routes.
#: ``min_refinement_steps`` 0: iterative refinement of the KKT solves only when IPOPT's
#: residual test asks for it (it still may, up to ``max_refinement_steps``), not always once:
#: 15-20 % faster at 10,000 and 100,000 segments, same objective to 1e-16.
DEFAULT_IPOPT_OPTIONS: Mapping[str, Any] = types.MappingProxyType({
    "ipopt.print_level": 0,
    "ipopt.sb": "yes",
    "print_time": False,
    "ipopt.tol": 1e-10,
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
        (:mod:`profileopt.planning.nlp.pieces`). None: the solver's own threshold
        (:meth:`split_threshold`), 10,000 with ``nlp_solver="ipopt"`` and never with the
        banded solver. IPOPT's time per segment and iteration is flat up to about 10,000
        segments and grows beyond, as its working set leaves the cache; pieces cost more
        iterations in all (each converges on its own). Measured on the benchmark routes
        (2-core machine): whole and pieces equal at 10,000 segments (within noise), pieces
        5 % faster at 15,000, 15 % at 20,000, 30 % at 100,000. The banded solver's time per
        iteration is proportional to N, so pieces only add iterations: at 100,000 segments
        whole took 4.1 s, pieces 6.4 s.
    piece_segments : int, default 4,000
        Most segments in one piece; every piece is solved with the one NLP of this size
        (built once, padded with fixed variables). On the 100,000-segment benchmark route,
        pieces of 3,000 to 6,000 segments took the same time within noise (plan 5.8-6.3 s),
        pieces of 10,000 took 7.2 s.
    cut_rounds : int, default 5
        How many times the cuts that did not check out are replaced before the route is
        solved whole.
    check_rtol : float, default :data:`profileopt.defaults.LIMIT_RTOL` (1e-6)
        Relative tolerance of the independent check of every returned profile: a solution
        that breaks a limit by more is replaced by the fallback profile.
    ipopt : Mapping[str, Any], default :data:`DEFAULT_IPOPT_OPTIONS`
        Options of ``casadi.nlpsol`` for IPOPT (keys as CasADi spells them, ``"ipopt.tol"``).
        The banded solver takes its tolerance and iteration limit from ``"ipopt.tol"`` and
        ``"ipopt.max_iter"`` too.
    nlp_solver : {"banded", "ipopt"}, default "banded"
        Which solver polishes the profile. ``"banded"``: the interior-point method of
        :mod:`profileopt.planning.nlp.banded_ipm`, which factorises the chain-structured Newton
        system in time proportional to N (3-4 times faster than IPOPT at 10,000 segments,
        same optimum), with IPOPT taking over wherever it does not converge; ``"ipopt"``:
        IPOPT only.
    """

    split_above_segments: int | None = None
    piece_segments: int = 4000
    cut_rounds: int = 5
    check_rtol: float = LIMIT_RTOL
    ipopt: Mapping[str, Any] = dataclasses.field(default_factory=lambda: DEFAULT_IPOPT_OPTIONS)
    nlp_solver: str = "banded"

    def __post_init__(self) -> None:
        if self.nlp_solver not in NLP_SOLVERS:
            raise InputError(f"SolverOptions.nlp_solver = {self.nlp_solver!r}: choose one of {', '.join(NLP_SOLVERS)}")
        for name in ("split_above_segments", "piece_segments", "cut_rounds"):
            value = getattr(self, name)
            if name == "split_above_segments" and value is None:
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
            ``split_above_segments``, or when it is None 10,000 for IPOPT and infinity for
            the banded solver.
        """
        if self.split_above_segments is not None:
            return self.split_above_segments
        return 10_000 if self.nlp_solver == "ipopt" else math.inf

    def ipopt_key(self) -> tuple:
        """The IPOPT options as a hashable, ordered key (for caching built solvers).

        Returns
        -------
        tuple of (str, object)
        """
        return tuple(sorted(self.ipopt.items()))
