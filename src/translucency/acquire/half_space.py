r"""The half-space's profile table: a homogeneous, index-matched, isotropically scattering half-space lit
by a normal pencil beam, tallied by photon walks (:func:`translucency.acquire.transport.random_walk`).

The profile of such a half-space depends on the albedo :math:`\alpha = \sigma_s/\sigma_t` alone once
distances are measured in mean free paths: :math:`R_d(r) = \sigma_t^2 f(\sigma_t r; \alpha)`.  This
module tallies f once per albedo on a grid (:func:`half_space_table`); :mod:`translucency.model.half_space`
reads the shipped table and interpolates it.  Unlike the dipole it holds the near peak (single and
low-order scattering, the 1/ρ core of the first scattering), which is what the import's near-peak model
needs where a clipped spot hides it (:mod:`translucency.rig.object.near_peak`).

Regenerate the shipped table (minutes)::

    python -m translucency.acquire.half_space src/translucency/data/half_space_profiles.npz
"""

from __future__ import annotations

import sys

import numpy as np

from .transport import TOP, random_walk
from .volume import Volume

#: albedos σ_s/σ_t of the table
ALBEDOS = (0.2, 0.4, 0.6, 0.7, 0.8, 0.85, 0.9, 0.93, 0.95, 0.97, 0.98, 0.99, 0.995, 0.998, 0.999)
#: radial bin edges in mean free paths: a first disc, then log-spaced annuli
RHO_EDGES = np.concatenate([[0.0], np.geomspace(0.01, 80.0, 90)])
#: the slab standing for the half-space: depth and width in mean free paths (σ_t = 1 mm⁻¹)
DEPTH, WIDTH, VOXEL = 300.0, 600.0, 20.0


def half_space_table(photons: int = 400_000, *, seed: int = 0) -> dict:
    r"""f(ρ; α) (annulus means, (len(ALBEDOS), len(RHO_EDGES) − 1)) and the total diffuse reflectance
    R_tot(α) = Σ exits / photons, for σ_t = 1 mm⁻¹ (so ρ in mm), three albedos a walk (one a channel).

    Examples
    --------
    >>> from translucency.acquire.half_space import half_space_table
    >>> t = half_space_table(2_000)   # the shipped table: 2,000,000 photons an albedo (minutes)
    >>> t["f"].shape, bool((t["R_total"] < 1).all())
    ((15, 90), True)
    """
    shape = (int(DEPTH / VOXEL), int(WIDTH / VOXEL), int(WIDTH / VOXEL))
    ring_area = np.pi * np.diff(RHO_EDGES**2)
    f = np.zeros((len(ALBEDOS), len(RHO_EDGES) - 1))
    total = np.zeros(len(ALBEDOS))
    for start in range(0, len(ALBEDOS), 3):
        group = list(ALBEDOS[start : start + 3])
        group += [group[-1]] * (3 - len(group))
        volume = Volume.homogeneous(
            shape,
            VOXEL,
            sigma_s=group,
            sigma_a=[1.0 - a for a in group],
            g=0.0,
            eta=1.0,
            description={"generator": "half-space table"},
        )
        for ch in range(min(3, len(ALBEDOS) - start)):
            res = random_walk(
                volume,
                ch,
                np.array([[WIDTH / 2, WIDTH / 2]]),
                photons,
                seed=seed + 101 * (start + ch),
                index_matched=True,
            )
            top = res.code == TOP
            rho = np.hypot(res.x[top] - WIDTH / 2, res.y[top] - WIDTH / 2)
            f[start + ch] = np.histogram(rho, RHO_EDGES)[0] / (photons * ring_area)
            total[start + ch] = top.sum() / photons
    return {
        "albedo": np.asarray(ALBEDOS),
        "rho_edges": RHO_EDGES,
        "f": f,
        "R_total": total,
        "photons": photons,
    }


def main(argv) -> None:
    out = argv[1] if len(argv) > 1 else "half_space_profiles.npz"
    photons = int(argv[2]) if len(argv) > 2 else 400_000
    np.savez_compressed(out, **half_space_table(photons))
    print(f"wrote {out}")


if __name__ == "__main__":
    main(sys.argv)
