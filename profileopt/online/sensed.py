"""The terrain a vehicle has measured so far along its path, and where measurement stops.

A sensor (a LiDAR, a stereo camera, a profiler) reports elevation samples along the path ahead
of the vehicle, a little more every cycle, in no particular order and with gaps. Terrain counts
as *measured* only as far as the samples are dense enough to measure wheel-scale roughness:
consecutive samples no further apart than
:data:`~profileopt.defaults.MAX_ROUGHNESS_SPACING_M` (the rule ``profileopt route`` applies to
point clouds and grids, :func:`profileopt.terrain.ground_track.supported_spacing_m`). Beyond the
first wider gap the terrain is *unseen*, whatever has been sensed there, until the gap is
filled.

Measured terrain is frozen: a later sample at a position already measured is ignored, so the
speeds the selector allows there never change under it (and a noisy re-measurement cannot
undo a plan under way). A gap that is never filled (a blind spot) is given up on when the
vehicle comes near it (:meth:`SensedTerrain.skip_gap`): the stretch starts again beyond it,
and the gap stays unseen. Samples far behind the vehicle are forgotten, so memory stays
bounded however long the route.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from ..core.route import Route
from ..defaults import MAX_ROUGHNESS_SPACING_M
from ..errors import InputError

__all__ = ["SensedTerrain"]


class SensedTerrain:
    """The samples sensed along the path: a measured (dense, frozen) stretch and pending ones.

    Parameters
    ----------
    start_m : float
        Where the path starts (m): the first measured sample must lie within
        ``max_spacing_m`` of it.
    max_spacing_m : float, default :data:`~profileopt.defaults.MAX_ROUGHNESS_SPACING_M`
        The widest gap (m) between consecutive samples of measured terrain.
    source : str, default "sensor"
        Named in messages and in the routes :meth:`stretch` returns.
    """

    def __init__(self, *, start_m: float, max_spacing_m: float = MAX_ROUGHNESS_SPACING_M,
                 source: str = "sensor") -> None:
        if not math.isfinite(start_m):
            raise InputError(f"{source}: start_m = {start_m!r} must be a finite position (m)")
        if not (math.isfinite(max_spacing_m) and max_spacing_m > 0):
            raise InputError(f"{source}: max_spacing_m = {max_spacing_m!r} must be a number > 0 (m)")
        self.start_m = float(start_m)
        self.max_spacing_m = float(max_spacing_m)
        self.source = source
        # measured samples, in order; columns s, z, x, y, speed limit (NaN where not given)
        self._measured = np.empty((0, 5))
        self._pending = np.empty((0, 5))
        self._has_xy: bool | None = None
        self._from_m = self.start_m  # where the measured stretch starts (moved by skip_gap)
        self._has_limit = False

    @property
    def measured_to_m(self) -> float:
        """Where the measured terrain ends (m): the last sample of the dense stretch, or where
        the stretch starts (``start_m``, or the end of a skipped gap) before any."""
        return float(self._measured[-1, 0]) if self._measured.shape[0] else self._from_m

    @property
    def measured_from_m(self) -> float:
        """The first measured sample still kept (m); where the stretch starts before any."""
        return float(self._measured[0, 0]) if self._measured.shape[0] else self._from_m

    @property
    def sample_count(self) -> int:
        """Samples held, measured and pending: what the memory grows with."""
        return int(self._measured.shape[0] + self._pending.shape[0])

    def add(self, s_m: ArrayLike, z_m: ArrayLike, *, x_m: ArrayLike | None = None, y_m: ArrayLike | None = None,
            speed_limit_mps: ArrayLike | None = None) -> None:
        """Take newly sensed samples.

        Parameters
        ----------
        s_m, z_m : array_like, shape (K,)
            Distance along the path (m) and elevation (m) of each sample, in any order.
            Samples at or before :attr:`measured_to_m` are ignored (measured terrain is
            frozen); of several at one position, the first is kept.
        x_m, y_m : array_like, shape (K,), optional
            The samples' position in the horizontal plane (m), for the path's turns: give
            them with every call or never.
        speed_limit_mps : array_like, shape (K,), optional
            A speed limit at each sample (m/s) from a map, if any.

        Raises
        ------
        InputError
            Arrays of different lengths, non-finite values, or x, y given in some calls only.
        """
        s = np.atleast_1d(np.asarray(s_m, dtype=float))
        z = np.atleast_1d(np.asarray(z_m, dtype=float))
        if s.ndim != 1 or z.shape != s.shape:
            raise InputError(f"{self.source}: s_m and z_m must be 1-D arrays of the same length, got shapes "
                             f"{s.shape} and {z.shape}")
        has_xy = x_m is not None or y_m is not None
        if has_xy and (x_m is None or y_m is None):
            raise InputError(f"{self.source}: give both x_m and y_m (the path in the horizontal plane) or neither")
        columns = {}
        for name, values in (("x_m", x_m), ("y_m", y_m), ("speed_limit_mps", speed_limit_mps)):
            if values is not None:
                column = np.atleast_1d(np.asarray(values, dtype=float))
                if column.shape != s.shape:
                    raise InputError(f"{self.source}: {name} has shape {column.shape} but s_m has {s.shape}; give one "
                                     "value per sample")
                columns[name] = column
        if s.size == 0:
            return
        if self._has_xy is not None and self._has_xy != has_xy:
            raise InputError(f"{self.source}: x_m and y_m were given with {'earlier' if self._has_xy else 'these'} "
                             "samples but not with the others; give them with every call or never")
        rows = np.full((s.size, 5), np.nan)
        rows[:, 0], rows[:, 1] = s, z
        if has_xy:
            rows[:, 2], rows[:, 3] = columns["x_m"], columns["y_m"]
        if speed_limit_mps is not None:
            rows[:, 4] = columns["speed_limit_mps"]
        checked = rows[:, :4] if has_xy else rows[:, :2]
        if not np.all(np.isfinite(checked)):
            bad = int(np.flatnonzero(~np.all(np.isfinite(checked), axis=1))[0])
            raise InputError(f"{self.source}: sample {bad} (s = {s[bad]!r} m) is not finite; drop it before "
                             "passing the samples")
        if speed_limit_mps is not None and not np.all(rows[:, 4] > 0):
            raise InputError(f"{self.source}: speed limits must be numbers > 0 (m/s)")
        self._has_xy = has_xy  # only once every check has passed
        self._has_limit = self._has_limit or speed_limit_mps is not None
        floor = self.measured_to_m if self._measured.shape[0] else self._from_m - self.max_spacing_m
        rows = rows[rows[:, 0] > floor]
        if not rows.shape[0]:
            return
        pending = np.concatenate([self._pending, rows])
        pending = pending[np.argsort(pending[:, 0], kind="stable")]
        keep = np.concatenate([[True], np.diff(pending[:, 0]) > 0])  # the first at each position
        self._pending = pending[keep]
        self._absorb()

    def _absorb(self) -> None:
        """Move the dense prefix of the pending samples into the measured stretch."""
        pending = self._pending
        if not pending.shape[0]:
            return
        if self._measured.shape[0]:
            gaps = np.diff(np.concatenate([[self.measured_to_m], pending[:, 0]]))
            wide = np.flatnonzero(gaps > self.max_spacing_m * (1 + 1e-9))
            dense = int(wide[0]) if wide.size else pending.shape[0]
        else:  # the stretch starts at start_m: its first sample within the spacing of it
            if pending[0, 0] > self._from_m + self.max_spacing_m * (1 + 1e-9):
                return
            wide = np.flatnonzero(np.diff(pending[:, 0]) > self.max_spacing_m * (1 + 1e-9))
            dense = int(wide[0]) + 1 if wide.size else pending.shape[0]
        self._measured = np.concatenate([self._measured, pending[:dense]])
        self._pending = pending[dense:]

    @property
    def gap_m(self) -> tuple[float, float] | None:
        """The gap after the measured stretch, (from, to) in m, when samples were sensed beyond
        it; None when there are none."""
        if not self._pending.shape[0]:
            return None
        return self.measured_to_m, float(self._pending[0, 0])

    def skip_gap(self) -> tuple[float, float] | None:
        """Give up on the gap after the measured stretch (a blind spot that was never filled):
        the measured stretch starts again at the first sample beyond it, and the samples before
        are dropped.

        Returns
        -------
        (from_m, to_m) or None
            The gap skipped (m); None when there is none.
        """
        gap = self.gap_m
        if gap is None:
            return None
        self._measured = np.empty((0, 5))
        self._from_m = gap[1]
        self._absorb()
        return gap

    def forget_before(self, s_m: float) -> None:
        """Drop measured samples before ``s_m`` (m), keeping the last one before it.

        Parameters
        ----------
        s_m : float
            Position (m) before which nothing is needed any more.
        """
        cut = int(np.searchsorted(self._measured[:, 0], s_m, side="right")) - 1
        if cut > 0:
            self._measured = self._measured[cut:]

    def stretch(self, from_m: float, to_m: float) -> Route | None:
        """The measured samples in [``from_m``, ``to_m``] as a route (None if fewer than 2).

        Parameters
        ----------
        from_m, to_m : float
            The stretch (m).

        Returns
        -------
        Route or None
            With x, y and speed limits where they were given.
        """
        s = self._measured[:, 0]
        lo, hi = int(np.searchsorted(s, from_m, side="left")), int(np.searchsorted(s, to_m, side="right"))
        if hi - lo < 2:
            return None
        rows = self._measured[lo:hi]
        limit = None
        if self._has_limit:
            limit = np.where(np.isnan(rows[:, 4]), np.inf, rows[:, 4])
            limit = None if not np.any(np.isfinite(limit)) else np.minimum(limit, 1e6)
        return Route(s_m=rows[:, 0].copy(), z_m=rows[:, 1].copy(), speed_limit_mps=limit, source=self.source,
                     x_m=rows[:, 2].copy() if self._has_xy else None,
                     y_m=rows[:, 3].copy() if self._has_xy else None)
