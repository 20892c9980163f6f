"""Allowable speeds: where a force model's prediction meets the vehicle's limit.

For one terrain value (RI) the admissible speeds of a model are the V in [0, v_max] with
F(V) <= F_limit. For a monotone model that is one interval [0, V*]; a lightly damped
suspension (SBEM:TF near resonance) can split it into several *bands*. This module finds
every band edge, for many RI values at once, with Newton's method on exact CasADi
derivatives of the model's own expression, safeguarded by bracketing so that it always
converges:

1. evaluate g(V) = F(V) / F_limit - 1 and g'(V) on a grid of speeds (0 and a log-spaced
   grid up to v_max, so that features at every speed scale are seen);
2. where g' changes sign between grid points, find the extremum (safeguarded Newton on g'
   with g''), so that between consecutive candidate points g is monotone and a peak above
   the limit between two admissible grid points cannot be missed;
3. every sign change of g between consecutive candidates brackets exactly one root;
   refine it with safeguarded Newton on g.

docs/paper-notes.md ("Which root") defines the bands of :func:`allowable_speed` (``band``, one of
:data:`BAND_CHOICES`).
"""

from __future__ import annotations

import dataclasses
import functools
from typing import TYPE_CHECKING, Callable, Literal

import casadi as ca
import numpy as np
from numpy.typing import ArrayLike

from ..core.symbolic import numpy_evaluator
from ..core.vehicle import require_vehicle
from ..errors import InputError
from ..terrain.roughness import check_ri, range_extremes, worst_case_elevation
from .forces import DEFAULT_MODEL, get_model, sbem_tf_crawl_bound_n

if TYPE_CHECKING:
    from ..core.vehicle import Vehicle

__all__ = ["BAND_CHOICES", "SpeedBands", "BandMemo", "speed_bands", "speed_bands_reusing", "allowable_speed",
           "safeguarded_newton", "max_force_over_segments", "speed_bands_of_sets", "max_force_of_sets", "PAIR_BLOCK"]

#: Which admissible band(s) of speeds: ``"first"`` the band from rest (every speed from 0 up
#: to its upper edge is admissible), ``"largest"`` the highest band, ``"all"`` every band
#: (meaningful only to the route planner, which chooses among them).
BAND_CHOICES = ("first", "largest", "all")

Band = Literal["first", "largest", "all"]

#: Points of the log-spaced search grid, spanning 6 decades below v_max (ratio 1.07 between
#: neighbours): far finer than a resonance peak (relative width ~ zeta) for zeta >= 0.02.
GRID_POINTS = 200
GRID_DECADES = 6.0


@dataclasses.dataclass(frozen=True)
class SpeedBands:
    """Admissible speed bands of a model for many terrain values.

    Row i lists the disjoint intervals [lower_mps[i, j], upper_mps[i, j]] of speeds whose
    predicted force is within the limit, in increasing order, padded with NaN.

    Attributes
    ----------
    lower_mps, upper_mps : numpy.ndarray, shape (N, B)
        Band edges (m/s); B is the largest number of bands of any row (at least 1).
    count : numpy.ndarray of int, shape (N,)
        Number of bands of each row (0: no admissible speed at all).
    peaks_mps : numpy.ndarray, shape (N, P)
        Speeds (m/s) of the interior local maxima of the force in (0, v_max), NaN-padded
        (P >= 1). With the band edges and the ends of a speed interval they locate the
        largest force over that interval (:meth:`max_force_speed`).
    """

    lower_mps: np.ndarray
    upper_mps: np.ndarray
    count: np.ndarray
    peaks_mps: np.ndarray

    def starts_at_rest(self) -> np.ndarray:
        """Whether the lowest band of each row starts at 0 m/s, shape (N,) of bool."""
        return (self.count > 0) & (self.lower_mps[:, 0] == 0.0)

    def first(self) -> np.ndarray:
        """Largest V with every speed in [0, V] admissible (m/s), shape (N,); 0 if none."""
        return np.where(self.starts_at_rest(), self.upper_mps[:, 0], 0.0)

    def first_band_only(self) -> "SpeedBands":
        """The same rows keeping only the band that starts at rest (``band="first"``)."""
        rest = self.starts_at_rest()
        return dataclasses.replace(
            self,
            lower_mps=np.where(rest, self.lower_mps[:, 0], np.nan)[:, None],
            upper_mps=np.where(rest, self.upper_mps[:, 0], np.nan)[:, None],
            count=rest.astype(self.count.dtype),
        )

    def largest_band_only(self) -> "SpeedBands":
        """The same rows keeping only the highest band (``band="largest"``); rows without
        any band stay empty."""
        has = self.count > 0
        rows = np.arange(self.count.size)
        last = np.maximum(self.count - 1, 0)
        return dataclasses.replace(
            self,
            lower_mps=np.where(has, self.lower_mps[rows, last], np.nan)[:, None],
            upper_mps=np.where(has, self.upper_mps[rows, last], np.nan)[:, None],
            count=has.astype(self.count.dtype),
        )

    def capped(self, cap_mps: np.ndarray) -> "SpeedBands":
        """Every band intersected with [0, cap]: upper edges clipped, bands starting above
        the cap dropped.

        Parameters
        ----------
        cap_mps : numpy.ndarray, shape (N,)
            The cap of each row (m/s).
        """
        cap = np.asarray(cap_mps, dtype=float)[:, None]
        keep = self.lower_mps <= cap  # NaN compares False: padding stays dropped
        return dataclasses.replace(
            self,
            lower_mps=np.where(keep, self.lower_mps, np.nan),
            upper_mps=np.where(keep, np.minimum(self.upper_mps, cap), np.nan),
            count=keep.sum(axis=1),
        )

    def largest(self) -> np.ndarray:
        """Largest admissible speed <= v_max (m/s), shape (N,); 0 if none."""
        last = np.maximum(self.count - 1, 0)
        top = self.upper_mps[np.arange(self.count.size), last]
        return np.where(self.count > 0, top, 0.0)


@functools.lru_cache(maxsize=64)
def _constraint_derivatives(model: str, vehicle: "Vehicle", envelope: bool = False
                            ) -> tuple[ca.Function, ca.Function]:
    """g = F / F_limit - 1 with its speed derivative, and g' with g'' (exact, CasADi).

    The terrain inputs are ``ri``, or with ``envelope`` ``ri_min`` and ``ri`` (the force is
    then the largest over the RI range, :meth:`profileopt.physics.forces.ForceModel.envelope_force_n`).
    """
    spec = get_model(model)
    v, ri = ca.SX.sym("speed_mps"), ca.SX.sym("ri")
    if envelope:
        ri_min = ca.SX.sym("ri_min")
        terrain, names = [ri_min, ri], ["ri_min", "ri"]
        force = spec.envelope_force_n(v, ri_min, ri, vehicle)
    else:
        terrain, names = [ri], ["ri"]
        force = spec.force_n(v, ri, vehicle)
    g = force / spec.limit_n(vehicle) - 1.0
    dg = ca.jacobian(g, v)
    d2g = ca.jacobian(dg, v)
    suffix = "_envelope" if envelope else ""
    return (
        ca.Function(f"{model}{suffix}_g", [v, *terrain], [g, dg], ["speed_mps", *names], ["g", "dg"]),
        ca.Function(f"{model}{suffix}_dg", [v, *terrain], [dg, d2g], ["speed_mps", *names], ["dg", "d2g"]),
    )


@functools.lru_cache(maxsize=64)
def _constraint_evaluators(model: str, vehicle: "Vehicle", envelope: bool = False) -> tuple[Callable, Callable]:
    """numpy evaluators of the two Functions of :func:`_constraint_derivatives`.

    They run those Functions' own instruction lists on whole arrays
    (:func:`profileopt.core.symbolic.numpy_evaluator`), bitwise equal to CasADi's evaluation.
    """
    return tuple(numpy_evaluator(fun) for fun in _constraint_derivatives(model, vehicle, envelope))


def _mapped(evaluate: Callable, x: np.ndarray, terrain: tuple[np.ndarray, ...]) -> tuple[np.ndarray, np.ndarray]:
    """Evaluate a two-output scalar Function at many points; ``x`` and the ``terrain``
    arrays broadcast together, and both outputs have their broadcast shape."""
    a, b = evaluate(x, *terrain)
    return a, b


def safeguarded_newton(
    fun, lo: np.ndarray, hi: np.ndarray, f_lo: np.ndarray, *, xtol: float, max_iter: int = 200
) -> np.ndarray:
    """Roots of many scalar functions, each bracketed in [lo, hi], by Newton with bisection.

    Parameters
    ----------
    fun : callable
        ``fun(x, idx) -> (f, df)``: f and its derivative at ``x`` for the problems
        ``idx`` (indices into the K problems), all of shape ``idx.shape``.
    lo, hi : numpy.ndarray, shape (K,)
        Brackets with f(lo) and f(hi) of opposite sign (or one of them zero).
    f_lo : numpy.ndarray, shape (K,)
        f(lo).
    xtol : float
        Absolute tolerance on the root (same unit as x).
    max_iter : int
        Bisection alone halves the bracket each step, so 200 steps always suffice.

    Returns
    -------
    numpy.ndarray, shape (K,)
        The roots. A Newton step that would leave the bracket, or that does not shrink it
        fast enough, is replaced by a bisection step, so the iteration always converges.
    """
    lo, hi = lo.astype(float).copy(), hi.astype(float).copy()
    x = 0.5 * (lo + hi)
    sign_lo = np.sign(f_lo)
    active = np.ones(x.shape, dtype=bool)
    older_step = np.abs(hi - lo)  # the step before the last one (rtsafe's dxold)
    last_step = np.abs(hi - lo)
    for _ in range(max_iter):
        if not active.any():
            break
        idx = np.flatnonzero(active)
        f, df = fun(x[idx], idx)
        same = np.sign(f) == sign_lo[idx]
        lo[idx] = np.where(same, x[idx], lo[idx])
        hi[idx] = np.where(same, hi[idx], x[idx])
        with np.errstate(divide="ignore", invalid="ignore"):
            newton = x[idx] - f / df
        # Newton only if it stays inside the bracket and at least halves the step before
        # last (as in Numerical Recipes' rtsafe); otherwise bisect. Steps thus shrink at least
        # by half every two iterations (a bisection halves the bracket), so it converges.
        inside = np.isfinite(newton) & (newton > lo[idx]) & (newton < hi[idx])
        fast = np.abs(newton - x[idx]) <= 0.5 * older_step[idx]
        x_new = np.where(inside & fast, newton, 0.5 * (lo[idx] + hi[idx]))
        x_new = np.where(f == 0, x[idx], x_new)  # an exact root: keep it, do not bisect away
        step = np.abs(x_new - x[idx])
        older_step[idx], last_step[idx] = last_step[idx], step
        x[idx] = x_new
        done = (f == 0) | (step <= xtol) | (hi[idx] - lo[idx] <= xtol)
        active[idx[done]] = False
    return x


def speed_bands(ri: ArrayLike, vehicle: "Vehicle", *, model: str = DEFAULT_MODEL,
                ri_min: ArrayLike | None = None) -> SpeedBands:
    """Every band of admissible speeds of ``model`` for each RI value (or range of values).

    Parameters
    ----------
    ri : array_like, shape (N,) or scalar
        Roughness index of each terrain patch (dimensionless), >= 0; with ``ri_min`` the
        largest RI of each patch.
    vehicle : Vehicle
        Quarter car, force limits and top speed v_max.
    model : str, default ``"sbem_tf"`` (:data:`~profileopt.physics.forces.DEFAULT_MODEL`)
        ``"prev_bem"``, ``"iecm"``, ``"sbem_ef"`` or ``"sbem_tf"``.
    ri_min : array_like, shape (N,) or scalar, optional
        The least RI of each patch, 0 <= ri_min <= ri: the bands are then the speeds
        admissible for every RI of the range (those of the largest force over the range,
        :func:`profileopt.physics.forces.envelope_force_n`, an upper bound for SBEM:TF), for
        terrain known only to lie within the range (the online selector's unseen terrain). A
        segment's known windows are a set, not a range: :func:`speed_bands_of_sets`.

    Returns
    -------
    SpeedBands
        Band edges (m/s) within [0, v_max]; edges are roots to within 1e-12 v_max.

    Raises
    ------
    InputError
        Unknown ``model``, or a NaN or negative ``ri``.
    """
    vehicle = require_vehicle(vehicle, "speed_bands")
    return speed_bands_reusing(ri, vehicle, model=model, ri_min=ri_min)[0]


@dataclasses.dataclass(frozen=True)
class BandMemo:
    """The distinct terrain values of one :func:`speed_bands_reusing` call and their bands.

    Attributes
    ----------
    vehicle : Vehicle
        The vehicle they were found for (reused only for the same object).
    model : str
        The force model.
    form : int
        1: the bands of each RI; 2: of each RI range (ri_min, ri).
    keys : numpy.ndarray of complex, shape (K,)
        The distinct values, sorted: ri + 0j, or ri_min + ri j.
    bands : SpeedBands
        Their bands, row k for ``keys[k]``.
    """

    vehicle: "Vehicle"
    model: str
    form: int
    keys: np.ndarray
    bands: SpeedBands


def speed_bands_reusing(ri: ArrayLike, vehicle: "Vehicle", *, model: str = DEFAULT_MODEL,
                        ri_min: ArrayLike | None = None, memo: BandMemo | None = None
                        ) -> tuple[SpeedBands, BandMemo]:
    """:func:`speed_bands`, finding each distinct terrain value once and taking those an
    earlier call found from its memo.

    The bands of a row depend on its terrain values alone, so equal rows share them: a
    planner that refines its segments asks again for the segments it kept whole (about
    two fifths of the refined ones on the benchmark's route) and for pieces that meet the
    same windows. The result is exactly that of :func:`speed_bands` with the same arguments.

    Parameters
    ----------
    ri, vehicle, model, ri_min
        As for :func:`speed_bands`.
    memo : BandMemo, optional
        From an earlier call; used only when its vehicle (the same object), model and form
        are this call's.

    Returns
    -------
    bands : SpeedBands
        As :func:`speed_bands` returns them, shape (N, ...).
    memo : BandMemo
        This call's distinct values and bands, for the next call.
    """
    ri = np.atleast_1d(np.asarray(ri, dtype=float))
    check_ri(ri)
    spec = get_model(model)
    if ri_min is None or spec.monotone:  # a monotone model's range is its largest value
        terrain: tuple[np.ndarray, ...] = (ri,)
    else:
        low = np.broadcast_to(np.atleast_1d(np.asarray(ri_min, dtype=float)), ri.shape)
        check_ri(low)
        if np.any(low > ri):
            raise InputError("ri_min must not exceed ri (the least and the largest RI of each patch)")
        # where even a crawl cannot reach the limit the range changes no band: its top's
        # bands are exact (forces.sbem_tf_crawl_bound_n), found with the plain model
        # (the bound grows with e_max: the largest RI decides for every row)
        top = float(ri.max(initial=0.0))
        crawl = float(sbem_tf_crawl_bound_n(worst_case_elevation(top, vehicle), vehicle)) if top > 0 else 0.0
        if crawl <= spec.limit_n(vehicle):
            terrain = (ri,)
        else:
            terrain = (low, ri)
    # one complex key per row, ordered as (ri_min, ri) tuples are: equal rows, equal bands
    key = terrain[0] + 1j * terrain[1] if len(terrain) == 2 else terrain[0] + 0j
    keys, inverse = np.unique(key, return_inverse=True)
    known = np.full(keys.size, -1)
    if (memo is not None and memo.keys.size and memo.vehicle is vehicle and memo.model == model
            and memo.form == len(terrain)):
        at = np.minimum(np.searchsorted(memo.keys, keys), memo.keys.size - 1)
        known = np.where(memo.keys[at] == keys, at, -1)
    # (bands, rows of the distinct values they fill, their rows to take: None for all)
    sources: list[tuple[SpeedBands, np.ndarray, np.ndarray | None]] = []
    old = np.flatnonzero(known >= 0)
    if old.size:
        sources.append((memo.bands, old, known[old]))  # type: ignore[union-attr]
    new = np.flatnonzero(known < 0)
    if new.size or not old.size:  # (an empty call still makes its empty bands)
        values = (keys.real[new], keys.imag[new]) if len(terrain) == 2 else (keys.real[new],)
        sources.append((_blocked_bands(values, vehicle, model), new, None))
    distinct = SpeedBands(*(_rows_from([(getattr(b, name), rows, pick) for b, rows, pick in sources], keys.size)
                            for name in _BAND_FIELDS))
    bands = SpeedBands(*(_trimmed(getattr(distinct, name)[inverse]) for name in _BAND_FIELDS))
    return bands, BandMemo(vehicle, model, len(terrain), keys, distinct)


_BAND_FIELDS = ("lower_mps", "upper_mps", "count", "peaks_mps")


def speed_bands_of_sets(values: ArrayLike, first: ArrayLike, stop: ArrayLike, vehicle: "Vehicle", *,
                        model: str = DEFAULT_MODEL, memo: BandMemo | None = None) -> tuple[SpeedBands, BandMemo]:
    """Every band of speeds admissible for each RI of a set, for many sets: exact.

    Set i holds the RIs ``values[first[i]:stop[i]]`` (the roughness windows a segment of
    route meets: every speed driven on it must be admissible for each of them). Its bands are
    the intersection of its members' bands. For a model whose force grows with the RI that
    is the bands of the set's largest RI. SBEM:TF does not grow with the RI below the speed
    V_c = 2 wn r_w r_p / pi (:func:`profileopt.physics.forces.sbem_tf_envelope_force_n`),
    and above V_c it does; so a member can forbid a speed the largest RI allows only below
    V_c, and only if its crawl bound (:func:`profileopt.physics.forces.sbem_tf_crawl_bound_n`,
    growing with the RI) exceeds the limit. The bands of a set are those of its largest RI
    intersected with the bands of every such member: exactly the speeds admissible for every
    member, where the bound of :func:`speed_bands` with ``ri_min`` (the largest force over the
    whole RI range between the set's least and largest) forbids speeds that no member's force
    reaches the limit at.

    Parameters
    ----------
    values : array_like, shape (K,)
        RIs (dimensionless), >= 0.
    first, stop : array_like of int, shape (N,)
        Set i is ``values[first[i]:stop[i]]``, non-empty.
    vehicle : Vehicle
        Quarter car, force limits and top speed v_max.
    model : str, default ``"sbem_tf"``
        Force model key.
    memo : BandMemo, optional
        From an earlier call with the same vehicle and model (its RIs are not found again).

    Returns
    -------
    bands : SpeedBands
        Shape (N, ...): band edges (m/s) within [0, v_max]; ``peaks_mps`` of a set holds the
        peaks of each member it intersects (the largest force over the set has its local
        maxima among them).
    memo : BandMemo
        For the next call.

    Raises
    ------
    InputError
        Unknown ``model``, or a NaN or negative RI.
    """
    values = np.atleast_1d(np.asarray(values, dtype=float))
    check_ri(values)
    first = np.asarray(first, dtype=np.intp)
    stop = np.asarray(stop, dtype=np.intp)
    n = first.size
    _, top = range_extremes(values, first, stop) if n else (np.empty(0), np.empty(0))
    members = _crawl_members(values, first, stop, top, vehicle, model)
    wanted = np.concatenate([top, values[members.window]])
    found, memo = speed_bands_reusing(wanted, vehicle, model=model, memo=memo)
    if not members.window.size:
        return found, memo
    mine = SpeedBands(*(getattr(found, name)[n:] for name in _BAND_FIELDS))
    rows = np.flatnonzero(members.counts)
    # the pairs (set, member) a block of sets at a time: a short segment meets hundreds of
    # windows, so a refined route has millions of pairs; each set's result is its own
    lower_parts, upper_parts, count_parts, peak_parts = [], [], [], []
    for r0, r1 in members.blocks(PAIR_BLOCK):
        pair_row, member = members.pairs(r0, r1)
        lower_b, upper_b, count_b = _intersected(mine, pair_row, member, r1 - r0)
        lower_parts.append(lower_b)
        upper_parts.append(upper_b)
        count_parts.append(count_b)
        peak_parts.append(_peaks_of_pairs(mine.peaks_mps[member], pair_row, r1 - r0))
    lower, upper, count = _stack_padded(lower_parts), _stack_padded(upper_parts), np.concatenate(count_parts)
    bands = SpeedBands(*(getattr(found, name)[:n] for name in _BAND_FIELDS))
    width = max(bands.lower_mps.shape[1], lower.shape[1])
    lower_all = _widened(bands.lower_mps, width)
    upper_all = _widened(bands.upper_mps, width)
    lower_all[rows], upper_all[rows] = _widened(lower, width), _widened(upper, width)
    counts = bands.count.copy()
    counts[rows] = count
    mine_peaks = _stack_padded(peak_parts)
    peak_width = max(bands.peaks_mps.shape[1], mine_peaks.shape[1])
    peaks = _widened(bands.peaks_mps, peak_width)
    peaks[rows] = _widened(mine_peaks, peak_width)
    return SpeedBands(lower_mps=_trimmed(lower_all), upper_mps=_trimmed(upper_all), count=counts,
                      peaks_mps=_trimmed(peaks)), memo


def max_force_of_sets(values: ArrayLike, first: ArrayLike, stop: ArrayLike, speed_mps: np.ndarray,
                      vehicle: "Vehicle", *, model: str = DEFAULT_MODEL, memo: BandMemo | None = None) -> np.ndarray:
    """Largest predicted force over the speeds between each segment's two boundary speeds and
    over every RI of its set (as :func:`speed_bands_of_sets`), in N.

    For each member the force over a speed interval is largest at an end or at one of the
    member's own interior maxima (:func:`max_force_over_segments`); the set's force is the
    largest of its members'. Only the members that :func:`speed_bands_of_sets` intersects
    can exceed the force of the set's largest RI, so only they are evaluated beside it.

    Parameters
    ----------
    values, first, stop
        The sets, as for :func:`speed_bands_of_sets`.
    speed_mps : numpy.ndarray, shape (N+1,)
        Speeds at the segment boundaries (m/s).
    vehicle : Vehicle
    model : str, default ``"sbem_tf"``
    memo : BandMemo, optional
        From :func:`speed_bands_of_sets` on the same sets (the members' peaks are not found
        again).

    Returns
    -------
    numpy.ndarray, shape (N,)
        Force (N).
    """
    values = np.atleast_1d(np.asarray(values, dtype=float))
    first = np.asarray(first, dtype=np.intp)
    stop = np.asarray(stop, dtype=np.intp)
    speed = np.asarray(speed_mps, dtype=float)
    _, top = range_extremes(values, first, stop)
    members = _crawl_members(values, first, stop, top, vehicle, model)
    wanted = np.concatenate([top, values[members.window]])
    found, _ = speed_bands_reusing(wanted, vehicle, model=model, memo=memo)
    n = first.size
    force = max_force_over_segments(model, vehicle, top, speed, found.peaks_mps[:n])
    if not members.window.size:
        return force
    rows = np.flatnonzero(members.counts)
    member_ri, member_peaks = values[members.window], found.peaks_mps[n:]
    best = np.full(rows.size, -np.inf)
    for r0, r1 in members.blocks(PAIR_BLOCK):  # as speed_bands_of_sets: a block of sets at a time
        pair_row, member = members.pairs(r0, r1)
        segment = rows[r0:r1][pair_row]
        pair_force = _max_force_between(model, vehicle, member_ri[member], speed[:-1][segment], speed[1:][segment],
                                        member_peaks[member])
        np.maximum.at(best[r0:r1], pair_row, pair_force)
    force[rows] = np.maximum(force[rows], best)
    return force


@dataclasses.dataclass(frozen=True)
class _Members:
    """The members of each set that can forbid a speed its largest RI allows.

    ``window`` lists them (indices into the values, in order); set i holds
    ``window[offset[i]:offset[i] + counts[i]]``."""

    window: np.ndarray
    counts: np.ndarray
    offset: np.ndarray

    def blocks(self, max_pairs: int) -> list[tuple[int, int]]:
        """Consecutive ranges [r0, r1) of the sets that have members (ranks among them), each
        with at most ``max_pairs`` (set, member) pairs, or one set."""
        cum = np.concatenate([[0], np.cumsum(self.counts[self.counts > 0])])
        out, r0 = [], 0
        while r0 < cum.size - 1:
            r1 = max(int(np.searchsorted(cum, cum[r0] + max_pairs, side="right")) - 1, r0 + 1)
            out.append((r0, r1))
            r0 = r1
        return out

    def pairs(self, r0: int, r1: int) -> tuple[np.ndarray, np.ndarray]:
        """The (set, member) pairs of the sets of ranks r0 to r1 - 1 among those that have
        members: each pair's set (rank - r0) and its member's index into ``window``."""
        have = self.counts > 0
        counts, offset = self.counts[have][r0:r1], self.offset[have][r0:r1]
        pair_row = np.repeat(np.arange(counts.size), counts)
        within = np.arange(pair_row.size) - np.repeat(np.cumsum(counts) - counts, counts)
        return pair_row, np.repeat(offset, counts) + within


def _crawl_members(values: np.ndarray, first: np.ndarray, stop: np.ndarray, top: np.ndarray, vehicle: "Vehicle",
                   model: str) -> _Members:
    """The members whose crawl bound exceeds the limit, of the sets whose largest RI's does
    (none for a model that grows with the RI)."""
    spec = get_model(model)
    none = _Members(np.empty(0, dtype=np.intp), np.zeros(first.size, dtype=np.intp), np.zeros(first.size, dtype=np.intp))
    if spec.monotone or not values.size or not first.size:
        return none
    limit = spec.limit_n(vehicle)
    over = np.asarray(sbem_tf_crawl_bound_n(worst_case_elevation(values, vehicle), vehicle), dtype=float) > limit
    ranked = np.concatenate([[0], np.cumsum(over)])
    begin, end = ranked[first], ranked[stop]
    counts = np.where(np.asarray(sbem_tf_crawl_bound_n(worst_case_elevation(top, vehicle), vehicle)) > limit,
                      end - begin, 0).astype(np.intp)
    if not counts.any():
        return none
    return _Members(np.flatnonzero(over), counts, begin.astype(np.intp))


def _intersected(member_bands: SpeedBands, pair_row: np.ndarray, pair_member: np.ndarray, rows: int
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The intersection of the bands of each row's members: a sweep over their band edges.

    A speed lies in the intersection when every member of its row has a band holding it, so
    the count of bands open there (each member's bands are disjoint: it adds at most one)
    equals the row's number of members. Edges are sorted by row, speed and then closings
    before openings: two bands that only touch give no band of zero width.
    """
    lower = member_bands.lower_mps[pair_member]
    upper = member_bands.upper_mps[pair_member]
    has = ~np.isnan(lower)
    row = np.broadcast_to(pair_row[:, None], lower.shape)[has]
    events_row = np.concatenate([row, row])
    events_v = np.concatenate([lower[has], upper[has]])
    delta = np.concatenate([np.ones(row.size, dtype=np.intp), -np.ones(row.size, dtype=np.intp)])
    order = np.lexsort((delta, events_v, events_row))
    events_row, events_v, delta = events_row[order], events_v[order], delta[order]
    open_now = np.cumsum(delta)  # each row's events sum to 0: the count restarts at every row
    need = np.bincount(pair_row, minlength=rows)
    starts = np.flatnonzero((delta > 0) & (open_now == need[events_row]))
    # the next event closes it (no row has more than `need` open)
    band_row = events_row[starts]
    band_lo, band_hi = events_v[starts], events_v[starts + 1]
    count = np.bincount(band_row, minlength=rows)
    return _ragged_to_padded(band_row, band_lo, rows), _ragged_to_padded(band_row, band_hi, rows), count


def _widened(values: np.ndarray, width: int) -> np.ndarray:
    """A NaN-padded (n, w) array padded to ``width`` columns (a copy)."""
    return np.pad(values, ((0, 0), (0, width - values.shape[1])), constant_values=np.nan)


def _peaks_of_pairs(pair_peaks: np.ndarray, pair_row: np.ndarray, rows: int) -> np.ndarray:
    """The distinct peaks (m/s) of each of ``rows`` rows' pairs, sorted, NaN-padded, shape
    (rows, P): ``pair_peaks`` (pairs, Q) holds each pair's, ``pair_row`` its row."""
    has = ~np.isnan(pair_peaks)
    row = np.broadcast_to(pair_row[:, None], pair_peaks.shape)[has]
    speed = pair_peaks[has]
    pairs = np.unique(np.stack([row.astype(float), speed], axis=1), axis=0)
    return _ragged_to_padded(pairs[:, 0].astype(np.intp), pairs[:, 1], rows)


def _blocked_bands(terrain: tuple[np.ndarray, ...], vehicle: "Vehicle", model: str) -> SpeedBands:
    """:func:`_speed_bands` in blocks of :data:`_BLOCK_ROWS` rows (rows are independent:
    this bounds the (rows x grid) temporaries)."""
    if terrain[0].size <= _BLOCK_ROWS:
        return _speed_bands(terrain, vehicle, model)
    blocks = [_speed_bands(tuple(t[i:i + _BLOCK_ROWS] for t in terrain), vehicle, model)
              for i in range(0, terrain[0].size, _BLOCK_ROWS)]
    return SpeedBands(*(_stack_padded([getattr(b, name) for b in blocks]) for name in _BAND_FIELDS))


def _rows_from(parts: list[tuple[np.ndarray, np.ndarray, np.ndarray | None]], n: int) -> np.ndarray:
    """An (n, width) NaN-padded array (or counts, (n,)) assembled from ``parts``: for each
    (source, rows, pick), its rows ``rows`` are the rows ``pick`` of ``source`` (all of them,
    in order, for None)."""
    if parts[0][0].ndim == 1:
        out = np.zeros(n, dtype=parts[0][0].dtype)
    else:
        out = np.full((n, max(source.shape[1] for source, _, _ in parts)), np.nan)
    for source, rows, pick in parts:
        taken = source if pick is None else source[pick]
        if taken.ndim == 1:
            out[rows] = taken
        else:
            out[rows, :taken.shape[1]] = taken
    return out


def _trimmed(values: np.ndarray) -> np.ndarray:
    """A NaN-padded (n, width) array without the columns that are NaN in every row (at least
    one column, as :func:`_ragged_to_padded` makes them); counts unchanged."""
    if values.ndim == 1:
        return values
    used = int(np.max(np.sum(~np.isnan(values), axis=1), initial=0))
    return values[:, :max(used, 1)]


#: RI values whose bands are found together; the work arrays are (rows x 2 grid points).
_BLOCK_ROWS = 2048
#: (segment, window) pairs intersected together (:func:`speed_bands_of_sets`): the work
#: arrays are a few times this long.
PAIR_BLOCK = 1 << 18


def _stack_padded(parts: list[np.ndarray]) -> np.ndarray:
    """Stack row blocks of NaN-padded (rows, width) arrays (or 1-D counts) into one."""
    if parts[0].ndim == 1:
        return np.concatenate(parts)
    width = max(p.shape[1] for p in parts)
    return np.concatenate([np.pad(p, ((0, 0), (0, width - p.shape[1])), constant_values=np.nan) for p in parts])


def _speed_bands(terrain: tuple[np.ndarray, ...], vehicle: "Vehicle", model: str) -> SpeedBands:
    """:func:`speed_bands` for validated terrain values, ``(ri,)`` or ``(ri_min, ri)``, each
    of shape (N,), all at once."""
    n = terrain[-1].size
    vmax = vehicle.max_speed_mps
    value_slope, slope_curvature = _constraint_evaluators(model, vehicle, len(terrain) == 2)
    columns = tuple(t[:, None] for t in terrain)
    xtol = 1e-12 * vmax

    grid = np.concatenate([[0.0], vmax * np.logspace(-GRID_DECADES, 0.0, GRID_POINTS)])
    k = grid.size
    v = np.broadcast_to(grid, (n, k))
    g, dg = _mapped(value_slope, grid[None, :], columns)  # (n, k) each

    # 2. interior extrema: g' changes sign inside a grid interval
    cand = np.empty((n, 2 * k - 1))
    cand[:, 0::2] = v
    cand[:, 1::2] = v[:, :-1]  # placeholder: a duplicate of the left point changes nothing
    gc = np.empty_like(cand)
    gc[:, 0::2] = g
    gc[:, 1::2] = g[:, :-1]
    rows, cols = np.nonzero(dg[:, :-1] * dg[:, 1:] < 0)
    if rows.size:
        def slope(x: np.ndarray, idx: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            return _mapped(slope_curvature, x, tuple(t[rows[idx]] for t in terrain))

        ext = safeguarded_newton(slope, v[rows, cols], v[rows, cols + 1], dg[rows, cols], xtol=xtol)
        g_ext = _mapped(value_slope, ext, tuple(t[rows] for t in terrain))[0]
        cand[rows, 2 * cols + 1] = ext
        gc[rows, 2 * cols + 1] = g_ext
        is_peak = dg[rows, cols] > 0
        peak_rows, peak_v = rows[is_peak], ext[is_peak]
    else:
        peak_rows, peak_v = np.empty(0, dtype=np.intp), np.empty(0)

    # 3. roots between consecutive candidates
    ok = gc <= 0.0
    change_r, change_c = np.nonzero(ok[:, :-1] != ok[:, 1:])
    roots = np.empty(0)
    if change_r.size:
        def value(x: np.ndarray, idx: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            return _mapped(value_slope, x, tuple(t[change_r[idx]] for t in terrain))

        roots = safeguarded_newton(
            value, cand[change_r, change_c], cand[change_r, change_c + 1], gc[change_r, change_c], xtol=xtol
        )
    entering = ~ok[change_r, change_c]  # inadmissible -> admissible: a lower edge

    # assemble bands: lower edges are 0 (if admissible at rest) and entering roots; upper
    # edges are leaving roots and v_max (if admissible at top speed); both in order.
    lower_r = np.concatenate([np.flatnonzero(ok[:, 0]), change_r[entering]])
    lower_v = np.concatenate([np.zeros(int(ok[:, 0].sum())), roots[entering]])
    upper_r = np.concatenate([change_r[~entering], np.flatnonzero(ok[:, -1])])
    upper_v = np.concatenate([roots[~entering], np.full(int(ok[:, -1].sum()), vmax)])
    count = np.bincount(lower_r, minlength=n)
    return SpeedBands(
        lower_mps=_ragged_to_padded(lower_r, lower_v, n),
        upper_mps=_ragged_to_padded(upper_r, upper_v, n),
        count=count,
        peaks_mps=_ragged_to_padded(peak_rows, peak_v, n),
    )


def _ragged_to_padded(rows: np.ndarray, values: np.ndarray, n: int) -> np.ndarray:
    """Values tagged with their row into an (n, width) array, each row sorted, NaN-padded."""
    width = max(int(np.bincount(rows, minlength=n).max(initial=0)), 1)
    out = np.full((n, width), np.nan)
    order = np.lexsort((values, rows))
    rows_s, vals_s = rows[order], values[order]
    first_of_row = np.searchsorted(rows_s, rows_s, side="left")
    out[rows_s, np.arange(rows_s.size) - first_of_row] = vals_s
    return out


def _check_band(band: str) -> None:
    if band == "all":
        raise InputError("allowable_speed: band 'all' means every band; use speed_bands(ri, vehicle) for every "
                         "band, or choose band 'first' or 'largest'")
    if band not in ("first", "largest"):
        raise InputError(f"allowable_speed: band {band!r} is unknown; choose 'first' or 'largest'")


def allowable_speed(
    ri: ArrayLike,
    vehicle: "Vehicle",
    *,
    model: str = DEFAULT_MODEL,
    band: Band = "first",
) -> np.ndarray | float:
    """The fastest speed (m/s) that keeps ``model``'s force within the vehicle's limit.

    Parameters
    ----------
    ri : array_like, any shape, or float
        Roughness index (dimensionless), >= 0; NaN or negative raises ``InputError``.
    vehicle : Vehicle
    model : str, default ``"sbem_tf"`` (:data:`~profileopt.physics.forces.DEFAULT_MODEL`)
        ``"prev_bem"``, ``"iecm"``, ``"sbem_ef"`` or ``"sbem_tf"``.
    band : {"first", "largest"}, default ``"first"``
        ``"first"`` (safe from rest): the largest V such that every speed in [0, V] keeps
        the force within the limit. ``"largest"``: the largest speed <= v_max whose force is
        within the limit (the root the paper's Newton iteration lands on; Fig. 6). They
        coincide when the force grows monotonically with speed. ``"all"`` (every band) is
        refused: :func:`speed_bands` gives every band.

    Returns
    -------
    float or numpy.ndarray of the shape of ``ri``
        Speed in [0, v_max] (m/s). RI = 0 gives v_max; a limit below the force at rest
        gives 0.

    Raises
    ------
    InputError
        Unknown ``model`` or ``band``, or a NaN or negative ``ri``.
    """
    vehicle = require_vehicle(vehicle, "allowable_speed")
    _check_band(band)
    get_model(model)
    values = np.asarray(ri, dtype=float)
    bands = speed_bands(values.ravel(), vehicle, model=model)
    out = (bands.first() if band == "first" else bands.largest()).reshape(values.shape)
    return float(out) if values.ndim == 0 else out


def max_force_over_segments(model: str, vehicle: "Vehicle", ri: np.ndarray, speed_mps: np.ndarray,
                            peaks_mps: np.ndarray, *, ri_min: np.ndarray | None = None) -> np.ndarray:
    """Largest predicted force over the speeds between each segment's two boundary speeds.

    The force of a speed interval is largest at one of its ends or at an interior local
    maximum of the force (a resonance peak), so those are the only candidates.

    Parameters
    ----------
    model : str
        Force model key.
    vehicle : Vehicle
        The quarter car and its limits.
    ri : numpy.ndarray, shape (N,)
        RI of each segment (with ``ri_min``: the largest RI of its windows).
    speed_mps : numpy.ndarray, shape (N+1,)
        Speeds at the boundaries (m/s).
    peaks_mps : numpy.ndarray, shape (N, P)
        Speeds of the force's interior local maxima of each segment, NaN-padded
        (:attr:`profileopt.physics.speeds.SpeedBands.peaks_mps`, of the same force).
    ri_min : numpy.ndarray, shape (N,), optional
        The least RI of each segment's windows: the force is then the largest over the RI
        range (:func:`profileopt.physics.forces.envelope_force_n`).

    Returns
    -------
    numpy.ndarray, shape (N,)
        Force (N).
    """
    return _max_force_between(model, vehicle, ri, speed_mps[:-1], speed_mps[1:], peaks_mps, ri_min=ri_min)


def _max_force_between(model: str, vehicle: "Vehicle", ri: np.ndarray, speed_a: np.ndarray, speed_b: np.ndarray,
                       peaks_mps: np.ndarray, *, ri_min: np.ndarray | None = None) -> np.ndarray:
    """:func:`max_force_over_segments` for the speed intervals between ``speed_a[i]`` and
    ``speed_b[i]``, shape (N,) each."""
    lo = np.minimum(speed_a, speed_b)[:, None]
    hi = np.maximum(speed_a, speed_b)[:, None]
    inside = (peaks_mps >= lo) & (peaks_mps <= hi)
    candidates = np.concatenate([lo, hi, np.where(inside, peaks_mps, lo)], axis=1)
    spec = get_model(model)
    high = np.broadcast_to(ri[:, None], candidates.shape)
    if ri_min is None:
        forces = spec.force_n(candidates, high, vehicle)
    else:
        forces = spec.envelope_force_n(candidates, np.broadcast_to(ri_min[:, None], candidates.shape), high, vehicle)
    return forces.max(axis=1)
