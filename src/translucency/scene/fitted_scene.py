r"""A user's Mitsuba scene with fitted translucent objects in it: prepared once, lit, rendered.

Two passes, each a wavefront over every vertex of every fitted object:

1. **light in** — the effective irradiance at each vertex from the whole scene
   (:func:`~translucency.scene.irradiance.scene_irradiance`: every emitter with the shadows of every
   shape, the indirect light of the other shapes, the glow of the fitted objects as it stands);
2. **through the body** — the exitance :math:`M = \pi T E` of each object's prepared transport
   (:class:`~translucency.scene.fitted.FittedObject`), which then glows
   (:class:`~translucency.scene.surfaces.GlowingSurfaces`).

The first pass sees the fitted objects dark; the second (``passes=2``, the default) sees them glowing
from the first, so that an object lit by the light its neighbour or the floor under it sends back, and
by itself across a concavity, is counted once more.  The irradiance is linear in the glow: the second
pass keeps the first's :math:`E_0` and traces only the glow's part, at a quarter of the samples
(:meth:`FittedScene.light`).  The picture is then path-traced through the scene's
own sensor and film by :class:`~translucency.scene.integrator.integrator_class` (the fitted objects glow,
reflect off their boundary, and light the other shapes).  A new light or camera costs the two passes
and the picture; the transports are built once.
"""

from __future__ import annotations

import time

import numpy as np

from .._validate import TranslucencyError
from ..mitsuba import mitsuba
from ..mitsuba.user_scenes import load_user_scene, mesh_buffers, segments_hit, shapes_by_id
from ..model.lean import lean_vector
from ..transport import TransportOptions
from .fitted import fitted_object
from .integrator import STRATEGIES, integrator_class
from .irradiance import scene_irradiance
from .surfaces import GlowingSurfaces


class FittedScene:
    """A Mitsuba scene with fitted objects (module docstring).

    Parameters
    ----------
    scene : str, Path, dict or mitsuba.Scene
        A Mitsuba XML file, a scene dict, or a loaded scene.
    models : dict
        Shape id → per-vertex model file (or loaded model).  Each shape must be the model's mesh
        (``translucency export MODEL --ply``) placed by its ``to_world``.
    scene_unit_mm : float
        Millimetres per scene unit (the models are in mm).
    roughness : float
        GGX α of a dielectric object's boundary (0: smooth).
    samples : int
        Irradiance samples per vertex of the first pass (the light of the scene's emitters).
    glow_samples : int, optional
        Samples per vertex of each later pass (the objects' glow alone; :meth:`light`); default a
        quarter of ``samples``.
    passes : int
        Light-in / through-the-body passes (module docstring).
    max_depth : int
        Longest path (bounces) of the picture and of the irradiance's rays.
    transport : TransportOptions, optional
        The objects' transport (:class:`~translucency.transport.TransportOptions`: its kind, near radius,
        the lean — objects whose model has one lean toward the light arriving from the scene, by its
        irradiance-weighted mean lean vector); default: the defaults.

    Examples
    --------
    The example scene (:func:`translucency.copy_examples`) with the example model in its shape
    ``object``, few samples:

    >>> import tempfile
    >>> from pathlib import Path
    >>> import translucency as tl
    >>> folder, model = Path(tempfile.mkdtemp()), tl.data.example_path("spot_coarse.model.zip")
    >>> _ = tl.copy_examples(folder), tl.export_ply(model, folder / "object.ply")   # the scene's object
    >>> from translucency.scene import FittedScene
    >>> fs = FittedScene(folder / "scene.xml", {"object": model}, samples=4, passes=1)
    >>> fs.prepare()  # the transports, once
    >>> [E.shape for E in fs.light()]   # each object's irradiance per vertex
    [(402, 3)]
    >>> image = fs.render(spp=2)
    >>> image.shape
    (240, 320, 3)
    """

    def __init__(
        self,
        scene,
        models: dict,
        *,
        scene_unit_mm: float = 1.0,
        roughness: float = 0.0,
        samples: int = 32,
        glow_samples: int | None = None,
        passes: int = 2,
        max_depth: int = 8,
        strategy: str = "mis",
        transport: TransportOptions | None = None,
    ):
        mi = mitsuba()
        glow_samples = max(1, samples // 4) if glow_samples is None else glow_samples
        if not models:
            raise TranslucencyError("models: name at least one fitted object (shape id = model file)")
        for option, value, lo in (
            ("samples", samples, 1),
            ("passes", passes, 1),
            ("glow_samples", glow_samples, 1),
            ("max_depth", max_depth, 1),
        ):
            if not isinstance(value, int) or value < lo:
                raise TranslucencyError(f"{option}: must be an integer >= {lo}, got {value!r}")
        if not scene_unit_mm > 0:
            raise TranslucencyError(f"scene_unit_mm: must be > 0, got {scene_unit_mm!r}")
        if strategy not in STRATEGIES:
            raise TranslucencyError(f"strategy: {strategy!r} is not one of {', '.join(STRATEGIES)}")
        self.source = scene
        self.scene = scene if isinstance(scene, mi.Scene) else load_user_scene(scene)
        self.samples, self.passes, self.max_depth = samples, passes, max_depth
        self.glow_samples = glow_samples
        self.transport = TransportOptions() if transport is None else transport
        shapes = shapes_by_id(self.scene)
        placed = dict(scene_unit_mm=scene_unit_mm, transport=self.transport, roughness=roughness)
        self.objects = [
            fitted_object(n, source, *_mesh_shape(shapes, n), **placed) for n, source in models.items()
        ]
        if not self.scene.emitters():
            raise TranslucencyError(
                "scene: no emitters (no light, no environment); nothing lights the fitted objects"
            )
        self._check_size(scene_unit_mm)  # (a wrong unit first: it makes the other checks' lines misleading)
        self._check_intersections()
        self._check_media()
        #: what of the user's scene is replaced (one line each, for the command line to print)
        self.notes = []
        if self.scene.integrator() is not None:
            kind = str(self.scene.integrator()).split("[")[0].strip()
            self.notes.append(
                f"scene: its integrator ({kind}) is replaced by translucency's (paths of up to "
                f"{max_depth} bounces, --max-depth)"
            )
        self.strategy = strategy
        self.glow = None  # prepare()
        self.prepare_s = None
        self.irradiance = [None] * len(self.objects)

    def prepare(self, progress=None) -> None:
        """Build each object's transport (at the near radius its prepared object chose) and the
        integrator: once per scene.  ``progress(k, n, name)`` before each object."""
        mi = mitsuba()
        t = time.perf_counter()
        for k, o in enumerate(self.objects):
            if progress:
                progress(k, len(self.objects), o.name)
            o.prepare()
        self.glow = GlowingSurfaces([o.glowing for o in self.objects])
        props = mi.Properties()
        props["max_depth"], props["strategy"] = int(self.max_depth), str(self.strategy)
        self.integrator = integrator_class()(props)
        self.integrator.glow = self.glow
        self.prepare_s = time.perf_counter() - t

    @property
    def vertices(self) -> int:
        """Vertices of all fitted objects."""
        return sum(len(o.mesh.vertices) for o in self.objects)

    @property
    def film_size(self) -> tuple[int, int]:
        """(width, height) of the first sensor's film, pixels."""
        return tuple(int(v) for v in self.scene.sensors()[0].film().crop_size())

    def _check_intersections(self) -> None:
        """One line for a fitted object that crosses another shape (its edges against the scene)."""
        shapes = list(self.scene.shapes())
        for o in self.objects:
            v = o.vertices
            e = np.asarray(o.mesh.edges_unique)
            hit = segments_hit(self.scene, v[e[:, 0]], v[e[:, 1]], skip=[o.shape])
            if (hit >= 0).any():
                other = shapes[int(hit[hit >= 0][0])].id()
                raise TranslucencyError(
                    f"shape '{o.name}': intersects shape '{other}' ({int((hit >= 0).sum())} of its edges "
                    "cross it); move one of them"
                )

    def _check_media(self) -> None:
        """One line for a medium our picture would ignore: inside or around a shape, or the camera's (the
        picture is traced surface to surface; a fitted object's inside is its model)."""
        mi = mitsuba()
        fitted = {o.name for o in self.objects}
        for shape in self.scene.shapes():
            for side, medium in (
                ("interior", shape.interior_medium()),
                ("exterior", shape.exterior_medium()),
            ):
                if medium is not None:
                    why = "the model is its inside" if shape.id() in fitted else "the picture has no media"
                    raise TranslucencyError(
                        f"shape '{shape.id()}': its {side} medium would be ignored ({why}); remove it"
                    )
        for sensor in self.scene.sensors():
            if any(k.startswith("medium.") for k in mi.traverse(sensor).keys()):
                raise TranslucencyError(
                    "sensor: its medium would be ignored (the picture has no media); remove it"
                )

    def _check_size(self, unit_mm: float) -> None:
        """One line for an object the scene's unit makes absurd: the camera inside its box, or less than a
        pixel across — with the size it became, in scene units."""
        sensor = self.scene.sensors()[0]
        M = np.asarray(sensor.world_transform().matrix, dtype=np.float64).reshape(4, 4)
        eye = M[:3, 3]
        W = self.film_size[0]
        fov = float(np.asarray(mitsuba().traverse(sensor).get("x_fov", [45.0])).ravel()[0])
        for o in self.objects:
            v = o.vertices
            lo, hi = v.min(axis=0), v.max(axis=0)
            size = float((hi - lo).max())  # across, scene units
            mm = size * unit_mm
            became = f"its {mm:.3g} mm are {size:.3g} scene units at {unit_mm:g} mm a unit"
            if np.all(eye > lo) and np.all(eye < hi):
                raise TranslucencyError(
                    f"shape '{o.name}': the camera is inside it ({became}); is the scene's unit right "
                    "(--scene-unit)?"
                )
            distance = float(np.linalg.norm(0.5 * (lo + hi) - eye))
            pixels = size / max(distance * 2 * np.tan(np.radians(fov) / 2), 1e-300) * W
            if pixels < 1.0:
                raise TranslucencyError(
                    f"shape '{o.name}': {pixels:.2g} pixels across from the camera {distance:.3g} units "
                    f"away ({became}); is the scene's unit right (--scene-unit)?"
                )

    def light(self, *, seed: int = 0) -> list[np.ndarray]:
        """Run the passes (module docstring); every object glows with its new exitance.  Returns the last
        pass's effective irradiance per object, (V, 3) each.

        The first pass sees the objects dark: :math:`E_0`, the light of the scene's emitters.  A later
        pass adds to it only what the objects' glow brings, :math:`E_p = E_0 + G(M_{p-1})` (``sources=
        "glow"``, ``glow_samples`` a vertex): the irradiance is linear in the glow, and :math:`E_0` is
        the same every pass."""
        if self.glow is None:
            self.prepare()
        for o in self.objects:
            o.set_exitance(np.zeros((len(o.mesh.vertices), 3)))
        self.glow.update()
        E0 = [self._irradiance(k, o, "all", self.samples, seed) for k, o in enumerate(self.objects)]
        E = E0
        for p in range(self.passes):
            if p > 0:
                E = [
                    _added(e0, self._irradiance(k, o, "glow", self.glow_samples, seed + 7919 * p))
                    for k, (o, e0) in enumerate(zip(self.objects, E0))
                ]
            for o, (e, ell) in zip(self.objects, E):
                o.set_exitance(o.exitance(e, ell))
            self.glow.update()
        self.irradiance = [e for e, _ in E]
        return self.irradiance

    def _irradiance(self, k: int, o, sources: str, samples: int, seed: int):
        """Object k's irradiance (V, 3) from ``sources`` and, where it leans, the light's mean lean vector
        (V, 3) (None otherwise), traced at every vertex."""
        return self._traced(k, o, slice(None), o.law, sources, samples, seed)

    def _traced(self, k: int, o, at, law, sources: str, samples: int, seed: int, salt: int = 0):
        """Object k's irradiance and mean lean vector (or None) traced at its vertices ``at`` with the
        incidence ``law`` of those vertices (:func:`~translucency.scene.irradiance.scene_irradiance`)."""
        lean = o.prepared.has_lean
        x, n = o.vertices, o.normals
        offset = 5e-4 * float(np.ptp(x, axis=0).max())  # the rays' start above the surface, whole object
        e = scene_irradiance(
            self.scene,
            self.glow,
            x[at],
            n[at],
            samples=samples,
            seed=seed + 104729 * k + 15485863 * salt,
            offset=offset,
            incidence=law,
            eta=o.eta,
            max_depth=self.max_depth,
            moment=(lambda w, nn, eta=o.eta: lean_vector(w, nn, eta)) if lean else None,
            sources=sources,
        )
        return e if lean else (e, None)

    def render(self, *, spp: int = 16, seed: int = 0, sensor: int = 0, glowing: bool = True) -> np.ndarray:
        """The picture (H, W, 3), linear RGB, through the scene's ``sensor`` (index), ``spp`` samples a
        pixel; :meth:`light` first.  ``glowing=False``: the fitted objects dark (their boundary's
        reflection only), to see what light they bring to the rest."""
        mi = mitsuba()
        if self.irradiance[0] is None:
            self.light(seed=seed)
        if not glowing:
            kept = [o.glowing.exitance for o in self.objects]
            for o in self.objects:
                o.set_exitance(np.zeros_like(o.glowing.exitance))
            self.glow.update()
            try:
                return self.render(spp=spp, seed=seed, sensor=sensor)
            finally:
                for o, M in zip(self.objects, kept):
                    o.set_exitance(M)
                self.glow.update()
        return np.asarray(
            mi.render(
                self.scene, integrator=self.integrator, spp=int(spp), seed=int(seed), sensor=int(sensor)
            ),
            dtype=np.float64,
        )[..., :3]


def _mesh_shape(shapes: dict, name: str):
    """(the shape, its vertices, its triangles) of the scene's shape ``name``, or one line why it cannot be
    a fitted object (none of that id, not a mesh, an emitter)."""
    shape = shapes.get(name)
    if shape is None:
        raise TranslucencyError(
            f"model {name}: the scene has no shape with id '{name}' (its shapes: "
            f"{', '.join(sorted(shapes)) or 'none'})"
        )
    if not shape.is_mesh():
        raise TranslucencyError(f"shape '{name}': not a mesh; place the model's mesh (a ply) there")
    if shape.is_emitter():
        raise TranslucencyError(
            f"shape '{name}': carries an area emitter; a fitted object glows with its own exitance "
            "(remove the emitter)"
        )
    return (shape, *mesh_buffers(shape))


def _added(first, glow):
    """The irradiance and mean lean of two parts of the light together: the lean is each part's mean
    weighted by its grey irradiance (the weight :func:`~translucency.scene.irradiance.scene_irradiance`
    averages with)."""
    (e0, ell0), (eg, ellg) = first, glow
    if ell0 is None:
        return e0 + eg, None
    w0, wg = e0.mean(axis=1, keepdims=True), eg.mean(axis=1, keepdims=True)
    total = w0 + wg
    ell = np.divide(w0 * ell0 + wg * ellg, total, out=np.zeros_like(ell0), where=total > 0)
    return e0 + eg, ell
