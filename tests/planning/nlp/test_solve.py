"""The NLP's solvers (profileopt.planning.nlp.solve): when a solve counts as a solution."""

import numpy as np

import profileopt
from profileopt.planning.options import SolverOptions


def test_ipopt_stalled_at_a_solution_is_a_solution():
    # A 2 cm x 2 m pit sampled every 0.05 m, atv-resonant: refined, the route has 0.1 m and
    # 5 m segments side by side, and IPOPT ends with "Search_Direction_Becomes_Too_Small" at
    # dual infeasibility 3e-10 (tol 1e-10), primal 6e-15, mu 1e-11, after a dozen steps of
    # 1e-15. Before, the planner fell back to a crawl: 138.6 s. Reference: the exact
    # minimum-time profile without smoothing or jerk bound (a lower bound, 9.1 s); the jerk
    # bound and comfort term cost a few per cent on 60 m.
    vehicle = profileopt.load_vehicle("atv-resonant")
    s = np.round(np.arange(0.0, 60.0 + 1e-9, 0.05), 10)
    route = profileopt.Route(s_m=s, z_m=-0.02 * ((s >= 40.0) & (s < 42.0)), source="pit")
    exact = profileopt.plan(route, vehicle, smoothing=0.0, max_jerk_mps3=float("inf"))
    profile = profileopt.plan(route, vehicle, solver_options=SolverOptions(nlp_solver="ipopt"))
    assert profile.status == "optimal"
    assert exact.travel_time_s <= profile.travel_time_s <= 1.1 * exact.travel_time_s
