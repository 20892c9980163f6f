"""Routes sampled along a track over a terrain map (profileopt.terrain.ground_track, issue 12).

Reference values: the synthetic ground of tests/geo_data.py is a closed-form surface, so the
ground under any sample is known exactly; the RI per roughness window comes from
conftest.window_ri (Eq. 1, computed directly per window, not with the package's prefix sums).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from profileopt.errors import InputError
from profileopt.terrain.ground_track import corridor_bins, resample_polyline, route_from_track

from conftest import window_ri
from geo_data import (ARC_ANGLE_RAD, ARC_RADIUS_M, cloud_points, surface_m, track_utm_m, write_geotiff,
                      write_gpx, write_laz)

pytestmark = pytest.mark.geo  # every test here reads or writes geographic files
pytest.importorskip("laspy")
pytest.importorskip("rasterio")

H_M = 0.1  # ground clearance of the bundled atv (models/atv.toml), the RI's normalising length
WINDOW_M = 5.0  # the default roughness window (profileopt.defaults)


@pytest.fixture(scope="module")
def ground(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """The synthetic ground's files: a GPX track, a classified LAZ, an unclassified LAZ and a
    GeoTIFF at 5 cm."""
    folder = tmp_path_factory.mktemp("ground")
    x, y, z, classes = cloud_points()
    unclassified = np.ones_like(classes)  # class 1, 'unassigned': a cloud nobody classified
    keep = classes != 7  # an unclassified cloud without its noise points (their class is all that marks them)
    return {
        "gpx": write_gpx(folder / "track.gpx", *track_utm_m(2.0)),
        "laz": write_laz(folder / "ground.laz", x, y, z, classes),
        "unclassified": write_laz(folder / "plain.laz", x[keep], y[keep], z[keep], unclassified[keep]),
        "tif": write_geotiff(folder / "ground.tif"),
    }


def _route(track_path: Path, terrain_path: Path | None, **options):
    from profileopt.io import read_terrain, read_track

    terrain = read_terrain(terrain_path) if terrain_path is not None else None
    return route_from_track(read_track(track_path), terrain, **options)


def _ri_errors(result) -> np.ndarray:
    """Relative error of each window's RI against the RI of the true ground under the same samples."""
    route = result.route
    truth = type(route)(s_m=route.s_m, z_m=surface_m(route.x_m, route.y_m), x_m=route.x_m, y_m=route.y_m)
    _, ri_true = window_ri(truth, WINDOW_M, H_M)
    _, ri = window_ri(route, WINDOW_M, H_M)
    return np.abs(ri / ri_true - 1.0)


# ------------------------------------------------------------------ the pieces


def test_resample_polyline_every_spacing_along_straight_lines() -> None:
    # an L: 3 m east then 4 m north; samples every 1 m: the corner is sample 3 (hand count)
    s, x, y = resample_polyline(np.array([0.0, 3.0, 3.0]), np.array([0.0, 0.0, 4.0]), 1.0)
    np.testing.assert_allclose(s, np.arange(8.0))
    np.testing.assert_allclose(x, [0, 1, 2, 3, 3, 3, 3, 3])
    np.testing.assert_allclose(y, [0, 0, 0, 0, 1, 2, 3, 4])
    s, _, _ = resample_polyline(np.array([0.0, 2.5]), np.array([0.0, 0.0]), 1.0)
    np.testing.assert_allclose(s, [0, 1, 2, 2.5])  # the end is kept, closer than the spacing


def test_corridor_bins_take_the_nearest_sample_within_the_strip() -> None:
    stations = np.column_stack([np.arange(5.0), np.zeros(5)])  # along the x axis, 1 m apart
    points = np.array([[1.2, 0.1],    # bin 1, 0.1 m across: kept
                       [2.6, -0.2],   # bin 3 (nearest), 0.2 m across: kept
                       [2.0, 0.31],   # 0.31 m across a 0.3 m strip: dropped
                       [-0.6, 0.0],   # before the first sample by more than half a spacing: dropped
                       [4.4, 0.0]])   # bin 4
    kept, bins = corridor_bins(points, stations, 0.3)
    assert kept.tolist() == [0, 1, 4]
    assert bins.tolist() == [1, 3, 4]


# ------------------------------------------------------------------ the synthetic ground


@pytest.mark.parametrize("terrain", ["laz", "tif"])
def test_route_ri_per_window_matches_the_true_ground(ground: dict, terrain: str) -> None:
    result = _route(ground["gpx"], ground[terrain])
    route = result.route
    # the route follows the arc: its length is R * angle (to the chord error of 2 m GPX steps,
    # R (angle - 2 sin(angle / 2)) / ... below 1 mm per step at R = 60 m)
    assert route.length_m == pytest.approx(ARC_RADIUS_M * ARC_ANGLE_RAD, rel=2e-3)
    assert result.roughness_measured and route.assumed_roughness is None
    assert "EPSG:32633" in result.crs_name
    errors = _ri_errors(result)
    assert np.median(errors) < 0.05  # the bound: median error within 5 %
    # and the elevations themselves: within a few mm of the ground (3 mm sensor noise, bilinear cells)
    assert np.median(np.abs(route.z_m - surface_m(route.x_m, route.y_m))) < 0.004


def test_vegetation_and_noise_do_not_become_bumps(ground: dict) -> None:
    # the same cloud with every class kept would rise by the vegetation; class 2 alone does not
    result = _route(ground["gpx"], ground["laz"])
    error = result.route.z_m - surface_m(result.route.x_m, result.route.y_m)
    assert np.max(np.abs(error)) < 0.03  # vegetation is 5 cm to 1 m, noise 2 m: none of it shows
    assert result.density_per_m2 == pytest.approx(1500.0, rel=0.05)  # the density written (geo_data)


def test_an_unclassified_cloud_takes_a_low_quantile_and_says_so(ground: dict) -> None:
    result = _route(ground["gpx"], ground["unclassified"])
    assert any("not classified" in line for line in result.comments)
    assert any("not classified" in line and "10th percentile" in line for line in result.notes)
    error = result.route.z_m - surface_m(result.route.x_m, result.route.y_m)
    # 13 % of the points are vegetation above the ground: the 10th percentile stays on it
    assert np.median(np.abs(error)) < 0.01


def test_a_coarse_dem_is_refused_for_roughness_and_planned_with_a_class(ground: dict, tmp_path: Path) -> None:
    from profileopt.terrain.assumed import AssumedRoughness

    coarse = write_geotiff(tmp_path / "coarse.tif", cell_m=1.0)
    with pytest.raises(InputError, match=r"cells are 1 m x 1 m.*at most 0.05 m.*roughness_class"):
        _route(ground["gpx"], coarse)
    result = _route(ground["gpx"], coarse, assumed_roughness=AssumedRoughness(road_class="C"))
    assert result.route.assumed_roughness.road_class == "C"
    assert not result.roughness_measured
    # the geometry and the grade still come from the DEM: within a few cm of the ground
    assert np.median(np.abs(result.route.z_m - surface_m(result.route.x_m, result.route.y_m))) < 0.05


def test_a_sparse_cloud_is_refused_with_the_density_found_and_needed(ground: dict, tmp_path: Path) -> None:
    x, y, z, classes = cloud_points(seed=1, density_per_m2=20.0)
    sparse = write_laz(tmp_path / "sparse.laz", x, y, z, classes)
    # needed: 3 points per 0.3 m x 0.05 m bin = 200 per m^2 (defaults.MIN_POINTS_PER_BIN)
    with pytest.raises(InputError, match=r"ground points \(class 2\) per m\^2.*needs 200 per m\^2"):
        _route(ground["gpx"], sparse)


def test_gaps_are_bridged_up_to_max_gap_and_refused_beyond(ground: dict, tmp_path: Path) -> None:
    x, y, z, classes = cloud_points(seed=2)
    tx, ty = track_utm_m(0.05)
    # a hole 0.5 m long across the track, 20 m along it (arc length R * angle)
    angle = np.arctan2(x - tx[0], (ty[0] + ARC_RADIUS_M) - y)
    hole = np.abs(angle * ARC_RADIUS_M - 20.0) < 0.25
    holed = write_laz(tmp_path / "holed.laz", x[~hole], y[~hole], z[~hole], classes[~hole])
    with pytest.raises(InputError, match=r"no ground points within the corridor from s = 19\.8\d to 20\.2\d m"):
        _route(ground["gpx"], holed)
    result = _route(ground["gpx"], holed, max_gap_m=0.6)
    assert len(result.gaps_m) == 1
    start, end = result.gaps_m[0]
    assert start == pytest.approx(19.75, abs=0.06) and end == pytest.approx(20.25, abs=0.06)


def test_a_track_outside_the_terrain_names_both_extents(ground: dict, tmp_path: Path) -> None:
    tx, ty = track_utm_m(2.0)
    far = write_gpx(tmp_path / "far.gpx", tx + 5000.0, ty)
    with pytest.raises(InputError, match=r"lies outside the terrain .*CRS"):
        _route(far, ground["tif"])
    half = write_gpx(tmp_path / "half.gpx", np.concatenate([tx, tx[-1] + np.arange(1, 20) * 2.0]),
                     np.concatenate([ty, np.full(19, ty[-1])]))
    with pytest.raises(InputError, match=r"leaves the terrain .* from s = "):
        _route(half, ground["tif"])


def test_options_are_checked() -> None:
    from profileopt.io.tracks import Track

    track = Track(x=np.array([0.0, 10.0]), y=np.zeros(2), z_m=np.zeros(2), crs=None, source="t.csv", notes=())
    for options, word in (({"spacing_m": 0.0}, "spacing_m"), ({"corridor_m": -1.0}, "corridor_m"),
                          ({"max_gap_m": math.nan}, "max_gap_m")):
        with pytest.raises(InputError, match=word):
            route_from_track(track, None, **options)


def test_a_track_alone_gives_geometry_and_grade_with_an_assumed_class() -> None:
    from profileopt.io.tracks import Track
    from profileopt.terrain.assumed import AssumedRoughness

    track = Track(x=np.array([0.0, 10.0, 20.0]), y=np.zeros(3), z_m=np.array([0.0, 1.0, 1.5]), crs=None,
                  source="t.csv", notes=())
    with pytest.raises(InputError, match="track's own elevations.*roughness"):
        route_from_track(track, None)
    result = route_from_track(track, None, spacing_m=0.5, assumed_roughness=AssumedRoughness(road_class="D"))
    # linear between the track's points: z(5 m) = 0.5, z(15 m) = 1.25 (hand interpolation)
    np.testing.assert_allclose(np.interp([5.0, 15.0], result.route.s_m, result.route.z_m), [0.5, 1.25])


@pytest.mark.parametrize("seed", [1, 4, 6])
def test_a_noisy_out_and_back_track_at_one_elevation_keeps_it(seed: int) -> None:
    # Reference: every point reads 500 m, so the ground is 500 m everywhere. A GPS out and back
    # along 150 m (a point every 3 m, 1.5 m of noise) whose elevations never change: every
    # reading after the first repeats it. Weighing them 1e-6 against the first's 1 left the
    # smoothing spline near singular: 500 m read as 500 to 1020 m (issue 29, from outside).
    from profileopt.io.tracks import Track
    from profileopt.terrain.assumed import AssumedRoughness

    rng = np.random.default_rng(seed)
    out = np.arange(0.0, 150.0 + 1e-9, 3.0)
    x = np.concatenate([out, 150.0 - out[1:]]) + rng.normal(0.0, 1.5, 2 * out.size - 1)
    y = rng.normal(0.0, 1.5, x.size)
    track = Track(x=x, y=y, z_m=np.full(x.size, 500.0), crs=None, source="t.gpx", notes=())
    result = route_from_track(track, None, assumed_roughness=AssumedRoughness(road_class="B"))
    np.testing.assert_allclose(result.route.z_m, 500.0, rtol=0, atol=1e-9)


def test_frozen_readings_are_left_out_and_the_ends_held() -> None:
    # Reference (hand): a track climbing 1 m per 10 m whose altimeter froze from 110 m to
    # 200 m (it repeats 10 m) and from 310 m on (it repeats 30 m). The readings kept lie on the
    # line z = s / 10, which the smoothing spline reproduces exactly (a line costs no
    # curvature): 15 m at 150 m; past the last reading kept (300 m) the curve holds 30 m, where
    # weighed 1e-6 the frozen readings let it run on up the line (39 m at 400 m).
    from profileopt.terrain.ground_track import smooth_track_elevations

    s = np.arange(0.0, 400.0 + 1e-9, 10.0)
    z = s / 10.0
    z[(s > 100.0) & (s <= 200.0)] = 10.0
    z[s > 300.0] = 30.0
    curve = smooth_track_elevations(s, z)
    np.testing.assert_allclose(curve(np.array([50.0, 150.0, 250.0])), [5.0, 15.0, 25.0], atol=1e-6)
    np.testing.assert_allclose(curve(np.array([300.0, 350.0, 400.0])), 30.0, atol=1e-6)


def test_a_csv_tracks_speed_limit_holds_from_its_point_to_the_next(tmp_path: Path) -> None:
    from profileopt.io import read_route, read_track
    from profileopt.io.routes import write_route
    from profileopt.terrain.assumed import AssumedRoughness

    path = tmp_path / "track.csv"
    path.write_text("x_m,y_m,z_m,speed_limit_mps\n0,0,0,5\n10,0,0,3\n20,0,0,4\n")
    track = read_track(path)
    result = route_from_track(track, None, spacing_m=2.5, assumed_roughness=AssumedRoughness(road_class="A"))
    s, limit = result.route.s_m, result.route.speed_limit_mps
    # hand table: the first piece 5 m/s, the point at 10 m the lower of 5 and 3, the second piece 3 m/s
    np.testing.assert_allclose(s, [0, 2.5, 5, 7.5, 10, 12.5, 15, 17.5, 20])
    np.testing.assert_allclose(limit, [5, 5, 5, 5, 3, 3, 3, 3, 3])
    out = tmp_path / "route.csv"
    write_route(result.route, out)
    np.testing.assert_array_equal(read_route(out).speed_limit_mps, limit)
    path.write_text("x,y,speed_limit\n0,0,5\n10,0,0\n")
    with pytest.raises(InputError, match=r"line 3: speed_limit = 0 m/s must be a number > 0"):
        read_track(path)


# ------------------------------------------------------------------ the review's cases


def test_a_sliver_at_the_end_moves_the_last_sample_and_huge_counts_are_refused() -> None:
    # 2.04 m at 1 m: a 0.04 m remainder is below half a spacing, so the last sample moves to the end
    s, _, _ = resample_polyline(np.array([0.0, 2.04]), np.zeros(2), 1.0)
    np.testing.assert_allclose(s, [0, 1, 2.04])
    with pytest.raises(InputError, match=r"spacing_m = 1e-06 m cuts the 60 m track into 6e\+07 samples"):
        resample_polyline(np.array([0.0, 60.0]), np.zeros(2), 1e-6)


@pytest.mark.slow
def test_roughness_is_measured_only_at_wheel_scale(ground: dict) -> None:
    from profileopt.terrain.assumed import AssumedRoughness

    # the dense cloud measures roughness at 0.05 m in a 0.15 m corridor (above); not so at 0.5 m
    # spacing or in a 1 m corridor, whatever its density (defaults.MAX_ROUGHNESS_*)
    with pytest.raises(InputError, match=r"samples every 0.5 m miss the bumps a wheel feels"):
        _route(ground["gpx"], ground["laz"], spacing_m=0.5)
    with pytest.raises(InputError, match=r"a corridor of 1 m each side averages ground the tyre does not touch"):
        _route(ground["gpx"], ground["laz"], corridor_m=1.0)
    coarse = _route(ground["gpx"], ground["laz"], spacing_m=0.5, assumed_roughness=AssumedRoughness(road_class="B"))
    assert not coarse.roughness_measured and coarse.route.assumed_roughness.road_class == "B"
    # where the terrain measures the roughness, an assumed class is not used, and a note says so
    fine = _route(ground["gpx"], ground["laz"], assumed_roughness=AssumedRoughness(road_class="A"))
    assert fine.roughness_measured and fine.route.assumed_roughness is None
    assert any("is not used" in note and "ISO 8608 class A" in note for note in fine.notes)


def test_a_sparse_unclassified_cloud_is_refused_even_with_a_class(tmp_path: Path) -> None:
    from profileopt.terrain.assumed import AssumedRoughness
    from profileopt.io import read_terrain, read_track

    x, y, z, classes = cloud_points(seed=4, density_per_m2=20.0)
    plain = write_laz(tmp_path / "plain.laz", x, y, z, np.ones_like(classes))
    gpx = write_gpx(tmp_path / "t.gpx", *track_utm_m(2.0))
    with pytest.raises(InputError, match=r"not classified and too sparse for roughness.*classify its ground"):
        route_from_track(read_track(gpx), read_terrain(plain), assumed_roughness=AssumedRoughness(road_class="C"))


def test_a_gap_at_an_end_is_held_flat_up_to_max_gap(tmp_path: Path) -> None:
    from profileopt.io import read_terrain, read_track

    x, y, z, classes = cloud_points(seed=5)
    tx, ty = track_utm_m(0.05)
    arc = np.arctan2(x - tx[0], (ty[0] + ARC_RADIUS_M) - y) * ARC_RADIUS_M
    cut = arc > 0.13  # no ground before 0.13 m along the track: the samples at 0, 0.05 and 0.1 m are empty
    cloud = read_terrain(write_laz(tmp_path / "cut.laz", x[cut], y[cut], z[cut], classes[cut]))
    track = read_track(write_gpx(tmp_path / "t.gpx", *track_utm_m(2.0)))
    result = route_from_track(track, cloud, max_gap_m=0.2)
    # the stretch from the start to the first sample with data (0.15 m) is bridged, flat
    np.testing.assert_allclose(result.gaps_m, [[0.0, 0.15]], atol=1e-6)
    assert result.route.z_m[0] == result.route.z_m[1] == result.route.z_m[2] == result.route.z_m[3]
    with pytest.raises(InputError, match=r"a stretch of 0.15 m at the start, longer than max_gap_m = 0.1 m"):
        route_from_track(track, cloud, max_gap_m=0.1)


def test_a_label_reads_back_as_the_assumed_roughness() -> None:
    from profileopt.terrain.assumed import AssumedRoughness

    for assumed in (AssumedRoughness(road_class="E"), AssumedRoughness(ri=0.012345678901234)):
        assert AssumedRoughness.from_label(assumed.label.replace(" ", "_")) == assumed
    with pytest.raises(InputError, match="neither"):
        AssumedRoughness.from_label("class C")


# ------------------------------------- the spacing a cloud's density supports (issue 30, item 16)


def test_the_finest_supported_spacing_by_hand() -> None:
    from profileopt.terrain.ground_track import cloud_spacing_m, supported_spacing_m

    # a terrain resolving 0.05 m or finer: half the wheel radius; coarser: rounded up to a cm,
    # up to the wheel radius (0.1 m); beyond it none
    assert [supported_spacing_m(r) for r in (0.01, 0.05, 0.0501, 0.074, 0.1, 0.1001)] == [0.05, 0.05, 0.06, 0.08,
                                                                                        0.1, None]
    # lambda = density x 0.3 m x spacing points per bin must be >= 3; runs of floor(0.2 / spacing)
    # empty bins in a row (a gap over 0.2 m) expected (length / spacing) exp(-lambda run) times, <= 0.05:
    # 135 per m^2 over 60 m: 0.08 expects 750 e^-6.48 = 1.15, 0.09 0.46, 0.1 0.18: none, so the fewest (0.1)
    assert cloud_spacing_m(135.0, 0.15, 60.0) == 0.1
    # 150 per m^2 over 10 m: 0.07 expects 143 e^-6.3 = 0.26, 0.08 0.093, 0.09 111 e^-8.1 = 0.034
    assert cloud_spacing_m(150.0, 0.15, 10.0) == 0.09
    # 300 per m^2: 0.05 (lambda 4.5, runs of 4: 1200 e^-18) as before
    assert cloud_spacing_m(300.0, 0.15, 60.0) == 0.05
    # 60 per m^2 needs 3 / (0.3 x 60) = 0.167 m: coarser than the wheel radius
    assert cloud_spacing_m(60.0, 0.15, 60.0) is None


def test_a_uav_density_cloud_is_sampled_at_the_spacing_it_supports(tmp_path: Path) -> None:
    # 135 ground points per m^2 (plus 16 % vegetation and noise): refused at 0.05 m before
    # (200 per m^2 needed); by default now sampled every 0.1 m with a note, and the RI in 5 m
    # windows is within 5 % (median) of the true ground's under the same samples
    from profileopt.io import read_terrain, read_track

    x, y, z, classes = cloud_points(seed=5, density_per_m2=135.0)
    laz = write_laz(tmp_path / "uav.laz", x, y, z, classes)
    track = read_track(write_gpx(tmp_path / "t.gpx", *track_utm_m(2.0)))
    cloud = read_terrain(laz, track=track)
    result = route_from_track(track, cloud)
    assert result.spacing_m == 0.1 and result.roughness_measured
    assert np.diff(result.route.s_m)[:-1] == pytest.approx(0.1, abs=1e-5)  # chords of the arc, 1e-7 shorter
    assert any("samples every 0.1 m, the finest spacing at which its 13" in note for note in result.notes)
    errors = _ri_errors(result)
    assert np.median(errors) < 0.05 and np.percentile(errors, 95) < 0.1
    # a spacing given is kept; too fine for the density, the message names the one that works
    with pytest.raises(InputError, match=r"roughness at 0.05 m needs 200 per m\^2 .*; spacing_m 0.1 measures it"):
        route_from_track(track, cloud, spacing_m=0.05)


def test_a_cloud_too_sparse_for_any_spacing_names_the_one_it_would_take(tmp_path: Path) -> None:
    from profileopt.io import read_terrain, read_track

    x, y, z, classes = cloud_points(seed=6, density_per_m2=60.0)
    track = read_track(write_gpx(tmp_path / "t.gpx", *track_utm_m(2.0)))
    cloud = read_terrain(write_laz(tmp_path / "sparse.laz", x, y, z, classes), track=track)
    with pytest.raises(InputError) as raised:
        route_from_track(track, cloud)
    message = str(raised.value)
    # 3 / (0.3 m x about 60 per m^2) = about 0.17 m
    assert "no spacing up to the wheel scale (0.1 m) measures it (3 points per bin would need bins 0.1" in message
    assert "give an assumed roughness" in message and "\n" not in message


def test_a_cloud_read_near_the_track_refuses_a_wider_corridor(tmp_path: Path) -> None:
    from profileopt.io import read_terrain, read_track

    x, y, z, classes = cloud_points(seed=7)
    track = read_track(write_gpx(tmp_path / "t.gpx", *track_utm_m(2.0)))
    cloud = read_terrain(write_laz(tmp_path / "c.laz", x, y, z, classes), track=track, spacing_m=0.05)
    assert cloud.kept_within_m is not None
    with pytest.raises(InputError, match=r"only the points within .* m of the track were read"):
        route_from_track(track, cloud, corridor_m=cloud.kept_within_m, spacing_m=0.05)


def test_no_points_near_the_track_is_one_line(tmp_path: Path) -> None:
    # the cloud's box covers the track, but its points lie 30 m away from it: nothing is kept
    from profileopt.io import read_terrain, read_track

    x, y, z, classes = cloud_points(seed=8, density_per_m2=50.0)
    far = np.concatenate([x, [x.min() - 40.0, x.max() + 40.0]]), np.concatenate([y, [y.min() - 40, y.max() + 40]])
    shifted_y = far[1] + 30.0
    laz = write_laz(tmp_path / "far.laz", far[0], shifted_y, np.concatenate([z, z[:2]]),
                    np.concatenate([classes, classes[:2]]))
    track = read_track(write_gpx(tmp_path / "t.gpx", *track_utm_m(2.0)))
    cloud = read_terrain(laz, track=track)
    with pytest.raises(InputError) as raised:
        route_from_track(track, cloud)
    assert f"the cloud has no points within {cloud.kept_within_m:.3g} m of the track; check that it covers" in str(
        raised.value)


def test_a_dem_is_sampled_at_its_cell_size_up_to_the_wheel_radius(tmp_path: Path) -> None:
    # the one rule for grids: cells of 0.08 m are sampled every 0.08 m (not refused at 0.05 m);
    # cells of 0.2 m measure no roughness at any spacing up to 0.1 m, so the default stays
    from profileopt.io import read_terrain, read_track
    from profileopt.terrain.assumed import AssumedRoughness

    track = read_track(write_gpx(tmp_path / "t.gpx", *track_utm_m(2.0)))
    fine = route_from_track(track, read_terrain(write_geotiff(tmp_path / "g8.tif", 0.08)))
    assert fine.spacing_m == 0.08 and fine.roughness_measured
    assert any("samples every 0.08 m, the finest spacing its cells (0.08 m x 0.08 m) resolve" in n for n in fine.notes)
    truth = surface_m(fine.route.x_m, fine.route.y_m)
    assert np.max(np.abs(fine.route.z_m - truth)) < 0.01  # bilinear over 8 cm cells of a surface with 0.6 m waves
    coarse = route_from_track(track, read_terrain(write_geotiff(tmp_path / "g20.tif", 0.2)),
                              assumed_roughness=AssumedRoughness(road_class="B"))
    assert coarse.spacing_m == 0.05 and not coarse.roughness_measured


def test_a_sparse_cloud_read_near_the_track_gives_the_route_of_the_whole_cloud() -> None:
    """Reading only the points near the track (issue 30, item 10) changes no elevation: the
    triangulated neighbourhood of a sparse cloud is judged from the whole file's ground
    density, which the reader counts over every chunk (before: the kept points' own density
    over their bounding box, which moved the real LiDAR walk-through's route by up to 0.29 m)."""
    from profileopt.io.terrain_maps import read_terrain
    from profileopt.io.tracks import read_track
    from profileopt.terrain.assumed import AssumedRoughness

    from conftest import REAL_DATA, ROOT

    track = read_track(ROOT / "examples" / "geo" / "hexbin-track.gpx")
    laz = REAL_DATA / "pdal-lidar" / "hexbin-crop.laz"
    whole, near = read_terrain(laz, terrain_crs=None), read_terrain(laz, terrain_crs=None, track=track)
    assert near.kept_within_m is not None and len(near) < len(whole) / 5  # only a strip was kept
    assert near.ground_density_per_m2 == whole.ground_density_per_m2
    assumed = AssumedRoughness(road_class="C")
    a = route_from_track(track, whole, assumed_roughness=assumed).route
    b = route_from_track(track, near, assumed_roughness=assumed).route
    np.testing.assert_array_equal(a.s_m, b.s_m)
    np.testing.assert_array_equal(a.z_m, b.z_m)
