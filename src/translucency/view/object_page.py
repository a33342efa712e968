r"""What the page shows of a per-vertex model: its relighting — the transport, the transfer, the exit law.

:func:`viewed_object` does the work once per model (the transport, the transfer of
:mod:`translucency.transport.transfer`, the error against the full relight); :meth:`ObjectView.page_data`
turns it into the arrays and the description the page (``static/viewer.js``) reads — with the mesh, the
maps and the profiles of :mod:`.surface` — and :meth:`ObjectView.relight` gives the live viewer the
radiance of a point or spot light.  The camera and the lights by default: :mod:`.defaults`.

Stored for the page (float16 where 3 significant digits do):

* ``transfer`` — :math:`t_{o,k,c}` in 8 bits over float16 scales, vertex-major, padded to whole RGBA
  texels (:mod:`.transfer_codec`);
* ``r1``, ``inv_mean_f`` and ``exit_table`` — the exit law :math:`\pi L / M = F(\mu_o; R_1) /
  \langle F \rangle` (:class:`translucency.model.incidence.HalfSpaceIncidence`) as per-vertex totals and a
  table :math:`F(\mu, R_1)` on an n × n grid of texel centres, or the boundary's
  :math:`F_t(\theta_o) / (1 - F_{dr})` (η ≠ 1), or none (Lambertian);
* the sky's coefficients, the exposure and the errors against the full relight.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from ..model.boundary import exit_factor, fresnel_transmittance
from ..model.incidence import HalfSpaceIncidence, cosine_mean, incidence_factor
from ..render.camera import Camera
from ..render.compare import rel_rmse
from ..render.lights import DirectionalLight, EnvironmentLight, PointLight, SpotLight
from ..render.picture import VertexPicture, coverage
from ..transport import PreparedObject
from ..transport.irradiance import vertex_irradiance
from ..transport.relight import relight_vertices, view_cosines
from ..transport.transfer import DEFAULT_BANDS, DEFAULT_DIRECTIONS, Transfer, transfer_vectors
from .defaults import DEFAULT_LIGHT, DEFAULT_VIEW, IRRADIANCE, POINT_DISTANCE, direction, point_intensity
from .surface import surface_data
from .transfer_codec import encode_transfer, quantised

#: the exit table's size (μ × R_1)
EXIT_TABLE = 64


@dataclass
class ObjectView:
    """A per-vertex model prepared for viewing (:func:`viewed_object`): the prepared object every renderer
    draws, and its transfer."""

    prepared: PreparedObject
    transfer: Transfer
    environment: EnvironmentLight
    name: str
    dataset: object = None
    errors: dict = field(default_factory=dict)
    seconds: dict = field(default_factory=dict)
    drafts: dict = field(default_factory=dict)  # coarse transports by their receivers (:meth:`relight`)
    companion: ObjectView | None = None  # a second model of the same mesh, shown beside and against this one

    model = property(lambda self: self.prepared.model, doc="The per-vertex model.")
    mesh = property(lambda self: self.prepared.mesh, doc="Its mesh, mm.")
    eta = property(lambda self: self.prepared.eta, doc="The boundary's relative index.")
    transport = property(lambda self: self.prepared.transport, doc="The prepared transport.")
    law = property(lambda self: self.prepared.law, doc="The incidence law.")
    scene = property(lambda self: self.prepared.shadow_scene, doc="The object alone, for shadow rays.")
    angles = property(
        lambda self: self.prepared.has_lean, doc="The transfer and the full relights lean toward the light."
    )

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
        :func:`~translucency.transport.lean.leaned`).  With ``receivers`` (vertex indices) a draft at
        those only: their irradiance through the transport coarsened to their cells
        (:meth:`~translucency.transport.relight.Transport.coarse`, prepared on the first call; the paper's
        model, a draft while the light moves)."""
        if receivers is None:  # (the camera's lean, the exit's, is off: unread)
            return self.prepared.through(self.prepared.irradiance(light), light, eye=self.centre)
        key = hash(np.asarray(receivers).tobytes())
        if key not in self.drafts:
            self.drafts[key] = (self.transport.coarse(self.mesh.vertices, receivers), self.law.at(receivers))
        coarse, law = self.drafts[key]
        E = vertex_irradiance(self.mesh, self.scene, light, self.eta, law, at=receivers)
        return relight_vertices(coarse, E)

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


def viewed_object(
    prepared: PreparedObject,
    *,
    environment: EnvironmentLight | None = None,
    bands: int = DEFAULT_BANDS,
    directions: int = DEFAULT_DIRECTIONS,
    dataset=None,
    name: str = "model",
    check_error: bool = True,
    progress=None,
) -> ObjectView:
    """The transfer of a prepared object (:class:`~translucency.transport.PreparedObject`: the transport
    every renderer draws, built here if it is not yet), and (``check_error``) the transfer's error against
    the full relight for a directional light and the environment, through the default camera.

    ``environment``: the page's sky (default: a constant sky); ``dataset``: the mesh data set the model
    was fitted to, for the measured profiles (None: the fit's alone); with the prepared object's lean
    drawn (``angles``, a model that has one), the transfer and the full relights lean toward the light
    (:mod:`translucency.transport.transfer`); ``progress(step)`` names each step.

    Examples
    --------
    >>> import translucency as tl
    >>> from translucency.render import object_of_model
    >>> model = tl.load_model(tl.data.example_path("spot_coarse.model.zip"))   # the example object
    >>> mesh, _ = object_of_model(model, {})
    >>> from translucency.transport import PreparedObject
    >>> from translucency.view.object_page import viewed_object
    >>> view = viewed_object(PreparedObject(model, mesh), name="spot")
    >>> sorted(view.errors)[-1], bool(view.errors["environment"] < 0.05)
    ('environment', True)
    """
    say = progress or (lambda step: None)
    seconds = {}
    t = time.perf_counter()
    say("transport")
    prepared.build()
    seconds["transport"] = time.perf_counter() - t
    t = time.perf_counter()
    say("transfer")
    transfer = transfer_vectors(
        prepared.transport, prepared.mesh, prepared.shadow_scene, prepared.law, bands=bands,
        directions=directions, eta=prepared.eta, angles=prepared.has_lean,
    )  # fmt: skip
    seconds["transfer"] = time.perf_counter() - t
    view = ObjectView(
        prepared=prepared,
        transfer=transfer,
        environment=environment or EnvironmentLight(IRRADIANCE / math.pi, samples=128),
        name=name,
        dataset=dataset,
        seconds=seconds,
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
    camera = Camera.looking_at(view.mesh, direction(*DEFAULT_VIEW), *size)
    mask = coverage(view.mesh, camera)
    picture = VertexPicture(view.mesh, camera, spp=4, eta=view.eta)
    exit_law = view.exit(camera.origin)
    lights = {
        "directional (default)": view.light_at("directional", direction(*DEFAULT_LIGHT)),
        "directional (side)": view.light_at("directional", direction(90.0, 10.0)),
        "directional (back)": view.light_at("directional", direction(DEFAULT_VIEW[0] + 180.0, 20.0)),
        "directional (above)": view.light_at("directional", (0.0, 0.0, 1.0)),
        "environment": view.environment,
    }
    stored = quantised(view.transfer)  # what the page holds: 8 bits and float16 scales
    out = {}
    for name, light in lights.items():
        E = view.prepared.irradiance(light)
        full = view.prepared.through(E, light, eye=view.centre)
        local = E if light.delta else None  # the page: its shadow map
        ours = np.maximum(stored.radiance(light.sh_coefficients(stored.bands), local), 0.0)
        out[name] = rel_rmse(picture.draw(full * exit_law), picture.draw(ours * exit_law), mask)
    return out


def _light_data(view: ObjectView) -> tuple[dict, dict]:
    transfer = view.transfer
    meta, arrays = encode_transfer(transfer)
    exit_law = _law_arrays(view, arrays)
    env = view.environment.sh_coefficients(transfer.bands)
    # the exposure: the default light's picture at 0.5 for its brightest percent of vertices
    default = view.relight(view.light_at("directional", direction(*DEFAULT_LIGHT)))
    eye = view.centre + view.size * np.asarray(direction(*DEFAULT_VIEW))
    bright = float(np.quantile(np.max(default * view.exit(eye), axis=1), 0.99))
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
