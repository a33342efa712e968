"""The fit's structure chosen by held-out error: the rule on known numbers, the splits (a half fit sees only
its half), the choice on a homogeneous and a fibrous scan, meshes, and what the user is told."""

import json

import numpy as np
import pytest
import trimesh
import zarr
from typer.testing import CliRunner

import translucency as tl
from translucency._validate import TranslucencyError
from translucency.cli.app import app
from translucency.fit.held_out import (
    held_out_error,
    held_out_terms,
    mesh_held_out_terms,
    pair_half,
    vertex_half,
)
from translucency.fit.mesh import fit_mesh
from translucency.fit.planar import fit_planar
from translucency.fit.structure import Structure, choose, resolve_structure, selection_points
from translucency.geometry import SampleGrid, window_geometry
from translucency.io.dataset import open_dataset
from translucency.io.mesh_dataset import open_mesh_dataset
from translucency.io.point_subset import point_subset

runner = CliRunner()

#: 3 × 3 points over 3 mm, 40 k photons, seed 4 (volume and photons)
SCAN = dict(side=3, span=3.0, photons=40_000, seed=4)


@pytest.fixture(scope="module")
def homogeneous(planar_scan):
    return planar_scan("homogeneous:marble", **SCAN)


@pytest.fixture(scope="module")
def fibers(planar_scan):
    return planar_scan("fibers", **SCAN)


@pytest.fixture(scope="module")
def ball(tmp_path_factory):
    """A 4 mm ball of homogeneous marble, 24 incident points (a mesh data set)."""
    mesh = trimesh.creation.icosphere(3, radius=4.0)
    path = tmp_path_factory.mktemp("ball") / "ball.zarr"
    kw = {"voxel_mm": 1.0, "points": 24, "photons": 3000, "index_matched": True}
    return tl.acquire_mesh(mesh, path, "homogeneous:marble", seed=0, **kw)


# -- the rule on known numbers -------------------------------------------------------------------------


def _terms(per_point_errors, norm=10.0):
    e = np.asarray(per_point_errors, dtype=float)
    return e, np.full(e.shape, norm)


def test_a_richer_structure_needs_to_win_by_more_than_the_split_noise():
    # m = 2 gains 0.04 a point on average, with a spread of ±0.15 between points: within its standard error
    gains = {1: [1.0, 1.0, 1.0, 1.0], 2: [0.8, 1.15, 0.9, 1.0], 4: [1.0] * 4, 8: [1.0] * 4, 16: [1.0] * 4}
    choice = choose(lambda s: _terms(gains[s.n_directions]), Structure(), ("n_directions",))
    assert choice.structure.n_directions == 1
    delta, se = choice.axes["n_directions"][0]["delta"], choice.axes["n_directions"][0]["se"]
    assert 0 < delta <= se  # iso is within one standard error of the best (m = 2)
    # the same mean gain on every point (no spread): a real win, m = 2 is kept
    gains[2] = [0.95, 0.95, 0.95, 0.95]
    choice = choose(lambda s: _terms(gains[s.n_directions]), Structure(), ("n_directions",))
    assert choice.structure.n_directions == 2
    assert "n_directions 2 over 1 by" in choice.summary_line()


def test_the_prior_is_kept_within_the_noise_and_a_choice_never_loses_to_a_simpler_one_beyond_it():
    # n = 4 is the best on average, n = 2 and n = 3 swing ±0.6 between points: both within one standard
    # error of it, so the prior n = 3 is kept ...
    e = {2: [0.5, 1.7, 0.5, 1.7], 3: [0.5, 1.7, 0.5, 1.7], 4: [1.0] * 4}
    assert choose(lambda s: _terms(e[s.n_terms]), Structure(), ("n_terms",)).structure.n_terms == 3
    # ... unless n = 3 is worse than the simpler n = 2 on every point (beyond their own noise): the guard
    e[3] = [0.55, 1.75, 0.55, 1.75]
    choice = choose(lambda s: _terms(e[s.n_terms]), Structure(), ("n_terms",))
    assert choice.structure.n_terms == 2 and "n_terms" not in choice.margins  # the simplest: no margin
    # the colour's prior (one fall-off per channel) is kept when the shared colour gains within the noise
    c = {"shared": [0.8, 1.15, 0.9, 1.0], "per-channel": [1.0] * 4}
    choice = choose(lambda s: _terms(c[s.colour]), Structure(), ("colour",))
    assert choice.structure.colour == "per-channel" and "within the noise" in choice.summary_line()


def test_the_search_stops_after_candidates_that_lower_nothing_and_the_guard_keeps_the_base():
    tried = []

    def score(s):
        tried.append(s.n_directions)
        return _terms([1.0, 1.1, 0.9] if s.n_directions == 1 else [1.2, 1.3, 1.1])

    choice = choose(score, Structure(), ("n_directions",))
    assert choice.structure == Structure() and tried == [1, 2, 4]  # 8 and 16 never fitted
    # a colour chosen on its own axis that then loses against the base on the same halves is undone
    values = {("shared", 1): [0.5, 0.5, 0.5], ("per-channel", 1): [1.0, 1.0, 1.0], ("shared", 2): [2.0] * 3}
    values[("per-channel", 2)] = [2.0] * 3
    choice = choose(lambda s: _terms(values[s.colour, s.n_directions]), Structure(), ("colour",))
    assert choice.structure.colour == "shared" and choice.guard["delta"] < 0


def test_options_say_what_is_chosen():
    assert resolve_structure("auto", None, None, None, planar=True)[4] == (
        "colour",
        "n_terms",
        "n_directions",
    )
    # the paper's structure is named, nothing chosen
    assert resolve_structure("aniso", None, 8, "shared", planar=True) == (
        "aniso",
        3,
        8,
        "shared",
        (),
        Structure("shared", 3, 8),
    )
    assert resolve_structure("auto", None, None, None, planar=False)[4] == ("colour", "n_terms")
    with pytest.raises(TranslucencyError, match="directions"):
        fit_planar("nowhere.zarr", "iso", n_directions="auto")
    with pytest.raises(TranslucencyError, match="m >= 2"):
        resolve_structure("aniso", None, 1, None, planar=True)
    assert len(selection_points(10_000)) == 625 and len(np.unique(selection_points(10_000))) == 625


# -- the splits ----------------------------------------------------------------------------------------


def test_a_planar_half_fit_does_not_see_the_other_half(homogeneous, tmp_path):
    """Corrupting the held-out half of the pairs changes nothing in a half fit, and all in its score."""
    sub = point_subset(homogeneous, np.arange(homogeneous.n_points), tmp_path / "copy.zarr")
    grid = SampleGrid.covering(sub["window_origin"].astype(np.float64), sub.pitch, sub.window)
    geom = window_geometry(
        sub["x_i"].astype(np.float64), sub["window_origin"].astype(np.float64), grid, sub.window
    )
    pixel = np.broadcast_to(geom.pixel, (sub.n_points, sub.window[0] * sub.window[1]))
    held = (pair_half(np.arange(sub.n_points), pixel, grid) == 1).reshape(sub.n_points, *sub.window)
    R = np.asarray(sub.group["R_d"][...], dtype=np.float32)
    a = fit_planar(sub, "iso", half=0, max_rounds=1)
    R[held] *= 3.0
    zarr.open_group(str(sub.path), mode="r+")["R_d"][...] = R
    sub = open_dataset(sub.path)
    b = fit_planar(sub, "iso", half=0, max_rounds=1)
    np.testing.assert_array_equal(a.model.c, b.model.c)
    e_a, y_a = held_out_terms(a, homogeneous)
    e_b, y_b = held_out_terms(b, sub)
    assert y_b.sum() > 5 * y_a.sum() and e_b.sum() > 2 * y_a.sum()  # the score reads the corrupted half
    assert np.isclose(np.sqrt(e_a.sum() / y_a.sum()), held_out_error(a, homogeneous))


def test_a_mesh_half_fit_does_not_see_the_other_half(ball, tmp_path):
    sub = point_subset(ball, np.arange(ball.n_points), tmp_path / "copy.zarr")
    a = fit_mesh(sub.path, "iso", half=0, max_rounds=1)
    R = np.asarray(sub.group["R_d"][...], dtype=np.float32)
    held = vertex_half(np.arange(sub.n_points), np.arange(R.shape[1])) == 1
    R[held] *= 3.0
    zarr.open_group(str(sub.path), mode="r+")["R_d"][...] = R
    b = fit_mesh(sub.path, "iso", half=0, max_rounds=1)
    np.testing.assert_array_equal(a.model.c, b.model.c)
    np.testing.assert_array_equal(a.model.alpha.values, b.model.alpha.values)
    e, y = mesh_held_out_terms(a, open_mesh_dataset(ball.path).group)
    assert e.shape == (ball.n_points,) and (y > 0).all()
    # the held-out error of the right model is near the data's own noise, far below one term's
    one = fit_mesh(ball.path, "iso", n_terms=1, half=0, max_rounds=1)
    e1, y1 = mesh_held_out_terms(one, open_mesh_dataset(ball.path).group)
    assert e.sum() / y.sum() < 0.5 * e1.sum() / y1.sum()


# -- the choice on scans -------------------------------------------------------------------------------


def test_a_homogeneous_scan_gets_one_direction(homogeneous):
    fit = fit_planar(homogeneous)
    record = fit.options["structure"]
    assert record["chosen"]["n_directions"] == 1 and fit.model.n_directions == 1
    assert fit.model.c.shape[-1] == record["chosen"]["n_terms"]
    assert record["points"] == homogeneous.n_points  # fewer points than the subset's least: all of them
    # the structure given by name is fitted as given, with no choice recorded
    assert "structure" not in fit_planar(homogeneous, "iso").options


def test_a_fibrous_scan_gets_directions_that_win_held_out(fibers):
    fit = fit_planar(fibers)
    record = fit.options["structure"]
    m = record["chosen"]["n_directions"]
    assert m >= 4 and fit.model.n_directions == m
    table = {row["value"]: row for row in record["axes"]["n_directions"]}
    assert table[m]["held_out"] < 0.85 * table[1]["held_out"]  # the lamellae show on held-out pairs
    assert table[1]["delta"] > 3 * table[1]["se"]  # by far more than the split's noise


def test_a_mesh_fit_chooses_terms_and_colour(ball):
    fit = fit_mesh(ball.path)
    record = fit.options["structure"]
    assert set(record["axes"]) == {"colour", "n_terms"}
    assert record["chosen"]["n_terms"] >= 2  # one exponential is far from a ball's profile
    assert fit.model.c.shape[1] == (1 if record["chosen"]["colour"] == "shared" else 3)
    assert "through" in fit.model.measured  # the final fit is a whole one (what a renderer needs)


# -- what the user is told ------------------------------------------------------------------------------


def test_cli_reports_the_choice_and_takes_the_papers_structure(homogeneous, tmp_path):
    out = tmp_path / "m.model.zip"
    r = runner.invoke(app, ["fit", str(homogeneous.path), "-o", str(out), "--json"])
    assert r.exit_code == 0, r.output
    summary = json.loads(r.output.strip().splitlines()[-1])
    assert summary["structure"]["chosen"]["label"].startswith("iso")
    assert summary["structure"]["runner_up"]["label"] != summary["structure"]["chosen"]["label"]
    r = runner.invoke(app, ["info", str(out)])
    assert "structure" in r.output and "held-out" in r.output
    paper = tmp_path / "paper.model.zip"
    argv = [
        "fit",
        str(homogeneous.path),
        "-o",
        str(paper),
        "--model",
        "aniso",
        "--colour",
        "shared",
        "--json",
    ]
    r = runner.invoke(app, argv)
    assert r.exit_code == 0, r.output
    assert json.loads(r.output.strip().splitlines()[-1])["structure"] is None
    model = tl.load_model(paper)
    assert model.c.shape[1:3] == (1, 8)  # one colour row (1, s_g, s_b), eight directions


# -- a named family with one axis auto ------------------------------------------------------------------


def _errors(record, axis):
    return {row["value"]: row["held_out"] for row in record["axes"][axis]}


def test_halves_interleave_and_alternate_between_points(homogeneous):
    grid = SampleGrid.covering(homogeneous["window_origin"].astype(np.float64), 0.25, homogeneous.window)
    pixel = np.arange(grid.shape[0] * grid.shape[1])[None, :].repeat(2, axis=0)
    h = pair_half(np.array([0, 1]), pixel, grid)
    assert abs(h[0].mean() - 0.5) < 0.01  # half of every window
    assert (h[0] != h[1]).all()  # a pixel held out in one window is fitted in the next
    row, col = np.divmod(pixel[0], grid.shape[1])
    assert (h[0] != pair_half(np.array([0]), (pixel[0] + 1)[None], grid)[0])[col < grid.shape[1] - 1].all()


def test_homogeneous_material_gets_one_direction(homogeneous):
    fit = fit_planar(homogeneous, "aniso", n_terms="auto", n_directions="auto", max_rounds=3)
    record = fit.options["structure"]
    assert set(record["axes"]) == {"n_terms", "n_directions"}  # the colour was given (per channel)
    assert record["chosen"]["n_directions"] == 1
    assert fit.model.kind == "exponential" and fit.model.n_directions == 1
    assert fit.model.c.shape[-1] == record["chosen"]["n_terms"]
    e = _errors(record, "n_directions")
    # no direction count buys anything on held-out pairs (none more than 3 % below the isotropic error) ...
    assert min(e.values()) >= e[1] / 1.03
    # ... and the terms were searched too (two to four; the record lists each one tried)
    assert set(_errors(record, "n_terms")) <= {2, 3, 4} and len(_errors(record, "n_terms")) >= 2


def test_fibers_get_many_directions(fibers):
    fit = fit_planar(fibers, "aniso", n_terms=3, n_directions="auto", max_rounds=3)
    record = fit.options["structure"]
    m = record["chosen"]["n_directions"]
    assert m >= 4 and fit.model.n_directions == m and set(record["axes"]) == {"n_directions"}
    e = _errors(record, "n_directions")
    # the lamellae's anisotropy shows on held-out pairs: the chosen m beats isotropy by a wide margin
    assert e[m] < 0.85 * e[1]


def test_held_out_error_of_the_right_model_is_near_its_in_sample_error(homogeneous):
    """Fitted on half 0 and scored on half 1, the isotropic model is as good as on pairs it saw (it does not
    fit the noise); a 16-direction fit is not better held out (it has nothing to find)."""
    iso = fit_planar(homogeneous, "iso", half=0, max_rounds=3)
    aniso = fit_planar(homogeneous, "aniso", n_directions=16, half=0, max_rounds=3)
    e_iso, e_aniso = held_out_error(iso, homogeneous, near=1.0), held_out_error(aniso, homogeneous, near=1.0)
    assert e_aniso >= e_iso * 0.99


def test_bad_selection_options(homogeneous):
    with pytest.raises(TranslucencyError, match="directions"):
        fit_planar(homogeneous, "iso", n_directions="auto")
    with pytest.raises(TranslucencyError, match="terms"):
        fit_planar(homogeneous, "iso", n_terms="many")
    with pytest.raises(TranslucencyError, match="half"):
        fit_planar(homogeneous, "iso", half=2)
    with pytest.raises(TranslucencyError, match="half"):  # a held-out fit of a structure still to choose
        fit_planar(homogeneous, half=0)
