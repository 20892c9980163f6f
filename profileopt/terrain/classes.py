"""The expected Roughness Index of an ISO 8608 road class over a roughness window.

When a route's elevation is too coarse to measure wheel-scale roughness (a DEM, a sparse
point cloud), the user assumes a roughness class instead (issue 12). Its RI is derived here
from the class's displacement PSD (docs/paper-notes.md, "Assumed roughness: ISO 8608
classes"):

    E[sigma^2] = integral over [n_min, n_max] of Gd(n) K(n W) dn,
    Gd(n) = Gd(n0) (n / n0)^-2,
    K(x) = 1 - (sin a / a)^2 - 3 (sin a - a cos a)^2 / a^4,   a = pi x,

where sigma^2 is the population variance of the profile about its least-squares line over
a window of length W (the detrended RI of Eq. 1 is sigma / h) and K the detrending gain:
the phase-averaged mean square that removing the line leaves of a unit-variance sinusoid of
n W cycles per window. The band is that of :func:`profileopt.terrain.synthetic.iso8608_profile`
(:data:`~profileopt.terrain.synthetic.ISO8608_N_MIN_CPM` to
:data:`~profileopt.terrain.synthetic.ISO8608_N_MAX_CPM`), so the class's RI is the RMS window RI of
the profiles the project synthesises for that class.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from ..core.checks import finite_positive
from ..errors import InputError
from .synthetic import (
    ISO8608_GD0_M3,
    ISO8608_N0_CPM,
    ISO8608_N_MAX_CPM,
    ISO8608_N_MIN_CPM,
)

__all__ = ["detrending_gain", "iso8608_expected_variance_m2", "iso8608_expected_rms_m", "iso8608_ri",
           "iso8608_class_key"]

#: Below this a = pi n W the closed form of K loses digits to cancellation (1 - 1 + a^4/45):
#: its Taylor series is used instead (four terms: relative error below 1e-9 there).
_SERIES_BELOW = 0.3


def iso8608_class_key(road_class: str) -> str:
    """The ISO 8608 class letter, upper case, or one line saying what is wrong.

    Parameters
    ----------
    road_class : str
        One letter A (smoothest) to H, case-insensitive; surrounding blanks are ignored.

    Returns
    -------
    str
        ``"A"`` to ``"H"``.

    Raises
    ------
    InputError
        Not one letter of A to H.
    """
    key = road_class.strip().upper() if isinstance(road_class, str) else None
    if key not in ISO8608_GD0_M3:
        raise InputError(f"road_class = {road_class!r}: not an ISO 8608 class; use one letter of "
                         f"{' '.join(ISO8608_GD0_M3)} (A smoothest)")
    return key


def detrending_gain(n_cpm: ArrayLike, *, window_m: float) -> np.ndarray:
    """K(n W): the share of a sinusoid's mean square left after removing the least-squares
    line over a window of length W, averaged over the phase.

    K(x) = 1 - (sin a / a)^2 - 3 (sin a - a cos a)^2 / a^4 with a = pi x, x = n W
    (docs/paper-notes.md, "Assumed roughness: ISO 8608 classes"); K ~ a^4 / 45 for long
    waves (the line follows them), K -> 1 for short ones. The window is taken as a
    continuum: a window of many samples.

    Parameters
    ----------
    n_cpm : array_like, shape (K,) or scalar
        Spatial frequency n (cycles/m), >= 0.
    window_m : float
        Window length W (m), > 0.

    Returns
    -------
    numpy.ndarray, shape of ``n_cpm``
        K (dimensionless), in [0, 1).
    """
    width = finite_positive("window_m", window_m)
    a = np.pi * np.abs(np.asarray(n_cpm, dtype=float)) * width
    small = a < _SERIES_BELOW
    a2 = np.where(small, a * a, 1.0)
    series = a2 * a2 * (1.0 / 45.0 - a2 * (4.0 / 1575.0 - a2 * (2.0 / 14175.0 - a2 * 16.0 / 3274425.0)))
    big = np.where(small, 1.0, a)
    closed = 1.0 - (np.sin(big) / big) ** 2 - 3.0 * (np.sin(big) - big * np.cos(big)) ** 2 / big**4
    return np.where(small, series, closed)


def iso8608_expected_variance_m2(road_class: str, *, window_m: float, n_min_cpm: float = ISO8608_N_MIN_CPM,
                                 n_max_cpm: float = ISO8608_N_MAX_CPM) -> float:
    """E[sigma^2]: the expected detrended mean square of an ISO 8608 profile over a window.

    The integral of Gd(n) K(n W) over the band (module docstring), with Gd(n0) the class's
    geometric mean (:data:`profileopt.terrain.synthetic.ISO8608_GD0_M3`). Substituting a = pi n W,
    E[sigma^2] = Gd(n0) n0^2 pi W times the integral of K(a) / a^2 over [pi n_min W, pi n_max W],
    evaluated by adaptive quadrature (relative error below 1e-10).

    Parameters
    ----------
    road_class : str
        ISO 8608 class, one letter A to H (case-insensitive).
    window_m : float
        Roughness window length W (m), > 0.
    n_min_cpm, n_max_cpm : float, default ISO8608_N_MIN_CPM and ISO8608_N_MAX_CPM
        The band (cycles/m), 0 < n_min < n_max: that of the profiles it describes.

    Returns
    -------
    float
        E[sigma^2] (m^2).

    Raises
    ------
    InputError
        An unknown class, a window that is not > 0 or a bad band.
    """
    from scipy import (
        integrate,  # only when a class's RI is derived: reading a route needs no SciPy
    )

    gd0 = ISO8608_GD0_M3[iso8608_class_key(road_class)]
    width = finite_positive("window_m", window_m)
    n_min, n_max = finite_positive("n_min_cpm", n_min_cpm), finite_positive("n_max_cpm", n_max_cpm)
    if not n_max > n_min:
        raise InputError(f"n_max_cpm = {n_max_cpm!r} must be greater than n_min_cpm = {n_min_cpm!r}")
    lo, hi = math.pi * n_min * width, math.pi * n_max * width
    # K oscillates with period pi in a: break the range there so the quadrature sees each lobe
    points = [math.pi * k for k in range(1, int(hi / math.pi) + 1) if lo < math.pi * k < hi][:500]
    value, _ = integrate.quad(lambda a: float(detrending_gain(a / (math.pi * width), window_m=width)) / (a * a),
                              lo, hi, points=points or None, limit=max(100, 2 * len(points) + 50),
                              epsabs=0.0, epsrel=1e-11)
    return gd0 * ISO8608_N0_CPM**2 * math.pi * width * value


def iso8608_expected_rms_m(road_class: str, *, window_m: float, n_min_cpm: float = ISO8608_N_MIN_CPM,
                           n_max_cpm: float = ISO8608_N_MAX_CPM) -> float:
    """sqrt(E[sigma^2]): the RMS over windows of the detrended STD of an ISO 8608 profile (m).

    The root of :func:`iso8608_expected_variance_m2`. By Jensen's inequality it is at least
    the mean of the windows' sigma, and the worst windows of one profile exceed it
    (docs/paper-notes.md, "Assumed roughness: ISO 8608 classes").

    Parameters
    ----------
    road_class : str
        ISO 8608 class, one letter A to H (case-insensitive).
    window_m : float
        Roughness window length W (m), > 0.
    n_min_cpm, n_max_cpm : float, default ISO8608_N_MIN_CPM and ISO8608_N_MAX_CPM
        The band (cycles/m).

    Returns
    -------
    float
        RMS of sigma (m).
    """
    return math.sqrt(iso8608_expected_variance_m2(road_class, window_m=window_m, n_min_cpm=n_min_cpm,
                                                  n_max_cpm=n_max_cpm))


def iso8608_ri(road_class: str, *, window_m: float, clearance_m: float) -> float:
    """The RI (Eq. 1, detrended) assumed for an ISO 8608 class: sqrt(E[sigma^2]) / h.

    Over the default band (:data:`~profileopt.terrain.synthetic.ISO8608_N_MIN_CPM` to
    :data:`~profileopt.terrain.synthetic.ISO8608_N_MAX_CPM`).

    Parameters
    ----------
    road_class : str
        ISO 8608 class, one letter A to H (case-insensitive).
    window_m : float
        Roughness window length W (m), > 0.
    clearance_m : float
        Ground clearance h (m), > 0.

    Returns
    -------
    float
        RI (dimensionless).
    """
    return iso8608_expected_rms_m(road_class, window_m=window_m) / finite_positive("clearance_m", clearance_m)


def smoothest_class_covering(ri: float, *, window_m: float, clearance_m: float) -> str:
    """The smoothest ISO 8608 class whose RI (:func:`iso8608_ri`) is at least ``ri``; ``"H"``
    when none is.

    Parameters
    ----------
    ri : float
        RI (dimensionless), e.g. the roughest window of a route.
    window_m : float
        Roughness window length W (m), > 0.
    clearance_m : float
        Ground clearance h (m), > 0.

    Returns
    -------
    str
        One letter A to H.
    """
    return next((c for c in "ABCDEFGH" if iso8608_ri(c, window_m=window_m, clearance_m=clearance_m) >= ri), "H")
