"""Model selection by held-out error with a named family: n_terms="auto", n_directions="auto" (the default
``model="auto"`` is tests/test_structure_choice.py)."""

import numpy as np
import pytest

from translucency._validate import TranslucencyError
from translucency.fit.held_out import held_out_error, pair_half
from translucency.fit.planar import fit_planar
from translucency.geometry import SampleGrid

#: 2 × 2 points over 2 mm, 100 k photons, seed 4 (volume and photons), as tests/test_evaluate.py's fibers
SCAN = dict(side=2, span=2.0, photons=100_000, seed=4)


@pytest.fixture(scope="module")
def homogeneous(planar_scan):
    return planar_scan("homogeneous:marble", **SCAN)


@pytest.fixture(scope="module")
def fibers(planar_scan):
    return planar_scan("fibers", **SCAN)


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
    # ... and more terms than the data support do not help either: one term is clearly short
    n = _errors(record, "n_terms")
    assert n[1] > 1.5 * min(n.values())


def test_fibers_get_many_directions(fibers):
    fit = fit_planar(fibers, "aniso", n_terms=3, n_directions="auto", max_rounds=3)
    record = fit.options["structure"]
    m = record["chosen"]["n_directions"]
    assert m >= 8 and fit.model.n_directions == m
    e = _errors(record, "n_directions")
    # the lamellae's anisotropy shows on held-out pairs: the chosen m beats isotropy by a wide margin
    assert e[m] < 0.7 * e[1]


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
