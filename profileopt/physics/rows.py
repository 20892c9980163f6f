"""Limits that couple a segment's speeds with its acceleration: one row each, normalised to g <= 1.

The friction circle and the drive power cannot be written as a cap on the speed or as
bounds on the acceleration alone: they hold only as rows on both together. Each *row
family* is written here once, on the speeds at a segment's two ends, its constant
acceleration and its per-segment data, and serves every caller alike: the planner's NLP
(symbolic, SX), its checks of a solution and the independent check of a finished profile
(numbers, numpy arrays). A new family is one more :class:`RowFamily` in
:data:`ROW_FAMILIES`; nothing else dispatches on a family's name.
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING, Any, Callable, Sequence

import numpy as np

from ..core.kinematics import segment_accel_mps2
from .motion import (
    drive_power_w,
    friction_radius_mps2,
    friction_usage,
    lateral_accel_mps2,
    tyre_accel_mps2,
)

if TYPE_CHECKING:
    from ..core.path import SegmentPath

__all__ = ["RowFamily", "ROW_FAMILIES", "row_values", "exact_row_values", "friction_data", "power_data",
           "friction_rows_needed", "power_rows_needed"]


@dataclasses.dataclass(frozen=True)
class RowFamily:
    """Rows on one segment's end speeds and acceleration, each normalised so that g <= 1 holds.

    Attributes
    ----------
    name : str
        The family's key in :data:`ROW_FAMILIES`.
    description : str
        What its rows limit, in words (for messages).
    data : tuple of str
        Names (with units) of the per-segment data columns, in order.
    count : int
        Rows per segment.
    neutral : tuple of float
        Data that keeps every row far from its bound (no turn, no grade, ample grip or power),
        for padding segments.
    rows : callable
        ``rows(speeds_mps, accel_mps2, data)``: ``speeds_mps`` the speeds at the segment's
        two ends (m/s), ``accel_mps2`` its acceleration (m/s^2), ``data`` the data columns;
        returns the ``count`` rows. Symbolic (CasADi) or numeric arguments alike.
    """

    name: str
    description: str
    data: tuple[str, ...]
    count: int
    neutral: tuple[float, ...]
    rows: Callable[[Sequence[Any], Any, Sequence[Any]], list[Any]]


def _friction_rows(speeds_mps: Sequence[Any], accel_mps2: Any, data: Sequence[Any]) -> list[Any]:
    """friction_usage(v_e, a, kappa, theta, mu) at both ends e and both grade extremes theta
    (rows e0-lo, e0-hi, e1-lo, e1-hi): the usage is convex in sin theta, so its largest value
    over the segment's grades is at one of them, and the lateral part grows with the speed."""
    kappa, lo, hi, mu = data[0], data[1], data[2], data[3]
    return [friction_usage(v, accel_mps2, kappa, theta, mu) for v in speeds_mps for theta in (lo, hi)]


def _power_rows(speeds_mps: Sequence[Any], accel_mps2: Any, data: Sequence[Any]) -> list[Any]:
    """drive power / P at both ends at the steepest grade (rows e0, e1)."""
    hi, mass, power = data[0], data[1], data[2]
    return [drive_power_w(mass, v, accel_mps2, hi) / power for v in speeds_mps]


#: The row families by name: ``friction`` (the friction circle, 4 rows) and ``power`` (the
#: drive power, 2 rows).
ROW_FAMILIES: dict[str, RowFamily] = {
    family.name: family for family in (
        RowFamily(name="friction", description="the friction circle",
                  data=("curvature_1pm", "grade_lo_rad", "grade_hi_rad", "friction_coefficient"), count=4,
                  neutral=(0.0, 0.0, 0.0, 1e3), rows=_friction_rows),
        RowFamily(name="power", description="the vehicle's drive power",
                  data=("grade_hi_rad", "mass_kg", "max_power_w"), count=2, neutral=(0.0, 1.0, 1e12),
                  rows=_power_rows),
    )
}


def row_values(family: str, speeds_mps: Sequence[Any], b: Sequence[Any], length_m: Any,
               data: Sequence[Any]) -> list[Any]:
    """The rows of one family on a segment, from its squared end speeds (symbolic or numeric).

    Parameters
    ----------
    family : str
        A key of :data:`ROW_FAMILIES`.
    speeds_mps : sequence of 2
        The speeds at the segment's ends (m/s), as the caller defines them from ``b`` (the
        NLP smooths sqrt(b) at rest, a check of a finished profile takes it exactly).
    b : sequence of 2
        The squared speeds at the segment's ends (m^2/s^2), for its acceleration.
    length_m : number, array or CasADi expression
        The segment's length (m).
    data : sequence
        The family's data columns (:attr:`RowFamily.data`).

    Returns
    -------
    list
        The family's :attr:`RowFamily.count` rows; each <= 1 where the limit holds.
    """
    return ROW_FAMILIES[family].rows(speeds_mps, segment_accel_mps2(b[0], b[1], length_m), data)


def exact_row_values(family: str, b: np.ndarray, length_m: np.ndarray, data: np.ndarray) -> np.ndarray:
    """The rows of a family on every segment of a profile, with the exact speeds sqrt(b).

    Parameters
    ----------
    family : str
        A key of :data:`ROW_FAMILIES`.
    b : numpy.ndarray, shape (N+1,)
        Squared speeds at the boundaries (m^2/s^2).
    length_m : numpy.ndarray, shape (N,)
        Segment lengths (m).
    data : numpy.ndarray, shape (N, D)
        The family's per-segment data, columns as :attr:`RowFamily.data` names them.

    Returns
    -------
    numpy.ndarray, shape (R, N)
        Each row's value per segment; <= 1 where the limit holds.
    """
    b = np.asarray(b, dtype=float)
    speeds = (np.sqrt(np.maximum(b[:-1], 0.0)), np.sqrt(np.maximum(b[1:], 0.0)))
    cols = [data[:, k] for k in range(data.shape[1])]
    rows = row_values(family, speeds, (b[:-1], b[1:]), length_m, cols)
    return np.array([np.asarray(r, dtype=float).ravel() for r in rows])


def friction_data(path: "SegmentPath", friction_coefficient: float) -> np.ndarray:
    """The ``friction`` family's data of each segment: its largest |curvature| (1/m), its grade
    range (rad) and mu (-), shape (N, 4).

    Parameters
    ----------
    path : SegmentPath
        Each segment's turns and slopes.
    friction_coefficient : float
        mu (-).

    Returns
    -------
    numpy.ndarray
    """
    n = path.curvature_max_1pm.size
    return np.column_stack([path.curvature_max_1pm, path.grade_lo_rad, path.grade_hi_rad,
                            np.full(n, friction_coefficient)])


def power_data(path: "SegmentPath", mass_kg: float, max_power_w: float) -> np.ndarray:
    """The ``power`` family's data of each segment: its steepest grade (rad), the mass (kg) and
    the drive power (W), shape (N, 3).

    Parameters
    ----------
    path : SegmentPath
        Each segment's turns and slopes.
    mass_kg : float
        Mass of the whole vehicle (kg).
    max_power_w : float
        Largest drive power at the wheels (W).

    Returns
    -------
    numpy.ndarray
    """
    n = path.grade_hi_rad.size
    return np.column_stack([path.grade_hi_rad, np.full(n, mass_kg), np.full(n, max_power_w)])


def friction_rows_needed(path: "SegmentPath", friction_coefficient: float, cap_mps: np.ndarray,
                         decel_mps2: np.ndarray, accel_mps2: np.ndarray) -> np.ndarray:
    """The segments whose caps and acceleration bounds do not keep the friction usage within
    the circle on their own, so that they need the ``friction`` rows, shape (N,) of bool.

    The largest usage a segment allows is at its cap (lateral part) with its largest drive or
    braking force at either grade extreme; an uncapped segment counts as capped at 1e6 m/s.
    A straight segment never needs the rows: its acceleration bounds keep the circle.

    Parameters
    ----------
    path : SegmentPath
        Each segment's turns and slopes.
    friction_coefficient : float
        mu (-).
    cap_mps : numpy.ndarray, shape (N,)
        The lowest speed cap of each segment (m/s); inf where none.
    decel_mps2, accel_mps2 : numpy.ndarray, shape (N,)
        The tightest deceleration (positive) and acceleration bounds of each segment (m/s^2).

    Returns
    -------
    numpy.ndarray of bool, shape (N,)
    """
    top = np.minimum(cap_mps, 1e6)  # an uncapped segment is capped by some limit in practice
    lateral = lateral_accel_mps2(top, path.curvature_max_1pm)
    usage = np.zeros(path.curvature_max_1pm.size)
    for a in (accel_mps2, -decel_mps2):
        for theta in (path.grade_lo_rad, path.grade_hi_rad):
            along = tyre_accel_mps2(a, theta)
            radius = friction_radius_mps2(friction_coefficient, theta)
            usage = np.maximum(usage, (along**2 + lateral**2) / radius**2)
    return (usage > 1.0 + 1e-12) & (path.curvature_max_1pm > 0)


def power_rows_needed(path: "SegmentPath", mass_kg: float, max_power_w: float, cap_mps: np.ndarray,
                      accel_mps2: np.ndarray) -> bool:
    """Whether any segment can reach the drive power, so that the ``power`` rows are needed:
    the fastest speed its caps allow times the most drive force per unit mass its bounds
    allow, (a_max + g sin theta_hi) v_cap, exceeds P / m somewhere.

    Parameters
    ----------
    path : SegmentPath
        Each segment's turns and slopes.
    mass_kg : float
        Mass of the whole vehicle (kg).
    max_power_w : float
        Largest drive power at the wheels (W).
    cap_mps : numpy.ndarray, shape (N,)
        The lowest speed cap of each segment (m/s); inf where none.
    accel_mps2 : numpy.ndarray, shape (N,)
        The tightest acceleration bound of each segment (m/s^2).

    Returns
    -------
    bool
    """
    drive = tyre_accel_mps2(accel_mps2, path.grade_hi_rad)
    with np.errstate(invalid="ignore"):  # no drive force at no cap: 0 * inf, never reaching P
        reach = np.maximum(drive, 0.0) * cap_mps
        return bool(np.any(reach * mass_kg > max_power_w * (1 - 1e-12)))
