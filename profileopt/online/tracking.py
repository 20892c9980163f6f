"""The command of one cycle: the fastest jerk-limited acceleration that stays under the envelope.

The horizon profile of the selector (:mod:`.selector`) is the greatest speed profile that keeps
every cap and the acceleration bounds: an *envelope*, b_env(s) = v_env(s)^2 piecewise linear in
s. Under it every speed is admissible; but it changes its acceleration abruptly where it meets
a cap. The vehicle instead changes its acceleration by at most J dt per cycle of length dt
(|jerk| <= J) and holds it constant within the cycle, so that b = v^2 is linear in s there too.

A state (s, v, a) is *safe* when a jerk-limited braking manoeuvre from it stays under the
envelope until the vehicle stops: the acceleration ramps down from a to -D at rate J, then
holds -D, D the least deceleration bound of the pieces the manoeuvre can cross (so it keeps
every bound on its way without a jump). Each cycle the command is the
largest acceleration a1 in [a - J dt, a + J dt] (and within the bounds) whose cycle stays under
the envelope and ends in a safe state. It exists whenever the current state is safe and the
envelope has not come down (terrain no worse than assumed): a1 = a - J dt follows the braking
manoeuvre of the last cycle, which was safe. So the vehicle keeps the jerk bound and stays
under the envelope, hence within every cap, cycle after cycle. When no such a1 exists (the
terrain came into view worse than assumed), the command brakes harder than the jerk bound
allows, as little as needed, and says so.

The check is exact where b is linear in s (the cycle, the -D phase: against the envelope's
knots) and conservative in the ramp: on each of its :data:`RAMP_SAMPLES` pieces b is concave
in s and is bounded by its chord raised by the largest gap a concave curve of that curvature
can leave.
"""

from __future__ import annotations

import dataclasses

import numpy as np

__all__ = ["TrackingStep", "jerk_limited_step", "cycle_end", "braking_margin_m", "RAMP_SAMPLES", "CANDIDATES", "MIN_BRAKING_MPS2"]

#: Pieces of the ramp of the braking manoeuvre checked against the envelope.
RAMP_SAMPLES = 12
#: The least deceleration (m/s^2) a braking manoeuvre assumes (a descent too steep to brake on
#: leaves none: then the command brakes as the envelope needs).
MIN_BRAKING_MPS2 = 0.01
#: Accelerations tried per cycle, evenly over [a - J dt, a + J dt] (the largest safe one wins).
CANDIDATES = 21


@dataclasses.dataclass(frozen=True)
class TrackingStep:
    """One cycle of jerk-limited motion.

    Attributes
    ----------
    accel_mps2 : float
        The acceleration held over the cycle (m/s^2), until the vehicle stops if it does.
    accel_after_mps2 : float
        The acceleration at the end of the cycle (m/s^2): ``accel_mps2``, or 0 at rest.
    position_m, speed_mps : float
        Where the vehicle is at the end of the cycle (m) and its speed (m/s).
    jerk_kept : bool
        False when even the hardest braking the jerk bound allows would leave the envelope,
        so the command brakes harder.
    """

    accel_mps2: float
    accel_after_mps2: float
    position_m: float
    speed_mps: float
    jerk_kept: bool


def braking_margin_m(speed_mps: float, decel_mps2: float, jerk_mps3: float) -> float:
    """Distance (m) that a jerk-limited stop from ``speed_mps`` at zero acceleration needs beyond
    a stop at constant deceleration: at most v D / (2 J) (the ramp to -D takes D / J seconds, at
    most the speed v).

    Parameters
    ----------
    speed_mps : float
        Speed (m/s), >= 0.
    decel_mps2 : float
        Deceleration held after the ramp (m/s^2), > 0.
    jerk_mps3 : float
        Jerk bound (m/s^3), > 0 (inf: 0).

    Returns
    -------
    float
    """
    return 0.0 if not np.isfinite(jerk_mps3) else speed_mps * decel_mps2 / jerk_mps3


def cycle_end(s: float, v: float, a: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Where a cycle held at constant acceleration ends, stopping at rest if it comes to rest.

    Parameters
    ----------
    s, v : float
        Position (m) and speed (m/s, >= 0) at the cycle's start.
    a : numpy.ndarray, shape (K,)
        Accelerations held (m/s^2), one per candidate.
    dt : float
        The cycle (s), > 0.

    Returns
    -------
    s1, v1, a_after : numpy.ndarray, shape (K,)
        Position (m) and speed (m/s) at the cycle's end, and the acceleration then (m/s^2):
        ``a``, or 0 at rest.
    """
    v_end = v + a * dt
    stops = v_end < 0
    s1 = np.where(stops, s + v * v / (2.0 * np.maximum(-a, 1e-300)), s + v * dt + 0.5 * a * dt * dt)
    v1 = np.maximum(v_end, 0.0)
    a_held = np.where(v1 <= 0, 0.0, a)
    return s1, v1, a_held


def _under(where: np.ndarray, b_env: np.ndarray, s_lo: np.ndarray, s_hi: np.ndarray, b_lo: np.ndarray,
           b_hi: np.ndarray) -> np.ndarray:
    """Whether the straight line in (s, b) from (s_lo, b_lo) to (s_hi, b_hi) stays under the
    envelope, for each of K lines (exact: checked at both ends and every knot between)."""
    tol = 1e-9 * max(float(np.max(b_env)), 1.0)
    ok = (b_lo <= np.interp(s_lo, where, b_env) + tol) & (b_hi <= np.interp(s_hi, where, b_env) + tol)
    inner = (where[None, :] > s_lo[:, None]) & (where[None, :] < s_hi[:, None])
    if np.any(inner):
        span = np.maximum(s_hi - s_lo, 1e-300)
        frac = (where[None, :] - s_lo[:, None]) / span[:, None]
        line = b_lo[:, None] + frac * (b_hi - b_lo)[:, None]
        ok &= ~np.any(inner & (line > b_env[None, :] + tol), axis=1)
    return ok


def _manoeuvre_decel(where: np.ndarray, decel_seg: np.ndarray, s1: np.ndarray, v1: np.ndarray, a1: np.ndarray,
                     jerk: float) -> np.ndarray:
    """D of the braking manoeuvre from each state: the largest deceleration that is at most the
    bound of every piece the manoeuvre at D crosses (a fixed point, found from the bound where
    it starts downwards), so that it keeps every bound without a jump; and the remainder of a
    manoeuvre, a cycle later, crosses only pieces it crossed, so it has the same D."""
    pieces = decel_seg.size
    first = np.clip(np.searchsorted(where, s1, side="right") - 1, 0, pieces - 1)
    decel = np.maximum(decel_seg[first], MIN_BRAKING_MPS2)
    span = np.arange(pieces)[None, :]
    for _ in range(pieces + 1):  # D only falls, a piece at a time: a fixed point within as many rounds
        ramp = np.maximum(a1 + decel, 0.0) / jerk if np.isfinite(jerk) else 0.0 * v1
        # the distance the ramp and the stop at -D can cover: at most v1 ramp + a1+ ramp^2 / 2
        # + v^2 / (2 D), v the largest speed in the ramp
        v_top = v1 + np.maximum(a1, 0.0) * ramp
        reach = v_top * ramp + v_top * v_top / (2.0 * decel)
        last = np.clip(np.searchsorted(where, s1 + reach + 1e-9, side="right") - 1, 0, pieces - 1)
        crossed = (span >= first[:, None]) & (span <= last[:, None])
        lower = np.maximum(np.where(crossed, decel_seg[None, :], np.inf).min(axis=1), MIN_BRAKING_MPS2)
        if np.all(lower >= decel):
            break
        decel = np.minimum(decel, lower)
    return decel


def _safe(where: np.ndarray, b_env: np.ndarray, s1: np.ndarray, v1: np.ndarray, a1: np.ndarray,
          decel_seg: np.ndarray, jerk: float) -> np.ndarray:
    """Whether braking with jerk ``jerk`` from (s1, v1, a1) down to -D, then at -D, stays under
    the envelope until the stop (module docstring), for K states (D:
    :func:`_manoeuvre_decel`)."""
    tol = 1e-9 * max(float(np.max(b_env)), 1.0)
    decel = _manoeuvre_decel(where, decel_seg, s1, v1, a1, jerk)
    ramp_t = np.maximum((a1 + decel) / jerk, 0.0) if np.isfinite(jerk) else np.zeros_like(a1)
    # the ramp: v(t) = v1 + a1 t - J t^2 / 2 until it ends or the vehicle stops
    t = ramp_t[:, None] * np.linspace(0.0, 1.0, RAMP_SAMPLES + 1)[None, :]
    jt = 0.0 if not np.isfinite(jerk) else jerk
    v_t = v1[:, None] + a1[:, None] * t - 0.5 * jt * t * t
    s_t = s1[:, None] + v1[:, None] * t + 0.5 * a1[:, None] * t * t - jt * t ** 3 / 6.0
    stopped = v_t <= 0
    # after a stop nothing moves: freeze position and speed
    first_stop = np.where(stopped.any(axis=1), stopped.argmax(axis=1), t.shape[1])
    cols = np.arange(t.shape[1])[None, :]
    frozen = cols >= first_stop[:, None]
    stop_col = np.minimum(first_stop, t.shape[1] - 1)
    s_stop = s_t[np.arange(t.shape[0]), stop_col]
    s_t = np.where(frozen, s_stop[:, None], s_t)
    v_t = np.where(frozen, 0.0, np.maximum(v_t, 0.0))
    # each piece: b = v^2 is concave in s along the ramp (db/ds = 2 a falls), so it lies above
    # its chord by at most |b''| ds^2 / 8 = (2 J / v) (v dt)^2 / 8 = J v dt^2 / 4 (v its largest
    # speed on the piece): the chord plus that, checked at the samples and the envelope's knots
    dt_piece = ramp_t / RAMP_SAMPLES
    v_piece = np.maximum(v_t[:, :-1], v_t[:, 1:])
    peak_t = np.clip(a1 / jt, 0.0, ramp_t) if jt > 0 else np.zeros_like(a1)
    v_peak = np.maximum(v1 + a1 * peak_t - 0.5 * jt * peak_t * peak_t, 0.0)
    v_piece = np.maximum(v_piece, v_peak[:, None])
    bow = jt * v_piece * dt_piece[:, None] ** 2 / 4.0
    b_t = v_t * v_t
    at_samples = np.all(b_t[:, 1:] + bow <= np.interp(s_t[:, 1:], where, b_env) + tol, axis=1)
    ramp_ok = at_samples
    lo_k, hi_k = np.searchsorted(where, [float(s_t.min()), float(s_t.max())], side="right")
    w_in, b_in = where[lo_k:hi_k], b_env[lo_k:hi_k]  # the knots the ramps can pass
    if w_in.size:
        inner = (w_in[None, None, :] > s_t[:, :-1, None]) & (w_in[None, None, :] < s_t[:, 1:, None])
        span = np.maximum(s_t[:, 1:] - s_t[:, :-1], 1e-300)
        frac = (w_in[None, None, :] - s_t[:, :-1, None]) / span[:, :, None]
        chord = b_t[:, :-1, None] + frac * (b_t[:, 1:] - b_t[:, :-1])[:, :, None] + bow[:, :, None]
        ramp_ok &= ~np.any(inner & (chord > b_in[None, None, :] + tol), axis=(1, 2))
    # then -D from the ramp's end to the stop: b linear in s
    s2, v2 = s_t[:, -1], v_t[:, -1]
    ok = _under(where, b_env, s2, s2 + v2 * v2 / (2.0 * decel), v2 * v2, np.zeros_like(v2))
    return ramp_ok & ok


def jerk_limited_step(position_m: float, speed_mps: float, accel_mps2: float, *, where_m: np.ndarray,
                      envelope_b: np.ndarray, max_accel_mps2: float, decel_mps2: np.ndarray, jerk_mps3: float,
                      cycle_s: float) -> TrackingStep:
    """The fastest jerk-limited cycle that stays under the envelope and ends in a safe state.

    Parameters
    ----------
    position_m, speed_mps, accel_mps2 : float
        The vehicle's state now (m, m/s, m/s^2).
    where_m : numpy.ndarray, shape (K,)
        The envelope's knots (m), increasing, from ``position_m`` on.
    envelope_b : numpy.ndarray, shape (K,)
        The envelope's squared speed at the knots (m^2/s^2), 0 at the last.
    max_accel_mps2 : float
        The largest acceleration allowed now (m/s^2).
    decel_mps2 : numpy.ndarray, shape (K-1,)
        The deceleration bound of each piece between the knots (m/s^2), > 0.
    jerk_mps3 : float
        Jerk bound J (m/s^3), > 0; inf: none.
    cycle_s : float
        Cycle dt (s), > 0.

    Returns
    -------
    TrackingStep
    """
    s, v, a = float(position_m), float(speed_mps), float(accel_mps2)
    step = jerk_mps3 * cycle_s if np.isfinite(jerk_mps3) else np.inf
    hi = min(a + step, max_accel_mps2)
    decel = np.maximum(np.asarray(decel_mps2, dtype=float), MIN_BRAKING_MPS2)
    d_now = float(decel[0])
    lo = min(max(a - step, -d_now), hi)  # a bound that falls faster than the jerk allows: the bound
    if not np.isfinite(step):
        lo, hi = -d_now, max_accel_mps2
    def tried(cand: np.ndarray, jerk: float) -> tuple[np.ndarray, ...]:
        """The cycle's end (s, v, a after) under each candidate acceleration, and whether it
        stays under the envelope and in a safe state (braking with ``jerk`` afterwards)."""
        s1, v1, a1 = cycle_end(s, v, cand, cycle_s)
        ok = _under(where_m, envelope_b, np.full(cand.size, s), s1, np.full(cand.size, v * v), v1 * v1)
        return s1, v1, a1, ok & _safe(where_m, envelope_b, s1, v1, a1, decel, jerk)

    if hi >= lo:
        cand = np.linspace(hi, lo, CANDIDATES)
        s1, v1, a1, ok = tried(cand, jerk_mps3)
        if np.any(ok):
            k = int(np.argmax(ok))
            if k > 0 and s1[k] <= s + 1e-12:
                # the best candidate leaves the vehicle where it is (at rest under a crawl's cap or
                # just before a stop, with a cycle long enough that the next larger candidate
                # overshoots): look between the two, so that it still creeps on
                fine = np.linspace(cand[k - 1], cand[k], CANDIDATES)[1:-1]
                f1, w1, b1, good = tried(fine, jerk_mps3)
                if np.any(good):
                    j = int(np.argmax(good))
                    return TrackingStep(float(fine[j]), float(b1[j]), float(f1[j]), float(w1[j]), True)
            return TrackingStep(float(cand[k]), float(a1[k]), float(s1[k]), float(v1[k]), True)
    # nothing within the jerk bound: brake harder, as little as the envelope needs
    cand = np.linspace(min(lo, hi), -d_now, CANDIDATES)
    s1, v1, a1, ok = tried(cand, np.inf)
    k = int(np.argmax(ok)) if np.any(ok) else cand.size - 1
    return TrackingStep(float(cand[k]), float(a1[k]), float(s1[k]), float(v1[k]), False)
