"""A speed profile checked on paper against the vehicle's own limits, before any simulation.

:func:`check_limits` checks that a profile covers its route, recomputes each segment's
predicted force from the profile's speeds (the file's ``force_n`` column is not trusted) and
finds where the profile first breaks each limit of the vehicle: top speed, the caps of
steps, the route's speed limits and turns, acceleration, deceleration, the friction circle,
drive power, jerk and predicted force. Every limit is computed here from the vehicle, the
route and :mod:`profileopt.physics`, never from the planner's own numbers, so it checks the
planner rather than repeating it. :func:`profileopt.verify` calls it before it simulates;
``profileopt verify`` turns its breaches into exit status 3.
"""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING

import numpy as np

from ..core.kinematics import boundary_jerk_mps3, segment_accel_mps2
from ..core.path import segment_path
from ..core.segments import Segments, route_roughness_windows, segments_at
from ..core.stations import segment_samples
from ..defaults import CRAWL_SPEED_MPS, DEFAULT_PATH_TOLERANCE_M, DEFAULT_ROUGHNESS_WINDOW_M, LIMIT_RTOL
from ..errors import InputError
from ..physics.forces import get_model
from ..physics.motion import STANDARD_GRAVITY_MPS2 as G
from ..physics.motion import (
    lateral_limit_mps2,
    lateral_speed_cap_mps,
    plans_on_grades,
    segment_friction_radius_mps2,
    turn_speed_cap_mps,
    tyre_accel_mps2,
)
from ..physics.rows import (
    ROW_FAMILIES,
    exact_row_values,
    friction_data,
    friction_rows_needed,
    power_data,
    power_rows_needed,
)
from ..physics.speeds import max_force_of_sets
from ..physics.steps import step_speed_cap_mps
from ..terrain.roughness import RoughnessWindows

if TYPE_CHECKING:
    from ..core.path import SegmentPath
    from ..core.profile import Profile
    from ..core.route import Route
    from ..core.vehicle import Vehicle

__all__ = ["check_limits", "route_as_planned", "LimitCheck", "LimitBreach", "STALE_FORCE_RTOL"]

#: The profile's force_n column counts as stale when it differs from the forces its speeds
#: give by more than this share of the limit: the file's 9 digits give a force back within
#: 5e-9 of it, and its 12-digit speeds the force within 1e-11 of it (2 x 5e-12, the force
#: growing at most as fast as v^2 between resonance peaks); an edited force is far beyond.
STALE_FORCE_RTOL = 1e-7


@dataclasses.dataclass(frozen=True)
class LimitBreach:
    """Where a profile first breaks one of the vehicle's limits, and how often.

    Attributes
    ----------
    quantity : str
        ``"speed"``, ``"acceleration"``, ``"deceleration"``, ``"jerk"``, ``"friction"``,
        ``"power"`` or ``"force"``.
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
        # enough digits that a breach just over the limit (LIMIT_RTOL = 1e-6) does not read as "1"
        digits = 4 if not math.isfinite(self.worst_ratio) or self.worst_ratio > 1.001 else 8
        value = f"{self.value:.{digits}g} {self.unit}" if math.isfinite(self.value) else "too large to compute"
        worst = (f"{self.worst_ratio:.{digits}g} times the limit" if math.isfinite(self.worst_ratio)
                 else "beyond any number")
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
    windows : RoughnessWindows
        The route's roughness windows, of the length checked with (``roughness_window_m`` of
        :func:`check_limits`; the segments' RI comes from them;
        :func:`profileopt.verification.window_check.check_windows` judges by them).
    checked : tuple of str
        The bounds checked, in words with their values and where they come from
        (``"jerk (the vehicle's 5 m/s^3)"``).
    unchecked : tuple of str
        The bounds not checked, and why (``"jerk (--max-jerk inf)"``).
    """

    model: str
    ri: np.ndarray
    predicted_n: np.ndarray
    limit_n: float
    breaches: tuple[LimitBreach, ...]
    notes: tuple[str, ...]
    windows: RoughnessWindows
    checked: tuple[str, ...] = ()
    unchecked: tuple[str, ...] = ()


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


def _recorded(profile: "Profile", key: str) -> tuple[str | None, float]:
    """A value the profile's settings line records, as text and as a number (NaN when it is
    not one; text None when it records none)."""
    text = profile.settings.get(key)
    if text is None:
        return None, math.nan
    try:
        return str(text), float(text)
    except (TypeError, ValueError):
        return str(text), math.nan


def _differs(recorded: float, used: float) -> bool:
    return not (recorded == used or abs(recorded - used) <= 1e-9 * abs(used))


def _planned_with_notes(profile: "Profile", *, jerk_mps3: float, jerk_words: str, window_m: float) -> list[str]:
    """What the profile's settings line records of the jerk bound and the roughness window
    where it differs from what is checked: reported, never obeyed."""
    notes = []
    text, recorded = _recorded(profile, "max_jerk_mps3")
    if text is not None and _differs(recorded, jerk_mps3):
        shown = f"{recorded:g} m/s^3" if math.isfinite(recorded) else ("inf" if recorded > 0 else text)
        notes.append(f"the profile was planned with --max-jerk {shown} (its settings line); verified against "
                     f"{jerk_words}")
    text, recorded = _recorded(profile, "roughness_window_m")
    if text is not None and _differs(recorded, window_m):
        notes.append(f"the profile was planned with --roughness-window {text} m (its settings line); verified with "
                     f"roughness windows of {window_m:g} m, and its ri column is not compared with the route's (pass "
                     f"--roughness-window {text} to verify with its own)")
    return notes


def _path_note(profile: "Profile", geometry) -> str | None:  # noqa: ANN001  (RouteGeometry)
    """A note when the path tolerance the profile records is not the one checked with."""
    if not geometry.tolerance_source:  # no x, y: the tolerance plays no part
        return None
    text, recorded = _recorded(profile, "path_tolerance_m")
    if text is None or not _differs(recorded, geometry.tolerance_m):
        return None
    how = ("estimated from the route's x, y, as plan does by default" if geometry.tolerance_source == "estimated"
           else "--path-tolerance")
    return (f"the profile was planned with a path tolerance of {text} m (its settings line); verified with "
            f"{geometry.tolerance_m:.3g} m ({how}), which finds the route's curvature")


def _first_breach(quantity: str, limit_name: str, values: np.ndarray, limit: np.ndarray, where_m: np.ndarray,
                  segments: np.ndarray, unit: str) -> LimitBreach | None:
    """The first place where ``values`` exceed ``limit`` by more than :data:`profileopt.defaults.LIMIT_RTOL`
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


def route_as_planned(route: "Route", profile: "Profile") -> tuple["Route", str | None]:
    """The route with the assumed roughness its profile was planned with.

    ``plan route.csv --roughness-class C`` (``plan(dataclasses.replace(route,
    assumed_roughness=...))``) records the assumption in the profile's settings, not in the
    route file: a profile is judged on the roughness it was planned for.

    Parameters
    ----------
    route : Route
        The route as read.
    profile : Profile
        A profile of it; ``profile.settings["roughness"]`` names an assumed roughness, if any.

    Returns
    -------
    (Route, str or None)
        The route (itself when the profile records no assumption) and a note when the
        profile's assumption differs from the route's own.

    Raises
    ------
    InputError
        The profile records a roughness that names no class and no RI.
    """
    from ..terrain.assumed import AssumedRoughness

    label = profile.settings.get("roughness")
    if label is None:
        return route, None
    try:
        assumed = AssumedRoughness.from_label(label)
    except InputError as exc:
        raise InputError(f"profile: its settings line records roughness={label}: {exc}; plan it again") from None
    if assumed == route.assumed_roughness:
        return route, None
    was = route.assumed_roughness.label if route.assumed_roughness else "none, measured"
    note = (f"the profile was planned with the assumed roughness {assumed.label} (the route's: {was}); it is "
            "judged with the profile's")
    return dataclasses.replace(route, assumed_roughness=assumed), note


def check_limits(
    route: "Route",
    profile: "Profile",
    vehicle: "Vehicle",
    *,
    model: str | None = None,
    max_jerk_mps3: float | None = None,
    path_tolerance_m: float | None = DEFAULT_PATH_TOLERANCE_M,
    roughness_window_m: float = DEFAULT_ROUGHNESS_WINDOW_M,
) -> LimitCheck:
    """Check a profile against the vehicle's own limits, on paper, from its speeds alone.

    The profile must cover the route exactly (its first and last boundaries are the route's
    first and last samples) and its RI column must be the route's own. The limits are the
    vehicle's, each computed here from :mod:`profileopt.physics`: the speed caps (the
    vehicle's top speed, SBEM:TF's step limit, the route's ``speed_limit`` and, for a vehicle
    that gives their keys, the lateral and friction caps of turns and the crawl through a
    turn sharper than its ``min_turn_radius_m``, with the path's curvature found as the planner
    finds it (:func:`profileopt.terrain.geometry.route_geometry`: a reversal is a turn of the
    sharpest radius, never a straight) with ``path_tolerance_m``, by default estimated from
    the route as the planner estimates it by default), the acceleration and
    deceleration bounds (on the route's grades, for such a vehicle), the friction circle and
    the drive power, the jerk bound (by default the vehicle's), and the model's force limit.
    What the profile's settings line records (its jerk bound, path tolerance, roughness
    window) is never used: where it differs from what is checked, a note says so, so that an
    edited settings line cannot loosen a limit. The predicted force of each segment is recomputed from the speeds:
    the largest force over every speed between its two boundary speeds and every roughness
    window it meets, resonance peaks included (:func:`profileopt.physics.speeds.max_force_of_sets`). The file's
    ``force_n`` column is not used (a note says so when it differs). A limit counts as kept
    within :data:`profileopt.defaults.LIMIT_RTOL` of it, the planner's own tolerance.

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
    max_jerk_mps3 : float, optional
        The jerk bound (m/s^3, > 0; ``inf``: not checked); default the vehicle's
        ``max_jerk_mps3``.
    path_tolerance_m : float or None, default None (estimate it from the route's x, y)
        The path tolerance the curvature of turns is found with (m, > 0), as ``plan``'s.
    roughness_window_m : float, default DEFAULT_ROUGHNESS_WINDOW_M (5 m)
        The roughness window (m, > 0): the segments' RI and the windows judged. The profile's
        RI column is compared with the route's only when the profile records this window.

    Returns
    -------
    LimitCheck

    Raises
    ------
    InputError
        The profile does not cover the route exactly, its RI column does not match the
        route's segments (with the roughness window it records), a bound given is not a
        number > 0, or the model is unknown.
    """
    key = profile.model if model is None else model
    force_model = get_model(key)
    route, planned_with = route_as_planned(route, profile)
    s = np.asarray(profile.s_m, dtype=float)
    v = np.asarray(profile.speed_mps, dtype=float)
    _check_coverage(route, s)
    starts, stops = segment_samples(route.s_m, s)
    jerk_bound = vehicle.max_jerk_mps3 if max_jerk_mps3 is None else float(max_jerk_mps3)
    for name, value in (("max_jerk_mps3", jerk_bound), ("roughness_window_m", roughness_window_m),
                        ("path_tolerance_m", path_tolerance_m)):
        if value is not None and not value > 0:
            raise InputError(f"{name} = {value!r}: must be a number > 0")
    jerk_words = (f"the vehicle's {jerk_bound:g} m/s^3" if max_jerk_mps3 is None
                  else f"--max-jerk {jerk_bound:g} m/s^3")
    window_m = float(roughness_window_m)
    window_text, recorded_window = _recorded(profile, "roughness_window_m")
    same_windows = window_text is None or not _differs(recorded_window, window_m)
    windows = route_roughness_windows(route, vehicle, window_m=window_m)
    segments = segments_at(s, windows, vehicle, starts=starts, stops=stops)
    ri_here = segments.ri
    mismatch = np.flatnonzero(~np.isclose(np.asarray(profile.ri, dtype=float)[:-1], ri_here, rtol=1e-6, atol=1e-9))
    if mismatch.size and same_windows:
        i = mismatch[0]
        raise InputError(
            f"{route.source}: segment {i} ({s[i]:g} to {s[i + 1]:g} m) has RI {ri_here[i]:.4g} on this route "
            f"but {profile.ri[i]:.4g} in the profile (largest RI of the {window_m:g} m roughness windows it "
            "meets); verify a profile on the route and vehicle (ground clearance) it was planned for, or plan "
            "it again"
        )
    notes = [planned_with] if planned_with else []
    notes += _planned_with_notes(profile, jerk_mps3=jerk_bound, jerk_words=jerk_words, window_m=window_m)
    limit = force_model.limit_n(vehicle)
    profile_limit = np.asarray(profile.force_limit_n, dtype=float)[:-1]
    if np.any(np.abs(profile_limit - limit) > 1e-9 * limit):
        notes.append(
            f"the profile's force_limit_n ({profile_limit.min():g} to {profile_limit.max():g} N) differs from "
            f"{vehicle.name or 'the vehicle'}'s {force_model.limit_key} = {limit:g} N: was it planned with "
            "another vehicle or model? The vehicle's limit is used"
        )
    jerk_name = "the vehicle's jerk limit" if max_jerk_mps3 is None else "the jerk bound given (--max-jerk)"
    length = np.diff(s)
    from ..terrain.geometry import (
        route_geometry,  # scipy: only when a profile is checked
    )

    geometry = route_geometry(route, tolerance_m=path_tolerance_m, grade_scale_m=2.0 * segments.roughness_window_m,
                              min_turn_radius_m=vehicle.min_turn_radius_m)
    path_note = _path_note(profile, geometry)
    if path_note:
        notes.append(path_note)
    path = segment_path(route, segments, geometry)
    caps = _speed_caps(route, vehicle, segments, path, force_model.key)
    decel_bound, accel_bound = _accel_bounds(vehicle, path)
    dynamic = force_model.key == "dynamic"  # its force is judged by the simulation alone (verify)
    row_data = _row_data(vehicle, path, decel_bound, accel_bound)
    n = s.size - 1
    index = np.arange(n)
    breaches: list[LimitBreach | None] = []
    # numbers as large as 1e155 m/s overflow on squaring: they break the limits, silently
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        # the vehicle's top speed first, then the caps of steps, the route's speed_limit and turns where lower
        top = np.maximum(v[:-1], v[1:])
        breaches.append(_first_breach("speed", "the vehicle's top speed", top, np.array(vehicle.max_speed_mps),
                                      s[:-1], index, "m/s"))
        for name, lim_cap in caps:
            lower = lim_cap < vehicle.max_speed_mps
            breaches.append(_first_breach("speed", name, top[lower], lim_cap[lower], s[:-1][lower], index[lower],
                                          "m/s"))
        b = v * v
        accel = segment_accel_mps2(b[:-1], b[1:], length)
        # judged as the tyres' force per unit mass, a + g sin(theta) (the grades the bounds
        # used): its bounds stay positive where a grade makes a's own bound negative
        on_grades = plans_on_grades(vehicle)
        lift_hi = G * np.sin(path.grade_hi_rad) if on_grades else 0.0
        lift_lo = G * np.sin(path.grade_lo_rad) if on_grades else 0.0
        words = " (drive force per unit mass, a + g sin(theta))" if on_grades else ""
        breaches.append(_first_breach("acceleration", "the vehicle's acceleration limit" + words, accel + lift_hi,
                                      accel_bound + lift_hi, s[:-1], index, "m/s^2"))
        breaches.append(_first_breach("deceleration", "the vehicle's deceleration limit" + words.replace(
            "drive", "braking").replace("a + g", "-(a + g").replace("theta))", "theta)))"), -(accel + lift_lo),
            decel_bound - lift_lo, s[:-1], index, "m/s^2"))
        for family, data in row_data:  # the friction circle, the drive power
            usage = exact_row_values(family, b, length, data).max(axis=0)
            breaches.append(_first_breach(family, ROW_FAMILIES[family].description, usage, np.array(1.0), s[:-1], index, "of the limit"))
        if n >= 2 and math.isfinite(jerk_bound):
            jerk = boundary_jerk_mps3(v[1:-1], accel[:-1], accel[1:], length[:-1], length[1:])
            breaches.append(_first_breach("jerk", jerk_name, np.abs(jerk), np.array(jerk_bound), s[1:-1],
                                          index[1:], "m/s^3"))
        if dynamic:  # no formula to predict with: the exact simulation is the model
            predicted = np.zeros(n)
            stale = np.empty(0, dtype=int)
        else:
            window_first, window_stop = segments.window_ranges()
            predicted = max_force_of_sets(segments.windows.ri, window_first, window_stop, v, vehicle,
                                          model=force_model.key)
            breaches.append(_first_breach("force", f"the {force_model.label} force limit", predicted,
                                          np.array(limit), s[:-1], index, "N"))
            recorded = np.asarray(profile.force_n, dtype=float)[:-1]
            stale = np.flatnonzero(~(np.abs(recorded - predicted) <= STALE_FORCE_RTOL * limit))
    if stale.size and same_windows:  # other windows: other forces, by design
        i = stale[0]
        notes.append(
            f"the profile's force_n column is stale in {stale.size} of {n} segments (first at s = {s[i]:g} m: "
            f"{recorded[i]:.6g} N recorded, {predicted[i]:.6g} N from its speeds): the predicted forces were "
            "recomputed from the speeds"
        )
    checked, unchecked = _checked_words(vehicle, caps, [family for family, _ in row_data],
                                        jerk_bound if n >= 2 else None, jerk_words, force_model, limit, geometry)
    return LimitCheck(model=force_model.key, ri=ri_here, predicted_n=predicted, limit_n=float(limit),
                      breaches=tuple(b for b in breaches if b is not None), notes=tuple(notes), windows=windows,
                      checked=checked, unchecked=unchecked)


#: Short names of the speed caps of :func:`_speed_caps`, by the first words of their names.
_CAP_WORDS = {"the step limit": "steps (SBEM:TF)", "the route's speed_limit": "the route's speed_limit",
              "the lateral acceleration limit": "turns (the vehicle's {lateral:g} m/s^2 lateral{path})",
              "the crawl through": "{crawl:g} m/s through turns sharper than the vehicle's {radius:g} m turning circle",
              "the friction limit": "friction in turns (the vehicle's friction_coefficient {mu:g})"}


def _checked_words(vehicle: "Vehicle", caps: list, families: list[str], jerk_mps3: float | None, jerk_words: str,
                   force_model, limit_n: float, geometry) -> tuple[tuple[str, ...], tuple[str, ...]]:  # noqa: ANN001
    """The bounds checked, in words with their values and sources, and those not checked."""
    how = {"estimated": "estimated from the route", "given": "given (--path-tolerance)"}.get(geometry.tolerance_source)
    values = {"lateral": lateral_limit_mps2(vehicle), "crawl": CRAWL_SPEED_MPS, "radius": vehicle.min_turn_radius_m,
              "mu": vehicle.friction_coefficient,
              "path": f", path tolerance {geometry.tolerance_m:.3g} m {how}" if how else ""}
    speed = [f"the vehicle's top speed {vehicle.max_speed_mps:g} m/s"]
    speed += [short.format(**values) for name, cap in caps for start, short in _CAP_WORDS.items()
              if name.startswith(start) and np.any(cap < vehicle.max_speed_mps)]  # those that cap somewhere
    checked = [f"speed ({', '.join(speed)})",
               f"acceleration (the vehicle's {vehicle.max_accel_mps2:g} m/s^2)",
               f"deceleration (the vehicle's {vehicle.max_decel_mps2:g} m/s^2)"]
    if "friction" in families:
        checked.append(f"friction circle (the vehicle's friction_coefficient {vehicle.friction_coefficient:g})")
    if "power" in families:
        checked.append(f"drive power (the vehicle's {vehicle.max_power_w:g} W)")
    unchecked = []
    if jerk_mps3 is None:
        unchecked.append("jerk (the profile has no interior boundary)")
    elif math.isfinite(jerk_mps3):
        checked.append(f"jerk ({jerk_words})")
    else:
        unchecked.append(f"jerk ({jerk_words.replace(' m/s^3', '')})")
    if force_model.key == "dynamic":
        checked.append(f"force (the dynamic model: the exact simulation's, the vehicle's {force_model.limit_key} "
                       f"{limit_n:g} N)")
    else:
        checked.append(f"predicted force ({force_model.label}, the vehicle's {force_model.limit_key} {limit_n:g} N)")
    return tuple(checked), tuple(unchecked)


def _speed_caps(route: "Route", vehicle: "Vehicle", segments: Segments, path: "SegmentPath",
                model: str) -> list[tuple[str, np.ndarray]]:
    """The caps on every speed driven in each segment besides the top speed, in words and m/s:
    SBEM:TF's step limit where the wheel meets a step or lands after a drop, the route's
    ``speed_limit`` (the lowest of the segment's samples), the lateral acceleration and
    the friction circle in turns, and the crawl through a turn sharper than the vehicle's
    turning circle (for a vehicle that gives their keys)."""
    caps = []
    if model == "sbem_tf":
        caps.append(("the step limit (SBEM:TF where the wheel meets a step or lands after a drop)",
                     step_speed_cap_mps(route.s_m, route.z_m, segments.boundaries_m, vehicle)))
    if route.speed_limit_mps is not None:
        caps.append(("the route's speed_limit", np.minimum.reduceat(route.speed_limit_mps, segments.first_sample)))
    lateral = lateral_limit_mps2(vehicle)
    if math.isfinite(lateral):
        caps.append(("the lateral acceleration limit in turns", lateral_speed_cap_mps(lateral, path.curvature_max_1pm)))
        if vehicle.min_turn_radius_m is not None:
            crawl = turn_speed_cap_mps(math.inf, path.curvature_max_1pm, vehicle.min_turn_radius_m)
            name = f"the crawl through a turn sharper than the vehicle's min_turn_radius_m ({vehicle.min_turn_radius_m:g} m)"
            caps.append((name, crawl))
    if vehicle.friction_coefficient is not None:
        radius = segment_friction_radius_mps2(vehicle.friction_coefficient, path.grade_lo_rad, path.grade_hi_rad)
        caps.append(("the friction limit in turns", lateral_speed_cap_mps(radius, path.curvature_max_1pm)))
    return caps


def _accel_bounds(vehicle: "Vehicle", path: "SegmentPath") -> tuple[np.ndarray, np.ndarray]:
    """The deceleration (positive) and acceleration bounds of each segment (m/s^2): the
    vehicle's, less the grade's pull for a vehicle that plans on grades, and the friction
    circle's along the path, -mu g cos theta <= a + g sin theta <= mu g cos theta."""
    n = path.grade_lo_rad.size
    if plans_on_grades(vehicle):
        decel = tyre_accel_mps2(vehicle.max_decel_mps2, path.grade_lo_rad)
        accel = -tyre_accel_mps2(-vehicle.max_accel_mps2, path.grade_hi_rad)
    else:
        decel, accel = np.full(n, vehicle.max_decel_mps2), np.full(n, vehicle.max_accel_mps2)
    if vehicle.friction_coefficient is not None:
        radius = segment_friction_radius_mps2(vehicle.friction_coefficient, path.grade_lo_rad, path.grade_hi_rad)
        decel = np.minimum(decel, tyre_accel_mps2(radius, path.grade_lo_rad))
        accel = np.minimum(accel, -tyre_accel_mps2(-radius, path.grade_hi_rad))
    return decel, accel


def _row_data(vehicle: "Vehicle", path: "SegmentPath", decel_mps2: np.ndarray, accel_mps2: np.ndarray
              ) -> list[tuple[str, np.ndarray]]:
    """The row families (:data:`profileopt.physics.rows.ROW_FAMILIES`) that can bind, with
    their data per segment: the friction circle where the route turns (on a straight the
    acceleration bounds keep it), the drive power where the bounds allow any drive force: the
    planner's own tests of where its rows are needed, with no speed cap."""
    uncapped = np.full(path.curvature_max_1pm.size, np.inf)
    out = []
    if vehicle.friction_coefficient is not None and np.any(
            friction_rows_needed(path, vehicle.friction_coefficient, uncapped, decel_mps2, accel_mps2)):
        out.append(("friction", friction_data(path, vehicle.friction_coefficient)))
    if vehicle.max_power_w is not None and vehicle.mass_kg is not None and power_rows_needed(
            path, vehicle.mass_kg, vehicle.max_power_w, uncapped, accel_mps2):
        out.append(("power", power_data(path, vehicle.mass_kg, vehicle.max_power_w)))
    return out
