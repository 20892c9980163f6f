"""The paper's figures: the library's data, the `profileopt figures` command and the example."""

from __future__ import annotations

import csv
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from profileopt import allowable_speed, load_vehicle
from profileopt.viz.figures import figure_1, figure_5, figure_6, write_figure

from conftest import ROOT

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
EXPECTED_COLUMNS = {
    "fig1_ri_vs_amplitude": ["amplitude_m", "ri"],
    "fig5_allowable_speed": ["amplitude_m", "ri", "prev_bem_mps", "iecm_mps", "sbem_ef_mps", "sbem_tf_mps"],
    "fig6_resonance": ["amplitude_m", "ri", "sbem_ef_mps", "sbem_tf_largest_mps", "sbem_tf_first_mps"],
}


def read_csv(path: Path) -> tuple[list[str], np.ndarray]:
    with open(path, newline="", encoding="utf-8") as handle:
        rows = list(csv.reader(handle))
    return rows[0], np.array(rows[1:], dtype=float)


def check_outputs(out: Path) -> None:
    files = sorted(p.name for p in out.iterdir())
    assert files == sorted(f"{stem}.{ext}" for stem in EXPECTED_COLUMNS for ext in ("png", "csv"))  # no temp files
    for stem, columns in EXPECTED_COLUMNS.items():
        assert (out / f"{stem}.png").read_bytes()[:8] == PNG_MAGIC
        assert (out / f"{stem}.png").stat().st_size > 20_000
        header, table = read_csv(out / f"{stem}.csv")
        assert header == columns
        assert table.shape == (100, len(columns))
        assert np.all(np.isfinite(table))
        np.testing.assert_allclose(table[:, 0], np.linspace(0.0, 0.1, 100), rtol=1e-15)


@pytest.mark.slow
def test_cli_writes_three_pngs_and_three_csvs(profileopt_command, tmp_path):
    out = tmp_path / "new" / "figs"  # created, parents too
    result = subprocess.run(
        [*profileopt_command, "figures", "--out", str(out)], capture_output=True, text=True, timeout=120
    )
    assert result.returncode == 0, result.stderr
    # one line per file written, in plan's words ("wrote PATH")
    printed = result.stdout.splitlines()
    assert len(printed) == 6 and all(line.startswith("wrote ") for line in printed), printed
    assert all(Path(line.removeprefix("wrote ")).exists() for line in printed)
    check_outputs(out)
    # the speeds in the CSV are the library's
    header, table = read_csv(out / "fig6_resonance.csv")
    ri = table[:, header.index("ri")]
    np.testing.assert_allclose(
        table[:, header.index("sbem_tf_first_mps")], allowable_speed(ri, load_vehicle("atv-resonant"), model="sbem_tf", band="first"),
        rtol=1e-12,
    )


@pytest.mark.parametrize(
    "args, needle",
    [(["--vehicle", "tank"], "tank"), (["--resonant-vehicle", "nope.toml"], "nope.toml")],
)
def test_cli_bad_vehicle_is_one_line_exit_2(profileopt_command, tmp_path, args, needle):
    result = subprocess.run(
        [*profileopt_command, "figures", "--out", str(tmp_path / "f"), *args], capture_output=True, text=True, timeout=120
    )
    assert result.returncode == 2
    assert result.stderr.count("\n") == 1 and needle in result.stderr and "Traceback" not in result.stderr
    assert not (tmp_path / "f").exists() or not any((tmp_path / "f").iterdir())


def test_cli_out_is_a_file(profileopt_command, tmp_path):
    target = tmp_path / "taken"
    target.write_text("x")
    result = subprocess.run(
        [*profileopt_command, "figures", "--out", str(target)], capture_output=True, text=True, timeout=120
    )
    assert result.returncode == 2
    assert "not a folder" in result.stderr and result.stderr.count("\n") == 1


@pytest.mark.slow
def test_example_script_runs(tmp_path):
    out = tmp_path / "example"
    result = subprocess.run(
        [sys.executable, str(ROOT / "examples" / "paper_figures.py"), str(out)],
        capture_output=True, text=True, timeout=120, cwd=tmp_path, env={**os.environ, "MPLBACKEND": "Agg"},
    )
    assert result.returncode == 0, result.stderr
    check_outputs(out)


def test_figure_1_is_the_sampled_ri_of_sinusoids():
    data = figure_1()
    amplitude = data.curve("amplitude_m").values
    # Eq. (1) on whole periods of a sinusoid: RI = A / (sqrt(2) h), h = 0.1 m -> 0 .. 0.707
    np.testing.assert_allclose(data.curve("ri").values, amplitude / (math.sqrt(2) * 0.1), rtol=1e-12, atol=1e-15)
    assert "not reconstructed" in data.caption and "1 cycles/m" in data.caption


def test_figure_5_and_6_curves_are_the_library_speeds():
    atv, res = load_vehicle("atv"), load_vehicle("atv-resonant")
    fig5 = figure_5(atv)
    ri = fig5.x.values
    assert fig5.columns == tuple(EXPECTED_COLUMNS["fig5_allowable_speed"])
    for key in ("prev_bem", "iecm", "sbem_ef", "sbem_tf"):
        np.testing.assert_array_equal(fig5.curve(f"{key}_mps").values, allowable_speed(ri, atv, model=key))
    fig6 = figure_6(res)
    assert fig6.columns == tuple(EXPECTED_COLUMNS["fig6_resonance"])
    np.testing.assert_array_equal(
        fig6.curve("sbem_tf_largest_mps").values, allowable_speed(ri, res, model="sbem_tf", band="largest")
    )
    labels = " ".join(c.label for c in fig6.curves)
    assert '"first"' in labels and '"largest"' in labels
    with pytest.raises(KeyError, match="sbem_tf_first_mps"):
        fig6.curve("sbem_tf_mps")


def test_write_figure_needs_an_existing_folder(tmp_path):
    from profileopt import InputError

    with pytest.raises(InputError, match="does not exist"):
        write_figure(figure_1(np.linspace(0, 0.1, 5)), tmp_path / "missing")
