"""Meshes as users have them: UV seams, holes, y-up files, their own filling (issue 12, item 8)."""

import numpy as np
import pytest
import trimesh
from typer.testing import CliRunner

from translucency import TranslucencyError
from translucency.cli.app import app
from translucency.io.mesh import close_holes, load_mesh

runner = CliRunner()


def _write_obj(path, vertices, faces):
    lines = [f"v {x} {y} {z}" for x, y, z in vertices] + [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in faces]
    path.write_text("\n".join(lines) + "\n")
    return path


def test_a_uv_seam_is_one_surface(tmp_path):
    """A closed ball whose vertices along a seam are written twice (as texture seams are) loads closed."""
    ball = trimesh.creation.icosphere(2, radius=1.0)
    v, f = np.asarray(ball.vertices), np.asarray(ball.faces).copy()
    seam = np.flatnonzero(v[:, 0] > 0.5)  # duplicate these vertices and use the copies in half the faces
    copy = {int(k): len(v) + n for n, k in enumerate(seam)}
    v2 = np.concatenate([v, v[seam]])
    for row in f[: len(f) // 2]:
        row[:] = [copy.get(int(k), int(k)) for k in row]
    raw = trimesh.Trimesh(v2, f, process=False)
    assert not raw.is_watertight
    mesh = load_mesh(_write_obj(tmp_path / "seam.obj", v2, f), scale_mm=10)
    assert mesh.is_watertight and len(mesh.vertices) == len(v)
    assert mesh.volume == pytest.approx(ball.volume * 1000, rel=1e-6)


def test_small_holes_are_closed_with_a_warning_and_large_ones_refused(tmp_path):
    ball = trimesh.creation.icosphere(3, radius=10.0)
    around = np.flatnonzero((ball.faces == 0).any(axis=1))  # the faces around vertex 0: one hole
    keep = np.setdiff1d(np.arange(len(ball.faces)), around)
    holed = trimesh.Trimesh(ball.vertices, ball.faces[keep], process=False)
    assert not holed.is_watertight
    path = _write_obj(tmp_path / "holed.obj", holed.vertices, holed.faces)
    with pytest.warns(UserWarning, match="1 holes were filled"):
        mesh = load_mesh(path)
    assert mesh.is_watertight and mesh.is_winding_consistent
    assert mesh.volume == pytest.approx(ball.volume, rel=1e-3)  # the patch lies where the cap was
    half = trimesh.Trimesh(ball.vertices, ball.faces[ball.triangles_center[:, 2] > 0], process=False)
    with pytest.raises(TranslucencyError, match="not closed"):
        load_mesh(_write_obj(tmp_path / "half.obj", half.vertices, half.faces))


def test_close_holes_orients_the_patch_like_the_surface():
    box = trimesh.creation.box((2, 3, 4))
    top = box.triangles_center[:, 2] > 1.9
    opened = trimesh.Trimesh(box.vertices, box.faces[~top], process=False)
    perimeters = close_holes(opened)
    assert perimeters == [pytest.approx(10.0)]  # 2 (2 + 3)
    assert opened.is_watertight and opened.is_winding_consistent
    assert opened.volume == pytest.approx(24.0)


def test_y_up_files_are_turned_to_z_up(tmp_path):
    tall = trimesh.creation.box((1.0, 5.0, 2.0))
    path = tmp_path / "tall.ply"
    tall.export(path)
    np.testing.assert_allclose(load_mesh(path, up="y").extents, [1.0, 2.0, 5.0], atol=1e-9)
    with pytest.raises(TranslucencyError, match="up: expected one of"):
        load_mesh(path, up="w")


def test_acquire_mesh_with_a_users_volume(tmp_path):
    ball = tmp_path / "ball.ply"
    trimesh.creation.icosphere(2, radius=3.0).export(ball)
    shape = (7, 7, 7, 3)  # 1 mm voxels over the 6 mm box (and a little more)
    np.savez(tmp_path / "vol.npz", sigma_s=np.full(shape, 2.0), sigma_a=np.full(shape, 0.01), voxel_mm=1.0)
    args = [
        "acquire",
        "mesh",
        "--mesh",
        str(ball),
        "--volume",
        str(tmp_path / "vol.npz"),
        "--points",
        "2",
        "--photons",
        "300",
        "--index-matched",
        "--out",
        str(tmp_path / "d.zarr"),
    ]
    res = runner.invoke(app, args)
    assert res.exit_code == 0, res.output
    both = runner.invoke(app, [*args[:-2], "--material", "skin", "--out", str(tmp_path / "e.zarr")])
    assert both.exit_code == 2 and "not both" in both.output


def test_a_mesh_in_metres_is_warned_about(tmp_path):
    path = tmp_path / "small.ply"
    trimesh.creation.icosphere(2, radius=0.04).export(path)  # an 8 cm ball written in metres
    with pytest.warns(UserWarning, match="scale_mm=1000 if it is in metres"):
        load_mesh(path)
