"""``acquire mesh --sample-seed``: a held-out truth of the same generated filling with other photons."""

import warnings

import numpy as np
import trimesh
from typer.testing import CliRunner

import translucency as tl
from translucency.cli.app import app
from translucency.io.dataset import dataset_identity
from translucency.render.object import object_from_dataset, volume_of_dataset

runner = CliRunner()

#: a 10 mm ball of generated (heterogeneous) marble: its filling depends on the sample seed
SMALL = {"voxel_mm": 1.0, "points": 3, "photons": 500, "index_matched": True}


def _filling(ds):
    """The filling a mesh data set was acquired from, rebuilt from its header: (σ_s, σ_a) in mm⁻¹."""
    mesh, header = object_from_dataset(ds.path)
    volume = volume_of_dataset(mesh, header)
    return volume.sigma_s, volume.sigma_a


def _other_sample_warnings(model, data, truth) -> list[str]:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        tl.evaluate_model(model, data, truth=truth)
    return [str(w.message) for w in caught if "another sample" in str(w.message)]


def test_a_mesh_truth_of_the_same_filling_with_another_photon_seed(tmp_path):
    ball = tmp_path / "ball.ply"
    trimesh.creation.icosphere(2, radius=5.0).export(ball)
    data = tl.acquire_mesh(ball, tmp_path / "data.zarr", "marble", seed=0, **SMALL)
    # the default sample seed is the photons' seed: the same data set bit for bit as sample_seed=seed
    explicit = tl.acquire_mesh(ball, tmp_path / "explicit.zarr", "marble", seed=0, sample_seed=0, **SMALL)
    assert explicit.header["request"] == data.header["request"]
    assert np.array_equal(np.asarray(explicit["R_d"]), np.asarray(data["R_d"]))
    # the truth through the command: the same filling (--sample-seed 0), other photons (--seed 1)
    args = ["acquire", "mesh", "--mesh", str(ball), "--material", "marble", "--voxel", "1", "--points", "3"]
    args += ["--photons", "500", "--index-matched", "--quiet", "--sample-seed", "0", "--seed", "1"]
    res = runner.invoke(app, [*args, "--out", str(tmp_path / "truth.zarr")])
    assert res.exit_code == 0, res.output
    truth = tl.open_dataset(tmp_path / "truth.zarr")
    other = tl.acquire_mesh(ball, tmp_path / "other.zarr", "marble", seed=1, **SMALL)  # another marble
    for a, b in zip(_filling(data), _filling(truth), strict=True):
        assert np.array_equal(a, b)
    assert not np.array_equal(_filling(data)[0], _filling(other)[0])
    assert dataset_identity(truth.header) == dataset_identity(data.header)
    assert dataset_identity(other.header) != dataset_identity(data.header)
    assert truth.header["seed"] == 1 and not np.array_equal(np.asarray(truth["R_d"]), np.asarray(data["R_d"]))
    # a model fitted to the data: the truth is the same sample, the other marble is not
    fit = tl.fit_model(data, "iso", tmp_path / "ball.model.zip", max_rounds=2).result
    assert _other_sample_warnings(fit, data, truth) == []
    assert len(_other_sample_warnings(fit, data, other)) == 1
    res = runner.invoke(
        app,
        ["evaluate", str(tmp_path / "ball.model.zip"), str(data.path), "--truth", str(truth.path)]
        + ["--report", str(tmp_path / "report")],
    )
    assert res.exit_code == 0 and "another sample" not in res.output, res.output
