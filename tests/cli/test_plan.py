"""``profileopt plan``'s choice of solver (profileopt.cli.plan): --solver and the summary's solver block."""

from __future__ import annotations

import json

import pytest

from profileopt import cli

from conftest import ROUTES


@pytest.mark.parametrize("solver", ["ipopt", "fatrop", "banded"])
def test_the_solver_block_names_the_back_end_that_made_the_plan(solver: str, capsys) -> None:
    assert cli.main(["plan", str(ROUTES / "curb.csv"), "--solver", solver, "--json", "--quiet"]) == 0
    block = json.loads(capsys.readouterr().out)["solver"]
    assert block["status"] == "optimal" and block["iterations"] > 0
    # FATROP or the banded method, or IPOPT where one of them stopped (then it says so)
    assert block["backend"] == solver or block["backend"].startswith(f"ipopt (the {solver} solver stopped")


def test_the_default_solver_is_ipopt_and_the_summary_line_says_so(capsys) -> None:
    assert cli.main(["plan", str(ROUTES / "curb.csv")]) == 0
    line = next(line for line in capsys.readouterr().out.splitlines() if line.strip().startswith("solver"))
    assert "optimal (ipopt, " in line and "NLP iterations" in line


def test_the_exact_profile_names_no_back_end(capsys) -> None:
    # smoothing and jerk off: the forward-backward profile is the optimum, no NLP is solved
    assert cli.main(["plan", str(ROUTES / "curb.csv"), "--smoothing", "0", "--max-jerk", "inf", "--json"]) == 0
    block = json.loads(capsys.readouterr().out)["solver"]
    assert block["status"] == "exact" and block["backend"] is None and block["iterations"] == 0


def test_an_unknown_solver_is_one_line_naming_the_choices(capsys) -> None:
    with pytest.raises(SystemExit) as exit_info:
        cli.main(["plan", str(ROUTES / "curb.csv"), "--solver", "mumps"])
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    assert "--solver" in err and "ipopt" in err and "fatrop" in err and "banded" in err
    assert "Traceback" not in err
