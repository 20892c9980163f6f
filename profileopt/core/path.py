"""The route's turns and slopes, per segment (for the limits) and per boundary (for output).

The curvature and grade come at every route sample from :mod:`profileopt.terrain.geometry`. A
segment's limits must hold everywhere inside it, so each segment carries the largest
|curvature| and the least and largest grade of its samples and of the sample just outside
each of its ends (the path between two samples lies between their values). The curvature
is taken over a wider reach, :attr:`~profileopt.terrain.geometry.RouteGeometry.curvature_reach_m`
either side: the smoothing spreads a turn's curvature over that length, so the full
curvature of a turn caps the speed wherever the route's own samples turn (the smoothed
path enters a turn more gently than the samples do).
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING

import numpy as np

from ..terrain.roughness import range_extremes

if TYPE_CHECKING:
    from ..terrain.geometry import RouteGeometry
    from .route import Route
    from .segments import Segments

__all__ = ["SegmentPath", "segment_path", "flat_path"]


@dataclasses.dataclass(frozen=True, eq=False)
class SegmentPath:
    """Turns and slopes of a route cut into N segments.

    Attributes
    ----------
    curvature_max_1pm : numpy.ndarray, shape (N,)
        Largest |curvature| of the path in each segment (1/m).
    grade_lo_rad, grade_hi_rad : numpy.ndarray, shape (N,)
        Least and largest grade in each segment (rad, positive uphill).
    curvature_1pm : numpy.ndarray, shape (N+1,)
        Signed curvature at the boundaries (1/m, left turns positive), for output.
    grade_rad : numpy.ndarray, shape (N+1,)
        Grade at the boundaries (rad), for output.
    tolerance_m : float
        The path tolerance the curvature was found with (m); 0 for a straight route.
    grade_scale_m : float
        The length over which the grade was measured (m).
    max_deviation_m : float
        How far the smoothed path strays from the route's samples (m).
    """

    curvature_max_1pm: np.ndarray
    grade_lo_rad: np.ndarray
    grade_hi_rad: np.ndarray
    curvature_1pm: np.ndarray
    grade_rad: np.ndarray
    tolerance_m: float = 0.0
    grade_scale_m: float = 0.0
    max_deviation_m: float = 0.0

    @property
    def has_turns(self) -> bool:
        """Whether any segment curves."""
        return bool(np.any(self.curvature_max_1pm > 0))


def segment_path(route: "Route", segments: "Segments", geometry: "RouteGeometry") -> SegmentPath:
    """Per-segment extremes and per-boundary values of a route's curvature and grade.

    Parameters
    ----------
    route : Route
        The route (its samples' positions).
    segments : Segments
        The route cut into N segments.
    geometry : RouteGeometry
        Curvature and grade at every sample (:func:`profileopt.terrain.geometry.route_geometry`).

    Returns
    -------
    SegmentPath
    """
    m = route.s_m.size
    first = np.maximum(segments.first_sample - 1, 0)
    stop = np.minimum(segments.first_sample + segments.samples + 1, m)
    bounds = segments.boundaries_m
    reach = float(geometry.curvature_reach_m)
    k_first = np.minimum(first, np.searchsorted(route.s_m, bounds[:-1] - reach, side="left"))
    k_stop = np.maximum(stop, np.minimum(np.searchsorted(route.s_m, bounds[1:] + reach, side="right"), m))
    _, kappa_max = range_extremes(np.abs(geometry.curvature_1pm), k_first, k_stop)
    grade_lo, grade_hi = range_extremes(geometry.grade_rad, first, stop)
    return SegmentPath(
        curvature_max_1pm=kappa_max, grade_lo_rad=grade_lo, grade_hi_rad=grade_hi,
        curvature_1pm=np.interp(bounds, route.s_m, geometry.curvature_1pm),
        grade_rad=np.interp(bounds, route.s_m, geometry.grade_rad),
        tolerance_m=float(geometry.tolerance_m), grade_scale_m=float(geometry.grade_scale_m),
        max_deviation_m=float(geometry.max_deviation_m),
    )


def flat_path(n: int) -> SegmentPath:
    """A straight, level path of N segments (no turns, no grade).

    Parameters
    ----------
    n : int
        Number of segments.

    Returns
    -------
    SegmentPath
    """
    return SegmentPath(curvature_max_1pm=np.zeros(n), grade_lo_rad=np.zeros(n), grade_hi_rad=np.zeros(n),
                       curvature_1pm=np.zeros(n + 1), grade_rad=np.zeros(n + 1))
