"""How two estimates of the same radiance image agree: per-pixel z-scores, ring profiles around the beam."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._validate import TranslucencyError
from .window import RadianceImage


def z_scores(a: RadianceImage, b: RadianceImage) -> np.ndarray:
    """Per-pixel, per-channel z = (a − b)/sqrt(var_a + var_b); NaN where both variances are 0.

    Examples
    --------
    >>> x, y = np.meshgrid([0.5, 1.5], [0.5, 1.5])
    >>> a = RadianceImage(np.ones((2, 2, 1)), np.full((2, 2, 1), 0.01), x, y, (0,), 0.0)
    >>> b = RadianceImage(np.full((2, 2, 1), 0.8), np.full((2, 2, 1), 0.01), x, y, (0,), 0.0)
    >>> z_scores(a, b)[..., 0].round(4)   # 0.2 / √0.02
    array([[1.4142, 1.4142],
           [1.4142, 1.4142]])
    """
    if a.radiance.shape != b.radiance.shape:
        raise TranslucencyError(f"images: shapes differ, {a.radiance.shape} and {b.radiance.shape}")
    s = np.sqrt(a.variance + b.variance)
    return np.divide(a.radiance - b.radiance, s, out=np.full(s.shape, np.nan), where=s > 0)


def ring_profile(image: RadianceImage, centre_xy, edges_mm) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mean radiance of the pixels whose centres lie in each ring around ``centre_xy``.

    Returns (ring mid-radii (R,), mean (R, C), variance of the mean (R, C)),
    pixels taken as independent; empty rings are NaN.

    Examples
    --------
    >>> x, y = np.meshgrid([-0.5, 0.5], [-0.5, 0.5])   # four pixels 0.71 mm from the centre
    >>> image = RadianceImage(np.arange(4.0).reshape(2, 2, 1), np.ones((2, 2, 1)), x, y, (0,), 0.0)
    >>> r, mean, var = ring_profile(image, (0.0, 0.0), [0.0, 0.5, 1.0])
    >>> r.tolist(), mean[:, 0].tolist(), var[:, 0].tolist()   # the inner ring is empty; var: 4 × 1 / 4²
    ([0.25, 0.75], [nan, 1.5], [nan, 0.25])
    """
    edges = np.asarray(edges_mm, dtype=np.float64)
    r = np.hypot(image.x - centre_xy[0], image.y - centre_xy[1])
    ring = np.digitize(r, edges) - 1
    R, C = len(edges) - 1, image.radiance.shape[-1]
    mean = np.full((R, C), np.nan)
    var = np.full((R, C), np.nan)
    for k in range(R):
        m = ring == k
        if m.any():
            mean[k] = image.radiance[m].mean(axis=0)
            var[k] = image.variance[m].sum(axis=0) / m.sum() ** 2
    return 0.5 * (edges[1:] + edges[:-1]), mean, var


@dataclass(kw_only=True)
class Agreement:
    """How two estimates of the same radiance image agree.

    ``z``: per-pixel, per-channel z-scores where either estimate has a
    variance (flattened); ``ring_*``: ring averages (R, C) around the beam with
    variances and their z-scores ``ring_z``.

    Examples
    --------
    >>> agree = Agreement(z=np.array([0.5, -1.0, 4.0, 0.5]), ring_r=np.array([0.25]),
    ...                   ring_ours=np.array([[1.1]]), ring_ours_var=np.array([[0.02]]),
    ...                   ring_ref=np.array([[1.0]]), ring_ref_var=np.array([[0.02]]))
    >>> agree.ring_z.round(4).tolist()   # 0.1 / √0.04
    [[0.5]]
    >>> s = agree.summary()
    >>> s["frac_abs_z_gt_3"], round(s["ring_chi2_per_dof"], 6)   # one of four pixels beyond 3σ
    (0.25, 0.25)
    """

    z: np.ndarray
    ring_r: np.ndarray
    ring_ours: np.ndarray
    ring_ours_var: np.ndarray
    ring_ref: np.ndarray
    ring_ref_var: np.ndarray

    @property
    def ring_z(self) -> np.ndarray:
        """(ours − ref)/σ per ring and channel; NaN for empty rings or zero variance."""
        s = np.sqrt(self.ring_ours_var + self.ring_ref_var)
        ok = np.isfinite(s) & (s > 0)
        return np.divide(self.ring_ours - self.ring_ref, s, out=np.full(s.shape, np.nan), where=ok)

    def summary(self) -> dict:
        """Mean and standard deviation of the pixel z-scores, fraction with |z| > 3, and ring χ²/dof."""
        z = self.z
        rz = self.ring_z[np.isfinite(self.ring_z)]
        return {
            "pixels": int(z.size),
            "z_mean": float(z.mean()),
            "z_std": float(z.std()),
            "frac_abs_z_gt_3": float(np.mean(np.abs(z) > 3)),
            "ring_chi2_per_dof": float(np.mean(rz**2)) if rz.size else float("nan"),
        }


def compare(ours: RadianceImage, ref: RadianceImage, centre_xy, ring_edges_mm) -> Agreement:
    """z-scores of ``ours`` against ``ref`` per pixel, and their ring profiles around ``centre_xy``.

    Examples
    --------
    >>> x, y = np.meshgrid([-0.5, 0.5], [-0.5, 0.5])
    >>> ours = RadianceImage(np.full((2, 2, 1), 1.1), np.full((2, 2, 1), 0.02), x, y, (0,), 0.0)
    >>> ref = RadianceImage(np.ones((2, 2, 1)), np.full((2, 2, 1), 0.02), x, y, (0,), 0.0)
    >>> agree = compare(ours, ref, (0.0, 0.0), [0.0, 1.0])
    >>> agree.z.round(4).tolist(), agree.ring_z.round(4).tolist()   # the ring's mean is 2× surer: √4
    ([0.5, 0.5, 0.5, 0.5], [[1.0]])
    """
    z = z_scores(ours, ref)
    r, m_o, v_o = ring_profile(ours, centre_xy, ring_edges_mm)
    _, m_r, v_r = ring_profile(ref, centre_xy, ring_edges_mm)
    return Agreement(
        z=z[np.isfinite(z)],
        ring_r=r,
        ring_ours=m_o,
        ring_ours_var=v_o,
        ring_ref=m_r,
        ring_ref_var=v_r,
    )
