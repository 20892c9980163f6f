"""profileopt.verify: per-segment simulated forces beside the prediction and the limit.

Reference values are closed forms for a sinusoidal road at constant speed (Inman,
Engineering Vibration, section 2.4; NOTES.md, Eq. 11 simplified), computed in this file.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from profileopt.errors import InputError
from profileopt.planner import Profile
from profileopt.route import Route
from profileopt.vehicle import load_vehicle
from profileopt.verify import VERIFICATION_COLUMNS, plot_verification, verify

ATV = load_vehicle("atv")
WAVELENGTH_M, AMPLITUDE_M, SPEED_MPS, LENGTH_M, SEGMENT_M = 10.0, 0.02, 5.0, 300.0, 10.0


def inman_transmitted_n(y_m: float, w_radps: float, vehicle) -> float:
    """Inman section 2.4: F_T = k Y r^2 sqrt((1 + (2 zeta r)^2) / ((1 - r^2)^2 + (2 zeta r)^2))."""
    k = vehicle.quarter_mass_kg * vehicle.natural_frequency_radps**2
    zeta, r = vehicle.damping_ratio, w_radps / vehicle.natural_frequency_radps
    return k * y_m * r**2 * math.sqrt((1 + (2 * zeta * r) ** 2) / ((1 - r**2) ** 2 + (2 * zeta * r) ** 2))


def excitation_n(y_m: float, w_radps: float, vehicle) -> float:
    """Amplitude of k y + c y' for y = Y sin(w t): Y sqrt(k^2 + (c w)^2)."""
    m, wn, zeta = vehicle.quarter_mass_kg, vehicle.natural_frequency_radps, vehicle.damping_ratio
    return y_m * math.sqrt((m * wn**2) ** 2 + (2 * zeta * m * wn * w_radps) ** 2)


W_RADPS = 2 * math.pi * SPEED_MPS / WAVELENGTH_M
F_T = inman_transmitted_n(AMPLITUDE_M, W_RADPS, ATV)  # 27.2 N
F_E = excitation_n(AMPLITUDE_M, W_RADPS, ATV)  # 26.1 N


def sinusoid_route() -> Route:
    s = np.arange(0.0, LENGTH_M + 0.01, 0.02)
    return Route(s_m=s, z_m=AMPLITUDE_M * np.sin(2 * np.pi * s / WAVELENGTH_M), source="sinusoid")


def constant_speed_profile(predicted_n: float, limit_n: float, model: str, speed_mps: float = SPEED_MPS) -> Profile:
    """A stand-in for a planned profile: constant speed over whole-wavelength segments."""
    s = np.arange(0.0, LENGTH_M + SEGMENT_M / 2, SEGMENT_M)
    n = s.size
    return Profile(
        s_m=s, speed_mps=np.full(n, speed_mps), accel_mps2=np.zeros(n), time_s=s / speed_mps,
        ri=np.full(n, AMPLITUDE_M / math.sqrt(2) / ATV.ground_clearance_m), e_max_m=np.full(n, 0.1),
        force_n=np.full(n, predicted_n), force_limit_n=np.full(n, limit_n), model=model,
    )


@pytest.mark.parametrize("model, closed_form", [("sbem_tf", F_T), ("iecm", F_E)])
def test_the_models_own_force_is_simulated_and_set_against_the_limit(model: str, closed_form: float) -> None:
    # Limit 0.999 of the steady-state amplitude: every settled segment is (just) over it.
    vehicle = ATV.replace(max_transmitted_force_n=0.999 * F_T, max_excitation_force_n=0.999 * F_E)
    profile = constant_speed_profile(0.5 * closed_form, 0.999 * closed_form, model)
    v = verify(sinusoid_route(), profile, vehicle, detrend=False)
    settled = v.s_m[:-1] >= 150.0  # 30 s in: the transient has decayed (exp(-1.5 * 30))
    assert v.quantity == ("transmitted" if model == "sbem_tf" else "excitation")
    assert np.allclose(v.simulated_n[settled], closed_form, rtol=1e-3)
    assert np.allclose(v.ratio[settled], 1 / 0.999, rtol=1e-3)
    assert np.all(v.over[settled])
    assert v.over_count == int(np.count_nonzero(v.simulated_n > 0.999 * closed_form))
    assert v.over_length_m == pytest.approx(SEGMENT_M * v.over_count)
    assert v.over_fraction == pytest.approx(v.over_count / 30)
    assert v.worst_ratio == pytest.approx(float(np.max(v.simulated_n)) / (0.999 * closed_form))
    assert np.all(v.underpredicted[settled])  # predicted half of it: not conservative
    assert not v.notes


def test_excitation_datum_is_the_segment_trend_so_a_grade_adds_nothing() -> None:
    base = sinusoid_route()
    graded = Route(s_m=base.s_m, z_m=base.z_m + 0.05 * base.s_m + 812.0, source="graded")
    profile = constant_speed_profile(0.0, 5000.0, "sbem_ef")
    flat = verify(base, profile, ATV)
    steep = verify(graded, profile, ATV)
    assert np.allclose(steep.excitation_peak_n, flat.excitation_peak_n, rtol=1e-4)
    # (1e-4: PCHIP is not linear in its data, so a grade changes the interpolant a little)
    assert np.allclose(steep.transmitted_peak_n, flat.transmitted_peak_n, rtol=1e-4)
    # without the detrending the grade would count: k * 0.05 m/m * 5 m = 225 N at least
    raw = verify(graded, profile, ATV, detrend=False)
    assert np.min(raw.excitation_peak_n) > 0.05 * ATV.spring_n_per_m * SEGMENT_M / 2


def test_lift_off_where_the_suspension_would_pull_the_wheel_down() -> None:
    # Steady state F_T swings between +-F; where F > m g the wheel would leave the ground.
    # 0.4 m amplitude at 15 m/s: r = 3.14, F = 1246 N > m g = 981 N.
    speed, amplitude = 15.0, 0.4
    force = inman_transmitted_n(amplitude, 2 * math.pi * speed / WAVELENGTH_M, ATV)
    route = Route(s_m=sinusoid_route().s_m, z_m=sinusoid_route().z_m * (amplitude / AMPLITUDE_M), source="x20")
    v = verify(route, constant_speed_profile(0.0, 5000.0, "sbem_tf", speed), ATV, detrend=False)
    settled = v.s_m[:-1] >= 150.0
    assert force > v.weight_n == pytest.approx(100.0 * 9.80665)
    assert np.all(v.lift_off[settled])
    # 2 %: a 0.4 m sine is no longer exactly what the wheel follows (its envelope adds
    # harmonics of relative size r Y (2 pi / lambda)^2 / 4 ~ 1 %)
    assert np.allclose(v.transmitted_down_n[settled], -force, rtol=0.02)
    assert np.allclose(v.transmitted_up_n[settled], force, rtol=0.02)
    assert not np.any(verify(sinusoid_route(), constant_speed_profile(0.0, 5000.0, "sbem_tf"), ATV).lift_off)


def test_a_profile_off_the_route_is_an_input_error() -> None:
    profile = constant_speed_profile(0.0, 5000.0, "sbem_tf")
    short = Route(s_m=np.linspace(0.0, 100.0, 1001), z_m=np.zeros(1001), source="short.csv")
    with pytest.raises(InputError, match="short.csv: the profile covers"):
        verify(short, profile, ATV)


def test_a_limit_that_differs_from_the_vehicle_is_noted() -> None:
    v = verify(sinusoid_route(), constant_speed_profile(0.0, 1234.0, "sbem_tf"), ATV)
    assert len(v.notes) == 1 and "1234" in v.notes[0] and "max_transmitted_force_n" in v.notes[0]
    assert np.all(v.limit_n == ATV.max_transmitted_force_n)


def test_unknown_model_is_an_input_error() -> None:
    with pytest.raises(InputError, match="--model"):
        verify(sinusoid_route(), constant_speed_profile(0.0, 5000.0, "sbem_tf"), ATV, model="magic")


def test_csv_is_complete_reproducible_and_atomic(tmp_path: Path) -> None:
    route, profile = sinusoid_route(), constant_speed_profile(100.0, 5000.0, "sbem_tf")
    first, second = tmp_path / "a.csv", tmp_path / "b.csv"
    verify(route, profile, ATV).to_csv(first)
    verify(route, profile, ATV).to_csv(second)
    assert first.read_bytes() == second.read_bytes()
    lines = first.read_text().splitlines()
    assert lines[0].startswith("# profileopt verify: route sinusoid, vehicle atv.toml, model sbem_tf")
    assert tuple(lines[1].split(",")) == VERIFICATION_COLUMNS
    table = np.loadtxt(first, delimiter=",", skiprows=2)
    assert table.shape == (30, len(VERIFICATION_COLUMNS))
    col = {name: table[:, i] for i, name in enumerate(VERIFICATION_COLUMNS)}
    assert np.allclose(col["ratio"], col["sim_transmitted_peak_n"] / 5000.0, rtol=1e-9)
    assert np.array_equal(col["s_end_m"][:-1], col["s_start_m"][1:])
    # a folder that does not exist: an InputError, and nothing is written anywhere
    with pytest.raises(InputError, match="does not exist"):
        verify(route, profile, ATV).to_csv(tmp_path / "missing" / "c.csv")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.csv", "b.csv"]


def test_plot_is_a_png(tmp_path: Path) -> None:
    v = verify(sinusoid_route(), constant_speed_profile(100.0, 5000.0, "sbem_tf"), ATV)
    out = tmp_path / "v.png"
    plot_verification(v, out)
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert [p.name for p in tmp_path.iterdir()] == ["v.png"]  # no temporary file left
