"""The options of a track over a terrain (profileopt.cli.track): the default --max-gap follows a
point cloud's density (issue 30 item 16, second round). At the density UAV LiDAR delivers
(100 to 135 ground points per m^2), the random gaps a kilometre of route meets are bridged;
a real hole, a strip of missing ground, is still refused; --max-gap overrides."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from profileopt.cli import main

pytest.importorskip("laspy")
pytest.importorskip("pyproj")

#: The strip's start (UTM 33N, m) and length (m).
X0, Y0, LENGTH_M = 500_000.0, 5_100_000.0, 1000.0


def strip_cloud(path: Path, density_per_m2: float, seed: int, hole_m: tuple[float, float] | None = None) -> Path:
    """A flat, slightly rough strip of ground points (class 2) along x, 0.6 m wide, scattered at
    random: within 0.15 m of the centre line (the default corridor) exactly density x 0.3 m x
    the length of them (so that the corridor measures the density asked for: a Poisson count
    would measure 99.5 or 100.5 per m^2 for 100, on either side of what 0.1 m needs), as many
    again outside it; none in ``hole_m`` (from, to along the strip)."""
    from geo_data import write_laz

    rng = np.random.default_rng(seed)
    inner = int(round(density_per_m2 * 0.3 * LENGTH_M))
    outer = int(round(density_per_m2 * 0.3 * LENGTH_M))
    x = rng.uniform(0.0, LENGTH_M, inner + outer)
    # (1 mm inside and outside the corridor's edge: the file's millimetres round no point across it)
    y = np.concatenate([rng.uniform(-0.149, 0.149, inner),
                        rng.choice([-1.0, 1.0], outer) * rng.uniform(0.151, 0.3, outer)])
    if hole_m is not None:
        keep = (x < hole_m[0]) | (x > hole_m[1])
        x, y = x[keep], y[keep]
    z = 100.0 + 0.01 * np.sin(2 * np.pi * x / 1.7) + rng.normal(0.0, 0.002, x.size)
    return write_laz(path, X0 + x, Y0 + y, z, np.full(x.size, 2, dtype=np.uint8))


def strip_track(path: Path) -> Path:
    path.write_text(f"x,y\n{X0:.1f},{Y0:.1f}\n{X0 + LENGTH_M:.1f},{Y0:.1f}\n")
    return path


def route(tmp_path: Path, cloud: Path, capsys: pytest.CaptureFixture, *options: str) -> tuple[int, str, Path]:
    out = tmp_path / "route.csv"
    status = main(["route", str(strip_track(tmp_path / "track.csv")), "--terrain", str(cloud), "-o", str(out),
                   *options])
    return status, capsys.readouterr().err, out


def test_uav_density_is_sampled_with_a_max_gap_its_density_leaves(tmp_path: Path,
                                                                   capsys: pytest.CaptureFixture) -> None:
    # before: "no ground points within the corridor from s = 125.40 to 125.50 m ... 0.30 m ...
    # longer than --max-gap = 0.2 m", 3 of 3 seeds
    cloud = strip_cloud(tmp_path / "c135.laz", 135.0, seed=1)
    status, err, out = route(tmp_path, cloud, capsys)
    assert status == 0, err
    assert "note: " + str(cloud) + ": --max-gap 0.4 m: stretches without ground points up to 0.4 m are bridged, as " \
           "its 135 ground points per m^2 within 0.15 m of the track leave such gaps by chance" in err
    assert "; --max-gap sets another" in err
    assert "max gap 0.4 m" in out.read_text()
    # the override is kept: the old 0.2 m refuses the random gaps of this cloud
    status, err, _ = route(tmp_path, cloud, capsys, "--max-gap", "0.2")
    assert status == 2 and "longer than --max-gap = 0.2 m" in err and len(err.strip().splitlines()) == 1


def test_a_missing_strip_of_ground_is_still_refused(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    cloud = strip_cloud(tmp_path / "hole.laz", 135.0, seed=1, hole_m=(500.0, 501.0))
    status, err, out = route(tmp_path, cloud, capsys)
    assert status == 2 and len(err.strip().splitlines()) == 1, err
    assert "no ground points within the corridor from s = 500.08 to 500.96 m" in err and "a stretch of 1.04 m" in err
    assert "longer than --max-gap = 0.4 m" in err
    assert not out.exists()


@pytest.mark.parametrize("density", [100.0, 135.0])
def test_uav_densities_are_accepted_whatever_the_scatter(tmp_path: Path, capsys: pytest.CaptureFixture,
                                                        density: float) -> None:
    # 100 per m^2: what 0.1 m spacing needs (3 per 0.3 m x 0.1 m bin); the default gap 0.5 m
    for seed in range(2, 8):
        cloud = strip_cloud(tmp_path / f"c{seed}.laz", density, seed=seed)
        status, err, _ = route(tmp_path, cloud, capsys)
        assert status == 0, (seed, err)
        gap = "0.5" if density == 100.0 else "0.4"
        assert f"--max-gap {gap} m:" in err, err


def test_max_gap_without_a_terrain_is_refused_even_at_the_old_default(tmp_path: Path,
                                                                      capsys: pytest.CaptureFixture) -> None:
    track = tmp_path / "t.gpx"
    track.write_text('<?xml version="1.0"?><gpx version="1.1" creator="t"><trk><trkseg><trkpt lat="46.0" '
                     'lon="13.0"><ele>100</ele></trkpt><trkpt lat="46.0005" lon="13.0"><ele>101</ele></trkpt>'
                     '</trkseg></trk></gpx>')
    assert main(["route", str(track), "--roughness-class", "C", "--max-gap", "0.2", "-o", str(tmp_path / "r.csv")]) \
        == 2
    assert "--max-gap applies to the ground points of a terrain" in capsys.readouterr().err
