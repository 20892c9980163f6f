"""Minimum-time rockit problem that keeps the force limit between its grid points.

Run:  python examples/mpc_rockit.py [--vehicle atv] [--route ROUTE.csv] [--from-m 950]
                                    [--distance-m 100] [--stages 40] [--out FOLDER]

Needs the ``mpc`` extra (``pip install 'profileopt[mpc]'``: do-mpc and rockit-meco).

The fastest way from rest over a stretch of a bundled route: rockit's free-time optimal
control problem with states position s and speed v, the acceleration a as a piecewise
constant control, multiple shooting on N intervals (RK4 is exact for s'' = a). The force
limit holds between the grid points through the two helpers of ``profileopt.mpc.constraints``:

* ``env = terrain_envelope(s, z, vehicle, reach_m=REACH)``: a smooth function of the
  position, never below the e_max of any roughness window within REACH ahead; each interval
  is held to at most REACH metres (``ocp.next(s) - s <= REACH``), since its duration is
  free, and the solved positions are checked against it (``check_stage_lengths(s, REACH)``:
  left out, the row's absence would give "success" with stages far longer than REACH);
* ``interval_force_constraints(v, ocp.next(v), env(s), vehicle)``: every speed between the
  interval's two speeds is admissible at every elevation up to env(s), the resonance peak
  between them included.

The example then checks its own trajectory independently (examples/mpc_window_check.py:
every window, the speeds driven inside it between the grid points), prints the worst
window's force over the limit, and exits with 1 if any window is over the limit.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

try:
    from rockit import FreeTime, MultipleShooting, Ocp
except ImportError:
    sys.exit("mpc_rockit.py needs rockit-meco, in the 'mpc' extra: pip install 'profileopt[mpc]'")

from profileopt import get_model, load_vehicle  # noqa: E402
from profileopt.errors import InputError  # noqa: E402
from profileopt.mpc.constraints import (  # noqa: E402
    force_constraints, force_limit_n, interval_force_constraints, terrain_envelope)
from profileopt.mpc.horizon import check_stage_lengths  # noqa: E402
from profileopt.io import read_route  # noqa: E402

from mpc_window_check import report, worst_window  # noqa: E402  (beside this file)

HERE = Path(__file__).resolve().parent
parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
parser.add_argument("--vehicle", default="atv", help="bundled vehicle name or .toml file (default: %(default)s)")
parser.add_argument("--route", default=None, help="route CSV (s,z) (default: trail.csv for atv, washboard.csv "
                    "for atv-resonant)")
parser.add_argument("--from-m", type=float, default=None, help="start from rest here, m (default: 950 on the "
                    "trail, 120 on the washboard)")
parser.add_argument("--distance-m", type=float, default=None, help="reach this far, m (default: 100 on the trail, "
                    "80 on the washboard)")
parser.add_argument("--stages", type=int, default=40, help="control intervals N (default: %(default)s)")
parser.add_argument("--pointwise", action="store_true", help="for comparison, the force limit only at the grid "
                    "points, on the e_max at each point (the constraint issue 10 found unsafe)")
parser.add_argument("--out", default=None, help="folder for the trajectory mpc_rockit_<vehicle>.csv")
args = parser.parse_args()

vehicle = load_vehicle(args.vehicle)
resonant = Path(vehicle.name).stem == "atv-resonant"
route = read_route(args.route or HERE / "routes" / ("washboard.csv" if resonant else "trail.csv"))
s_start = args.from_m if args.from_m is not None else (120.0 if resonant else 950.0)
distance = args.distance_m if args.distance_m is not None else (80.0 if resonant else 100.0)
s_end = min(s_start + distance, float(route.s_m[-1]))
n_stages, model_key = args.stages, "sbem_tf"
limit_n = force_limit_n(vehicle, model=model_key)
WINDOW = 5.0
REACH = math.ceil(2.0 * (s_end - s_start) / n_stages)  # m per interval at most: twice the mean
BACK_OFF = 1e-6  # rows held 1e-6 below 0: IPOPT meets constraints to about 1e-8

keep = (route.s_m >= s_start - WINDOW) & (route.s_m <= s_end + REACH + WINDOW)
t0 = time.perf_counter()
env = terrain_envelope(route.s_m[keep], route.z_m[keep], vehicle, window_m=WINDOW, reach_m=REACH)
t_env = time.perf_counter() - t0

# --- The optimal-control problem --------------------------------------------------------------
guess_s = distance / 3.0  # a guess of the travel time (s): 3 m/s on average
ocp = Ocp(T=FreeTime(guess_s))
s = ocp.state()  # position (m)
v = ocp.state()  # speed (m/s)
a = ocp.control()  # acceleration (m/s^2), constant over each interval
ocp.set_der(s, v)
ocp.set_der(v, a)
ocp.add_objective(ocp.T)  # travel time (s)
ocp.subject_to(-vehicle.max_decel_mps2 <= (a <= vehicle.max_accel_mps2))
ocp.subject_to(0 <= (v <= vehicle.max_speed_mps))
if args.pointwise:  # the unsafe way, for comparison: the terrain under each grid point only
    point_env = terrain_envelope(route.s_m[keep], route.z_m[keep], vehicle, window_m=WINDOW)
    rows = force_constraints(v, vehicle, e_max_m=point_env(s), model=model_key)
else:
    rows = interval_force_constraints(v, ocp.next(v), env(s), vehicle, model=model_key)
ocp.subject_to(rows.g <= -BACK_OFF, include_last=False)  # every interval, every speed in it
ocp.subject_to(ocp.next(s) - s <= REACH, include_last=False)  # the envelope's reach
ocp.subject_to(ocp.at_t0(s) == s_start)
ocp.subject_to(ocp.at_t0(v) == 0.0)
ocp.subject_to(ocp.at_tf(s) == s_end)
ocp.set_initial(s, s_start + distance * ocp.t / guess_s)
ocp.set_initial(v, distance / guess_s)
ocp.solver("ipopt", {"print_time": False, "ipopt.print_level": 0, "ipopt.sb": "yes"})
ocp.method(MultipleShooting(N=n_stages, M=1, intg="rk"))
t0 = time.perf_counter()
sol = ocp.solve()
t_solve = time.perf_counter() - t0

time_s, s_m = sol.sample(s, grid="control")
_, speed = sol.sample(v, grid="control")
_, accel = sol.sample(a, grid="control")
accel = accel[:n_stages]  # the control's last sample repeats the last interval's
try:  # the envelope covers a stage only if it is at most REACH long: check the solved positions
    stage_m = check_stage_lengths(s_m, REACH)
except InputError as exc:
    sys.exit(f"mpc_rockit.py: the solution is not covered by the envelope: {exc}")

# --- Its own check: every window, between the grid points --------------------------------------
check = worst_window(route.s_m, route.z_m, vehicle, time_s, s_m, speed, accel, model=model_key, window_m=WINDOW)
print(f"route {Path(route.source).name}, vehicle {Path(vehicle.name).stem}, model {model_key}: from rest at "
      f"{s_start:g} m to {s_end:g} m in {n_stages} intervals of at most {REACH:g} m (longest solved: "
      f"{stage_m.max():.3f} m)")
print(f"envelope: {keep.sum()} samples, built in {t_env:.2f} s; rockit + IPOPT: {t_solve:.2f} s "
      f"({sol.stats['iter_count']} iterations)")
print(f"minimum time: {time_s[-1]:.3f} s; speeds {speed.min():.3f} to {speed.max():.3f} m/s")
print(report(check, get_model(model_key).label, limit_n, WINDOW))
if args.out:
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    path = out / f"mpc_rockit_{Path(vehicle.name).stem}.csv"
    table = np.column_stack([time_s, s_m, speed, np.r_[accel, np.nan]])
    np.savetxt(path, table, delimiter=",", fmt="%.17g", comments="", header="time_s,s_m,speed_mps,accel_mps2")
    print(path)
sys.exit(0 if check.over == 0 else 1)
