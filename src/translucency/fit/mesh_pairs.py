"""The pairs (incident point i, vertex v) of a mesh data set as the fit reads them.

The low-level pieces shared by the mesh fit (:mod:`.mesh`), its held-out score (:mod:`.held_out`), its
through-body table (:mod:`.through`) and the evaluation (:mod:`translucency.evaluate.mesh_errors`): the
mesh's pitch (mm), the exclusion radius around x_i derived from it (mm), and rows of R_d (mm⁻²) with the
Euclidean distance r = |v − x_i| (mm) and the pairs that count.
"""

from __future__ import annotations

import numpy as np

__all__ = ["exclusion_radius", "mean_edge_length", "read_pairs"]


def read_pairs(group, vertices: np.ndarray, x_i: np.ndarray, exclusion: float, s: int, e: int):
    """Rows ``s:e`` of a mesh data set's group as the fit reads them: the measured R_d (k, V, 3) float32
    (mm⁻²), the Euclidean distance r = |v − x_i| (k, V) in mm, and the pairs that count (finite, r at least
    ``exclusion``: the incident vertex's own tally is left out; in a data set measured from photographs,
    the pairs its ``flags`` mark as not measured).  ``vertices`` (V, 3) and ``x_i`` (P, 3) float64 mm.
    The evaluation reads the pairs the same way (:mod:`translucency.evaluate.mesh_errors`)."""
    y = np.asarray(group["R_d"][s:e], dtype=np.float32)
    r = np.linalg.norm(vertices[None] - x_i[s:e, None], axis=2)
    valid = np.isfinite(y).all(axis=2) & (r >= exclusion)
    if "flags" in group:
        valid &= np.asarray(group["flags"][s:e]) == 0
    return y, r, valid


def mean_edge_length(vertices: np.ndarray, faces: np.ndarray) -> float:
    """Mean length (mm) of the first edge of every face: the mesh fit's pitch; its default exclusion
    radius is half of it."""
    return float(np.mean(np.linalg.norm(vertices[faces[:, 0]] - vertices[faces[:, 1]], axis=1)))


def exclusion_radius(pitch: float, exclusion_mm: float | None = None) -> float:
    """The radius (mm) within which pairs are left out: ``exclusion_mm``, or the fit's default, half the
    mesh's pitch (:func:`mean_edge_length`: the incident vertex's own cell)."""
    return pitch / 2 if exclusion_mm is None else float(exclusion_mm)
