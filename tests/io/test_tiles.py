"""profileopt.io.tiles: terrain in tiles read as one terrain (issue 32).

The reference for tiles is the one file they were cut from: a track over the tiles must give
the route it gives over that file, within float rounding (the tiles' coordinates are stored
with their own offsets). The ground is the closed-form surface of ``geo_data``, written with
laspy and rasterio themselves; the tiles are cut so that all four meet on the track.
"""

from __future__ import annotations

import subprocess
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("laspy")
pytest.importorskip("rasterio")

import geo_data as g  # noqa: E402
from conftest import PROFILEOPT  # noqa: E402
from profileopt.errors import InputError  # noqa: E402
from profileopt.io import read_terrain, read_track  # noqa: E402
from profileopt.io.tiles import GridTiles, read_tiles, terrain_files  # noqa: E402
from profileopt.terrain.ground_track import route_from_track  # noqa: E402

#: Where the tiles meet: a point on the track (the arc at 0.5 rad), so the track runs through
#: the corner that all four tiles share.
CORNER_M = (g.ORIGIN_M[0] + 10 + g.ARC_RADIUS_M * np.sin(0.5), g.ORIGIN_M[1] + 10 + g.ARC_RADIUS_M * (1 - np.cos(0.5)))
QUADRANTS = ("sw", "se", "nw", "ne")


def _quadrant(name: str, x: np.ndarray, y: np.ndarray, overlap_m: float = 0.0) -> np.ndarray:
    east = x >= CORNER_M[0] - overlap_m if name[1] == "e" else x < CORNER_M[0] + overlap_m
    north = y >= CORNER_M[1] - overlap_m if name[0] == "n" else y < CORNER_M[1] + overlap_m
    return east & north


@pytest.fixture(scope="module")
def ground(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """merged.laz, its four tiles in tiles/ (and a fifth far away), the same with 0.5 m
    buffers in buffered/, merged.tif and its four tiles in dem/, and track.gpx."""
    root = tmp_path_factory.mktemp("tiles")
    x, y, z, c = g.cloud_points()
    g.write_laz(root / "merged.laz", x, y, z, c)
    for folder, overlap in (("tiles", 0.0), ("buffered", 0.5)):
        (root / folder).mkdir()
        for name in QUADRANTS:
            keep = _quadrant(name, x, y, overlap)
            g.write_laz(root / folder / f"{name}.laz", x[keep], y[keep], z[keep], c[keep])
    g.write_laz(root / "tiles" / "far.laz", x[:1000] + 900.0, y[:1000] + 900.0, z[:1000], c[:1000])
    tx, ty = g.track_utm_m(2.0)
    g.write_gpx(root / "track.gpx", tx, ty)
    _dem_tiles(g.write_geotiff(root / "merged.tif", cell_m=0.05), root / "dem")
    return root


def _dem_tiles(merged: Path, folder: Path) -> None:
    """The raster cut into four on its own grid at the cell nearest the corner (rasterio windows)."""
    import rasterio
    from affine import Affine
    from rasterio.windows import Window

    folder.mkdir()
    with rasterio.open(merged) as dataset:
        row, col = dataset.index(*CORNER_M)
        profile = dataset.profile
        for name, (r0, r1) in (("n", (0, row)), ("s", (row, dataset.height))):
            for east, (c0, c1) in (("w", (0, col)), ("e", (col, dataset.width))):
                window = Window(c0, r0, c1 - c0, r1 - r0)
                a, _, c, _, e, f = tuple(dataset.transform)[:6]
                tile = dict(profile, height=r1 - r0, width=c1 - c0,
                            transform=Affine(a, 0.0, c + c0 * a, 0.0, e, f + r0 * e))
                with rasterio.open(folder / f"{name}{east}.tif", "w", **tile) as out:
                    out.write(dataset.read(1, window=window), 1)


def _route(ground: Path, terrain: object):
    track = read_track(ground / "track.gpx")
    return route_from_track(track, terrain).route


def test_a_track_over_four_laz_tiles_gives_the_route_over_their_merged_file(ground: Path) -> None:
    track = read_track(ground / "track.gpx")
    tiles = read_tiles(ground / "tiles", track=track)
    assert "read 4 of its 5 tiles" in tiles.notes[0] and "far.laz" not in tiles.notes[0]
    merged = read_terrain(ground / "merged.laz", track=track)
    one, four = _route(ground, merged), _route(ground, tiles)
    assert np.array_equal(one.s_m, four.s_m)
    assert np.allclose(one.z_m, four.z_m, rtol=0, atol=1e-9)  # coordinates stored with each tile's offsets
    # the track runs through the corner where all four meet: each tile gives points
    for name in QUADRANTS:
        assert str(ground / "tiles" / f"{name}.laz") in [str(p) for p in terrain_files(ground / "tiles")]
    near = np.hypot(tiles.x_m - CORNER_M[0], tiles.y_m - CORNER_M[1]) < 0.2
    quadrants = {name for name in QUADRANTS if _quadrant(name, tiles.x_m[near], tiles.y_m[near]).any()}
    assert quadrants == set(QUADRANTS)


def test_a_point_two_buffered_tiles_hold_counts_once(ground: Path) -> None:
    track = read_track(ground / "track.gpx")
    whole = read_tiles(sorted((ground / "buffered").iterdir()))
    merged = read_terrain(ground / "merged.laz")
    assert len(whole) == len(merged)  # the same points: those in the 0.5 m buffers once
    assert any("counted once" in note for note in whole.notes)
    first = sorted((ground / "buffered").iterdir())[0]
    assert whole.notes[0] == f"{first} and 3 more tiles: read all 4 tiles whole (no track to read only those near it)"
    def points(cloud) -> np.ndarray:  # noqa: ANN001  (rows x, y, z in mm, as the files store them)
        return np.unique(np.round(np.column_stack([cloud.x_m, cloud.y_m, cloud.z_m]) * 1000).astype(np.int64), axis=0)

    assert np.array_equal(points(whole), points(merged))
    buffered = read_tiles(sorted((ground / "buffered").iterdir()), track=track)
    assert np.allclose(_route(ground, merged).z_m, _route(ground, buffered).z_m, rtol=0, atol=1e-9)


def test_a_track_over_four_dem_tiles_gives_the_route_over_their_merged_file(ground: Path) -> None:
    track = read_track(ground / "track.gpx")
    tiles = read_tiles(ground / "dem", track=track)
    assert isinstance(tiles, GridTiles) and len(tiles.blocks) == 4
    merged = read_terrain(ground / "merged.tif", track=track)
    one, four = _route(ground, merged), _route(ground, tiles)
    assert np.allclose(one.z_m, four.z_m, rtol=0, atol=1e-9) and not np.isnan(four.z_m).any()
    # between the cell centres on either side of a seam: both tiles' cells, as in the mosaic
    x0, dx, y0, dy = merged.transform
    seam_x = np.linspace(CORNER_M[0] - 1.0, CORNER_M[0] + 1.0, 401)
    seam_y = np.full_like(seam_x, CORNER_M[1] + 0.013)
    assert np.allclose(tiles.elevation_at(seam_x, seam_y), merged.elevation_at(seam_x, seam_y), rtol=0, atol=1e-9)
    # and the surface itself, within what bilinear interpolation of 5 cm cells misses
    assert np.allclose(tiles.elevation_at(seam_x, seam_y), g.surface_m(seam_x, seam_y), atol=5e-3)


def test_tiles_of_two_kinds_or_two_crs_or_two_grids_are_refused(ground: Path, tmp_path: Path) -> None:
    with pytest.raises(InputError, match="GeoTIFF DEM among point cloud tiles"):
        read_tiles([ground / "tiles" / "sw.laz", ground / "dem" / "nw.tif"])
    x, y, z, c = g.cloud_points(density_per_m2=50.0)
    g.write_laz(tmp_path / "a.laz", x, y, z, c)
    g.write_laz(tmp_path / "b.laz", x, y, z, c, epsg=32634)
    with pytest.raises(InputError, match=r"b\.laz: its CRS .* is not that of a\.laz"):
        read_tiles(tmp_path)
    g.write_geotiff(tmp_path / "fine.tif", cell_m=0.05)
    g.write_geotiff(tmp_path / "coarse.tif", cell_m=0.07)
    with pytest.raises(InputError, match=r"fine\.tif: its cells .* are not on the grid of coarse\.tif.*gdalwarp"):
        read_tiles([tmp_path / "coarse.tif", tmp_path / "fine.tif"])
    (tmp_path / "empty").mkdir()
    with pytest.raises(InputError, match="empty: the folder holds no terrain tiles"):
        read_tiles(tmp_path / "empty")
    with pytest.raises(InputError, match="an OpenCRG surface is read alone"):
        read_tiles([tmp_path / "a.laz", tmp_path / "road.crg"])


def test_a_track_far_from_every_tile_is_refused(ground: Path, tmp_path: Path) -> None:
    tx, ty = g.track_utm_m(2.0)
    g.write_gpx(tmp_path / "away.gpx", tx + 5000.0, ty)
    with pytest.raises(InputError, match="away.gpx: the track .* meets none of the tiles"):
        read_tiles(ground / "tiles", track=read_track(tmp_path / "away.gpx"))


@pytest.mark.slow
def test_route_and_plan_take_several_terrain_files_or_a_folder(ground: Path, tmp_path: Path) -> None:
    runs = {}
    for name, terrain in (("merged", ["merged.laz"]), ("folder", ["tiles"]),
                          ("files", [f"tiles/{n}.laz" for n in QUADRANTS])):
        out = tmp_path / f"{name}.csv"
        done = subprocess.run([*PROFILEOPT, "route", "track.gpx", "--terrain", *terrain, "-o", str(out)],
                              cwd=ground, capture_output=True, text=True, timeout=120)
        assert done.returncode == 0, done.stderr
        rows = [line for line in out.read_text().splitlines() if not line.startswith("#")][1:]  # past the header
        runs[name] = np.array([line.split(",") for line in rows], dtype=float)
    assert np.allclose(runs["merged"], runs["folder"], rtol=0, atol=1e-9)
    assert np.allclose(runs["merged"], runs["files"], rtol=0, atol=1e-9)
    # a tile is an input: no output may replace it
    done = subprocess.run([*PROFILEOPT, "plan", "track.gpx", "--terrain", "tiles", "-o", "tiles/sw.laz"],
                          cwd=ground, capture_output=True, text=True, timeout=120)
    assert done.returncode == 2 and len(done.stderr.strip().splitlines()) == 1, done.stderr
    assert "sw.laz" in done.stderr
