"""ASPRS LAS and LAZ point clouds, read with laspy (LAZ through its lazrs backend).

:func:`read_las` returns a :class:`PointCloud` in metres; the units come from the file's
CRS (GeoTIFF keys or WKT). The header is checked against the file before laspy reads what
it counts, and the points are decoded in chunks, keeping only those a caller selects (near a
track), so that neither a hostile header nor a huge cloud exhausts memory
(:data:`MAX_CLOUD_POINTS`). A file that cannot be read raises
:class:`~profileopt.errors.InputError` whose one-line message names the file, what is wrong
and what would fix it. laspy (the ``geo`` extra) is imported only when a file is read.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import os
import re
import struct
from pathlib import Path
from typing import Any, Callable

import numpy as np

from ..errors import InputError
from . import inputs
from .geo import UNIT_RANGE_M, length_units_m, require_geo

__all__ = ["LasHeader", "PointCloud", "read_las", "read_las_header", "LAS_GROUND", "LINEAR_UNITS_M", "UNCLASSIFIED_CODES",
           "MAX_CLOUD_POINTS", "SCALE_RANGE"]

#: ASPRS standard class code of ground points (LAS 1.4 R15, Table 17).
LAS_GROUND = 2

#: Class codes that say "no class": 0 created, never classified; 1 unassigned (LAS 1.4 R15,
#: Table 17). A cloud with no other code is not classified at all.
UNCLASSIFIED_CODES = (0, 1)

#: EPSG linear unit codes (GeoTIFF 1.0, section 6.3.1.3) and their length in metres.
#: The US survey foot is exactly 1200/3937 m; the international foot exactly 0.3048 m.
LINEAR_UNITS_M: dict[int, tuple[str, float]] = {
    9001: ("metre", 1.0),
    9002: ("foot", 0.3048),
    9003: ("US survey foot", 1200.0 / 3937.0),
}
_USER_DEFINED = 32767

#: Most points a :class:`PointCloud` holds (20 million: about 500 MB as x, y, z in float64 and
#: a class byte, half the 1 GB a run may take, see :mod:`profileopt.io.inputs`). A larger
#: cloud is read in chunks of :data:`_CHUNK_POINTS` keeping only the points near a track
#: (``keep``); what is still larger is refused: thin it or cut it to the track.
MAX_CLOUD_POINTS = 20_000_000
#: Points decoded at a time (laspy's ``chunk_iterator``): about 100 MB while one chunk is read.
_CHUNK_POINTS = 2_000_000
#: The scale factors a LAS file may state (file units per stored integer). Below 1e-7 the
#: 32-bit integers span less than 430 units (and 5e-324 flattens every coordinate to its
#: offset); above 1 the coordinates are rounded to whole units, too coarse for a terrain.
SCALE_RANGE = (1e-7, 1.0)
#: Deepest nesting of brackets read in a WKT record (real ones nest 6 or 7 deep).
_MAX_WKT_DEPTH = 64
#: Bytes of a point record of each point data format, the least its record length may state
#: (LAS 1.4 R15, Tables 7-17; extra bytes may follow).
_FORMAT_BYTES = {0: 20, 1: 28, 2: 26, 3: 34, 4: 57, 5: 63, 6: 30, 7: 36, 8: 38, 9: 59, 10: 67}
#: Bytes of a LAS variable length record's header, and of an extended one's (LAS 1.4 R15, 2.5 and 2.6).
_VLR_HEADER_BYTES, _EVLR_HEADER_BYTES = 54, 60


@dataclasses.dataclass(frozen=True)
class LasHeader:
    """What a LAS file's public header block and CRS say about its points.

    Scale, offset and bounds are as stored, in the file's own units (``x = X * scale +
    offset``); :attr:`bounds_m` gives the bounds in metres.

    Attributes
    ----------
    path : str
        The file read.
    version : tuple of int
        (major, minor), e.g. (1, 2).
    point_format : int
        Point data record format (0-3, 6 or 7).
    record_length_bytes : int
        Bytes per point record (the standard size plus any extra bytes).
    point_count : int
        Number of point records (the 64-bit count of LAS 1.4, else the legacy count).
    scale, offset : tuple of float, length 3
        x, y, z scale factors (file units per integer step) and offsets (file units).
    min_xyz, max_xyz : tuple of float, length 3
        Bounds of the points as the header states them (file units).
    horizontal_unit_m, vertical_unit_m : float
        Length of the file's x/y unit and z unit in metres (1.0, 0.3048, 1200/3937, ...).
    crs : str
        The coordinate reference system as the file names it ("EPSG:32642", a WKT name),
        or "" if it names none.
    units_source : str
        Where the units were taken from (GeoKeys, WKT or the ``units_m`` argument).
    """

    path: str
    version: tuple[int, int]
    point_format: int
    record_length_bytes: int
    point_count: int
    scale: tuple[float, float, float]
    offset: tuple[float, float, float]
    min_xyz: tuple[float, float, float]
    max_xyz: tuple[float, float, float]
    horizontal_unit_m: float
    vertical_unit_m: float
    crs: str
    units_source: str

    @property
    def bounds_m(self) -> tuple[np.ndarray, np.ndarray]:
        """Header bounds in metres: (min, max), each shape (3,) as (x, y, z)."""
        unit = np.array([self.horizontal_unit_m, self.horizontal_unit_m, self.vertical_unit_m])
        return np.asarray(self.min_xyz) * unit, np.asarray(self.max_xyz) * unit


@dataclasses.dataclass(frozen=True)
class PointCloud:
    """A LAS point cloud in metres.

    Attributes
    ----------
    x_m, y_m, z_m : numpy.ndarray, shape (N,)
        Coordinates in metres: scale and offset applied, then converted from the file's
        units (easting, northing, elevation for a projected CRS).
    classification : numpy.ndarray of uint8, shape (N,)
        ASPRS class code of each point (2 = ground, :data:`LAS_GROUND`).
    header : LasHeader
        Point count, bounds, scale and offset as stored, and the units found.
    crs : pyproj.CRS or None
        The file's coordinate reference system as laspy parses it (GeoTIFF keys or WKT), or
        the one the caller supplied (:func:`~profileopt.io.terrain_maps.read_terrain`'s
        ``terrain_crs``); None if neither states one or pyproj cannot parse it.
    notes : tuple of str
        What the reader noticed or did (records beyond the header's count, points kept only
        near a track), one line each.
    file_extent_m : tuple of float or None
        (xmin, xmax, ymin, ymax) (m) of every point in the file, also of those not kept
        (``keep``); None: the points held.
    kept_within_m : float or None
        Only the points within this distance (m) of a track were kept
        (:func:`~profileopt.io.terrain_maps.read_terrain`'s ``track``); None: all of them.
    ground_density_per_m2 : float or None
        Ground points (class 2) of the whole file, also those not kept, per m^2 of their
        bounding box; None: none, or no area, or not counted.
    ground_count : int or None
        Ground points (class 2) of the whole file, also those not kept; None: not counted.
    """

    x_m: np.ndarray
    y_m: np.ndarray
    z_m: np.ndarray
    classification: np.ndarray
    header: LasHeader
    crs: Any = None
    notes: tuple[str, ...] = ()
    file_extent_m: tuple[float, float, float, float] | None = None
    kept_within_m: float | None = None
    ground_density_per_m2: float | None = None
    ground_count: int | None = None

    def extent_m(self) -> tuple[float, float, float, float]:
        """(xmin, xmax, ymin, ymax) (m) of the points in the file (all of them, also where
        only those near a track were kept)."""
        if self.file_extent_m is not None:
            return self.file_extent_m
        return (float(self.x_m.min()), float(self.x_m.max()), float(self.y_m.min()), float(self.y_m.max()))

    @property
    def is_classified(self) -> bool:
        """Whether any point has a class other than 0 (never classified) or 1 (unassigned)."""
        return bool(np.any(~np.isin(self.classification, UNCLASSIFIED_CODES)))

    def __len__(self) -> int:
        return int(self.x_m.size)

    def xyz_m(self, classes: int | tuple[int, ...] | None = None) -> np.ndarray:
        """Rows (x, y, z) in metres, shape (M, 3), of the points of the given class code(s)
        (all points if ``classes`` is None); the form :func:`~profileopt.roughness_index`
        takes.

        Parameters
        ----------
        classes : int or tuple of int, optional
            LAS classification code(s) to keep (e.g. 2, ground); None keeps every point.

        Returns
        -------
        numpy.ndarray, shape (M, 3)
            Coordinates x, y, z (m) of the M points kept, in file order.
        """
        keep = slice(None) if classes is None else np.isin(self.classification, np.atleast_1d(classes))
        return np.column_stack([self.x_m[keep], self.y_m[keep], self.z_m[keep]])

    def class_counts(self) -> dict[int, int]:
        """Number of points of each class code present."""
        codes, counts = np.unique(self.classification, return_counts=True)
        return {int(c): int(n) for c, n in zip(codes, counts)}


class _Bad(Exception):
    """A problem with a LAS file; :func:`read_las` prefixes the path and raises InputError."""


def read_las(path: str | os.PathLike, units_m: float | tuple[float, float] | None = None, *,
             crs: Any = None, keep: Callable[[Any, float | None], Any] | None = None) -> PointCloud:
    """Read an ASPRS LAS 1.0-1.4 point cloud, uncompressed (``.las``) or compressed (``.laz``).

    The public header block is checked against the file first (with ``struct``, before laspy
    reads anything it counts): the variable length records must fit between the header and
    the point data, and an uncompressed file must hold the point records its header counts.
    laspy then decodes the points in chunks (``LasReader.chunk_iterator``; LAZ through the
    lazrs backend), and ``x = X * scale + offset`` (likewise y, z) is converted to metres.
    With ``keep``, only the points it selects are held (those near a track), so a cloud of
    any size is read in bounded memory; at most :data:`MAX_CLOUD_POINTS` are held.

    Units. LAS itself does not fix a unit: the CRS in the variable length records does.
    Without ``units_m`` they are taken from the CRS that the header's global encoding
    marks as authoritative (WKT for LAS 1.4 with the WKT bit, else the GeoTIFF
    GeoKeyDirectory; the other one if that is missing; a LAS 1.4 extended VLR counts):

    * GeoKeys: ProjLinearUnitsGeoKey (3076) for x and y, VerticalUnitsGeoKey (4099) for z;
      codes 9001 metre, 9002 foot, 9003 US survey foot (1200/3937 m), or 32767 with
      ProjLinearUnitSizeGeoKey (3077) in metres. Without key 4099, z is taken to be in the
      horizontal unit (the file then states no vertical unit at all).
    * WKT (version 1 or 2): the UNIT / LENGTHUNIT of the projected CRS and of a vertical
      CRS (compound CRS), with the same rule for a missing vertical CRS.

    A geographic (degrees) or geocentric CRS, an unknown unit code, a unit outside
    :data:`~profileopt.io.geo.UNIT_RANGE_M` or no CRS at all is an error unless ``units_m`` is given.

    Parameters
    ----------
    path : str or os.PathLike
        The ``.las`` or ``.laz`` file.
    units_m : float or (float, float), optional
        Metres per file unit, for all three axes or as (horizontal, vertical), e.g.
        ``1200 / 3937`` for US survey feet. If given, the file's CRS is not consulted for
        the units (:attr:`PointCloud.crs` is still what the file states).
    crs : pyproj.CRS, optional
        The cloud's CRS instead of the one the file states (:attr:`PointCloud.crs`).
    keep : callable, optional
        Called once as ``keep(crs, density_per_m2)`` with the cloud's CRS (``crs``, else the
        file's, or None) and its mean density over the header's bounds (points per m^2, None
        if the bounds enclose no area); returns None (keep every point) or a function of the
        x and y (m) of a chunk of points returning a boolean mask of those to keep.

    Returns
    -------
    PointCloud
        Coordinates (m) and classification of the point records kept, the header, the CRS,
        the extent of every point in the file, and notes (records beyond the header's count).

    Raises
    ------
    InputError
        Not a LAS file, an unsupported version, a header that contradicts the file (more
        variable length records than fit, fewer point records than it counts), a file
        laspy cannot decode, no point records, more than :data:`MAX_CLOUD_POINTS` points to
        hold, scale factors outside :data:`SCALE_RANGE`, units that cannot be established,
        or laspy missing (each names the file, what is wrong and the fix).
    """
    path = Path(path)
    try:
        return _read_las(path, units_m, crs, keep)
    except _Bad as exc:
        raise InputError(f"{path}: {exc}") from None


def _check_layout(head: bytes, size: int, laz_chunks: int | None = None) -> tuple[int, int | None]:
    """The point count of a LAS public header block and the number of point records the file
    stores (None when compressed: only decoding tells), after checking that the header fits
    the file: its variable length records between the header and the point data, its
    extended ones after them (LAS 1.4 R15, Table 4; fields named as there). ``laz_chunks``:
    the chunks a LAZ file's chunk table counts (None: not compressed, or no table)."""
    if len(head) < 227:
        raise _Bad(f"is {size} bytes long, shorter than the 227-byte LAS public header block; the file is cut short")
    minor = head[25]
    header_size, offset, vlr_count = struct.unpack_from("<HII", head, 94)
    compressed = bool(head[104] & 0xC0)  # LAZ sets bit 7 (or 6) of the point data format
    record_bytes, legacy_count = struct.unpack_from("<HI", head, 105)
    if minor >= 4 and header_size >= 375 and len(head) >= 375:
        evlr_start, evlr_count, count = struct.unpack_from("<QIQ", head, 235)
        count = count or legacy_count
    else:
        evlr_start, evlr_count, count = 0, 0, legacy_count
    if not 227 <= header_size <= offset <= size:
        raise _Bad(f"its header says the header is {header_size} bytes and the point data start at byte {offset}, "
                   f"but the file is {size} bytes: the header ('header size', 'offset to point data') is damaged")
    room = (offset - header_size) // _VLR_HEADER_BYTES
    if vlr_count > room:
        raise _Bad(f"its header counts {vlr_count} variable length records, but at most {room} fit between the header "
                   f"(byte {header_size}) and the point data (byte {offset}): the header ('number of variable length "
                   "records', bytes 100-103) is damaged")
    if evlr_count and not (offset <= evlr_start and evlr_count <= (size - evlr_start) // _EVLR_HEADER_BYTES):
        raise _Bad(f"its header counts {evlr_count} extended variable length records from byte {evlr_start}, "
                   f"which do not fit in the file of {size} bytes: the header (bytes 235-246) is damaged")
    point_format = head[104] & 0x3F
    if point_format not in _FORMAT_BYTES or record_bytes < _FORMAT_BYTES[point_format]:
        least = f" (records of at least {_FORMAT_BYTES[point_format]} bytes)" if point_format in _FORMAT_BYTES else ""
        raise _Bad(f"its header states point data format {point_format}{least} and records of {record_bytes} bytes: "
                   "the header ('point data format', 'point data record length', bytes 104-106) is damaged or the "
                   "format is not LAS 1.0-1.4's")
    if compressed or record_bytes == 0:
        if count == 0 and laz_chunks:
            raise _Bad(f"its header counts 0 point records, but its compressed point data hold {laz_chunks:,} "
                       "chunk(s) of points: the header's point count ('number of point records') is wrong; set it to "
                       "the number of points the file holds (e.g. 'lasinfo -repair', LAStools)")
        if count == 0:
            raise _Bad("holds no points (its header counts 0 point records): no compressed point data follow its "
                       "header; a terrain needs measured points")
        return count, None
    end = evlr_start if evlr_count and evlr_start else size
    if minor >= 3 and head[6] & 0x02:  # waveform data packets inside the file, after the points
        end = min(end, struct.unpack_from("<Q", head, 227)[0] or end)
    stored = max(end - offset, 0) // record_bytes
    if count == 0 and stored:
        raise _Bad(f"its header counts 0 point records, but the file holds {stored:,} records of {record_bytes} bytes "
                   f"after byte {offset}: the header's point count ('number of point records') is wrong; set it to "
                   f"{stored} (e.g. 'lasinfo -repair', LAStools)")
    if count == 0:
        raise _Bad("holds no points (its header counts 0 point records): no records follow its header; a terrain "
                   "needs measured points")
    if stored < count:
        raise _Bad(f"is cut short: its header counts {count} point records of {record_bytes} bytes from byte "
                   f"{offset}, {count * record_bytes} bytes, but only {end - offset} follow ({stored} records)")
    return count, stored


def _preflight(path: Path) -> tuple[Any, int, int | None]:
    """laspy, and the point count and stored records of a LAS file whose header was checked
    against the file (:func:`_check_layout`) before laspy reads anything it counts."""
    laspy = require_geo("laspy", "reading LAS/LAZ")
    try:
        # a regular file only (not /dev/zero, not a FIFO): laspy would read it until memory runs out
        if os.path.exists(path):
            inputs.check_regular_input(path, "LAS file")
        with open(path, "rb") as handle:
            head = handle.read(375)
            size = os.fstat(handle.fileno()).st_size
            chunks = _laz_chunk_count(handle, head, size)
    except OSError as exc:
        raise _Bad(f"cannot read the LAS file ({exc.strerror}); check the path") from None
    if head[:4] != b"LASF":
        raise _Bad("does not start with 'LASF'; is this an ASPRS LAS or LAZ file?")
    if len(head) >= 26 and (head[24] != 1 or head[25] > 4):
        raise _Bad(f"LAS version {head[24]}.{head[25]} is not supported; this reader handles 1.0-1.4")
    count, stored = _check_layout(head, size, chunks)
    return laspy, count, stored


def _laz_chunk_count(handle: Any, head: bytes, size: int) -> int | None:
    """The number of chunks a LAZ file's chunk table counts (LASzip: the point data start
    with the 8-byte offset of the table, which starts with a version 0 and the count); None
    for a LAS file, or a table that is not there (a streamed file) or not readable."""
    if len(head) < 227 or head[:4] != b"LASF" or not head[104] & 0xC0:
        return None
    offset = struct.unpack_from("<I", head, 96)[0]
    handle.seek(offset)
    raw = handle.read(8)
    if len(raw) < 8:
        return None
    table = struct.unpack("<q", raw)[0]
    if not offset + 8 <= table <= size - 8:
        return None
    handle.seek(table)
    version, chunks = struct.unpack("<II", handle.read(8))
    return chunks if version == 0 else None


def _read_las(path: Path, units_m: float | tuple[float, float] | None, crs_given: Any,
              keep: Callable[[Any, float | None], Any] | None) -> PointCloud:
    laspy, count, stored = _preflight(path)
    if keep is None and count > MAX_CLOUD_POINTS:
        raise _Bad(f"holds {count:,} points, more than the {MAX_CLOUD_POINTS:,} read at once; read only the points "
                   "near a track (read_terrain's track, as profileopt route and plan do) or thin the cloud first "
                   "(e.g. 'pdal translate in.laz out.laz sample --filters.sample.radius=0.02')")
    with _quiet_laspy():
        return _decode(laspy, path, count, stored, units_m, crs_given, keep)


class _quiet_laspy:
    """laspy logs the errors it raises; the raised one becomes one line here."""

    def __enter__(self) -> None:
        self.logger = logging.getLogger("laspy")
        self.level = self.logger.level
        self.logger.setLevel(logging.CRITICAL)

    def __exit__(self, *exc: object) -> None:
        self.logger.setLevel(self.level)


def read_las_header(path: str | os.PathLike, units_m: float | tuple[float, float] | None = None, *,
                    crs: Any = None) -> tuple[LasHeader, Any]:
    """The header of a LAS or LAZ file and its CRS, without decoding a point: what a tile's
    bounds, count and units are (:func:`profileopt.io.tiles.read_tiles` chooses tiles by them).

    The header is checked as :func:`read_las` checks it; ``units_m`` and ``crs`` as there.

    Parameters
    ----------
    path : str or os.PathLike
        The ``.las`` or ``.laz`` file.
    units_m : float or (float, float), optional
        Metres per file unit (all axes, or horizontal and vertical); None: from the file's CRS.
    crs : pyproj.CRS, optional
        The cloud's CRS instead of the one the file states.

    Returns
    -------
    (LasHeader, pyproj.CRS or None)
        The header (bounds in file units, :attr:`LasHeader.bounds_m` in metres) and the CRS.

    Raises
    ------
    InputError
        What :func:`read_las` refuses about a header (one line naming the file).
    """
    path = Path(path)
    try:
        laspy, count, stored = _preflight(path)
        with _quiet_laspy():
            try:
                reader = laspy.open(path)
            except Exception as exc:  # laspy, lazrs, struct and numpy errors alike
                raise _Bad(_laspy_failure(exc)) from None
            with reader:
                return _stated(reader, path, count, stored, units_m, crs)
    except _Bad as exc:
        raise InputError(f"{path}: {exc}") from None


def _stated(reader: Any, path: Path, count: int, stored: int | None, units_m: float | tuple[float, float] | None,
            crs_given: Any) -> tuple[LasHeader, Any]:
    """What an open LAS file's header states, checked: its :class:`LasHeader` and its CRS."""
    head = reader.header
    if int(head.point_count) != count:  # a LAS 1.4 file whose two counts differ: laspy's decides
        count = int(head.point_count)
        if stored is not None and stored < count:
            raise _Bad(f"is cut short: its header counts {count} point records, the file holds {stored}")
    scale, offset = tuple(map(float, head.scales)), tuple(map(float, head.offsets))
    for axis, value in zip("xyz", scale):
        if not (math.isfinite(value) and SCALE_RANGE[0] <= abs(value) <= SCALE_RANGE[1]):
            raise _Bad(f"its {axis} scale factor {value:g} is outside {SCALE_RANGE[0]:g} to {SCALE_RANGE[1]:g} "
                       "(file units per stored integer), so its coordinates cannot be recovered: the header "
                       "('x, y, z scale factor', bytes 131-154) is damaged or was written wrongly")
    if not all(math.isfinite(v) for v in offset):
        raise _Bad(f"its offsets {offset} must be finite: the header ('x, y, z offset', bytes 155-178) is damaged")
    vlrs = {(v.user_id, v.record_id): v.record_data_bytes()
            for v in list(head.vlrs) + list(getattr(reader, "evlrs", None) or [])}
    minor = int(head.version.minor)
    if units_m is None:
        wkt_first = minor >= 4 and bool(head.global_encoding.wkt)
        horizontal_m, vertical_m, crs_name, source = _las_units(vlrs, wkt_first)
    else:
        pair = (units_m, units_m) if isinstance(units_m, (int, float)) else tuple(units_m)
        if len(pair) != 2 or not all(math.isfinite(float(u)) and float(u) > 0 for u in pair):
            raise _Bad(f"units_m = {units_m!r} must be a number > 0 or a pair (horizontal, vertical) of them")
        horizontal_m, vertical_m = (float(u) for u in pair)
        crs_name, source = "", f"units_m argument ({horizontal_m:g} m, {vertical_m:g} m per file unit)"
    try:
        parsed = head.parse_crs()
    except Exception:  # pyproj missing, or keys it cannot turn into a CRS: the units above still hold
        parsed = None
    header = LasHeader(
        path=str(path), version=(int(head.version.major), minor), point_format=int(head.point_format.id),
        record_length_bytes=int(head.point_format.size), point_count=count, scale=scale, offset=offset,
        min_xyz=tuple(map(float, head.mins)), max_xyz=tuple(map(float, head.maxs)),
        horizontal_unit_m=horizontal_m, vertical_unit_m=vertical_m, crs=crs_name, units_source=source,
    )
    return header, crs_given if crs_given is not None else parsed


def _decode(laspy: Any, path: Path, count: int, stored: int | None, units_m: float | tuple[float, float] | None,
            crs_given: Any, keep: Callable[[Any, float | None], Any] | None) -> PointCloud:
    """The points of a LAS file whose layout was checked (:func:`_check_layout`), decoded by laspy."""
    try:
        reader = laspy.open(path)
    except Exception as exc:  # laspy, lazrs, struct and numpy errors alike
        raise _Bad(_laspy_failure(exc)) from None
    with reader:
        header, crs = _stated(reader, path, count, stored, units_m, crs_given)
        laszip = _laszip_record(reader) if stored is None else None  # before laspy decodes (and drops it)
        count, horizontal_m, vertical_m = header.point_count, header.horizontal_unit_m, header.vertical_unit_m
        area_m2 = float(np.prod((np.asarray(header.max_xyz) - np.asarray(header.min_xyz))[:2])) * horizontal_m**2
        density = count / area_m2 if math.isfinite(area_m2) and area_m2 > 0 else None
        select = keep(crs, density) if keep is not None else None
        columns: tuple[list[np.ndarray], ...] = ([], [], [], [])  # x, y, z, class of each chunk kept
        held = decoded = 0
        low, high = np.full(2, np.inf), np.full(2, -np.inf)
        ground_low, ground_high, ground_count = np.full(2, np.inf), np.full(2, -np.inf), 0
        try:
            for points in reader.chunk_iterator(_CHUNK_POINTS):
                x = np.asarray(points.x, dtype=float) * horizontal_m
                y = np.asarray(points.y, dtype=float) * horizontal_m
                decoded += x.size
                if x.size == 0:
                    break
                low = np.minimum(low, [x.min(), y.min()])
                high = np.maximum(high, [x.max(), y.max()])
                classes = np.asarray(points.classification, dtype=np.uint8)
                ground = classes == LAS_GROUND
                if ground.any():  # the whole file's ground density, whatever is kept
                    ground_count += int(ground.sum())
                    ground_low = np.minimum(ground_low, [x[ground].min(), y[ground].min()])
                    ground_high = np.maximum(ground_high, [x[ground].max(), y[ground].max()])
                mask = slice(None) if select is None else np.asarray(select(x, y), dtype=bool)
                part = (x[mask], y[mask], np.asarray(points.z, dtype=float)[mask] * vertical_m, classes[mask])
                held += part[0].size
                if held > MAX_CLOUD_POINTS:
                    raise _Bad(f"holds more than {MAX_CLOUD_POINTS:,} points near the track (of {count:,}); thin "
                               "the cloud first (e.g. 'pdal translate in.laz out.laz sample "
                               "--filters.sample.radius=0.02') or cut it to the track")
                for column, values in zip(columns, part):
                    column.append(values)
        except _Bad:
            raise
        except Exception as exc:  # lazrs and laspy errors while decoding: the data end or are corrupt
            raise _Bad(f"its point data cannot be decoded after {decoded:,} of the {count:,} points the header "
                       f"counts ({_reason(exc)}): the file is cut short or its compressed data are damaged") from None
    if decoded < count:
        raise _Bad(f"holds {decoded:,} point records, its header counts {count:,}: the file is cut short")
    notes = []
    exact = True
    if stored is None:  # compressed: the records beyond the header's count, if any, found in its chunks
        stored, exact = _laz_stored(path, laszip, count)
    if stored is not None and stored > count and exact:
        notes.append(f"{path.name}: holds {stored:,} point records, but its header counts {count:,}: the first "
                     f"{count:,} were read, the other {stored - count:,} ignored (the header's count is wrong or records "
                     "were appended); set the count in its header to read them all")
    elif stored is not None and stored > count:
        notes.append(f"{path.name}: its compressed point data hold more point records than its header counts "
                     f"({count:,}; at least {stored:,} are stored): the first {count:,} were read, the others ignored "
                     "(the header's count is wrong or records were appended); set the count in its header to read "
                     "them all")
    x, y, z, classes = (_join(column) for column in columns)
    extent = (float(low[0]), float(high[0]), float(low[1]), float(high[1]))
    ground_area_m2 = float(np.prod(ground_high - ground_low)) if ground_count else 0.0
    return PointCloud(x_m=x, y_m=y, z_m=z, classification=classes, header=header, crs=crs,
                      notes=tuple(notes), file_extent_m=extent, ground_count=ground_count,
                      ground_density_per_m2=ground_count / ground_area_m2 if ground_area_m2 > 0 else None)


#: The most bytes the search for records beyond a LAZ file's count decodes at once (a chunk
#: of 50,000 points of 34 bytes is 1.7 MB; a larger chunk is not searched).
_MAX_CHUNK_SEARCH_BYTES = 256 * 2**20
#: Points a LASzip decoder may produce past the end of a chunk's data before it runs out of
#: bytes (from the arithmetic coder's last bytes); fewer than this beyond the header's count
#: is not taken for records.
_DECODE_SLACK = 16


def _laszip_record(reader: Any) -> tuple[int, bytes] | None:
    """The offset to the point data and the LASzip record of an open LAZ file, taken before
    its points are read (laspy drops the record from the header once it decodes); None for
    a LAS file."""
    head = reader.header
    for vlr in head.vlrs:
        if getattr(vlr, "record_id", None) == 22204 and str(getattr(vlr, "user_id", "")).startswith("laszip"):
            try:
                return int(head.offset_to_point_data), bytes(vlr.record_data_bytes())
            except Exception:  # a record laspy cannot give back: nothing to search with
                return None
    return None


def _laz_stored(path: Path, laszip: tuple[int, bytes] | None, count: int) -> tuple[int | None, bool]:
    """How many point records a LAZ file stores, when more than its header counts: (the
    number, True), or (a lower bound, False) when only that much is known; (None, True) when
    there are no more records, or this cannot tell (no lazrs, a chunk table not there).

    A LASzip file is a sequence of chunks; its chunk table gives each chunk's bytes (and, for
    variable-size chunks, its points). Chunks beyond those the header's count needs hold more
    records. Within the last chunk, the records beyond the count are found by decoding: if
    more points decode from the chunk's bytes than the header accounts for and compressing
    the points the header counts does not give those bytes back (LASzip's coding is
    deterministic), the chunk holds more; the largest count that decodes and compresses back
    to the chunk's bytes exactly is the number stored.
    """
    if laszip is None:
        return None, True
    try:
        import lazrs
    except ImportError:
        return None, True
    offset, vlr_bytes = laszip
    try:
        laz = lazrs.LazVlr(vlr_bytes)
        with open(path, "rb") as handle:
            handle.seek(offset)
            table = lazrs.read_chunk_table(handle, laz)
    except Exception:  # no LASzip record, no chunk table (a streamed file), a damaged one: cannot tell
        return None, True
    if not table:
        return None, True
    if laz.uses_variable_size_chunks():  # the table counts each chunk's points
        stored = sum(int(points) for points, _ in table)
        return (stored, True) if stored > count else (None, True)
    size, record = int(laz.chunk_size()), int(laz.item_size())
    needed = -(-count // size)
    last = len(table) - 1
    if last < needed - 1 or size * record > _MAX_CHUNK_SEARCH_BYTES or table[last][1] > _MAX_CHUNK_SEARCH_BYTES:
        return None, True
    start = offset + 8 + sum(int(nbytes) for _, nbytes in table[:last])
    with open(path, "rb") as handle:
        handle.seek(start)
        data = handle.read(int(table[last][1]))
    before = last * size  # points in the chunks before the last
    known = count - before if last == needed - 1 else 0  # the last chunk's points the header counts
    selection = lazrs.DecompressionSelection(lazrs.SELECTIVE_DECOMPRESS_ALL)

    def decoded(n: int) -> bytearray | None:
        out = bytearray(n * record)
        try:
            lazrs.decompress_points_with_chunk_table(data, vlr_bytes, out, [(n, len(data))], selection)
        except Exception:  # the chunk's bytes end before n points
            return None
        return out

    def compresses_back(points: bytearray) -> bool:
        import io

        sink = io.BytesIO()
        try:
            compressor = lazrs.LasZipCompressor(sink, laz)
            compressor.compress_many(points)
            compressor.done()
        except Exception:
            return False
        return sink.getvalue()[8:8 + len(data)] == data  # after the 8-byte offset of the chunk table

    if last == needed - 1:  # the header's count ends in the last chunk: does it hold more?
        if decoded(known + 1) is None:
            return None, True
        points = decoded(known)
        if points is None or compresses_back(points):
            return None, True
    low, high = known + 1, size  # the most points that decode from the chunk's bytes
    while low < high:
        middle = (low + high + 1) // 2
        if decoded(middle) is not None:
            low = middle
        else:
            high = middle - 1
    most = low if decoded(low) is not None else known
    for n in range(most, max(known, most - _DECODE_SLACK), -1):
        points = decoded(n)
        if points is not None and compresses_back(points):
            return before + n, True
    if last > needed - 1:  # whole chunks beyond the count: more records for certain
        return before + 1, False
    if most - known >= _DECODE_SLACK:
        return count + 1, False
    return None, True  # a few points past the end: the coder's last bytes, not records


def _join(chunks: list[np.ndarray]) -> np.ndarray:
    """One column from its chunks, freeing them as it goes: the peak is the chunks and one
    column, not twice the cloud."""
    whole = np.concatenate(chunks)
    chunks.clear()
    return whole


def _reason(exc: BaseException) -> str:
    """What laspy or lazrs said, on one line."""
    return " ".join(str(exc).split())[:160] or type(exc).__name__


def _laspy_failure(exc: BaseException) -> str:
    """The message for a file laspy cannot open: the LAZ backend missing, or what laspy says."""
    reason = _reason(exc)
    if "LazBackend" in reason or "lazrs" in reason.lower() and "install" in reason.lower():
        return "reading LAZ needs the lazrs backend of the geo extra: pip install 'profileopt[geo]'"
    return f"cannot be read as LAS/LAZ (laspy: {reason}); check that it is a whole LAS 1.0-1.4 or LAZ file"


def _las_units(vlrs: dict[tuple[str, int], bytes], wkt_first: bool) -> tuple[float, float, str, str]:
    """(horizontal m per unit, vertical m per unit, CRS name, source) from the CRS VLRs."""
    geokeys = vlrs.get(("LASF_Projection", 34735))
    wkt = vlrs.get(("LASF_Projection", 2112))
    readers = [("wkt", wkt), ("geokeys", geokeys)]
    for kind, payload in (readers if wkt_first else readers[::-1]):
        if payload is None:
            continue
        if kind == "wkt":
            return _wkt_units(payload.split(b"\0", 1)[0].decode("latin-1"))
        return _geokey_units(payload, vlrs.get(("LASF_Projection", 34736), b""))
    raise _Bad("names no coordinate reference system (no GeoKeyDirectory or WKT record), so its units "
               "are unknown; pass units_m (metres per file unit, e.g. 1200/3937 for US survey feet)")


def _check_unit(value: float, what: str) -> float:
    """``value`` (m per unit), if within :data:`~profileopt.io.geo.UNIT_RANGE_M`; else one line naming ``what``."""
    if not (math.isfinite(value) and UNIT_RANGE_M[0] <= value <= UNIT_RANGE_M[1]):
        raise _Bad(f"{what} states a unit of {value:g} m, not a length unit (they lie between {UNIT_RANGE_M[0]:g} "
                   f"and {UNIT_RANGE_M[1]:g} m): the record is damaged; pass units_m (metres per file unit)")
    return value


def _unit_m(code: int, what: str) -> tuple[str, float]:
    if code not in LINEAR_UNITS_M:
        raise _Bad(f"{what} = {code} is not a unit this reader knows (9001 metre, 9002 foot, "
                   "9003 US survey foot); pass units_m (metres per file unit)")
    return LINEAR_UNITS_M[code]


def _geokey_units(directory: bytes, doubles: bytes) -> tuple[float, float, str, str]:
    """Units from a GeoTIFF GeoKeyDirectory (LAS record 34735) and its doubles (34736)."""
    shorts = struct.unpack(f"<{len(directory) // 2}H", directory[: len(directory) // 2 * 2])
    if len(shorts) < 4 or len(shorts) < 4 + 4 * shorts[3]:
        raise _Bad("the GeoKeyDirectory record is truncated; pass units_m (metres per file unit)")
    keys = {shorts[i]: shorts[i + 1: i + 4] for i in range(4, 4 + 4 * shorts[3], 4)}

    def value(key: int) -> int | None:  # a key stored in the directory itself (location 0)
        return keys[key][2] if key in keys and keys[key][0] == 0 else None

    model = value(1024)
    if model in (2, 3):
        kind = "geographic (longitude/latitude in degrees)" if model == 2 else "geocentric"
        raise _Bad(f"its CRS is {kind}, not projected in a length unit; reproject it "
                   "(e.g. 'pdal translate ... reprojection --filters.reprojection.out_srs=EPSG:<UTM zone>')")
    epsg = value(3072)
    crs = f"EPSG:{epsg}" if epsg not in (None, _USER_DEFINED) else ""
    code = value(3076)
    if code is None and crs:  # the EPSG projected CRS defines its unit (laspy's add_crs writes no key 3076)
        units = _epsg_units(epsg)
        if units is not None:
            return units[0], units[1], crs, f"GeoKeys: ProjectedCSTypeGeoKey (3072) {epsg} (its unit: {units[0]:g} m)"
    if code is None:
        raise _Bad(f"the GeoKeyDirectory {('(' + crs + ') ') if crs else ''}has no ProjLinearUnitsGeoKey "
                   "(3076), so the horizontal unit is unknown; pass units_m (metres per file unit)")
    if code == _USER_DEFINED:
        size = keys.get(3077)
        if size is None or size[0] != 34736 or 8 * (size[2] + 1) > len(doubles):
            raise _Bad("ProjLinearUnitsGeoKey (3076) is user-defined but ProjLinearUnitSizeGeoKey (3077) "
                       "is missing; pass units_m (metres per file unit)")
        h_name = "user-defined"
        horizontal_m = _check_unit(struct.unpack_from("<d", doubles, 8 * size[2])[0],
                                   "ProjLinearUnitSizeGeoKey (3077)")
    else:
        h_name, horizontal_m = _unit_m(code, "ProjLinearUnitsGeoKey (3076)")
    v_code = value(4099)
    if v_code is None:
        v_name, vertical_m, v_note = h_name, horizontal_m, "VerticalUnitsGeoKey absent, z taken in the same unit"
    else:
        v_name, vertical_m = _unit_m(v_code, "VerticalUnitsGeoKey (4099)")
        v_note = f"VerticalUnitsGeoKey {v_code} ({v_name})"
    return horizontal_m, vertical_m, crs, f"GeoKeys: ProjLinearUnitsGeoKey {code} ({h_name}), {v_note}"


def _epsg_units(epsg: int) -> tuple[float, float] | None:
    """(horizontal, vertical) metres per unit of an EPSG projected CRS, None if pyproj is
    missing or does not know it as a projected CRS."""
    try:
        pyproj = require_geo("pyproj", "reading LAS/LAZ")
        crs = pyproj.CRS.from_epsg(epsg)
        return length_units_m(crs, "") if crs.is_projected else None
    except (InputError, Exception):  # pyproj's CRSError, or not projected
        return None


_WKT_TOKEN = re.compile(r'\s*("(?:[^"]|"")*"|[\[\](),]|[^\[\](),"\s]+)')


def _parse_wkt(text: str) -> tuple[str, list]:
    """A WKT string as nested (KEYWORD, [arguments]) with quoted strings unquoted."""
    tokens = [t for t in _WKT_TOKEN.findall(text)]
    position = 0

    def node(depth: int) -> tuple[str, list] | str:
        nonlocal position
        token = tokens[position]
        position += 1
        if token.startswith('"'):
            return token[1:-1].replace('""', '"')
        if position < len(tokens) and tokens[position] in "[(":
            if depth >= _MAX_WKT_DEPTH:
                raise _Bad(f"the WKT coordinate system record nests brackets more than {_MAX_WKT_DEPTH} deep (a "
                           "real CRS nests fewer than 10): it is damaged; pass units_m (metres per file unit)")
            position += 1
            args: list = []
            while tokens[position] not in "])":
                args.append(node(depth + 1))
                if tokens[position] == ",":
                    position += 1
            position += 1
            return token.upper(), args
        return token

    try:
        root = node(0)
    except IndexError:
        raise _Bad("the WKT coordinate system record is malformed; pass units_m (metres per file unit)") from None
    if not isinstance(root, tuple):
        raise _Bad("the WKT coordinate system record is malformed; pass units_m (metres per file unit)")
    return root


def _wkt_unit(crs: tuple[str, list]) -> float | None:
    """Metres per unit of a WKT CRS: its own UNIT / LENGTHUNIT, else its first axis's."""
    children = [c for c in crs[1] if isinstance(c, tuple)]
    for name, args in children:
        if name in ("UNIT", "LENGTHUNIT") and len(args) >= 2:
            return float(args[1])
    for name, args in children:
        if name == "AXIS":
            return _wkt_unit((name, args))
    return None


def _wkt_units(text: str) -> tuple[float, float, str, str]:
    """Units from an OGC WKT coordinate system record (LAS record 2112), WKT 1 or 2."""
    root = _parse_wkt(text)
    parts = [c for c in root[1] if isinstance(c, tuple)] if root[0] in ("COMPD_CS", "COMPOUNDCRS") else [root]
    horizontal = vertical = None
    name = ""
    for part in parts:
        label = part[1][0] if part[1] and isinstance(part[1][0], str) else part[0]
        if part[0] in ("PROJCS", "PROJCRS"):
            horizontal, name = part, label
        elif part[0] in ("VERT_CS", "VERTCRS"):
            vertical = part
        elif part[0] in ("GEOGCS", "GEOGCRS", "GEOCCS", "GEODCRS"):
            raise _Bad(f"its CRS {label!r} is geographic or geocentric, not projected in a length unit; "
                       "reproject it (e.g. with 'pdal translate ... reprojection')")
    if horizontal is None:
        raise _Bad(f"the WKT CRS {root[0]} has no projected CRS, so the units are unknown; pass units_m")
    try:
        horizontal_m = _wkt_unit(horizontal)
        vertical_m = _wkt_unit(vertical) if vertical is not None else horizontal_m
    except ValueError:  # a unit factor that is not a number
        horizontal_m = vertical_m = None
    if horizontal_m is None or vertical_m is None:
        raise _Bad(f"the WKT CRS {name!r} states no usable length unit; pass units_m (metres per file unit)")
    _check_unit(horizontal_m, f"the WKT CRS {name!r}")
    _check_unit(vertical_m, f"the WKT CRS {name!r} (vertical)")
    note = "vertical CRS unit" if vertical is not None else "no vertical CRS, z taken in the same unit"
    return horizontal_m, vertical_m, name, f"WKT: {horizontal_m:g} m per unit, {note}"
