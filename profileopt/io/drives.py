"""The driven profile of ``profileopt drive`` as a CSV file."""

from __future__ import annotations

import os
from typing import TYPE_CHECKING

import numpy as np

from .atomic import atomic_write

if TYPE_CHECKING:
    from ..online.drive import Drive

__all__ = ["write_drive", "DRIVE_COLUMNS"]

#: The columns of a drive CSV, in order.
DRIVE_COLUMNS = ("time_s", "s_m", "speed_mps", "accel_mps2", "edge_m", "edge_speed_mps")


def write_drive(drive: "Drive", path: str | os.PathLike, *, settings: dict[str, object]) -> None:
    """Write a driven profile atomically: a settings comment line, the header, one row per knot.

    Each row is a knot of the driven profile (every cycle's start and every segment boundary
    crossed): the time (s), position (m) and speed (m/s) there, the constant acceleration
    driven to the next knot (m/s^2), and the planning edge (m) and the horizon's speed there
    (m/s) of the cycle being driven. Numbers have 9 significant digits.

    Parameters
    ----------
    drive : Drive
        The closed-loop drive (:func:`profileopt.online.drive`).
    path : str or os.PathLike
        Output file ('-': standard output, inside an :class:`~profileopt.io.atomic.OutputSet`).
    settings : dict
        What the drive was run with, written as ``key=value`` on the first line (``# drive:``).
    """
    cycle = drive.knot_cycle
    columns = (drive.time_s, drive.s_m, drive.speed_mps, drive.knot_accel_mps2(), drive.cycle_edge_m[cycle],
               drive.cycle_edge_speed_mps[cycle])
    table = np.column_stack([np.asarray(c, dtype=float) + 0.0 for c in columns])
    meta = " ".join(f"{key}={str(value).replace(' ', '_')}" for key, value in settings.items())
    with atomic_write(path) as handle:
        handle.write(f"# drive: {meta}\n")
        handle.write(",".join(DRIVE_COLUMNS) + "\n")
        handle.write("".join(",".join(f"{x:.9g}" for x in row) + "\n" for row in table.tolist()))
