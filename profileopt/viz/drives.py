"""The picture of ``profileopt drive``: the speed driven online beside the offline plan.

Imported only when a picture is drawn (matplotlib).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from .plots import save_figure

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from ..core.profile import Profile
    from ..online.drive import Drive

__all__ = ["drive_figure", "plot_drive"]


def drive_figure(drive: "Drive", offline: "Profile | None", *, sensor_range_m: float, unseen: str,
                 route: str | None = None, vehicle: str | None = None) -> "Figure":
    """The picture of :func:`plot_drive` as a matplotlib ``Figure`` (nothing written).

    Parameters
    ----------
    drive : Drive
        The closed-loop drive.
    offline : Profile or None
        The same route's offline plan, drawn beside it (None: not drawn).
    sensor_range_m : float
        The sensing range (m), drawn in the middle panel.
    unseen : str
        What was assumed for unseen terrain, for the legend (e.g. ``"ISO 8608 class H"``).
    route, vehicle : str, optional
        Names for the title.

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.figure import Figure

    fig = Figure(figsize=(10, 8), layout="constrained")
    ax_v, ax_e, ax_f = fig.subplots(3, 1, sharex=True, height_ratios=[3, 1.2, 1.2])
    if offline is not None:
        ax_v.plot(offline.s_m, offline.speed_mps, color="0.55", lw=2.2,
                  label=f"offline plan, whole route known ({offline.travel_time_s:.1f} s)")
    ax_v.plot(drive.s_m, drive.speed_mps, color="tab:blue", lw=1.3,
              label=f"driven online ({drive.travel_time_s:.1f} s)")
    ax_v.axhline(drive.unseen_speed_mps, color="tab:red", ls="--", lw=1,
                 label=f"allowed on unseen terrain, {unseen} ({drive.unseen_speed_mps:.3g} m/s)")
    ax_v.set_ylabel("speed (m/s)")
    ax_v.set_ylim(bottom=0)
    ax_v.legend(loc="upper right", fontsize=8)
    ahead = drive.cycle_edge_m - drive.cycle_s_m
    ax_e.plot(drive.cycle_s_m, ahead, color="tab:green", lw=1, label="planned terrain ahead (measured and complete)")
    ax_e.axhline(sensor_range_m, color="0.3", ls=":", lw=1, label=f"sensing range ({sensor_range_m:g} m)")
    ax_e.set_ylabel("ahead (m)")
    ax_e.set_ylim(bottom=0)
    ax_e.legend(loc="lower right", fontsize=8)
    ax_f.plot(drive.window_start_m, drive.window_ratio, color="tab:purple", lw=0.8,
              label="simulated peak force / limit, per roughness window")
    ax_f.axhline(1.0, color="tab:red", lw=1, label="the limit")
    ax_f.set_ylabel("force / limit")
    ax_f.set_ylim(0, max(1.1, float(np.max(drive.window_ratio)) * 1.05))
    ax_f.set_xlabel("distance along the route (m)")
    ax_f.legend(loc="upper right", fontsize=8)
    names = " with ".join(name for name in (route, vehicle) if name)
    fig.suptitle(f"Online speed selection{': ' + names if names else ''}, {sensor_range_m:g} m of sensing "
                 f"(worst window {drive.worst_window_ratio:.2f} of the limit)")
    return fig


def plot_drive(drive: "Drive", offline: "Profile | None", path: str | Path, *, sensor_range_m: float, unseen: str,
               route: str | None = None, vehicle: str | None = None) -> None:
    """Draw a drive's speed beside the offline plan, how far ahead it had planned, and the simulated
    force per roughness window; written atomically (PNG, or the format the extension names).

    Parameters
    ----------
    drive : Drive
        The closed-loop drive.
    offline : Profile or None
        The offline plan of the same route (None: not drawn).
    path : str or pathlib.Path
        Output file.
    sensor_range_m : float
        The sensing range (m).
    unseen : str
        What was assumed for unseen terrain, for the legend.
    route, vehicle : str, optional
        Names for the title.
    """
    save_figure(drive_figure(drive, offline, sensor_range_m=sensor_range_m, unseen=unseen, route=route,
                             vehicle=vehicle), path)
