"""Does the exit's half of the lean help where light crosses the body, with an exit κ of its own?

The budget's oracle (``objects_budget.py --orders``) drew every vertex's exits by their own direction and
gained on the back-lit cases; the model's exit half (``leaned(..., exit=True)``, the lean both ways) lost.
The model's exit factor per pair is

    F_oi = exp(κ_o ℓ_o · (x_i − x_o)/r) / N(κ_o, (x_i − x_o)/r, n_o),   ℓ_o the camera's lean vector at x_o,

with the exit κ the light's (model/lean.py).  This script asks whether it is the size of κ_o that is wrong
or the factor's shape: for each case, one acquisition with the normal beam and 60° × 4 oblique beams, one
fit (``fit``'s defaults, the lean from the oblique beams), and the object drawn as ``render --angles`` draws
it (the through-body table and the light's lean) and with the exit factor on every near pair at κ_o = c κ
for each ``--scale`` c, each with and without the half-space exit law (the factor replaces it), against
the converged reference (rel. RMSE / FLIP / brightness):

    python benchmarks/exit_lean.py --meshes ../shared/meshes --spp 2304 --case CASE [--scale 0.25 ...]

Cases as in ``unscattered.py``.  The far field is drawn without the exit factor, as the lean draws it.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import tempfile
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from translucency.acquire.mesh import acquire_mesh
from translucency.angles import Incidence
from translucency.fit.mesh import fit_mesh
from translucency.mitsuba import mesh_scene
from translucency.model.lean import exit_normalisation, lean_vector
from translucency.render.compare import compare
from translucency.render.picture import VertexPicture, coverage
from translucency.render.reference import converged_reference
from translucency.transport.irradiance import vertex_irradiance
from translucency.transport.lean import light_lean, tilted
from translucency.transport.matrices import transport_matrices
from translucency.transport.relight import exit_fresnel, relight_vertices, view_cosines
from unscattered import scene_of


def exit_factors(leaned_T, mesh, eye, scale: float):
    """The light-leaned transport's near matrices (one per channel, as COO) and each pair's exit factor
    F_oi at κ_o = ``scale`` κ (M, 3)."""
    M = [leaned_T.tilt.matrix(leaned_T, c).tocoo() for c in range(3)]
    o, i = M[0].row, M[0].col
    rcv = o if leaned_T.receivers is None else np.asarray(leaned_T.receivers)[o]
    X = np.asarray(mesh.vertices, np.float64)
    n = np.asarray(mesh.vertex_normals, np.float64)
    v = X[i] - X[rcv]  # toward the incident vertex, mm
    r = np.linalg.norm(v, axis=1, keepdims=True)
    d = np.divide(v, r, out=np.zeros_like(v), where=r > 0)
    to_eye = np.asarray(eye, np.float64)[None, :] - X
    to_eye /= np.linalg.norm(to_eye, axis=1, keepdims=True)
    ell_o = lean_vector(to_eye, n, 1.0)[rcv]  # the camera's lean vector at each pair's receiver
    kappa_o = scale * leaned_T.lean[:, 0].astype(np.float64)[rcv]  # (M, 3)
    a = np.einsum("mk,mk->m", ell_o, d)
    F = np.exp(kappa_o * a[:, None]) / exit_normalisation(kappa_o, d, n[rcv], 1.0)
    return M, F


def run_case(case: str, args, scales) -> dict:
    """One case: the rows of the module docstring, printed and returned."""
    name, P, N, mesh, volume, light, camera, spp = scene_of(case, args.meshes, args.size)
    mask = coverage(mesh, camera)
    reference, info = converged_reference(mesh, volume, light, camera, mask, spp=spp or args.spp)
    data = acquire_mesh(
        mesh, volume, args.work / f"{name}_{P}x{N}_lean60.zarr", n_points=P, photons=N, seed=3,
        chunk_points=32, index_matched=True, incidence=Incidence((60.0,), 4),
    )  # fmt: skip
    model = fit_mesh(data, "iso").model
    scene = mesh_scene(mesh)
    picture = VertexPicture(mesh, camera, spp=16, light=light)
    T = transport_matrices(model, mesh)
    law = T.incidence("half-space")
    E = vertex_irradiance(mesh, scene, light, incidence=law)
    exit_law = law.exit(view_cosines(mesh, camera.origin))
    fresnel = exit_fresnel(mesh, camera.origin, 1.0)[:, None]

    def draw(transport, with_law=True):
        L = relight_vertices(transport, E) * fresnel
        img = picture.draw(L * exit_law if with_law and exit_law is not None else L)
        c = compare(reference, img, mask)
        return c["rel_rmse"], c["flip_mean_object"], float(img[mask].mean() / reference[mask].mean())

    T_light = tilted(T, mesh, light_lean(light, mesh, scene, 1.0))
    rows = [("the table (render)", draw(T)), ("+ the light's lean (render --angles)", draw(T_light))]
    for c in scales:
        M, F = exit_factors(T_light, mesh, camera.origin, c)
        mats = [
            sp.csr_matrix((m.data * F[:, k].astype(np.float32), (m.row, m.col)), m.shape)
            for k, m in enumerate(M)
        ]
        both = dataclasses.replace(T_light, matrices=mats, tilt=None)
        rows.append((f"+ the exit's lean, κ_o = {c:g} κ", draw(both)))
        rows.append((f"+ the exit's lean, κ_o = {c:g} κ, no exit law", draw(both, with_law=False)))
    for label, (e, f, b) in rows:
        print(f"{name:<22} {label:<50} rel RMSE {e:.3f}  FLIP {f:.3f}  brightness {b:.3f}", flush=True)
    return {
        "case": case,
        "reference_noise": info["noise"],
        "rows": [{"row": lab, "rel_rmse": e, "flip": f, "brightness": b} for lab, (e, f, b) in rows],
    }


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--meshes", type=Path, default=Path("../shared/meshes"))
    ap.add_argument("--case", action="append", required=True, help="a case spec (unscattered.py)")
    ap.add_argument("--spp", type=int, default=256, help="samples per pixel of each of the two references")
    ap.add_argument("--scale", type=float, action="append", help="κ_o / κ (default 0.25, 0.5, 1)")
    ap.add_argument("--size", type=int, nargs=2, default=(128, 96))
    ap.add_argument("--work", type=Path, default=Path(tempfile.mkdtemp(prefix="exit_lean_")))
    args = ap.parse_args()
    args.work.mkdir(parents=True, exist_ok=True)
    scales = args.scale or [0.25, 0.5, 1.0]
    out = [run_case(case, args, scales) for case in args.case]
    (args.work / "exit_lean.json").write_text(json.dumps(out, indent=1))
    print(f"written: {args.work / 'exit_lean.json'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
