"""Library messages in the command line's words (profileopt.cli.messages; issue 30 item 17):
the flags, never the library's parameter names or Python's keyword syntax."""

from __future__ import annotations

import pytest

from profileopt.cli import main
from profileopt.cli.messages import flags_for_parameters

from conftest import ROUTES

CURB = str(ROUTES / "curb.csv")


def test_keyword_arguments_and_parameters_become_flags() -> None:
    assert flags_for_parameters("keep_contact applies to the dynamic model (model='dynamic'), not SBEM:TF") == \
        "--keep-contact applies to the dynamic model (--model dynamic), not SBEM:TF"
    assert flags_for_parameters("force_margin = 0.5 applies to the dynamic model (model='dynamic')") == \
        "--force-margin = 0.5 applies to the dynamic model (--model dynamic)"
    # a quoted name is a file's key, and a plain word stays a word
    assert flags_for_parameters("key 'force_margin' of the vehicle; the model is right") == \
        "key 'force_margin' of the vehicle; the model is right"


@pytest.mark.parametrize("option, words", [
    (["--keep-contact"], "error: --keep-contact applies to the dynamic model (--model dynamic), not SBEM:TF"),
    (["--force-margin", "0.5"], "error: --force-margin = 0.5 applies to the dynamic model (--model dynamic)"),
])
def test_plan_names_the_flags_of_the_dynamic_model(option: list[str], words: str,
                                                   capsys: pytest.CaptureFixture) -> None:
    assert main(["plan", CURB, *option]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and words in err, err
    assert "keep_contact" not in err and "force_margin" not in err and "model='" not in err
