"""Does the lean hold beyond the angle it was fitted at?  The main job's pig (Figure 2's object), the lean
fitted from beams at 60° (``lean_objects.py --case pig``'s acquisition: 96 points × 8,000 photons, seed
3), and held-out beams at a steeper polar angle (another seed's points and photons, 48 × 4,000, seed 5).
Each held-out oblique beam is predicted from the same point's normal beam (its shape; its total from the
held-out beam: the shape alone is judged) by

* the paper's model (the normal beam's shape),
* the lean with the light's lean vector as it is (|ℓ| grows past 60°'s, 1 at η = 1, toward √2),
* the lean with |ℓ| held at ``--cap`` (its value at the fitted angle and around it: the lobe not
  extrapolated),

and the relative L2 error over the power per vertex (all points, beams, channels) is printed.

    python benchmarks/lean_extrapolation.py --polar 80 --work /tmp/lo_pig
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

from translucency.acquire.mesh import acquire_mesh
from translucency.angles import Incidence
from translucency.fit.mesh import fit_mesh
from translucency.io.mesh_dataset import open_mesh_dataset
from translucency.model.lean import lean_vector
from translucency.pipeline import figure2_scene
from translucency.transport.parameters import neighbour_weights


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--polar", type=float, default=80.0, help="the held-out beams' polar angle, degrees")
    ap.add_argument("--cap", type=float, nargs="*", default=[0.9, 1.0, 1.2], help="|ℓ| caps to compare")
    ap.add_argument("--work", type=Path, default=Path(tempfile.mkdtemp(prefix="lean_extrapolation_")))
    args = ap.parse_args()
    args.work.mkdir(parents=True, exist_ok=True)
    mesh, volume, _, _ = figure2_scene()

    def acquire(P, N, seed, polar, chunk):
        path = args.work / f"pig_{P}x{N}_{seed}_lean{polar:g}.zarr"  # (lean_objects.py's name: reused)
        t = time.perf_counter()
        acquire_mesh(mesh, volume, path, n_points=P, photons=N, seed=seed, chunk_points=chunk,
                     index_matched=True, reentry=True, incidence=Incidence((polar,), 4))  # fmt: skip
        print(f"{path.name}: {time.perf_counter() - t:.0f} s")
        return path

    model = fit_mesh(acquire(96, 8000, 3, 60.0, 32), "iso").model
    w_, idx = neighbour_weights(model, mesh)
    lean = np.einsum("vk,vkac->vac", w_, model.measured["lean"][idx])  # κ, λ at every vertex (V, 2, 3)
    ds = open_mesh_dataset(acquire(48, 4000, 5, args.polar, 16))
    X = np.asarray(ds["vertices"], dtype=np.float64)
    area = np.asarray(ds["vertex_area"], dtype=np.float64)
    frames = ds.incident_frames()
    toward = ds.incidence.world(frames)[:, 1:]  # (P, D, 3) the oblique beams' directions toward the light
    R0_all, R1_all = np.asarray(ds["R_d"], np.float64), np.asarray(ds["R_d_oblique"], np.float64)
    rows = ["paper", "lean"] + [f"lean, |l| <= {c:g}" for c in args.cap]
    err, norm = dict.fromkeys(rows, 0.0), 0.0
    for p, j in enumerate(np.asarray(ds["incident"])):
        d = X - X[j]
        r = np.linalg.norm(d, axis=1)
        use = r > 0
        d_hat = np.divide(d, r[:, None], out=np.zeros_like(d), where=use[:, None])
        n = frames[p, 2]
        ell0 = lean_vector(toward[p], n[None])  # (D, 3)
        M0 = area[:, None] * R0_all[p] * use[:, None]  # (V, 3) the normal beam's power per vertex
        M1 = area[None, :, None] * R1_all[p] * use[None, :, None]  # (D, V, 3) the oblique beams'
        total = M1.sum(1)  # (D, 3)
        for row, cap in zip(rows, [None, None, *args.cap]):
            k, lam = np.zeros((2, 3)) if row == "paper" else lean[j]
            length = np.linalg.norm(ell0, axis=1, keepdims=True)
            ell = ell0 if cap is None else ell0 * np.minimum(1.0, cap / np.maximum(length, 1e-12))
            a, depth = ell @ d_hat.T, (ell @ n)[:, None] * r[None, :]  # (D, V)
            shaped = M0[None] * np.exp(a[..., None] * k - depth[..., None] * lam)
            pred = total[:, None, :] * shaped / shaped.sum(1, keepdims=True)
            err[row] += float(np.sum((pred - M1) ** 2))
        norm += float(np.sum(M1**2))
    print(f"held-out beams at {args.polar:g}° (|ℓ| = {np.linalg.norm(ell0, axis=1).mean():.3f}); "
          "relative L2 of the power per vertex:")  # fmt: skip
    for row in rows:
        print(f"  {row:<16} {np.sqrt(err[row] / norm):.3f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
