"""Pictures people read (issue 30, item 15): a long plan drawn as an overview, legends that
list only what is drawn, no curvature panel for a straight (s,z) route, any format matplotlib
writes; maps with start, end, direction, names, a speed scale from 0 and grey terrain."""

from __future__ import annotations

import numpy as np
import pytest

from conftest import ROUTES
from profileopt import load_vehicle, plan, read_route
from profileopt.core.profile import Profile
from profileopt.core.route import Route
from profileopt.terrain.ground_track import TrackRoute
from profileopt.viz.maps import DIRECTION_ARROWS, plan_map_figure
from profileopt.viz.plots import MAX_DRAWN_SEGMENTS, plot_profile, profile_figure


def _labels(fig) -> list[str]:  # noqa: ANN001
    return [text.get_text() for legend in fig.legends for text in legend.get_texts()]


def _ylabels(fig) -> list[str]:  # noqa: ANN001
    return [ax.get_ylabel() for ax in fig.axes]


def out_and_back() -> Route:
    """100 m east, a half circle of radius 20 m, 100 m back west: an out-and-back x,y route."""
    ds, r = 0.05, 20.0
    a = np.arange(0.0, 100.0, ds)
    turn = np.arange(0.0, np.pi, ds / r)
    x = np.concatenate([a, 100.0 + r * np.sin(turn), 100.0 - a])
    y = np.concatenate([np.zeros_like(a), r - r * np.cos(turn), np.full_like(a, 2 * r)])
    s = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(x), np.diff(y)))])
    return Route(s, 0.01 * np.sin(2 * np.pi * s / 7.0), x_m=x, y_m=y, source="u-turn.csv")


@pytest.fixture(scope="module")
def curb_plan() -> Profile:
    return plan(read_route(ROUTES / "curb.csv"), load_vehicle("atv"))


@pytest.fixture(scope="module")
def turn_plan() -> tuple[Route, Profile]:
    route = out_and_back()
    return route, plan(route, load_vehicle("atv"))


def long_profile(n: int = 25 * MAX_DRAWN_SEGMENTS) -> Profile:
    """A made-up plan of n segments over 50 km (only what a picture reads)."""
    s = np.linspace(0.0, 50_000.0, n + 1)
    speed = 10.0 + 5.0 * np.sin(s / 700.0) ** 2
    seg = np.full(n, 1.0)
    first = np.where(np.sin(s[:-1] / 2000.0) > 0.5, 12.0, 40.0)  # the force holds it on some stretches
    return Profile(
        s_m=s, speed_mps=speed, accel_mps2=np.zeros(n + 1), time_s=np.cumsum(np.full(n + 1, 1.0)),
        ri=0.1 * np.abs(np.sin(s / 300.0)), e_max_m=np.zeros(n + 1), force_n=np.zeros(n + 1),
        force_limit_n=np.full(n + 1, 5000.0), allowable_first_mps=first, allowable_largest_mps=first,
        speed_cap_mps=20.0 * seg, band_upper_mps=20.0 * seg, settings={"max_speed_mps": 20.0, "vehicle": "atv"},
        curvature_1pm=np.zeros(n + 1), grade_rad=0.01 * np.sin(s / 100.0),
        binding=np.where(speed > 12.0, "force", "jerk").astype(object),
    )


@pytest.mark.slow  # two plans
def test_an_sz_route_has_no_curvature_panel_an_xy_route_has(curb_plan: Profile, turn_plan) -> None:
    assert not any("curvature" in label for label in _ylabels(profile_figure(curb_plan)))
    assert any("grade" in label for label in _ylabels(profile_figure(curb_plan)))
    assert any("curvature" in label for label in _ylabels(profile_figure(turn_plan[1])))


def test_a_long_plan_is_drawn_as_an_overview() -> None:
    profile = long_profile(n=5 * MAX_DRAWN_SEGMENTS)
    fig = profile_figure(profile)
    # each quantity reduced to the stretches of the overview: no artist draws 50,000 points
    for ax in fig.axes:
        for line in ax.get_lines():
            assert np.asarray(line.get_xdata()).size <= 2 * MAX_DRAWN_SEGMENTS
    labels = _labels(fig)
    assert any(label.startswith("planned speed (lowest to highest in each") for label in labels), labels
    assert any("first" in label and "lowest in each" in label for label in labels), labels


def test_the_legend_lists_only_what_is_drawn() -> None:
    profile = long_profile(n=400)
    held_by_the_cap = Profile(**{**{f: getattr(profile, f) for f in profile.__dataclass_fields__},
                                 "allowable_first_mps": np.full(400, 30.0), "allowable_largest_mps": np.full(400, 30.0)})
    labels = _labels(profile_figure(held_by_the_cap))
    assert not any("allowable" in label for label in labels), labels
    assert any("allowable" in label for label in _labels(profile_figure(profile)))


def test_a_jpg_plot_is_a_jpeg(tmp_path) -> None:
    plot_profile(long_profile(n=50), tmp_path / "plan.jpg")  # before: PNG bytes in a .jpg file
    assert (tmp_path / "plan.jpg").read_bytes()[:3] == b"\xff\xd8\xff"


class _Slope:
    """A terrain grid: elevation rising to the east."""

    def elevation_at(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        return 0.05 * np.asarray(x, dtype=float)


def test_a_plan_map_names_the_route_and_vehicle_and_marks_start_end_and_direction(turn_plan) -> None:
    route, profile = turn_plan
    made = TrackRoute(route=route, crs_name="", track_x_m=route.x_m, track_y_m=route.y_m, terrain_kind="grid",
                      roughness_measured=True, density_per_m2=None, resolution="", gaps_m=np.zeros((0, 2)),
                      comments=(), notes=(), terrain=_Slope())
    fig = plan_map_figure(profile, made, route="u-turn.csv", vehicle="atv")
    title = fig.get_suptitle()
    assert "u-turn.csv" in title and "atv" in title
    labels = _labels(fig)
    assert {"start", "end", "direction of travel"} <= set(labels), labels
    ax = fig.axes[0]
    arrows = [child for child in ax.texts if getattr(child, "arrow_patch", None) is not None]
    assert len(arrows) == DIRECTION_ARROWS
    # out and back: some arrows point east, some west
    east = [a.xy[0] > a.xyann[0] for a in arrows]
    assert any(east) and not all(east)
    speed = next(c for c in ax.collections if c.get_cmap().name == "plasma")
    assert speed.get_clim()[0] == 0.0  # the speed scale starts at 0
    terrain = [im for im in ax.images]
    assert terrain and terrain[0].get_cmap().name == "Greys"  # never read as a speed


@pytest.mark.slow  # a plan and its simulation
def test_a_verification_legend_lists_no_window_over_the_limit_when_none_is(curb_plan: Profile) -> None:
    from profileopt import verify
    from profileopt.viz.plots import verification_figure

    result = verify(read_route(ROUTES / "curb.csv"), curb_plan, load_vehicle("atv"))
    assert result.windows.over_count == 0
    labels = [t.get_text() for ax in verification_figure(result).axes if ax.get_legend()
              for t in ax.get_legend().get_texts()]
    assert "window within the limit" in labels and "window over the limit" not in labels, labels
