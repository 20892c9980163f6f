"""LAS point clouds (profileopt.io.read_las), the RI of real 3-D terrain patches and
examples/lidar_roughness.py.

Reference values: numbers stated by the data's README (data/README.md: point
counts, 92 % ground, extents in metres), the file size, the ASPRS LAS 1.2/1.4 header layout
(written here independently with ``struct``), and a plane fit with np.linalg.lstsq.
"""

from __future__ import annotations

import math
import struct
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from profileopt import load_vehicle, roughness_index
from profileopt.errors import InputError
from profileopt.io import LAS_GROUND, read_las

from conftest import REAL_DATA, ROOT

EXAMPLE = ROOT / "examples" / "lidar_roughness.py"
LIDAR = REAL_DATA / "pdal-lidar"
HEXBIN = LIDAR / "hexbin-crop.las"
CROP_4_6 = LIDAR / "4_6_crop.las"

US_SURVEY_FOOT_M = 1200.0 / 3937.0  # the US survey foot, exactly (EPSG unit 9003)
H_M = 0.1  # ground clearance of the Table 1 ATV (models/atv.toml)


# --------------------------------------------------------------- the two PDAL LAS files


@pytest.mark.geo
@pytest.mark.parametrize("path, count", [(HEXBIN, 38367), (CROP_4_6, 23875)])  # counts: data README
def test_point_count_matches_header_readme_and_file_size(path: Path, count: int) -> None:
    cloud = read_las(path)
    assert len(cloud) == cloud.header.point_count == count
    assert cloud.z_m.shape == cloud.classification.shape == (count,)
    # The records fill the file from the offset to point data (bytes 96-99) to its end.
    offset = struct.unpack_from("<I", path.read_bytes(), 96)[0]
    assert (path.stat().st_size - offset) == count * cloud.header.record_length_bytes


@pytest.mark.geo
@pytest.mark.parametrize("path", [HEXBIN, CROP_4_6])
def test_coordinate_range_equals_header_bounds(path: Path) -> None:
    cloud = read_las(path)
    low, high = cloud.header.bounds_m
    units = np.array([cloud.header.horizontal_unit_m] * 2 + [cloud.header.vertical_unit_m])
    # Within half an integer step of X, Y, Z (in metres): a header written from the rounded
    # values agrees to rounding, and a reader off by one step fails.
    half_step_m = 0.5 * np.asarray(cloud.header.scale) * units
    for axis, values in enumerate((cloud.x_m, cloud.y_m, cloud.z_m)):
        assert values.min() == pytest.approx(low[axis], abs=half_step_m[axis])
        assert values.max() == pytest.approx(high[axis], abs=half_step_m[axis])


@pytest.mark.geo
def test_hexbin_is_metres_utm_and_92_percent_ground() -> None:
    cloud = read_las(HEXBIN)
    assert cloud.header.version == (1, 2) and cloud.header.point_format == 1
    assert cloud.header.crs == "EPSG:32642"  # WGS 84 / UTM zone 42N
    assert cloud.header.horizontal_unit_m == cloud.header.vertical_unit_m == 1.0
    counts = cloud.class_counts()
    assert set(counts) <= set(range(32))  # format 1 keeps the class in 5 bits
    assert counts[LAS_GROUND] / len(cloud) == pytest.approx(0.92, abs=0.005)  # README: 92 % ground
    # README: 293 x 201 m.
    assert np.ptp(cloud.x_m) == pytest.approx(293, abs=0.5)
    assert np.ptp(cloud.y_m) == pytest.approx(201, abs=0.5)


@pytest.mark.geo
def test_4_6_crop_is_converted_from_us_survey_feet() -> None:
    cloud = read_las(CROP_4_6)
    assert cloud.header.point_format == 3
    assert cloud.header.crs == "EPSG:2903"
    assert cloud.header.horizontal_unit_m == cloud.header.vertical_unit_m == US_SURVEY_FOOT_M
    # README: 61 x 61 m; the header says 199.98 ft (x) and 199.98 ft (y).
    assert np.ptp(cloud.x_m) == pytest.approx(61, abs=0.1)
    assert np.ptp(cloud.y_m) == pytest.approx(61, abs=0.1)
    # z: the header's 7077.92 ft is 2157.35 m (hand: 7077.92 * 1200 / 3937).
    assert cloud.z_m.min() == pytest.approx(7077.92 * 1200 / 3937, abs=1e-6)
    # Forcing metres (units_m) leaves the numbers as stored.
    raw = read_las(CROP_4_6, units_m=1.0)
    np.testing.assert_allclose(raw.z_m * US_SURVEY_FOOT_M, cloud.z_m, rtol=1e-15)
    counts = cloud.class_counts()
    assert 0 < counts[LAS_GROUND] < len(cloud)  # ground under vegetation: both kinds present


def _real_patch() -> np.ndarray:
    """The ground points of a 10 m square in the middle of hexbin-crop.las, shape (M, 3)."""
    ground = read_las(HEXBIN).xyz_m(LAS_GROUND)
    x0, y0 = 393_770.0 + 100.0, 3_689_070.0 + 100.0
    inside = (ground[:, 0] >= x0) & (ground[:, 0] < x0 + 10) & (ground[:, 1] >= y0) & (ground[:, 1] < y0 + 10)
    return ground[inside]


@pytest.mark.geo
def test_ri_of_a_real_patch_against_a_plane_fit() -> None:
    patch = _real_patch()
    assert len(patch) >= 30
    # Independent: least-squares plane z = a + b (x - x0) + c (y - y0) about the first point
    # (shifted so that UTM coordinates lose no digits), RI = STD(residual) / h (Eq. 1).
    x, y, z = patch.T
    design = np.column_stack([np.ones(len(z)), x - x[0], y - y[0]])
    coef, *_ = np.linalg.lstsq(design, z, rcond=None)
    expected = np.std(z - design @ coef) / H_M
    assert roughness_index(patch, H_M) == pytest.approx(expected, rel=1e-9)
    assert expected > 0.1  # real ground is not a plane: the check is not 0 == 0


@pytest.mark.geo
def test_ri_of_a_real_patch_ignores_a_tilt() -> None:
    patch = _real_patch()
    before = roughness_index(patch, H_M)
    tilted = patch.copy()
    # A 30 % grade one way and -45 % the other, plus a height offset: a plane, not roughness.
    tilted[:, 2] += 12.0 + 0.3 * (patch[:, 0] - patch[0, 0]) - 0.45 * (patch[:, 1] - patch[0, 1])
    assert roughness_index(tilted, H_M) == pytest.approx(before, rel=1e-9)
    # Without detrending the tilt counts, so the test could fail.
    assert roughness_index(tilted, H_M, detrend=False) > 2 * before


@pytest.mark.geo
@pytest.mark.slow
def test_example_runs(tmp_path: Path) -> None:
    out = tmp_path / "map.png"
    run = subprocess.run([sys.executable, str(EXAMPLE), "--out", str(out)], capture_output=True, text=True,
                         cwd=tmp_path, timeout=120)
    assert run.returncode == 0, run.stderr
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "38367 points, 35318 ground" in run.stdout
    assert "of patches below 5 m/s" in run.stdout


@pytest.mark.slow
def test_example_without_data_says_so_in_one_line(tmp_path: Path) -> None:
    missing = tmp_path / "nowhere.las"
    run = subprocess.run([sys.executable, str(EXAMPLE), str(missing), "--out", str(tmp_path / "x.png")],
                         capture_output=True, text=True, timeout=60)
    assert run.returncode == 2
    assert run.stderr.strip().count("\n") == 0 and str(missing) in run.stderr and "not found" in run.stderr
    assert not (tmp_path / "x.png").exists()


# ----------------------------------------------- hand-built files (no data folder needed)


def _geokeys(*keys: tuple[int, int, int, int]) -> bytes:
    """A GeoKeyDirectory payload (GeoTIFF 1.0: version 1.1.0, then KeyID, location, count, value)."""
    flat = [1, 1, 0, len(keys)] + [v for key in keys for v in key]
    return struct.pack(f"<{len(flat)}H", *flat)


def _write_las(
    path: Path,
    counts_xyz: np.ndarray,
    classes: list[int],
    *,
    point_format: int = 0,
    minor: int = 2,
    scale: tuple[float, float, float] = (0.01, 0.01, 0.001),
    offset: tuple[float, float, float] = (1000.0, 2000.0, 100.0),
    vlrs: tuple[tuple[str, int, bytes], ...] = (),
    extra_bytes: int = 0,
    global_encoding: int = 0,
    signature: bytes = b"LASF",
    point_count: int | None = None,
) -> None:
    """A LAS file laid out by the ASPRS specification (independently of laspy, which reads it) (1.2 Table 3, 1.4 Table 3), with
    point format 0 (20 bytes) or 6 (30 bytes) records followed by ``extra_bytes`` zeros."""
    n = len(counts_xyz)
    header_bytes = {2: 227, 3: 235, 4: 375}[minor]
    vlr_blob = b"".join(struct.pack("<H16sHH32s", 0, user.encode(), rid, len(data), b"") + data
                        for user, rid, data in vlrs)
    layout = point_format & 0x3F  # the LAZ test sets bit 7 on a format 0 file
    record_length = {0: 20, 6: 30}[layout] + extra_bytes
    xyz = counts_xyz * np.array(scale) + np.array(offset)
    count = n if point_count is None else point_count
    legacy = 0 if (minor == 4 and point_format >= 6) else count
    header = struct.pack(
        "<4sHH16sBB32s32sHHHIIBHI5I3d3d6d", signature, 0, global_encoding, b"", 1, minor, b"test", b"test",
        1, 2024, header_bytes, header_bytes + len(vlr_blob), len(vlrs), point_format, record_length, legacy,
        legacy, 0, 0, 0, 0, *scale, *offset,
        xyz[:, 0].max(), xyz[:, 0].min(), xyz[:, 1].max(), xyz[:, 1].min(), xyz[:, 2].max(), xyz[:, 2].min(),
    )
    if minor >= 3:
        header += struct.pack("<Q", 0)  # start of waveform data
    if minor >= 4:
        header += struct.pack("<QIQ15Q", 0, 0, count, count, *([0] * 14))
    assert len(header) == header_bytes
    records = b""
    for (x, y, z), cls in zip(counts_xyz.astype(int), classes):
        if layout == 0:
            records += struct.pack("<iiiHBBbBH", x, y, z, 7, 0x09, cls, 0, 0, 1)
        else:
            records += struct.pack("<iiiHBBBBhHd", x, y, z, 7, 0x11, 0, cls, 0, 0, 1, 0.0)
        records += bytes(extra_bytes)
    path.write_bytes(header + vlr_blob + records)


COUNTS = np.array([[0, 0, 0], [1000, 0, 50], [0, 2000, -70], [123, 456, 789]])
FEET = (("LASF_Projection", 34735, _geokeys((1024, 0, 1, 1), (3072, 0, 1, 2903), (3076, 0, 1, 9003),
                                            (4099, 0, 1, 9003))),)


@pytest.mark.geo
def test_hand_built_las_12_in_us_survey_feet(tmp_path: Path) -> None:
    path = tmp_path / "feet.las"
    _write_las(path, COUNTS, [2, 1, 2, 31], vlrs=FEET, extra_bytes=3)
    cloud = read_las(path)
    feet = COUNTS * np.array([0.01, 0.01, 0.001]) + np.array([1000.0, 2000.0, 100.0])
    np.testing.assert_allclose(cloud.xyz_m(), feet * US_SURVEY_FOOT_M, rtol=1e-15)
    assert cloud.classification.tolist() == [2, 1, 2, 31]
    assert cloud.header.record_length_bytes == 23
    assert cloud.header.crs == "EPSG:2903"
    np.testing.assert_allclose(cloud.xyz_m(LAS_GROUND)[:, 2], feet[[0, 2], 2] * US_SURVEY_FOOT_M)


@pytest.mark.geo
def test_class_byte_flags_are_not_part_of_the_class(tmp_path: Path) -> None:
    # Format 0: bit 5 synthetic, 6 key-point, 7 withheld (LAS 1.2 Table 5).
    path = tmp_path / "flags.las"
    _write_las(path, COUNTS, [2 | 0x20, 2 | 0x80, 1 | 0x40, 6], vlrs=FEET)
    assert read_las(path).classification.tolist() == [2, 2, 1, 6]


@pytest.mark.geo
def test_hand_built_las_14_format_6_with_wkt(tmp_path: Path) -> None:
    wkt = ('COMPD_CS["test",PROJCS["NAD83 / UTM zone 13N",GEOGCS["NAD83",DATUM["x",SPHEROID["GRS 1980",6378137,'
           '298.257222101]],UNIT["degree",0.0174532925199433]],PROJECTION["Transverse_Mercator"],UNIT["metre",1]],'
           'VERT_CS["NAVD88 height (ftUS)",VERT_DATUM["v",2005],UNIT["US survey foot",0.304800609601219]]]')
    path = tmp_path / "wkt.las"
    _write_las(path, COUNTS, [2, 40, 2, 1], point_format=6, minor=4, global_encoding=0x10,
               vlrs=(("LASF_Projection", 2112, wkt.encode() + b"\0"),))
    cloud = read_las(path)
    assert cloud.header.version == (1, 4) and cloud.header.point_count == 4
    assert cloud.classification.tolist() == [2, 40, 2, 1]  # a whole byte for the class in format 6
    expected = COUNTS * np.array([0.01, 0.01, 0.001]) + np.array([1000.0, 2000.0, 100.0])
    np.testing.assert_allclose(cloud.x_m, expected[:, 0], rtol=1e-15)  # metres
    np.testing.assert_allclose(cloud.z_m, expected[:, 2] * 0.304800609601219, rtol=1e-15)  # US survey feet


@pytest.mark.geo
@pytest.mark.parametrize(
    "options, words",
    [
        ({"signature": b"LASX"}, "LASF"),
        ({"point_format": 0x80}, "damaged"),  # the LAZ bit without LAZ data: laspy finds no LasZip record
        ({"point_count": 9}, "is cut short: its header counts 9 point records"),
        ({"scale": (0.0, 0.01, 0.01)}, "x scale factor 0 is outside"),
        ({"vlrs": ()}, "units_m"),
        ({"vlrs": (("LASF_Projection", 34735, _geokeys((1024, 0, 1, 2), (2048, 0, 1, 4326))),)}, "geographic"),
        ({"vlrs": (("LASF_Projection", 34735, _geokeys((1024, 0, 1, 1), (3076, 0, 1, 9036))),)}, "9036"),
        ({"vlrs": (("LASF_Projection", 34735, _geokeys((1024, 0, 1, 1), (3072, 0, 1, 32767))),)}, "3076"),
    ],
)
def test_bad_files_raise_one_line_naming_the_file(tmp_path: Path, options: dict, words: str) -> None:
    path = tmp_path / "bad.las"
    _write_las(path, COUNTS, [2, 2, 2, 2], **{"vlrs": FEET, **options})
    with pytest.raises(InputError) as raised:
        read_las(path)
    message = str(raised.value)
    assert message.startswith(f"{path}: ") and "\n" not in message and words in message


@pytest.mark.geo
def test_unsupported_version_and_format_and_missing_file(tmp_path: Path) -> None:
    path = tmp_path / "v.las"
    _write_las(path, COUNTS, [2, 2, 2, 2], vlrs=FEET)
    raw = bytearray(path.read_bytes())
    raw[25] = 7  # LAS 1.7 does not exist
    path.write_bytes(bytes(raw))
    with pytest.raises(InputError, match="version 1.7"):
        read_las(path)
    raw[25], raw[104] = 2, 4  # point format 4 (57-byte records) with the 20-byte records of format 0
    path.write_bytes(bytes(raw))
    with pytest.raises(InputError, match="damaged"):
        read_las(path)
    with pytest.raises(InputError, match="cannot read"):
        read_las(tmp_path / "absent.las")


@pytest.mark.geo
def test_epsg_code_without_unit_key_takes_the_unit_of_that_crs(tmp_path: Path) -> None:
    # laspy's add_crs writes ProjectedCSTypeGeoKey (3072) without ProjLinearUnitsGeoKey (3076):
    # the EPSG CRS defines the unit (EPSG:2903: US survey foot; EPSG:32642: metre).
    for epsg, unit in ((2903, US_SURVEY_FOOT_M), (32642, 1.0)):
        path = tmp_path / f"{epsg}.las"
        _write_las(path, COUNTS, [2, 2, 2, 2], vlrs=(("LASF_Projection", 34735,
                                                       _geokeys((1024, 0, 1, 1), (3072, 0, 1, epsg))),))
        cloud = read_las(path)
        assert cloud.header.horizontal_unit_m == cloud.header.vertical_unit_m == pytest.approx(unit, rel=1e-12)
        assert cloud.header.crs == f"EPSG:{epsg}" and "3072" in cloud.header.units_source


@pytest.mark.geo
def test_units_m_reads_a_file_without_crs(tmp_path: Path) -> None:
    path = tmp_path / "nocrs.las"
    _write_las(path, COUNTS, [2, 2, 2, 2])
    cloud = read_las(path, units_m=(1.0, 0.3048))
    expected = COUNTS * np.array([0.01, 0.01, 0.001]) + np.array([1000.0, 2000.0, 100.0])
    np.testing.assert_allclose(cloud.z_m, expected[:, 2] * 0.3048, rtol=1e-15)
    assert "units_m" in cloud.header.units_source
    with pytest.raises(InputError, match="units_m"):
        read_las(path, units_m=-1.0)
    assert math.isclose(cloud.header.vertical_unit_m, 0.3048)


def test_atv_clearance_is_the_h_used_here() -> None:
    assert load_vehicle("atv").ground_clearance_m == H_M


# ------------------------------------------- hostile headers (issue 30, items 8, 10 and 11)


def _user_unit(size_m: float) -> tuple[tuple[str, int, bytes], ...]:
    """GeoKeys with a user-defined linear unit (3076 = 32767) of ``size_m`` metres (3077 in the doubles)."""
    return (("LASF_Projection", 34735, _geokeys((1024, 0, 1, 1), (3076, 0, 1, 32767), (3077, 34736, 1, 0))),
            ("LASF_Projection", 34736, struct.pack("<d", size_m)))


def _wkt(text: str) -> tuple[tuple[str, int, bytes], ...]:
    return (("LASF_Projection", 2112, text.encode() + b"\0"),)


_PROJCS = 'PROJCS["p",GEOGCS["g",DATUM["d",SPHEROID["s",6378137,298.257]]],PROJECTION["Transverse_Mercator"],'


@pytest.mark.geo
@pytest.mark.parametrize(
    "options, words",
    [
        # 5e-324 (the smallest double) turns every stored z into the offset: flat terrain
        ({"scale": (0.01, 0.01, 5e-324)}, "z scale factor 4.94066e-324 is outside 1e-07 to 1"),
        ({"scale": (0.01, 0.01, 1e-9)}, "z scale factor 1e-09 is outside"),
        ({"scale": (0.01, 0.01, 10.0)}, "z scale factor 10 is outside"),
        ({"vlrs": _user_unit(float("nan"))}, "ProjLinearUnitSizeGeoKey (3077) states a unit of nan m"),
        ({"vlrs": _user_unit(0.0)}, "states a unit of 0 m"),
        ({"vlrs": _user_unit(-0.3048)}, "states a unit of -0.3048 m"),
        ({"vlrs": _wkt(_PROJCS + 'UNIT["tiny",1e-300]]'), "minor": 4, "point_format": 6, "global_encoding": 0x10},
         "the WKT CRS 'p' states a unit of 1e-300 m, not a length unit"),
        # brackets nested 2,000 deep: Python's recursion limit (1,000) would end a recursive parser
        ({"vlrs": _wkt("PROJCS[" * 2000 + "]" * 2000), "minor": 4, "point_format": 6, "global_encoding": 0x10},
         "nests brackets more than 64 deep"),
        # before: "holds no points", which was false: 4 records follow the header
        ({"point_count": 0}, "its header counts 0 point records, but the file holds 4 records of 20 bytes after byte"),
    ],
)
def test_hostile_headers_are_one_line(tmp_path: Path, options: dict, words: str) -> None:
    path = tmp_path / "bad.las"
    _write_las(path, COUNTS, [2, 2, 2, 2], **{"vlrs": FEET, **options})
    with pytest.raises(InputError) as raised:
        read_las(path)
    message = str(raised.value)
    assert message.startswith(f"{path}: ") and "\n" not in message and words in message, message
    assert "download it again" not in message


@pytest.mark.geo
def test_a_user_defined_unit_in_range_is_used(tmp_path: Path) -> None:
    # the check of the unit's size refuses only what is not a length: a Clarke's foot is read
    path = tmp_path / "clarke.las"
    _write_las(path, COUNTS, [2, 2, 2, 2], vlrs=_user_unit(0.3047972654))
    cloud = read_las(path)
    expected = (COUNTS * np.array([0.01, 0.01, 0.001]) + np.array([1000.0, 2000.0, 100.0])) * 0.3047972654
    np.testing.assert_allclose(cloud.xyz_m(), expected, rtol=1e-15)


@pytest.mark.geo
def test_a_vlr_count_of_4294967295_is_refused_at_once(tmp_path: Path) -> None:
    # 422 bytes claiming 0xFFFFFFFF variable length records (bytes 100-103): laspy would try to
    # read them all (a hang, then MemoryError); at most (offset to points - header size) / 54 fit
    path = tmp_path / "vlrs.las"
    _write_las(path, COUNTS, [2, 2, 2, 2], vlrs=FEET)
    raw = bytearray(path.read_bytes())
    struct.pack_into("<I", raw, 100, 0xFFFFFFFF)
    path.write_bytes(bytes(raw[:422]))
    offset = struct.unpack_from("<I", raw, 96)[0]
    fit = (offset - 227) // 54  # 227-byte LAS 1.2 header, 54-byte VLR headers (LAS 1.2, 2.4)
    with pytest.raises(InputError) as raised:
        read_las(path)
    message = str(raised.value)
    assert "\n" not in message and f"counts 4294967295 variable length records, but at most {fit} fit" in message


@pytest.mark.geo
def test_records_beyond_the_header_count_get_a_note(tmp_path: Path) -> None:
    # 4 records stored, the header counts 2: laspy reads 2; the other 2 are named in a note
    path = tmp_path / "more.las"
    _write_las(path, COUNTS, [2, 2, 2, 2], vlrs=FEET, point_count=2)
    cloud = read_las(path)
    assert len(cloud) == 2
    assert len(cloud.notes) == 1 and "holds 4 point records, but its header counts 2" in cloud.notes[0]
    assert "the other 2 ignored" in cloud.notes[0]
    # a whole file has none
    _write_las(path, COUNTS, [2, 2, 2, 2], vlrs=FEET)
    assert read_las(path).notes == ()


def _laz_with_count(path: Path, stored: int, count: int, *, point_format: int = 3, version: str = "1.2",
                    seed: int = 0) -> Path:
    """A LAZ file of ``stored`` points (laspy, lazrs) whose header then says ``count``."""
    laspy = pytest.importorskip("laspy")
    pytest.importorskip("lazrs")
    rng = np.random.default_rng(seed)
    header = laspy.LasHeader(point_format=point_format, version=version)
    header.scales, header.offsets = np.array([0.001] * 3), np.array([1000.0, 2000.0, 100.0])
    las = laspy.LasData(header)
    las.X, las.Y = rng.integers(0, 70_000, stored), rng.integers(0, 2_000, stored)
    las.Z = 5_000 + np.cumsum(rng.integers(-3, 4, stored))  # a rough surface, as a real cloud's
    las.classification = np.full(stored, 2, dtype=np.uint8)
    las.write(str(path))
    raw = bytearray(path.read_bytes())
    if raw[25] >= 4:
        struct.pack_into("<Q", raw, 247, count)
        if struct.unpack_from("<I", raw, 107)[0]:
            struct.pack_into("<I", raw, 107, count)
    else:
        struct.pack_into("<I", raw, 107, count)
    path.write_bytes(bytes(raw))
    return path


@pytest.mark.geo
@pytest.mark.parametrize("stored, count, fmt", [
    (4_000, 2_500, (3, "1.2")),  # within the last (only) chunk of 50,000
    (4_000, 3_999, (3, "1.2")),
    (60_000, 30_000, (6, "1.4")),  # a whole chunk beyond the count, and more in the last
    (120_000, 50_000, (3, "1.2")),  # the count ends at a chunk's end
])
def test_laz_records_beyond_the_header_count_get_the_las_note(tmp_path: Path, stored: int, count: int,
                                                              fmt: tuple[int, str]) -> None:
    # Before: a LAZ whose header counts fewer points than it stores dropped the rest silently
    # (the same edit on a .las file had a note)
    path = _laz_with_count(tmp_path / "more.laz", stored, count, point_format=fmt[0], version=fmt[1])
    cloud = read_las(path, units_m=1.0)
    assert len(cloud) == count
    assert cloud.notes == (f"more.laz: holds {stored:,} point records, but its header counts {count:,}: the first "
                           f"{count:,} were read, the other {stored - count:,} ignored (the header's count is wrong "
                           "or records were appended); set the count in its header to read them all",)


@pytest.mark.geo
@pytest.mark.parametrize("stored, fmt", [(7, (3, "1.2")), (4_000, (3, "1.2")), (50_000, (6, "1.4")),
                                         (50_001, (3, "1.2")), (123_457, (7, "1.4"))])
def test_a_whole_laz_file_has_no_note(tmp_path: Path, stored: int, fmt: tuple[int, str]) -> None:
    path = _laz_with_count(tmp_path / "whole.laz", stored, stored, point_format=fmt[0], version=fmt[1])
    cloud = read_las(path, units_m=1.0)
    assert len(cloud) == stored and cloud.notes == ()


@pytest.mark.geo
def test_a_header_count_of_0_over_stored_records_says_the_count_is_wrong(tmp_path: Path) -> None:
    # Before: "holds no points", which was false
    path = _laz_with_count(tmp_path / "zero.laz", 4_000, 0)
    with pytest.raises(InputError) as raised:
        read_las(path, units_m=1.0)
    message = str(raised.value)
    assert "\n" not in message and "holds no points" not in message
    assert message.startswith(f"{path}: its header counts 0 point records, but its compressed point data hold 1 "
                              "chunk(s) of points: the header's point count ('number of point records') is wrong")


@pytest.mark.geo
def test_a_record_length_below_the_format_is_named(tmp_path: Path) -> None:
    path = tmp_path / "fmt.las"
    _write_las(path, COUNTS, [2, 2, 2, 2], vlrs=FEET)
    raw = bytearray(path.read_bytes())
    raw[104] = 4  # point format 4 (57-byte records, LAS 1.4 Table 11) with the 20-byte records of format 0
    path.write_bytes(bytes(raw))
    with pytest.raises(InputError, match=r"point data format 4 \(records of at least 57 bytes\) and records of 20 "):
        read_las(path)
