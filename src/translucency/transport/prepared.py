r"""A fitted object prepared for drawing: built once from one set of options, drawn by every renderer.

``render``, ``render scene``, the viewer, the glTF bake and the picture checks all draw a
:class:`PreparedObject`; none assembles a transport of its own.
"""

from __future__ import annotations

import functools
import time

import numpy as np

from .irradiance import vertex_irradiance
from .kinds import transport_kind
from .lean import lean_applies, lean_pairs, leaned, tilted
from .matrices import default_radius
from .options import TransportOptions
from .relight import relight_object, relight_vertices


class PreparedObject:
    r"""A per-vertex model on its mesh behind its boundary, with the transport every renderer applies.

    **What the default draws** (``TransportOptions()``), per vertex v of the mesh (mm), per channel:

    1. *Light in.*  The irradiance :math:`E_v` (W/mm²) of the light with the shadows of the object itself
       (:func:`~translucency.transport.irradiance.vertex_irradiance`), counted against the acquisition's
       normal-incidence beams by the incidence law: behind an index-matched boundary the half-space law
       (Chandrasekhar's plane albedo from each vertex's measured total, :mod:`translucency.model.incidence`),
       behind a dielectric (η ≠ 1) the Fresnel transmittance.
    2. *Through the body.*  :math:`L = T E` (W/(mm² sr)), the transport of the kind named by the options
       (:mod:`~translucency.transport.kinds`; the default: the fitted sums of exponentials between every
       pair within the near radius, the hierarchical far field beyond it, each vertex's own area and total
       as measured, and the through-body table where the model holds one).  The near radius is chosen
       once, here: the options' radius, or the model's 99 % energy radius, shrunk where the pairs would
       exceed ``max_pairs`` (:attr:`radius` is the one used).
    3. *The lean* (``angles``).  Where the model has one, the near pairs lean toward the light's direction
       (:mod:`translucency.transport.lean`); without ``angles``, or a model without a lean, the diffuse
       transport of step 2.
    4. *Out.*  The radiance toward the camera: a dielectric's :math:`F_t(\mu_o)/(1 - F_{dr,e})`, the
       half-space law's reciprocal exit behind an index-matched boundary, or Lambertian.

    Parameters
    ----------
    model : ReflectanceModel
        A per-vertex model (a fit on a mesh data set).
    mesh : trimesh.Trimesh
        Its mesh, mm, in the model's vertex order.
    eta : float
        The boundary's relative index (1: index-matched; :func:`translucency.render.boundary_eta`).
    options : TransportOptions, optional
        The transport's choices (default: the defaults).

    Examples
    --------
    >>> import translucency as tl
    >>> from translucency.render import object_of_model
    >>> model = tl.load_model(tl.data.example_path("spot_coarse.model.zip"))   # the example object
    >>> mesh, _ = object_of_model(model, {})
    >>> from translucency.render import Camera, parse_light
    >>> from translucency.transport import PreparedObject, TransportOptions
    >>> obj = PreparedObject(model, mesh, eta=1.0, options=TransportOptions())
    >>> light, camera = parse_light("point:60,-80,120,2e4"), Camera.looking_at(mesh)
    >>> L, E = obj.relight(light, camera.origin)   # radiance toward the camera and irradiance, per vertex
    >>> L.shape, bool(L.max() > 0)
    ((402, 3), True)
    """

    def __init__(self, model, mesh, *, eta: float = 1.0, options: TransportOptions | None = None):
        self.model, self.mesh, self.eta = model, mesh, float(eta)
        self.options = TransportOptions() if options is None else options
        self.kind = transport_kind(self.options.kind)
        # the near radius, chosen once: the user's, or the default at the options' pair limit (mm)
        given = self.options.radius
        self.radius = (
            float(given)
            if given is not None
            else default_radius(model, mesh, max_pairs=self.options.max_pairs)
        )
        self._transport = None
        self.seconds = None  # the transport's build, once built

    def build(self) -> PreparedObject:
        """Build the transport and, where it is drawn, the lean's pairs (once; later calls return at once);
        return the object."""
        if self._transport is None:
            t = time.perf_counter()
            shrink = self.options.radius is None  # a default radius may shrink until its pairs fit
            self._transport = self.kind.build(
                self.model, self.mesh, radius=self.radius, shrink=shrink, max_pairs=self.options.max_pairs
            )
            self.radius = float(self._transport.radius)
            if self.has_lean:
                self.lean_pairs  # noqa: B018 — the lean's pairs, built with the transport
            self.seconds = time.perf_counter() - t
        return self

    @property
    def transport(self):
        """The prepared :class:`~translucency.transport.relight.Transport` (built on first use)."""
        return self.build()._transport

    @functools.cached_property
    def law(self):
        """The incidence law of this object (:mod:`translucency.model.incidence`)."""
        return self.transport.incidence(self.kind.incidence, self.eta)

    @functools.cached_property
    def shadow_scene(self):
        """The object alone as a Mitsuba scene, for the shadow rays of its irradiance."""
        from ..mitsuba import mesh_scene  # Mitsuba loads only to draw

        return mesh_scene(self.mesh)

    @property
    def has_lean(self) -> bool:
        """Whether the lean is drawn at all: asked for (``angles``) and held by the model."""
        return bool(self.options.angles and self.transport.lean is not None)

    def leans_for(self, light) -> bool:
        """Whether the lean is drawn under ``light`` (one direction per vertex, or a sky's mean)."""
        return bool(self.options.angles and lean_applies(self.transport, light))

    @functools.cached_property
    def lean_pairs(self):
        """The lean's near pairs (:func:`~translucency.transport.lean.lean_pairs`), once per object."""
        return lean_pairs(self.transport, self.mesh, self.eta)

    def irradiance(self, light, scene=None) -> np.ndarray:
        """Step 1: the effective irradiance per vertex, W/mm² (``scene``: the shadowing scene, default the
        object alone)."""
        scene = self.shadow_scene if scene is None else scene
        return vertex_irradiance(self.mesh, scene, light, self.eta, self.law)

    def through(self, E, light=None, eye=None, scene=None) -> np.ndarray:
        """Steps 2 and 3: the radiance per vertex (V, 3), W/(mm² sr), for the irradiance ``E``; ``light``
        (and the camera at ``eye``, mm) say where the lean tilts, if it is drawn."""
        T = self.transport
        if light is not None and self.leans_for(light):
            scene = self.shadow_scene if scene is None else scene
            T = leaned(T, self.mesh, scene, light, eye, eta=self.eta, pairs=self.lean_pairs) or T
        return relight_vertices(T, E)

    def through_leaning(self, E, ell) -> np.ndarray:
        """Steps 2 and 3 for light whose lean vector at each vertex is ``ell`` (V, 3), the model's frame (a
        scene's irradiance-weighted mean): the radiance per vertex (V, 3)."""
        T = self.transport
        if ell is not None and self.has_lean:
            T = tilted(T, self.mesh, ell, eta=self.eta, pairs=self.lean_pairs)
        return relight_vertices(T, E)

    @functools.cached_property
    def medium_volume(self):
        """The medium the model's fit estimated from the scan (:mod:`translucency.medium`), on the voxel grid
        a walk reads."""
        from ..medium import medium_of  # only a kind that walks reads the medium

        return medium_of(self.model).volume(self.mesh)

    def relight(self, light, eye, scene=None):
        """Steps 1–4 under ``light`` seen from ``eye`` (mm): the radiance toward the camera per vertex
        (V, 3), W/(mm² sr), and the irradiance E.  A kind that draws a light its own way (a walk per light:
        :class:`~translucency.transport.walk.WalkedTransport`) has a ``relight`` of its own."""
        scene = self.shadow_scene if scene is None else scene
        if hasattr(self.kind, "relight"):
            return self.kind.relight(self, light, eye, scene)
        pairs = self.lean_pairs if self.leans_for(light) else None
        L, E, _ = relight_object(
            self.transport,
            self.mesh,
            scene,
            light,
            eye,
            eta=self.eta,
            incidence=self.law,
            angles=self.options.angles,
            pairs=pairs,
        )
        return L, E

    def describe(self) -> dict:
        """What is drawn, as a summary states it: the kind, the near radius, the law, the table, the lean."""
        T = self.transport
        out = {
            "transport": self.kind.name,
            "radius_mm": self.radius,
            "incidence": self.law.name,
            "through": bool(T.through),
            "angles": self.has_lean,
        }
        if hasattr(self.kind, "relight"):  # a kind that draws a light its own way: where it does not
            out["irradiance_only"] = (
                "a relight from the irradiance alone (a scene, the viewer, glTF) draws the default's "
                "through-body table instead of the walk"
            )
        return out
