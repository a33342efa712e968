r"""Radial profiles of measured data and the three model families fitted to them.

For an incident point of a planar data set, the window is averaged over rings
of one pixel width around x_i (the pixel under the beam is excluded: the
exclusion radius of one pixel), and the exponential sum, the dipole and the
Burley profile are fitted to the ring means by relative least squares.  The
errors are reported in the distance bands of the evaluation: near
(r < 1 mm), mid (1–4 mm) and far (> 4 mm).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..fit.profile import fit_burley_profile, fit_dipole_profile, fit_exponential_profile
from ..io.dataset import PlanarDataset
from ..model.burley import burley_R
from ..model.dipole import dipole_R_d

BANDS = {"near": (0.0, 1.0), "mid": (1.0, 4.0), "far": (4.0, np.inf)}


def ring_profile(window: np.ndarray, pitch: float) -> tuple[np.ndarray, np.ndarray]:
    """Ring means of a (H, W) window centred on x_i: (r in mm, mean R_d), r >= one pixel."""
    h, w = window.shape
    yy, xx = np.mgrid[0:h, 0:w]
    r = np.hypot(xx - w // 2, yy - h // 2) * pitch
    ring = np.round(r / pitch).astype(int)
    n_rings = min(h, w) // 2 + 1
    sums = np.bincount(ring.ravel(), window.ravel(), minlength=n_rings)[:n_rings]
    cnt = np.bincount(ring.ravel(), minlength=n_rings)[:n_rings]
    radii = np.arange(n_rings) * pitch
    keep = (np.arange(n_rings) >= 1) & (cnt > 0)
    return radii[keep], sums[keep] / cnt[keep]


@dataclass
class MeasuredProfile:
    """Measured ring profile of one incident point and channel, with the three fits."""

    point: int
    r: np.ndarray
    measured: np.ndarray
    exponential: np.ndarray
    dipole: np.ndarray
    burley: np.ndarray

    def band_errors(self, which: str) -> dict:
        """Relative L2 error of a fit in each distance band."""
        fit = getattr(self, which)
        out = {}
        for name, (lo, hi) in BANDS.items():
            sel = (self.r >= lo) & (self.r < hi)
            if sel.any():
                out[name] = float(np.linalg.norm(fit[sel] - self.measured[sel]) / np.linalg.norm(self.measured[sel]))
        return out


def measured_profile(ds: PlanarDataset, point: int, channel: int = 1, n_terms: int = 3) -> MeasuredProfile:
    """Fit exponential, dipole and Burley profiles to one incident point of ``ds``."""
    window = np.asarray(ds.group["R_d"][point, :, :, channel], dtype=np.float64)
    r, y = ring_profile(window, ds.pitch)
    ok = y > 0
    r, y = r[ok], y[ok]
    eta = float(ds.header["sample"]["eta"])
    expo = fit_exponential_profile(r, y, n_terms)
    sa, sp, _ = fit_dipole_profile(r, y, eta, sigma_a0=0.01, sigma_s_prime0=2.0)
    A, s, _ = fit_burley_profile(r, y, A0=0.8, s0=1.0)
    return MeasuredProfile(point, r, y, expo(r), dipole_R_d(r, sa, sp, eta), burley_R(r, A, s))


def plot_measured(profiles: list[MeasuredProfile], path, title: str) -> None:
    """Figure 1 (left) style: measured ring profiles and the three fits, log scale."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(profiles), figsize=(4.2 * len(profiles), 3.6), squeeze=False)
    for ax, p in zip(axes[0], profiles):
        ax.semilogy(p.r, p.measured, "ko", ms=3, label="measured (virtual DISCO)")
        ax.semilogy(p.r, p.exponential, "-", color="tab:orange", lw=2, label="3 exponentials (fit)")
        ax.semilogy(p.r, p.dipole, "--", color="tab:green", lw=1.5, label="dipole (fit)")
        ax.semilogy(p.r, p.burley, ":", color="tab:blue", lw=1.5, label="Burley (fit)")
        e, d = p.band_errors("exponential"), p.band_errors("dipole")
        ax.set_title(f"x_i #{p.point}: near err exp {100 * e['near']:.0f}% / dipole {100 * d['near']:.0f}%",
                     fontsize=9)
        ax.set_xlabel("r [mm]")
        ax.set_ylabel("$R_d$ [mm$^{-2}$] (G)")
        ax.grid(alpha=0.3, which="both")
    axes[0][0].legend(fontsize=7)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
