"""glTF in Blender: the exported file through Blender's own importer, rendered once by Cycles with its
subsurface scattering driven by the per-vertex Christensen–Burley attributes (slow; needs ``bpy`` from PyPI,
which pins one Python version: skipped elsewhere)."""

from __future__ import annotations

import numpy as np
import pytest

from test_view import runner, small_model  # noqa: F401 — the fixture: a ball and a thin ear
from translucency.cli.app import app
from translucency.io.gltf import read_glb


def _render(bpy, path, subsurface: float, back: bool = True) -> np.ndarray:
    """The imported object lit by a sun from behind (or from the camera's side), seen from −y, by Cycles
    (64 × 48, 16 samples); grey (H, W)."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.import_scene.gltf(filepath=str(path))
    obj = next(o for o in bpy.context.scene.objects if o.type == "MESH")
    mat = bpy.data.materials.new("burley")
    mat.use_nodes = True
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    bsdf = nodes["Principled BSDF"]
    albedo, mfp = nodes.new("ShaderNodeAttribute"), nodes.new("ShaderNodeAttribute")
    albedo.attribute_name, mfp.attribute_name = "_ALBEDO", "_MFP_MM"
    links.new(albedo.outputs["Vector"], bsdf.inputs["Base Color"])
    links.new(mfp.outputs["Vector"], bsdf.inputs["Subsurface Radius"])
    bsdf.inputs["Subsurface Weight"].default_value = subsurface
    bsdf.inputs["Subsurface Scale"].default_value = 0.001  # the radius in mm, the scene in metres
    bsdf.subsurface_method = "RANDOM_WALK"
    obj.data.materials.clear()
    obj.data.materials.append(mat)
    scene = bpy.context.scene
    cam = bpy.data.objects.new("cam", bpy.data.cameras.new("cam"))
    cam.data.clip_start = 1e-4  # the object is 6 cm away (the default clips at 10 cm)
    scene.collection.objects.link(cam)
    cam.location = (0.0045, -0.06, 0.0)
    cam.rotation_euler = (np.pi / 2, 0.0, 0.0)
    scene.camera = cam
    sun = bpy.data.objects.new("sun", bpy.data.lights.new("sun", "SUN"))
    sun.data.energy = 5.0
    scene.collection.objects.link(sun)
    sun.rotation_euler = (
        -np.pi / 2 if back else np.pi / 2,
        0.0,
        0.0,
    )  # shining towards −y (from behind) or +y
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = 16
    scene.render.resolution_x, scene.render.resolution_y = 64, 48
    scene.render.filepath = str(path.with_suffix(f".{subsurface:g}.{'back' if back else 'front'}.png"))
    bpy.ops.render.render(write_still=True)
    image = bpy.data.images.load(scene.render.filepath)
    px = np.asarray(image.pixels[:], dtype=np.float64).reshape(48, 64, 4)[::-1]
    return px[:, :, :3].mean(axis=2)


@pytest.mark.slow
def test_gltf_renders_in_blender_with_cycles_subsurface(small_model, tmp_path):  # noqa: F811
    bpy = pytest.importorskip("bpy")
    glb = tmp_path / "small.glb"
    assert runner.invoke(app, ["export", str(small_model), "--gltf", str(glb), "-q"]).exit_code == 0
    _, extras = read_glb(glb)
    assert extras["written_by"] == "translucency"
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.import_scene.gltf(filepath=str(glb))
    mesh = next(o for o in bpy.context.scene.objects if o.type == "MESH").data
    assert {"_ALBEDO", "_MFP_MM", "_BURLEY_S", "_REDUCTION_ERROR"} <= {a.name for a in mesh.attributes}
    with_sss, without = _render(bpy, glb, 1.0), _render(bpy, glb, 0.0)
    assert np.isfinite(with_sss).all() and with_sss.max() > 0
    # back-lit: light crosses the thin ear (right half of the picture) only with subsurface scattering
    ear = slice(32, 64)
    assert with_sss[:, ear].sum() > 1.5 * without[:, ear].sum() + 1e-6
