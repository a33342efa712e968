"""Where the fitted profile puts a mesh data set's light, by the pair's orientation and distance.

For every incident point i and vertex o of a mesh data set (e.g. one that ``objects_table.py --work DIR``
left behind), the measured energy Σ A_o R_d(x_i, x_o) against the fitted model's Σ A_o α_o P_i(r) — the
paper's model and, with the through-body table, the extension (:mod:`translucency.model.through`) — for
the pairs whose normals face the same way (n_i · n_o > 0.5), sideways, and apart (< −0.5), and by r:

    python benchmarks/through_energy.py DIR/spot-marble-backlit.zarr

prints model / measured per channel (1 is right; the paper's model carried 0.45 / 0.57 / 0.79 of the back
pairs' energy on the back-lit marble spot of docs/through-body.md).
"""

from __future__ import annotations

import argparse
import importlib
from pathlib import Path

import numpy as np

from translucency.io.mesh_dataset import open_mesh_dataset
from translucency.model.through import through_factor

fit_mesh = importlib.import_module("translucency.fit.mesh").fit_mesh  # the module, not fit()'s name


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("dataset", type=Path)
    args = ap.parse_args()
    ds = open_mesh_dataset(args.dataset)
    g = ds.group
    m = fit_mesh(args.dataset, "iso").model
    v, n = np.asarray(g["vertices"][...], float), np.asarray(g["normals"][...], float)
    area, inc = np.asarray(g["vertex_area"][...], float), np.asarray(g["incident"][...])
    R = np.asarray(g["R_d"][...], float)  # (P, V, 3)
    r = np.linalg.norm(v[None] - v[inc][:, None], axis=2)
    i = np.broadcast_to(np.arange(len(inc))[:, None], r.shape)
    paper = m.R_d(i, np.broadcast_to(v, r.shape + (3,)), alpha_o=np.broadcast_to(m.alpha.at(v), r.shape))
    cos = n[inc] @ n.T
    src = np.repeat(np.arange(len(inc)), len(v))
    k = np.stack(
        [
            through_factor(m.measured["through"][..., ch], src, cos.ravel(), r.ravel()).reshape(r.shape)
            for ch in range(3)
        ],
        axis=2,
    )
    edge = 0.5 * np.mean(np.linalg.norm(v[g["faces"][:, 0]] - v[g["faces"][:, 1]], axis=1))
    ok = np.isfinite(R).all(axis=2) & (r >= edge)
    R = np.nan_to_num(R)

    def ratio(sel, model):
        w = (sel & ok).astype(float)
        meas = np.einsum("pv,v,pvc->c", w, area, R)
        return np.einsum("pv,v,pvc->c", w, area, model) / np.where(meas > 0, meas, np.nan), int(w.sum())

    print(f"{'pairs':<34} {'count':>8}   paper's model / measured   through-body table / measured")
    kinds = [
        ("same side (n.n > 0.5)", cos > 0.5),
        ("sideways", np.abs(cos) <= 0.5),
        ("apart (n.n < -0.5)", cos < -0.5),
    ]
    for lo, hi in [(0, 5), (5, 10), (10, 15), (15, 25)]:
        kinds.append((f"apart, r {lo}-{hi} mm", (cos < -0.5) & (r >= lo) & (r < hi)))
        kinds.append((f"same side, r {lo}-{hi} mm", (cos > 0.5) & (r >= lo) & (r < hi)))
    for label, sel in kinds:
        a, count = ratio(sel, paper)
        b, _ = ratio(sel, paper * k)
        print(f"{label:<34} {count:>8}   {np.round(a, 3)}   {np.round(b, 3)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
