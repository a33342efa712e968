"""The anisotropic fit's regularisation (issue 13, item 3): shrinkage towards the mean of the
directions and anchors at r = 0 and beyond the window (``fit/_regularise.py``, module docstring).

Judged against an independent acquisition of the same sample (another photon seed), never only
against the data the model was fitted to.
"""

import numpy as np
import pytest

from translucency.evaluate.errors import planar_errors
from translucency.fit.planar import fit_planar


def _scans(planar_scan, sample):
    """3 × 3 points over 2 mm, 6 mm windows of 0.25 mm: the fitted data (40 k photons, seed 1) and the
    truth (120 k photons, seed 2) of one volume (generator seed 4)."""
    return [
        planar_scan(sample, side=3, span=2.0, photons=photons, seed=seed, volume_seed=4)
        for photons, seed in ((40_000, 1), (120_000, 2))
    ]


@pytest.fixture(scope="module")
def homogeneous(planar_scan):
    return _scans(planar_scan, "homogeneous:marble")


@pytest.fixture(scope="module")
def fibers(planar_scan):
    return _scans(planar_scan, "fibers")


def _fits(data):
    iso = fit_planar(data, "iso", max_rounds=3)
    aniso = fit_planar(data, "aniso", n_directions=8, max_rounds=3)
    return iso, aniso


def test_homogeneous_material_gives_isotropic_directions(homogeneous):
    """Nothing directional to find: held out, the anisotropic model is as good as the isotropic one,
    and in-sample it gains no more than its extra parameters' share of the noise (unregularised, it
    was 15 % worse held out and 12 % below the isotropic in-sample error on these data)."""
    data, truth = homogeneous
    iso, aniso = _fits(data)
    held = [planar_errors(f.model, truth).rel_l2 for f in (iso, aniso)]
    assert held[1] <= 1.02 * held[0]
    seen = [planar_errors(f.model, data).rel_l2 for f in (iso, aniso)]
    assert seen[1] >= 0.98 * seen[0]


def test_fibers_keep_their_direction_and_a_physical_total(fibers):
    """A directional sample is not shrunk away, and no direction grows a spike at x_i or a slow tail:
    the model's total reflectance matches the truth's tally of every exit as the isotropic one does."""
    data, truth = fibers
    iso, aniso = _fits(data)
    e_iso, e_aniso = (planar_errors(f.model, truth) for f in (iso, aniso))
    assert e_aniso.rel_l2 < 0.8 * e_iso.rel_l2
    tally = truth["total_diffuse"].astype(np.float64)
    for f in (iso, aniso):
        ratio = f.model.total_reflectance() * np.mean(f.model.alpha.values) / tally
        assert abs(np.median(ratio) - 1) < 0.2 and ratio.max() < 1.6
    assert (aniso.model.total_reflectance() < 1).all()


def test_fitted_totals_respect_the_measured_energy():
    """No profile may carry more energy than the point reflects: on the embedded sample, unguarded, 25 of
    1,024 isotropic profiles had totals of 1.04–1.96 where the tally says 0.38–0.81 (a term too slow for
    the window to see, or a spike inside the first pixel). Judged against the independent truth's tally."""
    from translucency.data import default_dataset_path, default_truth_path
    from translucency.io.dataset import open_dataset

    data, truth = open_dataset(default_dataset_path()), open_dataset(default_truth_path())
    tally = truth["total_diffuse"].astype(np.float64)
    iso = fit_planar(data, "iso").model
    total = iso.total_reflectance() * np.mean(iso.alpha.values)
    assert (total <= 1.0).all()
    ratio = total / tally
    assert np.median(np.abs(ratio - 1)) < 0.1 and ratio.max() < 1.5, np.percentile(ratio, [50, 100])
    # the anisotropic model: its directions are tied to the (bounded) isotropic fit at r = 0 and beyond
    # the window (bounding each point's mean over directions too cost fibers 20 % held out: not done)
    aniso = fit_planar(data, "aniso", n_directions=8).model
    ratio = aniso.total_reflectance() * np.mean(aniso.alpha.values) / tally
    assert np.median(np.abs(ratio - 1)) < 0.1 and np.quantile(ratio, 0.99) < 1.5, np.percentile(
        ratio, [50, 99]
    )
