"""profileopt.mpc.constraints: forces on every kind of argument, Jacobians, and the constraints
solving real horizon problems with IPOPT.

References: hand calculations of the paper's equations (Wilson et al., with the errata of
NOTES.md) for anchor values; central finite differences for derivatives; the bracketing
Newton root finder of profileopt.physics.speeds (an algorithm independent of IPOPT) for the optimal
speeds of the horizon problems, which are then checked by evaluating the forces again.
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
import pytest

from profileopt import InputError, allowable_speed, load_vehicle
from profileopt.mpc.constraints import (
    ForceConstraints,
    add_force_constraints,
    band_edges,
    constraint_function,
    force_constraints,
    force_function,
    force_limit_n,
    force_n,
)

MODELS = ["prev_bem", "iecm", "sbem_ef", "sbem_tf"]
E_MAX_MODELS = ["iecm", "sbem_ef", "sbem_tf"]
IPOPT = {"ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes", "ipopt.tol": 1e-10}

# atv with different limits for the two kinds of force, so that a mix-up shows
ATV = load_vehicle("atv").replace(max_excitation_force_n=4000.0, max_transmitted_force_n=5000.0)
RESONANT = load_vehicle("atv-resonant")
Z = 4.753424308816257  # sqrt(2) erfinv(2 Pe - 1) for Pe = 0.999999 (NOTES.md, Eq. 8)


def _hand_force(model: str, v: float, ri: float) -> float:
    """The four forces for the atv (m 100 kg, wn 3 rad/s, zeta 0.5, h = r = 0.1 m, f 1.5
    cycles/m), written out from the paper's equations by hand, independently of the package."""
    m, wn, zeta, h, r_w, f = 100.0, 3.0, 0.5, 0.1, 0.1, 1.5
    k, c = m * wn**2, 2 * zeta * m * wn  # 900 N/m, 300 N s/m
    if model == "prev_bem":  # NOTES.md reconstruction of [11]
        y = math.sqrt(2) * ri * h
        return k * y * math.sqrt(1 + (2 * zeta * 2 * math.pi * f * v / wn) ** 2)
    e = Z * ri * h  # Eq. 8
    x_w = math.sqrt(2 * e * r_w - e * e) if e < r_w else r_w  # Eq. 2
    w_b = math.pi * v / (2 * x_w)  # Eq. 12
    if model == "iecm":  # Eq. 6 with F_hat = F / k
        return k * e * (2 * zeta * v / (wn * x_w) + 1)
    if model == "sbem_ef":  # Eq. 11 simplified
        return e * math.sqrt(k**2 + (c * w_b) ** 2)
    rr = w_b / wn  # Eq. 13, Inman section 2.4
    return k * e * rr**2 * math.sqrt((1 + (2 * zeta * rr) ** 2) / ((1 - rr**2) ** 2 + (2 * zeta * rr) ** 2))


@pytest.mark.parametrize("model", MODELS)
def test_constraint_function_matches_hand_calculation_and_limit(model: str) -> None:
    limit = {"prev_bem": 4000.0, "iecm": 4000.0, "sbem_ef": 4000.0, "sbem_tf": 5000.0}[model]
    assert force_limit_n(ATV, model=model) == limit
    for v, ri in [(3.0, 0.1), (12.0, 0.35), (7.5, 0.6)]:  # e_max below and above r
        expected = _hand_force(model, v, ri)
        assert force_n(v, ATV, ri=ri, model=model) == pytest.approx(expected, rel=1e-13)
        assert float(force_function(ATV, model=model)(v, ri)) == pytest.approx(expected, rel=1e-13)
        g = constraint_function(ATV, model=model)
        assert float(g(v, ri)) == pytest.approx(expected / limit - 1.0, rel=1e-12, abs=1e-14)
        raw = constraint_function(ATV, model=model, normalised=False)
        assert float(raw(v, ri)) == pytest.approx(expected - limit, rel=1e-12)
        if model in E_MAX_MODELS:
            e = Z * ri * 0.1
            assert force_n(v, ATV, e_max_m=e, model=model) == pytest.approx(expected, rel=1e-12)
            assert float(force_function(ATV, model=model, terrain="e_max")(v, e)) == pytest.approx(expected, rel=1e-12)


@pytest.mark.parametrize("vehicle", [ATV, RESONANT], ids=["atv", "atv-resonant"])
@pytest.mark.parametrize("model", MODELS)
def test_numbers_numpy_sx_mx_dm_agree(model: str, vehicle) -> None:
    rng = np.random.default_rng(1)
    speed = np.r_[0.0, rng.uniform(0, 20, 9)]
    ri = np.r_[0.3, 0.0, rng.uniform(0, 1.5, 8)]
    numbers = np.array([force_n(float(v), vehicle, ri=float(r), model=model) for v, r in zip(speed, ri)])
    assert isinstance(force_n(1.0, vehicle, ri=0.2, model=model), float)
    as_numpy = force_n(speed, vehicle, ri=ri, model=model)
    assert isinstance(as_numpy, np.ndarray) and as_numpy.shape == (10,)
    as_dm = force_n(ca.DM(speed), vehicle, ri=ca.DM(ri), model=model)
    assert isinstance(as_dm, ca.DM)
    results = {"numpy": as_numpy, "DM": np.asarray(as_dm).ravel()}
    for kind in (ca.SX, ca.MX):
        v, r = kind.sym("v", 10), kind.sym("r", 10)
        expr = force_n(v, vehicle, ri=r, model=model)
        assert isinstance(expr, kind)
        results[kind.__name__] = np.asarray(ca.Function("f", [v, r], [expr])(speed, ri)).ravel()
    results["Function"] = np.asarray(force_function(vehicle, model=model, n_stages=10)(speed, ri)).ravel()
    for kind, values in results.items():
        np.testing.assert_allclose(values, numbers, rtol=1e-14, atol=1e-12, err_msg=kind)
    assert numbers[1] == 0.0 or model == "prev_bem"  # smooth ground: no force (NOTES.md)
    if model in E_MAX_MODELS:
        e = Z * ri * vehicle.ground_clearance_m
        v, t = ca.MX.sym("v", 10), ca.MX.sym("e", 10)
        mx = ca.Function("f", [v, t], [force_n(v, vehicle, e_max_m=t, model=model)])(speed, e)
        np.testing.assert_allclose(np.asarray(mx).ravel(), numbers, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(force_n(speed, vehicle, e_max_m=e, model=model), numbers, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("vehicle", [ATV, RESONANT], ids=["atv", "atv-resonant"])
@pytest.mark.parametrize(
    "model, terrain", [(m, "ri") for m in MODELS] + [(m, "e_max") for m in E_MAX_MODELS]
)
def test_jacobians_match_central_differences(model: str, terrain: str, vehicle) -> None:
    rng = np.random.default_rng(2)
    fn = force_function(vehicle, model=model, terrain=terrain)
    jac = fn.jacobian()
    g_jac = constraint_function(vehicle, model=model, terrain=terrain).jacobian()
    limit = force_limit_n(vehicle, model=model)

    def force(v: float, t: float) -> float:  # the plain-number path, not the Function
        return force_n(v, vehicle, ri=t, model=model) if terrain == "ri" else force_n(v, vehicle, e_max_m=t, model=model)

    checked = 0
    while checked < 12:
        v = rng.uniform(0.5, 19.5)
        t = rng.uniform(0.02, 1.2) if terrain == "ri" else rng.uniform(0.01, 0.5)
        e = t * Z * vehicle.ground_clearance_m if terrain == "ri" else t
        if abs(e - vehicle.wheel_radius_m) < 1e-3:  # the kink of X_w at e = r (Eq. 2)
            continue
        checked += 1
        dv, dt = 1e-6 * max(v, 1.0), 1e-6 * t
        fd_v = (force(v + dv, t) - force(v - dv, t)) / (2 * dv)
        fd_t = (force(v, t + dt) - force(v, t - dt)) / (2 * dt)
        j_v, j_t = (float(x) for x in jac(v, t, 0))
        scale = abs(force(v, t)) / max(v, 1.0) + 1e-9
        assert j_v == pytest.approx(fd_v, rel=1e-6, abs=1e-6 * scale)
        assert j_t == pytest.approx(fd_t, rel=1e-6, abs=1e-6 * abs(force(v, t)) / t)
        gv, gt = (float(x) for x in g_jac(v, t, 0))
        assert gv == pytest.approx(j_v / limit, rel=1e-12, abs=1e-15)
        assert gt == pytest.approx(j_t / limit, rel=1e-12, abs=1e-15)


def test_layouts_points_segments_and_scalar_terrain() -> None:
    speed, ri = np.array([2.0, 6.0, 9.0]), np.array([0.1, 0.3])
    f = lambda v, r: force_n(v, ATV, ri=r, model="sbem_tf")  # noqa: E731
    cons = force_constraints(speed, ATV, ri=ri, normalised=False)
    assert isinstance(cons, ForceConstraints) and cons.n_force == 4
    expected = [f(2.0, 0.1), f(6.0, 0.1), f(6.0, 0.3), f(9.0, 0.3)]  # both ends of each segment
    np.testing.assert_allclose(np.asarray(cons.g).ravel(), expected, rtol=1e-14)
    np.testing.assert_array_equal(cons.ubg, np.full(4, 5000.0))
    g, lbg, ubg = force_constraints(speed[:2], ATV, ri=ri)  # points
    np.testing.assert_allclose(np.asarray(g).ravel(), [f(2.0, 0.1) / 5000 - 1, f(6.0, 0.3) / 5000 - 1], rtol=1e-13)
    assert np.all(lbg == -np.inf) and np.all(ubg == 0.0)
    g, _, _ = force_constraints(speed, ATV, ri=0.2)  # one terrain value for every speed
    np.testing.assert_allclose(np.asarray(g).ravel(), f(speed, 0.2) / 5000 - 1, rtol=1e-13)
    a = ca.SX.sym("a", 2)
    g, lbg, ubg = force_constraints(ca.SX.sym("v", 3), ATV, ri=ri, accel_mps2=a)
    assert g.shape == (6, 1)
    np.testing.assert_array_equal(lbg[4:], [-4.0, -4.0])
    np.testing.assert_array_equal(ubg[4:], [2.5, 2.5])


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda v: force_constraints(v, ATV), "exactly one of ri"),
        (lambda v: force_constraints(v, ATV, ri=0.2, e_max_m=0.1), "exactly one of ri"),
        (lambda v: force_constraints(v, ATV, model="prev_bem", e_max_m=0.1), "roughness index only"),
        (lambda v: force_constraints(v, ATV, ri=np.ones(3)), "do not match"),
        (lambda v: force_constraints(v, ATV, ri=np.array([0.1, -0.1, 0.2, 0.1, 0.1])), ">= 0"),
        (lambda v: force_constraints(v, ATV, e_max_m=np.full(5, np.nan)), ">= 0"),
        (lambda v: force_constraints(v, ATV, ri=0.1, model="sbem"), "unknown"),
        (lambda v: force_function(ATV, model="sbem_tf", terrain="height"), "unknown"),
        (lambda v: band_edges([0.1], ATV, band="middle"), "unknown"),
        (lambda v: band_edges([0.1], ATV, band="containing"), "needs speed_mps"),
    ],
)
def test_mistakes_raise_input_error(call, message: str) -> None:
    with pytest.raises(InputError, match=message):
        call(ca.SX.sym("v", 5))


RI_HORIZON = np.array([0.0, 0.02, 0.1, 0.2, 0.3, 0.45, 0.6, 0.25, 0.05, 0.9])


def _check_speeds(v: np.ndarray, ri: np.ndarray, vehicle, model: str = "sbem_tf") -> None:
    """Independent check: allowable speeds by bracketing Newton, forces evaluated again."""
    expected = allowable_speed(ri, vehicle, model=model)
    np.testing.assert_allclose(v, expected, rtol=1e-6, atol=1e-6)
    ratio = force_n(v, vehicle, ri=ri, model=model) / force_limit_n(vehicle, model=model)
    assert np.all(ratio <= 1 + 1e-6)
    active = expected < vehicle.max_speed_mps
    assert active.sum() >= 6 and (~active).sum() >= 2  # the test exercises both cases
    np.testing.assert_allclose(ratio[active], 1.0, atol=1e-6)  # the limit binds ...
    assert np.all(ratio[~active & (ri > 0)] < 1 - 1e-3)  # ... except where v_max does


@pytest.mark.parametrize("normalised", [True, False])
def test_nlpsol_maximises_speeds_up_to_the_force_limit(normalised: bool) -> None:
    v = ca.SX.sym("v", 10)
    g, lbg, ubg = force_constraints(v, ATV, ri=RI_HORIZON, normalised=normalised)
    solver = ca.nlpsol("horizon", "ipopt", {"x": v, "f": -ca.sum1(v), "g": g}, IPOPT)
    sol = solver(x0=1.0, lbx=0.0, ubx=ATV.max_speed_mps, lbg=lbg, ubg=ubg)
    assert solver.stats()["success"]
    _check_speeds(np.asarray(sol["x"]).ravel(), RI_HORIZON, ATV)


def test_nlpsol_with_parameters_segments_and_acceleration() -> None:
    """Segments of 5 m from rest: v_{i+1}^2 = v_i^2 + 2 a_i ds, ri as parameters."""
    n, ds = 10, 5.0
    v, a, p = ca.SX.sym("v", n + 1), ca.SX.sym("a", n), ca.SX.sym("ri", n)
    cons = force_constraints(v, ATV, ri=p, accel_mps2=a)
    dyn = v[1:] ** 2 - v[:-1] ** 2 - 2 * a * ds
    x = ca.vertcat(v, a)
    solver = ca.nlpsol("segments", "ipopt", {"x": x, "p": p, "f": -ca.sum1(v), "g": ca.vertcat(cons.g, dyn)}, IPOPT)
    lbx = np.r_[0.0, np.zeros(n), np.full(n, -np.inf)]
    ubx = np.r_[0.0, np.full(n, ATV.max_speed_mps), np.full(n, np.inf)]
    ri = np.array([0.05, 0.05, 0.05, 0.05, 0.3, 0.3, 0.05, 0.05, 0.05, 0.05])
    sol = solver(x0=1.0, p=ri, lbx=lbx, ubx=ubx, lbg=np.r_[cons.lbg, np.zeros(n)], ubg=np.r_[cons.ubg, np.zeros(n)])
    assert solver.stats()["success"]
    speed, accel = np.asarray(sol["x"][: n + 1]).ravel(), np.asarray(sol["x"][n + 1:]).ravel()
    assert np.all(accel <= 2.5 + 1e-6) and np.all(accel >= -4.0 - 1e-6)
    # both ends of every segment within the limit of that segment's terrain
    for i in range(n):
        ends = force_n(speed[i:i + 2], ATV, ri=ri[i], model="sbem_tf") / 5000.0
        assert np.all(ends <= 1 + 1e-6)
    # Independent reference: the classic forward-backward pass. Boundary i is capped by the
    # allowable speeds of both segments it touches; v^2 grows by at most 2 a_max ds forward
    # and 2 d_max ds backward. Maximising the sum of speeds gives exactly these speeds.
    cap = np.minimum(np.r_[np.inf, allowable_speed(ri, ATV)], np.r_[allowable_speed(ri, ATV), np.inf])
    cap[0] = 0.0
    ref = cap.copy()
    for i in range(1, n + 1):
        ref[i] = min(ref[i], math.sqrt(ref[i - 1] ** 2 + 2 * 2.5 * ds))
    for i in range(n - 1, -1, -1):
        ref[i] = min(ref[i], math.sqrt(ref[i + 1] ** 2 + 2 * 4.0 * ds))
    np.testing.assert_allclose(speed, ref, rtol=1e-6, atol=1e-6)
    assert speed[4] == pytest.approx(allowable_speed(0.3, ATV), rel=1e-6)  # binds entering the rough part


def test_opti_helper_with_parameters_and_resolve() -> None:
    opti = ca.Opti()
    v, ri = opti.variable(10), opti.parameter(10)
    cons = add_force_constraints(opti, v, ATV, ri=ri)
    opti.subject_to(opti.bounded(0, v, ATV.max_speed_mps))
    opti.minimize(-ca.sum1(v))
    opti.solver("ipopt", {"print_time": False}, {"print_level": 0, "sb": "yes", "tol": 1e-10})
    opti.set_initial(v, 1.0)
    for ri_value in (RI_HORIZON, RI_HORIZON[::-1]):
        opti.set_value(ri, ri_value)
        sol = opti.solve()
        _check_speeds(sol.value(v), ri_value, ATV)
        np.testing.assert_allclose(sol.value(cons.force_n), force_n(sol.value(v), ATV, ri=ri_value, model="sbem_tf"))


def test_opti_helper_with_e_max_and_acceleration_bounds() -> None:
    opti = ca.Opti()
    v, a = opti.variable(11), opti.variable(10)
    e = Z * 0.1 * RI_HORIZON
    add_force_constraints(opti, v, ATV, model="sbem_ef", e_max_m=e, accel_mps2=a)
    opti.subject_to(v[1:] ** 2 == v[:-1] ** 2 + 2 * a * 5.0)
    opti.subject_to(opti.bounded(0, v, ATV.max_speed_mps))
    opti.minimize(-ca.sum1(v))
    opti.solver("ipopt", {"print_time": False}, {"print_level": 0, "sb": "yes", "tol": 1e-10})
    opti.set_initial(v, 1.0)
    sol = opti.solve()
    speed, accel = sol.value(v), sol.value(a)
    assert np.all(accel <= 2.5 + 1e-6) and np.all(accel >= -4.0 - 1e-6)
    assert accel.max() == pytest.approx(2.5, abs=1e-6) and accel.min() == pytest.approx(-4.0, abs=1e-6)
    for i in range(10):
        assert np.all(force_n(speed[i:i + 2], ATV, ri=RI_HORIZON[i], model="sbem_ef") <= 4000 * (1 + 1e-6))


def test_band_edges_of_resonant_vehicle() -> None:
    """At RI = 0.3 the resonant vehicle has two bands (NOTES.md, 'Which root')."""
    ri = np.array([0.05, 0.3])
    first, largest = band_edges(ri, RESONANT, band="first"), band_edges(ri, RESONANT, band="largest")
    np.testing.assert_array_equal(first.lower_mps, [0.0, 0.0])
    assert largest.lower_mps[1] > first.upper_mps[1] + 0.1  # a gap: forbidden speeds
    for i in range(2):
        for lo, hi in ((first.lower_mps[i], first.upper_mps[i]), (largest.lower_mps[i], largest.upper_mps[i])):
            inside = np.linspace(lo, hi, 2001)
            assert np.all(force_n(inside, RESONANT, ri=ri[i], model="sbem_tf") <= 1000.0 * (1 + 1e-9))
    gap = np.linspace(first.upper_mps[1] + 1e-3, largest.lower_mps[1] - 1e-3, 200)
    assert np.all(force_n(gap, RESONANT, ri=0.3, model="sbem_tf") > 1000.0)
    containing = band_edges(ri, RESONANT, band="containing", speed_mps=[1.0, 2.0])
    np.testing.assert_allclose(containing.lower_mps, [0.0, largest.lower_mps[1]])
    assert np.isnan(band_edges([0.3], RESONANT, band="containing", speed_mps=0.45).upper_mps[0])


def test_pointwise_constraint_jumps_a_band_and_band_bounds_prevent_it() -> None:
    """Why the docstring says to pin a resonant vehicle to a band: maximising the speed with
    the force constraint alone lands in the top band, above forbidden speeds the vehicle
    would have to pass through; the 'first' band bound keeps every speed below admissible."""
    ri = np.full(3, 0.3)
    v = ca.SX.sym("v", 3)
    g, lbg, ubg = force_constraints(v, RESONANT, ri=ri)
    solver = ca.nlpsol("bands", "ipopt", {"x": v, "f": -ca.sum1(v), "g": g}, IPOPT)
    edges = band_edges(ri, RESONANT, band="first")
    free = np.asarray(solver(x0=2.0, lbx=0, ubx=20.0, lbg=lbg, ubg=ubg)["x"]).ravel()
    pinned = np.asarray(solver(x0=0.1, lbx=edges.lower_mps, ubx=edges.upper_mps, lbg=lbg, ubg=ubg)["x"]).ravel()
    assert np.all(free > 3 * edges.upper_mps)  # pointwise-admissible, yet beyond a forbidden band
    np.testing.assert_allclose(pinned, edges.upper_mps, rtol=1e-6)
    for speed in pinned:  # every speed from rest up to the pinned one is admissible
        path = np.linspace(0.0, speed, 500)
        assert np.all(force_n(path, RESONANT, ri=0.3, model="sbem_tf") <= 1000.0 * (1 + 1e-6))


# ------------------------------------------------------------------ one vocabulary (issue 9)

def test_band_edges_refuses_all_and_names_speed_bands() -> None:
    with pytest.raises(InputError, match="speed_bands"):
        band_edges([0.1], ATV, band="all")


class _Recorder:
    """Not a casadi.Opti: anything with subject_to (rockit's Ocp, a user's own wrapper)."""

    def __init__(self) -> None:
        self.constraints: list = []

    def subject_to(self, constraint) -> None:
        self.constraints.append(constraint)


def test_add_force_constraints_accepts_any_problem_with_subject_to() -> None:
    problem = _Recorder()
    v, a = ca.MX.sym("v", 4), ca.MX.sym("a", 3)
    cons = add_force_constraints(problem, v, ATV, ri=np.full(3, 0.2), accel_mps2=a)
    assert len(problem.constraints) == 2 and cons.n_force == 6
    with pytest.raises(InputError, match="subject_to"):
        add_force_constraints(object(), v, ATV, ri=0.2)


def _same_constraints(old: ForceConstraints, new: ForceConstraints) -> None:
    assert str(old.g) == str(new.g)
    np.testing.assert_array_equal(old.lbg, new.lbg)
    np.testing.assert_array_equal(old.ubg, new.ubg)
    assert (old.model, old.n_force, old.limit_n) == (new.model, new.n_force, new.limit_n)


