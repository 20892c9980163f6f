"""Terrain maps: raster DEMs (GeoTIFF), OpenCRG road surfaces and point clouds, in metres.

:func:`read_terrain` picks the reader by the file name's ending: :func:`read_geotiff`
(an :class:`ElevationGrid`), :func:`read_crg_surface` (a :class:`CrgSurface`) or
:func:`~profileopt.io.las.read_las` (a :class:`~profileopt.io.las.PointCloud`). Grids and
surfaces answer :meth:`elevation_at` by bilinear interpolation between samples, NaN
outside or where a needed sample has no data; nothing is extrapolated.

Memory is bounded: given the track the terrain will be sampled along, :func:`read_terrain`
reads only what sampling needs (a cloud's points near the track, in chunks; a raster's window
around it). Without one, a cloud of more than :data:`~profileopt.io.las.MAX_CLOUD_POINTS`
points or a raster of more than :data:`MAX_GRID_CELLS` cells is refused.

Every problem is one :class:`~profileopt.errors.InputError` line naming the file, what is
wrong and how to fix it. rasterio, laspy and pyproj (the ``geo`` extra) are imported only
when a file needs them.
"""

from __future__ import annotations

import dataclasses
import math
import os
import re
from pathlib import Path
from typing import Any, Callable

import numpy as np

from ..errors import InputError
from . import inputs
from .elevation import parse_opencrg
from .geo import crs_label, length_units_m, parse_crs, require_geo
from .las import PointCloud, read_las

__all__ = ["ElevationGrid", "CrgSurface", "read_geotiff", "read_crg_surface", "read_terrain", "TERRAIN_SUFFIXES",
           "MAX_GRID_CELLS", "BAND_SCALE_RANGE"]

#: File name endings :func:`read_terrain` accepts, and the kind of terrain each holds.
TERRAIN_SUFFIXES = {".las": "LAS", ".laz": "LAZ", ".tif": "GeoTIFF", ".tiff": "GeoTIFF", ".crg": "OpenCRG"}

#: Most cells of a raster read (25 million: about 200 MB of elevations in float64, with the band
#: read and its mask about 350 MB at the peak); a larger raster is read only in the window
#: around a track (:func:`read_terrain`'s ``track``).
MAX_GRID_CELLS = 25_000_000
#: The band scale factors a DEM may state: 0 (or 1e-300) would make every elevation the offset.
BAND_SCALE_RANGE = (1e-6, 1e6)

#: Band unit names (GDAL's unit type) and their length in metres.
_BAND_UNITS_M = {"": 1.0, "m": 1.0, "metre": 1.0, "meter": 1.0, "metres": 1.0, "meters": 1.0,
                 "ft": 0.3048, "foot": 0.3048, "feet": 0.3048, "us survey foot": 1200.0 / 3937.0,
                 "ftus": 1200.0 / 3937.0, "us-ft": 1200.0 / 3937.0}


def _bilinear(grid: np.ndarray, row: np.ndarray, col: np.ndarray) -> np.ndarray:
    """Bilinear interpolation of ``grid`` at fractional indices; NaN outside [0, n - 1]
    (widened by 1e-9 of a step, so that a point on the edge computed with rounding errors
    counts as on it) or where one of the four samples is NaN (a weight of 0 does not excuse
    a NaN)."""
    rows, cols = grid.shape
    row, col = np.broadcast_arrays(np.asarray(row, dtype=float), np.asarray(col, dtype=float))
    out = np.full(row.shape, np.nan)
    edge = 1e-9
    inside = (row >= -edge) & (row <= rows - 1 + edge) & (col >= -edge) & (col <= cols - 1 + edge)
    r, c = np.clip(row[inside], 0, rows - 1), np.clip(col[inside], 0, cols - 1)
    r0 = np.minimum(np.floor(r).astype(np.int64), rows - 2)
    c0 = np.minimum(np.floor(c).astype(np.int64), cols - 2)
    fr, fc = r - r0, c - c0
    out[inside] = ((grid[r0, c0] * (1 - fc) + grid[r0, c0 + 1] * fc) * (1 - fr)
                   + (grid[r0 + 1, c0] * (1 - fc) + grid[r0 + 1, c0 + 1] * fc) * fr)
    return out


def _fraction(value: np.ndarray, axis: np.ndarray) -> np.ndarray:
    """Fractional index of ``value`` on the increasing ``axis``; NaN beyond its ends by more
    than 1e-9 of the smallest step (rounding on the edge counts as on it)."""
    value = np.asarray(value, dtype=float)
    index = np.interp(value, axis, np.arange(axis.size, dtype=float))
    tolerance = 1e-9 * float(np.min(np.diff(axis)))
    return np.where((value < axis[0] - tolerance) | (value > axis[-1] + tolerance) | np.isnan(value), np.nan, index)


@dataclasses.dataclass(frozen=True, eq=False)
class ElevationGrid:
    """A raster DEM in metres: elevations on a regular, north-up grid of cells.

    Attributes
    ----------
    z_m : numpy.ndarray, shape (rows, cols)
        Elevation (m) of each cell, NaN where the raster has no data.
    transform : tuple of float, (x0_m, dx_m, y0_m, dy_m)
        Where the cells are: the CENTRE of cell (row, col) is at ``x = x0_m + col * dx_m``,
        ``y = y0_m + row * dy_m`` (m, in ``crs``); dy_m is negative for the usual north-up
        raster whose first row is the northernmost.
    crs : pyproj.CRS or None
        The horizontal coordinate reference system.
    source : str
        The file read, for messages.
    cell_size_m : tuple of float
        (dx, |dy|): the cell's width and height (m).
    notes : tuple of str
        What was done on the way (units converted, CRS supplied), one line each.
    file_extent_m : tuple of float or None
        (xmin, xmax, ymin, ymax) (m) of the cell centres of the whole raster, where only a
        window around a track was read; None: those of :attr:`z_m` (:meth:`extent_m`).
    """

    z_m: np.ndarray
    transform: tuple[float, float, float, float]
    crs: Any
    source: str
    cell_size_m: tuple[float, float]
    notes: tuple[str, ...] = ()
    file_extent_m: tuple[float, float, float, float] | None = None

    def elevation_at(self, x_m: np.ndarray, y_m: np.ndarray) -> np.ndarray:
        """Bilinear interpolation between the four cell centres around each point.

        Parameters
        ----------
        x_m, y_m : numpy.ndarray
            Positions (m, in :attr:`crs`), of one shape (or broadcastable).

        Returns
        -------
        numpy.ndarray
            Elevation (m), NaN outside the cell centres' extent (:meth:`extent_m`) or where
            one of the four cells has no data.
        """
        x0, dx, y0, dy = self.transform
        return _bilinear(self.z_m, (np.asarray(y_m, dtype=float) - y0) / dy, (np.asarray(x_m, dtype=float) - x0) / dx)

    def extent_m(self) -> tuple[float, float, float, float]:
        """Where :meth:`elevation_at` is defined: (xmin, xmax, ymin, ymax) of the cell centres (m)."""
        x0, dx, y0, dy = self.transform
        rows, cols = self.z_m.shape
        xs, ys = (x0, x0 + (cols - 1) * dx), (y0, y0 + (rows - 1) * dy)
        return min(xs), max(xs), min(ys), max(ys)


@dataclasses.dataclass(frozen=True, eq=False)
class CrgSurface:
    """An OpenCRG road surface on a straight reference line, in metres.

    The reference line starts at (x0_m, y0_m) with heading phi_rad (counter-clockwise from
    the x axis); u runs along it, v to its left. A point (x, y) has
    ``u = u_m[0] + (x - x0) cos(phi) + (y - y0) sin(phi)`` and
    ``v = -(x - x0) sin(phi) + (y - y0) cos(phi)``.

    Attributes
    ----------
    u_m : numpy.ndarray, shape (nu,)
        Distance along the reference line of each row (m), increasing.
    v_m : numpy.ndarray, shape (nv,)
        Lateral position of each long section (m, left positive), increasing.
    z_m : numpy.ndarray, shape (nu, nv)
        Elevation (m), NaN where the file has no data.
    x0_m, y0_m : float
        Start of the reference line (m): the position of ``u_m[0]``, v = 0.
    phi_rad : float
        Heading of the reference line (rad).
    crs : pyproj.CRS or None
        None unless the caller supplied one (OpenCRG files state no CRS).
    source : str
        The file read, for messages.
    notes : tuple of str
        What was done on the way, one line each.
    """

    u_m: np.ndarray
    v_m: np.ndarray
    z_m: np.ndarray
    x0_m: float
    y0_m: float
    phi_rad: float
    crs: Any
    source: str
    notes: tuple[str, ...] = ()

    def uv_m(self, x_m: np.ndarray, y_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Surface coordinates (u, v) of map positions (x, y).

        Parameters
        ----------
        x_m, y_m : numpy.ndarray
            Positions (m), of one shape (or broadcastable).

        Returns
        -------
        (numpy.ndarray, numpy.ndarray)
            u along the reference line and v to its left (m).
        """
        dx, dy = np.asarray(x_m, dtype=float) - self.x0_m, np.asarray(y_m, dtype=float) - self.y0_m
        cos, sin = math.cos(self.phi_rad), math.sin(self.phi_rad)
        return self.u_m[0] + dx * cos + dy * sin, -dx * sin + dy * cos

    def elevation_at(self, x_m: np.ndarray, y_m: np.ndarray) -> np.ndarray:
        """Bilinear interpolation in (u, v) between the four samples around each point.

        Parameters
        ----------
        x_m, y_m : numpy.ndarray
            Positions (m), of one shape (or broadcastable).

        Returns
        -------
        numpy.ndarray
            Elevation (m), NaN outside the surface or where a needed sample has no data.
        """
        u, v = self.uv_m(x_m, y_m)
        return _bilinear(self.z_m, _fraction(u, self.u_m), _fraction(v, self.v_m))

    def extent_m(self) -> tuple[float, float, float, float]:
        """(xmin, xmax, ymin, ymax) (m) of the surface's four corners; the surface is the
        rotated rectangle inside, :meth:`elevation_at` is NaN in the rest of the box."""
        du, v = self.u_m[[0, -1, -1, 0]] - self.u_m[0], self.v_m[[0, 0, -1, -1]]
        cos, sin = math.cos(self.phi_rad), math.sin(self.phi_rad)
        x, y = self.x0_m + du * cos - v * sin, self.y0_m + du * sin + v * cos
        return float(x.min()), float(x.max()), float(y.min()), float(y.max())


def read_geotiff(path: str | os.PathLike, *, terrain_crs: str | None = None,
                 near: Callable[[Any], tuple[float, float, float, float] | None] | None = None) -> ElevationGrid:
    """Read band 1 of a GeoTIFF DEM (with rasterio) as an :class:`ElevationGrid` in metres.

    Cells whose value is the band's nodata value (or NaN) become NaN; the band's scale and
    offset, if it states them, are applied (a scale outside :data:`BAND_SCALE_RANGE` is
    refused: 0 would make every elevation the offset). Horizontal coordinates are converted to metres
    by the unit of the CRS's axes (a DEM in US survey feet gives metres all the same).
    Elevations are taken in metres unless the band's unit (GDAL unit type: ``ft``,
    ``US survey foot``) or a compound CRS's vertical part says otherwise; then they are
    converted. (A horizontal CRS in feet says nothing about z: unlike LAS, where z is then
    taken in the horizontal unit, a DEM's elevations stay metres.) Rotated or sheared rasters are refused.
    With ``near``, only the window of cells around the box it gives is read (rasterio
    windows), so a raster of any size is read in bounded memory; at most
    :data:`MAX_GRID_CELLS` cells are read.

    Parameters
    ----------
    path : str or os.PathLike
        The ``.tif`` / ``.tiff`` file.
    terrain_crs : str, optional
        The CRS of the raster (``EPSG:32633``): supplies one the file lacks, or overrides
        the file's (with a note).
    near : callable, optional
        Called once with the raster's CRS; returns the box (xmin, xmax, ymin, ymax) (m, in
        that CRS) whose cells are needed, or None for all of them.

    Returns
    -------
    ElevationGrid

    Raises
    ------
    InputError
        Not a readable GeoTIFF, no CRS and no ``terrain_crs``, a geographic CRS, a rotated
        or sheared raster, fewer than 2 x 2 cells, more than :data:`MAX_GRID_CELLS` cells
        to read, a band scale outside :data:`BAND_SCALE_RANGE` or an offset that is not
        finite, an unknown band unit, or rasterio missing (each one line).
    """
    path = Path(path)
    rasterio = require_geo("rasterio", "reading GeoTIFF")
    inputs.check_regular_input(path, "GeoTIFF file")
    notes: list[str] = []
    try:
        with rasterio.open(path) as dataset:
            transform, stated, unit = dataset.transform, dataset.crs, (dataset.units[0] or "")
            scale, offset = float(dataset.scales[0]), float(dataset.offsets[0])
            crs = geotiff_crs(path, stated, terrain_crs, notes)
            if transform.b != 0 or transform.d != 0:
                raise InputError(f"{path}: the raster is rotated or sheared (geotransform {tuple(transform)[:6]}); "
                                 "warp it north-up first, e.g. 'gdalwarp in.tif out.tif'")
            if not (math.isfinite(scale) and BAND_SCALE_RANGE[0] <= abs(scale) <= BAND_SCALE_RANGE[1]
                    and math.isfinite(offset)):
                raise InputError(f"{path}: band 1's scale {scale:g} and offset {offset:g} would make its elevations "
                                 f"meaningless (a scale must lie between {BAND_SCALE_RANGE[0]:g} and "
                                 f"{BAND_SCALE_RANGE[1]:g}, an offset be finite): the file's metadata are wrong; set "
                                 "them right (e.g. 'gdal_edit.py -scale 1 -offset 0 FILE')")
            horizontal_m = length_units_m(crs, str(path))[0]
            window = _window(dataset, near(crs) if near is not None else None, horizontal_m)
            rows, cols = (dataset.height, dataset.width) if window is None else (window.height, window.width)
            if rows * cols > MAX_GRID_CELLS:
                raise InputError(f"{path}: the raster has {rows:,} x {cols:,} cells to read, more than the "
                                 f"{MAX_GRID_CELLS:,} read at once; read only the window around a track "
                                 "(read_terrain's track, as profileopt route and plan do) or cut it first (e.g. "
                                 "'gdal_translate -projwin XMIN YMAX XMAX YMIN in.tif out.tif')")
            band = dataset.read(1, masked=True, window=window)
            full = _cell_centre_extent(transform, dataset.height, dataset.width, horizontal_m)
            if window is not None:  # the window's own geotransform (north-up: b = d = 0)
                transform = type(transform)(transform.a, 0.0, transform.c + window.col_off * transform.a,
                                            0.0, transform.e, transform.f + window.row_off * transform.e)
    except rasterio.errors.RasterioError as exc:
        raise unreadable_geotiff(path, exc) from None
    except rasterio.errors.CRSError as exc:  # not a RasterioError: a ValueError, raised as the file is opened
        raise unreadable_geotiff_crs(path, exc, terrain_crs) from None
    rows, cols = band.shape
    if rows < 2 or cols < 2:
        raise InputError(f"{path}: the raster has {rows} x {cols} cells; interpolation needs at least 2 x 2")
    vertical = next((p for p in crs.sub_crs_list if p.is_vertical), None) if crs.is_compound else None
    vertical_m = float(vertical.axis_info[0].unit_conversion_factor) if vertical is not None else 1.0
    if unit.strip().lower() not in _BAND_UNITS_M:
        raise InputError(f"{path}: band 1's unit {unit!r} is not a length unit this reader knows (m, ft, "
                         "US survey foot); convert the DEM to metres")
    band_m = _BAND_UNITS_M[unit.strip().lower()]
    if unit.strip():
        vertical_m = band_m
    z = np.ma.filled(band.astype(float), np.nan) * scale + offset
    if vertical_m != 1.0:
        notes.append(f"{path.name}: elevations converted from units of {vertical_m:g} m to metres")
    if horizontal_m != 1.0:
        notes.append(f"{path.name}: x, y converted from the CRS's unit ({horizontal_m:g} m) to metres")
        if vertical_m == 1.0 and not unit.strip() and vertical is None:
            notes.append(f"{path.name}: elevations taken in metres, as the file states no vertical unit, though its "
                         f"CRS is in units of {horizontal_m:g} m; if they are in that unit, convert the DEM "
                         "(e.g. gdal_calc) or set its band unit")
    dx, dy = transform.a * horizontal_m, transform.e * horizontal_m
    x0 = (transform.c + 0.5 * transform.a) * horizontal_m  # the centre of cell (0, 0)
    y0 = (transform.f + 0.5 * transform.e) * horizontal_m
    return ElevationGrid(z_m=z * vertical_m, transform=(x0, dx, y0, dy), crs=crs, source=str(path),
                         cell_size_m=(abs(dx), abs(dy)), notes=tuple(notes), file_extent_m=full)


def unreadable_geotiff(path: Path, exc: Exception) -> InputError:
    """The one line for a file rasterio cannot read as a GeoTIFF (its reason, whitespace folded)."""
    reason = " ".join(str(exc).split())[:160]
    return InputError(f"{path}: is not a readable GeoTIFF (rasterio: {reason}); check the file")


def unreadable_geotiff_crs(path: Path, exc: Exception, terrain_crs: str | None = None) -> InputError:
    """The one line for a GeoTIFF whose CRS (GeoKeys or WKT) GDAL cannot parse as it opens the
    file (a unit of NaN, 0 or a negative size): the file cannot be read at all, so
    ``terrain_crs`` cannot stand in for it.

    Parameters
    ----------
    path : pathlib.Path
        The file.
    exc : Exception
        rasterio's ``CRSError``.
    terrain_crs : str, optional
        The CRS the user gave (``--terrain-crs``), if any.

    Returns
    -------
    InputError
    """
    reason = " ".join(str(exc).split())[:160]
    given = (f"; --terrain-crs {terrain_crs} cannot stand in for it, as the file cannot be opened with it"
             if terrain_crs is not None else "")
    return InputError(f"{path}: its CRS (GeoTIFF GeoKeys or WKT) cannot be read (GDAL: {reason}; often a unit or "
                      f"parameter that is not a valid number: NaN, 0, negative){given}; set it right, e.g. "
                      f"'gdal_edit.py -a_srs EPSG:32633 {path.name}'")


def geotiff_crs(path: Path, stated: Any, terrain_crs: str | None, notes: list[str]) -> Any:
    """The raster's CRS: ``terrain_crs`` (with a note where it overrides the file's), else the file's."""
    crs = parse_crs(stated.to_wkt(), str(path), "the file's CRS") if stated is not None else None
    if terrain_crs is not None:
        given = parse_crs(terrain_crs, str(path), "--terrain-crs")
        if crs is not None and crs != given:
            notes.append(f"{path.name}: CRS {crs_label(given)} (--terrain-crs) instead of the file's {crs_label(crs)}")
        crs = given
    if crs is None:
        raise InputError(f"{path}: the GeoTIFF states no CRS; pass --terrain-crs (e.g. EPSG:32633)")
    return crs


def _cell_centre_extent(transform: Any, rows: int, cols: int, unit_m: float) -> tuple[float, float, float, float]:
    """(xmin, xmax, ymin, ymax) (m) of the centres of a north-up raster's cells."""
    xs = (transform.c + 0.5 * transform.a) * unit_m, (transform.c + (cols - 0.5) * transform.a) * unit_m
    ys = (transform.f + 0.5 * transform.e) * unit_m, (transform.f + (rows - 0.5) * transform.e) * unit_m
    return min(xs), max(xs), min(ys), max(ys)


def _window(dataset: Any, box_m: tuple[float, float, float, float] | None, unit_m: float) -> Any:
    """The rasterio window of the cells around ``box_m`` (m), widened by a cell each side for
    the interpolation and clipped to the raster, at least 2 x 2 cells; None: the whole raster."""
    if box_m is None:
        return None
    from rasterio.windows import Window

    transform = dataset.transform
    x0, x1, y0, y1 = (v / unit_m for v in box_m)
    cols = sorted(((x0 - transform.c) / transform.a, (x1 - transform.c) / transform.a))
    rows = sorted(((y0 - transform.f) / transform.e, (y1 - transform.f) / transform.e))

    def span(low: float, high: float, size: int) -> tuple[int, int]:
        start = int(np.clip(math.floor(low) - 1, 0, max(size - 2, 0)))
        stop = int(np.clip(math.ceil(high) + 1, start + 2, size))
        return start, stop

    c0, c1 = span(*cols, dataset.width)
    r0, r1 = span(*rows, dataset.height)
    return Window(c0, r0, c1 - c0, r1 - r0)


_V_AT = re.compile(r"^long section at v\s*=\s*([^,]*)", re.IGNORECASE)


def _lateral_m(path: Path, text: str) -> float:
    """The v (m) of a ``D:long section at v = ...`` line, or one line naming it."""
    from .table import decimal_number

    value = decimal_number(text)  # ASCII decimal notation, as every number the project reads
    if value is None or not math.isfinite(value):
        raise InputError(f"{path}: 'D:long section at v = {text.strip()}' does not state a lateral position in m; "
                         "write a finite number there (e.g. 'D:long section at v = -1.500,m')")
    return value


def read_crg_surface(path: str | os.PathLike, *, terrain_crs: str | None = None) -> CrgSurface:
    """Read an OpenCRG file (binary data formats) as a road surface on a straight reference line.

    The data are read by :func:`~profileopt.io.elevation.parse_opencrg`. Lateral positions
    come from the ``D:long section at v = ...`` lines when they state them, else from
    ``long_section_v_right`` (the first column), ``long_section_v_increment`` and
    ``long_section_v_left`` (the last). The reference line starts at
    ``reference_line_start_x``, ``reference_line_start_y`` with heading
    ``reference_line_start_phi`` (each 0 when absent, OpenCRG's default). A curved
    reference line (a ``reference line phi`` column, or start and end headings that
    differ), banking or slope columns, and reference line offsets are refused.

    Parameters
    ----------
    path : str or os.PathLike
        The ``.crg`` file.
    terrain_crs : str, optional
        The CRS in which x0, y0 are given (OpenCRG files state none); None leaves it unstated.

    Returns
    -------
    CrgSurface

    Raises
    ------
    InputError
        Everything :func:`~profileopt.io.elevation.parse_opencrg` refuses, a curved
        reference line, lateral positions missing or inconsistent with the columns, or an
        unknown CRS (each one line).
    """
    crg = parse_opencrg(path)
    path = crg.path
    names = [text.lower() for text in crg.columns]
    for text in names:
        if text.startswith("reference line phi"):
            raise InputError(f"{path}: the reference line is curved (a 'reference line phi' column); only straight "
                             "reference lines can be read as a surface, use read_opencrg for one track")
        if text.startswith("reference line"):
            raise InputError(f"{path}: column {text!r} (banking or slope of the reference line) is not supported; "
                             "apply it with OpenCRG's tools first")
    start_phi = crg.number("reference_line_start_phi", 0.0)
    end_phi = crg.number("reference_line_end_phi", start_phi)
    if not math.isclose(start_phi, end_phi, abs_tol=1e-12):
        raise InputError(f"{path}: reference_line_start_phi = {start_phi:g} and reference_line_end_phi = "
                         f"{end_phi:g} differ: the reference line is curved; only straight ones can be read")
    for key in ("reference_line_offset_x", "reference_line_offset_y", "reference_line_offset_phi",
                "reference_line_offset_z"):
        if crg.number(key, 0.0) != 0.0:
            raise InputError(f"{path}: header key {key!r} = {crg.keys[key]} moves the reference line; apply the "
                             "offset with OpenCRG's tools first")
    count = len(names)
    stated = [_V_AT.match(text) for text in crg.columns]
    if all(stated):
        v = np.array([_lateral_m(path, m.group(1)) for m in stated])
    elif any(stated):
        raise InputError(f"{path}: some 'D:' lines state 'long section at v = ...' and some do not; state all or none")
    else:
        if "long_section_v_right" not in crg.keys or "long_section_v_increment" not in crg.keys:
            raise InputError(f"{path}: the header states no lateral positions (long_section_v_right and "
                             "long_section_v_increment) and the 'D:' lines none either; add them")
        right = crg.number("long_section_v_right")
        step = crg.number("long_section_v_increment")
        v = right + step * np.arange(count)
        left = crg.number("long_section_v_left", float(v[-1]))
        if not (step > 0 or count == 1) or not math.isclose(left, v[-1], abs_tol=1e-6 * max(1.0, abs(step))):
            raise InputError(f"{path}: long_section_v_right = {right:g} + {count - 1} x long_section_v_increment = "
                             f"{step:g} gives {v[-1]:g}, but long_section_v_left = {left:g}; fix the header")
    if count < 2 or not np.all(np.diff(v) > 0):
        raise InputError(f"{path}: the lateral positions {v.tolist()[:6]} must be at least 2 and increase; "
                         "a surface needs 2 or more long sections")
    crs = None if terrain_crs is None else parse_crs(terrain_crs, str(path), "--terrain-crs")
    return CrgSurface(u_m=crg.u_m, v_m=v, z_m=crg.values, x0_m=crg.number("reference_line_start_x", 0.0),
                      y0_m=crg.number("reference_line_start_y", 0.0), phi_rad=start_phi, crs=crs, source=str(path))


def read_terrain(path: str | os.PathLike, *, terrain_crs: str | None = None, track: Any = None,
                 spacing_m: float | None = None, corridor_m: float | None = None
                 ) -> PointCloud | ElevationGrid | CrgSurface:
    """Read a terrain map, the reader chosen by the file name's ending.

    ``.las`` / ``.laz``: :func:`~profileopt.io.las.read_las`. With ``terrain_crs`` the
    cloud's CRS is that one (supplied, or overriding the file's) and its units are that
    CRS's axis units (z in the horizontal unit unless the CRS has a vertical part);
    without it, a file without a CRS is refused as by ``read_las``.
    ``.tif`` / ``.tiff``: :func:`read_geotiff`. ``.crg``: :func:`read_crg_surface`.

    With a ``track``, only the part of the terrain that sampling along it needs is read: a
    cloud's points within :func:`~profileopt.terrain.ground_track.cloud_margin_m` of the
    track (read in chunks, so a cloud of any size fits in memory), a raster's window of cells
    around the track's box and that margin. The track is placed on the terrain as
    :func:`~profileopt.terrain.ground_track.route_from_track` places it.

    Parameters
    ----------
    path : str or os.PathLike
        The terrain file.
    terrain_crs : str, optional
        The terrain's CRS (``EPSG:32633``), for a file that states none or states a wrong one.
    track : Track, optional
        The track the terrain will be sampled along (:func:`profileopt.io.read_track`).
    spacing_m, corridor_m : float, optional
        The ``spacing_m`` and ``corridor_m`` it will be sampled with (m); None: the
        defaults of :func:`~profileopt.terrain.ground_track.route_from_track`.

    Returns
    -------
    PointCloud or ElevationGrid or CrgSurface

    Raises
    ------
    InputError
        An unknown file ending, or what the reader refuses (one line).
    """
    path = Path(path)
    kind = TERRAIN_SUFFIXES.get(path.suffix.lower())
    if kind is None:
        raise InputError(f"{path}: a terrain file must end in {', '.join(TERRAIN_SUFFIXES)} (LAS/LAZ point cloud, "
                         f"GeoTIFF DEM or OpenCRG), not {path.suffix or 'no ending'!r}; rename or convert it")
    from ..defaults import DEFAULT_CORRIDOR_M

    corridor = DEFAULT_CORRIDOR_M if corridor_m is None else float(corridor_m)
    if kind == "GeoTIFF":
        near = None if track is None else (lambda crs: track_box_m(track, crs, str(path), None, spacing_m, corridor))
        return read_geotiff(path, terrain_crs=terrain_crs, near=near)
    if kind == "OpenCRG":
        return read_crg_surface(path, terrain_crs=terrain_crs)
    keep = None if track is None else NearTrack(track, str(path), spacing_m, corridor)
    return read_cloud(path, terrain_crs=terrain_crs, keep=keep)


def read_cloud(path: Path, *, terrain_crs: str | None, keep: "NearTrack | None") -> PointCloud:
    """A LAS/LAZ cloud as :func:`read_terrain` reads it: ``terrain_crs`` gives its CRS and
    units (else the file's); only the points ``keep`` selects are held (None: all)."""
    if terrain_crs is None:
        with _crs_is_the_fix():
            return _kept(read_las(path, keep=keep), keep)
    crs = parse_crs(terrain_crs, str(path), "--terrain-crs")
    units = length_units_m(crs, str(path))
    cloud = _kept(read_las(path, units_m=units, crs=crs, keep=keep), keep)
    header = dataclasses.replace(cloud.header, crs=crs_label(crs),
                                 units_source=f"--terrain-crs {crs_label(crs)} ({units[0]:g} m, {units[1]:g} m per unit)")
    return dataclasses.replace(cloud, header=header, crs=crs)


def cloud_header(path: Path, *, terrain_crs: str | None) -> tuple[Any, Any]:
    """The (:class:`~profileopt.io.las.LasHeader`, CRS) of a LAS/LAZ file as :func:`read_cloud`
    would read it, without decoding a point."""
    from .las import read_las_header

    if terrain_crs is None:
        with _crs_is_the_fix():
            return read_las_header(path)
    crs = parse_crs(terrain_crs, str(path), "--terrain-crs")
    return read_las_header(path, units_m=length_units_m(crs, str(path)), crs=crs)


class _crs_is_the_fix:
    """read_las's fix for a file without units names its API argument; here the CRS is the fix."""

    def __enter__(self) -> None:
        return None

    def __exit__(self, kind: Any, exc: Any, trace: Any) -> None:
        if isinstance(exc, InputError):
            message = re.sub(r"pass units_m \(metres per file unit[^)]*\)",
                             "give its CRS with terrain_crs (e.g. EPSG:32633)", str(exc))
            raise InputError(message) from None


def track_box_m(track: Any, crs: Any, source: str, density: float | None, spacing_m: float | None,
                 corridor_m: float) -> tuple[float, float, float, float]:
    """The box (m) around the track that sampling it needs: its own box widened by the margin."""
    from ..terrain.ground_track import cloud_margin_m, track_on_terrain_m

    x, y = track_on_terrain_m(track, crs, source)
    margin = cloud_margin_m(density, spacing_m, corridor_m)
    return float(x.min()) - margin, float(x.max()) + margin, float(y.min()) - margin, float(y.max()) + margin


class NearTrack:
    """The points of a cloud within ``margin_m`` of a track: the ``keep`` of read_las."""

    def __init__(self, track: Any, source: str, spacing_m: float | None, corridor_m: float, *,
                 density_per_m2: float | None = None) -> None:
        self.track, self.source, self.spacing_m, self.corridor_m = track, source, spacing_m, corridor_m
        self.margin_m: float | None = None
        # the density that sets the margin, when it is not the file's own (tiles: all of theirs)
        self.density_per_m2 = density_per_m2

    def __call__(self, crs: Any, density: float | None) -> Callable[[np.ndarray, np.ndarray], np.ndarray]:
        from scipy.spatial import cKDTree

        from ..core.route import path_distance_m
        from ..terrain.ground_track import cloud_margin_m, track_on_terrain_m

        if self.density_per_m2 is not None:
            density = self.density_per_m2
        x, y = track_on_terrain_m(self.track, crs, self.source)
        self.margin_m = margin = cloud_margin_m(density, self.spacing_m, self.corridor_m)
        # nodes every half margin along the track: a point within the margin of the track is
        # within hypot(margin, margin / 4) of a node
        along = path_distance_m(x, y)
        nodes_s = np.linspace(0.0, along[-1], max(int(math.ceil(along[-1] / (0.5 * margin))) + 1, 2))
        nodes = np.column_stack([np.interp(nodes_s, along, x), np.interp(nodes_s, along, y)])
        tree = cKDTree(nodes)
        reach = math.hypot(margin, 0.25 * margin) * (1 + 1e-9)
        box = (x.min() - reach, x.max() + reach, y.min() - reach, y.max() + reach)

        def select(px: np.ndarray, py: np.ndarray) -> np.ndarray:
            mask = (px >= box[0]) & (px <= box[1]) & (py >= box[2]) & (py <= box[3])
            inside = np.flatnonzero(mask)
            if inside.size:
                distance, _ = tree.query(np.column_stack([px[inside], py[inside]]), distance_upper_bound=reach)
                mask[inside] = np.isfinite(distance)
            return mask

        return select


def _kept(cloud: PointCloud, keep: NearTrack | None) -> PointCloud:
    """The cloud, with the distance from the track within which its points were kept."""
    if keep is None or keep.margin_m is None:
        return cloud
    return dataclasses.replace(cloud, kept_within_m=keep.margin_m)
