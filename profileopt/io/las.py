"""ASPRS LAS and LAZ point clouds, read with laspy (LAZ through its lazrs backend).

:func:`read_las` returns a :class:`PointCloud` in metres; the units come from the file's
CRS (GeoTIFF keys or WKT). A file that cannot be read raises
:class:`~profileopt.errors.InputError` whose one-line message names the file, what is wrong
and what would fix it. laspy (the ``geo`` extra) is imported only when a file is read.
"""

from __future__ import annotations

import dataclasses
import math
import os
import re
import struct
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InputError
from . import inputs
from .geo import length_units_m, require_geo

__all__ = ["LasHeader", "PointCloud", "read_las", "LAS_GROUND", "LINEAR_UNITS_M", "UNCLASSIFIED_CODES"]

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
    """

    x_m: np.ndarray
    y_m: np.ndarray
    z_m: np.ndarray
    classification: np.ndarray
    header: LasHeader
    crs: Any = None

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


def read_las(path: str | os.PathLike, units_m: float | tuple[float, float] | None = None) -> PointCloud:
    """Read an ASPRS LAS 1.0-1.4 point cloud, uncompressed (``.las``) or compressed (``.laz``).

    laspy reads the file (``laspy.read``; LAZ through the lazrs backend): the public header
    block gives the point format, record length, point count, scale factors, offsets and
    bounds, and ``x = X * scale + offset`` (likewise y, z) is converted to metres.

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

    A geographic (degrees) or geocentric CRS, an unknown unit code or no CRS at all is an
    error unless ``units_m`` is given.

    Parameters
    ----------
    path : str or os.PathLike
        The ``.las`` or ``.laz`` file.
    units_m : float or (float, float), optional
        Metres per file unit, for all three axes or as (horizontal, vertical), e.g.
        ``1200 / 3937`` for US survey feet. If given, the file's CRS is not consulted for
        the units (:attr:`PointCloud.crs` is still what the file states).

    Returns
    -------
    PointCloud
        Coordinates (m) and classification of every point record, the header and the CRS.

    Raises
    ------
    InputError
        Not a LAS file, an unsupported version, a truncated or damaged file (what laspy
        says), fewer point records than the header counts, zero or non-finite scale
        factors, units that cannot be established, or laspy missing (each names the file
        and the fix).
    """
    path = Path(path)
    try:
        return _read_las(path, units_m)
    except _Bad as exc:
        raise InputError(f"{path}: {exc}") from None


def _read_las(path: Path, units_m: float | tuple[float, float] | None) -> PointCloud:
    laspy = require_geo("laspy", "reading LAS/LAZ")
    try:
        # a regular file only (not /dev/zero, not a FIFO): laspy would read it until memory runs out
        if os.path.exists(path):
            inputs.check_regular_input(path, "LAS file")
        with open(path, "rb") as handle:
            head = handle.read(26)
    except OSError as exc:
        raise _Bad(f"cannot read the LAS file ({exc.strerror}); check the path") from None
    if head[:4] != b"LASF":
        raise _Bad("does not start with 'LASF'; is this an ASPRS LAS or LAZ file?")
    if len(head) == 26 and (head[24] != 1 or head[25] > 4):
        raise _Bad(f"LAS version {head[24]}.{head[25]} is not supported; this reader handles 1.0-1.4")
    try:
        las = laspy.read(path)
    except Exception as exc:  # laspy, lazrs, struct and numpy errors alike: the file is not whole
        reason = " ".join(str(exc).split())[:160] or type(exc).__name__
        if "LazBackend" in reason or "lazrs" in reason.lower() and "install" in reason.lower():
            raise _Bad("reading LAZ needs the lazrs backend of the geo extra: pip install 'profileopt[geo]'") from None
        raise _Bad(f"is truncated or damaged (laspy: {reason}); download it again") from None
    head = las.header
    count = int(head.point_count)
    if len(las.points) != count:
        raise _Bad(f"holds {len(las.points)} point records, the header says {count}; it is truncated, "
                   "download it again")
    scale, offset = tuple(map(float, head.scales)), tuple(map(float, head.offsets))
    if not (all(math.isfinite(v) and v != 0.0 for v in scale) and all(math.isfinite(v) for v in offset)):
        raise _Bad(f"scale factors {scale} must be finite and non-zero and offsets {offset} finite")
    vlrs = {(v.user_id, v.record_id): v.record_data_bytes() for v in list(head.vlrs) + list(las.evlrs or [])}
    minor = int(head.version.minor)
    if units_m is None:
        wkt_first = minor >= 4 and bool(head.global_encoding.wkt)
        horizontal_m, vertical_m, crs, source = _las_units(vlrs, wkt_first)
    else:
        pair = (units_m, units_m) if isinstance(units_m, (int, float)) else tuple(units_m)
        if len(pair) != 2 or not all(math.isfinite(float(u)) and float(u) > 0 for u in pair):
            raise _Bad(f"units_m = {units_m!r} must be a number > 0 or a pair (horizontal, vertical) of them")
        horizontal_m, vertical_m = (float(u) for u in pair)
        crs, source = "", f"units_m argument ({horizontal_m:g} m, {vertical_m:g} m per file unit)"
    try:
        parsed = head.parse_crs()
    except Exception:  # pyproj missing, or keys it cannot turn into a CRS: the units above still hold
        parsed = None

    header = LasHeader(
        path=str(path), version=(int(head.version.major), minor), point_format=int(head.point_format.id),
        record_length_bytes=int(head.point_format.size), point_count=count, scale=scale, offset=offset,
        min_xyz=tuple(map(float, head.mins)), max_xyz=tuple(map(float, head.maxs)),
        horizontal_unit_m=horizontal_m, vertical_unit_m=vertical_m, crs=crs, units_source=source,
    )
    return PointCloud(
        x_m=np.asarray(las.x, dtype=float) * horizontal_m,
        y_m=np.asarray(las.y, dtype=float) * horizontal_m,
        z_m=np.asarray(las.z, dtype=float) * vertical_m,
        classification=np.asarray(las.classification, dtype=np.uint8),
        header=header,
        crs=parsed,
    )


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
        h_name, horizontal_m = "user-defined", struct.unpack_from("<d", doubles, 8 * size[2])[0]
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

    def node() -> tuple[str, list] | str:
        nonlocal position
        token = tokens[position]
        position += 1
        if token.startswith('"'):
            return token[1:-1].replace('""', '"')
        if position < len(tokens) and tokens[position] in "[(":
            position += 1
            args: list = []
            while tokens[position] not in "])":
                args.append(node())
                if tokens[position] == ",":
                    position += 1
            position += 1
            return token.upper(), args
        return token

    try:
        root = node()
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
    if horizontal_m is None or vertical_m is None or not (horizontal_m > 0 and vertical_m > 0):
        raise _Bad(f"the WKT CRS {name!r} states no usable length unit; pass units_m (metres per file unit)")
    note = "vertical CRS unit" if vertical is not None else "no vertical CRS, z taken in the same unit"
    return horizontal_m, vertical_m, name, f"WKT: {horizontal_m:g} m per unit, {note}"
