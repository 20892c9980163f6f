"""profileopt.io.tracks on hostile and misleading tracks (issue 30 items 8, 9, 11).

Reference values: track lengths by a spherical haversine (an independent formula; within
0.5 % of the WGS 84 geodesic) and by hand (a 3-4-5 triangle); the route-sample cap as
the largest route file's memory (50 MB x 20 bytes per byte, the figures of
profileopt.io.inputs) over 1.1 kB per sample, written out.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from profileopt.errors import InputError
from profileopt.io import inputs, read_track
from profileopt.io.tracks import (DEGREES_EXTENT, Track, check_not_degrees, check_track_samples, degrees_like_extent,
                                  track_length_m)

pytestmark = pytest.mark.geo
pytest.importorskip("gpxpy")
pyproj = pytest.importorskip("pyproj")

GPX_HEAD = '<?xml version="1.0"?><gpx version="1.1" creator="t" xmlns="http://www.topografix.com/GPX/1/1">'


def haversine_m(lon: list[float], lat: list[float], radius_m: float = 6_371_008.8) -> float:
    """Length (m) of a polyline of lon, lat points on a sphere of the Earth's mean radius."""
    total = 0.0
    for i in range(len(lon) - 1):
        p1, p2 = math.radians(lat[i]), math.radians(lat[i + 1])
        dp, dl = p2 - p1, math.radians(lon[i + 1] - lon[i])
        h = math.sin(dp / 2) ** 2 + math.cos(p1) * math.cos(p2) * math.sin(dl / 2) ** 2
        total += 2 * radius_m * math.asin(math.sqrt(h))
    return total


def gpx_file(path: Path, points: list[tuple[float, float]], extra: str = "") -> Path:
    body = "".join(f'<trkpt lat="{lat}" lon="{lon}"><ele>100</ele></trkpt>' for lon, lat in points)
    path.write_text(f"{GPX_HEAD}<trk><trkseg>{body}</trkseg></trk>{extra}</gpx>")
    return path


# ------------------------------------------------------------------ item 9: the sample cap

LONG = [(10.0, 45.0), (12.0, 47.0), (14.0, 49.0)]  # about 540 km in a file of a few hundred bytes


def test_the_route_sample_cap_is_the_largest_route_files_rows() -> None:
    assert inputs.max_route_samples() == 50_000_000 * 20 // 1_100 == 909_090


def test_a_short_file_spanning_500_km_is_refused_before_sampling(tmp_path: Path) -> None:
    # before: 1e7 samples at 0.05 m, then MemoryError after 4 minutes at 3.3 GB
    track = read_track(gpx_file(tmp_path / "long.gpx", LONG))
    length = haversine_m(*zip(*LONG))
    assert track_length_m(track) == pytest.approx(length, rel=5e-3)
    with pytest.raises(InputError) as raised:
        check_track_samples(track, 0.05)
    message = str(raised.value)
    assert "\n" not in message
    assert f"{track_length_m(track) / 1000:.4g} km long" in message
    fit = float(message.split("give spacing_m ")[1].split(" ")[0])
    # the spacing named is the smallest of two significant digits that fits the cap
    cap = 909_090
    assert length / fit + 1 <= cap * 1.005 and length / (fit - 0.01) + 1 > cap * 0.995
    check_track_samples(track, fit)  # fits
    check_track_samples(track, math.nan)  # a bad spacing is the sampler's to refuse


def test_the_sample_cap_follows_a_raised_file_cap(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    track = read_track(gpx_file(tmp_path / "long.gpx", LONG))
    monkeypatch.setattr(inputs, "MAX_TABLE_BYTES", 1_000_000_000)  # room for 18 million samples
    check_track_samples(track, 0.05)


def test_a_projected_track_is_measured_in_the_plane() -> None:
    track = Track(x=np.array([0.0, 3.0, 3.0]), y=np.array([0.0, 4.0, 0.0]), z_m=None, crs=None, source="t.csv")
    assert track_length_m(track) == 9.0


# ------------------------------------------------------------ item 8: degrees taken as metres

def test_degrees_without_a_crs_are_recognised() -> None:
    lon = np.array([14.5, 14.501, 14.502])
    lat = np.array([46.0, 46.0002, 46.0004])
    assert degrees_like_extent(lon, lat) == pytest.approx(math.hypot(0.002, 0.0004))
    assert degrees_like_extent(lon + 400_000, lat) is None  # UTM eastings
    assert degrees_like_extent(np.array([0.0, 150.0]), np.array([0.0, 80.0])) is None  # a 170 m yard in metres
    assert degrees_like_extent(np.array([0.0, 1.9]), np.array([0.0, 0.0])) == 1.9
    assert degrees_like_extent(np.array([0.0, DEGREES_EXTENT]), np.array([0.0, 0.0])) is None


def test_a_csv_track_in_degrees_without_a_crs_is_refused(tmp_path: Path) -> None:
    # before: planned as a route 4 mm long
    path = tmp_path / "deg.csv"
    path.write_text("x,y,z\n14.5,46.0,300\n14.501,46.0002,301\n14.502,46.0004,302\n14.503,46.0006,303\n")
    track = read_track(path, smooth=False)
    with pytest.raises(InputError, match=r"deg\.csv: states no CRS .* look like longitude, latitude in degrees.*"
                                         r"track_crs EPSG:4326"):
        check_not_degrees(track)
    check_not_degrees(read_track(path, smooth=False, track_crs="EPSG:4326"))  # stated: fine


# -------------------------------------------------------------- item 8: GPX tracks and routes

def test_a_gpx_with_tracks_and_routes_notes_the_routes_it_ignores(tmp_path: Path) -> None:
    # before: the routes were dropped without a word
    route = '<rte><rtept lat="46.1" lon="14.1"/><rtept lat="46.2" lon="14.2"/></rte><rte></rte>'
    path = gpx_file(tmp_path / "both.gpx", [(14.0, 46.0), (14.001, 46.0)], route)
    track = read_track(path)
    assert track.x.tolist() == [14.0, 14.001]
    assert any("ignored 1 route(s) with points (<rte>)" in note for note in track.notes), track.notes
    alone = gpx_file(tmp_path / "alone.gpx", [(14.0, 46.0), (14.001, 46.0)])
    assert not any("route" in note for note in read_track(alone).notes)


# ------------------------------------------ item 8: GPX numbers in ASCII decimal notation only

GPX_POINTS = [(15.0, 45.0 + 1e-5 * k) for k in range(6)]


def _gpx_text(values: dict[int, tuple[str, str, str]], *, routes: bool = False) -> str:
    """A GPX file of six points, one per line (the first on line 3), point k's lat, lon and
    ele as text from ``values`` (else the numbers of GPX_POINTS)."""
    point, outer = ("rtept", ("<rte>", "</rte>")) if routes else ("trkpt", ("<trk><trkseg>", "</trkseg></trk>"))
    lines = []
    for k, (lon, lat) in enumerate(GPX_POINTS):
        lat_text, lon_text, ele = values.get(k, (f"{lat:.6f}", f"{lon:.6f}", "100"))
        lines.append(f'<{point} lat="{lat_text}" lon="{lon_text}"><ele>{ele}</ele></{point}>')
    return f"{GPX_HEAD}\n{outer[0]}\n" + "\n".join(lines) + f"\n{outer[1]}</gpx>\n"


@pytest.mark.parametrize(("values", "words"), [
    ({4: ("45.000040", "15.000000", "1_00")}, "line 7 (track 0 segment 0 point 4): <ele> = '1_00' is not a number"),
    ({4: ("45.000040", "15.000000", "\u0661\u0660\u0660")}, "<ele> = '\\u0661\\u0660\\u0660' is not a number"),
    ({2: ("\uff145.000020", "15.000000", "100")}, "line 5 (track 0 segment 0 point 2): lat = '\\uff145.000020' is"),
    ({2: ("45.000_020", "15.000000", "100")}, "lat = '45.000_020' is not a number"),
    ({5: ("45.000050", "1_5.0", "100")}, "line 8 (track 0 segment 0 point 5): lon = '1_5.0' is not a number"),
], ids=["ele 1_00", "ele Arabic-Indic", "lat full-width", "lat 45.000_020", "lon 1_5.0"])
def test_gpx_numbers_are_ascii_decimals_as_every_number_read(tmp_path: Path, values: dict, words: str) -> None:
    # before: gpxpy's float() read every one of these as a number (exit 0)
    for routes in (False, True):
        path = tmp_path / "t.gpx"
        path.write_text(_gpx_text(values, routes=routes), encoding="utf-8")
        with pytest.raises(InputError) as raised:
            read_track(path)
        message = str(raised.value)
        expected = words.replace("track 0 segment", "route 0 segment") if routes else words
        assert message.startswith(f"{path}: line ") and expected in message and "\n" not in message, message
        assert "ASCII digits 0-9" in message


def test_gpx_numbers_in_ascii_notation_are_read(tmp_path: Path) -> None:
    path = tmp_path / "t.gpx"
    path.write_text(_gpx_text({1: (" 45.000010 ", "+15.0", "\n 1.0e2 \n"), 3: ("45.00003", "15", "-12.5")}))
    track = read_track(path, smooth=False)
    assert track.x.tolist() == [15.0] * 6 and track.z_m.tolist() == [100.0, 100.0, 100.0, -12.5, 100.0, 100.0]


# ------------------------------------------------------------ item 11: GeoJSON that crashed

@pytest.mark.parametrize(("text", "words"), [
    ("[" * 100_000 + "]" * 100_000, ["nested deeper than it can be read"]),  # before: RecursionError
    ('{"type": "LineString", "coordinates": [' + "[" * 900 + "]" * 900 + ", [1, 2]]}",
     ["coordinate 0", "is not a position"]),
    ('{"type": "LineString", "coordinates": [[1' + "0" * 400 + ", 2], [3, 4]]}",  # before: OverflowError
     ["coordinate 0: a number of 401 digits"]),
    ('{"type": "LineString", "coordinates": [[1' + "0" * 5000 + ", 2], [3, 4]]}",  # int_max_str_digits
     ["a number of more than 4,300 digits"]),
], ids=["nested 100000 deep", "a position nested 900 deep", "400 digits", "5000 digits"])
def test_hostile_geojson_is_one_line(tmp_path: Path, text: str, words: list[str]) -> None:
    path = tmp_path / "t.geojson"
    path.write_text(text)
    with pytest.raises(InputError) as raised:
        read_track(path)
    message = str(raised.value)
    assert "\n" not in message and len(message) < 300, message
    for word in words:
        assert word in message, message


def test_a_geojson_with_a_lone_carriage_return_is_read(tmp_path: Path) -> None:
    # in JSON a \r is white space: no line-end question, unlike a CSV
    document = {"type": "LineString", "coordinates": [[14.0, 46.0], [14.001, 46.0]]}
    path = tmp_path / "t.geojson"
    path.write_text(json.dumps(document).replace(", [14.001", ",\r[14.001") + "\n")
    assert read_track(path).x.tolist() == [14.0, 14.001]
