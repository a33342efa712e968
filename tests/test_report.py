"""The Figure 1 report (issue 13, items 1 and 6): held-out numbers, the error beyond the truth's noise,
energy-weighted errors, fitted directions, and a report.json without NaN — on synthetic data sets whose
right answers are known (no photon transport: fast)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from translucency.evaluate.directions import spread_directions
from translucency.evaluate.errors import beyond, finite_or_null, planar_errors
from translucency.evaluate.report import write_report
from translucency.evaluate.rings import model_rings, ring_stats
from translucency.io.dataset import write_dataset
from translucency.model import DipoleModel, ExponentialModel, PlanarAlpha

PITCH, N_PX = 0.25, 13  # 3.25 mm windows: the far band (> 4 mm) is empty


def _grid_points(side=3, spacing=0.5, start=3.125):
    g = start + spacing * np.arange(side)
    xx, yy = np.meshgrid(g, g)
    return np.stack([xx.ravel(), yy.ravel()], axis=1)


def _aniso(x_i, slow_angle=0.0, m=8):
    """Two-term exponentials per direction; the direction ``slow_angle`` (and its opposite) decays slowest."""
    n = len(x_i)
    theta = 2 * np.pi * np.arange(m) / m
    along = np.abs(np.cos(theta - slow_angle))  # 1 along, 0 across
    d1 = -(4.0 - 2.5 * along)  # (m,) slower along
    c = np.zeros((n, 3, m, 2))
    d = np.zeros((n, 3, m, 2))
    c[..., 0], c[..., 1] = 0.3, 0.05
    d[..., 0] = d1
    d[..., 1] = 2 * d1
    return ExponentialModel(x_i, c, d, PlanarAlpha.uniform((40, 40), origin=(0.0, 0.0), pitch=0.25))


def _iso(x_i):
    n = len(x_i)
    c = np.zeros((n, 3, 1, 2))
    d = np.zeros((n, 3, 1, 2))
    c[..., 0], c[..., 1] = 0.3, 0.05
    d[..., 0], d[..., 1] = -2.0, -4.0
    return ExponentialModel(x_i, c, d, PlanarAlpha.uniform((40, 40), origin=(0.0, 0.0), pitch=0.25))


def _data(path, model, rel_noise, seed):
    """Windows of ``model`` with Gaussian noise of ``rel_noise`` × value (recorded as the variance)."""
    x_i = model.x_i[:, :2]
    origin = x_i - PITCH * N_PX / 2
    clean = model.R_d_window(np.arange(len(x_i)), origin, PITCH, (N_PX, N_PX))
    rng = np.random.default_rng(seed)
    noisy = clean * (1 + rel_noise * rng.standard_normal(clean.shape))
    return write_dataset(path, x_i, origin, noisy, PITCH, variance=(rel_noise * clean) ** 2), clean


def test_spread_directions_recover_the_slow_axis():
    x_i = _grid_points(2)
    for slow in (0.0, np.pi / 4, np.pi / 2):
        angle, ratio = spread_directions(_aniso(x_i, slow))
        # the main axis is a line: compare modulo π
        diff = np.angle(np.exp(2j * (angle - slow))) / 2
        np.testing.assert_allclose(diff, 0.0, atol=1e-6)
        assert (ratio > 1.2).all()  # 1.30: rms radii within 2 mm of rates 1.5 (along) and 4 (across) /mm
    _, ratio = spread_directions(_iso(x_i))
    np.testing.assert_allclose(ratio, 1.0, atol=1e-9)


def test_beyond_noise_subtracts_the_truths_variance(tmp_path):
    """A perfect model against a noisy truth: rel_l2 ≈ the noise floor, beyond_noise ≈ 0, while a wrong
    model's beyond_noise is its error against the noise-free windows."""
    x_i = _grid_points()
    true_model = _iso(x_i)
    truth, clean = _data(tmp_path / "truth.zarr", true_model, 0.05, seed=1)
    e = planar_errors(true_model, truth)
    assert e.rel_l2 == pytest.approx(e.noise["all"], rel=0.05)
    assert e.beyond_noise["all"] < 0.015  # sqrt of a small, noisy difference of squares
    wrong = _aniso(x_i)
    ew = planar_errors(wrong, truth)
    # against the clean windows (no noise at all) the wrong model's error is
    origin = x_i - PITCH * N_PX / 2
    pred = wrong.R_d_window(np.arange(len(x_i)), origin, PITCH, (N_PX, N_PX))
    yy, xx = np.mgrid[0:N_PX, 0:N_PX]
    r = np.hypot(xx - N_PX // 2, yy - N_PX // 2) * PITCH
    ok = np.broadcast_to((r >= PITCH)[None, :, :, None], pred.shape)
    clean_err = np.sqrt(((pred - clean) ** 2)[ok].sum() / (clean**2)[ok].sum())
    assert ew.beyond_noise["all"] == pytest.approx(clean_err, rel=0.05)
    assert ew.rel_l2 > ew.beyond_noise["all"]
    # maps: the same subtraction per pixel and per point
    assert np.nanmedian(e.per_pixel_beyond) < 0.5 * np.nanmedian(e.per_pixel_noise)
    assert np.nanmedian(ew.per_point_beyond) == pytest.approx(np.nanmedian(ew.per_point), rel=0.3)
    assert beyond(1.0, 2.0, 1.0) == 0.0 and beyond(5.0, 1.0, 4.0) == pytest.approx(1.0)


def test_energy_errors_and_their_noise_match_a_plain_loop(tmp_path):
    x_i = _grid_points(2)
    truth, _ = _data(tmp_path / "t.zarr", _iso(x_i), 0.1, seed=3)
    model = _aniso(x_i)
    e = planar_errors(model, truth)
    origin = x_i - PITCH * N_PX / 2
    pred = model.R_d_window(np.arange(len(x_i)), origin, PITCH, (N_PX, N_PX)).sum(-1) * PITCH**2
    y = np.asarray(truth.group["R_d"][...], dtype=float)
    v = np.asarray(truth.group["variance"][...], dtype=float).sum(-1) * PITCH**4
    y = y.sum(-1) * PITCH**2
    yy, xx = np.mgrid[0:N_PX, 0:N_PX]
    r = np.hypot(xx - N_PX // 2, yy - N_PX // 2) * PITCH
    sel = (r >= PITCH) & (r < 1.0)  # the near band
    em, ed, ev = pred[:, sel].sum(1), y[:, sel].sum(1), v[:, sel].sum(1)
    assert e.energy["near"] == pytest.approx(np.linalg.norm(em - ed) / np.linalg.norm(ed), rel=1e-5)
    assert e.energy_noise["near"] == pytest.approx(np.sqrt(ev.sum()) / np.linalg.norm(ed), rel=1e-5)


def test_empty_bands_are_null_not_nan(tmp_path):
    x_i = _grid_points(2)
    truth, _ = _data(tmp_path / "t.zarr", _iso(x_i), 0.05, seed=4)
    s = finite_or_null(planar_errors(_iso(x_i), truth).summary())
    assert s["rel_l2_far"] is None and s["noise_floor"]["far"] is None and s["beyond_noise"]["far"] is None
    assert s["rel_l2_near"] is not None
    json.dumps(s, allow_nan=False)  # raises on NaN
    assert finite_or_null({"a": [1.0, math.nan], "b": np.float64(math.inf)}) == {"a": [1.0, None], "b": None}


def test_ring_stats_and_fine_rings_against_direct_sums():
    rng = np.random.default_rng(5)
    w = rng.uniform(1, 2, (9, 9))
    var = rng.uniform(0, 0.1, (9, 9))
    r, mean, err = ring_stats(w, var, 0.5)
    yy, xx = np.mgrid[0:9, 0:9]
    ring = np.round(np.hypot(xx - 4, yy - 4)).astype(int)
    assert r[0] == 0.5 and mean[0] == pytest.approx(w[ring == 1].mean())
    assert err[1] == pytest.approx(np.sqrt(var[ring == 2].sum()) / (ring == 2).sum())
    # a model's ring means on a fine grid: the analytic ring average of c e^{dr}
    model = _iso(_grid_points(1))
    edges = np.array([0.0, 0.1, 0.5, 1.0])
    got = model_rings(model, 0, edges, samples=64, angles=8)
    c, d = 0.3, -2.0

    def ring_mean(a, b):  # ∫ (c e^{dr} + 0.05 e^{2dr}) r dr / ∫ r dr over [a, b]
        f = lambda k, dd, x: k * np.exp(dd * x) * (x / dd - 1 / dd**2)  # noqa: E731
        num = f(c, d, b) - f(c, d, a) + f(0.05, 2 * d, b) - f(0.05, 2 * d, a)
        return num / ((b**2 - a**2) / 2)

    np.testing.assert_allclose(got, [ring_mean(a, b) for a, b in zip(edges[:-1], edges[1:])], rtol=1e-3)


def test_held_out_report(tmp_path):
    """The report against a truth: relative paths, command, date, definitions, no NaN, residual and fine
    profile rows, the held-out and in-sample numbers side by side."""
    x_i = _grid_points(3)
    true_model = _aniso(x_i, np.pi / 2)
    fitted, _ = _data(tmp_path / "fitted.zarr", true_model, 0.2, seed=6)
    truth, _ = _data(tmp_path / "truth.zarr", true_model, 0.05, seed=7)
    dip = DipoleModel(x_i, [[0.01] * 3] * 9, [[1.0] * 3] * 9, 1.3, PlanarAlpha.uniform((40, 40), pitch=0.25))
    models = {"aniso": true_model, "iso": _iso(x_i), "dipole": dip}
    edges = np.arange(0.0, 1.0001, 0.05)
    fine = {
        "edges_mm": edges,
        "points": np.array([4]),
        "R_d": np.stack([model_rings(true_model, 4, edges, ch) for ch in range(3)], -1)[None],
        "variance": np.full((1, len(edges) - 1, 3), 1e-6),
        "photons": 1000,
    }
    out = tmp_path / "rep"
    s = write_report(models, fitted, out, truth=truth, fine=fine, command="translucency evaluate x")
    text = (out / "report.json").read_text()
    assert "NaN" not in text and json.loads(text)["rel_l2_far"] is None and math.isnan(s["rel_l2_far"])
    assert s["dataset"] == "../fitted.zarr" and s["truth"] == "../truth.zarr"
    assert s["command_line"] == "translucency evaluate x" and s["date"][:2] == "20"
    assert s["written_by"].startswith("translucency ") and "beyond_noise" in s["definition"]
    assert s["profile_points"] == [4] and s["fine_profiles"] == {
        "bin_mm": pytest.approx(0.05),
        "photons": 1000,
    }
    m = s["models"]
    # the true model is within the truth's noise; the others are not; in-sample (20 % noise) is worse
    assert m["aniso"]["beyond_noise"]["all"] < 0.02 < m["iso"]["beyond_noise"]["all"]
    assert m["aniso"]["rel_l2"] < m["aniso"]["in_sample"]["rel_l2"]
    assert m["dipole"]["energy_error"]["near"] > m["aniso"]["energy_error"]["near"]
    html = (out / "index.html").read_text()
    for words in (
        "independent acquisition",
        "in-sample",
        "beyond noise",
        "energy, near",
        "translucency evaluate x",
    ):
        assert words in html, words
    for name in ("profiles.png", "error_maps.png", "alpha.png", "params.png"):
        assert (out / name).stat().st_size > 10_000, name


def test_in_sample_report_has_no_beyond_noise(tmp_path):
    x_i = _grid_points(2)
    data, _ = _data(tmp_path / "d.zarr", _iso(x_i), 0.05, seed=8)
    s = write_report({"iso": _iso(x_i)}, data, tmp_path / "rep", command="c")
    assert s["truth"] is None and s["beyond_noise"] is None and "in_sample" not in s
    assert "NaN" not in (tmp_path / "rep" / "report.json").read_text()


def test_the_embedded_data_come_with_an_independent_truth():
    """The shipped scan, its held-out truth and the fine profiles: one sample, the same points, independent
    photons, the truth 3x the photons; all of it within the 25 MB the repository allows."""
    from translucency.data import (
        DATA_DIR,
        default_dataset_path,
        default_fine_profiles_path,
        default_truth_path,
    )
    from translucency.io.dataset import dataset_identity, open_dataset
    from translucency.pipeline import demo_volume, profile_points

    ds, truth = open_dataset(default_dataset_path()), open_dataset(default_truth_path())
    assert ds.complete() and truth.complete()
    assert dataset_identity(ds.header) == dataset_identity(truth.header)  # the same volume
    np.testing.assert_array_equal(ds["x_i"], truth["x_i"])
    a, b = ds.header["acquisition"], truth.header["acquisition"]
    assert a["seed"] != b["seed"] and b["photons"] >= 3 * a["photons"]
    with np.load(default_fine_profiles_path()) as f:
        points, x_f = f["points"], f["x_i"]
        assert f["R_d"].shape == (len(points), len(f["edges_mm"]) - 1, 3) and (f["R_d"] >= 0).all()
    np.testing.assert_allclose(x_f, ds["x_i"][points], atol=1e-6)
    x_i = ds["x_i"].astype(float)
    assert list(points) == profile_points(x_i, demo_volume())
    band = ds.header["sample"]["description"]["band_y_mm"]
    assert (x_i[points[:2], 1] < band).all() and (x_i[points[2:], 1] > band).all()
    size = sum(f.stat().st_size for f in DATA_DIR.rglob("*") if f.is_file())
    assert size < 25 * 2**20


# -- issue 22, item 6: a report that explains itself ------------------------------------------------------


@pytest.fixture
def figures(monkeypatch):
    """The report's figures by file name, drawn and kept open instead of written."""
    from translucency._plotting import pyplot
    from translucency.evaluate import error_maps, model_maps, profile_figure, relight

    caught = {}

    def keep(fig, path, **_):
        fig.canvas.draw()
        caught[Path(path).name] = fig

    for module in (error_maps, model_maps, profile_figure, relight):
        monkeypatch.setattr(module, "save_figure", keep, raising=False)
    yield caught
    for fig in caught.values():
        pyplot().close(fig)


def _texts(fig) -> str:
    from matplotlib.text import Text

    return "\n".join(t.get_text() for t in fig.findobj(Text))


def _overprinted(fig) -> list:
    """Pairs of titles and axis labels of different axes (colour bars included) whose boxes overlap."""
    renderer = fig.canvas.get_renderer()
    labels = [
        [t for t in (ax.title, ax.xaxis.label, ax.yaxis.label) if t.get_visible() and t.get_text()]
        for ax in fig.axes
    ]
    hits = []
    for i, mine in enumerate(labels):
        for theirs in labels[i + 1 :]:
            for t in mine:
                for u in theirs:
                    if t.get_window_extent(renderer).overlaps(u.get_window_extent(renderer)):
                        hits.append((t.get_text(), u.get_text()))
    return hits


def _three_models(tmp_path):
    x_i = _grid_points(3)
    true_model = _aniso(x_i, np.pi / 2)
    fitted, _ = _data(tmp_path / "fitted.zarr", true_model, 0.2, seed=6)
    truth, _ = _data(tmp_path / "truth.zarr", true_model, 0.05, seed=7)
    dip = DipoleModel(x_i, [[0.01] * 3] * 9, [[1.0] * 3] * 9, 1.3, PlanarAlpha.uniform((40, 40), pitch=0.25))
    return {"aniso": true_model, "iso": _iso(x_i), "dipole": dip}, fitted, truth


def test_in_sample_report_names_the_datas_own_noise(tmp_path, figures):
    """Without a truth no caption, colour bar or legend speaks of a truth's noise: the noise shown is the
    fitted data's own; the summary says the numbers are in-sample and how to get held-out ones."""
    models, fitted, _ = _three_models(tmp_path)
    s = write_report(models, fitted, tmp_path / "rep", command="c")
    for name in ("error_maps.png", "profiles.png"):
        text = _texts(figures[name])
        assert "truth" not in text, name
        assert "the data's own noise" in text, name
    page = (tmp_path / "rep" / "index.html").read_text()
    assert "truth's noise" not in page and "truth's own" not in page
    assert "±1σ band of the data's own noise" in page and "<th>the data's own noise</th>" in page
    assert s["summary"].startswith("In-sample") and "evaluate --truth" in s["summary"]
    assert "earn their parameters" in s["summary"]  # ... cannot be read from in-sample numbers


def test_held_out_report_keeps_the_truths_noise(tmp_path, figures):
    models, fitted, truth = _three_models(tmp_path)
    write_report(models, fitted, tmp_path / "rep", truth=truth, command="c")
    assert "the truth's noise" in _texts(figures["error_maps.png"])
    assert "the truth's noise (±1σ)" in _texts(figures["profiles.png"])
    page = (tmp_path / "rep" / "index.html").read_text()
    assert "±1σ band of the truth's noise" in page and "beyond the truth's noise" in page


def test_the_summary_says_which_model_wins_and_is_in_report_json(tmp_path):
    """The summary at the top of the page and in report.json: the true (anisotropic) model wins held out,
    against the truth's noise floor, its directions earn their parameters; no other report.json value
    changes (the same keys as before, plus "summary")."""
    models, fitted, truth = _three_models(tmp_path)
    out = tmp_path / "rep"
    s = write_report(models, fitted, out, truth=truth, command="c")
    on_disk = json.loads((out / "report.json").read_text())
    assert on_disk["summary"] == s["summary"] and isinstance(s["summary"], str)
    before = {"written_by", "command_line", "date", "dataset", "truth", "paths", "evaluated_against", "model"}
    before |= {"rel_l2", "rel_l2_near", "rel_l2_mid", "rel_l2_far", "noise_floor", "beyond_noise"}
    before |= {"energy_error", "energy_noise", "per_point", "flagged_points", "physics", "in_sample"}
    before |= {"bands_mm", "models", "profile_points", "fine_profiles", "definition"}
    assert set(on_disk) == before | {"summary"}
    text = s["summary"]
    floor = s["models"]["aniso"]["noise_floor"]["all"]
    assert text.startswith("Held out, against an independent acquisition: aniso is closest to the truth")
    assert f"a noise floor of {100 * floor:.2f} %" in text
    assert "The anisotropic model's directions earn their parameters" in text
    assert "Physics checks" in text
    page = (out / "index.html").read_text()
    assert page.index('<p class="summary"') < page.index("<h2>Errors</h2>")
    assert "td{white-space:nowrap}" in page and "\u00a0%</td>" in page  # a cell's number and % stay together


def _fake(kind="exponential", m=1, points=4):
    from types import SimpleNamespace

    terms = np.zeros((points, 3, m, 2))
    return SimpleNamespace(kind=kind, n_directions=m, n_points=points, c=terms, d=terms)


def _numbers(rel, floor, beyond, over=(), out=(), flagged=()):
    physics = {"over_albedo": list(over), "beyond_object": list(out), "max_total_reflectance": 1.2}
    return {
        "rel_l2": rel,
        "noise_floor": {"all": floor},
        "beyond_noise": None if beyond is None else {"all": beyond},
        "physics": physics,
        "flagged_points": list(flagged),
    }


@pytest.mark.parametrize(
    ("beyond_aniso", "verdict"),
    [
        (0.05, "earn their parameters: beyond the noise aniso's error is 38 % below iso's"),
        (0.076, "gain little for their parameters: beyond the noise aniso's error is 5 % below iso's"),
        (0.09, "do not earn their parameters: beyond the noise aniso's error is 12 % above iso's"),
    ],
)
def test_the_summary_weighs_the_directions_against_their_parameters(beyond_aniso, verdict):
    from translucency.evaluate.conclusion import conclusion

    models = {"aniso": _fake(m=8), "iso": _fake(), "dipole": _fake("dipole")}
    rel = float(np.hypot(beyond_aniso, 0.06))
    per_model = {
        "aniso": _numbers(rel, 0.06, beyond_aniso, over=[1]),
        "iso": _numbers(0.1, 0.06, 0.08),
        "dipole": _numbers(0.2, 0.06, 0.19, out=[0, 1]),
    }
    text = conclusion(per_model, models, held_out=True, n_points=4)
    assert verdict in text and "with 96 coefficients per point against 12" in text
    assert "more light out than in (total reflectance > 1) at 1 point of aniso (up to 1.2)" in text
    assert (
        "over half of a point's energy beyond the sample at 2 points of dipole; iso passes every check"
        in text
    )


def test_the_in_sample_summary_does_not_claim_a_winner_it_cannot_know():
    from translucency.evaluate.conclusion import conclusion

    models = {"iso": _fake(), "aniso": _fake(m=8)}
    per_model = {"iso": _numbers(0.12, 0.11, None, flagged=[2]), "aniso": _numbers(0.115, 0.11, None)}
    text = conclusion(per_model, models, held_out=False, n_points=4)
    assert text.startswith("In-sample, against the data the models were fitted to (no independent truth")
    assert "aniso scores lowest, 11.50 %" in text and "the data's own noise alone gives 11.00 %" in text
    assert "truth's" not in text and "beyond" not in text.split("Physics")[0]
    assert "every model reflects at most the light it receives" in text
    assert "Points the fits flagged, left out of the errors: iso 1." in text


def test_error_map_titles_clear_the_row_above(tmp_path, figures):
    """No title or axis label of one panel (or colour bar) runs into another's, with and without a truth:
    the lower rows' titles used to sit on the upper rows' 'x [mm]'."""
    models, fitted, truth = _three_models(tmp_path)
    write_report(models, fitted, tmp_path / "held-out", truth=truth, command="c")
    assert len(figures["error_maps.png"].axes) == 3 * 3 + 3  # three rows, a colour bar each
    for name in ("error_maps.png", "error_ratios.png", "profiles.png"):
        assert _overprinted(figures[name]) == [], name
    write_report(models, fitted, tmp_path / "in-sample", command="c")
    for name in ("error_maps.png", "error_ratios.png"):
        assert _overprinted(figures[name]) == [], name


def test_relight_figure_has_colour_bars_and_a_labelled_profile(tmp_path, figures):
    from translucency.evaluate.relight import plot_relighting

    rng = np.random.default_rng(3)
    reference = rng.uniform(0.5, 1.0, (20, 24, 3))
    preds = {"iso": reference * 1.05, "dipole": reference * 0.9}
    errors = plot_relighting(reference, preds, [0.0, 6.0, 0.0, 5.0], tmp_path / "relight.png")
    assert errors["iso"] == pytest.approx(0.05)
    fig = figures["relight.png"]
    bars = [ax for ax in fig.axes if ax.get_label() == "<colorbar>"]
    assert len(bars) == 2  # the exitance of reference and models; their differences
    assert "W mm" in bars[0].get_ylabel() and "bright level" in bars[1].get_ylabel()
    profile = fig.axes[len(preds) + 1]  # the lower row's first panel
    assert profile.get_title() == "profile across the middle rows" and "W mm" in profile.get_ylabel()
    assert _overprinted(fig) == []
