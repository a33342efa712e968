"""Evaluation: error measures against a plain implementation, and the accuracy claims on
virtual-DISCO data (photon transport, not the model being fitted)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from translucency.cli.app import app
from translucency.evaluate.errors import BANDS, planar_errors
from translucency.fit.planar import fit_planar
from translucency.io.dataset import write_dataset
from translucency.model import DipoleModel, PlanarAlpha

runner = CliRunner()


@pytest.fixture(scope="module")
def marble(planar_scan):
    """3 × 3 points over 3 mm, 100 k photons, seed 3."""
    return planar_scan("marble", side=3, span=3.0, photons=100_000, seed=3)


@pytest.fixture(scope="module")
def fibers(planar_scan):
    """2 × 2 points over 2 mm, 100 k photons, seed 4 (the data set of tests/test_model_selection.py)."""
    return planar_scan("fibers", side=2, span=2.0, photons=100_000, seed=4)


def test_errors_match_a_plain_loop(tmp_path):
    """rel_l2, the bands and the per-point errors against a pair-by-pair Python loop."""
    rng = np.random.default_rng(2)
    pitch, n = 0.5, 9
    x_i = np.array([[2.25, 2.25], [3.75, 2.25]])
    origin = x_i - pitch * n / 2
    R = rng.uniform(0.001, 0.1, (2, n, n, 3))
    mask = rng.uniform(size=(2, n, n)) > 0.2
    ds = write_dataset(tmp_path / "d.zarr", x_i, origin, R, pitch, mask=mask, variance=R * 1e-3)
    model = DipoleModel(
        x_i,
        [[0.01] * 3, [0.02] * 3],
        [[1.0] * 3, [2.0] * 3],
        1.3,
        PlanarAlpha(rng.uniform(0.8, 1.2, (20, 20)), (0.0, 0.0), pitch),
    )
    e = planar_errors(model, ds)
    num = {b: 0.0 for b in BANDS}
    den = {b: 0.0 for b in BANDS}
    per_point = []
    for i in range(2):
        pn = pd = 0.0
        for row in range(n):
            for col in range(n):
                xo = origin[i] + pitch * np.array([col + 0.5, row + 0.5])
                r = float(np.hypot(*(xo - x_i[i])))
                if not mask[i, row, col] or r < pitch:
                    continue
                f = model.R_d(np.array([i]), xo[None])[0]
                d2, y2 = float(((f - R[i, row, col]) ** 2).sum()), float((R[i, row, col] ** 2).sum())
                band = next(b for b, (lo, hi) in BANDS.items() if lo <= r < hi)
                num[band] += d2
                den[band] += y2
                pn += d2
                pd += y2
        per_point.append(np.sqrt(pn / pd))
    assert e.rel_l2 == pytest.approx(np.sqrt(sum(num.values()) / sum(den.values())), rel=1e-6)
    for b in ("near", "mid"):
        assert e.bands[b] == pytest.approx(np.sqrt(num[b] / den[b]), rel=1e-6)
    np.testing.assert_allclose(e.per_point, per_point, rtol=1e-6)
    assert e.noise["all"] == pytest.approx(np.sqrt(1e-3 * (R.sum(3) * mask)[...].sum() / 1), rel=0.5)


def test_marble_exponential_beats_dipole_near_the_incident_point(marble):
    """The paper's claim on photon data: near x_i the exponential sum follows, the dipole does not."""
    err = {
        kind: planar_errors(fit_planar(marble, kind, max_rounds=3).model, marble)
        for kind in ("iso", "dipole")
    }
    assert err["iso"].bands["near"] <= 0.5 * err["dipole"].bands["near"]
    assert err["iso"].rel_l2 < err["dipole"].rel_l2
    # and the exponential sum is within reach of the noise
    assert err["iso"].bands["near"] < 1.5 * err["iso"].noise["near"]


def test_fibers_need_the_anisotropic_model(fibers):
    iso = planar_errors(fit_planar(fibers, "iso", max_rounds=3).model, fibers)
    aniso = planar_errors(fit_planar(fibers, "aniso", n_directions=8, max_rounds=3).model, fibers)
    # issue 13's target on fibers: aniso ≤ 0.6 × iso (with Poisson weights iso itself fits them better
    # than it did with a relative error term: 8.7 % against 11.5 %; aniso 5.0 %)
    assert aniso.rel_l2 <= 0.6 * iso.rel_l2


def test_fit_and_evaluate_cli(marble, tmp_path):
    out = tmp_path / "iso.model.zip"
    res = runner.invoke(app, ["fit", str(marble.path), "--out", str(out), "--rounds", "2"])
    assert res.exit_code == 0, res.output
    dip = tmp_path / "dip.model.zip"
    assert (
        runner.invoke(
            app, ["fit", str(marble.path), "--out", str(dip), "--model", "dipole", "--rounds", "2"]
        ).exit_code
        == 0
    )
    js = tmp_path / "e.json"
    res = runner.invoke(
        app,
        [
            "evaluate",
            str(out),
            str(marble.path),
            "--compare",
            str(dip),
            "--report",
            str(tmp_path / "rep"),
            "--json-out",
            str(js),
            "--profiles",
            "0,4",
        ],
    )
    assert res.exit_code == 0, res.output
    summary = json.loads(js.read_text())
    for key in ("rel_l2", "rel_l2_near", "rel_l2_mid", "rel_l2_far"):
        assert 0 < summary[key] < 1
    assert summary["profile_points"] == [0, 4] and len(summary["models"]) == 2
    assert '<img src="error_maps.png">' in (tmp_path / "rep" / "index.html").read_text()


def test_cli_bad_input_is_one_line(marble, tmp_path):
    res = runner.invoke(app, ["fit", str(tmp_path / "nothing.zarr"), "--out", str(tmp_path / "x.model.zip")])
    assert res.exit_code == 2 and res.output.strip().startswith("error:") and "no such data set" in res.output
    res = runner.invoke(
        app, ["fit", str(marble.path), "--out", str(tmp_path / "x.model.zip"), "--model", "gauss"]
    )
    assert res.exit_code == 2 and "model: expected one of" in res.output
    res = runner.invoke(app, ["evaluate", str(tmp_path / "none.model.zip"), str(marble.path)])
    assert res.exit_code == 2 and "error:" in res.output
    other = tmp_path / "other.zarr"
    write_dataset(other, [[1.0, 1.0]], [[0.0, 0.0]], np.full((1, 8, 8, 3), 0.01), 0.25)
    fit = runner.invoke(app, ["fit", str(other), "--out", str(tmp_path / "o.model.zip"), "--rounds", "1"])
    assert fit.exit_code == 0, fit.output
    res = runner.invoke(app, ["evaluate", str(tmp_path / "o.model.zip"), str(marble.path)])
    assert res.exit_code == 2 and "incident points are not the data set's" in res.output


def test_relighting_matches_photon_transport(marble):
    """Superposing the fitted R_d over lit cells predicts what photon transport gives under that light."""
    from translucency.acquire.pattern import acquire_pattern
    from translucency.acquire.samples import sample_of_dataset
    from translucency.evaluate.relight import pattern_irradiance, relight

    model = fit_planar(marble, "iso", max_rounds=3).model
    x_i = marble["x_i"].astype(float)
    spacing = 1.5
    E = pattern_irradiance("edge", x_i)
    assert E[:, 0].sum() == 3  # the left column of the 3 x 3 grid
    origin, pitch, shape = x_i.min(0) - 3.0, 0.25, (36, 36)
    ref = acquire_pattern(
        sample_of_dataset(marble.header),
        x_i,
        spacing,
        E,
        origin,
        pitch,
        shape,
        photons=20_000,
        jitter=8,
        seed=2,
    )
    pred = relight(model, E, spacing**2, origin, pitch, shape, radius=3.0)
    # compare where the model is defined: within 2 mm of the lit cells (the fit saw r < 3 mm), once the
    # model's point sources (all light of a cell enters at x_i) are spread over their 1.5 mm cells
    from scipy.ndimage import uniform_filter

    spread = uniform_filter(pred, size=(6, 6, 1), mode="constant")
    yy, xx = origin[::-1, None, None] + pitch * (np.mgrid[0:36, 0:36] + 0.5)
    lit_x = x_i[E[:, 0] > 0, 0][0]
    near = (np.abs(xx - lit_x) < 0.75 + 2.0) & (yy > x_i[:, 1].min() - 0.75) & (yy < x_i[:, 1].max() + 0.75)
    a, b = spread[near], ref[near]
    assert 0.85 < a.sum() / b.sum() < 1.05
    # light carried across the shadow edge: right of the lit column, the model follows the photons
    dark = near & (xx > lit_x + 0.75)
    assert 0.7 < spread[dark].sum() / ref[dark].sum() < 1.3
