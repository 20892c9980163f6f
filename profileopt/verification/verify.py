"""Check a plan against a simulated vehicle: the forces it really causes on the route.

:func:`verify` drives the vehicle's quarter car (:mod:`profileopt.physics.simulate`) over the
route's own elevation samples at the profile's speeds and judges the drive by roughness
windows (:mod:`profileopt.verification.window_check`): in every window [a, a + W] of the route, the
simulated peak force while the vehicle is inside it against the window's own prediction
and the limit. It also sets each segment's simulated peak force beside the segment's
prediction and the limit, as before the windows. The segment's prediction is
recomputed from the profile's speeds (the file's ``force_n`` column is not trusted), and
before the simulation :func:`profileopt.verification.limit_check.check_limits` checks the profile against the vehicle's own
limits, computed from :mod:`profileopt.physics` alone: speed, acceleration, jerk, turns,
power and predicted force. The force compared with the limit is the one the model limits: the transmitted force
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

from ..core.stations import segment_index
from ..core.vehicle import require_vehicle
from ..errors import InputError
from ..defaults import DEFAULT_PATH_TOLERANCE_M, DEFAULT_ROUGHNESS_WINDOW_M
from ..io.atomic import atomic_write
from ..physics.forces import get_model
from ..core.route import with_assumed_roughness
from .limit_check import LimitBreach, LimitCheck, check_limits, route_as_planned
from ..physics.motion import STANDARD_GRAVITY_MPS2  # the static wheel load m g
from ..physics.simulate import QuarterCarRun, simulate_quarter_car
from .window_check import UNDERPREDICTION_TOLERANCE, WindowCheck, check_windows

if TYPE_CHECKING:
    from ..core.profile import Profile
    from ..core.route import Route
    from ..core.vehicle import Vehicle

__all__ = ["Verification", "verify", "VERIFICATION_COLUMNS", "STANDARD_GRAVITY_MPS2", "estimated_peak_bytes",
           "check_memory", "MAX_VERIFY_PEAK_BYTES", "VERIFY_BASE_BYTES", "VERIFY_BYTES_PER_SAMPLE",
           "VERIFY_BYTES_PER_STEP"]

#: The memory ``verify`` needs (bytes), measured as the peak resident set of ``profileopt
#: verify`` on rough ``s,z`` routes of 40,000 to 400,000 samples 5 cm apart (issue 30): a fixed
#: part (the interpreter and the numerical packages), a part per route sample (the wheel's
#: path and the simulation's knots, about 4 per sample on rough ground, with their
#: temporaries: the peak is the simulation's; the roughness windows need about half as much)
#: and a part per time step of the simulation's uniform grid. A 40 MB route (2.3 million
#: samples) needs about 3.4 GB.
VERIFY_BASE_BYTES = 160e6
VERIFY_BYTES_PER_SAMPLE = 1_400
VERIFY_BYTES_PER_STEP = 420
#: The largest peak (bytes) ``verify`` starts by default: the 1.5 GB the documentation promises
#: for planning the largest route on rough ground (docs/guide/bad-input.md), so that a vehicle
#: computer with 2 GB that plans a route verifies it, or is told beforehand that it cannot.
#: About 820,000 samples (a 14 MB ``s,z`` file, 41 km at 5 cm) driven at 10 m/s.
MAX_VERIFY_PEAK_BYTES = 1.5e9

#: Columns of the verification CSV, in order.
VERIFICATION_COLUMNS = (
    "s_start_m", "s_end_m", "speed_start_mps", "speed_end_mps", "ri",
    "predicted_force_n", "force_limit_n",
    "sim_transmitted_peak_n", "sim_transmitted_up_n", "sim_transmitted_down_n", "sim_excitation_peak_n",
    "ratio", "over_limit", "lift_off",
    "window_start_m", "window_ri", "window_predicted_n", "window_sim_peak_n", "window_ratio", "window_over_limit",
)
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
        Each segment's RI (dimensionless), measured on the route (:attr:`LimitCheck.ri`;
        the profile's own, which it is compared with, when the windows are the profile's).
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
    windows : WindowCheck
        Every roughness window of the route, its prediction and its simulated peak.
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
        ``windows`` (judging every roughness window), ``total``.
    notes : tuple of str
        Remarks for the user (for example a profile limit that differs from the vehicle's).
    breaches : tuple of LimitBreach
        Where the profile breaks the vehicle's own limits on paper (:func:`check_limits`);
        empty when it keeps them all.
    checked, unchecked : tuple of str
        The bounds checked on paper and those not checked, in words
        (:attr:`LimitCheck.checked`, :attr:`LimitCheck.unchecked`).
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
    windows: WindowCheck
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
    checked: tuple[str, ...] = ()
    unchecked: tuple[str, ...] = ()

    @property
    def keeps_limits(self) -> bool:
        """True when the profile keeps every limit of the vehicle on paper (no breach)."""
        return not self.breaches

    @property
    def passes(self) -> bool:
        """True when it keeps every limit and no roughness window's (nor segment's) simulated
        force exceeds the limit."""
        return self.keeps_limits and self.windows.over_count == 0 and self.over_count == 0

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
            Route, vehicle, model, the worst segment and counts over the limit, the bounds
            checked on paper and not (``checked``, ``not_checked``), the
            roughness windows (``windows``: :meth:`WindowCheck.summary`, the count over the
            limit and the worst window), the simulation's step, the notes (and the timings).
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
            "windows": self.windows.summary(),
            "time_step_s": self.run.time_step_s,
            "steps": self.run.steps,
            "notes": list(self.notes),
            "keeps_limits": self.keeps_limits,
            "checked": list(self.checked),
            "not_checked": list(self.unchecked),
            "breaches": [b.to_dict() for b in self.breaches],
        } | ({"timings_s": dict(self.timings_s)} if timings else {})

    def columns(self) -> dict[str, np.ndarray]:
        """The CSV columns by name, in order (:data:`VERIFICATION_COLUMNS`).

        The ``window_*`` columns describe the worst of the roughness windows that share a
        point with the segment (:meth:`WindowCheck.worst_meeting`): a window over the limit
        shows in every segment it meets.
        """
        win = self.windows
        k = win.worst_meeting(self.s_m)
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
            "window_start_m": win.start_m[k],
            "window_ri": win.ri[k],
            "window_predicted_n": win.predicted_n[k],
            "window_sim_peak_n": win.simulated_n[k],
            "window_ratio": win.ratio[k],
            "window_over_limit": win.over[k].astype(int),
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


def estimated_peak_bytes(route: "Route", profile: "Profile", vehicle: "Vehicle") -> tuple[float, int]:
    """The memory :func:`verify` will need at its peak (bytes), and the simulation's time steps.

    Parameters
    ----------
    route : Route
        The route (its number of samples counts).
    profile : Profile
        The speeds (the travel time they give, not the file's ``time_s``, counts).
    vehicle : Vehicle
        Its natural frequency sets the simulation's time step.

    Returns
    -------
    (float, int)
        :data:`VERIFY_BASE_BYTES` + :data:`VERIFY_BYTES_PER_SAMPLE` per sample +
        :data:`VERIFY_BYTES_PER_STEP` per time step, and the steps (0 when the speeds give
        no finite travel time: the simulation refuses them itself).
    """
    from ..physics.simulate import boundary_times_s, choose_time_step_s

    with np.errstate(all="ignore"):
        total_s = float(boundary_times_s(np.asarray(profile.s_m, dtype=float),
                                         np.asarray(profile.speed_mps, dtype=float))[-1])
    steps = int(math.ceil(total_s / choose_time_step_s(vehicle.natural_frequency_radps))) if math.isfinite(
        total_s) and total_s < 1e12 else 0
    return VERIFY_BASE_BYTES + VERIFY_BYTES_PER_SAMPLE * route.s_m.size + VERIFY_BYTES_PER_STEP * steps, steps


def check_memory(route: "Route", profile: "Profile", vehicle: "Vehicle", max_peak_bytes: float | None,
                 fix: str = "pass max_peak_bytes") -> None:
    """Refuse, before any work, a verification whose estimated peak exceeds ``max_peak_bytes``.

    Parameters
    ----------
    route, profile, vehicle
        As for :func:`verify`.
    max_peak_bytes : float or None
        The largest peak allowed (bytes); None: no bound.
    fix : str, optional
        How to allow more, for the message.

    Raises
    ------
    InputError
        One line: the estimate, the samples and steps it comes from, the bound and the fix.
    """
    if max_peak_bytes is None:
        return
    peak, steps = estimated_peak_bytes(route, profile, vehicle)
    if peak > max_peak_bytes:
        raise InputError(
            f"{route.source}: verifying it needs about {peak / 1e9:.2g} GB of memory ({route.s_m.size:,} route "
            f"samples at {VERIFY_BYTES_PER_SAMPLE / 1e3:g} kB, {steps:,} simulation steps at "
            f"{VERIFY_BYTES_PER_STEP / 1e3:g} kB), more than the {max_peak_bytes / 1e9:g} GB allowed; on a machine "
            f"with more memory {fix}")


def verify(
    route: "Route",
    profile: "Profile",
    vehicle: "Vehicle",
    *,
    model: str | None = None,
    detrend: bool = True,
    check: LimitCheck | None = None,
    roughness_seed: int = 0,
    max_jerk_mps3: float | None = None,
    path_tolerance_m: float | None = DEFAULT_PATH_TOLERANCE_M,
    roughness_window_m: float = DEFAULT_ROUGHNESS_WINDOW_M,
    max_peak_bytes: float | None = MAX_VERIFY_PEAK_BYTES,
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
        Datum of the excitation force: each window's (and, per segment, each segment's)
        least-squares line of the base input (True, as the RI) or mean (False).
    check : LimitCheck, optional
        The result of :func:`check_limits` for the same arguments, if already computed.
    roughness_seed : int, default 0
        For a route with an assumed roughness (:attr:`Route.assumed_roughness`), whose own
        elevation (a DEM or GPS profile) cannot show it: the seed (>= 0) of the random
        ISO 8608 profile added to the route's elevation for the simulation
        (:meth:`~profileopt.terrain.assumed.AssumedRoughness.realisation_m`), whose RMS
        window roughness is the assumed one. A note says so. Unused for other routes.
    max_jerk_mps3, path_tolerance_m, roughness_window_m
        The bounds checked (:func:`check_limits`): by default the vehicle's jerk limit, the
        path tolerance estimated from the route and 5 m windows, whatever the profile's
        settings record (notes say where they differ). Unused when ``check`` is given.
    max_peak_bytes : float or None, default MAX_VERIFY_PEAK_BYTES (1.5 GB)
        Refuse, before any work, when :func:`estimated_peak_bytes` exceeds it (None: no
        bound). Memory grows with the route's samples and the simulation's steps.

    Returns
    -------
    Verification

    Raises
    ------
    InputError
        The profile does not cover the route exactly, its RI column does not match the
        route's segments (another route, or a vehicle with another ground clearance), a
        segment is never crossed (speed 0 at both of its ends), a speed is too large to
        simulate, the model is unknown, or it would need more memory than ``max_peak_bytes``.
    """
    vehicle = require_vehicle(vehicle, "verify")
    check_memory(route, profile, vehicle, max_peak_bytes)
    t_start = time.perf_counter()
    if check is None:
        check = check_limits(route, profile, vehicle, model=model, max_jerk_mps3=max_jerk_mps3,
                             path_tolerance_m=path_tolerance_m, roughness_window_m=roughness_window_m)
    route, _ = route_as_planned(route, profile)  # the roughness it was planned with (check_limits notes it)
    force_model = get_model(check.model)
    s = np.asarray(profile.s_m, dtype=float)
    notes = check.notes
    if route.assumed_roughness is not None:  # drive ground like the one planned for, not the smooth model
        route, note = with_assumed_roughness(route, vehicle, window_m=check.windows.window_m, seed=roughness_seed)
        notes += (note,)
    run = simulate_quarter_car(route.s_m, route.z_m, s, profile.speed_mps, vehicle, detrend=detrend)
    t_sim = time.perf_counter()

    seg = segment_index(run.s_m, s)
    starts = np.searchsorted(seg, np.arange(s.size - 1), side="left")
    up = np.maximum.reduceat(run.transmitted_n, starts)
    down = np.minimum.reduceat(run.transmitted_n, starts)
    simulated = run.transmitted_peak_n if force_model.quantity == "transmitted" else run.excitation_peak_n
    limit_n = np.full(s.size - 1, check.limit_n)
    windows = check_windows(route, run, profile.speed_mps, vehicle, model=force_model.key, windows=check.windows,
                            detrend=detrend)
    t_end = time.perf_counter()
    return Verification(
        s_m=s.copy(),
        speed_mps=np.asarray(profile.speed_mps, dtype=float).copy(),
        ri=check.ri.copy(),  # the route's (the profile's own when they are compared)
        predicted_n=simulated.copy() if force_model.key == "dynamic" else check.predicted_n.copy(),
        limit_n=limit_n,
        transmitted_peak_n=run.transmitted_peak_n,
        transmitted_up_n=up,
        transmitted_down_n=down,
        excitation_peak_n=run.excitation_peak_n,
        simulated_n=simulated,
        ratio=simulated / limit_n,
        windows=windows,
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
            "windows": t_end - t_sim,
            "total": t_end - t_start,
        },
        notes=notes,
        breaches=check.breaches,
        checked=check.checked,
        unchecked=check.unchecked,
    )
