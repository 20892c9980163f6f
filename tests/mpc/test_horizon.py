"""profileopt.mpc.horizon: the terrain envelope and the interval force constraints, against
brute force.

References, each computed here independently of the helper under test:

* the envelope's requirement at a position x: the largest e_max (Eq. 8, z RI h) of every
  roughness window whose stretch [a, a + W] shares a point with [x, x + reach], found by
  comparing every window with every position (no search, no sparse table);
* the largest force over an interval of speeds and a range of elevations: the model's
  force (profileopt.physics.forces.force_n, checked against hand calculations in
  test_constraints.py) on a dense grid of speeds x elevations;
* the peak of phi(r) = r^2 T(r) (T the force transmissibility of Eq. 13, Inman section
  2.4, written out by hand below): a dense numerical maximisation, against the root of the
  cubic of force_peak_ratio.
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
import pytest

from profileopt import InputError, load_vehicle
from profileopt.mpc.constraints import (
    ForceConstraints,
    add_force_constraints,
    force_constraints,
    force_n,
    force_peak_ratio,
    interval_force_constraints,
    step_speed_envelope,
    terrain_envelope,
)
from profileopt.io import read_route
from profileopt.terrain.roughness import roughness_windows

from conftest import ROUTES

ATV = load_vehicle("atv")
RESONANT = load_vehicle("atv-resonant")
Z = 4.753424308816257  # sqrt(2) erfinv(2 Pe - 1) for Pe = 0.999999 (docs/paper-notes.md, Eq. 8)
W = 5.0


def _trail_piece(start_m: float, stop_m: float) -> tuple[np.ndarray, np.ndarray]:
    route = read_route(ROUTES / "trail.csv")
    keep = (route.s_m >= start_m) & (route.s_m <= stop_m)
    return route.s_m[keep], route.z_m[keep]


def _kerb_route() -> tuple[np.ndarray, np.ndarray]:
    """Smooth ground sampled every 0.05 m with a 0.05 m kerb exactly at s = 50 m (a
    multiple of the window length: the case the old 5 m segments missed)."""
    s = np.arange(0.0, 100.0 + 1e-9, 0.05)
    rng = np.random.default_rng(7)
    z = 0.002 * rng.standard_normal(s.size) + 0.01 * s
    z[s >= 50.0 - 1e-9] += 0.05
    return s, z


def _requirement(x: np.ndarray, s: np.ndarray, z: np.ndarray, reach: float, vehicle) -> np.ndarray:
    """Brute force: the largest e_max of the windows sharing a point with [x', x' + reach],
    x' the position held within the route (the envelope holds the end values outside)."""
    win = roughness_windows(s, z, vehicle.ground_clearance_m, window_m=W)
    e = Z * vehicle.ground_clearance_m * win.ri
    xc = np.clip(x, s[0], s[-1])
    out = np.empty(x.size)
    tol = 1e-9
    for i in range(0, x.size, 400):
        block = xc[i:i + 400, None]
        meets = (win.start_m[None, :] <= block + reach + tol) & (win.stop_m[None, :] >= block - tol)
        assert np.all(meets.any(axis=1))
        out[i:i + 400] = np.max(np.where(meets, e[None, :], -np.inf), axis=1)
    return out


def _dense_positions(s: np.ndarray) -> np.ndarray:
    rng = np.random.default_rng(3)
    mid = 0.5 * (s[1:] + s[:-1])
    return np.concatenate([s, mid, rng.uniform(s[0] - 3.0, s[-1] + 3.0, 2000), [s[0] - 50.0, s[-1] + 50.0]])


def _evaluate(fn: ca.Function, x: np.ndarray) -> np.ndarray:
    return np.asarray(fn.map(x.size)(x[None, :])).ravel()


@pytest.mark.parametrize("reach", [0.0, 3.7])
@pytest.mark.parametrize("where", ["trail", "kerb"])
def test_envelope_is_never_below_any_window_it_must_cover(where: str, reach: float) -> None:
    s, z = _trail_piece(1000.0, 1100.0) if where == "trail" else _kerb_route()
    env = terrain_envelope(s, z, ATV, reach_m=reach)
    x = _dense_positions(s)
    value, need = _evaluate(env, x), _requirement(x, s, z, reach, ATV)
    assert np.all(value >= need), f"below by {np.max(need - value):.3g} m at s = {x[np.argmax(need - value)]:.3f} m"
    # ... and not far above: at most the largest e_max within 4 knot intervals (h = W / 20)
    h = W / 20
    wider = np.maximum(_requirement(x - 4 * h, s, z, reach + 8 * h, ATV), need)
    assert np.all(value <= wider * (1 + 1e-9) + 1e-15)
    # the kerb (e_max ~ 0.1 m) is seen from every position whose stage can reach it
    if where == "kerb":
        at = np.abs(x - (50.0 - W - reach + 0.01)) < 0.02
        assert np.all(value[at] > 0.02)


def test_envelope_works_on_sx_mx_dm_and_numbers() -> None:
    s, z = _trail_piece(1000.0, 1060.0)
    env = terrain_envelope(s, z, RESONANT, reach_m=2.0)
    assert env.name_in() == ["s_m"] and env.name_out() == ["e_max_m"]
    x = np.array([990.0, 1000.0, 1012.345, 1030.0, 1059.9, 1070.0])
    reference = _evaluate(env, x)
    xs, xm = ca.SX.sym("x"), ca.MX.sym("x")
    assert isinstance(env(xs), ca.SX) and isinstance(env(xm), ca.MX)
    for kind, sym in (("SX", xs), ("MX", xm)):
        fn = ca.Function("f", [sym], [env(sym)])
        np.testing.assert_array_equal(_evaluate(fn, x), reference, err_msg=kind)
    np.testing.assert_array_equal([float(env(ca.DM(v))) for v in x], reference)
    np.testing.assert_array_equal([float(env(v)) for v in x], reference)
    # expands to SX inside a bigger MX graph (what nlpsol's "expand" does)
    y = ca.MX.sym("y", 3)
    assert ca.Function("g", [y], [env.map(3)(y.T).T]).expand().is_a("SXFunction")


def test_envelope_is_twice_continuously_differentiable_with_finite_derivatives() -> None:
    s, z = _trail_piece(1200.0, 1260.0)
    env = terrain_envelope(s, z, ATV, reach_m=1.0)
    x = ca.SX.sym("x")
    value = env(x)
    grad, hess = ca.gradient(value, x), ca.hessian(value, x)[0]
    derivatives = ca.Function("d", [x], [value, grad, hess])
    h = W / 20
    knots = s[0] - 4 * h + h * np.arange(5, 240)  # interior knots (where the cubics meet)
    points = np.concatenate([knots, knots + 0.37 * h, s[::7]])
    v, d1, d2 = (np.asarray(o).ravel() for o in derivatives.map(points.size)(points[None, :]))
    assert np.all(np.isfinite(d1)) and np.all(np.isfinite(d2))
    # first derivative against central differences (the spline is a cubic: 1e-5 m steps)
    step = 1e-5
    fd = (_evaluate(env, points + step) - _evaluate(env, points - step)) / (2 * step)
    np.testing.assert_allclose(d1, fd, rtol=1e-6, atol=1e-9)
    # value, slope and curvature are continuous across every knot: left and right limits
    # 1e-7 m apart differ by O(1e-7) times the next derivative, not by a jump
    eps = 1e-7
    for k in range(3):
        left = np.asarray(derivatives.map(knots.size)((knots - eps)[None, :])[k]).ravel()
        right = np.asarray(derivatives.map(knots.size)((knots + eps)[None, :])[k]).ravel()
        scale = np.max(np.abs(v)) / h ** k
        assert np.max(np.abs(right - left)) <= 1e-4 * scale, f"derivative {k} jumps"
    # the curvature is not trivially zero: the test looked at a curved spline
    assert np.max(np.abs(d2)) > 1e-3 * np.max(v) / h**2


def test_envelope_holds_the_end_values_outside_the_route_and_nan_is_nan() -> None:
    s, z = _trail_piece(1000.0, 1050.0)
    env = terrain_envelope(s, z, ATV, reach_m=1.5)
    h = W / 20
    ends = _requirement(np.array([s[0], s[-1]]), s, z, 1.5, ATV)  # the requirement at each end
    before = [float(env(x)) for x in (s[0] - 1e4, s[0] - 10.0, s[0] - 3 * h)]
    after = [float(env(x)) for x in (s[-1] + 4 * h, s[-1] + 10.0, s[-1] + 1e4)]
    assert before == [before[0]] * 3 and after == [after[0]] * 3
    np.testing.assert_allclose([before[0], after[0]], ends, rtol=2e-12)
    for bad in (math.nan, math.inf, -math.inf):
        assert math.isnan(float(env(bad)))


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"reach_m": -1.0}, "reach_m"),
        ({"reach_m": math.nan}, "reach_m"),
        ({"knot_spacing_m": 0.0}, "knot_spacing_m"),
        ({"knot_spacing_m": 1e-5}, "knot intervals"),
        ({"window_m": -5.0}, "window_m"),
        ({"window_m": 0.2}, "samples"),
    ],
)
def test_envelope_bad_input_is_one_input_error(kwargs: dict, message: str) -> None:
    s, z = _trail_piece(1000.0, 1100.0)
    with pytest.raises(InputError, match=message):
        terrain_envelope(s, z, ATV, **kwargs)


def test_envelope_refuses_a_bad_route() -> None:
    with pytest.raises(InputError, match="increase strictly"):
        terrain_envelope([0.0, 1.0, 1.0, 2.0], [0.0] * 4, ATV)


# ---------------------------------------------------------------------- the force's peak

def _phi(r: np.ndarray, zeta: float) -> np.ndarray:
    """phi(r) = r^2 T(r), T the base-excitation force transmissibility (Inman 2.4)."""
    return r**2 * np.sqrt((1 + (2 * zeta * r) ** 2) / ((1 - r**2) ** 2 + (2 * zeta * r) ** 2))


@pytest.mark.parametrize("zeta", [0.05, 0.1, 0.2, 0.3, 0.35])
def test_force_peak_ratio_is_the_numerical_maximum_of_phi(zeta: float) -> None:
    r = np.linspace(0.5, 2.5, 2_000_001)
    phi = _phi(r, zeta)
    interior = np.flatnonzero((phi[1:-1] > phi[:-2]) & (phi[1:-1] >= phi[2:])) + 1
    assert interior.size == 1
    assert force_peak_ratio(zeta) == pytest.approx(r[interior[0]], abs=2e-6)


def test_force_peak_ratio_is_none_when_phi_only_grows() -> None:
    # at zeta = 1 / (2 sqrt 2) the cubic is (x - 2)^2 (x + 1) / 2: a double root, no peak
    assert force_peak_ratio(0.36) is None and force_peak_ratio(ATV.damping_ratio) is None
    r = np.linspace(1e-3, 50, 200_001)
    for zeta in (0.36, 0.5, 1.0):
        assert np.all(np.diff(_phi(r, zeta)) > 0)
    assert force_peak_ratio(0.35) is not None
    with pytest.raises(InputError, match="damping_ratio"):
        force_peak_ratio(0.0)


# ---------------------------------------------------------------------- interval rows

def _brute_worst(v0: float, v1: float, e_lo: float, e_hi: float, vehicle, model: str = "sbem_tf") -> float:
    """Largest F / F_limit - 1 over a dense grid of speeds between v0 and v1 and
    elevations in [e_lo, e_hi], the ends included."""
    speeds = np.linspace(min(v0, v1), max(v0, v1), 1201)
    elevations = np.unique(np.r_[np.linspace(e_lo, e_hi, 401), e_lo, e_hi])
    limit = vehicle.max_transmitted_force_n if model == "sbem_tf" else vehicle.max_excitation_force_n
    return float(np.max(force_n(speeds[:, None], vehicle, e_max_m=elevations[None, :], model=model))) / limit - 1


@pytest.mark.slow
@pytest.mark.parametrize("vehicle", [ATV, RESONANT], ids=["atv", "atv-resonant"])
@pytest.mark.parametrize("model", ["sbem_tf", "iecm", "sbem_ef"])
def test_interval_rows_bound_every_speed_and_elevation_below(vehicle, model: str) -> None:
    rng = np.random.default_rng(11)
    for trial in range(60):
        top = (0.6, 3.0, 20.0)[trial % 3]  # crawling (around the peaks), slow, any speed
        v0, v1 = rng.uniform(0, top, 2)
        e_hi = rng.uniform(0.0, 0.25)
        e_lo = rng.uniform(0, e_hi) if trial % 4 == 0 else 0.0
        cons = interval_force_constraints(v0, v1, e_hi, vehicle, model=model, e_min_m=e_lo)
        rows = np.asarray(cons.g).ravel()
        brute = _brute_worst(v0, v1, e_lo, e_hi, vehicle, model)
        assert rows.max() >= brute - 1e-12, (v0, v1, e_lo, e_hi)
        # exact at a single elevation: the rows' largest is the largest force over the speeds
        exact = np.asarray(interval_force_constraints(v0, v1, e_hi, vehicle, model=model, e_min_m=e_hi).g).max()
        speeds = np.linspace(min(v0, v1), max(v0, v1), 200_001)
        limit = vehicle.max_transmitted_force_n if model == "sbem_tf" else vehicle.max_excitation_force_n
        at_top = float(np.max(force_n(speeds, vehicle, e_max_m=e_hi, model=model))) / limit - 1
        assert at_top - 1e-12 <= exact <= at_top + 1e-8 * (1 + abs(at_top))


def test_interval_rows_see_the_resonance_peak_between_two_admissible_speeds() -> None:
    """atv-resonant on the washboard (RI 0.28): bands [0, 0.32] and [0.53, 3.4] m/s
    (examples/routes/washboard.csv). Both ends admissible, the forbidden band in between."""
    e = Z * 0.1 * 0.28
    ends = force_n(np.array([0.2, 1.0]), RESONANT, e_max_m=e) / 1000.0 - 1
    assert np.all(ends < 0)  # the pointwise check passes ...
    jump = np.asarray(interval_force_constraints(0.2, 1.0, e, RESONANT).g).ravel()
    assert jump.size == 3 and np.all(jump[:2] < 0) and jump[2] > 0.5  # ... the peak does not
    within = np.asarray(interval_force_constraints(0.6, 3.0, e, RESONANT).g).ravel()
    assert np.all(within <= 0)
    assert np.asarray(interval_force_constraints(0.6, 3.0, e, ATV).g).size == 2  # no peak for atv


def test_a_single_elevation_would_not_cover_the_windows_below_it() -> None:
    """Why e_min_m defaults to 0: at crawling speed a lower window gives more force."""
    speed, e_top = 0.3, 0.075
    e = np.linspace(0.0, e_top, 3001)
    forces = force_n(speed, RESONANT, e_max_m=e)
    worst = float(forces.max())
    assert worst > 1.3 * float(force_n(speed, RESONANT, e_max_m=e_top))
    # a vehicle whose limit lies between the two
    vehicle = RESONANT.replace(max_transmitted_force_n=0.5 * (worst + float(force_n(speed, RESONANT, e_max_m=e_top))))
    single = np.asarray(interval_force_constraints(speed, speed, e_top, vehicle, e_min_m=e_top).g)
    covering = np.asarray(interval_force_constraints(speed, speed, e_top, vehicle).g)
    assert single.max() < 0 < covering.max()  # e_max alone says admissible; the range does not


def _stages_on_the_route(vehicle, s, z, env, ds: float, rng) -> float:
    """Largest (brute force - rows) over random stages: must be <= 0."""
    win = roughness_windows(s, z, vehicle.ground_clearance_m, window_m=W)
    e = Z * vehicle.ground_clearance_m * win.ri
    worst = -np.inf
    for trial in range(150):
        s_k = rng.uniform(s[0] - 2, s[-1])
        top = (0.5, 2.0, 20.0)[trial % 3]
        v0, v1 = rng.uniform(0, top, 2)
        rows = np.asarray(interval_force_constraints(v0, v1, env(s_k), vehicle).g).ravel()
        lo, hi = np.clip(s_k, s[0], s[-1]), np.clip(s_k + ds, s[0], s[-1])
        met = (win.start_m <= hi) & (win.stop_m >= lo)
        speeds = np.linspace(min(v0, v1), max(v0, v1), 401)
        brute = np.max(force_n(speeds[:, None], vehicle, e_max_m=e[met][None, :])) / vehicle.max_transmitted_force_n - 1
        worst = max(worst, brute - rows.max())
    return worst


@pytest.mark.slow
@pytest.mark.parametrize("vehicle", [ATV, RESONANT], ids=["atv", "atv-resonant"])
def test_composition_a_stage_is_safe_under_the_envelope_and_the_rows(vehicle) -> None:
    """With env = terrain_envelope(..., reach_m=ds), the rows of (v_k, v_k1, env(s_k)) bound
    the force at every speed between v_k and v_k1 in every window of [s_k, s_k + ds]."""
    s, z = _trail_piece(1240.0, 1300.0)
    ds = 2.5
    env = terrain_envelope(s, z, vehicle, reach_m=ds)
    assert _stages_on_the_route(vehicle, s, z, env, ds, np.random.default_rng(5)) <= 1e-12


def test_interval_rows_in_nlpsol_opti_and_anything_with_subject_to() -> None:
    """Fastest exit speed from rest over one interval on e = 0.133 m (the washboard's e_max)
    for atv-resonant: at exactly e_max (e_min_m = e_max) it stops at the band edge where the
    force first reaches the limit, never jumping to the upper band; over every e in
    [0, e_max] (the default) lower, and every speed up to it is admissible at every e."""
    e = Z * 0.1 * 0.28
    v = ca.SX.sym("v")
    ipopt = {"ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes", "ipopt.tol": 1e-10}
    g, lbg, ubg = interval_force_constraints(0.0, v, e, RESONANT, e_min_m=e)
    solver = ca.nlpsol("s", "ipopt", {"x": v, "f": -v, "g": g}, ipopt)
    top = float(solver(x0=0.1, lbx=0, ubx=3.0, lbg=lbg, ubg=ubg)["x"])
    speeds = np.linspace(0.0, 0.6, 60001)
    admissible = force_n(speeds, RESONANT, e_max_m=e) <= 1000.0
    first_edge = speeds[np.argmin(admissible)]  # the first inadmissible speed on the grid
    assert top == pytest.approx(first_edge, abs=2e-5)
    g, lbg, ubg = interval_force_constraints(0.0, v, e, RESONANT)
    solver = ca.nlpsol("s", "ipopt", {"x": v, "f": -v, "g": g}, ipopt)
    covering = float(solver(x0=0.1, lbx=0, ubx=3.0, lbg=lbg, ubg=ubg)["x"])
    assert 0.5 * top < covering < top
    assert _brute_worst(0.0, covering, 0.0, e, RESONANT) <= 1e-8
    opti = ca.Opti()
    x = opti.variable(2)
    cons = interval_force_constraints(x[0], x[1], e, RESONANT, e_min_m=e)
    assert isinstance(cons, ForceConstraints) and cons.n_force == 3 and cons[0] is cons.g
    opti.subject_to(cons.g <= cons.ubg)
    opti.subject_to([x[0] == 0, opti.bounded(0, x[1], 3.0)])
    opti.minimize(-x[1])
    opti.solver("ipopt", {"print_time": False}, {"print_level": 0, "sb": "yes", "tol": 1e-10})
    opti.set_initial(x, 0.1)
    assert opti.solve().value(x[1]) == pytest.approx(top, abs=1e-6)


def test_interval_rows_are_ordered_interval_by_interval_and_broadcast() -> None:
    v0, v1, e = np.array([0.1, 2.0, 5.0]), np.array([1.0, 0.5, 6.0]), np.array([0.05, 0.1, 0.15])
    g = np.asarray(interval_force_constraints(v0, v1, e, RESONANT).g).ravel()
    for i in range(3):
        single = np.asarray(interval_force_constraints(v0[i], v1[i], e[i], RESONANT).g).ravel()
        np.testing.assert_array_equal(g[3 * i:3 * i + 3], single)
    scalar = np.asarray(interval_force_constraints(v0, v1, 0.1, RESONANT).g).ravel()
    np.testing.assert_array_equal(scalar[3:6], g[3:6])
    sym = ca.MX.sym("v", 3)
    assert interval_force_constraints(sym, v1, e, RESONANT).g.shape == (9, 1)


def test_symbolic_negative_or_nan_elevation_is_never_admissible() -> None:
    e = ca.SX.sym("e")
    fn = ca.Function("g", [e], [interval_force_constraints(1.0, 2.0, e, RESONANT).g])
    for bad in (-0.01, math.nan):
        assert np.all(np.isnan(np.asarray(fn(bad))))
    assert np.all(np.asarray(fn(0.0)) == -1.0)  # smooth ground: no force


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda: interval_force_constraints(1.0, 2.0, -0.1, ATV), "e_max_m"),
        (lambda: interval_force_constraints(1.0, 2.0, math.nan, ATV), "e_max_m"),
        (lambda: interval_force_constraints(1.0, 2.0, 0.1, ATV, e_min_m=0.2), "must not exceed"),
        (lambda: interval_force_constraints(-1.0, 2.0, 0.1, ATV), ">= 0"),
        (lambda: interval_force_constraints([1.0, 2.0], [1.0], 0.1, ATV), "exit speeds"),
        (lambda: interval_force_constraints([1.0, 2.0], [1.0, 3.0], [0.1] * 3, ATV), "3 values for 2"),
        (lambda: interval_force_constraints(1.0, 2.0, 0.1, ATV, model="prev_bem"), "roughness index only"),
        (lambda: interval_force_constraints(1.0, 2.0, 0.1, ATV, model="sbem"), "unknown"),
    ],
)
def test_interval_rows_bad_input_is_one_input_error(call, message: str) -> None:
    with pytest.raises(InputError, match=message):
        call()


def test_add_force_constraints_takes_a_rockit_like_problem() -> None:
    """Anything with subject_to: here a stand-in with rockit's signature (expression first,
    keyword options after), which records the constraints it is given."""

    class Problem:
        def __init__(self) -> None:
            self.got: list = []

        def subject_to(self, constr, grid=None, include_first=True, include_last=True):
            self.got.append(constr)

    problem = Problem()
    add_force_constraints(problem, ca.MX.sym("v", 4), ATV, e_max_m=np.full(3, 0.05))
    assert len(problem.got) == 1 and problem.got[0].shape == (6, 1)


@pytest.mark.parametrize("e_min", [0.0, "symbol"])
def test_interval_rows_have_finite_derivatives_at_rest_and_on_smooth_ground(e_min) -> None:
    """The step width sqrt(e (2 r - e)) has an infinite slope at e = 0; no derivative of the
    rows may be NaN there (IPOPT stops at the first NaN), in SX and through MX calls."""
    for kind in (ca.SX, ca.MX):
        x = kind.sym("x", 3)
        low = x[2] if e_min == "symbol" else e_min
        g = interval_force_constraints(x[0], x[1], 0.05, RESONANT, e_min_m=low).g
        jac = ca.Function("j", [x], [ca.jacobian(g, x), ca.hessian(ca.sum1(g), x)[0]])
        for point in ([0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.3, 0.3, 0.0], [2.0, 1.0, 0.01]):
            for out in jac(point):
                assert np.all(np.isfinite(np.asarray(out))), (kind.__name__, point)
    # the 1e-12 m floor changes no row by more than a rounding error at driving speeds
    a = np.asarray(interval_force_constraints(0.5, 2.0, 0.05, RESONANT).g)
    b = np.asarray(interval_force_constraints(0.5, 2.0, 0.05, RESONANT, e_min_m=1e-12).g)
    np.testing.assert_array_equal(a, b)


# --- the mistakes made on the way (issue 31): one line each, saying what to give -----------


def _errors_of(call) -> str:
    from profileopt.errors import InputError

    with pytest.raises(InputError) as info:
        call()
    return str(info.value)


def test_a_vehicle_name_where_a_vehicle_goes_says_how_to_load_it():
    s, z = _kerb_route()
    assert "profileopt.load_vehicle('atv')" in _errors_of(lambda: terrain_envelope(s, z, "atv"))
    assert "profileopt.load_vehicle('atv')" in _errors_of(lambda: step_speed_envelope(s, z, "atv"))


def test_swapped_arguments_are_named():
    assert "swapped" in _errors_of(lambda: interval_force_constraints(1.0, 2.0, ATV, 0.05))
    assert "is a Vehicle" in _errors_of(lambda: force_constraints(1.0, 0.05, e_max_m=ATV))
    s, z = _kerb_route()
    assert "swapped" in _errors_of(lambda: step_speed_envelope(s, z, 3.0))


def test_a_route_where_its_arrays_go_says_which_arrays():
    from profileopt.core.route import Route

    s, z = _kerb_route()
    route = Route(s_m=s, z_m=z, source="kerb")
    assert "route.s_m, route.z_m" in _errors_of(lambda: terrain_envelope(route, ATV))
    assert "route.s_m, route.z_m" in _errors_of(lambda: step_speed_envelope(route, ATV))


def test_sx_speeds_with_an_mx_elevation_are_one_line():
    message = _errors_of(lambda: interval_force_constraints(ca.SX.sym("v0"), ca.SX.sym("v1"), ca.MX.sym("e"), ATV))
    assert "mix SX and MX" in message


def test_positions_in_km_are_caught():
    s, z = _kerb_route()
    assert "positions in km?" in _errors_of(lambda: terrain_envelope(s / 1000.0, z, ATV))


def test_speed_backoff_covers_speeds_just_outside_the_interval(atv_resonant) -> None:
    # Issue 31's back-off: just below the first band's edge the rows hold; with a tracking
    # error reaching over the edge they must not (the edge from the band search, independent
    # of the rows).
    from profileopt.physics.speeds import speed_bands
    from profileopt.terrain.roughness import worst_case_elevation

    ri = 0.3
    edge = float(speed_bands([ri], atv_resonant).first()[0])
    e = float(worst_case_elevation(ri, atv_resonant))
    v = np.array([0.97 * edge])
    g0 = np.asarray(interval_force_constraints(v, v, e, atv_resonant, e_min_m=e).g)
    g1 = np.asarray(interval_force_constraints(v, v, e, atv_resonant, e_min_m=e, speed_backoff_mps=0.05 * edge).g)
    assert g0.max() <= 0 < g1.max()
    with pytest.raises(InputError, match="speed_backoff_mps"):
        interval_force_constraints(v, v, e, atv_resonant, speed_backoff_mps=-0.1)


def test_reach_rows_bound_each_stage(atv) -> None:
    from profileopt.mpc.horizon import reach_constraints

    g, lbg, ubg = reach_constraints([0.0, 1.5, 4.0, 4.0], 2.0)
    np.testing.assert_allclose(np.asarray(g).ravel(), [1.5, 2.5, 0.0])
    assert list(lbg) == [0, 0, 0] and list(ubg) == [2.0, 2.0, 2.0]
    s = ca.SX.sym("s", 4)
    assert reach_constraints(s, 3.0).g.shape == (3, 1)
    for bad in (0.0, -1.0, math.nan):
        with pytest.raises(InputError, match="reach_m"):
            reach_constraints([0.0, 1.0], bad)
    with pytest.raises(InputError, match="at least 2"):
        reach_constraints([0.0], 1.0)


# ------------------------------------------------ the reach row, checked after a solve (issue 31)


def test_a_stage_longer_than_the_reach_is_refused_in_one_line_naming_it() -> None:
    from profileopt.mpc.horizon import check_stage_lengths

    # Hand-made horizon: the stage lengths are the differences 1.5, 2.5, 0, 3.0 m; with a
    # 2 m reach stages 1 and 3 are too long and stage 1 (from 1.5 to 4 m, 2.5 m) is the first.
    with pytest.raises(InputError) as caught:
        check_stage_lengths([0.0, 1.5, 4.0, 4.0, 7.0], 2.0)
    message = str(caught.value)
    assert "\n" not in message
    assert "stage 1 (from 1.5 to 4 m) is 2.5 m long" in message and "reach 2 m" in message
    assert "2 of 4 stages" in message and "reach_constraints(s, 2)" in message
    # as a column (sol.value of an Opti column) and as a DM alike
    with pytest.raises(InputError, match="stage 1 "):
        check_stage_lengths(ca.DM([0.0, 1.5, 4.0]), 2.0)
    with pytest.raises(InputError, match="stage 1 "):
        check_stage_lengths(np.array([[0.0], [1.5], [4.0]]), 2.0)


def test_stages_within_the_reach_pass_and_give_their_lengths() -> None:
    from profileopt.mpc.horizon import STAGE_LENGTH_TOLERANCE_M, check_stage_lengths

    # lengths 2.0 (the reach exactly), 0.5, 0 (standing still): all inside [0, 2]
    np.testing.assert_allclose(check_stage_lengths([10.0, 12.0, 12.5, 12.5], 2.0), [2.0, 0.5, 0.0])
    # the solver's tolerance: 1e-7 m over the reach passes, twice the tolerance does not
    check_stage_lengths([0.0, 2.0 + 1e-7], 2.0)
    with pytest.raises(InputError, match="longer than"):
        check_stage_lengths([0.0, 2.0 + 2 * STAGE_LENGTH_TOLERANCE_M], 2.0)
    with pytest.raises(InputError, match="longer than"):
        check_stage_lengths([0.0, 2.0 + 1e-7], 2.0, tolerance_m=0.0)


@pytest.mark.parametrize("positions, kwargs, words", [
    ([0.0, 1.0, 0.4], {}, "stage 1 (from 1 to 0.4 m) runs backwards (-0.6 m)"),
    ([0.0, 1.0, math.nan], {}, "stage 1 (from 1 to nan m) has a position that is not a finite number"),
    ([0.0, 1.0, 2.0, 3.0], {"horizon_m": (0.0, 1.5)}, "stage 2 (from 2 to 3 m) starts outside the envelopes' horizon"),
    ([0.0], {}, "at least 2 stages"),
    (np.zeros((2, 5)), {}, "shape (2, 5)"),
    (ca.SX.sym("s", 3), {}, "give the solved values"),
    ([0.0, 1.0], {"tolerance_m": -1.0}, "must be >= 0"),
])
def test_what_else_the_stage_check_refuses_is_one_line(positions, kwargs, words) -> None:
    from profileopt.mpc.horizon import check_stage_lengths

    with pytest.raises(InputError) as caught:
        check_stage_lengths(positions, 2.0, **kwargs)
    assert words in str(caught.value) and "\n" not in str(caught.value)


def _free_time_problem(n: int, distance_m: float, reach_m: float, *, with_reach_rows: bool):
    """Issue 31's failure mode, in a minimum-time casadi.Opti problem with free time steps:
    from rest at 0 to ``distance_m`` in ``n`` intervals, the force rows of every interval on
    terrain_envelope(reach_m) of the kerb route, with or without the reach rows."""
    from profileopt.mpc.horizon import reach_constraints

    s_route, z_route = _kerb_route()
    env = terrain_envelope(s_route, z_route, ATV, reach_m=reach_m)
    opti = ca.Opti()
    s, v, a, dt = opti.variable(n + 1), opti.variable(n + 1), opti.variable(n), opti.variable(n)
    opti.subject_to([s[1:] == s[:-1] + v[:-1] * dt + a * dt**2 / 2, v[1:] == v[:-1] + a * dt])
    opti.subject_to([s[0] == 0.0, v[0] == 0.0, s[-1] == distance_m, opti.bounded(0.0, v, ATV.max_speed_mps),
                     opti.bounded(-ATV.max_decel_mps2, a, ATV.max_accel_mps2), opti.bounded(0.01, dt, 20.0)])
    opti.subject_to(interval_force_constraints(v[:-1], v[1:], env.map(n)(s[:-1].T).T, ATV).g <= -1e-6)
    if with_reach_rows:
        g, lbg, ubg = reach_constraints(s, reach_m)
        opti.subject_to(opti.bounded(lbg, g, ubg))
    opti.minimize(ca.sum1(dt))
    opti.set_initial(s, np.linspace(0.0, distance_m, n + 1))
    opti.set_initial(v, 3.0)
    opti.set_initial(dt, distance_m / n / 3.0)
    opti.solver("ipopt", {"print_time": False, "expand": True}, {"print_level": 0, "sb": "yes", "max_iter": 500})
    sol = opti.solve()
    return sol.value(s)


def test_a_free_time_problem_without_the_reach_rows_is_caught_by_the_check() -> None:
    """Without the rows IPOPT reports success, yet the 6 stages sum to 60 m, so at least one
    is 10 m long (pigeonhole), five times the 2 m reach the envelope covers: the check
    refuses it, naming the first such stage of the solution. With the rows (40 stages of at
    most 2 m) the same problem passes."""
    from profileopt.mpc.horizon import check_stage_lengths

    s = _free_time_problem(6, 60.0, 2.0, with_reach_rows=False)  # solve() raises unless IPOPT succeeded
    lengths = np.diff(s)
    assert lengths.max() >= 60.0 / 6 - 1e-6
    first = int(np.argmax(lengths > 2.0 + 1e-6))
    with pytest.raises(InputError) as caught:
        check_stage_lengths(s, 2.0)
    assert f"stage {first} (from {s[first]:.6g} to {s[first + 1]:.6g} m) is {lengths[first]:.6g} m long" in str(
        caught.value)
    s = _free_time_problem(40, 60.0, 2.0, with_reach_rows=True)
    assert check_stage_lengths(s, 2.0).max() <= 2.0 + 1e-6
