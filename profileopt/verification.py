"""Check a plan against a simulated vehicle: the forces it really causes on the route.

:func:`verify` drives the vehicle's quarter car (:mod:`profileopt.simulate`) over the
route's own elevation samples at the profile's speeds, and sets each segment's simulated
peak force beside the model's prediction and the vehicle's limit. The prediction is
recomputed from the profile's speeds (the file's ``force_n`` column is not trusted), and
before the simulation :func:`check_limits` checks the profile against the vehicle's own
limits, the ones every plan keeps (:func:`profileopt.planning.default_limits`): speed,
acceleration, jerk and predicted force. The force compared with the limit is the one the model limits: the transmitted force
F_T for SBEM:TF, the excitation force F = k y + c y' for Prev:BEM, IECM and SBEM:EF.

The simulation is linear and keeps the wheel on the ground. A massless wheel presses on the
ground with m g + F_T, so where F_T < -m g the real wheel would leave the ground and land
again; such segments are flagged (``lift_off``): there the linear model's downward force is
not physical (a real vehicle would see the landing instead).
"""

from __future__ import annotations

import dataclasses
import json
import math
import time
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from .io.atomic import atomic_write
from .errors import InputError
from .forces import get_model
from .kinematics import boundary_jerk_mps3, segment_accel_mps2
from .planning.limits import default_limits
from .planning.limits.base import PlanContext
from .planning.limits.force import max_force_over_segments
from .planning.options import SolverOptions
from .planning.segments import Segments
from .simulate import QuarterCarRun, simulate_quarter_car
from .stations import segment_index, segment_samples
from .terrain import segment_roughness_index, worst_case_elevation

if TYPE_CHECKING:
    from .planning.result import Profile
    from .route import Route
    from .vehicle import Vehicle

__all__ = ["Verification", "verify", "check_limits", "LimitCheck", "LimitBreach", "VERIFICATION_COLUMNS",
           "STANDARD_GRAVITY_MPS2", "LIMIT_RTOL"]

#: Standard gravity (m/s^2), for the static wheel load m g.
STANDARD_GRAVITY_MPS2 = 9.80665
#: Columns of the verification CSV, in order.
VERIFICATION_COLUMNS = (
    "s_start_m", "s_end_m", "speed_start_mps", "speed_end_mps", "ri",
    "predicted_force_n", "force_limit_n",
    "sim_transmitted_peak_n", "sim_transmitted_up_n", "sim_transmitted_down_n", "sim_excitation_peak_n",
    "ratio", "over_limit", "lift_off",
)
#: A simulated peak counts as above the prediction only beyond this share of the limit,
#: so that the ringing after a rough patch over smooth ground (prediction 0) is not counted.
UNDERPREDICTION_TOLERANCE = 0.01
#: A profile keeps a limit when it exceeds it by at most this share of it: the planner's own
#: check (:attr:`profileopt.planning.SolverOptions.check_rtol`), so a planned profile passes.
LIMIT_RTOL = SolverOptions.check_rtol
#: The profile's force_n column counts as stale when it differs from the forces its speeds
#: give by more than this share of the limit (the file's 17 digits give them back exactly).
STALE_FORCE_RTOL = 1e-9


@dataclasses.dataclass(frozen=True)
class LimitBreach:
    """Where a profile first breaks one of the vehicle's limits, and how often.

    Attributes
    ----------
    quantity : str
        ``"speed"``, ``"acceleration"``, ``"deceleration"``, ``"jerk"`` or ``"force"``.
    limit_name : str
        The limit broken, in words (``"the vehicle's top speed"``).
    segment : int
        The first segment that breaks it (for jerk: the segment after the boundary).
    s_m : float
        Where (m): the segment's start, or the boundary for jerk.
    value : float
        The profile's value there (m/s, m/s^2, m/s^3 or N; deceleration as a positive number).
    limit : float
        The limit there, in the same unit.
    unit : str
        The unit of ``value`` and ``limit``.
    count : int
        How many segments (boundaries, for jerk) break it.
    of : int
        How many there are.
    worst_ratio : float
        The largest value / limit anywhere.
    """

    quantity: str
    limit_name: str
    segment: int
    s_m: float
    value: float
    limit: float
    unit: str
    count: int
    of: int
    worst_ratio: float

    def describe(self) -> str:
        """One line: which limit, where first, by how much, how often."""
        where = "at the boundary" if self.quantity == "jerk" else "in the segment from"
        places = "boundaries" if self.quantity == "jerk" else "segments"
        value = f"{self.value:.4g} {self.unit}" if math.isfinite(self.value) else "too large to compute"
        worst = f"{self.worst_ratio:.4g} times the limit" if math.isfinite(self.worst_ratio) else "beyond any number"
        return (f"breaks {self.limit_name} ({self.limit:.4g} {self.unit}) first {where} s = {self.s_m:g} m "
                f"(segment {self.segment}): {self.quantity} {value}; {self.count} of {self.of} {places}, "
                f"worst {worst}")

    def to_dict(self) -> dict:
        """The fields, JSON-ready (a value that is not a finite number is None)."""
        return {key: None if isinstance(value, float) and not math.isfinite(value) else value
                for key, value in dataclasses.asdict(self).items()}


@dataclasses.dataclass(frozen=True, eq=False)
class LimitCheck:
    """A profile checked against the vehicle's own limits, on paper (:func:`check_limits`).

    Attributes
    ----------
    model : str
        Force model key.
    ri : numpy.ndarray, shape (N,)
        Each segment's RI, measured on the route.
    predicted_n : numpy.ndarray, shape (N,)
        The model's largest force over the speeds between each segment's two boundary
        speeds (resonance peaks included), from the profile's speeds (N).
    limit_n : float
        The vehicle's limit for the model's force (N).
    breaches : tuple of LimitBreach
        The limits the profile breaks, in the order speed, acceleration, deceleration,
        jerk, force; empty when it keeps them all.
    notes : tuple of str
        Remarks (a stale force column, a force limit in the file that is not the vehicle's).
    """

    model: str
    ri: np.ndarray
    predicted_n: np.ndarray
    limit_n: float
    breaches: tuple[LimitBreach, ...]
    notes: tuple[str, ...]


@dataclasses.dataclass(frozen=True, eq=False)
class Verification:
    """A profile checked against the simulated quarter car, segment by segment.

    Attributes
    ----------
    s_m : numpy.ndarray, shape (N+1,)
        Segment boundaries (m).
    speed_mps : numpy.ndarray, shape (N+1,)
        The profile's speeds at the boundaries (m/s).
    ri : numpy.ndarray, shape (N,)
        Each segment's RI (dimensionless), from the profile.
    predicted_n : numpy.ndarray, shape (N,)
        The model's largest predicted force over the speeds driven in the segment (N),
        recomputed from the profile's speeds (:func:`check_limits`).
    limit_n : numpy.ndarray, shape (N,)
        The vehicle's limit for the model's force (N).
    transmitted_peak_n : numpy.ndarray, shape (N,)
        Simulated largest |F_T| in the segment (N).
    transmitted_up_n, transmitted_down_n : numpy.ndarray, shape (N,)
        Simulated largest and smallest F_T (N): upwards (compressing the suspension) and
        downwards.
    excitation_peak_n : numpy.ndarray, shape (N,)
        Simulated largest |k y + c y'| (N), y measured from the segment's trend line.
    simulated_n : numpy.ndarray, shape (N,)
        The simulated peak of the model's own force (``transmitted_peak_n`` for SBEM:TF,
        ``excitation_peak_n`` otherwise) (N).
    ratio : numpy.ndarray, shape (N,)
        ``simulated_n / limit_n`` (dimensionless); above 1 the plan is not safe there.
    model : str
        Force model key.
    quantity : str
        ``"transmitted"`` or ``"excitation"``.
    route, vehicle : str
        Where the route and the vehicle came from.
    weight_n : float
        Static wheel load m g (N); F_T below -m g means the wheel leaves the ground.
    travel_time_s : float
        Time to drive the profile (s).
    run : QuarterCarRun
        The simulation itself (time series), for plots.
    timings_s : dict
        Wall-clock seconds: ``simulate`` (of which ``envelope`` and ``integrate``),
        ``total``.
    notes : tuple of str
        Remarks for the user (for example a profile limit that differs from the vehicle's).
    breaches : tuple of LimitBreach
        Where the profile breaks the vehicle's own limits on paper (:func:`check_limits`);
        empty when it keeps them all.
    """

    s_m: np.ndarray
    speed_mps: np.ndarray
    ri: np.ndarray
    predicted_n: np.ndarray
    limit_n: np.ndarray
    transmitted_peak_n: np.ndarray
    transmitted_up_n: np.ndarray
    transmitted_down_n: np.ndarray
    excitation_peak_n: np.ndarray
    simulated_n: np.ndarray
    ratio: np.ndarray
    model: str
    quantity: str
    route: str
    vehicle: str
    weight_n: float
    travel_time_s: float
    run: QuarterCarRun
    timings_s: dict
    notes: tuple[str, ...] = ()
    breaches: tuple[LimitBreach, ...] = ()

    @property
    def keeps_limits(self) -> bool:
        """True when the profile keeps every limit of the vehicle on paper (no breach)."""
        return not self.breaches

    @property
    def passes(self) -> bool:
        """True when it keeps every limit and no segment's simulated force exceeds the limit."""
        return self.keeps_limits and self.over_count == 0

    @property
    def length_m(self) -> np.ndarray:
        """Segment lengths (m), shape (N,)."""
        return np.diff(self.s_m)

    @property
    def over(self) -> np.ndarray:
        """Segments whose simulated force exceeds the limit (bool, shape (N,))."""
        return self.ratio > 1.0

    @property
    def over_count(self) -> int:
        """Number of segments over the limit."""
        return int(np.count_nonzero(self.over))

    @property
    def over_length_m(self) -> float:
        """Total length of the segments over the limit (m)."""
        return float(np.sum(self.length_m[self.over]))

    @property
    def over_fraction(self) -> float:
        """Share of the segments over the limit (dimensionless, 0 to 1)."""
        return self.over_count / self.ratio.size

    @property
    def worst_ratio(self) -> float:
        """Largest simulated force / limit (dimensionless)."""
        return float(np.max(self.ratio))

    @property
    def worst_segment(self) -> int:
        """Index of the segment with the largest ratio."""
        return int(np.argmax(self.ratio))

    @property
    def lift_off(self) -> np.ndarray:
        """Segments where F_T < -m g: the real wheel would leave the ground (bool, (N,))."""
        return self.transmitted_down_n < -self.weight_n

    @property
    def underpredicted(self) -> np.ndarray:
        """Segments whose simulated force exceeds the prediction by more than 1 % of the
        limit: where the model was not conservative (bool, shape (N,))."""
        return self.simulated_n > self.predicted_n + UNDERPREDICTION_TOLERANCE * self.limit_n

    def summary(self, timings: bool = True) -> dict:
        """The headline numbers, JSON-ready (SI units in the key names).

        ``timings=False`` leaves out the wall-clock times, so that the same inputs give
        the same summary on every run.

        Parameters
        ----------
        timings : bool, optional
            Include ``"timings_s"``, the wall-clock time of each stage (s). Default True.

        Returns
        -------
        dict
            Route, vehicle, model, the worst segment and counts over the limit, the
            simulation's step, the notes (and the timings).
        """
        i = self.worst_segment
        return {
            "route": self.route,
            "vehicle": self.vehicle,
            "model": self.model,
            "quantity": self.quantity,
            "segments": int(self.ratio.size),
            "travel_time_s": self.travel_time_s,
            "worst_ratio": self.worst_ratio,
            "worst_segment_start_m": float(self.s_m[i]),
            "worst_simulated_n": float(self.simulated_n[i]),
            "worst_predicted_n": float(self.predicted_n[i]),
            "over_count": self.over_count,
            "over_length_m": self.over_length_m,
            "over_fraction": self.over_fraction,
            "underpredicted_count": int(np.count_nonzero(self.underpredicted)),
            "lift_off_count": int(np.count_nonzero(self.lift_off)),
            "time_step_s": self.run.time_step_s,
            "steps": self.run.steps,
            "notes": list(self.notes),
            "keeps_limits": self.keeps_limits,
            "breaches": [b.to_dict() for b in self.breaches],
        } | ({"timings_s": dict(self.timings_s)} if timings else {})

    def columns(self) -> dict[str, np.ndarray]:
        """The CSV columns by name, in order (:data:`VERIFICATION_COLUMNS`)."""
        return {
            "s_start_m": self.s_m[:-1],
            "s_end_m": self.s_m[1:],
            "speed_start_mps": self.speed_mps[:-1],
            "speed_end_mps": self.speed_mps[1:],
            "ri": self.ri,
            "predicted_force_n": self.predicted_n,
            "force_limit_n": self.limit_n,
            "sim_transmitted_peak_n": self.transmitted_peak_n,
            "sim_transmitted_up_n": self.transmitted_up_n,
            "sim_transmitted_down_n": self.transmitted_down_n,
            "sim_excitation_peak_n": self.excitation_peak_n,
            "ratio": self.ratio,
            "over_limit": self.over.astype(int),
            "lift_off": self.lift_off.astype(int),
        }

    def to_csv(self, path: str | Path) -> None:
        """Write one row per segment (:data:`VERIFICATION_COLUMNS`) atomically.

        Numbers carry 10 significant digits; the same inputs give the same bytes.

        Parameters
        ----------
        path : str or pathlib.Path
            The CSV file to create or replace; its folder must exist.
        """
        cols = self.columns()
        with atomic_write(path) as handle:
            handle.write(f"# profileopt verify: route {Path(self.route).name}, vehicle {Path(self.vehicle).name}, model {self.model} "
                         f"({self.quantity} force); forces in N, speeds in m/s, s in m\n")
            handle.write(",".join(VERIFICATION_COLUMNS) + "\n")
            for row in zip(*cols.values()):
                handle.write(",".join(str(int(v)) if isinstance(v, (np.integer, int)) else f"{v + 0.0:.10g}"
                                      for v in row) + "\n")

    def to_json(self, timings: bool = True) -> str:
        """:meth:`summary` as indented JSON (with ``timings=False``, the same on every run).

        Parameters
        ----------
        timings : bool, optional
            Include the wall-clock times (see :meth:`summary`). Default True.

        Returns
        -------
        str
        """
        return json.dumps(self.summary(timings), indent=2)


def _check_coverage(route: "Route", s: np.ndarray) -> None:
    """Refuse a profile whose first or last boundary is not the route's first or last sample."""
    span = max(abs(route.s_m[0]), abs(route.s_m[-1]), 1.0) * 1e-9
    for end, mine, theirs in (("start", s[0], route.s_m[0]), ("end", s[-1], route.s_m[-1])):
        gap = float(mine - theirs)
        if abs(gap) > span:
            side = "after" if gap > 0 else "before"
            raise InputError(
                f"{route.source}: the profile covers s = {s[0]:g} to {s[-1]:g} m but the route {route.s_m[0]:g} to "
                f"{route.s_m[-1]:g} m: the profile's {end} lies {abs(gap):g} m {side} the route's {end}; a profile "
                "must cover its route exactly, so verify the whole profile planned on this route"
            )


def _jerk_bound_mps3(profile: "Profile", vehicle: "Vehicle") -> tuple[float, str]:
    """The jerk bound the profile records in its settings (else the vehicle's), and its name."""
    recorded = profile.settings.get("max_jerk_mps3")
    if recorded is None:
        return vehicle.max_jerk_mps3, "the vehicle's jerk limit"
    try:
        bound = float(recorded)
    except (TypeError, ValueError):
        bound = math.nan
    if not bound > 0:
        raise InputError(f"profile: max_jerk_mps3={recorded} in its settings line is not a number > 0; write "
                         "the profile with 'profileopt plan -o'")
    return bound, "the jerk bound the profile was planned with"


def _first_breach(quantity: str, limit_name: str, values: np.ndarray, limit: np.ndarray, where_m: np.ndarray,
                  segments: np.ndarray, unit: str) -> LimitBreach | None:
    """The first place where ``values`` exceed ``limit`` by more than :data:`LIMIT_RTOL`
    (a value that is not a number counts as beyond), or None."""
    limit = np.broadcast_to(np.asarray(limit, dtype=float), values.shape)
    broken = ~(values <= limit * (1.0 + LIMIT_RTOL))
    if not np.any(broken):
        return None
    k = int(np.flatnonzero(broken)[0])
    ratio = values / limit
    worst = float(np.max(np.where(np.isnan(ratio), np.inf, ratio)))
    return LimitBreach(quantity=quantity, limit_name=limit_name, segment=int(segments[k]), s_m=float(where_m[k]),
                       value=float(values[k]), limit=float(limit[k]), unit=unit,
                       count=int(np.count_nonzero(broken)), of=int(values.size), worst_ratio=worst)


def check_limits(
    route: "Route",
    profile: "Profile",
    vehicle: "Vehicle",
    *,
    model: str | None = None,
) -> LimitCheck:
    """Check a profile against the vehicle's own limits, on paper, from its speeds alone.

    The profile must cover the route exactly (its first and last boundaries are the route's
    first and last samples) and its RI column must be the route's own. The limits are the
    ones every plan keeps (:func:`profileopt.planning.default_limits`): the speed caps (the
    vehicle's top speed and the route's ``speed_limit``), the acceleration and deceleration
    bounds, the jerk bound the profile records in its settings (else the vehicle's), and the
    model's force limit. The predicted force of each segment is recomputed from the speeds:
    the largest force over every speed between its two boundary speeds, resonance peaks
    included (:func:`profileopt.planning.limits.force.max_force_over_segments`). The file's
    ``force_n`` column is not used (a note says so when it differs). A limit counts as kept
    within :data:`LIMIT_RTOL` of it, the planner's own tolerance.

    Parameters
    ----------
    route : Route
        The terrain the profile was planned on.
    profile : Profile
        The speeds at the segment boundaries (m/s) and the RI of each segment.
    vehicle : Vehicle
        The vehicle and its limits.
    model : str, optional
        Force model key; default ``profile.model``.

    Returns
    -------
    LimitCheck

    Raises
    ------
    InputError
        The profile does not cover the route exactly, its RI column does not match the
        route's segments, its recorded jerk bound is not a number > 0, or the model is
        unknown.
    """
    key = profile.model if model is None else model
    force_model = get_model(key)
    s = np.asarray(profile.s_m, dtype=float)
    v = np.asarray(profile.speed_mps, dtype=float)
    _check_coverage(route, s)
    starts, stops = segment_samples(route.s_m, s)
    ri_here = segment_roughness_index(route.s_m, route.z_m, starts, vehicle.ground_clearance_m)
    mismatch = np.flatnonzero(~np.isclose(np.asarray(profile.ri, dtype=float)[:-1], ri_here, rtol=1e-6, atol=1e-9))
    if mismatch.size:
        i = mismatch[0]
        raise InputError(
            f"{route.source}: segment {i} ({s[i]:g} to {s[i + 1]:g} m) has RI {ri_here[i]:.4g} on this route "
            f"but {profile.ri[i]:.4g} in the profile; verify a profile on the route and vehicle (ground "
            "clearance) it was planned for"
        )
    notes: list[str] = []
    limit = force_model.limit_n(vehicle)
    profile_limit = np.asarray(profile.force_limit_n, dtype=float)[:-1]
    if np.any(np.abs(profile_limit - limit) > 1e-9 * limit):
        notes.append(
            f"the profile's force_limit_n ({profile_limit.min():g} to {profile_limit.max():g} N) differs from "
            f"{vehicle.name or 'the vehicle'}'s {force_model.limit_key} = {limit:g} N: was it planned with "
            "another vehicle or model? The vehicle's limit is used"
        )
    jerk_bound, jerk_name = _jerk_bound_mps3(profile, vehicle)
    length = np.diff(s)
    segments = Segments(boundaries_m=s, length_m=length, ri=ri_here, e_max_m=worst_case_elevation(ri_here, vehicle),
                        first_sample=starts, samples=stops - starts)
    context = PlanContext(route=route, vehicle=vehicle, segments=segments)
    limits = default_limits(vehicle, model=force_model.key, max_jerk_mps3=jerk_bound)
    caps = [c for c in (lim.speed_cap_mps(context) for lim in limits) if c is not None]
    accel_bounds = [b for b in (lim.accel_bounds_mps2(context) for lim in limits) if b is not None]
    jerk_limit = min(lim.jerk_bound_mps3(context) for lim in limits)
    bands = next(b for b in (lim.speed_bands(context) for lim in limits) if b is not None)
    n = s.size - 1
    index = np.arange(n)
    breaches: list[LimitBreach | None] = []
    # numbers as large as 1e155 m/s overflow on squaring: they break the limits, silently
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        # the vehicle's top speed first, then the route's speed_limit where it is lower
        cap = np.minimum.reduce(caps)
        top = np.maximum(v[:-1], v[1:])
        breaches.append(_first_breach("speed", "the vehicle's top speed", top, np.array(vehicle.max_speed_mps),
                                      s[:-1], index, "m/s"))
        lower = cap < vehicle.max_speed_mps
        breaches.append(_first_breach("speed", "the route's speed_limit", top[lower], cap[lower], s[:-1][lower],
                                      index[lower], "m/s"))
        b = v * v
        accel = segment_accel_mps2(b[:-1], b[1:], length)
        decel_bound = np.minimum.reduce([d for d, _ in accel_bounds])
        accel_bound = np.minimum.reduce([a for _, a in accel_bounds])
        breaches.append(_first_breach("acceleration", "the vehicle's acceleration limit", accel, accel_bound,
                                      s[:-1], index, "m/s^2"))
        breaches.append(_first_breach("deceleration", "the vehicle's deceleration limit", -accel, decel_bound,
                                      s[:-1], index, "m/s^2"))
        if n >= 2 and math.isfinite(jerk_limit):
            jerk = boundary_jerk_mps3(v[1:-1], accel[:-1], accel[1:], length[:-1], length[1:])
            breaches.append(_first_breach("jerk", jerk_name, np.abs(jerk), np.array(jerk_limit), s[1:-1],
                                          index[1:], "m/s^3"))
        predicted = max_force_over_segments(force_model.key, vehicle, ri_here, v, bands.peaks_mps)
        breaches.append(_first_breach("force", f"the {force_model.label} force limit", predicted, np.array(limit),
                                      s[:-1], index, "N"))
        recorded = np.asarray(profile.force_n, dtype=float)[:-1]
        stale = np.flatnonzero(~(np.abs(recorded - predicted) <= STALE_FORCE_RTOL * limit))
    if stale.size:
        i = stale[0]
        notes.append(
            f"the profile's force_n column is stale in {stale.size} of {n} segments (first at s = {s[i]:g} m: "
            f"{recorded[i]:.6g} N recorded, {predicted[i]:.6g} N from its speeds): the predicted forces were "
            "recomputed from the speeds"
        )
    return LimitCheck(model=force_model.key, ri=ri_here, predicted_n=predicted, limit_n=float(limit),
                      breaches=tuple(b for b in breaches if b is not None), notes=tuple(notes))


def verify(
    route: "Route",
    profile: "Profile",
    vehicle: "Vehicle",
    *,
    model: str | None = None,
    detrend: bool = True,
    check: LimitCheck | None = None,
) -> Verification:
    """Simulate the vehicle driving ``profile`` over ``route`` and compare with the limits.

    The profile is first checked against the vehicle's own limits (:func:`check_limits`;
    the breaches are in :attr:`Verification.breaches`), which also recomputes each
    segment's predicted force from the speeds; then the quarter car is simulated.

    Parameters
    ----------
    route : Route
        The terrain (the samples the profile was planned on).
    profile : Profile
        Speeds at the segment boundaries (m/s) and the RI of each segment.
    vehicle : Vehicle
        The quarter car (m, wn, zeta, r) and the force limits (N).
    model : str, optional
        The force model to check against; default ``profile.model`` (the model the profile
        was planned with, recorded in its CSV).
    detrend : bool, default True
        Datum of the excitation force: each segment's trend line (True, as the RI) or
        mean (False).
    check : LimitCheck, optional
        The result of :func:`check_limits` for the same arguments, if already computed.

    Returns
    -------
    Verification

    Raises
    ------
    InputError
        The profile does not cover the route exactly, its RI column does not match the
        route's segments (another route, or a vehicle with another ground clearance), a
        segment is never crossed (speed 0 at both of its ends), a speed is too large to
        simulate, or the model is unknown.
    """
    t_start = time.perf_counter()
    if check is None:
        check = check_limits(route, profile, vehicle, model=model)
    force_model = get_model(check.model)
    s = np.asarray(profile.s_m, dtype=float)
    run = simulate_quarter_car(route.s_m, route.z_m, s, profile.speed_mps, vehicle, detrend=detrend)
    t_sim = time.perf_counter()

    seg = segment_index(run.s_m, s)
    starts = np.searchsorted(seg, np.arange(s.size - 1), side="left")
    up = np.maximum.reduceat(run.transmitted_n, starts)
    down = np.minimum.reduceat(run.transmitted_n, starts)
    simulated = run.transmitted_peak_n if force_model.quantity == "transmitted" else run.excitation_peak_n
    limit_n = np.full(s.size - 1, check.limit_n)
    t_end = time.perf_counter()
    return Verification(
        s_m=s.copy(),
        speed_mps=np.asarray(profile.speed_mps, dtype=float).copy(),
        ri=np.asarray(profile.ri, dtype=float)[:-1].copy(),
        predicted_n=check.predicted_n.copy(),
        limit_n=limit_n,
        transmitted_peak_n=run.transmitted_peak_n,
        transmitted_up_n=up,
        transmitted_down_n=down,
        excitation_peak_n=run.excitation_peak_n,
        simulated_n=simulated,
        ratio=simulated / limit_n,
        model=force_model.key,
        quantity=force_model.quantity,
        route=str(route.source),
        vehicle=vehicle.name or "vehicle",
        weight_n=vehicle.quarter_mass_kg * STANDARD_GRAVITY_MPS2,
        travel_time_s=float(run.time_s[-1]),
        run=run,
        timings_s={
            "simulate": t_sim - t_start,
            "envelope": run.timings_s["envelope"],
            "integrate": run.timings_s["integrate"],
            "total": t_end - t_start,
        },
        notes=check.notes,
        breaches=check.breaches,
    )
