"""Where an oblique beam's power goes, by distance from its entry, against the normal beam's shape and the
lean (model/lean.py): the table of docs/lean.md, "The lean".

For up to ``--points`` incident points of a mesh data set acquired with ``--incidence`` (green channel),
the share of each oblique beam's power per band of |x_o − x_i| and through the body (d̂ · n_i < −0.5):
measured, predicted by the normal beam's shape (the paper's model), by the lean with κ alone and with κ
and λ (both fitted from the same data set: in-sample, as a check of the structure, not of the fit).

    python benchmarks/lean_bands.py DATASET.zarr [--points=200]

The documented table used the back-lit marble spot with every vertex a source (``objects_budget.py
--angles --data-axes`` writes it: spot-marble-backlit_2930x2000_axes.zarr).
"""

from __future__ import annotations

import sys

import numpy as np

from _options import options
from translucency.fit.lean import fit_lean
from translucency.io.mesh_dataset import open_mesh_dataset
from translucency.model.lean import lean_vector

EDGES = (0.0, 1.0, 2.0, 4.0, 8.0, 16.0, np.inf)


def main() -> int:
    path, opts = options(sys.argv, {"points": 200, "seed": 0})
    if path is None:
        raise SystemExit("give a mesh data set acquired with --incidence")
    ds = open_mesh_dataset(path)
    X = np.asarray(ds["vertices"], np.float64)
    A = np.asarray(ds["vertex_area"], np.float64)
    incident = np.asarray(ds["incident"])
    frames = ds.incident_frames()
    w = ds.incidence.world(frames)[:, 1:]
    rng = np.random.default_rng(opts["seed"])
    pts = np.sort(rng.choice(len(incident), min(opts["points"], len(incident)), replace=False))
    lean = fit_lean(ds)  # (P, 2, 3)
    names = ("measured", "normal beam's shape", "lean, κ only", "lean, κ and λ")
    shares = {k: np.zeros(len(EDGES)) for k in names}  # bands, then "through"
    for p in pts:
        R0 = np.asarray(ds.group["R_d"][p], np.float64)[:, 1]
        R1 = np.asarray(ds.group["R_d_oblique"][p], np.float64)[..., 1]
        d = X - X[incident[p]]
        r = np.linalg.norm(d, axis=1)
        use = r > 0
        d_hat = np.divide(d, r[:, None], out=np.zeros_like(d), where=use[:, None])
        ell = lean_vector(w[p], frames[p, 2][None])
        a, depth = ell @ d_hat.T, (ell @ frames[p, 2])[:, None] * r[None, :]
        band = np.clip(np.digitize(r, EDGES) - 1, 0, len(EDGES) - 2)
        through = (d_hat @ frames[p, 2] < -0.5) & use
        kappa, lam = lean[p, 0, 1], lean[p, 1, 1]
        kappa_only = kappa  # the joint fit's κ with λ set to 0 (the κ-only fit differs a little)
        M0 = A * R0 * use
        for k in range(len(w[p])):
            M1 = A * R1[k] * use
            for name, M in (
                ("measured", M1),
                ("normal beam's shape", M0),
                ("lean, κ only", M0 * np.exp(kappa_only * a[k])),
                ("lean, κ and λ", M0 * np.exp(kappa * a[k] - lam * depth[k])),
            ):
                M = M / M.sum()
                shares[name][:-1] += np.bincount(band[use], M[use], minlength=len(EDGES) - 1)
                shares[name][-1] += M[through].sum()
    n = len(pts) * len(w[0])
    head = [f"{lo:g}–{hi:g} mm" for lo, hi in zip(EDGES[:-1], EDGES[1:], strict=True)] + ["through"]
    print(f"{'share of an oblique beam power (G)':<36}" + "".join(f"{h:>11}" for h in head))
    for name, v in shares.items():
        print(f"{name:<36}" + "".join(f"{x / n:>11.3f}" for x in v))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
