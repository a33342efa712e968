r"""A fitted object in a scene: its per-vertex model, its mesh in the model's frame and in the scene's, its
prepared transport, its boundary.

The transport runs in the model's frame (mm, where :math:`R_d` was measured); the irradiance is gathered
in the scene's frame at the same vertices (:class:`~translucency.scene.pose.Pose` carries one onto the
other).  Per vertex the exitance is

.. math:: M_v = \pi\,(T E)_v \qquad (\text{W per scene-unit}^2 \text{ for } E \text{ in W per scene-unit}^2),

:math:`T` the sparse near field plus the far field of :func:`translucency.transport.transport_matrices`, and
it leaves with the exit law :math:`g_v(\mu)` of the object's boundary: a dielectric's
:math:`F_t(\mu)/(1 - F_{dr,e})`, the half-space incidence law's :math:`F(\mu)/\langle F \rangle` (index-
matched objects with measured totals), or Lambertian.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import trimesh

from ..io.vertex_model import check_vertex_model, load_vertex_model
from ..mitsuba import load_plugin
from ..model.boundary import exit_factor
from ..render import boundary_eta, object_of_model
from ..transport import PreparedObject, TransportOptions
from .pose import Pose, pose_of
from .surfaces import Glowing, exit_table


def read_vertex_model(source, *, name: str):
    """(model, header) of a per-vertex model file (or an already loaded model with ``header={}``);
    one line for a file that is not one, or a model that is not per-vertex."""
    purpose = f"the scene's object '{name}'"
    if not isinstance(source, (str, Path)):
        check_vertex_model(source, purpose)
        return source, {}
    return load_vertex_model(source, purpose)


def coat_of(eta: float, roughness: float):
    """The boundary's Mitsuba BSDF: None (index-matched), a smooth ``dielectric`` or a ``roughdielectric``
    (GGX, ``roughness`` = α) of index η against air."""
    if eta == 1.0:
        return None
    if roughness > 0:
        return load_plugin(
            {"type": "roughdielectric", "int_ior": float(eta), "ext_ior": 1.0, "alpha": float(roughness)}
        )
    return load_plugin({"type": "dielectric", "int_ior": float(eta), "ext_ior": 1.0})


@dataclass
class FittedObject:
    """One fitted object of a scene (module docstring): placed by :func:`fitted_object`, drawn through its
    :class:`~translucency.transport.PreparedObject`, glowing once :meth:`prepare` has built it."""

    name: str
    prepared: PreparedObject  # the model on its mesh (model frame, mm) behind its boundary, its transport
    pose: Pose
    shape: object  # the Mitsuba shape it is in the scene
    coat: object = None
    acquisition: dict = field(default_factory=dict)  # the data set's header (the filling, for a reference)
    scene_unit_mm: float = 1.0
    glowing: Glowing = None  # the object as a light of the scene, once prepared

    @property
    def model(self):
        """The per-vertex model."""
        return self.prepared.model

    @property
    def mesh(self) -> trimesh.Trimesh:
        """The model's mesh, model frame (mm), in the scene's triangle order."""
        return self.prepared.mesh

    @property
    def eta(self) -> float:
        """The boundary's relative index (1: index-matched)."""
        return self.prepared.eta

    @property
    def transport(self):
        """The prepared transport (:class:`~translucency.transport.relight.Transport`)."""
        return self.prepared.transport

    @property
    def law(self):
        """The incidence law of the object's boundary."""
        return self.prepared.law

    def prepare(self) -> None:
        """Build the transport (its near radius chosen by the prepared object) and the glowing surface."""
        self.prepared.build()
        self.glowing = Glowing(
            self.shape,
            self.vertices,
            np.asarray(self.mesh.faces),
            exit_law=self.exit_law(),
            coat=self.coat,
            normals=self.normals,
        )

    @property
    def vertices(self) -> np.ndarray:
        """(V, 3) vertices in the scene."""
        return self.pose.apply(self.mesh.vertices)

    @property
    def mean_edge(self) -> float:
        """The mesh's mean edge length, mm (model frame)."""
        return float(self.mesh.edges_unique_length.mean())

    @property
    def normals(self) -> np.ndarray:
        """(V, 3) outward vertex normals in the scene."""
        return self.pose.turn(self.mesh.vertex_normals)

    def exitance(self, E: np.ndarray, lean: np.ndarray | None = None) -> np.ndarray:
        r"""(V, 3) exitance :math:`M = \pi T E` for the effective irradiance ``E`` (V, 3); with ``lean``
        (V, 3), the light's mean lean vector at each vertex in the scene's frame, the transport leans
        toward it where the lean is drawn (:meth:`~translucency.transport.PreparedObject.through_leaning`)."""
        # the scene's frame turned to the model's: R^T ℓ
        ell = None if lean is None else np.asarray(lean, np.float64) @ self.pose.rotation
        return np.pi * self.prepared.through_leaning(E, ell).astype(np.float64)

    def exit_law(self) -> np.ndarray:
        """(V, EXIT_NODES, 3) the exit's angular law g_v(μ) (module docstring)."""
        V = len(self.mesh.vertices)
        if self.eta != 1.0:
            return exit_table(lambda mu: np.full((V, 3), float(exit_factor(mu, self.eta))))
        return exit_table(lambda mu: _or_ones(self.law.exit(np.full(V, max(mu, 1e-3))), V))

    def set_exitance(self, M: np.ndarray) -> None:
        """Glow with exitance M (V, 3) from now on."""
        self.glowing.exitance = np.asarray(M, dtype=np.float64)


def _or_ones(g, V):
    return np.ones((V, 3)) if g is None else g


def fitted_object(
    name: str,
    source,
    shape,
    shape_vertices,
    shape_faces,
    *,
    scene_unit_mm: float = 1.0,
    transport: TransportOptions | None = None,
    roughness: float = 0.0,
) -> FittedObject:
    """The fitted object ``name``: the model ``source`` (a file or a loaded per-vertex model) placed as the
    Mitsuba ``shape`` whose vertices and triangles are ``shape_vertices``, ``shape_faces`` (its transport
    not built yet: :meth:`FittedObject.prepare`).

    Refuses, in one line each, a model that is not per-vertex, a shape that is not the model's mesh or is
    resized (:func:`~translucency.scene.pose.pose_of`).  ``transport``: the transport's choices
    (:class:`~translucency.transport.TransportOptions`).
    """
    model, header = read_vertex_model(source, name=name)
    mesh, acquisition = object_of_model(model, header or {"meta": {"acquisition": {}}})
    pose = pose_of(name, mesh.vertices, mesh.faces, shape_vertices, shape_faces, scene_unit_mm=scene_unit_mm)
    if not np.array_equal(mesh.faces, shape_faces):  # the same triangles in the scene's order: what it hits
        mesh = trimesh.Trimesh(mesh.vertices, np.asarray(shape_faces, np.int64), process=False)
    eta = boundary_eta(acquisition)  # 1 (index-matched) for a loaded model without its header
    return FittedObject(
        name=name,
        prepared=PreparedObject(model, mesh, eta=eta, options=transport),
        pose=pose,
        shape=shape,
        coat=coat_of(eta, roughness),
        acquisition=acquisition,
        scene_unit_mm=float(scene_unit_mm),
    )
