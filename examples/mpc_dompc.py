"""Closed-loop do-mpc speed controller that keeps the force limit between its grid points.

Run:  python examples/mpc_dompc.py [--vehicle atv] [--route ROUTE.csv] [--from-m 950]
                                   [--distance-m 100] [--cruise 14] [--sensor-range 60]
                                   [--unseen worst] [--out FOLDER]

Needs the ``mpc`` extra (``pip install 'profileopt[mpc]'``: do-mpc and rockit-meco).

A longitudinal vehicle (states: position s and speed v; input: acceleration a, held over
each interval of dt seconds, so the discrete model below is exact) starts from rest and
tracks a cruise speed along a stretch of a bundled route, whose terrain it knows only
``--sensor-range`` metres ahead. do-mpc solves a horizon of N intervals each step and the
plant (do-mpc's simulator of the same model) applies the first acceleration. The force limit
enters through ``set_nl_cons`` with two helpers of ``profileopt.mpc``:

* ``preview = TerrainPreview(vehicle, horizon_m=..., reach_m=v_max * dt)``: ``preview.e_max(s,
  origin, e_coef)`` is a smooth function of the predicted position, never below the e_max of
  any roughness window an interval starting there can reach (an interval covers at most
  v_max * dt), and ``preview.speed_cap`` the cap of steps and speed limits; their
  coefficients are do-mpc time-varying parameters, set each step from the measured terrain
  (``preview.coefficients``), so the controller is built once;
* ``interval_force_constraints(v, v + a * dt, e_max, vehicle)``: every speed between the
  interval's two speeds is admissible at every elevation up to e_max, the resonance peak
  between them included.

A third row keeps every stage able to brake to the unseen terrain's speed where the measured
terrain ends, so that the next step has a plan too. After each solve the predicted positions
are checked (``preview.check_stages``: every stage forward, at most the envelopes' reach
v_max * dt long and inside the horizon; the speed bounds imply it here); a plan that failed
the check would not be applied (the example brakes instead) and makes it exit with 1.
So every interval the controller applies keeps the force limit in every window it passes
(the proof is in the docstring of interval_force_constraints). The example then checks its
own closed-loop trajectory independently (examples/mpc_window_check.py: every window, the
speeds driven inside it between the grid points) and prints the worst window's force over
the limit; it exits with 1 if any window is over the limit or IPOPT failed.
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

import casadi as ca
import numpy as np

try:
    with warnings.catch_warnings():  # do-mpc warns that its optional PyTorch part is missing
        warnings.simplefilter("ignore")
        import do_mpc
except ImportError:
    sys.exit("mpc_dompc.py needs do-mpc, in the 'mpc' extra: pip install 'profileopt[mpc]'")

from profileopt import get_model, load_vehicle  # noqa: E402
from profileopt.errors import InputError  # noqa: E402
from profileopt.mpc.constraints import (  # noqa: E402
    force_constraints, force_limit_n, interval_force_constraints, terrain_envelope)
from profileopt.mpc.preview import TerrainPreview  # noqa: E402
from profileopt.online import unseen_speed_mps  # noqa: E402
from profileopt.io import read_route  # noqa: E402

from mpc_window_check import report, worst_window  # noqa: E402  (beside this file)

# do-mpc calls numpy functions on CasADi values, which CasADi 3.8 answers with a one-time
# FutureWarning about its numpy mode: not this example's business
warnings.filterwarnings("ignore", message="(?s).*numpy function was called on a casadi value", category=FutureWarning)

HERE = Path(__file__).resolve().parent
parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
parser.add_argument("--vehicle", default="atv", help="bundled vehicle name or .toml file (default: %(default)s)")
parser.add_argument("--route", default=None, help="route CSV (s,z) (default: trail.csv for atv, washboard.csv "
                    "for atv-resonant)")
parser.add_argument("--from-m", type=float, default=None, help="start from rest here, m (default: 950 on the "
                    "trail, 100 on the washboard)")
parser.add_argument("--distance-m", type=float, default=None, help="drive this far, m (default: 100 on the trail, "
                    "70 on the washboard)")
parser.add_argument("--cruise", type=float, default=None, help="cruise speed to track, m/s (default: 14 on the "
                    "trail, 8 on the washboard)")
parser.add_argument("--dt", type=float, default=0.25, help="control interval, s (default: %(default)s)")
parser.add_argument("--horizon", type=int, default=12, help="intervals per horizon (default: %(default)s)")
parser.add_argument("--max-steps", type=int, default=400, help="stop after this many steps (default: %(default)s)")
parser.add_argument("--pointwise", action="store_true", help="for comparison, the force limit only at the grid "
                    "points, on the e_max at each point (the constraint issue 10 found unsafe)")
parser.add_argument("--sensor-range", type=float, default=60.0,
                    help="the terrain is known this far ahead of the vehicle, m (default: %(default)s)")
parser.add_argument("--unseen", default="worst",
                    help="terrain beyond it assumed: worst (ISO 8608 class H), a class A-H or an RI (default: %(default)s)")
parser.add_argument("--out", default=None, help="folder for the closed-loop log mpc_dompc_<vehicle>.csv")
args = parser.parse_args()

vehicle = load_vehicle(args.vehicle)
resonant = Path(vehicle.name).stem == "atv-resonant"
route = read_route(args.route or HERE / "routes" / ("washboard.csv" if resonant else "trail.csv"))
s_start = args.from_m if args.from_m is not None else (100.0 if resonant else 950.0)
distance = args.distance_m if args.distance_m is not None else (70.0 if resonant else 100.0)
cruise = args.cruise if args.cruise is not None else (8.0 if resonant else 14.0)
model_key, dt, n_horizon = "sbem_tf", args.dt, args.horizon
s_stop = min(s_start + distance, float(route.s_m[-1]))
limit_n = force_limit_n(vehicle, model=model_key)
WINDOW = 5.0
REACH = vehicle.max_speed_mps * dt  # the furthest one interval can take the vehicle (m)
# IPOPT meets constraints to about 1e-8: the rows are held 1e-6 below 0, so that the
# applied intervals are within the limit, not only within IPOPT's tolerance of it
BACK_OFF = 1e-6

# --- The terrain ahead, as parameters set each step from what the vehicle has measured -------
# TerrainPreview: the e_max envelope and the speed cap (steps, speed limits) on a horizon that
# moves with the vehicle, their coefficients do-mpc time-varying parameters: the controller is
# built once, whatever the route's length, and sees only --sensor-range metres ahead (past
# that, the --unseen class)
t0 = time.perf_counter()
preview = TerrainPreview(vehicle, horizon_m=(n_horizon + 1) * REACH + WINDOW, reach_m=REACH, window_m=WINDOW,
                         unseen=args.unseen)
v_unseen = unseen_speed_mps(args.unseen, vehicle, model=model_key, roughness_window_m=WINDOW)
t_env = time.perf_counter() - t0


def sensed(position_m: float):  # noqa: ANN201
    """The preview's coefficients from the samples known at ``position_m``: a window behind
    the vehicle and --sensor-range ahead."""
    keep = (route.s_m >= position_m - 2 * WINDOW) & (route.s_m <= position_m + args.sensor_range)
    limits = None if route.speed_limit_mps is None else route.speed_limit_mps[keep]
    return preview.coefficients(route.s_m[keep], route.z_m[keep], position_m, speed_limit_mps=limits)


# --- do-mpc: model, controller, plant -------------------------------------------------------
model = do_mpc.model.Model("discrete")
s = model.set_variable("_x", "s")  # position (m)
v = model.set_variable("_x", "v")  # speed (m/s)
a = model.set_variable("_u", "a")  # acceleration over the interval (m/s^2)
origin = model.set_variable("_tvp", "origin")  # where the preview's horizon starts (m)
e_coef = model.set_variable("_tvp", "e_coef", shape=(preview.n_coefficients, 1))
cap_coef = model.set_variable("_tvp", "cap_coef", shape=(preview.n_coefficients, 1))
measured_to = model.set_variable("_tvp", "measured_to")  # where the trusted measured terrain ends (m)
model.set_rhs("s", s + v * dt + a * dt**2 / 2)  # exact for constant a
model.set_rhs("v", v + a * dt)
model.setup()

mpc = do_mpc.controller.MPC(model)
mpc.settings.n_horizon = n_horizon
mpc.settings.t_step = dt
mpc.settings.store_full_solution = False
mpc.settings.supress_ipopt_output()
mpc.set_objective(lterm=(v - cruise) ** 2, mterm=(v - cruise) ** 2)
mpc.set_rterm(a=0.1)  # smooth accelerations
mpc.bounds["lower", "_x", "v"] = 0.0
mpc.bounds["upper", "_x", "v"] = vehicle.max_speed_mps
mpc.bounds["lower", "_u", "a"] = -vehicle.max_decel_mps2
mpc.bounds["upper", "_u", "a"] = vehicle.max_accel_mps2
if args.pointwise:  # the unsafe way, for comparison: the terrain under each grid point only
    keep = (route.s_m >= s_start - WINDOW) & (route.s_m <= s_stop + (n_horizon + 1) * REACH + WINDOW)
    point_env = terrain_envelope(route.s_m[keep], route.z_m[keep], vehicle, window_m=WINDOW)
    rows = force_constraints(v, vehicle, e_max_m=point_env(s), model=model_key)
else:
    rows = interval_force_constraints(v, v + a * dt, preview.e_max(s, origin, e_coef), vehicle, model=model_key)
    cap = preview.speed_cap(s, origin, cap_coef)  # steps and speed limits: both ends of the interval
    mpc.set_nl_cons("cap_start", v - cap, ub=-BACK_OFF)
    mpc.set_nl_cons("cap_end", v + a * dt - cap, ub=-BACK_OFF)
    # every stage can still brake to the unseen terrain's speed where the measured terrain ends,
    # so that the next step has a plan too
    room = ca.fmax(measured_to - (s + v * dt + a * dt**2 / 2), 0)  # from where the stage ends
    mpc.set_nl_cons("braking", (v + a * dt) ** 2 - 2 * vehicle.max_decel_mps2 * room, ub=v_unseen**2)
mpc.set_nl_cons("force", rows.g, ub=-BACK_OFF)
tvp = mpc.get_tvp_template()
now = {"coef": sensed(s_start)}


def tvp_now(t_now: float):  # noqa: ANN201
    """The preview's parameters for every stage of this step's horizon."""
    coef = now["coef"]
    for k in range(n_horizon + 1):
        tvp["_tvp", k, "origin"] = coef.origin_m
        tvp["_tvp", k, "e_coef"] = coef.e_max
        tvp["_tvp", k, "cap_coef"] = coef.speed_cap
        tvp["_tvp", k, "measured_to"] = coef.measured_to_m
    return tvp


mpc.set_tvp_fun(tvp_now)
mpc.setup()

plant = do_mpc.simulator.Simulator(model)
plant.settings.t_step = dt
plant.set_tvp_fun(lambda t_now: plant.get_tvp_template())  # the plant does not use them
plant.setup()

# --- Closed loop ------------------------------------------------------------------------------
x0 = np.array([[s_start], [0.0]])  # from rest
mpc.x0 = plant.x0 = x0
mpc.set_initial_guess()
log_t, log_s, log_v, log_a, solve_s, failures, refused = [0.0], [s_start], [0.0], [], [], 0, 0
t_loop = time.perf_counter()
while x0[0, 0] < s_stop and len(log_a) < args.max_steps:
    now["coef"] = sensed(float(x0[0, 0]))  # what the sensors have measured, as parameters
    t0 = time.perf_counter()
    u0 = mpc.make_step(x0)
    solve_s.append(time.perf_counter() - t0)
    failures += not mpc.solver_stats["success"]
    # the envelopes bound a stage only if it is at most REACH long and starts inside the
    # horizon: check the predicted positions before applying the first input
    predicted = [float(mpc.opt_x_num_unscaled["_x", k, 0, -1, "s"]) for k in range(n_horizon + 1)]
    try:
        preview.check_stages(predicted, origin_m=now["coef"].origin_m)
    except InputError as exc:
        print(f"t = {log_t[-1]:.2f} s: {exc}; braking instead", file=sys.stderr)
        refused += 1
        u0 = np.array([[max(-vehicle.max_decel_mps2, -float(x0[1, 0]) / dt)]])
    x0 = plant.make_step(u0)
    log_a.append(float(u0[0, 0]))
    log_t.append(log_t[-1] + dt)
    log_s.append(float(x0[0, 0]))
    log_v.append(float(x0[1, 0]))
t_loop = time.perf_counter() - t_loop

# --- Its own check: every window, between the grid points --------------------------------------
check = worst_window(route.s_m, route.z_m, vehicle, log_t, log_s, log_v, log_a, model=model_key, window_m=WINDOW)
ms = 1e3 * np.array(solve_s)
print(f"route {Path(route.source).name}, vehicle {Path(vehicle.name).stem}, model {model_key}: from rest at "
      f"{s_start:g} m to {log_s[-1]:.1f} m, cruise {cruise:g} m/s; horizon {n_horizon} x {dt:g} s")
print(f"preview: {preview.n_coefficients} coefficients per step, terrain known {args.sensor_range:g} m ahead, reach "
      f"{REACH:g} m, built in {t_env:.2f} s")
print(f"closed loop: {log_t[-1]:.2f} s of driving in {len(log_a)} do-mpc steps; IPOPT failures: {failures}; "
      f"plans refused by the stage check: {refused}; solve time per step: median {np.median(ms):.1f} ms, max "
      f"{ms.max():.1f} ms; loop {t_loop:.1f} s")
print(f"speeds driven: {min(log_v):.3f} to {max(log_v):.3f} m/s")
print(report(check, get_model(model_key).label, limit_n, WINDOW))
if args.out:
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    path = out / f"mpc_dompc_{Path(vehicle.name).stem}.csv"
    table = np.column_stack([log_t, log_s, log_v, np.r_[log_a, np.nan]])
    np.savetxt(path, table, delimiter=",", fmt="%.17g", comments="", header="time_s,s_m,speed_mps,accel_mps2")
    print(path)
sys.exit(0 if check.over == 0 and failures == 0 and refused == 0 else 1)
