"""Benchmark of ``profileopt plan`` against TOPP-RA and COPP (issues 3 and 14).

Run by hand, never by the test suite (it takes minutes and its numbers depend on the
machine)::

    pip install -e '.[bench]'          # TOPP-RA and COPP, the independent peer solvers
    python benchmarks/bench_plan.py    # sizes 1000 10000 100000, 5 repeats; table on stdout
    python benchmarks/bench_plan.py --sizes 1000 10000 --repeats 3 --out /tmp/results.md

For every size N (segments of 5 m) it generates a seeded synthetic route (an ISO 8608
random profile whose class changes along it, sampled every 0.5 m, so every segment holds
10 samples), writes it as a CSV in a temporary directory and then, side by side in the
same process and interleaved repeat by repeat, times:

``full``
    ``read_route`` -> ``plan`` (SBEM:TF, acceleration, jerk, default smoothing, vehicle
    ``atv``) -> ``write_profile``: the command's work, in process. Also the same problem
    through the real command line (``python -m profileopt plan ... -o``) in a fresh
    process, which adds interpreter start-up, imports and the printed summary.
``convex``
    the convex subset: per-segment speed caps (the force model's allowable speed and
    v_max) plus acceleration bounds, nothing else (``smoothing=0``, ``max_jerk_mps3=inf``).
    Timed with ``plan(method="auto")`` (the exact forward-backward pass), with
    ``plan(method="nlp")`` (the NLP solved although the pass is exact: IPOPT, the
    default back end), with TOPP-RA and with COPP's TOPP2-RA.
``jerk``
    the jerk-limited minimum-time problem: the convex subset plus the vehicle's jerk
    bound (``smoothing=0``). Timed with ``plan`` (IPOPT, the default back end), with
    ``SolverOptions(nlp_solver="banded")`` (the opt-in banded method, issue 28's 2x rule),
    with ``SolverOptions(nlp_solver="fatrop")`` when ``--fatrop`` is given, and with
    COPP's TOPP3-LP.

``plan`` refines its segments by default (issue 10: cut where the minimum-time profile
meets the force's cap and the roughness changes), so N names the segments asked for and
the table gives the segments planned beside it (about 2.4 N on this route). Every peer
runs the same refinement in its timed pipeline (:func:`planner_segments`, the planner's
own functions) and gets exactly the planner's boundaries and caps; the benchmark checks
that the boundaries of every written plan are the peers'.

TOPP-RA solves the same discrete problem: the path is the 1-D position p(s) = s (so
p' = 1 and p'' = 0), the grid points are the segment boundaries, the velocity bound at
each boundary is the smaller cap of the two segments meeting there (the planner's bound
on b = v^2 there), and the acceleration bounds are [-max_decel, max_accel]. With
x = sdot^2 and a constant path acceleration u_i per stage, TOPP-RA's dynamics
x_{i+1} = x_i + 2 ds_i u_i are the planner's b_{i+1} = b_i + 2 ds_i a_i, and its travel
time sum 2 ds_i / (sdot_i + sdot_{i+1}) is the planner's, so the two optima coincide and
any difference is the solver's. Its end-to-end time runs the same pipeline as the
planner's (read the CSV, segment, speed bands, solve, write the profile CSV through the
same ``write_profile``); only the solver differs. COPP's TOPP2-RA is set up the same way
(:func:`solve_copp_topp2`) and solves the same discrete problem.

COPP's TOPP3-LP (:func:`solve_copp_topp3`) gets the same stations, caps, acceleration
bounds and the jerk bound in m/s^3 (s is arc length, so COPP's axial jerk d3s/dt3 is the
vehicle's jerk). Its discrete model is not the planner's: COPP keeps the path
acceleration b = sddot at the stations, linear in s between them, and bounds the jerk
sqrt(a) db/ds at both ends of every interval; the planner keeps one constant acceleration
per segment and bounds v_j (a_j - a_{j-1}) / mean(ds) at interior boundaries. COPP's
constraints imply the planner's (the planner's a_j is the mean of COPP's b at the two ends
of segment j, so its jerk at a boundary is a weighted mean of COPP's two interval jerks
there, and COPP's linearised jerk rows are tighter than sqrt(a) db/ds <= bound), not the
other way round: COPP solves a stricter problem on the same grid and its optimum can only
be slower. Both answers are judged by the same check (:func:`violation`) on their
boundary speeds.

Every optimum is compared with the exact one, :func:`profileopt.planning.greatest_profile`
on the same caps, and every written profile is read back and checked against the caps,
the acceleration bounds, the force limit, and (full and jerk-limited problems) the jerk
bound of the planner's model. Peers' speeds are checked as they leave the solver.

Each timed run starts cold, as a fresh ``profileopt plan`` process would: every
``functools`` cache in ``profileopt`` (the built NLP, the CasADi functions of the force
models) is cleared first. Import time is not in the in-process rows; the ``CLI`` row
includes it.
"""

from __future__ import annotations

import argparse
import dataclasses
import gc
import importlib.metadata
import inspect
import math
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Callable

sys.path.insert(0, str(Path(__file__).resolve().parent))  # the benchmarks' shared helper
from installed import compile_package  # noqa: E402

# As `profileopt plan` does (profileopt.cli.app.main): no huge-page advice from NumPy, read
# when NumPy is imported, so it is set before the import.
os.environ.setdefault("NUMPY_MADVISE_HUGEPAGE", "0")
import numpy as np  # noqa: E402

import profileopt
from profileopt.io.profiles import write_profile
from profileopt import load_vehicle
from profileopt.defaults import DEFAULT_REFINE
from profileopt.core.vehicle import OPTIONAL_KEYS
from profileopt.physics.forces import get_model
from profileopt.io import read_profile, read_route
from profileopt.core.kinematics import boundary_jerk_mps3
from profileopt import Profile
from profileopt.core.segments import segment_route
from profileopt.planning import DEFAULT_SMOOTHING, SolverOptions, greatest_profile, plan
from profileopt.physics.steps import step_speed_cap_mps
from profileopt.cli.app import keep_arrays_on_the_heap
from profileopt.planning.refine import at_force_cap, refine_segments
from profileopt.physics.speeds import speed_bands
from profileopt.terrain.synthetic import iso8608_sections

REPO = Path(__file__).resolve().parent.parent

# As `profileopt plan` does (profileopt.cli.app): CasADi's OpenBLAS, loaded with the first
# IPOPT solver, on one thread, and freed arrays kept on the heap for reuse, so the in-process
# rows time what the command runs.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
keep_arrays_on_the_heap()

#: Segment length (m) of every plan, the command's default.
SEGMENT_LENGTH_M = 5.0
#: Force model of every plan.
MODEL = "sbem_tf"
#: ISO 8608 classes of the route's sections and how often each occurs. For the bundled atv
#: with SBEM:TF, class C leaves v_max (20 m/s) binding and G caps the speed at 2-8 m/s, so
#: the caps vary along the route and the acceleration bounds are active at every change.
CLASSES = ("C", "D", "E", "F", "G")
CLASS_WEIGHTS = (0.20, 0.30, 0.25, 0.17, 0.08)
#: Section lengths (m) are uniform in this range.
SECTION_LENGTH_M = (100.0, 600.0)
#: Highest spatial frequency of the random profile (cycles/m): below the Nyquist frequency
#: 1 / (2 * 0.5 m) = 1 cycle/m of the default sample spacing.
N_MAX_CPM = 0.9
#: The issue's targets.
FULL_TARGET_S = 1.0  # full problem, 10,000 segments, end to end
GAP_TARGET = 1e-4  # convex subset, relative to the exact optimum
SCALING_TARGET = 10.0  # t(100,000) / t(10,000), issue 14 (issue 3 asked for 12)
JERK_TARGET = 0.5  # jerk-limited problem: profileopt's time / COPP TOPP3-LP's, issue 14
CLI_TARGET = 2.0  # `profileopt plan` process / TOPP-RA in process on the convex subset, issue 14


# ---------------------------------------------------------------------------------------
# Routes


def route_sections(total_m: float, seed: int) -> list[tuple[str, float]]:
    """Seeded (ISO 8608 class, length in m) sections adding up to ``total_m``."""
    rng = np.random.default_rng(seed)
    sections: list[tuple[str, float]] = []
    covered = 0.0
    while covered < total_m - 1e-9:
        length = min(float(rng.uniform(*SECTION_LENGTH_M)), total_m - covered)
        if total_m - covered - length < SECTION_LENGTH_M[0] / 2:  # no sliver at the end
            length = total_m - covered
        sections.append((str(rng.choice(CLASSES, p=CLASS_WEIGHTS)), length))
        covered += length
    return sections


def write_route(path: Path, segments: int, spacing_m: float, seed: int) -> int:
    """Write a route of ``segments`` * 5 m sampled every ``spacing_m`` (columns s,z, m).

    Returns the number of samples.
    """
    total = segments * SEGMENT_LENGTH_M
    profile = iso8608_sections(route_sections(total, seed), spacing_m, seed, n_max_cpm=N_MAX_CPM)
    with open(path, "w", encoding="utf-8") as handle:
        handle.write(f"# bench_plan.py: ISO 8608 sections, seed {seed}, spacing {spacing_m} m\n")
        handle.write("s,z\n")
        np.savetxt(handle, np.column_stack([profile.s_m, profile.z_m]), delimiter=",", fmt=("%.3f", "%.6f"))
    return int(profile.s_m.size)


# ---------------------------------------------------------------------------------------
# The convex subset and its exact optimum


@dataclasses.dataclass(frozen=True)
class ConvexProblem:
    """Per-boundary caps of the convex subset and its exact optimum.

    Attributes
    ----------
    boundaries_m : numpy.ndarray, shape (N+1,)
    length_m : numpy.ndarray, shape (N,)
    ri : numpy.ndarray, shape (N,)
    e_max_m : numpy.ndarray, shape (N,)
    segment_cap_mps : numpy.ndarray, shape (N,)
        min(allowable speed of the model, v_max) per segment (m/s).
    boundary_cap_mps : numpy.ndarray, shape (N+1,)
        The smaller cap of the segments meeting at each boundary (m/s).
    upper_b : numpy.ndarray, shape (N+1,)
        Bound on b = v^2 (m^2/s^2), with the boundary speeds v0 = vend = 0.
    exact_b : numpy.ndarray, shape (N+1,)
        The exact optimum (greatest profile) (m^2/s^2).
    exact_time_s : float
    single_band : bool
        Every segment's admissible speeds are one interval [0, cap], so the caps above are
        the whole force constraint and the problem is convex.
    """

    boundaries_m: np.ndarray
    length_m: np.ndarray
    ri: np.ndarray
    e_max_m: np.ndarray
    segment_cap_mps: np.ndarray
    boundary_cap_mps: np.ndarray
    upper_b: np.ndarray
    exact_b: np.ndarray
    exact_time_s: float
    single_band: bool


def travel_time_s(b: np.ndarray, length_m: np.ndarray) -> float:
    """Travel time (s) with constant acceleration per segment: sum 2 ds / (v_i + v_{i+1})."""
    v = np.sqrt(np.maximum(b, 0.0))
    return float(np.sum(2.0 * length_m / (v[:-1] + v[1:])))


def _segment_caps(seg, vehicle, other_cap) -> tuple[np.ndarray, np.ndarray, np.ndarray, bool]:
    """Each segment's cap (its first band's top, at most ``other_cap``: v_max and SBEM:TF's
    step limit, :func:`_other_caps`), each boundary's (the smaller of the segments meeting
    there), the bound on b = v^2 at the boundaries (v0 = vend = 0), and whether every segment
    has one band [0, cap] (then the caps are the whole force constraint)."""
    bands = speed_bands(seg.ri, vehicle, model=MODEL)
    single = bool(np.all(bands.count == 1) and np.all(bands.lower_mps[:, 0] == 0.0))
    cap = np.minimum(bands.first(), other_cap)
    boundary_cap = np.concatenate([[cap[0]], np.minimum(cap[:-1], cap[1:]), [cap[-1]]])
    upper_b = boundary_cap**2
    upper_b[0] = upper_b[-1] = 0.0  # v0 = vend = 0
    return cap, boundary_cap, upper_b, single


def _other_caps(route, seg, vehicle) -> np.ndarray:
    """Each segment's cap besides the force's bands (m/s): v_max and, as in every sbem_tf plan,
    the step limit (the benchmark routes have no speed_limit)."""
    return np.minimum(vehicle.max_speed_mps, step_speed_cap_mps(route.s_m, route.z_m, seg.boundaries_m, vehicle))


def _exact_b(seg, upper_b: np.ndarray, vehicle) -> np.ndarray:
    """The exact optimum of the convex subset, v^2 at the boundaries (the forward-backward pass)."""
    return greatest_profile(np.zeros_like(upper_b), upper_b, seg.length_m,
                            vehicle.max_accel_mps2, vehicle.max_decel_mps2)


def planner_segments(route, vehicle):
    """The segments ``plan`` solves on with its default ``refine``: the route cut every
    SEGMENT_LENGTH_M, then, as the planner does, the segments where the minimum-time profile
    meets the force's cap (:func:`profileopt.planning.refine.at_force_cap`) cut again where
    the roughness changes (:func:`profileopt.planning.refine.refine_segments`). The peers
    run this too, so that every solver gets the same boundaries and caps (issue 14: "the
    identical problem")."""
    seg = segment_route(route, vehicle, SEGMENT_LENGTH_M)
    if not DEFAULT_REFINE:
        return seg
    other = _other_caps(route, seg, vehicle)
    cap, _, upper_b, _ = _segment_caps(seg, vehicle, other)
    marked = at_force_cap(_exact_b(seg, upper_b, vehicle), cap, other)
    return refine_segments(seg, route.s_m, vehicle, marked)


def convex_caps(route_path: Path, vehicle) -> ConvexProblem:
    """Segment the route as the planner does and compute the caps of the convex subset and
    its exact optimum (not timed)."""
    route = read_route(route_path)
    seg = planner_segments(route, vehicle)
    cap, boundary_cap, upper_b, single = _segment_caps(seg, vehicle, _other_caps(route, seg, vehicle))
    exact_b = _exact_b(seg, upper_b, vehicle)
    return ConvexProblem(seg.boundaries_m, seg.length_m, seg.ri, seg.e_max_m, cap, boundary_cap, upper_b,
                         exact_b, travel_time_s(exact_b, seg.length_m), single)


def violation(speed_mps: np.ndarray, accel_mps2: np.ndarray, problem: ConvexProblem, vehicle,
              jerk_mps3: float = math.inf, force_ratio: np.ndarray | None = None) -> float:
    """Largest relative violation of the caps, acceleration bounds, jerk and force (0 if none).

    Checked independently of every solver, on its boundary speeds alone: speed^2 against
    the per-boundary cap^2 (relative to v_max^2), the constant acceleration of each segment
    from the speeds at its ends against [-decel, accel], the jerk of profileopt's model
    v_j (a_j - a_{j-1}) / mean(ds) at interior boundaries
    (:func:`profileopt.core.kinematics.boundary_jerk_mps3`) against the bound, force_n /
    force_limit_n against 1.
    """
    b = speed_mps**2
    worst = [float(np.max(b - problem.boundary_cap_mps**2)) / vehicle.max_speed_mps**2]
    a = np.diff(b) / (2.0 * problem.length_m)
    worst.append(float(np.max(a - vehicle.max_accel_mps2)) / vehicle.max_accel_mps2)
    worst.append(float(np.max(-vehicle.max_decel_mps2 - a)) / vehicle.max_decel_mps2)
    if math.isfinite(jerk_mps3):
        jerk = boundary_jerk_mps3(speed_mps[1:-1], a[:-1], a[1:], problem.length_m[:-1], problem.length_m[1:])
        worst.append(float(np.max(np.abs(jerk)) - jerk_mps3) / jerk_mps3)
    if force_ratio is not None:
        worst.append(float(np.max(force_ratio)) - 1.0)
    del accel_mps2  # recomputed from the speeds, which define the profile
    return max(max(worst), 0.0)


# ---------------------------------------------------------------------------------------
# What is timed


def clear_caches() -> None:
    """Forget everything profileopt caches, as a fresh process would not have it."""
    for name, module in list(sys.modules.items()):
        if name == "profileopt" or name.startswith("profileopt."):
            for value in vars(module).values():
                if callable(getattr(value, "cache_clear", None)) and hasattr(value, "cache_info"):
                    value.cache_clear()


@dataclasses.dataclass
class Run:
    """One timed run: wall seconds end to end and of the optimiser, and what it produced."""

    end_to_end_s: float
    optimiser_s: float = math.nan
    build_s: float = math.nan
    iterations: int | None = None
    pieces: int | None = None
    travel_time_s: float = math.nan
    status: str = ""
    output: Path | None = None
    speed_mps: np.ndarray | None = None
    force_ratio: np.ndarray | None = None
    stages_s: dict[str, float] = dataclasses.field(default_factory=dict)


def run_plan(route_path: Path, out_path: Path, vehicle, **options) -> Run:
    """read_route -> plan -> write_profile, as ``profileopt plan route.csv -o out.csv`` does."""
    start = time.perf_counter()
    profile = plan(read_route(route_path), vehicle, segment_length_m=SEGMENT_LENGTH_M, model=MODEL, **options)
    write_profile(profile, out_path)
    wall = time.perf_counter() - start
    t = profile.timings_s
    optimiser = sum(t.get(k, 0.0) for k in ("choose", "build", "solve"))
    stages = {k: t.get(k, 0.0) for k in STAGES[1:]}
    stages[STAGES[0]] = wall - t.get("total", math.nan)
    return Run(wall, optimiser, t.get("build", math.nan), profile.iterations, profile.pieces or None,
               profile.travel_time_s, profile.status, out_path, stages_s=stages)


#: The benchmark's vehicle file, written in the work folder: the bundled atv without the
#: optional keys of turns and hills, so the acceleration bounds are the level ones that
#: TOPP-RA and COPP are given (the peers' convex subset is then the same problem).
LEVEL_VEHICLE_FILE = "atv-level.toml"

# (and the turning circle, which needs a lateral limit: the vehicle file would be refused without it)
_TURN_AND_HILL_KEYS = (*OPTIONAL_KEYS, "min_turn_radius_m")


def level_atv():
    """The bundled atv without the keys of turns and hills."""
    return load_vehicle("atv").replace(**{key: None for key in _TURN_AND_HILL_KEYS})


def write_level_atv(path: Path) -> None:
    """The bundled atv's file without the keys of turns and hills."""
    source = Path(load_vehicle("atv").name).read_text(encoding="utf-8").splitlines()
    kept = [line for line in source if line.split("=")[0].strip() not in _TURN_AND_HILL_KEYS]
    path.write_text("\n".join(kept) + "\n", encoding="utf-8")


def run_cli(route_path: Path, out_path: Path, vehicle_path: Path) -> Run:
    """``python -m profileopt plan route.csv --vehicle V.toml -o out.csv`` in a fresh process."""
    start = time.perf_counter()
    # --max-memory inf: the 100,000-segment route's estimate is above the 1.5 GB default (the
    # benchmark measures time on a machine with the memory; a user's run is refused in one line)
    done = subprocess.run([sys.executable, "-m", "profileopt", "plan", str(route_path), "--vehicle", str(vehicle_path),
                           "-o", str(out_path), "--max-memory", "inf"], capture_output=True, text=True, check=False)
    wall = time.perf_counter() - start
    if done.returncode != 0:
        raise RuntimeError(f"profileopt plan failed ({done.returncode}): {done.stderr.strip()}")
    return Run(wall, status="exit 0", output=out_path)


def solve_toppra(problem: ConvexProblem, vehicle) -> tuple[np.ndarray, str]:
    """TOPP-RA on the convex subset; returns the boundary speeds (m/s) and its return code."""
    import toppra
    import toppra.algorithm
    import toppra.constraint

    grid = problem.boundaries_m
    index = {float(s): i for i, s in enumerate(grid)}
    cap = problem.boundary_cap_mps

    def velocity_limits(s: float) -> np.ndarray:
        c = cap[index[float(s)]]  # called at the grid points only (and at s = grid[0])
        return np.array([[-c, c]])

    # p(s) = s: a cubic spline through two points of a straight line is that line.
    path = toppra.SplineInterpolator([grid[0], grid[-1]], [[grid[0]], [grid[-1]]])
    constraints = [
        toppra.constraint.JointVelocityConstraintVarying(velocity_limits),
        # p'' = 0, so collocation and interpolation impose the same bound on u_i.
        toppra.constraint.JointAccelerationConstraint(
            np.array([[-vehicle.max_decel_mps2, vehicle.max_accel_mps2]]),
            discretization_scheme=toppra.constraint.DiscretizationType.Collocation),
    ]
    algorithm = toppra.algorithm.TOPPRA(constraints, path, gridpoints=grid, solver_wrapper="seidel")
    _, sd, _ = algorithm.compute_parameterization(0.0, 0.0)
    code = str(algorithm.problem_data.return_code).split(".")[-1]
    if sd is None:
        return np.full(grid.size, np.nan), code
    return np.asarray(sd, dtype=float), code


def _copp_robot(problem: ConvexProblem, vehicle, jerk_mps3: float):
    """COPP's constraint buffer for the path p(s) = s on the segment boundaries.

    Stations are the boundaries (shifted to start at 0); dp/ds = 1 and the higher
    derivatives are 0, so COPP's axial velocity, acceleration and jerk are ds/dt, d2s/dt2
    and d3s/dt3, in m/s, m/s^2 and m/s^3 because s is arc length. Velocity bound at each
    station: the smaller cap of the segments meeting there (as TOPP-RA's); acceleration
    bounds [-max_decel, max_accel] at every station; jerk bounds +-jerk_mps3 if finite.
    """
    import copp_py as copp

    s = problem.boundaries_m - problem.boundaries_m[0]
    n = s.size
    robot = copp.Robot(1, capacity=n)
    robot.append_s(s)
    ones, zeros = np.ones((n, 1)), np.zeros((n, 1))
    robot.set_q(s[:, None].copy(), ones, zeros, 0, dddq=zeros if math.isfinite(jerk_mps3) else None)
    cap = problem.boundary_cap_mps[:, None].copy()
    robot.add_velocity_limits(cap, -cap, start_idx_s=0, length=n)
    robot.add_acceleration_limits(np.array([vehicle.max_accel_mps2]), np.array([-vehicle.max_decel_mps2]),
                                  start_idx_s=0, length=n)
    if math.isfinite(jerk_mps3):
        robot.add_jerk_limits(np.array([jerk_mps3]), np.array([-jerk_mps3]), start_idx_s=0, length=n)
    return robot


def solve_copp_topp2(problem: ConvexProblem, vehicle) -> tuple[np.ndarray, str, int | None]:
    """COPP's TOPP2-RA on the convex subset: boundary speeds (m/s), status, iterations (none).

    TOPP2 has a = sdot^2 at the stations and one path acceleration
    b_k = (a_{k+1} - a_k) / (2 ds_k) per interval, bounded at both its stations: the
    planner's b = v^2 and constant acceleration per segment, so the optimum is the same.
    """
    import copp_py as copp

    robot = _copp_robot(problem, vehicle, math.inf)
    n = problem.boundaries_m.size
    topp2 = copp.solver.topp2_ra.Problem(robot.constraints, idx_s_interval=(0, n - 1), a_boundary=(0.0, 0.0))
    a = copp.solver.topp2_ra.solve(topp2)
    return np.sqrt(np.maximum(np.asarray(a, dtype=float), 0.0)), "ok", None


def solve_copp_topp3(problem: ConvexProblem, vehicle) -> tuple[np.ndarray, str, int | None]:
    """COPP's TOPP3-LP on the jerk-limited problem: boundary speeds (m/s), status, iterations.

    COPP's documented pattern: TOPP2-RA (caps and acceleration, no jerk) gives the profile
    ``a_linearization`` at which TOPP3's jerk rows are linearised, then one TOPP3-LP solve
    (Clarabel, COPP's default options). TOPP3's unknowns are a = sdot^2 and b = sddot at
    the stations, with c = (b_{k+1} - b_k) / ds_k constant on each interval (b linear in s,
    a_{k+1} - a_k = ds_k (b_k + b_{k+1})) and jerk sqrt(a_k) c bounded at both stations of
    every interval. Its stations are the boundaries, so its speeds need no resampling.
    v0 = vend = 0 with zero acceleration there (``b_boundary``), one stationary interval
    at each end (``num_stationary_max=1``, COPP's recommended setting for a = b = 0).
    """
    import copp_py as copp

    robot = _copp_robot(problem, vehicle, vehicle.max_jerk_mps3)
    n = problem.boundaries_m.size
    topp2 = copp.solver.topp2_ra.Problem(robot.constraints, idx_s_interval=(0, n - 1), a_boundary=(0.0, 0.0))
    a_lin = copp.solver.topp2_ra.solve(topp2)
    topp3 = copp.solver.topp3_lp.Problem(robot.constraints, a_lin, idx_s_start=0, a_boundary=(0.0, 0.0),
                                         b_boundary=(0.0, 0.0), num_stationary_max=1)
    result = copp.solver.topp3_lp.solve_expert(topp3)
    status = str(result.solver_status).split(".")[-1]
    if result.profile is None:
        return np.full(n, np.nan), status, int(result.iterations)
    a = np.asarray(result.profile.a, dtype=float)
    return np.sqrt(np.maximum(a, 0.0)), status, int(result.iterations)


def solve_toppra_peer(problem: ConvexProblem, vehicle) -> tuple[np.ndarray, str, int | None]:
    """:func:`solve_toppra` in the shape :func:`run_peer` takes."""
    speed, code = solve_toppra(problem, vehicle)
    return speed, code, None


def run_peer(route_path: Path, out_path: Path, vehicle,
             solver: Callable[[ConvexProblem, object], tuple[np.ndarray, str, int | None]], label: str) -> Run:
    """The planner's pipeline with a peer as the solver: read, segment (refined as the planner
    does: :func:`planner_segments`), bands, solve, write.

    ``solver(problem, vehicle)`` returns the boundary speeds (m/s), a status and its
    iteration count (or None); ``label`` names it in the profile's status and settings.
    """
    start = time.perf_counter()
    route = read_route(route_path)
    seg = planner_segments(route, vehicle)
    cap, boundary_cap, _, _ = _segment_caps(seg, vehicle, _other_caps(route, seg, vehicle))
    problem = ConvexProblem(seg.boundaries_m, seg.length_m, seg.ri, seg.e_max_m, cap, boundary_cap,
                            np.empty(0), np.empty(0), math.nan, True)
    t = time.perf_counter()
    speed, code, iterations = solver(problem, vehicle)
    optimiser = time.perf_counter() - t
    accel = np.diff(speed**2) / (2.0 * seg.length_m)
    time_s = np.concatenate([[0.0], np.cumsum(2.0 * seg.length_m / (speed[:-1] + speed[1:]))])
    model = get_model(MODEL)
    # single band [0, cap]: the largest force inside a segment is at its larger end speed
    force = np.asarray(model.force_n(np.maximum(speed[:-1], speed[1:]), seg.ri, vehicle), dtype=float)
    limit = model.limit_n(vehicle)

    def per_row(x: np.ndarray) -> np.ndarray:
        return np.append(x, x[-1])

    profile = Profile(s_m=seg.boundaries_m, speed_mps=speed, accel_mps2=per_row(accel), time_s=time_s,
                      ri=per_row(seg.ri), e_max_m=per_row(seg.e_max_m), force_n=per_row(force),
                      force_limit_n=np.full(speed.size, limit), model=MODEL,
                      status=f"{label} {code}", settings={"solver": label, "model": MODEL})
    write_profile(profile, out_path)
    wall = time.perf_counter() - start
    return Run(wall, optimiser, iterations=iterations, travel_time_s=float(time_s[-1]), status=code,
               output=out_path, speed_mps=speed, force_ratio=force / limit)


def run_toppra(route_path: Path, out_path: Path, vehicle) -> Run:
    """The planner's pipeline with TOPP-RA as the solver (:func:`run_peer`)."""
    return run_peer(route_path, out_path, vehicle, solve_toppra_peer, "toppra")


# ---------------------------------------------------------------------------------------
# The table


@dataclasses.dataclass
class Row:
    """The repeats of one method on one size, summarised."""

    segments: int  # asked for: the route cut every SEGMENT_LENGTH_M
    problem: str
    method: str
    runs: list[Run]
    exact_time_s: float
    planned: int = 0  # solved on, after refining (planner_segments)
    violation: float = math.nan
    note: str = ""
    ratio_e2e: float | None = None
    ratio_opt: float | None = None
    target: str = ""
    met: str = ""

    @property
    def e2e(self) -> float:
        return statistics.median(r.end_to_end_s for r in self.runs)

    @property
    def optimiser(self) -> float:
        return statistics.median(r.optimiser_s for r in self.runs)

    @property
    def build(self) -> float:
        return statistics.median(r.build_s for r in self.runs)

    @property
    def travel(self) -> float:
        return self.runs[-1].travel_time_s

    @property
    def gap(self) -> float:
        return self.travel / self.exact_time_s - 1.0


def _seconds(x: float) -> str:
    if not math.isfinite(x):
        return "–"
    return f"{x:.3g}" if x < 100 else f"{x:.0f}"


def _spread(row: Row) -> str:
    times = [r.end_to_end_s for r in row.runs]
    if len(times) == 1:
        return _seconds(times[0])
    return f"{_seconds(row.e2e)} ({_seconds(min(times))}–{_seconds(max(times))})"


def _gap(row: Row) -> str:
    if not math.isfinite(row.travel):
        return "–"
    g = row.gap
    return "0" if g == 0 else f"{g:+.2e}"


def _ratio(x: float | None) -> str:
    if x is None or not math.isfinite(x):
        return ""
    return f"{x:.2g}" if x < 0.1 else f"{x:.2f}"


HEADER = ("segments", "problem", "method", "end to end (s)", "optimiser (s)", "NLP build (s)", "iterations",
          "NLP pieces",
          "travel time (s)", "vs exact optimum", "worst violation", "ours/peer e2e", "ours/peer optimiser",
          "target", "met?")


def _segments(row: Row) -> str:
    """Segments asked for, and planned on where refining added some."""
    if row.planned and row.planned != row.segments:
        return f"{row.segments:,} (refined: {row.planned:,})"
    return f"{row.segments:,}"


def markdown_table(rows: list[Row]) -> str:
    lines = ["| " + " | ".join(HEADER) + " |", "|" + "|".join("---" for _ in HEADER) + "|"]
    for row in rows:
        iters = [r.iterations for r in row.runs if r.iterations]
        pieces = [r.pieces for r in row.runs if r.pieces]
        cells = (
            _segments(row), row.problem, row.method + (f" ({row.note})" if row.note else ""), _spread(row),
            _seconds(row.optimiser), _seconds(row.build), str(iters[-1]) if iters else "",
            str(pieces[-1]) if pieces else "",
            f"{row.travel:.6g}" if math.isfinite(row.travel) else "–", _gap(row),
            f"{row.violation:.1e}" if math.isfinite(row.violation) else "–",
            _ratio(row.ratio_e2e), _ratio(row.ratio_opt), row.target, row.met,
        )
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


#: Stages of ``plan`` in the second table: everything outside ``plan`` (reading the CSV,
#: writing the profile), then ``Profile.timings_s`` keys (``simulate``: the simulation gate).
STAGES = ("read + write", "segment", "path", "bands", "choose", "refine", "build", "solve", "simulate")


def stages_table(rows: list[Row]) -> str:
    """Where the end-to-end time of each in-process ``plan`` row goes (medians, s)."""
    header = ("segments", "problem", "method", *STAGES, "rest of plan (assembly)")
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    for row in rows:
        if not row.runs[0].stages_s:
            continue
        medians = {k: statistics.median(r.stages_s[k] for r in row.runs) for k in STAGES}
        rest = statistics.median(r.end_to_end_s - sum(r.stages_s.values()) for r in row.runs)
        cells = (_segments(row), row.problem, row.method, *(_seconds(medians[k]) for k in STAGES),
                 _seconds(rest))
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


# ---------------------------------------------------------------------------------------
# Driver


def _versions() -> str:
    names = ("numpy", "scipy", "casadi", "toppra", "copp-py")
    found = []
    for name in names:
        try:
            found.append(f"{name} {importlib.metadata.version(name)}")
        except importlib.metadata.PackageNotFoundError:
            found.append(f"{name} missing")
    return f"python {platform.python_version()}, " + ", ".join(found)


def _machine() -> str:
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    nproc = subprocess.run(["nproc"], capture_output=True, text=True, check=False).stdout.strip() or os.cpu_count()
    return f"{cpu}; nproc {nproc}; {platform.system()} {platform.release()}"


def _commit() -> str:
    """The commit of the checkout the imported ``profileopt`` comes from (not this script's)."""
    checkout = Path(profileopt.__file__).resolve().parent.parent

    def git(*args: str) -> str:
        return subprocess.run(["git", *args], cwd=checkout, capture_output=True, text=True, check=False).stdout.strip()

    head = git("rev-parse", "--short", "HEAD")
    if not head:
        return f"{checkout} (not a git checkout)"
    dirty = git("status", "--porcelain", "--", "profileopt")
    return f"commit {head}" + (" with uncommitted changes in profileopt/" if dirty else "")


def _timed(label: str, fn: Callable[[], Run]) -> Run:
    clear_caches()
    gc.collect()
    run = fn()
    print(f"  {label}: {run.end_to_end_s:.3f} s", file=sys.stderr, flush=True)
    return run


#: The default back end's rows and the opt-in back ends' (issue 28).
DEFAULT_FULL = "plan (IPOPT, default)"
BANDED = SolverOptions(nlp_solver="banded")
FATROP = SolverOptions(nlp_solver="fatrop")


def bench_size(n: int, repeats: int, workdir: Path, vehicle, spacing_m: float, seed: int, cli: bool,
               fatrop: bool = False) -> list[Row]:
    route_path = workdir / f"route_{n}.csv"
    t = time.perf_counter()
    samples = write_route(route_path, n, spacing_m, seed)
    print(f"N = {n:,}: route of {samples:,} samples written in {time.perf_counter() - t:.1f} s", file=sys.stderr)
    problem = convex_caps(route_path, vehicle)
    asked = segment_route(read_route(route_path), vehicle, SEGMENT_LENGTH_M).count
    if asked != n:
        raise RuntimeError(f"expected {n} segments, the route has {asked}")
    planned = problem.length_m.size
    print(f"N = {n:,}: {planned:,} segments planned (refine={DEFAULT_REFINE})", file=sys.stderr)
    has_method = "method" in inspect.signature(plan).parameters

    full = {"smoothing": DEFAULT_SMOOTHING, "max_jerk_mps3": None}
    convex = {"smoothing": 0.0, "max_jerk_mps3": math.inf}
    cases: dict[tuple[str, str], Callable[[], Run]] = {
        ("full", DEFAULT_FULL): lambda: run_plan(route_path, workdir / "full.csv", vehicle, **full),
        ("full", "plan (banded)"): lambda: run_plan(route_path, workdir / "full-banded.csv", vehicle,
                                                    solver_options=BANDED, **full),
    }
    if cli:
        cases[("full", "`profileopt plan` CLI process")] = lambda: run_cli(route_path, workdir / "cli.csv",
                                                                        workdir / LEVEL_VEHICLE_FILE)
    if has_method:
        cases[("convex", "plan auto (exact FB)")] = lambda: run_plan(
            route_path, workdir / "auto.csv", vehicle, method="auto", **convex)
        cases[("convex", "plan NLP (forced)")] = lambda: run_plan(
            route_path, workdir / "ipopt.csv", vehicle, method="nlp", **convex)
    else:
        cases[("convex", "plan (no `method` keyword: auto only)")] = lambda: run_plan(
            route_path, workdir / "auto.csv", vehicle, **convex)
    cases[("convex", "TOPP-RA (seidel)")] = lambda: run_toppra(route_path, workdir / "toppra.csv", vehicle)
    cases[("convex", "COPP TOPP2-RA")] = lambda: run_peer(
        route_path, workdir / "copp2.csv", vehicle, solve_copp_topp2, "copp topp2_ra")
    # the jerk-limited problem: caps, acceleration and the vehicle's jerk bound, minimum time
    cases[("jerk", "plan (IPOPT, default, smoothing 0)")] = lambda: run_plan(
        route_path, workdir / "jerk.csv", vehicle, smoothing=0.0, max_jerk_mps3=None)
    cases[("jerk", "plan (banded, smoothing 0)")] = lambda: run_plan(
        route_path, workdir / "jerk-banded.csv", vehicle, smoothing=0.0, max_jerk_mps3=None, solver_options=BANDED)
    if fatrop:
        cases[("jerk", "plan (FATROP, smoothing 0)")] = lambda: run_plan(
            route_path, workdir / "jerk-fatrop.csv", vehicle, smoothing=0.0, max_jerk_mps3=None,
            solver_options=FATROP)
    cases[("jerk", "COPP TOPP3-LP")] = lambda: run_peer(
        route_path, workdir / "copp3.csv", vehicle, solve_copp_topp3, "copp topp3_lp")

    runs: dict[tuple[str, str], list[Run]] = {key: [] for key in cases}
    for r in range(repeats):  # interleaved, so that a noisy minute hits every method alike
        for key, fn in cases.items():
            runs[key].append(_timed(f"repeat {r + 1}/{repeats} {key[0]} {key[1]}", fn))

    rows = []
    for (kind, method), measured in runs.items():
        row = Row(n, kind, method, measured, problem.exact_time_s, planned=planned)
        last = measured[-1]
        jerk = vehicle.max_jerk_mps3 if kind in ("full", "jerk") else math.inf
        if last.speed_mps is not None:  # a peer: check its speeds directly, as they left the solver
            row.violation = violation(last.speed_mps, None, problem, vehicle, jerk, last.force_ratio)
        else:
            written = read_profile(last.output)
            if not np.array_equal(written.s_m, problem.boundaries_m):
                raise RuntimeError(f"{method}: the plan's boundaries are not the peers' (planner_segments)")
            if not math.isfinite(row.travel):
                row.runs[-1].travel_time_s = written.travel_time_s
            row.violation = violation(written.speed_mps, written.accel_mps2, problem, vehicle, jerk,
                                      written.force_n / written.force_limit_n)
        if not problem.single_band:
            row.note = "caps are not the whole force constraint: some segment has several bands"
        rows.append(row)
    return rows


@dataclasses.dataclass
class Scaling:
    """The full problem at 10,000 and 100,000 segments, run in alternating pairs."""

    small_s: list[float]
    large_s: list[float]

    @property
    def ratio(self) -> float:
        """Median of the large runs over median of the small ones."""
        return statistics.median(self.large_s) / statistics.median(self.small_s)

    def line(self) -> str:
        return (f"Scaling, measured in {len(self.small_s)} alternating pairs after the table (10,000 then 100,000 "
                f"segments, then 100,000 then 10,000, ...; the full problem in process, as the rows above): "
                f"medians {statistics.median(self.small_s):.3g} s and {statistics.median(self.large_s):.3g} s, "
                f"ratio {self.ratio:.1f} (target ≤ {SCALING_TARGET:g}: {'met' if self.ratio <= SCALING_TARGET else 'not met'}); "
                f"the pairs' own ratios {min(b / a for a, b in zip(self.small_s, self.large_s)):.1f}-"
                f"{max(b / a for a, b in zip(self.small_s, self.large_s)):.1f}.")


#: Alternating pairs for the scaling ratio, at least: on the shared 2-core machine single
#: pairs ranged from 6.6 to 11.0 within minutes (2026-11-27), and three pairs' median moved by
#: 10 % between runs of the same code, as much as the target's margin.
SCALING_PAIRS = 7


def paired_scaling(workdir: Path, vehicle, repeats: int) -> Scaling:
    """The 100,000/10,000 ratio measured side by side: the two sizes' blocks of the table run
    minutes apart, and on a shared machine a slow minute for the larger block (whose working
    set leaves the cache, so it suffers more from a busy neighbour) moved that ratio by more
    than 20 % between runs. Here each repeat runs both, in alternating order."""
    full = {"smoothing": DEFAULT_SMOOTHING, "max_jerk_mps3": None}
    small, large = [], []
    for r in range(repeats):
        order = (10_000, 100_000) if r % 2 == 0 else (100_000, 10_000)
        for n in order:
            run = _timed(f"pair {r + 1}/{repeats} full plan (IPOPT, default) at {n:,}",
                         lambda n=n: run_plan(workdir / f"route_{n}.csv", workdir / f"pair_{n}.csv", vehicle, **full))
            (small if n == 10_000 else large).append(run.end_to_end_s)
    return Scaling(small, large)


def judge(rows: list[Row], scaling: "Scaling | None" = None) -> None:
    """Fill the ratio, target and met? columns.

    Issue 3's targets (convex subset against TOPP-RA, full problem under 1 s at 10,000
    segments) and issue 14's (jerk-limited problem against COPP TOPP3-LP, the command line
    against TOPP-RA in process, 100,000 segments against 10,000); issue 14's are judged at
    the sizes it names, the ratios are shown at every size. The 100,000/10,000 target is
    judged on ``scaling`` (alternating pairs) when it was measured, else on the two rows.
    """
    by = {(r.segments, r.problem, r.method): r for r in rows}
    full10k = next((r for r in rows if r.segments == 10_000 and r.method == DEFAULT_FULL), None)
    for row in rows:
        toppra = by.get((row.segments, "convex", "TOPP-RA (seidel)"))
        copp3 = by.get((row.segments, "jerk", "COPP TOPP3-LP"))
        if row.problem == "convex" and row.method.startswith(("TOPP-RA", "COPP")):
            row.target = "reference" if row.method.startswith("TOPP-RA") else "peer (info)"
        elif row.problem == "convex":
            if toppra is not None:
                row.ratio_e2e = row.e2e / toppra.e2e
                row.ratio_opt = row.optimiser / toppra.optimiser
            row.target = f"optimiser ≤ TOPP-RA's, gap ≤ {GAP_TARGET:g}"
            if row.ratio_opt is not None:
                ok = row.ratio_opt <= 1.0 and abs(row.gap) <= GAP_TARGET and row.violation <= 1e-6
                row.met = f"{'yes' if ok else 'no'}; e2e ≤ TOPP-RA's: {'yes' if row.ratio_e2e <= 1.0 else 'no'}"
        elif row.problem == "jerk" and row.method.startswith("COPP"):
            row.target = "reference (peer)"
        elif row.problem == "jerk":
            if copp3 is not None:
                row.ratio_e2e = row.e2e / copp3.e2e
                row.ratio_opt = row.optimiser / copp3.optimiser
                row.target = f"optimiser ≤ {JERK_TARGET:g} × COPP TOPP3-LP's, travel time ≤ COPP's"
                if row.segments != 10_000:
                    row.target += " (judged at 10,000)"
                else:
                    no_worse = row.travel <= copp3.travel and row.violation <= 1e-6
                    ok = row.ratio_opt <= JERK_TARGET and no_worse
                    row.met = (f"{'yes' if ok else 'no'} (time: {'yes' if row.ratio_opt <= JERK_TARGET else 'no'}, "
                               f"travel time {row.travel / copp3.travel - 1.0:+.2%} vs COPP's); e2e ≤ {JERK_TARGET:g} × COPP's: "
                               f"{'yes' if row.ratio_e2e <= JERK_TARGET else 'no'}")
            _two_times_rule(row, by)
        elif row.method.startswith("`profileopt plan`"):
            if toppra is not None:
                row.ratio_e2e = row.e2e / toppra.e2e
                row.ratio_opt = row.e2e / toppra.optimiser  # the process against compute_parameterization
                row.target = (f"e2e ≤ {CLI_TARGET:g} × TOPP-RA's compute_parameterization (convex, in process; "
                              f"the optimiser column's ratio); e2e against TOPP-RA's whole script: info")
                if row.segments != 10_000:
                    row.target += " (judged at 10,000)"
                else:
                    row.met = (f"{'yes' if row.ratio_opt <= CLI_TARGET else 'no'} ({row.ratio_opt:.1f}×; "
                               f"{row.ratio_e2e:.1f}× the whole script)")
            else:
                row.target = "info (adds start-up, imports, summary)"
        elif row.method == "plan (banded)":
            _two_times_rule(row, by)
        elif row.method == DEFAULT_FULL:
            if row.segments == 10_000:
                row.target = f"< {FULL_TARGET_S:g} s e2e"
                row.met = "yes" if row.e2e < FULL_TARGET_S and row.violation <= 1e-6 else "no"
            elif row.segments == 100_000 and scaling is not None:
                row.target = f"≤ {SCALING_TARGET:g} × 10k, in alternating pairs (below the table)"
                row.met = (f"{'yes' if scaling.ratio <= SCALING_TARGET else 'no'} (pairs: {scaling.ratio:.1f}×; "
                           f"these rows: {row.e2e / full10k.e2e:.1f}×)" if full10k is not None else "")
            elif row.segments == 100_000 and full10k is not None:
                limit = SCALING_TARGET * full10k.e2e
                row.target = f"< {SCALING_TARGET:g} × 10k = {limit:.3g} s"
                row.met = f"{'yes' if row.e2e < limit else 'no'} ({row.e2e / full10k.e2e:.1f}×)"


def _two_times_rule(row: Row, by: dict) -> None:
    """Issue 28's rule for the banded back end: kept (opt-in) only if at least 2 times as fast
    as IPOPT, the best ecosystem back end, on the same problem with the same optimum."""
    if "banded" not in row.method:
        return
    ipopt = by.get((row.segments, row.problem, DEFAULT_FULL if row.problem == "full"
                    else "plan (IPOPT, default, smoothing 0)"))
    if ipopt is None:
        return
    speedup = ipopt.e2e / row.e2e
    rule = f"banded kept if ≥ 2 × faster than IPOPT: {speedup:.1f}× (optimiser {ipopt.optimiser / row.optimiser:.1f}×)"
    rule += f", travel time {row.travel / ipopt.travel - 1.0:+.1e} vs IPOPT's"
    row.met = f"{row.met}; {rule}" if row.met else rule
    if not row.target:
        row.target = "the 2× rule (issue 28)"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sizes", nargs="+", default=["1000", "10000", "100000"],
                        help="numbers of 5 m segments (space- or comma-separated; default 1000 10000 100000)")
    parser.add_argument("--repeats", type=int, default=5, help="timed runs of each method per size (default 5)")
    parser.add_argument("--out", type=Path, default=None,
                        help="also write the table to this Markdown file (default: stdout only; the "
                             "committed table is benchmarks/results.md, written only when named)")
    parser.add_argument("--spacing", type=float, default=0.5, help="route sample spacing in m (default 0.5)")
    parser.add_argument("--seed", type=int, default=8608, help="seed of the synthetic routes (default 8608)")
    parser.add_argument("--no-cli", action="store_true", help="skip the command-line process row")
    parser.add_argument("--fatrop", action="store_true",
                        help="add FATROP's jerk-limited row (slow: CasADi's FATROP interface; see the docs' solver page)")
    parser.add_argument("--pairs", type=int, default=SCALING_PAIRS,
                        help=f"alternating 10,000/100,000 pairs for the scaling ratio (default {SCALING_PAIRS})")
    args = parser.parse_args(argv)
    print(compile_package(), file=sys.stderr)
    sizes = [int(x) for item in args.sizes for x in item.split(",") if x]
    if args.repeats < 1 or any(n < 2 for n in sizes):
        parser.error("--repeats must be >= 1 and every size >= 2")
    if SEGMENT_LENGTH_M / args.spacing < 8:
        parser.error("--spacing must give every 5 m segment at least 8 samples (<= 0.625 m)")

    vehicle = level_atv()
    started = time.strftime("%Y-%m-%d %H:%M %Z")
    commit = _commit()  # at the start: the code the run imports, whatever is committed meanwhile
    load_before = os.getloadavg()
    rows: list[Row] = []
    with tempfile.TemporaryDirectory(prefix="bench_plan_") as tmp:
        workdir = Path(tmp)
        write_level_atv(workdir / LEVEL_VEHICLE_FILE)
        # warm-up: load the IPOPT plugin, TOPP-RA's and COPP's modules once, outside every timing
        bench_size(200, 1, workdir, vehicle, args.spacing, args.seed, cli=False)
        for n in sizes:
            rows += bench_size(n, args.repeats, workdir, vehicle, args.spacing, args.seed, cli=not args.no_cli,
                               fatrop=args.fatrop)
        scaling = (paired_scaling(workdir, vehicle, args.pairs)
                   if {10_000, 100_000} <= set(sizes) else None)
    judge(rows, scaling)
    load_after = os.getloadavg()

    header = "\n".join([
        f"Run {started} on {_machine()}.",
        f"{_versions()}; profileopt at {commit}.",
        f"Medians of {args.repeats} cold repeats per method (min–max in brackets), interleaved; load average "
        f"{load_before[0]:.2f} before, {load_after[0]:.2f} after. Vehicle atv without the keys of turns and "
        f"hills (the peers' problem: acceleration bounds without grade), model {MODEL}, "
        f"{SEGMENT_LENGTH_M:g} m segments, route samples every {args.spacing:g} m, seed {args.seed}.",
    ])
    text = (header + "\n\n" + markdown_table(rows) + "\n\nWhere the time of each in-process `plan` run goes "
            "(medians, s; `read + write` is everything outside `plan`, i.e. `read_route` and `write_profile`):\n\n"
            + stages_table(rows) + "\n" + ("\n" + scaling.line() + "\n" if scaling is not None else ""))
    print(text)
    if args.out is not None:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(text, encoding="utf-8")
        print(f"wrote {args.out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
