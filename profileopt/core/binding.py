"""Which limit holds the speed at each boundary of a plan: the profile's ``binding`` column.

At an interior boundary j the planned squared speed b_j is held by the first of these that is
active (within a relative tolerance):

1. its upper bound (the chosen speed band of the segments on either side, or the lowest of
   their caps): ``force``, ``speed_limit``, ``top_speed``, ``lateral`` or ``friction``;
2. a friction or power row of a segment beside it that this speed makes active (the
   segment's exit speed; for friction while braking, its entry speed): ``friction``,
   ``power``;
3. the acceleration bound of the segment before it (arriving as fast as it may):
   ``accel`` (or ``friction`` where the friction circle gives the tighter bound);
4. the deceleration bound of the segment after it (braking as hard as it may for a slower
   point ahead): ``decel`` (or ``friction``);
5. the jerk bound at it: ``jerk``.

Where none is active, the smoothing term holds the speed below every limit: ``jerk`` (the
comfort term penalises jerk). The first and the last boundary are ``boundary`` (their speeds
are the plan's v0 and vend).
"""

from __future__ import annotations

import numpy as np

from .kinematics import boundary_jerk_mps3, segment_accel_mps2

__all__ = ["BINDING_NAMES", "binding_labels", "binding_shares"]

#: Every value of the ``binding`` column, in the order the summary lists them.
BINDING_NAMES = ("force", "speed_limit", "top_speed", "lateral", "friction", "accel", "decel", "power", "jerk",
                 "boundary", "step", "simulated")


def binding_labels(b: np.ndarray, length_m: np.ndarray, *, upper_b: np.ndarray, upper_label: np.ndarray,
                   accel_mps2: np.ndarray, accel_label: np.ndarray, decel_mps2: np.ndarray,
                   decel_label: np.ndarray, rows: dict[str, np.ndarray], jerk_mps3: float,
                   rtol: float = 1e-5) -> np.ndarray:
    """The ``binding`` name of each boundary of a planned profile.

    Parameters
    ----------
    b : numpy.ndarray, shape (N+1,)
        Planned squared speeds (m^2/s^2).
    length_m : numpy.ndarray, shape (N,)
        Segment lengths (m).
    upper_b : numpy.ndarray, shape (N+1,)
        Upper bound on b at each boundary (m^2/s^2).
    upper_label : numpy.ndarray of str, shape (N+1,)
        Which limit gives that bound.
    accel_mps2, decel_mps2 : numpy.ndarray, shape (N,)
        Each segment's acceleration and deceleration bound (m/s^2).
    accel_label, decel_label : numpy.ndarray of str, shape (N,)
        Which limit gives each.
    rows : dict of str to numpy.ndarray, shape (R, N)
        Values of the ``friction`` and ``power`` rows (<= 1) of each segment
        (:data:`profileopt.physics.rows.ROW_FAMILIES`). An active row holds the segment's
        exit speed (more speed there means more drive force and more lateral acceleration),
        a friction row while braking its entry speed.
    jerk_mps3 : float
        Jerk bound (m/s^3), inf for none.
    rtol : float, default 1e-5
        A bound counts as active within this share of its scale.

    Returns
    -------
    numpy.ndarray of str, shape (N+1,)
        Names from :data:`BINDING_NAMES`.
    """
    n = length_m.size
    out = np.full(n + 1, "jerk", dtype=object)
    decided = np.zeros(n + 1, dtype=bool)

    def mark(where: np.ndarray, label: np.ndarray | str) -> None:
        new = where & ~decided
        out[new] = label[new] if isinstance(label, np.ndarray) else label
        decided[new] = True

    b_scale = max(float(np.max(upper_b[np.isfinite(upper_b)], initial=0.0)), 1e-12)
    mark(b >= upper_b - rtol * b_scale, upper_label)
    a = segment_accel_mps2(b[:-1], b[1:], length_m)
    for family, values in rows.items():
        # an active row of segment i bounds the speed that would make it larger: the exit
        # speed b_{i+1} (more drive force, and more speed in the turn), except for friction
        # while braking, where a higher entry speed b_i means harder braking
        active = np.any(values >= 1.0 - rtol, axis=0)
        holds_entry = active & (a < 0) if family == "friction" else np.zeros_like(active)
        holds_exit = active & ~holds_entry
        mark(np.concatenate([holds_entry, [False]]) | np.concatenate([[False], holds_exit]), family)
    a_scale = max(float(np.max(np.abs(np.concatenate([accel_mps2, decel_mps2])))), 1e-12)
    arriving = np.concatenate([[False], a >= accel_mps2 - rtol * a_scale])
    mark(arriving, np.concatenate([[""], accel_label]).astype(object))
    leaving = np.concatenate([-a >= decel_mps2 - rtol * a_scale, [False]])
    mark(leaving, np.concatenate([decel_label, [""]]).astype(object))
    if np.isfinite(jerk_mps3) and n >= 2:
        v = np.sqrt(np.maximum(b, 0.0))
        jerk = boundary_jerk_mps3(v[1:-1], a[:-1], a[1:], length_m[:-1], length_m[1:])
        mark(np.concatenate([[False], np.abs(jerk) >= jerk_mps3 * (1 - rtol), [False]]), "jerk")
    out[0] = out[-1] = "boundary"
    return out


def binding_shares(binding: np.ndarray, s_m: np.ndarray) -> dict[str, float]:
    """The share of the route's distance each limit holds (0 to 1; they sum to 1).

    Boundary j stands for half of each segment beside it.

    Parameters
    ----------
    binding : numpy.ndarray of str, shape (N+1,)
        The ``binding`` column.
    s_m : numpy.ndarray, shape (N+1,)
        Boundary positions (m).

    Returns
    -------
    dict of str to float
        Every name of :data:`BINDING_NAMES` that occurs, in that order.
    """
    ds = np.diff(s_m)
    weight = np.concatenate([ds, [0.0]]) / 2 + np.concatenate([[0.0], ds]) / 2
    total = float(weight.sum())
    shares = {}
    for name in BINDING_NAMES:
        share = float(weight[binding == name].sum()) / total if total > 0 else 0.0
        if share > 0:
            shares[name] = share
    return shares
