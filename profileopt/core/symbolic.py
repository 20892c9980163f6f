"""One expression, every kind of argument.

The physics (:mod:`profileopt.terrain.roughness`, :mod:`profileopt.physics.forces`) is written once, as
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
from numpy.typing import ArrayLike

__all__ = ["elementwise", "is_symbolic", "scalar_function", "numpy_evaluator", "mx_replay"]


def is_symbolic(*args: Any) -> bool:
    """True if any argument is a CasADi symbolic matrix (``SX`` or ``MX``).

    Parameters
    ----------
    *args : Any
        The values to test: numbers, numpy arrays or CasADi matrices.

    Returns
    -------
    bool
    """
    return any(isinstance(a, (ca.SX, ca.MX)) for a in args)


@functools.lru_cache(maxsize=256)
def scalar_function(builder: Callable, n_inputs: int, constants: Any, name: str) -> ca.Function:
    """The ``casadi.Function`` of ``builder`` on ``n_inputs`` scalar SX symbols.

    ``constants`` (a hashable object such as a frozen :class:`~profileopt.core.vehicle.Vehicle`)
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
    arrays = [np.asarray(a, dtype=float) for a in args]
    shape = np.broadcast_shapes(*(a.shape for a in arrays))
    size = int(np.prod(shape))
    if size == 0:
        return np.zeros(shape)
    if size >= _NUMPY_MIN_SIZE:  # the same instructions as whole-array numpy operations
        return _cached_evaluator(fun)(*arrays)[0]
    arrays = np.broadcast_arrays(*arrays)
    out = np.asarray(fun(*[a.ravel()[None, :] for a in arrays])).reshape(shape)
    if shape == ():
        return float(out)
    return out


#: From this many points on, numbers are evaluated by :func:`numpy_evaluator` (bitwise the
#: same values; below it, one CasADi call is cheaper than one numpy call per instruction).
_NUMPY_MIN_SIZE = 64


def elementwise(builder: Callable) -> Callable:
    """Decorate an expression builder ``builder(x1, ..., xn, vehicle)``.

    The decorated function accepts numbers, numpy arrays, ``casadi.DM``, ``casadi.SX`` or
    ``casadi.MX`` for ``x1 ... xn`` and returns a result of the same kind. ``vehicle`` (or
    whatever hashable constants object the builder takes last) is folded in as numbers.
    The symbolic builder itself stays available as ``.symbolic``.

    Parameters
    ----------
    builder : callable
        ``builder(x1, ..., xn, constants)``: builds a CasADi expression from scalar
        symbols ``x1 ... xn`` and a hashable constants object, its last parameter.

    Returns
    -------
    callable
        A function with the signature of ``builder``: symbolic inputs are passed to
        ``builder`` directly, numeric ones evaluated elementwise through a cached
        ``casadi.Function`` (arrays broadcast against each other).
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


# ---------------------------------------------------------------------------------------
# Evaluating a scalar SX Function on whole numpy arrays at once.

#: How each supported SX operation acts on numpy arrays, exactly as CasADi's virtual
#: machine does on doubles (casadi/core/calculus.hpp). Every one is correctly rounded in
#: IEEE arithmetic (or exact), so the results are bitwise those of CasADi. Operations not
#: listed (transcendental functions, whose last bit may differ between libraries) make
#: :func:`numpy_evaluator` fall back to CasADi itself.
_NUMPY_OPS: dict[int, Callable[..., Any]] = {
    ca.OP_ASSIGN: lambda x: x,
    ca.OP_ADD: np.add,
    ca.OP_SUB: np.subtract,
    ca.OP_MUL: np.multiply,
    ca.OP_DIV: np.divide,
    ca.OP_NEG: np.negative,
    ca.OP_SQRT: np.sqrt,
    ca.OP_SQ: lambda x: x * x,
    ca.OP_TWICE: lambda x: x + x,
    ca.OP_INV: lambda x: 1.0 / x,
    ca.OP_FABS: np.fabs,
    ca.OP_FLOOR: np.floor,
    ca.OP_CEIL: np.ceil,
    ca.OP_COPYSIGN: np.copysign,
    ca.OP_FMIN: np.fmin,  # C fmin: a NaN argument is ignored
    ca.OP_FMAX: np.fmax,
    ca.OP_SIGN: lambda x: np.where(x < 0, -1.0, np.where(x > 0, 1.0, x)),  # sign(nan) = nan
    ca.OP_LT: lambda x, y: np.where(x < y, 1.0, 0.0),
    ca.OP_LE: lambda x, y: np.where(x <= y, 1.0, 0.0),
    ca.OP_EQ: lambda x, y: np.where(x == y, 1.0, 0.0),
    ca.OP_NE: lambda x, y: np.where(x != y, 1.0, 0.0),
    ca.OP_NOT: lambda x: np.where(x == 0, 1.0, 0.0),  # !nan is false
    ca.OP_AND: lambda x, y: np.where((x != 0) & (y != 0), 1.0, 0.0),
    ca.OP_OR: lambda x, y: np.where((x != 0) | (y != 0), 1.0, 0.0),
    ca.OP_IF_ELSE_ZERO: lambda x, y: np.where(x != 0, y, 0.0),  # x ? y : 0, nan is true
}

#: Elements evaluated at once by a numpy evaluator: small enough for the intermediate
#: arrays to stay in the processor's cache, large enough to amortise numpy's call overhead.
_CHUNK_ELEMENTS = 1 << 14


def numpy_evaluator(fun: ca.Function) -> Callable[..., tuple[np.ndarray, ...]]:
    """A numpy version of a CasADi Function of scalars, for many points at once.

    The returned callable takes one array per input of ``fun`` (broadcast against each
    other like numpy operands) and returns a tuple with one array per output, of the
    broadcast shape. For an ``SXFunction`` whose inputs and outputs are all scalars and
    whose operations are all in :data:`_NUMPY_OPS`, it runs the Function's own instruction
    list (``fun.instruction_id``, ``instruction_input``, ``instruction_output``,
    ``instruction_constant``) as whole-array numpy operations, so the values are bitwise
    those of ``fun`` while each instruction costs one vectorised numpy call instead of one
    virtual-machine step per point; an instruction that depends only on an input that
    varies along one axis (a "row" input of shape (N, 1)) is computed once per row.
    Large inputs are processed in slices along the first axis so that intermediates stay
    in cache. Any other Function is evaluated by CasADi itself (``fun.map``) on the
    broadcast inputs.

    Parameters
    ----------
    fun : casadi.Function

    Returns
    -------
    callable
        ``evaluate(*arrays) -> tuple of numpy.ndarray``.
    """
    program = _numpy_program(fun)
    n_out = fun.n_out()

    def evaluate(*args: ArrayLike) -> tuple[np.ndarray, ...]:
        arrays = [np.asarray(a, dtype=float) for a in args]
        shape = np.broadcast_shapes(*(a.shape for a in arrays))
        if program is None or int(np.prod(shape)) == 0:
            return _casadi_evaluate(fun, arrays, shape)
        rows = shape[0] if shape else 1
        row_size = max(int(np.prod(shape[1:])), 1)
        step = max(_CHUNK_ELEMENTS // row_size, 1)
        if rows <= step:
            return _run(program, arrays, shape, n_out)
        outputs = tuple(np.empty(shape) for _ in range(n_out))
        for start in range(0, rows, step):
            stop = min(start + step, rows)
            part = [a[start:stop] if a.ndim == len(shape) and a.shape[0] == rows else a for a in arrays]
            for out, value in zip(outputs, _run(program, part, (stop - start,) + tuple(shape[1:]), n_out)):
                out[start:stop] = value
        return outputs

    return evaluate


_cached_evaluator = functools.lru_cache(maxsize=256)(numpy_evaluator)


def _numpy_program(fun: ca.Function) -> list[tuple] | None:
    """The instruction list of ``fun`` as (op, inputs, output) tuples, or None if it
    cannot be run with numpy exactly (not an SXFunction, an input that is not a dense
    scalar, an output that is not 1x1, or an operation outside :data:`_NUMPY_OPS`)."""
    if not fun.is_a("SXFunction"):
        return None
    scalar = ca.Sparsity.dense(1, 1)
    if any(fun.sparsity_in(i) != scalar for i in range(fun.n_in())) or any(
        fun.size_out(i) != (1, 1) for i in range(fun.n_out())  # a structural zero is fine
    ):
        return None
    program = []
    for k in range(fun.n_instructions()):
        op = fun.instruction_id(k)
        inputs, outputs = fun.instruction_input(k), fun.instruction_output(k)
        if op == ca.OP_CONST:
            program.append((op, fun.instruction_constant(k), outputs[0]))
        elif op == ca.OP_INPUT:
            program.append((op, inputs[0], outputs[0]))
        elif op == ca.OP_OUTPUT:
            program.append((op, inputs[0], outputs[0]))
        elif op in _NUMPY_OPS:
            arity = 2 if op in _BINARY_OPS else 1
            program.append((op, tuple(inputs[:arity]), outputs[0]))
        else:
            return None
    return program


_BINARY_OPS = frozenset({ca.OP_ADD, ca.OP_SUB, ca.OP_MUL, ca.OP_DIV, ca.OP_COPYSIGN, ca.OP_FMIN, ca.OP_FMAX,
                         ca.OP_LT, ca.OP_LE, ca.OP_EQ, ca.OP_NE, ca.OP_AND, ca.OP_OR, ca.OP_IF_ELSE_ZERO})


def _run(program: list[tuple], arrays: list[np.ndarray], shape: tuple[int, ...], n_out: int) -> tuple[np.ndarray, ...]:
    work: dict[int, Any] = {}
    outputs: list[Any] = [0.0] * n_out  # a structurally zero output is never written
    with np.errstate(all="ignore"):  # CasADi returns inf and nan silently, so do we
        for op, arg, out in program:
            if op == ca.OP_CONST:
                work[out] = arg
            elif op == ca.OP_INPUT:
                work[out] = arrays[arg]
            elif op == ca.OP_OUTPUT:
                outputs[out] = work[arg]
            else:
                work[out] = _NUMPY_OPS[op](*(work[i] for i in arg))
    return tuple(np.array(np.broadcast_to(o, shape), dtype=float) for o in outputs)


def _casadi_evaluate(fun: ca.Function, arrays: list[np.ndarray], shape: tuple[int, ...]) -> tuple[np.ndarray, ...]:
    """``fun`` (scalar inputs and outputs) at every point of the broadcast inputs, by CasADi."""
    size = int(np.prod(shape))
    if size == 0:
        return tuple(np.empty(shape) for _ in range(fun.n_out()))
    flat = [np.broadcast_to(a, shape).ravel()[None, :] for a in arrays]
    result = fun.map(size)(*flat)
    result = result if isinstance(result, (list, tuple)) else [result]
    return tuple(np.asarray(r).reshape(shape) for r in result)


# ---------------------------------------------------------------------------------------
# Evaluating a small SX Function on whole MX vectors at once.


def mx_replay(fun: ca.Function, inputs: list[list[ca.MX]]) -> list[list[ca.MX | None]]:
    """Run the instruction list of an SX Function with MX vectors as operands.

    Each instruction of ``fun`` (``fun.instruction_id`` etc.) becomes one elementwise MX
    operation (``MX.unary``/``MX.binary`` with the same operation code) on column vectors
    holding one value per evaluation point, so evaluating the result computes ``fun`` at
    every point with exactly its instruction sequence (bitwise the same values), but as
    one tight loop per instruction instead of one virtual-machine pass per point. The
    MX graph has one node per instruction whatever the number of points. Operands that
    do not depend on a varying input stay scalars (computed once).

    Parameters
    ----------
    fun : casadi.Function
        An ``SXFunction``.
    inputs : list of list of casadi.MX
        For every input of ``fun``, one MX per structural nonzero (in nonzero order):
        column vectors of one common length, or scalars shared by all points.

    Returns
    -------
    list of list of (casadi.MX or None)
        For every output of ``fun``, one MX per entry of its dense column-major shape;
        ``None`` for a structural zero.
    """
    if not fun.is_a("SXFunction"):
        raise TypeError(f"mx_replay needs an SXFunction, got {fun.class_name()} {fun.name()}")
    work: dict[int, ca.MX] = {}
    nonzeros: list[list[ca.MX | None]] = [[None] * fun.nnz_out(i) for i in range(fun.n_out())]
    for k in range(fun.n_instructions()):
        op = fun.instruction_id(k)
        args, out = fun.instruction_input(k), fun.instruction_output(k)
        if op == ca.OP_CONST:
            work[out[0]] = ca.MX(fun.instruction_constant(k))
        elif op == ca.OP_INPUT:
            work[out[0]] = inputs[args[0]][args[1]]
        elif op == ca.OP_OUTPUT:
            nonzeros[out[0]][out[1]] = work[args[0]]
        elif len(args) == 2:
            work[out[0]] = ca.MX.binary(op, work[args[0]], work[args[1]])
        elif len(args) == 1:
            work[out[0]] = ca.MX.unary(op, work[args[0]])
        else:
            raise TypeError(f"mx_replay: instruction {k} of {fun.name()} (operation {op}) is not elementwise")
    dense: list[list[ca.MX | None]] = []
    for i in range(fun.n_out()):
        sp = fun.sparsity_out(i)
        entries: list[ca.MX | None] = [None] * sp.numel()
        for position, value in zip(sp.find(), nonzeros[i]):
            entries[position] = value
        dense.append(entries)
    return dense
