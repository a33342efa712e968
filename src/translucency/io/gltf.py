r"""A per-vertex object as glTF 2.0 binary (``.glb``): the mesh, a baked colour and per-vertex attributes
a renderer can read — written and read by trimesh.

glTF's unit is the metre and its up axis +Y: positions are written in metres (our millimetres × 10⁻³),
our +z turned to glTF's +Y, :math:`(x, y, z) \mapsto (x, z, -y)` (Blender's and three.js's importers turn
it back up), and every length of an attribute says its unit in its name (``_MFP_MM``).  The colour is
linear RGB (glTF's ``COLOR_0``) scaled into [0, 1]; the scale back to radiance is in the file's
``extras`` (``translucency.colour_scale``).  Custom attributes start with an underscore, as glTF
requires (``_ALBEDO``, ``_MFP_MM``, ...).
"""

from __future__ import annotations

import json

import numpy as np

from .._validate import TranslucencyError
from .atomic import atomic_path

#: glTF's unit (the metre) in our millimetres
MM_PER_GLTF_UNIT = 1000.0
#: our frame (+z up) to glTF's (+Y up): a rotation about x by −90°, (x, y, z) → (x, z, −y)
Z_UP_TO_Y_UP = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])


def write_glb(path, vertices_mm, faces, colour, attributes: dict, extras: dict) -> None:
    """Write ``path`` (.glb): the mesh (mm, written in metres), ``colour`` (V, 3) linear RGB in [0, 1] as
    ``COLOR_0``, ``attributes`` {name: (V,) or (V, k) floats} as custom vertex attributes (names must
    start with ``_``) and ``extras`` (JSON) under the scene's ``extras["translucency"]``; atomically."""
    import trimesh  # trimesh loads only to write or read meshes

    for name in attributes:
        if not name.startswith("_"):
            raise TranslucencyError(f"glTF attribute {name!r}: custom attributes start with '_'")
    colour = np.clip(np.asarray(colour, dtype=np.float64), 0.0, 1.0)
    rgba = np.concatenate([colour, np.ones((len(colour), 1))], axis=1)
    mesh = trimesh.Trimesh(
        np.asarray(vertices_mm, dtype=np.float64) @ Z_UP_TO_Y_UP.T / MM_PER_GLTF_UNIT,
        np.asarray(faces),
        vertex_colors=np.round(rgba * 255).astype(np.uint8),
        process=False,
    )
    for name, value in attributes.items():
        mesh.vertex_attributes[name] = np.asarray(value, dtype=np.float32)
    scene = trimesh.Scene(mesh)
    scene.metadata["translucency"] = json.loads(json.dumps(extras))
    with atomic_path(path) as tmp:
        data = trimesh.exchange.gltf.export_glb(scene, include_normals=True)
        tmp.write_bytes(data)


def read_glb(path):
    """(mesh in mm, +z up, extras) of a .glb written by :func:`write_glb` (its attributes in
    ``mesh.vertex_attributes``, its colour in ``mesh.visual.vertex_colors``)."""
    import trimesh  # trimesh loads only to write or read meshes

    scene = trimesh.load(path, force="scene", process=False)
    mesh = next(iter(scene.geometry.values()))
    mesh.vertices = np.asarray(mesh.vertices) @ Z_UP_TO_Y_UP * MM_PER_GLTF_UNIT  # back to +z up, mm
    return mesh, scene.metadata.get("translucency", {})
