"""A transport added by a plug-in: one class registered in this module, drawn by every renderer through the
prepared object (translucency.transport) — no renderer changed.

The plug-in ``dimmed`` is the default transport at half its strength.  The light transport is linear,
L = T E, so every renderer's output under it is exactly half the default's (a factor of 2 is exact in
binary floating point): ``render``'s linear picture, the scene's glow, the glTF bake's colour scale
(normalised colours, so its scale doubles) and the viewer's exposure (set from the brightest vertices).
"""

from __future__ import annotations

import base64
import dataclasses
import json
from dataclasses import dataclass

import numpy as np
import pytest

from translucency import TranslucencyError
from translucency.transport import TRANSPORTS, PreparedObject, TransportOptions, register_transport
from translucency.transport.kinds import MeasuredTransport


@dataclass(frozen=True)
class Dimmed:
    """The default transport at half its strength: the near matrices, the own area and the far field."""

    name: str = "dimmed"
    summary: str = "the default, halved"
    incidence: str = "half-space"

    def build(self, model, mesh, **near):
        T = MeasuredTransport().build(model, mesh, **near)
        far = None if T.far is None else dataclasses.replace(T.far, alpha=0.5 * T.far.alpha)
        own = None if T.own is None else 0.5 * T.own
        return dataclasses.replace(T, matrices=[0.5 * M for M in T.matrices], own=own, far=far)


@pytest.fixture
def dimmed():
    register_transport(Dimmed())
    yield TransportOptions(kind="dimmed")
    del TRANSPORTS["dimmed"]


@pytest.fixture(scope="module")
def ball_model(tmp_path_factory):
    """A per-vertex model on a 162-vertex ball that carries its mesh."""
    import trimesh

    from helpers import random_exponential_model
    from translucency import save_model

    ball = trimesh.creation.icosphere(2, radius=5.0)
    model = random_exponential_model(
        np.random.default_rng(3), geometry="mesh", mesh=ball, points=np.arange(0, 162, 11)
    )
    model.faces = np.asarray(ball.faces)
    path = tmp_path_factory.mktemp("plugin") / "ball.model.zip"
    save_model(model, path)
    return model, ball, path


def test_an_unregistered_transport_is_one_line():
    with pytest.raises(TranslucencyError, match="transport: 'dimmed' is not one of default, paper"):
        TransportOptions(kind="dimmed")


def test_the_plugin_halves_the_transport_itself(ball_model, dimmed):
    model, ball, _ = ball_model
    E = np.linspace(0.5, 1.5, len(ball.vertices))  # W/mm²
    default = PreparedObject(model, ball).through(E)
    half = PreparedObject(model, ball, options=dimmed).through(E)
    np.testing.assert_array_equal(half, 0.5 * default)
    assert np.all(default > 0)


def test_render_draws_the_plugin(ball_model, dimmed):
    import translucency as tl

    _, _, path = ball_model
    default = tl.render_model(path, resolution=(32, 24), light="point@camera")
    half = tl.render_model(path, resolution=(32, 24), light="point@camera", transport=dimmed)
    assert default.picture.max() > 0
    np.testing.assert_allclose(half.picture, 0.5 * default.picture, rtol=1e-6, atol=1e-12)


def test_the_bake_and_the_page_draw_the_plugin(ball_model, dimmed, tmp_path):
    import translucency as tl

    _, _, path = ball_model
    default = tl.export_model(path, gltf=tmp_path / "a.glb")
    half = tl.export_model(path, gltf=tmp_path / "b.glb", transport=dimmed)
    # the colours are the radiance over its 99th percentile: the same; the scale that undoes it, twice
    assert half["colour_scale"] == pytest.approx(2 * default["colour_scale"], rel=1e-6)

    def exposure(folder):
        text = (folder / "data.js").read_text()
        data = json.loads(text.removeprefix("window.TL_DATA = ").removesuffix(";\n"))
        assert data["arrays"]  # (the page holds its arrays)
        base64.b64decode(next(iter(data["arrays"].values()))["b64"])
        return data["meta"]["exposure"]

    tl.view_model(path, tmp_path / "p1", open_browser=False)
    tl.view_model(path, tmp_path / "p2", open_browser=False, transport=dimmed)
    assert exposure(tmp_path / "p2") == pytest.approx(2 * exposure(tmp_path / "p1"), rel=1e-3)


def test_a_scene_draws_the_plugin(ball_model, dimmed):
    """One pass (the glow does not light the object back): the objects' exitance is exactly halved."""
    from translucency.mitsuba import mitsuba
    from translucency.scene import FittedScene

    mi = mitsuba()
    model, ball, _ = ball_model
    shape = mi.Mesh("object", len(ball.vertices), len(ball.faces), has_vertex_normals=False)
    params = mi.traverse(shape)
    params["vertex_positions"] = mi.Float(np.asarray(ball.vertices, np.float32).ravel())
    params["faces"] = mi.UInt32(np.asarray(ball.faces, np.uint32).ravel())
    params.update()
    scene = {
        "type": "scene",
        "ball": shape,
        "sky": {"type": "constant", "radiance": 0.1},
        "camera": {
            "type": "perspective",
            "to_world": mi.ScalarTransform4f().look_at(origin=[0, -40, 10], target=[0, 0, 0], up=[0, 0, 1]),
            "film": {"type": "hdrfilm", "width": 16, "height": 12},
        },
    }
    glow = {}
    for name, options in (("default", None), ("dimmed", dimmed)):
        fs = FittedScene(mi.load_dict(scene), {"ball": model}, samples=8, passes=1, transport=options)
        fs.light()
        glow[name] = fs.objects[0].glowing.exitance
    assert glow["default"].min() > 0
    np.testing.assert_allclose(glow["dimmed"], 0.5 * glow["default"], rtol=1e-6)
