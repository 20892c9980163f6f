"""Terrain in tiles: several LAS/LAZ or GeoTIFF files, or a folder of them, read as one terrain.

Public LiDAR and DEMs come as tiles (1 km x 1 km files by the hundred). :func:`read_tiles`
reads each tile's header only (a LAS header's bounds and count, a GeoTIFF's geotransform),
then, of the tiles whose bounds come within the sampling margin of the track, what
:func:`~profileopt.io.terrain_maps.read_terrain` reads of one file (a cloud's points near the
track, a raster's window around it), and joins them:

- clouds into one :class:`~profileopt.io.las.PointCloud`, the points of every tile read in
  turn; a point that two overlapping tiles both hold (a tile's buffer) counts once. The
  margin around the track is set by the density of all the tiles together, as it would be
  for one file holding them all, so a track over four tiles samples the same route as over
  their merged file;
- rasters into a :class:`GridTiles`, the windows of tiles on one grid of cells (the same cell
  size, cells aligned): interpolation between the cells on either side of a seam uses both
  tiles, so there is no gap at a seam. Tiles on different grids are refused (resample them
  onto one first).

Every problem is one :class:`~profileopt.errors.InputError` line naming the tile or folder,
what is wrong and the fix.
"""

from __future__ import annotations

import dataclasses
import math
import os
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from ..errors import InputError
from .las import PointCloud
from .terrain_maps import (
    MAX_GRID_CELLS,
    TERRAIN_SUFFIXES,
    ElevationGrid,
    NearTrack,
    cloud_header,
    geotiff_crs,
    read_cloud,
    read_geotiff,
    read_terrain,
    track_box_m,
    unreadable_geotiff,
    unreadable_geotiff_crs,
)

__all__ = ["GridTiles", "read_tiles", "terrain_files", "MAX_TILES"]

#: Most tiles named at once (a folder or a list): their headers are read to choose the tiles
#: near a track, a few kB and a few ms each; beyond this, give the tiles of the region.
MAX_TILES = 100_000
#: Tile kinds that join: point clouds with point clouds, rasters with rasters.
_TILE_KINDS = {"LAS": "point cloud", "LAZ": "point cloud", "GeoTIFF": "GeoTIFF DEM"}


def terrain_files(paths: str | os.PathLike | Sequence[str | os.PathLike]) -> list[Path]:
    """The terrain files that ``paths`` name: files as given, a folder's LAS, LAZ and GeoTIFF
    files (not its sub-folders), in name order, each once.

    Parameters
    ----------
    paths : path or sequence of paths
        Terrain files and folders of tiles.

    Returns
    -------
    list of pathlib.Path
        The files, folders expanded.

    Raises
    ------
    InputError
        A folder without terrain files, a missing path, no path at all, more than
        :data:`MAX_TILES` files.
    """
    given = [paths] if isinstance(paths, (str, os.PathLike)) else list(paths)
    if not given:
        raise InputError("no terrain file given; name a LAS/LAZ or GeoTIFF file, several, or a folder of them")
    files: list[Path] = []
    for item in map(Path, given):
        if item.is_dir():
            try:
                found = sorted(p for p in item.iterdir() if p.suffix.lower() in _TILE_SUFFIXES and p.is_file())
            except OSError as exc:
                raise InputError(f"{item}: cannot list the folder ({exc.strerror}); check its permissions") from None
            if not found:
                raise InputError(f"{item}: the folder holds no terrain tiles ({', '.join(sorted(_TILE_SUFFIXES))} "
                                 "files); name the folder that holds them, or the files")
            files.extend(found)
        else:
            files.append(item)
        if len(files) > MAX_TILES:
            raise InputError(f"{item}: more than {MAX_TILES:,} terrain tiles; give only the tiles of the region the "
                             "tracks cross")
    unique: dict[str, Path] = {}
    for file in files:
        unique.setdefault(os.path.realpath(file), file)
    return list(unique.values())


_TILE_SUFFIXES = {suffix for suffix, kind in TERRAIN_SUFFIXES.items() if kind in _TILE_KINDS}


@dataclasses.dataclass(frozen=True, eq=False)
class GridTiles:
    """Raster DEM tiles on one grid of cells, read around a track, as one terrain.

    Answers :meth:`elevation_at` as an :class:`~profileopt.io.terrain_maps.ElevationGrid` of
    their mosaic would, without building the mosaic: between the cell centres on either side
    of a seam it interpolates between the cells of both tiles.

    Attributes
    ----------
    blocks : tuple of ElevationGrid
        The windows read, each on the common grid.
    transform : tuple of float, (x0_m, dx_m, y0_m, dy_m)
        The common grid: the centre of its cell (row, col) is at ``x0_m + col * dx_m``,
        ``y0_m + row * dy_m`` (m); cell (0, 0) is the first block's.
    crs : pyproj.CRS
        The tiles' CRS.
    source : str
        The tiles, for messages.
    cell_size_m : tuple of float
        (dx, |dy|) (m).
    notes : tuple of str
        The tiles' notes and which tiles were read.
    file_extent_m : tuple of float
        (xmin, xmax, ymin, ymax) (m) of the cell centres of every tile read, whole.
    """

    blocks: tuple[ElevationGrid, ...]
    transform: tuple[float, float, float, float]
    crs: Any
    source: str
    cell_size_m: tuple[float, float]
    notes: tuple[str, ...] = ()
    file_extent_m: tuple[float, float, float, float] | None = None

    def __post_init__(self) -> None:
        x0, dx, y0, dy = self.transform
        offsets = []
        for block in self.blocks:
            bx0, _, by0, _ = block.transform
            offsets.append((int(round((by0 - y0) / dy)), int(round((bx0 - x0) / dx))))
        object.__setattr__(self, "_offsets", tuple(offsets))

    def elevation_at(self, x_m: np.ndarray, y_m: np.ndarray) -> np.ndarray:
        """Bilinear interpolation between the four cell centres around each point.

        Parameters
        ----------
        x_m, y_m : numpy.ndarray
            Positions (m, in :attr:`crs`), of one shape (or broadcastable).

        Returns
        -------
        numpy.ndarray
            Elevation (m); NaN where one of the four cells with a weight is in no tile read
            or has no data.
        """
        x0, dx, y0, dy = self.transform
        x, y = np.broadcast_arrays(np.asarray(x_m, dtype=float), np.asarray(y_m, dtype=float))
        row, col = (y - y0) / dy, (x - x0) / dx
        # a point on a cell centre computed with rounding errors counts as on it
        row = np.where(np.abs(row - np.round(row)) < 1e-9, np.round(row), row)
        col = np.where(np.abs(col - np.round(col)) < 1e-9, np.round(col), col)
        finite = np.isfinite(row) & np.isfinite(col)
        r0 = np.where(finite, np.floor(np.where(finite, row, 0.0)), 0).astype(np.int64)
        c0 = np.where(finite, np.floor(np.where(finite, col, 0.0)), 0).astype(np.int64)
        fr, fc = np.where(finite, row - r0, 0.0), np.where(finite, col - c0, 0.0)
        z00, z01 = self._cells(r0, c0), self._cells(r0, c0 + 1)
        z10, z11 = self._cells(r0 + 1, c0), self._cells(r0 + 1, c0 + 1)
        top = np.where(fc == 0, z00, z00 * (1 - fc) + z01 * fc)
        bottom = np.where(fc == 0, z10, z10 * (1 - fc) + z11 * fc)
        out = np.where(fr == 0, top, top * (1 - fr) + bottom * fr)
        return np.where(finite, out, np.nan)

    def _cells(self, row: np.ndarray, col: np.ndarray) -> np.ndarray:
        """The elevation (m) of the common grid's cells (row, col): the first tile's that holds
        it with data, NaN where none does."""
        out = np.full(row.shape, np.nan)
        for block, (r_off, c_off) in zip(self.blocks, self._offsets):
            rows, cols = block.z_m.shape
            inside = (row >= r_off) & (row < r_off + rows) & (col >= c_off) & (col < c_off + cols) & np.isnan(out)
            if inside.any():
                out[inside] = block.z_m[row[inside] - r_off, col[inside] - c_off]
        return out

    def extent_m(self) -> tuple[float, float, float, float]:
        """(xmin, xmax, ymin, ymax) (m) of the cell centres of the windows read."""
        extents = np.array([block.extent_m() for block in self.blocks])
        return (float(extents[:, 0].min()), float(extents[:, 1].max()), float(extents[:, 2].min()),
                float(extents[:, 3].max()))


@dataclasses.dataclass(frozen=True)
class _Tile:
    """What a tile's header says: its file, its kind, its box (m), its CRS, its point count."""

    path: Path
    kind: str
    box_m: tuple[float, float, float, float]
    crs: Any
    points: int | None = None
    cell_m: float | None = None


def read_tiles(paths: str | os.PathLike | Sequence[str | os.PathLike], *, terrain_crs: str | None = None,
               track: Any = None, spacing_m: float | None = None, corridor_m: float | None = None
               ) -> Any:
    """Read terrain tiles (several files, or folders of them) as one terrain, only those near a track.

    One file is read as :func:`~profileopt.io.terrain_maps.read_terrain` reads it. Several are
    point clouds (``.las``, ``.laz``) or GeoTIFF DEMs (``.tif``), not both, in one CRS. With a
    ``track``, the tiles whose header bounds come within the sampling margin of it are read
    (:func:`~profileopt.terrain.ground_track.cloud_margin_m`, with the density of all the
    tiles for clouds; a cell more for rasters), each as ``read_terrain`` reads one file
    around the track; without one, every tile is read whole (within the readers' caps).

    Parameters
    ----------
    paths : path or sequence of paths
        Terrain files, or folders of tiles (their ``.las``, ``.laz``, ``.tif``, ``.tiff``
        files).
    terrain_crs : str, optional
        The tiles' CRS (``EPSG:32633``), for tiles that state none or a wrong one.
    track : Track, optional
        The track the terrain will be sampled along (:func:`profileopt.io.read_track`).
    spacing_m, corridor_m : float, optional
        The spacing and corridor (m) it will be sampled with (as ``read_terrain``'s).

    Returns
    -------
    PointCloud or ElevationGrid or GridTiles or CrgSurface
        One terrain: a cloud of the tiles' points, or a grid of their cells.

    Raises
    ------
    InputError
        What :func:`terrain_files` or a reader refuses; clouds mixed with rasters, an OpenCRG
        file among tiles, tiles in different CRSs, rasters on different grids, a track far
        from every tile (one line each, naming the files).
    """
    from ..defaults import DEFAULT_CORRIDOR_M

    files = terrain_files(paths)
    if len(files) == 1:
        return read_terrain(files[0], terrain_crs=terrain_crs, track=track, spacing_m=spacing_m,
                            corridor_m=corridor_m)
    kinds = {}
    for file in files:
        kind = TERRAIN_SUFFIXES.get(file.suffix.lower())
        if kind not in _TILE_KINDS:
            raise InputError(f"{file}: among several terrain files, each must be a LAS/LAZ point cloud or a GeoTIFF "
                             f"DEM tile ({', '.join(sorted(_TILE_SUFFIXES))}), not {file.suffix or 'no ending'!r}; "
                             "an OpenCRG surface is read alone")
        kinds.setdefault(_TILE_KINDS[kind], file)
    if len(kinds) > 1:
        (a_kind, a), (b_kind, b) = list(kinds.items())[:2]
        raise InputError(f"{b}: a {b_kind} among {a_kind} tiles (such as {a.name}); give tiles of one kind")
    label = _label(paths, files)
    corridor = DEFAULT_CORRIDOR_M if corridor_m is None else float(corridor_m)
    tiles = [_header(file, terrain_crs) for file in files]
    for tile in tiles[1:]:
        if not _same_crs(tile.crs, tiles[0].crs):
            raise InputError(f"{tile.path}: its CRS ({_crs_name(tile.crs)}) is not that of {tiles[0].path.name} "
                             f"({_crs_name(tiles[0].crs)}); tiles must share one CRS: reproject them (e.g. 'pdal "
                             "translate' or 'gdalwarp -t_srs'), or give the CRS they all are in (terrain_crs)")
    clouds = tiles[0].kind == "point cloud"
    density = None
    if clouds:
        area = sum(_area_m2(tile.box_m) for tile in tiles)
        density = sum(tile.points or 0 for tile in tiles) / area if area > 0 else None
    chosen = tiles if track is None else _near_track(tiles, track, label, density, spacing_m, corridor)
    if track is None:
        note = f"{label}: read all {len(tiles)} tiles whole (no track to read only those near it)"
    else:
        note = (f"{label}: read {len(chosen)} of its {len(tiles)} tiles, those within reach of the track ("
                + ", ".join(tile.path.name for tile in chosen[:6]) + (", ..." if len(chosen) > 6 else "") + ")")
    if clouds:
        return _join_clouds(chosen, label, terrain_crs, track, spacing_m, corridor, density, note)
    return _join_grids(chosen, label, terrain_crs, track, spacing_m, corridor, note)


def _label(paths: Any, files: list[Path]) -> str:
    """How messages name the tiles: the folder, or the first file and how many more."""
    given = [paths] if isinstance(paths, (str, os.PathLike)) else list(paths)
    if len(given) == 1 and Path(given[0]).is_dir():
        return f"{given[0]} ({len(files)} tiles)"
    return f"{files[0]} and {len(files) - 1} more tile{'s' if len(files) > 2 else ''}"


def _header(path: Path, terrain_crs: str | None) -> _Tile:
    """A tile's box (m), CRS and point count from its header alone."""
    from .geo import length_units_m, require_geo

    if TERRAIN_SUFFIXES[path.suffix.lower()] != "GeoTIFF":
        header, crs = cloud_header(path, terrain_crs=terrain_crs)
        low, high = header.bounds_m
        return _Tile(path, "point cloud", (float(low[0]), float(high[0]), float(low[1]), float(high[1])), crs,
                     header.point_count)
    rasterio = require_geo("rasterio", "reading GeoTIFF")
    from . import inputs

    inputs.check_regular_input(path, "GeoTIFF file")
    try:
        with rasterio.open(path) as dataset:
            bounds, stated, transform = dataset.bounds, dataset.crs, dataset.transform
            crs = geotiff_crs(path, stated, terrain_crs, [])
    except rasterio.errors.RasterioError as exc:
        raise unreadable_geotiff(path, exc) from None
    except rasterio.errors.CRSError as exc:  # not a RasterioError: raised as the file is opened
        raise unreadable_geotiff_crs(path, exc, terrain_crs) from None
    unit = length_units_m(crs, str(path))[0]
    return _Tile(path, "GeoTIFF DEM", (bounds.left * unit, bounds.right * unit, min(bounds.bottom, bounds.top) * unit,
                                       max(bounds.bottom, bounds.top) * unit), crs,
                 cell_m=float(max(abs(transform.a), abs(transform.e))) * unit)


def _same_crs(a: Any, b: Any) -> bool:
    if a is None or b is None:
        return a is None and b is None
    return bool(a == b)


def _crs_name(crs: Any) -> str:
    from .geo import crs_label

    return "none stated" if crs is None else crs_label(crs)


def _area_m2(box: tuple[float, float, float, float]) -> float:
    area = (box[1] - box[0]) * (box[3] - box[2])
    return area if math.isfinite(area) and area > 0 else 0.0


def _near_track(tiles: list[_Tile], track: Any, label: str, density: float | None, spacing_m: float | None,
                corridor_m: float) -> list[_Tile]:
    """The tiles whose boxes come within the sampling margin of the track (a raster's: a cell more)."""
    from ..core.route import path_distance_m
    from ..terrain.ground_track import cloud_margin_m, track_on_terrain_m

    x, y = track_on_terrain_m(track, tiles[0].crs, label)
    margin = cloud_margin_m(density, spacing_m, corridor_m)
    if tiles[0].kind != "point cloud":  # a raster's cells: the interpolation reaches a cell further
        margin += max(tile.cell_m or 0.0 for tile in tiles)
    # nodes every half margin along the track: a point within the margin of the track is
    # within hypot(margin, margin / 4) of a node
    along = path_distance_m(x, y)
    count = max(int(math.ceil(along[-1] / (0.5 * margin))) + 1, 2)
    nodes_s = np.linspace(0.0, along[-1], count)
    nx, ny = np.interp(nodes_s, along, x), np.interp(nodes_s, along, y)
    reach = math.hypot(margin, 0.25 * margin) * (1 + 1e-9)
    chosen = [tile for tile in tiles
              if np.any((nx >= tile.box_m[0] - reach) & (nx <= tile.box_m[1] + reach)
                        & (ny >= tile.box_m[2] - reach) & (ny <= tile.box_m[3] + reach))]
    if not chosen:
        boxes = np.array([tile.box_m for tile in tiles])
        raise InputError(f"{track.source}: the track (x {x.min():.1f} to {x.max():.1f} m, y {y.min():.1f} to "
                         f"{y.max():.1f} m) meets none of the tiles {label} (x {boxes[:, 0].min():.1f} to "
                         f"{boxes[:, 1].max():.1f} m, y {boxes[:, 2].min():.1f} to {boxes[:, 3].max():.1f} m); are "
                         "the CRS of the track and of the tiles right (track_crs, terrain_crs)?")
    return chosen


def _join_clouds(tiles: list[_Tile], label: str, terrain_crs: str | None, track: Any, spacing_m: float | None,
                 corridor_m: float, density: float | None, note: str) -> PointCloud:
    """The clouds of ``tiles`` as one, each read near the track with the margin all of them set."""
    from .las import MAX_CLOUD_POINTS

    clouds = []
    held = 0
    for tile in tiles:
        keep = None if track is None else NearTrack(track, label, spacing_m, corridor_m, density_per_m2=density)
        cloud = read_cloud(tile.path, terrain_crs=terrain_crs, keep=keep)
        held += len(cloud)
        if held > MAX_CLOUD_POINTS:
            raise InputError(f"{label}: its tiles hold more than {MAX_CLOUD_POINTS:,} points near the track; thin "
                             "them first (e.g. 'pdal translate in.laz out.laz sample --filters.sample.radius=0.02') "
                             "or cut the track into parts")
        clouds.append(cloud)
    x = np.concatenate([c.x_m for c in clouds])
    y = np.concatenate([c.y_m for c in clouds])
    z = np.concatenate([c.z_m for c in clouds])
    classes = np.concatenate([c.classification for c in clouds])
    once = _once(x, y, z, [tile.box_m for tile in tiles])
    dropped = x.size - int(once.sum()) if once is not None else 0
    if once is not None:
        x, y, z, classes = x[once], y[once], z[once], classes[once]
    extents = np.array([c.extent_m() for c in clouds])
    ground = sum(c.ground_count or 0 for c in clouds)
    ground_area = sum(_area_m2(c.extent_m()) for c in clouds if c.ground_count)
    notes = [note] + [n for c in clouds for n in c.notes]
    if dropped:
        notes.append(f"{label}: {dropped:,} points held by two overlapping tiles counted once")
    first = clouds[0].header
    header = dataclasses.replace(first, path=label, point_count=sum(c.header.point_count for c in clouds),
                                 min_xyz=tuple(float(v) for v in np.min([c.header.bounds_m[0] for c in clouds], 0)),
                                 max_xyz=tuple(float(v) for v in np.max([c.header.bounds_m[1] for c in clouds], 0)),
                                 horizontal_unit_m=1.0, vertical_unit_m=1.0,
                                 units_source="each tile's own, joined in metres")
    kept = [c.kept_within_m for c in clouds if c.kept_within_m is not None]
    return PointCloud(x_m=x, y_m=y, z_m=z, classification=classes, header=header, crs=clouds[0].crs,
                      notes=tuple(notes), kept_within_m=min(kept) if kept else None,
                      file_extent_m=(float(extents[:, 0].min()), float(extents[:, 1].max()),
                                     float(extents[:, 2].min()), float(extents[:, 3].max())),
                      ground_count=ground, ground_density_per_m2=ground / ground_area if ground_area > 0 else None)


def _once(x: np.ndarray, y: np.ndarray, z: np.ndarray, boxes: list[tuple[float, float, float, float]]
          ) -> np.ndarray | None:
    """Which points to keep so that a point stored in two overlapping tiles counts once (the
    first tile's); None when no two tiles' boxes overlap."""
    overlaps = []
    for i, a in enumerate(boxes):
        for b in boxes[i + 1:]:
            box = (max(a[0], b[0]), min(a[1], b[1]), max(a[2], b[2]), min(a[3], b[3]))
            if box[0] <= box[1] and box[2] <= box[3]:
                overlaps.append(box)
    if not overlaps:
        return None
    shared = np.zeros(x.size, dtype=bool)
    for box in overlaps:
        shared |= (x >= box[0]) & (x <= box[1]) & (y >= box[2]) & (y <= box[3])
    keep = np.ones(x.size, dtype=bool)
    index = np.flatnonzero(shared)
    if index.size:
        _, first = np.unique(np.column_stack([x[index], y[index], z[index]]), axis=0, return_index=True)
        keep[index] = False
        keep[index[first]] = True
    return keep


def _join_grids(tiles: list[_Tile], label: str, terrain_crs: str | None, track: Any, spacing_m: float | None,
                corridor_m: float, note: str) -> ElevationGrid | GridTiles:
    """The windows of ``tiles`` around the track on their common grid of cells."""

    blocks = []
    cells = 0
    for tile in tiles:
        near = None if track is None else (lambda crs: track_box_m(track, crs, label, None, spacing_m, corridor_m))
        grid = read_geotiff(tile.path, terrain_crs=terrain_crs, near=near)
        cells += grid.z_m.size
        if cells > MAX_GRID_CELLS:
            raise InputError(f"{label}: its tiles have more than {MAX_GRID_CELLS:,} cells around the track; cut the "
                             "track into parts, or coarsen the tiles (gdalwarp -tr)")
        blocks.append(grid)
    ref = blocks[0]
    x0, dx, y0, dy = ref.transform
    for grid, tile in zip(blocks[1:], tiles[1:]):
        gx0, gdx, gy0, gdy = grid.transform
        col, row = (gx0 - x0) / dx, (gy0 - y0) / dy
        if (not math.isclose(gdx, dx, rel_tol=1e-9) or not math.isclose(gdy, dy, rel_tol=1e-9)
                or abs(col - round(col)) > 1e-6 or abs(row - round(row)) > 1e-6):
            raise InputError(f"{tile.path}: its cells ({abs(gdx):g} m x {abs(gdy):g} m, a centre at x {gx0:.6g}, "
                             f"y {gy0:.6g} m) are not on the grid of {tiles[0].path.name} ({abs(dx):g} m x "
                             f"{abs(dy):g} m, a centre at x {x0:.6g}, y {y0:.6g} m); resample the tiles onto one grid "
                             "(e.g. 'gdalwarp -tap -tr DX DY') or mosaic them ('gdalbuildvrt' then 'gdal_translate')")
    extents = np.array([grid.file_extent_m or grid.extent_m() for grid in blocks])
    notes = [note] + [n for grid in blocks for n in grid.notes]
    return GridTiles(blocks=tuple(blocks), transform=ref.transform, crs=ref.crs, source=label,
                     cell_size_m=ref.cell_size_m, notes=tuple(notes),
                     file_extent_m=(float(extents[:, 0].min()), float(extents[:, 1].max()),
                                    float(extents[:, 2].min()), float(extents[:, 3].max())))
