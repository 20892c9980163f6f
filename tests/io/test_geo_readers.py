"""Readers of GPS tracks and terrain maps (issue 12): profileopt.io.tracks, las (LAZ),
terrain_maps.

Reference values: Snyder's transverse Mercator series (USGS Professional Paper 1395, 1987,
eqs. 8-9, 8-10, 3-21), checked here against Snyder's own worked example (Clarke 1866,
40 deg 30' N, 73 deg 30' W, central meridian 75 W: x = 127,106.5 m, y = 4,484,124.4 m);
the exact US survey foot (1200/3937 m); files written by the tests from known functions (a
plane, which bilinear interpolation reproduces exactly); the geodesic gap in the bundled GPX
file from pyproj.Geod checked against a spherical haversine (an independent formula); the
bundled OpenCRG profiles as ``read_opencrg`` reads them.
"""

from __future__ import annotations

import json
import math
import struct
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from profileopt.errors import InputError
from profileopt.io import (CrgSurface, ElevationGrid, PointCloud, local_projected_crs, project_track, read_crg_surface,
                           read_geotiff, read_las, read_opencrg, read_terrain, read_track)
from profileopt.io.tracks import JOIN_GAP_M

from conftest import REAL_DATA, ROOT

pytestmark = pytest.mark.geo  # every test here reads or writes geographic files
laspy = pytest.importorskip("laspy")
rasterio = pytest.importorskip("rasterio")
pyproj = pytest.importorskip("pyproj")

GPX_DIR = REAL_DATA / "gpx-tracks"
KRC = sorted((REAL_DATA / "krc-rms-courses").glob("*.crg"))
US_FOOT_M = 1200.0 / 3937.0
WGS84_A, WGS84_F = 6378137.0, 1 / 298.257223563


def snyder_tm(lat_deg: float, lon_deg: float, lon0_deg: float, a: float, f: float, k0: float = 0.9996):
    """Transverse Mercator (x, y) in metres by Snyder's series, without false easting."""
    e2 = f * (2 - f)
    ep2 = e2 / (1 - e2)
    p = math.radians(lat_deg)
    A = math.radians(lon_deg - lon0_deg) * math.cos(p)
    N = a / math.sqrt(1 - e2 * math.sin(p) ** 2)
    T, C = math.tan(p) ** 2, ep2 * math.cos(p) ** 2
    M = a * ((1 - e2 / 4 - 3 * e2 ** 2 / 64 - 5 * e2 ** 3 / 256) * p
             - (3 * e2 / 8 + 3 * e2 ** 2 / 32 + 45 * e2 ** 3 / 1024) * math.sin(2 * p)
             + (15 * e2 ** 2 / 256 + 45 * e2 ** 3 / 1024) * math.sin(4 * p) - (35 * e2 ** 3 / 3072) * math.sin(6 * p))
    x = k0 * N * (A + (1 - T + C) * A ** 3 / 6 + (5 - 18 * T + T * T + 72 * C - 58 * ep2) * A ** 5 / 120)
    y = k0 * (M + N * math.tan(p) * (A * A / 2 + (5 - T + 9 * C + 4 * C * C) * A ** 4 / 24
                                     + (61 - 58 * T + T * T + 600 * C - 330 * ep2) * A ** 6 / 720))
    return x, y


def test_hand_formula_reproduces_snyders_example() -> None:
    a, b = 6378206.4, 6356583.8  # Clarke 1866
    x, y = snyder_tm(40.5, -73.5, -75.0, a, (a - b) / a)
    assert x == pytest.approx(127106.5, abs=0.05) and y == pytest.approx(4484124.4, abs=0.05)


def one_line(raised: pytest.ExceptionInfo, *words: str) -> str:
    message = str(raised.value)
    assert "\n" not in message
    for word in words:
        assert word in message, message
    return message


# ------------------------------------------------------------------------------ GPX


def test_mojstrovka_reads_and_projects_to_utm_33_by_hand_formula() -> None:
    track = read_track(GPX_DIR / "Mojstrovka.gpx", smooth=False)  # the points as the file gives them
    assert len(track) == 184 and track.z_m is not None and track.crs.to_epsg() == 4326
    # first point of the file: lat 46.434981, lon 13.748273, ele 1614.678
    assert (track.x[0], track.y[0], track.z_m[0]) == (13.748273, 46.434981, 1614.678)
    utm = local_projected_crs(track)
    assert utm.to_epsg() == 32633  # 13.7 deg E: zone floor((13.7 + 180) / 6) + 1 = 33, north
    projected = project_track(track, utm)
    for i in (0, 100, 183):
        x, y = snyder_tm(track.y[i], track.x[i], 15.0, WGS84_A, WGS84_F)
        assert projected.x[i] == pytest.approx(x + 500000.0, abs=0.005)
        assert projected.y[i] == pytest.approx(y, abs=0.005)
    assert projected.crs == utm and "projected from EPSG:4326 to EPSG:32633" in projected.notes[-1]


def test_projection_into_feet_gives_metres() -> None:
    track = read_track(GPX_DIR / "Mojstrovka.gpx")
    feet = pyproj.CRS("+proj=tmerc +lon_0=15 +k=0.9996 +x_0=500000 +ellps=WGS84 +units=us-ft +no_defs")
    projected = project_track(track, feet)
    x, y = snyder_tm(track.y[5], track.x[5], 15.0, WGS84_A, WGS84_F)
    assert projected.x[5] == pytest.approx(x + 500000.0, abs=0.005)
    assert projected.y[5] == pytest.approx(y, abs=0.005)


def test_korita_has_two_drives_refused_until_one_is_chosen() -> None:
    path = GPX_DIR / "korita-zbevnica.gpx"
    with pytest.raises(InputError) as raised:
        read_track(path)
    # track 1 ends at 45.380679639, 14.144522203; track 2 starts at 45.452595614, 14.018194014
    lat1, lon1, lat2, lon2 = map(math.radians, (45.380679639, 14.144522203, 45.452595614, 14.018194014))
    haversine = 2 * 6371008.8 * math.asin(math.sqrt(math.sin((lat2 - lat1) / 2) ** 2
                                                    + math.cos(lat1) * math.cos(lat2) * math.sin((lon2 - lon1) / 2) ** 2))
    message = one_line(raised, str(path), "track 1 segment 0", "track 2 segment 0", "--track-index",
                       "'03-OCT-10 #2' 358 points")
    gap = float(message.split(" ends ")[1].split(" m ")[0])
    assert gap == pytest.approx(haversine, rel=0.005)  # sphere vs ellipsoid: 0.5 %
    track = read_track(path, track_index=1)
    assert len(track) == 358 and track.z_m is not None
    assert len(read_track(path, track_index=3)) == 337
    with pytest.raises(InputError) as raised:
        read_track(path, track_index=0)  # an empty track
    one_line(raised, "track 0", "no points", "choose --track-index")


def gpx(body: str) -> str:
    return ('<?xml version="1.0"?><gpx version="1.1" creator="test" xmlns="http://www.topografix.com/GPX/1/1">'
            f"{body}</gpx>")


def pt(lat: float, lon: float, tag: str = "trkpt", ele: float | None = None, time: str | None = None) -> str:
    inner = (f"<ele>{ele}</ele>" if ele is not None else "") + (f"<time>{time}</time>" if time else "")
    return f'<{tag} lat="{lat}" lon="{lon}">{inner}</{tag}>'


# 1e-4 deg of latitude is 11.1 m; 3e-4 deg 33 m (< 50 m), 6e-4 deg 67 m (> 50 m)
SEG_A = "".join(pt(46.0 + 1e-4 * i, 14.0, ele=300 + i) for i in range(3))


def write(tmp_path: Path, name: str, text: str) -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def test_segments_within_the_gap_are_joined_with_a_note(tmp_path: Path) -> None:
    seg_b = "".join(pt(46.0005 + 1e-4 * i, 14.0, ele=400) for i in range(2))  # starts 33 m on
    path = write(tmp_path, "two.gpx", gpx(f"<trk><trkseg>{SEG_A}</trkseg><trkseg>{seg_b}</trkseg></trk>"))
    track = read_track(path)
    assert len(track) == 5 and track.y[3] == 46.0005
    assert any("joined track 0 segment 0 to track 0 segment 1 across a gap of 33." in n for n in track.notes)
    far = "".join(pt(46.0008 + 1e-4 * i, 14.0) for i in range(2))  # 67 m on
    path = write(tmp_path, "far.gpx", gpx(f"<trk><trkseg>{SEG_A}</trkseg></trk><trk><trkseg>{far}</trkseg></trk>"))
    with pytest.raises(InputError) as raised:
        read_track(path)
    one_line(raised, "ends 67 m", f"{JOIN_GAP_M:g} m", "--track-index")
    assert len(read_track(path, track_index=1)) == 2


def test_a_repeated_joint_point_is_dropped(tmp_path: Path) -> None:
    seg_b = pt(46.0002, 14.0, ele=302) + pt(46.0004, 14.0, ele=304)  # starts where SEG_A ends
    path = write(tmp_path, "joint.gpx", gpx(f"<trk><trkseg>{SEG_A}</trkseg><trkseg>{seg_b}</trkseg></trk>"))
    track = read_track(path)
    assert track.y.tolist() == [46.0, 46.0001, 46.0002, 46.0004]
    assert any("repeats the joint, dropped" in n for n in track.notes)


def test_routes_are_read_when_there_are_no_tracks(tmp_path: Path) -> None:
    path = write(tmp_path, "route.gpx", gpx("<rte>" + pt(46, 14, "rtept") + pt(46.001, 14.001, "rtept") + "</rte>"))
    track = read_track(path)
    assert track.x.tolist() == [14, 14.001] and track.z_m is None


def test_partial_elevations_give_no_z_with_a_note(tmp_path: Path) -> None:
    path = write(tmp_path, "ele.gpx", gpx("<trk><trkseg>" + pt(46, 14, ele=5) + pt(46.001, 14) + "</trkseg></trk>"))
    track = read_track(path)
    assert track.z_m is None and any("1 of 2 points have no elevation" in n for n in track.notes)


def test_standing_still_is_dropped_but_an_untimed_repeat_is_refused(tmp_path: Path) -> None:
    times = ["2020-01-01T00:00:00Z", "2020-01-01T00:00:05Z", "2020-01-01T00:00:09Z"]
    body = pt(46, 14, time=times[0]) + pt(46, 14, time=times[1]) + pt(46.001, 14, time=times[2])
    track = read_track(write(tmp_path, "stop.gpx", gpx(f"<trk><trkseg>{body}</trkseg></trk>")))
    assert len(track) == 2 and any("dropped 1 repeated point" in n for n in track.notes)
    body = pt(46, 14, time=times[0]) + pt(46, 14, time=times[0]) + pt(46.001, 14)
    path = write(tmp_path, "dup.gpx", gpx(f"<trk><trkseg>{body}</trkseg></trk>"))
    with pytest.raises(InputError) as raised:
        read_track(path)
    one_line(raised, str(path), "track 0 segment 0 point 1", "repeats the previous point", "remove the duplicate")


@pytest.mark.parametrize("body, words", [
    ("<trk><trkseg></trkseg></trk>", ["no track or route points", "<trkpt>"]),
    ("<trk><trkseg>" + pt(46, 14) + "</trkseg></trk>", ["1 point", "at least 2"]),
    ("<trk><trkseg>" + pt(46, 14) + pt(95, 14) + "</trkseg></trk>", ["point 1", "latitude 95", "out of range"]),
    ("<trk><trkseg>" + pt(46, 14) + pt(46, 190) + "</trkseg></trk>", ["point 1", "longitude 190"]),
    ("<trk><trkseg>" + pt(46, 14) + pt(float("nan"), 14) + "</trkseg></trk>", ["point 1", "not finite"]),
    ("<trk><trkseg>" + pt(46, 14) + "<trkpt lat='x' lon='1'/></trkseg></trk>", ["not a readable GPX"]),
    ("<trk><trkseg>", ["not a readable GPX"]),
])
def test_bad_gpx_is_one_line(tmp_path: Path, body: str, words: list[str]) -> None:
    path = write(tmp_path, "bad.gpx", gpx(body))
    with pytest.raises(InputError) as raised:
        read_track(path)
    one_line(raised, str(path), *words)


def test_gpx_refuses_a_track_crs_and_unknown_endings(tmp_path: Path) -> None:
    with pytest.raises(InputError) as raised:
        read_track(GPX_DIR / "Mojstrovka.gpx", track_crs="EPSG:32633")
    one_line(raised, "WGS 84", "drop --track-crs")
    with pytest.raises(InputError) as raised:
        read_track(tmp_path / "track.kml")
    one_line(raised, "track.kml", ".gpx, .geojson, .json, .csv")


# -------------------------------------------------------------------------- GeoJSON


LINE = {"type": "LineString", "coordinates": [[14.0, 46.0, 300.0], [14.001, 46.0, 301.5], [14.002, 46.001, 302.0]]}


@pytest.mark.parametrize("document", [
    LINE,
    {"type": "Feature", "properties": {}, "geometry": LINE},
    {"type": "FeatureCollection", "features": [
        {"type": "Feature", "properties": {}, "geometry": {"type": "Point", "coordinates": [14, 46]}},
        {"type": "Feature", "properties": {}, "geometry": LINE}]},
])
def test_geojson_forms(tmp_path: Path, document: dict) -> None:
    track = read_track(write(tmp_path, "t.geojson", json.dumps(document)))
    assert track.x.tolist() == [14.0, 14.001, 14.002] and track.z_m.tolist() == [300.0, 301.5, 302.0]
    assert track.crs.to_epsg() == 4326


def test_geojson_legacy_crs_and_override(tmp_path: Path) -> None:
    document = {"type": "LineString", "crs": {"type": "name", "properties": {"name": "EPSG:32633"}},
                "coordinates": [[400000.0, 5100000.0], [400010.0, 5100000.0]]}
    path = write(tmp_path, "utm.json", json.dumps(document))
    track = read_track(path)
    assert track.crs.to_epsg() == 32633 and track.x.tolist() == [400000.0, 400010.0] and track.z_m is None
    assert read_track(path, track_crs="EPSG:32634").crs.to_epsg() == 32634


@pytest.mark.parametrize("text, words", [
    (json.dumps({"type": "MultiLineString", "coordinates": [[[14, 46], [14, 46.1]]]}), ["MultiLineString", "join"]),
    (json.dumps({"type": "FeatureCollection", "features": [{"type": "Feature", "geometry": LINE}] * 2}),
     ["2 LineStrings", "exactly one"]),
    ('{"type": "LineString", "coordinates": [[14, 46], [14, NaN]]}', ["coordinate 1", "not finite"]),
    ('{"type": "LineString", "coordinates": [[14, 46], [14, "x"]]}', ["coordinate 1", "not a position"]),
    ('{"type": "LineString", "coordinates": [[14, 46], [14, 46]]}', ["coordinate 1", "repeats the previous point"]),
    ('{"type": "LineString", "coordinates": [[14, 46],', ["line 1", "not valid JSON"]),
    ('{"type": "LineString", "crs": {"type": "name", "properties": {"name": "EPSG:99999"}}, '
     '"coordinates": [[1, 2], [3, 4]]}', ["'EPSG:99999' is not a CRS pyproj knows", "EPSG:32633"]),
])
def test_bad_geojson_is_one_line(tmp_path: Path, text: str, words: list[str]) -> None:
    path = write(tmp_path, "bad.geojson", text)
    with pytest.raises(InputError) as raised:
        read_track(path)
    one_line(raised, str(path), *words)


# ------------------------------------------------------------------------------ CSV


def test_csv_with_and_without_a_crs(tmp_path: Path) -> None:
    path = write(tmp_path, "t.csv", "# surveyed\nx,y,z\n400000,5100000,10\n400003,5100004,11\n")
    plain = read_track(path)
    assert plain.crs is None and plain.x.tolist() == [400000, 400003] and plain.z_m.tolist() == [10, 11]
    utm = pyproj.CRS("EPSG:32633")
    same = project_track(plain, utm)  # no CRS: taken to be in the target's, in metres
    assert same.x.tolist() == plain.x.tolist() and same.crs == utm and "taken to be in EPSG:32633" in same.notes[-1]
    stated = read_track(path, track_crs="EPSG:32633")
    assert stated.crs.to_epsg() == 32633
    with pytest.raises(InputError) as raised:
        local_projected_crs(plain)
    one_line(raised, "states no CRS", "--track-crs")


def test_csv_in_us_survey_feet_becomes_metres(tmp_path: Path) -> None:
    path = write(tmp_path, "ft.csv", "x,y\n1000,2000\n1010,2000\n")
    track = read_track(path, track_crs="EPSG:2903")  # NAD83(HARN) / New Mexico Central (ftUS)
    np.testing.assert_allclose(track.x, [1000 * US_FOOT_M, 1010 * US_FOOT_M], rtol=1e-12)
    with pytest.raises(InputError) as raised:
        read_track(write(tmp_path, "ftm.csv", "x_m,y_m\n1000,2000\n1010,2000\n"), track_crs="EPSG:2903")
    one_line(raised, "x_m,y_m say metres", "rename them x,y")


@pytest.mark.parametrize("text, crs, words", [
    ("x,y\n1,2\n1,2\n", None, ["line 3", "repeats the previous point"]),
    ("x,y\n1,2\n", None, ["1 point", "at least 2"]),
    ("x,y\n1,2\n3,inf\n", None, ["line 3", "not a finite number"]),
    ("a,b\n1,2\n3,4\n", None, ["lacks the columns", "x,y"]),
    ("x,y\n14,46\n14,95\n", "EPSG:4326", ["line 3", "latitude 95", "out of range"]),
    ("x,y\n1,2\n3,4\n", "EPSG:nonsense", ["not a CRS pyproj knows", "give e.g. EPSG:32633"]),
])
def test_bad_csv_is_one_line(tmp_path: Path, text: str, crs: str | None, words: list[str]) -> None:
    path = write(tmp_path, "bad.csv", text)
    with pytest.raises(InputError) as raised:
        read_track(path, track_crs=crs)
    one_line(raised, str(path), *words)


def test_projection_targets_must_be_in_metres_and_utm_south() -> None:
    track = read_track(GPX_DIR / "Mojstrovka.gpx")
    with pytest.raises(InputError) as raised:
        project_track(track, pyproj.CRS("EPSG:4326"))
    one_line(raised, "geographic", "metres are needed", "EPSG:32633")
    south = type(track)(x=np.array([-70.6, -70.5]), y=np.array([-33.4, -33.5]), z_m=None, crs=track.crs, source="t")
    assert local_projected_crs(south).to_epsg() == 32719  # Santiago de Chile: zone 19 south


# ------------------------------------------------------------------------- LAS / LAZ


def write_laz(path: Path, n: int = 2000, classes: np.ndarray | None = None, crs: str | None = "EPSG:32633"):
    rng = np.random.default_rng(7)
    las = laspy.create(point_format=3, file_version="1.2")
    las.header.scales = [0.001, 0.001, 0.001]
    las.header.offsets = [400000.0, 5100000.0, 0.0]
    if crs is not None:
        las.header.add_crs(pyproj.CRS(crs))
    xyz = np.column_stack([400000 + rng.uniform(0, 50, n), 5100000 + rng.uniform(0, 50, n), rng.uniform(0, 5, n)])
    xyz = np.round(xyz, 3)
    las.x, las.y, las.z = xyz.T
    las.classification = classes if classes is not None else rng.choice([1, 2, 5], n).astype(np.uint8)
    las.write(path)
    return xyz, np.asarray(las.classification)


def test_laz_round_trip(tmp_path: Path) -> None:
    path = tmp_path / "cloud.laz"
    xyz, classes = write_laz(path)
    assert path.read_bytes()[104] & 0x80  # compressed: the LAZ bit of the point format byte
    cloud = read_las(path)
    np.testing.assert_allclose(cloud.xyz_m(), xyz, atol=1e-6)
    assert cloud.classification.tolist() == classes.tolist() and cloud.is_classified
    assert cloud.crs.to_epsg() == 32633 and cloud.header.horizontal_unit_m == 1.0
    unclassified = tmp_path / "raw.laz"
    write_laz(unclassified, classes=np.ones(2000, dtype=np.uint8))
    assert not read_las(unclassified).is_classified


def test_truncated_laz_is_one_line(tmp_path: Path) -> None:
    path = tmp_path / "cloud.laz"
    write_laz(path)
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])
    with pytest.raises(InputError) as raised:
        read_las(path)
    one_line(raised, str(path), "cannot be decoded after", "the file is cut short or its compressed data are damaged")
    assert "download it again" not in str(raised.value)  # the file is damaged: say what is wrong (issue 30)


def test_read_terrain_supplies_the_crs_and_its_units(tmp_path: Path) -> None:
    path = tmp_path / "nocrs.laz"
    xyz, _ = write_laz(path, crs=None)
    with pytest.raises(InputError, match="give its CRS with terrain_crs"):  # the fix read_terrain can take
        read_terrain(path)
    cloud = read_terrain(path, terrain_crs="EPSG:2903")
    assert isinstance(cloud, PointCloud) and cloud.crs.to_epsg() == 2903
    np.testing.assert_allclose(cloud.xyz_m(), xyz * US_FOOT_M, rtol=1e-12)
    with pytest.raises(InputError) as raised:
        read_terrain(path, terrain_crs="EPSG:4326")
    one_line(raised, "geographic", "metres are needed")


def test_real_las_through_read_terrain() -> None:
    cloud = read_terrain(REAL_DATA / "pdal-lidar" / "hexbin-crop.las")
    assert cloud.crs.to_epsg() == 32642 and cloud.is_classified and len(cloud) == 38367
    feet = read_terrain(REAL_DATA / "pdal-lidar" / "4_6_crop.las")
    assert feet.crs.to_epsg() == 2903 and feet.header.horizontal_unit_m == US_FOOT_M


# --------------------------------------------------------------------------- GeoTIFF


def plane(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    return 200.0 + 0.03 * (x - 400000.0) - 0.02 * (y - 5100000.0)


def write_tif(path: Path, crs: str | None, *, unit_m: float = 1.0, rotated: bool = False, nodata_cell=(2, 3)):
    """A 6 x 8 raster of 2 m cells (in the CRS's unit) whose value at each cell centre is
    ``plane`` there (metres); cell ``nodata_cell`` holds the nodata value."""
    from rasterio.transform import Affine

    left, top, size = 400000.0 / unit_m, 5100100.0 / unit_m, 2.0
    transform = Affine(size, 0.1 if rotated else 0.0, left, 0.0, -size, top)
    rows, cols = np.mgrid[0:6, 0:8]
    z = plane((left + (cols + 0.5) * size) * unit_m, (top - (rows + 0.5) * size) * unit_m).astype(np.float32)
    z[nodata_cell] = -9999.0
    with rasterio.open(path, "w", driver="GTiff", height=6, width=8, count=1, dtype="float32", crs=crs,
                       transform=transform, nodata=-9999.0) as out:
        out.write(z, 1)


def test_geotiff_plane_is_interpolated_exactly(tmp_path: Path) -> None:
    path = tmp_path / "dem.tif"
    write_tif(path, "EPSG:32633")
    grid = read_terrain(path)
    assert isinstance(grid, ElevationGrid) and grid.crs.to_epsg() == 32633 and grid.cell_size_m == (2.0, 2.0)
    assert grid.transform == (400001.0, 2.0, 5100099.0, -2.0)
    assert grid.extent_m() == (400001.0, 400015.0, 5100089.0, 5100099.0)
    x = np.array([400001.0, 400014.3, 400009.9, 400015.0])
    y = np.array([5100099.0, 5100097.7, 5100089.2, 5100089.0])
    np.testing.assert_allclose(grid.elevation_at(x, y), plane(x, y), atol=2e-4)  # float32 cells
    # outside the cell centres, and beside the nodata cell (row 2, col 3: centre 400007, 5100095)
    # whose neighbours stay exact
    assert np.isnan(grid.elevation_at(np.array([400000.5, 400008.5, 400007.1]),
                                      np.array([5100095.0, 5100094.0, 5100095.0]))).all()
    x, y = np.array([400010.0, 400005.0]), np.array([5100095.0, 5100093.0])
    np.testing.assert_allclose(grid.elevation_at(x, y), plane(x, y), atol=2e-4)
    assert np.isnan(grid.z_m[2, 3]) and np.isfinite(grid.z_m).sum() == 47


def test_geotiff_in_feet_gives_metres(tmp_path: Path) -> None:
    path = tmp_path / "ft.tif"
    write_tif(path, "EPSG:2903", unit_m=US_FOOT_M)
    grid = read_geotiff(path)
    assert grid.cell_size_m == pytest.approx((2 * US_FOOT_M, 2 * US_FOOT_M), rel=1e-12)
    x, y = np.array([400000.0 + 3.0]), np.array([5100100.0 - 2.0])
    np.testing.assert_allclose(grid.elevation_at(x, y), plane(x, y), atol=2e-4)


def test_bad_geotiffs_are_one_line(tmp_path: Path) -> None:
    path = tmp_path / "nocrs.tif"
    write_tif(path, None)
    with pytest.raises(InputError) as raised:
        read_geotiff(path)
    one_line(raised, str(path), "states no CRS; pass --terrain-crs (e.g. EPSG:32633)")
    assert read_geotiff(path, terrain_crs="EPSG:32633").crs.to_epsg() == 32633
    rotated = tmp_path / "rot.tif"
    write_tif(rotated, "EPSG:32633", rotated=True)
    with pytest.raises(InputError) as raised:
        read_geotiff(rotated)
    one_line(raised, "rotated or sheared", "gdalwarp")
    geographic = tmp_path / "geo.tif"
    write_tif(geographic, "EPSG:4326")
    with pytest.raises(InputError) as raised:
        read_geotiff(geographic)
    one_line(raised, "geographic", "metres are needed")
    broken = tmp_path / "broken.tif"
    broken.write_bytes(b"II*\x00garbage")
    with pytest.raises(InputError) as raised:
        read_geotiff(broken)
    one_line(raised, "not a readable GeoTIFF")
    with pytest.raises(InputError) as raised:
        read_terrain(tmp_path / "dem.asc")
    one_line(raised, ".las, .laz, .tif, .tiff, .crg")


# --------------------------------------------------------------------------- OpenCRG


def write_crg(path: Path, z: np.ndarray, *, step_u: float = 0.5, keys: str = "", v_lines: list[str] | None = None,
              v_keys: str = "long_section_v_right = -1.0\nlong_section_v_left = 1.0\nlong_section_v_increment = 1.0\n"):
    nu, nv = z.shape
    lines = v_lines if v_lines is not None else [f"D:long section {k + 1},m" for k in range(nv)]
    header = ("test surface\n$ROAD_CRG\nreference_line_start_u = 0.0\n"
              f"reference_line_end_u = {(nu - 1) * step_u}\nreference_line_increment = {step_u}\n{v_keys}{keys}"
              "$KD_DEFINITION\n#:KRBI\n" + "\n".join(lines) + "\n" + "$" * 72 + "\n")
    data = z.astype(">f4").tobytes()
    data += struct.pack(">f", float("nan")) * ((-len(data) // 4) % 20)  # NaN to whole 80-byte records
    path.write_bytes(header.encode() + data)


def surface_plane(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    return 1.0 + 0.1 * u - 0.25 * v


def test_crg_surface_on_a_rotated_reference_line(tmp_path: Path) -> None:
    u, v = np.arange(0, 10.5, 0.5), np.array([-1.0, 0.0, 1.0])
    phi = math.radians(30)
    path = tmp_path / "s.crg"
    write_crg(path, surface_plane(u[:, None], v[None, :]),
              keys=f"reference_line_start_x = 100\nreference_line_start_y = 50\nreference_line_start_phi = {phi}\n"
                   f"reference_line_end_phi = {phi}\n")
    surface = read_terrain(path)
    assert isinstance(surface, CrgSurface) and surface.crs is None
    assert surface.v_m.tolist() == [-1.0, 0.0, 1.0]
    # a point at (u, v) lies at (100, 50) + u (cos phi, sin phi) + v (-sin phi, cos phi)
    uu, vv = np.array([0.0, 3.3, 10.0, 7.7]), np.array([0.0, 0.4, 1.0, -0.9])
    x = 100 + uu * math.cos(phi) - vv * math.sin(phi)
    y = 50 + uu * math.sin(phi) + vv * math.cos(phi)
    np.testing.assert_allclose(surface.elevation_at(x, y), surface_plane(uu, vv), atol=1e-6)
    outside_x = 100 + np.array([10.2, 5.0]) * math.cos(phi) - np.array([0, 1.2]) * math.sin(phi)
    outside_y = 50 + np.array([10.2, 5.0]) * math.sin(phi) + np.array([0, 1.2]) * math.cos(phi)
    assert np.isnan(surface.elevation_at(outside_x, outside_y)).all()
    xmin, xmax, ymin, ymax = surface.extent_m()
    assert xmin == pytest.approx(100 - math.sin(phi)) and xmax == pytest.approx(100 + 10 * math.cos(phi) + math.sin(phi))


def test_crg_surface_positions_from_d_lines(tmp_path: Path) -> None:
    path = tmp_path / "v.crg"
    write_crg(path, surface_plane(np.arange(5)[:, None] * 0.5, np.array([[-2.0, 0.5]])), v_keys="",
              v_lines=["D:long section at v = -2.000,m", "D:long section at v = 0.500,m"])
    surface = read_crg_surface(path, terrain_crs="EPSG:32633")
    assert surface.v_m.tolist() == [-2.0, 0.5] and surface.crs.to_epsg() == 32633
    assert surface.elevation_at(np.array([1.0]), np.array([-1.0]))[0] == pytest.approx(surface_plane(1.0, -1.0))


@pytest.mark.parametrize("options, words", [
    ({"keys": "reference_line_start_phi = 0\nreference_line_end_phi = 0.1\n"}, ["curved", "differ"]),
    ({"v_lines": ["D:reference line phi,rad", "D:long section 1,m", "D:long section 2,m"]}, ["curved", "phi"]),
    ({"v_keys": ""}, ["no lateral positions", "long_section_v_right"]),
    ({"v_keys": "long_section_v_right = -1\nlong_section_v_left = 3\nlong_section_v_increment = 1\n"},
     ["long_section_v_left = 3", "fix the header"]),
])
def test_bad_crg_surfaces_are_one_line(tmp_path: Path, options: dict, words: list[str]) -> None:
    path = tmp_path / "bad.crg"
    write_crg(path, np.zeros((5, 3)), **options)
    with pytest.raises(InputError) as raised:
        read_crg_surface(path)
    one_line(raised, str(path), *words)


@pytest.mark.parametrize("path", KRC, ids=[p.name for p in KRC])
def test_krc_surface_centre_track_is_read_opencrgs_profile(path: Path) -> None:
    surface = read_crg_surface(path)
    profile = read_opencrg(path)
    assert surface.v_m.tolist() == [-3.0, 0.0, 3.0] and surface.z_m.shape == (10096, 3)
    np.testing.assert_array_equal(surface.elevation_at(profile.s_m, np.zeros_like(profile.s_m)), profile.z_m)
    assert surface.extent_m() == (0.0, 504.75, -3.0, 3.0)


# ------------------------------------------------------------------ the geo extra


@pytest.mark.parametrize("module, call", [
    ("laspy", lambda: read_las(REAL_DATA / "pdal-lidar" / "hexbin-crop.las")),
    ("rasterio", lambda: read_geotiff(ROOT / "nowhere.tif")),
    ("gpxpy", lambda: read_track(GPX_DIR / "Mojstrovka.gpx")),
    ("pyproj", lambda: read_track(GPX_DIR / "Mojstrovka.gpx")),
])
def test_missing_geo_package_is_one_line(monkeypatch: pytest.MonkeyPatch, module: str, call) -> None:
    monkeypatch.setitem(sys.modules, module, None)  # import raises ImportError
    with pytest.raises(InputError) as raised:
        call()
    one_line(raised, "needs the geo extra", "pip install 'profileopt[geo]'", module)


def test_importing_the_readers_imports_no_geo_package() -> None:
    probe = ("import sys, profileopt, profileopt.io\nfrom profileopt.io import tracks, terrain_maps, las, geo\n"
             "print(sorted(m for m in ('laspy', 'rasterio', 'pyproj', 'gpxpy', 'lazrs') if m in sys.modules))")
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=60, cwd=ROOT)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[]"


# ------------------------------------------------------------------------ GPS noise


def noisy_circle_gpx(path: Path, sigma_m: float, seed: int = 5) -> tuple[np.ndarray, np.ndarray]:
    """A GPX of 300 points 3 m apart on a 60 m circle in UTM 33N, with Gaussian noise of
    ``sigma_m`` in each coordinate; returns the noisy points in UTM 33N (m)."""
    rng = np.random.default_rng(seed)
    angle = np.arange(300) * 3.0 / 60.0
    x = 430_000.0 + 60.0 * np.sin(angle) + sigma_m * rng.standard_normal(angle.size)
    y = 5_100_000.0 - 60.0 * np.cos(angle) + sigma_m * rng.standard_normal(angle.size)
    lon, lat = pyproj.Transformer.from_crs(32633, 4326, always_xy=True).transform(x, y)
    points = "".join(f'<trkpt lat="{la:.10f}" lon="{lo:.10f}"><ele>100</ele></trkpt>\n' for la, lo in zip(lat, lon))
    path.write_text('<?xml version="1.0"?>\n<gpx version="1.1" creator="test" '
                    f'xmlns="http://www.topografix.com/GPX/1/1"><trk><trkseg>\n{points}</trkseg></trk></gpx>\n')
    return x, y


def test_a_noisy_gps_track_is_moved_onto_its_path_within_the_tolerance(tmp_path: Path) -> None:
    path = tmp_path / "noisy.gpx"
    x, y = noisy_circle_gpx(path, 1.5)
    track = read_track(path)
    done = track.smoothing
    # the noise put in, estimated within 15 % (tests/terrain/test_geometry.py for the estimator)
    assert done.smoothed and done.noise.noise_m == pytest.approx(1.5, rel=0.15)
    assert "moved onto the smoothest path" in track.notes[-1]
    moved = project_track(track, pyproj.CRS.from_epsg(32633))
    # each point moved by at most the tolerance (the tangent plane's error over 400 m: < 1 mm)
    distance = np.hypot(moved.x - x, moved.y - y)
    assert distance.max() <= done.tolerance_m + 1e-3
    # towards the circle: the points' distance from the centre strays from 60 m by less than
    # half as much (RMS) as the noisy points' (1.5 m across the path)
    rms = [float(np.sqrt(np.mean((np.hypot(px - 430_000.0, py - 5_100_000.0) - 60.0) ** 2)))
           for px, py in ((moved.x, moved.y), (x, y))]
    assert rms[0] < 0.5 * rms[1]
    given = read_track(path, path_tolerance_m=2.0)
    assert given.smoothing.tolerance_m == 2.0 and given.smoothing.tolerance_source == "given"
    moved = project_track(given, pyproj.CRS.from_epsg(32633))
    assert np.hypot(moved.x - x, moved.y - y).max() <= 2.0 + 1e-3
    raw = read_track(path, smooth=False)  # the file's points as they are
    assert raw.smoothing is None and not any("moved" in note for note in raw.notes)
    # a clean track (10 cm of noise every 3 m lengthens it by 0.1 %) is kept as it is
    noisy_circle_gpx(path, 0.1)
    kept = read_track(path)
    assert not kept.smoothing.smoothed
    np.testing.assert_array_equal(kept.x, read_track(path, smooth=False).x)


# ----------------------------------------- hostile terrain files (issue 30, items 8, 10 and 11)


def test_an_empty_las_or_laz_is_one_line(tmp_path: Path) -> None:
    # laspy writes a cloud without points; a terrain made of it was an internal error (zero-size array)
    for name in ("empty.las", "empty.laz"):
        las = laspy.create(point_format=3, file_version="1.2")
        las.header.add_crs(pyproj.CRS("EPSG:32633"))
        las.write(tmp_path / name)
        with pytest.raises(InputError) as raised:
            read_terrain(tmp_path / name)
        one_line(raised, name, "holds no points (its header counts 0 point records)")


def _cloud_track(tmp_path: Path) -> tuple[Path, object, np.ndarray]:
    """A 2,000-point LAZ (write_laz: x 400000-400050, y 5100000-5100050) and a CSV track
    across it (UTM 33N), straight from (400005, 5100025) to (400045, 5100025)."""
    from profileopt.io import read_track

    path = tmp_path / "cloud.laz"
    xyz, _ = write_laz(path)
    track_path = tmp_path / "track.csv"
    track_path.write_text("x,y\n400005,5100025\n400025,5100025\n400045,5100025\n")
    return path, read_track(track_path, track_crs="EPSG:32633"), xyz


def test_a_cloud_is_read_in_chunks_keeping_the_points_near_the_track(tmp_path: Path, monkeypatch) -> None:
    from profileopt.io import las
    from profileopt.terrain.ground_track import cloud_margin_m

    path, track, xyz = _cloud_track(tmp_path)
    # chunks of 300 points, at most 1,000 held: the 2,000-point cloud is refused whole ...
    monkeypatch.setattr(las, "_CHUNK_POINTS", 300)
    monkeypatch.setattr(las, "MAX_CLOUD_POINTS", 1000)
    with pytest.raises(InputError) as raised:
        read_terrain(path)
    one_line(raised, "holds 2,000 points, more than the 1,000 read at once", "near a track")
    # ... and read near the track: exactly the points within the margin of the segment (distance
    # to a straight segment by hand: across it |y - 5100025|, beyond its ends the distance to the end)
    cloud = read_terrain(path, track=track, spacing_m=0.05, corridor_m=0.15)
    low, high = np.asarray(cloud.header.min_xyz), np.asarray(cloud.header.max_xyz)
    margin = cloud_margin_m(2000 / np.prod((high - low)[:2]), 0.05, 0.15)  # the density over the header's bounds
    assert cloud.kept_within_m == margin
    beyond = np.clip(xyz[:, 0], 400005, 400045)
    distance = np.hypot(xyz[:, 0] - beyond, xyz[:, 1] - 5100025)
    near = distance <= margin
    assert 0 < near.sum() < 1000
    got = cloud.xyz_m()
    # the kept points include every point within the margin, and none beyond margin * 1.04
    # (the nodes every half margin along the track)
    assert {tuple(p) for p in np.round(xyz[near], 3)} <= {tuple(p) for p in np.round(got, 3)}
    assert len(got) <= (distance <= margin * 1.04).sum()
    # the extent is the whole file's, for the check that the track lies on the terrain
    np.testing.assert_allclose(cloud.extent_m(), (xyz[:, 0].min(), xyz[:, 0].max(), xyz[:, 1].min(),
                                                  xyz[:, 1].max()), atol=1e-6)
    # more points near the track than may be held: refused, naming the fix
    monkeypatch.setattr(las, "MAX_CLOUD_POINTS", 50)
    with pytest.raises(InputError) as raised:
        read_terrain(path, track=track)
    one_line(raised, "more than 50 points near the track (of 2,000); thin the cloud")


def test_a_geotiff_band_scale_of_zero_is_refused(tmp_path: Path) -> None:
    # band scale 0 made every elevation the offset: flat 0 m terrain, exit 0 (issue 30, item 8)
    path = tmp_path / "dem.tif"
    write_tif(path, "EPSG:32633")
    for scale in (0.0, 1e-300, float("nan")):
        with rasterio.open(path, "r+") as dataset:
            dataset.scales = (scale,)
        with pytest.raises(InputError) as raised:
            read_geotiff(path)
        one_line(raised, str(path), f"band 1's scale {scale:g} and offset 0", "metadata are wrong")
    with rasterio.open(path, "r+") as dataset:  # a real scale is applied (decimetres in the file)
        dataset.scales = (0.1,)
    x, y = np.array([400003.0]), np.array([5100097.0])
    assert read_geotiff(path).elevation_at(x, y)[0] == pytest.approx(0.1 * plane(x, y)[0], abs=2e-5)


def test_a_50000_by_50000_geotiff_is_read_in_the_window_around_the_track(tmp_path: Path) -> None:
    # 2.5e9 cells claimed (9.3 GiB of float32) in a sparse file of a few MB: reading it whole was a
    # MemoryError; only the window around the track is read
    from geo_data import surface_m, track_utm_m, write_gpx, write_sparse_geotiff

    from profileopt.io import read_track
    from profileopt.io.terrain_maps import MAX_GRID_CELLS
    from profileopt.terrain.ground_track import route_from_track

    path = write_sparse_geotiff(tmp_path / "big.tif")
    assert path.stat().st_size < 20e6
    with pytest.raises(InputError) as raised:
        read_terrain(path)
    one_line(raised, "50,000 x 50,000 cells to read, more than the 25,000,000", "window around a track")
    track = read_track(write_gpx(tmp_path / "t.gpx", *track_utm_m(2.0)))
    grid = read_terrain(path, track=track)
    assert grid.z_m.size < MAX_GRID_CELLS / 10
    assert grid.file_extent_m == pytest.approx((429000.025, 431499.975, 5098500.025, 5100999.975))
    result = route_from_track(track, grid)
    truth = surface_m(result.route.x_m, result.route.y_m)
    assert np.max(np.abs(result.route.z_m - truth)) < 2e-3  # float32 cells, bilinear over 5 cm
    assert result.roughness_measured


def test_a_window_read_agrees_with_the_whole_raster(tmp_path: Path) -> None:
    # the window's cells are the raster's own: same elevation at every sample
    from profileopt.io import read_track

    path = tmp_path / "dem.tif"
    write_tif(path, "EPSG:32633", nodata_cell=(5, 7))
    track_path = tmp_path / "t.csv"
    track_path.write_text("x,y\n400003,5100097\n400006,5100096\n")
    whole = read_terrain(path)
    part = read_terrain(path, track=read_track(track_path, track_crs="EPSG:32633"))
    assert part.file_extent_m == whole.extent_m()
    x, y = np.linspace(400003, 400006, 7), np.linspace(5100097, 5100096, 7)
    np.testing.assert_array_equal(part.elevation_at(x, y), whole.elevation_at(x, y))


@pytest.mark.parametrize("options, words", [
    ({"v_keys": "", "v_lines": ["D:long section at v = -,m", "D:long section at v = 1.0,m", "D:long section at v = 2,m"]},
     ["'D:long section at v = -' does not state a lateral position"]),
    ({"v_keys": "", "v_lines": ["D:long section at v = nan,m", "D:long section at v = 1.0,m",
                                "D:long section at v = 2,m"]}, ["'D:long section at v = nan'"]),
])
def test_bad_crg_lateral_positions_are_one_line(tmp_path: Path, options: dict, words: list[str]) -> None:
    path = tmp_path / "bad.crg"
    write_crg(path, np.zeros((5, 3)), **options)
    with pytest.raises(InputError) as raised:
        read_crg_surface(path)
    one_line(raised, str(path), *words)


def test_a_crg_end_of_1e308_is_one_line(tmp_path: Path) -> None:
    # (end - start) / increment overflowed to inf, then int(inf): OverflowError (exit 1)
    path = tmp_path / "far.crg"
    write_crg(path, np.zeros((5, 3)))
    path.write_bytes(path.read_bytes().replace(b"reference_line_end_u = 2.0", b"reference_line_end_u = 1e308"))
    for read in (read_crg_surface, read_opencrg):
        with pytest.raises(InputError) as raised:
            read(path)
        one_line(raised, str(path), "reference_line_end_u = 1e+308", "more than 1e308 rows",
                 "enough for 6 rows; the file is truncated or these keys are wrong")  # 80 bytes (padded) / 12


@pytest.mark.parametrize("text", ["+proj=longlat +R=1", "+proj=utm +zone=33 +a=3396190 +b=3376200"])
def test_a_crs_off_the_earth_is_one_line(tmp_path: Path, text: str) -> None:
    # pyproj refuses to transform between bodies (ProjError, exit 1): refused where the CRS is read
    from profileopt.cli import main
    from profileopt.io.geo import parse_crs

    with pytest.raises(InputError) as raised:
        parse_crs(text, "t.csv", "--track-crs")
    one_line(raised, "t.csv: --track-crs", "not on the Earth", "EPSG:32633")
    track = tmp_path / "t.csv"
    track.write_text("x,y\n14.1,46.0\n14.1005,46.0005\n14.101,46.001\n")
    dem = tmp_path / "dem.tif"
    write_tif(dem, "EPSG:32633")
    assert main(["route", str(track), "--track-crs", text, "--terrain", str(dem), "-o", str(tmp_path / "r.csv")]) == 2
    assert not (tmp_path / "r.csv").exists()


@pytest.mark.slow
def test_a_laz_bomb_is_read_in_bounded_memory(tmp_path: Path, monkeypatch) -> None:
    # 3 million identical points compress to a few kB (60 million made a 600 kB LAZ that peaked
    # at 3.2 GB): read in chunks of 100,000 near a track that passes 400 m away, the numpy arrays
    # held at once stay below 40 MB, where reading them whole takes 3e6 x (30-byte record + 25 bytes
    # of x, y, z, class) = 165 MB
    import tracemalloc

    from profileopt.io import las

    n = 3_000_000
    header = laspy.LasHeader(point_format=6, version="1.4")
    header.offsets, header.scales = [400000.0, 5100000.0, 0.0], [0.001, 0.001, 0.001]
    header.add_crs(pyproj.CRS("EPSG:32633"))
    path = tmp_path / "bomb.laz"
    with laspy.open(path, mode="w", header=header) as writer:
        points = laspy.ScaleAwarePointRecord.zeros(n, header=header)
        points.x[:], points.y[:], points.z[:], points.classification[:] = 400500.0, 5100025.0, 300.0, 2
        writer.write_points(points)
    del points
    assert path.stat().st_size < 100_000
    track_path = tmp_path / "track.csv"
    track_path.write_text("x,y\n400005,5100025\n400045,5100025\n")
    track = read_track(track_path, track_crs="EPSG:32633")
    monkeypatch.setattr(las, "_CHUNK_POINTS", 100_000)
    tracemalloc.start()
    try:
        cloud = read_terrain(path, track=track)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert len(cloud) == 0 and cloud.extent_m() == pytest.approx((400500.0, 400500.0, 5100025.0, 5100025.0))
    assert peak < 40e6


@pytest.mark.parametrize("unit, words", [("1e-300", "not length units (they lie between 1e-06 and 100000 m)"),
                                         ("0", "not length units"), ("-1", "not length units"),
                                         ("nan", "is not a CRS pyproj knows")])  # pyproj refuses NaN itself
def test_a_geotiff_whose_crs_unit_is_no_length_is_one_line(tmp_path: Path, unit: str, words: str) -> None:
    # a CRS unit of 1e-300 m (or 0, negative, NaN: in the file's GeoKeys or given) shrank the raster to a point
    wkt = ('PROJCS["p",GEOGCS["g",DATUM["d",SPHEROID["s",6378137,298.257]],PRIMEM["G",0],UNIT["degree",'
           f'0.0174532925199433]],PROJECTION["Transverse_Mercator"],UNIT["odd",{unit}]]')
    path = tmp_path / "dem.tif"
    write_tif(path, "EPSG:32633")
    with pytest.raises(InputError) as raised:
        read_terrain(path, terrain_crs=wkt)
    one_line(raised, str(path), words)


def write_tif_with_nan_unit(path: Path) -> Path:
    """A GeoTIFF whose CRS's linear unit (a GeoKey ProjLinearUnitSize) is NaN: written with a
    unit of 0.4321 m, whose double is then overwritten with NaN in the file's bytes."""
    wkt = ('PROJCS["UTM33 custom",GEOGCS["WGS 84",DATUM["WGS_1984",SPHEROID["WGS 84",6378137,298.257223563]],'
           'PRIMEM["Greenwich",0],UNIT["degree",0.0174532925199433]],PROJECTION["Transverse_Mercator"],'
           'PARAMETER["latitude_of_origin",0],PARAMETER["central_meridian",15],PARAMETER["scale_factor",0.9996],'
           'PARAMETER["false_easting",500000],PARAMETER["false_northing",0],UNIT["odd",0.4321],'
           'AXIS["Easting",EAST],AXIS["Northing",NORTH]]')
    write_tif(path, wkt)
    data = path.read_bytes()
    unit = struct.pack("<d", 0.4321)
    assert data.count(unit) == 1
    path.write_bytes(data.replace(unit, struct.pack("<d", float("nan"))))
    return path


def test_a_geotiff_whose_geokey_unit_is_nan_is_one_line(tmp_path: Path) -> None:
    # issue 30, second round: rasterio's CRSError (not a RasterioError) as the file was opened was
    # an internal error, with --terrain-crs too
    from profileopt.io.tiles import read_tiles

    path = write_tif_with_nan_unit(tmp_path / "nan.tif")
    for terrain_crs in (None, "EPSG:32633"):
        with pytest.raises(InputError) as raised:
            read_terrain(path, terrain_crs=terrain_crs)
        text = one_line(raised, str(path), "its CRS (GeoTIFF GeoKeys or WKT) cannot be read", "gdal_edit.py -a_srs")
        assert ("--terrain-crs EPSG:32633 cannot stand in for it" in text) == (terrain_crs is not None)
    other = tmp_path / "ok.tif"
    write_tif(other, "EPSG:32633")
    with pytest.raises(InputError) as raised:  # among tiles: read from its header
        read_tiles([other, path])
    one_line(raised, str(path), "cannot be read")
