"""profileopt.io.routes on misleading route files (issue 30 items 8 and 17).

Reference values: the routes' lengths by hand (straight lines along x).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from profileopt.errors import InputError
from profileopt.io import read_route


def _route(tmp_path: Path, text: str, name: str = "r.csv") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


@pytest.mark.parametrize(("name", "kind"), [("cloud.las", "point cloud (LAS)"), ("cloud.laz", "point cloud (LAZ)"),
                                            ("dem.TIF", "terrain map (GeoTIFF DEM)"),
                                            ("dem.tiff", "terrain map (GeoTIFF DEM)"),
                                            ("road.crg", "terrain surface (OpenCRG)")])
def test_a_terrain_file_is_not_read_as_a_route(tmp_path: Path, name: str, kind: str) -> None:
    # before: read as text, "header 'LASF...' lacks the columns 's,z'" (or a TOML-like mess)
    path = tmp_path / name
    path.write_bytes(b"LASF" + bytes(64))
    with pytest.raises(InputError, match=rf"{name}: is a {kind.replace('(', '[(]').replace(')', '[)]')}, not a "
                                         rf"route file; give it as --terrain"):
        read_route(path)


def test_an_xyz_route_in_degrees_is_refused(tmp_path: Path) -> None:
    # before: planned as a route 4 mm long
    path = _route(tmp_path, "x,y,z\n14.5,46.0,300\n14.501,46.0002,301\n14.502,46.0004,302\n")
    with pytest.raises(InputError, match=r"r\.csv: x, y look like longitude, latitude in degrees .* a route file's "
                                         r"are metres; make a route of them as a track \(profileopt route r\.csv "
                                         r"--track-crs EPSG:4326"):
        read_route(path)


def test_a_small_xyz_route_in_metres_is_read(tmp_path: Path) -> None:
    route = read_route(_route(tmp_path, "x,y,z\n0,0,0\n100,0,1\n150,0,1\n"))
    assert route.length_m == 150.0
    far = read_route(_route(tmp_path, "x,y,z\n500000,5100000,0\n500001,5100000,0\n", "utm.csv"))
    assert far.length_m == 1.0  # 1 m, but at UTM eastings: not degrees


@pytest.mark.parametrize("value", ["\u0660.05", "0_05", "\uff10.05"])
def test_an_assumed_ri_must_be_written_in_ascii_digits(tmp_path: Path, value: str) -> None:
    path = _route(tmp_path, f"# roughness_ri = {value}\ns,z\n0,0\n1,0\n")
    with pytest.raises(InputError, match=r"r\.csv: line 1: roughness_ri = .* is not usable"):
        read_route(path)
    assert read_route(_route(tmp_path, "# roughness_ri = 0.05\ns,z\n0,0\n1,0\n")).assumed_roughness.ri == 0.05
