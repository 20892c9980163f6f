"""Plan with every force model and check each plan in simulation.

The force models predict a worst case from a statistic of the terrain (the RI and a
confidence level); :func:`profileopt.verify` measures the forces a plan really
causes in the quarter-car simulation. This module runs that check for several models:

:func:`run_model`
    plan one route with one model and verify the plan (by roughness windows and by
    segments, :func:`profileopt.verify`): one :class:`ModelRun`. An
    infeasible route (:class:`~profileopt.errors.InfeasibleError`) or a solver failure
    (:class:`~profileopt.errors.PlanningError`) is recorded as the run's status, not
    raised.
:func:`compare_models`
    :func:`run_model` for each model on one route (what ``profileopt compare`` prints).

:mod:`profileopt.studies.safety` pools them over a whole route set (the safety study).

Everything reported is deterministic (no wall-clock times), so the same routes and
vehicles give the same numbers on every run.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import TYPE_CHECKING, Sequence

import numpy as np

from ..defaults import DEFAULT_REFINE, DEFAULT_SIMULATION_GATE
from ..core.vehicle import require_vehicle
from ..errors import InfeasibleError
from ..physics.forces import MODELS, get_model
from ..progress import NO_PROGRESS, Progress

if TYPE_CHECKING:
    from ..core.route import Route
    from ..core.vehicle import Vehicle
    from ..verification.verify import Verification

__all__ = ["Exceedance", "ModelRun", "run_model", "compare_models", "PLANNED", "INFEASIBLE", "SOLVER_FAILED"]

#: :attr:`ModelRun.outcome` of a run that was planned and simulated.
PLANNED = "planned"
#: :attr:`ModelRun.outcome` of a route that the model says cannot be driven.
INFEASIBLE = "infeasible"
#: :attr:`ModelRun.outcome` of a solver failure without a limit-keeping fallback.
SOLVER_FAILED = "solver failed"


@dataclasses.dataclass(frozen=True)
class Exceedance:
    """One segment whose simulated force exceeds the limit.

    Attributes
    ----------
    s_start_m, s_end_m, peak_s_m : float
        The segment, and where in it the simulated force of the model's kind peaks (m); a
        peak right after ``s_start_m`` is often the ringing of the segment before.
    ri : float
        The segment's RI (dimensionless).
    speed_start_mps, speed_end_mps : float
        Planned speeds at the segment's ends (m/s).
    predicted_n, simulated_n, limit_n : float
        The model's largest predicted force over the speeds driven in the segment, the
        simulated peak of that force in it, and the vehicle's limit for it (N).
    """

    s_start_m: float
    s_end_m: float
    peak_s_m: float
    ri: float
    speed_start_mps: float
    speed_end_mps: float
    predicted_n: float
    simulated_n: float
    limit_n: float

    @property
    def ratio(self) -> float:
        """Simulated force / limit (dimensionless, > 1)."""
        return self.simulated_n / self.limit_n


@dataclasses.dataclass(frozen=True)
class ModelRun:
    """One route planned with one force model and checked in simulation.

    The numbers are ``None`` unless ``outcome == "planned"``.

    Attributes
    ----------
    route : str
        The route's source (file name or label).
    vehicle : str
        The vehicle's name (its file's stem, e.g. ``"atv"``).
    model, label, quantity : str
        Force model key, its display label and the force it limits (``"transmitted"`` or
        ``"excitation"``).
    outcome : str
        ``"planned"``, ``"infeasible"`` or ``"solver failed"``.
    status : str
        The planner's status (``"optimal"``, ``"exact"``, ``"fallback: ..."``) when planned,
        else the error's one-line message.
    travel_time_s : float or None
        Time to drive the plan (s).
    segments : int or None
        Number of segments N.
    worst_ratio : float or None
        Largest simulated force / limit over the segments (dimensionless).
    worst_segment_start_m : float or None
        Start of the segment with the largest ratio (m).
    over_count : int or None
        Segments whose simulated force exceeds the limit.
    over_length_m : float or None
        Their total length (m).
    worst_transmitted_ratio : float or None
        Largest simulated |F_T| / ``max_transmitted_force_n`` (dimensionless), whatever the
        model limits.
    underpredicted_count : int or None
        Segments where the simulation exceeds the model's own prediction by more than 1 % of
        the limit.
    lift_off_count : int or None
        Segments where F_T < -m g (the real wheel would leave the ground).
    exceedances : tuple of Exceedance
        The segments over the limit, in order along the route.
    windows : dict or None
        The roughness windows (:meth:`profileopt.verification.window_check.WindowCheck.summary`): their
        count ``windows``, ``over_count`` (over the limit), ``underpredicted_count`` and the
        ``worst`` (``start_m``, ``ri``, ``simulated_n``, ``predicted_n``, ``ratio``, ...).
    """

    route: str
    vehicle: str
    model: str
    label: str
    quantity: str
    outcome: str
    status: str
    travel_time_s: float | None = None
    segments: int | None = None
    worst_ratio: float | None = None
    worst_segment_start_m: float | None = None
    over_count: int | None = None
    over_length_m: float | None = None
    worst_transmitted_ratio: float | None = None
    underpredicted_count: int | None = None
    lift_off_count: int | None = None
    exceedances: tuple[Exceedance, ...] = ()
    windows: dict | None = None

    @property
    def windows_over(self) -> int | None:
        """Roughness windows over the limit, ``None`` if not planned."""
        return None if self.windows is None else self.windows["over_count"]

    @property
    def worst_window_ratio(self) -> float | None:
        """Largest simulated force / limit of any roughness window, ``None`` if not planned."""
        return None if self.windows is None else self.windows["worst"]["ratio"]

    @property
    def planned(self) -> bool:
        """True if the route was planned and simulated."""
        return self.outcome == PLANNED

    @property
    def over_fraction(self) -> float | None:
        """Share of the segments over the limit (0 to 1), ``None`` if not planned."""
        if not self.planned:
            return None
        return self.over_count / self.segments

    def to_dict(self) -> dict:
        """The row of ``profileopt compare --json`` (keys in its order, SI units in names).

        A run that was not planned has only ``model``, ``label``, ``quantity`` and
        ``status`` (``"infeasible: <message>"`` or ``"solver failed: <message>"``).
        """
        row: dict = {"model": self.model, "label": self.label, "quantity": self.quantity}
        if not self.planned:
            row["status"] = f"{self.outcome}: {self.status}"
            return row
        row.update({name: getattr(self, name) for name in (
            "status", "travel_time_s", "segments", "worst_ratio", "worst_segment_start_m", "over_count",
            "over_fraction", "over_length_m", "worst_transmitted_ratio", "underpredicted_count", "lift_off_count",
            "windows")})
        return row


def _vehicle_label(vehicle: "Vehicle") -> str:
    return Path(vehicle.name).stem if vehicle.name else "vehicle"


def _exceedances(result: "Verification") -> tuple[Exceedance, ...]:
    """The segments of ``result`` over the limit, with where in each the force peaks."""
    run = result.run
    series = np.abs(run.transmitted_n if result.quantity == "transmitted" else run.excitation_n)
    out = []
    for i in np.flatnonzero(result.over):
        lo, hi = result.s_m[i], result.s_m[i + 1]
        last = i == result.ratio.size - 1
        inside = (run.s_m >= lo) & ((run.s_m <= hi) if last else (run.s_m < hi))
        peak_s = float(run.s_m[inside][np.argmax(series[inside])]) if np.any(inside) else float(lo)
        out.append(Exceedance(
            s_start_m=float(lo), s_end_m=float(hi), peak_s_m=peak_s, ri=float(result.ri[i]),
            speed_start_mps=float(result.speed_mps[i]), speed_end_mps=float(result.speed_mps[i + 1]),
            predicted_n=float(result.predicted_n[i]), simulated_n=float(result.simulated_n[i]),
            limit_n=float(result.limit_n[i]),
        ))
    return tuple(out)


def run_model(route: "Route", vehicle: "Vehicle", model: str, *, segment_length_m: float = 5.0,
              roughness_window_m: float = 5.0, refine: bool = DEFAULT_REFINE,
              simulation_gate: bool = DEFAULT_SIMULATION_GATE) -> ModelRun:
    """Plan ``route`` with ``model`` (planner defaults otherwise) and verify the plan.

    Parameters
    ----------
    route : Route
    vehicle : Vehicle
    model : str
        Force model key (:data:`profileopt.physics.forces.MODELS`).
    segment_length_m : float, default 5
        Segment length (m).
    roughness_window_m : float, default 5
        Roughness window length W (m), for the plan and for the check.
    refine : bool, default True (:data:`profileopt.defaults.DEFAULT_REFINE`)
        Plan with ``refine`` (:func:`profileopt.planning.plan`); False plans on uniform
        segments.
    simulation_gate : bool, default True (:data:`profileopt.defaults.DEFAULT_SIMULATION_GATE`)
        Plan with the planner's simulation gate (:mod:`profileopt.planning.gate`); False
        measures the force model's own plan.

    Returns
    -------
    ModelRun
        ``outcome`` ``"infeasible"`` if the planner raises
        :class:`~profileopt.errors.InfeasibleError`, ``"solver failed"`` if it raises
        :class:`~profileopt.errors.PlanningError`; otherwise the verification's numbers.

    Raises
    ------
    InputError
        Bad options or route (other than infeasibility), an unknown model.
    """
    from ..errors import PlanningError
    from ..planning import plan
    from ..verification.verify import verify

    force_model = get_model(model)
    common = {"route": str(route.source), "vehicle": _vehicle_label(vehicle), "model": force_model.key,
              "label": force_model.label, "quantity": force_model.quantity}
    try:
        profile = plan(route, vehicle, segment_length_m=segment_length_m, model=force_model.key,
                       roughness_window_m=roughness_window_m, refine=refine, simulation_gate=simulation_gate)
    except InfeasibleError as exc:
        return ModelRun(**common, outcome=INFEASIBLE, status=str(exc))
    except PlanningError as exc:
        return ModelRun(**common, outcome=SOLVER_FAILED, status=str(exc))
    result = verify(route, profile, vehicle, model=force_model.key, roughness_window_m=roughness_window_m)
    return ModelRun(
        **common,
        outcome=PLANNED,
        status=profile.status,
        travel_time_s=profile.travel_time_s,
        segments=int(result.ratio.size),
        worst_ratio=result.worst_ratio,
        worst_segment_start_m=float(result.s_m[result.worst_segment]),
        over_count=result.over_count,
        over_length_m=result.over_length_m,
        worst_transmitted_ratio=float(result.transmitted_peak_n.max() / vehicle.max_transmitted_force_n),
        underpredicted_count=int(result.underpredicted.sum()),
        lift_off_count=int(result.lift_off.sum()),
        exceedances=_exceedances(result),
        windows=result.windows.summary(),
    )


def compare_models(
    route: "Route",
    vehicle: "Vehicle",
    *,
    models: Sequence[str] | None = None,
    segment_length_m: float = 5.0,
    roughness_window_m: float = 5.0,
    refine: bool = DEFAULT_REFINE,
    simulation_gate: bool = DEFAULT_SIMULATION_GATE,
    progress: Progress = NO_PROGRESS,
) -> tuple[ModelRun, ...]:
    """:func:`run_model` for each model on one route (``profileopt compare``).

    Parameters
    ----------
    route : Route
    vehicle : Vehicle
    models : sequence of str, optional
        Model keys in the order wanted; default all four (:data:`profileopt.physics.forces.MODELS`).
    segment_length_m : float, default 5
        Segment length (m).
    roughness_window_m : float, default 5
        Roughness window length W (m).
    refine : bool, default True (:data:`profileopt.defaults.DEFAULT_REFINE`)
        Plan with ``refine`` (:func:`profileopt.planning.plan`); False plans on uniform
        segments.
    simulation_gate : bool, default True (:data:`profileopt.defaults.DEFAULT_SIMULATION_GATE`)
        Plan with the planner's simulation gate (:mod:`profileopt.planning.gate`); False
        measures the force model's own plan.
    progress : Progress, default :data:`profileopt.progress.NO_PROGRESS`
        Expects one step per model and is told each as it starts.

    Returns
    -------
    tuple of ModelRun
        One per model, in the order given.
    """
    vehicle = require_vehicle(vehicle, "compare_models")
    keys = list(MODELS) if models is None else list(models)
    progress.expect(len(keys))
    runs = []
    for key in keys:
        progress.step(f"{_short_source(route)}, {_vehicle_label(vehicle)}: planning and simulating with "
                      f"{get_model(key).label}")
        runs.append(run_model(route, vehicle, key, segment_length_m=segment_length_m,
                              roughness_window_m=roughness_window_m, refine=refine, simulation_gate=simulation_gate))
    return tuple(runs)


def _short_source(route: "Route") -> str:
    """A route's name for a progress display: its source's last part."""
    return Path(str(route.source)).name
