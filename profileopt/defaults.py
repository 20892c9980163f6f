"""The defaults and choices the command line shows, importable without CasADi or SciPy.

They are defined here once; :mod:`profileopt.physics.forces` and :mod:`profileopt.planning` take
them from here, so ``profileopt --help`` needs none of the numerical packages.
"""

from __future__ import annotations

__all__ = ["MODEL_KEYS", "PLAN_MODEL_KEYS", "DEFAULT_MODEL", "DEFAULT_SMOOTHING", "DEFAULT_SEGMENT_LENGTH_M", "DEFAULT_REFINE", "DEFAULT_SIMULATION_GATE", "DEFAULT_ROUGHNESS_WINDOW_M",
           "DEFAULT_PATH_TOLERANCE_M", "MIN_PATH_TOLERANCE_M", "CRAWL_SPEED_MPS", "PLAN_BANDS", "PLAN_METHODS", "PLAN_SOLVERS", "MAX_C_BYTES", "DEFAULT_TRACK_SPACING_M",
           "DEFAULT_CORRIDOR_M", "DEFAULT_MAX_GAP_M", "MIN_POINTS_PER_BIN", "MAX_ROUGHNESS_SPACING_M",
           "MAX_ROUGHNESS_CORRIDOR_M", "LIMIT_RTOL"]

#: The four force models, in the paper's order (keys of :data:`profileopt.physics.forces.MODELS`).
MODEL_KEYS = ("prev_bem", "iecm", "sbem_ef", "sbem_tf")
#: What ``plan --model`` takes: the paper's four models, and ``"dynamic"``, the quarter car's
#: own response simulated on the route's samples (for offline plans over measured terrain;
#: :mod:`profileopt.planning.dynamic`).
PLAN_MODEL_KEYS = (*MODEL_KEYS, "dynamic")
#: The model used when none is named: SBEM:TF, the paper's transmitted-force model.
DEFAULT_MODEL = "sbem_tf"
#: Weight of the jerk term: objective = time + w * integral (jerk / (1 m/s^3))^2 dt, both in s.
DEFAULT_SMOOTHING = 0.01
#: Segment length (m) when none is given: the planning resolution (docs: guide/planning.md, "Choosing --segment-length").
DEFAULT_SEGMENT_LENGTH_M = 5.0
#: Whether a plan refines its segments when not told (:func:`profileopt.planning.plan`,
#: ``refine``): cut where the plan meets the force's speed cap and the roughness changes, so
#: that the travel time does not depend on the segment length (docs: guide/planning.md, "Choosing
#: --segment-length": refined, 1 m and 0.5 m agree within 0.1 % on every bundled route,
#: unrefined within 2.3 %).
DEFAULT_REFINE = True
#: Drive every plan in the exact simulation and cap where it goes over the force limit
#: (:mod:`profileopt.planning.gate`); off only for studies of the force models themselves.
DEFAULT_SIMULATION_GATE = True
#: Roughness window length W (m) when none is given: every stretch [a, a + W] of the route
#: is judged by its own RI (docs/paper-notes.md, "Roughness windows"); 5 m, the segment
#: length that the RI was measured over before windows.
DEFAULT_ROUGHNESS_WINDOW_M = 5.0
#: The path tolerance when none is given: ``None``, estimate it from the route's own x, y
#: (:func:`profileopt.terrain.geometry.estimate_path_noise`): the horizontal noise of its points,
#: times the largest a noise of that spread reaches over so many points, sqrt(2 ln n) (the
#: universal threshold), never below :data:`MIN_PATH_TOLERANCE_M`. ``--path-tolerance M``
#: gives it instead (docs: guide/turns-and-hills.md).
DEFAULT_PATH_TOLERANCE_M = None
#: The smallest path tolerance (m) an estimate gives, and the sharpest turn the path is read
#: to make (radius, m): how far the smoothed path whose curvature limits the speed in turns
#: may stray from a route's x, y samples (:func:`profileopt.terrain.geometry.smooth_path`) at
#: least. Wider than the noise of a path surveyed by RTK-GNSS or LiDAR (1 cm standard
#: deviation, about 4 cm at most over thousands of samples), well inside the path-tracking
#: error of an off-road vehicle (decimetres), so the smoothed path is one the vehicle can
#: follow. A consumer GPS track (metres of noise) gets an estimate of its own noise.
MIN_PATH_TOLERANCE_M = 0.1
#: Speed (m/s) at which a turn sharper than the vehicle's ``min_turn_radius_m`` is planned
#: (:func:`profileopt.physics.motion.turn_speed_cap_mps`): a slow walk, at which the vehicle
#: is taken through a turn it cannot make in one sweep (a reversal, a hairpin tighter than
#: its turning circle) in several moves, with a note naming where.
CRAWL_SPEED_MPS = 1.0
#: Spacing (m) of the route samples taken along a track over a terrain map
#: (:func:`profileopt.terrain.ground_track.route_from_track`): half the 0.1 m wheel radius of the
#: bundled vehicles. Eq. (2) saturates a step's width at the wheel radius r, so the force
#: models see no detail narrower than r; two samples per r resolve every feature they do
#: see (the KRC ride courses are measured at this spacing too). A vehicle with larger
#: wheels may use r / 2.
DEFAULT_TRACK_SPACING_M = 0.05
#: Half-width (m) of the strip around the wheel path whose ground points give each sample's
#: elevation: the strip (0.3 m) is about the width of one ATV tyre, the ground one tyre rolls
#: on. Its median moves with a rock under half the tyre, not with a stray point (noise, a
#: twig). A wider strip averages ground the tyre does not touch; a narrower one needs a
#: denser cloud (:data:`MIN_POINTS_PER_BIN`).
DEFAULT_CORRIDOR_M = 0.15
#: Longest run (m) of samples with no ground point that is filled by a straight line
#: (and reported); a longer one is refused with its position. Twice the bundled wheels'
#: radius: a hole shorter than the wheel's diameter cannot swallow the wheel.
DEFAULT_MAX_GAP_M = 0.2
#: Ground points a sample's bin must expect on average (density x strip width x spacing)
#: for the cloud to measure roughness: with Poisson-scattered points, 3 expected leave 5 %
#: of the bins empty (e^-3), which the gap filling bridges.
MIN_POINTS_PER_BIN = 3.0
#: Coarsest spacing (m) of a route sampled along a track that measures roughness: one sample
#: per wheel radius of the bundled vehicles (0.1 m). A coarser route misses bumps the wheel
#: feels, whatever the terrain's resolution, so its roughness must be assumed.
MAX_ROUGHNESS_SPACING_M = 0.1
#: Widest corridor half-width (m) that measures roughness: twice the default, a strip of about
#: two tyres' width. A wider strip's median is the ground beside the tyre as much as under it.
MAX_ROUGHNESS_CORRIDOR_M = 0.3
#: The values of :func:`profileopt.plan`'s ``band``: every band of each segment (chosen over
#: the whole route), only the band from rest, or only the highest band.
PLAN_BANDS = ("all", "first", "largest")
#: Methods of ``plan`` (``--method``): "auto" (the exact forward-backward profile where it is
#: optimal, else the NLP) and "nlp" (always the NLP, whichever solver solves it).
PLAN_METHODS = ("auto", "nlp")
#: The NLP's solver back ends (``--solver``, ``SolverOptions.nlp_solver``), the default first:
#: IPOPT, FATROP on the NLP's stage form, the banded interior point written here
#: (:mod:`profileopt.planning.nlp.backends`).
PLAN_SOLVERS = ("ipopt", "fatrop", "banded")
#: Largest C export written (bytes, estimated from
#: :data:`profileopt.mpc.codegen.C_BYTES_PER_STAGE` before any work): 64 MB is about 2700 stages
#: of all four models (11 s to generate), far beyond an MPC horizon; 100,000 stages would be
#: 2.4 GB written in minutes. Evaluate a longer horizon in pieces, or the vectorised Python
#: Functions of :mod:`profileopt.mpc.constraints`.
MAX_C_BYTES = 64_000_000
#: A profile keeps a limit when it exceeds it by at most this share of it: the tolerance of
#: the planner's own check of a solution (``SolverOptions.check_rtol``) and of ``verify``'s
#: check on paper, so a planned profile passes.
LIMIT_RTOL = 1e-6
