r"""Where a fitted object stands in a scene: the similarity that carries the model's mesh onto the shape.

A scene names a fitted object by a mesh shape whose vertices are the model's own (the mesh
``translucency export --ply`` writes, placed by the shape's ``to_world``).  Its pose is the similarity
:math:`x_{scene} = s\,R\,x_{model} + t` that best carries the model's vertices (mm) onto the shape's
(scene units), by Umeyama's closed form (SVD of the cross-covariance); the scale must be
:math:`1/u` for a scene unit of u mm (the model's :math:`R_d` is per mm², so the object cannot be
resized), and the largest distance left after the fit must stay below :data:`TOLERANCE` of the object's
size — otherwise the shape is not the model's mesh.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._validate import TranslucencyError
from ..geometry import same_triangles

#: the largest vertex distance left after the best similarity, in object sizes (bounding-box diagonal): a
#: model file's vertices lie on a grid a hundredth of an edge fine (io/mesh_codec.py), the user's mesh not
TOLERANCE = 1e-3
#: how far the pose's scale may be from 1 / scene unit, relative
SCALE_TOLERANCE = 1e-3


@dataclass(frozen=True)
class Pose:
    r"""The similarity :math:`x \mapsto s R x + t` from the model's frame (mm) to the scene's."""

    scale: float
    rotation: np.ndarray  # (3, 3), det +1
    translation: np.ndarray  # (3,)
    residual: float  # largest vertex distance left, scene units

    def apply(self, points: np.ndarray) -> np.ndarray:
        """Model-frame points (N, 3) in the scene."""
        return self.scale * np.asarray(points, np.float64) @ self.rotation.T + self.translation

    def turn(self, vectors: np.ndarray) -> np.ndarray:
        """Model-frame directions (N, 3) in the scene (unit length kept)."""
        return np.asarray(vectors, np.float64) @ self.rotation.T

    @property
    def matrix(self) -> np.ndarray:
        """The 4 × 4 matrix of the pose."""
        m = np.eye(4)
        m[:3, :3] = self.scale * self.rotation
        m[:3, 3] = self.translation
        return m


def similarity(source: np.ndarray, target: np.ndarray) -> Pose:
    """The least-squares similarity carrying ``source`` (N, 3) onto ``target`` (N, 3) (Umeyama 1991).

    Examples
    --------
    >>> x = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    >>> pose = similarity(x, 2 * x + 5)
    >>> round(pose.scale, 6), pose.translation.round(6).tolist()
    (2.0, [5.0, 5.0, 5.0])
    """
    X, Y = np.asarray(source, np.float64), np.asarray(target, np.float64)
    mx, my = X.mean(axis=0), Y.mean(axis=0)
    A, B = X - mx, Y - my
    U, S, Vt = np.linalg.svd(B.T @ A / len(X))
    D = np.diag([1.0, 1.0, np.sign(np.linalg.det(U @ Vt)) or 1.0])
    R = U @ D @ Vt
    var = (A**2).sum() / len(X)
    s = float(np.trace(np.diag(S) @ D) / var) if var > 0 else 1.0
    t = my - s * R @ mx
    residual = float(np.max(np.linalg.norm(s * A @ R.T + s * R @ mx + t - Y, axis=1))) if len(X) else 0.0
    return Pose(s, R, t, residual)


def pose_of(
    name: str, model_vertices, model_faces, shape_vertices, shape_faces, *, scene_unit_mm=1.0
) -> Pose:
    """The pose of the shape ``name`` as the model's mesh, or one line saying why it is not that mesh.

    ``scene_unit_mm``: how many millimetres one scene unit is (1: the scene is in mm).
    """
    Vm, Vs = len(model_vertices), len(shape_vertices)
    if Vm != Vs or len(model_faces) != len(shape_faces):
        raise TranslucencyError(
            f"shape '{name}': {Vs:,} vertices and {len(shape_faces):,} triangles, but the model's mesh has "
            f"{Vm:,} and {len(model_faces):,} ({Vs - Vm:+,} vertices: re-triangulated or re-exported?); "
            "place the mesh 'translucency export MODEL --ply' writes"
        )
    Fm, Fs = np.asarray(model_faces), np.asarray(shape_faces)
    corner = Fm != Fs  # the triangles' corners that differ
    if corner.any() and not same_triangles(Fm, Fs):
        # how many triangles differ, and how many vertices their differing corners name
        moved = np.unique(np.concatenate([Fm[corner], Fs[corner]]))
        raise TranslucencyError(
            f"shape '{name}': re-triangulated or re-ordered — {int(corner.any(axis=1).sum()):,} of "
            f"{len(Fm):,} triangles and {len(moved):,} of {Vm:,} vertices differ from the model's mesh; "
            "place the mesh 'translucency export MODEL --ply' writes"
        )
    pose = similarity(model_vertices, shape_vertices)
    size = float(np.linalg.norm(np.ptp(np.asarray(shape_vertices, np.float64), axis=0)))
    if pose.residual > TOLERANCE * size:
        off = np.linalg.norm(pose.apply(model_vertices) - np.asarray(shape_vertices, np.float64), axis=1)
        raise TranslucencyError(
            f"shape '{name}': does not match the model's mesh ({int((off > TOLERANCE * size).sum()):,} of "
            f"{Vm:,} vertices off, the worst by {pose.residual:.3g} scene units after the best rotation, "
            "scale and shift); place the mesh 'translucency export MODEL --ply' writes, moved only by "
            "to_world"
        )
    want = 1.0 / float(scene_unit_mm)
    if abs(pose.scale / want - 1.0) > SCALE_TOLERANCE:
        raise TranslucencyError(
            f"shape '{name}': scaled by {pose.scale * scene_unit_mm:.4g} against the model's millimetres "
            f"(a scene unit = {scene_unit_mm:g} mm); a measured material cannot be resized — scale it by "
            f"{want:g}, or say the scene's unit (scene_unit_mm / --scene-unit)"
        )
    return pose
