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

__all__ = ["GEO_EXTRA_HINT", "require_geo", "parse_crs", "length_units_m", "crs_label"]

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
        pyproj is not installed, or ``text`` is not a CRS pyproj knows.
    """
    pyproj = require_geo("pyproj", "using a coordinate reference system")
    try:
        return pyproj.CRS.from_user_input(text)
    except pyproj.exceptions.CRSError:
        shown = " ".join(str(text).split())[:80]
        raise InputError(f"{source}: {option} {shown!r} is not a CRS pyproj knows; give e.g. EPSG:32633") from None


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
        coordinates in metres.
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
    if not (horizontal_m > 0 and vertical_m > 0):  # pragma: no cover - pyproj gives a factor for every length unit
        raise InputError(f"{source}: the CRS {crs_label(crs)} states no length unit; give a projected CRS in metres")
    return horizontal_m, vertical_m
