"""Held-out evaluation (issue 13, item 1): a model against an independent acquisition of the same sample
and points.

``acquire planar --seed`` seeds a generated sample's volume *and* the photons, so two ``--material marble``
acquisitions with different seeds measure two different marbles.  The truth here is the same volume
(written once, passed as ``--volume``) with another photon seed.
"""

import json

import numpy as np
from typer.testing import CliRunner

from translucency.acquire import make_sample
from translucency.cli.app import app
from translucency.io.dataset import dataset_identity, open_dataset

runner = CliRunner()


def _volume(tmp_path):
    path = tmp_path / "marble.npz"
    if not path.exists():
        v = make_sample("marble", (10.0, 10.0, 4.0), 0.5, seed=1)
        np.savez(path, sigma_s=v.sigma_s, sigma_a=v.sigma_a, voxel_mm=v.voxel_mm, g=v.g, eta=v.eta)
    return path


def _acquire(path, photons, seed):
    args = [
        "acquire",
        "planar",
        "--volume",
        str(_volume(path.parent)),
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
            "--json-out",
            str(tmp_path / "rep.json"),
        ],
    )
    assert res.exit_code == 0, res.output
    assert "another sample" not in res.output  # the truth measured the same volume
    assert dataset_identity(open_dataset(noisy).header) == dataset_identity(open_dataset(truth).header)
    s = json.loads((tmp_path / "rep.json").read_text())
    # paths in the report are relative to the report's folder
    assert s["truth"] == "../truth.zarr" and s["dataset"] == "../noisy.zarr" and "in_sample" in s
    assert "NaN" not in (tmp_path / "rep.json").read_text()
    # the fit follows the noisy data's noise in-sample; against the 20x cleaner truth its error is smaller
    assert s["rel_l2"] < s["in_sample"]["rel_l2"]
    assert s["noise_floor"]["all"] < s["in_sample"]["noise_floor"]["all"] / 3
    assert s["rel_l2"] > s["noise_floor"]["all"]  # no model beats the truth's own noise
    # the error beyond the truth's noise: sqrt(rel_l2² − noise²) (the bands' squares add up)
    b = s["beyond_noise"]["all"]
    assert np.isclose(b, np.sqrt(max(s["rel_l2"] ** 2 - s["noise_floor"]["all"] ** 2, 0.0)), rtol=1e-6)
    # energy-weighted errors: each point's energy within its window follows the truth closely ...
    assert 0 < s["energy_error"]["window"] < 0.1
    # ... and the total reflectance is the model's closed form against the truth's tally, point by point
    from translucency import load_model
    from translucency.evaluate.errors import planar_errors

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
