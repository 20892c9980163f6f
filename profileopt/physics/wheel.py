"""A rigid wheel rolling over a route's polyline: its height at the samples and its exact path.

Between samples the route means the straight line from one sample to the next; a rigid wheel
of radius r rolls on that polyline. :func:`wheel_envelope_m` gives the height of its lowest
point above each sample (the base input of the quarter car at the samples, for roughness and
the planner); :func:`wheel_path` the whole path between them, kinks included, as offset lines
and circular arcs (for the simulator, :mod:`profileopt.physics.simulate`, and the
steps of :mod:`profileopt.physics.steps`). The two agree at the samples.

Between samples the route means the straight line from one sample to the next. A rigid
wheel of radius r rolling on that polyline has its centre on the upper envelope of

* the segments offset by r along their upward normals (the wheel touches a segment inside
  it): segment i of slope m, raised vertically by r sqrt(1 + m^2), over the centre
  positions [x_i - r m / sqrt(1 + m^2), x_{i+1} - r m / sqrt(1 + m^2)] whose contact point
  lies on it (:func:`wheel_envelope_m` derives it);
* the circles of radius r about the vertices (the wheel touches a vertex). Only a convex
  vertex (the slope decreases across it, m_{i-1} > m_i) can carry the wheel alone, and only
  while the radius to it lies between the normals of its two segments, over the centre
  positions [x_i - r m_{i-1} / sqrt(1 + m_{i-1}^2), x_i - r m_i / sqrt(1 + m_i^2)]: outside
  that span the wheel touching the vertex would cut into a neighbouring segment, whose
  offset line is then higher. At a concave vertex the two offset lines cross above it.

Laid end to end (line, arc at a convex vertex, line, ...) these pieces form the raw offset
curve of the polyline; the wheel's centre is its upper envelope, the raw curve with the
loops that a concave vertex, a narrow pothole or a steep step cut into it trimmed away.
The lowest point of the wheel is the centre minus r, so the base input of the quarter car is
y(s) = (upper envelope) - r, a chain of straight lines and circular arcs of radius r:

    line:  y = z_ref + m (s - x_ref)
    arc:   y = z_c + sqrt(r^2 - (s - x_c)^2) - r     (z_c, x_c: the vertex)

Where one piece hands over to the next the path is continuous; its slope is continuous where
a line runs tangentially onto the arc of its own end vertex, and jumps (a kink) where the
contact switches between pieces that cross: two offset lines over a concave vertex, a line
and an arc (the wheel meets an edge ahead: a step of height e < r is met X_w =
sqrt(2 e r - e^2) before its edge, Eq. 2), or two arcs (a pothole bridged). The kinks are
located exactly (the crossings of two lines, of a line and a circle, of two circles of the
same radius, in closed form), not smoothed.

:func:`wheel_path` builds the envelope piece by piece, vectorised: the ends of all pieces'
spans cut the route into intervals on which the set of pieces present does not change; on
each, the highest piece at its middle is found and every other piece's crossings with it
inside the interval are computed; an interval with crossings is cut at them and examined
again, until every interval has one highest piece with nothing crossing it. Each cut is a
crossing of two pieces, so it ends. The work is done on the (interval, piece) pairs of the
pieces present, two to four per interval on a route sampled every few centimetres. Heights
are compared above a nearby vertex (a route 150 m up keeps its millimetres' digits), and an
interval is cut only where another piece rises above the highest by more than 64 units in
the last place of the largest elevation: rounding never invents crossings.

With r = 0 the path is the polyline itself (the base input without a wheel)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..errors import InputError

__all__ = ["wheel_envelope_m", "WheelPath", "wheel_path", "MAX_ROUNDS"]


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
    at the samples at about 1.4). :func:`profileopt.physics.wheel.wheel_path` gives the whole
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


#: Rounds of cutting intervals at crossings before :func:`wheel_path` gives up (a real
#: route needs 2 to 4).
MAX_ROUNDS = 200


@dataclasses.dataclass(frozen=True, eq=False)
class WheelPath:
    """y(s), the path of a rigid wheel's lowest point: P pieces, each a line or an arc.

    Piece p covers ``breaks_m[p] <= s <= breaks_m[p + 1]``. A line is
    y = z_ref + slope (s - x_ref); an arc is y = z_ref + sqrt(r^2 - (s - x_ref)^2) - r,
    the circle about the vertex (x_ref, z_ref).

    Attributes
    ----------
    breaks_m : numpy.ndarray, shape (P+1,)
        Where the pieces meet (m), increasing; the first and last are the route's ends.
    x_ref_m, z_ref_m : numpy.ndarray, shape (P,)
        A point of each line, or the vertex of each arc (m).
    slope : numpy.ndarray, shape (P,)
        Slope of each line (dimensionless); 0 for arcs.
    is_arc : numpy.ndarray of bool, shape (P,)
        True for arcs.
    wheel_radius_m : float
        r (m); 0 for the bare polyline.
    """

    breaks_m: np.ndarray
    x_ref_m: np.ndarray
    z_ref_m: np.ndarray
    slope: np.ndarray
    is_arc: np.ndarray
    wheel_radius_m: float

    @property
    def pieces(self) -> int:
        """Number of pieces P."""
        return int(self.slope.size)

    def piece_index(self, s_m: np.ndarray, side: str = "right") -> np.ndarray:
        """The piece holding each position; at a break, the piece after it or before it.

        Parameters
        ----------
        s_m : numpy.ndarray, shape (K,)
            Positions (m); outside the path they get its first or last piece.
        side : {"right", "left"}, default "right"
            At a break, the piece starting there ("right") or ending there ("left").

        Returns
        -------
        numpy.ndarray of int, shape (K,)
        """
        return np.clip(np.searchsorted(self.breaks_m, s_m, side=side) - 1, 0, self.pieces - 1)

    def evaluate(self, s_m: np.ndarray, piece: np.ndarray | None = None
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Height, slope and curvature of the path at given positions.

        Parameters
        ----------
        s_m : numpy.ndarray, shape (K,)
            Positions (m).
        piece : numpy.ndarray of int, shape (K,), optional
            The piece to evaluate at each position (its formula extends a little beyond its
            span, so rounding never matters); default :meth:`piece_index` (side "right").

        Returns
        -------
        y_m, dy_ds, d2y_ds2 : numpy.ndarray, shape (K,)
            y (m), dy/ds (dimensionless), d^2y/ds^2 (1/m).
        """
        s = np.asarray(s_m, dtype=float)
        p = self.piece_index(s) if piece is None else np.asarray(piece)
        d = s - self.x_ref_m[p]
        r = self.wheel_radius_m
        arc = self.is_arc[p]
        # on an arc |d| <= r sin(theta) < r; elsewhere the argument is unused
        root = np.sqrt(np.where(arc, np.maximum(r * r - d * d, 0.25 * r * r * 1e-30), 1.0))
        y = np.where(arc, self.z_ref_m[p] - d * d / (r + root), self.z_ref_m[p] + self.slope[p] * d)
        dy = np.where(arc, -d / root, self.slope[p])
        d2y = np.where(arc, -(r * r) / (root * root * root), 0.0)
        return y, dy, d2y

    def kinks(self) -> np.ndarray:
        """Jump of the slope dy/ds at each interior break (dimensionless), shape (P-1,)."""
        inner = self.breaks_m[1:-1]
        p = np.arange(self.pieces - 1)
        return self.evaluate(inner, p + 1)[1] - self.evaluate(inner, p)[1]


def _raw_pieces(s: np.ndarray, z: np.ndarray, r: float) -> dict[str, np.ndarray]:
    """The raw offset curve of the polyline continued 2 r along its end chords.

    Slots: 2 i is the offset line of segment i (vertices i, i + 1 of the padded polyline,
    i = 0 .. M), 2 v - 1 the arc of vertex v (v = 1 .. M, the samples), empty (span
    [inf, -inf]) unless v is convex. Returns the spans ``lo``, ``hi`` and the formula:
    the vertex ``x``, ``z``, a line's ``lift`` r (sqrt(1 + m^2) - 1) and slope ``m``, ``arc``.
    """
    pad = 2.0 * r
    head = (z[1] - z[0]) / (s[1] - s[0])
    tail = (z[-1] - z[-2]) / (s[-1] - s[-2])
    xs = np.concatenate([[s[0] - pad], s, [s[-1] + pad]])
    zs = np.concatenate([[z[0] - head * pad], z, [z[-1] + tail * pad]])
    dx, dz = np.diff(xs), np.diff(zs)
    hyp = np.hypot(dx, dz)
    m = dz / dx
    lift = r * dz * dz / (dx * (hyp + dx))  # r (sqrt(1 + m^2) - 1) without cancellation
    shift = r * dz / hyp  # r m / sqrt(1 + m^2)
    slots = 2 * m.size - 1
    lo, hi = np.full(slots, np.inf), np.full(slots, -np.inf)
    x_ref, z_ref, rise, slope = np.empty(slots), np.empty(slots), np.zeros(slots), np.zeros(slots)
    arc = np.zeros(slots, dtype=bool)
    lo[0::2], hi[0::2] = xs[:-1] - shift, xs[1:] - shift
    x_ref[0::2], z_ref[0::2], rise[0::2], slope[0::2] = xs[:-1], zs[:-1], lift, m
    # a vertex carries an arc where the two offset lines leave a gap between their spans:
    # decided by the very numbers that make the spans (a slope comparison can disagree with
    # them by a rounding at a straight vertex, and leave a gap no piece covers)
    convex = shift[:-1] > shift[1:]
    lo[1::2] = np.where(convex, xs[1:-1] - shift[:-1], np.inf)
    hi[1::2] = np.where(convex, xs[1:-1] - shift[1:], -np.inf)
    x_ref[1::2], z_ref[1::2], arc[1::2] = xs[1:-1], zs[1:-1], True
    return {"lo": lo, "hi": hi, "x": x_ref, "z": z_ref, "lift": rise, "m": slope, "arc": arc}


def _value(raw: dict, slot: np.ndarray, s: np.ndarray, r: float, datum: np.ndarray) -> np.ndarray:
    """Height of the raw pieces ``slot`` at positions ``s`` (inside their spans) above ``datum``.

    The datum is the elevation of a nearby vertex, so the small differences that decide
    which piece is higher keep their digits on a route hundreds of metres up.
    """
    d = s - raw["x"][slot]
    root = np.sqrt(np.maximum(r * r - d * d, 0.0))
    return (raw["z"][slot] - datum) + np.where(raw["arc"][slot], -d * d / (r + root),
                                               raw["lift"][slot] + raw["m"][slot] * d)


def _rises_above(raw: dict, p: np.ndarray, q: np.ndarray, a: np.ndarray, b: np.ndarray, r: float,
                 datum: np.ndarray, noise: float) -> np.ndarray:
    """True where piece q rises more than ``noise`` above piece p somewhere in [a, b].

    q - p is linear (two lines), convex (a line above an arc), monotone (two arcs of one
    radius) or concave (an arc above a line): its largest value is at an end of [a, b],
    or, for the last, where the arc's slope equals the line's.
    """
    gap = [_value(raw, q, x, r, datum) - _value(raw, p, x, r, datum) for x in (a, b)]
    top = np.maximum(gap[0], gap[1])
    concave = raw["arc"][q] & ~raw["arc"][p]
    if np.any(concave):
        m = raw["m"][p]
        x = np.clip(raw["x"][q] - r * m / np.sqrt(1 + m * m), a, b)
        top = np.where(concave, np.maximum(top, _value(raw, q, x, r, datum) - _value(raw, p, x, r, datum)), top)
    return top > noise


def _crossings(raw: dict, p: np.ndarray, q: np.ndarray, mid: np.ndarray, r: float, datum: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray]:
    """Positions where pieces p and q have the same height: up to two, NaN where none.

    Two lines: one crossing. A line and an arc (centre C, line height K above C_z - r at
    C_x, slope m): with d = s - C_x the arc is C_z - r + sqrt(r^2 - d^2), so
    sqrt(r^2 - d^2) = K + m d, (1 + m^2) d^2 + 2 K m d + K^2 - r^2 = 0, keeping the roots
    with K + m d >= 0 (squaring adds the others). Two arcs of the same radius about P1 and
    P2: the circles meet on the perpendicular bisector, D / 2 from the midpoint along
    P2 - P1 and sqrt(r^2 - D^2 / 4) across it; both upper halves need the point above both
    centres.
    """
    nan = np.full(p.shape, np.nan)
    arc_p, arc_q = raw["arc"][p], raw["arc"][q]
    first, second = nan.copy(), nan.copy()
    with np.errstate(divide="ignore", invalid="ignore"):
        # two lines, from their heights at the interval's middle (no large intercepts)
        lines = ~arc_p & ~arc_q
        gap = _value(raw, q, mid, r, datum) - _value(raw, p, mid, r, datum)
        dm = raw["m"][q] - raw["m"][p]
        first = np.where(lines & (dm != 0), mid - gap / dm, first)
        # a line and an arc
        mixed = arc_p ^ arc_q
        a_slot, l_slot = np.where(arc_p, p, q), np.where(arc_p, q, p)
        cx, cz = raw["x"][a_slot], raw["z"][a_slot]
        m = raw["m"][l_slot]
        k = (raw["z"][l_slot] - cz) + raw["lift"][l_slot] + m * (cx - raw["x"][l_slot]) + r
        disc = r * r * (1 + m * m) - k * k
        sq = np.sqrt(np.maximum(disc, 0.0))
        km = k * m
        t = -(km + np.where(km >= 0, sq, -sq))
        d1 = t / (1 + m * m)
        d2 = np.where(t != 0, (k * k - r * r) / t, d1)
        ok = mixed & (disc >= 0)
        tol = 1e-12 * r
        first = np.where(ok & (k + m * d1 >= -tol) & (np.abs(d1) <= r), cx + d1, first)
        second = np.where(ok & (k + m * d2 >= -tol) & (np.abs(d2) <= r), cx + d2, second)
        # two arcs
        both = arc_p & arc_q
        dx = raw["x"][q] - raw["x"][p]
        dz = raw["z"][q] - raw["z"][p]
        dd = dx * dx + dz * dz
        ok = both & (dd > 0) & (dd <= 4 * r * r)
        dist = np.sqrt(dd)
        half = np.sqrt(np.maximum(r * r - 0.25 * dd, 0.0))
        for sign, out in ((1.0, "first"), (-1.0, "second")):
            px = 0.5 * dx - sign * half * dz / dist  # relative to P1 = piece p's vertex
            pz = 0.5 * dz + sign * half * dx / dist
            above = (pz >= -tol) & (pz >= dz - tol)
            value = np.where(ok & above, raw["x"][p] + px, np.nan)
            if out == "first":
                first = np.where(both, value, first)
            else:
                second = np.where(both, value, second)
    return first, second


def _ranks(count: np.ndarray) -> np.ndarray:
    """0, 1, ..., count[i] - 1 for each i, concatenated."""
    total = int(count.sum())
    return np.arange(total) - np.repeat(np.cumsum(count) - count, count)


def wheel_path(s_m: np.ndarray, z_m: np.ndarray, wheel_radius_m: float) -> WheelPath:
    """The exact path y(s) of a rigid wheel's lowest point over the polyline of the samples.

    See the module docstring. The ground beyond the route's ends is continued along the
    first and last chord for 2 r (as :func:`profileopt.physics.wheel.wheel_envelope_m` does), so
    at the samples the two agree.

    Parameters
    ----------
    s_m : numpy.ndarray, shape (M,)
        Distance along the route (m), strictly increasing, M >= 2.
    z_m : numpy.ndarray, shape (M,)
        Elevation (m).
    wheel_radius_m : float
        Wheel radius r (m), >= 0; 0 gives the polyline itself.

    Returns
    -------
    WheelPath
        Covering [s_m[0], s_m[-1]].

    Raises
    ------
    InputError
        A radius that is not a finite number >= 0, fewer than 2 samples, non-finite
        values, or s not strictly increasing.
    """
    s = np.asarray(s_m, dtype=float)
    z = np.asarray(z_m, dtype=float)
    r = float(wheel_radius_m)
    if not (math.isfinite(r) and r >= 0):
        raise InputError(f"wheel radius = {wheel_radius_m!r} m: must be a finite number >= 0")
    if s.ndim != 1 or z.shape != s.shape or s.size < 2:
        raise InputError("route: s and z must be 1-D arrays of the same length >= 2")
    if not (np.all(np.isfinite(s)) and np.all(np.isfinite(z))):
        raise InputError("route: s and z must be finite numbers")
    if not np.all(np.diff(s) > 0):
        raise InputError("route: the distances s must increase strictly from sample to sample")
    if r == 0:
        return WheelPath(breaks_m=s.copy(), x_ref_m=s[:-1].copy(), z_ref_m=z[:-1].copy(),
                         slope=np.diff(z) / np.diff(s), is_arc=np.zeros(s.size - 1, dtype=bool),
                         wheel_radius_m=0.0)
    raw = _raw_pieces(s, z, r)
    lo, hi = raw["lo"], raw["hi"]
    # heights closer than this are the same to the simulation (m): no cut for them
    noise = 64.0 * float(np.spacing(max(float(np.max(np.abs(z))), r)))
    # Intervals between the ends of the pieces' spans: the pieces present are fixed on each.
    finite = np.isfinite(lo)
    ends = np.concatenate([lo[finite], hi[finite], s[[0, -1]]])
    ends = np.unique(ends[(ends >= s[0]) & (ends <= s[-1])])
    # (interval, piece) for every piece present on an interval: a span [lo, hi] covers the
    # intervals from the one starting at lo to the one ending at hi
    slots = np.flatnonzero(finite)
    first = np.searchsorted(ends, lo[slots], side="left")
    count = np.maximum(np.searchsorted(ends, hi[slots], side="right") - 1 - first, 0)
    pair_slot = np.repeat(slots, count)
    pair_item = np.repeat(first, count) + _ranks(count)
    order = np.argsort(pair_item, kind="stable")
    pair_item, pair_slot = pair_item[order], pair_slot[order]
    a, b = ends[:-1], ends[1:]

    done_a, done_b, done_slot = [], [], []
    for _ in range(MAX_ROUNDS):
        if a.size == 0:
            break
        # pairs are sorted by item; every item has one piece at least (the raw curve covers s)
        starts = np.searchsorted(pair_item, np.arange(a.size))
        mid = 0.5 * (a + b)
        datum = raw["z"][pair_slot[starts]]  # a vertex within r of the interval
        value = _value(raw, pair_slot, mid[pair_item], r, datum[pair_item])
        top = np.maximum.reduceat(value, starts)
        is_top = np.flatnonzero(value == top[pair_item])
        best = pair_slot[is_top[np.unique(pair_item[is_top], return_index=True)[1]]]
        tol = 16 * np.spacing(np.maximum(np.maximum(np.abs(a), np.abs(b)), r))
        rows = np.flatnonzero(pair_slot != best[pair_item])
        item, slot = pair_item[rows], pair_slot[rows]
        rises = _rises_above(raw, best[item], slot, a[item], b[item], r, datum[item], noise)
        item, slot = item[rises], slot[rises]
        cut_at, cut_of = [], []
        for root in _crossings(raw, best[item], slot, mid[item], r, datum[item]):
            inside = (root > a[item] + tol[item]) & (root < b[item] - tol[item])
            cut_at.append(root[inside])
            cut_of.append(item[inside])
        cut_of_all = np.concatenate(cut_of)
        settled = np.ones(a.size, dtype=bool)
        settled[cut_of_all] = False
        done_a.append(a[settled])
        done_b.append(b[settled])
        done_slot.append(best[settled])
        if settled.all():
            break
        # cut the unsettled intervals at every crossing found in them; the parts keep the
        # parent's pieces
        open_items = np.flatnonzero(~settled)
        parent = np.concatenate([cut_of_all, open_items, open_items])
        point = np.concatenate([np.concatenate(cut_at), a[open_items], b[open_items]])
        order = np.lexsort((point, parent))
        parent, point = parent[order], point[order]
        keep = (parent[1:] == parent[:-1]) & (point[1:] > point[:-1])
        a, b = point[:-1][keep], point[1:][keep]
        owner = parent[:-1][keep]
        sizes = np.diff(np.append(starts, pair_item.size))[owner]
        pair_slot = pair_slot[np.repeat(starts[owner], sizes) + _ranks(sizes)]
        pair_item = np.repeat(np.arange(a.size), sizes)
    else:  # pragma: no cover - each cut is a crossing of two pieces
        raise RuntimeError("wheel_path: the envelope did not settle; report this route")

    a = np.concatenate(done_a)
    b = np.concatenate(done_b)
    slot = np.concatenate(done_slot)
    order = np.argsort(a, kind="stable")
    a, b, slot = a[order], b[order], slot[order]
    new_piece = np.concatenate([[True], slot[1:] != slot[:-1]])
    breaks = np.append(a[new_piece], b[-1])
    slot = slot[new_piece]
    return WheelPath(breaks_m=breaks, x_ref_m=raw["x"][slot], z_ref_m=raw["z"][slot] + raw["lift"][slot],
                     slope=np.where(raw["arc"][slot], 0.0, raw["m"][slot]), is_arc=raw["arc"][slot].copy(),
                     wheel_radius_m=r)
