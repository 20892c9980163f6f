"""The height of a rigid wheel rolling over a route's samples, at the samples.

Between samples the route means the straight line from one sample to the next; a rigid wheel
of radius r rolls on that polyline, and :func:`wheel_envelope_m` gives the height of its
lowest point above each sample. The simulator (:mod:`profileopt.verification.simulate`) needs the same
path between the samples too, kinks included: :func:`profileopt.physics.wheel_path.wheel_path`
builds it as lines and arcs, and agrees with this function at the samples.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import InputError

__all__ = ["wheel_envelope_m"]


def wheel_envelope_m(s_m: np.ndarray, z_m: np.ndarray, wheel_radius_m: float) -> np.ndarray:
    r"""Base input y of a rigid wheel rolling over the piecewise-linear terrain through the samples (m).

    Between samples the route means the straight line from one sample to the next, so the
    wheel rolls on that polyline. With its centre above x, the wheel stands as low as it can
    without entering the ground: its centre height is

        w(x) = max over terrain points p with |x_p - x| <= r of z_p + sqrt(r^2 - (x_p - x)^2),

    and y(x) = w(x) - r is the height of its lowest point. On one segment the quantity
    maximised is a line plus the upper half of a circle, a concave function of x_p, so its
    maximum lies at one of the segment's ends or where the circle is tangent to the segment
    (never at |x_p - x| = r, where the circle is vertical). Hence w(x) is the largest of

    (a) the circles of radius r about the vertices, z_i + sqrt(r^2 - (x_i - x)^2) for
        |x_i - x| <= r;
    (b) the segments offset by r along their normals. A wheel touching segment i (slope
        m = (z_{i+1} - z_i) / (x_{i+1} - x_i), line z_i(x) = z_i + m (x - x_i)) at an
        inner point C = (x_c, z_i(x_c)) is tangent to it there, so its centre O lies a
        distance r from C along the upward unit normal (-m, 1) / sqrt(1 + m^2)::

                                    O  centre (x, w)
                                     \
                                    r \             ___---   segment, slope m > 0
                                       \    ___---
                                ___---  C  contact point (x_c, z_i(x_c))
                        ___---
                                    |<->|   x_c - x = r m / sqrt(1 + m^2)

        x = x_c - r m / sqrt(1 + m^2),   w = z_i(x_c) + r / sqrt(1 + m^2),

        and with z_i(x_c) = z_i(x) + m (x_c - x) = z_i(x) + r m^2 / sqrt(1 + m^2):

            w = z_i(x) + r sqrt(1 + m^2),
            valid for x in [x_i - r m / sqrt(1 + m^2), x_{i+1} - r m / sqrt(1 + m^2)],

        the centre positions whose contact point x_c lies on the segment: the line offset
        by r along its normal is the line raised by r sqrt(1 + m^2) vertically.

    (For m > 0, as sketched, the contact point is ahead of the centre, uphill; for m < 0 it
    is behind it; the formulas hold for either sign.) So on a straight incline
    y = z + r (sqrt(1 + m^2) - 1) exactly, however the samples are spaced; a step of height
    e < r is climbed along the circle about its top edge over X_w = sqrt(2 e r - e^2)
    (Eq. 2); a wheel bridges a pothole narrower than 2 r.

    Placing circles on the samples alone (ignoring the ground between them) would leave the
    wheel sagging between samples on a slope, by up to r (sqrt(1 + m^2) - 1) (7.7 mm on a
    slope of 0.4; 3.6 mm measured on a sinusoid of that slope sampled every 5 cm): a
    scallop at the sample spacing that the damper turns into force at speed.

    y is evaluated at the samples only. Between them the path has structure that values at
    the samples cannot show: a kink at every concave vertex (two offset lines meet), the
    wheel meeting an edge ahead, the drop off a step (off curb.csv's 0.15 m step sampled
    every 5 cm the path falls at the wall's slope, 3, for 2.5 cm; a curve through the values
    at the samples at about 1.4). :func:`profileopt.physics.wheel_path.wheel_path` gives the whole
    path, which is what the simulator drives on.

    The terrain beyond the route's ends is unknown; it is continued along the first and the
    last chord for 2 r, so that a wheel near an end is neither lifted nor dropped by missing
    ground (on a straight incline the formula above holds up to the last sample).

    Vectorised over the samples: one pass per neighbour offset, and only the vertices within
    r of a sample and the segments reaching within r of it can touch the wheel (about
    2 r / spacing offsets), so 2e5 samples at 1 cm take a few tens of milliseconds.

    Parameters
    ----------
    s_m : numpy.ndarray, shape (M,)
        Distance along the route (m), strictly increasing.
    z_m : numpy.ndarray, shape (M,)
        Elevation (m).
    wheel_radius_m : float
        Wheel radius r (m), > 0.

    Returns
    -------
    numpy.ndarray, shape (M,)
        y (m), in the datum of ``z_m``; y_j >= z_j.

    Raises
    ------
    InputError
        A radius that is not a finite number > 0, or s not strictly increasing.
    """
    s = np.asarray(s_m, dtype=float)
    z = np.asarray(z_m, dtype=float)
    r = float(wheel_radius_m)
    if not (math.isfinite(r) and r > 0):
        raise InputError(f"wheel radius = {wheel_radius_m!r} m: must be a finite number > 0")
    if s.size < 2:
        return z.copy()
    if not np.all(np.diff(s) > 0):
        raise InputError("route: the distances s must increase strictly from sample to sample")
    # The polyline, continued along the end chords by 2 r (one extra vertex at each end: a
    # contact point is always within r of the centre, and these vertices are beyond r).
    pad = 2.0 * r
    head_grade = (z[1] - z[0]) / (s[1] - s[0])
    tail_grade = (z[-1] - z[-2]) / (s[-1] - s[-2])
    xs = np.concatenate([[s[0] - pad], s, [s[-1] + pad]])
    zs = np.concatenate([[z[0] - head_grade * pad], z, [z[-1] + tail_grade * pad]])
    m_pts = s.size  # query j (sample j) is vertex j + 1 of the polyline

    # Segment i runs from vertex i to i + 1 (i = 0 .. M): slope, the offset's rise above the
    # line r (sqrt(1 + m^2) - 1) = r dz^2 / (dx (hyp + dx)) (no cancellation on gentle
    # ground), and the centre positions [lo, hi] whose contact point lies on it.
    dx = np.diff(xs)
    dz = np.diff(zs)
    hyp = np.hypot(dx, dz)
    slope = dz / dx
    lift = r * dz * dz / (dx * (hyp + dx))
    shift = r * dz / hyp  # r m / sqrt(1 + m^2)
    lo = xs[:-1] - shift
    hi = xs[1:] - shift

    # Offsets (in vertex index, relative to the query's own vertex) that can matter.
    own = np.arange(1, m_pts + 1)
    first = np.searchsorted(xs, s - r, side="left") - own  # first vertex within r, <= 0
    last = np.searchsorted(xs, s + r, side="right") - 1 - own  # last vertex within r, >= 0
    lowest, highest = int(first.min()), int(last.max())

    y = z.copy()  # vertex j's own circle: w - r = z_j
    r2 = r * r
    # (a) circles about the other vertices within r: z_i - d^2 / (r + sqrt(r^2 - d^2))
    for offset in range(lowest, highest + 1):
        if offset == 0:
            continue
        q = slice(max(0, -offset - 1), min(m_pts, m_pts + 1 - offset))  # queries j
        v = slice(q.start + 1 + offset, q.stop + 1 + offset)  # their vertices j + 1 + offset
        d = xs[v] - s[q]
        d2 = d * d
        inside = d2 <= r2
        if not np.any(inside):
            continue
        drop = np.where(inside, d2 / (r + np.sqrt(np.maximum(r2 - d2, 0.0))), np.inf)
        np.maximum(y[q], zs[v] - drop, out=y[q])
    # (b) offset segments: segment j + 1 + offset, for offsets from the one holding s - r
    # (first - 1) to the one holding s + r (last)
    for offset in range(lowest - 1, highest + 1):
        q = slice(max(0, -offset - 1), min(m_pts, m_pts - offset))  # queries j
        g = slice(q.start + 1 + offset, q.stop + 1 + offset)  # their segments
        x = s[q]
        valid = (lo[g] <= x) & (x <= hi[g])
        if not np.any(valid):
            continue
        line = zs[g] + slope[g] * (x - xs[g]) + lift[g]
        np.maximum(y[q], np.where(valid, line, -np.inf), out=y[q])
    return y
