"""The error budget of a rendered object, by ablation against a converged reference (issue 12, item 7).

Each row replaces one approximation of the pipeline by its exact (measured) counterpart and renders the
object again; the change of the relative RMSE against the converged volpath reference is that
approximation's share.  Every render is L_o = (1/π) Σ_j A_j E_j K(x_j, x_o) for a kernel K (exitance at
x_o per unit power entering at x_j, mm⁻²), drawn by the same Mitsuba picture:

=================  ==================================================================================
oracle             K = the photon tally itself, every vertex an incident point (needs V² storage:
                   a mesh of a few thousand vertices) — what no per-vertex model can beat
oracle, radial     each vertex's own tally replaced by its ring means in Euclidean r (own area and total
                   kept): the local model — a radially symmetric profile of the straight-line distance
points, radial     the ring means of the P incident points only, blended to every vertex with the
                   renderer's weights: interpolation between incident points
points, fit        the fitted exponentials (α = 1) in place of the ring means: the fit
points, fit, α     the fitted α as well: what ``render`` draws (checked against transport_matrices)
=================  ==================================================================================

plus the acquisition noise (4× the photons), the near field (the profile at r_min instead of the
measured own area), the transport radius, the picture's samples per pixel and the reference's own noise,
and the oracle without re-entry (light that leaves one part through the air tallied where it left, not
carried into the next part as ``volpath`` carries it).  ``--oracle-only``: the two oracle rows alone.

``--orders`` splits the oracle by scattering order (0: unscattered, 1: single, ≥ 2: multiple) with
normal beams and with beams along the light, each order drawn as an exitance (the exit law, Lambertian)
or by its own direction toward the camera, and prints each order's share of the unlit side's exitance and
its hue beside the reference's.

``--angles`` (issue 37, step 1) splits the oracle's error by the angles the data are blind to, with walks
of its own (every vertex a source, the same photons, re-entry), under a light of one direction per point
(directional, point, spot):

=======================  =============================================================================
oracle, normal beams     each beam enters along −n; exitance × the incidence and exit laws (today's)
(a) direction oracle     each beam enters along the light's direction of travel at that vertex (index-
                         matched: not refracted), plain irradiance; exitance × the exit law
(b) exit oracle          normal beams; the radiance toward the camera tallied from the exits whose
                         direction lies within ``CONE_DEG`` of the vertex's view direction:
                         L = Σ φ_o w / (A_o Ω_c cos θ_o), no exit law
(c) both                 beams along the light and the radiance toward the camera
(d) the data's axes      what a data set with both axes holds (issue 37, step 2: ``acquire mesh
                         --incidence 60 --azimuths 4 --exit-bins 3``, every vertex a source): the light's
                         direction blended from the normal and the four 60° beams, the camera's direction
                         read from its exit bin — each axis alone, then both
=======================  =============================================================================
The default case is the cow with skin under a spot (issue 12's case); needs ``cow.obj``:

    python benchmarks/objects_budget.py --meshes ../shared/meshes
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import json
import tempfile
import time
from pathlib import Path

import numpy as np

from translucency.acquire.mesh import acquire_mesh, exit_barycentric, object_volume
from translucency.acquire.mesh_walk import EXIT, mesh_random_walk
from translucency.angles import ExitBins, Incidence
from translucency.fit.lean import fit_lean
from translucency.fit.mesh import fit_mesh
from translucency.geometry import tangent_frames, vertex_areas
from translucency.io.mesh import load_mesh
from translucency.io.mesh_dataset import open_mesh_dataset
from translucency.mitsuba import mesh_scene
from translucency.model.directions import direction_weights
from translucency.model.lean import exit_normalisation, lean_vector
from translucency.render.camera import Camera
from translucency.render.compare import channel_shares, compare, vertex_thickness
from translucency.render.lights import parse_light
from translucency.render.picture import VertexPicture, coverage
from translucency.render.reference import converged_reference
from translucency.render.tonemap import auto_exposure, save_images
from translucency.transport.irradiance import vertex_irradiance
from translucency.transport.matrices import transport_matrices
from translucency.transport.parameters import neighbour_weights
from translucency.transport.relight import relight_vertices, view_cosines

fit_module = importlib.import_module("translucency.fit.mesh")  # the module, not fit()'s name

#: the half-angle of the exit oracle's cone about each vertex's view direction, degrees
CONE_DEG = 25.0
#: ``--fit``'s "tail free" rows: the slowest rate a term may take, × 1/(object's diagonal) (the fit's own,
#: ``fit.mesh.ENERGY_RADIUS_RATE``, keeps 99.9 % of each term's energy within the object)
TAIL_RATE = 1.0
#: the fixed rates of the exponentials fitted to the ring means (``--fit``), 1/(object's diagonal) to 2/edge
RING_RATES = 8
#: the geometry factor's range (a source above the exit's plane still reaches it around the body)
G_RANGE = (0.1, 20.0)
#: ``--orders``: the scattering orders told apart, 0 (unscattered), 1 (single) and ≥ 2 (multiple)
ORDER_CLASSES = 3
ORDER_NAMES = ("0", "1", ">=2")
CASE = "cow-skin-spot:cow.obj:8:z:skin:128:4000:spot:-60,70,90,0,0,0,25,3e4:-1,1.2,0.6"


def ring_means(R: np.ndarray, r: np.ndarray, area: np.ndarray, width: float, n_bins: int) -> np.ndarray:
    """Area-weighted ring means of one source's tally R (V, 3) over Euclidean r (V,): (n_bins, 3), mm⁻².
    The source's own vertex (r = 0) is left out; empty rings are 0."""
    b = np.minimum((r / width).astype(int), n_bins - 1)
    keep = r > 0
    w = np.bincount(b[keep], area[keep], minlength=n_bins)
    out = np.stack([np.bincount(b[keep], area[keep] * R[keep, c], minlength=n_bins) for c in range(3)], 1)
    return np.divide(out, w[:, None], out=np.zeros_like(out), where=w[:, None] > 0)


def table_shape(tables, w, idx, r_all, width):
    """K (V_o, V_j, 3) before normalisation: the ring tables (P, n_bins, 3) of each source's k points,
    read at the ring of r_oj and blended with (w, idx) (V_j, k)."""
    n_bins = tables.shape[1]
    b = np.minimum((r_all / width).astype(int), n_bins - 1)  # (V_o, V_j)
    K = np.zeros(r_all.shape + (3,))
    for kk in range(w.shape[1]):
        K += w[None, :, kk, None] * tables[idx[:, kk][None, :], b]
    return K


def fit_shape(model, w, idx, r_all, r_min):
    """K (V_o, V_j, 3) before normalisation: the fitted exponentials of each source's k points at the
    exact distance (below r_min at r_min, as the renderer), blended with (w, idx); α = 1."""
    c, d = model.c[:, :, 0, :], model.d[:, :, 0, :]  # (P, C, n)
    r = np.maximum(r_all, r_min)
    K = np.zeros(r_all.shape + (3,))
    for kk in range(w.shape[1]):
        p = idx[:, kk]  # (V_j,)
        scale = model.colour_scale[p] if c.shape[1] == 1 else np.ones((len(p), 3))
        for ch in range(3):
            cc, dd = c[p, min(ch, c.shape[1] - 1)], d[p, min(ch, c.shape[1] - 1)]  # (V_j, n)
            prof = np.einsum("jn,ojn->oj", cc, np.exp(dd[None] * r[..., None]))
            K[..., ch] += w[None, :, kk] * scale[None, :, ch] * prof
    return K


def normalised(K, own, total, area_src, w, idx, area):
    """The near field as the renderer takes it (``render.transport``) applied to a kernel shape K
    (V_o, V_j, 3): total blended, the own cell's share of it f = A own / total blended (``area_src``: the
    cells of the points' vertices), each column scaled to carry total_j (1 − f_j), the own cell on the
    diagonal."""
    V = len(area)
    f = np.divide(area_src[:, None] * own, total, out=np.zeros_like(own), where=total > 0)
    f_j = np.einsum("vk,vkc->vc", w, np.clip(f, 0, 1)[idx])
    total_j = np.einsum("vk,vkc->vc", w, total[idx])
    K[np.arange(V), np.arange(V)] = 0.0
    spread = np.einsum("ojc,o->jc", K, area)
    target = total_j * (1.0 - f_j)
    K *= np.divide(target, spread, out=np.zeros_like(spread), where=spread > 0)[None]
    K[np.arange(V), np.arange(V)] = f_j * total_j / area[:, None]
    return K


def radiance(K, area, E):
    """L_o = (1/π) Σ_j A_j E_j K_oj per channel, (V, 3)."""
    E = np.repeat(E[:, None], 3, 1) if E.ndim == 1 else E
    return np.einsum("ojc,jc->oc", K, area[:, None] * E) / np.pi


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--meshes", type=Path, default=Path("../shared/meshes"))
    ap.add_argument("--case", default=CASE, help="as in objects_table.py")
    ap.add_argument("--spp", type=int, default=256, help="samples per pixel of each of the two references")
    ap.add_argument("--size", type=int, nargs=2, default=(128, 96))
    ap.add_argument("--work", type=Path, default=Path(tempfile.mkdtemp(prefix="objects_budget_")))
    ap.add_argument(
        "--incidence", default="half-space", help="the incidence law of every row (render --incidence-law)"
    )
    ap.add_argument("--oracle-only", action="store_true", help="the oracle with and without re-entry only")
    ap.add_argument("--no-reentry", action="store_true", help="the pipeline's data without re-entry")
    ap.add_argument("--angles", action="store_true", help="the oracle split by the angles in and out")
    ap.add_argument(
        "--fit",
        action="store_true",
        help="the fit's rows alone, with its colour structure and its tail (the oracle from --orders' walks)",
    )
    ap.add_argument(
        "--orders", action="store_true", help="the oracle split by scattering order (0, 1, >= 2), both beams"
    )
    ap.add_argument(
        "--kernel-seed", type=int, default=41, help="the seed of --angles' walks (another: their noise)"
    )
    ap.add_argument(
        "--data-axes", action="store_true", help="with --angles: also the rows of a data set with both axes"
    )
    ap.add_argument("--data-polar", default="60", help="--data-axes' polar angles of incidence, degrees")
    args = ap.parse_args()
    args.work.mkdir(parents=True, exist_ok=True)
    parts = args.case.split(":")  # the material may hold a colon itself (homogeneous:potato)
    (name, file, scale, up), material = parts[:4], ":".join(parts[4:-5])
    points, photons, kind, light, view = parts[-5:]
    P, N = int(points), int(photons)
    mesh = load_mesh(args.meshes / file, scale_mm=float(scale), up=up)
    V = len(mesh.vertices)
    volume = object_volume(material, mesh, 1.0, seed=3)
    light = parse_light(f"{kind}:{light}")
    if (args.angles or args.orders) and not light.delta:  # (before the reference is rendered)
        ap.error("--angles, --orders: a light of one direction per point (directional, point or spot)")
    camera = Camera.looking_at(mesh, [float(v) for v in view.split(",")], *args.size)
    mask = coverage(mesh, camera)
    reference, info = converged_reference(mesh, volume, light, camera, mask, spp=args.spp)
    (args.work / "rows").mkdir(exist_ok=True)
    save_images(reference, args.work / "rows" / "reference", auto_exposure(reference, mask))
    scene = mesh_scene(mesh)
    picture = VertexPicture(mesh, camera, spp=16, light=light)
    area = vertex_areas(mesh)

    def acquire(n_points, n_photons, seed=3, reentry=not args.no_reentry):
        return acquire_mesh(
            mesh,
            volume,
            args.work / f"{name}_{n_points}x{n_photons}_{seed}{'' if reentry else '_first_exit'}.zarr",
            n_points=n_points,
            photons=n_photons,
            seed=seed,
            chunk_points=32,
            index_matched=True,
            reentry=reentry,
        )

    def oracle_kernel(reentry: bool):
        """K[o, j]: the tally with every vertex an incident point."""
        oracle = open_mesh_dataset(acquire(V, N, reentry=reentry))
        R = np.asarray(oracle.group["R_d"][...], dtype=np.float64)  # (V_j, V_o, 3)
        K = np.zeros((V, V, 3))
        K[:, oracle["incident"]] = R.transpose(1, 0, 2)
        return K

    rows = []
    # the pixels the light does not reach directly: where each row's hue is measured against the reference's
    unlit = vertex_irradiance(mesh, scene, light) == 0
    unlit = (
        VertexPicture(mesh, camera, spp=1).draw(np.repeat(unlit[:, None], 3, 1).astype(float))[..., 0] > 0.5
    ) & mask

    def row(label, L, what, pic=picture, law=True):  # law=False: L is a radiance already, no exit law
        img = pic.draw(L * exit_law if law and exit_law is not None else L)
        cmp = compare(reference, img, mask)
        save_images(img, args.work / "rows" / _slug(label), auto_exposure(reference, mask))
        hue = channel_shares(img, unlit) / channel_shares(reference, unlit)  # 1 is right
        rows.append(
            {
                "row": label,
                "what": what,
                "rel_rmse": cmp["rel_rmse"],
                "flip": cmp["flip_mean_object"],
                "brightness": float(img[mask].mean() / reference[mask].mean()),
                "unlit_hue": hue.tolist(),
            }
        )
        print(
            f"{label:<34} rel RMSE {cmp['rel_rmse']:.3f}  FLIP {cmp['flip_mean_object']:.3f}  "
            f"brightness {rows[-1]['brightness']:.3f}  unlit hue {np.round(hue, 2).tolist()}",
            flush=True,
        )
        return img

    t0 = time.perf_counter()
    # the pipeline as `render` runs it
    fit = fit_mesh(acquire(P, N), "iso")
    model = fit.model
    # every row under the same light in and out: the pipeline's incidence law (its measured totals)
    T = transport_matrices(model, mesh, through=False)
    law = T.incidence(args.incidence)
    E = vertex_irradiance(mesh, scene, light, incidence=law)
    exit_law = law.exit(view_cosines(mesh, camera.origin))
    row("pipeline (render's default)", relight_vertices(T, E), "all terms")
    if args.oracle_only:
        for reentry in (True, False):
            label = "oracle: the tally, every vertex" if reentry else "oracle without re-entry"
            row(label, radiance(oracle_kernel(reentry), area, E), "the tally itself")
        return _written(args, V, info, rows, t0)
    if args.fit:  # the fit's term: its colour structure and its tail, against the ring means it replaces
        cached = args.work / f"{name}_{N}_normal_beams_orders.npz"  # --orders' normal beams: the oracle
        Ksrc = np.load(cached)["M"].sum(0) if cached.is_file() else oracle_kernel(True)
        row("oracle: the tally, every vertex", radiance(Ksrc, area, E), "floor")
        data = acquire(P, N)
        fits = {"shared colour": model, "per channel": fit_mesh(data, "iso", colour="per-channel").model}
        with _slowest_rate(TAIL_RATE):  # each term may spread its light to the object's size and beyond
            fits["shared colour, tail free"] = fit_mesh(data, "iso").model
            fits["per channel, tail free"] = fit_mesh(data, "iso", colour="per-channel").model
        # the geometry factor from the material's own mean coefficients (an oracle of its parameters)
        inside = volume.sigma_s.reshape(-1, 3).mean(0), volume.sigma_a.reshape(-1, 3).mean(0)
        sp_t = inside[0] * (1 - volume.g) + inside[1]  # σ_t' (mm⁻¹)
        s_tr = np.sqrt(3 * inside[1] * sp_t)
        one = np.ones((V, 1))
        g_true = geometry_factor(mesh, one * s_tr, one / sp_t, one * 2 / (3 * sp_t))
        print(f"geometry factor from the material: σ_tr {s_tr.round(3)}, z_r {(1 / sp_t).round(3)} mm")
        # ... and from the data: each incident point's dipole fit (σ_a, σ_s'), blended to every vertex
        dip = fit_mesh(data, "dipole").model
        w_d, idx_d = neighbour_weights(dip, mesh)
        sp_t = np.einsum("vk,vkc->vc", w_d, (dip.sigma_a + dip.sigma_s_prime)[idx_d])
        s_tr = np.einsum(
            "vk,vkc->vc", w_d, np.sqrt(3 * dip.sigma_a * (dip.sigma_a + dip.sigma_s_prime))[idx_d]
        )
        g_data = geometry_factor(mesh, s_tr, 1 / sp_t, 2 / (3 * sp_t))
        print(f"geometry factor from the data: medians σ_tr {np.median(s_tr, 0).round(3)}, z_r "
              f"{np.median(1 / sp_t, 0).round(3)} mm")  # fmt: skip
        geometry = {"dipole geometry (material)": g_true, "dipole geometry (data)": g_data}
        radial_and_fit_rows(mesh, Ksrc, open_mesh_dataset(data), fits, E, row, geometry)
        for label, fitted in list(fits.items())[1:]:  # as `render` draws them, α and the near field
            T_fit = transport_matrices(fitted, mesh, through=False)
            E_fit = vertex_irradiance(mesh, scene, light, incidence=T_fit.incidence(args.incidence))
            row(f"pipeline, {label}", relight_vertices(T_fit, E_fit), "fit")
        return _written(args, V, info, rows, t0)
    if args.orders:
        order_rows(args, name, mesh, scene, volume, N, light, camera, E, exit_law, row, reference, mask)
        return _written(args, V, info, rows, t0)
    if args.angles:
        w_light = light.arrival(scene, np.asarray(mesh.vertices), np.asarray(mesh.vertex_normals))[0]
        E_plain = vertex_irradiance(mesh, scene, light)  # shadowed, no incidence law: the walks carry it
        eye = np.asarray(camera.origin, dtype=np.float64)
        tag = "" if args.kernel_seed == 41 else f"seed{args.kernel_seed}"  # another seed: the walks' noise
        for along, E_row in ((False, E), (True, E_plain)):
            kernels = angle_kernels(
                mesh, scene, volume, N, -w_light if along else None, eye,
                args.work / f"{name}_{N}_{'light' if along else 'normal'}_beams{tag and '_' + tag}.npz",
                seed=args.kernel_seed,
            )  # fmt: skip
            for view, K in zip((False, True), kernels):
                label = {
                    (False, False): "oracle, normal beams",
                    (True, False): "(a) direction oracle",
                    (False, True): "(b) exit oracle",
                    (True, True): "(c) direction and exit oracle",
                }[along, view]
                img = row(
                    label + (", " + tag if tag else ""), radiance(K, area, E_row), "angles", law=not view
                )
                first = args.work / "rows" / f"{_slug(label)}.npy"  # the default seed's picture
                if not tag:
                    np.save(first, img)
                elif first.is_file():  # the kernels' own noise, and the error of the two seeds' mean
                    noise, error = _two_seeds(reference, mask, np.load(first), img)
                    print(f"  {label}: one seed's noise {noise:.3f}; the two seeds' mean {error:.3f}")
        if args.data_axes:  # what a data set with both axes holds, every vertex a source
            polar = tuple(float(t) for t in args.data_polar.split(","))
            tag = "" if polar == (60.0,) else "_" + "_".join(f"{t:g}" for t in polar)
            ds = open_mesh_dataset(
                acquire_mesh(
                    mesh, volume, args.work / f"{name}_{V}x{N}_axes{tag}.zarr", n_points=V, photons=N, seed=3,
                    chunk_points=32, index_matched=True, reentry=True, incidence=Incidence(polar, 4),
                    exit_bins=ExitBins(3),
                )
            )  # fmt: skip
            K_in, K_out, K_both = data_axes_kernels(ds, mesh, w_light, eye)
            row("(d) data: incidence axis", radiance(K_in, area, E_plain), "data axes")
            row("(d) data: exit bins", radiance(K_out, area, E), "data axes", law=False)
            row("(d) data: both axes", radiance(K_both, area, E_plain), "data axes", law=False)
            # the lean (model/lean.py): κ per vertex fitted from the same oblique beams, on the normal beams
            lean = fit_lean(ds, 64)[np.argsort(np.asarray(ds["incident"]))]  # (V, 2, 3) by vertex
            K_normal = angle_kernels(
                mesh, scene, volume, N, None, eye, args.work / f"{name}_{N}_normal_beams.npz", seed=41
            )[0]
            for label, sides in (("in", (True, False)), ("out", (False, True)), ("both", (True, True))):
                K = lean_kernel(K_normal, mesh, lean, w_light, eye, *sides)
                row(f"(e) lean on the normal beams: {label}", radiance(K, area, E), "the lean")
        return _written(args, V, info, rows, t0)
    saved = model.measured
    model.measured = None
    row(
        "  near field from the profile",
        relight_vertices(transport_matrices(model, mesh, through=False), E),
        "near field",
    )
    model.measured = saved
    row(
        "  transport radius 1 m",
        relight_vertices(transport_matrices(model, mesh, radius=1000.0, through=False), E),
        "transport truncation",
    )
    fit4 = fit_mesh(acquire(P, 4 * N), "iso")
    row(
        f"  {4 * N} photons per point",
        relight_vertices(transport_matrices(fit4.model, mesh, through=False), E),
        "noise",
    )
    fitP = fit_mesh(acquire(4 * P, N), "iso")
    row(
        f"  {4 * P} incident points",
        relight_vertices(transport_matrices(fitP.model, mesh, through=False), E),
        "points",
    )

    # the oracle: every vertex an incident point, at the same photons per point
    Ksrc = oracle_kernel(True)
    L_oracle = radiance(Ksrc, area, E)
    row("oracle: the tally, every vertex", L_oracle, "floor: discretisation, exit law, noise")
    row(
        "  oracle drawn at 256 spp",
        L_oracle,
        "drawing",
        pic=VertexPicture(mesh, camera, spp=256, light=light),
    )
    radial_and_fit_rows(mesh, Ksrc, open_mesh_dataset(acquire(P, N)), {"": model}, E, row)
    row(
        "oracle without re-entry",
        radiance(oracle_kernel(reentry=False), area, E),
        "light crossing the air from part to part",
    )
    return _written(args, V, info, rows, t0)


def dipole_flux(x_i, n_i, x_o, n_o, sigma_tr, z_r, z_b):
    r"""The diffusion dipole of a source at x_i (normal n_i) read as the flux through the tangent plane
    of x_o (normal n_o), per unit power and per the dipole's own constant (mm⁻²):

    .. math:: F = \frac{(x_o - x_r)\cdot n_o\,(1 + \sigma_{tr} d_r) e^{-\sigma_{tr} d_r}}{d_r^3}
                - \frac{(x_o - x_v)\cdot n_o\,(1 + \sigma_{tr} d_v) e^{-\sigma_{tr} d_v}}{d_v^3},

    x_r = x_i − z_r n_i the real source, x_v = x_i + (z_r + 2 z_b) n_i its negative image: on a plane
    (n_o = n_i) Jensen's dipole R_d(r); through a slab (n_o = −n_i) the light that crosses it.  Arrays
    broadcast; σ_tr, z_r, z_b in mm⁻¹, mm, mm.  Clamped at 0 (a source above the exit's plane)."""
    x_r = x_i - z_r[..., None] * n_i
    x_v = x_i + (z_r + 2 * z_b)[..., None] * n_i
    out = 0.0
    for x_s, sign in ((x_r, 1.0), (x_v, -1.0)):
        dx = x_o - x_s
        d = np.sqrt(np.einsum("...k,...k->...", dx, dx))
        out = (
            out
            + sign * np.einsum("...k,...k->...", dx, n_o) * (1 + sigma_tr * d) * np.exp(-sigma_tr * d) / d**3
        )
    return np.maximum(out, 0.0)


def geometry_factor(mesh, sigma_tr, z_r, z_b):
    """g[o, j, c]: the dipole's flux through x_o's tangent plane from source j over its value at the same
    chord on j's own plane (:func:`dipole_flux`), per channel; ``sigma_tr`` (V, 3), ``z_r``, ``z_b`` (V, 3)
    per source.  1 on a plane; > 1 across a slab (the light that crosses a body at chord r is not the
    light that creeps along its surface to r)."""
    v = np.asarray(mesh.vertices, dtype=np.float64)
    n = np.asarray(mesh.vertex_normals, dtype=np.float64)
    V = len(v)
    g = np.ones((V, V, 3))
    x_o, n_o = v[:, None, :], n[:, None, :]
    x_j, n_j = v[None, :, :], n[None, :, :]
    r = np.linalg.norm(x_o - x_j, axis=2)
    for c in range(3):
        s, zr, zb = sigma_tr[None, :, c], z_r[None, :, c], z_b[None, :, c]
        real = dipole_flux(x_j, n_j, x_o, n_o, s, zr, zb)
        # the same chord on the source's own plane: x_o' = x_j + r t, t ⟂ n_j
        dr, dv = np.sqrt(r**2 + zr**2), np.sqrt(r**2 + (zr + 2 * zb) ** 2)
        flat = (
            zr * (1 + s * dr) * np.exp(-s * dr) / dr**3
            + (zr + 2 * zb) * (1 + s * dv) * np.exp(-s * dv) / dv**3
        )
        g[..., c] = np.divide(real, flat, out=np.ones_like(real), where=flat > 0)
    g[np.arange(V), np.arange(V)] = 1.0
    return np.clip(g, G_RANGE[0], G_RANGE[1])


def area_rings(r, area, width, n_bins):
    """(P, n_bins) the surface area in each ring of width ``width`` about each of P sources (r (P, V))."""
    b = np.minimum((r / width).astype(int), n_bins - 1)
    return np.stack([np.bincount(b[p], area, minlength=n_bins) for p in range(len(r))])


def ring_fit(tables, ring_area, centres, rates, weighting):
    """Non-negative amplitudes c (P, 3, K) of exp(−rates r) fitted to each source's ring means (P, n_bins, 3)
    per channel: ``relative`` weighs each ring's relative error by its circumference (near and far rings
    alike), ``energy`` each ring's absolute error by its area (where the light lies)."""
    from scipy.optimize import nnls

    A = np.exp(-np.outer(centres, rates))  # (n_bins, K)
    P = len(tables)
    c = np.zeros((P, 3, len(rates)))
    for p in range(P):
        keep = ring_area[p] > 0
        for ch in range(3):
            y = tables[p, keep, ch]
            if weighting == "relative":
                wgt = np.sqrt(centres[keep]) / np.maximum(y, 1e-3 * max(y.max(), 1e-30))
            else:
                wgt = np.sqrt(ring_area[p, keep])
            scale = wgt * y
            if not np.any(scale > 0):
                continue
            c[p, ch] = nnls(A[keep] * wgt[:, None], scale, maxiter=50 * len(rates))[0]
    return c


def ring_fit_shape(c, rates, w, idx, r_all, r_min):
    """K (V_o, V_j, 3) of :func:`ring_fit`'s exponentials at the exact distances (below r_min at r_min),
    blended with (w, idx) like :func:`fit_shape`."""
    r = np.maximum(r_all, r_min)
    K = np.zeros(r_all.shape + (3,))
    basis = np.exp(-r[..., None] * rates)  # (V_o, V_j, K)
    for kk in range(w.shape[1]):
        p = idx[:, kk]
        for ch in range(3):
            K[..., ch] += w[None, :, kk] * np.einsum("ojk,jk->oj", basis, c[p, ch])
    return K


def radial_and_fit_rows(mesh, Ksrc, data, fits: dict, E, row, geometry=None) -> None:
    """The rows between the oracle and the fit: the oracle's ring means (radial, Euclidean r), those of the
    data set's P incident points blended with the renderer's weights, and each fitted model of ``fits``
    ({label: model}) in their place, α = 1, all normalised as the renderer's near field."""
    V = len(mesh.vertices)
    area = vertex_areas(mesh)
    v = np.asarray(mesh.vertices, dtype=np.float64)
    r_all = np.linalg.norm(v[:, None] - v[None], axis=2)  # (V_o, V_j)
    width = float(np.mean(mesh.edges_unique_length))
    n_bins = int(np.ceil(r_all.max() / width)) + 1
    own = Ksrc[np.arange(V), np.arange(V)]
    total = np.einsum("ojc,o->jc", Ksrc, area)
    tables = np.stack([ring_means(Ksrc[:, j], r_all[:, j], area, width, n_bins) for j in range(V)])
    eye = (np.ones((V, 1)), np.arange(V)[:, None])
    row(
        "oracle, radial",
        radiance(normalised(table_shape(tables, *eye, r_all, width), own, total, area, *eye, area), area, E),
        "local model (radial, Euclidean r)",
    )
    # the P incident points of the pipeline, their ring means blended with the renderer's weights
    pts = np.asarray(data["incident"])
    P = len(pts)
    w, idx = neighbour_weights(next(iter(fits.values())), mesh)
    near = (own[pts], total[pts], area[pts], w, idx, area)
    shape = table_shape(tables[pts], w, idx, r_all, width)
    row(f"points, radial ({P})", radiance(normalised(shape, *near), area, E), "interpolation between points")
    for label, g in (
        geometry or {}
    ).items():  # the ring means of K / g, drawn × g: a radial profile × geometry
        flat = np.stack(
            [ring_means(Ksrc[:, j] / g[:, j], r_all[:, j], area, width, n_bins) for j in range(V)]
        )
        shape = table_shape(flat, *eye, r_all, width) * g
        row(
            f"oracle, radial × {label}",
            radiance(normalised(shape, own, total, area, *eye, area), area, E),
            "geo",
        )
        shape = table_shape(flat[pts], w, idx, r_all, width) * g
        row(f"points, radial ({P}) × {label}", radiance(normalised(shape, *near), area, E), "geometry")
    # exponentials fitted to the points' ring means themselves (non-negative amplitudes on a fixed grid of
    # rates, per channel): a fit that follows the rings' tail and hue, in place of the fit to the pairs
    centres = (np.arange(n_bins) + 0.5) * width
    diagonal = float(np.linalg.norm(np.ptp(v, axis=0)))
    rates = np.geomspace(1.0 / diagonal, 2.0 / width, RING_RATES)
    for weighting in ("relative", "energy"):
        c_nn = ring_fit(tables[pts], area_rings(r_all[pts], area, width, n_bins), centres, rates, weighting)
        shape = ring_fit_shape(c_nn, rates, w, idx, r_all, 0.5 * width)
        L = radiance(normalised(shape, *near), area, E)
        row(f"points, {RING_RATES} exponentials on the rings ({weighting})", L, "fit")
    # the fit in place of the ring means, at the exact distances (below r_min at r_min, as the renderer)
    for label, model in fits.items():
        shape = fit_shape(model, w, idx, r_all, 0.5 * width)
        row(
            f"points, fit ({P}, α = 1{label and ', ' + label})",
            radiance(normalised(shape, *near), area, E),
            "fit",
        )


def angle_kernels(mesh, scene, volume, photons, incoming, eye, path, chunk=256, seed=41, orders=False):
    """(K_M, K_L), each (V, V, 3): with every vertex j a source of ``photons`` a channel (index-matched,
    re-entry), beams along −n or along ``incoming`` (V, 3) where the light reaches the vertex from outside
    (elsewhere E = 0), K_M[o, j] the exitance at o per unit power (mm⁻²) and K_L[o, j] π × the radiance
    toward ``eye`` (mm) tallied from the scattered exits within ``CONE_DEG`` of the direction to it (read as
    an exitance with no exit law; the unscattered light is a delta along the beam, seen head-on only).  One
    walk for both; cached at ``path`` (.npz).

    ``orders``: each split by the photon's scattering order, (3, V, V, 3) for orders 0 (unscattered), 1
    (single scattering) and ≥ 2 (multiple scattering), which sum to the kernels above."""
    if path.is_file():
        cached = np.load(path)
        return cached["M"], cached["L"]
    n_cls = ORDER_CLASSES if orders else 1
    X = np.asarray(mesh.vertices, dtype=np.float64)
    n = np.asarray(mesh.vertex_normals, dtype=np.float64)
    V = len(X)
    area = vertex_areas(mesh)
    inward = None
    if incoming is not None:  # towards the surface: along the light; elsewhere (unlit: E = 0) along −n
        inward = np.where((np.einsum("vk,vk->v", incoming, n) < -1e-3)[:, None], incoming, -n)
    face_n = np.asarray(mesh.face_normals, dtype=np.float64)
    cos_c = np.cos(np.radians(CONE_DEG))
    omega_c = np.pi * (1 - cos_c**2)  # ∫ cos θ dω over the cone / cos θ_axis (exact for a constant L)
    K_M, K_L = np.zeros((n_cls, V, V, 3)), np.zeros((n_cls, V, V, 3))
    for ch in range(3):
        for lo in range(0, V, chunk):
            hi = min(lo + chunk, V)
            res = mesh_random_walk(
                scene, mesh.bounds, volume, ch, X[lo:hi], n[lo:hi], photons, seed=seed + 7919 * ch,
                first_point=lo, index_matched=True, reentry=True,
                incoming=None if inward is None else inward[lo:hi],
            )  # fmt: skip
            ok = np.flatnonzero(res.code == EXIT)
            point = np.repeat(np.arange(lo, hi), photons)[ok]
            pos, face = res.position[ok].astype(np.float64), res.face[ok]
            # the exits within the cone about the direction to the eye, each 1 / (Ω'_c cos θ_o) of radiance
            to_eye = eye - pos
            to_eye /= np.linalg.norm(to_eye, axis=1, keepdims=True)
            d = res.direction[ok] / np.linalg.norm(res.direction[ok], axis=1, keepdims=True)
            cos_o = np.maximum(np.einsum("ij,ij->i", face_n[face], to_eye), 0.1)
            cone = np.where(np.einsum("ij,ij->i", d, to_eye) > cos_c, np.pi / (omega_c * cos_o), 0.0)
            # light that crossed a thin part unscattered leaves along the beam, a delta in direction that a
            # camera sees only head-on — not spread over the cone (back-lit, 15° from the view: hot spots)
            cone[res.scatters[ok] == 0] = 0.0
            tri, bary = exit_barycentric(mesh, face, pos)
            cls = np.minimum(res.scatters[ok], n_cls - 1)[:, None]  # the order class (0 without orders)
            index = ((cls * V + tri) * V + point[:, None]).ravel()  # (class, o, j) flattened
            for K, weight in ((K_M, 1.0), (K_L, cone[:, None])):
                counts = np.bincount(index, (bary * weight).ravel(), n_cls * V * V)
                K[..., ch] += counts.reshape(n_cls, V, V)
        for K in (K_M, K_L):
            K[..., ch] /= photons * area[:, None]
    if not orders:
        K_M, K_L = K_M[0], K_L[0]
    np.savez(path, M=K_M, L=K_L)
    return K_M, K_L


def order_rows(args, name, mesh, scene, volume, N, light, camera, E, exit_law, row, reference, mask):
    """``--orders``: the oracle (every vertex a source, re-entry) split by scattering order, with normal
    beams and with beams along the light, each order drawn as an exitance (× the exit law: Lambertian)
    or by its own direction toward the camera (the cone of :func:`angle_kernels`); and the share of each
    order in the unlit side's exitance and in the thin parts', per channel, beside the reference's hue."""
    area = vertex_areas(mesh)
    w_light = light.arrival(scene, np.asarray(mesh.vertices), np.asarray(mesh.vertex_normals))[0]
    E_plain = vertex_irradiance(mesh, scene, light)  # shadowed, no incidence law: the walks carry it
    eye = np.asarray(camera.origin, dtype=np.float64)
    lit = (E_plain > 0) if E_plain.ndim == 1 else (E_plain.sum(axis=1) > 0)
    thin = vertex_thickness(mesh, scene) < 10.0
    unlit_px = VertexPicture(mesh, camera, spp=1).draw(np.repeat((~lit)[:, None], 3, 1).astype(float))
    unlit_px = (unlit_px[..., 0] > 0.5) & mask
    ref_hue = channel_shares(reference, unlit_px)
    law = (lambda L: L) if exit_law is None else (lambda L: L * exit_law)
    shares = {}
    for along, E_row in ((False, E), (True, E_plain)):
        beams = "light's beams" if along else "normal beams"
        M, L = angle_kernels(
            mesh, scene, volume, N, -w_light if along else None, eye,
            args.work / f"{name}_{N}_{'light' if along else 'normal'}_beams_orders.npz", orders=True,
        )  # fmt: skip
        X = np.stack([radiance(M[k], area, E_row) for k in range(ORDER_CLASSES)])  # (orders, V, 3): M/π
        Y = np.stack([radiance(L[k], area, E_row) for k in range(ORDER_CLASSES)])  # toward the camera
        row(f"{beams}: every order, Lambertian", law(X.sum(0)), "orders", law=False)
        row(f"{beams}: orders >= 1, Lambertian", law(X[1:].sum(0)), "orders", law=False)
        row(f"{beams}: orders >= 2 alone, Lambertian", law(X[2]), "orders", law=False)
        row(f"{beams}: >= 2 Lambertian + 1 by direction", law(X[2]) + Y[1], "orders", law=False)
        row(f"{beams}: every order by direction", Y.sum(0), "orders", law=False)
        for region, sel in (("unlit", ~lit), ("unlit, thin", ~lit & thin)):
            power = np.einsum("kvc,v->kc", X[:, sel], area[sel])  # (orders, 3) the region's exitance
            shares[f"{beams}, {region}"] = {
                "vertices": int(sel.sum()),
                "order_share": _share(power, 0).tolist(),  # (orders, R G B)
                "hue_by_order": _share(power, 1).tolist(),  # each order's R G B shares
                "hue_all": (power.sum(0) / power.sum()).tolist(),
            }
    print(f"the reference's hue on the unlit pixels (R, G, B shares): {np.round(ref_hue, 3).tolist()}")
    for key, sh in shares.items():
        print(f"{key} ({sh['vertices']} vertices): share of the exitance by order (R, G, B)")
        for k, label in enumerate(ORDER_NAMES):
            share, hue = np.round(sh["order_share"][k], 3), np.round(sh["hue_by_order"][k], 3)
            print(f"  order {label:<3} {share.tolist()}   its hue {hue.tolist()}")
        print(f"  all orders' hue {np.round(sh['hue_all'], 3).tolist()}")
    (args.work / "orders.json").write_text(json.dumps({"reference_hue_unlit": ref_hue.tolist(), **shares}))


def data_axes_kernels(ds, mesh, w_light, eye, chunk=128):
    r"""(K_in, K_out, K_both), each (V, V, 3), from a data set of every vertex a source with oblique beams
    at polar angles θ_1 < θ_2 < … and K azimuths each, and exit bins (:mod:`translucency.angles`).

    *In*: the light's direction ω at source j, (θ, φ) in j's tangent frame, is blended from the stored beams:
    linearly in sin θ between the normal (θ = 0) and the rings (no extrapolation past the last), and
    within a ring by :math:`\sum_k w_k(\varphi) R_k` with :math:`w_k` the hat weights between neighbouring
    azimuths (the paper's :math:`w_l`).  *Out*: π × the radiance toward ``eye`` at o,
    :math:`\pi R_{d,b} / \Omega'_b` of the exit bin b of o's view direction (o's vertex normal; away or
    back from x_j) — read as an exitance, no exit law.
    K_in is the blended exitance (the exit law applies), K_out the normal beam's bins, K_both both."""
    inc, bins = ds.incidence, ds.exit_bins
    K = inc.azimuths
    ring_sin = np.r_[0.0, np.sin(np.radians(inc.polar_deg))]  # the normal, then each ring
    X = np.asarray(ds["vertices"], dtype=np.float64)
    n_o = np.asarray(mesh.vertex_normals, dtype=np.float64)
    V = len(X)
    incident = np.asarray(ds["incident"])
    frames = tangent_frames(n_o[incident])  # as the acquisition set them
    w = np.asarray(w_light, dtype=np.float64)[incident]  # toward the light at each source
    local = np.einsum("pjk,pk->pj", frames, w)
    sin_t = np.sqrt(np.maximum(1 - np.clip(local[:, 2], -1, 1) ** 2, 0))
    # hat weights in sin θ over (normal, ring 1, ring 2, …), clamped at the last ring
    u = np.interp(np.minimum(sin_t, ring_sin[-1]), ring_sin, np.arange(len(ring_sin)))
    w_ring = np.maximum(0.0, 1.0 - np.abs(u[:, None] - np.arange(len(ring_sin))[None, :]))  # (P, 1 + rings)
    w_az = direction_weights(np.arctan2(local[:, 1], local[:, 0]), K)  # (P, K)
    weights = np.concatenate(
        [w_ring[:, :1], (w_ring[:, 1:, None] * w_az[:, None, :]).reshape(len(w), -1)], axis=1
    )  # (P, D): the normal beam, then ring by ring its K azimuths (the data set's order)
    to_eye = eye[None, :] - X
    to_eye /= np.linalg.norm(to_eye, axis=1, keepdims=True)
    per_sr = np.pi / bins.projected_solid_angle
    K_in, K_out, K_both = (np.zeros((V, V, 3)) for _ in range(3))
    for lo in range(0, len(incident), chunk):
        hi = min(lo + chunk, len(incident))
        B = np.asarray(ds.group["exit_bins"][lo:hi], dtype=np.float64)  # (n, D, V, 3, b)
        j = incident[lo:hi]
        blended = np.einsum("nd,ndvcb->nvcb", weights[lo:hi], B)
        away = X[None, :, :] - X[j][:, None, :]  # (n, V, 3): x_o − x_j
        b = bins.index(
            np.broadcast_to(to_eye, away.shape).reshape(-1, 3),
            np.broadcast_to(n_o, away.shape).reshape(-1, 3),
            away.reshape(-1, 3),
        ).reshape(hi - lo, V)
        take = b[:, :, None, None]
        K_in[:, j] = blended.sum(-1).transpose(1, 0, 2)
        K_out[:, j] = per_sr * np.take_along_axis(B[:, 0], take, axis=-1)[..., 0].transpose(1, 0, 2)
        K_both[:, j] = per_sr * np.take_along_axis(blended, take, axis=-1)[..., 0].transpose(1, 0, 2)
    return K_in, K_out, K_both


def lean_kernel(K, mesh, lean, w_light, eye, incidence=True, exit=True):
    """K (V_o, V_j, 3) with the lean of model/lean.py: per source j the incidence lobe of the light's
    direction with its reach (normalised per source over its receivers, own vertex apart), per receiver o
    the exit lobe of the direction to ``eye`` (normalised over the exit hemisphere per pair); ``lean``
    (V, 2, 3): κ and λ per vertex."""
    kappa, lam = lean[:, 0], lean[:, 1]
    X = np.asarray(mesh.vertices, dtype=np.float64)
    n = np.asarray(mesh.vertex_normals, dtype=np.float64)
    V = len(X)
    area = vertex_areas(mesh)
    d = X[:, None, :] - X[None, :, :]  # (o, j): x_o − x_j
    r = np.linalg.norm(d, axis=2)
    off = r > 0
    d /= np.where(off, r, 1.0)[..., None]
    out = K.copy()
    if incidence:
        ell = lean_vector(w_light, n)  # (V, 3) at the sources
        a = np.einsum("ojk,jk->oj", d, ell) * off  # (o, j)
        depth = np.einsum("jk,jk->j", ell, n)[None, :] * r  # (ℓ_j · n_j) r_oj
        for c in range(3):
            lobe = np.exp(kappa[None, :, c] * a - lam[None, :, c] * depth)
            lobe[~off] = 1.0
            spread = np.einsum("oj,o->j", K[..., c] * off, area)
            leaned = np.einsum("oj,o->j", K[..., c] * off * lobe, area)
            Z = np.divide(leaned, spread, out=np.ones(V), where=spread > 0)
            out[..., c] = np.where(off, K[..., c] * lobe / Z[None, :], K[..., c])
    if exit:
        to_eye = eye[None, :] - X
        to_eye /= np.linalg.norm(to_eye, axis=1, keepdims=True)
        ell_o = lean_vector(to_eye, n)  # (V, 3) at the receivers
        b = -np.einsum("ojk,ok->oj", d, ell_o) * off
        for c in range(3):
            k_o = np.broadcast_to(kappa[:, None, c], (V, V))
            N = exit_normalisation(
                k_o.reshape(-1), -d.reshape(-1, 3), np.broadcast_to(n[:, None], (V, V, 3)).reshape(-1, 3)
            ).reshape(V, V)
            out[..., c] = np.where(off, out[..., c] * np.exp(k_o * b) / N, out[..., c])
    return out


@contextlib.contextmanager
def _slowest_rate(rate: float):
    """Fits within it take ``rate`` / (object's diagonal) as their slowest admissible fall-off."""
    saved = fit_module.ENERGY_RADIUS_RATE
    fit_module.ENERGY_RADIUS_RATE = rate
    try:
        yield
    finally:
        fit_module.ENERGY_RADIUS_RATE = saved


def _share(a: np.ndarray, axis: int) -> np.ndarray:
    """``a`` over its sum along ``axis`` (nan where that sum is 0)."""
    total = a.sum(axis, keepdims=True)
    return np.divide(a, total, out=np.full_like(a, np.nan), where=total > 0)


def _slug(label: str) -> str:
    return "".join(c if c.isalnum() else "_" for c in label.strip()).strip("_")


def _two_seeds(reference, mask, A, B) -> tuple[float, float]:
    """One picture's relative noise from two seeds, ‖A − B‖ / (√2 ‖(A + B)/2‖) over the object, and the
    relative RMSE of their mean against the reference."""
    mean = 0.5 * (A + B)
    noise = np.sqrt(np.sum((A - B)[mask] ** 2) / np.sum(mean[mask] ** 2)) / np.sqrt(2)
    return float(noise), float(compare(reference, mean, mask)["rel_rmse"])


def _written(args, V, info, rows, t0) -> int:
    out = {
        "case": args.case,
        "vertices": V,
        "reference_noise": info["noise"],
        "rows": rows,
        "seconds": time.perf_counter() - t0,
    }
    print(f"reference noise {info['noise']:.3f}")
    (args.work / "objects_budget.json").write_text(json.dumps(out, indent=2))
    print(f"written: {args.work / 'objects_budget.json'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
