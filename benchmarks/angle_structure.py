"""How R_d depends on the direction of incidence and of exit, measured on a tally with both axes (issue 37).

Item 3 proposes, per incident point, a *first-order* dependence on the refracted incident direction (the
directional dipole's structure) and a per-vertex exit law.  This measures whether the data support that,
on a mesh of your choice, before any model is built.  With beams at one polar angle θ from K azimuths
φ_k of each incident point's tangent frame, every pair (x_i, x_o) has K readings R_d(φ_k); their Fourier
components over φ are

    c_0 = mean_k R_d(φ_k),   c_1 = |2/K Σ_k R_d(φ_k) e^{-i φ_k}|,   c_2 = |1/K Σ_k R_d(φ_k) (-1)^k|  (K = 4)

A first-order model holds c_0 and c_1; what it misses is c_2 (and beyond).  Printed per band of distance
|x_o − x_i| (sums over pairs weighted by the vertex areas, so a band's numbers are energies):

* ``oblique/normal``: c_0 against the normal beam's R_d — how much an oblique beam changes the total;
* ``c1/c0``, ``c2/c0``: the first and the second harmonic's size; ``forward``: the mean cosine between
  the first harmonic's phase and the azimuth of x_o seen from x_i, with the flight's direction (+1: light
  carried forward along the beam's tangent, the directional dipole's picture);
* the photon noise of c_2/c_0 (from the K readings' Poisson counts), so that a c_2 below it reads as zero;
* the exit law by band (the normal beam's bins): γ = π L / M per polar bin, away from and back toward x_i.

    python benchmarks/angle_structure.py [MESH.obj] [--size=20] [--up=y] [--material=marble]
        [--points=32] [--photons=20000] [--theta=60] [--folder=DIR]

MESH defaults to ``../shared/meshes/spot.obj`` when there (y up), else a 2,562-vertex icosphere.
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import numpy as np

from _options import options, sized_mesh
from translucency.acquire.mesh import acquire_mesh, object_volume
from translucency.angles import ExitBins, Incidence
from translucency.io.mesh_dataset import open_mesh_dataset

EDGES_MM = (0.0, 0.01, 1.0, 2.0, 4.0, 8.0, 16.0, np.inf)


DEFAULTS = {
    "size": 20.0,
    "up": "y",
    "material": "marble",
    "points": 32,
    "photons": 20000,
    "theta": 60.0,
    "folder": "",
}


def main(argv) -> None:
    path, o = options(argv, DEFAULTS)
    mesh = sized_mesh(path, o["size"], o["up"])
    folder = Path(o["folder"] or tempfile.mkdtemp(prefix="angle-structure-"))
    out = folder / "tally.zarr"
    K = 4
    incidence, bins = Incidence((o["theta"],), K), ExitBins(3)
    acquire_mesh(
        mesh, object_volume(o["material"], mesh, 0.5, seed=1), out, n_points=o["points"],
        photons=o["photons"], index_matched=True, incidence=incidence, exit_bins=bins, seed=3,
    )  # fmt: skip
    ds = open_mesh_dataset(out)
    v = np.asarray(ds["vertices"], dtype=np.float64)
    area = np.asarray(ds["vertex_area"], dtype=np.float64)
    incident = np.asarray(ds["incident"])
    frames = ds.incident_frames()  # (P, 3, 3): t, b, n
    R0 = ds.R_d_toward(0).astype(np.float64)  # (P, V, 3)
    Rk = np.stack([ds.R_d_toward(1 + k) for k in range(K)], axis=0).astype(np.float64)  # (K, P, V, 3)
    phi = 2 * np.pi * np.arange(K) / K
    c0 = Rk.mean(axis=0)
    a1 = (2.0 / K) * np.einsum("k,kpvc->pvc", np.exp(-1j * phi), Rk)
    # (with K = 4 the second harmonic's sin 2φ part vanishes at the samples: c_2 is its cos 2φ part only)
    c1, c2 = np.abs(a1), np.abs(np.einsum("k,kpvc->pvc", (-1.0) ** np.arange(K), Rk) / K)
    # the azimuth of x_o from x_i in each incident frame; the flight's tangent points at φ_k + π
    d = v[None, :, :] - v[incident][:, None, :]
    az = np.arctan2(np.einsum("pvk,pk->pv", d, frames[:, 1]), np.einsum("pvk,pk->pv", d, frames[:, 0]))
    # R_d(φ) = c_0 + c_1 cos(φ − φ*) gives a_1 = c_1 e^{−iφ*}; downstream means φ* + π = the azimuth of x_o
    forward = np.cos(-np.angle(a1) + np.pi - az[..., None])  # +1: the first harmonic peaks downstream
    # Poisson noise of c_2 (per pair: R_d = n / (N A), so Var R_d = R_d / (N A))
    N = ds.header["photons"]
    var_c2 = Rk.sum(axis=0) / (N * area[None, :, None]) / K**2
    r = np.linalg.norm(d, axis=2)
    binned = np.asarray(ds["exit_bins"][:, 0], dtype=np.float64)  # (P, V, 3, B) normal beams
    print(
        f"{len(v):,} vertices, {ds.n_points} points x {N:,} photons x {incidence.count} directions "
        f"(normal + {o['theta']:g} deg x {K}), {o['material']}, index-matched; energies weighted by area"
    )
    print("band mm      | oblique/normal RGB | c1/c0 RGB          | c2/c0 RGB (noise)         | forward")
    for lo, hi in zip(EDGES_MM[:-1], EDGES_MM[1:]):
        m = (r >= lo) & (r < hi)
        w = area[None, :] * m  # (P, V)

        def tot(x, w=w):
            return np.einsum("pvc,pv->c", x, w)

        e0, e1, e2, en = tot(c0), tot(c1), tot(c2), np.sqrt(np.einsum("pvc,pv->c", var_c2, w**2))
        fw = tot(forward * c1) / np.maximum(e1, 1e-30)
        print(
            f"{lo:4.2f}-{hi:<6.2f} | {' '.join(f'{x:5.2f}' for x in e0 / tot(R0))} | "
            f"{' '.join(f'{x:5.2f}' for x in e1 / e0)} | "
            f"{' '.join(f'{x:5.2f}' for x in e2 / e0)} ({' '.join(f'{x:5.3f}' for x in en / e0)}) | "
            f"{' '.join(f'{x:+5.2f}' for x in fw)}"
        )
    print("exit law of the normal beams, gamma = pi L / M per polar bin (cos theta edges "
          f"{', '.join(f'{c:.3f}' for c in bins.edges_cos)}), away | back, G channel:")  # fmt: skip
    for lo, hi in zip(EDGES_MM[:-1], EDGES_MM[1:]):
        m = ((r >= lo) & (r < hi)).astype(float) * area[None, :]
        law = bins.law(np.einsum("pvcb,pv->cb", binned, m))[1]  # (B,) green
        print(f"{lo:4.2f}-{hi:<6.2f} | away {' '.join(f'{x:4.2f}' for x in law[0::2])} | "
              f"back {' '.join(f'{x:4.2f}' for x in law[1::2])}")  # fmt: skip


if __name__ == "__main__":
    main(sys.argv)
