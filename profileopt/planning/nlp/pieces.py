"""Cutting a long route's NLP into pieces where its optimum is pinned, and checking the cuts.

Why: IPOPT's time per segment grows with the number of segments N once its vectors and
MUMPS's factors no longer fit in the processor's cache. Measured on a 2-core machine, a
whole solve took 49 us per segment up to 10,000 segments, 59 at 20,000 and 80 at 100,000
(with about the same number of iterations; every part of IPOPT slowed alike, function
evaluations included). Pieces of a few thousand segments keep every solve in cache, so a
long route costs N times a constant.

Why this is exact: the planner's NLP (:func:`profileopt.planning.nlp.problem.build_nlp`) is a chain. Its
terms and rows act on two consecutive squared speeds (a segment's travel time,
acceleration, friction and power rows) or three (a boundary's smoothing term and jerk). If two consecutive boundary
speeds b_k, b_{k+1} are held fixed, every term or row that involves a free variable left of
k lies wholly in boundaries 0..k+1, and every one that involves a free variable right of
k+1 lies wholly in k..N: the problem splits into two independent NLPs that share only the
fixed pair (and segment k's own row and time, which are then constants).

Which pairs the optimum holds at their caps is known only after solving, so cuts are
*guessed* before (:func:`cut_scores`, :func:`choose_cuts`: bottlenecks, segments whose cap
is the lowest of the caps around them, which the greatest profile reaches without a sharp
corner) and *checked* after (:func:`cut_multipliers`). The joined solution is a KKT point
of the whole NLP when each piece's solution is a KKT point of the piece, segment k's
acceleration row is inactive (a_k = 0 between equal caps), so are its friction and power
rows, and at every cut the whole
problem's Lagrangian gradient w.r.t. the two fixed variables has the sign of an active
upper bound: bound multiplier lam_x = -(grad f + J^T lam_g) >= 0, CasADi's sign
convention. That is the same optimality IPOPT certifies for the whole problem solved at
once. A cut that fails the check (:func:`wrong_cuts`), or beside a piece IPOPT cannot
solve, was a wrong guess: the planner replaces it (:func:`replace_cuts`) and solves the
whole route at once if no set of cuts checks out.
"""

from __future__ import annotations

import time
from typing import TYPE_CHECKING

import casadi as ca
import numpy as np

from ...core.kinematics import boundary_jerk_mps3, segment_accel_mps2
from ...physics.rows import ROW_FAMILIES
from .problem import cached_nlp, family_rows, objective_s
from .solve import solve_nlp

if TYPE_CHECKING:
    from ..bands import BandChoice
    from ..options import SolverOptions
    from .problem import Scaling

__all__ = ["CUT_REACH", "choose_cuts", "cut_multipliers", "cut_scores", "piece_bounds", "replace_cuts",
           "wrong_cuts", "solve_pieces"]

#: A cut's segment must have the lowest cap of the CUT_REACH boundaries on either side, and
#: cuts stay that many segments from the route's ends and from each other.
CUT_REACH = 20


def cut_scores(upper_b: np.ndarray, greatest_b: np.ndarray, length_m: np.ndarray) -> np.ndarray:
    """How likely the optimum holds each segment at its cap: lower is likelier, inf not a candidate.

    Parameters
    ----------
    upper_b : numpy.ndarray, shape (N+1,)
        Upper bounds on the squared speed at the boundaries (m^2/s^2).
    greatest_b : numpy.ndarray, shape (N+1,)
        The greatest profile under these bounds and the acceleration limits (m^2/s^2); the
        optimum lies below it, so a cut needs it at the cap.
    length_m : numpy.ndarray, shape (N,)
        Segment lengths (m).

    Returns
    -------
    numpy.ndarray, shape (N,)
        For a candidate segment k, the largest jerk (m/s^3) of the greatest profile at the
        boundaries k-1 .. k+2 around it; inf for the others. A candidate has b_k and
        b_{k+1} bounded by the same cap (segment k is the slower of its neighbours at both
        ends), that cap no higher than any other within :data:`CUT_REACH` boundaries, and the
        greatest profile at it on both boundaries. The optimum smooths the greatest
        profile's corners (jerk bound, smoothing term), so where they are sharp it may pass
        below the cap; where the greatest profile is gentle it holds the cap (on the
        100,000-segment benchmark route, every candidate scored up to the jerk bound was
        pinned, and 99.6 % of those up to twice that).
    """
    n = upper_b.size - 1
    r = CUT_REACH
    hi = upper_b
    tol = 1e-12 * np.maximum(hi, 1.0)
    same = np.abs(hi[:-1] - hi[1:]) <= tol[1:]
    reached = np.abs(greatest_b - hi) <= 1e-9 * np.maximum(hi, 1.0)
    padded = np.concatenate([np.full(r, np.inf), hi, np.full(r, np.inf)])
    lowest = np.lib.stride_tricks.sliding_window_view(padded, 2 * r + 2).min(axis=1)[:n]  # k-r .. k+1+r
    k = np.arange(n)
    candidate = same & reached[:-1] & reached[1:] & (hi[:-1] <= lowest + tol[:-1]) & (k >= r) & (k < n - r - 1)

    a = segment_accel_mps2(greatest_b[:-1], greatest_b[1:], length_m)
    jerk = np.zeros(n + 1)
    if n >= 2:
        v = np.sqrt(np.maximum(greatest_b[1:-1], 0.0))
        jerk[1:-1] = np.abs(boundary_jerk_mps3(v, a[:-1], a[1:], length_m[:-1], length_m[1:]))
    corner = np.lib.stride_tricks.sliding_window_view(np.concatenate([[0.0], jerk, [0.0, 0.0]]), 4).max(axis=1)[:n]
    return np.where(candidate, corner, np.inf)


def _best(score: np.ndarray, lo: int, end: int, excluded: set[int]) -> int:
    """The lowest-scored candidate in lo <= k < end (the last of equals), not excluded, and
    at least :data:`CUT_REACH` from the route's ends; -1 if none."""
    lo, end = max(lo, CUT_REACH), min(end, score.size - CUT_REACH - 1)
    if lo >= end:
        return -1
    window = score[lo:end].copy()
    for k in excluded:
        if lo <= k < end:
            window[k - lo] = np.inf
    best = end - 1 - int(np.argmin(window[::-1]))
    return best if np.isfinite(window[best - lo]) else -1


def _greedy(score: np.ndarray, piece_segments: int, start: int, excluded: set[int]) -> list[int] | None:
    """The cuts after boundary ``start`` (see :func:`choose_cuts`); None if some stretch
    holds no candidate."""
    n = score.size
    cuts: list[int] = []
    while n - start > piece_segments:  # start: first boundary of the current piece
        chosen = -1
        for low in (3 * piece_segments // 4, piece_segments // 4):
            # the piece is boundaries start .. k+1, so k <= start + piece_segments - 1
            chosen = _best(score, start + max(low, CUT_REACH), start + piece_segments, excluded)
            if chosen >= 0:
                break
        if chosen < 0:
            return None
        cuts.append(chosen)
        start = chosen
    return cuts


def choose_cuts(score: np.ndarray, piece_segments: int) -> np.ndarray:
    """Where to cut a route's NLP: segments k whose two boundary speeds are to be fixed.

    Parameters
    ----------
    score : numpy.ndarray, shape (N,)
        :func:`cut_scores` of the route.
    piece_segments : int
        Most segments in one piece (the size of the NLP the pieces are solved with).

    Returns
    -------
    numpy.ndarray of int, shape (K,)
        Increasing segment indices k: piece p spans boundaries cut[p-1] .. cut[p] + 1 (from
        0, to N), every piece at most ``piece_segments`` segments long, cuts at least
        :data:`CUT_REACH` apart and from the ends. Empty when the route fits in one piece,
        or when some stretch of it holds no candidate (then it is solved whole).

    Notes
    -----
    Walking along the route, each cut is the best-scored candidate among those that make
    the piece before it between 3/4 and all of ``piece_segments`` long (then, if there is
    none, between 1/4 and all); of equals, the farthest.
    """
    cuts = _greedy(score, piece_segments, 0, set())
    return np.asarray(cuts or [], dtype=int)


def replace_cuts(score: np.ndarray, cuts: np.ndarray, wrong: np.ndarray, piece_segments: int,
                 excluded: set[int]) -> np.ndarray:
    """New cuts in place of ``cuts[wrong]``, which did not check out (and are in ``excluded``).

    Each wrong cut, in order, is replaced by the best-scored candidate that is not excluded
    and keeps both pieces beside it at most ``piece_segments`` long. Where there is none,
    the cuts after the one before it are chosen again as :func:`choose_cuts` does, and if
    that finds none either, all the cuts (without the excluded ones).

    Parameters
    ----------
    score : numpy.ndarray, shape (N,)
        :func:`cut_scores` of the route.
    cuts : numpy.ndarray of int, shape (K,)
        The current cuts (segment indices, increasing, as :func:`choose_cuts` returns);
        not modified.
    wrong : numpy.ndarray of int
        Indices into ``cuts`` of the cuts to replace, increasing.
    piece_segments : int
        Most segments in one piece.
    excluded : set of int
        Segment indices that may not be cuts (those already tried, the wrong ones among them).

    Returns
    -------
    numpy.ndarray of int
        The new cuts; empty if no set of cuts is left.
    """
    n = score.size
    cuts = cuts.copy()
    for index in (int(i) for i in wrong):
        first = int(cuts[index - 1]) if index > 0 else 0  # the piece before starts here
        last = int(cuts[index + 1]) + 1 if index + 1 < cuts.size else n  # the piece after ends here
        # the piece after is k .. last, the piece before first .. k+1
        k = _best(score, max(last - piece_segments, first + CUT_REACH),
                  min(first + piece_segments, last - CUT_REACH), excluded)
        if k < 0:
            rest = _greedy(score, piece_segments, first, excluded)
            if rest is not None:
                return np.asarray(list(cuts[:index]) + rest, dtype=int)
            whole = _greedy(score, piece_segments, 0, excluded)  # the earlier cuts must move too
            return np.asarray(whole or [], dtype=int)
        cuts[index] = k
    return cuts


def wrong_cuts(lam_x: np.ndarray, scale: np.ndarray, free: np.ndarray, row_inactive: np.ndarray) -> np.ndarray:
    """Which cuts are not a KKT point of the whole NLP.

    Parameters
    ----------
    lam_x, scale : numpy.ndarray, shape (K, 2)
        From :func:`cut_multipliers`.
    free : numpy.ndarray of bool, shape (K, 2)
        Whether each fixed speed's lower bound is below its upper bound (a speed its band
        fixes anyway may take a multiplier of either sign).
    row_inactive : numpy.ndarray of bool, shape (K,)
        Whether the acceleration of the segment between each fixed pair is strictly inside
        its bounds (its multiplier is then 0, as :func:`cut_multipliers` takes it).

    Returns
    -------
    numpy.ndarray of int
        Indices into the cuts, increasing. A multiplier counts as negative below -1e-6 of
        the size of the terms that make it (IPOPT's tolerance is far tighter).
    """
    negative = (lam_x < -1e-6 * scale - 1e-12) & free
    return np.flatnonzero(np.any(negative, axis=1) | ~row_inactive)


def piece_bounds(cuts: np.ndarray, n: int) -> list[tuple[int, int]]:
    """The pieces (first boundary, last boundary) of a route of ``n`` segments cut at
    ``cuts`` (see :func:`choose_cuts`): consecutive pieces share the fixed pair k, k+1.

    Parameters
    ----------
    cuts : numpy.ndarray of int, shape (K,)
        Increasing segment indices of the cuts.
    n : int
        Number of segments of the route.

    Returns
    -------
    list of tuple of (int, int)
        K + 1 pairs (first, last) of boundary indices: the first piece starts at 0, piece p
        ends at ``cuts[p] + 1`` and the next starts at ``cuts[p]``, the last ends at ``n``.
    """
    starts = [0] + [int(k) for k in cuts]
    ends = [int(k) + 1 for k in cuts] + [n]
    return list(zip(starts, ends))


def cut_multipliers(grad_f: ca.Function, jac_g: ca.Function, y: np.ndarray, p_tail: np.ndarray,
                    length_scaled: np.ndarray, lam_accel: np.ndarray, lam_jerk: np.ndarray | None,
                    cuts: np.ndarray, data: np.ndarray | None = None, lam_rows: np.ndarray | None = None,
                    ) -> tuple[np.ndarray, np.ndarray]:
    """The whole NLP's bound multipliers on the fixed pairs of a joined piecewise solution.

    Parameters
    ----------
    grad_f, jac_g : casadi.Function
        ``nlp_grad_f`` (x, p) -> (f, grad f) and ``nlp_jac_g`` (x, p) -> (g, J) of the NLP
        of :func:`profileopt.planning.nlp.problem.build_nlp` for 5 segments (with the route's jerk setting).
    y : numpy.ndarray, shape (N+1,)
        The joined solution, scaled (b / b_ref).
    p_tail : numpy.ndarray, shape (6,)
        The parameters after the segment lengths (:data:`profileopt.planning.nlp.problem.PARAMETERS`), with
        the T_ref the multipliers are scaled for.
    length_scaled : numpy.ndarray, shape (N,)
        Segment lengths / L_ref.
    lam_accel : numpy.ndarray, shape (N,)
        Multipliers of the acceleration rows (segment i), for that T_ref.
    lam_jerk : numpy.ndarray, shape (N+1,) or None
        Multipliers of the jerk rows by boundary j (entries 0 and N unused); None without
        jerk rows.
    cuts : numpy.ndarray of int, shape (K,)
    data : numpy.ndarray, shape (N, D), optional
        The row families' data of every segment (the NLP's ``families``).
    lam_rows : numpy.ndarray, shape (R, N), optional
        Multipliers of the families' rows, row after row of the families.

    Returns
    -------
    lam_x : numpy.ndarray, shape (K, 2)
        -(grad f + J^T lam_g) of the whole NLP w.r.t. y_k and y_{k+1} at each cut; >= 0 is
        the sign of an active upper bound (the cut is right).
    scale : numpy.ndarray, shape (K, 2)
        The sum of the magnitudes of the terms that make up each entry, to judge how close
        to zero a small value is.

    Notes
    -----
    Every term and row that involves b_k or b_{k+1} lies within boundaries k-2 .. k+3, so
    the 5-segment NLP over that window gives their derivatives exactly; the rows of the
    window that do not touch the pair have zero derivative w.r.t. it.
    """
    lam_x = np.empty((cuts.size, 2))
    scale = np.empty((cuts.size, 2))
    for row, k in enumerate(cuts):
        window = slice(k - 2, k + 4)
        x = y[window]
        middle = [] if data is None else [data[k - 2:k + 3].T.ravel()]
        p = np.concatenate([length_scaled[k - 2:k + 3], *middle, p_tail])
        lam = [lam_accel[k - 2:k + 3]]
        if lam_jerk is not None:
            lam.append(lam_jerk[k - 1:k + 3])
        if lam_rows is not None:
            lam.extend(lam_rows[:, k - 2:k + 3])
        lam_g = np.concatenate(lam)
        grad = np.asarray(grad_f(x, p)[1]).ravel()[2:4]
        jac = np.asarray(ca.DM(jac_g(x, p)[1]).full())[:, 2:4]
        if jac.shape[0] != lam_g.size:
            raise ValueError(f"the 5-segment NLP has {jac.shape[0]} rows, {lam_g.size} multipliers given")
        lam_x[row] = -(grad + jac.T @ lam_g)
        scale[row] = np.abs(grad) + np.abs(jac.T) @ np.abs(lam_g)
    return lam_x, scale


def solve_pieces(length_m: np.ndarray, chosen: "BandChoice", decel_mps2: np.ndarray, accel_mps2: np.ndarray,
                 scaling: "Scaling", with_jerk: bool, score: np.ndarray, cuts: np.ndarray,
                 options: "SolverOptions", timings: dict[str, float], rows: dict[str, np.ndarray] | None = None,
                 ) -> tuple[np.ndarray | None, int, int, int]:
    """The NLP solved piece by piece between the fixed pairs at ``cuts``, each piece in the
    one NLP of ``options.piece_size()`` segments: the piece's boundaries, then (behind it, or in front of the last piece)
    padding boundaries fixed at the neighbouring fixed speed, whose rows are unbounded and
    whose terms involve fixed variables only. A cut that is not a KKT point of the whole
    problem, or beside a piece IPOPT cannot solve, is replaced by another between its
    neighbours (or, if there is none, the cuts from the one before it onwards are chosen
    again without it) and the changed pieces are solved again. Returns (b, iterations,
    pieces, taken_over); b is None when no set of cuts checks out within ``options.cut_rounds``
    rounds.

    Parameters
    ----------
    length_m : numpy.ndarray, shape (N,)
        Segment lengths (m).
    chosen : BandChoice
        Bounds on b and the greatest profile (the start point).
    decel_mps2, accel_mps2 : numpy.ndarray, shape (N,)
        Acceleration bounds of each segment (m/s^2).
    scaling : Scaling
        The NLP's scales for the whole route.
    with_jerk : bool
        Whether the jerk rows are on.
    score : numpy.ndarray, shape (N,)
        :func:`cut_scores` of the route.
    cuts : numpy.ndarray of int
        The first guess of cut segments (:func:`choose_cuts`).
    options : SolverOptions
        Piece size, rounds and IPOPT options.
    timings : dict
        ``build`` and ``solve`` seconds are added here.
    rows : dict of str to numpy.ndarray, shape (N, D_f), optional
        Row families of the NLP and their per-segment data (:data:`~profileopt.physics.rows.ROW_FAMILIES`):
        padding segments get their :attr:`~profileopt.physics.rows.RowFamily.neutral` data, a cut's own rows must be inactive
        (as its acceleration row), and their multipliers enter the cut check.

    Returns
    -------
    (b, iterations, pieces, taken_over) : tuple
        b (m^2/s^2), shape (N+1,), or None; NLP iterations of all the solves; the pieces of b;
        how many of them IPOPT solved where the chosen back end had stopped
        (:func:`~.solve.solve_nlp`).
    """
    n, w = length_m.size, options.piece_size()
    rows = rows or {}
    families = tuple(rows)
    data = np.column_stack(list(rows.values())) if rows else None
    neutral = np.concatenate([ROW_FAMILIES[f].neutral for f in families]) if rows else None
    n_family = sum(ROW_FAMILIES[f].count for f in families)  # family rows per segment
    t = time.perf_counter()
    nlp_with_jerk = with_jerk and w >= 2
    check = cached_nlp(5, with_jerk, options.ipopt_key(), families)
    grad_f, jac_g = check.get_function("nlp_grad_f"), check.get_function("nlp_jac_g")
    timings["build"] += time.perf_counter() - t
    t = time.perf_counter()
    piece_timings = {"build": 0.0, "solve": 0.0}  # the pieces' solver builds, moved to "build" below
    b_ref, l_ref = scaling.b_ref, scaling.l_ref
    lower, upper, start_b = chosen.lower_b / b_ref, chosen.upper_b / b_ref, chosen.greatest_b / b_ref
    length = length_m / l_ref
    t_whole = scaling.t_whole
    lbg_route, ubg_route = -decel_mps2 / scaling.a_ref, accel_mps2 / scaling.a_ref  # the route's accel rows
    n_rows = w + (w - 1 if nlp_with_jerk else 0)
    first_family = n_rows
    n_rows += n_family * w
    solved: dict[tuple[int, int], tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray | None]] = {}
    iterations, cuts, tried = 0, cuts.copy(), set()
    taken_over: set[tuple[int, int]] = set()  # pieces IPOPT solved after the chosen back end stopped

    def solve(first: int, last: int) -> bool:
        nonlocal iterations
        count, is_first, is_last = last - first, first == 0, last == n
        offset = w - count if is_last else 0  # the last piece is padded in front, the others behind
        real = slice(offset, offset + count + 1)
        x0, lbx, ubx = (np.full(w + 1, upper[first] if is_last else upper[last]) for _ in range(3))
        x0[real], lbx[real], ubx[real] = start_b[first:last + 1], lower[first:last + 1], upper[first:last + 1]
        fixed = ([] if is_first else [first, first + 1]) + ([] if is_last else [last - 1, last])
        for k in fixed:  # the cut pairs, at their caps
            lbx[offset + k - first] = ubx[offset + k - first] = x0[offset + k - first] = upper[k]
        p_length = np.ones(w)
        p_length[offset:offset + count] = length[first:last]
        lbg, ubg = np.full(n_rows, -np.inf), np.full(n_rows, np.inf)  # padding rows: unbounded
        accel_rows = slice(offset, offset + count)
        jerk_rows = slice(w + offset, w + offset + count - 1)  # interior boundaries offset+1 .. offset+count-1
        lbg[accel_rows], ubg[accel_rows] = lbg_route[first:last], ubg_route[first:last]
        if nlp_with_jerk:
            lbg[jerk_rows], ubg[jerk_rows] = -1.0, 1.0
        family_rows_real = [slice(first_family + r * w + offset, first_family + r * w + offset + count)
                            for r in range(n_family)]  # each family row's entries of the real segments
        extra = ()
        if data is not None:
            piece_data = np.tile(neutral, (w, 1))
            piece_data[offset:offset + count] = data[first:last]
            extra = (piece_data,)
            for real_rows in family_rows_real:
                ubg[real_rows] = 1.0
        t_ref = max(objective_s(chosen.greatest_b[first:last + 1], length_m[first:last], 0.0), 1e-6)
        result = solve_nlp(w, with_jerk, families, options, x0, lbx, ubx, p_length, lbg, ubg, scaling.tail(t_ref),
                           *extra, timings=piece_timings)
        iterations += result.iterations
        if result.success and "stopped" in result.solver:
            taken_over.add((first, last))
        if result.success:
            rescale = t_ref / t_whole  # multipliers of f / t_ref, expressed for f / t_whole
            lam_family = (np.array([result.lam_g[r] for r in family_rows_real]) * rescale if n_family else None)
            solved[first, last] = (result.y[real], result.lam_g[accel_rows] * rescale,
                                   result.lam_g[jerk_rows] * rescale, lam_family)
        return result.success

    a_cut = segment_accel_mps2(chosen.upper_b[:-1], chosen.upper_b[1:], length_m)  # between fixed pairs
    row_inside = (a_cut < accel_mps2 * (1 - 1e-9)) & (-a_cut < decel_mps2 * (1 - 1e-9))
    for family, family_data in rows.items():  # a cut's own family rows, constant there, inactive too
        row_inside &= family_rows(family, chosen.upper_b, length_m, family_data).max(axis=0) < 1 - 1e-9
    try:
        for round_ in range(options.cut_rounds + 1):
            pieces = piece_bounds(cuts, n)
            failed = [i for i, (first, last) in enumerate(pieces) if not ((first, last) in solved or solve(first, last))]
            if failed:  # a piece IPOPT cannot solve: the cuts beside it are suspect
                wrong = np.array(sorted({c for i in failed for c in (i - 1, i) if 0 <= c < cuts.size}), dtype=int)
            else:
                y, lam_accel = np.empty(n + 1), np.zeros(n)
                lam_jerk = np.zeros(n + 1) if nlp_with_jerk else None
                lam_rows = np.zeros((n_family, n)) if n_family else None
                for first, last in pieces:
                    y[first:last + 1], lam_accel[first:last], lam_piece_jerk, lam_piece_rows = solved[first, last]
                    if lam_jerk is not None:
                        lam_jerk[first + 1:last] = lam_piece_jerk
                    if lam_rows is not None:
                        lam_rows[:, first:last] = lam_piece_rows
                lam_accel[cuts] = 0.0  # the rows between fixed pairs (checked inactive below)
                if lam_rows is not None:
                    lam_rows[:, cuts] = 0.0
                with_rows = {"data": data, "lam_rows": lam_rows} if rows else {}
                lam_x, scale = cut_multipliers(grad_f, jac_g, y, scaling.tail(t_whole), length, lam_accel,
                                               lam_jerk, cuts, **with_rows)
                pair = np.stack([cuts, cuts + 1], axis=1)
                wrong = wrong_cuts(lam_x, scale, lower[pair] < upper[pair], row_inside[cuts])
                if wrong.size == 0:
                    return y * b_ref, iterations, len(pieces), len(taken_over.intersection(pieces))
            if round_ == options.cut_rounds:
                break
            tried.update(int(k) for k in cuts[wrong])
            cuts = replace_cuts(score, cuts, wrong, w, tried)
            if cuts.size == 0:
                break
        return None, iterations, 0, 0
    finally:
        timings["solve"] += time.perf_counter() - t - piece_timings["build"]
        timings["build"] += piece_timings["build"]
