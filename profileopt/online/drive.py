"""Drive a route the vehicle does not know in advance: the selector in closed loop, judged by
the exact simulation.

The route is revealed to the :class:`~.selector.SpeedSelector` only within the sensing range
ahead of the vehicle, every cycle, optionally with noise and at a coarser spacing; the vehicle
follows each command exactly (it drives the horizon profile for one cycle); the speed it drove
is then simulated on the real route in the quarter car ``verify`` uses and judged by roughness
windows (:func:`profileopt.verification.window_check.check_windows`).
"""

from __future__ import annotations

import dataclasses
import math
import os
import time
from typing import TYPE_CHECKING

import numpy as np

from ..core.segments import route_roughness_windows
from ..defaults import DEFAULT_MODEL, DEFAULT_PATH_TOLERANCE_M, DEFAULT_ROUGHNESS_WINDOW_M
from ..errors import InfeasibleError, InputError
from ..io.atomic import atomic_write
from ..physics.forces import get_model
from ..physics.simulate import boundary_times_s, simulate_quarter_car
from ..progress import NO_PROGRESS, Progress
from ..verification.window_check import check_windows
from .selector import (
    DEFAULT_CYCLE_S,
    DEFAULT_ONLINE_SEGMENT_LENGTH_M,
    DEFAULT_SENSOR_RANGE_M,
    DEFAULT_UNSEEN,
    DEFAULT_UNSEEN_DESCENT,
    CYCLE_WHY,
    MAX_CYCLE_S,
    SpeedSelector,
)

if TYPE_CHECKING:
    from ..core.route import Route
    from ..core.vehicle import Vehicle

__all__ = ["Drive", "drive", "write_drive", "DRIVE_COLUMNS", "MAX_CYCLES", "END_TOLERANCE_M", "MAX_SENSOR_NOISE_M"]

#: How close to the route's end (m) a vehicle at rest has arrived (it creeps the last
#: centimetres within the jerk bound).
END_TOLERANCE_M = 0.01
#: A speed (m/s) at or below which the vehicle counts as at rest at the route's end (the
#: commands' arithmetic leaves residues of 1e-12 m/s).
REST_MPS = 1e-9
#: The largest sensor noise (m) a drive takes: a standard deviation of the sensed elevations.
MAX_SENSOR_NOISE_M = 1.0
#: The most cycles one drive may take: a bound on time and memory (a 100 km route at 1 m/s and
#: 0.1 s is a million).
MAX_CYCLES = 2_000_000


@dataclasses.dataclass(frozen=True)
class Drive:
    """A closed-loop drive of the online selector over a route, and its exact simulation.

    Attributes
    ----------
    s_m, speed_mps : numpy.ndarray, shape (K,)
        The driven profile: positions (m) and speeds (m/s) at every cycle's end, constant
        acceleration in between.
    time_s : numpy.ndarray, shape (K,)
        Time at each position (s), from 0.
    knot_cycle : numpy.ndarray of int, shape (K,)
        The cycle whose command the vehicle follows from each knot on.
    cycle_s_m, cycle_speed_mps, cycle_accel_mps2, cycle_edge_m, cycle_edge_speed_mps : numpy.ndarray, shape (C,)
        Per cycle: position (m), speed (m/s), commanded acceleration (m/s^2), the planning edge
        (m) and the horizon's speed there (m/s).
    cycle_compute_s : numpy.ndarray, shape (C,)
        Wall time of the selector per cycle, sensing and update (s).
    emergencies : int
        Cycles whose command said the terrain was worse than assumed
        (:attr:`~.selector.Command.emergency`: braking harder than the jerk bound or as hard as
        the vehicle may, or ground already driven over above its caps).
    travel_time_s : float
        Time to drive the route (s).
    worst_window_ratio : float
        The largest simulated peak force of any roughness window over the limit (dimensionless;
        within the limit when at most 1).
    windows_over : int
        How many roughness windows go over the limit in the simulation.
    worst_s_m : float
        Where the worst window's peak is (m).
    window_start_m, window_ratio : numpy.ndarray, shape (W,)
        Each roughness window's start (m) and its simulated peak force over the limit.
    max_jerk_mps3 : float
        The largest change of the commanded acceleration between cycles over the cycle (m/s^3),
        while moving (coming to rest ends the braking at once).
    unseen_speed_mps : float
        The speed allowed on unseen terrain (m/s).
    notes : tuple of str
    """

    s_m: np.ndarray
    speed_mps: np.ndarray
    time_s: np.ndarray
    knot_cycle: np.ndarray
    cycle_s_m: np.ndarray
    cycle_speed_mps: np.ndarray
    cycle_accel_mps2: np.ndarray
    cycle_edge_m: np.ndarray
    cycle_edge_speed_mps: np.ndarray
    cycle_compute_s: np.ndarray
    emergencies: int
    travel_time_s: float
    worst_window_ratio: float
    windows_over: int
    worst_s_m: float
    window_start_m: np.ndarray
    window_ratio: np.ndarray
    max_jerk_mps3: float
    unseen_speed_mps: float
    notes: tuple[str, ...] = ()

    def compute_ms(self) -> dict[str, float]:
        """The selector's compute time per cycle (ms): ``median``, ``p99`` and ``max``.

        Returns
        -------
        dict
        """
        ms = self.cycle_compute_s * 1e3
        return {"median": float(np.median(ms)), "p99": float(np.percentile(ms, 99)), "max": float(np.max(ms))}

    def knot_accel_mps2(self) -> np.ndarray:
        """The constant acceleration driven from each knot to the next (m/s^2), shape (K,);
        0 after the last.

        Returns
        -------
        numpy.ndarray
        """
        from ..core.kinematics import segment_accel_mps2

        b = self.speed_mps**2
        return np.append(segment_accel_mps2(b[:-1], b[1:], np.diff(self.s_m)), 0.0)


def drive(route: "Route", vehicle: "Vehicle", *, sensor_range_m: float = DEFAULT_SENSOR_RANGE_M,
          unseen: str | float = DEFAULT_UNSEEN, model: str = DEFAULT_MODEL, cycle_s: float = DEFAULT_CYCLE_S,
          segment_length_m: float = DEFAULT_ONLINE_SEGMENT_LENGTH_M,
          roughness_window_m: float = DEFAULT_ROUGHNESS_WINDOW_M,
          path_tolerance_m: float | None = DEFAULT_PATH_TOLERANCE_M, sensor_noise_m: float = 0.0,
          sensor_spacing_m: float | None = None, seed: int = 0, max_jerk_mps3: float | None = None,
          unseen_descent: float = DEFAULT_UNSEEN_DESCENT, progress: Progress = NO_PROGRESS) -> Drive:
    """Drive ``route`` with the online selector, revealing it only within ``sensor_range_m``.

    Parameters
    ----------
    route : Route
        The route, measured terrain (not an assumed roughness).
    vehicle : Vehicle
    sensor_range_m : float, default 50
        Sensing range ahead of the vehicle (m), > 0.
    unseen : str or float, default ``"worst"``
        The assumption for unmeasured terrain (:func:`~.selector.unseen_speed_mps`).
    model : str, default ``"sbem_tf"``
    cycle_s : float, default 0.1
        Control cycle (s), at most :data:`~.selector.MAX_CYCLE_S` (1 s).
    segment_length_m, roughness_window_m, path_tolerance_m
        As :class:`~.selector.SpeedSelector`'s.
    sensor_noise_m : float, default 0
        Standard deviation of Gaussian noise added to each sensed elevation (m), from 0 to
        :data:`MAX_SENSOR_NOISE_M` (1 m); the simulation drives the true route.
    sensor_spacing_m : float, optional
        Sense every this many metres (m) along the path (linear interpolation of the route);
        None: the route's own samples.
    seed : int, default 0
        Seed of the noise.
    max_jerk_mps3 : float, optional
        Jerk bound of the commands (m/s^3); None: the vehicle's; inf: none.
    unseen_descent : float, default 0.05
        The steepest descent assumed on unseen ground (rise over run), as the selector's.
    progress : Progress, optional
        Told once when the drive starts and once when the simulation does.

    Returns
    -------
    Drive

    Raises
    ------
    InputError
        A bad option, or a route with an assumed roughness (nothing to sense).
    """
    if route.assumed_roughness is not None:
        raise InputError(f"{route.source}: its roughness is assumed ({route.assumed_roughness.label}), not measured, "
                         "so there is nothing for a sensor to see; drive a route of measured elevations")
    if not (math.isfinite(sensor_noise_m) and 0 <= sensor_noise_m <= MAX_SENSOR_NOISE_M):
        raise InputError(f"sensor_noise_m = {sensor_noise_m!r}: must be a finite number from 0 to "
                         f"{MAX_SENSOR_NOISE_M:g} m (a ranging sensor's noise is centimetres; more buries the "
                         "roughness a wheel feels)")
    s_true, z_true = route.s_m, route.z_m
    if sensor_spacing_m is not None:
        if not (math.isfinite(sensor_spacing_m) and sensor_spacing_m > 0):
            raise InputError(f"sensor_spacing_m = {sensor_spacing_m!r}: must be a finite number > 0 (m)")
        if route.length_m / sensor_spacing_m > 5e7:
            raise InputError(f"sensor_spacing_m = {sensor_spacing_m:g} m: {route.length_m:g} m would be more than "
                             "5e7 samples; sense at a coarser spacing")
        s_sense = np.append(np.arange(s_true[0], s_true[-1], sensor_spacing_m), s_true[-1])
    else:
        s_sense = s_true
    z_sense = np.interp(s_sense, s_true, z_true)
    rng = np.random.default_rng(seed)
    if sensor_noise_m > 0:
        z_sense = z_sense + rng.normal(0.0, sensor_noise_m, size=z_sense.size)
    xy = None
    if route.x_m is not None and route.y_m is not None:
        xy = (np.interp(s_sense, s_true, route.x_m), np.interp(s_sense, s_true, route.y_m))
    limit = None if route.speed_limit_mps is None else np.interp(s_sense, s_true, route.speed_limit_mps)
    if isinstance(cycle_s, bool) or not isinstance(cycle_s, (int, float)) or not (math.isfinite(cycle_s)
                                                                                  and 0 < cycle_s <= MAX_CYCLE_S):
        raise InputError(f"cycle_s = {cycle_s!r}: must be a number > 0 and at most {MAX_CYCLE_S:g} s ({CYCLE_WHY})")
    if route.length_m / (vehicle.max_speed_mps * cycle_s) > MAX_CYCLES:
        raise InputError(f"cycle_s = {cycle_s!r}: driving {route.length_m:g} m would take more than {MAX_CYCLES} "
                         f"cycles even at the top speed; use a cycle of at least "
                         f"{route.length_m / (vehicle.max_speed_mps * MAX_CYCLES):.3g} s")
    selector = SpeedSelector(vehicle, sensor_range_m=sensor_range_m, unseen=unseen, model=model,
                             segment_length_m=segment_length_m, roughness_window_m=roughness_window_m,
                             path_tolerance_m=path_tolerance_m, start_m=float(s_true[0]), end_m=float(s_true[-1]),
                             cycle_s=cycle_s, max_jerk_mps3=max_jerk_mps3, unseen_descent=unseen_descent)
    progress.expect(2)
    progress.step(f"driving {route.length_m:.0f} m with {sensor_range_m:g} m of sensing")
    pos, v = float(s_true[0]), 0.0
    revealed = 0
    knots_s, knots_v, knots_c = [pos], [v], [0]
    cyc_s, cyc_v, cyc_a, cyc_edge, cyc_edge_v, cyc_t = [], [], [], [], [], []
    emergencies, stuck = 0, 0
    end = float(s_true[-1])
    notes: list[str] = []
    for _ in range(MAX_CYCLES):
        if pos >= end - END_TOLERANCE_M and v <= REST_MPS:
            break
        t0 = time.perf_counter()
        upto = int(np.searchsorted(s_sense, pos + sensor_range_m, side="right"))
        if upto > revealed:
            part = slice(revealed, upto)
            selector.sense(s_sense[part], z_sense[part],
                           x_m=None if xy is None else xy[0][part], y_m=None if xy is None else xy[1][part],
                           speed_limit_mps=None if limit is None else limit[part])
            revealed = upto
        cmd = selector.update(pos, v)
        cyc_t.append(time.perf_counter() - t0)
        cyc_s.append(pos)
        cyc_v.append(v)
        cyc_a.append(cmd.accel_mps2)
        cyc_edge.append(cmd.edge_m)
        cyc_edge_v.append(cmd.edge_speed_mps)
        if cmd.emergency:
            emergencies += 1
            if emergencies == 1:
                notes.append(cmd.note)
        # the vehicle holds the command's acceleration for one cycle: v^2 linear in s
        if cmd.position_next_m <= pos + 1e-12:
            stuck += 1
            if stuck > max(100, int(10.0 / cycle_s)):
                raise InfeasibleError(
                    f"{route.source}: the vehicle stopped at {pos:.6g} m and no command moved it on for "
                    f"{stuck * cycle_s:.3g} s: a climb "
                    "steeper than its drive can hold, a descent too steep to brake on, or a cap of 0 m/s ahead; "
                    "'profileopt plan' on the route names the reason")
        else:
            stuck = 0
            knots_s.append(cmd.position_next_m)
            knots_v.append(cmd.speed_mps)
            knots_c.append(len(cyc_s))  # the next cycle starts here
        pos, v = cmd.position_next_m, cmd.speed_mps
        if pos > end:  # past the route's end (the selector could not stop in time): no terrain to drive on
            b_end = np.interp(end, [knots_s[-2], knots_s[-1]], [knots_v[-2] ** 2, knots_v[-1] ** 2])
            knots_s[-1], knots_v[-1] = end, math.sqrt(max(b_end, 0.0))
            notes.append(f"the vehicle reached the route's end at {knots_v[-1]:.4g} m/s, unable to stop there")
            break
    else:
        raise InputError(f"{route.source}: the drive took more than {MAX_CYCLES} cycles of {cycle_s:g} s; use a "
                         "longer --cycle or a shorter route")
    if selector.blind_m > 0:
        notes.append(f"{selector.blind_m:.4g} m of the route were never sensed with samples at most "
                     f"{selector.terrain.max_spacing_m:g} m apart: driven as unseen terrain")
    s_k, v_k, c_k = np.asarray(knots_s), np.asarray(knots_v), np.asarray(knots_c)
    keep = np.concatenate([[True], np.diff(s_k) > 1e-9])
    s_k, v_k, c_k = s_k[keep], v_k[keep], np.minimum(c_k[keep], len(cyc_s) - 1)
    if v_k[-1] == 0.0:
        s_k[-1] = end  # at rest within END_TOLERANCE_M of it
    progress.step("simulating the driven speed on the route")
    run = simulate_quarter_car(route.s_m, route.z_m, s_k, v_k, vehicle)
    windows = route_roughness_windows(route, vehicle, window_m=roughness_window_m)
    check = check_windows(route, run, v_k, vehicle, model=get_model(model).key, windows=windows)
    ratio = check.simulated_n / check.limit_n
    worst = int(np.argmax(ratio))
    accel = np.asarray(cyc_a)
    moving = np.asarray(cyc_v)[1:] > 0  # starting from rest: the acceleration at rest is 0
    jerk = float(np.max(np.abs(np.diff(accel))[moving], initial=0.0) / cycle_s) if accel.size > 1 else 0.0
    return Drive(s_m=s_k, speed_mps=v_k, time_s=boundary_times_s(s_k, v_k), knot_cycle=c_k,
                 cycle_s_m=np.asarray(cyc_s),
                 cycle_speed_mps=np.asarray(cyc_v), cycle_accel_mps2=accel, cycle_edge_m=np.asarray(cyc_edge),
                 cycle_edge_speed_mps=np.asarray(cyc_edge_v), cycle_compute_s=np.asarray(cyc_t),
                 emergencies=emergencies, travel_time_s=float(run.time_s[-1]),
                 worst_window_ratio=float(ratio[worst]), windows_over=int(np.sum(ratio > 1.0 + 1e-9)),
                 worst_s_m=float(check.peak_s_m[worst]), window_start_m=np.asarray(check.start_m, dtype=float),
                 window_ratio=ratio, max_jerk_mps3=jerk,
                 unseen_speed_mps=selector.unseen_speed_mps, notes=tuple(notes))


#: The columns of a drive CSV, in order.
DRIVE_COLUMNS = ("time_s", "s_m", "speed_mps", "accel_mps2", "edge_m", "edge_speed_mps")


def write_drive(drive: Drive, path: str | os.PathLike, *, settings: dict[str, object]) -> None:
    """Write a driven profile atomically: a settings comment line, the header, one row per knot.

    Each row is a knot of the driven profile (every cycle's start): the time (s), position (m)
    and speed (m/s) there, the constant acceleration driven to the next knot (m/s^2), and the
    planning edge (m) and the horizon's speed there (m/s) of the cycle being driven. Numbers
    have 9 significant digits.

    Parameters
    ----------
    drive : Drive
        The closed-loop drive (:func:`profileopt.online.drive`).
    path : str or os.PathLike
        Output file ('-': standard output, inside an :class:`~profileopt.io.atomic.OutputSet`).
    settings : dict
        What the drive was run with, written as ``key=value`` on the first line (``# drive:``).
    """
    cycle = drive.knot_cycle
    columns = (drive.time_s, drive.s_m, drive.speed_mps, drive.knot_accel_mps2(), drive.cycle_edge_m[cycle],
               drive.cycle_edge_speed_mps[cycle])
    table = np.column_stack([np.asarray(c, dtype=float) + 0.0 for c in columns])
    meta = " ".join(f"{key}={str(value).replace(' ', '_')}" for key, value in settings.items())
    with atomic_write(path) as handle:
        handle.write(f"# drive: {meta}\n")
        handle.write(",".join(DRIVE_COLUMNS) + "\n")
        handle.write("".join(",".join(f"{x:.9g}" for x in row) + "\n" for row in table.tolist()))
