"""Checks of the quarter-car simulation against closed forms
(tests/verification/test_simulate_exact.py holds the check against an independent
integrator on the exact wheel path).

References
----------
* Inman, Engineering Vibration, section 2.4: steady-state base excitation y = Y sin(w t),
  transmitted force amplitude F_T = k Y r^2 sqrt((1 + (2 zeta r)^2) / ((1 - r^2)^2 +
  (2 zeta r)^2)), r = w / wn; the base-excitation force k y + c y' has amplitude
  Y sqrt(k^2 + (c w)^2) (NOTES.md, Eq. 11 simplified).
* Wheel geometry (paper's Fig. 2, Eq. 2): a wheel of radius r meets a step of height e
  (e < r) when its centre is X_w = sqrt(2 e r - e^2) before the step's edge, and then
  follows the circle of radius r about that edge.
* A wheel resting on a straight line of slope g touches it where the radius is normal to
  it, so its centre stands r / cos(atan g) = r sqrt(1 + g^2) above the line, vertically;
  its lowest point r (sqrt(1 + g^2) - 1) above the ground below it.
* On smooth ground z(x) curved less than 1/r the wheel touches one point x_c, its centre
  on the normal there (the offset curve): x = x_c - r z' / sqrt(1 + z'^2),
  w = z(x_c) + r / sqrt(1 + z'^2), z' = z'(x_c) (:func:`offset_curve_m` solves for x_c by
  Newton's method). Expanded for small r: x_c = x + r z' + O(r^2 z' z''), so
  y = w - r = z(x) + r z'^2 - r z'^2 / 2 + O(r^2 z'^2 z'', r z'^4) = z + r z'^2 / 2 + ...
  For z = A sin(k x) that adds r A^2 k^2 / 4 (1 + cos 2 k x): a second harmonic, whose
  steady-state force follows from the same transfer functions (:func:`two_harmonic_peaks_n`).
* The ground is the polyline through the samples. On z = A sin(k x) sampled every h a
  chord's slope is z' at the chord's middle to O(h^2), and the wheel (or the bare
  polyline) takes the slope of the chord it stands on, within h / 2 of that middle: its
  slope differs from the smooth ground's by at most |z''| h / 2 = A k^2 h / 2, its height
  by O(h^2). At speed v the damper turns that into at most c v A k^2 h / 2 on either
  force, to first order in h (:func:`polyline_excess_n`).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from profileopt.errors import InputError
from profileopt.physics.forces import sbem_ef_force_n, sbem_tf_force_n
from profileopt.physics.simulate import boundary_times_s, position_at_time, simulate_quarter_car
from profileopt.physics.wheel import wheel_envelope_m
from profileopt.terrain.roughness import step_width
from profileopt.core.vehicle import load_vehicle

ATV = load_vehicle("atv")  # wn = 3 rad/s, zeta = 0.5, r = 0.1 m
RESONANT = load_vehicle("atv-resonant")  # wn = 6 rad/s, zeta = 0.1


def inman_transmitted_n(y_m: float, w_radps: float, vehicle) -> float:
    """Inman section 2.4, written here from the textbook (not via profileopt.physics.forces)."""
    k = vehicle.quarter_mass_kg * vehicle.natural_frequency_radps**2
    zeta = vehicle.damping_ratio
    r = w_radps / vehicle.natural_frequency_radps
    return k * y_m * r**2 * math.sqrt((1 + (2 * zeta * r) ** 2) / ((1 - r**2) ** 2 + (2 * zeta * r) ** 2))


def excitation_amplitude_n(y_m: float, w_radps: float, vehicle) -> float:
    """Amplitude of k y + c y' for y = Y sin(w t): Y sqrt(k^2 + (c w)^2)."""
    m, wn, zeta = vehicle.quarter_mass_kg, vehicle.natural_frequency_radps, vehicle.damping_ratio
    k, c = m * wn**2, 2 * zeta * m * wn
    return y_m * math.sqrt(k**2 + (c * w_radps) ** 2)


def offset_curve_m(x_m: np.ndarray, amplitude_m: float, wavelength_m: float, r_m: float) -> np.ndarray:
    """Exact y = w - r of a wheel of radius r on the smooth z = A sin(k x) (needs A k^2 < 1/r).

    The centre above x touches at x_c with x = x_c - r z'(x_c) / sqrt(1 + z'(x_c)^2) (module
    docstring), solved by Newton's method from x_c = x + r z'(x); then
    y = z(x_c) + r / sqrt(1 + z'^2) - r.
    """
    k = 2 * math.pi / wavelength_m
    assert amplitude_m * k * k < 1.0 / r_m  # the wheel fits every valley: one contact point
    x = np.asarray(x_m, dtype=float)
    xc = x + r_m * amplitude_m * k * np.cos(k * x)
    for _ in range(50):
        slope = amplitude_m * k * np.cos(k * xc)
        curvature = -amplitude_m * k * k * np.sin(k * xc)
        root = np.sqrt(1 + slope * slope)
        step = (xc - r_m * slope / root - x) / (1 - r_m * curvature / root**3)
        xc = xc - step
        if np.max(np.abs(step)) < 1e-15:
            break
    slope = amplitude_m * k * np.cos(k * xc)
    root = np.sqrt(1 + slope * slope)
    return amplitude_m * np.sin(k * xc) - r_m * slope * slope / (root * (1 + root))


def two_harmonic_peaks_n(amplitude_m: float, wavelength_m: float, speed_mps: float,
                         vehicle) -> tuple[float, float]:
    """Steady-state peaks (|F_T|, |F|) for the wheel's base input on z = A sin(k x) at speed V.

    y = A sin(k x) + r A^2 k^2 / 4 cos(2 k x) (+ a constant, which moves no force and which
    the segment mean removes from F): the first-order offset curve of the module docstring.
    Each harmonic of frequency w passes through the textbook transfer functions (Inman
    2.4): x / y = (k + i c w) / (k - m w^2 + i c w), F_T = m x'' = -m w^2 x, F = (k + i c w) y.
    The peaks of the sum are taken on a fine grid over one period (phase error (pi/N)^2/2).
    """
    m, wn, zeta = vehicle.quarter_mass_kg, vehicle.natural_frequency_radps, vehicle.damping_ratio
    k_spring, c = m * wn**2, 2 * zeta * m * wn
    k = 2 * math.pi / wavelength_m
    r = vehicle.wheel_radius_m
    w = k * speed_mps
    t = np.linspace(0.0, 2 * math.pi / w, 200_001)
    f_t = np.zeros_like(t)
    f_e = np.zeros_like(t)
    # A sin(w t) = Re(-i A e^{i w t}); r A^2 k^2 / 4 cos(2 w t) = Re(r A^2 k^2 / 4 e^{2 i w t})
    for freq, phasor in ((w, -1j * amplitude_m), (2 * w, r * amplitude_m**2 * k * k / 4)):
        rotation = phasor * np.exp(1j * freq * t)
        x_over_y = (k_spring + 1j * c * freq) / (k_spring - m * freq**2 + 1j * c * freq)
        f_t += (-m * freq**2 * x_over_y * rotation).real
        f_e += ((k_spring + 1j * c * freq) * rotation).real
    return float(np.max(np.abs(f_t))), float(np.max(np.abs(f_e)))


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


@pytest.mark.parametrize("grade", [-2.0, -0.3, 0.0, 0.05, 0.3, 1.5])
def test_straight_incline_is_the_line_raised_exactly_at_any_spacing(grade: float) -> None:
    # Right triangle of the radius to the contact point (module docstring): the lowest point
    # of the wheel stands r (sqrt(1 + g^2) - 1) above the ground directly below its centre,
    # wherever the samples are (spacings from 2 mm to 0.3 m, larger than r) and up to both
    # ends (the ground beyond them is continued along the end chords). Circles on the
    # samples alone would sag between samples by up to r (sqrt(1 + g^2) - 1).
    r = 0.1
    rng = np.random.default_rng(7)
    s = 3.0 + np.cumsum(rng.uniform(0.002, 0.3, 400))
    z = 250.0 + grade * s
    y = wheel_envelope_m(s, z, r)
    expected = r * (math.sqrt(1 + grade * grade) - 1)
    assert np.max(np.abs((y - z) - expected)) < 1e-12 * (1 + abs(grade) * s.max())


@pytest.mark.parametrize("grade", [0.2, 1.0])
def test_roof_and_valley_give_the_circle_and_the_offset_lines(grade: float) -> None:
    # Roof z = -g |x|: the wheel rolls over the apex on the circle about it while the
    # contact point is the apex, |x| <= r g / sqrt(1 + g^2) (where the circle's slope
    # reaches the roof's), then rides the offset lines y = -g |x| + r (sqrt(1 + g^2) - 1).
    # Valley z = g |x|: both offset lines are valid around x = 0 (the wheel touches both
    # sides), so y = g |x| + r (sqrt(1 + g^2) - 1) everywhere.
    r = 0.1
    s = np.linspace(-1.0, 1.0, 801)  # apex at a sample
    lift = r * (math.sqrt(1 + grade**2) - 1)
    on_circle = np.abs(s) <= r * grade / math.sqrt(1 + grade**2)
    circle = -s * s / (r + np.sqrt(np.maximum(r * r - s * s, 0.0)))  # apex - (r - sqrt(r^2 - x^2))
    roof = np.where(on_circle, circle, -grade * np.abs(s) + lift)
    assert np.max(np.abs(wheel_envelope_m(s, -grade * np.abs(s), r) - roof)) < 1e-13
    assert np.max(np.abs(wheel_envelope_m(s, grade * np.abs(s), r) - (grade * np.abs(s) + lift))) < 1e-13


def test_envelope_matches_brute_force_on_rough_irregular_ground() -> None:
    # The definition itself: the centre above x_j is the highest z_p + sqrt(r^2 - (x_p - x_j)^2)
    # over the points p of the polyline (continued 2 r along the end chords), here over its
    # vertices and the polyline cut every 2 um; a tangent contact point is then missed by
    # <= 1 um, at a stationary point of the height, which lowers the maximum by at most
    # (1 + m^2)^1.5 / r * (1 um)^2 / 2 < 2e-10 m for slopes |m| <= 3.
    r = 0.1
    rng = np.random.default_rng(3)
    s = np.cumsum(rng.uniform(0.01, 0.25, 120))
    z = 40.0 + np.cumsum(rng.uniform(-1.0, 1.0, s.size) * np.diff(s, prepend=s[0] - 0.1))
    y = wheel_envelope_m(s, z, r)
    head, tail = (z[1] - z[0]) / (s[1] - s[0]), (z[-1] - z[-2]) / (s[-1] - s[-2])
    xs = np.concatenate([[s[0] - 2 * r], s, [s[-1] + 2 * r]])
    zs = np.concatenate([[z[0] - 2 * r * head], z, [z[-1] + 2 * r * tail]])
    reference = np.empty(s.size)
    for j, x in enumerate(s):
        xp = np.concatenate([np.arange(x - r, x + r, 2e-6), s[np.abs(s - x) <= r]])
        zp = np.interp(xp, xs, zs)
        reference[j] = np.max(zp + np.sqrt(np.maximum(r * r - (xp - x) ** 2, 0.0))) - r
    assert np.all(reference <= y + 1e-12)  # nothing on the polyline sticks into the wheel
    assert np.max(y - reference) < 1e-9  # and the wheel touches it
    assert np.all(y >= z)


def test_sinusoid_envelope_is_its_offset_curve_at_any_spacing() -> None:
    # A sinusoid of wavelength 4.7 m >> r, slope up to A k = 0.40 (the washboard's 0.38):
    # the rigid wheel's exact envelope is the offset curve (module docstring). The polyline
    # through samples h apart lies between the curve and A k^2 h^2 / 8 below it, and the
    # envelope moves with the ground by no more than the ground moves, so each envelope is
    # within A k^2 h^2 / 8 of the offset curve: 1.3e-4 m at 5 cm, 1.3e-6 m at 5 mm; so the
    # two agree to 1.4e-4 m. (Circles on the samples alone were 3.6 mm off at 5 cm.)
    r, amplitude, wavelength = 0.1, 0.3, 4.7
    k = 2 * math.pi / wavelength
    envelopes = {}
    for spacing in (0.05, 0.005):
        s = np.arange(0.0, 40.0 + spacing / 2, spacing)
        y = wheel_envelope_m(s, 500.0 + amplitude * np.sin(k * s), r) - 500.0
        inner = (s > 1.0) & (s < 39.0)  # away from the end chords
        bound = amplitude * k * k * spacing**2 / 8
        assert np.max(np.abs(y - offset_curve_m(s, amplitude, wavelength, r))[inner]) < bound + 1e-10
        envelopes[spacing] = s[inner], y[inner]
    (s_coarse, y_coarse), (s_fine, y_fine) = envelopes[0.05], envelopes[0.005]
    common = np.isin(np.round(s_fine / 0.005), np.round(s_coarse / 0.005))
    assert np.array_equal(np.round(s_fine[common] / 0.005), np.round(s_coarse / 0.005))
    assert np.max(np.abs(y_fine[common] - y_coarse)) < 1.4e-4


def test_envelope_rejects_a_bad_radius_or_unordered_samples() -> None:
    s = np.linspace(0.0, 1.0, 11)
    with pytest.raises(InputError, match="wheel radius"):
        wheel_envelope_m(s, 0 * s, 0.0)
    with pytest.raises(InputError, match="increase strictly"):
        wheel_envelope_m(s[::-1], 0 * s, 0.1)


def test_envelope_bridges_a_narrow_pothole() -> None:
    # A pothole 0.1 m wide and 0.2 m deep under a wheel of r = 0.1: the wheel sinks only
    # to r - sqrt(r^2 - 0.05^2) = 0.0134 m below the rim (chord geometry).
    s = np.arange(-1.0, 1.0 + 1e-9, 1e-3)
    z = np.where(np.abs(s) < 0.05 - 1e-9, -0.2, 0.0)
    y = wheel_envelope_m(s, z, 0.1)
    # the rim samples are at s = +-0.05 (the first flat samples), 0.05 from the centre
    assert y.min() == pytest.approx(-(0.1 - math.sqrt(0.1**2 - 0.05**2)), abs=1e-12)


def test_envelope_of_a_long_route_lies_on_or_above_every_sample() -> None:
    # 2 km at 1 cm (10 neighbours each side; about 0.07 s, a speed for benchmarks, not a
    # timed test): the wheel never sinks below a sample it stands over.
    rng = np.random.default_rng(1)
    s = np.arange(200_000) * 0.01
    z = np.cumsum(rng.normal(0.0, 0.003, s.size))
    y = wheel_envelope_m(s, z, 0.1)
    assert np.all(y >= z) and np.any(y > z)


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


def polyline_excess_n(vehicle, speed: float, wavelength: float, amplitude: float, spacing: float) -> float:
    """How far the polyline through samples of A sin(k x) may move the forces (module docstring)."""
    k = 2 * math.pi / wavelength
    return vehicle.damping_ns_per_m * speed * amplitude * k * k * spacing / 2


@pytest.mark.parametrize(
    "vehicle, speed",
    [(ATV, 2.0), (ATV, 5.0), (ATV, 12.0), (RESONANT, 60.0 / (2 * math.pi)), (RESONANT, 3.0)],
    ids=["atv-r0.42", "atv-r1.05", "atv-r2.5", "resonant-r1", "resonant-r0.31"],
)
def test_sinusoidal_road_gives_steady_state_amplitudes(vehicle, speed: float) -> None:
    # The ground is the polyline through samples 2 cm apart: its slope steps move both
    # forces by at most c v A k^2 h / 2 from the smooth sinusoid's (0.02 to 0.3 N here,
    # 0.03 to 1.3 % of the force); beyond that the simulation adds 2e-4 at most. The
    # reference is the two-harmonic closed form (the rigid wheel's second harmonic
    # r A^2 k^2 / 4 cos 2kx counts at this precision: 3e-4 of the force at 5 m/s).
    wavelength, amplitude, spacing = 10.0, 0.02, 0.02
    run, b = _sinusoid_run(vehicle, speed, wavelength, amplitude, 400.0, spacing, 10.0)
    settled = b[:-1] >= 250.0  # after >= 20 s: transients decayed by exp(-zeta wn t) < 1e-5
    f_t, f_e = two_harmonic_peaks_n(amplitude, wavelength, speed, vehicle)
    excess = polyline_excess_n(vehicle, speed, wavelength, amplitude, spacing)
    assert np.all(np.abs(run.transmitted_peak_n[settled] - f_t) <= excess + 2e-4 * f_t)
    assert np.all(np.abs(run.excitation_peak_n[settled] - f_e) <= excess + 2e-4 * f_e)
    # and the textbook's single harmonic is within 1 % of that (Inman 2.4)
    w = 2 * math.pi * speed / wavelength
    assert f_t == pytest.approx(inman_transmitted_n(amplitude, w, vehicle), rel=0.01)
    assert f_e == pytest.approx(excitation_amplitude_n(amplitude, w, vehicle), rel=0.01)


@pytest.mark.parametrize("envelope", [True, False], ids=["wheel", "polyline"])
def test_the_forces_exceed_the_smooth_ground_by_the_polylines_first_order_in_the_spacing(envelope: bool) -> None:
    # The ground is the polyline through the samples. Each chord's slope is the sinusoid's
    # at the chord's middle to O(h^2), and the wheel (or the bare polyline) takes the slope
    # of the chord it stands on, so y' differs from the smooth ground's by up to
    # v |z''| h / 2 = v A k^2 h / 2, and the damper passes c times that: the forces exceed
    # the smooth closed form by at most c v A k^2 h / 2 to first order in h, and halving
    # the spacing halves the excess. Measured at 5 m/s (atv): 0.077 N at 2 cm, 0.039 N at
    # 1 cm, bound 0.118 and 0.059 N, on 27.2 N. The method itself adds nothing visible:
    # what is left is the polyline's.
    wavelength, amplitude, speed = 10.0, 0.02, 5.0
    w = 2 * math.pi * speed / wavelength
    if envelope:
        f_t, f_e = two_harmonic_peaks_n(amplitude, wavelength, speed, ATV)
    else:  # the bare polyline: the single harmonic of the textbook (Inman 2.4)
        f_t, f_e = inman_transmitted_n(amplitude, w, ATV), excitation_amplitude_n(amplitude, w, ATV)
    excess = {}
    for spacing in (0.02, 0.01):
        run, b = _sinusoid_run(ATV, speed, wavelength, amplitude, 400.0, spacing, 10.0, envelope=envelope)
        settled = b[:-1] >= 250.0
        bound = polyline_excess_n(ATV, speed, wavelength, amplitude, spacing)
        excess[spacing] = (float(np.max(run.transmitted_peak_n[settled])) - f_t,
                           float(np.max(run.excitation_peak_n[settled])) - f_e)
        assert 0.0 < excess[spacing][0] <= bound + 1e-4 * f_t
        assert 0.0 < excess[spacing][1] <= bound + 1e-4 * f_e
    for col in (0, 1):
        assert excess[0.02][col] / excess[0.01][col] == pytest.approx(2.0, rel=0.05)


def test_force_at_20_mps_on_a_sampled_sinusoid_is_the_closed_form() -> None:
    # atv-resonant at its top speed, 20 m/s, on z = 0.3 sin(2 pi x / 4.7 m) sampled every
    # 5 cm and 2.5 cm (one wavelength per segment: the segment mean of the samples is the
    # mean of y), the wheel on. The reference is the two-harmonic closed form (module
    # docstring); the second harmonic adds 1.8 % to the single-sinusoid textbook value here:
    # the rigid wheel's real geometry. The polyline's slope steps may add up to
    # c v A k^2 h / 2 (2.1 % at 5 cm); measured +1.37 % (F_T) and +1.48 % (F) at 5 cm,
    # +0.65 % and +0.73 % at 2.5 cm: first order in the spacing.
    amplitude, wavelength, speed = 0.3, 4.7, 20.0
    f_t, f_e = two_harmonic_peaks_n(amplitude, wavelength, speed, RESONANT)
    excess = []
    for spacing in (0.05, 0.025):
        run, b = _sinusoid_run(RESONANT, speed, wavelength, amplitude, 128 * wavelength, spacing, wavelength)
        settled = b[:-1] >= 64 * wavelength  # after 15 s: transients down by exp(-zeta wn t) = 1e-4
        bound = polyline_excess_n(RESONANT, speed, wavelength, amplitude, spacing)
        assert np.all(np.abs(run.transmitted_peak_n[settled] - f_t) <= bound)
        assert np.all(np.abs(run.excitation_peak_n[settled] - f_e) <= bound)
        excess.append(float(np.max(run.transmitted_peak_n[settled])) - f_t)
    assert excess[0] / excess[1] == pytest.approx(2.0, rel=0.15)
    w = 2 * math.pi * speed / wavelength
    assert f_t / inman_transmitted_n(amplitude, w, RESONANT) - 1 == pytest.approx(0.0177, abs=0.001)
    assert f_e / excitation_amplitude_n(amplitude, w, RESONANT) - 1 == pytest.approx(0.0190, abs=0.001)


def steady_state_peaks_n(amplitude_m: float, wavelength_m: float, speed_mps: float, vehicle,
                         points: int = 1024) -> tuple[float, float]:
    """Steady-state peaks (|F_T|, |F|) of the wheel's exact path on the smooth A sin(k x).

    The offset curve (:func:`offset_curve_m`, exact) over one wavelength, expanded in a
    Fourier series (it is smooth: A k^2 r < 1, so its coefficients fall geometrically; at
    1024 points the last ones are 1e-16 of the first); each harmonic passes through the
    textbook transfer functions (Inman 2.4) as in :func:`two_harmonic_peaks_n`; the mean
    moves no force and the segment mean removes it from F.
    """
    m, wn, zeta = vehicle.quarter_mass_kg, vehicle.natural_frequency_radps, vehicle.damping_ratio
    k_spring, c = m * wn**2, 2 * zeta * m * wn
    x = np.arange(points) * wavelength_m / points
    coef = np.fft.rfft(offset_curve_m(x, amplitude_m, wavelength_m, vehicle.wheel_radius_m)) / points
    coef[0] = 0.0
    coef[1:] *= 2.0  # y = sum Re(coef_n e^{i n w t})
    w = 2 * math.pi * speed_mps / wavelength_m * np.arange(coef.size)
    x_over_y = (k_spring + 1j * c * w) / (k_spring - m * w**2 + 1j * c * w)
    phase = np.exp(1j * np.outer(np.arange(points) * 2 * math.pi / points, np.arange(coef.size)))
    f_t = (phase @ (-m * w**2 * x_over_y * coef)).real
    f_e = (phase @ ((k_spring + 1j * c * w) * coef)).real
    return float(np.max(np.abs(f_t))), float(np.max(np.abs(f_e)))


def test_washboard_force_at_20_mps_converges_to_the_smooth_grounds_as_the_spacing_shrinks() -> None:
    # washboard.csv's corrugation (A = 0.04 m, 1.5 cycles/m, r k = 0.94: the two-harmonic
    # form no longer holds) under atv-resonant at 20 m/s. Reference: the steady state of the
    # wheel's exact path on the smooth sinusoid, 950.7 N (F_T) and 951.3 N (F)
    # (steady_state_peaks_n, independent of the simulator). The route's own sampling, 5 cm
    # (13 samples per wavelength), gives 1.9 % more (968.9 N); 1.25 cm 0.8 %, 5 mm 0.36 %:
    # the polyline's slope steps, within c v A k^2 h / 2 (22 % at 5 cm: the wheel, rolling
    # over every convex vertex on an arc, smooths most of them). (Before, with the path
    # interpolated through its heights at the samples, 5 cm gave 1.2-1.4 % less than the
    # offset curve at 5 mm, whose own polyline the new path shows to be 0.36 % high.)
    amplitude, wavelength, speed, length = 0.04, 2.0 / 3.0, 20.0, 400.0
    f_t, f_e = steady_state_peaks_n(amplitude, wavelength, speed, RESONANT)
    assert (f_t, f_e) == pytest.approx(steady_state_peaks_n(amplitude, wavelength, speed, RESONANT, 2048), rel=1e-6)
    boundaries = np.arange(0.0, length + 1.0, 2.0)  # 3 wavelengths per segment
    speeds = np.full(boundaries.size, speed)
    settled = boundaries[:-1] >= 300.0  # 15 s: transients down by exp(-0.6 * 15) = 1e-4
    excess = []
    for spacing in (0.05, 0.0125, 0.005):
        s = np.arange(0.0, length + spacing / 2, spacing)
        run = simulate_quarter_car(s, 150.0 + amplitude * np.sin(2 * np.pi * s / wavelength),
                                   boundaries, speeds, RESONANT, detrend=False)
        bound = polyline_excess_n(RESONANT, speed, wavelength, amplitude, spacing)
        for sampled, reference in ((run.transmitted_peak_n, f_t), (run.excitation_peak_n, f_e)):
            assert np.all(np.abs(sampled[settled] - reference) <= bound)
        excess.append(float(np.max(run.transmitted_peak_n[settled])) / f_t - 1)
    assert excess[0] > excess[1] > excess[2] > 0.0
    assert excess[2] < 0.005
    assert float(np.max(run.excitation_peak_n[settled])) < RESONANT.max_excitation_force_n


@pytest.mark.parametrize("speed", [0.1, 0.3])
def test_sbem_sinusoid_matches_eq_11_and_13(speed: float) -> None:
    # The SBEM's own terrain: a sinusoid of amplitude e whose quarter period is X_w
    # (wavelength 4 X_w, so w = w_b of Eq. 12). The wheel cannot follow it (its curvature
    # pi^2 / (8 r) exceeds 1 / r), so the raw samples are fed in (envelope=False): their
    # polyline, 400 samples per wavelength, whose slope steps add at most
    # c v A k^2 h / 2 = 0.6-0.7 % of the forces (test above).
    e = 0.02
    wavelength = 4 * float(step_width(e, ATV))  # 0.24 m
    n_waves = 60
    run, b = _sinusoid_run(ATV, speed, wavelength, e, n_waves * wavelength, wavelength / 400,
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


@pytest.mark.parametrize("chunk", [2, 7, 500])
def test_the_run_is_the_same_computed_in_chunks_of_any_size(monkeypatch, chunk: int) -> None:
    """Every row and every peak equal, bit for bit, whether the forces are computed for all
    knots at once or a few at a time (chunk edges cut between a knot's left and right rows,
    inside an interval with a turning point, and at the last knot)."""
    import profileopt.physics.simulate as simulate

    rng = np.random.default_rng(7)
    s = np.arange(0.0, 40.0, 0.05)
    z = 0.02 * rng.standard_normal(s.size)
    z[(s > 12) & (s < 14)] += 0.08  # a block: kinks where the wheel meets and leaves it
    boundaries = np.linspace(0.0, s[-1], 41)
    speeds = np.concatenate([[0.3], rng.uniform(1.0, 6.0, boundaries.size - 1)])

    def run():
        return simulate_quarter_car(s, z, boundaries, speeds, RESONANT)

    monkeypatch.setattr(simulate, "CHUNK_KNOTS", 1 << 40)
    whole = run()
    monkeypatch.setattr(simulate, "CHUNK_KNOTS", chunk)
    chunked = run()
    assert whole.time_s.size > 20 * chunk  # many chunks
    for name in ("time_s", "s_m", "speed_mps", "base_m", "mass_m", "transmitted_n", "excitation_n",
                 "transmitted_peak_n", "excitation_peak_n"):
        assert np.array_equal(getattr(whole, name), getattr(chunked, name)), name
