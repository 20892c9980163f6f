"""A planned speed profile: what the planner returns, what a profile CSV holds.

:class:`Profile` has one row per segment boundary (the CSV columns
:data:`PROFILE_COLUMNS`), what the planner knows beyond them (bands, allowable speeds, the
limits it was planned under) and derived quantities: the jerk at the boundaries and a
summary for people and for ``--json`` (:meth:`Profile.summary`).
"""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING

import numpy as np

from ..defaults import DEFAULT_MODEL, LIMIT_RTOL
from .binding import binding_shares
from .kinematics import boundary_jerk_mps3
from .path import turn_notes

if TYPE_CHECKING:
    from .path import SegmentPath

__all__ = ["Profile", "PROFILE_COLUMNS", "BASE_COLUMNS", "at_limit"]

#: The first eight columns of a profile CSV: all that files written before turns and hills hold.
BASE_COLUMNS = ("s_m", "speed_mps", "accel_mps2", "time_s", "ri", "e_max_m", "force_n", "force_limit_n")
#: Columns of a profile CSV, in order: the eight, then the path's curvature and grade at each
#: row and the limit that holds the speed there (``binding``, text; see
#: :mod:`profileopt.core.binding`).
PROFILE_COLUMNS = BASE_COLUMNS + ("curvature_1pm", "grade_rad", "binding")


def at_limit(margin: dict, rtol: float = LIMIT_RTOL) -> dict:
    """A margin whose ratio is above 1 by at most ``rtol`` (rounding: the plan keeps the limit
    within the tolerance it is checked to) read as exactly 1, at the limit.

    Parameters
    ----------
    margin : dict
        ``{"ratio": float or None, "s_m": float or None}`` (a limit's
        :meth:`~profileopt.planning.limits.Limit.margins` entry).
    rtol : float, default :data:`~profileopt.defaults.LIMIT_RTOL`
        The relative tolerance within which a value keeps its limit.

    Returns
    -------
    dict
        ``margin`` with ``ratio`` 1.0 where it was in (1, 1 + rtol]; any other ratio as it is
        (above the tolerance it is a breach, and reads as one).
    """
    ratio = margin.get("ratio")
    if ratio is not None and 1.0 < ratio <= 1.0 + rtol:
        return {**margin, "ratio": 1.0}
    return margin


@dataclasses.dataclass(frozen=True, eq=False)
class Profile:
    """A speed profile along a route: one row per segment boundary.

    Attributes
    ----------
    s_m : numpy.ndarray, shape (N+1,)
        Segment boundaries (m).
    speed_mps : numpy.ndarray, shape (N+1,)
        Speed at each boundary (m/s). Inside a segment the acceleration is constant, so
        v(s)^2 is linear in s between boundaries.
    accel_mps2 : numpy.ndarray, shape (N+1,)
        Acceleration of the segment starting at that row (m/s^2); the last row repeats.
    time_s : numpy.ndarray, shape (N+1,)
        Arrival time at each boundary (s).
    ri, e_max_m, force_n, force_limit_n : numpy.ndarray, shape (N+1,)
        The segment's RI, worst-case elevation (m), the largest predicted force over the
        speeds driven inside it (N) and the model's force limit (N); last row repeats.
    status : str
        ``"optimal"`` (the NLP solver converged), ``"exact"`` (the forward-backward profile is
        the optimum: smoothing and jerk off), ``"fallback: <solver status>"`` (no solver gave
        a usable solution; the returned profile keeps every limit but is not optimal) or
        ``"read"`` (from a file).
    success : bool
        True unless the fallback was used.
    model : str
        Force model key.
    objective : float
        Travel time plus smoothing term (s), as minimised.
    timings_s : dict
        Wall-clock seconds of the stages (``segment``, ``path``, ``bands``, ``choose``,
        ``refine`` when refining, ``build``, ``solve``, ``total``).
    iterations : int
        NLP solver iterations (0 if not run), of all its solves together (the chosen back
        end's and IPOPT's where IPOPT took over).
    pieces : int
        How many NLP solves make up the profile: 1 for a route solved whole, more for a
        long route solved in pieces (exactly; by default only with FATROP, see
        :attr:`~profileopt.planning.options.SolverOptions.split_above_segments`), 0 if none.
    solver : str
        The NLP back end whose answer the profile is (``"ipopt"``, ``"fatrop"``,
        ``"banded"``, or ``"ipopt (the <name> solver stopped: <why>)"``); ``""`` when no NLP
        was solved (the exact forward-backward profile, a profile read from a file).
    notes : tuple of str
        Remarks for the user (merged segments, fallback, ignored columns).
    allowable_first_mps, allowable_largest_mps : numpy.ndarray, shape (N,) or None
        Per-segment allowable speeds of the model under both semantics (m/s), capped by the
        speed limits, for plots and summaries.
    speed_cap_mps : numpy.ndarray, shape (N,) or None
        Per-segment speed caps min(v_max, speed_limit) (m/s).
    band_lower_mps, band_upper_mps : numpy.ndarray, shape (N,) or None
        The admissible speed band chosen for each segment (m/s), capped by the speed caps:
        both boundary speeds of segment i lie in [band_lower_mps[i], band_upper_mps[i]].
    settings : dict
        What the profile was planned with: vehicle, model, segment_length_m, smoothing,
        max_accel_mps2, max_decel_mps2, max_jerk_mps3, v0_mps, vend_mps, method, band;
        path_tolerance_m and, for a route with x, y, path_tolerance_source (``estimated`` or
        ``given``) and path_noise_m (:attr:`profileopt.terrain.geometry.RouteGeometry.settings`).
        Written into the CSV's first (comment) line and read back by
        :func:`profileopt.io.read_profile`.
    limits : tuple of Limit
        The limits the profile was planned under (empty for a profile read from a file).
    cap_source : numpy.ndarray of int, shape (N,), or None
        For each segment, the index in ``limits`` of the limit whose cap is lowest there.
    band_source : int
        Index in ``limits`` of the limit that gave the speed bands (-1: none).
    curvature_1pm, grade_rad : numpy.ndarray, shape (N+1,), or None
        The path's signed curvature (1/m, left turns positive) and grade (rad, uphill
        positive) at each row; None for a profile read from a file without them.
    binding : numpy.ndarray of str, shape (N+1,), or None
        The limit that holds the speed at each row (:data:`~profileopt.core.binding.BINDING_NAMES`).
    path : SegmentPath or None
        Each segment's turns and slopes, as the limits saw them (None when read from a file).
    roughness : dict or None
        Where the RI came from (:func:`profileopt.core.segments.roughness_source`):
        ``{"source": "measured"}`` or ``{"source": "assumed", "label", "ri", "window_m"}``;
        None when read from a file (the settings' ``roughness`` key then tells).
    """

    s_m: np.ndarray
    speed_mps: np.ndarray
    accel_mps2: np.ndarray
    time_s: np.ndarray
    ri: np.ndarray
    e_max_m: np.ndarray
    force_n: np.ndarray
    force_limit_n: np.ndarray
    status: str = "read"
    success: bool = True
    model: str = DEFAULT_MODEL
    objective: float = float("nan")
    timings_s: dict = dataclasses.field(default_factory=dict)
    iterations: int = 0
    pieces: int = 0
    solver: str = ""
    notes: tuple[str, ...] = ()
    allowable_first_mps: np.ndarray | None = None
    allowable_largest_mps: np.ndarray | None = None
    speed_cap_mps: np.ndarray | None = None
    band_lower_mps: np.ndarray | None = None
    band_upper_mps: np.ndarray | None = None
    settings: dict = dataclasses.field(default_factory=dict)
    limits: tuple = ()
    cap_source: np.ndarray | None = None
    band_source: int = -1
    curvature_1pm: np.ndarray | None = None
    grade_rad: np.ndarray | None = None
    binding: np.ndarray | None = None
    path: "SegmentPath | None" = None
    roughness: dict | None = None

    @property
    def travel_time_s(self) -> float:
        """Time to drive the whole route (s)."""
        return float(self.time_s[-1])

    @property
    def distance_m(self) -> float:
        """Length of the route (m)."""
        return float(self.s_m[-1] - self.s_m[0])

    def columns(self) -> dict[str, np.ndarray]:
        """The CSV columns by name, in order: :data:`PROFILE_COLUMNS`, or only the first
        eight (:data:`BASE_COLUMNS`) for a profile read from a file written without the
        others.

        Returns
        -------
        dict of str to numpy.ndarray, each shape (N+1,)
        """
        names = PROFILE_COLUMNS if self.binding is not None else BASE_COLUMNS
        return {name: getattr(self, name) for name in names}

    def jerk_mps3(self) -> np.ndarray:
        """Jerk v da/ds at the interior boundaries (m/s^3), shape (N-1,).

        Returns
        -------
        numpy.ndarray
        """
        ds = np.diff(self.s_m)
        a = self.accel_mps2[:-1]
        return boundary_jerk_mps3(self.speed_mps[1:-1], a[:-1], a[1:], ds[:-1], ds[1:])

    def _limits_off(self) -> list[str]:
        """The limits of turns and hills not in :attr:`limits` (their vehicle keys missing)."""
        if not self.limits:
            return []
        names = {limit.name for limit in self.limits}
        wanted = (("lateral", "lateral and rollover (max_lateral_accel_mps2, track_width_m, cg_height_m)"),
                  ("friction", "friction (friction_coefficient)"), ("power", "power (mass_kg, max_power_w)"))
        off = [text for name, text in wanted if name not in names]
        if any(getattr(limit, "grade", True) is False for limit in self.limits):
            off.append("grade in the acceleration bounds (any of the keys above)")
        return off

    def _roughness(self) -> dict:
        """Where the RI came from: the planner's account, or what a read file's settings say."""
        if self.roughness is not None:
            return dict(self.roughness)
        label = self.settings.get("roughness")
        if label is None:
            return {"source": "measured"}
        return {"source": "assumed", "label": str(label).replace("_", " ")}

    def summary(self) -> dict:
        """A short account of a planned profile, for people and for ``--json``.

        Returns
        -------
        dict
            ``distance_m``, ``travel_time_s``, ``mean_speed_mps``, ``segments``, ``model``;
            ``slowest_segment`` (index, ``s_start_m``, ``s_end_m``, ``top_speed_mps``, ``ri``
            and ``reason``: which limit holds the vehicle back there; of the segments whose
            top speed is held by a limit, the slowest, so not the run-up from rest);
            ``margins`` (from each of :attr:`limits`: the largest ratio of each constrained
            quantity to its limit, and where: force, lateral, friction, accel, decel, power,
            jerk; a ratio above 1 by no more than the check's tolerance
            :data:`~profileopt.defaults.LIMIT_RTOL` reads 1, at the limit: :func:`at_limit`);
            ``binding`` (the share of the distance each limit holds the speed, 0 to
            1, from the ``binding`` column); ``limits_off`` (the limits of turns and hills
            the vehicle file leaves off); ``roughness`` (``source``: ``"measured"`` or
            ``"assumed"``, then its ``label``, the ``ri`` every window got and ``window_m``;
            for a profile read from a file, the label its settings record); for a route with
            x, y, ``path`` (:meth:`path_summary`: the path tolerance, where it came from, the
            noise estimated, the turns sharper than the turning circle); ``solver``
            (status, success, backend: the NLP back end or null, iterations, pieces, time_s); ``notes`` (the plan's, then the
            path's: each turn sharper than the vehicle's turning circle, each reversal).
            Plain Python numbers only.
        """
        n = self.s_m.size - 1
        v = self.speed_mps
        top = np.maximum(v[:-1], v[1:])
        accel = self.accel_mps2[:-1]
        tol = 1e-6 * max(float(v.max()), 1.0)
        # The slowest segment that a limit holds back (its speed reaches its band's upper edge);
        # the run-up from rest and the final braking are slow too, but tell nothing.
        band_upper = self.band_upper_mps
        held = np.flatnonzero(top >= band_upper - tol) if band_upper is not None else np.empty(0, dtype=int)
        i = int(held[np.argmin(top[held])]) if held.size else int(np.argmin(top))
        a_max = float(self.settings.get("max_accel_mps2", math.nan))
        d_max = float(self.settings.get("max_decel_mps2", math.nan))
        reason = "the acceleration, jerk and smoothing terms"
        if band_upper is not None and top[i] >= band_upper[i] - tol:
            cap = self.speed_cap_mps[i] if self.speed_cap_mps is not None else math.inf
            if band_upper[i] >= cap - tol and self.cap_source is not None:
                reason = self.limits[int(self.cap_source[i])].cap_reason(self, i)
            elif self.band_source >= 0:
                reason = self.limits[self.band_source].band_reason(self, i)
        elif math.isfinite(a_max) and accel[i] >= a_max * (1 - 1e-6):
            reason = "accelerating at max_accel_mps2 (from a slower point before it)"
        elif math.isfinite(d_max) and -accel[i] >= d_max * (1 - 1e-6):
            reason = "braking at max_decel_mps2 (for a slower point after it)"
        margins: dict[str, dict] = {}
        for limit in self.limits:
            margins.update({key: at_limit(margin) for key, margin in limit.margins(self).items()})
        path = self.path_summary()
        path_notes = []
        if self.path is not None and self.path.turns:
            limited = any(limit.name == "lateral" for limit in self.limits)
            path_notes = [note for note in turn_notes(self.path.turns, self.path.min_turn_radius_m,
                                                      turns_limited=limited) if note not in self.notes]
        return {
            "distance_m": self.distance_m,
            "travel_time_s": self.travel_time_s,
            "mean_speed_mps": self.distance_m / self.travel_time_s if self.travel_time_s > 0 else 0.0,
            "segments": n,
            "model": self.model,
            "slowest_segment": {
                "index": i, "s_start_m": float(self.s_m[i]), "s_end_m": float(self.s_m[i + 1]),
                "top_speed_mps": float(top[i]), "ri": float(self.ri[i]), "reason": reason,
            },
            "margins": margins,
            "binding": binding_shares(self.binding, self.s_m) if self.binding is not None else {},
            "limits_off": self._limits_off(),
            "roughness": self._roughness(),
            **({"path": path} if path is not None else {}),
            "solver": {
                "status": self.status, "success": self.success, "backend": self.solver or None,
                "iterations": self.iterations, "pieces": self.pieces,
                "time_s": float(self.timings_s.get("total", math.nan)),
            },
            "notes": [*self.notes, *path_notes],
        }

    def path_summary(self) -> dict | None:
        """The path tolerance the curvature was found with, and why, for a route with x, y.

        Returns
        -------
        dict or None
            ``tolerance_m`` (m), ``source`` (``"estimated"`` from the route's x, y, or
            ``"given"``), ``noise_m`` (the horizontal noise estimated, m) and, for a planned
            profile, ``points`` (how many measured points it was estimated from),
            ``max_deviation_m`` (how far the smoothed path strays from the samples, m),
            ``min_turn_radius_m`` (the vehicle's turning circle, m, or None) and
            ``sharp_turns`` (how many stretches are sharper than it, or reverse). None for a
            route without x, y (a straight path) or a profile file that records no source.
        """
        if self.path is not None:
            if not self.path.tolerance_source:
                return None
            return {"tolerance_m": float(self.path.tolerance_m), "source": self.path.tolerance_source,
                    "noise_m": float(self.path.noise_m), "points": int(self.path.noise_points),
                    "max_deviation_m": float(self.path.max_deviation_m),
                    "min_turn_radius_m": self.path.min_turn_radius_m, "sharp_turns": len(self.path.turns)}
        source = self.settings.get("path_tolerance_source")
        if source is None:
            return None
        try:
            tolerance, noise = float(self.settings["path_tolerance_m"]), float(self.settings.get("path_noise_m", "nan"))
        except (KeyError, TypeError, ValueError):
            return None
        return {"tolerance_m": tolerance, "source": str(source), "noise_m": noise}
