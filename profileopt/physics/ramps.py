"""The steep ramps of a wheel's path that start or end in a kink: steps met and drops landed.

A rigid wheel's path y(s) (:mod:`profileopt.physics.wheel_path`) kinks where its contact jumps from
one piece of the ground to another, and there its slope always rises (the path is an upper
envelope). Two kinds of kink start or end a ramp that the quarter car meets suddenly:

* a **landing**: the path runs down at slope -s and the kink takes at least half of that
  slope away at once (the wheel lands after a drop). The ramp runs from the path's last
  highest point before the kink down to the kink;
* a **climb**: the kink gives the path at least half of its following slope +s at once
  (the wheel meets a step ahead, or the foot of a steep ramp). The ramp runs from the kink
  up to the path's next highest point.

The rise d of a ramp is the height between its kink and that highest point. The step limit
of SBEM:TF bounds the force on each ramp with :func:`profileopt.physics.ramp_force.ramp_force_n` and
caps the speed of every segment that shares a point with it.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .wheel_path import WheelPath

__all__ = ["WheelRamps", "wheel_ramps", "SUDDEN_SHARE"]

#: A kink starts or ends a ramp when it takes away (landing) or brings (climb) at least this
#: share of the ramp's slope at once (dimensionless).
SUDDEN_SHARE = 0.5


@dataclasses.dataclass(frozen=True)
class WheelRamps:
    """R ramps of a wheel's path, each with a kink at one end.

    Attributes
    ----------
    start_m, end_m : numpy.ndarray, shape (R,)
        Where each ramp starts and ends along the route (m), start <= end.
    kink_m : numpy.ndarray, shape (R,)
        Where its kink is (m): ``end_m`` for a landing, ``start_m`` for a climb.
    slope : numpy.ndarray, shape (R,)
        |dy/ds| of the path next to the kink on the ramp's side (dimensionless), > 0.
    rise_m : numpy.ndarray, shape (R,)
        Height between the kink and the ramp's highest end (m), >= 0.
    landing : numpy.ndarray of bool, shape (R,)
        True for a landing, False for a climb.
    """

    start_m: np.ndarray
    end_m: np.ndarray
    kink_m: np.ndarray
    slope: np.ndarray
    rise_m: np.ndarray
    landing: np.ndarray

    @property
    def count(self) -> int:
        """Number of ramps R."""
        return int(self.slope.size)


def _landings(path: WheelPath) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Kink position, slope, rise and top position of every landing of ``path``."""
    inner = path.breaks_m[1:-1]
    piece = np.arange(path.pieces - 1)
    y_kink, before, _ = path.evaluate(inner, piece)
    after = path.evaluate(inner, piece + 1)[1]
    land = (before < 0) & (after - before >= -SUDDEN_SHARE * before)
    # the path's highest points: its breaks and the tops of its arcs are where it can turn
    s = np.unique(np.clip(np.concatenate([path.breaks_m, path.x_ref_m[path.is_arc]]),
                          path.breaks_m[0], path.breaks_m[-1]))
    y = path.evaluate(s)[0]
    top = np.concatenate([[True], (y[1:-1] >= y[:-2]) & (y[1:-1] >= y[2:]), [True]])
    last_top = np.maximum.accumulate(np.where(top, np.arange(s.size), 0))
    # the last highest point strictly before each kink
    at = np.searchsorted(s, inner[land], side="left") - 1
    j = last_top[np.maximum(at, 0)]
    return inner[land], -before[land], np.maximum(y[j] - y_kink[land], 0.0), s[j]


def _mirrored(path: WheelPath) -> WheelPath:
    """The same path driven the other way, on positions ``L - s`` (L = first + last break)."""
    total = path.breaks_m[0] + path.breaks_m[-1]
    return WheelPath(breaks_m=(total - path.breaks_m)[::-1].copy(), x_ref_m=(total - path.x_ref_m)[::-1].copy(),
                     z_ref_m=path.z_ref_m[::-1].copy(), slope=-path.slope[::-1].copy(),
                     is_arc=path.is_arc[::-1].copy(), wheel_radius_m=path.wheel_radius_m)


def wheel_ramps(path: WheelPath) -> WheelRamps:
    """Every landing and climb of a wheel's path (:class:`WheelRamps`), sorted by start.

    A climb is a landing of the path driven the other way, so both are found by one rule.

    Parameters
    ----------
    path : WheelPath
        The path of the wheel's lowest point (:func:`profileopt.physics.wheel_path.wheel_path`).

    Returns
    -------
    WheelRamps
    """
    total = path.breaks_m[0] + path.breaks_m[-1]
    kink_l, slope_l, rise_l, top_l = _landings(path)
    kink_c, slope_c, rise_c, top_c = _landings(_mirrored(path))
    kink_c, top_c = total - kink_c, total - top_c
    start = np.concatenate([top_l, kink_c])
    order = np.argsort(start, kind="stable")
    return WheelRamps(start_m=start[order], end_m=np.concatenate([kink_l, top_c])[order],
                      kink_m=np.concatenate([kink_l, kink_c])[order],
                      slope=np.concatenate([slope_l, slope_c])[order],
                      rise_m=np.concatenate([rise_l, rise_c])[order],
                      landing=np.concatenate([np.ones(kink_l.size, bool), np.zeros(kink_c.size, bool)])[order])
