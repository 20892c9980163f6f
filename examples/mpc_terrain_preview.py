"""Terrain-preview MPC: a receding-horizon speed controller that keeps the SBEM:TF force
within its limit against the terrain ahead, beside the offline minimum-time plan.

Run:  python examples/mpc_terrain_preview.py [--route ROUTE.csv] [--vehicle atv]
                                              [--cruise 12] [--from-m 0] [--until-m 2000]
                                              [--out mpc_out]

A longitudinal vehicle (states: position s and speed v; input: acceleration a) drives a
bundled route in closed loop. Every 0.25 s it solves a 4 s horizon with IPOPT through one
``casadi.Opti`` built once (the current state is a parameter; each solve is warm-started
from the previous one shifted by a step): track a cruise speed, respect the acceleration
bounds, and keep the model's force within its limit against the terrain the vehicle will
reach, e_max(s) being a CasADi interpolant of the predicted position. The closed-loop
speed is plotted beside the offline plan of ``profileopt.plan`` and the worst force ratio
met along the way is checked independently of the controller, segment by segment.
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
from profileopt.io import atomic_path, read_route  # noqa: E402
from profileopt.constraints import add_force_constraints, force_limit_n, force_n, speed_bands  # noqa: E402
from profileopt.planning import PlanContext, SpeedLimit, plan, segment_route  # noqa: E402
from profileopt.stations import segment_index  # noqa: E402

HERE = Path(__file__).resolve().parent
parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
parser.add_argument("--route", default=str(HERE / "routes" / "trail.csv"), help="route CSV (s,z) (default: %(default)s)")
parser.add_argument("--vehicle", default="atv", help="bundled vehicle name or .toml file (default: %(default)s)")
parser.add_argument("--model", default="sbem_tf", choices=["iecm", "sbem_ef", "sbem_tf"],
                    help="force model (default: %(default)s)")
parser.add_argument("--cruise", type=float, default=12.0, help="desired cruise speed in m/s (default: %(default)s)")
parser.add_argument("--from-m", type=float, default=0.0, help="start (from rest) this far along the route, m (default: %(default)s)")
parser.add_argument("--until-m", type=float, default=None, help="stop after driving this distance, m (default: to the end of the route)")
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

# --- Terrain: the planner's own 5 m segments, each with its worst-case elevation (Eq. 8) ---
seg = segment_route(route, vehicle, segment_length_m=5.0)
bounds_m, e_seg = seg.boundaries_m, seg.e_max_m
# the planner's speed cap of each segment: top speed and the route's speed_limit column
cap_seg = SpeedLimit(max_speed_mps=v_max).speed_cap_mps(PlanContext(route=route, vehicle=vehicle, segments=seg))

# --- Controller settings ------------------------------------------------------------------
DT, N = 0.25, 16  # control interval (s) and horizon (stages): 4 s of preview
REACH = v_max * DT  # the furthest the vehicle can travel in one interval (m)

# --- Why the force constraint below is safe, and when it is not enough --------------------
# Over interval k the vehicle moves from s_k to s_{k+1} <= s_k + REACH with constant
# acceleration, so its speed passes through every value between v_k and v_{k+1}, over
# every terrain patch in [s_k, s_k + REACH]. The controller therefore holds both v_k and
# v_{k+1} against e_ahead(s_k), the LARGEST e_max of the segments in [s_k, s_k + REACH]
# (the 'segments' layout of profileopt.constraints.force_constraints). That covers the
# whole interval if the force grows with speed and with e_max (then the largest force over
# the interval is at an end and on the roughest patch): checked just below for this
# vehicle. For a lightly damped suspension (SBEM:TF of atv-resonant) the force is not
# monotone: admissible speeds form bands and a speed between two stages can be forbidden.
# Then the controller also bounds v_k and v_{k+1} by the 'first' band edge of every
# segment within reach (every speed from 0 to it is admissible, so any speed path below it
# is safe): band_edges/allowable_speed(..., band="first"), the docstring of
# profileopt.constraints ("Resonance and controllers") says why 'largest' needs more care.
bands = speed_bands(seg.ri, vehicle, model=model)
one_band_from_rest = bool(np.all((bands.count == 1) & (bands.lower_mps[:, 0] == 0.0)))
e_grid = np.linspace(0.0, 1.05 * e_seg.max(), 120)
f_grid = force_n(np.linspace(0.0, v_max, 120)[:, None], vehicle, e_max_m=e_grid[None, :], model=model)
monotone = one_band_from_rest and bool(np.all(np.diff(f_grid, axis=0) >= 0) and np.all(np.diff(f_grid, axis=1) >= 0))
ceiling_seg = np.minimum(cap_seg, v_max if monotone else bands.first())

# Preview tables as smooth functions of the predicted position s: cubic B-splines whose
# coefficient j is the worst value (largest e_max, smallest ceiling) over every segment
# within reach of the support [t_j, t_{j+4}] of basis function j. B-spline basis functions
# are non-negative and sum to one, so the spline at any s is a weighted mean of
# coefficients that each cover [s, s + REACH]: it never understates the worst e_max (never
# overstates the ceiling) within reach, and it is twice differentiable, which IPOPT needs
# (a piecewise-linear casadi.interpolant of the same values made IPOPT cycle at its kinks
# and hit max_iter in 5 of 760 steps; an interpolating 'bspline' interpolant can dip below
# its data between the samples). The knots cover every position a horizon can reach.
H, DEGREE = 0.5, 3
knots = np.arange(s_start - REACH - DEGREE * H, route.s_m[-1] + (N + 2) * REACH, H)
lo = knots[: -DEGREE - 1]
hi = knots[DEGREE + 1:] + REACH
j_lo = segment_index(lo, bounds_m)  # segment of lo
j_hi = segment_index(hi, bounds_m)  # segment of hi
e_coef, ceiling_coef = e_seg[j_lo].copy(), ceiling_seg[j_lo].copy()
for d in range(1, int(np.max(j_hi - j_lo)) + 1):
    idx = np.minimum(j_lo + d, j_hi)
    e_coef = np.maximum(e_coef, e_seg[idx])
    ceiling_coef = np.minimum(ceiling_coef, ceiling_seg[idx])
e_ahead = ca.Function.bspline("e_ahead_m", [knots.tolist()], e_coef.tolist(), [DEGREE], 1, {})
ceiling = ca.Function.bspline("ceiling_mps", [knots.tolist()], ceiling_coef.tolist(), [DEGREE], 1, {})
use_ceiling = bool(np.any(ceiling_coef < v_max))

# --- The optimal-control problem, built once ----------------------------------------------
opti = ca.Opti()
X = opti.variable(2, N + 1)  # rows: position s (m), speed v (m/s)
U = opti.variable(1, N)  # acceleration a (m/s^2), constant over each interval
x_now = opti.parameter(2)
a_before = opti.parameter()  # the acceleration applied last, for the smoothness term
s, v, a = X[0, :].T, X[1, :].T, U.T
opti.subject_to(X[:, 0] == x_now)
opti.subject_to(s[1:] == s[:-1] + v[:-1] * DT + a * DT**2 / 2)  # exact for constant a
opti.subject_to(v[1:] == v[:-1] + a * DT)
opti.subject_to(opti.bounded(0, v[1:], v_max))
terrain_k = e_ahead.map(N)(s[:-1].T).T  # e_max ahead of each interval's start (m)
# N + 1 speeds against N terrain values: both ends of every interval; plus a's bounds
add_force_constraints(opti, v, vehicle, e_max_m=terrain_k, model=model, accel_mps2=a)
if use_ceiling:  # bands (or route speed limits): pin both ends of each interval below
    cap_k = ceiling.map(N)(s[:-1].T).T
    opti.subject_to(v[:-1] <= cap_k)
    opti.subject_to(v[1:] <= cap_k)
jerk = ca.diff(ca.vertcat(a_before, a))
opti.minimize(ca.sumsqr(v[1:] - args.cruise) + 0.1 * ca.sumsqr(a) + 1.0 * ca.sumsqr(jerk))
opti.solver("ipopt", {"print_time": False}, {"print_level": 0, "sb": "yes", "tol": 1e-8, "max_iter": 200})

# --- Closed loop ----------------------------------------------------------------------------
peaks = bands.peaks_mps  # interior force maxima per segment, for the independent check


def worst_ratio(s0: float, v0: float, acc: float) -> tuple[float, float]:
    """Largest F / F_limit over one interval of the real motion, on the real segments.

    The interval is cut at the segment boundaries it crosses; on each piece the speed runs
    monotonically between two values, and the largest force over that speed range is at an
    end or at an interior force peak of that segment (profileopt.speeds.SpeedBands.peaks_mps).
    """
    t = np.linspace(0.0, DT, 2)
    s1 = s0 + v0 * DT + acc * DT**2 / 2
    crossings = bounds_m[(bounds_m > s0) & (bounds_m < s1)]
    if crossings.size:  # times at which the boundaries are reached
        if abs(acc) < 1e-12:
            tc = (crossings - s0) / v0
        else:
            tc = (-v0 + np.sqrt(np.maximum(v0**2 + 2 * acc * (crossings - s0), 0.0))) / acc
        t = np.sort(np.concatenate([t, np.clip(tc, 0.0, DT)]))
    worst, where = 0.0, s0
    for ta, tb in zip(t[:-1], t[1:]):
        sa = s0 + v0 * ta + acc * ta**2 / 2
        sb = s0 + v0 * tb + acc * tb**2 / 2
        i = int(segment_index([0.5 * (sa + sb)], bounds_m)[0])
        va, vb = sorted((v0 + acc * ta, v0 + acc * tb))
        inner = peaks[i][(peaks[i] > va) & (peaks[i] < vb)]
        speeds = np.concatenate([[va, vb], inner])
        r = float(np.max(force_n(speeds, vehicle, e_max_m=e_seg[i], model=model))) / limit_n
        if r > worst:
            worst, where = r, sa
    return worst, where


state = np.array([s_start, 0.0])  # from rest at the start of the route
a_last = 0.0
X_guess = np.vstack([s_start + np.arange(N + 1) * 0.0, np.zeros(N + 1)])
U_guess = np.zeros((1, N))
log = {"t": [0.0], "s": [state[0]], "v": [state[1]], "a": [], "ratio": []}
solve_times, failures = [], 0
worst, worst_at = 0.0, s_start
t_loop = time.perf_counter()
while state[0] < s_stop and len(solve_times) < 20000:
    opti.set_value(x_now, state)
    opti.set_value(a_before, a_last)
    opti.set_initial(X, X_guess)
    opti.set_initial(U, U_guess)
    t0 = time.perf_counter()
    try:
        sol = opti.solve()
        X_opt, U_opt = sol.value(X), np.atleast_2d(sol.value(U))
    except RuntimeError:
        print(f"t = {log['t'][-1]:.2f} s: IPOPT {opti.stats()['return_status']}; driving the last plan's tail",
              file=sys.stderr)
        # Infeasible or not converged: drive the tail of the last plan (it kept every
        # limit for the remaining stages) and brake at the end of it.
        failures += 1
        U_opt = np.hstack([U_guess[:, :-1], [[-vehicle.max_decel_mps2]]])
        X_opt = X_guess
    solve_times.append(time.perf_counter() - t0)
    # the actuator saturates at the bounds (IPOPT meets them to ~1e-8); never reverse
    acc = float(np.clip(U_opt[0, 0], -vehicle.max_decel_mps2, vehicle.max_accel_mps2))
    acc = max(acc, -state[1] / DT)
    r, r_at = worst_ratio(state[0], state[1], acc)
    if r > worst:
        worst, worst_at = r, r_at
    state = np.array([state[0] + state[1] * DT + acc * DT**2 / 2, state[1] + acc * DT])
    a_last = acc
    # warm start: the plan shifted by one interval, its last stage repeated
    X_guess = np.hstack([X_opt[:, 1:], X_opt[:, -1:] + np.array([[X_opt[1, -1] * DT], [0.0]])])
    U_guess = np.hstack([U_opt[:, 1:], U_opt[:, -1:]])
    for key, value in (("t", log["t"][-1] + DT), ("s", state[0]), ("v", state[1]), ("a", acc), ("ratio", r)):
        log[key].append(value)
t_loop = time.perf_counter() - t_loop

# --- The offline plan for the same route ----------------------------------------------------
t_plan = time.perf_counter()
profile = plan(route, vehicle, model=model)
t_plan = time.perf_counter() - t_plan

steps = len(solve_times)
ms = 1e3 * np.array(solve_times)
print(f"route {Path(args.route).name} ({s_stop - s_start:g} m driven), vehicle {Path(vehicle.name).stem}, "
      f"model {model}; horizon {N} x {DT:g} s, cruise {args.cruise:g} m/s")
print("force monotone in speed and e_max on this route: " + ("yes (force constraint exact)" if monotone
      else "no (speeds also pinned below the 'first' band edge)"))
print(f"closed loop: {log['t'][-1]:.1f} s of driving in {steps} MPC steps; IPOPT failures: {failures}")
print(f"solve time per step: mean {ms.mean():.1f} ms, median {np.median(ms):.1f} ms, max {ms.max():.1f} ms; "
      f"first solve {ms[0]:.0f} ms (CasADi builds the solver); closed loop {t_loop:.1f} s")
print(f"offline plan ({profile.status}): {profile.travel_time_s:.1f} s for the whole route, planned in {t_plan:.2f} s")
print(f"worst force ratio met: {worst:.9f} ({label}, limit {limit_n:g} N) at s = {worst_at:.1f} m "
      "(IPOPT meets active constraints to about 1e-8)")

# --- Plot ----------------------------------------------------------------------------------
out = Path(args.out)
out.mkdir(parents=True, exist_ok=True)
fig, (ax_v, ax_r) = plt.subplots(2, 1, sharex=True, figsize=(11, 6))
ax_v.plot(profile.s_m, profile.speed_mps, color="0.45", lw=1.5, zorder=2, label="offline plan (minimum time)")
ax_v.plot(log["s"], log["v"], color="C0", label=f"closed-loop MPC (cruise {args.cruise:g} m/s)")
first_seg = np.minimum(cap_seg, bands.first())
# wide and underneath: the offline plan rides it wherever the force limit holds it back
ax_v.stairs(first_seg, bounds_m, baseline=None, color="C3", lw=4.0, alpha=0.4, zorder=1,
            label="allowable speed per segment ('first')")
ax_v.set_ylabel("speed (m/s)")
ax_v.set_ylim(0, v_max * 1.05)
ax_v.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)  # outside: it hid data
ax_r.plot(profile.s_m, profile.force_n / profile.force_limit_n, color="0.6", label="offline plan, per segment")
ax_r.plot(log["s"][:-1], log["ratio"], color="C0", label="MPC: largest F / F_limit per step")
ax_r.axhline(1.0, color="C3", lw=0.8, label="limit")
ax_r.set_ylabel("force / limit (-)")
ax_r.set_xlabel("distance along the route s (m)")
ax_r.set_xlim(s_start, s_stop)
ax_r.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)
fig.tight_layout()
csv = out / "mpc_closed_loop.csv"  # one row per control step: the state, then the input applied
with atomic_path(csv) as tmp:
    table = np.column_stack([log["t"][:-1], log["s"][:-1], log["v"][:-1], log["a"], log["ratio"]])
    np.savetxt(tmp, table, delimiter=",", fmt="%.17g", comments="",
               header="time_s,s_m,speed_mps,accel_mps2,force_ratio")
print(csv)
png = out / "mpc_terrain_preview.png"
with atomic_path(png) as tmp:
    fig.savefig(tmp, format="png", dpi=120)
print(png)
sys.exit(0 if worst <= 1 + 1e-6 else 1)
