"""The simulator against a from-scratch simulation of the same wheel, and its convergence.

The reference is written here from the definitions alone, sharing no code with
profileopt.physics.simulate or profileopt.physics.wheel:

* the wheel's path, pointwise: the centre of a wheel of radius r above s stands on the
  highest of the circles of radius r about the points of the polyline within r of s. On
  a segment of slope m the height of that circle above s, z(x_p) + sqrt(r^2 - (x_p - s)^2),
  is concave in x_p, so its largest value is at the point where its derivative
  m - (x_p - s) / sqrt(r^2 - (x_p - s)^2) vanishes, x_p = s + r m / sqrt(1 + m^2), or at
  an end of the segment; the slope of the path is (x_p - s) / sqrt(r^2 - (x_p - s)^2) at
  the winning contact point x_p (envelope theorem);
* the kinematics: s(t) = s_i + v_i tau + a_i tau^2 / 2 inside segment i;
* the quarter car m x'' = -k (x - y) - c (x' - y'), integrated by scipy's DOP853 at
  rtol 1e-10 in the state (x, p = x' - (c / m) y), whose right-hand side needs y but not
  y' (p' = (-k (x - y) - c x') / m): y is continuous, its slope is not, and the adaptive
  steps see no jump. F_T = -k (x - y) - c (x' - y') is then evaluated every 2 us.
"""

from __future__ import annotations

import bisect
import math

import numpy as np
import pytest
import scipy.integrate

from profileopt.io import read_route
from profileopt.physics.simulate import MAX_ARC_STEP_RAD, simulate_quarter_car
from profileopt.core.vehicle import load_vehicle

from conftest import ROUTES

ATV = load_vehicle("atv")
RESONANT = load_vehicle("atv-resonant")


def wheel_height(xs: list, zs: list, r: float, q: float) -> tuple[float, float]:
    """Lowest point of the wheel whose centre is above q, and its slope dy/ds (pointwise)."""
    lo = max(bisect.bisect_left(xs, q - r) - 1, 0)
    hi = min(bisect.bisect_right(xs, q + r), len(xs) - 1)
    best, slope = -math.inf, 0.0
    for i in range(lo, hi):
        x0, x1, z0, z1 = xs[i], xs[i + 1], zs[i], zs[i + 1]
        m = (z1 - z0) / (x1 - x0)
        for xp in (min(max(q + r * m / math.sqrt(1 + m * m), x0), x1), x0, x1):
            d = xp - q
            if abs(d) <= r:
                height = z0 + m * (xp - x0) + math.sqrt(r * r - d * d)
                if height > best:
                    best, slope = height, d / math.sqrt(max(r * r - d * d, 1e-300))
    return best - r, slope


def wheel_heights(xs: np.ndarray, zs: np.ndarray, r: float, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`wheel_height` at many positions at once."""
    best, slope = np.full(q.shape, -np.inf), np.zeros(q.shape)
    lo = np.searchsorted(xs, q - r) - 1
    for offset in range(int(np.max(np.searchsorted(xs, q + r) - lo)) + 1):
        i = np.clip(lo + offset, 0, xs.size - 2)
        x0, x1, z0, z1 = xs[i], xs[i + 1], zs[i], zs[i + 1]
        m = (z1 - z0) / (x1 - x0)
        for xp in (np.clip(q + r * m / np.sqrt(1 + m * m), x0, x1), x0, x1):
            d = xp - q
            height = np.where(np.abs(d) <= r, z0 + m * (xp - x0) + np.sqrt(np.maximum(r * r - d * d, 0.0)), -np.inf)
            higher = height > best
            slope = np.where(higher, d / np.sqrt(np.maximum(r * r - d * d, 1e-300)), slope)
            best = np.where(higher, height, best)
    return best - r, slope


def from_scratch_peaks(s: np.ndarray, z: np.ndarray, b: np.ndarray, v: np.ndarray, vehicle
                       ) -> tuple[np.ndarray, object]:
    """Largest |F_T| in each segment, by the module docstring's recipe."""
    r = vehicle.wheel_radius_m
    m = vehicle.quarter_mass_kg
    k = m * vehicle.natural_frequency_radps**2
    c = 2 * vehicle.damping_ratio * m * vehicle.natural_frequency_radps
    accel = (v[1:] ** 2 - v[:-1] ** 2) / (2 * np.diff(b))
    times = np.concatenate([[0.0], np.cumsum(2 * np.diff(b) / (v[:-1] + v[1:]))])
    xs, zs, bl, vl, tl, al = s.tolist(), z.tolist(), b.tolist(), v.tolist(), times.tolist(), accel.tolist()

    def position(t: float) -> float:
        i = min(max(bisect.bisect_right(tl, t) - 1, 0), len(bl) - 2)
        tau = t - tl[i]
        return bl[i] + vl[i] * tau + 0.5 * al[i] * tau * tau

    def rhs(t: float, state: np.ndarray) -> list:
        y = wheel_height(xs, zs, r, position(t))[0]
        velocity = state[1] + c / m * y
        return [velocity, (-k * (state[0] - y) - c * velocity) / m]

    y0 = wheel_height(xs, zs, r, b[0])[0]
    slope0 = wheel_height(xs, zs, r, b[0] + 1e-9)[1]  # settled on the ground ahead (x' = y'(0+))
    sol = scipy.integrate.solve_ivp(rhs, (0.0, times[-1]), [y0, slope0 * v[0] - c / m * y0], method="DOP853",
                                    rtol=1e-10, atol=1e-12, dense_output=True, max_step=1e-3)
    assert sol.success
    t = np.linspace(0.0, times[-1], int(times[-1] / 2e-6) + 1)
    seg = np.clip(np.searchsorted(times, t, side="right") - 1, 0, b.size - 2)
    tau = t - times[seg]
    pos = b[seg] + v[seg] * tau + 0.5 * accel[seg] * tau * tau
    speed = v[seg] + accel[seg] * tau
    x, p = sol.sol(t)
    y, slope = wheel_heights(s, z, r, pos)
    force = -k * (x - y) - c * (p + c / m * y - slope * speed)
    peaks = np.zeros(b.size - 1)
    np.maximum.at(peaks, seg, np.abs(force))
    return peaks, sol


CASES = {
    # the 0.15 m curb up at 102.5 m (sampled every 5 cm: a ramp of slope 3), braking into it
    "curb-up": ("curb.csv", [101.0, 102.0, 103.0, 104.0], [8.4, 8.0, 7.5, 7.8]),
    # and down at 152.5 m, accelerating off it
    "curb-down": ("curb.csv", [151.0, 152.0, 153.0, 154.0], [7.5, 7.9, 8.3, 8.6]),
    # the KRC 1-inch course where verify's interpolated path gave 893 N and the exact one 1498 N
    "krc-270": ("krc_rms_1in.csv", [270.0, 271.0, 272.0, 273.0, 274.0, 275.0], [9.3, 9.0, 8.7, 8.4, 8.2, 8.1]),
}


@pytest.mark.parametrize("case", list(CASES))
def test_per_segment_peaks_agree_with_a_from_scratch_simulation(case: str) -> None:
    name, boundaries, speeds = CASES[case]
    route = read_route(ROUTES / name)
    b, v = np.array(boundaries), np.array(speeds)
    keep = (route.s_m >= b[0] - 0.5) & (route.s_m <= b[-1] + 0.5)  # the wheel never reaches the ends
    s, z = route.s_m[keep], route.z_m[keep]
    reference, _ = from_scratch_peaks(s, z, b, v, ATV)
    run = simulate_quarter_car(s, z, b, v, ATV)
    # measured: within 2e-4 (the reference samples F_T every 2 us, so at a kink it misses
    # the one-sided limit by up to |F_T'| 2 us)
    assert np.allclose(run.transmitted_peak_n, reference, rtol=1e-3)
    assert np.max(reference) > 1000.0  # a sharp peak really is there


def test_the_peak_on_a_step_is_where_the_wheel_meets_the_wall() -> None:
    # curb.csv's step up: samples 102.45 m (low) and 102.50 m (0.15 m higher). The wheel
    # meets the ramp's offset line at s1 = 102.45 - r (sqrt(10) - 1) / 3 (test_wheel_path.py);
    # there its slope jumps by ~3 and F_T by c v 3 at once, the largest force of the segment.
    route = read_route(ROUTES / "curb.csv")
    step = int(np.argmax(np.diff(route.z_m)))
    assert route.z_m[step + 1] - route.z_m[step] > 0.14
    b = np.array([100.0, 105.0])
    run = simulate_quarter_car(route.s_m, route.z_m, b, np.array([8.0, 8.0]), ATV)
    i = int(np.argmax(np.abs(run.transmitted_n)))
    s1 = route.s_m[step] - 0.1 * (math.sqrt(10.0) - 1) / 3
    assert run.s_m[i] == pytest.approx(s1, abs=0.01)  # the ground is not flat before it: ~s1
    assert run.transmitted_n[i] == run.transmitted_peak_n[0]
    kink = np.flatnonzero((np.diff(run.time_s) == 0) & (np.abs(run.s_m[1:] - s1) < 0.01))
    assert kink.size == 1  # both sides of the kink are rows, at one time
    jump = run.transmitted_n[kink[0] + 1] - run.transmitted_n[kink[0]]
    assert jump == pytest.approx(ATV.damping_ns_per_m * 8.0 * 2.9, rel=0.05)


@pytest.fixture(scope="module")
def drives() -> dict:
    """Two bundled routes driven at a fixed, varying profile (no planner involved)."""
    out = {}
    for name, vehicle in (("curb.csv", "atv"), ("krc_rms_1in.csv", "atv"), ("krc_rms_1in.csv", "atv-resonant")):
        route = read_route(ROUTES / name)
        b = np.append(np.arange(route.s_m[0], route.s_m[-1] - 1.0, 5.0), route.s_m[-1])
        v = 6.0 + 3.0 * np.sin(b / 37.0) ** 2  # 6 to 9 m/s, accelerating and braking
        v[0] = 0.0  # from rest
        out[(name, vehicle)] = (route, b, v, load_vehicle(vehicle))
    return out


@pytest.mark.parametrize("key", [("curb.csv", "atv"), ("krc_rms_1in.csv", "atv"),
                                 ("krc_rms_1in.csv", "atv-resonant")], ids=["curb", "krc", "krc-resonant"])
def test_the_peaks_converge_as_the_time_step_and_the_arc_steps_shrink(drives, key) -> None:
    # Every kink is a knot whatever the step, forces turning between knots are found, and the
    # input is exact on the path's lines: refining the time grid 16 times changes no peak
    # by more than 1e-4 of itself (measured 6e-5), nor does a grid 4 times coarser. The
    # arcs' quadratic input is second order in their angle step: halving it quarters the
    # change, which at the default 0.02 rad is below 1e-4 of the force limit.
    route, b, v, vehicle = drives[key]
    base = simulate_quarter_car(route.s_m, route.z_m, b, v, vehicle)
    for factor in (1 / 16, 4.0):
        run = simulate_quarter_car(route.s_m, route.z_m, b, v, vehicle, time_step_s=base.time_step_s * factor)
        for new, old in ((run.transmitted_peak_n, base.transmitted_peak_n), (run.excitation_peak_n, base.excitation_peak_n)):
            assert np.max(np.abs(new - old) / np.maximum(old, 1.0)) < 1e-4
    peaks = [base.transmitted_peak_n] + [
        simulate_quarter_car(route.s_m, route.z_m, b, v, vehicle, max_arc_step_rad=MAX_ARC_STEP_RAD / n).transmitted_peak_n
        for n in (2, 4)]
    first, second = peaks[1] - peaks[0], peaks[2] - peaks[1]
    i = int(np.argmax(np.abs(first)))
    assert np.max(np.abs(first)) < 1e-4 * vehicle.max_transmitted_force_n
    assert first[i] / second[i] == pytest.approx(4.0, rel=0.25)


def test_a_peak_between_steps_is_found_even_on_a_coarse_grid() -> None:
    # A ramp of 2 cm up, then flat ground sampled every metre: in the segment after it the
    # lightly damped suspension swings freely and F_T peaks between knots (grid points and
    # samples). With 20 steps per natural period instead of 200 or 2000 the segment's peak
    # is the same to 1e-7 (the turning point is placed by a cubic through the neighbouring
    # values and rates, and the force is evaluated there exactly); the values at the grid
    # points and knots alone miss it by 4e-4 (measured).
    s = np.round(np.concatenate([np.arange(0.0, 10.0, 1.0), np.arange(10.0, 12.0, 0.05),
                                 np.arange(12.0, 40.5, 1.0)]), 9)
    z = np.clip((s - 10.5) * 0.04, 0.0, 0.02)
    b = np.array([0.0, 12.0, 40.0])
    v = np.array([5.0, 5.0, 5.0])
    period = 2 * math.pi / RESONANT.natural_frequency_radps
    peaks = {}
    for steps in (2000, 200, 20):
        run = simulate_quarter_car(s, z, b, v, RESONANT, time_step_s=period / steps)
        peaks[steps] = run.transmitted_peak_n
    assert np.allclose(peaks[20], peaks[2000], rtol=1e-7) and np.allclose(peaks[200], peaks[2000], rtol=1e-7)
    free = run.s_m >= 12.0
    on_grid = np.isclose(run.time_s / run.time_step_s, np.round(run.time_s / run.time_step_s), atol=1e-9)
    at_knots = np.max(np.abs(run.transmitted_n[free & (on_grid | np.isin(run.s_m, s))]))
    assert at_knots < (1 - 2e-4) * peaks[2000][1]
    assert np.max(np.abs(run.transmitted_n[free])) == peaks[20][1]  # the turning point is a row


@pytest.mark.parametrize("damping_ratio", [0.02, 0.3, 1.5])
@pytest.mark.parametrize("steps", [1, 2, 3, 1000, 100_003])
def test_the_grid_recursion_is_lfilters(damping_ratio: float, steps: int) -> None:
    """The grid recursion W_k = Phi W_{k-1} + D_k against scipy.signal.lfilter (an independent
    implementation: each component of W is D filtered by the adjugate of I - Phi z^-1 over its
    determinant): a quarter car's transition over 5 ms, a random drive of ``steps`` steps (a
    prime count, so the last block is short); the same outputs to 1e-12 of their size."""
    import scipy.signal

    from profileopt.physics.quarter_car import grid_recursion, transition

    f11, f12, f21, f22 = (float(v[0]) for v in transition(np.array([0.005]), 20.0, damping_ratio))
    den = [1.0, -(f11 + f22), f11 * f22 - f12 * f21]
    drive = np.random.default_rng(7).normal(size=(steps, 2))
    expected = np.stack([scipy.signal.lfilter([1.0, -f22], den, drive[:, 0])
                         + scipy.signal.lfilter([0.0, f12], den, drive[:, 1]),
                         scipy.signal.lfilter([0.0, f21], den, drive[:, 0])
                         + scipy.signal.lfilter([1.0, -f11], den, drive[:, 1])], axis=1)
    got = grid_recursion((f11, f12, f21, f22), drive)
    assert got.shape == (steps, 2)
    assert np.max(np.abs(got - expected)) <= 1e-12 * np.max(np.abs(expected))
