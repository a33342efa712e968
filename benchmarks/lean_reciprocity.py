"""How reciprocal the lean is (model/lean.py): S(x_i, ω_l → x_o, ω_v) against S(x_o, ω_v → x_i, ω_l).

A marble ball (6 mm radius, 642 vertices) acquired with the normal beam and 4 beams at 60° per incident
point, fitted (the lean: κ, λ), its near transport prepared (no far field).  For a directional light ω_l
and a distant camera ω_v, and then with the two swapped, each pair (o, i) whose source faces the first
direction and receiver the second is drawn both ways; the lean's factor on each (the leaned value over the
paper's) is compared:

    |log( f(i, l → o, v) / f(o, v → i, l) )|, weighted by the pair's power

for the lean of the light alone (``render --angles``) and for the lean both ways (the camera's too:
``leaned(..., exit=True)``).  Exact reciprocity gives 0.

    python benchmarks/lean_reciprocity.py
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np
import trimesh

from translucency.acquire.mesh import acquire_mesh, object_volume
from translucency.angles import Incidence
from translucency.fit.mesh import fit_mesh
from translucency.mitsuba import mesh_scene
from translucency.render.lights import DirectionalLight
from translucency.transport.lean import leaned
from translucency.transport.matrices import transport_matrices


def main() -> int:
    tmp = Path(tempfile.mkdtemp(prefix="lean_reciprocity_"))
    ball = trimesh.creation.icosphere(3, radius=6.0)
    vol = object_volume("homogeneous:marble", ball, 1.0, seed=3)
    data = acquire_mesh(
        ball, vol, tmp / "ball.zarr", n_points=24, photons=4000, seed=3, chunk_points=8,
        index_matched=True, incidence=Incidence((60.0,), 4),
    )  # fmt: skip
    model = fit_mesh(data, "iso").model
    T = transport_matrices(model, ball, far_field=False)
    paper = T.matrices[min(1, len(T.matrices) - 1)].tocsr()  # green
    scene = mesh_scene(ball)
    l = np.array([1.0, -0.3, 0.4]) / np.linalg.norm([1.0, -0.3, 0.4])
    v = np.array([-0.2, 1.0, 0.5]) / np.linalg.norm([-0.2, 1.0, 0.5])
    n = np.asarray(ball.vertex_normals)

    def green(light_dir, view_dir, exit):
        tilted = leaned(T, ball, scene, DirectionalLight(tuple(-light_dir)), 1e5 * view_dir, exit=exit)
        return tilted.tilt.matrix(T, 1)

    for exit, label in ((False, "the light's lean (render --angles)"), (True, "the lean both ways")):
        forward, backward = green(l, v, exit).tocoo(), green(v, l, exit)
        o, i = forward.row, forward.col
        keep = (o != i) & (n[i] @ l > 0.2) & (n[o] @ v > 0.2)
        o, i = o[keep], i[keep]
        f_fwd = forward.data[keep] / np.asarray(paper[o, i]).ravel()
        f_bwd = np.asarray(backward[i, o]).ravel() / np.asarray(paper[i, o]).ravel()
        log_ratio = np.abs(np.log(f_fwd / f_bwd))
        w = forward.data[keep] / forward.data[keep].sum()
        print(
            f"{label:<36} |log S(i→o)/S(o→i)|: power-weighted mean {np.sum(w * log_ratio):.3f}, "
            f"95th percentile {np.percentile(log_ratio, 95):.3f} ({keep.sum():,} pairs)"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
