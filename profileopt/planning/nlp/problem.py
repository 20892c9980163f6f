"""The planner's nonlinear program, built in a time that hardly grows with its size.

The NLP of :func:`profileopt.plan` (variables, parameters, objective, constraints
and bounds are documented in :func:`build_nlp`) is a sum of small *stages*: one per
segment (travel time and acceleration, on the two squared speeds at its ends) and one per
interior boundary (the smoothing term and the jerk, on the three squared speeds around it).
Each stage is written once, here, as a tiny CasADi SX expression, and differentiated
exactly by CasADi (``casadi.gradient``/``casadi.hessian`` of the stage alone). The problem
handed to IPOPT is an MX graph that runs each stage Function's instruction list once on
whole vectors, one elementwise MX operation per instruction
(:func:`profileopt.core.symbolic.mx_replay`), so the graph does not grow with N and every
evaluation is a few tight loops. Its derivatives are supplied as Functions too (the
``grad_f``, ``jac_g`` and ``hess_lag`` options of ``casadi.nlpsol``): the stage
derivatives placed on the diagonals of the known banded sparsity (stage k acts on the
boundaries k, k+1 (and k+2), so its entries are stage 0's shifted by k). No symbolic
differentiation of the whole problem happens, which is what made building a
10,000-segment SX problem take seconds.

Optional *row families* add rows on a segment's two squared speeds with data of their own
per segment (:data:`~profileopt.physics.rows.ROW_FAMILIES`): the friction circle and the drive power of turns and
hills (:mod:`profileopt.physics.motion`), each evaluated at both ends of the segment (the higher
speed is where they are tightest) and, for friction, at both extremes of its grade.

Every stage contribution is an exact term of the objective or one entry of g, so the
gradient, Jacobian and Hessian are exactly those of the whole problem (the tests check
them against ``casadi.jacobian``/``casadi.hessian`` of an independently written SX NLP).
"""

from __future__ import annotations

import dataclasses
import functools
from typing import Any, Mapping

import casadi as ca
import numpy as np

from ...core.kinematics import (
    boundary_jerk_mps3,
    jerk_squared_time,
    segment_accel_mps2,
    segment_time_s,
)
from ...core.symbolic import mx_replay
from ...physics.rows import ROW_FAMILIES, exact_row_values, row_values
from ..options import DEFAULT_IPOPT_OPTIONS, SolverOptions

__all__ = ["SPEED_EPS_MPS", "PARAMETERS", "build_nlp", "cached_nlp", "Scaling",
           "NlpResult", "row_bounds", "objective_s", "family_rows", "nlp_parts", "diagonal_matrix",
           "NlpParts"]

#: Speed (m/s) that keeps sqrt(b) differentiable at rest in the NLP's time and jerk terms.
SPEED_EPS_MPS = 1e-3

#: The global parameters after the N scaled segment lengths (and the row families' data),
#: in order (see build_nlp).
PARAMETERS = ("b_ref", "l_ref", "a_ref", "t_ref", "weight", "inv_jerk")

# ---------------------------------------------------------------------------------------
# The formulas, each written once (symbolic; SX or MX arguments).


def speed_mps(b: Any) -> Any:
    """v = sqrt(b + eps^2) (m/s) from the squared speed b (m^2/s^2), smooth at rest."""
    return ca.sqrt(b + SPEED_EPS_MPS**2)


def jerk_terms(b: tuple[Any, Any, Any], ds_m: tuple[Any, Any]) -> tuple[Any, Any]:
    """At an interior boundary j: (v_j da^2 / dsm_j, jerk_j = v_j da / dsm_j).

    ``b`` holds b_{j-1}, b_j, b_{j+1} (m^2/s^2), ``ds_m`` the lengths of the segments
    before and after boundary j (m). See :func:`profileopt.core.kinematics.jerk_squared_time`
    and :func:`profileopt.core.kinematics.boundary_jerk_mps3`.
    """
    a_before = segment_accel_mps2(b[0], b[1], ds_m[0])
    a_after = segment_accel_mps2(b[1], b[2], ds_m[1])
    v = speed_mps(b[1])
    return (jerk_squared_time(v, a_before, a_after, ds_m[0], ds_m[1]),
            boundary_jerk_mps3(v, a_before, a_after, ds_m[0], ds_m[1]))


# ---------------------------------------------------------------------------------------
# Stages and their exact derivatives (tiny SX Functions).

#: Upper-triangle entries (row, column) of a stage's local Hessian, in output order.
_TRIU_2 = ((0, 0), (0, 1), (1, 1))
_TRIU_3 = ((0, 0), (0, 1), (1, 1), (0, 2), (1, 2), (2, 2))


def _stages() -> dict[str, ca.Function]:
    """The two kinds of stage, as Functions of their values and exact derivatives.

    Segment stage, inputs (z = [y_i, y_{i+1}], ds_scaled_i, q): f = travel_i / T_ref and
    g = a_i / a_ref. Boundary stage, inputs (z = [y_{j-1}, y_j, y_{j+1}], [ds_scaled_{j-1},
    ds_scaled_j], q): f = weight v_j da^2 / dsm_j / T_ref and g = jerk_j / J. q holds
    :data:`PARAMETERS`. For each kind (``seg``, ``bnd``), ``*_f`` returns f, ``*_g`` g,
    ``*_fdf`` f and grad f, ``*_gdg`` g and grad g (gradients are columns, w.r.t. z), and
    ``*_h`` takes (z, ds, lam_g, q, lam_f) and returns the upper triangle of
    the Hessian of lam_f f + lam_g g w.r.t. z (entries :data:`_TRIU_2` / :data:`_TRIU_3`).
    """
    q = ca.SX.sym("q", len(PARAMETERS))
    b_ref, l_ref, a_ref, t_ref, weight, inv_jerk = (q[k] for k in range(len(PARAMETERS)))
    lam_f, lam_g = ca.SX.sym("lam_f"), ca.SX.sym("lam_g")
    out: dict[str, ca.Function] = {}

    z = ca.SX.sym("z", 2)
    ds = ca.SX.sym("ds")
    b, length = b_ref * z, l_ref * ds
    f = segment_time_s(speed_mps(b[0]), speed_mps(b[1]), length) / t_ref
    g = segment_accel_mps2(b[0], b[1], length) / a_ref
    out.update(_stage_functions("seg", z, ds, q, f, g, lam_f, lam_g, _TRIU_2))

    z = ca.SX.sym("z", 3)
    ds = ca.SX.sym("ds", 2)
    b, length = b_ref * z, l_ref * ds
    smooth, jerk = jerk_terms((b[0], b[1], b[2]), (length[0], length[1]))
    f = weight * smooth / t_ref
    g = jerk * inv_jerk
    out.update(_stage_functions("bnd", z, ds, q, f, g, lam_f, lam_g, _TRIU_3))

    for family in ROW_FAMILIES.values():
        z = ca.SX.sym("z", 2)
        ds = ca.SX.sym("ds")
        d = ca.SX.sym("d", len(family.data))
        b, length = b_ref * z, l_ref * ds
        rows = row_values(family.name, (speed_mps(b[0]), speed_mps(b[1])), (b[0], b[1]), length,
                          [d[k] for k in range(len(family.data))])
        assert len(rows) == family.count
        for k, g in enumerate(rows):
            out.update(_row_functions(f"{family.name}{k}", z, ds, d, q, g, lam_g))
    return out


def _row_functions(name: str, z: ca.SX, ds: ca.SX, d: ca.SX, q: ca.SX, g: ca.SX, lam_g: ca.SX
                   ) -> dict[str, ca.Function]:
    hess = ca.hessian(lam_g * g, z)[0]
    return {
        f"{name}_g": ca.Function(f"{name}_g", [z, ds, d, q], [g]),
        f"{name}_gdg": ca.Function(f"{name}_gdg", [z, ds, d, q], [g, ca.gradient(g, z)]),
        f"{name}_h": ca.Function(f"{name}_h", [z, ds, d, lam_g, q], [ca.vertcat(*(hess[r, c] for r, c in _TRIU_2))]),
    }


def family_rows(family: str, b: np.ndarray, length_m: np.ndarray, data: np.ndarray, *, smooth: bool = True
                ) -> np.ndarray:
    """The rows of a row family evaluated on numbers: the same expressions as the NLP's.

    Parameters
    ----------
    family : str
        A key of :data:`~profileopt.physics.rows.ROW_FAMILIES`.
    b : numpy.ndarray, shape (N+1,)
        Squared speeds at the boundaries (m^2/s^2).
    length_m : numpy.ndarray, shape (N,)
        Segment lengths (m).
    data : numpy.ndarray, shape (N, D)
        The family's per-segment data, columns as :data:`~profileopt.physics.rows.ROW_FAMILIES` names them.
    smooth : bool, default True
        True: the NLP's speed sqrt(b + eps^2) (what IPOPT kept); False: the exact speed
        sqrt(b), for judging a finished profile (the eps would add eps^2 / (2 b) at a crawl).

    Returns
    -------
    numpy.ndarray, shape (R, N)
        Each row's value per segment; <= 1 where the limit holds.
    """
    if not smooth:
        return exact_row_values(family, b, length_m, data)
    cols = [data[:, k] for k in range(data.shape[1])]
    rows = row_values(family, (speed_mps(b[:-1]), speed_mps(b[1:])), (b[:-1], b[1:]), length_m, cols)
    return np.array([np.asarray(r, dtype=float).ravel() for r in rows])


def _stage_functions(name: str, z: ca.SX, ds: ca.SX, q: ca.SX, f: ca.SX, g: ca.SX, lam_f: ca.SX,
                     lam_g: ca.SX, triu: tuple[tuple[int, int], ...]) -> dict[str, ca.Function]:
    hess = ca.hessian(lam_f * f + lam_g * g, z)[0]
    return {
        f"{name}_f": ca.Function(f"{name}_f", [z, ds, q], [f]),
        f"{name}_g": ca.Function(f"{name}_g", [z, ds, q], [g]),
        f"{name}_fdf": ca.Function(f"{name}_fdf", [z, ds, q], [f, ca.gradient(f, z)]),
        f"{name}_gdg": ca.Function(f"{name}_gdg", [z, ds, q], [g, ca.gradient(g, z)]),
        f"{name}_h": ca.Function(f"{name}_h", [z, ds, lam_g, q, lam_f], [ca.vertcat(*(hess[r, c] for r, c in triu))]),
    }


# ---------------------------------------------------------------------------------------
# Placing stage values in the problem's vectors and banded matrices (no index arrays: the
# pattern of stage k is the same as that of stage 0, shifted by k).


def _shifted(v: ca.MX, before: int, after: int) -> ca.MX:
    """Column vector v with ``before`` zeros above and ``after`` below."""
    return ca.vertcat(ca.MX.zeros(before, 1), v, ca.MX.zeros(after, 1)) if before or after else v


def diagonal_matrix(v: ca.MX, rows: int, cols: int, offset: int) -> ca.MX:
    """A (rows x cols) sparse matrix whose entries (k, k + offset) are v[k] (v a column of k
    entries, possibly none).

    Parameters
    ----------
    v : casadi.MX, shape (k, 1)
        The entries.
    rows, cols : int
        Shape of the matrix.
    offset : int
        Column offset of the diagonal (>= 0).

    Returns
    -------
    casadi.MX, shape (rows, cols)
    """
    k = v.size1()
    block = ca.diag(v)  # k x k, sparse diagonal
    return ca.vertcat(ca.horzcat(ca.MX(k, offset), block, ca.MX(k, cols - offset - k)), ca.MX(rows - k, cols))


@dataclasses.dataclass(frozen=True)
class NlpParts:
    """The NLP's symbols and placed stage outputs (see :func:`nlp_parts`). ``jac_blocks``:
    one tuple of columns per row block (accelerations, jerks, each family row), column r of
    a block holding d row_k / d y_{k + r} for the block's rows k; ``hess_diagonals``: the
    upper triangle's diagonals at offsets 0, 1, 2 (lengths N+1, N, N-1)."""

    name: str
    x: ca.MX
    p: ca.MX
    lam_f: ca.MX
    lam_g: ca.MX
    f: ca.MX
    g: ca.MX
    f_d: ca.MX
    grad: ca.MX
    g_d: ca.MX
    jac_blocks: tuple[tuple[ca.MX, ...], ...]
    hess_diagonals: tuple[ca.MX, ca.MX, ca.MX]


def nlp_parts(n: int, with_jerk: bool, families: tuple[str, ...], *, scaled: bool = False) -> "NlpParts":
    """The symbolic pieces of the planner's NLP, placed but not yet assembled into matrices.

    :func:`build_nlp` assembles them into IPOPT's sparse Jacobian and Hessian;
    :func:`profileopt.planning.nlp.backends.banded.build_banded_oracle` returns them as dense bands.

    Parameters
    ----------
    n : int
        Number of segments N >= 1.
    with_jerk : bool
        Whether g holds the jerk rows (only when N >= 2).
    families : tuple of str
        Row families (:data:`~profileopt.physics.rows.ROW_FAMILIES`), in this order.
    scaled : bool, default False
        True: the variables are x_j = y_j / sigma_j with a scale sigma_j > 0 per boundary,
        given as N+1 more parameters after the tail; the stages see y = sigma x and their
        derivatives are carried over by the chain rule (gradient times sigma_j, Jacobian
        column times sigma_j, Hessian entry (j, k) times sigma_j sigma_k). False: x = y.

    Returns
    -------
    NlpParts
    """
    n = int(n)
    if n < 1:
        raise ValueError(f"the NLP needs at least one segment, got n = {n}")
    jerk = bool(with_jerk) and n >= 2
    nx, m = n + 1, n - 1  # variables, interior boundaries
    st = _stages()
    unknown = [f for f in families if f not in ROW_FAMILIES]
    if unknown:
        raise ValueError(f"unknown row families {unknown}; choose from {sorted(ROW_FAMILIES)}")
    n_data = sum(len(ROW_FAMILIES[f].data) for f in families)

    x = ca.MX.sym("y", nx)
    tail_at = n + n * n_data
    p = ca.MX.sym("p", tail_at + len(PARAMETERS) + (nx if scaled else 0))
    lam_f = ca.MX.sym("lam_f")
    q = [p[tail_at + k] for k in range(len(PARAMETERS))]
    sigma = p[tail_at + len(PARAMETERS):] if scaled else None
    y = sigma * x if scaled else x  # what the stages see
    data_cols: dict[str, list[ca.MX]] = {}
    start = n
    for family in families:  # each data column of each family: N entries of p
        names = ROW_FAMILIES[family].data
        data_cols[family] = [p[start + k * n:start + (k + 1) * n] for k in range(len(names))]
        start += n * len(names)
    # (family, row, stage inputs) of every family row, in the order of g
    fam_rows = [(family, k, [[y[:n], y[1:]], [p[:n]], data_cols[family]])
                for family in families for k in range(ROW_FAMILIES[family].count)]
    # stage inputs: one column per scalar input, one entry per stage
    seg = [[y[:n], y[1:]], [p[:n]]]
    bnd = [[y[:m], y[1:n], y[2:]], [p[:m], p[1:n]]] if m else None

    def stages(kind: str, what: str, extra: list | None = None, shared: list | None = None,
               inputs: list | None = None) -> list[list[ca.MX]]:
        """The outputs of stage Function ``kind_what`` at every stage, as columns."""
        if inputs is None:
            inputs, count = (seg, n) if kind == "seg" else (bnd, m)
        else:
            count = n
        outputs = mx_replay(st[f"{kind}_{what}"], inputs + (extra or []) + [q] + (shared or []))
        return [[_column(v, count) for v in out] for out in outputs]

    # objective and constraints (the oracle's f and g)
    f = ca.sum1(stages("seg", "f")[0][0])
    g_parts = [stages("seg", "g")[0][0]]
    if m:
        f = f + ca.sum1(stages("bnd", "f")[0][0])
        if jerk:
            g_parts.append(stages("bnd", "g")[0][0])
    for family, k, inputs in fam_rows:
        g_parts.append(stages(f"{family}{k}", "g", inputs=inputs)[0][0])
    g = ca.vertcat(*g_parts)
    ng = g.size1()

    # gradient of f: entry r of stage k's gradient belongs to variable k + r
    (f_seg,), df_seg = stages("seg", "fdf")
    f_d = ca.sum1(f_seg)
    grad = _shifted(df_seg[0], 0, 1) + _shifted(df_seg[1], 1, 0)
    if m:
        (f_bnd,), df_bnd = stages("bnd", "fdf")
        f_d = f_d + ca.sum1(f_bnd)
        grad = grad + sum(_shifted(df_bnd[r], r, 2 - r) for r in range(3))

    # Jacobian of g: row i (segment) holds columns i, i+1; row n + j - 1 (boundary j)
    # holds columns j-1, j, j+1: shifted diagonals of the stage gradients.
    (g_seg,), dg_seg = stages("seg", "gdg")
    g_d = [g_seg]
    jac_blocks = [dg_seg]
    if jerk:
        (g_bnd,), dg_bnd = stages("bnd", "gdg")
        g_d.append(g_bnd)
        jac_blocks.append(dg_bnd)
    for family, k, inputs in fam_rows:
        (g_fam,), dg_fam = stages(f"{family}{k}", "gdg", inputs=inputs)
        g_d.append(g_fam)
        jac_blocks.append(dg_fam)

    # Hessian of the Lagrangian, upper triangle: entry (r, c) of stage k's local Hessian
    # lands on (k + r, k + c); the stage Hessians are summed where they overlap.
    lam_g = ca.MX.sym("lam_g", ng)
    (h_seg,) = stages("seg", "h", [[lam_g[:n]]], [[lam_f]])
    parts = [(h_seg[e], r, c, n) for e, (r, c) in enumerate(_TRIU_2)]
    if m:
        lam_jerk = lam_g[n:n + m] if jerk else ca.MX(0.0)
        (h_bnd,) = stages("bnd", "h", [[lam_jerk]], [[lam_f]])
        parts += [(h_bnd[e], r, c, m) for e, (r, c) in enumerate(_TRIU_3)]
    first_row = n + (m if jerk else 0)
    for j, (family, k, inputs) in enumerate(fam_rows):
        lam_rows = lam_g[first_row + j * n:first_row + (j + 1) * n]
        (h_fam,) = stages(f"{family}{k}", "h", [[lam_rows]], inputs=inputs)
        parts += [(h_fam[e], r, c, n) for e, (r, c) in enumerate(_TRIU_2)]
    by_offset: dict[int, list[ca.MX]] = {}
    for v, r, c, count in parts:  # diagonal c - r, starting at row r
        by_offset.setdefault(c - r, []).append(_shifted(v, r, nx - (c - r) - r - count))
    hess_diagonals = tuple(sum(by_offset[offset]) if offset in by_offset else ca.MX.zeros(nx - offset, 1)
                           for offset in range(3))
    if scaled:  # d/dx = sigma d/dy
        grad = grad * sigma
        jac_blocks = [tuple(column * sigma[r:r + column.size1()] for r, column in enumerate(block))
                      for block in jac_blocks]
        hess_diagonals = tuple(diagonal * sigma[:nx - offset] * sigma[offset:]
                               for offset, diagonal in enumerate(hess_diagonals))
    name = (f"profileopt_n{n}_{'jerk' if with_jerk else 'nojerk'}" + "".join(f"_{f}" for f in families)
            + ("_scaled" if scaled else ""))
    return NlpParts(name, x, p, lam_f, lam_g, f, g, f_d, grad, ca.vertcat(*g_d), tuple(jac_blocks), hess_diagonals)


def build_nlp(n: int, with_jerk: bool, ipopt_options: Mapping[str, Any] = DEFAULT_IPOPT_OPTIONS,
              families: tuple[str, ...] = (), *, scaled: bool = False) -> ca.Function:
    """The IPOPT solver of the planner's NLP for N = n segments, in y = b / b_ref (b = v^2).

    Parameters
    ----------
    n : int
        Number of segments N >= 1; there are N + 1 variables y (squared speeds at the
        boundaries over b_ref).
    with_jerk : bool
        Whether g holds the jerk constraints (only when N >= 2).
    ipopt_options : Mapping[str, Any], default :data:`~profileopt.planning.options.DEFAULT_IPOPT_OPTIONS`
        Options of ``casadi.nlpsol`` for IPOPT.
    families : tuple of str, default ()
        Row families (:data:`~profileopt.physics.rows.ROW_FAMILIES`) to add, in this order.
    scaled : bool, default False
        True: the variables are y_j / sigma_j, with the N+1 scales sigma_j > 0 after the
        parameters below (:func:`nlp_parts`).

    Returns
    -------
    casadi.Function
        ``casadi.nlpsol`` (IPOPT with ``ipopt_options``, exact Hessian) with x = y, shape
        (N+1,), and parameters p, shape (N + N D + 6,): segment lengths / L_ref (N), the
        families' data (N per data column, family after family, D columns in all), then b_ref
        (m^2/s^2), L_ref (m), a_ref (m/s^2), T_ref (s), the smoothing weight (-) and 1/J
        (s^3/m). Constraints g: the accelerations a_i / a_ref (N), then, with jerk and
        N >= 2, jerk_j / J at the N-1 interior boundaries, jerk_j = v_j (a_j - a_{j-1}) /
        dsm_j (jerk = v da/ds, dsm_j = (ds_{j-1} + ds_j) / 2). Objective: (travel time +
        weight * integral (jerk / (1 m/s^3))^2 dt) / T_ref, with travel time = sum 2 ds_i /
        (v_i + v_{i+1}), integral jerk^2 dt = sum v_j (a_j - a_{j-1})^2 / dsm_j, and
        v = sqrt(b + eps^2), eps = :data:`SPEED_EPS_MPS`. After the jerk rows, each family's
        rows (N per row of the family, row after row), bounded above by 1.

    Notes
    -----
    The objective and g run the stage Functions of :func:`_stages` on all stages at once
    (graph size independent of N); ``grad_f``, ``jac_g`` and ``hess_lag`` are the exact stage
    derivatives placed on the diagonals of the banded structure (Hessian bandwidth 2), so
    IPOPT receives exactly the derivatives of the whole problem.
    """
    parts = nlp_parts(n, with_jerk, families, scaled=scaled)
    x, p, nx = parts.x, parts.p, parts.x.size1()
    jac = ca.vertcat(*(sum(diagonal_matrix(block[r], block[r].size1(), nx, r) for r in range(len(block)))
                       for block in parts.jac_blocks))
    hess = sum(diagonal_matrix(diagonal, nx, nx, offset) for offset, diagonal in enumerate(parts.hess_diagonals))
    name = parts.name
    options = dict(ipopt_options)
    options["grad_f"] = ca.Function(f"{name}_grad_f", [x, p], [parts.f_d, parts.grad], ["x", "p"], ["f", "grad_f_x"])
    options["jac_g"] = ca.Function(f"{name}_jac_g", [x, p], [parts.g_d, jac], ["x", "p"], ["g", "jac_g_x"])
    options["hess_lag"] = ca.Function(f"{name}_hess_lag", [x, p, parts.lam_f, parts.lam_g], [hess],
                                      ["x", "p", "lam_f", "lam_g"], ["triu_hess_gamma_x_x"])
    return ca.nlpsol(name, "ipopt", {"x": x, "p": p, "f": parts.f, "g": parts.g}, options)


def _column(v: ca.MX | None, count: int) -> ca.MX:
    """A stage output as a column of ``count`` entries (a structural zero or a value the
    same for every stage, such as a parameter-only derivative, is repeated)."""
    if v is None:
        return ca.MX.zeros(count, 1)
    return v if v.size1() == count else ca.repmat(v, count, 1)


# ---------------------------------------------------------------------------------------
# Solving: the NLP built once per (size, jerk on/off, IPOPT options), re-solved with parameters.


@functools.lru_cache(maxsize=8)
def cached_nlp(n: int, with_jerk: bool, ipopt_key: tuple = SolverOptions().ipopt_key(),
               families: tuple[str, ...] = (), scaled: bool = False) -> ca.Function:
    """:func:`build_nlp` for N = n segments, built once per size and options and cached.

    Variables y = b / b_ref (b = v^2) at the N+1 boundaries; parameters: segment lengths /
    L_ref (n), then b_ref, L_ref, a_ref, T_ref, the smoothing weight and 1/J; constraints
    a_i / a_ref and, with jerk, jerk_j / J; objective (travel time + weight * integral
    jerk^2 dt) / T_ref.

    Parameters
    ----------
    n : int
        Number of segments.
    with_jerk : bool
        Whether the jerk rows are in g (only when n >= 2).
    ipopt_key : tuple
        The IPOPT options as :meth:`SolverOptions.ipopt_key` gives them.
    families : tuple of str, default ()
        Row families (:data:`~profileopt.physics.rows.ROW_FAMILIES`).
    scaled : bool, default False
        A scale per boundary (:func:`build_nlp`).

    Returns
    -------
    casadi.Function
        The IPOPT solver.
    """
    return build_nlp(n, with_jerk and n >= 2, dict(ipopt_key), families, scaled=scaled)


@dataclasses.dataclass(frozen=True)
class Scaling:
    """The NLP's parameters after the segment lengths, shared by every solve of one plan.

    Attributes
    ----------
    b_ref : float
        Squared-speed scale (m^2/s^2): the highest upper bound on b.
    l_ref : float
        Length scale (m): the mean segment length.
    a_ref : float
        Acceleration scale (m/s^2): the largest acceleration bound.
    weight : float
        Smoothing weight (-).
    inv_jerk : float
        1 / jerk bound (s^3/m), 0 without one.
    t_whole : float
        T_ref of the whole route: the greatest profile's travel time (s).
    """

    b_ref: float
    l_ref: float
    a_ref: float
    weight: float
    inv_jerk: float
    t_whole: float

    def tail(self, t_ref: float) -> np.ndarray:
        """The parameters after the segment lengths, with time scale ``t_ref`` (s).

        Parameters
        ----------
        t_ref : float
            Time scale of the objective (s).

        Returns
        -------
        numpy.ndarray, shape (6,)
        """
        return np.array([self.b_ref, self.l_ref, self.a_ref, t_ref, self.weight, self.inv_jerk])


@dataclasses.dataclass(frozen=True)
class NlpResult:
    """One solve of the planner's NLP, in scaled units.

    Attributes
    ----------
    y : numpy.ndarray, shape (N+1,)
        b / b_ref at the boundaries.
    lam_g : numpy.ndarray
        Multipliers of the rows (CasADi's sign convention: > 0 where an upper bound holds).
    success : bool
        Whether the solver converged.
    status : str
        ``"optimal"`` or the solver's reason for stopping.
    iterations : int
        Iterations.
    solver : str, default "ipopt"
        The back end whose answer it is (:mod:`profileopt.planning.nlp.backends`).
    """

    y: np.ndarray
    lam_g: np.ndarray
    success: bool
    status: str
    iterations: int
    solver: str = "ipopt"


def row_bounds(with_jerk: bool, decel_mps2: np.ndarray, accel_mps2: np.ndarray, a_ref: float,
               families: tuple[str, ...] = ()) -> tuple[np.ndarray, np.ndarray]:
    """Bounds on the rows of the NLP: a_i / a_ref (N), then jerk_j / J (N-1) when
    ``with_jerk``, then the families' rows (<= 1).

    Parameters
    ----------
    with_jerk : bool
        Whether the NLP has jerk rows (N >= 2 and a finite bound).
    decel_mps2, accel_mps2 : numpy.ndarray, shape (N,)
        Deceleration (positive) and acceleration bounds of each segment (m/s^2).
    a_ref : float
        Acceleration scale (m/s^2).
    families : tuple of str, default ()
        Row families (:data:`~profileopt.physics.rows.ROW_FAMILIES`).

    Returns
    -------
    lbg, ubg : numpy.ndarray
    """
    n = decel_mps2.size
    lbg, ubg = [-decel_mps2 / a_ref], [accel_mps2 / a_ref]
    if with_jerk and n >= 2:
        lbg.append(np.full(n - 1, -1.0))
        ubg.append(np.full(n - 1, 1.0))
    for family in families:
        rows = n * ROW_FAMILIES[family].count
        lbg.append(np.full(rows, -np.inf))
        ubg.append(np.ones(rows))
    return np.concatenate(lbg), np.concatenate(ubg)


def objective_s(b: np.ndarray, length_m: np.ndarray, smoothing: float) -> float:
    """Travel time plus the smoothing term (s) of a squared-speed profile, exactly.

    Parameters
    ----------
    b : numpy.ndarray, shape (N+1,)
        Squared speeds at the boundaries (m^2/s^2).
    length_m : numpy.ndarray, shape (N,)
        Segment lengths (m).
    smoothing : float
        Weight of the jerk term (-).

    Returns
    -------
    float
    """
    v = np.sqrt(np.maximum(b, 0.0))
    travel = float(np.sum(segment_time_s(v[:-1], v[1:], length_m)))
    if length_m.size < 2 or smoothing == 0:
        return travel
    a = segment_accel_mps2(b[:-1], b[1:], length_m)
    return travel + smoothing * float(np.sum(jerk_squared_time(v[1:-1], a[:-1], a[1:], length_m[:-1], length_m[1:])))
