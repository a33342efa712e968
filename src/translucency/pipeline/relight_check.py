"""The relighting check: the sample under a pattern of light, each model against photon transport."""

from __future__ import annotations

import numpy as np

from ..acquire.pattern import acquire_pattern
from ..acquire.samples import sample_of_dataset
from ..acquire.volume import Volume
from ..evaluate.relight import pattern_irradiance, plot_relighting, relight

#: the models' pairs are summed out to this many half-windows: light crosses the grid from a lit cell
#: farther than half a window on the fibrous band (docs/accuracy.md, the relighting check)
RELIGHT_RADIUS_WINDOWS = 4


def relight_check(
    ds,
    models: dict,
    figure,
    *,
    pattern: str = "stripe",
    photons: int = 1000,
    seed: int = 5,
    volume: Volume | None = None,
) -> dict:
    """Relight the data set's sample with each model and with photon transport; plot and compare.

    The light falls on the cells of the incident grid (side = grid spacing);
    the exitance is compared on the data set's pixel grid over the scanned area
    plus a margin of half a window.

    Parameters
    ----------
    ds : PlanarDataset
        The scan (its sample is remade from its header unless ``volume`` is given).
    models : dict
        ``{name: model}``, each relit.
    figure : str or Path
        The plot to write.
    pattern : str
        The light's pattern over the incident grid's cells (``"stripe"``, ...).
    photons : int
        Photons per lit cell entry of the transport reference.
    seed : int
        The reference's photon seed.
    volume : Volume, optional
        The sample (default: the data set's, from its header).

    Returns
    -------
    dict
        ``pattern``, ``photons_per_entry``, ``rel_l2`` (each model's relative L2 error against the
        reference) and ``total_ratio`` (each model's total exitance over the reference's).

    Examples
    --------
    The shipped scan relit with a quick isotropic fit; its sample (the data set records a volume made by
    :func:`translucency.pipeline.demo_volume`) is given for the photon reference (10-20 s, so not run
    here):

    >>> import tempfile
    >>> from translucency.data import default_dataset
    >>> from translucency.fit.planar import fit_planar
    >>> from translucency.pipeline import demo_volume
    >>> from translucency.pipeline.relight_check import relight_check
    >>> ds = default_dataset()
    >>> models = {"iso": fit_planar(ds, "iso", n_terms=2, max_rounds=1).model}  # doctest: +SKIP
    >>> out = relight_check(ds, models, tempfile.mkdtemp() + "/relight.png", volume=demo_volume(),
    ...                     photons=200)  # doctest: +SKIP
    >>> sorted(out), sorted(out["rel_l2"])  # doctest: +SKIP
    (['pattern', 'photons_per_entry', 'rel_l2', 'total_ratio'], ['iso'])
    """
    x_i = ds["x_i"].astype(np.float64)
    spacing = float(np.min(np.diff(np.unique(x_i[:, 0]))))
    E = pattern_irradiance(pattern, x_i)
    margin = ds.pitch * (ds.window[1] // 2)
    origin = x_i.min(axis=0) - margin
    shape = tuple(int(round((np.ptp(x_i[:, k]) + 2 * margin) / ds.pitch)) for k in (1, 0))
    reference = acquire_pattern(
        volume if volume is not None else sample_of_dataset(ds.header),
        x_i,
        spacing,
        E,
        origin,
        ds.pitch,
        shape,
        photons=photons,
        seed=seed,
    )
    preds = {
        name: relight(m, E, spacing**2, origin, ds.pitch, shape, radius=RELIGHT_RADIUS_WINDOWS * margin)
        for name, m in models.items()
    }
    extent = [origin[0], origin[0] + shape[1] * ds.pitch, origin[1], origin[1] + shape[0] * ds.pitch]
    errors = plot_relighting(reference, preds, extent, figure)
    total = float(reference.sum())
    return {
        "pattern": pattern,
        "photons_per_entry": photons,
        "rel_l2": errors,
        "total_ratio": {n: float(B.sum() / total) for n, B in preds.items()},
    }
