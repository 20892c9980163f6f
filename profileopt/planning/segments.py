"""A route cut into segments: stations, the samples of each segment and its terrain numbers.

Segment i covers s_i <= s < s_{i+1} (the last one closed); which samples that is, is
decided in one place, :mod:`profileopt.stations`. Each segment's roughness index (RI,
Eq. 1, detrended) is measured from its own samples and gives the worst-case elevation
e_max of Eq. (8).
"""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING

import numpy as np

from ..defaults import DEFAULT_SEGMENT_LENGTH_M
from ..errors import InputError
from ..stations import segment_samples
from ..terrain import segment_roughness_index, worst_case_elevation

if TYPE_CHECKING:
    from ..route import Route
    from ..vehicle import Vehicle

__all__ = ["Segments", "segment_route", "MIN_SAMPLES_PER_SEGMENT", "DEFAULT_SEGMENT_LENGTH_M"]

#: A segment's RI is a standard deviation: with fewer samples it means little.
MIN_SAMPLES_PER_SEGMENT = 8


@dataclasses.dataclass(frozen=True, eq=False)
class Segments:
    """A route cut into segments, with each segment's samples and roughness.

    Attributes
    ----------
    boundaries_m : numpy.ndarray, shape (N+1,)
        Segment boundaries s_i (m); segment i covers s_i <= s < s_{i+1}, the last one closed.
    length_m : numpy.ndarray, shape (N,)
        Segment lengths (m).
    ri : numpy.ndarray, shape (N,)
        Detrended RI of each segment's own samples (dimensionless).
    e_max_m : numpy.ndarray, shape (N,)
        Worst-case elevation of Eq. (8) (m).
    first_sample : numpy.ndarray of int, shape (N,)
        Index of each segment's first route sample.
    samples : numpy.ndarray of int, shape (N,)
        Number of route samples in each segment.
    notes : tuple of str
        Decisions taken while segmenting (e.g. a short tail merged into its neighbour).
    """

    boundaries_m: np.ndarray
    length_m: np.ndarray
    ri: np.ndarray
    e_max_m: np.ndarray
    first_sample: np.ndarray
    samples: np.ndarray
    notes: tuple[str, ...] = ()

    @property
    def count(self) -> int:
        """Number of segments N."""
        return int(self.length_m.size)


def segment_route(route: "Route", vehicle: "Vehicle", segment_length_m: float = DEFAULT_SEGMENT_LENGTH_M
                  ) -> Segments:
    """Cut a route into segments of ``segment_length_m`` and measure each one's roughness.

    Parameters
    ----------
    route : Route
        The terrain samples.
    vehicle : Vehicle
        Supplies h (for the RI) and Pe (for e_max).
    segment_length_m : float, default 5
        Segment length (m), > 0 and at most the route's length. The last segment takes what
        is left; if that tail holds fewer than ``MIN_SAMPLES_PER_SEGMENT`` samples it is
        merged into the segment before it (noted in ``Segments.notes``).

    Returns
    -------
    Segments

    Raises
    ------
    InputError
        A bad segment length, or a segment with fewer than ``MIN_SAMPLES_PER_SEGMENT``
        samples (the message says what sample spacing is needed).
    """
    length = float(segment_length_m)
    total = route.length_m
    if not (math.isfinite(length) and length > 0):
        raise InputError(f"segment_length_m = {segment_length_m!r} m: must be a number > 0")
    if length > total * (1 + 1e-12):
        raise InputError(
            f"segment_length_m = {length:g} m is longer than the route {route.source} ({total:g} m); "
            "choose a shorter segment length"
        )
    s, z = route.s_m, route.z_m
    if total / length > s.size:  # more segments than samples: refuse before allocating them
        raise InputError(
            f"segment_length_m = {length:g} m cuts {route.source} ({total:g} m, {s.size} samples) into more "
            f"segments than it can fill with {MIN_SAMPLES_PER_SEGMENT} samples each; use at least "
            f"{MIN_SAMPLES_PER_SEGMENT * total / s.size:.3g} m"
        )
    n_full = max(int(math.floor(total / length + 1e-9)), 1)
    bounds = s[0] + length * np.arange(n_full + 1)
    if total - n_full * length > 1e-9 * max(total, 1.0):
        bounds = np.append(bounds, s[-1])
    bounds[-1] = s[-1]
    starts, stops = segment_samples(s, bounds)
    counts = stops - starts
    notes: tuple[str, ...] = ()
    if counts.size > 1 and counts[-1] < MIN_SAMPLES_PER_SEGMENT:
        notes = (
            f"the last {bounds[-1] - bounds[-2]:.3g} m hold only {counts[-1]} samples; "
            "merged into the segment before them",
        )
        bounds = np.delete(bounds, -2)
        starts, stops = segment_samples(s, bounds)
        counts = stops - starts
    thin = np.flatnonzero(counts < MIN_SAMPLES_PER_SEGMENT)
    if thin.size:
        i = thin[0]
        spacing = length / MIN_SAMPLES_PER_SEGMENT
        raise InputError(
            f"{route.source}: segment {i} ({bounds[i]:g} to {bounds[i + 1]:g} m) holds {counts[i]} samples; "
            f"measuring roughness needs at least {MIN_SAMPLES_PER_SEGMENT}: sample the route every "
            f"{spacing:.3g} m or closer, or raise segment_length_m"
        )
    ri = segment_roughness_index(s, z, starts, vehicle.ground_clearance_m)
    return Segments(
        boundaries_m=bounds,
        length_m=np.diff(bounds),
        ri=ri,
        e_max_m=worst_case_elevation(ri, vehicle),
        first_sample=starts,
        samples=counts,
        notes=notes,
    )
