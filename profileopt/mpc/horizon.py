"""The force limit over a controller's horizon, between its grid points and on the terrain
its predicted positions reach.

A model predictive controller keeps the force limit only where its constraints look: at
the stage points, on the terrain given to each stage. Between two stages the vehicle drives
every speed between the two stage speeds (constant acceleration), over every roughness
window it passes. Two helpers make the limit hold there too:

:func:`terrain_envelope`
    A ``casadi.Function`` of the position s (m), smooth (twice continuously
    differentiable) and usable on ``SX``, ``MX`` and ``DM``, that is never below the
    worst-case elevation e_max (Eq. 8) of any roughness window overlapping [s, s + reach].
:func:`interval_force_constraints`
    Rows g <= 0 that hold only when every speed between a stage's entry and exit speeds
    keeps the force within the limit at every elevation up to e_max, the resonance peak
    between them included (a plan cannot jump over a forbidden band of speeds).

Composed, they make a stage safe: see :func:`interval_force_constraints` ("Why a stage is
safe"). :func:`step_speed_envelope` adds SBEM:TF's step limit, as the planner keeps it: a
smooth speed cap of the position where the wheel meets a step or lands after a drop. All
three are also importable from :mod:`profileopt.mpc.constraints`. Each envelope covers a stage
at most its reach long: :func:`reach_constraints` gives the rows 0 <= s_{k+1} - s_k <= reach
for a problem whose stage positions are free, and :func:`check_stage_lengths` checks a solved
horizon against them before it is applied. :class:`ForceConstraints`
is the ``(g, lbg, ubg)`` triple both this module and :func:`~profileopt.mpc.constraints.force_constraints`
return.

Units: positions and elevations in m, speeds in m/s, forces in N; g is dimensionless.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from typing import Any, Iterator

import casadi as ca
import numpy as np
from numpy.typing import ArrayLike

from ..core.route import Route
from ..core.vehicle import Vehicle, require_vehicle
from ..core.symbolic import is_symbolic
from ..errors import InputError
from ..physics.forces import (
    DEFAULT_MODEL,
    check_e_max_model,
    force_n,
    force_peak_ratio,
    get_model,
    sbem_tf_envelope_force_n,
)
from ..physics.steps import step_caps
from ..terrain.roughness import (
    check_e_max,
    range_extremes,
    roughness_windows,
    step_width,
    worst_case_elevation,
)


__all__ = [
    "ConstraintTriple",
    "ForceConstraints",
    "reach_constraints",
    "check_stage_lengths",
    "STAGE_LENGTH_TOLERANCE_M",
    "terrain_envelope",
    "step_speed_envelope",
    "interval_force_constraints",
    "force_peak_ratio",
    "MAX_ENVELOPE_INTERVALS",
]


class ConstraintTriple:
    """Rows ``g`` with bounds ``lbg <= g <= ubg`` that unpack as the triple of ``casadi.nlpsol``.

    ``g, lbg, ubg = cons``; ``dict(cons)`` and ``**cons`` give the same three by name;
    ``cons[0]`` .. ``cons[2]`` index the triple. Subclasses are dataclasses with the fields
    ``g``, ``lbg`` and ``ubg`` (and more, reached as attributes).
    """

    def __iter__(self) -> Iterator[Any]:
        return iter((self.g, self.lbg, self.ubg))

    def __len__(self) -> int:
        return 3

    def keys(self) -> tuple[str, str, str]:
        """``("g", "lbg", "ubg")``: with :meth:`__getitem__`, ``dict(cons)`` and ``**cons``
        give the same three as unpacking."""
        return ("g", "lbg", "ubg")

    def __getitem__(self, key: str | int) -> Any:
        if isinstance(key, int) and not isinstance(key, bool) and -3 <= key < 3:
            return (self.g, self.lbg, self.ubg)[key]
        if key not in self.keys():
            raise KeyError(f"{key!r}: a {type(self).__name__} maps 'g', 'lbg' and 'ubg' (or 0, 1, 2 as the triple; "
                           "attributes hold the rest)")
        return getattr(self, key)


@dataclasses.dataclass(frozen=True)
class ForceConstraints(ConstraintTriple):
    """Force-limit (and optional acceleration) constraints lbg <= g <= ubg.

    Unpacks as the triple ``g, lbg, ubg = force_constraints(...)`` that
    ``casadi.nlpsol`` takes (``{"g": g}`` and ``lbg=lbg, ubg=ubg`` at the call), indexes
    like it (``cons[0]`` is ``g``), and converts to the dict of the same three:
    ``dict(cons)``, ``{**cons}``.

    Attributes
    ----------
    g : casadi.SX, casadi.MX or casadi.DM, shape (R, 1)
        The constraint expressions: first the ``n_force`` force rows, then the acceleration
        rows (if an acceleration vector was given). A force row is F / F_limit - 1
        (dimensionless, ``normalised=True``) or F (N); an acceleration row is a (m/s^2).
    lbg, ubg : numpy.ndarray, shape (R,)
        Bounds: force rows (-inf, 0] normalised or (-inf, F_limit] raw; acceleration rows
        [-max_decel_mps2, max_accel_mps2].
    force_n : casadi.SX, casadi.MX or casadi.DM, shape (n_force, 1)
        The force (N) of each force row, for inspection.
    limit_n : float
        The force limit F_limit (N).
    n_force : int
        Number of force rows.
    model : str
        The force model.
    normalised : bool
        Whether the force rows are F / F_limit - 1.
    """

    g: Any
    lbg: np.ndarray
    ubg: np.ndarray
    force_n: Any
    limit_n: float
    n_force: int
    model: str
    normalised: bool



# ---------------------------------------------------------------------------------------
# The terrain ahead as a smooth function of the position
# ---------------------------------------------------------------------------------------

#: Knot intervals a :func:`terrain_envelope` may have: its expression grows with them (about
#: 9 operations each, every one evaluated at every call).
MAX_ENVELOPE_INTERVALS = 200_000

#: Relative margin added to the envelope: it covers the rounding of the spline's evaluation
#: (a few 1e-16 of the largest e_max), so that "never below" holds in floating point too.
_ROUNDING_MARGIN = 1e-12
#: The least median spacing (m) of a route's samples the envelopes take: closer samples are
#: positions given in km (a route sampled every 5 cm, in km, is 5e-5 apart).
_LEAST_SPACING_M = 1e-3


def terrain_envelope(
    positions_m: ArrayLike,
    elevations_m: ArrayLike,
    vehicle: "Vehicle | None" = None,
    *,
    window_m: float = 5.0,
    reach_m: float = 0.0,
    knot_spacing_m: float | None = None,
) -> ca.Function:
    """The largest worst-case elevation a stage starting at s can meet, as a smooth
    ``casadi.Function`` of s.

    Every roughness window [a, a + W] of the route (at any offset a: each distinct set of
    samples with the stretch its windows cover,
    :func:`~profileopt.terrain.roughness.roughness_windows`) has its RI (Eq. 1) and its e_max =
    z RI h (Eq. 8). The requirement at s is the largest e_max of the windows that overlap
    [s, s + reach_m]: every window a vehicle can be inside while it moves from s to at most
    s + reach_m. The Function returns a value never below that requirement, at every s.

    Construction: a uniform cubic B-spline with knots ``knot_spacing_m`` = h apart, whose
    coefficient j is the requirement's maximum over the support of basis function j (4 knot
    intervals). The basis functions are non-negative and sum to one, so at any s the spline
    is a weighted mean of coefficients that each cover s: it is never below the requirement
    at s. It is a cubic on each knot interval and twice continuously differentiable
    everywhere, which IPOPT needs (a piecewise-linear table makes it cycle at the kinks).
    It is written out as an ``SX`` expression (the coefficients of every knot interval's
    cubic, the active one picked by the interval's index; no ``interpolant``), so it expands
    to ``SX``, calls on ``MX`` and evaluates on numbers. Its size and evaluation cost grow
    with the knot intervals (about 9 operations each); its derivatives cost a few
    operations, since they flow through the one active cubic. Outside the route it holds
    the end values: from 3 h before the first sample and from 4 h after the last on, it is
    constant, the requirement at that end. A NaN or infinite position gives NaN. A
    relative margin of 1e-12 covers the rounding of the evaluation.

    How conservative: at s the value lies between the requirement (windows overlapping
    [s, s + reach_m]) and the largest e_max of the windows overlapping
    [s - 4 h, s + reach_m + 4 h]: it rises at most 4 h before a rougher stretch and falls
    at most 4 h after it.

    Parameters
    ----------
    positions_m : array_like, shape (M,)
        Distance along the route of each sample (m), strictly increasing.
    elevations_m : array_like, shape (M,)
        Elevation of each sample (m).
    vehicle : Vehicle
        Supplies the ground clearance h and the confidence of Eq. (8). Required: the default
        None is there only so that a mistaken ``terrain_envelope(route, vehicle)`` gets a
        message, and is refused.
    window_m : float, default 5.0
        Roughness window length W (m), as ``roughness_window_m`` of the planner.
    reach_m : float, default 0.0
        How far beyond s a stage can take the vehicle (m), >= 0: for a controller with
        interval dt and top speed v_max, ``reach_m = v_max * dt`` covers every stage.
    knot_spacing_m : float, optional
        Knot spacing h (m), > 0; default ``window_m / 20`` (0.25 m for 5 m windows). The
        expression has one cubic per knot interval over the route: build the envelope for
        the stretch a controller will drive, not a whole long route, or choose a larger h.

    Returns
    -------
    casadi.Function
        ``terrain_envelope``: input ``s_m`` (1 x 1, m), output ``e_max_m`` (1 x 1, m).
        ``fn.map(N)`` evaluates N positions (a row of N). Its derivatives are continuous to
        the second.

    Raises
    ------
    InputError
        Bad samples (as for a route), a window length that is not > 0 (a window longer
        than the route is the whole route), a window holding fewer than
        :data:`~profileopt.terrain.roughness.MIN_SAMPLES_PER_WINDOW` samples, a negative or
        non-finite ``reach_m``, a ``knot_spacing_m`` that is not > 0, or more than
        :data:`MAX_ENVELOPE_INTERVALS` knot intervals.
    """
    _refuse_route("terrain_envelope", positions_m)
    vehicle = require_vehicle(vehicle, "terrain_envelope")
    window = _finite_number(window_m, "window_m", "m")
    if not window > 0:
        raise InputError(f"terrain_envelope: window_m = {window_m!r} m must be > 0 (the roughness window length)")
    grid = _SplineGrid.of("terrain_envelope", positions_m, elevations_m, reach_m,
                          window / 20.0 if knot_spacing_m is None else knot_spacing_m)
    s, z, reach, h = grid.s_m, grid.z_m, grid.reach_m, grid.h_m
    try:
        windows = roughness_windows(s, z, vehicle.ground_clearance_m, window_m=window, source="terrain_envelope")
    except InputError as exc:
        raise InputError(str(exc)) from None
    e_window = np.asarray(worst_case_elevation(windows.ri, vehicle), dtype=float)

    # coefficient j is the requirement's maximum over basis function j's support
    first, stop = windows.overlapping(grid.lo_m, grid.hi_m + reach)
    coef = range_extremes(e_window, first, stop)[1]
    coef = coef + _ROUNDING_MARGIN * float(np.max(coef))
    doc = (f"Largest worst-case elevation e_max (m) of the {window:g} m roughness windows overlapping "
           f"[s_m, s_m + {reach:g} m] (an upper bound, cubic B-spline with knots {h:g} m apart); "
           f"input s_m: position along the route (m); output e_max_m (m).")
    return _spline_function(coef, grid, "terrain_envelope", "e_max_m", doc)


def step_speed_envelope(
    positions_m: ArrayLike,
    elevations_m: ArrayLike,
    vehicle: "Vehicle | None" = None,
    *,
    reach_m: float = 0.0,
    knot_spacing_m: float = 0.25,
) -> ca.Function:
    """SBEM:TF's step limit for a stage starting at s: a speed cap (m/s), as a smooth
    ``casadi.Function`` of s.

    The planner keeps, beside Eq. (13), a cap wherever the rigid wheel meets a step or lands
    after a drop (docs: guide/steps.md, "Steps and drops"): each ramp of the wheel's path that starts or
    ends in a kink (:func:`profileopt.physics.steps.wheel_ramps`) caps every speed driven while the
    vehicle is on it at :func:`profileopt.physics.steps.ramp_speed_cap_mps`
    (:func:`profileopt.physics.steps.step_caps`, the planner's very caps). The requirement at
    s is the lowest cap of the ramps that overlap [s, s + reach_m], or the vehicle's top
    speed; the Function is never above it. Built as :func:`terrain_envelope` is (a uniform
    cubic B-spline whose coefficient j is the requirement's minimum over basis function j's
    support: a weighted mean of coefficients that each cover s, twice continuously
    differentiable, an ``SX`` expression without ``interpolant``), so it drops at most 4 h
    before a ramp and rises at most 4 h after it. With ``cap = step_speed_envelope(...,
    reach_m=ds)``, a stage from s_k to s_k + ds at constant acceleration keeps the step
    limit when both v_k <= cap(s_k) and v_k1 <= cap(s_k).

    Parameters
    ----------
    positions_m : array_like, shape (M,)
        Distance along the route of each sample (m), strictly increasing.
    elevations_m : array_like, shape (M,)
        Elevation of each sample (m).
    vehicle : Vehicle
        Supplies the quarter car, the wheel radius, the top speed and
        ``max_transmitted_force_n``. Required (None is refused with a message, as by
        :func:`terrain_envelope`).
    reach_m : float, default 0.0
        How far beyond s a stage can take the vehicle (m), >= 0.
    knot_spacing_m : float, default 0.25
        Knot spacing h (m), > 0.

    Returns
    -------
    casadi.Function
        ``step_speed_envelope``: input ``s_m`` (1 x 1, m), output ``speed_cap_mps`` (1 x 1,
        m/s), at most the vehicle's top speed.

    Raises
    ------
    InputError
        Bad samples (as for a route), a negative or non-finite ``reach_m``, a
        ``knot_spacing_m`` that is not > 0, or more than :data:`MAX_ENVELOPE_INTERVALS` knot
        intervals.
    """
    _refuse_route("step_speed_envelope", positions_m)
    vehicle = require_vehicle(vehicle, "step_speed_envelope")
    grid = _SplineGrid.of("step_speed_envelope", positions_m, elevations_m, reach_m, knot_spacing_m)
    reach, h = grid.reach_m, grid.h_m
    top = float(vehicle.max_speed_mps)
    # coefficient j: the lowest cap of the ramps meeting [lo_j, hi_j + reach]
    coef = step_caps(grid.s_m, grid.z_m, vehicle).lowest_over(grid.lo_m, grid.hi_m + reach, top)
    coef = coef - _ROUNDING_MARGIN * top
    doc = (f"SBEM:TF's step limit (m/s) over the ramps of the wheel's path overlapping [s_m, s_m + {reach:g} m] "
           f"(a lower bound, cubic B-spline with knots {h:g} m apart, at most the top speed {top:g} m/s); "
           f"input s_m: position along the route (m); output speed_cap_mps (m/s).")
    return _spline_function(coef, grid, "step_speed_envelope", "speed_cap_mps", doc)


@dataclasses.dataclass(frozen=True)
class _SplineGrid:
    """The knots of an envelope over a route's samples: interval i is [start + i h, start +
    (i + 1) h] and uses coefficients i .. i + 3; basis function j's support, clipped to the
    route (outside it, the nearer end's value), is [lo_m[j], hi_m[j]]."""

    s_m: np.ndarray
    z_m: np.ndarray
    reach_m: float
    h_m: float
    start_m: float
    n_intervals: int
    lo_m: np.ndarray
    hi_m: np.ndarray

    @classmethod
    def of(cls, name: str, positions_m: ArrayLike, elevations_m: ArrayLike, reach_m: Any, knot_spacing_m: Any
           ) -> "_SplineGrid":
        """Validate the samples, reach_m and knot_spacing_m (one InputError naming ``name``)."""
        route = Route(s_m=np.asarray(positions_m, dtype=float), z_m=np.asarray(elevations_m, dtype=float),
                      source=name)
        reach = _finite_number(reach_m, "reach_m", "m")
        if reach < 0:
            raise InputError(f"{name}: reach_m = {reach_m!r} m must be >= 0 (how far a stage can go)")
        h = _finite_number(knot_spacing_m, "knot_spacing_m", "m")
        if not h > 0:
            raise InputError(f"{name}: knot_spacing_m = {knot_spacing_m!r} m must be > 0")
        s0, s1 = float(route.s_m[0]), float(route.s_m[-1])
        spacing = float(np.median(np.diff(route.s_m)))
        if spacing < _LEAST_SPACING_M:
            raise InputError(f"{name}: the samples are {spacing:.3g} m apart along the route: positions in km? give "
                             "them in m")
        n_intervals = math.ceil((s1 - s0) / h) + 8  # 4 flat intervals beyond each end
        if n_intervals > MAX_ENVELOPE_INTERVALS:
            raise InputError(
                f"{name}: {s1 - s0:g} m of route at knot_spacing_m = {h:g} m makes {n_intervals} knot "
                f"intervals, above {MAX_ENVELOPE_INTERVALS}; build it for the stretch the controller will drive, "
                "or choose a larger knot_spacing_m")
        start = s0 - 4.0 * h
        j = np.arange(n_intervals + 3)
        return cls(s_m=route.s_m, z_m=route.z_m, reach_m=reach, h_m=h, start_m=start, n_intervals=n_intervals,
                   lo_m=np.clip(start + (j - 3) * h, s0, s1), hi_m=np.clip(start + (j + 1) * h, s0, s1))


def _spline_function(coef: np.ndarray, grid: _SplineGrid, name: str, output: str, doc: str) -> ca.Function:
    """The uniform cubic B-spline with coefficients ``coef`` (shape (n_intervals + 3,)) on the
    knots of ``grid``, as a ``casadi.Function`` of ``s_m`` (see :func:`terrain_envelope`:
    clamped to its end intervals outside, NaN for a non-finite s). At every s it is a weighted
    mean, with non-negative weights summing to one, of the four coefficients whose support
    holds s."""
    s_sym = ca.SX.sym("s_m")
    value = spline_value(s_sym, coef, start_m=grid.start_m, h_m=grid.h_m, n_intervals=grid.n_intervals)
    fn = ca.Function(name, [s_sym], [value], ["s_m"], [output])
    fn.__doc__ = doc
    return fn


def spline_value(s_m: Any, coef: Any, *, start_m: Any, h_m: float, n_intervals: int) -> Any:
    """The uniform cubic B-spline with knots ``h_m`` apart from ``start_m`` and coefficients
    ``coef`` at ``s_m``, as an ``SX`` expression: the one formula of the envelopes.

    Interval i is [start + i h, start + (i + 1) h] and uses coefficients i .. i + 3; outside
    [start, start + n_intervals h] the spline holds its end intervals' edge values (the clamp's
    kinks lie where the envelopes are constant, so they stay smooth); a non-finite s gives
    NaN. At every s the value is a weighted mean, with non-negative weights summing to one, of
    the four coefficients whose support holds s.

    Parameters
    ----------
    s_m : casadi.SX, shape (1, 1)
        Position (m).
    coef : numpy.ndarray or casadi.SX, shape (n_intervals + 3,)
        Coefficients: numbers (a fixed envelope) or symbols (a parametric one,
        :class:`profileopt.mpc.preview.TerrainPreview`).
    start_m : float or casadi.SX
        The first knot (m).
    h_m : float
        Knot spacing (m), > 0.
    n_intervals : int
        Number of knot intervals.

    Returns
    -------
    casadi.SX
    """
    numeric = isinstance(coef, np.ndarray)
    c = coef if numeric else ca.vec(coef)
    c0, c1, c2, c3 = (c[k:k + n_intervals] for k in range(4))
    # the cubic of interval i in u in [0, 1]: sum_k c_{i+k} b_k(u), b_k the uniform cubic
    # B-spline pieces, in powers of u (written so that four equal coefficients give
    # exactly that constant)
    a2 = (c0 - 2.0 * c1 + c2) / 2.0
    a0 = c1 + a2 / 3.0
    a1 = (c2 - c0) / 2.0
    a3 = (c3 - c0 + 3.0 * (c1 - c2)) / 6.0
    y = ca.fmin(ca.fmax((s_m - start_m) / h_m, 0), n_intervals)
    index = ca.fmin(ca.floor(y), n_intervals - 1)
    u = y - index
    # The active interval's four coefficients, picked by its index (exactly one term is
    # not zero). They depend on s only through floor(), whose derivative is 0, so every
    # derivative flows through the one cubic in u below: the gradient and the Hessian cost
    # a few operations, not one per interval as a sum of pieces would.
    selected = [ca.SX(0.0)] * 4
    for i in range(n_intervals):
        here = index == i
        selected = [acc + (float(power[i]) if numeric else power[i]) * here
                    for acc, power in zip(selected, (a0, a1, a2, a3))]
    b0, b1, b2, b3 = selected
    value = b0 + u * (b1 + u * (b2 + u * b3))
    return ca.if_else(ca.fabs(s_m) < math.inf, value, math.nan)


def _refuse_route(name: str, positions_m: Any) -> None:
    """One line for a Route given where its arrays go (``terrain_envelope(route, vehicle)``)."""
    if isinstance(positions_m, Route):
        raise InputError(f"{name}: positions_m is a Route; give its arrays: {name}(route.s_m, route.z_m, vehicle)")


def _finite_number(value: Any, name: str, unit: str) -> float:
    try:
        out = float(value)
    except (TypeError, ValueError):
        raise InputError(f"{name} = {value!r}: give a number in {unit}") from None
    if not math.isfinite(out):
        raise InputError(f"{name} = {value!r} {unit}: must be a finite number")
    return out


# ---------------------------------------------------------------------------------------
# Every speed between two stages
# ---------------------------------------------------------------------------------------


def _column(value: Any) -> Any:
    """``value`` as a column: SX, MX and DM reshaped, numbers and arrays as DM."""
    if isinstance(value, (ca.SX, ca.MX, ca.DM)):
        return ca.vec(value)
    return ca.DM(np.asarray(value, dtype=float).reshape(-1, 1))


def _numeric(value: Any) -> np.ndarray | None:
    """The numbers of ``value`` (None for a symbol)."""
    if is_symbolic(value):
        return None
    return np.asarray(value.full() if isinstance(value, ca.DM) else value, dtype=float)


#: The least elevation (m) the SBEM:TF interval bound is computed from (see
#: :func:`interval_force_constraints`, e_min_m).
_LEAST_E_MIN_M = 1e-12


@functools.lru_cache(maxsize=32)
def _interval_rows(model: str, vehicle: "Vehicle") -> ca.Function:
    """The bounding forces (N) of one interval's rows, as an SX Function of (v_start,
    v_end, e_max, e_min): 3 rows for SBEM:TF with a force peak, else 2."""
    v0, v1, e_hi, e_lo = (ca.SX.sym(name) for name in ("v_start", "v_end", "e_max_m", "e_min_m"))
    if model == "sbem_tf":
        # X_w(e) = sqrt(e (2 r - e)) has an infinite slope at e = 0, which makes NaN of
        # every derivative through it (inf * 0): the least elevation is taken at least
        # _LEAST_E_MIN_M (see the docstring of e_min_m), and a NaN or negative one still
        # gives NaN
        e_least = ca.if_else(e_lo >= 0, ca.fmax(e_lo, _LEAST_E_MIN_M), e_lo)

        def bound(speed: Any) -> Any:
            return sbem_tf_envelope_force_n(speed, e_least, e_hi, vehicle)
    else:
        def bound(speed: Any) -> Any:
            return force_n(speed, vehicle, e_max_m=e_hi, model=model)

    columns = [bound(v0), bound(v1)]
    r_phi = force_peak_ratio(vehicle.damping_ratio) if model == "sbem_tf" else None
    if r_phi is not None:
        wn = vehicle.natural_frequency_radps
        v_peak = r_phi * 2.0 * step_width(e_hi, vehicle) * wn / math.pi
        inside = ca.fmin(ca.fmax(v_peak, ca.fmin(v0, v1)), ca.fmax(v0, v1))
        columns.append(bound(inside))
    return ca.Function(f"{model}_interval_forces", [v0, v1, e_hi, e_lo], [ca.vertcat(*columns)],
                       ["v_start", "v_end", "e_max_m", "e_min_m"], ["force_n"])


def reach_constraints(positions_m: Any, reach_m: float) -> ConstraintTriple:
    """Rows 0 <= s_{k+1} - s_k <= reach_m for a horizon whose stage positions are variables.

    An envelope built with ``reach_m`` (:func:`terrain_envelope`, :func:`step_speed_envelope`,
    :class:`~profileopt.mpc.preview.TerrainPreview`) bounds the terrain a stage meets only if
    the stage is at most ``reach_m`` long: in a free-time (or time-parameterised) problem
    nothing else keeps a stage that short, and a controller that leaves the row out can
    return "success" with a stage far longer, over terrain no row saw (issue 31: a 98.5 m
    stage simulated at 1.81 times the limit). Add these rows with the force rows.

    Parameters
    ----------
    positions_m : SX, MX, DM, numpy array or sequence, shape (N+1,)
        The stage positions s_0 .. s_N (m).
    reach_m : float
        The envelopes' reach (m), > 0.

    Returns
    -------
    ConstraintTriple
        ``g`` the N differences s_{k+1} - s_k (m), ``lbg`` 0 (forward driving), ``ubg``
        ``reach_m``.

    Raises
    ------
    InputError
        Fewer than 2 positions, or a ``reach_m`` that is not a finite number > 0.
    """
    reach = _finite_number(reach_m, "reach_constraints: reach_m", "m")
    if reach <= 0:
        raise InputError(f"reach_constraints: reach_m = {reach_m!r} m must be > 0: the envelopes' reach")
    s = _column(positions_m)
    n = s.shape[0] - 1
    if n < 1:
        raise InputError("reach_constraints: give the positions of at least 2 stages (m)")
    return _Rows(g=s[1:] - s[:-1], lbg=np.zeros(n), ubg=np.full(n, reach))


#: How far (m) a solved stage may exceed the reach, or run backwards, and still pass
#: :func:`check_stage_lengths`: IPOPT meets the reach rows (and, in a time-parameterised
#: problem, the speed bounds that imply them) only to its tolerance, about 1e-8 m for
#: horizons of metres; 1e-6 m (a micrometre) leaves room for that and no more.
STAGE_LENGTH_TOLERANCE_M = 1e-6


def check_stage_lengths(positions_m: Any, reach_m: float, *, tolerance_m: float = STAGE_LENGTH_TOLERANCE_M,
                        horizon_m: tuple[float, float] | None = None) -> np.ndarray:
    """Refuse a solved horizon with a stage longer than the envelopes' reach: call after each solve.

    The envelopes (:func:`terrain_envelope`, :func:`step_speed_envelope`,
    :class:`~profileopt.mpc.preview.TerrainPreview`) bound the terrain a stage meets only if
    it runs forward and at most ``reach_m`` far: 0 <= s_{k+1} - s_k <= reach_m, the rows of
    :func:`reach_constraints`. A problem that leaves those rows out (or whose time steps are
    free and unbounded) can still end in "success" with a stage far longer, over terrain no
    force row saw (issue 31: a 98.5 m stage simulated at 1.81 times the limit). This check,
    on the solved positions, catches that before the plan is applied: it raises, so a
    controller treats the plan as it treats a failed solve (keep the last plan's tail, brake),
    and it names the first offending stage so that the missing row can be found. In a
    time-parameterised problem (s_{k+1} - s_k = (v_k + v_{k+1}) dt / 2 with 0 <= v <= v_max)
    the speed bounds imply the rows for ``reach_m = v_max * dt``; the check then confirms
    that the reach the envelopes were built with is that one.

    Parameters
    ----------
    positions_m : numpy array, sequence, casadi.DM or number array, shape (N+1,)
        The solved stage positions s_0 .. s_N (m), e.g. ``sol.value(s)``; a row or column
        vector is taken as it is. Symbols (``SX``, ``MX``) are refused: give their values.
    reach_m : float
        The reach the envelopes were built with (m), >= 0.
    tolerance_m : float, default :data:`STAGE_LENGTH_TOLERANCE_M` (1e-6)
        Stages from -tolerance_m to reach_m + tolerance_m long pass (m), >= 0: the solver's
        tolerance on the rows. Give 0 for the rows exactly.
    horizon_m : (float, float), optional
        Where the envelopes are bounds (m), ``(start, end)``: for a
        :class:`~profileopt.mpc.preview.TerrainPreview`, ``(coef.origin_m, coef.origin_m +
        preview.horizon_m)``. Given, every stage must also start (s_0 .. s_{N-1}) within it,
        to the same tolerance.

    Returns
    -------
    numpy.ndarray, shape (N,)
        The stage lengths s_{k+1} - s_k (m), each within [-tolerance_m, reach_m +
        tolerance_m], for a log or a margin.

    Raises
    ------
    InputError
        One line naming the first stage (index k from 0, its start and end in m, its
        length in m) that is longer than ``reach_m``, runs backwards, has a position that is
        not a finite number or starts outside ``horizon_m``, with the reach, how many stages
        are out, and what to add; or bad arguments (fewer than 2 positions, symbols, a
        matrix, a ``reach_m`` or ``tolerance_m`` that is not a finite number >= 0).

    Examples
    --------
    >>> check_stage_lengths([0.0, 1.5, 3.0], 2.0)
    array([1.5, 1.5])
    >>> check_stage_lengths([0.0, 1.5, 4.0, 4.0], 2.0)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    profileopt.errors.InputError: check_stage_lengths: stage 1 (from 1.5 to 4 m) is 2.5 m long, longer than ...
    """
    name = "check_stage_lengths"
    reach = _finite_number(reach_m, f"{name}: reach_m", "m")
    tol = _finite_number(tolerance_m, f"{name}: tolerance_m", "m")
    if reach < 0 or tol < 0:
        raise InputError(f"{name}: reach_m = {reach_m!r} m and tolerance_m = {tolerance_m!r} m must be >= 0")
    if is_symbolic(positions_m):
        raise InputError(f"{name}: positions_m are symbols; give the solved values (sol.value(s), "
                         "opti.value(s) or the solver's x), not the variables")
    try:
        s = np.asarray(positions_m.full() if isinstance(positions_m, ca.DM) else positions_m, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{name}: positions_m = {positions_m!r}: give the stage positions as numbers (m)") from None
    if s.ndim > 2 or (s.ndim == 2 and min(s.shape) > 1):
        raise InputError(f"{name}: positions_m has shape {s.shape}; give one row of stage positions (m), "
                         "e.g. the position row of the states, not the whole state matrix")
    s = s.ravel()
    if s.size < 2:
        raise InputError(f"{name}: give the positions of at least 2 stages (m); got {s.size}")
    lengths = np.diff(s)
    bad_value = ~np.isfinite(s[:-1]) | ~np.isfinite(s[1:])
    too_long = lengths > reach + tol
    backwards = lengths < -tol
    outside = np.zeros(lengths.size, dtype=bool)
    if horizon_m is not None:
        try:
            start, end = (float(x) for x in horizon_m)
        except (TypeError, ValueError):
            raise InputError(f"{name}: horizon_m = {horizon_m!r}: give (start, end) in m") from None
        outside = (s[:-1] < start - tol) | (s[:-1] > end + tol)
    bad = bad_value | too_long | backwards | outside
    if not np.any(bad):
        return lengths
    k = int(np.argmax(bad))
    where = f"stage {k} (from {s[k]:.6g} to {s[k + 1]:.6g} m)"
    out = f"{int(np.sum(bad))} of {lengths.size} stages are out"
    if bad_value[k]:
        raise InputError(f"{name}: {where} has a position that is not a finite number; {out}: do not apply this plan")
    if too_long[k]:
        raise InputError(f"{name}: {where} is {lengths[k]:.6g} m long, longer than the envelopes' reach "
                         f"{reach:g} m, over terrain no force row saw; {out}: do not apply this plan, and bound "
                         f"every stage with reach_constraints(s, {reach:g}) (or build the envelopes with a reach "
                         "of at least v_max * dt)")
    if backwards[k]:
        raise InputError(f"{name}: {where} runs backwards ({lengths[k]:.6g} m); the envelopes hold for forward "
                         f"driving, 0 <= s[k+1] - s[k]; {out}: do not apply this plan, and keep the speeds >= 0 "
                         "(reach_constraints(s, reach_m) gives the row)")
    raise InputError(f"{name}: {where} starts outside the envelopes' horizon {start:.6g} to {end:.6g} m; {out}: do "
                     "not apply this plan, and build the preview with a longer horizon_m")


@dataclasses.dataclass(frozen=True)
class _Rows(ConstraintTriple):
    g: Any
    lbg: np.ndarray
    ubg: np.ndarray


def interval_force_constraints(
    v_start: Any,
    v_end: Any,
    e_max_m: Any,
    vehicle: "Vehicle",
    *,
    model: str = DEFAULT_MODEL,
    e_min_m: Any = 0.0,
    speed_backoff_mps: float = 0.0,
) -> ForceConstraints:
    """The force limit over every speed between each interval's entry and exit speeds.

    Over an interval with constant acceleration the speed passes through every value
    between ``v_start`` and ``v_end``. These rows hold (g <= 0) only when every one of those
    speeds keeps the force within the limit at every elevation e in [e_min_m, e_max_m],
    including the force's resonance peak between them: a plan cannot jump over a forbidden
    band of speeds between two stages.

    Rows per interval, each F / F_limit - 1 <= 0, ordered interval by interval:

    * IECM and SBEM:EF (the force grows with speed and with e): F(v_start, e_max) and
      F(v_end, e_max); 2 rows.
    * SBEM:TF: G(v_start), G(v_end) and G(clip(V_phi, min(v_start, v_end), max(v_start,
      v_end))), where G(V) = :func:`~profileopt.physics.forces.sbem_tf_envelope_force_n` (V,
      e_min, e_max) is an upper bound of the force over every e in [e_min, e_max] (exact
      at e_min = e_max, and above 2 wn r_w r_p / pi at any e_min) and V_phi =
      r_phi 2 X_w(e_max) wn / pi with r_phi of :func:`force_peak_ratio`; 3 rows. For a
      suspension with zeta >= 1 / (2 sqrt 2) (no interior peak, e.g. the bundled ``atv``)
      the third row is left out: 2 rows.

    Why the rows cover every speed in between (SBEM:TF). Write r_hi = pi V / (2 X_w(e_max)
    wn). G(V) = k e_max r_hi^2 T(clip(r_p, r_hi, kappa r_hi)) with kappa = X_w(e_max) /
    X_w(e_min) >= 1 and r_p the peak of T. While r_hi <= r_p, G grows with V (r_hi^2 grows
    and T is evaluated at min(r_p, kappa r_hi), where T still rises); from r_hi = r_p on,
    G = k e_max phi(r_hi), which rises to r_phi > r_p (phi' = 2 r T > 0 at r_p), falls, and
    rises again (:func:`force_peak_ratio`). So G rises on [0, V_phi], and on any interval
    of speeds its maximum is at an end or at V_phi when V_phi lies inside: exactly the
    three rows. Without an interior peak G never falls and the two ends suffice. The third
    row is continuous and, because V_phi is a stationary point of G, continuously
    differentiable in the speeds where V_phi crosses an end.

    Why a stage is safe. Let ``env = terrain_envelope(positions, elevations, vehicle,
    reach_m=ds)`` and let the vehicle move over a stage from s_k with speed >= 0 (s never
    decreases), at most ds far, its speed running monotonically from v_k to v_{k+1}
    (constant acceleration). Every window w it is inside during the stage overlaps
    [s_k, s_k + ds], so 0 <= e_w <= env(s_k) (the envelope's guarantee). Every speed v it
    drives then lies between v_k and v_{k+1}, and F(v, e_w) <= G(v) <= the largest row of
    ``interval_force_constraints(v_k, v_{k+1}, env(s_k), vehicle)``, because the default
    ``e_min_m = 0`` makes G bound the force at every e in [0, env(s_k)]. So g <= 0 keeps
    every speed driven inside every window within the limit. The range [0, e_max] is
    needed: SBEM:TF is not monotone in e at crawling speeds (below 2 wn r_w r_p / pi,
    0.16 m/s for ``atv``, 0.38 m/s for ``atv-resonant``), where a lower window can give a
    larger force than the highest one; above that speed G(V) = F(V, e_max) exactly, so
    the range costs nothing there. Give ``e_min_m = e_max_m`` for the force at exactly
    e_max.

    Parameters
    ----------
    v_start, v_end : SX, MX, DM, numpy array or number, shape (N,)
        Entry and exit speed of each interval (m/s), >= 0 (forward driving).
    e_max_m : SX, MX, DM, numpy array or number, shape (N,) or scalar
        The largest worst-case elevation of each interval (m), >= 0, e.g. ``env(s_k)``.
    vehicle : Vehicle
    model : str, default ``"sbem_tf"`` (:data:`~profileopt.physics.forces.DEFAULT_MODEL`)
        ``"iecm"``, ``"sbem_ef"`` or ``"sbem_tf"`` (Prev:BEM is defined on the RI only).
    e_min_m : SX, MX, DM, numpy array or number, shape (N,) or scalar, default 0.0
        The least elevation each interval's bound must cover (m), 0 <= e_min <= e_max
        (SBEM:TF only; the other models' force grows with e). Values below 1e-12 m are
        taken as 1e-12 m, where the step width's infinite slope at 0 would make every
        derivative NaN; the elevations below it are covered all the same except at speeds
        below 2 wn r_p X_w(1e-12 m) / pi (2e-6 m/s for the bundled vehicles, where their
        force is under 1e-7 N).

    speed_backoff_mps : float, default 0.0
        A speed-tracking error (m/s), >= 0: the rows cover every speed from
        max(min(v_start, v_end) - speed_backoff_mps, 0) to max(v_start, v_end) +
        speed_backoff_mps, for a vehicle that follows the planned speeds within that much.

    Returns
    -------
    ForceConstraints
        Unpacks as ``g, lbg, ubg``: ``g`` has 2 or 3 rows per interval (above), ``lbg``
        -inf and ``ubg`` 0; ``force_n`` holds the bounding force (N) of each row.

    Raises
    ------
    InputError
        Prev:BEM or an unknown model, lengths that do not match, a negative or NaN
        elevation, ``e_min_m`` above ``e_max_m``, a negative speed given as a number, or a
        ``speed_backoff_mps`` that is not a finite number >= 0.
        A symbolic negative or NaN elevation gives NaN rows, never g <= 0.
    """
    if isinstance(e_max_m, Vehicle) and not isinstance(vehicle, Vehicle):
        raise InputError("interval_force_constraints: e_max_m is a Vehicle and vehicle is not: the arguments are "
                         "swapped; give (v_start, v_end, e_max_m, vehicle)")
    vehicle = require_vehicle(vehicle, "interval_force_constraints")
    kinds = {type(x).__name__ for x in (v_start, v_end, e_max_m, e_min_m) if isinstance(x, (ca.SX, ca.MX))}
    if kinds == {"SX", "MX"}:
        raise InputError("interval_force_constraints: the speeds and e_max_m mix SX and MX symbols; give all of one "
                         "kind (call an SX Function on MX symbols, or expand an MX Function to SX)")
    spec = get_model(model)
    check_e_max_model(model)
    for name, value in (("e_max_m", e_max_m), ("e_min_m", e_min_m)):
        try:
            check_e_max(value)
        except InputError as exc:
            raise InputError(f"interval_force_constraints: {name}: {exc}") from None
    for name, value in (("v_start", v_start), ("v_end", v_end)):
        numbers = _numeric(value)
        if numbers is not None and (np.any(np.isnan(numbers)) or np.any(numbers < 0)):
            raise InputError(f"interval_force_constraints: {name} must be speeds >= 0 in m/s (forward driving)")
    v0, v1 = _column(v_start), _column(v_end)
    n = v0.shape[0]
    if v1.shape[0] != n or n == 0:
        raise InputError(f"interval_force_constraints: {n} entry speeds and {v1.shape[0]} exit speeds; give one of "
                         "each per interval (at least one)")
    e_hi, e_lo = _column(e_max_m), _column(e_min_m)
    for name, col in (("e_max_m", e_hi), ("e_min_m", e_lo)):
        if col.shape[0] not in (1, n):
            raise InputError(f"interval_force_constraints: {name} has {col.shape[0]} values for {n} intervals; "
                             "give one per interval or one for all")
    if e_hi.shape[0] == 1:
        e_hi = ca.repmat(e_hi, n, 1)
    if e_lo.shape[0] == 1:
        e_lo = ca.repmat(e_lo, n, 1)
    lows, highs = _numeric(e_lo), _numeric(e_hi)
    if lows is not None and highs is not None and np.any(lows > highs):
        raise InputError("interval_force_constraints: e_min_m must not exceed e_max_m (the least and the largest "
                         "elevation each interval covers)")

    backoff = _finite_number(speed_backoff_mps, "interval_force_constraints: speed_backoff_mps", "m/s")
    if backoff < 0:
        raise InputError(f"interval_force_constraints: speed_backoff_mps = {speed_backoff_mps!r} m/s must be >= 0")
    if backoff > 0:  # the rows are symmetric in the two speeds: widen the interval both ways
        v0, v1 = ca.fmax(ca.fmin(v0, v1) - backoff, 0.0), ca.fmax(v0, v1) + backoff
    rows_fn = _interval_rows(model, vehicle)
    # one call of the scalar rows per interval: compact in MX graphs, inlined for SX
    force = ca.vec(rows_fn.map(n)(v0.T, v1.T, e_hi.T, e_lo.T))  # interval by interval
    limit = spec.limit_n(vehicle)
    rows = int(force.shape[0])
    return ForceConstraints(g=force / limit - 1.0, lbg=np.full(rows, -np.inf), ubg=np.zeros(rows), force_n=force,
                            limit_n=limit, n_force=rows, model=model, normalised=True)
