"""The profile returned when the NLP cannot be solved: slower, but keeping every limit.

It is the exact forward-backward profile (:func:`~profileopt.planning.bands.choose_bands`)
with acceleration bounds so low that the jerk bound holds at every boundary whatever the
pattern of accelerations: with |a| <= a' everywhere, |a_j - a_{j-1}| <= 2 a', so
jerk = v da/ds <= v_top 2 a' / ds_min <= J when a' = J ds_min / (2 v_top).
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import InfeasibleError, PlanningError
from ..physics.speeds import SpeedBands
from .bands import BandChoice, DrivePower, choose_bands

__all__ = ["fallback_choice"]


def fallback_choice(bands: SpeedBands, length_m: np.ndarray, boundaries_m: np.ndarray, decel_mps2: np.ndarray,
                    accel_mps2: np.ndarray, jerk_mps3: float, v0_mps: float, vend_mps: float,
                    power: DrivePower | None = None) -> BandChoice:
    """Bands and forward-backward profile with acceleration bounds lowered to keep the jerk bound.

    Parameters
    ----------
    bands : SpeedBands
        The usable admissible speed bands of each segment (m/s), capped.
    length_m : numpy.ndarray, shape (N,)
        Segment lengths (m).
    boundaries_m : numpy.ndarray, shape (N+1,)
        Segment boundaries (m), for messages.
    decel_mps2, accel_mps2 : numpy.ndarray, shape (N,)
        Deceleration (positive) and acceleration bounds of each segment (m/s^2).
    jerk_mps3 : float
        Jerk bound (m/s^3); inf: the bounds are not lowered.
    v0_mps, vend_mps : float
        Speeds at the start and at the end (m/s).
    power : DrivePower, optional
        The drive power limit of the forward pass.

    Returns
    -------
    BandChoice
        Its ``greatest_b`` is the fallback profile.

    Raises
    ------
    PlanningError
        Not even this profile exists.
    """
    a, d = accel_mps2, decel_mps2
    if math.isfinite(jerk_mps3):
        v_top = float(np.nanmax(bands.upper_mps))
        cap = jerk_mps3 * float(length_m.min()) / (2.0 * max(v_top, 1e-9))
        a, d = np.minimum(a, cap), np.minimum(d, cap)
    try:
        return choose_bands(bands.lower_mps, bands.upper_mps, bands.count, length_m, a, d, v0_mps, vend_mps,
                            boundaries_m, power)
    except InfeasibleError as exc:
        raise PlanningError(f"the NLP solvers failed and no jerk-limited fallback exists ({exc})") from None
