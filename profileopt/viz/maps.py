"""Maps: a route drawn over its terrain, plain or coloured by the planned speed.

Like :mod:`profileopt.viz.plots`, each function draws on a bare matplotlib ``Figure`` (no
pyplot, no window, no global state) and writes its PNG atomically; matplotlib is imported
only when a map is drawn.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .plots import envelope_trace, plan_title, save_figure

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


#: Bins of a long route's elevation panel (its lowest and highest in each), beyond four
#: samples per bin.
MAX_ELEVATION_POINTS = 2000
#: Direction arrows drawn along a route (evenly spaced), beside it on the right of travel so
#: that the two ways of an out-and-back track show apart.
DIRECTION_ARROWS = 10


def _terrain_background(ax: Any, fig: "Figure", terrain: Any, view: tuple[float, float, float, float],
                        cmap: str = "terrain") -> None:
    """The terrain under the map: a DEM or OpenCRG grid as an image, a point cloud's ground
    points (all points if it is not classified) as dots, coloured by elevation (``cmap``), with
    a colour bar."""
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
            art = ax.scatter(terrain.x_m[inside], terrain.y_m[inside], c=terrain.z_m[inside], s=2, cmap=cmap,
                             linewidths=0, rasterized=True)
    else:  # a grid: sample it on a raster over the view (works for rotated OpenCRG surfaces too)
        xs = np.linspace(x0, x1, 400)
        ys = np.linspace(y0, y1, 400)
        gx, gy = np.meshgrid(xs, ys)
        z = terrain.elevation_at(gx.ravel(), gy.ravel()).reshape(gx.shape)
        if np.isfinite(z).any():
            art = ax.imshow(z, extent=(x0, x1, y0, y1), origin="lower", cmap=cmap, interpolation="nearest")
    if art is not None:
        fig.colorbar(art, ax=ax, label="terrain elevation (m)", shrink=0.8)


def _start_end_direction(ax: Any, x: np.ndarray, y: np.ndarray, colour: str) -> None:
    """Mark the start (filled triangle) and the end (hollow square) of the path x, y, and
    :data:`DIRECTION_ARROWS` arrows along it, each set a little to the right of travel."""
    ax.plot(x[0], y[0], "^", color=colour, ms=10, markeredgecolor="white", zorder=6, label="start")
    ax.plot(x[-1], y[-1], "s", color="none", ms=12, markeredgecolor=colour, markeredgewidth=2.2, zorder=6,
            label="end")
    step = np.hypot(np.diff(x), np.diff(y))
    s = np.concatenate([[0.0], np.cumsum(step)])
    if x.size < 3 or s[-1] <= 0:
        return
    x0, x1 = ax.get_xlim()
    y0, y1 = ax.get_ylim()
    size = max(abs(x1 - x0), abs(y1 - y0))
    for at in s[-1] * (np.arange(1, DIRECTION_ARROWS + 1) - 0.5) / DIRECTION_ARROWS:
        i = int(np.clip(np.searchsorted(s, at), 1, x.size - 1))
        dx, dy = x[i] - x[i - 1], y[i] - y[i - 1]
        norm = np.hypot(dx, dy)
        if norm == 0:
            continue
        ux, uy = dx / norm, dy / norm
        px, py = x[i] + 0.02 * size * uy, y[i] - 0.02 * size * ux  # the right of travel
        ax.annotate("", xy=(px + 0.015 * size * ux, py + 0.015 * size * uy),
                    xytext=(px - 0.015 * size * ux, py - 0.015 * size * uy),
                    arrowprops={"arrowstyle": "-|>", "color": colour, "lw": 1.6, "shrinkA": 0, "shrinkB": 0},
                    zorder=6)
    ax.plot([], [], marker=r"$\rightarrow$", ls="none", color=colour, ms=12, label="direction of travel")


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
    _map_axes(ax_map, result)
    _start_end_direction(ax_map, route.x_m, route.y_m, "black")
    ax_map.legend(loc="best", fontsize="small")
    if route.s_m.size > 4 * MAX_ELEVATION_POINTS:  # a long route: its lowest and highest in each bin
        xs, lo, hi = envelope_trace(route.s_m, route.z_m, MAX_ELEVATION_POINTS)
        ax_z.fill_between(xs, lo, hi, color="crimson", lw=0.8)  # the edge keeps a flat stretch visible
    else:
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
        Output file (PNG, or the format its extension names: :func:`profileopt.viz.plots.save_figure`).
    title : str, optional
        The picture's title.
    """
    save_figure(route_map_figure(result, title=title), path)


def plan_map_figure(profile: "Profile", result: "TrackRoute", *, title: str | None = None, route: str | None = None,
                    vehicle: str | None = None) -> "Figure":
    """The route over its terrain coloured by the planned speed, with a mark where each
    limit holds the speed (the profile's ``binding`` column), nothing written.

    Parameters
    ----------
    profile : Profile
        A plan of ``result.route`` (:func:`profileopt.plan`).
    result : TrackRoute
        The route made from the track (its map coordinates and terrain).
    title : str, optional
        Replaces the whole title.
    route : str, optional
        The route's name for the title (e.g. its file name).
    vehicle : str, optional
        The vehicle's name for the title; default the one the profile records.

    Returns
    -------
    matplotlib.figure.Figure

    Notes
    -----
    The terrain is drawn in greys, so that its colours cannot be read as speeds; the speed's
    colour bar starts at 0 m/s.
    """
    from matplotlib.collections import LineCollection
    from matplotlib.figure import Figure

    from ..core.binding import BINDING_NAMES
    from .plots import BINDING_COLOURS

    path = result.route
    fig = Figure(figsize=(11, 9), layout="constrained")
    ax = fig.subplots()
    _terrain_background(ax, fig, result.terrain, _view(result), cmap="Greys")
    x = np.interp(profile.s_m, path.s_m - path.s_m[0], path.x_m)
    y = np.interp(profile.s_m, path.s_m - path.s_m[0], path.y_m)
    speed = profile.speed_mps
    pieces = np.stack([np.column_stack([x[:-1], y[:-1]]), np.column_stack([x[1:], y[1:]])], axis=1)
    line = LineCollection(pieces, array=0.5 * (speed[:-1] + speed[1:]), cmap="plasma", linewidths=5)
    line.set_clim(0.0, max(float(np.max(speed)), 1e-3))  # from 0: a colour is a speed, not a share of the range
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
    _map_axes(ax, result)
    _start_end_direction(ax, x, y, "black")
    # below the map: "best" cannot see the route (a LineCollection) and covered its end
    fig.legend(*ax.get_legend_handles_labels(), loc="outside lower center", ncols=3, fontsize="small")
    if title is None:
        title = (f"{plan_title(profile, route=route, vehicle=vehicle)}, planned speed along the route: "
                 f"{profile.distance_m:.0f} m in {profile.travel_time_s:.0f} s")
    fig.suptitle(title)
    return fig


def plot_plan_map(profile: "Profile", result: "TrackRoute", path: str | Path, *, title: str | None = None,
                  route: str | None = None, vehicle: str | None = None) -> None:
    """Draw :func:`plan_map_figure` into a PNG, atomically.

    Parameters
    ----------
    profile : Profile
        A plan of ``result.route``.
    result : TrackRoute
        The route made from the track.
    path : str or pathlib.Path
        Output file (PNG, or the format its extension names:
        :func:`profileopt.viz.plots.save_figure`).
    title : str, optional
        Replaces the whole title.
    route, vehicle : str, optional
        Names for the title (:func:`plan_map_figure`).
    """
    save_figure(plan_map_figure(profile, result, title=title, route=route, vehicle=vehicle), path)
