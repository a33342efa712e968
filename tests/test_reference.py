"""The converged reference of Figure 2: shipped, found by its key, and consistent with a fresh render."""

import json

import numpy as np
import pytest

from translucency.pipeline import FIGURE2_REFERENCE_SPP, figure2_scene
from translucency.render.compare import rel_rmse
from translucency.render.picture import coverage
from translucency.render.reference import SHIPPED, converged_reference, reference_key, render_reference


def test_the_main_jobs_reference_is_shipped_under_its_key():
    pig, volume, light, camera = figure2_scene()
    key = reference_key(pig, volume, light, camera, FIGURE2_REFERENCE_SPP, 1.0)
    info = json.loads((SHIPPED / f"{key}.json").read_text())
    assert info["spp"] == FIGURE2_REFERENCE_SPP and info["renders"] == 2 and info["noise"] < 0.05
    image, found = converged_reference(
        pig, volume, light, camera, coverage(pig, camera), spp=FIGURE2_REFERENCE_SPP
    )
    assert found["cached"] == str(SHIPPED) and image.shape == (120, 160, 3)


def test_noise_is_measured_from_two_independent_renders(tmp_path):
    """The cached entry is reused; its noise is the disagreement of two seeds, (A − B)/2 relative."""
    import trimesh

    from translucency.acquire.mesh import object_volume
    from translucency.render.camera import Camera
    from translucency.render.lights import PointLight

    ball = trimesh.creation.icosphere(2, radius=4.0)
    vol = object_volume("homogeneous:marble", ball, 1.0)
    cam = Camera.looking_at(ball, width=24, height=18)
    mask = coverage(ball, cam)
    light = PointLight((20.0, -20.0, 30.0), 1e3)
    mean, info = converged_reference(ball, vol, light, cam, mask, spp=8, cache=tmp_path)
    a, _ = render_reference(ball, vol, light, cam, spp=8, seed=0)
    b, _ = render_reference(ball, vol, light, cam, spp=8, seed=1)
    np.testing.assert_allclose(mean, 0.5 * (a + b), rtol=1e-6, atol=1e-9)
    expected = np.sqrt(np.mean((a - b)[mask] ** 2)) / (2 * np.sqrt(np.mean(mean[mask] ** 2)))
    assert info["noise"] == pytest.approx(expected, rel=1e-6) and info["cached"] is None
    again, info2 = converged_reference(ball, vol, light, cam, mask, spp=8, cache=tmp_path)
    assert info2["cached"] == str(tmp_path) and np.allclose(again, mean, rtol=1e-6)


@pytest.mark.slow
def test_the_shipped_reference_agrees_with_a_fresh_render():
    """2 x 16 spp now against the shipped 2 x 256 spp: their difference is the fresh render's noise."""
    pig, volume, light, camera = figure2_scene()
    mask = coverage(pig, camera)
    shipped, info = converged_reference(pig, volume, light, camera, mask, spp=FIGURE2_REFERENCE_SPP)
    fresh, fresh_info = converged_reference(pig, volume, light, camera, mask, spp=16, cache=False)
    expected = np.hypot(fresh_info["noise"], info["noise"])
    assert rel_rmse(fresh, shipped, mask) < 1.5 * expected
    assert fresh[mask].mean() == pytest.approx(shipped[mask].mean(), rel=0.02)
