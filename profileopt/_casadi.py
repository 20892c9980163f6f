"""One expression, every kind of argument.

The physics (:mod:`profileopt.terrain`, :mod:`profileopt.forces`) is written once, as
functions that build CasADi expressions. :func:`elementwise` turns such a builder into a
public function that

* returns the expression itself for ``casadi.SX`` or ``casadi.MX`` arguments (so users can
  embed it in their own problems and get exact derivatives), and
* evaluates that same expression, through a cached ``casadi.Function`` mapped over the
  elements, for plain numbers, numpy arrays (broadcast against each other) and
  ``casadi.DM``.

There is therefore no second, hand-written numpy copy of any formula.
"""

from __future__ import annotations

import functools
import inspect
from typing import Any, Callable

import casadi as ca
import numpy as np

__all__ = ["elementwise", "is_symbolic", "scalar_function"]


def is_symbolic(*args: Any) -> bool:
    """True if any argument is a CasADi symbolic matrix (``SX`` or ``MX``)."""
    return any(isinstance(a, (ca.SX, ca.MX)) for a in args)


@functools.lru_cache(maxsize=256)
def scalar_function(builder: Callable, n_inputs: int, constants: Any, name: str) -> ca.Function:
    """The ``casadi.Function`` of ``builder`` on ``n_inputs`` scalar SX symbols.

    ``constants`` (a hashable object such as a frozen :class:`~profileopt.vehicle.Vehicle`)
    is passed through unchanged and so folded into the function as numbers.
    """
    xs = [ca.SX.sym(f"x{i}") for i in range(n_inputs)]
    return ca.Function(name, xs, [builder(*xs, constants)])


def _evaluate(fun: ca.Function, args: tuple) -> Any:
    if any(isinstance(a, ca.DM) for a in args):
        shapes = {ca.DM(a).shape for a in args if isinstance(a, ca.DM) and ca.DM(a).numel() != 1}
        shape = shapes.pop() if len(shapes) == 1 else (1, 1)
        flat = [np.broadcast_to(np.asarray(ca.DM(a)).ravel(order="F") if ca.DM(a).numel() != 1
                                else float(a), (int(np.prod(shape)),)) for a in args]
        out = np.asarray(fun(*[f[None, :] for f in flat])).ravel()
        return ca.DM(out.reshape(shape, order="F"))
    arrays = np.broadcast_arrays(*[np.asarray(a, dtype=float) for a in args])
    shape = arrays[0].shape
    if arrays[0].size == 0:
        return np.zeros(shape)
    out = np.asarray(fun(*[a.ravel()[None, :] for a in arrays])).reshape(shape)
    if shape == ():
        return float(out)
    return out


def elementwise(builder: Callable) -> Callable:
    """Decorate an expression builder ``builder(x1, ..., xn, vehicle)``.

    The decorated function accepts numbers, numpy arrays, ``casadi.DM``, ``casadi.SX`` or
    ``casadi.MX`` for ``x1 ... xn`` and returns a result of the same kind. ``vehicle`` (or
    whatever hashable constants object the builder takes last) is folded in as numbers.
    The symbolic builder itself stays available as ``.symbolic``.
    """
    signature = inspect.signature(builder)
    names = list(signature.parameters)
    n_inputs = len(names) - 1

    @functools.wraps(builder)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        bound = signature.bind(*args, **kwargs)
        values = [bound.arguments[n] for n in names]
        inputs, constants = tuple(values[:-1]), values[-1]
        if is_symbolic(*inputs):
            return builder(*inputs, constants)
        fun = scalar_function(builder, n_inputs, constants, builder.__name__)
        return _evaluate(fun, inputs)

    wrapper.symbolic = builder  # type: ignore[attr-defined]
    return wrapper
