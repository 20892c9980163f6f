"""Every picture the project draws: planned profiles, verifications and the paper's figures.

Each function draws on a bare matplotlib ``Figure`` (the object API, no pyplot): it renders
with Agg whatever backend the caller chose, opens no window, changes no global state and is
freed with the object, so it is safe in scripts, tests, servers and notebooks. matplotlib is
imported only when a picture is drawn.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..core.stations import segment_index
from ..io.atomic import atomic_path, picture_format
from ..physics.forces import get_model

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from ..core.profile import Profile
    from ..verification.verify import Verification

__all__ = ["bin_reduce", "profile_figure", "plot_profile", "verification_figure", "plot_verification", "save_figure",
           "envelope_trace", "BINDING_COLOURS", "MAX_DRAWN_SEGMENTS", "OVERVIEW_BINS"]


#: Most segments drawn one by one in a profile's picture (about two per pixel column); a
#: longer plan is drawn as its overview: each quantity's lowest and highest value (its
#: lowest allowable speed, its highest RI) in each of :data:`OVERVIEW_BINS` equal stretches.
MAX_DRAWN_SEGMENTS = 2000
#: Stretches of a long plan's overview (:data:`MAX_DRAWN_SEGMENTS`).
OVERVIEW_BINS = 800
#: Bins of a verification's window curves; beyond ten times as many windows (one per route
#: sample: a route of some km) each curve is drawn as its lowest to highest in each bin.
MAX_DRAWN_WINDOWS = 3000


def bin_reduce(edges: np.ndarray, s: np.ndarray, values: np.ndarray, how: str) -> np.ndarray:
    """Per bin of ``edges``, the lowest (``how="min"``) or highest (``"max"``) of the
    ``values`` at positions ``s`` inside it, NaN values ignored; NaN for a bin with none.

    Parameters
    ----------
    edges : numpy.ndarray, shape (B+1,)
        Bin edges along the route (m), increasing.
    s : numpy.ndarray, shape (M,)
        Positions of the values (m), non-decreasing.
    values : numpy.ndarray, shape (M,)
        The values (any unit).
    how : {"min", "max"}
        Which extreme of each bin.

    Returns
    -------
    numpy.ndarray, shape (B,)
    """
    which = segment_index(s, edges)
    bins = edges.size - 1
    starts = np.searchsorted(which, np.arange(bins), side="left")
    filled = np.diff(np.append(starts, which.size)) > 0
    out = np.full(bins, np.nan)
    if np.any(filled):
        ufunc = np.fmin if how == "min" else np.fmax  # fmin and fmax skip NaN
        out[filled] = ufunc.reduceat(np.asarray(values, dtype=float), starts[filled])
    return out


class _Drawn:
    """A profile's arrays as they are drawn: each segment's own values, or for a long plan
    (more than :data:`MAX_DRAWN_SEGMENTS`) the lowest or highest in each overview bin."""

    def __init__(self, s: np.ndarray) -> None:
        self.s = s
        self.overview = s.size - 1 > MAX_DRAWN_SEGMENTS
        self.edges = np.linspace(s[0], s[-1], OVERVIEW_BINS + 1) if self.overview else s
        self.bin_m = float(self.edges[1] - self.edges[0]) if self.overview else 0.0
        self._mid = 0.5 * (s[:-1] + s[1:])

    def segments(self, values: np.ndarray, how: str) -> np.ndarray:
        """Per-segment values (shape N) as drawn over :attr:`edges` by ``stairs``."""
        return bin_reduce(self.edges, self._mid, values, how) if self.overview else values

    def rows(self, values: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Per-row values (shape N+1): positions, lowest and highest (the same when not an overview)."""
        if not self.overview:
            return self.s, values, values
        centres = 0.5 * (self.edges[:-1] + self.edges[1:])
        return centres, bin_reduce(self.edges, self.s, values, "min"), bin_reduce(self.edges, self.s, values, "max")

    def suffix(self, what: str) -> str:
        """A legend's words for an overview's reduction ("" when each segment is drawn)."""
        return f" ({what} in each {self.bin_m:.3g} m)" if self.overview else ""


def profile_figure(profile: "Profile", *, title: str | None = None, route: str | None = None,
                   vehicle: str | None = None) -> "Figure":
    """The picture of :func:`plot_profile` as a matplotlib ``Figure`` (nothing written).

    Parameters
    ----------
    profile : Profile
        A profile returned by :func:`profileopt.plan`.
    title : str, optional
        Replaces the whole title.
    route : str, optional
        The route's name for the title (e.g. its file name).
    vehicle : str, optional
        The vehicle's name for the title; default the one the profile records.

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.figure import Figure

    s = profile.s_m
    drawn = _Drawn(s)
    turns = profile.binding is not None and profile.curvature_1pm is not None and profile.grade_rad is not None
    # an s,z route has a straight path: no curvature panel (always 0), the grade still tells
    curved = turns and (profile.path_summary() is not None or bool(np.any(profile.curvature_1pm != 0)))
    if turns:
        names = ["v", "ri", *(["k"] if curved else []), "g", "b"]
        ratios = {"v": 3, "ri": 1, "k": 1, "g": 1, "b": 1.3}
        fig = Figure(figsize=(10, 11 if curved else 9.6), layout="constrained")
        axes = dict(zip(names, fig.subplots(len(names), 1, sharex=True, height_ratios=[ratios[n] for n in names])))
    else:
        fig = Figure(figsize=(10, 7), layout="constrained")
        axes = dict(zip(("v", "ri"), fig.subplots(2, 1, sharex=True, height_ratios=[3, 1])))
    ax_v, ax_ri = axes["v"], axes["ri"]
    label = get_model(profile.model).label
    cap = profile.speed_cap_mps
    top_speed = profile.settings.get("max_speed_mps") if profile.settings else None

    def model_only(values: np.ndarray) -> np.ndarray:
        """The allowable speed where the force model holds it below the speed cap, NaN (a
        gap) where the cap holds it: the cap has its own line."""
        if cap is None:
            return values
        return np.where(values < cap * (1 - 1e-9), values, np.nan)

    lowest = drawn.suffix("lowest")
    # Lines that can coincide are drawn widest at the bottom, so that each one stays visible
    # around the one on top: the speed cap (wide grey dashes), "largest" (wide, translucent),
    # "first" (red dashes), the planned speed (narrow, on top). No baseline: a gap in a line
    # is a gap, not a drop to 0. A line with nothing to draw has no legend entry.
    if cap is not None:
        held = top_speed is not None and bool(np.any(cap < top_speed * (1 - 1e-9)))
        cap_label = (f"speed cap: top speed {top_speed:g} m/s" if top_speed is not None else "speed cap: top speed")
        if held:
            cap_label += "".join(f", {text}" for text in _cap_sources(profile)) + lowest
        ax_v.stairs(drawn.segments(cap, "min"), drawn.edges, baseline=None, color="0.55", linewidth=3.5,
                    linestyle=(0, (5, 2)), zorder=2, label=cap_label)
    for values, style in (
            (profile.allowable_largest_mps, {"color": "tab:orange", "linewidth": 6.0, "alpha": 0.45, "zorder": 3,
                                             "label": f'allowable, {label} "largest" (may be above resonance)'}),
            (profile.allowable_first_mps, {"color": "tab:red", "linewidth": 2.6, "linestyle": (0, (4, 2)),
                                           "zorder": 4, "label": f'allowable, {label} "first" (safe from rest)'})):
        if values is None:
            continue
        shown = drawn.segments(model_only(values), "min")
        if np.all(np.isnan(shown)):  # the cap holds the speed everywhere: nothing of its own to draw
            continue
        ax_v.stairs(shown, drawn.edges, baseline=None, **{**style, "label": style["label"] + lowest})
    if drawn.overview:
        x, lo, hi = drawn.rows(profile.speed_mps)
        ax_v.fill_between(x, lo, hi, color="tab:blue", alpha=0.55, linewidth=0, zorder=5,
                          label="planned speed" + drawn.suffix("lowest to highest"))
    else:
        ax_v.plot(s, profile.speed_mps, color="tab:blue", linewidth=1.6, zorder=5, label="planned speed")
    ax_v.set_ylabel("speed (m/s)")
    highest = max(float(np.max(profile.speed_mps)), float(np.nanmax(cap)) if cap is not None else 0.0)
    ax_v.set_ylim(0, 1.06 * max(highest, 1e-3))
    ax_v.grid(True, alpha=0.3)
    fig.legend(*ax_v.get_legend_handles_labels(), loc="outside lower center", ncols=2, fontsize="small")
    if title is None:
        title = (f"{plan_title(profile, route=route, vehicle=vehicle)}, {profile.distance_m:.0f} m in "
                 f"{profile.travel_time_s:.1f} s (status {profile.status})")
    ax_v.set_title(title)
    ax_ri.stairs(drawn.segments(profile.ri[:-1], "max"), drawn.edges, color="tab:green", fill=True, alpha=0.5)
    ax_ri.set_ylabel("RI (-) of the\nroughest window met" + ("\n(highest per bin)" if drawn.overview else ""))
    ax_ri.grid(True, alpha=0.3)
    ax_ri.set_xlim(s[0], s[-1])
    if not turns:
        ax_ri.set_xlabel("distance along the route s (m)")
        return fig
    for key, values, colour, ylabel in (("k", profile.curvature_1pm, "tab:purple", "curvature (1/m)\nleft +, right -"),
                                        ("g", 100.0 * np.tan(profile.grade_rad), "tab:brown", "grade (%)\nuphill +")):
        if key not in axes:
            continue
        ax = axes[key]
        x, lo, hi = drawn.rows(values)
        if drawn.overview:
            ax.fill_between(x, lo, hi, color=colour, alpha=0.7, linewidth=0)
        else:
            ax.plot(x, values, color=colour, linewidth=1.2)
        ax.axhline(0.0, color="0.6", linewidth=0.8)
        ax.set_ylabel(ylabel)
        ax.grid(True, alpha=0.3)
    _binding_panel(axes["b"], s, profile.binding)
    axes["b"].set_xlabel("distance along the route s (m)")
    return fig


def _cap_sources(profile: "Profile") -> list[str]:
    """What, besides the top speed, lowers the speed cap somewhere (for the cap's legend)."""
    if profile.cap_source is None or not profile.limits:
        return ["route's speed_limit or turns"]
    top = float(profile.settings.get("max_speed_mps", np.inf))
    texts = []
    for k in np.unique(profile.cap_source):
        if k < 0:
            continue
        name = profile.limits[int(k)].name
        lowered = bool(np.any((profile.cap_source == k) & (profile.speed_cap_mps < top * (1 - 1e-9))))
        if lowered:
            texts.append({"speed cap": "route's speed_limit", "lateral": "turns (lateral acceleration)",
                          "friction": "turns (friction)"}.get(name, name))
    return texts


#: A colour per value of the binding column (tab10), so every plan shows each limit alike.
BINDING_COLOURS = {"force": "tab:red", "speed_limit": "tab:gray", "top_speed": "tab:olive", "lateral": "tab:purple",
                    "friction": "tab:pink", "accel": "tab:green", "decel": "tab:orange", "power": "tab:brown",
                    "jerk": "tab:cyan", "boundary": "black", "step": "darkred",
                   "simulated": "magenta"}


def _binding_panel(ax: object, s: np.ndarray, binding: np.ndarray) -> None:
    """One row per limit that holds the speed somewhere, filled where it does: row j of the
    profile stands for the half segments on either side of it; neighbouring rows of one
    limit are drawn as one bar."""
    from ..core.binding import BINDING_NAMES

    mid = 0.5 * (s[:-1] + s[1:])
    left = np.concatenate([[s[0]], mid])
    right = np.concatenate([mid, [s[-1]]])
    present = [name for name in BINDING_NAMES if np.any(binding == name)]
    for row, name in enumerate(present):
        held = np.concatenate([[False], binding == name, [False]]).astype(np.int8)
        starts, ends = np.flatnonzero(np.diff(held) == 1), np.flatnonzero(np.diff(held) == -1) - 1
        ax.broken_barh(list(zip(left[starts], right[ends] - left[starts])), (row - 0.4, 0.8),
                       color=BINDING_COLOURS[name])
    ax.set_yticks(range(len(present)), present, fontsize="small")
    ax.set_ylim(-0.6, len(present) - 0.4)
    ax.invert_yaxis()
    ax.set_ylabel("what holds\nthe speed")
    ax.grid(True, axis="x", alpha=0.3)


def plan_title(profile: "Profile", *, route: str | None = None, vehicle: str | None = None) -> str:
    """The start of a plan's title: ``"trail.csv: SBEM:TF plan for atv"``.

    Parameters
    ----------
    profile : Profile
        The plan (its model, and its recorded vehicle when ``vehicle`` is not given).
    route, vehicle : str, optional
        The route's file name and the vehicle's name, as the user knows them.

    Returns
    -------
    str
    """
    vehicle = vehicle or (Path(str(profile.settings.get("vehicle", ""))).stem if profile.settings else "")
    where = f"{route}: " if route else ""
    who = f" for {vehicle}" if vehicle else ""
    return f"{where}{get_model(profile.model).label} plan{who}"


def save_figure(fig: "Figure", path: str | Path, dpi: int = 110) -> None:
    """Write ``fig`` to ``path`` atomically (:func:`profileopt.io.atomic_path`), in the format
    its extension names (:func:`profileopt.io.atomic.picture_format`: ``.jpg``, ``.pdf``,
    ``.svg``, ...; PNG without an extension).

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The picture.
    path : str or pathlib.Path
        The file to write.
    dpi : int, default 110
        Dots per inch of a raster format.
    """
    fmt = picture_format(path)  # an extension matplotlib cannot write is an InputError
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=dpi, format=fmt)


def plot_profile(profile: "Profile", path: str | Path, title: str | None = None, *, route: str | None = None,
                 vehicle: str | None = None) -> None:
    """Draw a profile's speed, the per-segment allowable speeds and RI against distance.

    Top: planned speed (m/s) beside each segment's allowable speed under both semantics of
    docs/paper-notes.md ("first": every speed from rest up to it is admissible; "largest": the fastest
    admissible speed, possibly above resonance), drawn where the force model holds the speed
    below the speed cap, and the speed cap (the vehicle's top speed and the route's
    ``speed_limit``) as its own line. Bottom: each segment's RI (its roughest window's). The title names the route and the
    vehicle. A plan of more than :data:`MAX_DRAWN_SEGMENTS` segments is drawn as an
    overview (each quantity's lowest or highest in each of :data:`OVERVIEW_BINS` stretches).
    Written atomically (:func:`save_figure`: PNG, or the format the extension names).

    Parameters
    ----------
    profile : Profile
        A profile returned by :func:`profileopt.plan` (the per-segment allowable speeds are
        not stored in a profile CSV, so a profile read back is drawn without them).
    path : str or pathlib.Path
        Output file (PNG, or the format its extension names: :func:`save_figure`).
    title : str, optional
        Replaces the whole title.
    route, vehicle : str, optional
        Names for the title (:func:`profile_figure`).
    """
    save_figure(profile_figure(profile, title=title, route=route, vehicle=vehicle), path)


def envelope_trace(x: np.ndarray, values: np.ndarray, bins: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per-bin min and max of ``values`` along ``x`` (for plotting millions of points).

    Parameters
    ----------
    x : numpy.ndarray, shape (K,)
        Increasing positions (m).
    values : numpy.ndarray, shape (K,)
        The values at them.
    bins : int
        How many equal bins from ``x[0]`` to ``x[-1]``.

    Returns
    -------
    (centres, lowest, highest) : tuple of numpy.ndarray
        Of the bins holding a point: their centres (m), and the least and greatest value in each.
    """
    edges = np.linspace(x[0], x[-1], bins + 1)
    which = segment_index(x, edges)
    starts = np.searchsorted(which, np.arange(bins), side="left")
    filled = np.diff(np.append(starts, which.size)) > 0
    starts = starts[filled]
    centres = 0.5 * (edges[:-1] + edges[1:])[filled]
    return centres, np.minimum.reduceat(values, starts), np.maximum.reduceat(values, starts)


def _step(boundaries: np.ndarray, values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return np.repeat(boundaries, 2)[1:-1], np.repeat(values, 2)


def verification_figure(verification: "Verification") -> "Figure":
    """The picture of :func:`plot_verification` as a matplotlib ``Figure`` (nothing written).

    Parameters
    ----------
    verification : Verification
        The result of :func:`profileopt.verify` (it holds the simulated run).

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.figure import Figure

    v = verification
    run = v.run
    win = v.windows
    series = run.transmitted_n if v.quantity == "transmitted" else run.excitation_n
    label = ("transmitted force F_T" if v.quantity == "transmitted"
             else "excitation force k y + c y' (y from each segment's line)")
    fig = Figure(figsize=(10, 8), layout="constrained")
    top, bottom = fig.subplots(2, 1, height_ratios=[3, 2])
    xs, lo, hi = envelope_trace(run.s_m, series, 3000)
    top.fill_between(xs, lo, hi, color="0.6", lw=0, label=f"simulated {label}")
    centre = win.start_m + 0.5 * win.window_m
    for values, colour, text in (
            (win.simulated_n, "C0", f"simulated peak |F| while inside each {win.window_m:g} m window (at its centre)"),
            (win.predicted_n, "C2", f"predicted for each window ({get_model(v.model).label}, at its RI)")):
        if centre.size > 10 * MAX_DRAWN_WINDOWS:  # a long route: the lowest to highest in each bin
            xs, w_lo, w_hi = envelope_trace(centre, values, MAX_DRAWN_WINDOWS)
            top.fill_between(xs, w_lo, w_hi, color=colour, lw=0.6, alpha=0.7,
                             label=f"{text}, lowest to highest in each {(centre[-1] - centre[0]) / MAX_DRAWN_WINDOWS:.3g} m")
        else:
            top.plot(centre, values, color=colour, lw=1.0, label=text)
    top.plot(*_step(v.s_m, v.limit_n), color="C3", ls="--", lw=2.6, alpha=0.6, zorder=1.5,
             label="limit")  # wide, under the prediction that reaches it
    top.axhline(-v.weight_n, color="C4", ls=":", lw=1, label="-m g (wheel lifts off below)")
    top.set_xlabel("s (m)")
    top.set_ylabel("force (N)")
    top.set_xlim(v.s_m[0], v.s_m[-1])
    speed_axis = top.twinx()
    speed_axis.plot(v.s_m, v.speed_mps, color="C1", lw=1, alpha=0.8, label="planned speed (right axis)")
    speed_axis.set_ylabel("planned speed (m/s)", color="C1")
    # the legends sit outside the axes: inside, they covered the points that matter (at the
    # limit, where a plan drives)
    handles, labels = top.get_legend_handles_labels()
    more = speed_axis.get_legend_handles_labels()
    top.legend(handles + more[0], labels + more[1], loc="lower left", bbox_to_anchor=(0.0, 1.01), ncols=2,
               fontsize=8, borderaxespad=0.0)
    fig.suptitle(f"{Path(v.route).name}: {get_model(v.model).label} plan, {Path(v.vehicle).stem}; "
                 f"{win.over_count}/{win.count} windows over the limit, worst {win.worst_ratio:.2f} x limit; "
                 f"{v.over_count}/{v.ratio.size} segments")

    over = win.over
    for which, size, colour, text in ((~over, 3, "C0", "window within the limit"),
                                      (over, 5, "C3", "window over the limit")):
        if np.any(which):  # a legend lists only what is drawn
            bottom.scatter(win.predicted_n[which], win.simulated_n[which], s=size, color=colour, rasterized=True,
                           label=text)
    top_value = max(float(np.max(win.simulated_n)), float(np.max(win.predicted_n)), win.limit_n) * 1.05
    bottom.plot([0, top_value], [0, top_value], color="0.3", lw=1, label="simulated = predicted")
    bottom.axhline(win.limit_n, color="C3", ls="--", lw=1, label="limit")
    bottom.set_xlim(0, top_value)
    bottom.set_ylim(0, top_value)
    bottom.set_xlabel("predicted peak force of the window (N)")
    bottom.set_ylabel("simulated peak force while inside (N)")
    bottom.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, borderaxespad=0.0)
    return fig


def plot_verification(verification: "Verification", path: str | Path) -> None:
    """Write a PNG: forces and limit along s, and simulated versus predicted per window.

    Top: the simulated force of the model's kind along s (band between its smallest and
    largest value in each of 3000 bins), each roughness window's simulated peak and
    prediction (plotted at the window's centre) and the limit; the speed on the right
    axis. Bottom: per window, the simulated peak against the prediction (points above the
    diagonal: the model was not conservative there; above the dashed line: over the limit).

    The file is written through :func:`profileopt.io.atomic_path`.

    Parameters
    ----------
    verification : Verification
        The result of :func:`profileopt.verify` (it holds the simulated run).
    path : str or pathlib.Path
        Output file (PNG, or the format its extension names: :func:`save_figure`).
    """
    save_figure(verification_figure(verification), path)
