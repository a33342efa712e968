"""Per-vertex models evaluated on mesh data sets: held out against an independent acquisition, the
barycentric tally's noise, a scalar reference of the sums, and the one-line refusals of ``evaluate``."""

import copy
import json

import numpy as np
import pytest
import trimesh
from typer.testing import CliRunner

import translucency as tl
from helpers import random_exponential_model
from translucency.cli.app import app
from translucency.evaluate.errors import BANDS
from translucency.evaluate.mesh_errors import TALLY_VARIANCE_FACTOR, check_same_points, mesh_errors
from translucency.evaluate.mesh_report import write_mesh_report
from translucency.io.model_file import save_model

runner = CliRunner()


@pytest.fixture(scope="module")
def ball(tmp_path_factory):
    """A 4 mm ball of homogeneous marble acquired twice (seeds 0 and 1: the same object, other photons),
    and the fit of the first; (data, truth, fit, folder)."""
    folder = tmp_path_factory.mktemp("ball")
    mesh = trimesh.creation.icosphere(3, radius=4.0)
    kw = {"voxel_mm": 1.0, "points": 4, "photons": 3000, "index_matched": True}
    data = tl.acquire_mesh(mesh, folder / "ball.zarr", "homogeneous:marble", seed=0, **kw)
    truth = tl.acquire_mesh(mesh, folder / "ball_seed1.zarr", "homogeneous:marble", seed=1, **kw)
    fit = tl.fit_model(
        data, "iso", folder / "ball.model.zip", max_rounds=2
    ).result  # written, with its record
    return data, truth, fit, folder


def test_held_out_error_is_above_the_noise_and_below_a_wrong_model(ball):
    data, truth, fit, _ = ball
    held = tl.evaluate_model(fit, data, truth=truth)
    in_sample = tl.evaluate_model(fit, data)
    assert np.isfinite(held.rel_l2) and all(np.isfinite(held.bands[b]) for b in ("near", "mid"))
    # the truth's noise is independent of the model: its error cannot fall far below that floor
    assert held.rel_l2 >= 0.8 * held.noise["all"] > 0
    assert held.per_point.shape == (4,) and np.isfinite(held.per_point).all()
    assert held.rel_l2 != in_sample.rel_l2
    wrong = copy.deepcopy(fit.model)
    wrong.c = wrong.c * 2.0  # twice the light everywhere
    bad = tl.evaluate_model(wrong, data, truth=truth, exclusion_mm=fit.options["exclusion_mm"])
    # ||2M - T|| = ||(M - T) + M|| and ||M|| / ||T|| lie within 1 ± e (e the fit's error): 1 - 2e .. 1 + 2e
    e = held.rel_l2
    assert 1 - 2 * e <= bad.rel_l2 <= 1 + 2 * e
    assert bad.rel_l2 > 2 * held.rel_l2


def test_noise_floor_matches_the_difference_of_two_seeds(ball):
    """Two acquisitions with other seeds differ by var₀ + var₁; the barycentric tally's variance is
    TALLY_VARIANCE_FACTOR x the Poisson R_d / (N A_v) (a factor of 1 would overstate it twice)."""
    data, truth, _, _ = ball
    area = data["vertex_area"].astype(np.float64)
    v = data["vertices"].astype(np.float64)
    r = np.linalg.norm(v[None] - v[data["incident"]][:, None], axis=2)
    ok = r > 0.5
    R0, R1 = (np.asarray(d["R_d"], dtype=np.float64) for d in (data, truth))
    diff2 = ((R0 - R1) ** 2).sum(2)[ok].sum()
    poisson = ((R0 + R1) / (data.header["photons"] * area[None, :, None])).sum(2)[ok].sum()
    assert 0.35 < diff2 / poisson < 0.65
    assert TALLY_VARIANCE_FACTOR == 0.5


def _scalar_errors(model, ds, exclusion, map_radius=4.0):
    """A plain loop over every pair (x_i, v) and channel: the sums behind rel_l2, bands, points, vertices."""
    v = ds["vertices"].astype(np.float64)
    inc = ds["incident"]
    area = ds["vertex_area"].astype(np.float64)
    R = np.asarray(ds["R_d"], dtype=np.float64)
    N = ds.header["photons"]
    err = {b: 0.0 for b in BANDS}
    ref = {b: 0.0 for b in BANDS}
    var = {b: 0.0 for b in BANDS}
    pt_err, pt_ref = np.zeros(len(inc)), np.zeros(len(inc))
    vx_err, vx_ref = np.zeros(len(v)), np.zeros(len(v))
    for i in range(len(inc)):
        for o in range(len(v)):
            r = float(np.sqrt(sum((v[o, k] - v[inc[i], k]) ** 2 for k in range(3))))
            if r < exclusion:
                continue
            pred = model.R_d(np.array([i]), v[o][None])[0]
            band = next(b for b, (lo, hi) in BANDS.items() if lo <= r < hi)
            for c in range(3):
                d2, y2 = (pred[c] - R[i, o, c]) ** 2, R[i, o, c] ** 2
                err[band] += d2
                ref[band] += y2
                var[band] += TALLY_VARIANCE_FACTOR * R[i, o, c] / (N * area[o])
                pt_err[i] += d2
                pt_ref[i] += y2
                if r < map_radius:
                    vx_err[o] += d2
                    vx_ref[o] += y2
    return err, ref, var, pt_err, pt_ref, vx_err, vx_ref


def test_per_vertex_sums_match_a_plain_loop_over_pairs(ball, rng):
    data = ball[0]
    mesh = data.mesh()
    model = random_exponential_model(rng, geometry="mesh", mesh=mesh, points=data["incident"])
    fast = mesh_errors(model, data, exclusion_mm=0.3, chunk_points=3)
    err, ref, var, pt_err, pt_ref, vx_err, vx_ref = _scalar_errors(model, data, 0.3)
    total = sum(err.values()) / sum(ref.values())
    np.testing.assert_allclose(fast.rel_l2, np.sqrt(total), rtol=1e-9)
    for b in BANDS:
        if ref[b] > 0:
            np.testing.assert_allclose(fast.bands[b], np.sqrt(err[b] / ref[b]), rtol=1e-9)
            np.testing.assert_allclose(fast.noise[b], np.sqrt(var[b] / ref[b]), rtol=1e-9)
    np.testing.assert_allclose(fast.per_point, np.sqrt(pt_err / pt_ref), rtol=1e-9)
    seen = vx_ref > 0
    np.testing.assert_allclose(fast.per_vertex[seen], np.sqrt(vx_err[seen] / vx_ref[seen]), rtol=1e-9)
    assert np.isnan(fast.per_vertex[~seen]).all()


def test_a_truth_of_other_incident_vertices_is_refused_naming_the_first(ball):
    data, truth, _, _ = ball

    class Other:  # the truth with its incident vertices changed from point 2 on
        path = truth.path

        def __getitem__(self, name):
            arr = truth[name]
            if name == "incident":
                arr = arr.copy()
                arr[2:] = (arr[2:] + 1) % len(truth["vertices"])
            return arr

    first = r"incident point 2 is vertex \d+, the data set's is vertex"
    with pytest.raises(tl.TranslucencyError, match=first):
        check_same_points(data, Other())

    class Fewer(Other):
        def __getitem__(self, name):
            return truth[name][:3] if name == "incident" else truth[name]

    fewer = r"3 incident points, the data set 4 \(the first 3 agree\)"
    with pytest.raises(tl.TranslucencyError, match=fewer):
        check_same_points(data, Fewer())


def test_report_writes_json_page_and_figure(ball, tmp_path):
    data, truth, fit, _ = ball
    s = write_mesh_report({"iso": fit.model}, data, tmp_path / "rep", truth=truth, command="test")
    saved = json.loads((tmp_path / "rep" / "report.json").read_text())
    assert saved["geometry"] == "mesh" and saved["evaluated_against"].startswith("truth")
    assert saved["rel_l2"] == pytest.approx(s["rel_l2"]) and "in_sample" in saved
    assert len(saved["per_point"]["values"]) == 4 and saved["beyond_noise"]["all"] is not None
    assert (tmp_path / "rep" / "mesh_errors.png").stat().st_size > 10_000
    assert "the truth's noise" in (tmp_path / "rep" / "index.html").read_text()
    alone = write_mesh_report({"iso": fit.model}, data, tmp_path / "alone", command="test")
    assert alone["beyond_noise"] is None and alone["truth"] is None


def test_cli_evaluates_a_per_vertex_model_on_a_mesh_data_set(ball, tmp_path):
    """``evaluate MODEL MESH.zarr`` used to say 'not a translucency data set'."""
    data, truth, fit, folder = ball
    model = folder / "ball.model.zip"
    res = runner.invoke(
        app,
        ["evaluate", str(model), str(data.path), "--truth", str(truth.path), "--report", str(tmp_path / "r")]
        + ["--json", "--quiet"],
    )
    assert res.exit_code == 0, res.output
    out = json.loads(res.stdout)
    held = tl.evaluate_model(model, data, truth=truth)  # the same stored model through the API
    assert out["rel_l2"] == pytest.approx(held.rel_l2) and out["in_sample"]["rel_l2"] > 0
    assert (tmp_path / "r" / "report.json").is_file()


def test_cli_refuses_mismatched_kinds_in_one_line(ball, tmp_path, rng, planar_scan):
    data, _, _, folder = ball
    planar_data = planar_scan("homogeneous:marble", side=1, span=0.0, photons=100, seed=0).path
    planar = random_exponential_model(rng)
    save_model(planar, tmp_path / "planar.model.zip")
    for args in (
        [str(tmp_path / "planar.model.zip"), str(data.path)],
        [str(folder / "ball.model.zip"), str(planar_data)],
        [str(folder / "ball.model.zip"), str(data.path), "--truth", str(planar_data)],
    ):
        res = runner.invoke(app, ["evaluate", *args, "--report", str(tmp_path / "never")])
        lines = res.output.strip().splitlines()
        assert res.exit_code == 2 and len(lines) == 1, res.output
        assert "evaluate takes a planar model with a planar data set" in " ".join(res.output.split())
        assert not (tmp_path / "never").exists()
    with pytest.raises(tl.TranslucencyError, match="^model: a planar model and a mesh data set; evaluate"):
        tl.evaluate_model(planar, data)
