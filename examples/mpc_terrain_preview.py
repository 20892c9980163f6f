"""Terrain-preview MPC: a receding-horizon speed controller that keeps the SBEM:TF force
within its limit against the terrain ahead, beside the offline minimum-time plan.

Run:  python examples/mpc_terrain_preview.py [--route ROUTE.csv] [--vehicle atv]
                                              [--cruise 12] [--from-m 0] [--until-m 2000]
                                              [--sensor-range 60] [--unseen worst] [--out mpc_out]

A longitudinal vehicle (states: position s and speed v; input: acceleration a) drives a
bundled route in closed loop, seeing its terrain only within ``--sensor-range`` metres ahead.
Every 0.25 s it solves a 4 s horizon with IPOPT through one ``casadi.Opti`` built once (the
current state, the terrain ahead and where the measured terrain ends are parameters; each
solve is warm-started from the previous one shifted by a step): track a cruise speed, respect
the acceleration bounds, and keep the model's force within its limit against the terrain the
vehicle will reach. ``profileopt.mpc.preview.TerrainPreview`` gives the terrain as parameters
of a fixed-size expression, set each step from what is measured: the largest e_max of every
roughness window an interval starting at the predicted position s can reach (the ``unseen``
class's beyond the measured terrain) and the speed cap of steps and speed limits;
``interval_force_constraints`` keeps every speed between an interval's two speeds admissible
at that e_max, the resonance peak between them included; and a terminal row keeps the last
stage able to brake to the unseen terrain's speed by the end of the measured terrain, so the
next step has a plan too. Each solved plan is checked before it is applied
(``preview.check_stages``: every stage forward, at most the envelopes' reach long and inside
the horizon; here the speed bounds imply it, and a plan that failed it would be treated as a
failed solve). The closed-loop speed is plotted beside the offline plan of
``profileopt.plan``, and the closed loop is checked independently of the controller, window
by window (examples/mpc_window_check.py).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import casadi as ca
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from profileopt import get_model, load_vehicle  # noqa: E402
from profileopt.errors import InputError  # noqa: E402
from profileopt.io import atomic_path, read_route  # noqa: E402
from profileopt.mpc.constraints import force_limit_n, interval_force_constraints  # noqa: E402
from profileopt.mpc.preview import TerrainPreview  # noqa: E402
from profileopt.online import unseen_speed_mps  # noqa: E402
from profileopt.planning import plan  # noqa: E402

from mpc_window_check import report, worst_window  # noqa: E402  (beside this file)

HERE = Path(__file__).resolve().parent
parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
parser.add_argument("--route", default=str(HERE / "routes" / "trail.csv"), help="route CSV (s,z) (default: %(default)s)")
parser.add_argument("--vehicle", default="atv", help="bundled vehicle name or .toml file (default: %(default)s)")
parser.add_argument("--model", default="sbem_tf", choices=["iecm", "sbem_ef", "sbem_tf"],
                    help="force model (default: %(default)s)")
parser.add_argument("--cruise", type=float, default=12.0, help="desired cruise speed in m/s (default: %(default)s)")
parser.add_argument("--from-m", type=float, default=0.0, help="start (from rest) this far along the route, m (default: %(default)s)")
parser.add_argument("--until-m", type=float, default=None, help="stop after driving this distance, m (default: to the end of the route)")
parser.add_argument("--sensor-range", type=float, default=60.0,
                    help="the terrain is known this far ahead of the vehicle, m (default: %(default)s)")
parser.add_argument("--unseen", default="worst",
                    help="terrain beyond it assumed: worst (ISO 8608 class H), a class A-H or an RI (default: %(default)s)")
parser.add_argument("--out", default="mpc_out", help="folder for the plot (default: %(default)s)")
args = parser.parse_args()

route = read_route(args.route)
vehicle = load_vehicle(args.vehicle)
model = args.model
limit_n = force_limit_n(vehicle, model=model)
label = get_model(model).label
v_max = vehicle.max_speed_mps
s_start = float(route.s_m[0]) + args.from_m
s_stop = float(route.s_m[-1]) if args.until_m is None else min(s_start + args.until_m, float(route.s_m[-1]))

# --- Controller settings ------------------------------------------------------------------
DT, N = 0.25, 16  # control interval (s) and horizon (stages): 4 s of preview
REACH = v_max * DT  # the furthest the vehicle can travel in one interval (m)
WINDOW = 5.0  # roughness window length (m)
BACK_OFF = 1e-6  # force rows held 1e-6 below 0: IPOPT meets constraints to about 1e-8

# --- Why the force constraint below is safe -------------------------------------------------
# Over interval k the vehicle moves from s_k to s_{k+1} <= s_k + REACH with constant
# acceleration, so its speed passes through every value between v_k and v_{k+1}, inside
# every roughness window that overlaps [s_k, s_k + REACH]. e_ahead(s_k) is never below the
# e_max of any of those windows (TerrainPreview with reach_m=REACH: measured windows, and the
# unseen class's e_max past the measured terrain), and interval_force_constraints(v_k,
# v_{k+1}, e_ahead(s_k)) holds every speed between v_k and v_{k+1} at every elevation up to
# it, the force peak near resonance included: so a lightly damped suspension (atv-resonant)
# cannot jump over a forbidden band of speeds between two stages. The proof is in the
# docstring of interval_force_constraints. e_ahead is a C2 cubic B-spline of s (IPOPT cycles
# at the kinks of a piecewise-linear table) whose coefficients are parameters: the problem is
# built once, whatever the route's length, and each step sets them.
HORIZON_M = (N + 1) * REACH + WINDOW  # the farthest a last stage's windows can lie ahead (m)
preview = TerrainPreview(vehicle, horizon_m=HORIZON_M, reach_m=REACH, window_m=WINDOW, unseen=args.unseen)
v_unseen = unseen_speed_mps(args.unseen, vehicle, model=model, roughness_window_m=WINDOW)


def build_controller() -> dict:
    """The optimal-control problem, built once: the current state, the last acceleration, the
    preview's coefficients and the end of the measured terrain are parameters."""
    opti = ca.Opti()
    X = opti.variable(2, N + 1)  # rows: position s (m), speed v (m/s)
    U = opti.variable(1, N)  # acceleration a (m/s^2), constant over each interval
    x_now = opti.parameter(2)
    a_before = opti.parameter()  # the acceleration applied last, for the smoothness term
    origin = opti.parameter()  # where the preview's horizon starts (m): the vehicle's position
    e_coef = opti.parameter(preview.n_coefficients)
    cap_coef = opti.parameter(preview.n_coefficients)
    measured_to = opti.parameter()  # the end of the measured terrain (m)
    s, v, a = X[0, :].T, X[1, :].T, U.T
    opti.subject_to(X[:, 0] == x_now)
    opti.subject_to(s[1:] == s[:-1] + v[:-1] * DT + a * DT**2 / 2)  # exact for constant a
    opti.subject_to(v[1:] == v[:-1] + a * DT)
    opti.subject_to(opti.bounded(0, v[1:], v_max))
    # 1e-7 inside the actuator's bounds: IPOPT meets bounds only to ~1e-8, and a plan braking
    # 1e-8 harder than the actuator can leave the next step's problem infeasible (the state
    # driven is then not the one planned)
    opti.subject_to(opti.bounded(-vehicle.max_decel_mps2 * (1 - 1e-7), a, vehicle.max_accel_mps2 * (1 - 1e-7)))
    terrain_k = preview.e_max.map(N)(s[:-1].T, origin, e_coef).T  # the largest e_max each interval can meet (m)
    rows = interval_force_constraints(v[:-1], v[1:], terrain_k, vehicle, model=model)
    opti.subject_to(rows.g <= -BACK_OFF)  # every speed of every interval
    cap_k = preview.speed_cap.map(N)(s[:-1].T, origin, cap_coef).T  # steps and speed limits
    opti.subject_to(v[:-1] <= cap_k)
    opti.subject_to(v[1:] <= cap_k)
    # the last stage can still brake to the unseen terrain's speed where the measured one ends
    room = ca.fmax(measured_to - s[-1], 0)
    opti.subject_to(v[-1] ** 2 <= v_unseen**2 + 2 * vehicle.max_decel_mps2 * (1 - 1e-7) * room)
    jerk = ca.diff(ca.vertcat(a_before, a))
    opti.minimize(ca.sumsqr(v[1:] - args.cruise) + 0.1 * ca.sumsqr(a) + 1.0 * ca.sumsqr(jerk))
    opti.solver("ipopt", {"print_time": False, "expand": True},
                {"print_level": 0, "sb": "yes", "tol": 1e-8, "max_iter": 200})
    return {"opti": opti, "X": X, "U": U, "x_now": x_now, "a_before": a_before, "origin": origin,
            "e_coef": e_coef, "cap_coef": cap_coef, "measured_to": measured_to}


def sensed(position_m: float) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """The route's samples the vehicle knows at ``position_m``: a window behind it and the
    sensing range ahead (and the map's speed limits there, if the route has them)."""
    keep = (route.s_m >= position_m - 2 * WINDOW) & (route.s_m <= position_m + args.sensor_range)
    limits = None if route.speed_limit_mps is None else route.speed_limit_mps[keep]
    return route.s_m[keep], route.z_m[keep], limits


# --- Closed loop ------------------------------------------------------------------------------
state = np.array([s_start, 0.0])  # from rest at the start of the route
a_last = 0.0
X_guess = np.vstack([s_start + np.arange(N + 1) * 0.0, np.zeros(N + 1)])
U_guess = np.zeros((1, N))
log = {"t": [0.0], "s": [state[0]], "v": [state[1]], "a": []}
solve_times, failures, refused = [], 0, 0
t_loop = time.perf_counter()
ctrl = build_controller()
while state[0] < s_stop and len(solve_times) < 20000:
    opti, X, U = ctrl["opti"], ctrl["X"], ctrl["U"]
    s_seen, z_seen, limits_seen = sensed(state[0])
    coef = preview.coefficients(s_seen, z_seen, state[0], speed_limit_mps=limits_seen)
    opti.set_value(ctrl["x_now"], state)
    opti.set_value(ctrl["a_before"], a_last)
    opti.set_value(ctrl["origin"], coef.origin_m)
    opti.set_value(ctrl["e_coef"], coef.e_max)
    opti.set_value(ctrl["cap_coef"], coef.speed_cap)
    opti.set_value(ctrl["measured_to"], coef.measured_to_m)
    opti.set_initial(X, X_guess)
    opti.set_initial(U, U_guess)
    t0 = time.perf_counter()
    try:
        sol = opti.solve()
        X_opt, U_opt = sol.value(X), np.atleast_2d(sol.value(U))
        # the envelopes bound a stage only if it is at most REACH long and starts inside the
        # horizon: check the solved positions before applying the plan (raises InputError)
        preview.check_stages(X_opt[0], origin_m=coef.origin_m)
    except (RuntimeError, InputError) as exc:
        refused_now = isinstance(exc, InputError)
        why = str(exc) if refused_now else f"IPOPT {opti.stats()['return_status']}"
        print(f"t = {log['t'][-1]:.2f} s: {why}; driving the last plan's tail", file=sys.stderr)
        # Infeasible, not converged or refused: drive the tail of the last plan (it kept
        # every limit for the remaining stages) and brake at the end of it.
        refused += refused_now
        failures += not refused_now
        U_opt = np.hstack([U_guess[:, :-1], [[-vehicle.max_decel_mps2]]])
        X_opt = X_guess
    solve_times.append(time.perf_counter() - t0)
    # the actuator saturates at the bounds (IPOPT meets them to ~1e-8); never reverse
    acc = float(np.clip(U_opt[0, 0], -vehicle.max_decel_mps2, vehicle.max_accel_mps2))
    acc = max(acc, -state[1] / DT)
    state = np.array([state[0] + state[1] * DT + acc * DT**2 / 2, state[1] + acc * DT])
    a_last = acc
    # warm start: the plan shifted by one interval, its last stage repeated
    X_guess = np.hstack([X_opt[:, 1:], X_opt[:, -1:] + np.array([[X_opt[1, -1] * DT], [0.0]])])
    U_guess = np.hstack([U_opt[:, 1:], U_opt[:, -1:]])
    for key, value in (("t", log["t"][-1] + DT), ("s", state[0]), ("v", state[1]), ("a", acc)):
        log[key].append(value)
t_loop = time.perf_counter() - t_loop
# the independent check: every roughness window, every speed driven inside it
check = worst_window(route.s_m, route.z_m, vehicle, log["t"], log["s"], log["v"], log["a"], model=model,
                     window_m=WINDOW)

# --- The offline plan for the same route ----------------------------------------------------
t_plan = time.perf_counter()
profile = plan(route, vehicle, model=model)
t_plan = time.perf_counter() - t_plan

steps = len(solve_times)
ms = 1e3 * np.array(solve_times)
print(f"route {Path(args.route).name} ({s_stop - s_start:g} m driven), vehicle {Path(vehicle.name).stem}, "
      f"model {model}; horizon {N} x {DT:g} s, cruise {args.cruise:g} m/s")
print(f"closed loop: {log['t'][-1]:.1f} s of driving in {steps} MPC steps, the terrain known {args.sensor_range:g} m "
      f"ahead ({preview.n_coefficients} preview coefficients per step); IPOPT failures: {failures}; plans refused "
      f"by the stage check: {refused}")
print(f"solve time per step: mean {ms.mean():.1f} ms, median {np.median(ms):.1f} ms, max {ms.max():.1f} ms; "
      f"first solve {ms[0]:.0f} ms (CasADi builds the solver once); closed loop {t_loop:.1f} s")
print(f"offline plan ({profile.status}): {profile.travel_time_s:.1f} s for the whole route, planned in {t_plan:.2f} s")
print(report(check, label, limit_n, WINDOW))

# --- Plot ----------------------------------------------------------------------------------
out = Path(args.out)
out.mkdir(parents=True, exist_ok=True)
fig, (ax_v, ax_r) = plt.subplots(2, 1, sharex=True, figsize=(11, 6))
ax_v.plot(profile.s_m, profile.speed_mps, color="0.45", lw=1.5, zorder=2, label="offline plan (minimum time)")
ax_v.plot(log["s"], log["v"], color="C0", label=f"closed-loop MPC (cruise {args.cruise:g} m/s)")
ax_v.set_ylabel("speed (m/s)")
ax_v.set_ylim(0, v_max * 1.05)
ax_v.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)  # outside: it hid data
ax_r.plot(profile.s_m, profile.force_n / profile.force_limit_n, color="0.6", label="offline plan, per segment")
ax_r.plot(check.start_m + WINDOW / 2, check.ratio, color="C0", label="MPC: largest F / F_limit per window\n"
          "(at the window's middle)")
ax_r.axhline(1.0, color="C3", lw=0.8, label="limit")
ax_r.set_ylabel("force / limit (-)")
ax_r.set_xlabel("distance along the route s (m)")
ax_r.set_xlim(s_start, s_stop)
ax_r.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)
fig.suptitle(f"{Path(args.route).name}, {Path(args.vehicle).stem}, {label}: closed-loop MPC seeing "
             f"{args.sensor_range:g} m ahead against the offline plan, {s_start:g}-{s_stop:g} m", fontsize=11)
fig.tight_layout()
csv = out / "mpc_closed_loop.csv"  # one row per control step: the state, then the input applied
with atomic_path(csv) as tmp:
    table = np.column_stack([log["t"][:-1], log["s"][:-1], log["v"][:-1], log["a"]])
    np.savetxt(tmp, table, delimiter=",", fmt="%.17g", comments="", header="time_s,s_m,speed_mps,accel_mps2")
print(csv)
png = out / "mpc_terrain_preview.png"
with atomic_path(png) as tmp:
    fig.savefig(tmp, format="png", dpi=120)
print(png)
sys.exit(0 if check.over == 0 and refused == 0 else 1)
