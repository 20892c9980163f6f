"""The real-data elevation readers (profileopt.io.elevation): OpenCRG and x-y profiles, on
hand-built files and on the bundled measured courses.

Reference values: hand-built files written here as the formats describe them, and numbers
stated by the data's source (data/README.md and the files' own headers).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from profileopt.errors import InputError
from profileopt.io import read_opencrg, read_xy_profile

from conftest import REAL_DATA


def write_crg(path: Path, rows: np.ndarray, fmt: str = "KRBI", increment: float = 0.5) -> None:
    """A minimal OpenCRG file as the format describes it: text header ending in a line of
    '$', then big-endian rows padded with NaN to 80-byte records."""
    header = "\n".join(
        [
            "$CT",
            "hand-made test road = not a key",
            "$",
            "$ROAD_CRG",
            "reference_line_start_u = 0.0",
            f"reference_line_end_u = {increment * (rows.shape[0] - 1)!r}",
            f"reference_line_increment = {increment!r}   ! a comment",
            "$",
            "$KD_DEFINITION",
            f"#:{fmt}",
            "U:reference line u,m,0.000,0.500",
            *[f"D:long section {i + 1},m" for i in range(rows.shape[1])],
            "$",
            "$" * 72,
            "",
        ]
    ).encode()
    dtype = ">f4" if fmt == "KRBI" else ">f8"
    data = rows.astype(dtype).tobytes()
    data += np.full((-len(data) % 80) // np.dtype(dtype).itemsize, np.nan, dtype=dtype).tobytes()
    path.write_bytes(header + data)


def test_read_opencrg_hand_made(tmp_path):
    rows = np.column_stack([np.arange(7) * 1.0, np.arange(7) * 10.0, np.arange(7) * 100.0])
    write_crg(tmp_path / "road.crg", rows)
    s, z = read_opencrg(tmp_path / "road.crg")
    np.testing.assert_array_equal(s, np.arange(7) * 0.5)
    np.testing.assert_array_equal(z, rows[:, 1])  # the middle track by default
    np.testing.assert_array_equal(read_opencrg(tmp_path / "road.crg", track=2).z_m, rows[:, 2])
    write_crg(tmp_path / "double.crg", rows[:, :1], fmt="KDBI")
    np.testing.assert_array_equal(read_opencrg(tmp_path / "double.crg").z_m, rows[:, 0])


def test_read_opencrg_refuses_broken_files(tmp_path):
    rows = np.ones((7, 3))
    write_crg(tmp_path / "road.crg", rows)
    good = (tmp_path / "road.crg").read_bytes()
    (tmp_path / "short.crg").write_bytes(good[:-100])
    with pytest.raises(InputError, match="truncated"):
        read_opencrg(tmp_path / "short.crg")
    (tmp_path / "text.crg").write_bytes(good.replace(b"#:KRBI", b"#:LRFI"))
    with pytest.raises(InputError, match="not supported"):
        read_opencrg(tmp_path / "text.crg")
    (tmp_path / "noend.crg").write_bytes(good.replace(b"$" * 72, b"#" * 72))
    with pytest.raises(InputError, match="ends the header"):
        read_opencrg(tmp_path / "noend.crg")
    with pytest.raises(InputError, match="track 5"):
        read_opencrg(tmp_path / "road.crg", track=5)
    rows[3, 1] = np.nan
    write_crg(tmp_path / "hole.crg", rows)
    with pytest.raises(InputError, match="NaN"):
        read_opencrg(tmp_path / "hole.crg")


def test_read_xy_profile(tmp_path):
    path = tmp_path / "p.txt"
    path.write_text("# distance elevation\n10.0 1.5\n\n10.25, 1.75\n10.5\t2.0\n")
    s, z = read_xy_profile(path)
    np.testing.assert_array_equal(s, [10.0, 10.25, 10.5])
    np.testing.assert_array_equal(z, [1.5, 1.75, 2.0])
    path.write_text("0 1\n1 2\n1 3\n")
    with pytest.raises(InputError, match="line 3.*does not increase"):
        read_xy_profile(path)
    path.write_text("0 1\n1 x\n")
    with pytest.raises(InputError, match="line 2"):
        read_xy_profile(path)


@pytest.mark.parametrize("inches, header_rms_in", [(1, 0.96944), (2, 1.7441), (4, 3.3005)])
def test_krc_course_length_spacing_and_rms(inches, header_rms_in):
    s, z = read_opencrg(REAL_DATA / "krc-rms-courses" / f"detrended_rms_course_{inches}in.crg")
    # data/README.md: 504.75 m at 5 cm spacing, 100 m flat run-in
    assert s.size == 10_096 and s[0] == 0.0 and s[-1] == pytest.approx(504.75, abs=1e-9)
    np.testing.assert_allclose(np.diff(s), 0.05, atol=1e-9)
    assert np.all(z[s < 99.9] == 0.0)
    rough = (s >= 100.0) & (s <= 404.8)  # "Undulated surface starts at = 100 m", 304.8 m long
    rms_in = np.std(z[rough]) / 0.0254
    # The file's own header states the detrended RMS (1 in: 0.96944, 2 in: 1.7441, 4 in:
    # 3.3005); we measured 0.957, 1.741, 3.303 in.
    assert rms_in == pytest.approx(header_rms_in, rel=0.02)
    # The courses are named by their nominal RMS (1, 2, 4 in = 25.4, 50.8, 101.6 mm);
    # detrending removed long waves, so the measured RMS is 4 %, 13 % and 17 % below it.
    assert 0.80 * inches < rms_in < 1.0 * inches


def test_iri_profile_matches_readme():
    s, z = read_xy_profile(REAL_DATA / "iri-road-profile" / "profile_1.txt")
    # README: 544 m at 0.25 m spacing, absolute elevations 582-583 m
    assert s[-1] - s[0] == pytest.approx(544.0) and np.allclose(np.diff(s), 0.25)
    assert 582.0 <= z.min() and z.max() <= 583.2


@pytest.mark.parametrize("end_u, words", [
    # (1e308 - 0) / 0.5 overflows to inf: int(inf) was an OverflowError (exit 1)
    ("1e308", "reference_line_end_u = 1e+308 every reference_line_increment = 0.5 m is more than 1e308 rows"),
    # finite but far beyond the data: named before any array of that size is made
    ("1e15", "is 2e+15 rows of 2 KRBI values, but the file holds 80 data bytes, enough for 10 rows"),
])
def test_a_reference_line_end_beyond_the_data_is_one_line(tmp_path, end_u: str, words: str) -> None:
    path = tmp_path / "far.crg"
    write_crg(path, np.zeros((4, 2)))  # 4 rows x 2 values x 4 bytes = 32 bytes, padded to 80
    path.write_bytes(path.read_bytes().replace(b"reference_line_end_u = 1.5", f"reference_line_end_u = {end_u}".encode()))
    with pytest.raises(InputError) as raised:
        read_opencrg(path)
    message = str(raised.value)
    assert message.startswith(f"{path}: ") and "\n" not in message and words in message, message
