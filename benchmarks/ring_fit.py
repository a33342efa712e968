"""The fit's term in the picture: the fitted exponentials against exponentials fitted to the ring means.

The error budget (``objects_budget.py --fit``) puts the fit first among the back-lit marble's terms and
finds that non-negative exponentials on a fixed grid of rates, fitted to each incident point's ring means
(area-weighted means of R_d over rings of Euclidean r, one edge wide), come closer to the reference than
``fit``'s three exponentials fitted to the pairs.  This script asks it of the whole pipeline: the same
data set and model (``fit``'s default, a fall-off per channel), each point's profile replaced by

* ``rings``: K exponentials e^{−a r}, a on a geometric grid from 1/diagonal to 2/edge, amplitudes by
  NNLS on the ring means, each ring weighted by its area (where the light lies);
* ``fit + tail``: the fitted three, plus NNLS exponentials no faster than 1/``slow`` mm⁻¹ fitted to the
  ring means' excess over the fit beyond ``near`` mm — a fit whose tail follows the data;

and the object rendered by ``render``'s chain against the converged reference (relative RMSE, FLIP,
brightness, the thin parts' brightness and the unlit side's hue):

    python benchmarks/ring_fit.py --meshes ../shared/meshes --spp SPP --case CASE [--case CASE ...]

A case is as in ``unscattered.py`` (or ``pig``); its data set is acquired as there (seed 3, the
unscattered light apart) unless ``--work`` holds it already.
"""

from __future__ import annotations

import argparse
import copy
import json
import sys
import tempfile
from pathlib import Path

import numpy as np
from scipy.optimize import nnls

sys.path.insert(0, str(Path(__file__).parent))
from objects_budget import area_rings, ring_fit, ring_means  # noqa: E402
from translucency.acquire.mesh import acquire_mesh  # noqa: E402
from translucency.fit.mesh import fit_mesh  # noqa: E402
from translucency.io.mesh_dataset import open_mesh_dataset  # noqa: E402
from translucency.mitsuba import mesh_scene  # noqa: E402
from translucency.render.compare import compare, region_errors  # noqa: E402
from translucency.render.picture import VertexPicture, coverage  # noqa: E402
from translucency.render.reference import converged_reference  # noqa: E402
from translucency.transport.matrices import transport_matrices  # noqa: E402
from translucency.transport.relight import relight_object  # noqa: E402
from unscattered import scene_of  # noqa: E402

#: rates of the ``rings`` variant
RING_RATES = 8


def point_rings(ds):
    """(tables (P, n_bins, 3), ring area (P, n_bins), ring centres (n_bins,) mm, rates (K,) mm⁻¹)."""
    g = ds.group
    R_d = np.asarray(g["R_d"][...], dtype=np.float64)  # (P, V, 3)
    v = np.asarray(g["vertices"][...], dtype=np.float64)
    area = np.asarray(g["vertex_area"][...], dtype=np.float64)
    edges = v[np.asarray(g["faces"][...])]
    width = float(np.mean(np.linalg.norm(edges - np.roll(edges, 1, axis=1), axis=2)))  # mean edge, mm
    r = np.linalg.norm(v[np.asarray(g["incident"][...])][:, None] - v[None], axis=2)  # (P, V)
    n_bins = int(np.ceil(r.max() / width)) + 1
    tables = np.stack([ring_means(R_d[p], r[p], area, width, n_bins) for p in range(len(r))])
    centres = (np.arange(n_bins) + 0.5) * width
    rates = np.geomspace(1.0 / float(np.linalg.norm(np.ptp(v, axis=0))), 2.0 / width, RING_RATES)
    return tables, area_rings(r, area, width, n_bins), centres, rates


def with_profile(model, c, d):
    """A copy of ``model`` whose exponentials are c, d (P, 3, n): α, near field and frames kept."""
    out = copy.copy(model)
    out.c, out.d = c[:, :, None, :].copy(), np.ascontiguousarray(d[:, :, None, :])
    return out


def tail_profile(model, tables, ring_area, centres, rates, near, slow):
    """``fit + tail``: (c, d) (P, 3, 3 + K') of the fit plus NNLS tail terms (module docstring)."""
    c3, d3 = np.asarray(model.c)[:, :, 0, :], np.asarray(model.d)[:, :, 0, :]
    fitted = np.einsum("pck,pbck->pbc", c3, np.exp(d3[:, None] * centres[None, :, None, None]))
    slow_rates = rates[rates <= 1.0 / slow]
    A = np.exp(-np.outer(centres, slow_rates))
    ct = np.zeros((len(tables), 3, len(slow_rates)))
    for p in range(len(tables)):
        keep = (ring_area[p] > 0) & (centres > near)
        wgt = np.sqrt(ring_area[p, keep])
        for ch in range(3):
            excess = tables[p, keep, ch] - fitted[p, keep, ch]
            ct[p, ch] = nnls(A[keep] * wgt[:, None], excess * wgt, maxiter=500)[0]
    c = np.concatenate([c3, ct], axis=2)
    return c, np.concatenate([d3, np.broadcast_to(-slow_rates, ct.shape)], axis=2)


def _row(c: dict, label: str, model) -> dict:
    """Render ``model`` in the case ``c`` and print its line against the reference."""
    mesh, camera, reference, mask = c["mesh"], c["camera"], c["reference"], c["mask"]
    L, E, _ = relight_object(
        transport_matrices(model, mesh, through=False), mesh, c["scene"], c["light"], camera.origin
    )
    ours = c["picture"].draw(L)
    cmp = compare(reference, ours, mask)
    regions = region_errors(mesh, c["scene"], camera, E, reference, ours, mask)
    r = {
        "case": c["name"],
        "profile": label,
        "rel_rmse": cmp["rel_rmse"],
        "flip": cmp["flip_mean_object"],
        "brightness": float(ours[mask].mean() / reference[mask].mean()),
        "thin": regions["thin"]["brightness"],
        "unlit_hue": regions["unlit"]["colour"],
        "reference_noise": c["noise"],
    }
    hue = np.round(r["unlit_hue"], 2).tolist()
    print(
        f"{c['name']:<22} {label:<34} rel RMSE {r['rel_rmse']:.3f}  FLIP {r['flip']:.3f}  "
        f"brightness {r['brightness']:.3f}  thin {r['thin']:.2f}x  unlit hue {hue}  noise {c['noise']:.3f}",
        flush=True,
    )
    return r


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--meshes", type=Path, default=Path("../shared/meshes"))
    ap.add_argument("--case", action="append", required=True)
    ap.add_argument("--spp", type=int, default=256)
    ap.add_argument("--size", type=int, nargs=2, default=(128, 96))
    ap.add_argument("--work", type=Path, default=Path(tempfile.mkdtemp(prefix="ring_fit_")))
    ap.add_argument("--near", type=float, nargs="+", default=[2.0, 8.0], help="mm, the tail's start")
    ap.add_argument("--slow", type=float, nargs="+", default=[2.0, 5.0], help="mm, the tail's fastest 1/rate")
    args = ap.parse_args()
    args.work.mkdir(parents=True, exist_ok=True)
    out = []
    for case in args.case:
        name, P, N, mesh, volume, light, camera, spp = scene_of(case, args.meshes, args.size)
        mask = coverage(mesh, camera)
        reference, info = converged_reference(mesh, volume, light, camera, mask, spp=spp or args.spp)
        scene = mesh_scene(mesh)
        picture = VertexPicture(mesh, camera, spp=16, light=light)
        path = args.work / f"{name}_{P}x{N}_apart.zarr"
        if not path.exists():
            acquire_mesh(
                mesh, volume, path, n_points=P, photons=N, seed=3, chunk_points=32, index_matched=True
            )
        model = fit_mesh(path, "iso").model
        tables, ring_area, centres, rates = point_rings(open_mesh_dataset(path))

        case_ = dict(
            name=name,
            mesh=mesh,
            scene=scene,
            light=light,
            camera=camera,
            picture=picture,
            reference=reference,
            mask=mask,
            noise=info["noise"],
        )

        def row(label, m, c=case_):
            out.append(_row(c, label, m))

        row("fit (the default)", model)
        c = ring_fit(tables, ring_area, centres, rates, "energy")
        row(f"rings ({RING_RATES} exponentials)", with_profile(model, c, np.broadcast_to(-rates, c.shape)))
        for near in args.near:
            for slow in args.slow:
                c, d = tail_profile(model, tables, ring_area, centres, rates, near, slow)
                row(f"fit + tail beyond {near:g} mm, 1/a >= {slow:g} mm", with_profile(model, c, d))
    (args.work / "ring_fit.json").write_text(json.dumps(out, indent=2))
    print(f"written: {args.work / 'ring_fit.json'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
