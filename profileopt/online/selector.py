"""Choose the speed every cycle from the terrain sensed ahead: the online speed selector.

The offline planner (:func:`profileopt.plan`) knows the whole route. A vehicle driving into
unknown terrain knows only what its sensors have measured ahead (:mod:`.sensed`), and must
never go faster than it could if the terrain beyond were as bad as assumed. Each cycle the
:class:`SpeedSelector`

1. takes the newly sensed samples and, for every segment whose neighbourhood is now measured
   (the roughness windows, the grade's fit and the steps' ramps that decide its speeds:
   :attr:`SpeedSelector.margin_m`), computes once and for all the same speed bands, caps and
   acceleration bounds the offline planner computes (:mod:`profileopt.planning.limits`: force
   windows, steps, speed limits and top speed, turns, friction, grades, drive power) on the
   measured samples around it, in two stages over two cycles so that no cycle does it all (the
   force's first band from a table built once, :mod:`.band_table`), and where a step's cap
   binds, rounds of a simulation gate (below);
   of the force's bands it keeps the first, [0, v_first] (the paper-notes' "Which root": safe
   for a vehicle that may have to slow down anywhere, as one that sees only so far must), and,
   where that binds, the highest band above it, for a short feature (below);
2. appends, past the last such segment (the *planning edge*), the terrain not yet measured as
   the ``unseen`` assumption: a roughness class (or an RI) whose first admissible band,
   [0, v_unseen], is the speed allowed there;
3. computes the *envelope* over that horizon: the greatest speed at every point from which
   every later cap, the edge's v_unseen included, can still be met braking within the
   deceleration bounds (:func:`profileopt.planning.bands.braking_profile`, the backward pass
   of the offline planner's forward-backward profile); and, for the report, the
   forward-backward plan from the current speed (:attr:`Command.horizon_speed_mps`);
4. commands the fastest acceleration for this cycle that changes by at most the jerk bound,
   keeps the acceleration and drive power bounds, and keeps the vehicle under the envelope,
   now and while braking with the jerk bound afterwards (:mod:`.tracking`).

Safety by construction (docs: guide/online.md). Under the envelope every speed keeps every
cap of the measured segments, and at the planning edge it is at most v_unseen, from which the
vehicle can keep to any terrain no worse than assumed. The state after each command is
*safe* (a jerk-limited braking manoeuvre from it stays under the envelope), so the next
cycle has a command too, whenever the newly measured terrain is no worse than assumed (its
caps are at least v_unseen): the vehicle is never faster than on the offline plan of a route
whose unmeasured part is exactly as bad as assumed (the plan on the first band; on every band
where a feature is crossed in its upper band, below). Where the terrain turns out worse (a kerb
past the sensing range that the assumption does not cover, seen too late), the selector
brakes harder than the jerk bound, or as hard as the vehicle may, and says so
(:attr:`Command.emergency`).

The upper band. A resonant vehicle's speeds on rough ground may be [0, v1] and [lo, hi] above
resonance, every speed between over the limit: the offline plan crosses a kerb's roughness
windows at speed in [lo, hi], and a vehicle there must not slow down below lo before the
rough ground ends. The selector does so for a *feature*, a run of measured segments whose
upper band (:meth:`SpeedSelector._upper_band`, from a table built once, as the first band's)
starts above their first band's top, only when what is measured proves it can: (a) the
feature ends before the planning edge;
(b) the envelope with the feature capped at hi (the other caps, and the unseen tail, as
before) is at least lo at every boundary from the vehicle to the feature, and lo plus the
*tracking lag* at the feature's boundaries; (c) the vehicle is already at lo plus that lag.
The tracking lag is how far the commanded speed can fall below the envelope: the tracker
rides a braking curve to its end, then takes its deceleration d back to 0 at the jerk bound J,
losing d^2 / (2 J) (1.6 m/s for the resonant atv at 4 m/s^2: it stopped dead at a kerb's first
band), so on the feature and a lead-in before it the envelope brakes at a lower d_f, for which
d_f^2 / (2 J) + d_f dt is half the band's narrowest width; at the feature's end, where the
braking for what follows begins, the lag is d^2 / (8 J) + d dt
(:meth:`SpeedSelector._tracking_lag_mps`). The lead-in is long enough for the vehicle to come
off the approach's harder braking, entering the feature behind the curve by what that costs
(when the band is wide enough), or to come off it and catch up; when the vehicle is past its
start already, it runs from the vehicle, judged by the vehicle's own speed and braking
(:meth:`SpeedSelector._upper_band_lead_in`). The choice is made
only in a cycle whose command keeps the jerk bound under the new envelope. It is sticky once
the vehicle is on the lead-in; before that, a choice whose (b) fails is taken back when the
vehicle can keep the jerk bound under the first band. (b) keeps holding while the terrain
that comes into view is no worse than assumed, because the envelope never comes down where the
vehicle can be (above); if it is worse, the emergency path brakes as for any surprise, and a
speed below a chosen band at a cycle's start is said (:attr:`Command.note`). On
``examples/routes/curb.csv`` (resonant atv, 50 m of sensing, class B assumed) it drives
74.8 s, 1.089 times the offline plan's 68.6 s, where the first band alone took 105.4 s
(1.535); the exact simulation finds no window over the limit (at most 0.95 of it). Where the
step limit sees a ramp, the upper band is driven in the simulation gate (below) at both its
edges, each moved into the band round by round where it goes over the limit less
:data:`GATE_FORCE_MARGIN` (the top down, the bottom up), the band dropped if that empties it
(a block: the landing off its trailing edge); speeds between the edges are not simulated, the
drive's simulation judges.

The offline planner's simulation gate (:mod:`profileopt.planning.gate`), in part: where a step's
cap binds on a new stretch (its bound assumes the suspension at rest), the stretch is driven
in the exact simulation at its caps, from rest at the start of the margin before it, and the
caps are lowered where the force goes over the limit less :data:`GATE_FORCE_MARGIN`, one
round per cycle (:meth:`SpeedSelector._gate_round`). The simulation of the caps is not that of
the speeds the vehicle will drive (those depend on terrain not yet measured, and at a ramp the
force depends on the speed history, not on the crossing speed alone: hence the margin), so
``profileopt drive`` simulates the driven profile and reports every roughness window.
"""

from __future__ import annotations

import dataclasses
import math
import time
from typing import TYPE_CHECKING, Iterator

import numpy as np
from numpy.typing import ArrayLike
from scipy.ndimage import minimum_filter1d

from ..core.path import segment_path
from ..core.segments import route_roughness_windows, segments_at
from ..core.stations import segment_samples
from ..defaults import (
    DEFAULT_MODEL,
    DEFAULT_PATH_TOLERANCE_M,
    DEFAULT_ROUGHNESS_WINDOW_M,
    MAX_ROUGHNESS_SPACING_M,
    MODEL_KEYS,
)
from ..errors import InputError
from ..physics.motion import plans_on_grades, power_accel_mps2, tyre_accel_mps2
from ..physics.speeds import speed_bands
from ..physics.steps import MAX_RAMP_M, TREND_HALF_WIDTH_M
from ..planning.bands import DrivePower, boundary_bounds, braking_profile, greatest_profile
from ..planning.gate import GATE_MARGIN, MAX_GATE_ROUNDS, GateCheck, check_speeds, gate_applies, gate_caps
from ..planning.limits import ForceLimit, PlanContext, default_limits
from ..terrain.assumed import unseen_roughness
from ..terrain.geometry import route_geometry
from .band_table import first_band_table
from .sensed import SensedTerrain
from .tracking import MIN_BRAKING_MPS2, braking_margin_m, cycle_end, jerk_limited_step

if TYPE_CHECKING:
    from ..core.route import Route
    from ..core.vehicle import Vehicle

__all__ = ["SpeedSelector", "Command", "unseen_speed_mps", "DEFAULT_SENSOR_RANGE_M", "DEFAULT_CYCLE_S", "MAX_CYCLE_S",
           "CYCLE_WHY", "DEFAULT_ONLINE_SEGMENT_LENGTH_M", "DEFAULT_UNSEEN", "DEFAULT_UNSEEN_DESCENT",
           "GATE_FORCE_MARGIN"]

#: Sensing range (m) when none is given: what a vehicle LiDAR resolves at wheel scale.
DEFAULT_SENSOR_RANGE_M = 50.0
#: Control cycle (s) when none is given.
DEFAULT_CYCLE_S = 0.1
#: The longest control cycle (s) the selector takes. Each command holds one acceleration for a
#: whole cycle, so a longer cycle is a coarser control: at the top speed the vehicle covers
#: max_speed_mps * cycle_s between two looks at the terrain (20 m at 1 s for the bundled
#: vehicles, 40 % of the default sensing range). The bundled courses drive with cycles up to 1 s
#: (tests/online/test_drive.py).
MAX_CYCLE_S = 1.0
#: Why :data:`MAX_CYCLE_S`, for the messages that refuse a longer cycle.
CYCLE_WHY = ("each command holds one acceleration for a whole cycle, over which the vehicle may cover "
             "20 m; a speed controller runs every 0.02-0.5 s")
#: Share of the force limit the online simulation gate keeps free (dimensionless): it drives a
#: new stretch at its caps (or an upper band's edges) from rest, but the vehicle crosses it
#: later along a speed history that depends on terrain not yet measured, and at a ramp the
#: transmitted force depends on that history, not on the crossing speed alone. Measured (a
#: 6 cm drop on a -10 % grade with a few mm of roughness, resonant atv, crossed at 5.37 m/s):
#: 0.991 of the limit at constant speed, 0.982-1.013 through it at constant accelerations of
#: -2 to +1 m/s^2, 1.026 along the selector's jerk-limited commands, where the gate's run
#: decelerating into it gave 0.978. The offline gate simulates the plan itself and keeps none.
GATE_FORCE_MARGIN = 0.05
#: Least share an upper band's top is lowered by in one round of the gate (dimensionless), and
#: its bottom raised by (its inverse). A round moves the edge by the square of the force's
#: excess over the limit less the margin (the force on a ramp grows less than in proportion to
#: the speed: 2.5 % for 3.4 % of speed on the drop of GATE_FORCE_MARGIN's measurement, so a
#: round in proportion fell short and took four), and by at least 2 %, so that the rounds
#: end; all of an edge's rounds run in one cycle (a cycle's wait is latency at the planning edge).
GATE_SHRINK_UPPER = 0.98
#: Segment length (m) of the online selector: fine enough that a step's or a window's cap holds
#: only a metre of route, coarse enough that a 100 m horizon is a hundred segments.
DEFAULT_ONLINE_SEGMENT_LENGTH_M = 1.0
#: The shortest segment (m): the widest gap between samples of measured terrain, so that every
#: segment holds samples.
MIN_ONLINE_SEGMENT_LENGTH_M = MAX_ROUGHNESS_SPACING_M
#: The most segments a horizon may hold (sensor_range_m / segment_length_m, and what a cycle
#: plans over): a bound on the time and memory of a cycle.
MAX_HORIZON_SEGMENTS = 10_000
#: The most segments one chunk of work computes: samples given far ahead at once are planned a
#: bounded piece at a time.
MAX_CHUNK_SEGMENTS = 200
#: How much newly measured route (m) is planned at once. Each chunk has a fixed cost (about
#: 2 ms for each of its two stages, one per cycle) and its wait is latency: the planning edge
#: lags the sensors by up to a chunk and a cycle. On the trail at 50 m of sensing (atv, the
#: route's class assumed) chunks of 5 m drove 1.102 times the offline time, of 3 m 1.092, of
#: 2 m the same with a higher median compute per cycle (4.2 ms against 3.4 ms, a loaded machine).
CHUNK_M = 3.0
#: Where a segment's higher cap begins after the boundary's lower one (m): the envelope's
#: step up, a knot this far after the boundary.
JUMP_M = 1e-6
#: The steepest descent (rise over run) assumed on unseen ground when none is given: 5 %.
DEFAULT_UNSEEN_DESCENT = 0.05
#: The assumption for terrain not yet measured when none is given.
DEFAULT_UNSEEN = "worst"


def unseen_speed_mps(unseen: str | float, vehicle: "Vehicle", *, model: str = DEFAULT_MODEL,
                     roughness_window_m: float = DEFAULT_ROUGHNESS_WINDOW_M) -> float:
    """The speed (m/s) allowed on terrain not yet measured: the top of the first admissible band
    for every RI up to the assumed one (:func:`profileopt.physics.speeds.speed_bands` with
    ``ri_min=0``), so that it holds on any terrain no rougher than assumed and the vehicle may
    slow down anywhere on it.

    Parameters
    ----------
    unseen : str or float
        ``"worst"``, an ISO 8608 class A-H or an RI
        (:func:`profileopt.terrain.assumed.unseen_roughness`).
    vehicle : Vehicle
        The quarter car, its force limit and top speed.
    model : str, default ``"sbem_tf"``
        Force model key, one of the paper's four.
    roughness_window_m : float, default 5
        The roughness window W (m) a class's RI is computed over.

    Returns
    -------
    float
        Speed (m/s), in [0, max_speed_mps].
    """
    ri = unseen_roughness(unseen).ri_for(clearance_m=vehicle.ground_clearance_m, window_m=roughness_window_m)
    bands = speed_bands(np.array([ri]), vehicle, model=model, ri_min=np.array([0.0]))
    return float(bands.first()[0])


@dataclasses.dataclass(frozen=True)
class Command:
    """What the selector tells the vehicle for one cycle.

    Attributes
    ----------
    speed_mps : float
        The speed to be at one cycle from now (m/s).
    accel_mps2 : float
        The acceleration to hold over this cycle (m/s^2).
    position_next_m : float
        Where the vehicle is one cycle from now holding it (m).
    horizon_s_m, horizon_speed_mps : numpy.ndarray, shape (K,)
        The plan over the measured horizon: positions from the current one to the planning edge
        (m), and the speeds there (m/s) of the fastest profile from the current speed that keeps
        every limit but the jerk bound (the forward-backward pass), ending at most at
        :attr:`unseen_speed_mps`.
    edge_m : float
        The planning edge (m): where measured, planned terrain ends and the ``unseen``
        assumption begins (the route's end when it is measured to there).
    edge_speed_mps : float
        The plan's speed at the edge (m/s), at most :attr:`unseen_speed_mps`.
    unseen_speed_mps : float
        The speed allowed on unseen terrain (m/s).
    emergency : bool
        True when the terrain came into view worse than assumed, too late for the jerk bound
        (the command brakes harder) or for any limit-keeping profile at all (the command is
        the hardest braking the vehicle may do).
    note : str
        Why, when ``emergency``; else empty.
    compute_s : float
        Wall time of this cycle's :meth:`SpeedSelector.update` (s).
    """

    speed_mps: float
    accel_mps2: float
    position_next_m: float
    horizon_s_m: np.ndarray
    horizon_speed_mps: np.ndarray
    edge_m: float
    edge_speed_mps: float
    unseen_speed_mps: float
    emergency: bool = False
    note: str = ""
    compute_s: float = 0.0


class _Grown:
    """Per-segment arrays that grow at the end and are forgotten at the start."""

    def __init__(self) -> None:
        self.offset = 0  # global index of row 0
        self.top = np.empty(0)  # the first band's top, capped (m/s)
        self.decel = np.empty(0)
        self.accel = np.empty(0)
        self.grade_hi = np.empty(0)
        self.power_binds = np.empty(0, dtype=bool)
        #: The force's upper band (m/s) above the first band's gap, capped by the other limits
        #: (module docstring, "The upper band"); NaN where there is none.
        self.upper_lo = np.empty(0)
        self.upper_hi = np.empty(0)
        #: Whether the upper band was chosen for the segment (sticky, :meth:`SpeedSelector.update`).
        self.chosen = np.empty(0, dtype=bool)
        #: The deceleration (m/s^2) the envelope assumes on the segment when it is in a chosen
        #: feature or its lead-in, so that the vehicle tracks it closely (inf: the segment's own).
        self.envelope_decel = np.empty(0)
        #: How far (m/s) the vehicle may enter a chosen feature below the envelope, for the
        #: short lead-in (:meth:`SpeedSelector._upper_band_lead_in`); 0 elsewhere.
        self.entry_lag = np.empty(0)

    @property
    def end(self) -> int:
        return self.offset + self.top.size

    def append(self, top: np.ndarray, decel: np.ndarray, accel: np.ndarray, grade_hi: np.ndarray,
               power_binds: np.ndarray, upper_lo: np.ndarray | None = None,
               upper_hi: np.ndarray | None = None) -> None:
        n = top.size
        self.top = np.concatenate([self.top, top])
        self.decel = np.concatenate([self.decel, decel])
        self.accel = np.concatenate([self.accel, accel])
        self.grade_hi = np.concatenate([self.grade_hi, grade_hi])
        self.power_binds = np.concatenate([self.power_binds, power_binds])
        self.upper_lo = np.concatenate([self.upper_lo, np.full(n, np.nan) if upper_lo is None else upper_lo])
        self.upper_hi = np.concatenate([self.upper_hi, np.full(n, np.nan) if upper_hi is None else upper_hi])
        self.chosen = np.concatenate([self.chosen, np.zeros(n, dtype=bool)])
        self.envelope_decel = np.concatenate([self.envelope_decel, np.full(n, np.inf)])
        self.entry_lag = np.concatenate([self.entry_lag, np.zeros(n)])

    def forget_before(self, index: int) -> None:
        drop = min(max(index - self.offset, 0), self.top.size)
        if drop:
            self.top, self.decel, self.accel = self.top[drop:], self.decel[drop:], self.accel[drop:]
            self.grade_hi, self.power_binds = self.grade_hi[drop:], self.power_binds[drop:]
            self.upper_lo, self.upper_hi = self.upper_lo[drop:], self.upper_hi[drop:]
            self.chosen, self.envelope_decel = self.chosen[drop:], self.envelope_decel[drop:]
            self.entry_lag = self.entry_lag[drop:]
            self.offset += drop


def _boundary_b(top_b: np.ndarray, *, end_b: float) -> np.ndarray:
    """Squared speed allowed at each boundary (m^2/s^2), shape (N+1,): the lower of the caps
    of the segments either side (``top_b``, shape (N,)); at the last, also ``end_b``."""
    return np.concatenate([[top_b[0]], np.minimum(top_b[:-1], top_b[1:]), [min(top_b[-1], end_b)]])


def _envelope(where: np.ndarray, top_b: np.ndarray, braking: np.ndarray, decel: np.ndarray
              ) -> tuple[np.ndarray, np.ndarray]:
    """The envelope as knots and b = v^2 there, piecewise linear in s: at each boundary the
    braking profile; inside segment i the least of its cap top_b[i] and the braking line from
    the next boundary, braking[i + 1] + 2 d_i (s_{i+1} - s), with a knot where they cross and
    one :data:`JUMP_M` after the boundary (where a higher cap begins)."""
    length = np.diff(where)
    slope = 2.0 * np.maximum(decel, 1e-300)
    after = np.minimum(top_b, braking[1:] + slope * length)  # just after each segment's start
    cross = where[1:] - (top_b - braking[1:]) / slope
    inside = (cross > where[:-1] + JUMP_M) & (cross < where[1:])
    room = length > 2.0 * JUMP_M
    knots = np.concatenate([where, where[:-1][room] + JUMP_M, cross[inside]])
    values = np.concatenate([braking, after[room], top_b[inside]])
    order = np.argsort(knots, kind="stable")
    return knots[order], values[order]


def _piece_values(knots: np.ndarray, where: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Per piece between ``knots``, the value of the segment (between ``where``) it lies in."""
    mid = 0.5 * (knots[:-1] + knots[1:])
    return values[np.clip(np.searchsorted(where, mid, side="right") - 1, 0, values.size - 1)]


def _features(upper_lo: np.ndarray, top: np.ndarray, final: np.ndarray) -> list[tuple[int, int]]:
    """The *features* of a horizon (module docstring, "The upper band"): maximal runs
    [i0, i1) of pieces of final segments with an upper band whose lower edge is above the
    first band's top ``top``, each as (i0, i1)."""
    inside = final & np.isfinite(upper_lo) & (top < np.where(np.isfinite(upper_lo), upper_lo, np.inf))
    if not np.any(inside):
        return []
    change = np.diff(np.concatenate([[0], inside.astype(np.int8), [0]]))
    return list(zip(np.flatnonzero(change == 1).tolist(), np.flatnonzero(change == -1).tolist()))


def _sliding_min(values: np.ndarray, half_width: int) -> np.ndarray:
    """The least of ``values[i - half_width : i + half_width + 1]`` for each i, shape (N,)."""
    if values.size <= 1 or half_width <= 0:
        return values
    return minimum_filter1d(values, size=2 * half_width + 1, mode="nearest")


class SpeedSelector:
    """The online speed selector (module docstring): sense, then update, every cycle.

    Parameters
    ----------
    vehicle : Vehicle
        The vehicle: quarter car, force limits, top speed, acceleration bounds (and turns,
        friction and power where its file gives them).
    sensor_range_m : float, default :data:`DEFAULT_SENSOR_RANGE_M` (50)
        How far ahead of the vehicle the sensors measure (m), > 0: only for the
        :attr:`margin_m` check and messages; what counts is what :meth:`sense` is given.
    unseen : str or float, default ``"worst"``
        The assumption for terrain not yet measured: ``"worst"`` (ISO 8608 class H, the
        roughest), a class A-H, or an RI (:func:`unseen_speed_mps`).
    model : str, default ``"sbem_tf"``
        Force model, one of the paper's four (the ``dynamic`` model needs the whole route).
    segment_length_m : float, default :data:`DEFAULT_ONLINE_SEGMENT_LENGTH_M` (1)
        Planning resolution (m), > 0.
    roughness_window_m : float, default 5
        Roughness window W (m), as :func:`profileopt.plan`'s.
    path_tolerance_m : float or None, default None
        As :func:`profileopt.plan`'s, for the turns of x, y samples (None: estimated on each
        measured stretch).
    start_m : float, default 0
        Where the path starts (m): segment boundaries are at ``start_m + k segment_length_m``.
    end_m : float, optional
        Where the path ends (m), if known: the plan stops there at ``vend_mps`` once it is
        measured. None: it goes on.
    vend_mps : float, default 0
        Speed at ``end_m`` (m/s).
    cycle_s : float, default :data:`DEFAULT_CYCLE_S` (0.1)
        The control cycle (s): each command holds one acceleration for a cycle; at most
        :data:`MAX_CYCLE_S` (1 s).
    max_jerk_mps3 : float, optional
        Jerk bound (m/s^3): the command's acceleration changes by at most this times
        ``cycle_s`` per cycle (:mod:`.tracking`); None: the vehicle's; inf: none.
    unseen_descent : float, default :data:`DEFAULT_UNSEEN_DESCENT` (0.05)
        The steepest descent assumed on unseen ground (rise over run), for a vehicle that
        plans on grades: the braking it allows there.

    Raises
    ------
    InputError
        A bad option (the message names it).
    """

    def __init__(self, vehicle: "Vehicle", *, sensor_range_m: float = DEFAULT_SENSOR_RANGE_M,
                 unseen: str | float = DEFAULT_UNSEEN, model: str = DEFAULT_MODEL,
                 segment_length_m: float = DEFAULT_ONLINE_SEGMENT_LENGTH_M,
                 roughness_window_m: float = DEFAULT_ROUGHNESS_WINDOW_M,
                 path_tolerance_m: float | None = DEFAULT_PATH_TOLERANCE_M, start_m: float = 0.0,
                 end_m: float | None = None, vend_mps: float = 0.0, cycle_s: float = DEFAULT_CYCLE_S,
                 max_jerk_mps3: float | None = None, unseen_descent: float = DEFAULT_UNSEEN_DESCENT) -> None:
        from ..core.vehicle import require_vehicle

        vehicle = require_vehicle(vehicle, "SpeedSelector")
        if model not in MODEL_KEYS:
            raise InputError(f"model = {model!r}: the online selector takes one of {', '.join(MODEL_KEYS)} (the "
                             "dynamic model simulates the whole route, which is not known online)")
        for name, value in (("sensor_range_m", sensor_range_m), ("segment_length_m", segment_length_m),
                            ("roughness_window_m", roughness_window_m), ("cycle_s", cycle_s)):
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not (math.isfinite(value)
                                                                                        and value > 0):
                raise InputError(f"{name} = {value!r}: must be a finite number > 0")
        if cycle_s > MAX_CYCLE_S:
            raise InputError(f"cycle_s = {cycle_s!r}: must be at most {MAX_CYCLE_S:g} s ({CYCLE_WHY})")
        if segment_length_m < MIN_ONLINE_SEGMENT_LENGTH_M or sensor_range_m / segment_length_m > MAX_HORIZON_SEGMENTS:
            raise InputError(f"segment_length_m = {segment_length_m!r}: must be at least "
                             f"{MIN_ONLINE_SEGMENT_LENGTH_M:g} m (the widest gap between measured samples) and at "
                             f"least sensor_range_m / {MAX_HORIZON_SEGMENTS} = "
                             f"{sensor_range_m / MAX_HORIZON_SEGMENTS:.3g} m")
        if not math.isfinite(start_m):
            raise InputError(f"start_m = {start_m!r}: must be a finite position (m)")
        if end_m is not None and not (math.isfinite(end_m) and end_m > start_m):
            raise InputError(f"end_m = {end_m!r}: must be a finite position (m) after start_m = {start_m!r}")
        if not (math.isfinite(vend_mps) and 0.0 <= vend_mps <= vehicle.max_speed_mps):
            raise InputError(f"vend_mps = {vend_mps!r}: must be a speed from 0 to the vehicle's top speed "
                             f"{vehicle.max_speed_mps:g} m/s")
        if path_tolerance_m is not None and (isinstance(path_tolerance_m, bool) or not isinstance(
                path_tolerance_m, (int, float)) or not (math.isfinite(path_tolerance_m) and path_tolerance_m > 0)):
            raise InputError(f"path_tolerance_m = {path_tolerance_m!r}: must be a finite number > 0 (m), or None to "
                             "estimate it")
        self.vehicle = vehicle
        self.model = model
        self.sensor_range_m = float(sensor_range_m)
        self.segment_length_m = float(segment_length_m)
        self.roughness_window_m = float(roughness_window_m)
        self.path_tolerance_m = path_tolerance_m
        self.start_m = float(start_m)
        self.end_m = None if end_m is None else float(end_m)
        self.vend_mps = float(vend_mps)
        self.cycle_s = float(cycle_s)
        jerk = vehicle.max_jerk_mps3 if max_jerk_mps3 is None else max_jerk_mps3
        if isinstance(jerk, bool) or not isinstance(jerk, (int, float)) or math.isnan(jerk) or not jerk > 0:
            raise InputError(f"max_jerk_mps3 = {max_jerk_mps3!r}: must be a number > 0 (m/s^3; inf: no bound)")
        self.max_jerk_mps3 = float(jerk)
        if isinstance(unseen_descent, bool) or not isinstance(unseen_descent, (int, float)) or not (
                0.0 <= unseen_descent <= 1.0):
            raise InputError(f"unseen_descent = {unseen_descent!r}: must be a grade from 0 to 1 (rise over run, "
                             "e.g. 0.1 for 10 %)")
        self.unseen_descent = float(unseen_descent)
        #: How much measured terrain (m) a segment needs on either side before its speeds are
        #: final: the longer of a roughness window (the windows that share a point with it; the
        #: grade's fit, centred, over two) and the ramp and trend a step's cap looks at
        #: (tests/online/test_selector.py: equal to the offline planner's on kerbs and washboard,
        #: and not with 5 m).
        self.margin_m = max(self.roughness_window_m, MAX_RAMP_M + TREND_HALF_WIDTH_M)
        if self.margin_m >= self.sensor_range_m:
            raise InputError(f"sensor_range_m = {sensor_range_m:g} m: a segment's speeds need {self.margin_m:g} m of "
                             "measured terrain beyond it (a roughness window and a step's ramp), so no terrain would "
                             f"ever be planned before the route's end; give more than {self.margin_m:g} m of range or "
                             "a shorter roughness window")
        self.unseen = unseen_roughness(unseen)
        self.unseen_speed_mps = unseen_speed_mps(unseen, vehicle, model=model,
                                                 roughness_window_m=self.roughness_window_m)
        self.limits = default_limits(vehicle, model=model, max_jerk_mps3=math.inf)
        self._power = next((limit for limit in self.limits if limit.name == "power"), None)
        self._force = next((limit for limit in self.limits if isinstance(limit, ForceLimit)), None)
        self._band_table = first_band_table(vehicle, model)
        #: Whether new stretches where a step's cap binds are driven in the exact simulation
        #: before their speeds are final (the transmitted force's models: SBEM:TF).
        self._gated = gate_applies(model)
        self.terrain = SensedTerrain(start_m=self.start_m)
        self._segments = _Grown()
        self._tail_decel = float(vehicle.max_decel_mps2)
        if plans_on_grades(vehicle):  # the deceleration bound on the steepest descent assumed
            self._tail_decel = float(tyre_accel_mps2(vehicle.max_decel_mps2, -math.atan(self.unseen_descent)))
        self._last_accel = 0.0
        self._work: Iterator[None] | None = None
        self._driven: list[tuple[float, float]] = []  # positions and speeds on ground not yet planned
        self._late = ""
        self._blind_m = 0.0
        #: Segments whose speeds are computed together (:data:`CHUNK_M`).
        self._chunk = max(int(math.ceil(CHUNK_M / self.segment_length_m - 1e-9)), 1)

    # -- the segment grid ------------------------------------------------------------------
    def _boundary_m(self, k: int | np.ndarray) -> float | np.ndarray:
        """Global boundary k (m); the last one is ``end_m``."""
        b = self.start_m + self.segment_length_m * np.asarray(k, dtype=float)
        if self.end_m is not None:
            b = np.minimum(b, self.end_m)
        return float(b) if np.ndim(b) == 0 else b

    def _segment_count(self) -> int | None:
        """Segments of the whole path (the last one takes what is left), None without an end."""
        if self.end_m is None:
            return None
        n = (self.end_m - self.start_m) / self.segment_length_m
        return max(int(math.ceil(n - 1e-9)), 1)

    def _segment_of(self, position_m: float) -> int:
        k = int(math.floor((position_m - self.start_m) / self.segment_length_m + 1e-12))
        total = self._segment_count()
        if total is not None:
            k = min(k, total - 1)
        return max(k, 0)

    @property
    def blind_m(self) -> float:
        """Length (m) of the gaps in the sensed terrain given up on so far (blind spots, or
        samples sparser than the rule): driven as unseen terrain."""
        return self._blind_m

    @property
    def planned_to_m(self) -> float:
        """The planning edge (m): the end of the last segment whose speeds are final."""
        return float(self._boundary_m(self._segments.end))

    # -- sensing -----------------------------------------------------------------------------
    def sense(self, s_m: ArrayLike, z_m: ArrayLike, *, x_m: ArrayLike | None = None, y_m: ArrayLike | None = None,
              speed_limit_mps: ArrayLike | None = None) -> None:
        """Take newly sensed samples along the path (:meth:`SensedTerrain.add`). Their segments'
        speeds are computed by the next calls of :meth:`update`, one stage per cycle.

        Parameters
        ----------
        s_m, z_m : array_like, shape (K,)
            Distance along the path (m) and elevation (m) of each sample.
        x_m, y_m : array_like, shape (K,), optional
            Their horizontal position (m), for the turns.
        speed_limit_mps : array_like, shape (K,), optional
            Speed limits at the samples (m/s), from a map.
        """
        self.terrain.add(s_m, z_m, x_m=x_m, y_m=y_m, speed_limit_mps=speed_limit_mps)

    def _skip_blind_spot(self, pos: float) -> None:
        """Give up on a gap in the measured terrain that is still open when the vehicle comes
        within :attr:`margin_m` of it (a blind spot): the segments whose neighbourhood meets it
        are unseen (v_unseen), and the measured stretch starts again beyond it."""
        gap = self.terrain.gap_m
        if gap is None or self._work is not None or pos + self.margin_m < gap[0]:
            return
        first = self._segments.end
        upto = int(math.ceil((gap[1] + self.margin_m - self.start_m) / self.segment_length_m - 1e-9))
        total = self._segment_count()
        if total is not None:
            upto = min(upto, total)
        n = max(upto - first, 0)
        if n:
            self._segments.append(np.full(n, self.unseen_speed_mps), np.full(n, self._tail_decel),
                                  np.full(n, float(self.vehicle.max_accel_mps2)), np.zeros(n), np.zeros(n, bool))
        self.terrain.skip_gap()
        self._blind_m += gap[1] - gap[0]

    def _advance(self) -> None:
        """One stage of the work on newly measured segments (:meth:`_chunk_stages`)."""
        if self._work is None:
            self._work = self._chunk_stages()
        try:
            next(self._work)
        except StopIteration:
            self._work = None
        except BaseException:
            self._work = None  # not a dead generator: the next cycle starts the chunk again
            raise

    def _chunk_stages(self) -> Iterator[None]:
        """Final speeds of the segments whose neighbourhood is now measured (module docstring,
        1), in stages, one per cycle (a generator): the measured stretch around them, its
        roughness windows and geometry; the force model's first band and the other limits; where
        a step's cap binds, rounds of the simulation gate (:meth:`_gate_round`)."""
        measured = self.terrain.measured_to_m
        total = self._segment_count()
        at_end = self.end_m is not None and measured >= self.end_m - 1e-9
        if at_end:
            last = total
        else:
            last = int(math.floor((measured - self.margin_m - self.start_m) / self.segment_length_m + 1e-9))
            if total is not None:
                last = min(last, total)
        first = self._segments.end
        if last <= first or (not at_end and last - first < self._chunk):
            return
        if last - first > MAX_CHUNK_SEGMENTS:  # samples far ahead at once: a bounded piece per chunk
            last, at_end = first + MAX_CHUNK_SEGMENTS, False
        lo_m = max(self._boundary_m(first) - self.margin_m, self.terrain.measured_from_m)
        hi_m = measured if at_end else min(measured, self._boundary_m(last) + self.margin_m)
        route = self.terrain.stretch(lo_m, hi_m)
        if route is None:
            return
        # only the new segments: the stretch around them is there for their windows, grades and steps
        bounds = np.asarray(self._boundary_m(np.arange(first, last + 1)), dtype=float)
        slack = self.terrain.max_spacing_m * (1 + 1e-9)  # a first sample within the spacing of the start
        if bounds[0] < route.s_m[0] - slack or bounds[-1] > route.s_m[-1] + 1e-9:
            return  # not measured around them yet (forgotten, or a gap): later
        bounds = np.clip(bounds, route.s_m[0], route.s_m[-1])
        # the limits see segments from the stretch's start to its end (a speed limit's cap, for
        # one, takes the least limit of each segment's samples up to the next segment's first):
        # one segment before the new ones and one after, computed and dropped
        lead = bounds[0] > route.s_m[0] + 1e-9
        trail = bounds[-1] < route.s_m[-1] - 1e-9
        bounds = np.concatenate([[route.s_m[0]] if lead else [], bounds, [route.s_m[-1]] if trail else []])
        new = slice(1 if lead else 0, bounds.size - 1 - (1 if trail else 0))
        starts, stops = segment_samples(route.s_m, bounds)
        windows = route_roughness_windows(route, self.vehicle, window_m=self.roughness_window_m)
        seg = segments_at(bounds, windows, self.vehicle, starts=starts, stops=stops)
        geometry = route_geometry(route, tolerance_m=self.path_tolerance_m,
                                  grade_scale_m=2.0 * self.roughness_window_m,
                                  min_turn_radius_m=self.vehicle.min_turn_radius_m)
        path = segment_path(route, seg, geometry)
        context = PlanContext(route=route, vehicle=self.vehicle, segments=seg, path=path)
        yield
        first_top = np.full(seg.count, np.inf)
        force_top = np.full(seg.count, np.inf)
        for limit in self.limits:
            if limit is self._force:  # the first band's top, from the table (module docstring, 1)
                window_first, window_stop = seg.window_ranges()
                force_top = self._band_table.first_of_sets(seg.windows.ri, window_first, window_stop)
            else:
                got = limit.speed_bands(context)
                if got is not None:
                    first_top = np.minimum(first_top, got.first())
        others_top = first_top  # every limit's first band but the force's
        first_top = np.minimum(first_top, force_top)
        n = seg.count
        cap = np.full(n, np.inf)
        decel, accel = np.full(n, np.inf), np.full(n, np.inf)
        step_cap = np.full(n, np.inf)
        for limit in self.limits:
            limited = limit.speed_cap_mps(context)
            if limited is not None:
                cap = np.minimum(cap, limited)
                if limit.name == "step":
                    step_cap = np.asarray(limited, dtype=float)
            bounds_a = limit.accel_bounds_mps2(context)
            if bounds_a is not None:
                decel, accel = np.minimum(decel, bounds_a[0]), np.minimum(accel, bounds_a[1])
        for limit in self.limits:  # rows the forward-backward pass cannot keep: tighter bounds
            if limit.name == "power":
                continue  # kept exactly by the forward pass (DrivePower)
            inner_b = limit.inner_bounds(context, cap, decel, accel)
            if inner_b is not None:
                cap, decel, accel = inner_b
        top = np.minimum(first_top, cap)
        if self._gated and np.any(step_cap[new] <= top[new] * (1 + 1e-9)) and np.all(top > 0):
            # a step's cap binds: its bound assumes the suspension at rest (the gate, below)
            for round_number in range(1, MAX_GATE_ROUNDS + 1):
                yield
                lowered = self._gate_round(route, bounds, top, new, round_number)
                if lowered is None:
                    break
                top = lowered
        # the force's upper band (module docstring, "The upper band"), where the first band's top
        # binds below every other cap and the top speed
        other_cap = np.minimum(np.minimum(others_top, cap), float(self.vehicle.max_speed_mps))
        upper_lo, upper_hi = np.full(n, np.nan), np.full(n, np.nan)
        needs = np.zeros(n, dtype=bool)
        needs[new] = (force_top[new] < other_cap[new] * (1 - 1e-9)) & (top[new] >= force_top[new] * (1 - 1e-9))
        if self._force is not None and np.any(needs):
            window_first, window_stop = seg.window_ranges()
            upper_lo, upper_hi = self._upper_band(seg.windows.ri, window_first, window_stop, other_cap, top, needs)
            rough = np.isfinite(upper_lo) & np.isfinite(step_cap)
            if self._gated and np.any(rough[new]):
                # where the step limit sees a ramp, the upper band too is driven in the gate's
                # simulation, at each of its edges, each moved into the band where it goes over
                # (the top down, the bottom up: away from resonance), round by round as the gate
                # lowers a cap; if that empties the band, the first band there
                moved = np.zeros(n, dtype=bool)
                moved[new] = rough[new]
                for band_edge, join, sign in ((upper_hi, np.fmin, -1.0), (upper_lo, np.fmax, 1.0)):
                    yield  # one cycle per edge: its rounds within it (a wait is latency at the edge)
                    for round_number in range(1, MAX_GATE_ROUNDS + 2):
                        worst = self._upper_band_worst(route, bounds, top, upper_lo, band_edge, join, new)
                        if worst <= 1.0 - GATE_MARGIN or round_number > MAX_GATE_ROUNDS:
                            break
                        band_edge[moved] *= max(1.0 / GATE_SHRINK_UPPER, (worst / (1.0 - GATE_MARGIN)) ** 2) ** sign
                        if np.any(upper_hi[moved] <= upper_lo[moved]):
                            break
                    if worst > 1.0 - GATE_MARGIN or np.any(upper_hi[moved] <= upper_lo[moved]):
                        upper_lo[new], upper_hi[new] = np.nan, np.nan
                        break
        # the forward pass keeps the power limit step by step (slow) only where it can bind
        binds = self._power is not None and self._power.nlp_rows(context, cap, decel, accel) is not None
        self._segments.append(top[new], decel[new], accel[new], path.grade_hi_rad[new],
                              np.full(new.stop - new.start, binds), upper_lo[new], upper_hi[new])
        self._check_passed(bounds[new.start:new.stop + 1], top[new])

    def _upper_band(self, ri: np.ndarray, window_first: np.ndarray, window_stop: np.ndarray, other_cap: np.ndarray,
                    top: np.ndarray, needs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The force's upper band of each segment that ``needs`` it: edges (lo, hi) in m/s,
        shape (N,) each, NaN where there is none.

        Segment i meets the roughness windows ``ri[window_first[i]:window_stop[i]]``. Each
        window's highest band comes from the band table
        (:meth:`.band_table.FirstBandTable.highest_of_sets`, for the RI range holding the
        window's RI: admissible for every RI of the range; on smooth ground the first, [0, v1]);
        the segment's band is their intersection [largest lo, least hi], capped by
        ``other_cap`` (every other cap and the top speed), when that is not empty and starts
        above ``top`` (the first band's top as the selector has it): an upper band. It is
        admissible for every window, so for the segment, and never wider than the exact bands
        (:meth:`ForceLimit.speed_bands`), which cost 15-50 ms per new stretch of the bundled
        routes with the resonant atv: a cycle's budget three times over. The highest band is
        the fastest; a vehicle that enters it from smooth ground brakes from above into it, so
        the bands between are never driven.

        Parameters
        ----------
        ri : numpy.ndarray, shape (K,)
            The roughness windows' RIs (dimensionless).
        window_first, window_stop : numpy.ndarray of int, shape (N,)
            The windows each segment meets.
        other_cap : numpy.ndarray, shape (N,)
            Every cap but the force's first band, and the top speed (m/s).
        top : numpy.ndarray, shape (N,)
            The segments' caps with the force's first band (m/s).
        needs : numpy.ndarray of bool, shape (N,)
            The segments whose upper band is wanted.

        Returns
        -------
        lo, hi : numpy.ndarray, shape (N,)
            The band's edges (m/s), NaN where there is none.
        """
        rows = np.flatnonzero(needs)
        # rougher than the table: no upper band there (the first band, as before)
        lo, hi = self._band_table.highest_of_sets(ri, window_first[rows], window_stop[rows])
        hi = np.minimum(hi, other_cap[rows])
        ok = np.isfinite(lo) & (hi > lo) & (lo > top[rows])
        upper_lo, upper_hi = np.full(top.size, np.nan), np.full(top.size, np.nan)
        upper_lo[rows[ok]], upper_hi[rows[ok]] = lo[ok], hi[ok]
        return upper_lo, upper_hi

    def _gate_round(self, route: "Route", bounds: np.ndarray, top: np.ndarray, new: slice,
                    round_number: int) -> np.ndarray | None:
        """One round of the simulation gate on a new stretch (module docstring, 1): the exact
        quarter car (:func:`profileopt.physics.simulate.simulate_quarter_car`, the one ``verify``
        uses) driven over the measured stretch at the caps, from rest at its start (the margin
        before the new segments lets it settle); where the transmitted force over the new
        segments goes over the limit less :data:`GATE_FORCE_MARGIN`, their caps are lowered as the
        offline planner's gate lowers them (:func:`profileopt.planning.gate.gate_caps`). None: it
        holds."""
        speed = np.sqrt(_boundary_b(top * top, end_b=math.inf))
        check = self._simulate(route, bounds, speed, new)
        if check.passes:
            return None
        caps = gate_caps(check, self.vehicle, round_number)
        lowered = top.copy()
        for start_m, end_m, cap_mps in zip(caps.start_m, caps.end_m, caps.cap_mps):
            meets = (bounds[1:] > start_m) & (bounds[:-1] < end_m)
            meets[:new.start] = False
            meets[new.stop:] = False
            lowered[meets] = np.minimum(lowered[meets], cap_mps)
        return lowered if np.any(lowered < top) else None

    def _simulate(self, route: "Route", bounds: np.ndarray, speed_mps: np.ndarray, new: slice) -> GateCheck:
        """The gate's run: the exact quarter car over the measured stretch at the boundary speeds
        ``speed_mps`` (m/s, shape (N+1,)), from rest at its start, judged over the new segments
        against the limit less :data:`GATE_FORCE_MARGIN`."""
        return check_speeds(route, bounds, speed_mps, self.vehicle, window_m=self.roughness_window_m,
                            force_margin=GATE_FORCE_MARGIN, judged_m=(float(bounds[new.start]), float(bounds[new.stop])))

    def _upper_band_worst(self, route: "Route", bounds: np.ndarray, top: np.ndarray, upper_lo: np.ndarray,
                          band_edge: np.ndarray, join: np.ufunc, new: slice) -> float:
        """The largest force over the new segments, as a share of the limit less
        :data:`GATE_FORCE_MARGIN` (dimensionless), when the exact quarter car (as in
        :meth:`_gate_round`) drives them at ``band_edge`` (m/s, shape (N,): an edge of the upper
        band) where they have an upper band, and at their caps ``top`` elsewhere; at a boundary
        between two segments with a band, ``join`` of their edges (``numpy.fmin`` for the top
        edge, ``numpy.fmax`` for the bottom one: the speed there that keeps both bands), and
        between one and a segment without, the band's edge (the vehicle keeps to the band up to
        the feature's ends)."""
        banded = np.isfinite(upper_lo)
        seg_speed = np.where(banded, band_edge, top)
        speed = np.sqrt(_boundary_b(seg_speed * seg_speed, end_b=math.inf))
        left = np.concatenate([[False], banded])
        right = np.concatenate([banded, [False]])
        edge_left = np.concatenate([[np.nan], band_edge])
        edge_right = np.concatenate([band_edge, [np.nan]])
        speed = np.where(left & right, join(edge_left, edge_right),
                         np.where(left, edge_left, np.where(right, edge_right, speed)))
        return self._simulate(route, bounds, speed, new).worst_ratio

    def _check_passed(self, bounds: np.ndarray, top: np.ndarray) -> None:
        """Whether the vehicle already drove faster than the caps of segments just computed
        (terrain worse than assumed, measured too late): then the next command says so."""
        if not self._driven:
            return
        s, v = np.array(self._driven).T
        seg = np.searchsorted(bounds, s, side="right") - 1
        inside = (seg >= 0) & (seg < top.size)
        over = inside & (v > top[np.clip(seg, 0, top.size - 1)] * (1 + 1e-9) + 1e-12)
        if np.any(over):
            k = int(np.flatnonzero(over)[0])
            cap = float(top[seg[k]])
            self._late = (f"the terrain at {s[k]:.6g} m came into view after the vehicle was there at {v[k]:.4g} m/s, "
                          f"above its cap of {cap:.4g} m/s: worse than the unseen assumption "
                          f"({self.unseen.label})")
        self._driven = [(p, w) for p, w in self._driven if p >= bounds[-1]]

    # -- one cycle -----------------------------------------------------------------------------
    def update(self, position_m: float, speed_mps: float, accel_mps2: float | None = None) -> Command:
        """The command for this cycle, from the vehicle's position, speed and acceleration.

        Parameters
        ----------
        position_m : float
            Where the vehicle is along the path (m).
        speed_mps : float
            Its speed (m/s), >= 0.
        accel_mps2 : float, optional
            The acceleration it applies now (m/s^2), from which the next may differ by at most
            the jerk bound times the cycle; None: the last command's (0 at first).

        Returns
        -------
        Command
        """
        t0 = time.perf_counter()
        pos, v0 = float(position_m), float(speed_mps)
        a0 = self._last_accel if accel_mps2 is None else float(accel_mps2)
        if not (math.isfinite(pos) and math.isfinite(v0) and v0 >= 0 and math.isfinite(a0)):
            raise InputError(f"position_m = {position_m!r}, speed_mps = {speed_mps!r}, accel_mps2 = {accel_mps2!r}: "
                             "give a finite position (m), a speed >= 0 (m/s) and a finite acceleration (m/s^2)")
        if v0 <= 0:
            a0 = max(a0, 0.0)  # at rest nothing pulls backwards
        if pos >= self.planned_to_m:
            self._driven.append((pos, v0))
        self._skip_blind_spot(pos)
        self._advance()
        segs = self._segments
        k0 = self._segment_of(pos)
        if k0 < segs.offset:
            raise InputError(f"position_m = {pos!r} m is {self._boundary_m(segs.offset) - pos:.3g} m behind the "
                             f"earliest position still planned ({self._boundary_m(segs.offset):.6g} m): the selector "
                             f"keeps {self.margin_m:g} m behind the vehicle; give positions that go back no further")
        segs.forget_before(self._segment_of(pos - self.margin_m))  # some way back: positions jitter
        behind = min(pos, self.planned_to_m) - 2.0 * self.margin_m  # nothing before is needed again
        self.terrain.forget_before(behind)
        if self._driven and self._driven[0][0] < behind:
            self._driven = [(p, w) for p, w in self._driven if p >= behind]
        total = self._segment_count()
        finished = total is not None and segs.end >= total
        if self.end_m is not None and pos >= self.end_m - 1e-9:
            if v0 > 0:
                return self._braking(pos, v0, pos, t0, f"{v0:.4g} m/s at the path's end ({self.end_m:.6g} m)")
            return self._finish(pos, v0, 0.0, np.array([pos]), np.array([v0]), pos, t0, emergency=False, note="")
        rows = np.arange(k0, min(segs.end, k0 + MAX_HORIZON_SEGMENTS)) - segs.offset
        where = np.concatenate([[pos], self._boundary_m(rows + segs.offset + 1)])
        top, decel, accel = segs.top[rows], segs.decel[rows], segs.accel[rows]
        grade_hi, power_binds = segs.grade_hi[rows], bool(np.any(segs.power_binds[rows]))
        # per piece: its segment (global; -1 in the unseen tail), the upper band, the choice
        piece_seg = rows + segs.offset
        upper_lo, upper_hi = segs.upper_lo[rows], segs.upper_hi[rows]
        chosen, env_decel, entry_lag = segs.chosen[rows], segs.envelope_decel[rows], segs.entry_lag[rows]
        edge = float(where[-1])
        finished = finished and k0 + MAX_HORIZON_SEGMENTS >= segs.end
        if not finished:  # the unseen terrain: [0, v_unseen], long enough to stop from it
            vu = self.unseen_speed_mps
            # braking on unseen ground: on the assumed descent, and no harder than on the ground
            # in sight (else the ground it turns out to be could lower the envelope already
            # driven under, through the bounds of a cycle that crosses into it)
            d = min(self._tail_decel, float(np.min(decel))) if decel.size else self._tail_decel
            d = max(d, MIN_BRAKING_MPS2)  # a descent too steep to brake on in sight: the least braking
            # long enough that its end does not hold the speed at the edge below v_unseen, even
            # braking with the jerk bound; two pieces, so that a vehicle at rest may start into it
            tail = vu * vu / (2.0 * d) + braking_margin_m(vu, d, self.max_jerk_mps3) + self.segment_length_m
            ends = self.end_m is not None and edge + tail >= self.end_m
            if ends:  # the path ends within it: there the vehicle stops (or leaves at vend)
                tail = max(self.end_m - edge, 2e-9)
            where = np.append(where, [edge + tail / 2, edge + tail])
            top = np.append(top, [vu, vu])
            decel = np.append(decel, [d, d])
            accel = np.append(accel, [float(self.vehicle.max_accel_mps2)] * 2)
            grade_hi = np.append(grade_hi, [0.0, 0.0])
            piece_seg = np.append(piece_seg, [-1, -1])
            upper_lo, upper_hi = np.append(upper_lo, [np.nan] * 2), np.append(upper_hi, [np.nan] * 2)
            chosen, env_decel = np.append(chosen, [False, False]), np.append(env_decel, [np.inf] * 2)
            entry_lag = np.append(entry_lag, [0.0, 0.0])
            end_b = self.vend_mps ** 2 if ends else 0.0
        else:
            end_b = self.vend_mps ** 2
        if where[1:].size and where[1] - where[0] <= 1e-9:  # at a boundary: drop the empty first piece
            where, top, decel, accel, grade_hi = where[1:], top[1:], decel[1:], accel[1:], grade_hi[1:]
            piece_seg, upper_lo, upper_hi = piece_seg[1:], upper_lo[1:], upper_hi[1:]
            chosen, env_decel, entry_lag = chosen[1:], env_decel[1:], entry_lag[1:]
        if top.size == 0:
            return self._finish(pos, v0, 0.0, np.array([pos]), np.array([v0]), edge, t0, emergency=False, note="")
        # a command holds one acceleration for a cycle, which may cross segment boundaries: each
        # segment's bounds become the tightest of the segments within a cycle's travel
        reach = int(math.ceil(self.vehicle.max_speed_mps * self.cycle_s / self.segment_length_m)) + 1
        decel, accel = _sliding_min(decel, reach), _sliding_min(accel, reach)
        length = np.diff(where)
        final = piece_seg >= 0  # the final segments' pieces (not the unseen tail)
        # the upper band (module docstring, "The upper band"): the features whose choice is open
        trial_chosen, trial_decel = chosen.copy(), env_decel.copy()
        opened, closed = [], []
        stored_braking = None
        for i0, i1 in _features(upper_lo, top, final):
            if np.all(chosen[i0:i1]):  # chosen in an earlier cycle
                k = i0
                while k > 0 and np.isfinite(env_decel[k - 1]) and not chosen[k - 1]:  # its lead-in
                    k -= 1
                if k == 0:
                    continue  # the vehicle is on its lead-in or in it: committed (sticky, below)
                if stored_braking is None:
                    stored_braking = braking_profile(_boundary_b(np.where(chosen, upper_hi, top) ** 2, end_b=end_b),
                                                     length, np.minimum(decel, env_decel))
                if self._upper_band_holds(stored_braking, upper_lo, upper_hi, decel, float(env_decel[i0]), None,
                                          i0, i1, entry_lag_mps=float(entry_lag[i0])):
                    continue
                # not committed yet, and (b) no longer holds (what came into view after it is
                # worse than assumed): back to the first band, if the vehicle can (below)
                trial_chosen[i0:i1] = False
                trial_decel[k:i1] = np.inf
                closed.append((k, i0, i1))
                continue
            lead = self._upper_band_lead_in(where, top, decel, upper_lo, upper_hi, trial_chosen, trial_decel,
                                            final, end_b, v0, a0, i0, i1, accel=accel)
            if lead is not None:
                j0, d_lead, lag_in = lead
                trial_chosen[i0:i1] = True
                trial_decel[j0:i1] = np.minimum(trial_decel[j0:i1], d_lead)
                opened.append((i0, i1, lag_in))
        max_accel = float(accel[0])
        if self._power is not None and v0 > 0:
            faster = v0 + max(max_accel, 0.0) * self.cycle_s  # the power bound at the cycle's highest speed
            max_accel = min(max_accel, float(power_accel_mps2(self._power.max_power_w, self._power.mass_kg, faster,
                                                              grade_hi[0])))
        cap_top = np.where(trial_chosen, upper_hi, top)
        upper, braking, knots, envelope = self._envelope_of(where, cap_top, decel, trial_decel, end_b)
        step = jerk_limited_step(pos, v0, a0, where_m=knots, envelope_b=envelope, max_accel_mps2=max_accel,
                                 decel_mps2=_piece_values(knots, where, decel), jerk_mps3=self.max_jerk_mps3,
                                 cycle_s=self.cycle_s)
        if (opened or closed) and not step.jerk_kept:
            # the vehicle's state is not safe under the new envelope (an upper band's lead-in lies
            # below the first band's braking curve there; or, going back to the first band, its
            # caps lie below the vehicle's braking): the last cycle's choice, unless that is no
            # better (terrain worse than assumed came into view late, a kerb at speed: both
            # brake harder than the jerk bound) and brakes harder; on a tie (both as hard as the
            # vehicle may) the new one (an upper band: whose caps on the feature it can still
            # reach)
            kept = self._envelope_of(where, np.where(chosen, upper_hi, top), decel, env_decel, end_b)
            kept_step = jerk_limited_step(pos, v0, a0, where_m=kept[2], envelope_b=kept[3],
                                          max_accel_mps2=max_accel, decel_mps2=_piece_values(kept[2], where, decel),
                                          jerk_mps3=self.max_jerk_mps3, cycle_s=self.cycle_s)
            if kept_step.jerk_kept or kept_step.accel_mps2 > step.accel_mps2:
                trial_chosen, trial_decel, opened, closed = chosen, env_decel, [], []
                (upper, braking, knots, envelope), step = kept, kept_step
        # The choices are stored per segment. Once the vehicle is on a feature's lead-in, the
        # choice is kept (sticky) whatever comes into view: dropping it inside the feature would
        # mean braking through resonance on rough ground. (b) keeps holding in the cycles after
        # whenever the newly measured terrain is no worse than assumed: the feature's caps and
        # the envelope's deceleration on it are fixed, and new segments past the planning edge,
        # whose caps are at least v_unseen, only raise the envelope where the vehicle can be (the
        # module docstring's safety argument), so the speeds (b) asked for are still there. When
        # the terrain is worse (a step past the planning edge, rougher ground than assumed),
        # the envelope after the feature comes down: before the lead-in the first band is taken
        # back (above); after it, the tracker brakes for it as for any surprise, harder than the
        # jerk bound if it must (Command.emergency), and a speed below the band at a cycle's
        # start is said (the note of ``below``): the vehicle then crosses speeds between the
        # bands, over the limit by the force model, as the offline plan would on that terrain.
        for i0, i1, lag_in in opened:
            rows_now = piece_seg[i0:i1] - segs.offset
            segs.chosen[rows_now] = True
            segs.entry_lag[rows_now] = lag_in
            lead_rows = piece_seg[:i1][(piece_seg[:i1] >= 0) & np.isfinite(trial_decel[:i1])] - segs.offset
            segs.envelope_decel[lead_rows] = np.minimum(segs.envelope_decel[lead_rows],
                                                        trial_decel[:i1][np.isfinite(trial_decel[:i1])])
        for k, i0, i1 in closed:
            segs.chosen[piece_seg[i0:i1] - segs.offset] = False
            segs.entry_lag[piece_seg[i0:i1] - segs.offset] = 0.0
            segs.envelope_decel[piece_seg[k:i1] - segs.offset] = np.inf
        below = ""
        if trial_chosen[0] and v0 < upper_lo[0] * (1 - 1e-6):
            below = (f"{v0:.4g} m/s at {pos:.6g} m, below the upper band [{upper_lo[0]:.4g}, {upper_hi[0]:.4g}] m/s "
                     "chosen there: the speeds between the bands are over the force limit (terrain after it worse "
                     "than assumed, or the tracking fell short)")
        if v0 * v0 > braking[0] * (1 + 1e-9) + 1e-12:  # faster than any limit-keeping profile allows
            allowed = math.sqrt(max(braking[0], 0.0))  # < 0: a descent ahead too steep to brake on
            return self._braking(pos, v0, edge, t0, f"{v0:.4g} m/s, where at most {allowed:.4g} m/s keeps the "
                                                    "limits of the terrain ahead")
        power = None
        if self._power is not None and power_binds:
            power = DrivePower(self._power.max_power_w / self._power.mass_kg, grade_hi)
        plan_upper = upper.copy()
        plan_upper[0] = v0 * v0
        # no lower bounds but the current speed: where entering a coarse climb fast would stall,
        # the report's plan enters it slower, never below the speed the vehicle has now
        plan_lower = np.zeros_like(plan_upper)
        plan_lower[0] = plan_upper[0]
        plan = np.sqrt(np.maximum(greatest_profile(plan_lower, plan_upper, length, accel, decel, power), 0.0))
        keep = where.size - (0 if finished else 2)
        note = ""
        if not step.jerk_kept:  # this cycle's braking past the jerk bound, or at it but short
            if abs(step.accel_mps2 - a0) > self.max_jerk_mps3 * self.cycle_s * (1 + 1e-9):
                note = f"braking harder than the jerk bound allows at {pos:.6g} m to stay within the limits"
            else:
                note = (f"braking as hard as the jerk bound allows at {pos:.6g} m, short of the braking that keeps "
                        "the limits")
            note += " of terrain that came into view worse than assumed"
        late, self._late = self._late, ""
        note = "; ".join(n for n in (late, below, note) if n)
        self._last_accel = step.accel_after_mps2
        return Command(speed_mps=step.speed_mps, accel_mps2=step.accel_mps2, position_next_m=step.position_m,
                       horizon_s_m=where[:keep].copy(), horizon_speed_mps=plan[:keep].copy(), edge_m=edge,
                       edge_speed_mps=float(plan[keep - 1]), unseen_speed_mps=self.unseen_speed_mps,
                       emergency=not step.jerk_kept or bool(late) or bool(below), note=note,
                       compute_s=time.perf_counter() - t0)

    def _envelope_of(self, where: np.ndarray, cap_top: np.ndarray, decel: np.ndarray, envelope_decel: np.ndarray,
                     end_b: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The envelope (module docstring, 3) under the caps ``cap_top`` (m/s, per piece), braking
        at the pieces' bounds ``decel`` but no harder than ``envelope_decel`` (m/s^2; inf where
        the bound holds: lower on a chosen feature and its lead-in, "The upper band").

        Returns
        -------
        upper, braking : numpy.ndarray, shape (N+1,)
            The caps at the boundaries and the braking profile there (m^2/s^2).
        knots, envelope : numpy.ndarray, shape (K,)
            The envelope's knots (m) and b there (m^2/s^2) (:func:`_envelope`).
        """
        length = np.diff(where)
        shaped = np.minimum(decel, envelope_decel)
        top_b = cap_top * cap_top
        upper = _boundary_b(top_b, end_b=end_b)
        braking = braking_profile(upper, length, shaped)
        knots, envelope = _envelope(where, top_b, braking, shaped)
        return upper, braking, knots, envelope

    def _tracking_lag_mps(self, decel_mps2: float, *, ramp_in: bool = False) -> float:
        """The most (m/s) the command's speed falls below the envelope where the envelope's
        braking at ``decel_mps2`` ends in a cap, or with ``ramp_in`` where it starts, plus one
        cycle of that braking (d dt: a command is chosen once a cycle, among
        :data:`~.tracking.CANDIDATES`).

        Where it ends, the vehicle on the braking curve must ramp its deceleration back to 0 at
        the jerk bound J (:func:`~.tracking.jerk_limited_step` takes the largest acceleration
        that keeps under the envelope, so it rides the curve to its end): it loses d^2 / (2 J)
        more. Where it starts, the vehicle ramps up to d at J and is below the line by at most
        d^2 / (8 J) where it starts (it begins the ramp half of it, d / (2 J), before the line,
        the earliest the safety manoeuvre of :mod:`.tracking`, a ramp to d and d held, asks)."""
        jerk = self.max_jerk_mps3
        lag = 0.0 if not math.isfinite(jerk) else decel_mps2 * decel_mps2 / ((8.0 if ramp_in else 2.0) * jerk)
        return lag + decel_mps2 * self.cycle_s

    def _decel_for_lag(self, lag_mps: float) -> float:
        """The deceleration (m/s^2) whose :meth:`_tracking_lag_mps` is ``lag_mps`` (its inverse)."""
        jerk, dt = self.max_jerk_mps3, self.cycle_s
        if not math.isfinite(jerk):
            return lag_mps / dt
        return jerk * (math.sqrt(dt * dt + 2.0 * lag_mps / jerk) - dt)

    def _upper_band_lead_in(self, where: np.ndarray, top: np.ndarray, decel: np.ndarray, upper_lo: np.ndarray,
                            upper_hi: np.ndarray, chosen: np.ndarray, envelope_decel: np.ndarray, final: np.ndarray,
                            end_b: float, v0: float, a0: float, i0: int, i1: int, *, accel: np.ndarray
                            ) -> tuple[int, float, float] | None:
        """Whether the upper band may be chosen for the feature of pieces [i0, i1) of the horizon
        (module docstring, "The upper band"), and if so the first piece of its lead-in, the
        deceleration (m/s^2) the envelope assumes on the lead-in and the feature, and how far
        (m/s) below the envelope the vehicle may enter the feature; None: the first band.

        Required: (a) the feature ends before the planning edge (``final`` pieces after it);
        (b) the envelope with the feature capped at its
        upper band (the pieces before it unchanged, the unseen tail as assumed) is at least the
        band's lower edge at every boundary from the vehicle to the feature, and that plus the
        tracking lag (:meth:`_tracking_lag_mps`) and the entry lag (below) at the feature's
        boundaries: the lag of the envelope's deceleration inside it, of the horizon's hardest
        at its end, where braking for what follows starts; (c) the vehicle is already that fast.

        The envelope brakes on the feature and its lead-in at d_f, chosen so that the lag is
        half the band's narrowest width, no harder than the bounds: inside the feature the
        vehicle tracks the caps without falling out of the band. The lead-in, before it, lets a
        vehicle on the approach's harder braking D come off it to d_f at the jerk bound J,
        falling (D - d_f)^2 / (2 J) + (D - d_f) dt behind the envelope (the second term: a
        cycle's wait). Two lengths are tried, the short first: (1) only that ramp, (D - d_f) / J
        and a cycle, and the vehicle enters the feature that far behind (the *entry lag*, added
        to what (b) asks inside the feature); (2) that ramp and the time to catch up again, 2
        sqrt(lag / J) at the jerk bound, with no entry lag. A lead-in is the time it takes at
        the envelope's speed there. The short one costs least before the feature: a vehicle
        already braking for the feature's first band (a kerb seen late with the worst terrain
        assumed beyond it) lies under its envelope, and under the long one's only if it
        lags that braking by more than the long lead-in's slower braking gives away.

        When the vehicle is past the start of a lead-in that (b) needs (the feature's end came
        into view late, at short sensing ranges, while the vehicle brakes for the feature's
        first band), the lead-in is the stretch from the vehicle to the feature, braking at d_f,
        and the entry lag and (c) are those of the vehicle's own state, speed ``v0`` (m/s) and
        acceleration ``a0`` (m/s^2), rather than of the approach's hardest braking D. The
        tracker takes the fastest acceleration that keeps under the envelope: below it, it only
        comes off its braking D0 = -a0 at the jerk bound J (after at most a cycle), to no less
        than v_low = v0 - D0 dt - D0^2 / (2 J), and speeds up after; on it, it comes off D0 to
        d_f, falling (D0 - d_f)^2 / (2 J) + (D0 - d_f) dt behind (the entry lag, as above).
        So (b) is asked with that entry lag and (c) as v_low at least the band's lower edge at
        every boundary of the feature. Not where another feature chosen in its upper band lies
        between the vehicle and this one (the lead-in's gentler braking would lower the
        envelope over it, whose own (b) is not asked again), nor where a piece up to the
        feature's end has a negative acceleration bound ``accel`` (m/s^2, per piece: a climb
        steeper than the drive holds, where the vehicle cannot come off its braking)."""
        if i0 == 0 or i1 >= final.size or not final[i1]:  # inside it already, or (a)
            return None
        width = float(np.min(np.diff(self._feature_floor(upper_lo, upper_hi, i0, i1), axis=0)))
        if not width > 0:
            return None
        hardest = float(np.max(decel))
        d_f = min(self._decel_for_lag(0.5 * width), hardest)
        jerk, dt = self.max_jerk_mps3, self.cycle_s
        if math.isfinite(jerk) and hardest > d_f:
            behind = (hardest - d_f) ** 2 / (2.0 * jerk)
            ramp_s = (hardest - d_f) / jerk + dt
            leads = [(ramp_s, behind + (hardest - d_f) * dt), (ramp_s + 2.0 * math.sqrt(behind / jerk), 0.0)]
        else:
            leads = [(dt, 0.0)]
        trial_top = np.where(chosen, upper_hi, top)
        trial_top[i0:i1] = upper_hi[i0:i1]
        upper = _boundary_b(trial_top * trial_top, end_b=end_b)
        h = float(upper[i0])  # the most b the envelope has where the feature starts

        def braking_from(j0: int) -> np.ndarray:
            """The envelope's braking profile with the lead-in from piece j0 braking at d_f."""
            trial_decel = envelope_decel.copy()
            trial_decel[j0:i1] = np.minimum(trial_decel[j0:i1], d_f)
            return braking_profile(upper, np.diff(where), np.minimum(decel, trial_decel))

        for lead_s, entry_lag in leads:
            # the lead-in's length L: T at the envelope's speed v there, v^2 <= h + 2 d_f L
            lead_m = lead_s * lead_s * d_f + math.sqrt(lead_s ** 4 * d_f * d_f + lead_s * lead_s * h)
            start_m = float(where[i0]) - lead_m
            if start_m < where[0]:
                break  # the vehicle is on this lead-in already (and on the longer one): below
            j0 = int(np.searchsorted(where, start_m, side="right")) - 1
            if self._upper_band_holds(braking_from(j0), upper_lo, upper_hi, decel, d_f, v0, i0, i1,
                                      entry_lag_mps=entry_lag):
                return j0, d_f, entry_lag
        else:
            return None
        # a lead-in already begun: from the vehicle, (c) asked of its own state (docstring); not
        # over another chosen feature, whose own (b) the gentler braking here would not recheck
        if np.any(chosen[:i0]) or np.any(accel[:i1] < 0):
            return None
        braking_now = max(-a0, 0.0)
        ramp = max(braking_now - d_f, 0.0)
        v_low, entry_lag = v0 - braking_now * dt, ramp * dt
        if math.isfinite(jerk):
            v_low -= braking_now ** 2 / (2.0 * jerk)
            entry_lag += ramp * ramp / (2.0 * jerk)
        floor = self._feature_floor(upper_lo, upper_hi, i0, i1)[0]
        if v_low >= float(np.max(floor)) and self._upper_band_holds(braking_from(0), upper_lo, upper_hi, decel, d_f,
                                                                    None, i0, i1, entry_lag_mps=entry_lag):
            return 0, d_f, entry_lag
        return None

    @staticmethod
    def _feature_floor(upper_lo: np.ndarray, upper_hi: np.ndarray, i0: int, i1: int) -> np.ndarray:
        """The upper band at the feature's boundaries i0 .. i1 (m/s), shape (2, i1 - i0 + 1):
        the least and the greatest speed there that keeps the band of the pieces either side
        (:func:`profileopt.planning.bands.boundary_bounds`)."""
        lo, hi = upper_lo[i0:i1], upper_hi[i0:i1]
        lower_b, _ = boundary_bounds(lo, hi, float(lo[0]), float(lo[-1]))
        _, upper_b = boundary_bounds(lo, hi, float(hi[0]), float(hi[-1]))
        return np.sqrt(np.stack([lower_b, upper_b]))

    def _upper_band_holds(self, braking: np.ndarray, upper_lo: np.ndarray, upper_hi: np.ndarray, decel: np.ndarray,
                          d_f: float, v0: float | None, i0: int, i1: int, *, entry_lag_mps: float) -> bool:
        """Conditions (b) and (c) of :meth:`_upper_band_lead_in` for the feature [i0, i1) under the
        envelope's braking profile ``braking`` (m^2/s^2 at the boundaries, the feature capped at
        its upper band and braking at ``d_f`` m/s^2 on it and its lead-in); (b) alone when
        ``v0`` is None (a choice already made: the vehicle's speed was checked then, and the
        tracking keeps it since). ``entry_lag_mps``: how far below the envelope the vehicle may
        enter the feature (m/s), from its lead-in."""
        floor = self._feature_floor(upper_lo, upper_hi, i0, i1)[0]
        margin_in = self._tracking_lag_mps(d_f) + entry_lag_mps
        margin_end = max(margin_in, self._tracking_lag_mps(float(np.max(decel[i1:])), ramp_in=True))
        speed = np.sqrt(np.maximum(braking[:i1 + 1], 0.0))
        need = np.concatenate([np.full(i0, floor[0]), floor[:-1] + margin_in, [floor[-1] + margin_end]])
        return bool(np.all(speed >= need) and (v0 is None or v0 >= floor[0] + margin_in))

    def _finish(self, pos: float, v0: float, accel: float, where: np.ndarray, speed: np.ndarray, edge: float,
                t0: float, *, emergency: bool, note: str) -> Command:
        """A command that holds ``accel`` for one cycle (stopping at rest), with the given horizon."""
        ends = cycle_end(pos, v0, np.array([accel]), self.cycle_s)
        s1, v1, self._last_accel = (float(x[0]) for x in ends)
        return Command(speed_mps=v1, accel_mps2=accel, position_next_m=s1, horizon_s_m=where.copy(),
                       horizon_speed_mps=speed.copy(), edge_m=edge, edge_speed_mps=float(speed[-1]),
                       unseen_speed_mps=self.unseen_speed_mps, emergency=emergency, note=note,
                       compute_s=time.perf_counter() - t0)

    def _braking(self, pos: float, v0: float, edge: float, t0: float, why: str) -> Command:
        """Brake as hard as the vehicle may: no profile keeps the limits from here."""
        late, self._late = self._late, ""
        note = "; ".join(n for n in (late, f"at {pos:.6g} m: {why}; braking as hard as the vehicle may") if n)
        return self._finish(pos, v0, -float(self.vehicle.max_decel_mps2), np.array([pos]), np.array([v0]), edge,
                            t0, emergency=True, note=note)
