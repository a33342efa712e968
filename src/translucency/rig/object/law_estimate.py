r"""The exit law γ estimated from the photographs themselves (``exit_law: "from-views"``).

The first :data:`LAW_SHOTS` shots are read once more by views that reach :data:`LAW_GRAZING_DEG` from
the normal; every vertex that two or more cameras see whole (outside the spot) gives its radiance cell
means L, their cosines μ, slants :math:`s = \omega\cdot\hat t` and distance r (mm) from the hit to
:func:`.exit_law.fit_from_views`.
"""

from __future__ import annotations

import numpy as np

from .cameras import Camera
from .exit_law import ExitLaw, fit_from_views
from .radiance import shot_cell_means
from .setup import ObjectRig
from .views import CameraView, prepare_view

#: the laser shots the exit law is estimated from (the first ones)
LAW_SHOTS = 16

#: the views the exit law is estimated from reach this close to grazing (degrees from the normal)
LAW_GRAZING_DEG = 85.0


def estimate_law(rig: ObjectRig, cameras: list[CameraView], mesh, scene, hits, area) -> ExitLaw:
    """The exit law from views of the first :data:`LAW_SHOTS` shots, closer to grazing than the data's."""
    # the law sees views closer to grazing than the data do: its normalisation needs them
    law_cams = [
        prepare_view(c, cam.camera, rig, mesh, scene, grazing_deg=LAW_GRAZING_DEG)
        for c, cam in zip(rig.cameras, cameras)
    ]
    return law_from_views(rig, law_cams, rig.shots[:LAW_SHOTS], mesh, hits, area)


def _slant(mesh, camera: Camera, hit: np.ndarray) -> np.ndarray:
    """s = ω·t̂ per vertex: the view towards ``camera`` against the unit tangent pointing away from the hit."""
    v = np.asarray(mesh.vertices, dtype=np.float64)
    n = np.asarray(mesh.vertex_normals, dtype=np.float64)
    omega = camera.centre - v
    omega /= np.linalg.norm(omega, axis=1, keepdims=True)
    t = v - hit
    t -= np.einsum("ij,ij->i", t, n)[:, None] * n
    t /= np.maximum(np.linalg.norm(t, axis=1, keepdims=True), 1e-12)
    return np.einsum("ij,ij->i", omega, t)


def law_from_views(rig: ObjectRig, cameras: list[CameraView], shots, mesh, hits, area) -> ExitLaw:
    """The exit law γ estimated from vertices seen by two cameras in ``shots``
    (:func:`.exit_law.fit_from_views`)."""
    Ls, vs, mus, ss, rs = [], [], [], [], []
    for shot in shots:
        per_cam, _ = shot_cell_means(shot, cameras, rig)
        r = np.linalg.norm(mesh.vertices - hits[shot.index], axis=1)
        L = np.full((len(cameras), len(area), 3), np.nan)
        v = np.full_like(L, np.nan)
        mu = np.zeros((len(cameras), len(area)))
        sl = np.zeros_like(mu)
        for k, (cam, cm) in enumerate(zip(cameras, per_cam)):
            if cm is None:
                continue
            good = (cm[2] / np.maximum(area, 1e-30) >= rig.min_coverage) & (r > rig.spot_radius_mm)
            good &= cam.map.den / np.maximum(area, 1e-30) >= 0.95  # views of the whole cell only
            L[k][good], v[k][good] = cm[0][good], cm[1][good]
            mu[k] = cam.map.mu_v
            sl[k] = _slant(mesh, cam.camera, hits[shot.index])
        Ls.append(L)
        vs.append(v)
        mus.append(mu)
        ss.append(sl)
        rs.append(r)
    return fit_from_views(
        np.concatenate(Ls, axis=1),
        np.concatenate(vs, axis=1),
        np.concatenate(mus, axis=1),
        np.concatenate(ss, axis=1),
        np.concatenate(rs),
    )
