r"""What the page shows of a per-vertex model: its mesh, transfer, exit law, maps and profiles.

:func:`prepare_object` does the work once per model (the transport, the transfer of
:mod:`translucency.render.transfer`, the maps, the ring profiles, the error against the full relight);
:meth:`ObjectView.page_data` turns it into the arrays and the description the page
(``static/viewer.js``) reads, and :meth:`ObjectView.relight` gives the live viewer the radiance of a
point or spot light.

Stored for the page (float16 where 3 significant digits do: the transfer, normals, maps):

* ``transfer`` — :math:`t_{o,k,c}` / ``transfer_scale``, vertex-major, padded to whole RGBA texels;
* ``r1``, ``inv_mean_f`` and ``exit_table`` — the exit law :math:`\pi L / M = F(\mu_o; R_1) /
  \langle F \rangle` (:class:`translucency.model.incidence.HalfSpaceIncidence`) as per-vertex totals and a
  table :math:`F(\mu, R_1)` on an n × n grid of texel centres, or the boundary's
  :math:`F_t(\theta_o) / (1 - F_{dr})` (η ≠ 1), or none (Lambertian);
* maps per vertex, blended from the incident points as the transport blends their profiles;
* for every incident point the fit's ring means of :math:`R_d` (mm⁻²) and, where the data set is at hand,
  the measured ones, on the same rings.
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass, field

import numpy as np
from scipy.spatial import cKDTree

from ..geometry import vertex_areas
from ..mitsuba import mesh_scene
from ..model.boundary import exit_factor, fresnel_transmittance
from ..model.bounds import check_physics
from ..model.incidence import HalfSpaceIncidence, cosine_mean, incidence_factor
from ..render.camera import Camera
from ..render.compare import rel_rmse
from ..render.irradiance import vertex_irradiance
from ..render.lean import lean_pairs, leaned
from ..render.lights import DirectionalLight, EnvironmentLight, PointLight, SpotLight
from ..render.parameters import neighbour_weights
from ..render.picture import VertexPicture, coverage
from ..render.relight import relight_vertices, view_cosines
from ..render.transfer import DEFAULT_BANDS, DEFAULT_DIRECTIONS, Transfer, transfer_vectors
from ..render.transport import transport_matrices
from .maps import page_maps

#: texels per row of the transfer texture (WebGL2 guarantees 2048 at least; 4096 everywhere we know)
TEXTURE_WIDTH = 2048
#: the exit table's size (μ × R_1)
EXIT_TABLE = 64
#: the default camera: as ``render --view 1,-1.6,0.7`` (azimuth, elevation in degrees)
DEFAULT_VIEW = (math.degrees(math.atan2(-1.6, 1.0)), math.degrees(math.atan2(0.7, math.hypot(1.0, 1.6))))
#: the default light: directional, from this azimuth and elevation (degrees)
DEFAULT_LIGHT = (-30.0, 40.0)
#: a directional light's irradiance (W/mm²); point lights get the intensity that gives it at the
#: default distance
IRRADIANCE = 1.0
#: a point light's distance by default, object sizes (as ``render``'s relative lights)
POINT_DISTANCE = 1.5
#: triangles of the mesh drawn while things move (software WebGL draws ~0.5 M triangles a second on 2 cores)
REDUCED_FACES = 8000
#: rings of the profiles: log-spaced radii
PROFILE_RINGS = 24


@dataclass
class ObjectView:
    """A per-vertex model prepared for viewing (:func:`prepare_object`)."""

    model: object
    mesh: object
    transport: object
    law: object
    scene: object
    transfer: Transfer
    eta: float
    environment: EnvironmentLight
    name: str
    dataset: object = None
    errors: dict = field(default_factory=dict)
    seconds: dict = field(default_factory=dict)
    drafts: dict = field(default_factory=dict)  # coarse transports by their receivers (:meth:`relight`)
    companion: ObjectView | None = None  # a second model of the same mesh, shown beside and against this one
    angles: bool = False  # the transfer and the full relights lean toward the light (the model's lean)
    pairs: object = None  # the lean's pairs of the transport (render/lean.py), prepared on the first lean

    @property
    def centre(self) -> np.ndarray:
        """The middle of the object's bounding box (mm): lights and the camera turn about it."""
        return 0.5 * (self.mesh.bounds[0] + self.mesh.bounds[1])

    @property
    def size(self) -> float:
        """The bounding box's diagonal (mm)."""
        return float(np.linalg.norm(self.mesh.extents))

    @property
    def point_intensity(self) -> float:
        return point_intensity(self.size)

    def light_at(self, kind: str, direction, distance: float = POINT_DISTANCE, cutoff: float = 20.0):
        """The light the page's controls describe: ``direction`` from the centre towards the light,
        ``distance`` in object sizes."""
        w = np.asarray(direction, dtype=np.float64)
        w = w / np.linalg.norm(w)
        if kind == "directional":
            return DirectionalLight(tuple(-w), IRRADIANCE)
        position = tuple(self.centre + w * float(distance) * self.size)
        if kind == "point":
            return PointLight(position, self.point_intensity)
        if kind == "spot":
            return SpotLight(position, tuple(self.centre), float(cutoff), self.point_intensity)
        raise ValueError(f"light kind {kind!r}")

    def relight(self, light, receivers=None) -> np.ndarray:
        """Radiance per vertex (V, 3) of a light, before the exit law (the page applies it): irradiance
        with shadow rays, then the sparse transport (with :attr:`angles`, leaned toward the light:
        :func:`~translucency.render.lean.leaned`).  With ``receivers`` (vertex indices) a draft at
        those only: their irradiance through the transport coarsened to their cells
        (:meth:`~translucency.render.relight.Transport.coarse`, prepared on the first call; the paper's
        model, a draft while the light moves)."""
        if receivers is None:
            E = vertex_irradiance(self.mesh, self.scene, light, self.eta, self.law)
            return relight_vertices(self._leaned(light) or self.transport, E)
        key = hash(np.asarray(receivers).tobytes())
        if key not in self.drafts:
            self.drafts[key] = (self.transport.coarse(self.mesh.vertices, receivers), self.law.at(receivers))
        coarse, law = self.drafts[key]
        E = vertex_irradiance(self.mesh, self.scene, light, self.eta, law, at=receivers)
        return relight_vertices(coarse, E)

    def _leaned(self, light):
        """The transport leaned toward ``light`` with :attr:`angles` (None: the paper's, or not leaned)."""
        if not self.angles:
            return None
        if self.pairs is None:
            self.pairs = lean_pairs(self.transport, self.mesh, self.eta)
        eye = self.centre  # (the camera's lean, the exit's, is off: unread)
        return leaned(self.transport, self.mesh, self.scene, light, eye, eta=self.eta, pairs=self.pairs)

    def exit(self, viewpoint) -> np.ndarray:
        """The exit law toward ``viewpoint`` (V, 3), as the page computes it."""
        cos_o = view_cosines(self.mesh, viewpoint)
        if self.eta != 1.0:
            return np.repeat(exit_factor(cos_o, self.eta)[:, None], 3, axis=1)
        out = self.law.exit(cos_o)
        return np.ones((len(cos_o), 3)) if out is None else out

    def light_data(self) -> tuple[dict, dict]:
        """(meta, arrays) of the relighting: the transfer, the exit law, the sky, the exposure and the
        errors (module docstring); with a :attr:`companion`, its transfer too (``b_``-prefixed arrays,
        ``meta["compare"]``: the page shows it beside this one and their difference)."""
        meta, arrays = _light_data(self)
        if self.companion is not None:
            other_meta, other = _light_data(self.companion)
            arrays.update(
                {f"b_{k}": other[k] for k in ("transfer", "transfer_run", "irradiance_run", "local")}
            )
            meta["compare"] = {
                "name": self.companion.name,
                "transfer_scale": other_meta["transfer_scale"],
                "irradiance_scale": other_meta["irradiance_scale"],
            }
        return meta, arrays

    def page_data(self) -> tuple[dict, dict]:
        """(meta, arrays) of the whole static page: :func:`surface_data` and :meth:`light_data`."""
        meta, arrays = surface_data(self.model, self.mesh, name=self.name, dataset=self.dataset)
        light_meta, light_arrays = self.light_data()
        meta["subtitle"] += f", {self.transfer.bands**2} transfer coefficients per channel"
        return {**meta, **light_meta, "live": False}, {**arrays, **light_arrays}


def prepare_object(
    model,
    mesh,
    *,
    eta: float = 1.0,
    incidence: str = "half-space",
    environment: EnvironmentLight | None = None,
    bands: int = DEFAULT_BANDS,
    directions: int = DEFAULT_DIRECTIONS,
    radius: float | None = None,
    dataset=None,
    name: str = "model",
    check_error: bool = True,
    angles: bool = False,
    progress=None,
) -> ObjectView:
    """The transport and the transfer of ``model`` on ``mesh``, and (``check_error``) the transfer's error
    against the full relight for a directional light and the environment, through the default camera.

    ``environment``: the page's sky (default: a constant sky); ``dataset``: the mesh data set the model
    was fitted to, for the measured profiles (None: the fit's alone); ``angles``: with a model that has
    a lean, the transfer and the full relights lean toward the light (:mod:`translucency.render.transfer`);
    ``progress(step)`` names each step.
    """
    say = progress or (lambda step: None)
    seconds = {}
    t = time.perf_counter()
    say("transport")
    transport = transport_matrices(model, mesh, radius=radius)
    scene = mesh_scene(mesh)
    law = transport.incidence(incidence, eta)
    seconds["transport"] = time.perf_counter() - t
    t = time.perf_counter()
    say("transfer")
    angles = bool(angles and transport.lean is not None)
    transfer = transfer_vectors(
        transport, mesh, scene, law, bands=bands, directions=directions, eta=eta, angles=angles
    )
    seconds["transfer"] = time.perf_counter() - t
    view = ObjectView(
        model=model,
        mesh=mesh,
        transport=transport,
        law=law,
        scene=scene,
        transfer=transfer,
        eta=eta,
        environment=environment or EnvironmentLight(IRRADIANCE / math.pi, samples=128),
        name=name,
        dataset=dataset,
        seconds=seconds,
        angles=angles,
    )
    if check_error:
        say("error against the full relight")
        view.errors = transfer_errors(view)
    return view


def transfer_errors(view: ObjectView, size=(160, 120)) -> dict:
    r"""Relative RMSE of the page's picture against the full relight (``render``'s chain: irradiance with
    shadow rays and the incidence law, the transport, the exit law) for the same light, drawn through the
    default camera by :class:`~translucency.render.picture.VertexPicture` and compared over the object's
    pixels (:func:`translucency.render.compare.rel_rmse`): the default directional light, three more
    directions and the environment."""
    az, el = DEFAULT_VIEW
    direction = _unit(az, el)
    camera = Camera.looking_at(view.mesh, direction, *size)
    mask = coverage(view.mesh, camera)
    picture = VertexPicture(view.mesh, camera, spp=4, eta=view.eta)
    exit_law = view.exit(camera.origin)
    lights = {
        "directional (default)": view.light_at("directional", _unit(*DEFAULT_LIGHT)),
        "directional (side)": view.light_at("directional", _unit(90.0, 10.0)),
        "directional (back)": view.light_at("directional", _unit(DEFAULT_VIEW[0] + 180.0, 20.0)),
        "directional (above)": view.light_at("directional", (0.0, 0.0, 1.0)),
        "environment": view.environment,
    }
    stored = quantised(view.transfer)  # what the page holds: 8 bits and float16 scales
    out = {}
    for name, light in lights.items():
        E = vertex_irradiance(view.mesh, view.scene, light, view.eta, view.law)
        full = relight_vertices(view._leaned(light) or view.transport, E)
        local = E if light.delta else None  # the page: its shadow map
        ours = np.maximum(stored.radiance(light.sh_coefficients(stored.bands), local), 0.0)
        out[name] = rel_rmse(picture.draw(full * exit_law), picture.draw(ours * exit_law), mask)
    return out


def _runs(transfer: Transfer) -> np.ndarray:
    r"""(V, 4, K): the rest :math:`r = t - a \bar E` of each channel, then :math:`\bar E`."""
    t = transfer.coefficients.astype(np.float64)
    E = transfer.irradiance.astype(np.float64)
    rest = t - transfer.local.astype(np.float64)[:, None, :] * E[:, :, None]  # (V, K, 3)
    return np.concatenate([rest.transpose(0, 2, 1), E[:, None, :]], axis=1)


def encode_transfer(transfer: Transfer) -> tuple[dict, dict]:
    """(meta, arrays): the transfer as the page holds it, in 8 bits.

    Per vertex four runs of ⌈K/4⌉ RGBA texels — the rest r = t − a Ē of R, G, B, then Ē
    (:mod:`translucency.render.transfer`: sharp lights) — each value over its run's largest magnitude;
    the runs' scales in float16 per vertex (``transfer_run``, ``irradiance_run``) over one global scale
    each (``transfer_scale``, ``irradiance_scale``); ``local`` a in float16.  The page adds a Ē back for
    the sky."""
    runs = _runs(transfer)  # (V, 4, K)
    V, _, K = runs.shape
    run_scale = np.max(np.abs(runs), axis=2)  # (V, 4)
    kq = -(-K // 4)
    q = np.zeros((V, 4, kq * 4), dtype=np.int8)
    with np.errstate(invalid="ignore", divide="ignore"):
        q[:, :, :K] = np.nan_to_num(np.round(127.0 * runs / run_scale[:, :, None]), nan=0.0).astype(np.int8)
    rows = -(-q.size // (4 * TEXTURE_WIDTH))
    tex = np.zeros(rows * TEXTURE_WIDTH * 4, dtype=np.int8)
    tex[: q.size] = q.ravel()
    scale_t = float(np.max(run_scale[:, :3])) or 1.0
    scale_e = float(np.max(run_scale[:, 3])) or 1.0
    arrays = {
        "transfer": tex,
        "transfer_run": (run_scale[:, :3] / scale_t).astype(np.float16),
        "irradiance_run": (run_scale[:, 3] / scale_e).astype(np.float16),
        "local": transfer.local.astype(np.float16),
    }
    meta = {
        "bands": transfer.bands,
        "stride": 4 * kq,
        "kq": kq,
        "texture_width": TEXTURE_WIDTH,
        "transfer_scale": scale_t,
        "irradiance_scale": scale_e,
    }
    return meta, arrays


def quantised(transfer: Transfer) -> Transfer:
    """The transfer as the page decodes it from :func:`encode_transfer` (8 bits, float16 scales)."""
    meta, arrays = encode_transfer(transfer)
    V, K, kq = len(transfer.local), transfer.bands**2, meta["kq"]
    # 8-bit SNORM, read as the GPU reads it: q / 127
    q = arrays["transfer"][: V * 4 * kq * 4].reshape(V, 4, kq * 4)[:, :, :K] / 127.0
    run = np.concatenate(
        [
            arrays["transfer_run"].astype(np.float64) * meta["transfer_scale"],
            arrays["irradiance_run"].astype(np.float64)[:, None] * meta["irradiance_scale"],
        ],
        axis=1,
    )
    values = q * run[:, :, None]  # (V, 4, K)
    local = arrays["local"].astype(np.float64)
    return dataclasses.replace(
        transfer,
        coefficients=values[:, :3].transpose(0, 2, 1) + local[:, None, :] * values[:, 3][:, :, None],
        irradiance=values[:, 3],
        local=local,
    )


def point_intensity(size: float) -> float:
    """I (W/sr) of a point light that gives the directional light's irradiance at the default distance
    from an object of ``size`` mm."""
    return IRRADIANCE * (POINT_DISTANCE * size) ** 2


def _unit(az: float, el: float) -> tuple:
    a, e = math.radians(az), math.radians(el)
    return (math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e))


def surface_data(model, mesh, *, name: str, dataset=None) -> tuple[dict, dict]:
    """(meta, arrays) of what needs no transport: the mesh, the maps and the profiles (seconds).

    The live viewer shows these first, while the transport and the transfer are prepared."""
    V, F = len(mesh.vertices), len(mesh.faces)
    arrays = {
        "position": np.asarray(mesh.vertices, np.float32),
        "normal": np.asarray(mesh.vertex_normals, np.float16),
        "index": np.asarray(mesh.faces, np.uint32),
    }
    maps = _maps(model, mesh, arrays)
    profiles = _profiles(model, mesh, dataset, arrays)
    _reduced_mesh(mesh, arrays)
    meta = {
        "title": name,
        "subtitle": f"{V:,} vertices, {model.n_points} incident points",
        "vertices": V,
        "faces": F,
        "centre": [float(x) for x in 0.5 * (mesh.bounds[0] + mesh.bounds[1])],
        "size": float(np.linalg.norm(mesh.extents)),
        "view": {"az": DEFAULT_VIEW[0], "el": DEFAULT_VIEW[1]},
        "default_light": {
            "kind": "directional",
            "az": DEFAULT_LIGHT[0],
            "el": DEFAULT_LIGHT[1],
            "dist": POINT_DISTANCE,
        },
        "maps": maps,
        "profiles": profiles,
        "directional_irradiance": IRRADIANCE,
        "point_intensity": point_intensity(float(np.linalg.norm(mesh.extents))),
    }
    return meta, arrays


def _light_data(view: ObjectView) -> tuple[dict, dict]:
    transfer = view.transfer
    meta, arrays = encode_transfer(transfer)
    exit_law = _law_arrays(view, arrays)
    env = view.environment.sh_coefficients(transfer.bands)
    # the exposure: the default light's picture at 0.5 for its brightest percent of vertices
    default = view.relight(view.light_at("directional", _unit(*DEFAULT_LIGHT)))
    bright = float(
        np.quantile(
            np.max(default * view.exit(view.centre + view.size * np.asarray(_unit(*DEFAULT_VIEW))), axis=1),
            0.99,
        )
    )
    meta |= {
        "exit_law": exit_law,
        "exit_table_size": EXIT_TABLE,
        "eta": view.eta,
        "exposure": 0.5 / bright if bright > 0 else 1.0,
        # how far the light spreads inside before half of it is out: the local shadow's softening (mm)
        "blur_mm": float(np.median(view.model.energy_radius(0.5))),
        "env": {"coefficients": env.tolist()},
        "errors": view.errors,
        "about": _about(view),
    }
    return meta, arrays


def reduced_mesh(mesh):
    """(reduced mesh, source) — the mesh drawn while the light or the camera moves: a quadric decimation
    to :data:`REDUCED_FACES` triangles (``fast_simplification`` through trimesh), each of its vertices
    standing for the full mesh's vertex nearest it (``source``, whose attributes, transfer and draft
    relight it takes); None for a mesh no larger."""
    if len(mesh.faces) <= REDUCED_FACES:
        return None
    reduced = mesh.simplify_quadric_decimation(face_count=REDUCED_FACES)
    _, source = cKDTree(np.asarray(mesh.vertices)).query(np.asarray(reduced.vertices))
    return reduced, source


def _reduced_mesh(mesh, arrays: dict) -> None:
    """The reduced mesh's arrays for the page (``lod_position``, ``lod_index``, ``lod_source``)."""
    found = reduced_mesh(mesh)
    if found is None:
        return
    reduced, source = found
    arrays["lod_position"] = np.asarray(reduced.vertices, np.float32)
    arrays["lod_index"] = np.asarray(reduced.faces, np.uint32)
    arrays["lod_source"] = np.asarray(source, np.uint32)


def _law_arrays(view: ObjectView, arrays: dict) -> bool:
    """The incidence and exit laws' arrays (module docstring): tables over (μ, R_1) at texel centres, the
    per-vertex totals R_1 where the law needs them; returns whether there is an exit law (else Lambertian)."""
    n = EXIT_TABLE
    centres = (np.arange(n) + 0.5) / n
    mu = np.clip(centres, 1e-3, 1.0)
    law = view.law
    if isinstance(law, HalfSpaceIncidence):
        R1 = np.clip(law.reflectance, 0.0, 1.0)
        arrays["r1"] = R1.astype(np.float16)
        table = incidence_factor(
            mu[None, :], np.clip(centres, 1e-6, 1.0 - 1e-6)[:, None]
        )  # rows R1, columns μ
        arrays["incidence_table"] = table.astype(np.float16)
        if law.both_ways:
            arrays["inv_mean_f"] = (1.0 / cosine_mean(R1)).astype(np.float16)
            arrays["exit_table"] = arrays["incidence_table"]
            return True
        return False
    if view.eta != 1.0:  # the boundary's laws, the same for every vertex and channel
        ratio = fresnel_transmittance(mu, view.eta) / fresnel_transmittance(1.0, view.eta)
        arrays["incidence_table"] = np.tile(ratio, (n, 1)).astype(np.float16)
        arrays["exit_table"] = np.tile(exit_factor(mu, view.eta), (n, 1)).astype(np.float16)
        return True
    return False


def _maps(model, mesh, arrays: dict) -> list:
    """The per-vertex maps: total reflectance, 99 % energy radius, α and the physics flags."""
    w, idx = neighbour_weights(model, mesh)
    blend = lambda per_point: np.einsum("vk,vk->v", w, np.asarray(per_point, np.float64)[idx])  # noqa: E731
    check = check_physics(model, size_mm=float(np.max(mesh.extents)))
    values = {
        "map_reflectance": (
            "total diffuse reflectance (mean of R, G, B)",
            "",
            blend(model.total_reflectance().mean(axis=1)),
        ),
        "map_radius": ("99 % energy radius", "mm", blend(model.energy_radius(0.99))),
        "map_alpha": (
            "modulation texture α",
            "",
            np.asarray(model.alpha.at(np.asarray(mesh.vertices)), np.float64),
        ),
    }
    legend = (
        f"nearest incident point breaks a bound ({int(check.flagged.sum())} of {model.n_points} points): "
        f"{check.describe()}"
    )
    return page_maps(values, check.flagged[idx[:, 0]], legend, arrays)  # a vertex: its nearest point's flags


def _profiles(model, mesh, dataset, arrays: dict) -> dict:
    """Ring means of the fit's R_d around each incident point and, with the data set, the measured ones."""
    v = np.asarray(mesh.vertices, np.float64)
    area = vertex_areas(mesh)
    edge = float(np.mean(mesh.edges_unique_length))
    r_max = float(np.max(model.energy_radius(0.99)))
    edges = np.geomspace(max(edge, 1e-3), max(r_max, 2 * edge), PROFILE_RINGS + 1)
    centres = np.sqrt(edges[:-1] * edges[1:])
    N, R = model.n_points, PROFILE_RINGS
    fit = np.full((N, R, 3), np.nan)
    measured = np.full((N, R, 3), np.nan) if dataset is not None else None
    for i in range(N):
        r = np.linalg.norm(v - model.x_i[i], axis=1)
        ring = np.searchsorted(edges, r, side="right") - 1
        ok = (ring >= 0) & (ring < R)
        wsum = np.bincount(ring[ok], area[ok], minlength=R)
        with np.errstate(invalid="ignore", divide="ignore"):
            Rd = model.R_d(np.full(int(ok.sum()), i), v[ok])
            data = None if measured is None else np.asarray(dataset["R_d"][i], np.float64)[ok]
            for c in range(3):
                fit[i, :, c] = np.bincount(ring[ok], area[ok] * Rd[:, c], minlength=R) / wsum
                if measured is not None:
                    measured[i, :, c] = np.bincount(ring[ok], area[ok] * data[:, c], minlength=R) / wsum
    arrays["profile_points"] = np.asarray(model.x_i, np.float32)
    arrays["profile_model"] = np.nan_to_num(fit, nan=0.0).astype(np.float32)
    if measured is not None:
        arrays["profile_measured"] = np.nan_to_num(measured, nan=0.0).astype(np.float32)
    return {"count": N, "radii_mm": centres.tolist(), "measured": measured is not None}


def _about(view: ObjectView) -> str:
    e = view.errors
    lines = [
        f"Relit by precomputed radiance transfer: {view.transfer.bands} bands of real spherical harmonics "
        f"({view.transfer.directions} directions, shadows and the subsurface transport included).",
    ]
    if view.angles:
        lines.append(
            "The model's lean is drawn: the transport leans toward each direction the light arrives from "
            "(render --angles)."
        )
    if e:
        chain = "render --angles' chain" if view.angles else "render's chain"
        lines.append(
            f"Relative RMSE against the full relight ({chain}) through the default camera: "
            + ", ".join(f"{k} {v:.3f}" for k, v in e.items())
            + "."
        )
    lines.append(f"Incidence law: {view.law.name}; boundary η = {view.eta:g}.")
    return "<br>".join(lines)
