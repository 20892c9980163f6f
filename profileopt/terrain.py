"""Terrain roughness: the Roughness Index (Eq. 1), worst-case elevation (Eq. 8) and the
width of a step the wheel rolls over (Eq. 2).

Equation numbers are those of Wilson et al., "Velocity Selection for High-Speed UGVs in
Rough Unknown Terrains using Force Prediction" (see ``shared/paper``), with the project's
errata in ``NOTES.md``.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import casadi as ca
import numpy as np
from numpy.typing import ArrayLike

from ._casadi import elementwise, is_symbolic

if TYPE_CHECKING:
    from .vehicle import Vehicle

__all__ = [
    "roughness_index",
    "segment_roughness_index",
    "elevation_z_score",
    "worst_case_elevation",
    "step_width",
]


def roughness_index(
    elevations: ArrayLike,
    clearance: float,
    positions: ArrayLike | None = None,
    detrend: bool = True,
) -> float:
    """Roughness Index RI = STD(e / h) of a terrain patch (Eq. 1).

    The population standard deviation (ddof = 0) of the elevations divided by the
    vehicle's ground clearance. RI = 0 is perfectly smooth ground; it grows without bound
    with roughness.

    With ``detrend=True`` (the default) the least-squares line (profile) or plane (point
    cloud) is removed first, because a constant grade is not roughness: a vehicle climbing
    a smooth 10 % slope feels no bumps. ``detrend=False`` is the paper's raw definition
    (only the mean is removed, as the standard deviation does).

    Parameters
    ----------
    elevations : array_like, shape (M,) or (M, 3)
        A longitudinal profile of elevations e (m), or a point cloud of rows (x, y, z) (m).
    clearance : float
        Ground clearance h (m), > 0.
    positions : array_like, shape (M,), optional
        Distance along the profile of each elevation (m), used to fit the trend of a 1-D
        profile. If omitted, the samples are taken as evenly spaced. Not used for clouds.
    detrend : bool, default True
        Remove the least-squares line (profile) or plane (cloud) before taking the STD.

    Returns
    -------
    float
        RI (dimensionless).

    Raises
    ------
    ValueError
        Non-finite values, fewer than 2 samples (3 points for a cloud), mismatched shapes
        or a clearance that is not > 0.
    """
    h = float(clearance)
    if not (math.isfinite(h) and h > 0):
        raise ValueError(f"clearance = {clearance!r} m: must be a finite number > 0")
    e = np.asarray(elevations, dtype=float)
    if not np.all(np.isfinite(e)):
        raise ValueError("elevations contain NaN or inf; remove or fill those samples")
    if e.ndim == 2 and e.shape[1] == 3:
        if e.shape[0] < 3:
            raise ValueError(f"a point cloud needs at least 3 points, got {e.shape[0]}")
        z = e[:, 2]
        if detrend:
            design = np.column_stack([np.ones(len(z)), e[:, 0] - e[:, 0].mean(), e[:, 1] - e[:, 1].mean()])
            coef, *_ = np.linalg.lstsq(design, z, rcond=None)
            z = z - design @ coef
        return float(np.std(z / h))
    if e.ndim != 1:
        raise ValueError(f"elevations must have shape (M,) or (M, 3), got {e.shape}")
    if e.size < 2:
        raise ValueError(f"a profile needs at least 2 samples, got {e.size}")
    s = np.arange(e.size, dtype=float) if positions is None else np.asarray(positions, dtype=float)
    if s.shape != e.shape:
        raise ValueError(f"positions have shape {s.shape} but elevations {e.shape}")
    if not np.all(np.isfinite(s)):
        raise ValueError("positions contain NaN or inf")
    return float(segment_roughness_index(s, e, np.array([0]), h, detrend=detrend)[0])


def segment_roughness_index(
    positions_m: np.ndarray,
    elevations_m: np.ndarray,
    starts: np.ndarray,
    clearance_m: float,
    detrend: bool = True,
) -> np.ndarray:
    """RI (Eq. 1) of many consecutive segments of one profile at once.

    Segment i holds the samples ``starts[i] <= j < starts[i+1]`` (the last runs to the end).
    The STD of the residual of a least-squares line is computed from the segment's moments,
    var(e) - cov(s, e)^2 / var(s), with each segment shifted to its first sample so that
    absolute elevations (hundreds of metres) lose no precision.

    Parameters
    ----------
    positions_m, elevations_m : numpy.ndarray, shape (M,)
        Distance along the profile (m) and elevation (m), finite.
    starts : numpy.ndarray of int, shape (N,)
        Index of the first sample of each segment, strictly increasing, ``starts[0] == 0``.
    clearance_m : float
        Ground clearance h (m).
    detrend : bool, default True
        Remove each segment's least-squares line (else only its mean).

    Returns
    -------
    numpy.ndarray, shape (N,)
        RI of each segment (dimensionless).
    """
    s = np.asarray(positions_m, dtype=float)
    z = np.asarray(elevations_m, dtype=float)
    starts = np.asarray(starts, dtype=np.intp)
    counts = np.diff(np.append(starts, s.size)).astype(float)
    seg = np.repeat(np.arange(starts.size), counts.astype(np.intp))
    ds = s - s[starts][seg]
    dz = z - z[starts][seg]

    def mean(x: np.ndarray) -> np.ndarray:
        return np.add.reduceat(x, starts) / counts

    ms, mz = mean(ds), mean(dz)
    var_z = mean(dz * dz) - mz * mz
    if detrend:
        var_s = mean(ds * ds) - ms * ms
        cov = mean(ds * dz) - ms * mz
        with np.errstate(invalid="ignore", divide="ignore"):
            var_z = var_z - np.where(var_s > 0, cov * cov / np.where(var_s > 0, var_s, 1.0), 0.0)
    return np.sqrt(np.maximum(var_z, 0.0)) / clearance_m


def elevation_z_score(confidence: float) -> float:
    """The factor sqrt(2) erfinv(2 Pe - 1) of Eq. (8) (dimensionless).

    The z-score below which a zero-mean normal elevation stays with probability Pe;
    4.7534 for Pe = 0.999999 (NOTES.md).
    """
    return math.sqrt(2.0) * float(ca.erfinv(2.0 * confidence - 1.0))


def _check_ri(ri: Any) -> None:
    if is_symbolic(ri):
        return
    values = np.asarray(ri.full() if isinstance(ri, ca.DM) else ri, dtype=float)
    if np.any(np.isnan(values)) or np.any(values < 0):
        raise ValueError("RI must be a number >= 0 (NaN or a negative RI was given)")


def worst_case_elevation(ri: Any, vehicle: "Vehicle") -> Any:
    """Worst-case elevation e_max = sqrt(2) erfinv(2 Pe - 1) RI h (Eq. 8), in metres.

    Parameters
    ----------
    ri : float, numpy.ndarray, casadi.DM, SX or MX
        Roughness index (dimensionless), >= 0. Any shape.
    vehicle : Vehicle
        Supplies the confidence Pe and the ground clearance h (m).

    Returns
    -------
    Same kind and shape as ``ri``: e_max (m).
    """
    _check_ri(ri)
    return elevation_z_score(vehicle.confidence) * vehicle.ground_clearance_m * ri


@elementwise
def step_width(e_m: Any, vehicle: "Vehicle") -> Any:
    """Horizontal distance X_w over which the wheel climbs a step of height e (Eq. 2), in m.

    X_w = sqrt(2 e r - e^2), saturated at the wheel radius r once e >= r (NOTES.md),
    written as sqrt(e_c (2 r - e_c)) with e_c = min(e, r) so that it is continuous.

    Parameters
    ----------
    e_m : float, array_like, casadi.DM, SX or MX
        Step height e (m), >= 0. Any shape.
    vehicle : Vehicle
        Supplies the wheel radius r (m).

    Returns
    -------
    Same kind and shape as ``e_m``: X_w (m).
    """
    r = vehicle.wheel_radius_m
    e_c = ca.fmin(e_m, r)
    return ca.sqrt(e_c * (2.0 * r - e_c))
