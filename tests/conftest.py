"""Shared fixtures and constants of the test suite.

Layout: the tests mirror the package, ``tests/<package>/test_<module>.py`` (``tests/core/``,
``tests/terrain/``, ``tests/physics/``, ``tests/planning/`` with ``nlp/``,
``tests/verification/``, ``tests/studies/``, ``tests/mpc/``, ``tests/io/``, ``tests/viz/``),
``tests/cli/`` the commands as a user runs them (bad input, outputs, the expected outputs
in ``tests/expected/``), and ``tests/`` itself the whole project (layout, docstrings,
examples, what a newcomer runs). The folders are not packages, so every test file has a
basename of its own.

Running (``[tool.pytest.ini_options]`` in pyproject.toml):

* ``python -m pytest -q`` runs the whole suite, on as many worker processes as the machine
  has cores (pytest-xdist, ``-n auto`` in ``addopts``; ``-n 0`` runs in this process, for a
  debugger or a single test);
* ``python -m pytest -m "not slow" -q`` leaves out the long tests: one to two minutes on 2 cores
  (the whole suite: 5 to 9 minutes; the safety study's two modules take about a minute and a half
  each on one worker);
* markers, registered with ``--strict-markers``: ``slow``, ``geo`` (needs the ``geo``
  extra), ``mpc`` (do-mpc and rockit), ``cc`` (compiles generated C); ``-m "not geo"`` and
  so on leave a group out.

Hypothesis profiles: ``dev`` (the default: few examples, quick), ``ci`` (as many, the same
examples every run, no example database) and ``thorough`` (2000 examples per property, a
long hunt), chosen with the option of hypothesis's pytest plugin, e.g.
``python -m pytest --hypothesis-profile thorough tests/planning/test_planner_properties.py``.
A test's own ``@settings`` sets only what the test needs (a deadline, a health check),
never the number of examples, so the profile decides it.

Paths: everything the tests read is inside the repository (``data/real/`` holds the measured
terrain, ``examples/routes/`` the bundled routes), so a fresh clone runs every test with
nothing beside it, wherever it is. Test modules that need a path at import time (in a
``parametrize`` list, say) import the constant (``from conftest import ROUTES``; the
``pythonpath`` option puts ``tests/`` on the path); tests use the fixtures. No test depends
on the clone's path or the terminal's width: children that print help get ``COLUMNS`` from
:data:`WIDE_TERMINAL`.
"""

from __future__ import annotations

import os

# CasADi's MUMPS runs on OpenBLAS, whose extra threads spin on the other core for no gain on
# these banded systems; the command line sets one thread (profileopt.cli.app.main), and so do
# the tests, whose two workers already use both cores (before CasADi is first loaded)
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import importlib.util
import math
import re
import sys
import types
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, settings

from profileopt import force_n, load_vehicle
from profileopt.core.vehicle import OPTIONAL_KEYS

# Hypothesis profiles (see the module's docstring); ``--hypothesis-profile NAME`` loads
# another after this file is read. No deadline: a plan's time depends on the machine.
_PATIENT = {"deadline": None, "suppress_health_check": [HealthCheck.too_slow]}
settings.register_profile("dev", max_examples=30, **_PATIENT)
settings.register_profile("ci", max_examples=30, derandomize=True, database=None, print_blob=True, **_PATIENT)
settings.register_profile("thorough", max_examples=2000, **_PATIENT)
settings.load_profile("dev")

#: the repository (this file is tests/conftest.py)
ROOT = Path(__file__).resolve().parents[1]
#: the bundled example routes
ROUTES = ROOT / "examples" / "routes"
#: the measured terrain bundled with the repository (sources and licences: data/README.md)
REAL_DATA = ROOT / "data" / "real"

#: the ``profileopt`` command, run by the interpreter that runs the tests (``python -m
#: profileopt`` is the console script's entry point, profileopt.cli:main)
PROFILEOPT = (sys.executable, "-m", "profileopt")

#: the documentation's sources (Markdown pages; the README is the front door)
DOCS = ROOT / "docs"


def markdown_pages() -> list[Path]:
    """The Markdown a user reads: README.md and the documentation's pages, not its build
    output (folders whose names start with ``_`` or ``.``, ``build``, generated API pages)."""
    skip = ("build", "generated")
    pages = [p for p in sorted(DOCS.rglob("*.md"))
             if not any(part.startswith(("_", ".")) or part in skip for part in p.relative_to(DOCS).parent.parts)]
    return [ROOT / "README.md", *pages]


def markdown_section(page: str, title: str) -> str:
    """The section of a Markdown page (``page``: its path from the repository's top, e.g.
    ``"docs/guide/mpc.md"``) whose heading starts with ``title``: its heading and everything
    up to the next heading of the same level or above. Lines inside code fences are never
    headings (a shell comment ``# ...``). Fails naming the page when no heading matches, so a
    test that reads a snippet says where it looked when the text has moved."""
    lines = (ROOT / page).read_text(encoding="utf-8").splitlines(keepends=True)
    fence = False
    start = level = None
    for i, line in enumerate(lines):
        if line.lstrip().startswith(("```", "~~~")):
            fence = not fence
            continue
        heading = None if fence else re.match(r"(#+) (.*)", line)
        if heading is None:
            continue
        if start is None and heading.group(2).startswith(title):
            start, level = i, len(heading.group(1))
        elif start is not None and len(heading.group(1)) <= level:
            return "".join(lines[start:i])
    if start is None:
        raise AssertionError(f"no heading starting {title!r} in {page}: has the text moved to another page?")
    return "".join(lines[start:])


def load_script(path: Path, name: str) -> types.ModuleType:
    """Import a script of the repository (an example, a benchmark) as module ``name``, once:
    it is registered in ``sys.modules`` under that name (its dataclasses and pickling look
    their module up there), and a second call returns the same module."""
    if name in sys.modules:
        return sys.modules[name]
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


#: the environment entries that make a child's terminal wide: argparse then wraps no help
#: line (a default may be a long absolute path, the clone's folder), so a test reads the
#: same help wherever the clone is and however wide the terminal it runs in
WIDE_TERMINAL = {"COLUMNS": "10000"}


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """The longest tests first: the files that hold a test marked ``slow(seconds=N)`` (about N
    seconds on one core) come first, the longest first, each file's tests together and in
    their order (so a module's fixture is still made once), then every other file as
    collected. With several workers the safety study (minutes) then starts at once while the
    others share the rest, rather than starting last and running alone at the end."""
    def seconds(item: pytest.Item) -> float:
        mark = item.get_closest_marker("slow")
        return float(mark.kwargs.get("seconds", 0)) if mark else 0.0

    longest: dict[Path, float] = {}
    for item in items:
        longest[item.path] = max(longest.get(item.path, 0.0), seconds(item))
    items.sort(key=lambda item: -longest[item.path])  # stable: the rest keep their order


@pytest.fixture(scope="session")
def atv():
    """The bundled ``atv`` (the paper's Table 1)."""
    return load_vehicle("atv")


@pytest.fixture(scope="session")
def atv_resonant():
    """The bundled ``atv-resonant`` (the lightly damped ATV of the paper's Fig. 6)."""
    return load_vehicle("atv-resonant")


@pytest.fixture(scope="session")
def profileopt_command() -> list[str]:
    """The argv prefix that runs the ``profileopt`` command: ``[*profileopt_command, "plan", ...]``."""
    return list(PROFILEOPT)


@pytest.fixture(scope="session")
def check_profile():
    """``check_profile(profile, route, vehicle, *, jerk=None, rtol=1e-6, grid=64, written=False)``: assert
    that a planned profile keeps every limit (see :func:`_check_profile`)."""
    return _check_profile


def _check_profile(profile, route, vehicle, *, jerk=None, rtol=1e-6, grid=64, written=False):
    """Assert that ``profile`` keeps every limit (independent of the planner's own check).

    An evaluation of every constraint written independently of the planner: speeds against
    the caps, accelerations recomputed from speed^2 differences, jerk v da/ds, and the
    model's force on a fine grid of the speeds each segment passes through.
    """
    s, v = profile.s_m, profile.speed_mps
    vmax = vehicle.max_speed_mps
    assert np.all(v >= 0) and np.all(v <= vmax * (1 + rtol))
    if route.speed_limit_mps is not None:
        # every sample inside a segment caps both of the segment's boundary speeds
        seg = np.searchsorted(s, route.s_m, side="right") - 1
        seg = np.clip(seg, 0, s.size - 2)
        cap = np.full(s.size - 1, np.inf)
        np.minimum.at(cap, seg, route.speed_limit_mps)
        assert np.all(np.maximum(v[:-1], v[1:]) <= cap * (1 + rtol))
    ds = np.diff(s)
    accel = (v[1:] ** 2 - v[:-1] ** 2) / (2 * ds)  # constant acceleration in s: v^2 linear
    # a profile read back from its CSV (written=True) has its columns to 9 significant digits
    # (profileopt.io.profiles.COLUMN_FORMATS): within 5e-9 of the planner's
    digits = 1e-8 if written else 1e-9
    np.testing.assert_allclose(profile.accel_mps2[:-1], accel, rtol=digits, atol=digits)
    check_turns_and_hills(profile, route, vehicle, accel, rtol)
    j_max = vehicle.max_jerk_mps3 if jerk is None else jerk
    if math.isfinite(j_max) and ds.size >= 2:
        jerk_values = v[1:-1] * np.diff(accel) / (0.5 * (ds[:-1] + ds[1:]))
        assert np.all(np.abs(jerk_values) <= j_max * (1 + rtol))
    # every roughness window again, from the route's own samples, and the speeds driven
    # inside it against its own RI (the definition of issue 10)
    window_m = float(profile.settings.get("roughness_window_m", 5.0))
    start_m, ri_w = window_ri(route, window_m, vehicle.ground_clearance_m)
    # a segment's ri column is the largest RI of the windows that share a point with it
    seg_lo = np.searchsorted(start_m, s[:-1] - window_m - 1e-9 * window_m, side="left")
    seg_hi = np.searchsorted(start_m, s[1:] + 1e-9 * window_m, side="right")
    ri_seg = np.array([ri_w[a:b].max() for a, b in zip(seg_lo, seg_hi)])
    # atol: prefix sums carry an absolute variance error of about 1e-16 times the mean
    # square of the block they run through (a flat window after rough ground: RI 7e-9 for 0
    # on krc_rms_2in.csv; 2e-7 for 0 on a plain 20 % climb 17 m high), 1e-6 RI being 0.1
    # micrometre of elevation at h = 0.1 m
    np.testing.assert_allclose(profile.ri[:-1], ri_seg, rtol=1e-6, atol=1e-6)
    v_lo, v_hi = window_speeds(s, v, start_m, window_m)
    frac = np.linspace(0.0, 1.0, grid)
    speeds = v_lo[:, None] + (v_hi - v_lo)[:, None] * frac[None, :]
    forces = force_n(speeds, vehicle, ri=np.broadcast_to(ri_w[:, None], speeds.shape), model=profile.model)
    limit = profile.force_limit_n[0]
    assert np.all(forces <= limit * (1 + rtol)), f"force ratio {forces.max() / limit} in a roughness window"
    # the reported force (the largest over the segment's windows) is within the limit
    assert np.all(profile.force_n <= limit * (1 + rtol))
    # time: dt = 2 ds / (v_i + v_{i+1}) for constant acceleration; time_s is a running sum,
    # so its differences carry an absolute rounding of a few eps times the total (6e-12
    # relative on a refined segment of 6 ms at the end of a 160 s route)
    # (written: each time rounded to 9 digits, a difference of two off by 1e-8 of the total)
    np.testing.assert_allclose(np.diff(profile.time_s), 2 * ds / (v[:-1] + v[1:]), rtol=1e-12,
                               atol=(1e-8 if written else 8 * np.finfo(float).eps) * float(profile.time_s[-1]))


G = 9.80665  # standard gravity (m/s^2), ISO 80000-3


def grade_direct(route, scale_m: float) -> np.ndarray:
    """Grade theta (rad) at every sample: atan of the slope of the least-squares line of z over
    the samples within scale_m / 2 of it (clipped at the route's ends), from each window's
    centred samples directly (chunked), independent of the package's prefix sums."""
    s, z = route.s_m, route.z_m
    first = np.searchsorted(s, s - scale_m / 2 - 1e-9, side="left")
    stop = np.searchsorted(s, s + scale_m / 2 + 1e-9, side="right")
    out = np.empty(s.size)
    width = int((stop - first).max())
    for lo in range(0, s.size, 4000):
        hi = min(lo + 4000, s.size)
        idx = first[lo:hi, None] + np.arange(width)[None, :]
        inside = idx < stop[lo:hi, None]
        idx = np.minimum(idx, s.size - 1)
        count = inside.sum(axis=1)
        ss, zz = np.where(inside, s[idx], 0.0), np.where(inside, z[idx], 0.0)
        sc = np.where(inside, ss - (ss.sum(axis=1) / count)[:, None], 0.0)
        zc = np.where(inside, zz - (zz.sum(axis=1) / count)[:, None], 0.0)
        out[lo:hi] = np.arctan((sc * zc).sum(axis=1) / (sc * sc).sum(axis=1))
    return out


def check_turns_and_hills(profile, route, vehicle, accel: np.ndarray, rtol: float) -> None:
    """Acceleration bounds (on grades, for a vehicle that gives any key of turns and hills),
    lateral acceleration, friction circle and drive power, at every speed and grade of every
    segment: the grade recomputed by :func:`grade_direct` over twice the roughness window, the
    curvature the plan's own (its estimate is tested in tests/terrain/test_geometry.py)."""
    s, v = profile.s_m, profile.speed_mps
    on_grades = any(getattr(vehicle, key) is not None for key in OPTIONAL_KEYS)  # any key of turns and hills
    n = s.size - 1
    lo = hi = np.zeros(n)
    if on_grades:
        window_m = float(profile.settings.get("roughness_window_m", 5.0))
        grade = grade_direct(route, 2 * window_m)
        first = np.maximum(np.searchsorted(route.s_m, s[:-1], side="left") - 1, 0)
        stop = np.minimum(np.searchsorted(route.s_m, s[1:], side="left") + 1, route.s_m.size)
        lo = np.array([grade[a:b].min() for a, b in zip(first, stop)])
        hi = np.array([grade[a:b].max() for a, b in zip(first, stop)])
    # a + g sin(theta) within [-max_decel, max_accel] at every grade of the segment
    scale = max(vehicle.max_accel_mps2, vehicle.max_decel_mps2)
    assert np.all(accel + G * np.sin(hi) <= vehicle.max_accel_mps2 + rtol * scale + 1e-9)
    assert np.all(-(accel + G * np.sin(lo)) <= vehicle.max_decel_mps2 + rtol * scale + 1e-9)
    top = np.maximum(v[:-1], v[1:])
    kappa = profile.path.curvature_max_1pm if profile.path is not None else np.zeros(n)
    lateral = top**2 * kappa
    a_lat = min(vehicle.max_lateral_accel_mps2 or math.inf,
                G * vehicle.track_width_m / (2 * vehicle.cg_height_m) if vehicle.track_width_m else math.inf)
    assert np.all(lateral <= a_lat * (1 + rtol))
    if vehicle.friction_coefficient is not None:
        for theta in (lo, hi):
            usage = ((accel + G * np.sin(theta)) ** 2 + lateral**2) / (vehicle.friction_coefficient * G * np.cos(theta)) ** 2
            assert np.all(usage <= 1 + 2 * rtol), usage.max()
    if vehicle.max_power_w is not None:
        power = vehicle.mass_kg * (accel + G * np.sin(hi)) * top
        assert np.all(power <= vehicle.max_power_w * (1 + rtol)), power.max() / vehicle.max_power_w


def window_sets(s: np.ndarray, window_m: float) -> tuple[np.ndarray, ...]:
    """Every distinct set of samples a roughness window [a, a + W] holds, at any offset a in
    [s_0, s_end - W] (issue 29), found from the offsets directly: the samples held change
    only where a or a + W passes a sample, so every set is held at one of the offsets a = a
    sample or a sample less W, or on an open interval between two consecutive ones (at its
    midpoint). A sample within 1e-9 W of an end counts as inside.

    Returns
    -------
    first, stop : numpy.ndarray of int, shape (K,)
        Each set is the samples ``first <= j < stop``; sorted, each once.
    a_lo, a_hi : numpy.ndarray, shape (K,)
        The least and the largest offset (m) holding it, or the ends of the open interval
        holding it (the windows there reach those ends' windows in the limit).
    """
    tol = 1e-9 * max(window_m, 1.0)
    width = min(window_m, float(s[-1] - s[0]))  # a route shorter than W is one window
    points = np.unique(np.clip(np.concatenate([s, s - width]), s[0], s[-1] - width))
    held_at = np.concatenate([points, 0.5 * (points[:-1] + points[1:])])
    lo = np.concatenate([points, points[:-1]])
    hi = np.concatenate([points, points[1:]])
    first = np.searchsorted(s, held_at - tol, side="left")
    stop = np.searchsorted(s, held_at + width + tol, side="right")
    keys, which = np.unique(first * (s.size + 1) + stop, return_inverse=True)
    a_lo, a_hi = np.full(keys.size, np.inf), np.full(keys.size, -np.inf)
    np.minimum.at(a_lo, which, lo)
    np.maximum.at(a_hi, which, hi)
    return keys // (s.size + 1), keys % (s.size + 1), a_lo, a_hi


def direct_ri(s: np.ndarray, z: np.ndarray, first: np.ndarray, stop: np.ndarray, clearance_m: float) -> np.ndarray:
    """Eq. (1) detrended of the samples ``first <= j < stop`` of each window, shape (K,):
    two passes over each window's centred samples (numpy.polyfit's normal equations),
    independent of the prefix sums the package uses; in chunks of windows."""
    out = np.empty(first.size)
    for c in range(0, first.size, 8192):
        f, t = first[c:c + 8192], stop[c:c + 8192]
        width = int((t - f).max())
        idx = np.minimum(f[:, None] + np.arange(width)[None, :], s.size - 1)
        inside = np.arange(width)[None, :] < (t - f)[:, None]
        count = inside.sum(axis=1)
        xs = np.where(inside, s[idx] - s[f][:, None], 0.0)
        zs = np.where(inside, z[idx] - z[f][:, None], 0.0)
        dx = np.where(inside, xs - (xs.sum(axis=1) / count)[:, None], 0.0)
        dz = np.where(inside, zs - (zs.sum(axis=1) / count)[:, None], 0.0)
        slope = (dx * dz).sum(axis=1) / (dx * dx).sum(axis=1)
        residual = np.where(inside, dz - slope[:, None] * dx, 0.0)
        out[c:c + 8192] = np.sqrt((residual**2).sum(axis=1) / count) / clearance_m
    return out


def window_ri(route, window_m: float, clearance_m: float) -> tuple[np.ndarray, np.ndarray]:
    """Start (m) and RI of roughness windows [a, a + W] that stand for every window at any
    offset (issue 29), shapes (K,), sorted by start: each set of :func:`window_sets` as the
    two windows at the ends a_lo and a_hi of the offsets holding it, both with its RI
    (:func:`direct_ri`). Every window holding the set lies in [a_lo, a_hi + W], which those
    two cover (a_hi - a_lo is below a sample spacing, less than W): the speeds driven in
    them are the speeds driven in the set's windows, to their limits. So a check over these
    windows is a check over every offset."""
    s, z = route.s_m, route.z_m
    first, stop, a_lo, a_hi = window_sets(s, window_m)
    ri = direct_ri(s, z, first, stop, clearance_m)
    starts = np.concatenate([a_lo, a_hi])
    order = np.argsort(starts, kind="stable")
    return starts[order], np.concatenate([ri, ri])[order]


def window_speeds(s: np.ndarray, v: np.ndarray, start_m: np.ndarray, window_m: float) -> tuple[np.ndarray, np.ndarray]:
    """Least and largest speed (m/s) driven inside each window [a, a + W], shape (K,): v^2
    is linear in s inside a segment (constant acceleration), so the extremes lie at the
    window's two ends or at a segment boundary inside it."""
    def speed_at(x: np.ndarray) -> np.ndarray:
        i = np.clip(np.searchsorted(s, x, side="right") - 1, 0, s.size - 2)
        t = np.clip((x - s[i]) / (s[i + 1] - s[i]), 0.0, 1.0)
        return np.sqrt(v[i] ** 2 + t * (v[i + 1] ** 2 - v[i] ** 2))

    ends = np.minimum(start_m + window_m, s[-1])
    lo, hi = speed_at(start_m), speed_at(ends)
    v_lo, v_hi = np.minimum(lo, hi), np.maximum(lo, hi)
    first = np.searchsorted(s, start_m, side="right")
    stop = np.searchsorted(s, ends, side="left")
    for k in np.flatnonzero(stop > first):
        inner = v[first[k]:stop[k]]
        v_lo[k], v_hi[k] = min(v_lo[k], inner.min()), max(v_hi[k], inner.max())
    return v_lo, v_hi
