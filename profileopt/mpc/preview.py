"""The terrain envelopes over a moving horizon, as parameters: build a controller once, update
what it sees every step.

:func:`~profileopt.mpc.horizon.terrain_envelope` and
:func:`~profileopt.mpc.horizon.step_speed_envelope` are fixed functions of a whole stretch of
route: a controller that drives a long route must rebuild its solver for each stretch, or
carry an expression that grows with the route (7,573 nodes for 300 m, 70,590 for 3 km). A
:class:`TerrainPreview` is the same two envelopes on a horizon of fixed length that moves with
the vehicle: the B-spline's knots are placed from a parameter ``origin_m`` and its
coefficients are a parameter vector, so the expression has a fixed size, the solver is built
once, and each step only sets the parameters from the terrain measured so far
(:meth:`TerrainPreview.coefficients`).

Terrain that is not measured (beyond the last sample given, less the margin a window or a
step's ramp needs to be seen whole, or before the first) is taken as
the ``unseen`` assumption of the online selector (:func:`profileopt.terrain.assumed.unseen_roughness`,
:func:`profileopt.online.selector.unseen_speed_mps`):
its e_max is that of an ISO 8608 class (``"worst"``: class H) or an RI, so a controller whose
horizon reaches past what its sensors measured keeps the force limit there for any terrain no
rougher than assumed. Steps are not part of that assumption: beyond the samples the step cap
is the vehicle's top speed, and a step that comes into view is kept from then on.

Every envelope at s bounds a stage from s at most ``reach_m`` long that starts within the
horizon: :meth:`TerrainPreview.check_stages` checks a solved horizon's positions against
that before the plan is applied. :meth:`TerrainPreview.stage_functions` and
:meth:`TerrainPreview.path_stage_functions` are the envelopes at n stages at once, the form
``profileopt export-c --preview`` writes as C.

Units: positions and elevations in m, speeds in m/s.
"""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING

import casadi as ca
import numpy as np
from numpy.typing import ArrayLike

from ..errors import InputError
from ..physics.steps import MAX_RAMP_M, TREND_HALF_WIDTH_M, step_caps
from ..terrain.assumed import unseen_roughness
from ..terrain.roughness import range_extremes, roughness_windows, worst_case_elevation
from .horizon import STAGE_LENGTH_TOLERANCE_M, check_stage_lengths, spline_value

if TYPE_CHECKING:
    from ..core.vehicle import Vehicle

__all__ = ["TerrainPreview", "PreviewCoefficients", "PathCoefficients", "DEFAULT_PREVIEW_KNOT_SPACING_M",
           "MAX_PREVIEW_INTERVALS", "UNSEEN_GRADE"]

#: Knot spacing (m) of a preview when none is given: 1 m. With 0.25 m knots a kerb's cap
#: falls within 1 m and a time-domain MPC near it met IPOPT's iteration limit four times in a
#: row (do-mpc, atv-resonant); with 1 m it converged at every step. The price: the envelope
#: rises up to 4 knots (4 m) before a rougher stretch and falls up to 4 m after it.
DEFAULT_PREVIEW_KNOT_SPACING_M = 1.0
#: The most knot intervals a preview may have (horizon / knot spacing): a bound on the size of
#: its expression (about 9 operations per interval).
MAX_PREVIEW_INTERVALS = 20_000
#: Knot intervals of the preview outside its horizon, before and after (so that the spline's
#: clamped ends lie outside it).
_PAD = 3
#: Relative margin of the coefficients over the requirement, for the rounding of the evaluation.
_ROUNDING_MARGIN = 1e-12
#: The steepest grade assumed of a path not given (rise over run, either way): 5 %, the online
#: selector's default unseen descent (:class:`profileopt.online.SpeedSelector`).
UNSEEN_GRADE = 0.05


@dataclasses.dataclass(frozen=True)
class PathCoefficients:
    """The parameter values of the path envelopes for one step (:meth:`TerrainPreview.path_coefficients`).

    Attributes
    ----------
    origin_m : float
        As :attr:`PreviewCoefficients.origin_m` (m).
    curvature : numpy.ndarray, shape (K,)
        Coefficients of the |curvature| envelope (1/m): never below the path's |kappa| where
        a stage can be.
    grade_max, grade_min : numpy.ndarray, shape (K,)
        Coefficients of the steepest uphill and downhill grade envelopes (rad): the first never
        below, the second never above the path's grade where a stage can be.
    path_to_m : float
        Where the given path ends for the envelopes (m); beyond it the tightest turn the vehicle
        can make and +-:data:`UNSEEN_GRADE` are assumed.
    """

    origin_m: float
    curvature: np.ndarray
    grade_max: np.ndarray
    grade_min: np.ndarray
    path_to_m: float


@dataclasses.dataclass(frozen=True)
class PreviewCoefficients:
    """The parameter values of one step.

    Attributes
    ----------
    origin_m : float
        Where the horizon starts (m): the value of the preview's ``origin_m`` parameter, a
        multiple of the knot spacing at most the origin asked for.
    e_max : numpy.ndarray, shape (K,)
        Coefficients of the e_max envelope (m).
    speed_cap : numpy.ndarray, shape (K,)
        Coefficients of the speed cap (m/s): the step limit and the speed limits.
    measured_to_m : float
        Where the trusted terrain ends (m): the last sample given less
        :attr:`TerrainPreview.margin_m`; beyond it the terrain is the ``unseen`` assumption.
    """

    origin_m: float
    e_max: np.ndarray
    speed_cap: np.ndarray
    measured_to_m: float


class TerrainPreview:
    """The e_max envelope and the step speed cap over a moving horizon (module docstring).

    Parameters
    ----------
    vehicle : Vehicle
        The quarter car: ground clearance and confidence (e_max), wheel radius and force limit
        (steps), top speed.
    horizon_m : float
        Length of the horizon from ``origin_m`` (m), > 0: at least the farthest a controller's
        last stage can start from its first, plus ``reach_m``.
    reach_m : float, default 0
        How far beyond s a stage can take the vehicle (m), >= 0: for a controller with
        interval dt and top speed v_max, ``v_max * dt``.
    knot_spacing_m : float, default :data:`DEFAULT_PREVIEW_KNOT_SPACING_M` (1)
        Knot spacing h (m), > 0.
    window_m : float, default 5
        Roughness window W (m), > 0.
    unseen : str or float, default ``"worst"``
        The assumption for terrain not measured: ``"worst"`` (ISO 8608 class H), a class A-H
        or an RI.
    position_error_m : float, default 0
        How far the controller's position may be from the vehicle's (m), >= 0 (a back-off for
        the position estimate and its tracking): the envelopes at s then bound every window
        and ramp overlapping [s - position_error_m, s + reach_m + position_error_m].

    Attributes
    ----------
    e_max : casadi.Function
        ``preview_e_max(s_m, origin_m, e_coef) -> e_max_m``: never below the e_max of any
        roughness window overlapping [s, s + reach_m] (widened by ``position_error_m`` both
        ways), for s in [origin_m, origin_m + horizon_m] (behind the origin it is not a
        bound), with ``e_coef`` from
        :meth:`coefficients` for that origin. Twice
        continuously differentiable in s; ``SX`` inside (``expand`` it), callable on ``MX``.
    speed_cap : casadi.Function
        ``preview_speed_cap(s_m, origin_m, cap_coef) -> speed_cap_mps``: never above SBEM:TF's
        step cap of any ramp of the wheel's path overlapping [s, s + reach_m] (widened as
        ``e_max``; as
        :func:`~profileopt.mpc.horizon.step_speed_envelope`) nor above any speed limit given
        there. A stage from s_k to at most s_k + reach_m at constant acceleration keeps both
        when v_k <= cap(s_k) and v_k+1 <= cap(s_k).
    curvature, grade_max, grade_min : casadi.Function
        ``preview_curvature(s_m, origin_m, curvature_coef) -> curvature_1pm`` never below the
        path's |curvature| over the same stretch as ``e_max`` (and the smoothing's reach);
        ``preview_grade_max`` / ``preview_grade_min`` never below / above its grade (rad)
        there; coefficients from :meth:`path_coefficients`. For
        :func:`~profileopt.mpc.motion_constraints.lateral_constraints` (``v_k`` and ``v_k+1``
        with ``curvature(s_k)``) and
        :func:`~profileopt.mpc.motion_constraints.friction_constraints` (both grades).
    n_coefficients : int
        K, the length of each coefficient vector.
    unseen_e_max_m : float
        e_max (m) of unmeasured terrain.
    horizon_m, reach_m, position_error_m : float
        As given (m). Every envelope holds only for a stage at most ``reach_m`` long that
        starts within the horizon: keep the rows of
        :func:`~profileopt.mpc.horizon.reach_constraints` (``reach_m``) in a free-time problem,
        and check each solved horizon with :meth:`check_stages`.
    """

    def __init__(self, vehicle: "Vehicle", *, horizon_m: float, reach_m: float = 0.0,
                 knot_spacing_m: float = DEFAULT_PREVIEW_KNOT_SPACING_M, window_m: float = 5.0,
                 unseen: str | float = "worst", position_error_m: float = 0.0) -> None:
        from ..core.vehicle import require_vehicle

        vehicle = require_vehicle(vehicle, "TerrainPreview")
        for name, value, least in (("horizon_m", horizon_m, "> 0"), ("knot_spacing_m", knot_spacing_m, "> 0"),
                                   ("window_m", window_m, "> 0"), ("reach_m", reach_m, ">= 0"),
                                   ("position_error_m", position_error_m, ">= 0")):
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or (
                    value < 0 if least == ">= 0" else value <= 0):
                raise InputError(f"TerrainPreview: {name} = {value!r} m must be a finite number {least}")
        self.vehicle = vehicle
        self.horizon_m, self.reach_m = float(horizon_m), float(reach_m)
        self.position_error_m = float(position_error_m)
        self.h_m, self.window_m = float(knot_spacing_m), float(window_m)
        self.n_intervals = int(math.ceil(self.horizon_m / self.h_m - 1e-9)) + 2 * _PAD
        if self.n_intervals > MAX_PREVIEW_INTERVALS:
            raise InputError(f"TerrainPreview: horizon_m = {horizon_m:g} m at knot_spacing_m = {knot_spacing_m:g} m "
                             f"makes {self.n_intervals} knot intervals, above {MAX_PREVIEW_INTERVALS}; choose a "
                             "larger knot spacing or a shorter horizon")
        self.n_coefficients = self.n_intervals + 3
        #: The samples' last metres that are not trusted (m): a roughness window, or a step's
        #: ramp and trend (:attr:`profileopt.online.SpeedSelector.margin_m`), reaching past them.
        self.margin_m = max(self.window_m, MAX_RAMP_M + TREND_HALF_WIDTH_M)
        ri = unseen_roughness(unseen).ri_for(clearance_m=vehicle.ground_clearance_m, window_m=self.window_m)
        self.unseen_e_max_m = float(worst_case_elevation(ri, vehicle))
        s, origin = ca.SX.sym("s_m"), ca.SX.sym("origin_m")
        coef = ca.SX.sym("coef", self.n_coefficients)
        value = spline_value(s, coef, start_m=origin - _PAD * self.h_m, h_m=self.h_m, n_intervals=self.n_intervals)
        self.e_max = ca.Function("preview_e_max", [s, origin, coef], [value], ["s_m", "origin_m", "e_coef"],
                                 ["e_max_m"])
        self.speed_cap = ca.Function("preview_speed_cap", [s, origin, coef], [value],
                                     ["s_m", "origin_m", "cap_coef"], ["speed_cap_mps"])
        self.curvature = ca.Function("preview_curvature", [s, origin, coef], [value],
                                     ["s_m", "origin_m", "curvature_coef"], ["curvature_1pm"])
        self.grade_max = ca.Function("preview_grade_max", [s, origin, coef], [value],
                                     ["s_m", "origin_m", "grade_max_coef"], ["grade_max_rad"])
        self.grade_min = ca.Function("preview_grade_min", [s, origin, coef], [value],
                                     ["s_m", "origin_m", "grade_min_coef"], ["grade_min_rad"])

    def stage_functions(self, *, n_stages: int = 1, prefix: str = "preview") -> tuple[ca.Function, ca.Function]:
        """:attr:`e_max` and :attr:`speed_cap` at ``n_stages`` positions at once (for C export).

        Parameters
        ----------
        n_stages : int, default 1
            How many positions each call takes.
        prefix : str, default ``"preview"``
            The Functions are named ``<prefix>_e_max`` and ``<prefix>_speed_cap`` (C identifiers).

        Returns
        -------
        (casadi.Function, casadi.Function)
            ``(s_m, origin_m, e_coef) -> e_max_m`` and ``(s_m, origin_m, cap_coef) ->
            speed_cap_mps``: ``s_m`` and the output n_stages x 1 (m, m/s), ``origin_m`` a
            number (m), the coefficients K x 1 (:meth:`coefficients`).

        See Also
        --------
        path_stage_functions : the curvature and grade envelopes in the same form.
        """
        return self._stages(((self.e_max, "e_max", "e_coef", "e_max_m"),
                             (self.speed_cap, "speed_cap", "cap_coef", "speed_cap_mps")), n_stages, prefix)

    def path_stage_functions(self, *, n_stages: int = 1,
                             prefix: str = "preview") -> tuple[ca.Function, ca.Function, ca.Function]:
        """:attr:`curvature`, :attr:`grade_max` and :attr:`grade_min` at ``n_stages`` positions at once (for C export).

        The path envelopes in the form of :meth:`stage_functions`: each stage's value is the
        scalar Function's at that stage's position (the same expression, evaluated n_stages
        times), for a controller that evaluates its whole horizon in one call.

        Parameters
        ----------
        n_stages : int, default 1
            How many positions each call takes.
        prefix : str, default ``"preview"``
            The Functions are named ``<prefix>_curvature``, ``<prefix>_grade_max`` and
            ``<prefix>_grade_min`` (C identifiers).

        Returns
        -------
        (casadi.Function, casadi.Function, casadi.Function)
            ``(s_m, origin_m, curvature_coef) -> curvature_1pm`` (1/m), ``(s_m, origin_m,
            grade_max_coef) -> grade_max_rad`` and ``(s_m, origin_m, grade_min_coef) ->
            grade_min_rad`` (rad): ``s_m`` and the output n_stages x 1, ``origin_m`` a number
            (m), the coefficients K x 1 (:meth:`path_coefficients`: ``curvature``,
            ``grade_max``, ``grade_min``).
        """
        return self._stages(((self.curvature, "curvature", "curvature_coef", "curvature_1pm"),
                             (self.grade_max, "grade_max", "grade_max_coef", "grade_max_rad"),
                             (self.grade_min, "grade_min", "grade_min_coef", "grade_min_rad")), n_stages, prefix)

    def check_stages(self, positions_m: ArrayLike, *, origin_m: float | None = None,
                     tolerance_m: float = STAGE_LENGTH_TOLERANCE_M) -> np.ndarray:
        """Refuse a solved horizon whose stages this preview's envelopes do not cover: call after each solve.

        :func:`~profileopt.mpc.horizon.check_stage_lengths` with this preview's ``reach_m``:
        every stage must run forward and at most ``reach_m`` far (and, with ``origin_m``,
        start within the horizon ``[origin_m, origin_m + horizon_m]``), else the envelopes at
        its start do not bound the terrain it meets.

        Parameters
        ----------
        positions_m : array_like, shape (N+1,)
            The solved stage positions s_0 .. s_N (m), e.g. ``sol.value(s)``.
        origin_m : float, optional
            The origin the step's parameters were set with (``coef.origin_m``, m); given,
            every stage must also start within the horizon.
        tolerance_m : float, default :data:`~profileopt.mpc.horizon.STAGE_LENGTH_TOLERANCE_M` (1e-6)
            The solver's tolerance on the rows (m), >= 0.

        Returns
        -------
        numpy.ndarray, shape (N,)
            The stage lengths (m).

        Raises
        ------
        InputError
            One line naming the first stage longer than ``reach_m``, running backwards or
            starting outside the horizon (its index from 0, its start, end and length in m,
            and the reach); or bad positions.
        """
        horizon = None
        if origin_m is not None:
            if isinstance(origin_m, bool) or not isinstance(origin_m, (int, float)) or not math.isfinite(origin_m):
                raise InputError(f"TerrainPreview.check_stages: origin_m = {origin_m!r} must be a finite position (m)")
            horizon = (float(origin_m), float(origin_m) + self.horizon_m)
        try:
            return check_stage_lengths(positions_m, self.reach_m, tolerance_m=tolerance_m, horizon_m=horizon)
        except InputError as exc:
            message = str(exc).replace("check_stage_lengths: ", "", 1)
            if self.reach_m == 0 and "longer than" in message:
                message += "; this preview was built with reach_m = 0 (the envelopes at a point only)"
            raise InputError(f"TerrainPreview.check_stages: {message}") from None

    def _stages(self, specs: tuple, n_stages: int, prefix: str) -> tuple[ca.Function, ...]:
        """Each ``(fn, kind, coef_name, output)`` of ``specs`` at ``n_stages`` positions, named
        ``<prefix>_<kind>``."""
        if not (isinstance(n_stages, int) and not isinstance(n_stages, bool) and n_stages >= 1):
            raise InputError(f"n_stages = {n_stages!r}: must be an integer >= 1")
        s, origin = ca.SX.sym("s_m", n_stages), ca.SX.sym("origin_m")
        out = []
        for fn, kind, coef_name, output in specs:
            coef = ca.SX.sym(coef_name, self.n_coefficients)
            value = ca.vertcat(*(fn(s[i], origin, coef) for i in range(n_stages)))
            out.append(ca.Function(f"{prefix}_{kind}", [s, origin, coef], [value], ["s_m", "origin_m", coef_name],
                                   [output]))
        return tuple(out)

    def _supports(self, origin_m: float) -> tuple[np.ndarray, np.ndarray]:
        """Each basis function's support [lo, hi] (m) for a horizon starting at ``origin_m``."""
        start = origin_m - _PAD * self.h_m
        j = np.arange(self.n_coefficients)
        return start + (j - 3) * self.h_m, start + (j + 1) * self.h_m

    def path_coefficients(self, positions_m: ArrayLike, elevations_m: ArrayLike, origin_m: float, *,
                          x_m: ArrayLike | None = None, y_m: ArrayLike | None = None,
                          path_tolerance_m: float | None = None) -> PathCoefficients:
        """The parameter values of the curvature and grade envelopes over a path's samples.

        The path's curvature and grade are the planner's (:func:`profileopt.terrain.geometry.route_geometry`:
        the smoothed path within ``path_tolerance_m``, estimated from x, y when not given; the
        grade over twice the roughness window). Coefficient j of the curvature envelope is the
        largest |kappa| of the samples in basis function j's support widened by the reach, the
        position error and the smoothing's own reach; of the grade envelopes the largest and
        least grade there. Where the support reaches past the samples (less half the grade's
        window and the smoothing's reach) the vehicle's tightest turn (1 / ``min_turn_radius_m``)
        and +-:data:`UNSEEN_GRADE` are assumed.

        Parameters
        ----------
        positions_m, elevations_m : array_like, shape (M,)
            The path's samples: distance along it (m), strictly increasing, and elevation (m).
        origin_m : float
            Where the horizon starts (m), as for :meth:`coefficients`.
        x_m, y_m : array_like, shape (M,), optional
            The path in the horizontal plane (m); without them it is straight.
        path_tolerance_m : float, optional
            Largest deviation of the smoothed path from a sample (m), > 0; estimated from x, y
            when not given.

        Returns
        -------
        PathCoefficients

        Raises
        ------
        InputError
            Bad samples (as for a route), a non-finite origin, or a vehicle without
            ``min_turn_radius_m`` when the horizon reaches past the path given.
        """
        from ..core.route import Route
        from ..terrain.geometry import route_geometry

        if isinstance(origin_m, bool) or not isinstance(origin_m, (int, float)) or not math.isfinite(origin_m):
            raise InputError(f"TerrainPreview.path_coefficients: origin_m = {origin_m!r} must be a finite position (m)")
        route = Route(s_m=np.asarray(positions_m, dtype=float), z_m=np.asarray(elevations_m, dtype=float),
                      x_m=None if x_m is None else np.asarray(x_m, dtype=float),
                      y_m=None if y_m is None else np.asarray(y_m, dtype=float),
                      source="TerrainPreview.path_coefficients")
        geometry = route_geometry(route, tolerance_m=path_tolerance_m, grade_scale_m=2.0 * self.window_m,
                                  min_turn_radius_m=self.vehicle.min_turn_radius_m)
        s = route.s_m
        origin_m = math.floor(float(origin_m) / self.h_m + 1e-9) * self.h_m
        spread = self.reach_m + self.position_error_m + geometry.curvature_reach_m
        trusted = max(float(s[-1]) - max(self.window_m, geometry.curvature_reach_m), float(s[0]))
        lo, hi = self._supports(origin_m)
        lo = np.maximum(lo, origin_m) - self.position_error_m - geometry.curvature_reach_m
        hi = np.maximum(hi, origin_m) + spread
        first = np.searchsorted(s, np.clip(lo, s[0], trusted), side="left")
        stop = np.maximum(np.searchsorted(s, np.clip(hi, s[0], trusted), side="right"), first + 1)
        stop = np.minimum(stop, s.size)
        first = np.minimum(first, stop - 1)
        kappa_hi = range_extremes(np.abs(geometry.curvature_1pm), first, stop)[1]
        grade_lo, grade_hi = range_extremes(geometry.grade_rad, first, stop)
        beyond = (hi > trusted) | (lo < s[0])
        if np.any(beyond):
            radius = self.vehicle.min_turn_radius_m
            if radius is None:
                raise InputError("TerrainPreview.path_coefficients: the horizon reaches past the path given and the "
                                 "vehicle has no min_turn_radius_m to assume there; give the path as far as the "
                                 "horizon reaches, or add min_turn_radius_m (m) to the vehicle file")
            unseen = math.atan(UNSEEN_GRADE)
            kappa_hi = np.where(beyond, np.maximum(kappa_hi, 1.0 / float(radius)), kappa_hi)
            grade_hi = np.where(beyond, np.maximum(grade_hi, unseen), grade_hi)
            grade_lo = np.where(beyond, np.minimum(grade_lo, -unseen), grade_lo)
        pad = _ROUNDING_MARGIN * max(float(np.max(np.abs(np.concatenate([kappa_hi, grade_hi, grade_lo])))), 1e-300)
        return PathCoefficients(origin_m=float(origin_m), curvature=kappa_hi + pad, grade_max=grade_hi + pad,
                                grade_min=grade_lo - pad, path_to_m=trusted)

    def coefficients(self, positions_m: ArrayLike, elevations_m: ArrayLike, origin_m: float, *,
                     speed_limit_mps: ArrayLike | None = None) -> PreviewCoefficients:
        """The parameter values for a horizon starting at ``origin_m`` over the measured samples.

        Coefficient j of the e_max envelope is the largest e_max (Eq. 8) of the roughness windows
        of the samples that overlap basis function j's support widened by ``reach_m``, and at
        least the unseen e_max where that support reaches past the samples; of the speed cap,
        the lowest cap of the wheel's ramps there (:func:`profileopt.physics.steps.step_caps`)
        and the lowest speed limit of the samples there, at most the top speed. (The spline is
        a weighted mean of the coefficients that cover s, so a coefficient-wise least of two
        caps is below both.)

        Parameters
        ----------
        positions_m : array_like, shape (M,)
            Distance along the path of each measured sample (m), strictly increasing, M >= 2.
        elevations_m : array_like, shape (M,)
            Elevation of each sample (m).
        origin_m : float
            Where the horizon starts (m), normally the vehicle's position; moved down to a
            multiple of the knot spacing (:attr:`PreviewCoefficients.origin_m`: pass that to
            the Functions), so that the knots stay where they are from step to step.
        speed_limit_mps : array_like, shape (M,), optional
            A speed limit at each sample (m/s), > 0, from a map.

        Returns
        -------
        PreviewCoefficients

        Raises
        ------
        InputError
            Bad samples (as for a route) or a non-finite origin.
        """
        from ..core.route import Route

        if isinstance(origin_m, bool) or not isinstance(origin_m, (int, float)) or not math.isfinite(origin_m):
            raise InputError(f"TerrainPreview.coefficients: origin_m = {origin_m!r} must be a finite position (m)")
        route = Route(s_m=np.asarray(positions_m, dtype=float), z_m=np.asarray(elevations_m, dtype=float),
                      source="TerrainPreview.coefficients")
        s, z = route.s_m, route.z_m
        # knots at multiples of h: the origin moved down to one, so that the envelope at a
        # position does not change from one step to the next while the terrain there does not
        origin_m = math.floor(float(origin_m) / self.h_m + 1e-9) * self.h_m
        # the samples' last margin_m are not trusted: windows and ramps that reach past the
        # last sample are seen only in part there
        trusted = max(float(s[-1]) - self.margin_m, float(s[0]))
        lo, hi = self._supports(float(origin_m))
        # only positions from the origin on are bounded: the support's part behind it does not count
        # (widened by the position error both ways: the vehicle may be that far behind or ahead)
        error = self.position_error_m
        lo = np.maximum(lo, float(origin_m)) - error
        hi = np.maximum(hi + self.reach_m, float(origin_m)) + error
        # the windows of the measured samples
        windows = roughness_windows(s, z, self.vehicle.ground_clearance_m, window_m=self.window_m,
                                    source="TerrainPreview.coefficients")
        e_window = np.asarray(worst_case_elevation(windows.ri, self.vehicle), dtype=float)
        inside_lo, inside_hi = np.clip(lo, s[0], trusted), np.clip(hi, s[0], trusted)
        first, stop = windows.overlapping(inside_lo, inside_hi)
        measured = range_extremes(e_window, first, stop)[1]
        beyond = (hi > trusted) | (lo < s[0])
        e_coef = np.where(beyond, np.maximum(measured, self.unseen_e_max_m), measured)
        e_coef = e_coef + _ROUNDING_MARGIN * float(np.max(e_coef))
        top = float(self.vehicle.max_speed_mps)
        caps = step_caps(s, z, self.vehicle).lowest_over(inside_lo, inside_hi, top)
        if speed_limit_mps is not None:
            limit = np.asarray(speed_limit_mps, dtype=float)
            if limit.shape != s.shape or not np.all(limit > 0):
                raise InputError("TerrainPreview.coefficients: give one speed limit > 0 (m/s) per sample")
            a = np.searchsorted(s, inside_lo, side="right") - 1  # the samples whose limit holds there
            b = np.searchsorted(s, inside_hi, side="left") + 1
            running = [float(np.min(limit[max(i, 0):max(k, i + 1)])) for i, k in zip(a, b)]
            caps = np.minimum(caps, running)
        caps = np.where((hi < s[0]) | (lo > trusted), top, caps) - _ROUNDING_MARGIN * top
        return PreviewCoefficients(origin_m=float(origin_m), e_max=e_coef, speed_cap=caps, measured_to_m=trusted)
