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
import math
from typing import TYPE_CHECKING

import numpy as np

from ..defaults import CRAWL_SPEED_MPS
from ..terrain.geometry import REVERSAL_LENGTH_M
from ..terrain.roughness import range_extremes

if TYPE_CHECKING:
    from ..terrain.geometry import RouteGeometry, SharpTurn
    from .route import Route
    from .segments import Segments

__all__ = ["SegmentPath", "segment_path", "flat_path", "turn_notes"]

#: Most sharp turns named one by one in a plan's notes; the rest are counted.
MAX_TURN_NOTES = 3


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
    tolerance_source : str
        Where the tolerance came from: ``"given"``, ``"estimated"`` (from the route's x, y),
        or ``""`` (a straight route, no x, y).
    noise_m : float
        The horizontal noise estimated from the route's x, y (m); 0 without them.
    noise_points : int
        How many measured points it was estimated from.
    min_turn_radius_m : float or None
        The vehicle's turning circle the turns were judged against (m): a segment sharper
        than it is driven at a crawl (:mod:`profileopt.planning.limits.lateral`).
    turns : tuple of SharpTurn
        The stretches sharper than that turning circle, and the reversals
        (:func:`profileopt.terrain.geometry.sharp_turns`); :func:`turn_notes` words them.
    curvature_reach_m : float
        How far beyond its own samples a segment's largest curvature was taken (m; the
        module docstring).
    """

    curvature_max_1pm: np.ndarray
    grade_lo_rad: np.ndarray
    grade_hi_rad: np.ndarray
    curvature_1pm: np.ndarray
    grade_rad: np.ndarray
    tolerance_m: float = 0.0
    grade_scale_m: float = 0.0
    max_deviation_m: float = 0.0
    tolerance_source: str = ""
    noise_m: float = 0.0
    noise_points: int = 0
    min_turn_radius_m: float | None = None
    turns: tuple = ()
    curvature_reach_m: float = 0.0

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
        max_deviation_m=float(geometry.max_deviation_m), tolerance_source=geometry.tolerance_source,
        noise_m=float(geometry.noise_m), noise_points=int(geometry.noise_points),
        min_turn_radius_m=geometry.min_turn_radius_m, turns=tuple(geometry.turns), curvature_reach_m=reach,
    )


def turn_notes(turns: tuple[SharpTurn, ...], min_turn_radius_m: float | None, *, turns_limited: bool
               ) -> list[str]:
    """One line for each of the first few sharp turns of a route, and how many more there are.

    Parameters
    ----------
    turns : tuple of SharpTurn
        The turns sharper than the turning circle, and the reversals
        (:func:`profileopt.terrain.geometry.sharp_turns`).
    min_turn_radius_m : float or None
        The vehicle's turning circle (m).
    turns_limited : bool
        Whether the plan keeps a limit of turns (the vehicle file gives a lateral limit): a
        turn sharper than the turning circle is then crawled, else nothing slows it.

    Returns
    -------
    list of str
    """
    notes = []
    for turn in turns[:MAX_TURN_NOTES]:
        degrees = f"{math.degrees(turn.heading_change_rad):.0f} deg"
        what = (f"the path reverses (its heading turns {degrees} within {REVERSAL_LENGTH_M:g} m)" if turn.reversal
                else f"the path turns {degrees}")
        text = (f"s = {turn.s_m:.1f} m (x {turn.x_m:.2f}, y {turn.y_m:.2f}): {what}, a turn of radius "
                f"{turn.radius_m:.3g} m")
        if not turns_limited:
            notes.append(f"{text}: not slowed there, the vehicle file gives no limit of turns "
                         "(max_lateral_accel_mps2, track_width_m and cg_height_m)")
        elif min_turn_radius_m is not None and turn.radius_m < min_turn_radius_m:
            notes.append(f"{text}, sharper than the vehicle's min_turn_radius_m {min_turn_radius_m:g} m: planned "
                         f"at a crawl (at most {CRAWL_SPEED_MPS:g} m/s), the vehicle turning there in several moves")
        else:
            notes.append(f"{text}: planned at the speed the lateral limit allows in it")
    if len(turns) > MAX_TURN_NOTES:
        notes.append(f"and {len(turns) - MAX_TURN_NOTES} more such turns (the profile's curvature_1pm shows them)")
    return notes


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
