"""profileopt.mpc.motion_constraints: the lateral, friction and power rows against closed forms,
solved by IPOPT, on every kind of argument, with exact derivatives and clear input errors.

References (closed forms, each cited next to its use): the lateral speed limit on an arc,
v = sqrt(a_lat R); the static rollover threshold g t / (2 h_cg) (Gillespie, Fundamentals of
Vehicle Dynamics, 1992, section 9); the friction circle (a + g sin theta)^2 + (v^2 / R)^2
<= (mu g cos theta)^2; the power limit m (a + g sin theta) v <= P. Derivatives are
checked against central finite differences of the numeric rows.
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
import pytest

from profileopt import InputError, load_vehicle
from profileopt.mpc.constraints import force_constraints
from profileopt.mpc.motion_constraints import (
    MotionConstraints,
    friction_constraints,
    lateral_constraints,
    power_constraints,
)

G = 9.80665  # standard gravity (m/s^2), ISO 80000-3
IPOPT = {"ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes", "ipopt.tol": 1e-12}
ATV = load_vehicle("atv")  # a_lat 4 m/s^2, t 1.0 m, h_cg 0.6 m, mu 0.6, m 450 kg, P 30 kW
MU, MASS, POWER = 0.6, 450.0, 30000.0
BARE = ATV.replace(max_lateral_accel_mps2=None, track_width_m=None, cg_height_m=None, friction_coefficient=None,
                   mass_kg=None, max_power_w=None)


def _numbers(x) -> np.ndarray:
    return np.asarray(ca.DM(x)).ravel()


def _maximise(x, objective, cons: MotionConstraints, lbx, ubx, x0):
    """Solve max objective(x) s.t. cons with IPOPT; return x."""
    solver = ca.nlpsol("s", "ipopt", {"x": x, "f": -objective, "g": cons.g}, IPOPT)
    sol = solver(x0=x0, lbx=lbx, ubx=ubx, lbg=cons.lbg, ubg=cons.ubg)
    assert solver.stats()["success"]
    return _numbers(sol["x"])


# ---------------------------------------------------------------------------------------
# Lateral
# ---------------------------------------------------------------------------------------


def test_lateral_speed_on_an_arc_is_sqrt_of_a_lat_times_radius() -> None:
    # closed form: v^2 / R <= a_lat on R = 25 m with a_lat = 4 m/s^2 gives v <= sqrt(4 * 25) = 10 m/s
    # (ATV's rollover threshold 9.80665 / 1.2 = 8.17 m/s^2 is larger, so a_lat = 4 binds)
    v = ca.SX.sym("v")
    cons = lateral_constraints(v, 1.0 / 25.0, ATV)
    assert cons.limit == 4.0 and cons.name == "lateral"
    best = _maximise(v, v, cons, 0.0, 50.0, 1.0)
    assert best[0] == pytest.approx(10.0, abs=1e-6)


def test_lateral_sign_of_curvature_does_not_matter() -> None:
    left = _numbers(lateral_constraints([10.0, 5.0], [1 / 25, -1 / 25], ATV).g)
    assert left == pytest.approx([0.0, 25 / 25 / 4 - 1])  # 5^2 / 25 / 4 - 1 = -0.75
    kappa = ca.SX.sym("k")
    fn = ca.Function("f", [kappa], [lateral_constraints(10.0, kappa, ATV).g])
    assert float(fn(-1 / 25)) == pytest.approx(0.0, abs=1e-14)


def test_lateral_limit_is_the_smaller_of_the_given_and_the_rollover_threshold() -> None:
    rollover = G * 1.0 / (2 * 0.6)  # Gillespie 1992: g t / (2 h_cg), t = 1.0 m, h_cg = 0.6 m = 8.1722 m/s^2
    only_rollover = ATV.replace(max_lateral_accel_mps2=None)
    assert lateral_constraints(1.0, 0.1, only_rollover).limit == pytest.approx(rollover, rel=1e-15)
    # v at the limit on R = 10 m: sqrt(rollover * 10); g there is 0
    v = math.sqrt(rollover * 10.0)
    assert _numbers(lateral_constraints(v, 0.1, only_rollover).g)[0] == pytest.approx(0.0, abs=1e-14)
    higher_given = ATV.replace(max_lateral_accel_mps2=9.0)  # 9 > 8.17: rollover binds
    assert lateral_constraints(1.0, 0.1, higher_given).limit == pytest.approx(rollover, rel=1e-15)
    only_given = ATV.replace(track_width_m=None, cg_height_m=None, max_lateral_accel_mps2=9.0)
    assert lateral_constraints(1.0, 0.1, only_given).limit == 9.0


def test_lateral_segments_layout_gives_entry_and_exit_rows() -> None:
    # 3 boundary speeds, 2 segments of radius 25 m and 100 m: rows v0,v1 on 1/25, v1,v2 on 1/100
    g = _numbers(lateral_constraints([2.0, 10.0, 20.0], [1 / 25, 1 / 100], ATV).g)
    expected = [4 / 25 / 4 - 1, 100 / 25 / 4 - 1, 100 / 100 / 4 - 1, 400 / 100 / 4 - 1]
    assert g == pytest.approx(expected, abs=1e-14)
    # one curvature for all: one row per speed
    assert _numbers(lateral_constraints([2.0, 10.0, 20.0], 1 / 25, ATV).g) == pytest.approx(
        [4 / 100 - 1, 100 / 100 - 1, 400 / 100 - 1])


# ---------------------------------------------------------------------------------------
# Friction
# ---------------------------------------------------------------------------------------


def test_friction_speed_on_flat_arc_and_accel_at_rest() -> None:
    radius = 20.0
    v_max = math.sqrt(MU * G * radius)  # closed form: v^2 / R = mu g at a = 0 on flat ground
    g = _numbers(friction_constraints([v_max, 0.999 * v_max, 1.001 * v_max], 0.0, 1 / radius, 0.0, ATV).g)
    assert g[0] == pytest.approx(0.0, abs=1e-12) and g[1] < 0 < g[2]
    a_max = MU * G  # closed form: at v = 0 the whole circle is longitudinal, |a| <= mu g
    g = _numbers(friction_constraints(0.0, [a_max, -a_max, 1.001 * a_max], 1 / radius, 0.0, ATV).g)
    assert g[:2] == pytest.approx([0.0, 0.0], abs=1e-12) and g[2] > 0


def test_friction_on_a_grade_admits_the_shifted_interval() -> None:
    theta = math.atan(0.2)
    lo = -MU * G * math.cos(theta) - G * math.sin(theta)  # closed form: |a + g sin theta| <= mu g cos theta
    hi = MU * G * math.cos(theta) - G * math.sin(theta)
    a = [lo, hi, lo - 1e-3, hi + 1e-3, 0.5 * (lo + hi)]
    g = _numbers(friction_constraints(5.0, a, 0.0, theta, ATV).g)
    assert g[:2] == pytest.approx([0.0, 0.0], abs=1e-12)
    assert g[2] > 0 and g[3] > 0 and g[4] < 0


def test_friction_opti_largest_accel_on_an_arc() -> None:
    v, radius = 6.0, 10.0
    expected = math.sqrt((MU * G) ** 2 - (v**2 / radius) ** 2)  # closed form: rest of the friction circle
    opti = ca.Opti()
    a = opti.variable()
    g, lbg, ubg = friction_constraints(v, a, 1 / radius, 0.0, ATV)
    opti.subject_to(g <= ubg)
    opti.minimize(-a)
    opti.set_initial(a, 0.0)
    opti.solver("ipopt", IPOPT)
    assert opti.solve().value(a) == pytest.approx(expected, abs=1e-6)


# ---------------------------------------------------------------------------------------
# Power
# ---------------------------------------------------------------------------------------


def test_power_speed_on_a_climb_is_p_over_m_g_sin_theta() -> None:
    theta = math.atan(0.1)  # a 10 % climb
    expected = POWER / (MASS * G * math.sin(theta))  # closed form: m g sin theta v = P at a = 0
    v = ca.SX.sym("v")
    cons = power_constraints(v, 0.0, theta, ATV)
    assert cons.limit == POWER and cons.name == "power"
    best = _maximise(v, v, cons, 0.0, 200.0, 1.0)
    assert best[0] == pytest.approx(expected, abs=1e-6)


def test_power_braking_is_never_limited() -> None:
    theta = math.atan(0.1)
    a = -G * math.sin(theta) - 0.1  # a + g sin theta = -0.1 < 0: braking
    g = _numbers(power_constraints([0.0, 10.0, 1e3, 1e6], a, theta, ATV).g)
    assert np.all(g <= -1.0)
    # downhill coasting (a = 0, theta < 0) needs no power either
    assert np.all(_numbers(power_constraints([5.0, 50.0], 0.0, -0.1, ATV).g) < -1.0 + 1e-15)


# ---------------------------------------------------------------------------------------
# Every kind of argument, exact derivatives
# ---------------------------------------------------------------------------------------

SPEEDS = np.array([3.0, 7.0, 11.0, 6.0])  # 4 boundary speeds: 3 segments
ACCELS = np.array([0.8, -0.4, -1.5])
CURVATURES = np.array([0.02, -0.05, 0.0])
GRADES = np.array([0.05, -0.08, 0.12])


def _all_three(v, a):
    return ca.vertcat(lateral_constraints(v, CURVATURES, ATV).g,
                      friction_constraints(v, a, CURVATURES, GRADES, ATV).g,
                      power_constraints(v, a, GRADES, ATV).g)


def test_sx_mx_dm_and_numpy_give_the_same_rows() -> None:
    reference = _numbers(_all_three(SPEEDS, ACCELS))
    assert reference.shape == (18,)  # 3 functions x 2 rows per segment x 3 segments
    assert _numbers(_all_three(ca.DM(SPEEDS), ca.DM(ACCELS))) == pytest.approx(reference, rel=1e-15)
    assert _numbers(_all_three(list(SPEEDS), list(ACCELS))) == pytest.approx(reference, rel=1e-15)
    for kind in (ca.SX, ca.MX):
        v, a = kind.sym("v", 4), kind.sym("a", 3)
        fn = ca.Function("rows", [v, a], [_all_three(v, a)])
        assert _numbers(fn(SPEEDS, ACCELS)) == pytest.approx(reference, rel=1e-14)
    # the rows of segment 1 (speeds 7 and 11, a = -0.4, kappa = -0.05, theta = -0.08), by hand
    seg = reference[2:4]
    assert seg == pytest.approx([49 * 0.05 / 4 - 1, 121 * 0.05 / 4 - 1], rel=1e-14)
    power = reference[12 + 2:12 + 4]
    assert power == pytest.approx([MASS * (-0.4 + G * math.sin(-0.08)) * s / POWER - 1 for s in (7, 11)], rel=1e-14)


def test_jacobian_matches_finite_differences() -> None:
    v, a = ca.SX.sym("v", 4), ca.SX.sym("a", 3)
    x = ca.vertcat(v, a)
    jac = ca.Function("rows_jacobian", [x], [ca.jacobian(_all_three(v, a), x)])
    x0 = np.concatenate([SPEEDS, ACCELS])
    exact = np.asarray(jac(x0))
    step = 1e-6
    numeric = np.zeros_like(exact)
    for j in range(x0.size):
        up, down = x0.copy(), x0.copy()
        up[j] += step
        down[j] -= step
        numeric[:, j] = (_numbers(_all_three(up[:4], up[4:])) - _numbers(_all_three(down[:4], down[4:]))) / (2 * step)
    assert np.abs(exact).max() > 0.1  # not a trivially zero Jacobian
    assert exact == pytest.approx(numeric, abs=1e-7)


def test_unpacks_indexes_and_converts_to_a_dict() -> None:
    cons = power_constraints([1.0, 2.0], 0.0, 0.0, ATV)
    g, lbg, ubg = cons
    assert dict(cons).keys() == {"g", "lbg", "ubg"} and cons[0] is g and cons["ubg"] is ubg
    assert list(lbg) == [-np.inf, -np.inf] and list(ubg) == [0.0, 0.0]
    with pytest.raises(KeyError):
        cons["value"]


# ---------------------------------------------------------------------------------------
# Bad input
# ---------------------------------------------------------------------------------------


@pytest.mark.parametrize("call, keys", [
    (lambda: lateral_constraints(1.0, 0.1, BARE), ["max_lateral_accel_mps2", "track_width_m", "cg_height_m"]),
    (lambda: friction_constraints(1.0, 0.0, 0.1, 0.0, BARE), ["friction_coefficient"]),
    (lambda: power_constraints(1.0, 0.0, 0.0, BARE), ["mass_kg", "max_power_w"]),
])
def test_missing_vehicle_keys_are_named(call, keys) -> None:
    with pytest.raises(InputError) as info:
        call()
    message = str(info.value)
    assert all(key in message for key in keys) and "to the vehicle file" in message and "\n" not in message


def test_mismatched_lengths_name_the_argument() -> None:
    with pytest.raises(InputError, match="curvature_1pm"):
        lateral_constraints([1.0, 2.0, 3.0, 4.0], [0.1, 0.1], ATV)
    with pytest.raises(InputError, match="accel_mps2 has 3.*grade_rad has 2"):
        friction_constraints([1.0, 2.0, 3.0], [0.0, 0.0, 0.0], 0.1, [0.0, 0.0], ATV)
    with pytest.raises(InputError, match="accel_mps2"):
        power_constraints(ca.SX.sym("v", 5), ca.SX.sym("a", 3), 0.0, ATV)
    with pytest.raises(InputError, match="no speeds"):
        power_constraints([], 0.0, 0.0, ATV)


@pytest.mark.parametrize("call, name", [
    (lambda: lateral_constraints([1.0, math.nan], 0.1, ATV), "speed_mps"),
    (lambda: lateral_constraints(1.0, math.nan, ATV), "curvature_1pm"),
    (lambda: friction_constraints(1.0, ca.DM([math.nan]), 0.1, 0.0, ATV), "accel_mps2"),
    (lambda: power_constraints(1.0, 0.0, np.array([0.0, math.nan]), ATV), "grade_rad"),
    (lambda: power_constraints(-1.0, 0.0, 0.0, ATV), "speed_mps"),
    (lambda: power_constraints(1.0, 0.0, 10.0, ATV), "grade_rad"),  # 10 % given as 10 rad
])
def test_nan_negative_speed_and_steep_grade_are_refused(call, name) -> None:
    with pytest.raises(InputError, match=name):
        call()


# ---------------------------------------------------------------------------------------
# Together with the force limit, in one Opti problem
# ---------------------------------------------------------------------------------------


def test_all_limits_together_with_force_constraints_in_opti() -> None:
    # 4 segments of 10 m from 5 m/s, fastest speeds: a 40 % climb where friction binds, a
    # 25 m radius bend where the lateral limit binds, a 30 % climb where power binds
    vehicle = ATV.replace(max_power_w=20000.0)
    n, ds = 4, 10.0
    curvature = np.array([0.0, 1 / 25, 1 / 25, 0.0])
    grade = np.array([math.atan(0.4), 0.0, 0.0, math.atan(0.3)])
    ri = np.full(n, 0.05)
    opti = ca.Opti()
    v, a = opti.variable(n + 1), opti.variable(n)
    opti.subject_to(v[1:] ** 2 == v[:-1] ** 2 + 2 * a * ds)  # constant acceleration over each segment
    opti.subject_to(v[0] == 5.0)
    opti.subject_to(opti.bounded(0, v, vehicle.max_speed_mps))

    def groups(v, a):
        return [force_constraints(v, vehicle, ri=ri, accel_mps2=a), lateral_constraints(v, curvature, vehicle),
                friction_constraints(v, a, curvature, grade, vehicle), power_constraints(v, a, grade, vehicle)]

    for g, lbg, ubg in groups(v, a):
        opti.subject_to(opti.bounded(ca.DM(lbg), g, ca.DM(ubg)))
    opti.minimize(-ca.sum1(v))
    opti.set_initial(v, 5.0)
    opti.solver("ipopt", IPOPT)
    sol = opti.solve()
    v_opt, a_opt = sol.value(v), sol.value(a)
    # every row holds when evaluated again with the numbers
    force, lateral, friction, power = (_numbers(group.g) for group in groups(v_opt, a_opt))
    bounds = groups(v_opt, a_opt)[0]
    assert np.all(force <= bounds.ubg + 1e-6) and np.all(force >= bounds.lbg - 1e-6)
    # the climb: friction binds, a_0 = mu g cos theta - g sin theta (closed form at kappa = 0)
    theta = math.atan(0.4)
    assert a_opt[0] == pytest.approx(MU * G * math.cos(theta) - G * math.sin(theta), abs=1e-6)
    assert friction.max() == pytest.approx(0.0, abs=1e-6)
    # the bend: its speeds are sqrt(a_lat R) = sqrt(4 * 25) = 10 m/s (closed form)
    assert v_opt[2:4] == pytest.approx([10.0, 10.0], abs=1e-6) and lateral.max() == pytest.approx(0.0, abs=1e-6)
    # the last climb: the exit speed's power row binds, m (a_3 + g sin theta) v_4 = P
    assert power[-1] == pytest.approx(0.0, abs=1e-6) and a_opt[3] < vehicle.max_accel_mps2 - 0.1


def test_constraints_module_re_exports_the_three() -> None:
    import profileopt.mpc.constraints as constraints

    assert constraints.lateral_constraints is lateral_constraints
    assert constraints.friction_constraints is friction_constraints
    assert constraints.power_constraints is power_constraints
    assert constraints.MotionConstraints is MotionConstraints
    assert {"lateral_constraints", "friction_constraints", "power_constraints"} <= set(constraints.__all__)
