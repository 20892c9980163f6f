"""What the readers of geographic files share: the optional packages and coordinate systems.

The packages of the ``geo`` extra (laspy with lazrs, rasterio, pyproj, gpxpy) are imported
only when a file needs them (``import profileopt`` and ``profileopt --help`` import none of
them); without one, :func:`require_geo` says in one line which extra to install.

A CRS is a :class:`pyproj.CRS`. :func:`parse_crs` turns a user's string (``EPSG:32633``,
WKT, PROJ) into one or says in one line that pyproj does not know it;
:func:`length_units_m` gives the metres per unit of a projected CRS's horizontal axes and
of its vertical axis (a compound CRS's vertical part), refusing a geographic CRS where
metres are needed.
"""

from __future__ import annotations

import importlib
from types import ModuleType
from typing import Any

from ..errors import InputError

__all__ = ["GEO_EXTRA_HINT", "EARTH_RADIUS_M", "UNIT_RANGE_M", "require_geo", "parse_crs", "length_units_m", "crs_label"]

#: The Earth's equatorial radius (m, WGS 84): a CRS whose ellipsoid is more than 2 % from it
#: (every terrestrial ellipsoid is within 0.2 %) is on another body, or a unit sphere.
EARTH_RADIUS_M = 6_378_137.0
#: Lengths (m) a CRS's unit may have: from a micrometre to 100 km (a unit of 1e-300 m or of
#: NaN is a damaged record, not a unit).
UNIT_RANGE_M = (1e-6, 1e5)
#: How to install the optional packages, for the messages that need one of them.
GEO_EXTRA_HINT = "pip install 'profileopt[geo]'"


def require_geo(module: str, what: str) -> ModuleType:
    """Import one package of the ``geo`` extra, or raise one line naming the extra.

    Parameters
    ----------
    module : str
        The module to import ("laspy", "rasterio", "pyproj", "gpxpy").
    what : str
        What it is needed for, for the message ("reading LAS/LAZ").

    Returns
    -------
    module
        The imported module.

    Raises
    ------
    InputError
        The package is not installed.
    """
    try:
        return importlib.import_module(module)
    except ImportError:
        raise InputError(f"{what} needs the geo extra ({module} is not installed): {GEO_EXTRA_HINT}") from None


def parse_crs(text: str, source: str, option: str) -> Any:
    """The :class:`pyproj.CRS` a user named, or one line saying pyproj does not know it.

    Parameters
    ----------
    text : str
        What the user gave: an authority code (``EPSG:32633``), WKT or a PROJ string.
    source : str
        The file the CRS is for, for the message.
    option : str
        Where the user gave it ("--track-crs", "the file's 'crs' member"), for the message.

    Returns
    -------
    pyproj.CRS

    Raises
    ------
    InputError
        pyproj is not installed, ``text`` is not a CRS pyproj knows, or its ellipsoid is
        not the Earth's (``+proj=longlat +R=1``: pyproj cannot transform it to an Earth CRS).
    """
    pyproj = require_geo("pyproj", "using a coordinate reference system")
    shown = " ".join(str(text).split())[:80]
    try:
        crs = pyproj.CRS.from_user_input(text)
    except pyproj.exceptions.CRSError:
        raise InputError(f"{source}: {option} {shown!r} is not a CRS pyproj knows; give e.g. EPSG:32633") from None
    ellipsoid = crs.ellipsoid
    radius_m = float(ellipsoid.semi_major_metre) if ellipsoid is not None else EARTH_RADIUS_M
    if not abs(radius_m - EARTH_RADIUS_M) <= 0.02 * EARTH_RADIUS_M:
        raise InputError(f"{source}: {option} {shown!r} is a CRS on a body of radius {radius_m:g} m, not on the "
                         "Earth (PROJ does not transform between them); give an Earth CRS, e.g. EPSG:32633")
    return crs


def crs_label(crs: Any) -> str:
    """A short name of a CRS for messages and notes: ``EPSG:32633`` if it has one, else its name.

    Parameters
    ----------
    crs : pyproj.CRS or None
        The CRS (None: "no CRS").

    Returns
    -------
    str
    """
    if crs is None:
        return "no CRS"
    code = crs.to_authority(min_confidence=90)
    return f"{code[0]}:{code[1]}" if code else crs.name


def length_units_m(crs: Any, source: str) -> tuple[float, float]:
    """Metres per unit of a projected CRS: (horizontal axes, vertical axis).

    The horizontal factor is that of the first axis of the projected CRS (both axes of a
    projected CRS share one unit); the vertical one that of a compound CRS's vertical part,
    or the horizontal one when the CRS has no vertical part (the file then states no
    vertical unit, and z is taken in the horizontal unit).

    Parameters
    ----------
    crs : pyproj.CRS
        The coordinate reference system.
    source : str
        The file whose CRS it is, for the message.

    Returns
    -------
    (float, float)
        Metres per unit of x and y, and of z (1.0 for metres, 0.3048 for feet, 1200/3937
        for US survey feet).

    Raises
    ------
    InputError
        The CRS is geographic or geocentric (degrees, or no map plane): it cannot give
        coordinates in metres; or its unit is outside :data:`UNIT_RANGE_M`.
    """
    parts = list(crs.sub_crs_list) if crs.is_compound else [crs]
    horizontal = next((p for p in parts if p.is_projected), None)
    if horizontal is None:
        kind = "geographic (degrees)" if any(p.is_geographic for p in parts) else "not projected"
        raise InputError(f"{source}: the CRS {crs_label(crs)} is {kind}, and metres are needed here; "
                         "give a projected CRS such as the UTM zone, e.g. EPSG:32633")
    axis = horizontal.axis_info[0]
    horizontal_m = float(axis.unit_conversion_factor)
    vertical = next((p for p in parts if p.is_vertical), None)
    vertical_m = float(vertical.axis_info[0].unit_conversion_factor) if vertical is not None else horizontal_m
    low, high = UNIT_RANGE_M
    if not (low <= horizontal_m <= high and low <= vertical_m <= high):  # NaN, 0, 1e-300: not a length unit
        raise InputError(f"{source}: the CRS {crs_label(crs)} states units of {horizontal_m:g} m (x, y) and "
                         f"{vertical_m:g} m (z), not length units (they lie between {low:g} and {high:g} m); give a "
                         "projected CRS in metres, e.g. EPSG:32633")
    return horizontal_m, vertical_m
