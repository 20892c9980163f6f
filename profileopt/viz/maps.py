"""Maps: a route drawn over its terrain, plain or coloured by the planned speed.

Like :mod:`profileopt.viz.plots`, each function draws on a bare matplotlib ``Figure`` (no
pyplot, no window, no global state) and writes its PNG atomically; matplotlib is imported
only when a map is drawn.

A map keeps x and y to one scale and fits the figure to the route's extent: the figure's
size, and for a long thin route the panel beside or below the map, are chosen from it, so
that the map fills its part of the figure. Legends sit outside the maps, never on the
route. Coordinates too long to read (UTM) are told from a round origin that the axis label
states. A long plan is drawn in at most :data:`MAX_MAP_PIECES` pieces, each in the colour
of its lowest speed and the slowest on top, with marks of what holds the speed at least
:data:`MARK_SPACING` of the map apart.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable

import numpy as np

from .plots import bin_reduce, envelope_trace, plan_title, save_figure

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure
    from matplotlib.gridspec import GridSpec

    from ..core.profile import Profile
    from ..core.route import Route
    from ..terrain.ground_track import TrackRoute

__all__ = ["route_map_figure", "plot_route_map", "plan_map_figure", "plot_plan_map"]

#: Most terrain points drawn as the background of a map (a random, seeded subset beyond it):
#: enough to show the ground's shape, few enough to draw in a second.
MAX_BACKGROUND_POINTS = 200_000
#: Bins of a long route's elevation panel (its lowest and highest in each), beyond four
#: samples per bin.
MAX_ELEVATION_POINTS = 2000
#: Direction arrows drawn along a route (evenly spaced), beside it on the right of travel so
#: that the two ways of an out-and-back track show apart.
DIRECTION_ARROWS = 10
#: Most pieces of a plan map's speed line: a longer plan is cut into this many equal
#: stretches, each drawn in the colour of its lowest speed (a crawl stays in sight).
MAX_MAP_PIECES = 3000
#: Most vertices of a map's line (the route's samples beyond it are thinned evenly).
MAX_LINE_VERTICES = 60_000
#: Least distance between two marks of what holds the speed, as a share of the map's longer
#: side: on a long route only some stretches are marked (the legend says how many), so that
#: the marks never hide the speed's colours or each other.
MARK_SPACING = 0.03
#: Least distance between two track points drawn on a route map, as a share of its longer side.
TRACK_POINT_SPACING = 0.006
#: A map more than this many times as tall as wide (or as wide as tall) is laid out beside
#: (or above) the other panels instead of over them.
ELONGATED = 2.5
#: On an elongated plan map, a slow stretch smaller than this share of the map's longer side
#: is also drawn enlarged in a panel of its own.
ZOOM_SHARE = 0.02
#: Least half-width (m) of that enlarged panel.
ZOOM_MIN_HALF_M = 20.0

#: The mark of each value of the binding column (its colour is plots.BINDING_COLOURS').
BINDING_MARKERS = {"force": "o", "speed_limit": "s", "top_speed": "D", "lateral": "^", "friction": "v",
                   "accel": "<", "decel": ">", "power": "p", "jerk": "h", "boundary": "*", "step": "X",
                   "simulated": "P"}


def _view(result: "TrackRoute") -> tuple[float, float, float, float]:
    """The map's extent: the route and its track with a margin of 5 % of their size (at least 5 m)."""
    x = np.concatenate([result.route.x_m, result.track_x_m])
    y = np.concatenate([result.route.y_m, result.track_y_m])
    pad = max(0.05 * max(np.ptp(x), np.ptp(y)), 5.0)
    return x.min() - pad, x.max() + pad, y.min() - pad, y.max() + pad


def _aspect(view: tuple[float, float, float, float]) -> float:
    """Height over width of a view."""
    x0, x1, y0, y1 = view
    return (y1 - y0) / max(x1 - x0, 1e-9)


def _origin(lo: float, hi: float) -> float:
    """A round origin for the tick labels of an axis from ``lo`` to ``hi`` (m): 0 for numbers
    short enough to read, else ``lo`` rounded down to a power of ten no larger than the span
    (UTM 5099997.5 to 5100015 reads 7.5 to 25 from 5099990)."""
    span = hi - lo
    if span <= 0 or max(abs(lo), abs(hi)) < 1e5:
        return 0.0
    step = 10.0 ** math.floor(math.log10(span))
    return math.floor(lo / step) * step


def _tick_text(value: float) -> str:
    """A tick label: the number to the micrometre, trailing zeros dropped, a true minus sign."""
    value = round(value, 6)
    value = 0.0 if value == 0 else value
    return f"{value:.6f}".rstrip("0").rstrip(".").replace("-", "\N{MINUS SIGN}")


def _map_axes(ax: "Axes", view: tuple[float, float, float, float], crs_name: str) -> None:
    """One scale on both axes (the view grows to fill the axes' place, never shrinks), and tick
    labels told from a round origin when the coordinates are long (the label states it)."""
    from matplotlib.ticker import FuncFormatter

    x0, x1, y0, y1 = view
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    # one scale on both axes: _fit widens the view to the shape of the axes' place. (An aspect
    # fixed by matplotlib would shrink the axes inside their place, and the constrained layout,
    # which measures the labels from the shrunk axes, then lets them overlap their neighbours.)
    ax._profileopt_view = view  # noqa: SLF001  (the view asked for, for _fit)
    labels = []
    for axis, lo, hi, name in ((ax.xaxis, x0, x1, "x"), (ax.yaxis, y0, y1, "y")):
        origin = _origin(lo, hi)
        axis.set_major_formatter(FuncFormatter(lambda value, _pos, o=origin: _tick_text(value - o)))
        text = f"{name} (m)" if origin == 0 else f"{name} \N{MINUS SIGN} {origin:,.0f} (m)"
        labels.append(text.replace(" ", "\N{NO-BREAK SPACE}"))  # kept on one line by _fit's wrapping
    ax.set_xlabel(labels[0] + (f", {crs_name}" if crs_name else ""), fontsize="small")
    ax.set_ylabel(labels[1], fontsize="small")
    ax.tick_params(labelsize="small")


def _terrain_background(ax: "Axes", terrain: Any, view: tuple[float, float, float, float], cmap: str = "terrain",
                        clim: tuple[float, float] | None = None) -> Any:
    """The terrain under the map: a DEM or OpenCRG grid as an image, a point cloud's ground
    points (all points if it is not classified) as dots, coloured by elevation (``cmap``,
    between ``clim`` if given). Returns the artist for a colour bar (None: nothing drawn)."""
    if terrain is None:
        return None
    x0, x1, y0, y1 = view
    grow = 0.25 * max(x1 - x0, y1 - y0)  # the view may be widened to fill the axes (_fit)
    x0, x1, y0, y1 = x0 - grow, x1 + grow, y0 - grow, y1 + grow
    art = None
    if hasattr(terrain, "classification"):
        ground = terrain.classification == 2 if terrain.is_classified else True  # vegetation and noise hide it
        inside = np.flatnonzero((terrain.x_m >= x0) & (terrain.x_m <= x1) & (terrain.y_m >= y0) & (terrain.y_m <= y1)
                                & ground)
        if inside.size > MAX_BACKGROUND_POINTS:
            inside = np.sort(np.random.default_rng(0).choice(inside, MAX_BACKGROUND_POINTS, replace=False))
        if inside.size:
            art = ax.scatter(terrain.x_m[inside], terrain.y_m[inside], c=terrain.z_m[inside], s=2, cmap=cmap,
                             linewidths=0, rasterized=True, zorder=1)
    else:  # a grid: sample it on a raster over the view (works for rotated OpenCRG surfaces too)
        xs = np.linspace(x0, x1, 400)
        ys = np.linspace(y0, y1, 400)
        gx, gy = np.meshgrid(xs, ys)
        z = terrain.elevation_at(gx.ravel(), gy.ravel()).reshape(gx.shape)
        if np.isfinite(z).any():
            art = ax.imshow(z, extent=(x0, x1, y0, y1), origin="lower", cmap=cmap, interpolation="nearest",
                            zorder=1, aspect="auto")  # one scale on both axes by _fit, not by matplotlib
    if art is not None and clim is not None:
        art.set_clim(*clim)
    return art


def _start_end(ax: "Axes", x: np.ndarray, y: np.ndarray, colour: str, *, label: bool = True) -> None:
    """Mark the start (filled triangle) and the end (hollow square) of the path x, y."""
    ax.plot(x[0], y[0], "^", color=colour, ms=10, markeredgecolor="white", zorder=6,
            label="start" if label else None)
    ax.plot(x[-1], y[-1], "s", color="none", ms=12, markeredgecolor=colour, markeredgewidth=2.2, zorder=6,
            label="end" if label else None)


def _arrows(ax: "Axes", x: np.ndarray, y: np.ndarray, colour: str, size: float, count: int = DIRECTION_ARROWS,
            *, label: bool = True) -> int:
    """``count`` arrows evenly along the path x, y, each set a little to the right of travel
    (``size``: the map's longer side, m); returns how many were drawn."""
    step = np.hypot(np.diff(x), np.diff(y))
    s = np.concatenate([[0.0], np.cumsum(step)])
    if x.size < 3 or s[-1] <= 0:
        return 0
    drawn = 0
    for at in s[-1] * (np.arange(1, count + 1) - 0.5) / count:
        i = int(np.clip(np.searchsorted(s, at), 1, x.size - 1))
        dx, dy = x[i] - x[i - 1], y[i] - y[i - 1]
        norm = np.hypot(dx, dy)
        if norm == 0:
            continue
        ux, uy = dx / norm, dy / norm
        px, py = x[i] + 0.025 * size * uy, y[i] - 0.025 * size * ux  # the right of travel
        ax.annotate("", xy=(px + 0.015 * size * ux, py + 0.015 * size * uy),
                    xytext=(px - 0.015 * size * ux, py - 0.015 * size * uy),
                    arrowprops={"arrowstyle": "-|>", "color": colour, "lw": 1.6, "shrinkA": 0, "shrinkB": 0},
                    zorder=6)
        drawn += 1
    if drawn and label:  # a legend entry for the arrows (an annotation has none of its own)
        ax.plot([], [], marker=r"$\rightarrow$", ls="none", color=colour, ms=12, label="direction of travel")
    return drawn


def _agg(fig: "Figure") -> None:
    """Give the figure an Agg canvas (to measure text), whatever backend the caller chose."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    if not isinstance(fig.canvas, FigureCanvasAgg):
        FigureCanvasAgg(fig)


def _fit(fig: "Figure", panels: list[tuple["Axes", Callable[[float, float], float]]], free: str,
         bounds: tuple[float, float], *, grid: "GridSpec | None" = None,
         resized: Callable[[float, float], None] | None = None) -> None:
    """Choose the figure's size along ``free`` ("width" or "height", within ``bounds``, inches)
    so that each panel's place has the length its target wants along it (given the place's
    width and height, inches), as the constrained layout lays it out. With ``grid``, the
    panels are its rows or columns and their ratios follow; ``resized(width, height)`` is
    called after each change (to keep other parts of the figure at a set size)."""
    _agg(fig)
    engine = fig.get_layout_engine()
    along = 0 if free == "width" else 1
    for _ in range(5):
        engine.execute(fig)
        size = fig.get_size_inches()
        places = [_inches(ax) for ax, _target in panels]
        _wrap_labels(fig, [ax for ax, _target in panels])  # a label no wider than its map
        have = [place[along] for place in places]
        want = [max(target(*place), 0.3) for (_ax, target), place in zip(panels, places)]
        new = float(np.clip(size[along] + sum(want) - sum(have), *bounds))
        if grid is not None and len(panels) > 1:
            ratios = (grid.get_width_ratios() if free == "width" else grid.get_height_ratios()) or [1.0] * len(panels)
            ratios = [r * w / max(h, 1e-3) for r, w, h in zip(ratios, want, have)]
            (grid.set_width_ratios if free == "width" else grid.set_height_ratios)(ratios)
        if abs(new - size[along]) < 0.01 and all(abs(w - h) < 0.05 for w, h in zip(want, have)):
            break
        size[along] = new
        fig.set_size_inches(size)
        if resized is not None:
            resized(*size)
    for _ in range(4):  # the views widened, their ticks and so the layout change a little: again
        engine.execute(fig)
        _wrap_labels(fig, [ax for ax, _target in panels])
        engine.execute(fig)
        if _fill_views(fig) < 1e-4:
            break


def _inches(ax: "Axes") -> tuple[float, float]:
    """The width and height of the axes' place in the figure, inches (as last laid out)."""
    box = ax.get_position(original=True).transformed(ax.get_figure(root=False).transSubfigure)
    dpi = ax.get_figure(root=True).dpi
    return box.width / dpi, box.height / dpi


def _all_axes(fig: "Figure") -> list["Axes"]:
    """The figure's axes and its subfigures'."""
    return [*fig.get_axes(), *(ax for sub in fig.subfigs for ax in _all_axes(sub))]


def _wrap_labels(fig: "Figure", maps: list["Axes"]) -> None:
    """Break each map's x label into lines no wider than the map (a narrow map's CRS name)."""
    import textwrap

    for ax in maps:
        chars = max(14, int(_inches(ax)[0] * 13))
        ax.set_xlabel("\n".join(textwrap.wrap(ax.get_xlabel().replace("\n", " "), chars, break_long_words=False)))


def _fill_views(fig: "Figure") -> float:
    """Widen each map's view (``_map_axes``) to the shape of its place, so that a metre is as
    long across as up and nothing is blank beside the map; returns the largest relative
    change of a view's width or height."""
    change = 0.0
    for ax in _all_axes(fig):
        view = getattr(ax, "_profileopt_view", None)
        if view is None:
            continue
        width, height = _inches(ax)
        want = height / max(width, 1e-9)
        x0, x1, y0, y1 = view
        cx, cy, w, h = 0.5 * (x0 + x1), 0.5 * (y0 + y1), x1 - x0, y1 - y0
        if h / w < want:
            h = w * want
        else:
            w = h / want
        old = ax.get_xlim(), ax.get_ylim()
        change = max(change, abs(w / (old[0][1] - old[0][0]) - 1), abs(h / (old[1][1] - old[1][0]) - 1))
        ax.set_xlim(cx - 0.5 * w, cx + 0.5 * w)
        ax.set_ylim(cy - 0.5 * h, cy + 0.5 * h)
    return change


def _legend_below(fig: "Figure", handles: list, labels: list[str]) -> Any:
    """A legend below the figure's panels, in as many columns (3 at most) as its width holds."""
    renderer = fig.canvas.get_renderer()
    for columns in (3, 2, 1):
        legend = fig.legend(handles, labels, loc="outside lower center", ncols=columns, fontsize="small")
        if columns == 1 or legend.get_window_extent(renderer).width <= 0.97 * fig.bbox.width:
            return legend
        legend.remove()
    return None


def _wrapped(text: str, width_in: float) -> str:
    """A title broken into lines that fit a figure ``width_in`` inches wide."""
    import textwrap

    return "\n".join(textwrap.wrap(text, max(30, int(width_in * 10.5)))) or text


def _thinned_track(result: "TrackRoute", size: float) -> tuple[np.ndarray, str]:
    """The indices of the track points drawn (at least :data:`TRACK_POINT_SPACING` of the map
    apart along the track) and their legend entry."""
    x, y = result.track_x_m, result.track_y_m
    n = x.size
    if n < 2:
        return np.arange(n), "track points"
    gap = np.median(np.hypot(np.diff(x), np.diff(y)))
    every = max(1, int(math.ceil(TRACK_POINT_SPACING * size / max(gap, 1e-9))))
    keep = np.arange(0, n, every)
    if every == 1:
        return keep, "track points"
    return keep, f"track points ({keep.size:,} of {n:,} shown)"


def route_map_figure(result: "TrackRoute", *, title: str | None = None) -> "Figure":
    """The track over its terrain and the route's elevation along it (nothing written).

    The map keeps one scale on both axes and fills its part of the figure: a map taller than
    :data:`ELONGATED` times its width stands beside the elevation panel, any other above it.
    The legend sits outside the map; the track's points are drawn under the route (thinned
    to at least :data:`TRACK_POINT_SPACING` of the map apart).

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

    view = _view(result)
    ratio = _aspect(view)
    size = max(view[1] - view[0], view[3] - view[2])
    tall = ratio > ELONGATED
    side_in = 5.0  # the elevation panel's width beside a tall map, or its height below any other
    if tall:
        fig = Figure(figsize=(4.0 + side_in, 9.0), layout="constrained")
        grid = fig.add_gridspec(1, 2, width_ratios=[4.0, side_in])
        top, bottom = fig.add_subfigure(grid[0]), fig.add_subfigure(grid[1])
        ax_z, ax_key = bottom.subplots(2, 1, height_ratios=[2.5, 1.0])
        ax_key.set_axis_off()  # it holds the legend, under the elevation panel
    else:
        side_in = 2.8
        fig = Figure(figsize=(10.0, 7.0 + side_in), layout="constrained")
        grid = fig.add_gridspec(2, 1, height_ratios=[7.0, side_in])
        top, bottom = fig.add_subfigure(grid[0]), fig.add_subfigure(grid[1])
        ax_z = bottom.subplots()
        ax_key = None
    ax_map = top.subplots()
    art = _terrain_background(ax_map, result.terrain, view)
    if art is not None:
        top.colorbar(art, ax=ax_map, label="terrain elevation (m)", shrink=0.8)
    route = result.route
    ax_map.plot(route.x_m, route.y_m, color="crimson", lw=1.5, zorder=3,
                label=f"route, a sample every {route.s_m[1] - route.s_m[0]:.3g} m")
    keep, points_label = _thinned_track(result, size)
    ax_map.plot(result.track_x_m[keep], result.track_y_m[keep], "o", color="black", ms=2.2, zorder=2,
                label=points_label)  # under the route: the points show where it bends, the route stays in sight
    _map_axes(ax_map, view, result.crs_name)
    _start_end(ax_map, route.x_m, route.y_m, "black")
    _arrows(ax_map, route.x_m, route.y_m, "black", size)
    handles, labels = ax_map.get_legend_handles_labels()
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
    fig.suptitle(_wrapped(title or "route over its terrain", fig.get_figwidth()))
    if tall:  # the legend above the elevation panel, beside the map
        ax_key.legend(handles, labels, loc="upper center", fontsize="small")

        def resized(width: float, height: float) -> None:
            grid.set_width_ratios([max(width - side_in, 0.5), side_in])

        _fit(fig, [(ax_map, lambda w, h: h / ratio)], "width", (side_in + 1.0, side_in + 9.0), resized=resized)
    else:  # below the map
        _agg(fig)
        top.legend(handles, labels, loc="outside lower center", ncols=3 if len(labels) > 4 else len(labels),
                   fontsize="small")

        def resized(width: float, height: float) -> None:
            grid.set_height_ratios([max(height - side_in, 0.5), side_in])

        _fit(fig, [(ax_map, lambda w, h: w * ratio)], "height", (side_in + 3.0, side_in + 9.0), resized=resized)
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


def _pieces(path: "Route", edges: np.ndarray) -> list[np.ndarray]:
    """The route's line from ``edges[k]`` to ``edges[k+1]`` (m along it) for each k: the
    route's own samples between them (thinned to :data:`MAX_LINE_VERTICES` in all), so that
    a bend is drawn as the route bends, not as a chord."""
    along = path.s_m - path.s_m[0]
    inside = along[(along > edges[0]) & (along < edges[-1])]
    stride = max(1, int(math.ceil(inside.size / MAX_LINE_VERTICES)))
    at = np.union1d(inside[::stride], edges)
    x = np.interp(at, along, path.x_m)
    y = np.interp(at, along, path.y_m)
    cut = np.searchsorted(at, edges)
    return [np.column_stack([x[a:b + 1], y[a:b + 1]]) for a, b in zip(cut[:-1], cut[1:])]


def _speed_line(ax: "Axes", pieces: list[np.ndarray], speeds: np.ndarray, top: float) -> Any:
    """The pieces as one line in the colours of their speeds (plasma, from 0 to ``top``), the
    slowest drawn last: where the route passes twice, or a short crawl shares a pixel with
    fast driving, the slow colour shows."""
    from matplotlib.collections import LineCollection

    order = np.argsort(-speeds, kind="stable")
    line = LineCollection([pieces[k] for k in order], array=speeds[order], cmap="plasma", linewidths=5,
                          capstyle="round", joinstyle="round", zorder=2)
    line.set_clim(0.0, top)  # from 0: a colour is a speed, not a share of the range
    ax.add_collection(line)
    return line


def _slow_spot(speed: np.ndarray) -> int | None:
    """The row of the slowest local minimum of the speed away from the start and the end (the
    speed from which a plan starts, or to which it stops, is not a crawl); None if there is
    none below 90 % of the top speed."""
    if speed.size < 3:
        return None
    mid = speed[1:-1]
    low = (mid <= speed[:-2]) & (mid <= speed[2:]) & ((mid < speed[:-2]) | (mid < speed[2:]))
    rows = np.flatnonzero(low) + 1
    if rows.size == 0:
        return None
    i = int(rows[np.argmin(speed[rows])])
    return i if speed[i] < 0.9 * float(np.max(speed)) else None


def _slow_run(speed: np.ndarray, i: int) -> tuple[int, int]:
    """The rows around row ``i`` slower than halfway between its speed and the median speed."""
    typical = float(np.median(speed))
    below = speed[i] + 0.5 * max(typical - speed[i], 0.1 * (float(np.max(speed)) - speed[i]))
    fast = np.flatnonzero(speed >= below)
    before, after = fast[fast < i], fast[fast > i]
    return (int(before[-1]) + 1 if before.size else 0), (int(after[0]) - 1 if after.size else speed.size - 1)


def _marks(binding: np.ndarray, x: np.ndarray, y: np.ndarray, rows: np.ndarray, spacing: float,
           taken: list[tuple[float, float]]) -> np.ndarray:
    """Which of the stretch starts ``rows`` to mark: each at least ``spacing`` (m) from every
    other mark and from the points ``taken``. The limits take turns, the one that holds the
    speed on fewest stretches first, each its next start along the route that has room: every
    limit is marked somewhere if it can be, and none crowds out another."""
    names, counts = np.unique(binding[rows], return_counts=True)
    queues = {name: list(rows[binding[rows] == name]) for name in names[np.argsort(counts, kind="stable")]}
    px = np.array([p[0] for p in taken], dtype=float)
    py = np.array([p[1] for p in taken], dtype=float)
    chosen = []
    while queues:
        for name in list(queues):
            queue = queues[name]
            while queue:
                j = queue.pop(0)
                if not px.size or float(np.min(np.hypot(px - x[j], py - y[j]))) >= spacing:
                    chosen.append(j)
                    px, py = np.append(px, x[j]), np.append(py, y[j])
                    break
            if not queue:
                del queues[name]
    return np.array(sorted(chosen), dtype=int)


def _zoom_window(x: np.ndarray, y: np.ndarray, speed: np.ndarray, view: tuple[float, float, float, float]
                 ) -> tuple[int, tuple[float, float, float, float]] | None:
    """The slowest stretch's row and a square around it to enlarge, if the map is elongated
    (room beside or below it) and the stretch is smaller than :data:`ZOOM_SHARE` of it."""
    ratio = _aspect(view)
    if 1 / ELONGATED <= ratio <= ELONGATED:
        return None
    i = _slow_spot(speed)
    if i is None:
        return None
    lo, hi = _slow_run(speed, i)
    rx, ry = x[lo:hi + 1], y[lo:hi + 1]
    extent = max(float(np.ptp(rx)), float(np.ptp(ry)))
    if extent >= ZOOM_SHARE * max(view[1] - view[0], view[3] - view[2]):
        return None
    half = max(1.5 * extent, ZOOM_MIN_HALF_M)
    cx, cy = 0.5 * (rx.min() + rx.max()), 0.5 * (ry.min() + ry.max())
    return i, (cx - half, cx + half, cy - half, cy + half)


def plan_map_figure(profile: "Profile", result: "TrackRoute", *, title: str | None = None, route: str | None = None,
                    vehicle: str | None = None) -> "Figure":
    """The route over its terrain coloured by the planned speed, with marks where limits hold
    the speed (the profile's ``binding`` column), nothing written.

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
    colour bar starts at 0 m/s. Each segment is drawn in the colour of the lower of its two
    speeds, and a plan of more than :data:`MAX_MAP_PIECES` segments in that many pieces, each
    in the colour of its lowest speed: the slowest pieces are drawn on top. A limit's mark stands where it starts to hold the speed, at most one mark per
    :data:`MARK_SPACING` of the map (the legend says how many stretches are marked); the
    start and end speeds are shown by the start and end marks. A ring marks the slowest
    point away from the start and the end; on an elongated map where that stretch is too
    small to see, a panel beside (or below) the map shows it enlarged.
    """
    from matplotlib.figure import Figure
    from matplotlib.patches import Rectangle

    from ..core.binding import BINDING_NAMES
    from .plots import BINDING_COLOURS

    path = result.route
    view = _view(result)
    ratio = _aspect(view)
    size = max(view[1] - view[0], view[3] - view[2])
    s = profile.s_m
    speed = profile.speed_mps
    along = path.s_m - path.s_m[0]
    x = np.interp(s, along, path.x_m)
    y = np.interp(s, along, path.y_m)
    zoom = _zoom_window(x, y, speed, view)
    tall = ratio > 1.0
    if zoom is not None and tall:  # the map, and the slow stretch enlarged beside it
        fig = Figure(figsize=(11.0, 9.5), layout="constrained")
        grid = fig.add_gridspec(1, 2, width_ratios=[1.0 / ratio, 1.0])
    elif zoom is not None:  # the map, and the slow stretch enlarged below it
        fig = Figure(figsize=(11.0, 9.5), layout="constrained")
        grid = fig.add_gridspec(2, 1, height_ratios=[ratio, 0.4])
    else:
        fig = Figure(figsize=(11.0, 9.0), layout="constrained")
        grid = fig.add_gridspec(1, 1)
    ax = fig.add_subplot(grid[0])
    ax_zoom = fig.add_subplot(grid[1]) if zoom is not None else None
    maps = [ax] if ax_zoom is None else [ax, ax_zoom]
    terrain = _terrain_background(ax, result.terrain, view, cmap="Greys")

    n = s.size - 1
    if n > MAX_MAP_PIECES:  # a long plan: each stretch in the colour of its lowest speed
        edges = np.linspace(s[0], s[-1], MAX_MAP_PIECES + 1)
        shown = bin_reduce(edges, s, speed, "min")
        centres = 0.5 * (edges[:-1] + edges[1:])
        filled = np.isfinite(shown)
        shown = np.interp(centres, centres[filled], shown[filled])
    else:
        edges, shown = s, np.minimum(speed[:-1], speed[1:])
    top = max(float(np.max(speed)), 1e-3)
    line = _speed_line(ax, _pieces(path, edges), shown, top)
    fig.colorbar(line, ax=maps, label="planned speed (m/s)", shrink=0.8)
    if terrain is not None:
        fig.colorbar(terrain, ax=maps, label="terrain elevation (m)", shrink=0.8)
    _map_axes(ax, view, result.crs_name)
    _start_end(ax, x, y, "black")
    _arrows(ax, x, y, "black", size)

    # what holds the speed: a mark where each stretch starts (not the start and end speeds)
    marked: dict[str, np.ndarray] = {}
    totals: dict[str, int] = {}
    zoom_marked: dict[str, np.ndarray] = {}
    if profile.binding is not None:
        binding = np.asarray(profile.binding)
        starts = np.flatnonzero(np.concatenate([[True], binding[1:] != binding[:-1]]))
        starts = starts[binding[starts] != "boundary"]
        ends = [(x[0], y[0]), (x[-1], y[-1])]  # and the ring of the slowest point: nothing on them
        slowest = _slow_spot(speed)
        if slowest is not None:
            ends.append((x[slowest], y[slowest]))
        chosen = _marks(binding, x, y, starts, MARK_SPACING * size, ends)
        for name in BINDING_NAMES:
            totals[name] = int(np.sum(binding[starts] == name))
            marked[name] = chosen[binding[chosen] == name]
        if zoom is not None:
            z0, z1, w0, w1 = zoom[1]
            near = starts[(x[starts] >= z0) & (x[starts] <= z1) & (y[starts] >= w0) & (y[starts] <= w1)]
            chosen = _marks(binding, x, y, near, MARK_SPACING * (z1 - z0), ends)
            zoom_marked = {name: chosen[binding[chosen] == name] for name in BINDING_NAMES}
    for name in BINDING_NAMES:
        rows = np.union1d(marked.get(name, []), zoom_marked.get(name, [])).astype(int)
        if rows.size == 0:
            continue
        label = f"{name} holds the speed from here"
        if rows.size < totals[name]:
            label += f" ({rows.size} of {totals[name]:,} stretches marked)"
        for axes, where in ((ax, marked.get(name)), (ax_zoom, zoom_marked.get(name))):
            if axes is not None and where is not None and where.size:
                axes.scatter(x[where], y[where], marker=BINDING_MARKERS[name], s=36, color=BINDING_COLOURS[name],
                             edgecolors="white", linewidths=0.6, zorder=4, label=label)

    slow = _slow_spot(speed)
    if slow is not None:
        where = "; enlarged " + ("beside" if tall else "below") if zoom is not None else ""
        ring = {"marker": "o", "ms": 17, "color": "none", "markeredgecolor": "black", "markeredgewidth": 1.4,
                "zorder": 5}
        ax.plot(x[slow], y[slow], ls="none", **ring,
                label=f"slowest away from the ends: {speed[slow]:.3g} m/s at s = {s[slow]:,.0f} m{where}")
    if zoom is not None:
        i, window = zoom
        z0, z1, w0, w1 = window
        # the terrain on the map's grey scale: its colour bar serves both
        _terrain_background(ax_zoom, result.terrain, window, cmap="Greys",
                            clim=terrain.get_clim() if terrain is not None else None)
        whole = np.minimum(speed[:-1], speed[1:])
        inside = np.flatnonzero(((x[:-1] >= z0) & (x[:-1] <= z1) & (y[:-1] >= w0) & (y[:-1] <= w1))
                                | ((x[1:] >= z0) & (x[1:] <= z1) & (y[1:] >= w0) & (y[1:] <= w1)))
        bounds = np.union1d(inside, inside + 1)
        pieces = _pieces(path, s[bounds])
        # the pieces between consecutive rows only (a jump between two passes is no piece)
        joined = np.flatnonzero(np.diff(bounds) == 1)
        _speed_line(ax_zoom, [pieces[k] for k in joined], whole[bounds[joined]], top)
        _map_axes(ax_zoom, window, "")
        _start_end(ax_zoom, x, y, "black", label=False)
        run = np.flatnonzero((x >= z0) & (x <= z1) & (y >= w0) & (y <= w1))
        first = run[: np.searchsorted(run, i) + 1]
        gaps = np.flatnonzero(np.diff(first) > 1)
        a = int(first[gaps[-1] + 1]) if gaps.size else int(first[0])
        rest = run[np.searchsorted(run, i):]
        gaps = np.flatnonzero(np.diff(rest) > 1)
        b = int(rest[gaps[0]]) if gaps.size else int(rest[-1])
        _arrows(ax_zoom, x[a:b + 1], y[a:b + 1], "black", z1 - z0, count=4, label=False)
        ax_zoom.plot(x[i], y[i], ls="none", **ring)
        ax_zoom.set_title(f"enlarged: {z1 - z0:,.0f} m across, around s = {s[i]:,.0f} m", fontsize="small")
        ax.add_patch(Rectangle((z0, w0), z1 - z0, w1 - w0, fill=False, edgecolor="black", lw=1.0, zorder=5))

    # the legend below the maps ("best" cannot see the route, a LineCollection, and covered its end)
    handles, labels = [], []
    for axes in maps:
        for handle, text in zip(*axes.get_legend_handles_labels()):
            if text not in labels:
                handles.append(handle)
                labels.append(text)
    last = [k for k, text in enumerate(labels) if text.startswith("slowest")]  # the ring after the marks
    handles = [h for k, h in enumerate(handles) if k not in last] + [handles[k] for k in last]
    labels = [t for k, t in enumerate(labels) if k not in last] + [labels[k] for k in last]
    if title is None:
        title = (f"{plan_title(profile, route=route, vehicle=vehicle)}, planned speed along the route: "
                 f"{profile.distance_m:.0f} m in {profile.travel_time_s:.0f} s")
    if zoom is not None and tall:
        panels = [(ax, lambda w, h: h / ratio), (ax_zoom, lambda w, h: h)]
        free, bounds = "width", (8.0, 16.0)
    elif zoom is not None:
        panels = [(ax, lambda w, h: w * ratio), (ax_zoom, lambda w, h: min(4.0, w))]
        free, bounds = "height", (5.0, 13.0)
    elif ratio > 1.0:
        panels, free, bounds = [(ax, lambda w, h: h / ratio)], "width", (7.5, 11.0)
    else:
        panels, free, bounds = [(ax, lambda w, h: w * ratio)], "height", (4.5, 10.0)
    _agg(fig)
    legend = _legend_below(fig, handles, labels)
    fig.suptitle(_wrapped(title, fig.get_figwidth()))
    _fit(fig, panels, free, bounds, grid=grid)
    legend.remove()  # again, in as many columns as the width found holds, and the title in as many lines
    _legend_below(fig, handles, labels)
    fig.suptitle(_wrapped(title, fig.get_figwidth()))
    _fit(fig, panels, free, bounds, grid=grid)
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
