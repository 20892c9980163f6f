"""A roughness the user assumes for a route whose elevation cannot measure it (issue 12).

A route from a GPS track over a DEM or a sparse point cloud has the path and its grade but
not the wheel-scale roughness. The user then gives an ISO 8608 class or an RI
(:class:`AssumedRoughness`, carried by :attr:`profileopt.core.route.Route.assumed_roughness` and
by a route file's ``# roughness_class = C`` or ``# roughness_ri = 0.05`` line). The planner
gives every roughness window of such a route the assumed RI
(:func:`profileopt.core.segments.route_roughness_windows`), and ``verify`` drives the route's
elevation plus a seeded realisation of that roughness (:meth:`AssumedRoughness.realisation_m`),
so that the plan is judged on ground like the one it was planned for.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
from numpy.typing import ArrayLike

from ..errors import InputError
from .classes import iso8608_class_key, iso8608_expected_rms_m, iso8608_ri
from .synthetic import ISO8608_N_MAX_CPM, ISO8608_N_MIN_CPM, iso8608_profile

__all__ = ["AssumedRoughness", "MAX_ASSUMED_RI", "REALISATION_NYQUIST_SHARE", "WORST_CLASS", "unseen_roughness"]

#: An assumed RI above this (an RMS roughness twice the ground clearance) is no terrain a
#: vehicle drives; the roughest class, H, over 5 m is 1.29 for a clearance of 0.1 m.
MAX_ASSUMED_RI = 2.0
#: verify's synthetic roughness on a route sampled too coarsely for ISO8608_N_MAX_CPM stops
#: at this share of the route's Nyquist frequency (and is scaled up to the assumed RMS).
REALISATION_NYQUIST_SHARE = 0.9
#: The class whose spectral shape carries a given RI (every class has the same shape).
_SHAPE_CLASS = "C"


@dataclasses.dataclass(frozen=True)
class AssumedRoughness:
    """The roughness assumed for a route: an ISO 8608 class or an RI, exactly one.

    Attributes
    ----------
    road_class : str or None
        ISO 8608 class, one letter A (smoothest) to H; stored upper case.
    ri : float or None
        The RI (Eq. 1, detrended; dimensionless) of every roughness window, in
        [0, :data:`MAX_ASSUMED_RI`].
    """

    road_class: str | None = None
    ri: float | None = None

    def __post_init__(self) -> None:
        if (self.road_class is None) == (self.ri is None):
            raise InputError("assumed roughness: give exactly one of road_class (ISO 8608, A to H) and ri, "
                             f"got road_class = {self.road_class!r} and ri = {self.ri!r}")
        if self.road_class is not None:
            object.__setattr__(self, "road_class", iso8608_class_key(self.road_class))
            return
        try:
            value = float(self.ri)
        except (TypeError, ValueError):
            raise InputError(f"assumed roughness: ri = {self.ri!r} is not a number; give the RI, e.g. 0.05") from None
        if not (math.isfinite(value) and 0.0 <= value <= MAX_ASSUMED_RI):
            raise InputError(f"assumed roughness: ri = {self.ri!r} is not in [0, {MAX_ASSUMED_RI:g}]; the RI is "
                             "the RMS roughness over the ground clearance, dimensionless (was it given in percent "
                             "or in mm?)")
        object.__setattr__(self, "ri", value)

    @property
    def label(self) -> str:
        """What was assumed, for people: ``"ISO 8608 class C"`` or ``"RI 0.05 given"``."""
        if self.road_class is not None:
            return f"ISO 8608 class {self.road_class}"
        return f"RI {self.ri!r} given"  # repr: read back exactly by from_label

    @classmethod
    def from_label(cls, label: str) -> "AssumedRoughness":
        """The assumed roughness a :attr:`label` names, as a profile file records it (blanks
        may be written as underscores: ``ISO_8608_class_C``, ``RI_0.05_given``).

        Parameters
        ----------
        label : str
            ``"ISO 8608 class C"`` or ``"RI 0.05 given"``, with blanks or underscores.

        Returns
        -------
        AssumedRoughness

        Raises
        ------
        InputError
            Neither form.
        """
        words = str(label).replace("_", " ").split()
        if len(words) == 4 and words[:3] == ["ISO", "8608", "class"]:
            return cls(road_class=words[3])
        if len(words) == 3 and words[0] == "RI" and words[2] == "given":
            try:
                return cls(ri=float(words[1]))
            except ValueError:
                pass
        raise InputError(f"assumed roughness {label!r} is neither 'ISO 8608 class X' nor 'RI <value> given'")

    def ri_for(self, *, clearance_m: float, window_m: float) -> float:
        """The RI of every roughness window of the route, for a vehicle and window length.

        A class gives its RMS window RI (:func:`profileopt.terrain.classes.iso8608_ri`);
        a given RI is itself.

        Parameters
        ----------
        clearance_m : float
            The vehicle's ground clearance h (m), > 0.
        window_m : float
            The roughness window length W actually used (m), > 0.

        Returns
        -------
        float
            RI (dimensionless).
        """
        if self.road_class is None:
            return float(self.ri)
        return iso8608_ri(self.road_class, window_m=window_m, clearance_m=clearance_m)

    def realisation_band_cpm(self, s_m: ArrayLike) -> tuple[float, float]:
        """The band of :meth:`realisation_m` at these samples (cycles/m): ISO8608_N_MIN_CPM to
        the smaller of ISO8608_N_MAX_CPM and REALISATION_NYQUIST_SHARE / (2 d), d the median
        sample spacing.

        Parameters
        ----------
        s_m : array_like, shape (M,)
            The route's distances (m), strictly increasing, M >= 2.

        Returns
        -------
        n_min_cpm, n_max_cpm : float
            The band (cycles/m).

        Raises
        ------
        InputError
            Samples so sparse (spacing above 0.9 / (2 ISO8608_N_MIN_CPM), 41 m) that no band
            is left.
        """
        spacing = float(np.median(np.diff(np.asarray(s_m, dtype=float))))
        n_max = min(ISO8608_N_MAX_CPM, REALISATION_NYQUIST_SHARE * 0.5 / spacing)
        if not n_max > ISO8608_N_MIN_CPM:
            raise InputError(f"the route's samples are {spacing:g} m apart: too sparse to carry any roughness "
                             f"wave shorter than {1 / ISO8608_N_MIN_CPM:.0f} m; resample the route more densely")
        return ISO8608_N_MIN_CPM, n_max

    def realisation_m(self, s_m: ArrayLike, *, clearance_m: float, window_m: float, seed: int) -> np.ndarray:
        """A seeded random ISO 8608 profile at ``s_m`` whose RMS window roughness is the
        assumed one: the elevation verify adds to the route's.

        A class's own profile (:func:`profileopt.terrain.synthetic.iso8608_profile`) over the band
        ISO8608_N_MIN_CPM to ISO8608_N_MAX_CPM, at the median sample spacing d, read at
        ``s_m`` by linear interpolation. A route too coarse for that band (its Nyquist
        frequency 1 / (2 d) below ISO8608_N_MAX_CPM / REALISATION_NYQUIST_SHARE) gets the
        band up to REALISATION_NYQUIST_SHARE of its Nyquist frequency instead. A given RI
        takes class C's shape. Either is scaled so that its expected detrended RMS over
        windows of ``window_m`` is ``ri_for(...) * clearance_m`` (a class over the full band:
        a factor 1).

        Parameters
        ----------
        s_m : array_like, shape (M,)
            The route's distances (m), strictly increasing, M >= 2.
        clearance_m : float
            Ground clearance h (m), > 0.
        window_m : float
            The roughness window length W of the plan (m), > 0.
        seed : int
            Seed (>= 0) of the random phases.

        Returns
        -------
        numpy.ndarray, shape (M,)
            Elevation to add (m).

        Raises
        ------
        InputError
            A bad seed, or samples too sparse for any band (:meth:`realisation_band_cpm`).
        """
        s = np.asarray(s_m, dtype=float)
        spacing = float(np.median(np.diff(s)))
        _, n_max = self.realisation_band_cpm(s)
        shape = self.road_class or _SHAPE_CLASS
        length = float(s[-1] - s[0])
        base_s, base_z = iso8608_profile(shape, length + 2.0 * spacing, spacing, seed, n_max_cpm=n_max)
        wanted = self.ri_for(clearance_m=clearance_m, window_m=window_m) * clearance_m
        scale = wanted / iso8608_expected_rms_m(shape, window_m=window_m, n_max_cpm=n_max)
        return scale * np.interp(s - s[0], base_s, base_z)


#: What an ``unseen="worst"`` assumption means (:func:`unseen_roughness`): the roughest ISO 8608
#: class, H.
WORST_CLASS = "H"


def unseen_roughness(unseen: str | float) -> AssumedRoughness:
    """The roughness an ``unseen`` option names: ``"worst"`` (ISO 8608 class H,
    :data:`WORST_CLASS`), a class letter A-H, or an RI (a number): what the online selector and
    the MPC preview assume for terrain not yet measured.

    Parameters
    ----------
    unseen : str or float
        The assumption.

    Returns
    -------
    AssumedRoughness

    Raises
    ------
    InputError
        Anything else.
    """
    if isinstance(unseen, str):
        text = unseen.strip()
        if text.lower() == "worst":
            return AssumedRoughness(road_class=WORST_CLASS)
        if len(text) == 1 and text.isalpha():
            return AssumedRoughness(road_class=text)
        try:
            value = float(text)
        except ValueError:
            raise InputError(f"unseen = {unseen!r}: give 'worst', an ISO 8608 class A to H, or an RI (a number, "
                             "e.g. 0.05)") from None
        return AssumedRoughness(ri=value)
    if isinstance(unseen, bool) or not isinstance(unseen, (int, float)):
        raise InputError(f"unseen = {unseen!r}: give 'worst', an ISO 8608 class A to H, or an RI (a number)")
    return AssumedRoughness(ri=float(unseen))
