r"""Radial profiles of the three models for the materials of Jensen's table.

For each material and channel this computes, on a radial grid (mm):

* the dipole :math:`R_d(r)` of Jensen et al. 2001 from the measured
  :math:`\sigma_a, \sigma_s'` and :math:`\eta = 1.3`;
* the best relative-least-squares fit of the Christensen–Burley profile
  (A and s free, started from the searchlight rule :math:`s = \tilde s(A)/\ell`,
  :math:`\ell = 1/\sigma_t'`);
* the best relative-least-squares n-term exponential fit (the paper's model).

Both families are fitted to the same dipole samples, so the comparison is one
of *shape*: how well two fixed-ratio exponentials over r, or n free
exponentials, follow diffusion theory's profile.

Until measured data exist this shows how the three families differ in shape;
the fits to physically simulated measurements come with the acquisition and
fitting stages.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .._plotting import pyplot
from ..fit.profile import ProfileFit, fit_burley_profile, fit_exponential_profile
from ..model.alpha import PlanarAlpha
from ..model.burley import burley_energy_within, burley_R, burley_shape
from ..model.dipole import dipole_R_d, dipole_total_reflectance
from ..model.exponential import ExponentialModel
from ..model.extent import SemiInfinite
from ..model.materials import Material

CHANNELS = ("R", "G", "B")


@dataclass
class MaterialProfiles:
    """Profiles (shape (J, 3), mm⁻²) and fits of one material.

    Examples
    --------
    >>> from translucency.model import material
    >>> p = material_profiles(material("marble"), r=np.linspace(0.1, 10.0, 60))
    >>> p.dipole.shape, bool((p.rel_l2("exponential") < 0.02).all())   # 3 exponentials: within 2 %
    ((60, 3), True)
    >>> p.rel_l2("burley").round(2)   # Burley's two: about 12 % from the dipole
    array([0.12, 0.11, 0.12])
    >>> p.summary()["total_reflectance_dipole"]   # Jensen's closed form, RGB
    [0.86654, 0.8338, 0.80099]
    """

    material: Material
    r: np.ndarray
    dipole: np.ndarray
    burley: np.ndarray
    exponential: np.ndarray
    fits: list[ProfileFit] = field(default_factory=list)
    total_dipole: np.ndarray | None = None
    burley_A: np.ndarray | None = None
    burley_s: np.ndarray | None = None

    def rel_l2(self, which: str) -> np.ndarray:
        """Relative L2 difference of ``which`` ("burley" or "exponential") from the dipole, per channel."""
        other = getattr(self, which)
        return np.linalg.norm((other - self.dipole) / self.dipole, axis=0) / np.sqrt(len(self.r))

    def summary(self) -> dict:
        return {
            "total_reflectance_dipole": self.total_dipole.round(5).tolist(),
            "total_reflectance_published": self.material.R_d_published.tolist(),
            "exp_fit_total": [float(2 * np.pi * np.sum(f.c / f.d**2)) for f in self.fits],
            "burley_fit_total": burley_energy_within(np.inf, self.burley_A, self.burley_s).round(5).tolist(),
            "exp_fit_rel_rms_vs_dipole": self.rel_l2("exponential").round(5).tolist(),
            "burley_fit_rel_rms_vs_dipole": self.rel_l2("burley").round(5).tolist(),
            "exp_fit": [{"c": f.c.tolist(), "d": f.d.tolist()} for f in self.fits],
            "burley_fit": {"A": self.burley_A.tolist(), "s": self.burley_s.tolist()},
        }


def material_profiles(mat: Material, r=None, n_terms: int = 3) -> MaterialProfiles:
    """Dipole, Burley and exponential-fit profiles of one material.

    Parameters
    ----------
    mat : Material
        A row of :data:`translucency.model.MATERIALS`.
    r : array_like, optional
        Radii in mm; default 400 points from 0.05 to 20 mm.
    n_terms : int
        Terms of the exponential fit.

    Examples
    --------
    >>> from translucency.model import material
    >>> p = material_profiles(material("skin1"))
    >>> p.dipole.shape
    (400, 3)
    """
    r = np.linspace(0.05, 20.0, 400) if r is None else np.asarray(r, dtype=float)
    dipole = dipole_R_d(r[:, None], mat.sigma_a, mat.sigma_s_prime, mat.eta)
    total = dipole_total_reflectance(mat.sigma_a, mat.sigma_s_prime, mat.eta)
    s0 = burley_shape(total, mat.mean_free_path)
    # per colour channel c
    burley_fits = [fit_burley_profile(r, dipole[:, c], A0=total[c], s0=s0[c]) for c in range(3)]
    A, s = (np.array([f[j] for f in burley_fits]) for j in (0, 1))
    burley = burley_R(r[:, None], A, s)
    fits = [fit_exponential_profile(r, dipole[:, c], n_terms) for c in range(3)]
    expo = np.stack([f(r) for f in fits], axis=1)
    return MaterialProfiles(mat, r, dipole, burley, expo, fits, total, A, s)


def fits_model(profiles: list[MaterialProfiles]) -> ExponentialModel:
    """The exponential fits of ``profiles`` as one per-channel model (C = 3, m = 1): one incident point
    per material, 1 mm apart along x.

    Jensen's coefficients describe semi-infinite slabs: the model's object is one
    (:class:`~translucency.model.extent.SemiInfinite`), so the physical bounds place no edge under its
    profiles (a skim-milk profile reaches beyond 100 mm).

    Examples
    --------
    >>> from translucency.model import MATERIALS
    >>> m = fits_model([material_profiles(MATERIALS["marble"])])
    >>> m.n_points, m.extent.kind
    (1, 'semi-infinite')
    """
    n = len(profiles)
    c = np.array([[[f.c] for f in p.fits] for p in profiles])  # (N, 3, 1, n)
    d = np.array([[[f.d] for f in p.fits] for p in profiles])
    x_i = np.stack([np.arange(n, dtype=float), np.zeros(n)], axis=1)
    model = ExponentialModel(x_i, c, d, PlanarAlpha.uniform((1, n), origin=(-0.5, -0.5), pitch=1.0))
    model.extent = SemiInfinite()
    return model


def plot_profiles(profiles: list[MaterialProfiles], path, channel: int = 1) -> None:
    """Write a PNG with one log-scale panel of R_d(r) per material.

    Examples
    --------
    Four panels a row, each 4 × 3.2 inches at 110 dpi (about a second a figure):

    >>> import tempfile
    >>> import matplotlib.image as mpimg
    >>> import numpy as np
    >>> from pathlib import Path
    >>> from translucency.evaluate.baselines import material_profiles, plot_profiles
    >>> from translucency.model import material
    >>> marble = material_profiles(material("marble"), r=np.linspace(0.1, 10.0, 60))
    >>> path = Path(tempfile.mkdtemp()) / "profiles.png"
    >>> plot_profiles([marble], path)
    >>> mpimg.imread(path).shape  # one row: 352 × 1760 pixels, RGBA
    (352, 1760, 4)

    Five materials or more take two rows (704 × 1760 pixels), nine or more three.
    """
    plt = pyplot()

    n = len(profiles)
    cols = 4
    rows = int(np.ceil(n / cols))
    fig, axes = plt.subplots(rows, cols, figsize=(4 * cols, 3.2 * rows), squeeze=False)
    for ax, p in zip(axes.ravel(), profiles):
        ax.semilogy(p.r, p.dipole[:, channel], "k-", lw=2, label="dipole (Jensen 2001)")
        ax.semilogy(
            p.r,
            p.exponential[:, channel],
            "--",
            color="tab:orange",
            lw=1.5,
            label=f"{len(p.fits[channel].c)} exponentials (fit)",
        )
        ax.semilogy(p.r, p.burley[:, channel], ":", color="tab:blue", lw=1.5, label="Burley (fit)")
        e = p.rel_l2("exponential")[channel]
        b = p.rel_l2("burley")[channel]
        ax.set_title(f"{p.material.name}: exp {100 * e:.1f}%, Burley {100 * b:.0f}%", fontsize=10)
        ax.set_xlabel("r [mm]")
        ax.set_ylabel(f"$R_d$ [mm$^{{-2}}$], {CHANNELS[channel]}")
        floor = max(p.dipole[:, channel].min(), 1e-12 * p.dipole[:, channel].max())
        ax.set_ylim(floor * 0.5, p.dipole[:, channel].max() * 3)
        ax.grid(alpha=0.3, which="both")
    for ax in axes.ravel()[n:]:
        ax.axis("off")
    axes.ravel()[0].legend(fontsize=8, loc="upper right")
    fig.suptitle(
        "Radial profiles of the Jensen 2001 materials: dipole, its 3-term exponential fit, "
        "and Christensen–Burley fitted to it (rms relative difference in the titles)",
        fontsize=11,
    )
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
