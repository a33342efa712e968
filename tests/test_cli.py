"""The command line: help everywhere, the main job, info, one-line errors."""

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from conftest import random_exponential_model
from translucency import load_model, save_model
from translucency.cli.app import app

runner = CliRunner()


@pytest.mark.parametrize("args", [["--help"], ["demo", "--help"], ["info", "--help"], ["materials", "--help"]])
def test_help(args):
    res = runner.invoke(app, args)
    assert res.exit_code == 0
    assert "Usage" in res.output


def test_help_lists_commands():
    out = runner.invoke(app, ["--help"]).output
    for cmd in ("demo", "info", "materials"):
        assert cmd in out


def test_info_on_valid_model(tmp_path, rng):
    path = save_model(random_exponential_model(rng, n_points=5, m=8), tmp_path / "m.model.zip", dtype="float16")
    res = runner.invoke(app, ["info", str(path)])
    assert res.exit_code == 0, res.output
    assert "exponential" in res.output and "float16" in res.output and "yes" in res.output
    assert f"{path.stat().st_size:,} bytes" in res.output


def test_info_on_garbage_is_one_line(tmp_path):
    bad = tmp_path / "junk.model.zip"
    bad.write_bytes(b"\x00" * 100)
    res = runner.invoke(app, ["info", str(bad)])
    assert res.exit_code == 2
    lines = [ln for ln in res.output.strip().splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("error:") and "junk.model.zip" in res.output.replace("\n", "")
    assert "Traceback" not in res.output


def test_demo_writes_real_outputs(tmp_path):
    res = runner.invoke(app, ["demo", "--out", str(tmp_path)])
    assert res.exit_code == 0, res.output
    png = (tmp_path / "baselines.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 50_000
    summary = json.loads((tmp_path / "baselines.json").read_text())["materials"]
    assert len(summary) == 12
    # the 3-term fit follows the dipole far better than the 2-exponential Burley shape
    for name, row in summary.items():
        assert max(row["exp_fit_rel_rms_vs_dipole"]) < 0.15, name
        assert np.mean(row["exp_fit_rel_rms_vs_dipole"]) < np.mean(row["burley_fit_rel_rms_vs_dipole"]), name
    model = load_model(tmp_path / "dipole_fits.model.zip")
    assert model.n_points == 12 and model.colour == "per-channel"
    assert not [p for p in tmp_path.iterdir() if ".tmp-" in p.name]
