"""Held-out evaluation (issue 13, item 1): a model against an independent acquisition of the same points."""

import json

import numpy as np
from typer.testing import CliRunner

from translucency.cli.app import app

runner = CliRunner()


def _acquire(path, photons, seed):
    args = [
        "acquire",
        "planar",
        "--material",
        "marble",
        "--out",
        str(path),
        "--grid",
        "2",
        "--span",
        "2",
        "--photons",
        str(photons),
        "--seed",
        str(seed),
        "--size",
        "10",
        "10",
        "4",
        "--voxel",
        "0.5",
        "--window",
        "6",
        "--pitch",
        "0.25",
    ]
    res = runner.invoke(app, args)
    assert res.exit_code == 0, res.output
    return path


def test_evaluate_against_an_independent_truth(tmp_path):
    noisy = _acquire(tmp_path / "noisy.zarr", 3_000, seed=1)
    truth = _acquire(tmp_path / "truth.zarr", 60_000, seed=2)
    res = runner.invoke(
        app, ["fit", str(noisy), "--out", str(tmp_path / "iso.model.zip"), "--exclusion", "0.5"]
    )
    assert res.exit_code == 0, res.output
    res = runner.invoke(
        app,
        [
            "evaluate",
            str(tmp_path / "iso.model.zip"),
            str(noisy),
            "--truth",
            str(truth),
            "--report",
            str(tmp_path / "rep"),
            "--json",
            str(tmp_path / "rep.json"),
        ],
    )
    assert res.exit_code == 0, res.output
    s = json.loads((tmp_path / "rep.json").read_text())
    assert s["truth"] == str(truth) and "in_sample" in s
    # the fit follows the noisy data's noise in-sample; against the 20x cleaner truth its error is smaller
    assert s["rel_l2"] < s["in_sample"]["rel_l2"]
    assert s["noise_floor"]["all"] < s["in_sample"]["noise_floor"]["all"] / 3
    assert s["rel_l2"] > s["noise_floor"]["all"]  # no model beats the truth's own noise
    # energy-weighted errors: each point's energy within its window follows the truth closely ...
    assert 0 < s["energy_error"]["window"] < 0.1
    # ... and the total reflectance is the model's closed form against the truth's tally, point by point
    from translucency import load_model
    from translucency.evaluate.errors import planar_errors
    from translucency.io.dataset import open_dataset

    model = load_model(tmp_path / "iso.model.zip")
    ours = model.total_reflectance().sum(1) * model.alpha.values.mean()
    theirs = open_dataset(truth)["total_diffuse"].astype(float).sum(1)
    expected = np.linalg.norm(ours - theirs) / np.linalg.norm(theirs)
    assert np.isclose(s["energy_error"]["total"], expected, rtol=1e-6)
    # the fit's exclusion radius (0.5 mm) is honoured: the in-sample near band matches a direct evaluation
    direct = planar_errors(model, noisy, exclusion_mm=0.5)
    assert np.isclose(direct.bands["near"], s["in_sample"]["rel_l2_near"])
    html = (tmp_path / "rep" / "index.html").read_text()
    assert "independent acquisition" in html and "in-sample" in html
