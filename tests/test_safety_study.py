"""The safety study (profileopt.study, examples/safety_study.py) on its fixed, seeded route set.

The study is run once for the module (about 12 s on 2 cores: 26 route-vehicle pairs, four
models each). It holds the SBEM:TF figure at what was measured (a regression test: the
study is deterministic, so the count of segments over the limit is an exact integer), and
checks the paper's qualitative claim on the whole set: Prev:BEM is aggressive, IECM less,
the SBEM models are (nearly) safe. The bookkeeping is checked against independent
recomputations: the pooled totals against sums over the runs, the planner's infeasibility
verdicts against the force at standstill, the exceedances on the curb against the route's
construction.
"""

from __future__ import annotations

import importlib.util
import math
import sys
from pathlib import Path

import numpy as np
import pytest

from profileopt import force_n, get_model, load_vehicle
from profileopt.planning import segment_route
from profileopt.study import INFEASIBLE, SafetyStudy

from conftest import ROOT

EXAMPLE = ROOT / "examples" / "safety_study.py"


def _load_example():
    spec = importlib.util.spec_from_file_location("safety_study_example", EXAMPLE)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses and pickling look modules up by name
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def example():
    return _load_example()


@pytest.fixture(scope="module")
def study(example) -> SafetyStudy:
    return example.run_study()


def test_sbem_tf_pooled_fraction_is_what_was_measured(study: SafetyStudy) -> None:
    # Measured on 2026-11-23 with `python examples/safety_study.py`, after the simulator
    # learned the wheel's exact path between samples (profileopt.wheel_path: the kinks of
    # the path are no longer smoothed by an interpolation through its heights at the
    # samples): SBEM:TF plans drive 2634 segments on the 26 route-vehicle pairs, and the
    # simulated transmitted force exceeds the limit in 4 of them, all at curb.csv's step
    # (0.15 m between samples 5 cm apart: a ramp of slope 3 whose foot the wheel meets with
    # a kink of slope 3, a jump of c v 3 in F_T): up (100-105 m) 1.042 (atv) and 1.021
    # (atv-resonant), down (150-155 m) 1.077 and 1.297. These depend on the sampling of
    # the step (README, "How a result on steps depends on the sampling"). Off the curb the
    # largest ratio is 0.955 (krc_rms_1in.csv, atv-resonant). (Before, with the path
    # interpolated through its heights at the samples: 0 segments, worst 0.861; with
    # circles on the samples alone: 3 segments.)
    tf = study.total("sbem_tf")
    assert (tf.over_count, tf.segments) == (4, 2634)
    assert tf.infeasible_runs == 0 and tf.runs == 26
    assert tf.worst_ratio < 1.35
    where = sorted((Path(r.route).name, r.vehicle, e.s_start_m)
                   for r in study.runs if r.model == "sbem_tf" for e in r.exceedances)
    assert where == [("curb.csv", "atv", 100.0), ("curb.csv", "atv", 150.0),
                     ("curb.csv", "atv-resonant", 100.0), ("curb.csv", "atv-resonant", 150.0)]
    off_the_curb = [r.worst_ratio for r in study.runs
                    if r.model == "sbem_tf" and r.planned and Path(r.route).name != "curb.csv"]
    assert max(off_the_curb) < 0.97


def test_the_paper_claim_holds_on_the_pooled_set(study: SafetyStudy) -> None:
    fraction = {t.model: t.over_fraction for t in study.totals}
    # Prev:BEM is the most aggressive, then IECM, then SBEM:EF (the paper's Figs. 5 and 6)
    assert fraction["prev_bem"] >= fraction["iecm"] >= fraction["sbem_ef"]
    assert fraction["prev_bem"] > 10 * fraction["sbem_tf"]
    # and SBEM:TF is rarely exceeded: fewer than 1 segment in 200
    assert fraction["sbem_tf"] < 0.005
    # the same order on the pairs every model can drive (the same segments for each)
    common = {t.model: t for t in study.totals_where_all_planned()}
    assert len({t.segments for t in common.values()}) == 1
    assert common["prev_bem"].over_fraction >= common["iecm"].over_fraction >= common["sbem_ef"].over_fraction
    assert common["sbem_tf"].over_fraction < 0.005
    # the price: Prev:BEM is the fastest and SBEM:TF the slowest on average
    times = {t.model: t.mean_time_ratio for t in study.totals}
    assert times["sbem_tf"] == 1.0
    assert times["prev_bem"] < times["iecm"] < 1.0 and times["sbem_ef"] < 1.0


def test_totals_are_the_sums_of_the_runs(study: SafetyStudy) -> None:
    assert len(study.pairs()) == 26 and len(study.runs) == 26 * 4
    for total in study.totals:
        runs = [r for r in study.runs if r.model == total.model]
        planned = [r for r in runs if r.planned]
        assert total.runs == len(runs) and total.infeasible_runs == len(runs) - len(planned)
        assert total.segments == sum(r.segments for r in planned)
        assert total.over_count == sum(len(r.exceedances) for r in planned)
        assert total.worst_ratio == max(r.worst_ratio for r in planned)
        assert total.runs_over == sum(1 for r in planned if r.exceedances)
    for run in study.runs:
        if run.planned:
            assert run.over_count == len(run.exceedances)
            assert all(e.ratio > 1.0 and e.s_start_m <= e.peak_s_m <= e.s_end_m for e in run.exceedances)
            assert (run.over_count > 0) == (run.worst_ratio > 1.0)
        else:
            assert run.travel_time_s is None and run.over_fraction is None and not run.exceedances
            assert run.to_dict()["status"].startswith("infeasible: ")


def test_infeasible_exactly_where_a_segment_is_over_the_limit_at_standstill(example, study: SafetyStudy) -> None:
    # IECM and SBEM:EF predict k e_max > 0 even at speed 0 (Eq. 11 at V = 0), so a segment
    # with k * 4.7534 * RI * h above the limit cannot be driven at any speed; Prev:BEM and
    # SBEM:TF (F_T -> 0 as V -> 0) can always creep. Recomputed here from each segment's RI,
    # independently of the planner's own infeasibility test.
    vehicles = {name: load_vehicle(name) for name in example.VEHICLES}
    routes = {r.source: r for r in example.route_set()}
    for run in study.runs:
        vehicle = vehicles[run.vehicle]
        ri = segment_route(routes[run.route], vehicle, study.segment_length_m).ri
        model = get_model(run.model)
        stuck = bool(np.any(force_n(0.0, vehicle, ri=ri, model=run.model) > model.limit_n(vehicle)))
        assert (run.outcome == INFEASIBLE) == stuck, (run.route, run.vehicle, run.model)
    assert sum(run.outcome == INFEASIBLE for run in study.runs) == 6


def test_curb_exceedances_are_at_the_edges(study: SafetyStudy) -> None:
    # curb.csv (examples/routes/make_routes.py): 0.15 m up at s = 102.5 m, down at 152.5 m.
    # Where a plan exceeds the limit there, the force peaks within a wheel radius or two of
    # an edge (the rigid wheel meets the ramp the samples make, 0.07 m before its foot).
    # With the wheel's exact path every model's plans exceed it there: 13 segments (Prev:BEM
    # and SBEM:TF 2 per vehicle, IECM 2 for atv, SBEM:EF 2 for atv and 1 for atv-resonant).
    edges = (102.5, 152.5)
    found = 0
    for run in study.runs:
        if Path(run.route).name == "curb.csv":
            for e in run.exceedances:
                edge = min(edges, key=lambda x: abs(e.peak_s_m - x))
                assert e.s_start_m < edge < e.s_end_m
                assert abs(e.peak_s_m - edge) < 0.25
                found += 1
                if run.model.startswith("sbem"):
                    # an SBEM plan is at the model's limit there: no margin left
                    assert math.isclose(e.predicted_n, e.limit_n, rel_tol=1e-6)
    assert found == 13


def test_example_prints_and_writes_the_same_markdown(example, study, tmp_path, monkeypatch, capsys) -> None:
    monkeypatch.setattr(example, "run_study", lambda: study)  # the study itself ran above
    out = tmp_path / "comparison.md"
    assert example.main(["--out", str(out)]) == 0
    printed = capsys.readouterr().out
    written = out.read_text()
    assert printed.startswith(written)  # then "wrote ..."
    assert "| SBEM:TF | 4 of 2634 (0.15 %) |" in written
    assert "`python examples/safety_study.py`" in written
    for label in ("Prev:BEM", "IECM", "SBEM:EF", "SBEM:TF"):
        assert f"| {label} |" in written
    assert written == example.report(study) + "\n"
    assert list(tmp_path.iterdir()) == [out]  # no temporary file left behind
