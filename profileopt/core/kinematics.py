"""Kinematics of a speed profile with constant acceleration inside each segment.

A profile gives the speed at the segment boundaries. Inside a segment the acceleration is
constant, so the squared speed b = v^2 is linear in distance. These few formulas are used by
the planner's NLP (on CasADi symbols), by the planner's own checks and outputs and by the
simulator (on numpy arrays): they are plain arithmetic, so one definition serves both.
"""

from __future__ import annotations

from typing import Any

__all__ = ["segment_accel_mps2", "segment_time_s", "boundary_jerk_mps3", "jerk_squared_time"]


def segment_accel_mps2(b_left: Any, b_right: Any, length_m: Any) -> Any:
    """Constant acceleration a = (b_right - b_left) / (2 ds) of a segment (m/s^2).

    Parameters
    ----------
    b_left, b_right : array_like or CasADi, shape (N,)
        Squared speeds at the segment's ends (m^2/s^2).
    length_m : array_like or CasADi, shape (N,)
        Segment lengths ds (m), > 0.
    """
    return (b_right - b_left) / (2.0 * length_m)


def segment_time_s(v_left: Any, v_right: Any, length_m: Any) -> Any:
    """Time to drive a segment at constant acceleration: 2 ds / (v_left + v_right) (s).

    Parameters
    ----------
    v_left, v_right : array_like or CasADi, shape (N,)
        Speeds at the segment's ends (m/s), not both 0.
    length_m : array_like or CasADi, shape (N,)
        Segment lengths ds (m).
    """
    return 2.0 * length_m / (v_left + v_right)


def boundary_jerk_mps3(v_mid: Any, a_before: Any, a_after: Any, ds_before: Any, ds_after: Any) -> Any:
    """Jerk v da/ds at an interior boundary: v_j (a_j - a_{j-1}) / dsm_j (m/s^3).

    The acceleration jumps at a boundary; its change over the mean of the two segment
    lengths, dsm_j = (ds_{j-1} + ds_j) / 2, times the speed there is the discrete jerk.

    Parameters
    ----------
    v_mid : array_like or CasADi, shape (N-1,)
        Speed at the boundary (m/s).
    a_before, a_after : array_like or CasADi, shape (N-1,)
        Accelerations of the segments before and after it (m/s^2).
    ds_before, ds_after : array_like or CasADi, shape (N-1,)
        Their lengths (m).
    """
    return v_mid * (a_after - a_before) / (0.5 * (ds_before + ds_after))


def jerk_squared_time(v_mid: Any, a_before: Any, a_after: Any, ds_before: Any, ds_after: Any) -> Any:
    """A boundary's share of the integral of jerk^2 dt: v_j (a_j - a_{j-1})^2 / dsm_j (m^2/s^5).

    With jerk = v da/ds and dt = ds / v, jerk^2 dt = v (da/ds)^2 ds; over the boundary's
    share dsm_j of the route that is v_j da_j^2 / dsm_j. Arguments as
    :func:`boundary_jerk_mps3`.

    Parameters
    ----------
    v_mid : array_like or CasADi, shape (N-1,)
        Speed at the boundary (m/s).
    a_before, a_after : array_like or CasADi, shape (N-1,)
        Accelerations of the segments before and after it (m/s^2).
    ds_before, ds_after : array_like or CasADi, shape (N-1,)
        Their lengths (m).
    """
    return v_mid * (a_after - a_before) ** 2 / (0.5 * (ds_before + ds_after))
