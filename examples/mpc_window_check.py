"""The check the MPC examples run on their own trajectories: every roughness window, every
speed driven while inside it, between the grid points.

Used by ``examples/mpc_dompc.py`` and ``examples/mpc_rockit.py``; also a command:

    python examples/mpc_window_check.py LOG.csv --route ROUTE.csv --vehicle atv

checks a log with the columns time_s, s_m, speed_mps, accel_mps2 (the acceleration held
over the interval that starts at that row; the last row's is ignored).

The definition (issue 10): a trajectory keeps the force limit when, for every roughness
window [a, a + W] of the route, every speed driven while the vehicle is inside that window
is admissible for that window's RI. With the acceleration constant over each interval, the
position s(t) and speed v(t) are known exactly between the grid points. For each window the
time the vehicle is inside it is found by solving s(t) = a and s(t) = a + W, the speeds
driven then form one interval [lowest, highest] (the speeds at entry and exit and at the
grid points in between), and the largest force over that interval is at one of its ends or
at an interior force peak of the window's RI (``profileopt.physics.speeds.speed_bands``, found by
Newton's method on the model's own expression, independently of the controllers' helpers).
"""

from __future__ import annotations

import argparse
import dataclasses
import sys

import numpy as np

from profileopt import load_vehicle
from profileopt.mpc.constraints import force_limit_n, force_n
from profileopt.io import read_route
from profileopt.physics.speeds import speed_bands
from profileopt.terrain.roughness import range_extremes, roughness_windows


@dataclasses.dataclass(frozen=True)
class WindowCheck:
    """The worst window of a trajectory.

    Attributes
    ----------
    worst_ratio : float
        Largest force over the limit (dimensionless) of any window the vehicle entered.
    worst_start_m : float
        Where that window starts (m).
    over : int
        Windows whose ratio exceeds 1.
    windows : int
        Windows the vehicle entered.
    start_m, ratio : numpy.ndarray, shape (windows,)
        Where each window entered starts (m) and its largest force over the limit.
    """

    worst_ratio: float
    worst_start_m: float
    over: int
    windows: int
    start_m: np.ndarray
    ratio: np.ndarray


def _time_to(x: np.ndarray, s: np.ndarray, v: np.ndarray, a: np.ndarray, j: np.ndarray) -> np.ndarray:
    """Time after node j at which s(t) = x within interval j (s non-decreasing there)."""
    dx = np.maximum(x - s[j], 0.0)
    root = np.sqrt(np.maximum(v[j] ** 2 + 2.0 * a[j] * dx, 0.0))
    denominator = v[j] + root
    return np.where(denominator > 0, 2.0 * dx / np.where(denominator > 0, denominator, 1.0), 0.0)


def worst_window(route_s_m, route_z_m, vehicle, time_s, s_m, speed_mps, accel_mps2, *, model="sbem_tf",
                 window_m=5.0) -> WindowCheck:
    """Check a trajectory of constant-acceleration intervals against every roughness window.

    Parameters
    ----------
    route_s_m, route_z_m : array, shape (M,)
        The route's samples (m).
    vehicle : Vehicle
    time_s, s_m, speed_mps : array, shape (K + 1,)
        The grid points: time (s), position (m) and speed (m/s), positions non-decreasing.
    accel_mps2 : array, shape (K,)
        Acceleration held over each interval (m/s^2).
    model : str
        Force model.
    window_m : float
        Roughness window length W (m).
    """
    t, s = np.asarray(time_s, float), np.asarray(s_m, float)
    v = np.maximum(np.asarray(speed_mps, float), 0.0)  # IPOPT meets v >= 0 to about 1e-8
    a = np.asarray(accel_mps2, float)[: s.size - 1]
    windows = roughness_windows(route_s_m, route_z_m, vehicle.ground_clearance_m, window_m=window_m)
    first, stop = windows.overlapping([s[0]], [s[-1]])
    k = np.arange(first[0], stop[0])
    enter, leave = windows.start_m[k], windows.stop_m[k]  # the stretch the windows holding its samples cover
    last = s.size - 2  # the last interval
    # entry: the first time s >= a (node 0 if the vehicle starts inside)
    j_in = np.clip(np.searchsorted(s, enter, side="left") - 1, 0, last)
    tau_in = np.where(enter <= s[0], 0.0, _time_to(np.maximum(enter, s[0]), s, v, a, j_in))
    # exit: the last time s <= a + W (the last node if the vehicle ends inside)
    ends_inside = leave >= s[-1]
    j_out = np.where(ends_inside, last, np.clip(np.searchsorted(s, leave, side="right") - 1, 0, last))
    tau_out = np.where(ends_inside, t[j_out + 1] - t[j_out], _time_to(np.minimum(leave, s[-1]), s, v, a, j_out))
    v_in = np.maximum(v[j_in] + a[j_in] * tau_in, 0.0)
    v_out = np.maximum(v[j_out] + a[j_out] * tau_out, 0.0)
    low, high = np.minimum(v_in, v_out), np.maximum(v_in, v_out)
    between = j_out > j_in  # grid points inside the window: nodes j_in + 1 .. j_out
    if np.any(between):
        least, largest = range_extremes(v, j_in[between] + 1, j_out[between] + 1)
        low[between] = np.minimum(low[between], least)
        high[between] = np.maximum(high[between], largest)
    ri = windows.ri[k]
    peaks = speed_bands(ri, vehicle, model=model).peaks_mps  # interior force maxima, NaN-padded
    inside = (peaks > low[:, None]) & (peaks < high[:, None])
    speeds = np.column_stack([low, high, np.where(inside, peaks, low[:, None])])
    forces = force_n(speeds, vehicle, ri=np.broadcast_to(ri[:, None], speeds.shape), model=model)
    ratio = forces.max(axis=1) / force_limit_n(vehicle, model=model)
    worst = int(np.argmax(ratio))
    return WindowCheck(float(ratio[worst]), float(enter[worst]), int(np.sum(ratio > 1.0)), int(k.size), enter, ratio)


def report(check: WindowCheck, label: str, limit_n: float, window_m: float) -> str:
    """One line: the worst window's force over the limit and the count over the limit."""
    return (f"worst window force over the limit: {check.worst_ratio:.9f} ({label}, limit {limit_n:g} N) in the "
            f"window from {check.worst_start_m:.2f} to {check.worst_start_m + window_m:.2f} m; "
            f"windows over the limit: {check.over} of {check.windows}")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("log", help="CSV with time_s, s_m, speed_mps, accel_mps2")
    parser.add_argument("--route", required=True, help="route CSV (s,z)")
    parser.add_argument("--vehicle", default="atv", help="bundled vehicle name or .toml file (default: %(default)s)")
    parser.add_argument("--model", default="sbem_tf", help="force model (default: %(default)s)")
    parser.add_argument("--window", type=float, default=5.0, help="roughness window length, m (default: %(default)s)")
    args = parser.parse_args()
    log = np.genfromtxt(args.log, delimiter=",", names=True)
    route, vehicle = read_route(args.route), load_vehicle(args.vehicle)
    check = worst_window(route.s_m, route.z_m, vehicle, log["time_s"], log["s_m"], log["speed_mps"],
                         log["accel_mps2"][:-1], model=args.model, window_m=args.window)
    print(report(check, args.model, force_limit_n(vehicle, model=args.model), args.window))
    return 0 if check.over == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
