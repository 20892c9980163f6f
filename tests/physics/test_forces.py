"""The four force models against independently derived numbers.

Vehicles: the paper's Table 1 ATV (k = m wn^2 = 100 * 3^2 = 900 N/m, c = 2 zeta m wn =
2 * 0.5 * 100 * 3 = 300 N s/m, r = h = 0.1 m) and its resonance case (wn = 6 rad/s, zeta =
0.1: k = 3600 N/m, c = 120 N s/m). Most hand values use e = 0.02 m, for which Eq. (2) gives
X_w = sqrt(2 * 0.02 * 0.1 - 0.02^2) = sqrt(0.0036) = 0.06 m exactly, and the speed
V = 0.72 / pi m/s, for which Eq. (12) gives w_b = pi V / (2 X_w) = 0.72 / 0.12 = 6 rad/s.
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
import pytest
import scipy.integrate
import scipy.signal
import scipy.special

from profileopt import MODELS, InputError, force_n, get_model, load_vehicle
from profileopt.physics.forces import (
    base_frequency_radps,
    iecm_force_n,
    prev_bem_force_n,
    sbem_ef_force_n,
    sbem_tf_force_n,
)

ATV = load_vehicle("atv")
RES = load_vehicle("atv-resonant")
V6 = 0.72 / math.pi  # w_b = 6 rad/s at e = 0.02 m (X_w = 0.06 m)
Z = math.sqrt(2) * scipy.special.erfinv(2 * 0.999999 - 1)  # Eq. (8) factor, 4.7534


# ------------------------------------------------------------------ hand-derived values

def test_base_frequency_eq12():
    # w_b = pi V / (2 X_w) = pi * (0.72 / pi) / (2 * 0.06) = 6 rad/s
    assert base_frequency_radps(V6, 0.02, ATV) == pytest.approx(6.0, rel=1e-14)


def test_iecm_hand_value():
    # Eq. (6) with F_hat = F / k (NOTES.md erratum of Eq. 5):
    # F = k e (2 zeta V / (wn X_w) + 1) = 900 * 0.02 * (2 * 0.5 * 2 / (3 * 0.06) + 1)
    #   = 18 * (100/9 + 1) = 18 * 109 / 9 = 218 N
    assert iecm_force_n(2.0, 0.02, ATV) == pytest.approx(218.0, rel=1e-13)
    # at rest only the spring: F = k e = 18 N
    assert iecm_force_n(0.0, 0.02, ATV) == pytest.approx(18.0, rel=1e-13)


def test_sbem_ef_hand_value_from_eq11():
    # Eq. (11) with 2 X_w / (pi V) = 1 / w_b = 1/6:
    #   numerator   2 k^2 e X_w / (pi c V) = k^2 e / (c w_b) = 810000 * 0.02 / 1800 = 9
    #             + pi c e V / (2 X_w)     = c e w_b = 300 * 0.02 * 6          = 36
    #   denominator sqrt(1 + 4 k^2 X_w^2 / (pi^2 c^2 V^2)) = sqrt(1 + k^2 / (c w_b)^2)
    #             = sqrt(1 + 810000 / 3240000) = sqrt(1.25)
    #   F = 45 / sqrt(1.25) = 18 sqrt(5) = 40.2492... N
    assert sbem_ef_force_n(V6, 0.02, ATV) == pytest.approx(45.0 / math.sqrt(1.25), rel=1e-13)
    # resonant vehicle: numerator k^2 e / (c w_b) + c e w_b = 3600^2 * 0.02 / 720 + 120 * 0.02 * 6
    #   = 360 + 14.4 = 374.4; denominator sqrt(1 + 3600^2 / 720^2) = sqrt(26); F = 73.4273 N
    assert sbem_ef_force_n(V6, 0.02, RES) == pytest.approx(374.4 / math.sqrt(26.0), rel=1e-13)


def test_sbem_tf_hand_value_from_eq13():
    # Table 1: r = w_b / wn = 6 / 3 = 2, 2 zeta r = 2:
    #   F_T = k e r^2 sqrt((1 + 4) / ((1 - 4)^2 + 4)) = 900 * 0.02 * 4 * sqrt(5 / 13) = 72 sqrt(5/13)
    assert sbem_tf_force_n(V6, 0.02, ATV) == pytest.approx(72.0 * math.sqrt(5.0 / 13.0), rel=1e-13)
    # resonant vehicle at resonance, r = 6 / 6 = 1, 2 zeta r = 0.2:
    #   F_T = 3600 * 0.02 * 1 * sqrt((1 + 0.04) / (0 + 0.04)) = 72 sqrt(26) = 367.13 N
    assert sbem_tf_force_n(V6, 0.02, RES) == pytest.approx(72.0 * math.sqrt(26.0), rel=1e-13)


def test_prev_bem_hand_value():
    # NOTES.md reconstruction: Y = sqrt(2) RI h = sqrt(2) * 0.5 * 0.1 = 0.0707 m,
    # w = 2 pi f V = 2 pi * 1.5 * 2 = 6 pi rad/s, 2 zeta w / wn = 2 * 0.5 * 6 pi / 3 = 2 pi,
    # F = k Y sqrt(1 + (2 pi)^2) = 900 * 0.0707107 * 6.36226 = 404.89 N
    expected = 900.0 * math.sqrt(2) * 0.05 * math.sqrt(1.0 + 4.0 * math.pi**2)
    assert prev_bem_force_n(2.0, 0.5, ATV) == pytest.approx(expected, rel=1e-13)
    assert expected == pytest.approx(404.89, abs=0.01)
    assert force_n(2.0, ATV, ri=0.5, model="prev_bem") == pytest.approx(expected, rel=1e-13)


def test_models_of_ri_use_e_max_of_eq8():
    # RI such that e_max = Z RI h = 0.02 m: every paper model then gives its hand value
    ri = 0.02 / (Z * 0.1)
    assert force_n(2.0, ATV, ri=ri, model="iecm") == pytest.approx(218.0, rel=1e-12)
    assert force_n(V6, ATV, ri=ri, model="sbem_ef") == pytest.approx(45.0 / math.sqrt(1.25), rel=1e-12)
    assert force_n(V6, ATV, ri=ri, model="sbem_tf") == pytest.approx(72.0 * math.sqrt(5.0 / 13.0), rel=1e-12)
    assert get_model("sbem_tf").limit_n(RES) == 1000.0
    assert get_model("iecm").limit_n(ATV) == 5000.0


def test_step_saturation_e_at_least_r():
    # e = 0.2 m >= r: X_w = r = 0.1 m. IECM: 900 * 0.2 * (2 * 0.5 * 2 / (3 * 0.1) + 1)
    #   = 180 * (20/3 + 1) = 1380 N
    assert iecm_force_n(2.0, 0.2, ATV) == pytest.approx(1380.0, rel=1e-13)
    # SBEM:EF: w_b = pi * 2 / (2 * 0.1) = 10 pi; F = 0.2 sqrt(900^2 + (300 * 10 pi)^2)
    assert sbem_ef_force_n(2.0, 0.2, ATV) == pytest.approx(0.2 * math.hypot(900.0, 3000.0 * math.pi), rel=1e-13)
    # beyond r, X_w is fixed so each e-model is exactly proportional to e
    for fun in (iecm_force_n, sbem_ef_force_n, sbem_tf_force_n):
        for v in (0.3, 2.0, 15.0):
            assert fun(v, 0.4, ATV) == pytest.approx(2.0 * fun(v, 0.2, ATV), rel=1e-13)
            assert fun(v, 0.1, ATV) == pytest.approx(0.5 * fun(v, 0.2, ATV), rel=1e-13)


@pytest.mark.parametrize("key", list(MODELS))
def test_smooth_ground_gives_zero_force(key):
    speeds = np.array([0.0, 0.1, 5.0, 20.0])
    np.testing.assert_array_equal(force_n(speeds, ATV, ri=0.0, model=key), 0.0)
    np.testing.assert_array_equal(force_n(speeds, RES, ri=np.zeros(4), model=key), 0.0)
    # the same through a symbolic evaluation (the untaken 0/0 branch must not leak a NaN)
    v, ri = ca.SX.sym("v"), ca.SX.sym("ri")
    fun = ca.Function("f", [v, ri], [force_n(v, ATV, ri=ri, model=key)])
    assert float(fun(3.0, 0.0)) == 0.0


@pytest.mark.parametrize("key", list(MODELS))
@pytest.mark.parametrize("ri", [math.nan, -0.01])
def test_bad_ri_raises(key, ri):
    with pytest.raises(ValueError, match="RI"):
        force_n(1.0, ATV, ri=ri, model=key)


def test_unknown_model_names_the_choices():
    with pytest.raises(ValueError, match="sbem_tf"):
        get_model("sbem")


# ------------------------------------------------------------------ independent derivations

SPEEDS = np.array([0.05, 0.3, V6, 1.0, 4.0, 12.0, 20.0])
HEIGHTS = np.array([0.005, 0.02, 0.07, 0.1, 0.25])


@pytest.mark.parametrize("vehicle", [ATV, RES], ids=["atv", "resonant"])
def test_sbem_ef_is_the_peak_of_eq9_at_t_max_of_eq10(vehicle):
    k, c, r = vehicle.spring_n_per_m, vehicle.damping_ns_per_m, vehicle.wheel_radius_m
    for e in HEIGHTS:
        x_w = math.sqrt(2 * min(e, r) * r - min(e, r) ** 2)  # Eq. (2), saturated
        for v in SPEEDS:
            dt = x_w / v  # Eq. (3)
            w = math.pi / (2 * dt)

            def eq9(t):  # F(t) = k e sin(pi t / (2 dt)) + c e pi / (2 dt) cos(pi t / (2 dt))
                return k * e * np.sin(w * t) + c * e * w * np.cos(w * t)

            t_max = 2 * x_w / (math.pi * v) * math.atan(2 * k * x_w / (math.pi * c * v))  # Eq. (10)
            # Eq. (11) as printed in the paper
            eq11 = (2 * k**2 * e * x_w / (math.pi * c * v) + math.pi * c * e * v / (2 * x_w)) / math.sqrt(
                1 + 4 * k**2 * x_w**2 / (math.pi**2 * c**2 * v**2)
            )
            got = sbem_ef_force_n(v, e, vehicle)
            assert got == pytest.approx(eq9(t_max), rel=1e-12)
            assert got == pytest.approx(eq11, rel=1e-12)
            # and it is the maximum over a whole period (4 dt), found by brute force
            t = np.linspace(0.0, 4 * dt, 20001)
            assert eq9(t).max() == pytest.approx(got, rel=1e-7)
            assert eq9(t).max() <= got * (1 + 1e-12)


@pytest.mark.parametrize("vehicle", [ATV, RES], ids=["atv", "resonant"])
def test_sbem_tf_is_the_transmitted_force_of_a_base_excited_oscillator(vehicle):
    # Inman, Engineering Vibration, section 2.4: m x'' + c (x' - y') + k (x - y) = 0 for a
    # base motion y. The force through spring and damper, F_T = k (x - y) + c (x' - y'), is
    # -m x''. With X / Y = (c s + k) / (m s^2 + c s + k):
    #     F_T / Y = -m s^2 (c s + k) / (m s^2 + c s + k),
    # and the steady-state amplitude for y = e sin(w_b t) is e |F_T / Y (j w_b)|.
    m, k, c = vehicle.quarter_mass_kg, vehicle.spring_n_per_m, vehicle.damping_ns_per_m
    num = [-m * c, -m * k, 0.0, 0.0]
    den = [m, c, k]
    for e in HEIGHTS:
        for v in SPEEDS:
            w_b = base_frequency_radps(v, e, vehicle)
            _, h = scipy.signal.freqs(num, den, worN=[w_b])
            assert sbem_tf_force_n(v, e, vehicle) == pytest.approx(e * abs(h[0]), rel=1e-9)


@pytest.mark.parametrize("vehicle, v", [(RES, V6), (ATV, 0.4), (RES, 1.3)], ids=["resonance", "atv", "above"])
def test_sbem_tf_matches_a_time_domain_simulation(vehicle, v):
    # Simulate the base-excited quarter car from rest until the transient has died out and
    # take the largest spring + damper force over the last periods.
    m, k, c = vehicle.quarter_mass_kg, vehicle.spring_n_per_m, vehicle.damping_ns_per_m
    e = 0.02
    w = base_frequency_radps(v, e, vehicle)
    decay_s = 1.0 / (vehicle.damping_ratio * vehicle.natural_frequency_radps)
    t_end = 22 * decay_s + 4 * 2 * math.pi / w  # transient down to e^-22 ~ 3e-10

    def rhs(t, state):
        x, xd = state
        y, yd = e * math.sin(w * t), e * w * math.cos(w * t)
        return [xd, -(c * (xd - yd) + k * (x - y)) / m]

    t = np.linspace(t_end - 3 * 2 * math.pi / w, t_end, 30001)
    sol = scipy.integrate.solve_ivp(rhs, (0.0, t_end), [0.0, 0.0], t_eval=t, rtol=1e-11, atol=1e-13, method="DOP853")
    x, xd = sol.y
    force = k * (x - e * np.sin(w * t)) + c * (xd - e * w * np.cos(w * t))
    assert np.abs(force).max() == pytest.approx(sbem_tf_force_n(v, e, vehicle), rel=2e-6)


# ------------------------------------------------------------------ every kind of argument

POINTS = [(0.0, 0.05), (0.7, 0.1), (3.0, 0.15), (12.0, 0.4), (20.0, 0.7)]


@pytest.mark.parametrize("key", list(MODELS))
@pytest.mark.parametrize("vehicle", [ATV, RES], ids=["atv", "resonant"])
def test_numbers_arrays_dm_sx_mx_agree(key, vehicle):
    v = np.array([p[0] for p in POINTS])
    ri = np.array([p[1] for p in POINTS])
    numbers = np.array([force_n(a, vehicle, ri=b, model=key) for a, b in POINTS])
    assert all(isinstance(force_n(a, vehicle, ri=b, model=key), float) for a, b in POINTS)
    np.testing.assert_allclose(force_n(v, vehicle, ri=ri, model=key), numbers, rtol=1e-14)
    # broadcasting: a (5, 1) speed column against a (1, 5) RI row
    grid = force_n(v[:, None], vehicle, ri=ri[None, :], model=key)
    assert grid.shape == (5, 5)
    np.testing.assert_allclose(np.diag(grid), numbers, rtol=1e-14)
    dm = force_n(ca.DM(v), vehicle, ri=ca.DM(ri), model=key)
    assert isinstance(dm, ca.DM)
    np.testing.assert_allclose(np.asarray(dm).ravel(), numbers, rtol=1e-14)
    for sym in (ca.SX, ca.MX):
        sv, sr = sym.sym("v"), sym.sym("ri")
        expr = force_n(sv, vehicle, ri=sr, model=key)
        assert isinstance(expr, sym)
        fun = ca.Function("f", [sv, sr], [expr])
        got = np.array([float(fun(a, b)) for a, b in POINTS])
        np.testing.assert_allclose(got, numbers, rtol=1e-13)


@pytest.mark.parametrize("key", list(MODELS))
@pytest.mark.parametrize("sym", [ca.SX, ca.MX], ids=["SX", "MX"])
def test_casadi_jacobians_match_central_differences(key, sym):
    # points away from the X_w kink at e_max = r (RI = r / (Z h) = 0.2104) and from RI = 0
    points = [(0.5, 0.05), (3.0, 0.15), (9.0, 0.4), (V6, 0.1)]
    for vehicle in (ATV, RES):
        sv, sr = sym.sym("v"), sym.sym("ri")
        expr = force_n(sv, vehicle, ri=sr, model=key)
        jac = ca.Function("j", [sv, sr], [ca.jacobian(expr, ca.vertcat(sv, sr))])
        for v, ri in points:
            exact = np.asarray(jac(v, ri)).ravel()
            hv, hr = 1e-6 * max(v, 1.0), 1e-7
            fd_v = (force_n(v + hv, vehicle, ri=ri, model=key) - force_n(v - hv, vehicle, ri=ri, model=key)) / (2 * hv)
            fd_r = (force_n(v, vehicle, ri=ri + hr, model=key) - force_n(v, vehicle, ri=ri - hr, model=key)) / (2 * hr)
            scale = abs(force_n(v, vehicle, ri=ri, model=key))
            np.testing.assert_allclose(exact, [fd_v, fd_r], rtol=1e-6, atol=1e-8 * scale)


# ------------------------------------------------------------------ one vocabulary (issue 9)

def test_force_n_of_e_max_is_the_models_own_expression():
    from profileopt.physics.forces import DEFAULT_MODEL, FORCE_OF_E_MAX

    assert DEFAULT_MODEL == "sbem_tf" and set(FORCE_OF_E_MAX) == {"iecm", "sbem_ef", "sbem_tf"}
    assert force_n(V6, ATV, e_max_m=0.02) == sbem_tf_force_n(V6, 0.02, ATV)
    assert force_n(2.0, ATV, e_max_m=0.02, model="iecm") == iecm_force_n(2.0, 0.02, ATV)
    ri = 0.02 / (Z * 0.1)
    assert force_n(V6, ATV, ri=ri) == force_n(V6, ATV, ri=ri, model="sbem_tf")


@pytest.mark.parametrize(
    "kwargs, match",
    [({}, "ri.*e_max_m"), ({"ri": 0.1, "e_max_m": 0.02}, "ri.*e_max_m"),
     ({"e_max_m": 0.02, "model": "prev_bem"}, "model 'prev_bem'.*ri"), ({"ri": 0.1, "model": "tf"}, "model 'tf'"),
     ({"e_max_m": -0.1}, "e_max_m")],
)
def test_force_n_input_errors_name_the_parameters(kwargs, match):
    with pytest.raises(InputError, match=match):
        force_n(1.0, ATV, **kwargs)


def test_force_n_rejects_a_misspelt_keyword():
    with pytest.raises(TypeError):
        force_n(1.0, ATV, r=0.1)


def test_get_model_raises_input_error():
    with pytest.raises(InputError, match="model 'sbem'.*sbem_tf"):
        get_model("sbem")


