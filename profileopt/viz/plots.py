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
from ..io.atomic import atomic_path
from ..physics.forces import get_model

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from ..core.profile import Profile
    from ..verification.verify import Verification

__all__ = ["profile_figure", "plot_profile", "verification_figure", "plot_verification",
           "BINDING_COLOURS"]


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
    turns = profile.binding is not None and profile.curvature_1pm is not None and profile.grade_rad is not None
    if turns:
        fig = Figure(figsize=(10, 11), layout="constrained")
        ax_v, ax_ri, ax_k, ax_g, ax_b = fig.subplots(5, 1, sharex=True, height_ratios=[3, 1, 1, 1, 1.3])
    else:
        fig = Figure(figsize=(10, 7), layout="constrained")
        ax_v, ax_ri = fig.subplots(2, 1, sharex=True, height_ratios=[3, 1])
    label = get_model(profile.model).label
    cap = profile.speed_cap_mps
    top_speed = profile.settings.get("max_speed_mps") if profile.settings else None

    def model_only(values: np.ndarray) -> np.ndarray:
        """The allowable speed where the force model holds it below the speed cap, NaN (a
        gap) where the cap holds it: the cap has its own line."""
        if cap is None:
            return values
        return np.where(values < cap * (1 - 1e-9), values, np.nan)

    # Lines that can coincide are drawn widest at the bottom, so that each one stays visible
    # around the one on top: the speed cap (wide grey dashes), "largest" (wide, translucent),
    # "first" (red dashes), the planned speed (narrow, on top). No baseline: a gap in a line
    # is a gap, not a drop to 0.
    if cap is not None:
        held = top_speed is not None and bool(np.any(cap < top_speed * (1 - 1e-9)))
        cap_label = (f"speed cap: top speed {top_speed:g} m/s" if top_speed is not None else "speed cap: top speed")
        if held:
            cap_label += "".join(f", {text}" for text in _cap_sources(profile))
        ax_v.stairs(cap, s, baseline=None, color="0.55", linewidth=3.5, linestyle=(0, (5, 2)), zorder=2,
                    label=cap_label)
    if profile.allowable_largest_mps is not None:
        ax_v.stairs(model_only(profile.allowable_largest_mps), s, baseline=None, color="tab:orange", linewidth=6.0, alpha=0.45,
                    zorder=3, label=f'allowable, {label} "largest" (may be above resonance)')
    if profile.allowable_first_mps is not None:
        ax_v.stairs(model_only(profile.allowable_first_mps), s, baseline=None, color="tab:red", linewidth=2.6,
                    linestyle=(0, (4, 2)), zorder=4, label=f'allowable, {label} "first" (safe from rest)')
    ax_v.plot(s, profile.speed_mps, color="tab:blue", linewidth=1.6, zorder=5, label="planned speed")
    ax_v.set_ylabel("speed (m/s)")
    highest = max(float(np.max(profile.speed_mps)), float(np.nanmax(cap)) if cap is not None else 0.0)
    ax_v.set_ylim(0, 1.06 * max(highest, 1e-3))
    ax_v.grid(True, alpha=0.3)
    fig.legend(*ax_v.get_legend_handles_labels(), loc="outside lower center", ncols=2, fontsize="small")
    if title is None:
        vehicle = vehicle or (Path(str(profile.settings.get("vehicle", ""))).stem if profile.settings else "")
        where = f"{route}: " if route else ""
        who = f" for {vehicle}" if vehicle else ""
        title = (f"{where}{label} plan{who}, {profile.distance_m:.0f} m in {profile.travel_time_s:.1f} s "
                 f"(status {profile.status})")
    ax_v.set_title(title)
    ax_ri.stairs(profile.ri[:-1], s, color="tab:green", fill=True, alpha=0.5)
    ax_ri.set_ylabel("RI (-) of the\nroughest window met")
    ax_ri.grid(True, alpha=0.3)
    ax_ri.set_xlim(s[0], s[-1])
    if not turns:
        ax_ri.set_xlabel("distance along the route s (m)")
        return fig
    ax_k.plot(s, profile.curvature_1pm, color="tab:purple", linewidth=1.2)
    ax_k.axhline(0.0, color="0.6", linewidth=0.8)
    ax_k.set_ylabel("curvature (1/m)\nleft +, right -")
    ax_k.grid(True, alpha=0.3)
    ax_g.plot(s, 100.0 * np.tan(profile.grade_rad), color="tab:brown", linewidth=1.2)
    ax_g.axhline(0.0, color="0.6", linewidth=0.8)
    ax_g.set_ylabel("grade (%)\nuphill +")
    ax_g.grid(True, alpha=0.3)
    _binding_panel(ax_b, s, profile.binding)
    ax_b.set_xlabel("distance along the route s (m)")
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
    profile stands for the half segments on either side of it."""
    from ..core.binding import BINDING_NAMES

    mid = 0.5 * (s[:-1] + s[1:])
    left = np.concatenate([[s[0]], mid])
    right = np.concatenate([mid, [s[-1]]])
    present = [name for name in BINDING_NAMES if np.any(binding == name)]
    for row, name in enumerate(present):
        where = np.flatnonzero(binding == name)
        ax.broken_barh(list(zip(left[where], right[where] - left[where])), (row - 0.4, 0.8),
                       color=BINDING_COLOURS[name])
    ax.set_yticks(range(len(present)), present, fontsize="small")
    ax.set_ylim(-0.6, len(present) - 0.4)
    ax.invert_yaxis()
    ax.set_ylabel("what holds\nthe speed")
    ax.grid(True, axis="x", alpha=0.3)


def plot_profile(profile: "Profile", path: str | Path, title: str | None = None, *, route: str | None = None,
                 vehicle: str | None = None) -> None:
    """Draw a profile's speed, the per-segment allowable speeds and RI against distance.

    Top: planned speed (m/s) beside each segment's allowable speed under both semantics of
    docs/paper-notes.md ("first": every speed from rest up to it is admissible; "largest": the fastest
    admissible speed, possibly above resonance), drawn where the force model holds the speed
    below the speed cap, and the speed cap (the vehicle's top speed and the route's
    ``speed_limit``) as its own line. Bottom: each segment's RI (its roughest window's). The title names the route and the
    vehicle. Written atomically as PNG.

    Parameters
    ----------
    profile : Profile
        A profile returned by :func:`profileopt.plan` (the per-segment allowable speeds are
        not stored in a profile CSV, so a profile read back is drawn without them).
    path : str or pathlib.Path
        Output PNG file.
    title : str, optional
        Replaces the whole title.
    route, vehicle : str, optional
        Names for the title (:func:`profile_figure`).
    """
    fig = profile_figure(profile, title=title, route=route, vehicle=vehicle)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110, format="png")


def _envelope_trace(x: np.ndarray, values: np.ndarray, bins: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per-bin min and max of ``values`` along ``x`` (for plotting millions of points)."""
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
    xs, lo, hi = _envelope_trace(run.s_m, series, 3000)
    top.fill_between(xs, lo, hi, color="0.6", lw=0, label=f"simulated {label}")
    centre = win.start_m + 0.5 * win.window_m
    top.plot(centre, win.simulated_n, color="C0", lw=1.0,
             label=f"simulated peak |F| while inside each {win.window_m:g} m window (at its centre)")
    top.plot(centre, win.predicted_n, color="C2", lw=1.0,
             label=f"predicted for each window ({get_model(v.model).label}, at its RI)")
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
    bottom.scatter(win.predicted_n[~over], win.simulated_n[~over], s=3, color="C0", rasterized=True,
                   label="window within the limit")
    bottom.scatter(win.predicted_n[over], win.simulated_n[over], s=5, color="C3", rasterized=True,
                   label="window over the limit")
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
        Output PNG file.
    """
    fig = verification_figure(verification)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=110)
