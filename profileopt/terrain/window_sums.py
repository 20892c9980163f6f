"""Least-squares moments of many windows of a sampled profile, from prefix sums.

The roughness windows (:func:`profileopt.terrain.roughness.roughness_windows`, Eq. 1 detrended) and
the grade of a route (:func:`profileopt.terrain.geometry.path_grade_rad`) need, for every window of
samples, the count, the variance of s, the covariance of s and z and the variance of z: a
least-squares line per window. Formed from running sums they cost time proportional to the
samples; :func:`window_line_moments` guards against the cancellation that running sums
suffer on long routes, and :func:`batched_window_moments` forms them in cache-sized batches.
"""

from __future__ import annotations

import numpy as np

__all__ = ["WINDOW_BATCH", "window_line_moments", "batched_window_moments"]

#: Windows whose moments are formed together: their samples' work arrays stay in cache.
WINDOW_BATCH = 1 << 15


def window_line_moments(positions_m: np.ndarray, elevations_m: np.ndarray, first: np.ndarray, stop: np.ndarray,
                        *, block_m: float, block_origin_m: float | None = None, with_var_z: bool = True
                        ) -> tuple[np.ndarray, ...]:
    """Count, centred moments and least-squares slope of the samples of many windows,
    from prefix sums, in time proportional to the samples.

    Running sums over a whole long route lose the digits that the variance of one window
    needs (s in kilometres against a window of metres, elevations of hundreds of metres).
    So the sums restart every ``block_m`` metres, relative to the block's first sample, and
    each window (at most ``block_m`` long, so within two blocks) moves its parts to its own
    first sample by the exact binomial shift before the moments are formed.

    Parameters
    ----------
    positions_m, elevations_m : numpy.ndarray, shape (M,)
        Samples, s increasing.
    first, stop : numpy.ndarray of int, shape (K,)
        Window k holds samples ``first[k] <= j < stop[k]``, ``stop - first >= 1``, spanning
        at most ``block_m``.
    block_m : float
        Block length (m), at least the longest window's extent.
    block_origin_m : float, optional
        Where the blocks start (m); default the first sample. Pass the route's first
        position when giving a slice of it, so the result does not depend on the slicing.
    with_var_z : bool, default True
        False: skip the variance of z (returned as None), for a caller that only needs the
        slope (a fifth less work).

    Returns
    -------
    count, var_s, cov, var_z : numpy.ndarray, shape (K,)
        Samples per window, population variance of s (m^2), covariance of s and z (m^2) and
        population variance of z (m^2; None when ``with_var_z`` is False).
    """
    s = np.asarray(positions_m, dtype=float)
    z = np.asarray(elevations_m, dtype=float)
    first = np.asarray(first, dtype=np.intp)
    stop = np.asarray(stop, dtype=np.intp)
    m = s.size
    block = np.floor((s - (s[0] if block_origin_m is None else block_origin_m)) / block_m).astype(np.intp)
    block -= block[0]
    block_first = np.searchsorted(block, np.arange(block[-1] + 1), side="left")
    origin = block_first[block]
    u, w = s - s[origin], z - z[origin]
    pos = np.arange(m) - origin
    table = np.zeros((block[-1] + 1, int(pos.max()) + 1))
    # a window (at most block_m long) lies in one block or two: parts lo <= j < hi
    split = np.where(block[stop - 1] != block[first], block_first[np.minimum(block[first] + 1, block[-1])], stop)
    parts = []
    for lo, hi in ((first, split), (split, stop)):
        lo_c = np.minimum(lo, m - 1)
        n = (hi - lo).astype(float)
        ref = origin[lo_c]
        restart = lo_c == ref  # the part starts at its block's first sample
        parts.append((lo_c, np.maximum(hi - 1, 0), n, restart, s[ref] - s[first], z[ref] - z[first]))

    def window_sums(q: np.ndarray) -> list[np.ndarray]:
        """Sums of q over each part, q taken relative to the part's block origin."""
        table[block, pos] = q  # prefix sums restarting at each block
        prefix = np.cumsum(table, axis=1)[block, pos]
        return [np.where(n > 0, prefix[last] - np.where(restart, 0.0, prefix[np.maximum(lo - 1, 0)]), 0.0)
                for lo, last, n, restart, _, _ in parts]

    su_p, sw_p = window_sums(u), window_sums(w)
    count = sum(p[2] for p in parts)
    # each part moved to the window's first sample: sum (u + d)^2 = suu + 2 d su + n d^2, ...
    su = sum(su_p[i] + p[2] * p[4] for i, p in enumerate(parts))
    sw = sum(sw_p[i] + p[2] * p[5] for i, p in enumerate(parts))
    suu = sum(q + 2 * p[4] * su_p[i] + p[2] * p[4] ** 2 for i, (q, p) in enumerate(zip(window_sums(u * u), parts)))
    suw = sum(q + p[4] * sw_p[i] + p[5] * su_p[i] + p[2] * p[4] * p[5]
              for i, (q, p) in enumerate(zip(window_sums(u * w), parts)))
    mu, mw = su / count, sw / count
    if not with_var_z:
        return count, suu / count - mu * mu, suw / count - mu * mw, None
    sww = sum(q + 2 * p[5] * sw_p[i] + p[2] * p[5] ** 2 for i, (q, p) in enumerate(zip(window_sums(w * w), parts)))
    return count, suu / count - mu * mu, suw / count - mu * mw, sww / count - mw * mw


def batched_window_moments(positions_m: np.ndarray, elevations_m: np.ndarray, first: np.ndarray,
                           stop: np.ndarray, *, block_m: float, with_var_z: bool = True
                           ) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """:func:`window_line_moments` of many windows, formed :data:`WINDOW_BATCH` windows at
    a time so that each batch's work arrays stay in the processor's cache (a million
    windows at once ran from memory). Each batch's slice of the route starts at a block's
    first sample, so the sums are bit for bit those of one pass over the whole route.

    Parameters
    ----------
    positions_m, elevations_m : numpy.ndarray, shape (M,)
        Samples, s increasing.
    first, stop : numpy.ndarray of int, shape (K,)
        Window k holds samples ``first[k] <= j < stop[k]``, ``first`` non-decreasing.
    block_m : float
        Block length (m), at least the longest window's extent.
    with_var_z : bool, default True
        False: skip the variance of z (returned as None).

    Returns
    -------
    var_s, cov, var_z : numpy.ndarray, shape (K,)
        As :func:`window_line_moments` (var_z None when ``with_var_z`` is False).
    """
    s, z = positions_m, elevations_m
    count = first.size
    var_s, cov = np.empty(count), np.empty(count)
    var_z = np.empty(count) if with_var_z else None
    block = np.floor((s - s[0]) / block_m).astype(np.intp)
    for lo in range(0, count, WINDOW_BATCH):
        hi = min(lo + WINDOW_BATCH, count)
        a, b = int(np.searchsorted(block, block[first[lo]], side="left")), int(stop[lo:hi].max())
        _, var_s[lo:hi], cov[lo:hi], vz = window_line_moments(s[a:b], z[a:b], first[lo:hi] - a, stop[lo:hi] - a,
                                                             block_m=block_m, block_origin_m=float(s[0]),
                                                             with_var_z=with_var_z)
        if var_z is not None:
            var_z[lo:hi] = vz
    return var_s, cov, var_z
