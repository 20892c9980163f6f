"""IPOPT, the default back end (profileopt.planning.nlp.backends.ipopt): what it does to the
process it runs in. Its optimum is checked against the exact profile and a reference NLP in
tests/planning/nlp/test_problem.py and test_solve.py."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest
from conftest import ROUTES

_THREADS_AFTER_A_PLAN = """
import ctypes, os
from pathlib import Path
import casadi as ca
import numpy as np
import profileopt
s_m = np.arange(0.0, 200.0, 0.1)
profile = profileopt.plan(profileopt.Route(s_m, 0.02 * np.sin(s_m), source="wavy.csv"),
                          profileopt.load_vehicle("atv"), smoothing=0.1)
assert profile.solver == "ipopt", profile.solver
for path in sorted(Path(ca.__file__).parent.glob("libcasadi-tp-openblas*")):
    try:
        print(ctypes.CDLL(str(path), mode=os.RTLD_NOLOAD | os.RTLD_LAZY).openblas_get_num_threads())
        break
    except OSError:
        continue
"""


@pytest.mark.slow
@pytest.mark.skipif(not hasattr(os, "RTLD_NOLOAD") or (os.cpu_count() or 1) < 2,
                    reason="OpenBLAS starts one thread per core: with one core there is nothing to see")
@pytest.mark.parametrize("environment, threads", [({}, 1), ({"OPENBLAS_NUM_THREADS": "2"}, 2)])
def test_a_python_plan_leaves_ipopts_blas_on_one_thread_unless_the_environment_says(environment: dict,
                                                                                   threads: int) -> None:
    """Without OPENBLAS_NUM_THREADS, CasADi's OpenBLAS starts a thread per core; the solve then
    takes the same wall time and half again the CPU time (one_blas_thread's docstring)."""
    env = {key: value for key, value in os.environ.items() if key not in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS")}
    done = subprocess.run([sys.executable, "-c", _THREADS_AFTER_A_PLAN], env={**env, **environment},
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    assert int(done.stdout.split()[-1]) == threads


@pytest.mark.parametrize("extra, words", [
    ({"ipopt.mu_stratgy": "monotone"}, "IPOPT has no option 'mu_stratgy'"),  # before: CasADi's RuntimeError
    ({"ipopt.tol": -1.0}, "out of range"),  # before: CasADi's RuntimeError
    # before: the plan fell back to the slower safe profile with a note (409.9 s for 55.3 s)
    ({"ipopt.linear_solver": "ma57"}, "Invalid_Option"),
])
def test_ipopt_options_it_refuses_are_one_line_input_errors(extra: dict, words: str) -> None:
    import numpy as np

    import profileopt
    from profileopt.errors import InputError
    from profileopt.planning.options import DEFAULT_IPOPT_OPTIONS, SolverOptions

    s_m = np.arange(0.0, 100.0, 0.1)
    route = profileopt.Route(s_m, 0.02 * np.sin(s_m), source="wavy.csv")
    options = SolverOptions(ipopt={**DEFAULT_IPOPT_OPTIONS, **extra})
    with pytest.raises(InputError, match=words) as caught:
        profileopt.plan(route, profileopt.load_vehicle("atv"), smoothing=0.1, solver_options=options)
    assert "\n" not in str(caught.value)


def test_a_crawl_beside_fast_ground_converges_in_tens_of_iterations() -> None:
    """Issue 28: IPOPT within 60 iterations. On the first band the resonant atv crawls at
    0.1-0.3 m/s over much of KRC 1 in: with one scale for the route (y = b / b_ref) those
    boundaries' variables sat at about 2e-4 beside 1 elsewhere, and IPOPT took 69 iterations
    (the trail: 189). With a scale per boundary (boundary_scales) 30 (the trail: 123, still
    over: the docs' solver page)."""
    import profileopt

    route = profileopt.read_route(ROUTES / "krc_rms_1in.csv")
    profile = profileopt.plan(route, profileopt.load_vehicle("atv-resonant"), band="first")
    assert profile.solver == "ipopt" and profile.status == "optimal"
    assert profile.iterations <= 60, profile.iterations
