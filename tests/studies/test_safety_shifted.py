"""The safety study's criterion for SBEM:TF (issue 10) on the example's whole route set: 14
routes, each also shifted by 1/4, 1/2 and 3/4 of a segment, both vehicles (112 pairs). Apart
from test_safety.py (the four models on the unshifted routes) so that the two studies, about
a minute and a half each on one core, run on two workers side by side."""

from __future__ import annotations

import pytest

from profileopt import load_vehicle
from profileopt.studies.safety import SafetyStudy, safety_study

from conftest import ROOT, load_script, window_sets


@pytest.fixture(scope="module")
def example():
    return load_script(ROOT / "examples" / "safety_study.py", "safety_study_example")


@pytest.fixture(scope="module")
def tf_study(example) -> SafetyStudy:
    """SBEM:TF, both vehicles, the example's whole route set (as example.run_study plans it)."""
    return safety_study(example.route_set(), [load_vehicle(name) for name in example.VEHICLES], models=["sbem_tf"],
                        segment_length_m=example.SEGMENT_LENGTH_M)


@pytest.mark.slow(seconds=110)  # the study: 112 plans and simulations
def test_sbem_tf_keeps_every_window_within_the_limit_in_simulation(example, tf_study: SafetyStudy) -> None:
    # Issue 10 ("Done when") asks for 0 windows over the limit in simulation. Measured with
    # `python examples/safety_study.py` (2026-11-26, refined segments and the step limit, the
    # defaults; the simulator on the wheel's exact path): SBEM:TF drives 1009280 windows on
    # the 112 route-vehicle pairs and none is over the limit; the worst is 0.98 of it (the
    # 0.05 m kerbs and krc_rms_1in.csv with atv-resonant). Without the step limit 400 were
    # over, by at most 1 %, all where the wheel lands after curb.csv's 0.15 m drop
    # (README, safety study); with it the curb's worst window is 0.94.
    tf = tf_study.total("sbem_tf")
    assert tf.infeasible_runs == 0 and tf.runs == 112
    assert tf.windows_over == 0 and tf.runs_window_over == 0 and tf.worst_window_ratio < 1.0
    assert all(run.windows_over == 0 for run in tf_study.runs if run.model == "sbem_tf")
    # the step limit holds the speed somewhere only where the ground has a step: the drop of
    # curb.csv (a plan of another route is the same with and without it, README)
    curb = [r for r in tf_study.runs if r.model == "sbem_tf" and example.base_name(r.route) == "curb.csv"
            and r.vehicle == "atv-resonant"]
    assert curb and max(r.worst_window_ratio for r in curb) < 0.96
    # the windows counted are every window of every route: each distinct set of samples a
    # 5 m window holds at any offset (issue 29; on these routes, 5 cm apart, two per sample
    # with room: the window starting at it and the one starting just after the sample
    # before), counted here from the offsets themselves (conftest.window_sets)
    expected = 0
    for route in example.route_set():
        expected += 2 * int(window_sets(route.s_m, 5.0)[0].size)  # two vehicles
    assert tf.windows == expected
