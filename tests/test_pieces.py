"""Solving a long route's NLP in pieces (profileopt._pieces, planner._solve_pieces).

The reference for every piecewise profile is the same NLP solved whole by IPOPT (an
independent computation: one KKT system over all segments, no cuts, no padding), and every
profile is checked against every limit by ``check_profile``. The cut check itself is
compared with IPOPT's own bound multipliers of the whole solve.
"""

from __future__ import annotations

import numpy as np
import pytest

import profileopt.planner as planner
from profileopt import _pieces, load_vehicle, plan
from profileopt.route import Route, read_route
from profileopt.synthetic import iso8608_sections
from test_planner import ROUTES, check_profile


@pytest.fixture(scope="module")
def atv():
    return load_vehicle("atv")


@pytest.fixture(scope="module")
def iso_route() -> Route:
    """3 km whose ISO 8608 class changes B-D-C-E-B: 600 segments of 5 m."""
    sections = [("B", 600.0), ("D", 800.0), ("C", 600.0), ("E", 400.0), ("B", 600.0)]
    profile = iso8608_sections(sections, 0.5, 11, n_max_cpm=0.9)
    return Route(profile.s_m, profile.z_m, source="iso")


def solve(monkeypatch, route, vehicle, piece_segments, **options):
    """plan() with routes of more than ``piece_segments`` segments cut into pieces that long."""
    monkeypatch.setattr(planner, "PIECE_SEGMENTS", piece_segments)
    monkeypatch.setattr(planner, "SPLIT_ABOVE_SEGMENTS", piece_segments)
    return plan(route, vehicle, **options)


def assert_same_optimum(split, whole) -> None:
    assert split.success and whole.success
    # IPOPT's tolerance (1e-10 on the scaled problem) and a flat optimum: 1e-7 is tight
    assert split.objective == pytest.approx(whole.objective, rel=1e-7)
    np.testing.assert_allclose(split.speed_mps, whole.speed_mps, rtol=0, atol=2e-3)


@pytest.mark.parametrize("name, vehicle_name, piece_segments, options", [
    ("iso", "atv", 150, {}),
    ("iso", "atv", 150, {"max_jerk_mps3": float("inf")}),  # smoothing only: no jerk rows
    ("iso", "atv", 150, {"smoothing": 0.0, "method": "ipopt"}),  # jerk bound only
    ("trail.csv", "atv", 200, {}),
    ("krc_rms_2in.csv", "atv", 50, {}),  # measured ride course (real ground)
    ("iri_road.csv", "atv", 60, {}),  # measured road profile
    ("washboard.csv", "atv-resonant", 60, {}),  # above-resonance bands: lower bounds too
])
def test_pieces_give_the_optimum_of_the_whole_route(monkeypatch, iso_route, name, vehicle_name, piece_segments,
                                                    options):
    route = iso_route if name == "iso" else read_route(ROUTES / name)
    vehicle = load_vehicle(vehicle_name)
    whole = solve(monkeypatch, route, vehicle, 10**9, **options)
    split = solve(monkeypatch, route, vehicle, piece_segments, **options)
    assert whole.pieces == 1 and split.pieces >= 2  # it was really cut
    assert_same_optimum(split, whole)
    check_profile(split, route, vehicle, jerk=options.get("max_jerk_mps3"))


def test_cut_check_reproduces_ipopts_bound_multipliers(monkeypatch, iso_route, atv):
    """At pinned pairs of the whole solve, cut_multipliers on the whole solve's multipliers
    gives IPOPT's own multipliers of those bounds (lam_x = -(grad f + J^T lam_g))."""
    calls = []
    original = planner._ipopt

    def spy(nlp, *args):
        calls.append((nlp, args))
        return original(nlp, *args)

    monkeypatch.setattr(planner, "_ipopt", spy)
    solve(monkeypatch, iso_route, atv, 10**9)
    (nlp, (x0, lbx, ubx, length, lbg, ubg, p_tail)), = calls
    result = nlp.solver(x0=x0, lbx=lbx, ubx=ubx, lbg=lbg, ubg=ubg, p=np.concatenate([length, p_tail]))
    y, lam_x, lam_g = (np.asarray(result[k]).ravel() for k in ("x", "lam_x", "lam_g"))
    n = length.size
    # upper bounds IPOPT holds active (interior point: y within ~1e-8 of them, lam_x > 0)
    at_cap = (ubx - y <= 1e-6) & (lam_x > 1e-8)
    pinned = np.flatnonzero(at_cap[:-1] & at_cap[1:] & (np.arange(n) >= 2) & (np.arange(n) < n - 3))
    assert pinned.size >= 20
    lam_jerk = np.zeros(n + 1)
    lam_jerk[1:n] = lam_g[n:]
    check = planner._build_nlp(5, True).solver
    got, scale = _pieces.cut_multipliers(check.get_function("nlp_grad_f"), check.get_function("nlp_jac_g"), y,
                                         p_tail, length, lam_g[:n], lam_jerk, pinned)
    expected = np.stack([lam_x[pinned], lam_x[pinned + 1]], axis=1)
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-7 * scale.max())


# Unforced, the cuts at 150 segments a piece fall at 124, 268, 379 and 528. A wrong first
# cut (in 112..149) is replaced between its neighbours (and the second, chosen after it and
# also wrong, likewise, until none is left there and the cuts are chosen again); a wrong
# third one (in 380..417) has no other candidate between its neighbours, so the cuts from
# there on are chosen again at once.
@pytest.mark.parametrize("first, end", [(112, 150), (380, 418)])
def test_a_wrong_cut_is_found_and_replaced(monkeypatch, iso_route, atv, first, end):
    """Force a cut onto a segment the optimum does not drive at its cap: the check must
    reject it, other cuts must be tried, and the result must still be the optimum."""
    whole = solve(monkeypatch, iso_route, atv, 10**9)
    cap = whole.band_upper_mps
    below = np.flatnonzero(np.maximum(whole.speed_mps[:-1], whole.speed_mps[1:]) < cap * (1 - 1e-3))
    wrong = int(below[(below >= first) & (below < end)][0])
    original = planner.cut_scores

    def scores(*args):
        score = original(*args)
        score[wrong] = -1.0  # the best-looking candidate
        return score

    replaced = []
    original_replace = planner.replace_cut

    def replace(score, cuts, index, piece_segments, excluded):
        replaced.append(int(cuts[index]))
        return original_replace(score, cuts, index, piece_segments, excluded)

    monkeypatch.setattr(planner, "cut_scores", scores)
    monkeypatch.setattr(planner, "replace_cut", replace)
    split = solve(monkeypatch, iso_route, atv, 150)
    assert replaced[0] == wrong  # (its replacement may be rejected in turn)
    assert split.pieces >= 2
    assert_same_optimum(split, whole)
    check_profile(split, iso_route, atv)


def test_when_no_cut_checks_out_the_route_is_solved_whole(monkeypatch, iso_route, atv):
    whole = solve(monkeypatch, iso_route, atv, 10**9)
    v, cap = whole.speed_mps, whole.band_upper_mps
    below = np.maximum(v[:-1], v[1:]) < cap * (1 - 1e-3)

    def scores(*args):  # only wrong candidates
        return np.where(below & (np.arange(below.size) >= _pieces.CUT_REACH)
                        & (np.arange(below.size) < below.size - _pieces.CUT_REACH - 1), 1.0, np.inf)

    monkeypatch.setattr(planner, "cut_scores", scores)
    split = solve(monkeypatch, iso_route, atv, 150)
    assert split.pieces == 1
    assert split.objective == whole.objective  # the same whole solve
    assert split.iterations > whole.iterations  # after the pieces that did not check out


def test_choose_cuts_keeps_pieces_within_size():
    rng = np.random.default_rng(3)
    n, w, reach = 5000, 300, _pieces.CUT_REACH
    score = np.where(rng.random(n) < 0.05, rng.random(n), np.inf)
    score[:reach] = score[n - reach - 1:] = np.inf
    cuts = _pieces.choose_cuts(score, w)
    pieces = _pieces.piece_bounds(cuts, n)
    assert pieces[0][0] == 0 and pieces[-1][1] == n
    assert all(first < last and last - first <= w for first, last in pieces)
    assert all(b[0] == a[1] - 1 for a, b in zip(pieces, pieces[1:]))  # neighbours share the fixed pair
    assert np.all(np.isfinite(score[cuts])) and np.all(np.diff(cuts) >= reach)
    # a short route is one piece; a stretch without candidates longer than a piece, none
    assert _pieces.choose_cuts(score[:w], w).size == 0
    score[1000:1000 + w] = np.inf
    assert _pieces.choose_cuts(score, w).size == 0


def test_summary_and_command_report_the_pieces(monkeypatch, capsys):
    from profileopt import cli

    profile = solve(monkeypatch, read_route(ROUTES / "trail.csv"), load_vehicle("atv"), 200)
    assert profile.pieces == 3  # 400 segments, cut at segments 118 and 256
    assert planner.summarize(profile)["solver"]["pieces"] == 3
    assert cli.main(["plan", str(ROUTES / "trail.csv"), "--vehicle", "atv"]) == 0
    assert "IPOPT iterations over 3 pieces" in capsys.readouterr().out
