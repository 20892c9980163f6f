"""Speed bands chosen for a whole route, and the exact minimum-time profile within them.

Each segment's admissible speeds are one or more *bands* (the force model's, capped by the
speed limits). Inside a segment the vehicle passes through every speed between its entry
and exit speeds, so a limit that holds for every speed of a band holds over the whole
segment when both boundary speeds lie in one band of that segment (docs/paper-notes.md,
"Which root"). :func:`choose_bands` picks one band per segment for the whole route at once
(the greatest feasible assignment, which is also the fastest) and :func:`greatest_profile`
is the exact minimum-time profile for those bands and the acceleration bounds: with
smoothing and jerk off it is the optimum.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..errors import InfeasibleError

__all__ = ["BandChoice", "DrivePower", "boundary_bounds", "braking_profile", "choose_bands", "greatest_profile",
           "snap_to_band",
           "BOUNDARY_SNAP_RTOL"]

#: A boundary speed (v0_mps, vend_mps) this close to an admissible band, relative to the
#: band edge (or 1e-9 m/s near rest), is taken as that edge: a speed copied from a band
#: edge that another plan printed, or rounded in the last digits, must not fail on rounding.
BOUNDARY_SNAP_RTOL = 1e-6


@dataclasses.dataclass(frozen=True, eq=False)
class DrivePower:
    """The drive power limit as the forward pass sees it.

    In segment i, at constant acceleration a_i, the power m (a_i + g sin theta) v <= P must
    hold at every speed driven and every grade of the segment: at its higher speed and its
    steepest grade, a_i <= P / (m max(v_i, v_{i+1})) - g sin(theta_hi,i)
    (:func:`profileopt.physics.motion.power_accel_mps2`).

    Attributes
    ----------
    power_per_mass_w_per_kg : float
        P / m (W/kg = m^2/s^3).
    grade_hi_rad : numpy.ndarray, shape (N,)
        The steepest grade of each segment (rad).
    """

    power_per_mass_w_per_kg: float
    grade_hi_rad: np.ndarray

    def longest_exact_segment_m(self) -> np.ndarray:
        """Per segment, the longest segment (m) for which the forward pass is exact, shape (N,).

        Slowing down at the power limit over a segment of length ds, the largest exit speed
        b_i + 2 ds (P/m / sqrt(b_i) - g sin theta) falls as the entry speed b_i rises below
        (ds P/m)^(2/3); the steady climbing speed P / (m g sin theta) lies in that region when
        ds (g sin theta)^3 > (P/m)^2. There, entering faster can end slower, the feasible set
        is no longer a lattice, and the forward pass (which enters as fast as it may) can stall
        where a slower entry would climb. Segments up to (P/m)^2 / (g sin theta)^3 keep it
        exact (inf on the level and downhill).
        """
        from ..physics.motion import STANDARD_GRAVITY_MPS2

        lift = STANDARD_GRAVITY_MPS2 * np.sin(self.grade_hi_rad)
        with np.errstate(divide="ignore"):
            return np.where(lift > 0, self.power_per_mass_w_per_kg**2 / np.maximum(lift, 1e-300) ** 3, np.inf)


def _power_step(b_i: float, ds: float, pm: float, gs: float) -> float:
    """The largest b_{i+1} that the power limit allows after b_i over a segment of length ds
    (m), with P/m = ``pm`` and g sin(theta_hi) = ``gs``: exact for constant acceleration.

    Speeding up (b_{i+1} >= b_i), the limit binds at v_{i+1} = u:
    (u^2 - b_i) / (2 ds) + gs <= pm / u, i.e. u^3 + (2 ds gs - b_i) u - 2 ds pm <= 0, whose
    left side has one positive root (it is -2 ds pm < 0 at 0 and convex for u > 0): found by
    Newton's method from above, which converges monotonically on a convex increasing branch.
    If that root is below sqrt(b_i), the vehicle slows down and the limit binds at v_i:
    b_{i+1} <= b_i + 2 ds (pm / sqrt(b_i) - gs).
    """
    b_i = max(b_i, 0.0)
    c, k = 2.0 * ds * gs - b_i, 2.0 * ds * pm
    u = k ** (1.0 / 3.0) + math.sqrt(max(-c, 0.0))  # f(u) >= 0 here (see above)
    for _ in range(60):
        f = u * u * u + c * u - k
        step = f / (3.0 * u * u + c)
        u -= step
        if abs(step) <= 1e-15 * u:
            break
    if u * u >= b_i:
        return u * u
    return b_i + 2.0 * ds * (pm / math.sqrt(b_i) - gs)


def _forward_with_power(lower_b: np.ndarray, upper_b: np.ndarray, length_m: np.ndarray, accel_mps2: np.ndarray,
                        power: DrivePower) -> np.ndarray:
    """The forward pass b_{i+1} <= min(upper, b_i + 2 a ds, power step), in order.

    On a segment longer than :meth:`DrivePower.longest_exact_segment_m` the exit speed that
    the power allows can fall as the entry speed rises (entering above the steady climbing
    speed P / (m g sin theta), the vehicle slows down all the way at the power limit), down to
    a stall. Where entering at b_i would end below what the next boundary needs
    (``lower_b``, and at least rest), the pass enters slower if that ends faster: at the best
    of the entry speeds :func:`_best_entry` names, never below the boundary's own lower bound,
    lowering b_i, and the backward pass then brakes into it. So a climb that a slower entry
    makes is not refused. Elsewhere it enters as fast as it may, which is faster over the
    segment itself; either way the profile keeps every limit but may not be the fastest there
    (the planner says so).
    """
    from ..physics.motion import STANDARD_GRAVITY_MPS2

    n = length_m.size
    accel = np.broadcast_to(np.asarray(accel_mps2, dtype=float), (n,))
    gs = STANDARD_GRAVITY_MPS2 * np.sin(power.grade_hi_rad)
    pm = float(power.power_per_mass_w_per_kg)
    coarse = length_m > power.longest_exact_segment_m()
    out = np.empty(n + 1)
    b = out[0] = upper_b[0]
    for i in range(n):
        ds, a_i, gs_i, top = float(length_m[i]), float(accel[i]), float(gs[i]), float(upper_b[i + 1])
        nxt = _exit_b(b, top, ds, a_i, pm, gs_i)
        if coarse[i] and nxt < max(float(lower_b[i + 1]), 0.0):
            for entry in _best_entry(b, float(lower_b[i]), a_i, pm, gs_i):
                exit_b = _exit_b(entry, top, ds, a_i, pm, gs_i)
                if exit_b > nxt:
                    out[i], nxt = entry, exit_b
        out[i + 1] = b = nxt
    return out


def _exit_b(b: float, top: float, ds: float, accel: float, pm: float, gs: float) -> float:
    """The largest b_{i+1} (m^2/s^2) after entering a segment of length ``ds`` (m) at b
    (m^2/s^2): within the bound ``top``, the acceleration bound ``accel`` (m/s^2) and the
    power limit (P/m = ``pm``, g sin(theta_hi) = ``gs``)."""
    nxt = min(top, b + 2.0 * accel * ds)
    # the power row at the higher of the two speeds: skip the root where it holds
    a = (nxt - b) / (2.0 * ds)
    if (a + gs) > 0.0 and (a + gs) * math.sqrt(max(nxt, b, 0.0)) > pm:
        nxt = min(nxt, _power_step(b, ds, pm, gs))
    return nxt


def _best_entry(b: float, lowest: float, accel: float, pm: float, gs: float) -> tuple[float, ...]:
    """The entry speeds in [``lowest``, b) (m^2/s^2) at which a slower entry can end a segment
    faster than entering at b, with P/m = ``pm``, g sin(theta_hi) = ``gs`` and the acceleration
    bound ``accel`` (m/s^2).

    As a function of the entry x, the exit is min(x + 2 a ds, F(x)), with F the power step
    (:func:`_power_step`): increasing up to the steady climbing speed x_s = (P / (m g sin
    theta))^2, where F(x) = x; above it the vehicle slows down at the power limit and F falls,
    then rises again. Where a < 0 the line x + 2 a ds (increasing) crosses the falling F at
    x_c = (P/m / (a + g sin theta))^2 > x_s, a local maximum of the exit (for a >= 0, x_c <=
    x_s, on the rising part). So over [lowest, b] the exit is greatest at b, at ``lowest`` (the
    boundary's own lower bound: an entry must keep it), at x_s or at x_c: the candidates
    returned (those in [lowest, b)).
    """
    if gs <= 0.0:
        return ()
    lowest = max(lowest, 0.0)
    candidates = [lowest, (pm / gs) ** 2]
    if accel + gs > 0.0:
        candidates.append((pm / (accel + gs)) ** 2)
    return tuple(x for x in candidates if lowest <= x < b)


def greatest_profile(
    lower_b: np.ndarray, upper_b: np.ndarray, length_m: np.ndarray, accel_mps2: float, decel_mps2: float,
    power: DrivePower | None = None,
) -> np.ndarray:
    """The pointwise-greatest squared-speed profile within bounds and acceleration limits.

    Solves b_j <= upper_b[j], b_{j+1} - b_j <= 2 a ds_j, b_j - b_{j+1} <= 2 d ds_j exactly
    (a forward and a backward pass, each a min-plus prefix scan done with
    ``numpy.minimum.accumulate``; O(N)). Among all profiles meeting these constraints it is
    greatest at every boundary, hence of least travel time; it is feasible for the lower
    bounds too iff any profile is (check ``result >= lower_b``).

    With a drive power limit (``power``) the forward pass also keeps, in each segment,
    a <= P / (m v_max) - g sin(theta_hi) (:class:`DrivePower`), solved exactly step by step
    (a loop in Python: about 3 us per segment). On segments no longer than
    :meth:`DrivePower.longest_exact_segment_m` the constraint keeps the feasible set a lattice
    (b_{i+1} <= F_i(b_i) with F_i increasing), so the greatest profile still exists and is
    found by repeating the two passes until neither changes it (once in practice); on longer
    ones the result keeps every limit but may not be the fastest (the planner says so), and
    where entering a climb fast would stall short of ``lower_b``, it enters slower
    (:func:`_forward_with_power`).

    Parameters
    ----------
    lower_b, upper_b : numpy.ndarray, shape (N+1,)
        Bounds on b = v^2 at the boundaries (m^2/s^2); ``lower_b`` is used only with
        ``power``, on segments too long for the power limit to keep the profile greatest.
    length_m : numpy.ndarray, shape (N,)
        Segment lengths (m).
    accel_mps2, decel_mps2 : float or numpy.ndarray, shape (N,)
        Acceleration and deceleration bounds (m/s^2), for all segments or each. On a grade
        either may be negative: a climb steeper than the drive can hold forces a slowdown
        (accel < 0), a descent steeper than the brakes can hold a speed-up (decel < 0).
    power : DrivePower, optional
        The drive power limit, if any.

    Returns
    -------
    numpy.ndarray, shape (N+1,)
        b (m^2/s^2).
    """
    if power is None:
        up = np.concatenate([[0.0], np.cumsum(2.0 * accel_mps2 * length_m)])
        forward = up + np.minimum.accumulate(upper_b - up)
        return np.minimum(forward, braking_profile(forward, length_m, decel_mps2))
    b = np.asarray(upper_b, dtype=float)
    for _ in range(100):
        forward = _forward_with_power(lower_b, b, length_m, accel_mps2, power)
        backward = np.minimum(forward, braking_profile(forward, length_m, decel_mps2))
        if np.array_equal(backward, b):
            break
        b = backward
    return b


def braking_profile(upper_b: np.ndarray, length_m: np.ndarray, decel_mps2: float | np.ndarray) -> np.ndarray:
    """The greatest squared-speed profile within bounds from which every later bound can still be
    met braking within the deceleration bounds: the backward pass of :func:`greatest_profile`.

    Solves b_j <= upper_b[j] and b_j - b_{j+1} <= 2 d_j ds_j exactly (a min-plus suffix scan).

    Parameters
    ----------
    upper_b : numpy.ndarray, shape (N+1,)
        Bounds on b = v^2 at the boundaries (m^2/s^2).
    length_m : numpy.ndarray, shape (N,)
        Segment lengths (m).
    decel_mps2 : float or numpy.ndarray, shape (N,)
        Deceleration bounds (m/s^2).

    Returns
    -------
    numpy.ndarray, shape (N+1,)
        b (m^2/s^2).
    """
    down = np.concatenate([[0.0], np.cumsum(2.0 * decel_mps2 * length_m)])
    return np.minimum.accumulate((upper_b + down)[::-1])[::-1] - down


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

    def violation(self, b: np.ndarray) -> float:
        """Largest violation of the chosen bands by squared speeds ``b``, relative to the
        highest upper bound (0 if none).

        Parameters
        ----------
        b : numpy.ndarray, shape (N+1,)
            Squared speeds at the boundaries (m^2/s^2).

        Returns
        -------
        float
        """
        scale_b = max(float(self.upper_b.max()), 1.0)
        return float(max(np.max(self.lower_b - b), np.max(b - self.upper_b), 0.0)) / scale_b


def boundary_bounds(lo: np.ndarray, hi: np.ndarray, v0: float, vend: float) -> tuple[np.ndarray, np.ndarray]:
    """Per-boundary bounds on b = v^2 from the chosen bands of the segments on either side.

    Parameters
    ----------
    lo, hi : numpy.ndarray, shape (N,)
        Lower and upper edge of each segment's chosen band (m/s).
    v0, vend : float
        Speeds at the start and at the end of the route (m/s).

    Returns
    -------
    lower, upper : numpy.ndarray, shape (N+1,)
        Bounds on b at the boundaries (m^2/s^2).
    """
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
    power: DrivePower | None = None,
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
        Segment lengths (m).
    accel_mps2, decel_mps2 : float or numpy.ndarray, shape (N,)
        Acceleration and deceleration bounds (m/s^2, both > 0).
    v0_mps, vend_mps : float
        Boundary speeds (m/s).
    where : numpy.ndarray, shape (N+1,)
        Boundary positions (m), for messages.
    power : DrivePower, optional
        The drive power limit of :func:`greatest_profile`.

    Returns
    -------
    BandChoice

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
        lower, upper = boundary_bounds(lo, hi, v0_mps, vend_mps)
        b = greatest_profile(lower, upper, length_m, accel_mps2, decel_mps2, power)
        short = b < lower - tol
        if not short.any():
            # v = 0 at both ends (to within 1e-6 m/s, an absolute speed: a slow segment is not
            # a standstill, whatever the top speed of the route)
            standstill = np.flatnonzero((b[:-1] <= 1e-12) & (b[1:] <= 1e-12))
            if standstill.size:  # v = 0 at both ends: constant acceleration never moves
                i = standstill[0]
                raise InfeasibleError(
                    f"segment {i} ({where[i]:g} to {where[i + 1]:g} m) would have to start and end at "
                    "0 m/s, so it can never be driven; use shorter segments (segment_length_m) or "
                    "nonzero v0_mps/vend_mps"
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
            error = InfeasibleError(_infeasible_message(int(j[0]), b, lower, where, v0_mps, vend_mps,
                                                        (bands_lower_mps, bands_upper_mps, count),
                                                        power=power is not None))
            error.position_m = float(where[int(j[0])])  # where the profile fell short, for hints
            raise error
        band[lowerable] -= 1


def _bands_text(lower_mps: np.ndarray, upper_mps: np.ndarray, count: int) -> str:
    """The admissible speed bands of one segment, e.g. "[0, 0.32] and [0.53, 3.39] m/s"."""
    parts = [f"[{lower_mps[k]:.3g}, {upper_mps[k]:.3g}]" for k in range(count)]
    return " and ".join(parts) + " m/s"


def _infeasible_message(j: int, b: np.ndarray, lower: np.ndarray, where: np.ndarray, v0: float, vend: float,
                        bands: tuple[np.ndarray, np.ndarray, np.ndarray], *, power: bool = False) -> str:
    """Why boundary j cannot be reached, named from the segments' full band lists ``bands``
    (lower edges (N, B), upper edges (N, B), counts (N,)), not from the lowered assignment;
    ``power``: a drive power limit holds the acceleration too (its key is named beside
    max_accel_mps2)."""
    n = where.size - 1
    drive = "max_accel_mps2 or max_power_w" if power else "max_accel_mps2"
    reach = math.sqrt(max(b[j], 0.0))
    if j in (0, n):
        i, flag, speed = (0, "v0_mps", v0) if j == 0 else (n - 1, "vend_mps", vend)
        lo_row, hi_row, cnt = bands[0][i], bands[1][i], int(bands[2][i])
        where_text = "first" if j == 0 else "last"
        inside = [k for k in range(cnt) if lo_row[k] - 1e-12 <= speed <= hi_row[k] + 1e-12]
        if cnt == 1:  # one band from rest: the plain story of speed limits and braking
            if speed > hi_row[0]:
                return (f"{flag} = {speed:g} m/s is above the allowable speed {hi_row[0]:.3g} m/s of the "
                        f"{where_text} segment; {'start' if j == 0 else 'end'} slower")
            if j == 0:
                return (f"starting at v0_mps = {speed:g} m/s the vehicle cannot brake in time for the limits "
                        f"ahead (it can only be at {reach:.3g} m/s); start slower or raise max_decel_mps2")
            return (f"the route cannot end at vend_mps = {speed:g} m/s: the vehicle can reach only {reach:.3g} "
                    f"m/s there; lower vend_mps or raise {drive}")
        if not inside:
            return (f"{flag} = {speed:g} m/s is not an admissible speed of the {where_text} segment, whose "
                    f"admissible speeds are {_bands_text(lo_row, hi_row, cnt)}; choose {flag} in one of them")
        if j == 0:
            return (f"starting at v0_mps = {speed:g} m/s (in the band [{lo_row[inside[0]]:.3g}, "
                    f"{hi_row[inside[0]]:.3g}] m/s of the first segment) the vehicle cannot meet the limits "
                    f"ahead: it can only be at {reach:.3g} m/s there (braking in time, or leaving the band "
                    "would pass through speeds the force limit forbids); start at another speed or raise "
                    "max_decel_mps2")
        return (f"the route cannot end at vend_mps = {speed:g} m/s (in the band [{lo_row[inside[0]]:.3g}, "
                f"{hi_row[inside[0]]:.3g}] m/s of the last segment): the vehicle can only be at {reach:.3g} "
                "m/s there (reaching that band would pass through speeds the force limit forbids, or "
                f"needs more acceleration); choose another vend_mps or raise {drive}")
    return (f"at s = {where[j]:g} m the speed must be at least {math.sqrt(lower[j]):.3g} m/s but the "
            f"acceleration bounds allow only {reach:.3g} m/s; relax v0_mps/vend_mps or the vehicle's "
            "acceleration limits")


def snap_to_band(speed_mps: float, lower_mps: np.ndarray, upper_mps: np.ndarray, count: int, name: str
                 ) -> tuple[float, str | None]:
    """A boundary speed moved onto the nearest admissible band when it lies just outside it.

    Parameters
    ----------
    speed_mps : float
        The requested speed (m/s), e.g. ``v0_mps``.
    lower_mps, upper_mps : numpy.ndarray, shape (B,)
        Band edges of the segment at that boundary (m/s), NaN-padded.
    count : int
        Number of bands.
    name : str
        The parameter's name, for the note.

    Returns
    -------
    (speed_mps, note) : tuple
        The speed to plan with and a note saying it was moved (None when it was not). A
        speed inside a band, or farther than :data:`BOUNDARY_SNAP_RTOL` from every band, is
        returned unchanged (the band choice then names the bands).
    """
    lo, hi = lower_mps[:count], upper_mps[:count]
    if count == 0 or np.any((lo <= speed_mps) & (speed_mps <= hi)):
        return speed_mps, None
    edges = np.concatenate([lo, hi])
    k = int(np.argmin(np.abs(edges - speed_mps)))
    edge = float(edges[k])
    if abs(edge - speed_mps) > max(BOUNDARY_SNAP_RTOL * edge, 1e-9):
        return speed_mps, None
    band = k % count
    return edge, (f"{name} = {float(speed_mps)!r} m/s lies {abs(edge - speed_mps):.2g} m/s outside the admissible band "
                  f"[{lo[band]:.6g}, {hi[band]:.6g}] m/s; planned with {name} = {edge!r} m/s, its edge")
