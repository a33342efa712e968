"""``translucency export MODEL --mitsuba DIR`` (render/medium_scene.py): the scene Mitsuba loads holds the
estimated medium's voxels where the Volume has them (the z flip included), a fitted ball's scene renders, the
folder is refused without --overwrite and a model without a medium in one line, and (slow) the exported scene
renders as the project's own volpath reference of the same Volume in the same mesh."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest
import trimesh
from json_schemas import SCHEMAS, check
from typer.testing import CliRunner

from helpers import error_line, random_exponential_model
from translucency import load_model, save_model
from translucency.acquire.mesh import acquire_mesh, object_volume
from translucency.cli.app import app
from translucency.fit.mesh import fit_mesh
from translucency.mitsuba import mitsuba
from translucency.render import Camera, coverage, object_of_model, parse_light, rel_rmse, render_reference
from translucency.render.lights import DEFAULT_LIGHT, Placement, place_light
from translucency.render.medium_scene import FILES, scene_volume, write_mitsuba_scene

runner = CliRunner()


def _shape(scene, name="object"):
    return next(s for s in scene.shapes() if s.id() == name)


def _render(scene_xml, *, spp: int, width: int, height: int, seed: int = 0) -> np.ndarray:
    mi = mitsuba()
    scene = mi.load_file(str(scene_xml), spp=spp, resx=width, resy=height)
    return np.asarray(mi.render(scene, seed=seed), dtype=np.float64)


@pytest.fixture
def box_model():
    """A random per-vertex model on a box (10 × 6 × 4 mm, off the origin) carrying a medium that differs
    from point to point: every axis of the grid has its own length and the coefficients vary along each."""
    rng = np.random.default_rng(7)
    box = trimesh.creation.box(extents=(10.0, 6.0, 4.0)).subdivide().subdivide()
    box.apply_translation((3.0, -2.0, 7.0))
    points = rng.choice(len(box.vertices), 12, replace=False)
    model = random_exponential_model(rng, geometry="mesh", mesh=box, points=points)
    model.faces = np.asarray(box.faces)
    sigma_s = rng.uniform(0.5, 5.0, (len(points), 3))
    sigma_a = rng.uniform(0.001, 0.2, (len(points), 3))
    model.measured = {"medium": np.stack([sigma_s, sigma_a], axis=1)}
    return model, box


def test_the_scene_holds_the_volumes_voxels_where_the_volume_has_them(box_model, tmp_path):
    """σ_t and σ_s of the loaded scene's medium at voxel centres (top and bottom layers, corners and
    inside) are the Volume's [iz, iy, ix] there, z index 0 at the top."""
    import drjit as dr

    model, box = box_model
    mi = mitsuba()
    xml = write_mitsuba_scene(model, box, tmp_path / "scene", voxels=10)
    assert sorted(p.name for p in xml.parent.iterdir() if not p.name.startswith(".")) == sorted(
        FILES.values()
    )
    volume = scene_volume(model, box, voxels=10)
    Z, Y, X = volume.shape
    assert (X, Y, Z) == (10, 6, 4)  # 1 mm voxels over the 10 × 6 × 4 mm box
    assert np.ptp(volume.sigma_t[:, 0, 0, 0]) > 0.05  # the medium changes along z: a flip would show
    lo, hi = box.bounds
    vox = volume.voxel_mm
    idx = np.array([(0, 0, 0), (Z - 1, 0, 0), (0, Y - 1, X - 1), (Z - 1, Y - 1, X - 1), (1, 2, 3), (2, 4, 7)])
    iz, iy, ix = idx.T
    p = np.stack([lo[0] + (ix + 0.5) * vox, lo[1] + (iy + 0.5) * vox, hi[2] - (iz + 0.5) * vox], axis=1)
    # the how-to's recipe to move the object: the same operations on the shape and after the grids' matrix
    text = xml.read_text()
    moved = xml.with_name("moved.xml")
    moved.write_text(
        re.sub(r"(<matrix [^>]*/>)", r'\1<translate x="100" />', text).replace(
            '<string name="filename" value="object.ply" />',
            '<string name="filename" value="object.ply" /><transform name="to_world"><translate x="100" />'
            "</transform>",
        )
    )
    for path, shift in ((xml, 0.0), (moved, 100.0)):
        scene = mi.load_file(str(path))
        assert scene.bbox().min.x == pytest.approx(lo[0] + shift, abs=1e-4)
        medium = _shape(scene).interior_medium()
        mei = dr.zeros(mi.MediumInteraction3f, len(p))
        q = p + [shift, 0.0, 0.0]
        mei.p = mi.Point3f(*(np.ascontiguousarray(q[:, j], dtype=np.float32) for j in range(3)))
        sigma_s, _, sigma_t = medium.get_scattering_coefficients(mei)
        for c in range(3):
            np.testing.assert_allclose(np.asarray(sigma_t[c]), volume.sigma_t[iz, iy, ix, c], rtol=1e-5)
            np.testing.assert_allclose(np.asarray(sigma_s[c]), volume.sigma_s[iz, iy, ix, c], rtol=1e-5)
    # the boundary: index-matched by default, a smooth dielectric of int_ior η on request
    assert str(_shape(scene).bsdf()).startswith("Null")
    glass = write_mitsuba_scene(
        model, box, tmp_path / "glass", voxels=10, eta=1.4, light=parse_light("env:0.5")
    )
    assert str(_shape(mi.load_file(str(glass))).bsdf()).startswith("SmoothDielectric")


def test_a_failed_write_leaves_no_folder_behind(box_model, tmp_path, monkeypatch):
    import translucency.mitsuba

    def broken(*args, **kwargs):
        raise OSError("disk full")

    monkeypatch.setattr(translucency.mitsuba, "write_ply", broken)
    with pytest.raises(OSError):
        write_mitsuba_scene(*box_model, tmp_path / "scene", voxels=10)
    assert not (tmp_path / "scene").exists()


@pytest.fixture(scope="module")
def fitted_ball(tmp_path_factory):
    """A marble ball (icosphere of 5 mm, 162 vertices), 4 incident points of 1000 photons index-matched,
    fitted (the fit stores the estimated medium) and saved."""
    folder = tmp_path_factory.mktemp("export_mitsuba")
    ball = trimesh.creation.icosphere(2, radius=5.0)
    marble = object_volume("homogeneous:marble", ball, 1.0)
    data = acquire_mesh(
        ball, marble, folder / "ball.zarr", n_points=4, photons=1000, chunk_points=4, index_matched=True
    )
    fit = fit_mesh(data, "iso", n_terms=1, colour="shared", max_rounds=1)
    assert fit.model.measured["medium"].shape == (4, 2, 3)
    return save_model(fit.model, folder / "ball.model.zip")


def test_a_fitted_balls_scene_from_the_command_line_renders_it(fitted_ball, tmp_path):
    out = tmp_path / "ball-mitsuba"
    res = runner.invoke(app, ["export", str(fitted_ball), "--mitsuba", str(out)])
    assert res.exit_code == 0, res.output
    assert "Mitsuba scene" in res.output
    image = _render(out / "scene.xml", spp=16, width=48, height=36)
    assert image.shape == (36, 48, 3) and np.isfinite(image).all() and (image >= 0).all()
    mesh, _ = object_of_model(load_model(fitted_ball), {})
    mask = coverage(mesh, Camera.looking_at(mesh, width=48, height=36))  # the scene's default camera
    assert mask.sum() > 50
    lit = image[mask].mean(axis=0)
    assert (lit > 0).all() and lit.mean() > 10 * image[~mask].mean()  # the object glows, the void is dark


def test_the_folder_is_refused_without_overwrite_and_a_model_without_a_medium_in_one_line(
    box_model, tmp_path
):
    model, box = box_model
    path = save_model(model, tmp_path / "box.model.zip")
    out = tmp_path / "box-mitsuba"
    res = runner.invoke(app, ["export", str(path), "--mitsuba", str(out), "--json"])
    assert res.exit_code == 0, res.output
    summary = json.loads(res.stdout)
    assert check(summary, SCHEMAS["export"]) == []  # docs/json.md's schema
    assert summary["mitsuba"] == str(out / "scene.xml") and summary["voxels"] == [48, 29, 20]
    first = (out / "scene.xml").read_bytes()
    line = error_line(["export", path, "--mitsuba", out])
    assert f"--mitsuba {out}" in line and "--overwrite" in line
    assert (
        runner.invoke(app, ["export", str(path), "--mitsuba", str(out), "--overwrite", "-q"]).exit_code == 0
    )
    assert (out / "scene.xml").read_bytes() == first
    # a folder translucency did not write: refused whatever the flags, its file kept
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "notes.txt").write_text("my notes")
    assert "not a translucency output folder" in error_line(
        ["export", path, "--mitsuba", mine, "--overwrite"]
    )
    assert [p.name for p in mine.iterdir()] == ["notes.txt"]
    # a model fitted before the estimate: one line, nothing written
    del model.measured["medium"]
    old = save_model(model, tmp_path / "old.model.zip")
    line = error_line(["export", old, "--mitsuba", tmp_path / "old-mitsuba", "--ply", tmp_path / "old.ply"])
    assert line == f"error: {old}: holds no estimated medium; fit it again with this version"
    assert not (tmp_path / "old-mitsuba").exists() and not (tmp_path / "old.ply").exists()


@pytest.mark.slow
def test_the_exported_scene_renders_as_the_volpath_reference_of_the_same_volume(fitted_ball, tmp_path):
    """The scene file (its grids read back from the .vol files, their placement, mm, the camera, the light,
    the boundary, the integrator) path-traced against the reference's own scene of the same Volume in the
    same mesh: within 5 % relative RMSE over the object.

    Both one channel at a time: the loaded scene's two grids made grey in memory (channel c copied into all
    three), as the reference renders; an RGB medium under volpath's spectral MIS would carry several times
    the noise at the same samples, and the comparison is of the files, not of Mitsuba's chromatic
    sampling."""
    out = tmp_path / "ball-mitsuba"
    assert runner.invoke(app, ["export", str(fitted_ball), "--mitsuba", str(out), "-q"]).exit_code == 0
    model = load_model(fitted_ball)
    mesh, _ = object_of_model(model, {})
    width, height, spp = 32, 24, 2048
    camera = Camera.looking_at(mesh, width=width, height=height)  # the scene's default camera
    mask = coverage(mesh, camera)
    mi = mitsuba()
    scene = mi.load_file(str(out / "scene.xml"), spp=spp, resx=width, resy=height)
    params = mi.traverse(scene)
    grids = {k: np.array(params[k]) for k in params.keys() if k.endswith(("sigma_t.data", "albedo.data"))}
    assert len(grids) == 2
    channels = []
    for c in range(3):
        for key, grid in grids.items():
            params[key] = mi.TensorXf(np.ascontiguousarray(np.repeat(grid[..., c : c + 1], 3, axis=-1)))
        params.update()
        channels.append(np.asarray(mi.render(scene, seed=c), dtype=np.float64)[..., c])
    ours = np.stack(channels, axis=2)
    view = np.subtract(camera.origin, camera.target)  # the scene's default light, placed for its camera
    light = place_light(parse_light(DEFAULT_LIGHT), Placement.of(mesh, view))
    reference, _ = render_reference(mesh, scene_volume(model, mesh), light, camera, spp=spp, seed=1)
    error = rel_rmse(ours, reference, mask)
    print(f"exported scene against the reference: relative RMSE {error:.4f} over {mask.sum()} pixels")
    assert error < 0.05
