r"""Errors of a per-vertex model on a mesh data set's oblique beams (``acquire mesh --incidence``): held out,
what the lean (:mod:`translucency.model.lean`) predicts of light arriving at an angle against what the
paper's model does.

For incident point i and oblique beam d (toward the light :math:`w_d`, cosine :math:`\mu_d` to the normal)
both models start from the fitted profile at the data set's pairs, :math:`\hat R(x_i, v) = \alpha(v)
P_i(r)`, and take the beam's total from the model's own incidence law (Chandrasekhar's plane albedo of the
point's measured total, :mod:`translucency.model.incidence`; nothing of the data set's oblique totals):

.. math:: \hat R_{paper}(d, v) = F(\mu_d)\, \hat R(x_i, v), \qquad
          \hat R_{lean}(d, v) = \hat R_{paper}(d, v)\, e^{g_d(v)} / Z_d,

the lean's exponent :math:`g_d(v) = \kappa_i \vec\ell_d \cdot \hat d_v - \lambda_i (\vec\ell_d \cdot n_i) r`
(:func:`~translucency.model.lean.lean_exponent`) and Z_d normalising over the pairs that count (the fit's
exclusion radius, as :mod:`.mesh_errors`). The relative L2 error over all pairs, beams and channels, and the
data's noise on the same scale (the barycentric tally's variance :math:`R_d / (2 N A_v)`), are returned.
"""

from __future__ import annotations

import numpy as np

from ..fit.mesh import exclusion_radius, mean_edge_length, read_pairs
from ..io.mesh_dataset import MeshDataset, open_mesh_dataset
from ..model.incidence import incidence_law
from ..model.lean import lean_exponent, lean_vector
from .mesh_errors import TALLY_VARIANCE_FACTOR


def oblique_errors(
    model, dataset, *, exclusion_mm: float | None = None, chunk_points: int = 16
) -> dict | None:
    """Relative L2 errors of ``model`` on the oblique beams of a mesh data set, with and without its lean.

    Parameters
    ----------
    model : ReflectanceModel
        A mesh model of the data set's incident points (its fit, or another acquisition's).
    dataset : MeshDataset or path
        With oblique beams; None is returned for a data set without them.
    exclusion_mm : float, optional
        Pairs closer than this are left out (default: half the mean edge length, as the fit).

    Returns
    -------
    dict or None
        ``paper`` and ``lean`` (None for a model without a lean): relative L2 errors; ``noise``: the data's
        own on that scale; ``beams``: oblique beams per point; ``polar_deg``.

    Examples
    --------
    A ball scanned with beams at 45° besides the normal ones, fitted (with its lean) and scored on the
    oblique beams:

    >>> import tempfile, trimesh
    >>> import translucency as tl
    >>> from translucency.evaluate.oblique_errors import oblique_errors
    >>> ball = trimesh.creation.icosphere(2, radius=4.0)
    >>> data = tl.acquire_mesh(ball, tempfile.mkdtemp() + "/ball.zarr", "homogeneous:marble", voxel_mm=1.0,
    ...                        points=4, photons=300, index_matched=True, incidence=(45,), azimuths=2)
    >>> e = oblique_errors(tl.fit_model(data, "iso", n_terms=1, max_rounds=1).model, data)
    >>> e["beams"], e["polar_deg"], bool(e["lean"] < e["paper"])
    (2, [45.0], True)
    """
    ds = dataset if isinstance(dataset, MeshDataset) else open_mesh_dataset(dataset)
    inc = ds.incidence
    if inc.count == 1:
        return None
    vertices = ds["vertices"].astype(np.float64)
    incident = np.asarray(ds["incident"])
    x_i = vertices[incident]
    P, V = len(incident), len(vertices)
    area = ds["vertex_area"].astype(np.float64)
    exclusion = exclusion_radius(mean_edge_length(vertices, np.asarray(ds["faces"])), exclusion_mm)
    frames = ds.incident_frames()
    w = inc.world(frames)[:, 1:]  # (P, D, 3) toward the light
    mu = inc.local()[1:, 2]  # (D,) cosines to the normal
    eta = 1.0 if ds.header.get("request", {}).get("index_matched") else float(ds.header["eta"])
    total = (model.measured or {}).get("total")
    law = incidence_law("half-space", total, eta)  # the model's own law of the oblique totals
    lean = (model.measured or {}).get("lean")  # (P, 2, 3): κ, λ
    alpha_o = model.alpha.at(vertices)
    var_scale = TALLY_VARIANCE_FACTOR / (float(ds.header["photons"]) * np.maximum(area, 1e-12))
    err2 = {"paper": 0.0, "lean": 0.0}
    ref2 = var = 0.0
    for s in range(0, P, chunk_points):
        e = min(s + chunk_points, P)
        _, r, ok = read_pairs(ds.group, vertices, x_i, exclusion, s, e)
        i = np.broadcast_to(np.arange(s, e)[:, None], r.shape)
        pred = model.R_d(
            i, np.broadcast_to(vertices, (e - s, V, 3)), alpha_o=np.broadcast_to(alpha_o, r.shape)
        )  # (k, V, 3)
        y = np.asarray(ds.group["R_d_oblique"][s:e], dtype=np.float64)  # (k, D, V, 3)
        ok = ok[:, None, :] & np.isfinite(y).all(axis=3)
        F = law.at(np.arange(s, e)).factor(np.broadcast_to(mu, (e - s, len(mu))))  # (k, D, 3) or None
        F = np.ones((e - s, len(mu), 3)) if F is None else F
        paper = F[:, :, None, :] * pred[:, None]  # (k, D, V, 3)
        predictions = {"paper": paper}
        if lean is not None:
            predictions["lean"] = _lean_prediction(
                paper, pred, lean[s:e], vertices, x_i[s:e], w[s:e], frames[s:e], eta, r, ok, area
            )
        for name, p in predictions.items():
            err2[name] += float(np.where(ok[..., None], (p - y) ** 2, 0.0).sum())
        ref2 += float(np.where(ok[..., None], y**2, 0.0).sum())
        var += float(np.where(ok[..., None], y * var_scale[None, None, :, None], 0.0).sum())
    rel = {k: float(np.sqrt(v / ref2)) if ref2 > 0 else float("nan") for k, v in err2.items()}
    return {
        "paper": rel["paper"],
        "lean": rel["lean"] if lean is not None else None,
        "noise": float(np.sqrt(var / ref2)) if ref2 > 0 else float("nan"),
        "beams": int(inc.count - 1),
        "polar_deg": [float(t) for t in inc.polar_deg],
    }


def _lean_prediction(paper, pred, lean, vertices, x_i, w, frames, eta, r, ok, area) -> np.ndarray:
    """A chunk's lean R_d (k, D, V, 3), mm⁻²: the paper's times e^g / Z, Z over the pairs that count."""
    d = vertices[None] - x_i[:, None]  # (k, V, 3)
    d /= np.maximum(np.linalg.norm(d, axis=2, keepdims=True), 1e-12)
    ell = lean_vector(w, frames[:, None, 2], eta)  # (k, D, 3)
    g = lean_exponent(
        lean[:, 0, None, None, :],
        lean[:, 1, None, None, :],
        ell[:, :, None, None, :],
        d[:, None, :, None, :],
        frames[:, None, None, None, 2],
        r[:, None, :, None],
    )  # (k, D, V, 3)
    lobe = np.exp(g) * ok[..., None]
    base = pred[:, None] * area[None, None, :, None] * ok[..., None]
    Z = (base * lobe).sum(2) / np.maximum(base.sum(2), 1e-300)  # (k, D, 3)
    return paper * lobe / np.maximum(Z[:, :, None, :], 1e-300)
