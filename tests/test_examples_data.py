"""The example files the documentation's commands use (``translucency examples``, translucency/data/examples):
each loads as the commands read it, the generated ones are what their script makes, the scene parses with its
``object`` shape, the filling covers the meshes, and the command copies them without replacing a user's file.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
import trimesh
from typer.testing import CliRunner

import translucency as tl
from translucency.acquire import load_volume
from translucency.acquire.mesh import check_filling
from translucency.cli.app import app
from translucency.data import EXAMPLES, example_path
from translucency.data.make_examples import (
    SUN_AZIMUTH_DEG,
    SUN_ELEVATION_DEG,
    filling,
    sky,
)
from translucency.io.mesh import load_mesh
from translucency.io.mesh_dataset import open_mesh_dataset
from translucency.mitsuba.user_scenes import load_user_scene, shapes_by_id
from translucency.render.lights.environment import EnvironmentLight
from translucency.rig.shared.hdr import read_hdr

runner = CliRunner()

#: how the documentation reads each mesh: (scale_mm, up) and about how large that makes it (mm)
MESHES = {"spot.obj": (1.0, "z", 103.1), "cow.obj": (1.0, "z", 104.4)}


def test_the_package_holds_every_example_and_nothing_else():
    folder = example_path("spot.obj").parent
    assert sorted(p.name for p in folder.iterdir()) == sorted(EXAMPLES)
    generated = sum(example_path(n).stat().st_size for n in EXAMPLES if not n.endswith(".obj"))
    assert generated < 1_000_000  # the sky, the filling, the scene and the licences stay small
    licences = example_path("LICENSES.md").read_text()
    assert all(f"`{name}`" in licences for name in EXAMPLES) and "CC0" in licences


@pytest.mark.parametrize("name", sorted(MESHES))
def test_the_meshes_are_closed_as_the_commands_read_them(name):
    scale, up, size = MESHES[name]
    mesh = load_mesh(example_path(name), scale_mm=scale, up=up)  # seams merged, as acquire mesh does
    assert mesh.is_watertight and mesh.is_winding_consistent and mesh.volume > 0
    assert abs(float(np.max(mesh.extents)) - size) < 0.1
    assert check_filling(mesh, load_volume(example_path("filling.npz"))) is None  # the filling covers it


def test_the_sky_is_finite_linear_rgb_with_its_sun_up():
    image = read_hdr(example_path("sky.exr"))
    assert image.shape == (32, 64, 3) and np.isfinite(image).all() and image.min() >= 0
    assert np.allclose(image, sky(), rtol=1e-3, atol=1e-6)  # what make_examples writes
    # read as the env: light reads it, the sun is where make_examples put it and the zenith is blue
    env = EnvironmentLight(1.0, filename=str(example_path("sky.exr")))
    e, a = np.radians(SUN_ELEVATION_DEG), np.radians(SUN_AZIMUTH_DEG)
    sun = [np.sin(a) * np.cos(e), np.cos(a) * np.cos(e), np.sin(e)]
    L = env.radiance_at(np.array([sun, [0.0, 0.0, 1.0], [0.0, 0.0, -1.0]]))
    assert L[0].sum() > 0.9 * image.sum(axis=-1).max()
    assert L[1, 2] > 2 * L[1, 0] and L[2].sum() < L[1].sum()  # blue above, a dim ground below


def test_the_filling_is_a_valid_volume_as_its_script_makes_it():
    volume = load_volume(example_path("filling.npz"))
    made = filling()
    assert np.array_equal(volume.sigma_s, made["sigma_s"]) and np.array_equal(volume.sigma_a, made["sigma_a"])
    assert volume.voxel_mm == 4.0 and volume.size_mm == (108.0, 108.0, 108.0)
    assert (volume.sigma_s > 1.0).all() and (volume.sigma_a > 0).all()  # scattering, absorbing everywhere
    assert volume.sigma_a[..., 0].max() > 10 * volume.sigma_a[..., 0].min()  # veins: heterogeneous


@pytest.fixture(scope="module")
def examples_folder(tmp_path_factory):
    folder = tmp_path_factory.mktemp("examples") / "ex"
    res = runner.invoke(app, ["examples", str(folder)])
    assert res.exit_code == 0, res.output
    return folder


def test_the_scene_parses_with_its_object_on_the_floor(examples_folder):
    """scene.xml in millimetres around object.ply (here spot.obj as the tutorial's model would export it)."""
    spot = load_mesh(examples_folder / "spot.obj")
    spot.export(examples_folder / "object.ply")
    scene = load_user_scene(examples_folder / "scene.xml")
    shapes = shapes_by_id(scene)
    assert {"object", "floor", "lamp"} <= set(shapes)
    assert len(scene.emitters()) == 2  # the sky and the lamp
    film = scene.sensors()[0].film()
    assert [int(v) for v in film.crop_size()] == [320, 240]
    floor = np.asarray(shapes["floor"].bbox().min)[2]
    assert 0 < spot.bounds[0, 2] - floor < 0.1  # the feet just above the floor
    assert np.allclose(np.asarray(shapes["object"].bbox().min), spot.bounds[0], atol=1e-3)


def test_the_command_copies_and_never_replaces_a_users_file(examples_folder):
    for name in EXAMPLES:
        assert (examples_folder / name).read_bytes() == example_path(name).read_bytes()
    again = runner.invoke(app, ["examples", str(examples_folder), "--json"])
    assert again.exit_code == 0 and json.loads(again.stdout)["written"] == []  # the same files: kept
    mine = examples_folder / "scene.xml"
    mine.write_text("<scene version='3.0.0'/>")
    res = runner.invoke(app, ["examples", str(examples_folder)], env={"COLUMNS": "400"})
    errors = [ln for ln in res.output.splitlines() if ln.startswith("error:")]
    assert res.exit_code == 2 and len(errors) == 1, res.output
    assert str(mine) in errors[0] and "--overwrite" in errors[0]
    assert mine.read_text() == "<scene version='3.0.0'/>"  # untouched
    res = runner.invoke(app, ["examples", str(examples_folder), "--overwrite", "--json"])
    assert res.exit_code == 0 and json.loads(res.stdout)["written"] == ["scene.xml"]
    assert mine.read_bytes() == example_path("scene.xml").read_bytes()
    assert not [p for p in examples_folder.iterdir() if p.name.startswith(".")]  # no temporary left


def test_acquire_planar_reads_the_filling(examples_folder, tmp_path):
    out = tmp_path / "filling.zarr"
    args = ["acquire", "planar", "--volume", str(examples_folder / "filling.npz"), "--grid", "2"]
    args += ["--span", "4", "--photons", "300", "--window", "2", "--pitch", "0.5", "--out", str(out), "-q"]
    res = runner.invoke(app, args)
    assert res.exit_code == 0, res.output
    data = tl.open_dataset(out)
    assert data.n_points == 4 and data.complete()
    assert data.header["sample"]["description"]["generator"] == "file"
    assert data.header["sample"]["size_mm"] == [108.0, 108.0, 108.0]
    R = np.asarray(data.read("R_d"), dtype=np.float64)
    assert np.isfinite(R).all() and R.sum() > 0


def test_acquire_mesh_reads_spot_with_the_filling(examples_folder, tmp_path):
    out = tmp_path / "spot.zarr"
    args = ["acquire", "mesh", "--mesh", str(examples_folder / "spot.obj")]
    args += ["--volume", str(examples_folder / "filling.npz"), "--points", "2", "--photons", "200"]
    args += ["--chunk", "2", "--out", str(out), "-q"]
    res = runner.invoke(app, args)
    assert res.exit_code == 0, res.output
    data = open_mesh_dataset(out)
    assert data.n_points == 2 and data.complete()
    assert data.header["filling"]["path"] == str((examples_folder / "filling.npz").resolve())
    assert np.isfinite(np.asarray(data.read("R_d"), dtype=np.float64)).all()


def test_example_path_refuses_an_unknown_name():
    with pytest.raises(tl.TranslucencyError, match="no example 'teapot.obj'"):
        example_path("teapot.obj")
    assert isinstance(trimesh.load(example_path("cow.obj"), force="mesh"), trimesh.Trimesh)
