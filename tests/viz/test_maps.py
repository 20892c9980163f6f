"""Maps people can read (issue 30, item 15): a legend lists only what is drawn and sits off
the data, the map fills the figure whatever the route's shape, a crawl on a long route shows,
labels stay inside the figure, one scale on both axes."""

from __future__ import annotations

import numpy as np
import pytest

from profileopt.core.profile import Profile
from profileopt.core.route import Route
from profileopt.terrain.ground_track import TrackRoute
from profileopt.viz.maps import (
    BINDING_MARKERS,
    MAX_MAP_PIECES,
    _origin,
    plan_map_figure,
    route_map_figure,
)
from profileopt.viz.plots import BINDING_COLOURS

#: UTM-like coordinates: seven digits, the kind whose labels were cut off at the left edge.
EAST, NORTH = 345_000.0, 5_095_000.0


def _made(route: Route, terrain: object = None, track: tuple[np.ndarray, np.ndarray] | None = None) -> TrackRoute:
    x, y = track if track is not None else (route.x_m, route.y_m)
    return TrackRoute(route=route, crs_name="WGS 84 / UTM zone 33N (EPSG:32633)", track_x_m=x, track_y_m=y,
                      terrain_kind="track", roughness_measured=False, density_per_m2=None, resolution="",
                      gaps_m=np.zeros((0, 2)), comments=(), notes=(), terrain=terrain)


def _route(x: np.ndarray, y: np.ndarray) -> Route:
    s = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(x), np.diff(y)))])
    return Route(s, 300.0 + 0.001 * s, x_m=x, y_m=y, source="made.csv")


def wavy(length_m: float = 50_000.0, step_m: float = 2.0) -> Route:
    """A 50 km route going north-east in wide bends."""
    t = np.arange(0.0, length_m, step_m) / length_m
    return _route(EAST + 30_000.0 * t + 1_500.0 * np.sin(14 * np.pi * t), NORTH + 30_000.0 * t)


def out_and_back(length_m: float = 26_000.0, step_m: float = 2.0) -> Route:
    """Out 26 km north in gentle bends, a hairpin, and back the same way: a map 9 times as tall as wide."""
    a = np.arange(0.0, length_m, step_m)
    x = EAST + 1_200.0 * np.sin(2 * np.pi * a / 13_000.0)
    x = np.concatenate([x, x[::-1] + 3.0])
    y = NORTH + np.concatenate([a, a[::-1]])
    return _route(x, y)


def u_turn() -> Route:
    """The short out-and-back over a DEM: 60 m east, a U-turn of radius 4 m, 60 m back west."""
    a = np.arange(0.0, 60.0, 0.05)
    turn = np.linspace(0.0, np.pi, 120)
    x = EAST + np.concatenate([a, 60.0 + 4.0 * np.sin(turn), a[::-1]])
    y = NORTH + 0.5 + np.concatenate([np.full_like(a, 8.0), 4.0 + 4.0 * np.cos(turn), np.full_like(a, 0.0)])
    return _route(x, y)


def profile_along(route: Route, speed: np.ndarray, binding: np.ndarray) -> Profile:
    """A made-up plan of ``route`` (only what a map reads) at the route's samples."""
    s = route.s_m - route.s_m[0]
    n = s.size - 1
    return Profile(
        s_m=s, speed_mps=speed, accel_mps2=np.zeros(n + 1), time_s=np.arange(n + 1.0), ri=np.zeros(n + 1),
        e_max_m=np.zeros(n + 1), force_n=np.zeros(n + 1), force_limit_n=np.full(n + 1, 5000.0),
        speed_cap_mps=np.full(n, 20.0), band_upper_mps=np.full(n, 20.0),
        settings={"max_speed_mps": 20.0, "vehicle": "atv"}, curvature_1pm=np.zeros(n + 1),
        grade_rad=np.zeros(n + 1), binding=binding.astype(object),
    )


def busy_plan(route: Route) -> Profile:
    """Speed 20 m/s, slower on rough stretches (down to 10.5 m/s), and hundreds of stretches held
    by force, jerk, accel and decel in turn: the 50 km plan whose marks hid its colours."""
    s = route.s_m - route.s_m[0]
    rough = np.sin(s / 900.0) > 0.3
    speed = np.where(rough, 20.0 - 6.0 * np.abs(np.sin(s / 900.0)), 20.0)
    speed[np.argmin(np.abs(s - 9_600.0))] = 10.5
    cycle = np.array(["force", "jerk", "jerk", "force", "accel", "decel"], dtype=object)
    binding = np.where(rough, cycle[(s // 37.0).astype(int) % cycle.size], "top_speed").astype(object)
    binding[0] = binding[-1] = "boundary"
    return profile_along(route, speed, binding)


def crawl_plan(route: Route) -> Profile:
    """20 m/s, braking into the hairpin at the far end to a 0.63 m/s crawl, and out again."""
    s = route.s_m - route.s_m[0]
    turn = 0.5 * s[-1]
    speed = np.minimum(20.0, np.sqrt(0.63 ** 2 + 2 * 2.0 * np.abs(s - turn)))
    speed = np.minimum(speed, np.sqrt(2 * 2.0 * s) + 1e-3)
    speed = np.minimum(speed, np.sqrt(2 * 2.0 * (s[-1] - s)))
    binding = np.where(speed < 19.99, "lateral", "top_speed").astype(object)
    binding[0] = binding[-1] = "boundary"
    return profile_along(route, speed, binding)


def _drawn(fig):  # noqa: ANN001, ANN202
    """The figure drawn with Agg: its pixels (RGB, rows from the top) and its renderer."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    if not isinstance(fig.canvas, FigureCanvasAgg):
        FigureCanvasAgg(fig)
    fig.canvas.draw()
    return np.asarray(fig.canvas.buffer_rgba())[..., :3].astype(int), fig.canvas.get_renderer()


def _maps(fig) -> list:  # noqa: ANN001
    """The map axes (those with a speed line or a route over x, y), not the colour bars or the elevation panel."""
    def axes(f):  # noqa: ANN001, ANN202
        return [*f.axes, *(a for sub in f.subfigs for a in axes(sub))]
    return [ax for ax in dict.fromkeys(axes(fig)) if ax.get_xlabel().startswith("x") and ax.get_ylabel().startswith("y")]


def _legends(fig) -> list:  # noqa: ANN001
    out = list(fig.legends)
    for sub in fig.subfigs:
        out += list(sub.legends)
    for ax in fig.axes:
        if ax.get_legend() is not None:
            out.append(ax.get_legend())
    return out


def _pixels_of(image: np.ndarray, box, colour: str, tolerance: int = 6) -> int:  # noqa: ANN001
    """How many pixels inside ``box`` (display units, y up) are ``colour``."""
    from matplotlib.colors import to_rgb

    height = image.shape[0]
    x0, x1 = int(np.ceil(box.x0)), int(np.floor(box.x1))
    y0, y1 = height - int(np.floor(box.y1)), height - int(np.ceil(box.y0))
    part = image[y0:y1, x0:x1]
    want = np.round(np.array(to_rgb(colour)) * 255).astype(int)
    return int(np.sum(np.all(np.abs(part - want) <= tolerance, axis=-1)))


def _equal_scale(ax) -> float:  # noqa: ANN001
    """Metres per pixel across over metres per pixel up (1: one scale on both axes)."""
    box = ax.get_window_extent()
    x0, x1 = ax.get_xlim()
    y0, y1 = ax.get_ylim()
    return ((x1 - x0) / box.width) / ((y1 - y0) / box.height)


@pytest.fixture(scope="module")
def long_map():  # noqa: ANN201
    route = wavy()
    profile = busy_plan(route)
    return profile, plan_map_figure(profile, _made(route), route="xyz50.csv", vehicle="atv")


def test_every_limit_the_legend_lists_has_marks_of_its_colour_on_the_map(long_map) -> None:
    _profile, fig = long_map
    image, _renderer = _drawn(fig)
    ax = _maps(fig)[0]
    labels = [t.get_text() for legend in _legends(fig) for t in legend.get_texts()]
    listed = [name for name in BINDING_MARKERS if any(t.startswith(f"{name} holds") for t in labels)]
    # before: force, accel and decel listed, their marks all hidden under hundreds of jerk marks
    assert {"force", "jerk"} <= set(listed), labels
    for name in listed:
        assert _pixels_of(image, ax.get_window_extent(), BINDING_COLOURS[name]) >= 5, name


def test_a_long_route_has_few_marks_apart_and_its_slow_colours_show(long_map) -> None:
    profile, fig = long_map
    ax = _maps(fig)[0]
    marks = [c for c in ax.collections if c.get_label().split(" ")[0] in BINDING_MARKERS]
    points = np.concatenate([c.get_offsets() for c in marks])
    assert 4 <= len(points) <= 60, len(points)  # before: hundreds, the line pale under their white edges
    gaps = np.hypot(*(points[:, None, :] - points[None, :, :]).transpose(2, 0, 1)) + np.eye(len(points)) * 1e9
    x0, x1 = ax.get_xlim()
    assert gaps.min() > 0.02 * (x1 - x0)  # no mark on another
    # the speed line: at most MAX_MAP_PIECES pieces, each in its lowest speed, the slowest on top
    line = next(c for c in ax.collections if c.get_cmap().name == "plasma")
    speeds = np.asarray(line.get_array())
    assert speeds.size <= MAX_MAP_PIECES
    assert speeds[-1] == pytest.approx(10.5) and np.all(np.diff(speeds) <= 0)
    assert line.get_clim()[0] == 0.0
    image, _renderer = _drawn(fig)
    from matplotlib import colormaps

    slow_colour = colormaps["plasma"](line.norm(10.5))
    assert _pixels_of(image, ax.get_window_extent(), slow_colour, tolerance=12) >= 3
    labels = [t.get_text() for legend in _legends(fig) for t in legend.get_texts()]
    assert any(t.startswith("slowest away from the ends: 10.5 m/s") for t in labels), labels


@pytest.fixture(scope="module")
def tall_map():  # noqa: ANN201
    route = out_and_back()
    profile = crawl_plan(route)
    return profile, plan_map_figure(profile, _made(route), route="oab50.gpx", vehicle="atv")


def test_a_tall_thin_route_fills_the_figure_and_its_crawl_is_enlarged(tall_map) -> None:
    profile, fig = tall_map
    _image, _renderer = _drawn(fig)
    maps = _maps(fig)
    assert len(maps) == 2  # the map, and the crawl at the hairpin enlarged beside it
    area = sum(ax.get_window_extent().width * ax.get_window_extent().height for ax in maps)
    assert area >= 0.4 * fig.bbox.width * fig.bbox.height  # before: two thirds of the figure blank
    for ax in maps:
        assert _equal_scale(ax) == pytest.approx(1.0, rel=0.02)
    overview, zoom = maps
    x0, x1 = overview.get_xlim()
    line_x, line_y = _line_xy(overview)
    assert x1 - x0 <= 1.05 * (np.ptp(line_x) + 0.1 * np.ptp(line_y))  # not widened into blank
    zx0, zx1 = zoom.get_xlim()
    zy0, zy1 = zoom.get_ylim()
    assert zx1 - zx0 < 200.0 and zy1 - zy0 < 200.0
    crawl = next(c for c in zoom.collections if c.get_cmap().name == "plasma")
    row = int(np.argmin(profile.speed_mps[1:-1])) + 1
    assert float(np.min(crawl.get_array())) == pytest.approx(profile.speed_mps[row])  # the crawl, in its colour
    assert zx0 < out_and_back().x_m[row] < zx1
    assert "enlarged" in zoom.get_title()


def _line_xy(ax) -> tuple[np.ndarray, np.ndarray]:  # noqa: ANN001
    """The x and y of the route's line on a map."""
    line = next(c for c in ax.collections if c.get_cmap().name == "plasma")
    points = np.concatenate(line.get_segments())
    return points[:, 0], points[:, 1]


def test_a_tall_map_keeps_start_end_arrows_title_and_scales(tall_map) -> None:
    _profile, fig = tall_map
    labels = [t.get_text() for legend in _legends(fig) for t in legend.get_texts()]
    assert {"start", "end", "direction of travel"} <= set(labels), labels
    assert "oab50.gpx" in fig.get_suptitle() and "atv" in fig.get_suptitle()
    overview = _maps(fig)[0]
    arrows = [t for t in overview.texts if getattr(t, "arrow_patch", None) is not None]
    north = [a.xy[1] > a.xyann[1] for a in arrows]
    assert any(north) and not all(north)  # out and back: both ways shown


def _overlaps(a, b) -> bool:  # noqa: ANN001
    return a.x0 < b.x1 and b.x0 < a.x1 and a.y0 < b.y1 and b.y0 < a.y1


@pytest.mark.parametrize("shape", ["wide", "tall"])
def test_a_route_map_legend_is_off_the_map_and_nothing_is_cut_off(shape: str) -> None:
    route = out_and_back() if shape == "tall" else u_turn()
    track = route.x_m[::5], route.y_m[::5]
    fig = route_map_figure(_made(route, terrain=_Slope(), track=track), title="oab.csv over dem.tif")
    _image, renderer = _drawn(fig)
    (ax,) = _maps(fig)
    map_box = ax.get_window_extent()
    legends = _legends(fig)
    assert legends
    for legend in legends:
        box = legend.get_window_extent(renderer)
        assert not _overlaps(box, map_box)  # before: on the route, the start over its own word
        assert box.x0 >= -1 and box.x1 <= fig.bbox.width + 1  # before: past the narrow axes, text clipped
    whole = fig.get_tightbbox(renderer)
    assert whole.x0 >= -0.02 and whole.y0 >= -0.02  # inches: the y label and the ticks inside the figure
    assert whole.x1 <= fig.get_figwidth() + 0.02 and whole.y1 <= fig.get_figheight() + 0.02
    assert ax.yaxis.label.get_window_extent(renderer).x0 >= 0
    assert _equal_scale(ax) == pytest.approx(1.0, rel=0.02)
    # the map and the elevation panel fill the figure (a tall map stands beside the panel)
    panels = [ax, next(a for sub in fig.subfigs for a in sub.axes if "ground elevation" in a.get_ylabel())]
    area = sum(a.get_window_extent().width * a.get_window_extent().height for a in panels)
    assert area >= 0.4 * fig.bbox.width * fig.bbox.height
    # the track's points are drawn under the route, never hiding it
    points = next(line for line in ax.get_lines() if line.get_label().startswith("track points"))
    route_line = next(line for line in ax.get_lines() if line.get_label().startswith("route"))
    assert points.get_zorder() < route_line.get_zorder()


def test_a_thousand_track_points_are_thinned() -> None:
    route = out_and_back()
    track = route.x_m[::26], route.y_m[::26]  # 1,000 points
    fig = route_map_figure(_made(route, track=track))
    (ax,) = _maps(fig)
    points = next(line for line in ax.get_lines() if line.get_label().startswith("track points"))
    assert len(points.get_xdata()) < len(track[0]) / 2
    assert "of 1,000 shown" in points.get_label()


class _Slope:
    """A terrain grid: elevation rising to the east."""

    def elevation_at(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        return 0.05 * (np.asarray(x, dtype=float) - EAST)


@pytest.mark.slow
def test_a_plan_map_over_utm_has_its_labels_and_legend_inside_the_figure(long_map, tall_map) -> None:
    route = u_turn()  # over a DEM, y ticks with decimals: "y (m)" was cut off at the left edge
    s = route.s_m
    speed = np.minimum(np.minimum(np.sqrt(4 * s), np.sqrt(4 * (s[-1] - s))), 4.0 + 0.1 * np.abs(s - 0.5 * s[-1]))
    binding = np.where(speed < 10, "lateral", "top_speed").astype(object)
    dem = plan_map_figure(profile_along(route, speed, binding), _made(route, terrain=_Slope()), route="oab.csv")
    for _profile, fig in (long_map, tall_map, (None, dem)):
        _image, renderer = _drawn(fig)
        whole = fig.get_tightbbox(renderer)
        assert whole.x0 >= -0.02 and whole.y0 >= -0.02
        assert whole.x1 <= fig.get_figwidth() + 0.02 and whole.y1 <= fig.get_figheight() + 0.02
        for ax in _maps(fig):
            assert ax.yaxis.label.get_window_extent(renderer).x0 >= 0
            for legend in _legends(fig):
                assert not _overlaps(legend.get_window_extent(renderer), ax.get_window_extent())
        maps = _maps(fig)
        for left, right in zip(maps, maps[1:]):  # the enlarged panel's labels clear of the map beside it
            assert right.get_tightbbox(renderer).x0 >= left.get_window_extent().x1


def test_long_coordinates_are_told_from_a_round_origin() -> None:
    assert _origin(5_099_997.5, 5_100_015.0) == 5_099_990.0
    assert _origin(393_780.0, 393_945.0) == 393_700.0
    assert _origin(-1_500.0, 31_000.0) == 0.0  # short numbers: as they are
    route = out_and_back()
    fig = route_map_figure(_made(route))
    (ax,) = _maps(fig)
    _drawn(fig)
    assert "5,090,000" in ax.get_ylabel()
    assert all(len(t.get_text()) <= 6 for t in ax.get_yticklabels())
