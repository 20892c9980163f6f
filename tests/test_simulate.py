"""Checks of the quarter-car simulation against closed forms and an independent integrator.

References
----------
* Inman, Engineering Vibration, section 2.4: steady-state base excitation y = Y sin(w t),
  transmitted force amplitude F_T = k Y r^2 sqrt((1 + (2 zeta r)^2) / ((1 - r^2)^2 +
  (2 zeta r)^2)), r = w / wn; the base-excitation force k y + c y' has amplitude
  Y sqrt(k^2 + (c w)^2) (NOTES.md, Eq. 11 simplified).
* Wheel geometry (paper's Fig. 2, Eq. 2): a wheel of radius r meets a step of height e
  (e < r) when its centre is X_w = sqrt(2 e r - e^2) before the step's edge, and then
  follows the circle of radius r about that edge.
"""

from __future__ import annotations

import math
import time

import numpy as np
import pytest
import scipy.integrate
import scipy.interpolate

from profileopt.errors import InputError
from profileopt.forces import sbem_ef_force_n, sbem_tf_force_n
from profileopt.simulate import (
    boundary_times_s,
    position_at_time,
    simulate_quarter_car,
    wheel_envelope_m,
)
from profileopt.terrain import step_width
from profileopt.vehicle import load_vehicle

ATV = load_vehicle("atv")  # wn = 3 rad/s, zeta = 0.5, r = 0.1 m
RESONANT = load_vehicle("atv-resonant")  # wn = 6 rad/s, zeta = 0.1


def inman_transmitted_n(y_m: float, w_radps: float, vehicle) -> float:
    """Inman section 2.4, written here from the textbook (not via profileopt.forces)."""
    k = vehicle.quarter_mass_kg * vehicle.natural_frequency_radps**2
    zeta = vehicle.damping_ratio
    r = w_radps / vehicle.natural_frequency_radps
    return k * y_m * r**2 * math.sqrt((1 + (2 * zeta * r) ** 2) / ((1 - r**2) ** 2 + (2 * zeta * r) ** 2))


def excitation_amplitude_n(y_m: float, w_radps: float, vehicle) -> float:
    """Amplitude of k y + c y' for y = Y sin(w t): Y sqrt(k^2 + (c w)^2)."""
    m, wn, zeta = vehicle.quarter_mass_kg, vehicle.natural_frequency_radps, vehicle.damping_ratio
    k, c = m * wn**2, 2 * zeta * m * wn
    return y_m * math.sqrt(k**2 + (c * w_radps) ** 2)


# --------------------------------------------------------------------------- wheel envelope


@pytest.mark.parametrize("e", [0.005, 0.02, 0.05, 0.09])
def test_step_is_climbed_over_x_w(e: float) -> None:
    r = ATV.wheel_radius_m
    ds = 1e-4
    s = np.arange(-4000, 4001) * ds  # edge of the step at s = 0 (the first high sample)
    z = np.where(s >= 0, e, 0.0)
    y = wheel_envelope_m(s, z, r)
    # Rise begins where the circle about the edge clears the flat ground: |s| = X_w (Eq. 2).
    x_w = math.sqrt(2 * e * r - e * e)
    first = s[np.flatnonzero(y > 0)[0]]
    assert -x_w <= first <= -x_w + ds * (1 + 1e-9)  # the first sample past -X_w
    assert first == pytest.approx(-float(step_width(e, ATV)), abs=1.5 * ds)
    # In between it is the circle of radius r about the edge, then the top of the step.
    climbing = (s > -x_w) & (s < 0)
    assert np.allclose(y[climbing], e + np.sqrt(r**2 - s[climbing] ** 2) - r, atol=1e-15)
    assert np.all(y[s < -x_w] == 0.0) and np.all(y[s >= 0] == e)


def test_envelope_over_a_step_taller_than_the_wheel_starts_at_r() -> None:
    r, e, ds = 0.1, 0.25, 1e-3
    s = np.arange(-500, 501) * ds
    y = wheel_envelope_m(s, np.where(s >= 0, e, 0.0), r)
    first = s[np.flatnonzero(y > 0)[0]]
    assert first == pytest.approx(-r, abs=ds)  # X_w saturates at r (NOTES.md, Eq. 2)
    assert y[np.flatnonzero(y > 0)[0]] == pytest.approx(e - r, abs=0.05)  # the wheel meets a wall


def test_envelope_leaves_ground_flatter_than_the_wheel_alone() -> None:
    # Curvature Y (2 pi / lam)^2 = 0.0079 1/m, far below 1/r = 10 1/m: the wheel touches
    # every sample it stands on, so y = z exactly.
    s = np.arange(0.0, 50.0, 0.02)
    z = 0.02 * np.sin(2 * np.pi * s / 10.0) + 300.0
    assert np.array_equal(wheel_envelope_m(s, z, 0.1), z)


def test_envelope_bridges_a_narrow_pothole() -> None:
    # A pothole 0.1 m wide and 0.2 m deep under a wheel of r = 0.1: the wheel sinks only
    # to r - sqrt(r^2 - 0.05^2) = 0.0134 m below the rim (chord geometry).
    s = np.arange(-1.0, 1.0 + 1e-9, 1e-3)
    z = np.where(np.abs(s) < 0.05 - 1e-9, -0.2, 0.0)
    y = wheel_envelope_m(s, z, 0.1)
    # the rim samples are at s = +-0.05 (the first flat samples), 0.05 from the centre
    assert y.min() == pytest.approx(-(0.1 - math.sqrt(0.1**2 - 0.05**2)), abs=1e-12)


def test_envelope_is_fast_on_a_long_route() -> None:
    rng = np.random.default_rng(1)
    s = np.arange(200_000) * 0.01  # 2 km at 1 cm: 10 neighbours each side
    z = np.cumsum(rng.normal(0.0, 0.003, s.size))
    start = time.perf_counter()
    y = wheel_envelope_m(s, z, 0.1)
    assert time.perf_counter() - start < 1.0
    assert np.all(y >= z)


# --------------------------------------------------------------------------- time along s


def test_boundary_times_from_rest_match_constant_acceleration() -> None:
    a = 2.0
    b = np.linspace(0.0, 40.0, 9)
    v = np.sqrt(2 * a * b)  # v^2 = 2 a s: constant acceleration from rest
    assert np.allclose(boundary_times_s(b, v), np.sqrt(2 * b / a), rtol=1e-14)  # s = a t^2 / 2
    t = np.linspace(0.0, math.sqrt(2 * 40.0 / a), 101)
    s, speed = position_at_time(t, b, v, boundary_times_s(b, v))
    assert np.allclose(s, 0.5 * a * t**2, atol=1e-12)
    assert np.allclose(speed, a * t, atol=1e-12)


def test_a_segment_at_rest_at_both_ends_is_an_input_error() -> None:
    with pytest.raises(InputError, match="speed 0 at both ends"):
        boundary_times_s(np.array([0.0, 5.0, 10.0]), np.array([1.0, 0.0, 0.0]))


def test_profile_beyond_the_route_is_an_input_error() -> None:
    s = np.linspace(0.0, 10.0, 101)
    with pytest.raises(InputError, match="covers"):
        simulate_quarter_car(s, 0 * s, np.array([0.0, 20.0]), np.array([1.0, 1.0]), ATV)


# --------------------------------------------------------------------------- closed forms


def _sinusoid_run(vehicle, speed: float, wavelength: float, amplitude: float, length: float,
                  spacing: float, segment: float, envelope: bool = True, detrend: bool = False):
    s = np.arange(0.0, length + spacing / 2, spacing)
    z = 150.0 + amplitude * np.sin(2 * np.pi * s / wavelength)  # absolute datum on purpose
    b = np.arange(0.0, length + segment / 2, segment)
    run = simulate_quarter_car(s, z, b, np.full(b.size, speed), vehicle, envelope=envelope, detrend=detrend)
    return run, b


@pytest.mark.parametrize(
    "vehicle, speed",
    [(ATV, 2.0), (ATV, 5.0), (ATV, 12.0), (RESONANT, 60.0 / (2 * math.pi)), (RESONANT, 3.0)],
    ids=["atv-r0.42", "atv-r1.05", "atv-r2.5", "resonant-r1", "resonant-r0.31"],
)
def test_sinusoidal_road_gives_steady_state_amplitudes(vehicle, speed: float) -> None:
    wavelength, amplitude = 10.0, 0.02
    run, b = _sinusoid_run(vehicle, speed, wavelength, amplitude, 400.0, 0.02, 10.0)
    w = 2 * math.pi * speed / wavelength  # road frequency (rad/s)
    settled = b[:-1] >= 250.0  # after >= 20 s: transients decayed by exp(-zeta wn t) < 1e-5
    f_t = inman_transmitted_n(amplitude, w, vehicle)
    f_e = excitation_amplitude_n(amplitude, w, vehicle)
    assert np.allclose(run.transmitted_peak_n[settled], f_t, rtol=0.01)
    # whole wavelengths per segment (detrend=False: y from the segment mean, which is 0)
    assert np.allclose(run.excitation_peak_n[settled], f_e, rtol=0.01)


def test_sinusoidal_road_is_much_tighter_than_one_percent() -> None:
    # The 1 % of the issue is loose; the method is second order. Guard what it achieves.
    run, b = _sinusoid_run(ATV, 5.0, 10.0, 0.02, 400.0, 0.02, 10.0)
    w = 2 * math.pi * 5.0 / 10.0
    settled = b[:-1] >= 250.0
    assert np.allclose(run.transmitted_peak_n[settled], inman_transmitted_n(0.02, w, ATV), rtol=1e-4)
    assert np.allclose(run.excitation_peak_n[settled], excitation_amplitude_n(0.02, w, ATV), rtol=1e-4)


@pytest.mark.parametrize("speed", [0.1, 0.3])
def test_sbem_sinusoid_matches_eq_11_and_13(speed: float) -> None:
    # The SBEM's own terrain: a sinusoid of amplitude e whose quarter period is X_w
    # (wavelength 4 X_w, so w = w_b of Eq. 12). The wheel cannot follow it (its curvature
    # pi^2 / (8 r) exceeds 1 / r), so the raw samples are fed in (envelope=False).
    e = 0.02
    wavelength = 4 * float(step_width(e, ATV))  # 0.24 m
    n_waves = 60
    run, b = _sinusoid_run(ATV, speed, wavelength, e, n_waves * wavelength, wavelength / 200,
                           wavelength, envelope=False)
    settled = b[:-1] >= 0.7 * b[-1]
    assert np.allclose(run.transmitted_peak_n[settled], sbem_tf_force_n(speed, e, ATV), rtol=0.01)
    assert np.allclose(run.excitation_peak_n[settled], sbem_ef_force_n(speed, e, ATV), rtol=0.01)


def test_flat_road_gives_zero_force_at_any_speed_profile() -> None:
    s = np.linspace(0.0, 100.0, 2001)
    b = np.linspace(0.0, 100.0, 21)
    v = np.minimum(np.sqrt(2 * 2.0 * b), np.sqrt(2 * 3.0 * (100.0 - b)))  # from rest to rest
    run = simulate_quarter_car(s, np.full(s.size, 582.37), b, v, ATV)
    assert np.max(np.abs(run.transmitted_n)) < 1e-9
    assert np.max(np.abs(run.excitation_n)) < 1e-9


def test_constant_grade_at_constant_speed_gives_zero_force() -> None:
    s = np.linspace(0.0, 100.0, 2001)
    b = np.linspace(0.0, 100.0, 21)
    run = simulate_quarter_car(s, 40.0 + 0.08 * s, b, np.full(b.size, 6.0), ATV)
    assert np.max(np.abs(run.transmitted_n)) < 1e-6  # the mass rides up the grade with the wheel
    assert np.max(np.abs(run.excitation_n)) < 1e-6  # the trend line is the datum


# --------------------------------------------------------------------------- independent integrator


def test_matches_solve_ivp_over_a_bump_at_changing_speed() -> None:
    # A smooth bump then a step down, driven while accelerating and braking; compare the
    # lfilter-based exact discretisation with an adaptive Runge-Kutta on the same input.
    s = np.arange(0.0, 30.0 + 1e-9, 0.01)
    z = 0.04 * np.exp(-(((s - 8.0) / 0.4) ** 2)) + np.where(s > 18.0, -0.03, 0.0)
    b = np.linspace(0.0, 30.0, 7)
    v = np.array([2.0, 4.0, 6.0, 6.0, 5.0, 3.0, 1.0])
    run = simulate_quarter_car(s, z, b, v, ATV)

    y_of_s = scipy.interpolate.PchipInterpolator(s, wheel_envelope_m(s, z, ATV.wheel_radius_m))
    dy_of_s = y_of_s.derivative()
    times = boundary_times_s(b, v)
    k, c, m = ATV.spring_n_per_m, ATV.damping_ns_per_m, ATV.quarter_mass_kg

    def rhs(t, q):
        pos, speed = position_at_time(np.array([t]), b, v, times)
        y, dy = y_of_s(pos[0]), dy_of_s(pos[0]) * speed[0]
        return [q[1], (-k * (q[0] - y) - c * (q[1] - dy)) / m]

    y0 = float(y_of_s(0.0))
    sol = scipy.integrate.solve_ivp(rhs, (0.0, times[-1]), [y0, float(dy_of_s(0.0)) * v[0]],
                                    t_eval=run.time_s[::20], rtol=1e-10, atol=1e-12, max_step=0.002)
    pos, speed = position_at_time(sol.t, b, v, times)
    f_ref = k * (y_of_s(pos) - sol.y[0]) + c * (dy_of_s(pos) * speed - sol.y[1])
    f_sim = run.transmitted_n[::20]
    scale = np.max(np.abs(f_ref))
    assert scale > 100.0  # the bump and the step really excite the suspension
    assert np.max(np.abs(f_sim - f_ref)) < 2e-3 * scale


def test_wheel_on_a_straight_incline_stands_above_it_up_to_both_ends() -> None:
    # On a straight incline of grade g the wheel touches the ground below-ahead of its
    # centre; its lowest point stands r (sqrt(1 + g^2) - 1) above the ground directly below
    # (right triangle of the radius to the contact point). The ends see missing ground
    # beyond them continued along the end chords, so the same holds there.
    g, r = 0.3, 0.1
    s = np.arange(0.0, 2.0 + 1e-9, 0.005)
    y = wheel_envelope_m(s, 10.0 + g * s, r)
    # samples every 5 mm approximate the contact point to O(ds^2 / r)
    assert np.allclose(y - (10.0 + g * s), r * (math.sqrt(1 + g * g) - 1), atol=2e-4)
    assert abs((y[-1] - y[-2]) - (y[1] - y[0])) < 1e-4  # no step at either end
