"""Pictures of planned profiles (matplotlib's object API; no global backend is touched)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ._io import atomic_path
from .forces import get_model

if TYPE_CHECKING:
    from .planner import Profile

__all__ = ["plot_profile"]


def plot_profile(profile: "Profile", path: str | Path, title: str | None = None) -> None:
    """Draw a profile's speed, the per-segment allowable speeds and RI against distance.

    Top: planned speed (m/s) beside each segment's allowable speed under both semantics of
    NOTES.md ("first": every speed from rest up to it is admissible; "largest": the fastest
    admissible speed, possibly above resonance) and the speed cap. Bottom: segment RI.
    Written atomically as PNG.

    Parameters
    ----------
    profile : Profile
        A profile returned by :func:`profileopt.plan` (the per-segment allowable speeds are
        not stored in a profile CSV, so a profile read back is drawn without them).
    path : str or pathlib.Path
        Output PNG file.
    title : str, optional
    """
    from matplotlib.figure import Figure

    s = profile.s_m
    fig = Figure(figsize=(10, 6.5), layout="constrained")
    ax_v, ax_ri = fig.subplots(2, 1, sharex=True, height_ratios=[3, 1])
    label = get_model(profile.model).label
    if profile.allowable_largest_mps is not None:
        ax_v.stairs(profile.allowable_largest_mps, s, color="tab:orange", linewidth=1.2, zorder=4,
                    label=f'allowable, {label} "largest" (may be above resonance)')
    if profile.allowable_first_mps is not None:
        ax_v.stairs(profile.allowable_first_mps, s, color="tab:red", linewidth=1.2, linestyle="--", zorder=5,
                    label=f'allowable, {label} "first" (safe from rest)')
    if profile.speed_cap_mps is not None:
        ax_v.stairs(profile.speed_cap_mps, s, color="0.5", linewidth=0.8, linestyle=":",
                    label="speed cap (top speed, speed_limit)")
    ax_v.plot(s, profile.speed_mps, color="tab:blue", linewidth=2.0, label="planned speed")
    ax_v.set_ylabel("speed (m/s)")
    top = max(float(np.max(profile.speed_mps)), float(np.nanmax(profile.speed_cap_mps))
              if profile.speed_cap_mps is not None else 0.0)
    ax_v.set_ylim(0, 1.3 * max(top, 1e-3))  # room for the legend above the curves
    ax_v.grid(True, alpha=0.3)
    ax_v.legend(loc="upper center", ncols=2, fontsize="small")
    ax_v.set_title(title or f"{label} plan: {profile.distance_m:.0f} m in {profile.travel_time_s:.1f} s "
                   f"(status {profile.status})")
    ax_ri.stairs(profile.ri[:-1], s, color="tab:green", fill=True, alpha=0.5)
    ax_ri.set_ylabel("segment RI (-)")
    ax_ri.set_xlabel("distance along the route s (m)")
    ax_ri.grid(True, alpha=0.3)
    ax_ri.set_xlim(s[0], s[-1])
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110, format="png")
