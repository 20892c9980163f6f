"""Synthetic ground with a known surface, written as the files people plan from: a LAZ point
cloud (ground, vegetation and noise points), a GeoTIFF DEM in a UTM CRS, and a GPX track in
WGS 84 over it (issue 12).

The surface z(x, y) is known in closed form (:func:`surface_m`), so the ground under any
route is known exactly, independently of the code under test. Written with the reference
libraries themselves (laspy + lazrs, rasterio, gpxpy, pyproj), not with profileopt.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

#: UTM zone 33N (WGS 84): the CRS of the synthetic ground.
UTM_EPSG = 32633
#: The ground's south-west corner (easting, northing, m): in Slovenia, inside zone 33.
ORIGIN_M = (430_000.0, 5_100_000.0)
#: The track: an arc of this radius (m) turning left through this angle (rad), starting 10 m
#: in from the origin heading east.
ARC_RADIUS_M = 60.0
ARC_ANGLE_RAD = 1.0
#: Ground points per m^2 of the synthetic cloud (a UGV-mounted LiDAR's density).
CLOUD_DENSITY_PER_M2 = 1500.0
#: The cloud covers this far (m) either side of the track.
CLOUD_HALF_WIDTH_M = 1.0


def surface_m(x_m: np.ndarray, y_m: np.ndarray) -> np.ndarray:
    """The synthetic ground's elevation (m): a 3 % grade, long swells and wheel-scale bumps
    (wavelengths 0.6 m to 12 m, a few mm to 5 cm)."""
    u = np.asarray(x_m) - ORIGIN_M[0]
    w = np.asarray(y_m) - ORIGIN_M[1]
    return (300.0 + 0.03 * u + 0.01 * w
            + 0.05 * np.sin(2 * np.pi * u / 12.0) * np.cos(2 * np.pi * w / 15.0)
            + 0.02 * np.sin(2 * np.pi * (u + 0.7 * w) / 2.3)
            + 0.012 * np.sin(2 * np.pi * (0.6 * u - w) / 1.1 + 0.4)
            + 0.006 * np.cos(2 * np.pi * (u + w) / 0.6))


def track_utm_m(spacing_m: float = 2.0) -> tuple[np.ndarray, np.ndarray]:
    """The track's points (m, UTM 33N) every ``spacing_m`` along the arc."""
    length = ARC_RADIUS_M * ARC_ANGLE_RAD
    t = np.linspace(0.0, ARC_ANGLE_RAD, int(round(length / spacing_m)) + 1)
    x0, y0 = ORIGIN_M[0] + 10.0, ORIGIN_M[1] + 10.0
    return x0 + ARC_RADIUS_M * np.sin(t), y0 + ARC_RADIUS_M * (1.0 - np.cos(t))


def write_gpx(path: Path, x_m: np.ndarray, y_m: np.ndarray) -> Path:
    """A GPX 1.1 track of UTM 33N points, in WGS 84 latitude and longitude (pyproj)."""
    import gpxpy.gpx
    from pyproj import Transformer

    lon, lat = Transformer.from_crs(UTM_EPSG, 4326, always_xy=True).transform(x_m, y_m)
    gpx = gpxpy.gpx.GPX()
    track = gpxpy.gpx.GPXTrack(name="synthetic arc")
    segment = gpxpy.gpx.GPXTrackSegment()
    for la, lo in zip(lat, lon):
        segment.points.append(gpxpy.gpx.GPXTrackPoint(latitude=float(la), longitude=float(lo)))
    track.segments.append(segment)
    gpx.tracks.append(track)
    path.write_text(gpx.to_xml(version="1.1"), encoding="utf-8")
    return path


def cloud_points(seed: int = 0, density_per_m2: float = CLOUD_DENSITY_PER_M2
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Points within CLOUD_HALF_WIDTH_M of the track: ground (class 2) on the surface with
    3 mm of sensor noise, then 15 % more points of vegetation (classes 3-5, 5 cm to 1 m
    above it) and 1 % of noise (class 7, 2 m above or below). Returns x, y, z (m) and class."""
    rng = np.random.default_rng(seed)
    tx, ty = track_utm_m(0.05)
    length = ARC_RADIUS_M * ARC_ANGLE_RAD
    count = int(density_per_m2 * 2 * CLOUD_HALF_WIDTH_M * (length + 2.0))
    # uniform over the strip: a point along the track and an offset across it
    along = rng.uniform(-1.0, length + 1.0, count) / ARC_RADIUS_M
    across = rng.uniform(-CLOUD_HALF_WIDTH_M, CLOUD_HALF_WIDTH_M, count)
    radius = ARC_RADIUS_M - across
    x = tx[0] + radius * np.sin(along)
    y = ty[0] + ARC_RADIUS_M - radius * np.cos(along)
    z = surface_m(x, y) + rng.normal(0.0, 0.003, count)
    classes = np.full(count, 2, dtype=np.uint8)
    n_veg, n_noise = int(0.15 * count), int(0.01 * count)
    pick = rng.choice(count, n_veg + n_noise, replace=False)
    veg, noise = pick[:n_veg], pick[n_veg:]
    extra_x = np.concatenate([x[veg], x[noise]])
    extra_y = np.concatenate([y[veg], y[noise]])
    extra_z = np.concatenate([z[veg] + rng.uniform(0.05, 1.0, n_veg), z[noise] + rng.choice([-2.0, 2.0], n_noise)])
    extra_c = np.concatenate([rng.choice(np.array([3, 4, 5], dtype=np.uint8), n_veg),
                              np.full(n_noise, 7, dtype=np.uint8)])
    return (np.concatenate([x, extra_x]), np.concatenate([y, extra_y]), np.concatenate([z, extra_z]),
            np.concatenate([classes, extra_c]))


def write_laz(path: Path, x: np.ndarray, y: np.ndarray, z: np.ndarray, classes: np.ndarray, *,
              epsg: int | None = UTM_EPSG) -> Path:
    """A LAS 1.4 point format 6 file (LAZ when ``path`` ends in .laz), 1 mm resolution,
    with the CRS as WKT (laspy)."""
    import laspy

    header = laspy.LasHeader(point_format=6, version="1.4")
    header.offsets = np.array([np.floor(x.min()), np.floor(y.min()), np.floor(z.min())])
    header.scales = np.array([0.001, 0.001, 0.001])
    if epsg is not None:
        from pyproj import CRS

        header.add_crs(CRS.from_epsg(epsg))
    las = laspy.LasData(header)
    las.x, las.y, las.z = x, y, z
    las.classification = classes
    las.write(str(path))
    return path


def write_geotiff(path: Path, cell_m: float = 0.05, *, epsg: int | None = UTM_EPSG) -> Path:
    """The surface sampled at cell centres on a north-up grid covering the track (rasterio),
    float32, no-data -9999."""
    import rasterio
    from affine import Affine

    tx, ty = track_utm_m(0.5)
    west, north = np.floor(tx.min()) - 3.0, np.ceil(ty.max()) + 3.0
    cols = int(np.ceil((tx.max() + 3.0 - west) / cell_m))
    rows = int(np.ceil((north - (ty.min() - 3.0)) / cell_m))
    xc = west + (np.arange(cols) + 0.5) * cell_m
    yc = north - (np.arange(rows) + 0.5) * cell_m
    z = surface_m(xc[None, :], yc[:, None]).astype(np.float32)
    profile = dict(driver="GTiff", height=rows, width=cols, count=1, dtype="float32", nodata=-9999.0,
                   transform=Affine(cell_m, 0.0, west, 0.0, -cell_m, north))
    if epsg is not None:
        profile["crs"] = f"EPSG:{epsg}"
    with rasterio.open(path, "w", **profile) as dst:
        dst.write(z, 1)
    return path


def write_sparse_geotiff(path: Path, cells: int = 50_000, cell_m: float = 0.05, margin_m: float = 5.0) -> Path:
    """A ``cells`` x ``cells`` GeoTIFF (UTM 33N) of which only the tiles within ``margin_m`` of
    the track hold the surface (float32, no-data -9999); the rest is never written, so the
    file is small (a sparse GeoTIFF: 2.5e9 cells in about 7 MB) though it claims 9.3 GiB of
    float32 cells (issue 30). Its north-west corner lies 1 km west and north of ORIGIN_M."""
    import rasterio
    from affine import Affine
    from rasterio.windows import Window

    west, north = ORIGIN_M[0] - 1000.0, ORIGIN_M[1] + 1000.0
    profile = dict(driver="GTiff", height=cells, width=cells, count=1, dtype="float32", nodata=-9999.0,
                   tiled=True, blockxsize=256, blockysize=256, sparse_ok=True, crs=f"EPSG:{UTM_EPSG}",
                   transform=Affine(cell_m, 0.0, west, 0.0, -cell_m, north))
    tx, ty = track_utm_m(0.5)
    c0, c1 = int((tx.min() - margin_m - west) / cell_m), int((tx.max() + margin_m - west) / cell_m)
    r0, r1 = int((north - ty.max() - margin_m) / cell_m), int((north - ty.min() + margin_m) / cell_m)
    xc = west + (np.arange(c0, c1) + 0.5) * cell_m
    yc = north - (np.arange(r0, r1) + 0.5) * cell_m
    with rasterio.open(path, "w", **profile) as dst:
        dst.write(surface_m(xc[None, :], yc[:, None]).astype(np.float32), 1, window=Window(c0, r0, c1 - c0, r1 - r0))
    return path
