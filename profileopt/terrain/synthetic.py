"""Seeded synthetic terrain: ISO 8608 random profiles, washboard, curbs and ramps.

Every generator returns elevations in metres along a distance s in metres. The random
ones are fully determined by their arguments and an integer ``seed`` (a
:func:`numpy.random.default_rng` stream), so examples and tests are reproducible.

ISO 8608 (see ``docs/paper-notes.md``, "Terrain for examples and tests") classifies road roughness by
the one-sided displacement power spectral density

    Gd(n) = Gd(n0) (n / n0)^-2,   n0 = 0.1 cycles/m,

with the geometric-mean Gd(n0) of each class A..H in :data:`ISO8608_GD0_M3`. A random
profile is the sum of cosines z(s) = sum_i a_i cos(2 pi n_i s - phi_i) with uniform random
phases phi_i and a_i^2 / 2 the spectral power of the band around n_i, evaluated here with
one inverse real FFT (see :func:`iso8608_profile`).

The deterministic shapes (:func:`washboard`, :func:`step`, :func:`ramp`) take the sample
positions and return elevations to be added to a base profile.
"""

from __future__ import annotations

import math
from typing import NamedTuple, Sequence

import numpy as np
from numpy.typing import ArrayLike

from ..core.checks import finite_positive
from ..errors import InputError

__all__ = [
    "ElevationProfile",
    "ISO8608_GD0_M3",
    "ISO8608_N0_CPM",
    "ISO8608_N_MIN_CPM",
    "ISO8608_N_MAX_CPM",
    "iso8608_variance_m2",
    "iso8608_profile",
    "iso8608_sections",
    "washboard",
    "step",
    "ramp",
]

#: Reference spatial frequency n0 of ISO 8608 (cycles/m).
ISO8608_N0_CPM = 0.1

#: Default spatial-frequency band of the synthesised profiles (cycles/m): waves from about
#: 90 m (longer ones are grade, which the roughness windows detrend away) down to 0.25 m
#: (shorter ones a wheel bridges; sampled routes resolve them at spacings below 0.125 m).
#: The expected RI of a class (:mod:`profileopt.terrain.classes`) integrates the same band.
ISO8608_N_MIN_CPM = 0.011
ISO8608_N_MAX_CPM = 4.0

#: Geometric-mean displacement PSD Gd(n0) of each ISO 8608 class (m^3 = m^2 / (cycles/m)).
#: Class limits are a factor 2 either side (docs/paper-notes.md).
ISO8608_GD0_M3: dict[str, float] = {
    letter: 16e-6 * 4.0**i for i, letter in enumerate("ABCDEFGH")
}


class ElevationProfile(NamedTuple):
    """A longitudinal terrain profile; unpacks as ``s_m, z_m = profile``.

    Attributes
    ----------
    s_m : numpy.ndarray, shape (M,)
        Distance along the path (m), strictly increasing.
    z_m : numpy.ndarray, shape (M,)
        Elevation at each distance (m).
    """

    s_m: np.ndarray
    z_m: np.ndarray



def _gd0_m3(road_class: str) -> float:
    key = road_class.upper() if isinstance(road_class, str) else road_class
    if key not in ISO8608_GD0_M3:
        raise InputError(
            f"road_class = {road_class!r}: not an ISO 8608 class; use one letter of A B C D E F G H"
        )
    return ISO8608_GD0_M3[key]


def _check_band(spacing_m: float, n_min_cpm: float, n_max_cpm: float) -> tuple[float, float]:
    n_min = finite_positive("n_min_cpm", n_min_cpm)
    n_max = finite_positive("n_max_cpm", n_max_cpm)
    if n_max <= n_min:
        raise InputError(f"n_max_cpm = {n_max_cpm!r} must be greater than n_min_cpm = {n_min_cpm!r}")
    nyquist = 0.5 / spacing_m
    if n_max >= nyquist:
        raise InputError(
            f"n_max_cpm = {n_max_cpm!r} cycles/m is not below the Nyquist frequency "
            f"1 / (2 spacing_m) = {nyquist:g} cycles/m; reduce spacing_m or n_max_cpm"
        )
    return n_min, n_max


def _check_seed(seed: int) -> int:
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise InputError(f"seed = {seed!r}: must be an integer >= 0 (it makes the profile reproducible)")
    return int(seed)


def _sample_count(length_m: float, spacing_m: float) -> int:
    """Samples 0, spacing, ..., up to length (inclusive within 1e-9 of a spacing)."""
    if spacing_m >= length_m:
        raise InputError(f"spacing_m = {spacing_m!r} must be smaller than length_m = {length_m!r}")
    return int(math.floor(length_m / spacing_m + 1e-9)) + 1


def iso8608_variance_m2(gd0_m3: float, n_min_cpm: float, n_max_cpm: float) -> float:
    """Variance of an ISO 8608 profile band-limited to [n_min, n_max] (m^2).

    The integral of Gd(n) = Gd(n0) (n / n0)^-2 over the band (docs/paper-notes.md):
    sigma^2 = Gd(n0) n0^2 (1 / n_min - 1 / n_max).

    Parameters
    ----------
    gd0_m3 : float
        Gd(n0) (m^3), e.g. ``ISO8608_GD0_M3["C"]``.
    n_min_cpm, n_max_cpm : float
        Band edges (cycles/m), 0 < n_min < n_max.

    Returns
    -------
    float
        sigma^2 (m^2).
    """
    return gd0_m3 * ISO8608_N0_CPM**2 * (1.0 / n_min_cpm - 1.0 / n_max_cpm)


def _unit_iso8608(n_samples: int, spacing_m: float, seed: int, n_min: float, n_max: float) -> np.ndarray:
    """Random profile with Gd(n0) = 1 m^3 at ``n_samples`` points ``spacing_m`` apart (m).

    The frequencies are the FFT bins n_k = k / L of a period L >= the profile length and
    >= 8 / n_min (so that a bin is at most n_min / 8 wide and no power falls on the
    constant bin). Component k carries exactly the power of Gd over its bin
    [n_k - dn/2, n_k + dn/2] clipped to [n_min, n_max] (the exact form of docs/paper-notes.md's
    Gd(n_k) dn), a_k = sqrt(2 P_k), so over one period the variance is exactly
    :func:`iso8608_variance_m2`. The cosine sum sum_k a_k cos(2 pi n_k s - phi_k) at
    s = j spacing is then one inverse real FFT: O(L log L) instead of O(K M).
    """
    import scipy.fft  # only when a profile is synthesised: reading a route needs no SciPy

    n_fft = scipy.fft.next_fast_len(max(n_samples, math.ceil(8.0 / (n_min * spacing_m))), real=True)
    dn = 1.0 / (n_fft * spacing_m)
    k = np.arange(n_fft // 2 + 1, dtype=float)
    lo = np.clip((k - 0.5) * dn, n_min, n_max)
    hi = np.clip((k + 0.5) * dn, n_min, n_max)
    with np.errstate(divide="ignore"):
        # integral of n0^2 / n^2 over [lo, hi] (Gd(n0) = 1); 0 where the bin is outside
        power = np.where(hi > lo, ISO8608_N0_CPM**2 * (1.0 / lo - 1.0 / hi), 0.0)
    power[0] = 0.0
    if n_fft % 2 == 0:
        power[-1] = 0.0  # the Nyquist bin has no phase freedom; n_max < Nyquist keeps it empty
    amplitude = np.sqrt(2.0 * power)
    phase = np.random.default_rng(seed).uniform(0.0, 2.0 * np.pi, size=k.size)
    # irfft: z_j = (1/N) [X_0 + 2 sum_k Re(X_k e^{2 pi i k j / N})], so X_k = (N/2) a_k e^{-i phi_k}
    spectrum = 0.5 * n_fft * amplitude * np.exp(-1j * phase)
    return scipy.fft.irfft(spectrum, n=n_fft)[:n_samples]


def iso8608_profile(
    road_class: str,
    length_m: float,
    spacing_m: float,
    seed: int,
    n_min_cpm: float = ISO8608_N_MIN_CPM,
    n_max_cpm: float = ISO8608_N_MAX_CPM,
) -> ElevationProfile:
    """A random road profile of one ISO 8608 class.

    z(s) = sum_k a_k cos(2 pi n_k s - phi_k) with phases phi_k uniform in [0, 2 pi) drawn
    from ``numpy.random.default_rng(seed)`` and a_k^2 / 2 the power of
    Gd(n) = Gd(n0) (n / n0)^-2 in the band of n_k (docs/paper-notes.md). The frequencies are
    evenly spaced (bins of width dn = 1 / L, L = max(length, 8 / n_min) rounded up to a fast
    FFT size), so the profile is evaluated with one inverse FFT: 100 km at 0.05 m takes a
    fraction of a second. The variance over a long profile is
    sigma^2 = Gd(n0) n0^2 (1 / n_min - 1 / n_max) (:func:`iso8608_variance_m2`); a short
    one varies about it with its few longest waves. The mean over the FFT period is 0.

    Parameters
    ----------
    road_class : str
        ISO 8608 class, one letter ``"A"`` (smoothest) to ``"H"`` (case-insensitive).
    length_m : float
        Profile length (m), > spacing_m. Samples run from 0 to the largest multiple of
        ``spacing_m`` not beyond it.
    spacing_m : float
        Sample spacing (m), > 0.
    seed : int
        Seed (>= 0) of the random phases; the same arguments give the same profile.
    n_min_cpm, n_max_cpm : float, default 0.011 and 4.0
        Spatial-frequency band (cycles/m); n_max must be below the Nyquist frequency
        1 / (2 spacing_m).

    Returns
    -------
    ElevationProfile
        ``s_m`` shape (M,) = 0, spacing, ... (m) and ``z_m`` shape (M,) (m).

    Raises
    ------
    InputError
        Unknown class, a length, spacing or band edge that is not a finite positive number,
        spacing >= length, n_max <= n_min or n_max at or above Nyquist, a seed that is not
        an integer >= 0.
    """
    gd0 = _gd0_m3(road_class)
    length = finite_positive("length_m", length_m)
    spacing = finite_positive("spacing_m", spacing_m)
    n_samples = _sample_count(length, spacing)
    n_min, n_max = _check_band(spacing, n_min_cpm, n_max_cpm)
    z = math.sqrt(gd0) * _unit_iso8608(n_samples, spacing, _check_seed(seed), n_min, n_max)
    return ElevationProfile(np.arange(n_samples) * spacing, z)


def iso8608_sections(
    sections: Sequence[tuple[str, float]],
    spacing_m: float,
    seed: int,
    transition_m: float = 10.0,
    n_min_cpm: float = ISO8608_N_MIN_CPM,
    n_max_cpm: float = ISO8608_N_MAX_CPM,
) -> ElevationProfile:
    """A random profile whose ISO 8608 class changes along it, without steps at the joins.

    One random profile with Gd(n0) = 1 m^3 (:func:`iso8608_profile`'s method) is
    multiplied by sqrt(Gd(n0)) of the class of each section. Because every class has the
    same spectral shape, that scales the local PSD to the section's class. At each join
    the factor changes as a raised cosine over ``transition_m`` centred on the join, so
    the surface stays continuous and smooth.

    Parameters
    ----------
    sections : sequence of (str, float)
        (ISO 8608 class letter, section length in m) in driving order.
    spacing_m : float
        Sample spacing (m), > 0.
    seed : int
        Seed (>= 0) of the random phases.
    transition_m : float, default 10.0
        Length (m) over which the class changes at a join, >= 0 and at most the shorter
        of the two sections it joins.
    n_min_cpm, n_max_cpm : float, default 0.011 and 4.0
        Spatial-frequency band (cycles/m), as in :func:`iso8608_profile`.

    Returns
    -------
    ElevationProfile
        ``s_m`` shape (M,) from 0 to the sum of the section lengths (m), ``z_m`` (m).

    Raises
    ------
    InputError
        An empty list, an unknown class, a non-positive length, a transition longer than a
        section it joins, or any problem :func:`iso8608_profile` refuses.
    """
    if len(sections) == 0:
        raise InputError("sections is empty; give at least one (class, length_m) pair")
    gd0 = np.array([_gd0_m3(c) for c, _ in sections])
    lengths = np.array([finite_positive(f"length of section {i} ({c!r})", n) for i, (c, n) in enumerate(sections)])
    spacing = finite_positive("spacing_m", spacing_m)
    width = float(transition_m)
    if not (math.isfinite(width) and width >= 0):
        raise InputError(f"transition_m = {transition_m!r}: must be a finite number >= 0")
    shortest_pair = np.minimum(lengths[:-1], lengths[1:])
    if lengths.size > 1 and width > shortest_pair.min():
        raise InputError(
            f"transition_m = {transition_m!r} m is longer than a section it joins "
            f"({shortest_pair.min():g} m); shorten transition_m or lengthen that section"
        )
    n_samples = _sample_count(float(lengths.sum()), spacing)
    n_min, n_max = _check_band(spacing, n_min_cpm, n_max_cpm)
    unit = _unit_iso8608(n_samples, spacing, _check_seed(seed), n_min, n_max)
    s = np.arange(n_samples) * spacing
    scale = np.sqrt(gd0)
    factor = np.full(n_samples, scale[0])
    for join, before, after in zip(np.cumsum(lengths)[:-1], scale[:-1], scale[1:]):
        if width > 0:
            x = np.clip((s - (join - 0.5 * width)) / width, 0.0, 1.0)
            blend = 0.5 - 0.5 * np.cos(np.pi * x)
        else:
            blend = (s >= join).astype(float)
        factor = np.where(s >= join - 0.5 * width, before + (after - before) * blend, factor)
    return ElevationProfile(s, factor * unit)


def washboard(
    s_m: ArrayLike,
    amplitude_m: float,
    wavelength_m: float,
    start_m: float | None = None,
    end_m: float | None = None,
) -> np.ndarray:
    """Sinusoidal corrugation z = A sin(2 pi (s - start) / wavelength) (m).

    Over a whole number of wavelengths its standard deviation is A / sqrt(2), so its RI
    (Eq. 1) is A / (sqrt(2) h) (docs/paper-notes.md, "Fig. 1"). It starts at zero height at
    ``start_m``; choose the section length as a whole number of wavelengths to end at zero
    too.

    Parameters
    ----------
    s_m : array_like, shape (M,)
        Distance along the path (m).
    amplitude_m : float
        Amplitude A (m), >= 0 (half the crest-to-trough height).
    wavelength_m : float
        Corrugation wavelength (m), > 0 (1 / spatial frequency in cycles/m).
    start_m, end_m : float, optional
        The corrugation covers start <= s < end; elsewhere z = 0. Default: everywhere,
        phase zero at s = 0.

    Returns
    -------
    numpy.ndarray, shape (M,)
        Elevation (m).
    """
    s = np.asarray(s_m, dtype=float)
    amplitude = float(amplitude_m)
    if not (math.isfinite(amplitude) and amplitude >= 0):
        raise InputError(f"amplitude_m = {amplitude_m!r}: must be a finite number >= 0")
    wavelength = finite_positive("wavelength_m", wavelength_m)
    start = 0.0 if start_m is None else float(start_m)
    inside = np.ones(s.shape, dtype=bool) if start_m is None else s >= start
    if end_m is not None:
        if not float(end_m) > start:
            raise InputError(f"end_m = {end_m!r} must be greater than start_m = {start_m!r}")
        inside &= s < float(end_m)
    return np.where(inside, amplitude * np.sin(2.0 * np.pi * (s - start) / wavelength), 0.0)


def step(s_m: ArrayLike, position_m: float, height_m: float) -> np.ndarray:
    """A curb: z = height for s >= position, 0 before it (m).

    Parameters
    ----------
    s_m : array_like, shape (M,)
        Distance along the path (m).
    position_m : float
        Where the step is (m); the sample at exactly this distance is on the top.
    height_m : float
        Step height (m); negative for a step down.

    Returns
    -------
    numpy.ndarray, shape (M,)
        Elevation (m).
    """
    s = np.asarray(s_m, dtype=float)
    position, height = float(position_m), float(height_m)
    if not (math.isfinite(position) and math.isfinite(height)):
        raise InputError(f"position_m = {position_m!r} and height_m = {height_m!r} must be finite numbers")
    return np.where(s >= position, height, 0.0)


def ramp(s_m: ArrayLike, start_m: float, end_m: float, rise_m: float) -> np.ndarray:
    """A constant grade: 0 before ``start_m``, rising linearly by ``rise_m`` to ``end_m``,
    then level at ``rise_m`` (m). The grade is rise / (end - start).

    Parameters
    ----------
    s_m : array_like, shape (M,)
        Distance along the path (m).
    start_m, end_m : float
        Where the grade begins and ends (m), end > start.
    rise_m : float
        Total change of elevation (m); negative for a descent.

    Returns
    -------
    numpy.ndarray, shape (M,)
        Elevation (m).
    """
    s = np.asarray(s_m, dtype=float)
    start, end, rise = float(start_m), float(end_m), float(rise_m)
    if not all(math.isfinite(x) for x in (start, end, rise)):
        raise InputError(f"start_m, end_m and rise_m must be finite numbers, got {start_m!r}, {end_m!r}, {rise_m!r}")
    if not end > start:
        raise InputError(f"end_m = {end_m!r} must be greater than start_m = {start_m!r}")
    return rise * np.clip((s - start) / (end - start), 0.0, 1.0)
