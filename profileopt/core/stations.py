"""Which samples, and which points, belong to which segment of a route.

A route's segments are cut at boundaries s_0 < s_1 < ... < s_N (m). Segment i covers
s_i <= s < s_{i+1}, the last one closed at s_N. Everything that asks "which segment" (the
planner's roughness per segment, the simulator's datum per segment, the verification's
peak force per segment) asks it here, so that they all agree.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["segment_samples", "segment_index"]


def segment_samples(positions_m: ArrayLike, boundaries_m: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """The range of samples in each segment: samples ``starts[i]:stops[i]`` lie in segment i.

    Parameters
    ----------
    positions_m : array_like, shape (M,)
        Sample positions s (m), increasing.
    boundaries_m : array_like, shape (N+1,)
        Segment boundaries (m), increasing.

    Returns
    -------
    starts, stops : numpy.ndarray of int, shape (N,)
        First sample of each segment and one past its last (``stops[i] == starts[i + 1]``);
        a segment without samples has ``starts[i] == stops[i]``.
    """
    s = np.asarray(positions_m, dtype=float)
    b = np.asarray(boundaries_m, dtype=float)
    starts = np.searchsorted(s, b[:-1], side="left")
    stops = np.append(starts[1:], np.searchsorted(s, b[-1], side="right"))
    return starts, stops


def segment_index(points_m: ArrayLike, boundaries_m: ArrayLike) -> np.ndarray:
    """The segment each point lies in; points outside go to the first or last segment.

    Also serves any other axis cut into intervals (times at the boundaries, plot bins).

    Parameters
    ----------
    points_m : array_like, shape (K,)
        Positions (m).
    boundaries_m : array_like, shape (N+1,)
        Segment boundaries (m), increasing.

    Returns
    -------
    numpy.ndarray of int, shape (K,)
        Index i in 0 .. N-1 with boundaries_m[i] <= point < boundaries_m[i+1].
    """
    b = np.asarray(boundaries_m, dtype=float)
    return np.clip(np.searchsorted(b, points_m, side="right") - 1, 0, b.size - 2)
