"""Choose the speed every cycle from the terrain sensed ahead: the online speed selector.

The offline planner (:func:`profileopt.plan`) knows the whole route. A vehicle driving into
unknown terrain knows only what its sensors have measured ahead (:mod:`.sensed`), and must
never go faster than it could if the terrain beyond were as bad as assumed. Each cycle the
:class:`SpeedSelector`

1. takes the newly sensed samples and, for every segment whose whole neighbourhood is now
   measured (the roughness windows, the grade's fit and the steps' ramps that decide its
   speeds: :attr:`SpeedSelector.margin_m`), computes once and for all the same admissible
   speed bands, caps and acceleration bounds the offline planner computes
   (:mod:`profileopt.planning.limits`: force windows, steps, speed limits and top speed, turns,
   friction, grades, drive power), on the measured samples around it;
2. appends, past the last such segment (the *planning edge*), the terrain not yet measured as
   the ``unseen`` assumption: a roughness class (or an RI) whose first admissible band,
   [0, v_unseen], is the speed allowed there, stopping at rest eventually;
3. chooses the bands and the minimum-time profile over that horizon from the vehicle's
   current position and speed exactly (:func:`profileopt.planning.bands.choose_bands`, the
   forward-backward pass the offline planner starts from): the *envelope*, under which every
   speed keeps every limit but the jerk bound;
4. commands the fastest acceleration for this cycle that changes by at most the jerk bound
   and keeps the vehicle under the envelope, now and while braking with the jerk bound
   afterwards (:mod:`.tracking`).

Safety by construction (docs: guide/online.md). The horizon profile keeps every limit on the
measured segments and ends at the planning edge no faster than v_unseen, from which the
vehicle can keep to any terrain no worse than assumed. The next cycle's problem therefore has
a feasible solution, the rest of this one's, whenever the newly measured terrain is no worse
than assumed: the command is never faster than the offline plan of a route whose unmeasured
part is exactly as bad as assumed, and never infeasible while the assumption holds. Where the
terrain turns out worse (a kerb past the sensing range that the assumption does not cover,
seen too late to slow down), the selector brakes as hard as the vehicle may and says so
(:attr:`Command.emergency`).

What it does not keep: the offline planner's simulation gate (:mod:`profileopt.planning.gate`:
the exact simulation needs the speeds after the horizon), so where the model's caps fall short
of the simulated force (issue 29's short blocks and pits) so does the selector;
``profileopt drive`` reports the simulated force of every roughness window.
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
from ..errors import InfeasibleError, InputError
from ..physics.motion import power_accel_mps2
from ..physics.speeds import speed_bands
from ..physics.steps import MAX_RAMP_M, TREND_HALF_WIDTH_M
from ..planning.bands import DrivePower, choose_bands, snap_to_band
from ..planning.limits import PlanContext, default_limits
from ..terrain.assumed import AssumedRoughness
from ..terrain.geometry import route_geometry
from .sensed import SensedTerrain
from .tracking import braking_margin_m, jerk_limited_step

if TYPE_CHECKING:
    from ..core.vehicle import Vehicle

__all__ = ["SpeedSelector", "Command", "unseen_speed_mps", "unseen_roughness", "DEFAULT_SENSOR_RANGE_M",
           "DEFAULT_CYCLE_S", "DEFAULT_ONLINE_SEGMENT_LENGTH_M", "DEFAULT_UNSEEN", "WORST_CLASS"]

#: Sensing range (m) when none is given: what a vehicle LiDAR resolves at wheel scale.
DEFAULT_SENSOR_RANGE_M = 50.0
#: Control cycle (s) when none is given.
DEFAULT_CYCLE_S = 0.1
#: Segment length (m) of the online selector: fine enough that a step's or a window's cap holds
#: only a metre of route, coarse enough that a 100 m horizon is a hundred segments.
DEFAULT_ONLINE_SEGMENT_LENGTH_M = 1.0
#: The shortest segment (m): the widest gap between samples of measured terrain, so that every
#: segment holds samples.
MIN_ONLINE_SEGMENT_LENGTH_M = MAX_ROUGHNESS_SPACING_M
#: The most segments a horizon may hold (sensor_range_m / segment_length_m): a bound on the time
#: and memory of a cycle.
MAX_HORIZON_SEGMENTS = 10_000
#: The assumption for terrain not yet measured when none is given.
DEFAULT_UNSEEN = "worst"
#: What ``unseen="worst"`` means: the roughest ISO 8608 class, H.
WORST_CLASS = "H"


def unseen_roughness(unseen: str | float) -> AssumedRoughness:
    """The roughness an ``unseen`` option names: ``"worst"`` (ISO 8608 class H), a class letter
    A-H, or an RI (a number).

    Parameters
    ----------
    unseen : str or float
        The assumption.

    Returns
    -------
    AssumedRoughness

    Raises
    ------
    InputError
        Anything else.
    """
    if isinstance(unseen, str):
        text = unseen.strip()
        if text.lower() == "worst":
            return AssumedRoughness(road_class=WORST_CLASS)
        if len(text) == 1 and text.isalpha():
            return AssumedRoughness(road_class=text)
        try:
            value = float(text)
        except ValueError:
            raise InputError(f"unseen = {unseen!r}: give 'worst', an ISO 8608 class A to H, or an RI (a number, "
                             "e.g. 0.05)") from None
        return AssumedRoughness(ri=value)
    if isinstance(unseen, bool) or not isinstance(unseen, (int, float)):
        raise InputError(f"unseen = {unseen!r}: give 'worst', an ISO 8608 class A to H, or an RI (a number)")
    return AssumedRoughness(ri=float(unseen))


def unseen_speed_mps(unseen: str | float, vehicle: "Vehicle", *, model: str = DEFAULT_MODEL,
                     roughness_window_m: float = DEFAULT_ROUGHNESS_WINDOW_M) -> float:
    """The speed (m/s) allowed on terrain not yet measured: the top of the first admissible band
    for every RI up to the assumed one (:func:`profileopt.physics.speeds.speed_bands` with
    ``ri_min=0``), so that it holds on any terrain no rougher than assumed and the vehicle may
    slow down anywhere on it.

    Parameters
    ----------
    unseen : str or float
        ``"worst"``, an ISO 8608 class A-H or an RI (:func:`unseen_roughness`).
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
        The envelope over the measured horizon: positions from the current one to the planning
        edge (m) and the greatest admissible speeds there (m/s).
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

    def __init__(self, bands: int) -> None:
        self.offset = 0  # global index of row 0
        self.lower = np.empty((0, bands))
        self.upper = np.empty((0, bands))
        self.count = np.empty(0, dtype=int)
        self.decel = np.empty(0)
        self.accel = np.empty(0)
        self.grade_hi = np.empty(0)
        self.power_binds = np.empty(0, dtype=bool)

    @property
    def end(self) -> int:
        return self.offset + self.count.size

    def append(self, lower: np.ndarray, upper: np.ndarray, count: np.ndarray, decel: np.ndarray,
               accel: np.ndarray, grade_hi: np.ndarray, power_binds: np.ndarray) -> None:
        width = max(self.lower.shape[1], lower.shape[1])
        self.lower = np.concatenate([_padded(self.lower, width), _padded(lower, width)])
        self.upper = np.concatenate([_padded(self.upper, width), _padded(upper, width)])
        self.count = np.concatenate([self.count, count])
        self.decel = np.concatenate([self.decel, decel])
        self.accel = np.concatenate([self.accel, accel])
        self.grade_hi = np.concatenate([self.grade_hi, grade_hi])
        self.power_binds = np.concatenate([self.power_binds, power_binds])

    def forget_before(self, index: int) -> None:
        drop = min(max(index - self.offset, 0), self.count.size)
        if drop:
            self.lower, self.upper = self.lower[drop:], self.upper[drop:]
            self.count, self.decel, self.accel = self.count[drop:], self.decel[drop:], self.accel[drop:]
            self.grade_hi, self.power_binds = self.grade_hi[drop:], self.power_binds[drop:]
            self.offset += drop


def _sliding_min(values: np.ndarray, half_width: int) -> np.ndarray:
    """The least of ``values[i - half_width : i + half_width + 1]`` for each i, shape (N,)."""
    if values.size <= 1 or half_width <= 0:
        return values
    return minimum_filter1d(values, size=2 * half_width + 1, mode="nearest")


def _padded(a: np.ndarray, width: int) -> np.ndarray:
    if a.shape[1] == width:
        return a
    return np.concatenate([a, np.full((a.shape[0], width - a.shape[1]), np.nan)], axis=1)


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
        The control cycle (s): each command holds one acceleration for a cycle.
    max_jerk_mps3 : float, optional
        Jerk bound (m/s^3): the command's acceleration changes by at most this times
        ``cycle_s`` per cycle (:mod:`.tracking`); None: the vehicle's; inf: none.

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
                 max_jerk_mps3: float | None = None) -> None:
        from ..core.vehicle import Vehicle

        if not isinstance(vehicle, Vehicle):
            raise InputError(f"vehicle = {vehicle!r}: give a Vehicle (profileopt.load_vehicle('atv')), not a "
                             f"{type(vehicle).__name__}")
        if model not in MODEL_KEYS:
            raise InputError(f"model = {model!r}: the online selector takes one of {', '.join(MODEL_KEYS)} (the "
                             "dynamic model simulates the whole route, which is not known online)")
        for name, value in (("sensor_range_m", sensor_range_m), ("segment_length_m", segment_length_m),
                            ("roughness_window_m", roughness_window_m), ("cycle_s", cycle_s)):
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not (math.isfinite(value)
                                                                                        and value > 0):
                raise InputError(f"{name} = {value!r}: must be a finite number > 0")
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
        #: How much measured terrain (m) a segment needs on either side before its speeds are
        #: final: a roughness window, and the trend and ramp a step's cap looks at (or the
        #: grade's fit over two windows, whichever is longer).
        self.margin_m = self.roughness_window_m + max(self.roughness_window_m, MAX_RAMP_M + TREND_HALF_WIDTH_M)
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
        self.terrain = SensedTerrain(start_m=self.start_m)
        self._segments = _Grown(bands=1)
        self._tail_decel = float(vehicle.max_decel_mps2)
        self._last_accel = 0.0
        self._work: Iterator[None] | None = None
        #: Segments whose speeds are computed together (a stretch of at least one roughness
        #: window): each computation has a fixed cost, about 5 ms, so fewer are cheaper.
        self._chunk = max(int(math.ceil(self.roughness_window_m / self.segment_length_m - 1e-9)), 1)

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

    def _advance(self) -> None:
        """One stage of the work on newly measured segments (:meth:`_chunk_stages`), so that no
        cycle does all of it."""
        if self._work is None:
            self._work = self._chunk_stages()
        try:
            next(self._work)
        except StopIteration:
            self._work = None

    def _chunk_stages(self) -> Iterator[None]:
        """Final speeds of the segments whose neighbourhood is measured (module docstring, 1), in
        three stages, one per cycle (a generator): the measured stretch around them, its
        roughness windows and geometry; the force model's speed bands; the other limits."""
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
        lo_m = max(self._boundary_m(first) - self.margin_m, self.terrain.measured_from_m)
        hi_m = measured if at_end else min(measured, self._boundary_m(last) + self.margin_m)
        route = self.terrain.stretch(lo_m, hi_m)
        if route is None:
            return
        # only the new segments: the stretch around them is there for their windows, grades and steps
        bounds = np.asarray(self._boundary_m(np.arange(first, last + 1)), dtype=float)
        if bounds[0] < route.s_m[0] - 1e-9 or bounds[-1] > route.s_m[-1] + 1e-9:
            return  # not measured around them yet (forgotten, or a gap): later
        bounds = np.clip(bounds, route.s_m[0], route.s_m[-1])
        starts, stops = segment_samples(route.s_m, bounds)
        windows = route_roughness_windows(route, self.vehicle, window_m=self.roughness_window_m)
        seg = segments_at(bounds, windows, self.vehicle, starts=starts, stops=stops)
        geometry = route_geometry(route, tolerance_m=self.path_tolerance_m,
                                  grade_scale_m=2.0 * self.roughness_window_m,
                                  min_turn_radius_m=self.vehicle.min_turn_radius_m)
        path = segment_path(route, seg, geometry)
        context = PlanContext(route=route, vehicle=self.vehicle, segments=seg, path=path)
        yield
        bands = None
        for limit in self.limits:
            got = limit.speed_bands(context)
            if got is not None:
                bands = got
        yield
        n = seg.count
        cap = np.full(n, np.inf)
        decel, accel = np.full(n, np.inf), np.full(n, np.inf)
        for limit in self.limits:
            limited = limit.speed_cap_mps(context)
            if limited is not None:
                cap = np.minimum(cap, limited)
            bounds_a = limit.accel_bounds_mps2(context)
            if bounds_a is not None:
                decel, accel = np.minimum(decel, bounds_a[0]), np.minimum(accel, bounds_a[1])
        for limit in self.limits:  # rows the forward-backward pass cannot keep: tighter bounds
            if limit.name == "power":
                continue  # kept exactly by the forward pass (DrivePower)
            inner_b = limit.inner_bounds(context, cap, decel, accel)
            if inner_b is not None:
                cap, decel, accel = inner_b
        usable = bands.capped(cap)
        # the forward pass keeps the power limit step by step (slow) only where it can bind
        binds = self._power is not None and self._power.nlp_rows(context, cap, decel, accel) is not None
        self._segments.append(usable.lower_mps, usable.upper_mps, usable.count, decel, accel, path.grade_hi_rad,
                              np.full(n, binds))

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
        self._advance()
        segs = self._segments
        k0 = self._segment_of(pos)
        segs.forget_before(k0)
        self.terrain.forget_before(pos - 2.0 * self.margin_m)
        ready = segs.end
        total = self._segment_count()
        finished = total is not None and ready >= total
        if self.end_m is not None and pos >= self.end_m - 1e-9:
            return self._finish(pos, v0, 0.0, np.array([pos]), np.array([v0]), pos, t0, emergency=False, note="")
        ks = np.arange(max(k0, segs.offset), ready)
        if ks.size and k0 >= segs.offset:
            where = np.concatenate([[pos], self._boundary_m(ks + 1)])
            rows = ks - segs.offset
            lower, upper, count = segs.lower[rows], segs.upper[rows], segs.count[rows]
            decel, accel, grade_hi = segs.decel[rows], segs.accel[rows], segs.grade_hi[rows]
            power_binds = bool(np.any(segs.power_binds[rows]))
        else:
            where = np.array([pos])
            width = segs.lower.shape[1]
            lower, upper = np.empty((0, width)), np.empty((0, width))
            count = np.empty(0, dtype=int)
            decel, accel, grade_hi = np.empty(0), np.empty(0), np.empty(0)
            power_binds = False
        edge = float(where[-1])
        if not finished:  # the unseen terrain: [0, v_unseen], long enough to stop from it
            vu = self.unseen_speed_mps
            d = self._tail_decel
            # long enough that its end does not hold the speed at the edge below v_unseen, even
            # braking with the jerk bound; two pieces, so that a vehicle at rest may start into it
            tail = vu * vu / (2.0 * d) + braking_margin_m(vu, d, self.max_jerk_mps3) + self.segment_length_m
            where = np.append(where, [edge + tail / 2, edge + tail])
            row_lo = np.full((2, lower.shape[1]), np.nan)
            row_hi = np.full((2, lower.shape[1]), np.nan)
            row_lo[:, 0], row_hi[:, 0] = 0.0, vu
            lower, upper = np.concatenate([lower, row_lo]), np.concatenate([upper, row_hi])
            count = np.append(count, [1, 1])
            decel = np.append(decel, [d, d])
            accel = np.append(accel, [float(self.vehicle.max_accel_mps2)] * 2)
            grade_hi = np.append(grade_hi, [0.0, 0.0])
            vend = 0.0
        else:
            vend = self.vend_mps
        length = np.diff(where)
        if length.size and length[0] <= 1e-9:  # at a boundary: drop the empty first piece
            where, length = where[1:], length[1:]
            lower, upper, count = lower[1:], upper[1:], count[1:]
            decel, accel, grade_hi = decel[1:], accel[1:], grade_hi[1:]
        if length.size == 0:
            return self._finish(pos, v0, 0.0, np.array([pos]), np.array([v0]), edge, t0, emergency=False, note="")
        # a command holds one acceleration for a cycle, which may cross segment boundaries: each
        # segment's bounds become the tightest of the segments within a cycle's travel
        reach = int(math.ceil(self.vehicle.max_speed_mps * self.cycle_s / self.segment_length_m)) + 1
        decel, accel = _sliding_min(decel, reach), _sliding_min(accel, reach)
        power = None
        if self._power is not None and power_binds:
            power = DrivePower(self._power.max_power_w / self._power.mass_kg, grade_hi)
        start, _ = snap_to_band(v0, lower[0], upper[0], int(count[0]), "speed_mps")
        try:
            chosen = choose_bands(lower, upper, count, length, accel, decel, start, vend, where, power)
        except InfeasibleError as exc:
            return self._braking(pos, v0, edge, t0, str(exc))
        b_env = chosen.greatest_b
        max_accel = float(accel[0])
        if self._power is not None and v0 > 0:
            faster = v0 + max(max_accel, 0.0) * self.cycle_s  # the power bound at the cycle's highest speed
            max_accel = min(max_accel, float(power_accel_mps2(self._power.max_power_w, self._power.mass_kg, faster,
                                                              grade_hi[0])))
        step = jerk_limited_step(pos, v0, a0, where_m=where, envelope_b=b_env, max_accel_mps2=max_accel,
                                 decel_mps2=decel, jerk_mps3=self.max_jerk_mps3, cycle_s=self.cycle_s)
        speed = np.sqrt(np.maximum(b_env, 0.0))
        keep = where.size - (0 if finished else 2)
        note = "" if step.jerk_kept else (f"braking harder than the jerk bound allows at {pos:.6g} m to stay within "
                                          "the limits of terrain that came into view worse than assumed")
        self._last_accel = step.accel_mps2
        return Command(speed_mps=step.speed_mps, accel_mps2=step.accel_mps2, position_next_m=step.position_m,
                       horizon_s_m=where[:keep].copy(), horizon_speed_mps=speed[:keep].copy(), edge_m=edge,
                       edge_speed_mps=float(np.interp(edge, where, speed)), unseen_speed_mps=self.unseen_speed_mps,
                       emergency=not step.jerk_kept, note=note, compute_s=time.perf_counter() - t0)

    def _finish(self, pos: float, v0: float, accel: float, where: np.ndarray, speed: np.ndarray, edge: float,
                t0: float, *, emergency: bool, note: str) -> Command:
        """A command that holds ``accel`` for one cycle (stopping at rest), with the given horizon."""
        v1 = max(v0 + accel * self.cycle_s, 0.0)
        if accel < 0 and v1 == 0.0:
            s1 = pos + v0 * v0 / (2.0 * -accel)
        else:
            s1 = pos + (v0 + v1) / 2.0 * self.cycle_s
        self._last_accel = accel if v1 > 0 else 0.0
        return Command(speed_mps=v1, accel_mps2=accel, position_next_m=s1, horizon_s_m=where.copy(),
                       horizon_speed_mps=speed.copy(), edge_m=edge, edge_speed_mps=float(speed[-1]),
                       unseen_speed_mps=self.unseen_speed_mps, emergency=emergency, note=note,
                       compute_s=time.perf_counter() - t0)

    def _braking(self, pos: float, v0: float, edge: float, t0: float, why: str) -> Command:
        """Brake as hard as the vehicle may: no profile keeps the limits from here."""
        return self._finish(pos, v0, -float(self.vehicle.max_decel_mps2), np.array([pos]), np.array([v0]), edge,
                            t0, emergency=True,
                            note=f"no profile keeps every limit from {v0:.3g} m/s at {pos:.6g} m: {why}; braking")
