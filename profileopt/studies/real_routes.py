"""The real-route study: routes people drive, planned with default options and driven in simulation.

Beside the safety study (:mod:`profileopt.studies.safety`, every force model over flat
synthetic courses), this study plans routes as a user would meet them, with
:func:`profileopt.plan`'s defaults and nothing tuned, for each vehicle, and drives every plan
in the exact simulation (:func:`profileopt.verify`):

- GPS tracks (GPX) with an assumed roughness class, and a track over a LiDAR cloud, made into
  routes by the library's public path (:func:`study_track_route`: ``read_track``,
  ``read_terrain``, ``route_from_track``, as ``profileopt plan TRACK --roughness-class B``);
- hilly synthetic roads (:func:`synthetic_routes`): 8 cm kerbs and drops on grades of -15 %
  to +15 %, on a crest and in a dip, potholes on a climb, a washboard on a descent, a block
  field on a grade, rolling hills, each beside the same road without its obstacles;
- the obstacle family of issue 29 (:func:`obstacle_study`): every block, pit, kerb and drop
  of :data:`OBSTACLE_HEIGHTS_M` x :data:`OBSTACLE_WIDTHS_M` sampled every
  :data:`OBSTACLE_SPACINGS_M` on 60 m of flat ground (:func:`obstacle_route`).

Per (route, vehicle) a :class:`PairResult`: travel time, which limits hold the speed and
where (the profile's ``binding`` column, :func:`profileopt.core.binding.binding_shares`),
the worst simulated roughness window and where, whether ``verify`` passes, the plan's notes
(among them the planner's ``simulation gate:`` note) and the sharpest turn the plan used.
:meth:`RealRouteStudy.markdown` renders them as one table. ``examples/real_routes_study.py``
runs the study and draws a picture of each pair (docs/guide/real-routes.md).

The module composes the public API (plan, verify, the route readers, the synthetic terrain
generators); it adds no physics. Everything reported is deterministic (no wall-clock times).
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from pathlib import Path
from typing import TYPE_CHECKING, Callable, NamedTuple, Sequence

import numpy as np

from ..core.binding import binding_shares
from ..core.route import Route
from ..errors import InfeasibleError, InputError, PlanningError
from ..planning.gate import covered_m
from ..planning.limits import SimulatedLimit
from ..terrain.synthetic import iso8608_profile, step, washboard

if TYPE_CHECKING:
    from ..core.profile import Profile
    from ..core.vehicle import Vehicle
    from ..verification.verify import Verification

__all__ = [
    "DEFAULT_VEHICLES", "PLANNED", "INFEASIBLE", "SOLVER_FAILED", "REFUSED", "GATE_NOTE_PREFIX",
    "TERRAIN_LIMITS", "KERB_HEIGHT_M", "SYNTHETIC_LENGTH_M", "SYNTHETIC_SPACING_M",
    "OBSTACLE_KINDS", "OBSTACLE_HEIGHTS_M", "OBSTACLE_WIDTHS_M", "OBSTACLE_SPACINGS_M", "OBSTACLE_FAMILY",
    "StudyRoute", "PairResult", "PairRun", "RealRouteStudy", "ObstacleStudy",
    "study_pair", "real_route_study", "study_track_route", "graded_road_m", "synthetic_routes",
    "obstacle_route", "obstacle_study",
]

#: The vehicles every route is driven by: the paper's ATV and its lightly damped variant.
DEFAULT_VEHICLES = ("atv", "atv-resonant")
#: :attr:`PairResult.outcome` of a pair that was planned and simulated.
PLANNED = "planned"
#: :attr:`PairResult.outcome` of a route the planner says the vehicle cannot drive.
INFEASIBLE = "infeasible"
#: :attr:`PairResult.outcome` of a solver failure without a limit-keeping fallback.
SOLVER_FAILED = "solver failed"
#: :attr:`PairResult.outcome` of a route the planner refuses as input (one line saying why).
REFUSED = "refused"
#: How the planner's note on its simulation gate begins (:mod:`profileopt.planning.gate`).
GATE_NOTE_PREFIX = "simulation gate:"
#: The ``binding`` names that are the ground's and the path's limits (not the drive's
#: acceleration, braking, jerk or top speed): where these hold the speed is listed by place.
TERRAIN_LIMITS = ("force", "step", "simulated", "lateral", "friction", "speed_limit", "power")

#: Height of the kerbs and drops of the synthetic routes (m): a road kerb.
KERB_HEIGHT_M = 0.08
#: Length (m) and sample spacing (m) of the synthetic routes.
SYNTHETIC_LENGTH_M = 400.0
SYNTHETIC_SPACING_M = 0.05

#: The obstacle family of issue 29: kinds, heights (m), widths of blocks and pits (m) and
#: sample spacings (m); kerbs and drops have no width.
OBSTACLE_KINDS = ("block", "pit", "kerb", "drop")
OBSTACLE_HEIGHTS_M = (0.02, 0.05, 0.1, 0.2, 0.3)
OBSTACLE_WIDTHS_M = (0.05, 0.2, 0.5, 1.0, 2.0)
OBSTACLE_SPACINGS_M = (0.01, 0.05, 0.2)
#: Every (kind, height_m, width_m, spacing_m) of the family, in a fixed order: blocks and pits
#: over heights x widths x spacings, then kerbs and drops (width 0) over heights x spacings:
#: 180 routes.
OBSTACLE_FAMILY: tuple[tuple[str, float, float, float], ...] = tuple(
    [(kind, h, w, ds) for kind in ("block", "pit")
     for h, w, ds in itertools.product(OBSTACLE_HEIGHTS_M, OBSTACLE_WIDTHS_M, OBSTACLE_SPACINGS_M)]
    + [(kind, h, 0.0, ds) for kind in ("kerb", "drop") for h, ds in itertools.product(OBSTACLE_HEIGHTS_M, OBSTACLE_SPACINGS_M)]
)
#: Length of an obstacle route (m) and where its obstacle starts (m): 40 m of run-up.
_OBSTACLE_ROUTE_M = 60.0
_OBSTACLE_AT_M = 40.0


@dataclasses.dataclass(frozen=True, eq=False)
class StudyRoute:
    """A named route of the study.

    Attributes
    ----------
    name : str
        Short name for tables and file names.
    route : Route
        The route planned.
    description : str
        One line saying what it is.
    baseline : Route or None
        The same road without its obstacles (kerbs, potholes, ...), planned too so that the
        obstacles' cost shows as a ratio of travel times; None for none.
    extra_vehicles : tuple of str
        Vehicles (bundled names) that drive this route besides the study's own: e.g.
        ``atv-low-range`` on a mountain track that the others cannot climb.
    """

    name: str
    route: Route
    description: str = ""
    baseline: Route | None = None
    extra_vehicles: tuple[str, ...] = ()


@dataclasses.dataclass(frozen=True)
class PairResult:
    """One route planned for one vehicle with default options, and the plan simulated.

    Attributes
    ----------
    route, vehicle : str
        The route's name and the vehicle's (a bundled name or a file's stem).
    outcome : str
        :data:`PLANNED`, :data:`INFEASIBLE`, :data:`SOLVER_FAILED` or :data:`REFUSED`.
    status : str
        The profile's solver status, or the planner's message when it did not plan.
    distance_m : float
        Length of the route (m).
    travel_time_s : float
        Planned travel time (s); nan if not planned.
    mean_speed_mps : float
        distance / travel time (m/s); nan if not planned.
    baseline_time_s : float
        Travel time of the route's baseline (the same road without its obstacles) for the
        same vehicle (s); nan without a baseline or if the baseline could not be planned.
    binding : dict of str to float
        The share of the distance each limit holds the speed (0 to 1; the profile summary's
        ``binding``).
    binding_runs : tuple of (str, float, float)
        Where each limit holds the speed: (name, start_m, end_m) stretches in order, each
        boundary of the profile standing for the half segments on either side of it.
    slowest_speed_mps, slowest_s_m : float
        The top speed of the slowest segment a limit holds back (m/s) and where it starts
        (m) (the summary's ``slowest_segment``).
    slowest_reason : str
        What holds it back, in words.
    sharpest_curvature_1pm : float
        The largest |curvature| of the path the plan used (1/m; 0 for a straight ``s,z``
        route): of each segment's largest, as the limits saw it (the profile's ``path``).
    sharpest_curvature_s_m : float
        Where the segment that holds it starts (m).
    steepest_grade_pct : float
        The largest |grade| the plan used (%), likewise.
    path_tolerance_m : float
        The path tolerance the plan's curvature was found with (m; nan for a straight
        ``s,z`` route).
    path_tolerance_source : str
        Where it came from: ``"estimated"`` from the route's own x, y, ``"given"``, or "" (the
        summary's ``path``, when the profile records it).
    worst_window_ratio : float
        Simulated peak force / limit of the worst roughness window (``verify``'s
        ``windows.worst_ratio``); nan if not planned.
    worst_window_start_m, worst_window_stop_m : float
        That window's extent (m).
    worst_window_peak_s_m : float
        Where the vehicle is when the force peaks (m).
    worst_window_speed_mps : float
        The largest speed driven inside that window (m/s).
    windows, windows_over : int
        Roughness windows checked, and those whose simulated force exceeds the limit.
    worst_segment_ratio : float
        Largest simulated force / limit of a segment (dimensionless).
    passes : bool
        ``verify``'s verdict: every limit kept on paper and no window or segment over the
        force limit in simulation.
    keeps_limits : bool
        Every limit of the vehicle kept on paper (``verify``'s ``keeps_limits``).
    plan_notes, verify_notes : tuple of str
        The notes of the plan (the summary's: refining, the simulation gate, the assumed
        roughness, the turns sharper than the vehicle's turning circle, ...) and of the
        verification.
    gate_capped_m : float
        Length of route the planner's simulation gate capped (m): the stretches of the
        plan's :class:`~profileopt.planning.limits.SimulatedLimit`, overlaps counted once.
    """

    route: str
    vehicle: str
    outcome: str
    status: str
    distance_m: float
    travel_time_s: float = math.nan
    mean_speed_mps: float = math.nan
    baseline_time_s: float = math.nan
    binding: dict = dataclasses.field(default_factory=dict)
    binding_runs: tuple[tuple[str, float, float], ...] = ()
    slowest_speed_mps: float = math.nan
    slowest_s_m: float = math.nan
    slowest_reason: str = ""
    sharpest_curvature_1pm: float = math.nan
    sharpest_curvature_s_m: float = math.nan
    steepest_grade_pct: float = math.nan
    path_tolerance_m: float = math.nan
    path_tolerance_source: str = ""
    worst_window_ratio: float = math.nan
    worst_window_start_m: float = math.nan
    worst_window_stop_m: float = math.nan
    worst_window_peak_s_m: float = math.nan
    worst_window_speed_mps: float = math.nan
    windows: int = 0
    windows_over: int = 0
    worst_segment_ratio: float = math.nan
    passes: bool = False
    keeps_limits: bool = False
    plan_notes: tuple[str, ...] = ()
    verify_notes: tuple[str, ...] = ()
    gate_capped_m: float = 0.0

    @property
    def planned(self) -> bool:
        """True when the route was planned (and simulated)."""
        return self.outcome == PLANNED

    @property
    def gate_note(self) -> str:
        """The planner's note on its simulation gate (it capped the plan), or "" if none."""
        return next((note for note in self.plan_notes if note.startswith(GATE_NOTE_PREFIX)), "")

    @property
    def gated(self) -> bool:
        """True when the planner's simulation gate capped the plan."""
        return bool(self.gate_note)

    @property
    def time_ratio(self) -> float:
        """Travel time / the baseline's (dimensionless): what the obstacles cost; nan without
        a baseline."""
        if not (self.planned and self.baseline_time_s > 0):
            return math.nan
        return self.travel_time_s / self.baseline_time_s

    @property
    def min_turn_radius_m(self) -> float:
        """The sharpest turn's radius 1 / curvature (m; inf on a straight route)."""
        k = self.sharpest_curvature_1pm
        return math.inf if k == 0 else 1.0 / k

    def runs_of(self, names: Sequence[str]) -> list[tuple[str, float, float]]:
        """The stretches where any of ``names`` holds the speed, in route order.

        Parameters
        ----------
        names : sequence of str
            ``binding`` names (:data:`profileopt.core.binding.BINDING_NAMES`).

        Returns
        -------
        list of (str, float, float)
            (name, start_m, end_m).
        """
        return [run for run in self.binding_runs if run[0] in names]

    def to_dict(self) -> dict:
        """The result as plain Python values, JSON-ready (SI units in the key names).

        Returns
        -------
        dict
            Every attribute, ``binding_runs`` as lists, and ``time_ratio``, ``gated``.
        """
        out = dataclasses.asdict(self)
        out["binding_runs"] = [list(run) for run in self.binding_runs]
        out["plan_notes"], out["verify_notes"] = list(self.plan_notes), list(self.verify_notes)
        out["time_ratio"], out["gated"] = self.time_ratio, self.gated
        return out


class PairRun(NamedTuple):
    """One pair's result with the plan and the verification it came from (for pictures).

    Attributes
    ----------
    result : PairResult
    route : StudyRoute
    vehicle : Vehicle
    profile : Profile or None
        None if the route was not planned.
    verification : Verification or None
        None if the route was not planned.
    """

    result: PairResult
    route: StudyRoute
    vehicle: "Vehicle"
    profile: "Profile | None"
    verification: "Verification | None"


def _vehicle(vehicle: "str | Vehicle") -> "Vehicle":
    from ..core.vehicle import load_vehicle

    return load_vehicle(vehicle) if isinstance(vehicle, (str, Path)) else vehicle


def _vehicle_label(vehicle: "Vehicle") -> str:
    return Path(vehicle.name).stem if vehicle.name else "vehicle"


def _binding_runs(binding: np.ndarray, s_m: np.ndarray) -> tuple[tuple[str, float, float], ...]:
    """Consecutive boundaries held by the same limit, as (name, start, end) stretches; boundary
    j stands for [mid_{j-1}, mid_j] (the weighting of ``binding_shares``)."""
    mid = 0.5 * (s_m[:-1] + s_m[1:])
    left = np.concatenate([[s_m[0]], mid])
    right = np.concatenate([mid, [s_m[-1]]])
    runs: list[tuple[str, float, float]] = []
    for name, group in itertools.groupby(range(binding.size), key=lambda j: str(binding[j])):
        rows = list(group)
        runs.append((name, float(left[rows[0]]), float(right[rows[-1]])))
    return tuple(runs)


def _not_planned(message: str, source: str) -> str:
    """The planner's message without the route's name in front."""
    text = str(message)
    return text[len(source) + 2:] if text.startswith(f"{source}: ") else text


def study_pair(route: StudyRoute, vehicle: "str | Vehicle", *, baseline_time_s: float | None = None) -> PairRun:
    """Plan one route for one vehicle with default options, verify the plan, and report.

    Parameters
    ----------
    route : StudyRoute
        The route (and its baseline, planned too unless ``baseline_time_s`` is given).
    vehicle : str or Vehicle
        A bundled name (``"atv"``), a vehicle file's path, or a loaded vehicle.
    baseline_time_s : float, optional
        The baseline's travel time for this vehicle (s) if already known (nan: it could not
        be planned); default: plan ``route.baseline`` now (if any).

    Returns
    -------
    PairRun
        The :class:`PairResult`, with the profile and the verification (None when the
        planner did not plan: :attr:`PairResult.outcome` says why).
    """
    from ..planning import plan
    from ..verification.verify import verify

    loaded = _vehicle(vehicle)
    label = _vehicle_label(loaded)
    if baseline_time_s is None:
        baseline_time_s = _baseline_time_s(route.baseline, loaded)
    common = {"route": route.name, "vehicle": label, "distance_m": float(route.route.s_m[-1] - route.route.s_m[0]),
              "baseline_time_s": float(baseline_time_s)}
    source = str(route.route.source)
    try:
        profile = plan(route.route, loaded)
    except InfeasibleError as exc:
        return PairRun(PairResult(**common, outcome=INFEASIBLE, status=_not_planned(exc, source)), route, loaded, None, None)
    except PlanningError as exc:
        return PairRun(PairResult(**common, outcome=SOLVER_FAILED, status=_not_planned(exc, source)), route, loaded, None,
                       None)
    except InputError as exc:
        return PairRun(PairResult(**common, outcome=REFUSED, status=_not_planned(exc, source)), route, loaded, None, None)
    check = verify(route.route, profile, loaded)
    summary = profile.summary()
    slowest = summary["slowest_segment"]
    windows = check.windows
    worst = windows.describe(windows.worst)
    curvature, grade = _turns_and_slopes(profile)
    k = int(np.argmax(curvature))
    path = summary.get("path") or {}
    result = PairResult(
        **common,
        outcome=PLANNED,
        status=profile.status,
        travel_time_s=profile.travel_time_s,
        mean_speed_mps=float(summary["mean_speed_mps"]),
        binding=dict(binding_shares(profile.binding, profile.s_m)) if profile.binding is not None else {},
        binding_runs=_binding_runs(profile.binding, profile.s_m) if profile.binding is not None else (),
        slowest_speed_mps=float(slowest["top_speed_mps"]),
        slowest_s_m=float(slowest["s_start_m"]),
        slowest_reason=str(slowest["reason"]),
        sharpest_curvature_1pm=float(curvature[k]),
        sharpest_curvature_s_m=float(profile.s_m[min(k, profile.s_m.size - 1)]),
        steepest_grade_pct=100.0 * float(np.max(grade)),
        path_tolerance_m=(_number(path.get("tolerance_m", profile.settings.get("path_tolerance_m")))
                          if route.route.x_m is not None else math.nan),
        path_tolerance_source=str(path.get("source", "")),
        worst_window_ratio=float(windows.worst_ratio),
        worst_window_start_m=worst["start_m"],
        worst_window_stop_m=worst["stop_m"],
        worst_window_peak_s_m=worst["peak_s_m"],
        worst_window_speed_mps=worst["speed_high_mps"],
        windows=windows.count,
        windows_over=windows.over_count,
        worst_segment_ratio=check.worst_ratio,
        passes=check.passes,
        keeps_limits=check.keeps_limits,
        plan_notes=tuple(summary.get("notes", profile.notes)),
        verify_notes=tuple(check.notes),
        gate_capped_m=sum(covered_m(limit.caps) for limit in profile.limits if isinstance(limit, SimulatedLimit)),
    )
    return PairRun(result, route, loaded, profile, check)


def _turns_and_slopes(profile: "Profile") -> tuple[np.ndarray, np.ndarray]:
    """|curvature| (1/m) and |grade| (rise over run) per segment as the limits saw them (the
    profile's ``path``: each segment's extremes), or at the boundaries (its columns)."""
    path = profile.path
    if path is not None and getattr(path, "curvature_max_1pm", None) is not None:
        return (np.asarray(path.curvature_max_1pm, dtype=float),
                np.tan(np.maximum(np.abs(path.grade_lo_rad), np.abs(path.grade_hi_rad))))
    zeros = np.zeros(profile.s_m.size)
    return (np.abs(profile.curvature_1pm) if profile.curvature_1pm is not None else zeros,
            np.abs(np.tan(profile.grade_rad)) if profile.grade_rad is not None else zeros)


def _number(value: object) -> float:
    """A float, nan for None or anything that is not a number."""
    try:
        return float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        return math.nan


def _baseline_time_s(baseline: Route | None, vehicle: "Vehicle") -> float:
    """The baseline's planned travel time (s); nan without one or if it cannot be planned."""
    if baseline is None:
        return math.nan
    from ..planning import plan

    try:
        return plan(baseline, vehicle).travel_time_s
    except (InfeasibleError, PlanningError, InputError):
        return math.nan


@dataclasses.dataclass(frozen=True)
class RealRouteStudy:
    """Every route of a study planned for each of its vehicles and simulated.

    Attributes
    ----------
    results : tuple of PairResult
        One per (route, vehicle), routes outermost, then vehicles in order.
    routes : tuple of str
        The routes' names, in order.
    vehicles : tuple of str
        The study's vehicles (each route's ``extra_vehicles`` come after them).
    descriptions : dict of str to str
        Each route's one-line description, by name.
    """

    results: tuple[PairResult, ...]
    routes: tuple[str, ...]
    vehicles: tuple[str, ...]
    descriptions: dict = dataclasses.field(default_factory=dict)

    def result(self, route: str, vehicle: str) -> PairResult:
        """The result of one (route, vehicle) pair.

        Parameters
        ----------
        route : str
            A route's name.
        vehicle : str
            A vehicle's name (``"atv"``).

        Returns
        -------
        PairResult

        Raises
        ------
        KeyError
            No such pair in the study.
        """
        for row in self.results:
            if (row.route, row.vehicle) == (route, vehicle):
                return row
        raise KeyError(f"({route!r}, {vehicle!r}) is not a pair of this study")

    @property
    def planned(self) -> tuple[PairResult, ...]:
        """The pairs that were planned and simulated."""
        return tuple(r for r in self.results if r.planned)

    @property
    def failing(self) -> tuple[PairResult, ...]:
        """The planned pairs that ``verify`` rejects."""
        return tuple(r for r in self.planned if not r.passes)

    def markdown(self) -> str:
        """The study as one Markdown table, a row per (route, vehicle).

        Columns: distance, travel time, travel time over the baseline's (the same road
        without its obstacles), mean speed, the slowest held segment, the limits that hold
        the speed with their shares of the distance (1 % or more), where the ground's and the
        path's limits hold it (:data:`TERRAIN_LIMITS`), the worst simulated roughness window
        (simulated / limit, at the force's peak), the verdict of ``verify``, how much the
        planner's simulation gate capped, and the sharpest turn's radius (with the path
        tolerance it was found with, and whether that was estimated or given).

        Returns
        -------
        str
        """
        lines = [
            "| route | vehicle | m | time (s) | / bare road | mean (m/s) | slowest (m/s at m) | what holds the speed "
            "(share of distance) | where the ground or the path holds it (m) | worst window sim / limit (at m) | "
            "verify | gate capped | sharpest turn radius (m) (path tolerance) |",
            "|---|---|---:|---:|---:|---:|---:|---|---|---:|---|---:|---:|",
        ]
        for r in self.results:
            if not r.planned:
                reason = r.status.split(";")[0].split(": ")[0]
                lines.append(f"| {r.route} | {r.vehicle} | {r.distance_m:.0f} | {r.outcome}: {_cell(reason)} "
                             + "| " * 9 + "|")
                continue
            ratio = f"{r.time_ratio:.2f}" if math.isfinite(r.time_ratio) else ""
            turn = "straight" if r.sharpest_curvature_1pm == 0 else f"{r.min_turn_radius_m:.3g}"
            if math.isfinite(r.path_tolerance_m):
                turn += f" ({r.path_tolerance_m:.2g} m{', ' + r.path_tolerance_source if r.path_tolerance_source else ''})"
            verdict = "passes" if r.passes else f"**fails** ({r.windows_over} windows over)"
            gated = ("" if not r.gated else f"{r.gate_capped_m:.0f} m" if math.isfinite(r.gate_capped_m) else "yes")
            lines.append(
                f"| {r.route} | {r.vehicle} | {r.distance_m:.0f} | {r.travel_time_s:.1f} | {ratio} | "
                f"{r.mean_speed_mps:.2f} | {r.slowest_speed_mps:.2f} at {r.slowest_s_m:.0f} | {_shares(r.binding)} | "
                f"{_where(r)} | {r.worst_window_ratio:.3f} (at {r.worst_window_peak_s_m:.1f}) | {verdict} | {gated} | "
                f"{turn} |"
            )
        return "\n".join(lines)

    def notes_markdown(self) -> str:
        """The notes of every pair's plan and verification, as a Markdown list per pair (the
        messages of the pairs not planned too).

        Returns
        -------
        str
        """
        lines = []
        for r in self.results:
            notes = list(r.plan_notes) + [f"verify: {n}" for n in r.verify_notes]
            if not r.planned:
                notes = [f"{r.outcome}: {r.status}"]
            lines.append(f"- **{r.route}, {r.vehicle}**" + ("" if notes else ": no notes"))
            lines.extend(f"  - {_cell(note)}" for note in notes)
        return "\n".join(lines)


def _cell(text: str) -> str:
    """Text safe inside a Markdown table cell."""
    return " ".join(str(text).split()).replace("|", "/")


def _shares(binding: dict) -> str:
    """``"accel 42 %, jerk 37 %"``: the limits holding 1 % or more of the distance, largest first."""
    big = sorted(((share, name) for name, share in binding.items() if share >= 0.01), reverse=True)
    return ", ".join(f"{name} {100 * share:.0f} %" for share, name in big)


def _where(result: PairResult, most: int = 3) -> str:
    """Where the ground's and the path's limits hold the speed: up to ``most`` stretches per
    limit, those less than 1 m apart merged."""
    parts = []
    for name in TERRAIN_LIMITS:
        runs = [(a, b) for n, a, b in result.runs_of((name,))]
        if not runs:
            continue
        merged = [list(runs[0])]
        for a, b in runs[1:]:
            if a - merged[-1][1] < 1.0:
                merged[-1][1] = b
            else:
                merged.append([a, b])
        shown = ", ".join(f"{a:.0f}-{b:.0f}" for a, b in merged[:most])
        more = f" (+{len(merged) - most} more)" if len(merged) > most else ""
        parts.append(f"{name} {shown}{more}")
    return "; ".join(parts)


def real_route_study(
    routes: Sequence[StudyRoute],
    vehicles: Sequence["str | Vehicle"] = DEFAULT_VEHICLES,
    *,
    on_pair: Callable[[PairRun], None] | None = None,
) -> RealRouteStudy:
    """Plan every route for every vehicle with default options, verify, and collect.

    Parameters
    ----------
    routes : sequence of StudyRoute
        The routes, in order; each is driven by every vehicle and its own
        ``extra_vehicles``.
    vehicles : sequence of str or Vehicle, default :data:`DEFAULT_VEHICLES`
        Bundled names, vehicle file paths or loaded vehicles.
    on_pair : callable, optional
        Called with each :class:`PairRun` as soon as it is made (to draw its picture); the
        study keeps only the :class:`PairResult`, so the profiles and simulations of a long
        study are not all held at once.

    Returns
    -------
    RealRouteStudy

    Raises
    ------
    InputError
        An unknown vehicle name or a bad vehicle file.
    """
    loaded = [_vehicle(v) for v in vehicles]
    results = []
    baselines: dict[tuple[int, str], float] = {}  # a baseline shared by several routes is planned once
    for route in routes:
        for vehicle in loaded + [_vehicle(v) for v in route.extra_vehicles]:
            key = (id(route.baseline), _vehicle_label(vehicle))
            if route.baseline is not None and key not in baselines:
                baselines[key] = _baseline_time_s(route.baseline, vehicle)
            run = study_pair(route, vehicle, baseline_time_s=baselines.get(key, math.nan))
            if on_pair is not None:
                on_pair(run)
            results.append(run.result)
    return RealRouteStudy(
        results=tuple(results),
        routes=tuple(r.name for r in routes),
        vehicles=tuple(_vehicle_label(v) for v in loaded),
        descriptions={r.name: r.description for r in routes},
    )


# ---------------------------------------------------------------------------------- routes


def study_track_route(name: str, track_path: str | Path, *, terrain_path: str | Path | None = None,
                      road_class: str = "B", track_index: int | None = None, description: str = "",
                      extra_vehicles: Sequence[str] = ()) -> StudyRoute:
    """A GPS track (over a terrain map, or on its own elevations) as a study route.

    The public path of ``profileopt plan TRACK [--terrain TERRAIN] --roughness-class CLASS``:
    :func:`profileopt.io.read_track`, :func:`profileopt.io.read_terrain` and
    :func:`profileopt.terrain.ground_track.route_from_track` with its default spacing,
    corridor and gap, and the roughness of an ISO 8608 class assumed (a GPS track or an
    airborne LiDAR cloud gives the route's shape and grade, not its roughness).

    Parameters
    ----------
    name : str
        The route's name in the study.
    track_path : str or pathlib.Path
        A GPX, GeoJSON or CSV track.
    terrain_path : str or pathlib.Path, optional
        A point cloud, DEM or OpenCRG surface under the track; default none (the track's own
        elevations, smoothed).
    road_class : str, default "B"
        The ISO 8608 class assumed for the roughness (``--roughness-class``).
    track_index : int, optional
        Which track of a GPX file of several drives (``--track-index``).
    description : str, optional
        One line for the study's table.
    extra_vehicles : sequence of str, optional
        Vehicles that drive this route besides the study's own.

    Returns
    -------
    StudyRoute

    Raises
    ------
    InputError
        The ``geo`` extra is missing (one line naming it), or a file cannot be read or
        sampled (as ``profileopt plan`` says).
    """
    from ..io import read_terrain, read_track
    from ..terrain.assumed import AssumedRoughness
    from ..terrain.ground_track import route_from_track

    terrain = read_terrain(terrain_path) if terrain_path is not None else None
    track = read_track(track_path, track_index=track_index)
    made = route_from_track(track, terrain, assumed_roughness=AssumedRoughness(road_class=road_class))
    return StudyRoute(name=name, route=made.route, description=description, extra_vehicles=tuple(extra_vehicles))


def graded_road_m(s_m: np.ndarray, grades: Sequence[float], joins_m: Sequence[float], curve_m: float) -> np.ndarray:
    """Elevation of a road of constant grades joined by smooth vertical curves (m).

    The grade is ``grades[0]`` before ``joins_m[0]``, ``grades[k]`` between ``joins_m[k-1]``
    and ``joins_m[k]``, and changes linearly over ``curve_m`` centred on each join (a
    parabolic vertical curve, as roads are built): the elevation is continuous with a
    continuous slope, 0 at s = 0.

    Parameters
    ----------
    s_m : numpy.ndarray, shape (M,)
        Distance along the road (m).
    grades : sequence of float
        The grades, rise over run (0.05 for 5 %), one more than ``joins_m``.
    joins_m : sequence of float
        Where the grade changes (m), increasing, at least ``curve_m`` apart.
    curve_m : float
        Length of each vertical curve (m), > 0.

    Returns
    -------
    numpy.ndarray, shape (M,)
        Elevation (m).

    Raises
    ------
    InputError
        ``grades`` is not one longer than ``joins_m``, or ``curve_m`` is not positive.
    """
    if len(grades) != len(joins_m) + 1:
        raise InputError(f"grades has {len(grades)} entries; give one more than joins_m ({len(joins_m)})")
    if not (math.isfinite(curve_m) and curve_m > 0):
        raise InputError(f"curve_m = {curve_m!r}: must be a finite number > 0")
    s = np.asarray(s_m, dtype=float)
    half = 0.5 * curve_m

    def bent(x: np.ndarray) -> np.ndarray:
        """The integral of a unit ramp of grade from -half to +half about 0 (the curve's shape)."""
        return np.where(x <= -half, 0.0, np.where(x >= half, x, (x + half) ** 2 / (2.0 * curve_m)))

    z = grades[0] * s
    for join, before, after in zip(joins_m, grades[:-1], grades[1:]):
        z = z + (after - before) * (bent(s - join) - bent(np.asarray(-join)))
    return z


def _samples(length_m: float, spacing_m: float) -> np.ndarray:
    return np.round(spacing_m * np.arange(round(length_m / spacing_m) + 1), 10)


def synthetic_routes(length_m: float = SYNTHETIC_LENGTH_M, spacing_m: float = SYNTHETIC_SPACING_M, *,
                     texture_class: str = "B", seed: int = 29) -> list[StudyRoute]:
    """The hilly synthetic roads of the study, each with its baseline (the bare road).

    Every road starts and ends level (a vertical curve into and out of its grade) and has a
    seeded ISO 8608 texture (class ``texture_class``, a gravel road); its baseline is the
    same road and texture without the obstacles. Positions scale with ``length_m``
    (quoted here for the default 400 m):

    - ``kerb+drop <g> %`` for g = 0, +5, -5, +15, -15: an 8 cm kerb up at 150 m and an 8 cm
      drop at 250 m on a constant grade g (:data:`KERB_HEIGHT_M`);
    - ``crest kerb, dip drop`` and ``crest drop, dip kerb``: +10 % up to a crest at 130 m,
      -10 % down to a dip at 270 m, +10 % again (vertical curves 40 m long), the kerb and
      the drop at the crest's top and the dip's bottom, one way round and the other;
    - ``potholes +10 %``: five potholes 5-10 cm deep and 0.3-1 m long, 25 m apart, on a 10 %
      climb;
    - ``washboard -5 %``: 100 m of washboard (2 cm amplitude, 0.75 m wavelength) on a 5 %
      descent;
    - ``block field +8 %``: twelve blocks 5-12 cm high, 0.2-0.6 m long, at seeded places
      over 100 m of an 8 % climb;
    - ``rolling hills``: grades from -15 % to +15 % changing every 45-50 m over 20 m vertical
      curves, with a kerb, a drop, a pothole and 20 m of washboard on them.

    Parameters
    ----------
    length_m : float, default :data:`SYNTHETIC_LENGTH_M`
        Length of every road (m), at least 40 (the tests use short ones).
    spacing_m : float, default :data:`SYNTHETIC_SPACING_M`
        Sample spacing (m).
    texture_class : str, default "B"
        ISO 8608 class of the texture on every road.
    seed : int, default 29
        Seed of the textures and of the block field's places.

    Returns
    -------
    list of StudyRoute
        Eleven routes, each with ``baseline`` set.

    Raises
    ------
    InputError
        A length below 40 m, a bad spacing, class or seed.
    """
    if not length_m >= 40.0:
        raise InputError(f"length_m = {length_m!r}: give at least 40 m (the obstacles sit from 0.3 to 0.7 of it)")
    s = _samples(length_m, spacing_m)
    f = length_m / SYNTHETIC_LENGTH_M  # positions below are for 400 m
    h = KERB_HEIGHT_M
    rng = np.random.default_rng(seed)

    def texture(k: int) -> np.ndarray:
        return iso8608_profile(texture_class, float(s[-1]), spacing_m, seed + k).z_m[: s.size]

    def level_ends(grade: float) -> np.ndarray:
        """Level for the first and last 8 % of the road, the grade between (10 % curves)."""
        return graded_road_m(s, [0.0, grade, 0.0], [0.08 * length_m, 0.92 * length_m], 0.1 * length_m)

    def pits(where_m: Sequence[float], widths_m: Sequence[float], depths_m: Sequence[float]) -> np.ndarray:
        z = np.zeros_like(s)
        for a, w, d in zip(where_m, widths_m, depths_m):
            z -= d * ((s >= a) & (s < a + w))
        return z

    routes = []

    def add(name: str, description: str, bare: np.ndarray, obstacles: np.ndarray, k: int) -> None:
        rough = texture(k)
        routes.append(StudyRoute(
            name=name, description=description,
            route=Route(s, bare + rough + obstacles, source=name),
            baseline=Route(s, bare + rough, source=f"{name} (bare road)"),
        ))

    for k, grade in enumerate((0.0, 0.05, -0.05, 0.15, -0.15)):
        pct = f"{100 * grade:+.0f}" if grade else "0"
        add(f"kerb+drop {pct} %", f"an {100 * h:.0f} cm kerb up at {150 * f:g} m and a drop at {250 * f:g} m on a "
            f"{pct} % grade", level_ends(grade),
            step(s, 150 * f, h) + step(s, 250 * f, -h), k)
    crest, dip = 130 * f, 270 * f
    hills = graded_road_m(s, [0.0, 0.10, -0.10, 0.10, 0.0],
                          [0.05 * length_m, crest, dip, 0.95 * length_m], 40 * f)
    add("crest kerb, dip drop", f"+10 % to a crest at {crest:g} m, -10 % to a dip at {dip:g} m (40 m vertical "
        f"curves); an {100 * h:.0f} cm kerb up on the crest, a drop in the dip", hills,
        step(s, crest, h) + step(s, dip, -h), 5)
    add("crest drop, dip kerb", "the same road; the drop on the crest, the kerb in the dip", hills,
        step(s, crest, -h) + step(s, dip, h), 5)
    holes = [f * x for x in (150.0, 175.0, 200.0, 225.0, 250.0)]
    add("potholes +10 %", f"five potholes 5-10 cm deep, 0.3-1 m long, from {holes[0]:g} m to {holes[-1]:g} m on a "
        "10 % climb", level_ends(0.10), pits(holes, [0.3, 0.5, 1.0, 0.6, 0.4], [0.05, 0.08, 0.10, 0.06, 0.10]), 6)
    add("washboard -5 %", f"washboard (2 cm amplitude, 0.75 m wavelength) from {150 * f:g} m to {250 * f:g} m on a "
        "5 % descent", level_ends(-0.05), washboard(s, 0.02, 0.75, start_m=150 * f, end_m=250 * f), 7)
    starts = np.sort(rng.uniform(150 * f, 250 * f - 1.0, size=12))
    add("block field +8 %", f"twelve blocks 5-12 cm high, 0.2-0.6 m long, at seeded places from {150 * f:g} m to "
        f"{250 * f:g} m on an 8 % climb", level_ends(0.08),
        -pits(starts, rng.uniform(0.2, 0.6, size=12), rng.uniform(0.05, 0.12, size=12)), 8)
    joins = [f * x for x in (30.0, 75.0, 120.0, 165.0, 210.0, 255.0, 300.0, 350.0)]
    rolling = graded_road_m(s, [0.0, 0.08, 0.15, -0.05, -0.15, 0.10, -0.10, 0.04, 0.0], joins, 20 * f)
    add("rolling hills", f"grades 0, +8, +15, -5, -15, +10, -10, +4, 0 % changing every 45-50 m over {20 * f:g} m "
        f"vertical curves; an {100 * h:.0f} cm kerb on the +15 % climb, a drop on the -15 % descent, a 10 cm pothole "
        "on the +10 % climb, 20 m of washboard on the -10 % descent", rolling,
        step(s, 97.5 * f, h) + step(s, 187.5 * f, -h) + pits([232.5 * f], [0.5], [0.10])
        + washboard(s, 0.02, 0.75, start_m=267.5 * f, end_m=287.5 * f), 9)
    return routes


def obstacle_route(kind: str, height_m: float, width_m: float, spacing_m: float) -> Route:
    """60 m of flat ground sampled every ``spacing_m`` with one obstacle at 40 m.

    40 m of run-up, so the plan meets the obstacle fast. The obstacle family of issue 29
    (:data:`OBSTACLE_FAMILY`).

    Parameters
    ----------
    kind : str
        ``"block"`` (ground ``height_m`` higher from 40 m to 40 m + ``width_m``), ``"pit"``
        (as deep), ``"kerb"`` (``height_m`` higher from 40 m on) or ``"drop"`` (lower).
    height_m : float
        Height or depth of the obstacle (m), >= 0.
    width_m : float
        Length of a block or a pit along the route (m); unused for a kerb or a drop.
    spacing_m : float
        Sample spacing (m).

    Returns
    -------
    Route
        Its source reads ``"<kind> <height_m> m x <width_m> m every <spacing_m> m"``.

    Raises
    ------
    InputError
        An unknown kind.
    """
    if kind not in OBSTACLE_KINDS:
        raise InputError(f"kind = {kind!r}: one of {', '.join(OBSTACLE_KINDS)}")
    s = np.round(np.arange(0.0, _OBSTACLE_ROUTE_M + 1e-9, spacing_m), 10)
    inside = (s >= _OBSTACLE_AT_M) & (s < _OBSTACLE_AT_M + width_m)
    z = {"block": height_m * inside, "pit": -height_m * inside, "kerb": height_m * (s >= _OBSTACLE_AT_M),
         "drop": -height_m * (s >= _OBSTACLE_AT_M)}[kind]
    return Route(s_m=s, z_m=z, source=f"{kind} {height_m} m x {width_m} m every {spacing_m} m")


@dataclasses.dataclass(frozen=True)
class ObstacleStudy:
    """The obstacle family planned for each vehicle and simulated.

    Attributes
    ----------
    cases : tuple of (str, float, float, float)
        (kind, height_m, width_m, spacing_m) of each route, in order.
    study : RealRouteStudy
        Its results: route names are the routes' sources
        (:func:`obstacle_route`), each baseline the same flat ground without the obstacle.
    """

    cases: tuple[tuple[str, float, float, float], ...]
    study: RealRouteStudy

    @property
    def results(self) -> tuple[PairResult, ...]:
        """Every (route, vehicle) result, routes outermost."""
        return self.study.results

    def counts(self) -> dict:
        """The headline numbers, JSON-ready.

        Returns
        -------
        dict
            ``plans``, ``planned`` (the others not drivable or refused), ``over_limit``
            (planned pairs ``verify`` rejects), ``worst_window_ratio`` and ``worst`` (its
            route and vehicle), ``gated`` (plans the planner's simulation gate capped) and
            ``gated_capped_m`` (the most it capped of one route, m).
        """
        planned = self.study.planned
        worst = max(planned, key=lambda r: r.worst_window_ratio, default=None)
        gated = [r for r in planned if r.gated]
        return {
            "plans": len(self.results),
            "planned": len(planned),
            "over_limit": len(self.study.failing),
            "worst_window_ratio": worst.worst_window_ratio if worst else math.nan,
            "worst": f"{worst.route}, {worst.vehicle}" if worst else "",
            "gated": len(gated),
            "gated_capped_m": max((r.gate_capped_m for r in gated), default=0.0),
        }

    def markdown(self, slowest: int = 10) -> str:
        """The counts as a sentence, then the slowest routes, those the simulation gate capped
        and every route over the limit as a Markdown table each.

        Parameters
        ----------
        slowest : int, default 10
            How many of the slowest plans (by travel time over the flat ground's) to list.

        Returns
        -------
        str
        """
        c = self.counts()
        lines = [
            f"{c['plans']} plans ({len(self.cases)} routes x {len(self.study.vehicles)} vehicles): {c['planned']} "
            f"planned, {c['over_limit']} over the force limit in `verify`, worst window {c['worst_window_ratio']:.3f} "
            f"x the limit ({c['worst']}); the planner's simulation gate capped {c['gated']} of them (at most "
            f"{c['gated_capped_m']:.1f} m of a route).",
            "",
            f"The {slowest} slowest (travel time over 60 m of flat ground's, for the same vehicle):",
            "",
            _obstacle_table(sorted(self.study.planned, key=lambda r: -r.time_ratio)[:slowest]),
        ]
        gated = [r for r in self.study.planned if r.gated]
        lines += ["", f"Capped by the planner's simulation gate: {len(gated)}."]
        if gated:
            lines += ["", _obstacle_table(gated)]
        over = self.study.failing
        lines += ["", f"Over the limit in `verify`: {len(over)}."]
        if over:
            lines += ["", _obstacle_table(sorted(over, key=lambda r: -r.worst_window_ratio))]
        not_planned = [r for r in self.results if not r.planned]
        if not_planned:
            lines += ["", f"Not planned: {len(not_planned)}."] + [f"- {r.route}, {r.vehicle}: {r.outcome}: "
                                                                   f"{_cell(r.status)}" for r in not_planned]
        return "\n".join(lines)


def _obstacle_table(rows: Sequence[PairResult]) -> str:
    lines = ["| route | vehicle | time (s) | / flat | slowest (m/s) | worst window sim / limit | gate capped (m) |",
             "|---|---|---:|---:|---:|---:|---:|"]
    for r in rows:
        gated = f"{r.gate_capped_m:.1f}" if r.gated else ""
        lines.append(f"| {r.route} | {r.vehicle} | {r.travel_time_s:.2f} | {r.time_ratio:.2f} | "
                     f"{r.slowest_speed_mps:.2f} | {r.worst_window_ratio:.3f} | {gated} |")
    return "\n".join(lines)


def obstacle_study(family: Sequence[tuple[str, float, float, float]] = OBSTACLE_FAMILY,
                   vehicles: Sequence["str | Vehicle"] = DEFAULT_VEHICLES, *,
                   on_pair: Callable[[PairRun], None] | None = None) -> ObstacleStudy:
    """Plan every obstacle route for every vehicle with default options, and verify.

    The whole family (360 plans with the two default vehicles) takes about 4-6 minutes on 2
    cores.

    Parameters
    ----------
    family : sequence of (str, float, float, float), default :data:`OBSTACLE_FAMILY`
        (kind, height_m, width_m, spacing_m) of each route (:func:`obstacle_route`).
    vehicles : sequence of str or Vehicle, default :data:`DEFAULT_VEHICLES`
    on_pair : callable, optional
        Called with each :class:`PairRun` (see :func:`real_route_study`).

    Returns
    -------
    ObstacleStudy
    """
    flat = {ds: obstacle_route("kerb", 0.0, 0.0, ds) for ds in sorted({case[3] for case in family})}
    routes = []
    for kind, height_m, width_m, spacing_m in family:
        route = obstacle_route(kind, height_m, width_m, spacing_m)
        routes.append(StudyRoute(name=str(route.source), route=route, baseline=flat[spacing_m],
                                 description=f"a {kind} on 60 m of flat ground"))
    return ObstacleStudy(cases=tuple(tuple(case) for case in family),
                         study=real_route_study(routes, vehicles, on_pair=on_pair))
