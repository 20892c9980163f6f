"""The safety study: every force model over a fixed set of routes and vehicles, pooled.

:func:`safety_study` runs :func:`profileopt.studies.compare.compare_models` over every (route,
vehicle) pair of a set, with per-model totals pooled over the set (:class:`SafetyStudy`):
the fraction of all roughness windows (and of all segments) whose simulated force exceeds
the limit, the paper's claim (Prev:BEM is aggressive, the SBEM models are safe) put to a
test on many routes at once (``examples/safety_study.py``).

Everything reported is deterministic (no wall-clock times), so the same routes and
vehicles give the same numbers on every run.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path
from typing import TYPE_CHECKING, Sequence

import numpy as np

from ..defaults import DEFAULT_REFINE
from ..physics.forces import MODELS, get_model
from ..progress import NO_PROGRESS, Progress
from .compare import INFEASIBLE, ModelRun, compare_models

if TYPE_CHECKING:
    from ..core.route import Route
    from ..core.vehicle import Vehicle

__all__ = ["ModelTotals", "SafetyStudy", "safety_study"]


@dataclasses.dataclass(frozen=True)
class ModelTotals:
    """One model's results pooled over every (route, vehicle) pair of a study.

    Attributes
    ----------
    model, label : str
        Force model key and display label.
    runs : int
        (route, vehicle) pairs tried.
    infeasible_runs : int
        Pairs the model could not plan (infeasible or solver failure); they add no segments.
    segments : int
        Segments driven, summed over the planned pairs.
    over_count : int
        Of those, segments whose simulated force exceeds the limit.
    over_length_m : float
        Their total length (m).
    worst_ratio : float
        Largest simulated force / limit over every planned pair (dimensionless; nan if none
        was planned).
    worst_run : str
        ``"route, vehicle"`` of that worst ratio (empty if none).
    runs_over : int
        Planned pairs with at least one segment over the limit.
    travel_time_s : float
        Total travel time over the planned pairs (s).
    mean_time_ratio : float
        Mean over the pairs that both this model and the study's reference model planned of
        travel time / the reference's travel time (dimensionless; nan if there is no such
        pair).
    windows, windows_over : int
        Roughness windows of the planned pairs, and those over the limit.
    worst_window_ratio : float
        Largest simulated force / limit of any window (nan if no pair was planned).
    worst_window_run : str
        ``"route, vehicle"`` of that window (empty if none).
    runs_window_over : int
        Planned pairs with at least one window over the limit.
    """

    model: str
    label: str
    runs: int
    infeasible_runs: int
    segments: int
    over_count: int
    over_length_m: float
    worst_ratio: float
    worst_run: str
    runs_over: int
    travel_time_s: float
    mean_time_ratio: float
    windows: int = 0
    windows_over: int = 0
    worst_window_ratio: float = math.nan
    worst_window_run: str = ""
    runs_window_over: int = 0

    @property
    def over_fraction(self) -> float:
        """Pooled share of segments over the limit: over_count / segments (nan if none)."""
        return self.over_count / self.segments if self.segments else math.nan

    @property
    def window_over_fraction(self) -> float:
        """Pooled share of windows over the limit: windows_over / windows (nan if none)."""
        return self.windows_over / self.windows if self.windows else math.nan


@dataclasses.dataclass(frozen=True)
class SafetyStudy:
    """Every model planned and simulated on every (route, vehicle) pair, and the totals.

    Attributes
    ----------
    runs : tuple of ModelRun
        One per (route, vehicle, model), routes outermost, then vehicles, then models.
    totals : tuple of ModelTotals
        One per model, in the order of the study's models.
    models : tuple of str
        The model keys, in order.
    reference_model : str
        The model travel times are compared with (``ModelTotals.mean_time_ratio``).
    segment_length_m : float
        Segment length used for every plan (m).
    roughness_window_m : float
        Roughness window length W of every plan and check (m).
    refine : bool
        Whether every plan was made with ``refine``.
    """

    runs: tuple[ModelRun, ...]
    totals: tuple[ModelTotals, ...]
    models: tuple[str, ...]
    reference_model: str
    segment_length_m: float
    roughness_window_m: float = 5.0
    refine: bool = DEFAULT_REFINE

    def total(self, model: str) -> ModelTotals:
        """The pooled totals of one model (by key).

        Parameters
        ----------
        model : str
            A force model key of this study, one of :attr:`models` (e.g. ``"sbem_ef"``).

        Returns
        -------
        ModelTotals

        Raises
        ------
        KeyError
            ``model`` is not one of the study's models.
        """
        for row in self.totals:
            if row.model == model:
                return row
        raise KeyError(f"model {model!r} is not in this study ({', '.join(self.models)})")

    def pairs(self) -> list[tuple[str, str]]:
        """The (route, vehicle) pairs of the study, in order."""
        return [(runs[0].route, runs[0].vehicle) for runs in self._grouped()]

    def _grouped(self) -> list[tuple[ModelRun, ...]]:
        """The runs of each (route, vehicle) pair, pairs in order."""
        groups: dict[tuple[str, str], list[ModelRun]] = {}
        for run in self.runs:
            groups.setdefault((run.route, run.vehicle), []).append(run)
        return [tuple(runs) for runs in groups.values()]

    def totals_where_all_planned(self) -> tuple[ModelTotals, ...]:
        """Per-model totals pooled over only the pairs that every model could plan.

        The pooled :attr:`totals` of a model leave out the pairs it found infeasible, so
        models that refuse different pairs are pooled over different segments; these totals
        compare every model on the same segments.
        """
        pairs = [runs for runs in self._grouped() if all(r.planned for r in runs)]
        return tuple(_totals(pairs, key, self.reference_model) for key in self.models)

    def markdown(self) -> str:
        """The pooled totals as a Markdown table (one row per model): roughness windows
        first (the definition of keeping the limit), then segments."""
        reference = get_model(self.reference_model).label
        lines = [
            f"| model | windows over the limit (pooled) | worst window simulated / limit (where) | "
            f"pairs with a window over | segments over the limit | worst segment | "
            f"mean travel time / {reference} | not drivable |",
            "|---|---:|---:|---:|---:|---:|---:|---:|",
        ]
        for t in self.totals:
            share = f"{100 * t.window_over_fraction:.2f} %" if t.windows else "n/a"
            lines.append(
                f"| {t.label} | {t.windows_over} of {t.windows} ({share}) | {t.worst_window_ratio:.2f} "
                f"({t.worst_window_run}) | {t.runs_window_over} of {t.runs - t.infeasible_runs} | "
                f"{t.over_count} of {t.segments} | {t.worst_ratio:.2f} | {t.mean_time_ratio:.2f} | "
                f"{t.infeasible_runs} of {t.runs} |"
            )
        return "\n".join(lines)

    def exceedance_markdown(self, every_pair: bool = False) -> str:
        """Windows over the limit per (route, vehicle) pair and model, as a Markdown table.

        ``every_pair=False`` lists only the pairs where some model has a window or a segment
        over the limit. A cell reads ``windows over / windows (worst ratio)``, or ``not
        drivable``.

        Parameters
        ----------
        every_pair : bool, optional
            List every (route, vehicle) pair, not only those with a window over the limit.
            Default False.

        Returns
        -------
        str
            The table: a header row of model labels, then one row per pair listed.
        """
        labels = [get_model(m).label for m in self.models]
        lines = ["| route | vehicle | " + " | ".join(labels) + " |",
                 "|---|---|" + "---:|" * len(labels)]
        for route, vehicle in self.pairs():
            runs = {r.model: r for r in self.runs if (r.route, r.vehicle) == (route, vehicle)}
            if not every_pair and not any(r.planned and (r.windows_over or r.over_count) for r in runs.values()):
                continue
            cells = []
            for key in self.models:
                run = runs[key]
                if not run.planned:
                    cells.append("not drivable" if run.outcome == INFEASIBLE else run.outcome)
                elif run.windows_over:
                    cells.append(f"**{run.windows_over}** / {run.windows['windows']} ({run.worst_window_ratio:.2f})")
                else:
                    cells.append(f"0 / {run.windows['windows']} ({run.worst_window_ratio:.2f})")
            lines.append(f"| {_short(route)} | {vehicle} | " + " | ".join(cells) + " |")
        return "\n".join(lines)


class _StepsOnly(Progress):
    """Passes on the steps, not what is expected (the study expected every run at its start)."""

    def __init__(self, inner: Progress) -> None:
        self._inner = inner

    def step(self, name: str) -> None:
        self._inner.step(name)


def _short(source: str) -> str:
    """A route's file name (its source without folders)."""
    return Path(source).name


def _totals(pairs: Sequence[tuple[ModelRun, ...]], model: str, reference_model: str) -> ModelTotals:
    """Pool one model's runs; ``pairs`` holds each (route, vehicle) pair's runs."""
    mine = [r for runs in pairs for r in runs if r.model == model]
    done = [r for r in mine if r.planned]
    worst = max(done, key=lambda r: r.worst_ratio, default=None)
    worst_window = max(done, key=lambda r: r.worst_window_ratio, default=None)
    ratios = []
    for runs in pairs:
        by_model = {r.model: r for r in runs}
        run, ref = by_model.get(model), by_model.get(reference_model)
        if run is not None and ref is not None and run.planned and ref.planned and ref.travel_time_s > 0:
            ratios.append(run.travel_time_s / ref.travel_time_s)
    return ModelTotals(
        model=model,
        label=get_model(model).label,
        runs=len(mine),
        infeasible_runs=len(mine) - len(done),
        segments=sum(r.segments for r in done),
        over_count=sum(r.over_count for r in done),
        over_length_m=float(sum(r.over_length_m for r in done)),
        worst_ratio=worst.worst_ratio if worst else math.nan,
        worst_run=f"{_short(worst.route)}, {worst.vehicle}" if worst else "",
        runs_over=sum(1 for r in done if r.over_count > 0),
        travel_time_s=float(sum(r.travel_time_s for r in done)),
        mean_time_ratio=float(np.mean(ratios)) if ratios else math.nan,
        windows=sum(r.windows["windows"] for r in done),
        windows_over=sum(r.windows_over for r in done),
        worst_window_ratio=worst_window.worst_window_ratio if worst_window else math.nan,
        worst_window_run=f"{_short(worst_window.route)}, {worst_window.vehicle}" if worst_window else "",
        runs_window_over=sum(1 for r in done if r.windows_over > 0),
    )


def safety_study(
    routes: Sequence["Route"],
    vehicles: Sequence["Vehicle"],
    models: Sequence[str] | None = None,
    *,
    segment_length_m: float = 5.0,
    roughness_window_m: float = 5.0,
    reference_model: str = "sbem_tf",
    refine: bool = DEFAULT_REFINE,
    simulation_gate: bool = False,
    progress: Progress = NO_PROGRESS,
) -> SafetyStudy:
    """Plan every route for every vehicle with every model, simulate, and pool the results.

    Parameters
    ----------
    routes : sequence of Route
        The route set; every route is driven by every vehicle. (For a route meant for one
        vehicle only, run two studies or pass that vehicle alone.)
    vehicles : sequence of Vehicle
    models : sequence of str, optional
        Model keys; default all four (:data:`profileopt.physics.forces.MODELS`) in their order.
    segment_length_m : float, default 5
        Segment length of every plan (m).
    roughness_window_m : float, default 5
        Roughness window length W of every plan and check (m).
    reference_model : str, default ``"sbem_tf"``
        Model whose travel time the others are compared with (include it in ``models``,
        else every ``mean_time_ratio`` is nan).
    refine : bool, default True (:data:`profileopt.defaults.DEFAULT_REFINE`)
        Plan with ``refine`` (:func:`profileopt.planning.plan`); False plans on uniform
        segments.
    simulation_gate : bool, default False
        Plan with the planner's simulation gate (:mod:`profileopt.planning.gate`). Off by
        default: the study measures the force models themselves, and with the gate SBEM:TF's
        plans keep the limit in simulation by construction (and cost a simulation more each).
    progress : Progress, default :data:`profileopt.progress.NO_PROGRESS`
        Expects every (route, vehicle, model) run at the start and is told each as it
        starts (:func:`profileopt.progress.terminal_progress` shows it).

    Returns
    -------
    SafetyStudy
        Per (route, vehicle, model) :class:`ModelRun` rows and per-model
        :class:`ModelTotals`. A model that cannot plan a pair (infeasible) is recorded in
        its row and counted in ``infeasible_runs``; its pooled fraction is over the pairs it
        did plan.

    Raises
    ------
    InputError
        A route too sparsely sampled for the segment length, an unknown model, ...
    """
    keys = tuple(get_model(m).key for m in (MODELS if models is None else models))
    reference_key = get_model(reference_model).key
    progress.expect(len(routes) * len(vehicles) * len(keys))  # all at once: the bar's length is the study's
    steps = _StepsOnly(progress)
    pairs = [
        compare_models(route, vehicle, models=keys, segment_length_m=segment_length_m,
                       roughness_window_m=roughness_window_m, refine=refine, simulation_gate=simulation_gate,
                       progress=steps)
        for route in routes
        for vehicle in vehicles
    ]
    return SafetyStudy(
        runs=tuple(r for runs in pairs for r in runs),
        totals=tuple(_totals(pairs, key, reference_key) for key in keys),
        models=keys,
        reference_model=reference_key,
        segment_length_m=float(segment_length_m),
        roughness_window_m=float(roughness_window_m),
        refine=bool(refine),
    )
