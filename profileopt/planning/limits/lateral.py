"""The lateral acceleration limit in turns: the vehicle's own bound and its rollover threshold,
and its turning circle.

v^2 kappa <= a_lat, where a_lat is the smaller of ``max_lateral_accel_mps2`` and the static
rollover threshold g t / (2 h_cg) (:func:`profileopt.physics.motion.lateral_limit_mps2`). With the
segment's largest |kappa| it caps every speed driven inside the segment at
sqrt(a_lat / kappa_max). Where kappa_max is sharper than the vehicle's ``min_turn_radius_m``
(a reversal, a hairpin tighter than its turning circle) the vehicle cannot make the turn in
one sweep: the cap is then at most :data:`~profileopt.defaults.CRAWL_SPEED_MPS`
(:func:`profileopt.physics.motion.turn_speed_cap_mps`), and the plan's notes name the place
(:func:`profileopt.terrain.geometry.sharp_turns`).
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING

import numpy as np

from ...defaults import CRAWL_SPEED_MPS
from ...physics.motion import lateral_accel_mps2, turn_speed_cap_mps
from .base import Limit, PlanContext, worst_ratio

if TYPE_CHECKING:
    from ...core.profile import Profile

__all__ = ["LateralLimit"]


@dataclasses.dataclass(frozen=True)
class LateralLimit(Limit):
    """v^2 |kappa| <= limit_mps2 at every speed and curvature of every segment, and a crawl
    where a segment turns sharper than the vehicle's ``min_turn_radius_m``.

    Attributes
    ----------
    limit_mps2 : float
        Lateral acceleration limit (m/s^2), > 0.
    """

    limit_mps2: float
    name = "lateral"
    binding = "lateral"

    def speed_cap_mps(self, context: PlanContext) -> np.ndarray:
        """sqrt(limit / kappa_max) per segment (m/s), inf on straights, at most
        CRAWL_SPEED_MPS where kappa_max > 1 / min_turn_radius_m, shape (N,).

        Parameters
        ----------
        context : PlanContext
            The route, vehicle and segments of the plan.

        Returns
        -------
        numpy.ndarray
        """
        return turn_speed_cap_mps(self.limit_mps2, context.turns_and_slopes.curvature_max_1pm,
                                  context.vehicle.min_turn_radius_m)

    def cap_stretches_m(self, context: PlanContext) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        """The route's sharp turns and reversals (:attr:`SegmentPath.turns
        <profileopt.core.path.SegmentPath.turns>`): each stretch widened by the curvature's reach
        (a segment takes its largest curvature that far beyond its samples), and the cap of its
        sharpest point (m/s). Refining then cuts a segment held at that cap just outside the
        stretch, so that a crawl through a hairpin or a reversal holds the turn, not the whole
        segment around it; the pieces outside take their own curvature's cap. None without
        sharp turns (an ordinary turn's cap holds whole segments).

        Parameters
        ----------
        context : PlanContext
            The route, vehicle and segments of the plan.

        Returns
        -------
        (start_m, end_m, cap_mps) : tuple of numpy.ndarray, shape (R,), or None
        """
        path = context.path
        if path is None or not path.turns:
            return None
        reach = path.curvature_reach_m
        start = np.array([turn.start_m for turn in path.turns]) - reach
        end = np.array([turn.end_m for turn in path.turns]) + reach
        kappa = np.array([1.0 / turn.radius_m for turn in path.turns])  # radius inf: 0
        return start, end, turn_speed_cap_mps(self.limit_mps2, kappa, context.vehicle.min_turn_radius_m)

    def check(self, profile: "Profile") -> float:
        """How far the largest lateral acceleration in any segment exceeds the limit, or its
        speed the crawl where it turns sharper than the turning circle (relative).

        Parameters
        ----------
        profile : Profile
            The profile about to be returned.

        Returns
        -------
        float
        """
        crawl = float(np.max(_crawled(profile), initial=0.0)) / CRAWL_SPEED_MPS - 1.0
        return max(float(np.max(_lateral(profile), initial=0.0)) / self.limit_mps2 - 1.0, crawl, 0.0)

    def margins(self, profile: "Profile") -> dict[str, dict]:
        """The largest lateral acceleration over the limit, and where.

        Parameters
        ----------
        profile : Profile
            A planned profile.

        Returns
        -------
        dict
            ``{"lateral": {...}}``.
        """
        return {"lateral": worst_ratio(_lateral(profile), self.limit_mps2, profile.s_m[:-1])}

    def cap_reason(self, profile: "Profile", segment: int) -> str:
        """"the lateral acceleration limit (... m/s^2) in a turn of radius ... m".

        Parameters
        ----------
        profile : Profile
            A planned profile.
        segment : int
            Index of the segment.

        Returns
        -------
        str
        """
        kappa = float(profile.path.curvature_max_1pm[segment]) if profile.path is not None else 0.0
        radius = f"{1.0 / kappa:.3g} m" if kappa > 0 else "inf"
        circle = _turning_circle_m(profile)
        sharper = (f", sharper than the vehicle's min_turn_radius_m ({circle:g} m)"
                   if circle is not None and kappa * circle > 1.0 else "")
        if sharper and self.limit_mps2 > CRAWL_SPEED_MPS**2 * kappa:  # the crawl is below the lateral cap
            return f"a crawl ({CRAWL_SPEED_MPS:g} m/s) through a turn of radius {radius}{sharper}"
        return f"the lateral acceleration limit ({self.limit_mps2:.3g} m/s^2) in a turn of radius {radius}{sharper}"


def _turning_circle_m(profile: Profile) -> float | None:
    """The turning circle the profile's path was judged against (m), or None."""
    return profile.path.min_turn_radius_m if profile.path is not None else None


def _crawled(profile: Profile) -> np.ndarray:
    """Each segment's top speed where it turns sharper than the turning circle (m/s), else 0."""
    circle = _turning_circle_m(profile)
    if profile.path is None or circle is None:
        return np.zeros(profile.s_m.size - 1)
    top = np.maximum(profile.speed_mps[:-1], profile.speed_mps[1:])
    return np.where(profile.path.curvature_max_1pm * circle > 1.0, top, 0.0)


def _lateral(profile: "Profile") -> np.ndarray:
    """The largest lateral acceleration of each segment (m/s^2), shape (N,)."""
    if profile.path is None:
        return np.zeros(profile.s_m.size - 1)
    top = np.maximum(profile.speed_mps[:-1], profile.speed_mps[1:])
    return lateral_accel_mps2(top, profile.path.curvature_max_1pm)
