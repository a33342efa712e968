r"""A virtual scan of an estimated medium: the acquisition's pencil beams walked through it.

For incident vertex i and channel λ, ``photons`` photons enter at :math:`x_i` along :math:`-n_i` behind an
index-matched boundary, walk through the voxel volume
(:func:`~translucency.acquire.mesh_walk.mesh_random_walk`, light that leaves one part through the air into
another followed) and are tallied where they leave, shared
among the exit triangle's vertices by barycentric weight:

.. math:: R_d(x_i, x_o) = \frac{\#\{\text{exits at } o\}}{N\, A_o} \quad [\text{mm}^{-2}],

the unscattered exits left out (as ``acquire mesh`` records them apart).  The same estimator as the
acquisition's (:mod:`translucency.acquire.mesh`), on rows that are returned instead of written.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..acquire.mesh import exit_barycentric, splat_barycentric
from ..acquire.mesh_walk import EXIT, mesh_random_walk
from ..geometry import vertex_areas


@dataclass(frozen=True)
class Exits:
    """The photons of a walk that left scattered (:func:`walk_beams`): per exit, its beam (index into the
    entries), where it left (mm), its flight direction there, its triangle's vertices and barycentric
    weights."""

    beam: np.ndarray  # (n,)
    position: np.ndarray  # (n, 3) mm
    direction: np.ndarray  # (n, 3) unit, outwards
    face: np.ndarray  # (n,)
    tri: np.ndarray  # (n, 3) the exit triangle's vertices
    bary: np.ndarray  # (n, 3) the exit's barycentric weights there


def walk_beams(
    mesh, volume, channel: int, entry, normal, *, photons: int = 1, incoming=None, seed: int = 0, scene=None
) -> Exits:
    """``photons`` photons per entry (``entry``, ``normal`` (n, 3); arriving along ``incoming`` or −normal)
    walked through ``volume`` in ``channel`` behind an index-matched boundary, light that leaves one part
    through the air into another followed; the exits of the photons that scattered (the unscattered light,
    a delta along its beam, is left out), each with the entry it came from."""
    from ..mitsuba import mesh_scene  # Mitsuba loads only to walk

    scene = mesh_scene(mesh) if scene is None else scene
    res = mesh_random_walk(
        scene, mesh.bounds, volume, channel, entry, normal, photons, seed=seed, index_matched=True,
        reentry=True, incoming=incoming,
    )  # fmt: skip
    ok = np.flatnonzero((res.code == EXIT) & (res.scatters > 0))
    position = res.position[ok].astype(np.float64)
    tri, bary = exit_barycentric(mesh, res.face[ok], position)
    return Exits(ok // photons, position, res.direction[ok], res.face[ok], tri, bary)


def virtual_scan(mesh, volume, incident, photons: int, *, seed: int = 0, scene=None) -> np.ndarray:
    """R_d (n, V, 3) in mm⁻² of ``volume`` inside ``mesh`` for the beams at the vertices ``incident`` (n,).

    Examples
    --------
    >>> import trimesh
    >>> from translucency.acquire.volume import Volume
    >>> ball = trimesh.creation.icosphere(2, radius=5.0)
    >>> slab = Volume.homogeneous((24, 24, 24), 0.5, [1.0] * 3, [0.05] * 3, eta=1.0)
    >>> R = virtual_scan(ball, slab, [0], 2000)
    >>> total = (R[0] * vertex_areas(ball)[:, None]).sum(axis=0)  # the diffuse reflectance, < 1
    >>> bool((total > 0.2).all() and (total < 1).all())
    True
    """
    from ..mitsuba import mesh_scene  # Mitsuba loads only to walk

    scene = mesh_scene(mesh) if scene is None else scene
    incident = np.asarray(incident, dtype=np.int64)
    V, n = len(mesh.vertices), len(incident)
    area = vertex_areas(mesh)
    entry, normal = np.asarray(mesh.vertices)[incident], np.asarray(mesh.vertex_normals)[incident]
    R = np.zeros((n, V, 3), np.float64)
    for ch in range(3):  # the unscattered light apart, as acquired
        out = walk_beams(mesh, volume, ch, entry, normal, photons=photons, seed=seed + 7919 * ch, scene=scene)
        R[..., ch] = splat_barycentric(out.tri, out.bary, out.beam, n, V) / (photons * area)
    return R
