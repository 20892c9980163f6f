"""The refine round of a plan: which segments to cut after the first choice of bands, and where.

A segment is held to every roughness window and every ramp of the wheel's path that shares a
point with it, so a long segment that reaches into a rough stretch or touches a step is held
to its speeds over its whole length. After the bands are chosen once, the planner cuts

- the segments where the minimum-time profile meets its band's top, set by the force, where
  the roughness of their windows changes (:func:`.segments.refine_segments`);
- the segments where it meets a cap set on stretches of the route (a step's, a speed-limit
  zone's; :meth:`.limits.Limit.cap_stretches_m`) just outside the stretch that sets it
  (:func:`.segments.stretch_cuts`), and where their roughness changes as well: the cap hid
  their band's top, which the pieces off the stretch meet once they are free of it;

then chooses the bands again on the finer segments and solves once.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from .limits.base import Limit, PlanContext
from .segments import Segments, at_cap, at_force_cap, refine_segments, stretch_cuts

__all__ = ["refined_segments"]


def refined_segments(limits: Sequence[Limit], context: PlanContext, greatest_b: np.ndarray, band_top_mps: np.ndarray,
                     cap_mps: np.ndarray, cap_source: np.ndarray) -> Segments:
    """The plan's segments cut where the first minimum-time profile meets a cap.

    Parameters
    ----------
    limits : sequence of Limit
        The plan's limits.
    context : PlanContext
        The route, vehicle and segments of the first round.
    greatest_b : numpy.ndarray, shape (N+1,)
        The first round's minimum-time profile, v^2 at the boundaries (m^2/s^2).
    band_top_mps : numpy.ndarray, shape (N,)
        Top of each segment's chosen band (m/s), speed caps included.
    cap_mps : numpy.ndarray, shape (N,)
        Each segment's lowest cap (m/s).
    cap_source : numpy.ndarray of int, shape (N,)
        The index in ``limits`` of the limit giving that cap (-1: none).

    Returns
    -------
    Segments
        ``context.segments`` itself when nothing is cut.
    """
    seg, s_m = context.segments, context.route.s_m
    at = at_cap(greatest_b, cap_mps)
    cuts = []
    for k, limit in enumerate(limits):
        mine = at & (cap_source == k)
        if mine.any() and (stretches := limit.cap_stretches_m(context)) is not None:
            cuts.append(stretch_cuts(seg, s_m, np.where(mine, cap_mps, np.nan), *stretches))
    # refine_segments walks a segment cut at a stretch for roughness changes too (the cap
    # hid its band top)
    return refine_segments(seg, s_m, context.vehicle, at_force_cap(greatest_b, band_top_mps, cap_mps),
                           cut_at=np.concatenate(cuts) if cuts else None)
