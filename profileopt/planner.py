"""The minimum-time speed profile along a route under per-segment force limits.

The route is cut into segments; each segment's roughness gives, through the chosen force
model, the *bands* of admissible speeds (:func:`profileopt.speeds.speed_bands`). Inside a
segment the vehicle passes through every speed between its entry and exit speeds, so the
force limit holds over the whole segment exactly when both boundary speeds lie in one band
of that segment (NOTES.md, "Which root"). The planner therefore

1. chooses one band per segment for the whole route at once: the greatest feasible
   assignment, which is also the fastest (see :func:`choose_bands`);
2. computes the exact minimum-time profile for those bands and the acceleration bounds by a
   vectorised forward-backward pass (:func:`greatest_profile`); with smoothing and jerk off
   that is already the optimum;
3. polishes it with IPOPT on the nonlinear program in the squared speed b = v^2 at the
   segment boundaries (Verscheure et al. 2009): travel time plus a smoothness term, subject
   to the band bounds, the acceleration bounds and the jerk bound.

If IPOPT fails, a profile that keeps every limit (the forward-backward profile with the
acceleration bounds lowered far enough that the jerk bound holds) is returned instead, with
the solver's status, and the command line says so.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import time
from pathlib import Path
from typing import TYPE_CHECKING

import casadi as ca
import numpy as np

from ._io import atomic_write
from ._nlp import build_nlp
from ._pieces import choose_cuts, cut_multipliers, cut_scores, piece_bounds, replace_cuts, wrong_cuts
from .errors import InfeasibleError, InputError, PlanningError
from .forces import MODELS, get_model
from .kinematics import boundary_jerk_mps3, jerk_squared_time, segment_accel_mps2, segment_time_s
from .speeds import SpeedBands, speed_bands
from .terrain import segment_roughness_index, worst_case_elevation
from .vehicle import vehicle_reference

if TYPE_CHECKING:
    from .route import Route
    from .vehicle import Vehicle

__all__ = [
    "BandChoice",
    "Segments",
    "Profile",
    "PlanningError",
    "segment_route",
    "choose_bands",
    "greatest_profile",
    "plan",
    "read_profile",
    "PROFILE_COLUMNS",
    "MIN_SAMPLES_PER_SEGMENT",
    "DEFAULT_SMOOTHING",
]

#: A segment's RI is a standard deviation: with fewer samples it means little.
MIN_SAMPLES_PER_SEGMENT = 8
#: Weight of the jerk term: objective = time + w * integral (jerk / (1 m/s^3))^2 dt, both in s.
DEFAULT_SMOOTHING = 0.01
#: Columns of a profile CSV, in order.
PROFILE_COLUMNS = ("s_m", "speed_mps", "accel_mps2", "time_s", "ri", "e_max_m", "force_n", "force_limit_n")
#: Relative tolerance of the independent constraint check of every returned profile.
_CHECK_RTOL = 1e-6


@dataclasses.dataclass(frozen=True, eq=False)
class Segments:
    """A route cut into segments, with each segment's roughness and speed caps.

    Attributes
    ----------
    boundaries_m : numpy.ndarray, shape (N+1,)
        Segment boundaries s_i (m); segment i covers s_i <= s < s_{i+1}, the last one closed.
    length_m : numpy.ndarray, shape (N,)
        Segment lengths (m).
    ri : numpy.ndarray, shape (N,)
        Detrended RI of each segment's own samples (dimensionless).
    e_max_m : numpy.ndarray, shape (N,)
        Worst-case elevation of Eq. (8) (m).
    speed_cap_mps : numpy.ndarray, shape (N,)
        min(v_max, the route's speed_limit over the segment's samples) (m/s).
    samples : numpy.ndarray of int, shape (N,)
        Number of route samples in each segment.
    notes : tuple of str
        Decisions taken while segmenting (e.g. a short tail merged into its neighbour).
    """

    boundaries_m: np.ndarray
    length_m: np.ndarray
    ri: np.ndarray
    e_max_m: np.ndarray
    speed_cap_mps: np.ndarray
    samples: np.ndarray
    notes: tuple[str, ...] = ()

    @property
    def count(self) -> int:
        """Number of segments N."""
        return int(self.length_m.size)


def segment_route(route: "Route", vehicle: "Vehicle", segment_length_m: float = 5.0) -> Segments:
    """Cut a route into segments of ``segment_length_m`` and measure each one's roughness.

    Parameters
    ----------
    route : Route
    vehicle : Vehicle
        Supplies h (for the RI), Pe (for e_max) and v_max.
    segment_length_m : float, default 5
        Segment length (m), > 0 and at most the route's length. The last segment takes what
        is left; if that tail holds fewer than ``MIN_SAMPLES_PER_SEGMENT`` samples it is
        merged into the segment before it (noted in ``Segments.notes``).

    Returns
    -------
    Segments

    Raises
    ------
    InputError
        A bad segment length, or a segment with fewer than ``MIN_SAMPLES_PER_SEGMENT``
        samples (the message says what sample spacing is needed).
    """
    length = float(segment_length_m)
    total = route.length_m
    if not (math.isfinite(length) and length > 0):
        raise InputError(f"--segment-length = {segment_length_m!r} m: must be a number > 0")
    if length > total * (1 + 1e-12):
        raise InputError(
            f"--segment-length = {length:g} m is longer than the route {route.source} ({total:g} m); "
            "choose a shorter segment length"
        )
    s, z = route.s_m, route.z_m
    if total / length > s.size:  # more segments than samples: refuse before allocating them
        raise InputError(
            f"--segment-length = {length:g} m cuts {route.source} ({total:g} m, {s.size} samples) into more "
            f"segments than it can fill with {MIN_SAMPLES_PER_SEGMENT} samples each; use at least "
            f"{MIN_SAMPLES_PER_SEGMENT * total / s.size:.3g} m"
        )
    n_full = max(int(math.floor(total / length + 1e-9)), 1)
    bounds = s[0] + length * np.arange(n_full + 1)
    if total - n_full * length > 1e-9 * max(total, 1.0):
        bounds = np.append(bounds, s[-1])
    bounds[-1] = s[-1]
    starts = np.searchsorted(s, bounds[:-1], side="left")
    counts = np.diff(np.append(starts, s.size))
    notes: tuple[str, ...] = ()
    if counts.size > 1 and counts[-1] < MIN_SAMPLES_PER_SEGMENT:
        notes = (
            f"the last {bounds[-1] - bounds[-2]:.3g} m hold only {counts[-1]} samples; "
            "merged into the segment before them",
        )
        bounds = np.delete(bounds, -2)
        starts = starts[:-1]
        counts = np.diff(np.append(starts, s.size))
    thin = np.flatnonzero(counts < MIN_SAMPLES_PER_SEGMENT)
    if thin.size:
        i = thin[0]
        spacing = length / MIN_SAMPLES_PER_SEGMENT
        raise InputError(
            f"{route.source}: segment {i} ({bounds[i]:g} to {bounds[i + 1]:g} m) holds {counts[i]} samples; "
            f"measuring roughness needs at least {MIN_SAMPLES_PER_SEGMENT}: sample the route every "
            f"{spacing:.3g} m or closer, or raise --segment-length"
        )
    ri = segment_roughness_index(s, z, starts, vehicle.ground_clearance_m)
    cap = np.full(starts.size, vehicle.max_speed_mps)
    if route.speed_limit_mps is not None:
        cap = np.minimum(cap, np.minimum.reduceat(route.speed_limit_mps, starts))
    return Segments(
        boundaries_m=bounds,
        length_m=np.diff(bounds),
        ri=ri,
        e_max_m=worst_case_elevation(ri, vehicle),
        speed_cap_mps=cap,
        samples=counts,
        notes=notes,
    )


def greatest_profile(
    lower_b: np.ndarray, upper_b: np.ndarray, length_m: np.ndarray, accel_mps2: float, decel_mps2: float
) -> np.ndarray:
    """The pointwise-greatest squared-speed profile within bounds and acceleration limits.

    Solves b_j <= upper_b[j], b_{j+1} - b_j <= 2 a ds_j, b_j - b_{j+1} <= 2 d ds_j exactly
    (a forward and a backward pass, each a min-plus prefix scan done with
    ``numpy.minimum.accumulate``; O(N)). Among all profiles meeting these constraints it is
    greatest at every boundary, hence of least travel time; it is feasible for the lower
    bounds too iff any profile is (check ``result >= lower_b``).

    Parameters
    ----------
    lower_b, upper_b : numpy.ndarray, shape (N+1,)
        Bounds on b = v^2 at the boundaries (m^2/s^2); ``lower_b`` is not used here.
    length_m : numpy.ndarray, shape (N,)
        Segment lengths (m).
    accel_mps2, decel_mps2 : float
        Acceleration and deceleration bounds (m/s^2, both > 0).

    Returns
    -------
    numpy.ndarray, shape (N+1,)
        b (m^2/s^2).
    """
    del lower_b  # the greatest solution does not depend on the lower bounds
    up = np.concatenate([[0.0], np.cumsum(2.0 * accel_mps2 * length_m)])
    forward = up + np.minimum.accumulate(upper_b - up)
    down = np.concatenate([[0.0], np.cumsum(2.0 * decel_mps2 * length_m)])
    backward = np.minimum.accumulate((forward + down)[::-1])[::-1] - down
    return np.minimum(forward, backward)


@dataclasses.dataclass(frozen=True)
class BandChoice:
    """The band of admissible speeds chosen for each segment, and what follows from it.

    Attributes
    ----------
    lower_b, upper_b : numpy.ndarray, shape (N+1,)
        Bounds on the squared speed b = v^2 at each boundary (m^2/s^2): the intersection
        of the chosen bands of the segments on either side (and v0, vend at the ends).
    band : numpy.ndarray of int, shape (N,)
        Index of the chosen band of each segment (0 = lowest).
    greatest_b : numpy.ndarray, shape (N+1,)
        The exact minimum-time squared-speed profile for these bands (m^2/s^2).
    """

    lower_b: np.ndarray
    upper_b: np.ndarray
    band: np.ndarray
    greatest_b: np.ndarray


def _boundary_bounds(lo: np.ndarray, hi: np.ndarray, v0: float, vend: float) -> tuple[np.ndarray, np.ndarray]:
    """Per-boundary bounds on b from the bands of the segments on either side."""
    lo2, hi2 = lo**2, hi**2
    lower = np.concatenate([[v0**2], np.maximum(lo2[:-1], lo2[1:]), [vend**2]])
    upper = np.concatenate([[v0**2], np.minimum(hi2[:-1], hi2[1:]), [vend**2]])
    lower[0], lower[-1] = max(lower[0], lo2[0]), max(lower[-1], lo2[-1])
    upper[0], upper[-1] = min(upper[0], hi2[0]), min(upper[-1], hi2[-1])
    return lower, upper


def choose_bands(
    bands_lower_mps: np.ndarray,
    bands_upper_mps: np.ndarray,
    count: np.ndarray,
    length_m: np.ndarray,
    accel_mps2: float,
    decel_mps2: float,
    v0_mps: float,
    vend_mps: float,
    where: np.ndarray,
) -> BandChoice:
    """Choose one admissible speed band per segment, for the whole route at once.

    Bands are ordered, so raising a segment's band raises both its lower and upper speed.
    Raising upper bounds only raises the greatest profile, so if two band assignments are
    feasible their componentwise maximum is feasible too, and it is at least as fast. There
    is thus one greatest feasible assignment, and it is the fastest. It is found by starting
    every segment in its highest band and lowering, round after round, each segment whose
    lower bound the greatest profile cannot reach: a segment lowered that way is above its
    band in every feasible assignment, so no feasible choice is ever lost.

    This is what an experienced driver does on washboard: accelerate on smooth ground to
    above resonance, hold the upper band over the corrugations, and slow down below
    resonance only where something ahead (a stop, rougher ground) forces it.

    Parameters
    ----------
    bands_lower_mps, bands_upper_mps : numpy.ndarray, shape (N, B)
        Band edges (m/s) per segment, NaN-padded, already capped by the speed limits.
    count : numpy.ndarray of int, shape (N,)
        Number of bands per segment.
    length_m : numpy.ndarray, shape (N,)
    accel_mps2, decel_mps2 : float
    v0_mps, vend_mps : float
        Boundary speeds (m/s).
    where : numpy.ndarray, shape (N+1,)
        Boundary positions (m), for messages.

    Raises
    ------
    InfeasibleError
        No assignment keeps every limit; the message says where and why.
    """
    n = count.size
    rows = np.arange(n)
    empty = np.flatnonzero(count == 0)
    if empty.size:
        i = empty[0]
        raise InfeasibleError(
            f"segment {i} ({where[i]:g} to {where[i + 1]:g} m): the predicted force exceeds the limit "
            "at every speed, so the route cannot be driven; choose another route or a vehicle with a "
            "higher force limit"
        )
    band = count - 1
    tol = 1e-9 * max(float(np.nanmax(bands_upper_mps)) ** 2, 1.0)
    while True:
        lo, hi = bands_lower_mps[rows, band], bands_upper_mps[rows, band]
        lower, upper = _boundary_bounds(lo, hi, v0_mps, vend_mps)
        b = greatest_profile(lower, upper, length_m, accel_mps2, decel_mps2)
        short = b < lower - tol
        if not short.any():
            standstill = np.flatnonzero((b[:-1] <= tol) & (b[1:] <= tol))
            if standstill.size:  # v = 0 at both ends: constant acceleration never moves
                i = standstill[0]
                raise InfeasibleError(
                    f"segment {i} ({where[i]:g} to {where[i + 1]:g} m) would have to start and end at "
                    "0 m/s, so it can never be driven; use shorter segments (--segment-length) or "
                    "nonzero --v0/--vend"
                )
            return BandChoice(lower_b=lower, upper_b=upper, band=band.copy(), greatest_b=np.maximum(b, lower))
        j = np.flatnonzero(short)
        # the segments on either side of boundary j whose own lower edge is out of reach
        left = j[j > 0] - 1
        right = j[j < n]
        culprits = np.unique(np.concatenate([left[lo[left] ** 2 > b[left + 1] + tol],
                                             right[lo[right] ** 2 > b[right] + tol]]))
        lowerable = culprits[band[culprits] > 0]
        if lowerable.size == 0:
            raise InfeasibleError(_infeasible_message(int(j[0]), b, lower, where, v0_mps, vend_mps,
                                                      (bands_lower_mps, bands_upper_mps, count)))
        band[lowerable] -= 1


def _bands_text(lower_mps: np.ndarray, upper_mps: np.ndarray, count: int) -> str:
    """The admissible speed bands of one segment, e.g. "[0, 0.32] and [0.53, 3.39] m/s"."""
    parts = [f"[{lower_mps[k]:.3g}, {upper_mps[k]:.3g}]" for k in range(count)]
    return " and ".join(parts) + " m/s"


def _infeasible_message(j: int, b: np.ndarray, lower: np.ndarray, where: np.ndarray, v0: float, vend: float,
                        bands: tuple[np.ndarray, np.ndarray, np.ndarray]) -> str:
    """Why boundary j cannot be reached, named from the segments' full band lists ``bands``
    (lower edges (N, B), upper edges (N, B), counts (N,)), not from the lowered assignment."""
    n = where.size - 1
    reach = math.sqrt(max(b[j], 0.0))
    if j in (0, n):
        i, flag, speed = (0, "--v0", v0) if j == 0 else (n - 1, "--vend", vend)
        lo_row, hi_row, cnt = bands[0][i], bands[1][i], int(bands[2][i])
        where_text = "first" if j == 0 else "last"
        inside = [k for k in range(cnt) if lo_row[k] - 1e-12 <= speed <= hi_row[k] + 1e-12]
        if cnt == 1:  # one band from rest: the plain story of speed limits and braking
            if speed > hi_row[0]:
                return (f"{flag} = {speed:g} m/s is above the allowable speed {hi_row[0]:.3g} m/s of the "
                        f"{where_text} segment; {'start' if j == 0 else 'end'} slower")
            if j == 0:
                return (f"starting at --v0 = {speed:g} m/s the vehicle cannot brake in time for the limits "
                        f"ahead (it can only be at {reach:.3g} m/s); start slower or raise max_decel_mps2")
            return (f"the route cannot end at --vend = {speed:g} m/s: the vehicle can reach only {reach:.3g} "
                    "m/s there; lower --vend or raise max_accel_mps2")
        if not inside:
            return (f"{flag} = {speed:g} m/s is not an admissible speed of the {where_text} segment, whose "
                    f"admissible speeds are {_bands_text(lo_row, hi_row, cnt)}; choose {flag} in one of them")
        if j == 0:
            return (f"starting at --v0 = {speed:g} m/s (in the band [{lo_row[inside[0]]:.3g}, "
                    f"{hi_row[inside[0]]:.3g}] m/s of the first segment) the vehicle cannot meet the limits "
                    f"ahead: it can only be at {reach:.3g} m/s there (braking in time, or leaving the band "
                    "would pass through speeds the force limit forbids); start at another speed or raise "
                    "max_decel_mps2")
        return (f"the route cannot end at --vend = {speed:g} m/s (in the band [{lo_row[inside[0]]:.3g}, "
                f"{hi_row[inside[0]]:.3g}] m/s of the last segment): the vehicle can only be at {reach:.3g} "
                "m/s there (reaching that band would pass through speeds the force limit forbids, or "
                "needs more acceleration); choose another --vend or raise max_accel_mps2")
    return (f"at s = {where[j]:g} m the speed must be at least {math.sqrt(lower[j]):.3g} m/s but the "
            f"acceleration bounds allow only {reach:.3g} m/s; relax --v0/--vend or the vehicle's "
            "acceleration limits")


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
        ``"optimal"`` (IPOPT converged), ``"exact"`` (the forward-backward profile is the
        optimum: smoothing and jerk off), ``"fallback: <IPOPT status>"`` (IPOPT failed; the
        returned profile keeps every limit but is not optimal) or ``"read"`` (from a file).
    success : bool
        True unless the fallback was used.
    model : str
        Force model key.
    objective : float
        Travel time plus smoothing term (s), as minimised.
    timings_s : dict
        Wall-clock seconds of the stages (``segment``, ``bands``, ``choose``, ``build``,
        ``solve``, ``total``).
    iterations : int
        IPOPT iterations (0 if not run), of all its solves together.
    pieces : int
        How many IPOPT solves make up the profile: 1 for a route solved whole, more for a
        long route solved in pieces (exactly; see :data:`SPLIT_ABOVE_SEGMENTS`), 0 if none.
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
        max_accel_mps2, max_decel_mps2, max_jerk_mps3, v0_mps, vend_mps, method. Written
        into the CSV's first (comment) line and read back by :func:`read_profile`.
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
    model: str = "sbem_tf"
    objective: float = float("nan")
    timings_s: dict = dataclasses.field(default_factory=dict)
    iterations: int = 0
    pieces: int = 0
    notes: tuple[str, ...] = ()
    allowable_first_mps: np.ndarray | None = None
    allowable_largest_mps: np.ndarray | None = None
    speed_cap_mps: np.ndarray | None = None
    band_lower_mps: np.ndarray | None = None
    band_upper_mps: np.ndarray | None = None
    settings: dict = dataclasses.field(default_factory=dict)

    @property
    def travel_time_s(self) -> float:
        """Time to drive the whole route (s)."""
        return float(self.time_s[-1])

    @property
    def distance_m(self) -> float:
        """Length of the route (m)."""
        return float(self.s_m[-1] - self.s_m[0])

    def columns(self) -> dict[str, np.ndarray]:
        """The CSV columns by name, in order."""
        return {name: getattr(self, name) for name in PROFILE_COLUMNS}

    def to_csv(self, path: str | Path) -> None:
        """Write the profile CSV atomically (columns :data:`PROFILE_COLUMNS`).

        Numbers are written with 17 significant digits (``%.17g``), so reading the file
        back gives the same floats and the same input gives the same bytes.
        """
        table = np.column_stack(list(self.columns().values()))
        meta = " ".join(f"{k}={_format_setting(v)}" for k, v in self.settings.items())
        with atomic_write(path) as handle:
            handle.write(f"# profileopt profile: {meta} status={self.status.replace(' ', '_')}\n")
            handle.write(",".join(PROFILE_COLUMNS) + "\n")
            np.savetxt(handle, table, delimiter=",", fmt="%.17g")


def _format_setting(value: object) -> str:
    if isinstance(value, float):
        return repr(value)
    return str(value).replace(" ", "_")


def read_profile(path: str | Path) -> Profile:
    """Read a profile CSV written by :meth:`Profile.to_csv`.

    Raises
    ------
    InputError
        Missing file, wrong header, non-numeric or non-finite cells, or s not increasing.
    """
    path = Path(path)
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except FileNotFoundError:
        raise InputError(f"{path}: profile file not found; check the path") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"{path}: cannot read the profile file ({exc})") from None
    settings: dict[str, object] = {}
    settings_line = 1
    for number, line in enumerate(lines, start=1):
        if line.startswith("# profileopt profile:"):
            settings_line = number
            for item in line.split(":", 1)[1].split():
                key, _, value = item.partition("=")
                settings[key] = value
    # (file line number, text) of the lines that are neither blank nor comments
    lines = [(n, ln) for n, ln in enumerate(lines, start=1) if ln.strip() and not ln.lstrip().startswith("#")]
    if not lines:
        raise InputError(f"{path}: the profile file is empty; write one with 'profileopt plan -o'")
    header_line, header_text = lines[0]
    header = tuple(c.strip() for c in header_text.split(","))
    if header != PROFILE_COLUMNS:
        raise InputError(f"{path}: line {header_line}: header must be {','.join(PROFILE_COLUMNS)}; "
                         f"got {','.join(header)} (write the profile with 'profileopt plan -o')")
    rows = []
    for number, line in lines[1:]:
        cells = [c.strip() for c in line.split(",")]
        if len(cells) != len(PROFILE_COLUMNS):
            raise InputError(f"{path}: line {number}: {len(cells)} cells but the header has "
                             f"{len(PROFILE_COLUMNS)}; make every row match the header")
        for name, cell in zip(PROFILE_COLUMNS, cells):
            try:
                value = float(cell)
            except ValueError:
                raise InputError(f"{path}: line {number}: {name} = '{cell}' is not a number; "
                                 "every cell must be a number in SI units") from None
            if not math.isfinite(value):
                raise InputError(f"{path}: line {number}: {name} = {cell} is not a finite number; "
                                 "give a finite number")
        rows.append([float(c) for c in cells])
    numbers = [n for n, _ in lines[1:]]
    if len(rows) < 2:
        raise InputError(f"{path}: {len(rows)} data row(s); a profile needs at least 2 (the start and the end "
                         "of the route)")
    table = np.array(rows)
    bad = np.flatnonzero(np.diff(table[:, 0]) <= 0)
    if bad.size:
        i = bad[0] + 1
        raise InputError(f"{path}: line {numbers[i]}: s_m = {table[i, 0]:g} m does not increase (previous "
                         f"{table[i - 1, 0]:g} m); s_m must increase strictly, so sort the rows or drop duplicates")
    bad = np.flatnonzero(table[:, 1] < 0)
    if bad.size:
        i = bad[0]
        raise InputError(f"{path}: line {numbers[i]}: speed_mps = {table[i, 1]:g} m/s is negative; "
                         "speeds must be >= 0")
    model = str(settings.get("model", "sbem_tf"))
    if model not in MODELS:
        raise InputError(f"{path}: line {settings_line}: model={model} is unknown; it must be one of "
                         f"{', '.join(MODELS)}")
    return Profile(**{name: table[:, i] for i, name in enumerate(PROFILE_COLUMNS)}, model=model,
                   settings=settings)


# ---------------------------------------------------------------------------------------
# The nonlinear program, built once per (size, jerk on/off) and re-solved with parameters.


@dataclasses.dataclass(frozen=True)
class _Nlp:
    solver: ca.Function
    n: int
    with_jerk: bool


@functools.lru_cache(maxsize=8)
def _build_nlp(n: int, with_jerk: bool) -> _Nlp:
    """The NLP for N = n segments, built once per size (:func:`profileopt._nlp.build_nlp`).

    Variables y = b / b_ref (b = v^2) at the N+1 boundaries; parameters: segment lengths /
    L_ref (n), then b_ref, L_ref, a_ref, T_ref, the smoothing weight and 1/J; constraints
    a_i / a_ref and, with jerk, jerk_j / J; objective (travel time + weight * integral
    jerk^2 dt) / T_ref. Its build time hardly grows with n (stage Functions mapped over the
    segments, their exact derivatives supplied to IPOPT).
    """
    return _Nlp(solver=build_nlp(n, with_jerk), n=n, with_jerk=with_jerk)


# ---------------------------------------------------------------------------------------
# Planning


def _validate_options(vehicle: "Vehicle", model: str, segment_length_m: float, smoothing: float,
                      max_jerk_mps3: float, v0_mps: float, vend_mps: float) -> None:
    try:
        get_model(model)
    except ValueError as exc:
        raise InputError(f"--model: {exc}") from None
    if not (math.isfinite(smoothing) and smoothing >= 0):
        raise InputError(f"--smoothing = {smoothing!r}: must be a finite number >= 0 (0 is pure minimum time)")
    if math.isnan(max_jerk_mps3) or not max_jerk_mps3 > 0:
        raise InputError(f"--max-jerk = {max_jerk_mps3!r} m/s^3: must be > 0 ('inf' turns the jerk limit off)")
    for flag, value in (("--v0", v0_mps), ("--vend", vend_mps)):
        if not (math.isfinite(value) and value >= 0):
            raise InputError(f"{flag} = {value!r} m/s: must be a finite speed >= 0")
        if value > vehicle.max_speed_mps:
            raise InputError(f"{flag} = {value:g} m/s is above the vehicle's max_speed_mps = "
                             f"{vehicle.max_speed_mps:g} m/s; give a lower boundary speed")


def _max_force_over_segments(model: str, vehicle: "Vehicle", ri: np.ndarray, speed: np.ndarray,
                             peaks: np.ndarray) -> np.ndarray:
    """Largest predicted force (N) over the speeds between each segment's end speeds."""
    lo = np.minimum(speed[:-1], speed[1:])[:, None]
    hi = np.maximum(speed[:-1], speed[1:])[:, None]
    inside = (peaks >= lo) & (peaks <= hi)
    candidates = np.concatenate([lo, hi, np.where(inside, peaks, lo)], axis=1)
    forces = get_model(model).force_n(candidates, np.broadcast_to(ri[:, None], candidates.shape), vehicle)
    return forces.max(axis=1)


def _violations(b: np.ndarray, lower: np.ndarray, upper: np.ndarray, length_m: np.ndarray,
                accel: float, decel: float, jerk: float) -> dict[str, float]:
    """Largest relative violation of each constraint by the squared speeds b (0 if none)."""
    scale_b = max(float(upper.max()), 1.0)
    a = segment_accel_mps2(b[:-1], b[1:], length_m)
    out = {
        "speed": float(max(np.max(lower - b), np.max(b - upper), 0.0)) / scale_b,
        "accel": float(max(np.max(a - accel), np.max(-decel - a), 0.0)) / accel,
        "jerk": 0.0,
    }
    if math.isfinite(jerk) and length_m.size >= 2:
        j = boundary_jerk_mps3(np.sqrt(np.maximum(b[1:-1], 0.0)), a[:-1], a[1:], length_m[:-1], length_m[1:])
        out["jerk"] = float(max(np.max(np.abs(j)) - jerk, 0.0)) / jerk
    return out


def plan(
    route: "Route",
    vehicle: "Vehicle",
    *,
    segment_length_m: float = 5.0,
    model: str = "sbem_tf",
    smoothing: float = DEFAULT_SMOOTHING,
    max_jerk_mps3: float | None = None,
    v0_mps: float = 0.0,
    vend_mps: float = 0.0,
    method: str = "auto",
    bands: str = "all",
) -> Profile:
    """The fastest smooth speed profile along ``route`` that keeps every limit.

    Parameters
    ----------
    route : Route
    vehicle : Vehicle
    segment_length_m : float, default 5
        Length of the segments whose roughness is measured (m).
    model : str, default ``"sbem_tf"``
        Force model: ``"sbem_tf"``, ``"sbem_ef"``, ``"iecm"`` or ``"prev_bem"``.
    smoothing : float, default :data:`DEFAULT_SMOOTHING` (0.01)
        Weight w of the comfort term: the objective is travel time + w * integral of
        (jerk / 1 m/s^3)^2 dt, both in seconds. 0 is pure minimum time.
    max_jerk_mps3 : float, optional
        Jerk bound (m/s^3); ``None`` takes the vehicle's ``max_jerk_mps3``, ``inf`` turns
        it off.
    v0_mps, vend_mps : float, default 0
        Speed at the start and at the end of the route (m/s).
    method : {"auto", "ipopt"}, default "auto"
        ``"auto"`` returns the exact forward-backward profile without running IPOPT when it
        is provably optimal (smoothing 0 and no jerk bound); ``"ipopt"`` always solves the
        NLP (for benchmarks and tests of the NLP itself).
    bands : {"all", "first"}, default "all"
        ``"all"`` lets each segment use any band of admissible speeds, chosen over the whole
        route (a resonant vehicle may cross washboard above resonance); ``"first"`` keeps
        every segment in its band that starts at rest (NOTES.md "first" semantics: safe for
        a vehicle that may have to slow down anywhere).

    Returns
    -------
    Profile
        ``status`` says how it was obtained; a profile is never returned that breaks a
        force, speed, acceleration or jerk limit.

    Raises
    ------
    InputError
        Bad options or a route too sparsely sampled for its segments.
    InfeasibleError
        No profile keeps every limit (an impassable segment, unreachable boundary speeds).
    PlanningError
        IPOPT failed and no limit-keeping fallback profile exists (please report it).
    """
    t_start = time.perf_counter()
    jerk = vehicle.max_jerk_mps3 if max_jerk_mps3 is None else float(max_jerk_mps3)
    _validate_options(vehicle, model, segment_length_m, smoothing, jerk, v0_mps, vend_mps)
    if method not in ("auto", "ipopt"):
        raise InputError(f"--method = {method!r}: choose 'auto' or 'ipopt'")
    if bands not in ("all", "first"):
        raise InputError(f"--bands = {bands!r}: choose 'all' or 'first'")
    timings: dict[str, float] = {}
    seg = segment_route(route, vehicle, segment_length_m)
    timings["segment"] = time.perf_counter() - t_start

    t = time.perf_counter()
    speed_sets = speed_bands(seg.ri, vehicle, model)
    all_bands = speed_sets.capped(seg.speed_cap_mps)  # every band, for reports and messages
    usable = speed_sets.first_band_only().capped(seg.speed_cap_mps) if bands == "first" else all_bands
    lower_mps, upper_mps, count = usable.lower_mps, usable.upper_mps, usable.count
    timings["bands"] = time.perf_counter() - t

    t = time.perf_counter()
    a_max, d_max = vehicle.max_accel_mps2, vehicle.max_decel_mps2
    args = (lower_mps, upper_mps, count, seg.length_m)
    try:
        chosen = choose_bands(*args, a_max, d_max, v0_mps, vend_mps, seg.boundaries_m)
    except InfeasibleError as exc:  # name the route, as every input message does
        raise InfeasibleError(f"{route.source}: {exc}") from None
    timings["choose"] = time.perf_counter() - t

    notes = list(seg.notes)
    iterations = pieces = 0
    exact = method == "auto" and smoothing == 0 and not math.isfinite(jerk)
    if exact:
        b, status, success = chosen.greatest_b, "exact", True
    else:
        result = _solve_nlp(seg, chosen, vehicle, smoothing, jerk)
        b, status, iterations, pieces = result.b, result.status, result.iterations, result.pieces
        timings.update(result.timings)
        success = status == "optimal"
        if success:
            worst = _violations(b, chosen.lower_b, chosen.upper_b, seg.length_m, a_max, d_max, jerk)
            if max(worst.values()) > _CHECK_RTOL:
                status, success = f"solution breaks a limit ({max(worst, key=worst.get)})", False
        if not success:
            notes.append(f"IPOPT gave no usable solution ({status}); returning a slower profile that keeps "
                         "every limit")
            chosen = _fallback(args, vehicle, jerk, v0_mps, vend_mps, seg)
            b = chosen.greatest_b
            status, pieces = f"fallback: {status}", 0
    b = np.clip(b, chosen.lower_b, chosen.upper_b) if success else b
    profile = _assemble(seg, b, vehicle, model, speed_sets, all_bands, lower_mps, upper_mps, chosen)
    worst_force = float(np.max(profile.force_n / profile.force_limit_n))
    if worst_force > 1.0 + _CHECK_RTOL:  # the bands promise this; never hand back a breach
        raise PlanningError(
            f"{route.source}: the planned profile reaches {worst_force:.4g} times the force limit although "
            "every speed was taken from the admissible bands; please report this with the route and vehicle"
        )
    settings = {
        "vehicle": vehicle_reference(vehicle) or "unnamed", "model": model,
        "segment_length_m": float(segment_length_m), "smoothing": float(smoothing),
        "max_speed_mps": vehicle.max_speed_mps, "max_accel_mps2": a_max, "max_decel_mps2": d_max,
        "max_jerk_mps3": jerk,
        "v0_mps": float(v0_mps), "vend_mps": float(vend_mps), "method": method, "bands": bands,
    }
    timings["total"] = time.perf_counter() - t_start
    return dataclasses.replace(
        profile, status=status, success=success, objective=_objective(b, seg.length_m, smoothing),
        timings_s=timings, iterations=iterations, pieces=pieces, notes=tuple(notes), settings=settings,
    )


def _objective(b: np.ndarray, length_m: np.ndarray, smoothing: float) -> float:
    """Travel time plus the smoothing term (s) of a squared-speed profile, exactly."""
    v = np.sqrt(np.maximum(b, 0.0))
    travel = float(np.sum(segment_time_s(v[:-1], v[1:], length_m)))
    if length_m.size < 2 or smoothing == 0:
        return travel
    a = segment_accel_mps2(b[:-1], b[1:], length_m)
    return travel + smoothing * float(np.sum(jerk_squared_time(v[1:-1], a[:-1], a[1:], length_m[:-1], length_m[1:])))


#: A route of more segments than this is solved in pieces (:data:`PIECE_SEGMENTS`). IPOPT's
#: time per segment and iteration is flat up to about 10,000 segments and grows beyond, as
#: its working set leaves the cache; pieces cost more iterations in all (each converges on
#: its own). Measured on the benchmark routes (2-core machine): whole and pieces equal at
#: 10,000 segments (within noise), pieces 5 % faster at 15,000, 15 % at 20,000, 30 % at 100,000.
SPLIT_ABOVE_SEGMENTS = 10_000

#: Most segments in one piece of a long route: pieces are cut at bottlenecks where the
#: optimum is pinned and checked to be exact (:mod:`profileopt._pieces`), and every piece
#: is solved with the one NLP of this size (built once, padded with fixed variables).
#: On the 100,000-segment benchmark route, pieces of 3,000 to 6,000 segments took the same
#: time within noise (plan 5.8-6.3 s), pieces of 10,000 took 7.2 s.
PIECE_SEGMENTS = 4000


@dataclasses.dataclass(frozen=True)
class _NlpResult:
    b: np.ndarray  # (N+1,) squared speeds, m^2/s^2
    status: str
    iterations: int  # IPOPT iterations, all solves together
    pieces: int  # IPOPT solves whose solutions make up b
    timings: dict[str, float]


@dataclasses.dataclass(frozen=True)
class _Scaling:
    """The NLP's parameters after the segment lengths, shared by every solve of one plan."""

    b_ref: float
    l_ref: float
    a_ref: float
    weight: float
    inv_jerk: float
    t_whole: float  # T_ref of the whole route: the greatest profile's travel time (s)

    def tail(self, t_ref: float) -> np.ndarray:
        return np.array([self.b_ref, self.l_ref, self.a_ref, t_ref, self.weight, self.inv_jerk])


def _ipopt(nlp: _Nlp, x0: np.ndarray, lbx: np.ndarray, ubx: np.ndarray, length_scaled: np.ndarray,
           lbg: np.ndarray, ubg: np.ndarray, p_tail: np.ndarray) -> tuple[np.ndarray, np.ndarray, bool, str, int]:
    """One IPOPT solve, all in scaled units: (y, lam_g, success, status, iterations)."""
    result = nlp.solver(x0=x0, lbx=lbx, ubx=ubx, lbg=lbg, ubg=ubg, p=np.concatenate([length_scaled, p_tail]))
    stats = nlp.solver.stats()
    success = bool(stats.get("success", False))
    status = "optimal" if success else str(stats.get("return_status", "failed"))
    return (np.asarray(result["x"]).ravel(), np.asarray(result["lam_g"]).ravel(), success, status,
            int(stats.get("iter_count", 0)))


def _row_bounds(n: int, with_jerk: bool, vehicle: "Vehicle", a_ref: float) -> tuple[np.ndarray, np.ndarray]:
    """Bounds on the rows of the n-segment NLP: a_i / a_ref (n), then jerk_j / J (n-1)."""
    lbg, ubg = [np.full(n, -vehicle.max_decel_mps2 / a_ref)], [np.full(n, 1.0)]
    if with_jerk and n >= 2:
        lbg.append(np.full(n - 1, -1.0))
        ubg.append(np.full(n - 1, 1.0))
    return np.concatenate(lbg), np.concatenate(ubg)


def _solve_nlp(seg: Segments, chosen: BandChoice, vehicle: "Vehicle", smoothing: float,
               jerk: float) -> _NlpResult:
    """IPOPT's optimum over the chosen bands: in pieces on a long route (exact, checked), or
    whole (a short route, or a long one whose cuts do not check out)."""
    n = seg.count
    with_jerk = math.isfinite(jerk)
    scaling = _Scaling(b_ref=max(float(chosen.upper_b.max()), 1e-6), l_ref=float(seg.length_m.mean()),
                       a_ref=vehicle.max_accel_mps2, weight=smoothing,
                       inv_jerk=1.0 / jerk if with_jerk else 0.0,
                       t_whole=max(_objective(chosen.greatest_b, seg.length_m, 0.0), 1e-6))
    timings = {"build": 0.0, "solve": 0.0}
    iterations = 0
    if n > max(SPLIT_ABOVE_SEGMENTS, PIECE_SEGMENTS):
        score = cut_scores(chosen.upper_b, chosen.greatest_b, seg.length_m)
        cuts = choose_cuts(score, PIECE_SEGMENTS)
        if cuts.size:
            b, iterations, pieces = _solve_pieces(seg, chosen, vehicle, scaling, with_jerk, score, cuts, timings)
            if b is not None:
                return _NlpResult(b, "optimal", iterations, pieces, timings)

    t = time.perf_counter()
    nlp = _build_nlp(n, with_jerk)
    timings["build"] += time.perf_counter() - t
    t = time.perf_counter()
    b_ref = scaling.b_ref
    lbg, ubg = _row_bounds(n, nlp.with_jerk, vehicle, scaling.a_ref)
    y, _, _, status, spent = _ipopt(nlp, chosen.greatest_b / b_ref, chosen.lower_b / b_ref, chosen.upper_b / b_ref,
                                    seg.length_m / scaling.l_ref, lbg, ubg, scaling.tail(scaling.t_whole))
    timings["solve"] += time.perf_counter() - t
    return _NlpResult(y * b_ref, status, iterations + spent, 1, timings)


#: How many times the cuts that did not check out are replaced before the route is solved whole.
_CUT_ROUNDS = 5


def _solve_pieces(seg: Segments, chosen: BandChoice, vehicle: "Vehicle", scaling: _Scaling, with_jerk: bool,
                  score: np.ndarray, cuts: np.ndarray, timings: dict[str, float]) -> tuple[np.ndarray | None, int, int]:
    """The NLP solved piece by piece between the fixed pairs at ``cuts`` (see
    :mod:`profileopt._pieces`), each piece in the one NLP of :data:`PIECE_SEGMENTS`
    segments: the piece's boundaries, then (behind it, or in front of the last piece)
    padding boundaries fixed at the neighbouring fixed speed, whose rows are unbounded and
    whose terms involve fixed variables only. A cut that is not a KKT point of the whole
    problem, or beside a piece IPOPT cannot solve, is replaced by another between its
    neighbours (or, if there is none, the cuts from the one before it onwards are chosen
    again without it) and the changed pieces are solved again. Returns (b, iterations,
    pieces); b is None when no set of cuts checks out within :data:`_CUT_ROUNDS` rounds.
    """
    n, w = seg.count, PIECE_SEGMENTS
    t = time.perf_counter()
    nlp = _build_nlp(w, with_jerk)
    check = _build_nlp(5, with_jerk).solver
    grad_f, jac_g = check.get_function("nlp_grad_f"), check.get_function("nlp_jac_g")
    timings["build"] += time.perf_counter() - t
    t = time.perf_counter()
    b_ref, l_ref = scaling.b_ref, scaling.l_ref
    lower, upper, start_b = chosen.lower_b / b_ref, chosen.upper_b / b_ref, chosen.greatest_b / b_ref
    length = seg.length_m / l_ref
    t_whole = scaling.t_whole
    lbg_real, ubg_real = _row_bounds(w, nlp.with_jerk, vehicle, scaling.a_ref)
    solved: dict[tuple[int, int], tuple[np.ndarray, np.ndarray, np.ndarray]] = {}
    iterations, cuts, tried = 0, cuts.copy(), set()

    def solve(first: int, last: int) -> bool:
        nonlocal iterations
        count, is_first, is_last = last - first, first == 0, last == n
        offset = w - count if is_last else 0  # the last piece is padded in front, the others behind
        real = slice(offset, offset + count + 1)
        x0, lbx, ubx = (np.full(w + 1, upper[first] if is_last else upper[last]) for _ in range(3))
        x0[real], lbx[real], ubx[real] = start_b[first:last + 1], lower[first:last + 1], upper[first:last + 1]
        fixed = ([] if is_first else [first, first + 1]) + ([] if is_last else [last - 1, last])
        for k in fixed:  # the cut pairs, at their caps
            lbx[offset + k - first] = ubx[offset + k - first] = x0[offset + k - first] = upper[k]
        p_length = np.ones(w)
        p_length[offset:offset + count] = length[first:last]
        lbg, ubg = np.full(lbg_real.size, -np.inf), np.full(ubg_real.size, np.inf)
        accel_rows = slice(offset, offset + count)
        jerk_rows = slice(w + offset, w + offset + count - 1)  # interior boundaries offset+1 .. offset+count-1
        lbg[accel_rows], ubg[accel_rows] = lbg_real[accel_rows], ubg_real[accel_rows]
        if nlp.with_jerk:
            lbg[jerk_rows], ubg[jerk_rows] = lbg_real[jerk_rows], ubg_real[jerk_rows]
        t_ref = max(_objective(chosen.greatest_b[first:last + 1], seg.length_m[first:last], 0.0), 1e-6)
        y, lam_g, success, _, spent = _ipopt(nlp, x0, lbx, ubx, p_length, lbg, ubg, scaling.tail(t_ref))
        iterations += spent
        if success:
            rescale = t_ref / t_whole  # multipliers of f / t_ref, expressed for f / t_whole
            solved[first, last] = (y[real], lam_g[accel_rows] * rescale, lam_g[jerk_rows] * rescale)
        return success

    a_cut = segment_accel_mps2(chosen.upper_b[:-1], chosen.upper_b[1:], seg.length_m)  # between fixed pairs
    row_inside = (a_cut < vehicle.max_accel_mps2 * (1 - 1e-9)) & (-a_cut < vehicle.max_decel_mps2 * (1 - 1e-9))
    try:
        for round_ in range(_CUT_ROUNDS + 1):
            pieces = piece_bounds(cuts, n)
            failed = [i for i, (first, last) in enumerate(pieces) if not ((first, last) in solved or solve(first, last))]
            if failed:  # a piece IPOPT cannot solve: the cuts beside it are suspect
                wrong = np.array(sorted({c for i in failed for c in (i - 1, i) if 0 <= c < cuts.size}), dtype=int)
            else:
                y, lam_accel = np.empty(n + 1), np.zeros(n)
                lam_jerk = np.zeros(n + 1) if nlp.with_jerk else None
                for first, last in pieces:
                    y[first:last + 1], lam_accel[first:last], lam_piece_jerk = solved[first, last]
                    if lam_jerk is not None:
                        lam_jerk[first + 1:last] = lam_piece_jerk
                lam_accel[cuts] = 0.0  # the rows between fixed pairs (checked inactive below)
                lam_x, scale = cut_multipliers(grad_f, jac_g, y, scaling.tail(t_whole), length, lam_accel,
                                               lam_jerk, cuts)
                pair = np.stack([cuts, cuts + 1], axis=1)
                wrong = wrong_cuts(lam_x, scale, lower[pair] < upper[pair], row_inside[cuts])
                if wrong.size == 0:
                    return y * b_ref, iterations, len(pieces)
            if round_ == _CUT_ROUNDS:
                break
            tried.update(int(k) for k in cuts[wrong])
            cuts = replace_cuts(score, cuts, wrong, w, tried)
            if cuts.size == 0:
                break
        return None, iterations, 0
    finally:
        timings["solve"] += time.perf_counter() - t


def _fallback(args: tuple, vehicle: "Vehicle", jerk: float, v0: float, vend: float, seg: Segments) -> BandChoice:
    """A profile that keeps every limit: forward-backward with acceleration bounds so low
    that the jerk bound holds at every boundary whatever the pattern of accelerations.

    With |a| <= a' everywhere, |a_j - a_{j-1}| <= 2 a', so jerk = v da/ds <= v_top 2 a' /
    ds_min <= J when a' = J ds_min / (2 v_top).
    """
    a, d = vehicle.max_accel_mps2, vehicle.max_decel_mps2
    if math.isfinite(jerk):
        v_top = float(np.nanmax(args[1]))
        cap = jerk * float(seg.length_m.min()) / (2.0 * max(v_top, 1e-9))
        a, d = min(a, cap), min(d, cap)
    try:
        chosen = choose_bands(*args, a, d, v0, vend, seg.boundaries_m)
    except InfeasibleError as exc:
        raise PlanningError(f"IPOPT failed and no jerk-limited fallback exists ({exc})") from None
    return chosen


def _assemble(seg: Segments, b: np.ndarray, vehicle: "Vehicle", model: str, bands: SpeedBands,
              all_bands: SpeedBands, lower_mps: np.ndarray, upper_mps: np.ndarray, chosen: BandChoice) -> Profile:
    """The Profile of squared speeds b: per-row arrays, the largest force per segment, and
    the allowable speeds under both semantics from ``all_bands`` (every band, capped)."""
    speed = np.sqrt(np.maximum(b, 0.0))
    accel = segment_accel_mps2(b[:-1], b[1:], seg.length_m)
    dt = segment_time_s(speed[:-1], speed[1:], seg.length_m)
    time_s = np.concatenate([[0.0], np.cumsum(dt)])
    force = _max_force_over_segments(model, vehicle, seg.ri, speed, bands.peaks_mps)
    rows = np.arange(seg.count)
    first, largest = all_bands.first(), all_bands.largest()

    def per_row(x: np.ndarray) -> np.ndarray:
        return np.append(x, x[-1])

    return Profile(
        s_m=seg.boundaries_m,
        speed_mps=speed,
        accel_mps2=per_row(accel),
        time_s=time_s,
        ri=per_row(seg.ri),
        e_max_m=per_row(seg.e_max_m),
        force_n=per_row(force),
        force_limit_n=np.full(seg.count + 1, get_model(model).limit_n(vehicle)),
        model=model,
        allowable_first_mps=first,
        allowable_largest_mps=largest,
        speed_cap_mps=seg.speed_cap_mps,
        band_lower_mps=lower_mps[rows, chosen.band],
        band_upper_mps=upper_mps[rows, chosen.band],
    )


def jerk_mps3(profile: Profile) -> np.ndarray:
    """Jerk v da/ds at the interior boundaries (m/s^3), shape (N-1,)."""
    ds = np.diff(profile.s_m)
    a = profile.accel_mps2[:-1]
    return boundary_jerk_mps3(profile.speed_mps[1:-1], a[:-1], a[1:], ds[:-1], ds[1:])


def summarize(profile: Profile) -> dict:
    """A short account of a planned profile, for people and for ``--json``.

    Returns
    -------
    dict
        ``distance_m``, ``travel_time_s``, ``mean_speed_mps``; ``slowest_segment`` (index,
        ``s_start_m``, ``s_end_m``, ``top_speed_mps``, ``ri`` and ``reason``: which limit
        holds the vehicle back there; of the segments whose top speed is held by a limit,
        the slowest, so not the run-up from rest); ``margins`` (the largest ratio of each constrained
        quantity to its limit, and where: force, acceleration, deceleration, jerk); and
        ``solver`` (status, success, iterations, time_s). Plain Python numbers only.
    """
    n = profile.s_m.size - 1
    settings = profile.settings
    spec = get_model(profile.model)
    v = profile.speed_mps
    top = np.maximum(v[:-1], v[1:])
    accel = profile.accel_mps2[:-1]
    tol = 1e-6 * max(float(v.max()), 1.0)
    # The slowest segment that a limit holds back (its speed reaches its band's upper edge);
    # the run-up from rest and the final braking are slow too, but tell nothing.
    held = np.flatnonzero(top >= profile.band_upper_mps - tol) if profile.band_upper_mps is not None \
        else np.empty(0, dtype=int)
    i = int(held[np.argmin(top[held])]) if held.size else int(np.argmin(top))
    a_max = float(settings.get("max_accel_mps2", math.nan))
    d_max = float(settings.get("max_decel_mps2", math.nan))
    j_max = float(settings.get("max_jerk_mps3", math.inf))
    reason = "the acceleration, jerk and smoothing terms"
    if profile.band_upper_mps is not None and top[i] >= profile.band_upper_mps[i] - tol:
        cap = profile.speed_cap_mps[i] if profile.speed_cap_mps is not None else math.inf
        if profile.band_upper_mps[i] >= cap - tol:
            top_speed = float(settings.get("max_speed_mps", math.inf))
            reason = "the vehicle's top speed" if cap >= top_speed - tol else f"the route's speed_limit ({cap:.3g} m/s)"
        else:
            reason = f"the {spec.label} force limit ({spec.quantity}, {profile.force_limit_n[i]:g} N) at RI {profile.ri[i]:.3f}"
            if profile.allowable_largest_mps is not None and profile.band_upper_mps[i] < profile.allowable_largest_mps[i] - tol:
                reason += (f", held below resonance: the faster band up to {profile.allowable_largest_mps[i]:.3g} m/s "
                           "cannot be entered or left in time")
    elif math.isfinite(a_max) and accel[i] >= a_max * (1 - 1e-6):
        reason = "accelerating at max_accel_mps2 (from a slower point before it)"
    elif math.isfinite(d_max) and -accel[i] >= d_max * (1 - 1e-6):
        reason = "braking at max_decel_mps2 (for a slower point after it)"

    def worst(values: np.ndarray, limit: float, where: np.ndarray) -> dict:
        # None: the constraint is off, or never used (no segment accelerates, say)
        if values.size == 0 or not math.isfinite(limit) or values.max() <= 0:
            return {"ratio": None, "s_m": None}
        k = int(np.argmax(values))
        return {"ratio": float(values[k] / limit), "s_m": float(where[k])}

    force_ratio = profile.force_n[:-1] / profile.force_limit_n[:-1]
    k = int(np.argmax(force_ratio))
    return {
        "distance_m": profile.distance_m,
        "travel_time_s": profile.travel_time_s,
        "mean_speed_mps": profile.distance_m / profile.travel_time_s if profile.travel_time_s > 0 else 0.0,
        "segments": n,
        "model": profile.model,
        "slowest_segment": {
            "index": i, "s_start_m": float(profile.s_m[i]), "s_end_m": float(profile.s_m[i + 1]),
            "top_speed_mps": float(top[i]), "ri": float(profile.ri[i]), "reason": reason,
        },
        "margins": {
            "force": {"ratio": float(force_ratio[k]), "s_m": float(profile.s_m[k])},
            "accel": worst(accel, a_max, profile.s_m[:-1]),
            "decel": worst(-accel, d_max, profile.s_m[:-1]),
            "jerk": worst(np.abs(jerk_mps3(profile)), j_max, profile.s_m[1:-1]),
        },
        "solver": {
            "status": profile.status, "success": profile.success, "iterations": profile.iterations,
            "pieces": profile.pieces,
            "time_s": float(profile.timings_s.get("total", math.nan)),
        },
        "notes": list(profile.notes),
    }
