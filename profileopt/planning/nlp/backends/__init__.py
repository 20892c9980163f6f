"""The NLP's solver back ends, one module each, behind one interface (:class:`~.base.Backend`).

- :mod:`~profileopt.planning.nlp.backends.ipopt`: IPOPT with MUMPS, the default;
- :mod:`~profileopt.planning.nlp.backends.fatrop`: FATROP on the NLP's stage form (opt-in);
- :mod:`~profileopt.planning.nlp.backends.banded`: the banded interior-point method written
  here (opt-in: more than twice as fast as IPOPT on long routes).

``SolverOptions(nlp_solver=NAME)`` and ``profileopt plan --solver NAME`` choose one;
:func:`profileopt.planning.nlp.solve.solve_nlp` is where it is called.
"""

from __future__ import annotations

from . import banded, fatrop, ipopt
from .base import Backend, NlpInstance

__all__ = ["BACKENDS", "Backend", "NlpInstance", "get_backend"]

#: Every back end by name, the default first.
BACKENDS: dict[str, Backend] = {b.name: b for b in (ipopt.BACKEND, fatrop.BACKEND, banded.BACKEND)}


def get_backend(name: str) -> Backend:
    """The back end called ``name``.

    Parameters
    ----------
    name : str
        A key of :data:`BACKENDS`.

    Returns
    -------
    Backend
    """
    return BACKENDS[name]
