"""The top of the force model's first admissible speed band, tabulated once per vehicle and
model: the online selector's force limit at a table look-up per roughness window.

The selector keeps, of each segment's speed bands, the first, [0, V]
(:mod:`profileopt.online.selector`): V is the largest speed with every speed in [0, V]
admissible for every roughness window the segment meets, that is the least over those windows
of each window's own V. Finding V exactly for every new window (a safeguarded Newton solve of
the force model, :func:`profileopt.physics.speeds.speed_bands`) costs a few milliseconds per
call however few the windows, most of a cycle's budget. The table holds, for consecutive RI
ranges [r_(i-1), r_i] of a geometric grid, the V that holds for *every* RI of the range (the
bands of the range, ``speed_bands(r_i, ri_min=r_(i-1))``: the largest force over the range,
resonance peaks included); a window with RI r in (r_(i-1), r_i] takes that entry. So the
table's V is never above the exact one, for any model and any vehicle, monotone in the RI or
not; it is below it by at most the change of V across one grid step (a grid ratio of 1.0026:
for the bundled vehicles on random sets at least 0.996 of the exact V above a crawl with
SBEM:TF, at most 0.06 m/s below it with any model, tests/online/test_band_table.py). RIs above
the grid are found exactly.
"""

from __future__ import annotations

import dataclasses
import functools
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from ..physics.speeds import speed_bands, speed_bands_of_sets
from ..terrain.roughness import check_ri, range_extremes

if TYPE_CHECKING:
    from ..core.vehicle import Vehicle

__all__ = ["FirstBandTable", "first_band_table", "RI_GRID_LOW", "RI_GRID_HIGH", "RI_GRID_POINTS"]

#: The grid's least RI (its first entry covers [0, RI_GRID_LOW]).
RI_GRID_LOW = 1e-4
#: The grid's largest RI; rougher windows are found exactly.
RI_GRID_HIGH = 4.0
#: Grid points, geometric from RI_GRID_LOW to RI_GRID_HIGH: a ratio of 1.0026 between neighbours.
RI_GRID_POINTS = 4096


@dataclasses.dataclass(frozen=True)
class FirstBandTable:
    """The first band's top for ranges of RI, for one vehicle and force model.

    Attributes
    ----------
    vehicle : Vehicle
        The quarter car, its force limit and top speed.
    model : str
        Force model key.
    ri_grid : numpy.ndarray, shape (M,)
        Increasing RIs r_0 .. r_(M-1) (dimensionless).
    top_mps : numpy.ndarray, shape (M,)
        Entry i: the largest V (m/s) with every speed in [0, V] admissible for every RI in
        [r_(i-1), r_i] (r_(-1) = 0); 0 where no band starts at rest.
    highest_lo_mps, highest_hi_mps : numpy.ndarray, shape (M,)
        Entry i: the edges (m/s) of the highest band admissible for every RI in
        [r_(i-1), r_i]: the first, [0, v1], where it is the only one; NaN where there is none
        (the selector's upper band, :mod:`.selector`).
    """

    vehicle: "Vehicle"
    model: str
    ri_grid: np.ndarray
    top_mps: np.ndarray
    highest_lo_mps: np.ndarray
    highest_hi_mps: np.ndarray

    def first_of_sets(self, values: ArrayLike, first: ArrayLike, stop: ArrayLike) -> np.ndarray:
        """The first band's top of each set of RIs (m/s): never above the exact one.

        Parameters
        ----------
        values : array_like, shape (K,)
            RIs (dimensionless), >= 0.
        first, stop : array_like of int, shape (N,)
            Set i is ``values[first[i]:stop[i]]``, non-empty (the windows a segment meets:
            :meth:`profileopt.core.segments.Segments.window_ranges`).

        Returns
        -------
        numpy.ndarray, shape (N,)
            Speed (m/s) V of each set, with [0, V] admissible for each of its RIs, within
            [0, max_speed_mps].
        """
        values = np.atleast_1d(np.asarray(values, dtype=float))
        check_ri(values)
        first = np.asarray(first, dtype=np.intp)
        stop = np.asarray(stop, dtype=np.intp)
        if not first.size:
            return np.empty(0)
        at, beyond = self._rows(values)
        per_window = self.top_mps[at]
        per_window[beyond] = -1.0  # marks the sets to find exactly
        tops, _ = range_extremes(per_window, first, stop)
        exact = tops < 0.0
        if np.any(exact):
            bands, _ = speed_bands_of_sets(values, first[exact], stop[exact], self.vehicle, model=self.model)
            tops[exact] = bands.first()
        return tops

    def highest_of_sets(self, values: ArrayLike, first: ArrayLike, stop: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """The highest band admissible for every RI of each set (m/s): the intersection of the
        table's highest bands of the ranges holding its RIs, never wider than the exact one.

        Parameters
        ----------
        values : array_like, shape (K,)
            RIs (dimensionless), >= 0.
        first, stop : array_like of int, shape (N,)
            Set i is ``values[first[i]:stop[i]]``, non-empty.

        Returns
        -------
        lo, hi : numpy.ndarray, shape (N,)
            The band's edges (m/s): the largest lower edge and the least upper edge of its RIs'
            ranges; lo = inf and hi = -inf where an RI is rougher than the table or its range has
            no band (so that no band is taken there).
        """
        values = np.atleast_1d(np.asarray(values, dtype=float))
        at, beyond = self._rows(values)
        lo_w = np.where(beyond | np.isnan(self.highest_lo_mps[at]), np.inf, self.highest_lo_mps[at])
        hi_w = np.where(beyond | np.isnan(self.highest_hi_mps[at]), -np.inf, self.highest_hi_mps[at])
        first = np.asarray(first, dtype=np.intp)
        stop = np.asarray(stop, dtype=np.intp)
        _, lo = range_extremes(lo_w, first, stop)
        hi, _ = range_extremes(hi_w, first, stop)
        return lo, hi

    def _rows(self, values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The table's row of the range (r_(at-1), r_at] holding each RI, and whether the RI is
        rougher than the table (its row then the last)."""
        at = np.searchsorted(self.ri_grid, values, side="left")
        beyond = at >= self.ri_grid.size
        return np.minimum(at, self.ri_grid.size - 1), beyond


@functools.lru_cache(maxsize=16)
def first_band_table(vehicle: "Vehicle", model: str) -> FirstBandTable:
    """The :class:`FirstBandTable` of a vehicle and model, built once per process (about 0.1 s).

    Parameters
    ----------
    vehicle : Vehicle
        The quarter car, its force limit and top speed.
    model : str
        Force model key.

    Returns
    -------
    FirstBandTable
    """
    grid = np.geomspace(RI_GRID_LOW, RI_GRID_HIGH, RI_GRID_POINTS)
    below = np.concatenate([[0.0], grid[:-1]])
    bands = speed_bands(grid, vehicle, model=model, ri_min=below)
    top = bands.first()
    rows, last = np.arange(grid.size), np.maximum(bands.count - 1, 0)
    some = bands.count >= 1
    highest_lo = np.where(some, bands.lower_mps[rows, last], np.nan)
    highest_hi = np.where(some, bands.upper_mps[rows, last], np.nan)
    for array in (top, grid, highest_lo, highest_hi):
        array.setflags(write=False)
    return FirstBandTable(vehicle=vehicle, model=model, ri_grid=grid, top_mps=top, highest_lo_mps=highest_lo,
                          highest_hi_mps=highest_hi)
