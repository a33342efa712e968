r"""A fitted scene whose irradiance is traced at a reduced set of vertices (:mod:`.reduced`).

On the 27 k-vertex pig at 32 samples, a spacing of 2 mean edges saves a sixth of a light's time and adds a
quarter to its picture's error against a converged irradiance; at 16 samples it saves nothing
(``benchmarks/scene_speed.py``).  Kept for that benchmark; unstable.
"""

from __future__ import annotations

from .._validate import TranslucencyError
from ..scene import FittedScene
from .reduced import ReducedVertices


class ReducedScene(FittedScene):
    """:class:`~translucency.scene.FittedScene` whose irradiance is traced at one vertex per cell of a grid
    ``irradiance_spacing`` mean edges wide and at the shadow edges between them, interpolated elsewhere
    (0: at every vertex, as the scene it extends).

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> import translucency as tl
    >>> folder, model = Path(tempfile.mkdtemp()), tl.data.example_path("spot_coarse.model.zip")
    >>> _ = tl.copy_examples(folder), tl.export_ply(model, folder / "object.ply")   # the scene's object
    >>> from translucency.experimental.scene import ReducedScene
    >>> fs = ReducedScene(folder / "scene.xml", {"object": model}, irradiance_spacing=2.0, samples=4,
    ...                   passes=1)
    >>> E = fs.light()
    >>> [len(r.traced) < 402 for r in fs.reduced]   # fewer vertices traced than the object's 402
    [True]
    """

    def __init__(self, scene, models: dict, *, irradiance_spacing: float = 0.0, **options):
        if not (irradiance_spacing == 0 or irradiance_spacing >= 1):
            raise TranslucencyError(f"irradiance_spacing: 0 or >= 1 mean edges, got {irradiance_spacing!r}")
        self.irradiance_spacing = float(irradiance_spacing)
        self.reduced = [None] * len(models)  # each object's ReducedVertices (None: every vertex)
        self._reduced_at = 0.0  # the spacing self.reduced was built for
        super().__init__(scene, models, **options)

    def light(self, *, seed: int = 0):
        """:meth:`FittedScene.light` with the reduced vertex sets built once per spacing."""
        if self._reduced_at != self.irradiance_spacing:
            self.reduced = [
                ReducedVertices(o.vertices, o.normals, o.mean_edge * o.pose.scale, self.irradiance_spacing)
                if self.irradiance_spacing > 0
                else None
                for o in self.objects
            ]
            self._reduced_at = self.irradiance_spacing
        return super().light(seed=seed)

    def _irradiance(self, k: int, o, sources: str, samples: int, seed: int):
        """Object k's irradiance and mean lean vector: traced at the reduced vertices and at the shadow
        edges between them, interpolated elsewhere."""
        reduced = self.reduced[k]
        if reduced is None:
            return super()._irradiance(k, o, sources, samples, seed)
        at = reduced.traced
        e_s, ell_s = self._traced(k, o, at, o.law.at(at), sources, samples, seed)
        E = reduced.interpolate(e_s)
        ell = None if ell_s is None else reduced.interpolate(ell_s)
        E[at] = e_s
        if ell is not None:
            ell[at] = ell_s
        edge = reduced.to_refine(e_s)
        if len(edge):  # a shadow's edge crosses here: traced at its own vertices
            E[edge], ell_edge = self._traced(k, o, edge, o.law.at(edge), sources, samples, seed, salt=1)
            if ell is not None:
                ell[edge] = ell_edge
        return E, ell
