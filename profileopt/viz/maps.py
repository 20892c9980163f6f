"""Maps: a route drawn over its terrain, plain or coloured by the planned speed.

Like :mod:`profileopt.viz.plots`, each function draws on a bare matplotlib ``Figure`` (no
pyplot, no window, no global state) and writes its PNG atomically; matplotlib is imported
only when a map is drawn.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..io.atomic import atomic_path

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from ..core.profile import Profile
    from ..terrain.ground_track import TrackRoute

__all__ = ["route_map_figure", "plot_route_map", "plan_map_figure", "plot_plan_map"]

#: Most terrain points drawn as the background of a map (a random, seeded subset beyond it):
#: enough to show the ground's shape, few enough to draw in a second.
MAX_BACKGROUND_POINTS = 200_000


def _view(result: "TrackRoute") -> tuple[float, float, float, float]:
    """The map's extent: the route and its track with a margin of 5 % of their size (at least 5 m)."""
    x = np.concatenate([result.route.x_m, result.track_x_m])
    y = np.concatenate([result.route.y_m, result.track_y_m])
    pad = max(0.05 * max(np.ptp(x), np.ptp(y)), 5.0)
    return x.min() - pad, x.max() + pad, y.min() - pad, y.max() + pad


def _terrain_background(ax: Any, fig: "Figure", terrain: Any, view: tuple[float, float, float, float]) -> None:
    """The terrain under the map: a DEM or OpenCRG grid as an image, a point cloud's ground
    points (all points if it is not classified) as dots, coloured by elevation, with a colour bar."""
    x0, x1, y0, y1 = view
    art = None
    if terrain is None:
        return
    if hasattr(terrain, "classification"):
        ground = terrain.classification == 2 if terrain.is_classified else True  # vegetation and noise hide it
        inside = np.flatnonzero((terrain.x_m >= x0) & (terrain.x_m <= x1) & (terrain.y_m >= y0) & (terrain.y_m <= y1)
                                & ground)
        if inside.size > MAX_BACKGROUND_POINTS:
            inside = np.sort(np.random.default_rng(0).choice(inside, MAX_BACKGROUND_POINTS, replace=False))
        if inside.size:
            art = ax.scatter(terrain.x_m[inside], terrain.y_m[inside], c=terrain.z_m[inside], s=2, cmap="terrain",
                             linewidths=0, rasterized=True)
    else:  # a grid: sample it on a raster over the view (works for rotated OpenCRG surfaces too)
        xs = np.linspace(x0, x1, 400)
        ys = np.linspace(y0, y1, 400)
        gx, gy = np.meshgrid(xs, ys)
        z = terrain.elevation_at(gx.ravel(), gy.ravel()).reshape(gx.shape)
        if np.isfinite(z).any():
            art = ax.imshow(z, extent=(x0, x1, y0, y1), origin="lower", cmap="terrain", interpolation="nearest")
    if art is not None:
        fig.colorbar(art, ax=ax, label="terrain elevation (m)", shrink=0.8)


def _map_axes(ax: Any, result: "TrackRoute") -> None:
    ax.set_aspect("equal")
    x0, x1, y0, y1 = _view(result)
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_xlabel(f"x (m), {result.crs_name}" if result.crs_name else "x (m)", fontsize="small")
    ax.set_ylabel("y (m)")
    ax.ticklabel_format(useOffset=False, style="plain")
    ax.tick_params(labelsize="small")


def route_map_figure(result: "TrackRoute", *, title: str | None = None) -> "Figure":
    """The track over its terrain and the route's elevation along it (nothing written).

    Parameters
    ----------
    result : TrackRoute
        A route made by :func:`profileopt.terrain.ground_track.route_from_track`.
    title : str, optional
        The picture's title.

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.figure import Figure

    fig = Figure(figsize=(10, 10), layout="constrained")
    ax_map, ax_z = fig.subplots(2, 1, height_ratios=[3, 1])
    _terrain_background(ax_map, fig, result.terrain, _view(result))
    route = result.route
    ax_map.plot(route.x_m, route.y_m, color="crimson", lw=1.5, label=f"route, a sample every "
                f"{route.s_m[1] - route.s_m[0]:.3g} m")
    ax_map.plot(result.track_x_m, result.track_y_m, "o", color="black", ms=2.5, label="track points")
    ax_map.plot(route.x_m[0], route.y_m[0], "^", color="crimson", ms=9, label="start")
    _map_axes(ax_map, result)
    ax_map.legend(loc="best", fontsize="small")
    ax_z.plot(route.s_m, route.z_m, color="crimson", lw=0.8)
    for start, end in result.gaps_m:
        ax_z.axvspan(start, end, color="orange", alpha=0.4, lw=0)
    ax_z.set_xlabel("distance along the route s (m)")
    ax_z.set_ylabel("ground elevation z (m)")
    ax_z.grid(True, alpha=0.3)
    rough = (f"roughness assumed: {route.assumed_roughness.label}" if route.assumed_roughness is not None
             else "roughness measured" if result.roughness_measured else "")
    gaps = f"; {len(result.gaps_m)} gaps bridged (orange)" if len(result.gaps_m) else ""
    ax_z.set_title(f"{result.terrain_kind}: {rough}{gaps}", fontsize="small")
    fig.suptitle(title or "route over its terrain")
    return fig


def plot_route_map(result: "TrackRoute", path: str | Path, *, title: str | None = None) -> None:
    """Draw :func:`route_map_figure` into a PNG, atomically.

    Parameters
    ----------
    result : TrackRoute
        A route made by :func:`profileopt.terrain.ground_track.route_from_track`.
    path : str or pathlib.Path
        Output PNG file.
    title : str, optional
        The picture's title.
    """
    fig = route_map_figure(result, title=title)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110, format="png")


def plan_map_figure(profile: "Profile", result: "TrackRoute", *, title: str | None = None) -> "Figure":
    """The route over its terrain coloured by the planned speed, with a mark where each
    limit holds the speed (the profile's ``binding`` column), nothing written.

    Parameters
    ----------
    profile : Profile
        A plan of ``result.route`` (:func:`profileopt.plan`).
    result : TrackRoute
        The route made from the track (its map coordinates and terrain).
    title : str, optional
        The picture's title.

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.collections import LineCollection
    from matplotlib.figure import Figure

    from ..core.binding import BINDING_NAMES
    from .plots import BINDING_COLOURS

    route = result.route
    fig = Figure(figsize=(11, 9), layout="constrained")
    ax = fig.subplots()
    _terrain_background(ax, fig, result.terrain, _view(result))
    x = np.interp(profile.s_m, route.s_m - route.s_m[0], route.x_m)
    y = np.interp(profile.s_m, route.s_m - route.s_m[0], route.y_m)
    speed = profile.speed_mps
    pieces = np.stack([np.column_stack([x[:-1], y[:-1]]), np.column_stack([x[1:], y[1:]])], axis=1)
    line = LineCollection(pieces, array=0.5 * (speed[:-1] + speed[1:]), cmap="plasma", linewidths=5)
    ax.add_collection(line)
    fig.colorbar(line, ax=ax, label="planned speed (m/s)", shrink=0.8)
    if profile.binding is not None:
        # one mark at the start of each stretch that a limit holds (where the binding limit changes)
        change = np.flatnonzero(np.concatenate([[True], profile.binding[1:] != profile.binding[:-1]]))
        markers = dict(zip(BINDING_NAMES, "osD^v<>ph*X"))
        for name in BINDING_NAMES:
            where = change[profile.binding[change] == name]
            if where.size:
                ax.scatter(x[where], y[where], marker=markers[name], s=40, color=BINDING_COLOURS[name],
                           edgecolors="white", linewidths=0.7, zorder=3,
                           label="the start or end speed" if name == "boundary" else f"{name} holds the speed from here")
    ax.plot(x[0], y[0], "^", color="black", ms=9, zorder=4, label="start")
    _map_axes(ax, result)
    # below the map: "best" cannot see the route (a LineCollection) and covered its end
    fig.legend(*ax.get_legend_handles_labels(), loc="outside lower center", ncols=3, fontsize="small")
    fig.suptitle(title or f"planned speed along the route: {profile.distance_m:.0f} m in {profile.travel_time_s:.0f} s")
    return fig


def plot_plan_map(profile: "Profile", result: "TrackRoute", path: str | Path, *, title: str | None = None) -> None:
    """Draw :func:`plan_map_figure` into a PNG, atomically.

    Parameters
    ----------
    profile : Profile
        A plan of ``result.route``.
    result : TrackRoute
        The route made from the track.
    path : str or pathlib.Path
        Output PNG file.
    title : str, optional
        The picture's title.
    """
    fig = plan_map_figure(profile, result, title=title)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110, format="png")
