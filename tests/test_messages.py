"""Messages that diagnose: each bad input a newcomer tries gets one line naming the real reason (exit
status 2, nothing written), and numbers in messages are printed plainly."""

import numpy as np
import pytest
import trimesh
from typer.testing import CliRunner

from helpers import error_line, flat, random_exponential_model
from translucency import save_model
from translucency._validate import TranslucencyError, plain
from translucency.acquire import GENERATORS
from translucency.cli.app import app
from translucency.io.mesh import load_mesh
from translucency.io.outputs import MARKER
from translucency.render.lights import DirectionalLight, parse_light

runner = CliRunner()


@pytest.fixture(scope="module")
def ball_dataset(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("ball")
    trimesh.creation.icosphere(1, radius=4.0).export(tmp / "ball.ply")
    args = ["acquire", "mesh", "--mesh", tmp / "ball.ply", "--material", "homogeneous:marble", "--voxel", "1"]
    res = runner.invoke(
        app, [*map(str, args), "--points", "2", "--photons", "200", "--out", str(tmp / "b.zarr")]
    )
    assert res.exit_code == 0, res.output
    return tmp / "b.zarr"


def test_aniso_on_a_mesh_data_set_names_the_reason(ball_dataset, tmp_path):
    """`fit bunny.zarr --model aniso` said `directions: ... needs m >= 2, got 1` (m never given)."""
    line = error_line(["fit", ball_dataset, "--model", "aniso", "-o", tmp_path / "m.model.zip"])
    assert "--model aniso" in line and "planar data sets" in line and "mesh data set" in line, line
    assert "m >= 2" not in line
    assert not (tmp_path / "m.model.zip").exists()


def test_a_mesh_folder_is_not_a_mesh_file(tmp_path):
    """`acquire mesh --mesh FOLDER` said `--out …: is, holds or lies inside the input`."""
    (tmp_path / "meshes").mkdir()
    for out in (tmp_path / "meshes" / "x.zarr", tmp_path / "x.zarr"):
        line = error_line(["acquire", "mesh", "--mesh", tmp_path / "meshes", "--out", out])
        assert line.startswith("error: --mesh ") and "is a folder, not a mesh file" in line, line
        assert not out.exists()


def test_a_single_triangle_is_counted_right(tmp_path):
    """A single-triangle OBJ said `the surface is not closed (0 open or non-manifold edges …)`."""
    (tmp_path / "tri.obj").write_text("v 0 0 0\nv 10 0 0\nv 0 10 0\nf 1 2 3\n")
    line = error_line(["acquire", "mesh", "--mesh", tmp_path / "tri.obj", "--out", tmp_path / "t.zarr"])
    assert "3 open edges" in line and "a single triangle has no volume" in line, line
    assert "0 open" not in line


def test_an_open_box_and_a_flat_surface(tmp_path):
    box = trimesh.creation.box((10, 10, 10))
    box.faces = box.faces[1:]  # one triangle missing: a hole too large to fill
    box.export(tmp_path / "open.obj")
    with pytest.raises(TranslucencyError, match=r"not closed \(3 open edges, 1 hole, up to"):
        load_mesh(tmp_path / "open.obj")
    (tmp_path / "flat.obj").write_text("v 0 0 0\nv 10 0 0\nv 0 10 0\nf 1 2 3\nf 1 3 2\n")  # two-sided
    with pytest.raises(TranslucencyError, match="closed but encloses no volume"):
        load_mesh(tmp_path / "flat.obj")


def test_an_unwritable_folder_is_not_a_lack_of_disk_space(tmp_path):
    """`--out /proc/x.zarr` said `only 0 KiB free`."""
    planar = ["acquire", "planar", "--material", "marble", "--grid", "2", "--photons", "10"]
    line = error_line([*planar, "--out", "/proc/x.zarr"])
    assert "/proc cannot be written" in line and "free" not in line, line
    (tmp_path / "notes.txt").write_text("mine")
    line = error_line([*planar, "--out", tmp_path / "notes.txt" / "x.zarr"])
    assert "is a file, not a folder" in line, line
    assert (tmp_path / "notes.txt").read_text() == "mine"


def test_numbers_in_messages_are_plain():
    """`(np.float64(-5.0), …)`, `DirectionalLight(direction=(np.float64(…`: numbers as people write them."""
    assert plain((np.float64(-5.0), np.float64(0.0), np.float64(120.0))) == "(-5, 0, 120)"
    light = parse_light("directional:1,2,-3")
    assert isinstance(light, DirectionalLight)
    assert plain(light) == "DirectionalLight(direction=(0.2673, 0.5345, -0.8018), irradiance=1)"
    assert "np." not in plain(light) and "array" not in plain(np.arange(3.0))
    assert "np." not in repr(light)  # render's summary and figure2.json show the light as its repr


@pytest.fixture(scope="module")
def ball_model(ball_dataset):
    model = ball_dataset.parent / "b.model.zip"
    res = runner.invoke(app, ["fit", str(ball_dataset), "-o", str(model), "--rounds", "1", "-q"])
    assert res.exit_code == 0, res.output
    return model


def test_point_light_inside_the_object_is_named_plainly(ball_model, tmp_path):
    model = ball_model
    line = error_line(["render", model, "--light", "point:-1,0,0.5,100", "--out", tmp_path / "img", "-q"])
    assert "the point light at (-1, 0, 0.5) mm is inside the object" in line, line
    assert not (tmp_path / "img" / "ours.png").exists()


def test_fit_help_names_mesh_data_sets():
    out = flat(runner.invoke(app, ["fit", "--help"], env={"COLUMNS": "240"}).output)
    assert "A planar or a mesh data set" in out and "planar data sets only" in out


def test_every_sample_in_help_and_in_the_error_is_one_list(tmp_path):
    """`acquire planar --help` listed 5 samples, the error 7: both come from GENERATORS."""
    for command in (["acquire", "planar"], ["acquire", "mesh"], ["acquire", "photographs"]):
        out = flat(runner.invoke(app, [*command, "--help"], env={"COLUMNS": "400"}).output)
        assert ", ".join(GENERATORS) in out, command
    line = error_line(["acquire", "planar", "--material", "wood", "--out", tmp_path / "w.zarr"])
    assert ", ".join(GENERATORS) in line


def test_light_syntax_error_lists_environment_maps():
    with pytest.raises(TranslucencyError, match=r"env:L, env:MAP.exr\[,scale\]"):
        parse_light("lamp:1,2,3")


def test_an_output_folder_with_its_article(tmp_path):
    """ "a output folder" → "an output folder"."""
    (tmp_path / "rep").mkdir()
    (tmp_path / "rep" / MARKER).write_text('{"written_by": "translucency"}')
    (tmp_path / "rep" / "index.html").write_text("<html></html>")
    res = runner.invoke(app, ["demo", "--out", str(tmp_path / "rep")])
    assert "an output folder written by translucency" in res.output and " a output" not in res.output


# -- a newcomer's wrong kinds: each named for what it is, with what to do instead ---------------------
@pytest.fixture
def kinds(tmp_path, rng, ball_dataset):
    """A model file, a mesh data set, a mesh file and a volume, by name."""
    model = save_model(random_exponential_model(rng, n_points=2), tmp_path / "m.model.zip")
    trimesh.creation.icosphere(1, radius=4.0).export(tmp_path / "ball.obj")
    np.savez(tmp_path / "vol.npz", sigma_s=np.ones((2, 2, 2, 3)), sigma_a=np.ones((2, 2, 2, 3)), voxel_mm=1.0)
    return {
        "model": model,
        "mesh data": ball_dataset,
        "mesh": tmp_path / "ball.obj",
        "volume": tmp_path / "vol.npz",
    }


@pytest.mark.parametrize(
    ("args", "expected"),
    [
        (
            ["fit", "{model}", "-o", "{tmp}/x.model.zip"],
            "m.model.zip: is a model file, not a data set; give a data",
        ),
        (
            ["fit", "{mesh}", "-o", "{tmp}/x.model.zip"],
            "is a mesh file, not a data set; make a data set of it with",
        ),
        (["fit", "{mesh data}", "-o", "{tmp}/x.zarr"], "--out {tmp}/x.zarr: names a data set (.zarr)"),
        (["acquire", "planar", "--material", "marble", "--out", "{tmp}/x.model.zip"], "names a model file"),
        (["demo", "--out", "{tmp}/x.zarr"], "--out {tmp}/x.zarr: names a data set (.zarr)"),
        (["info", "{mesh}"], "is a mesh file, not a model file or a data set"),
        (["info", "{tmp}"], "a folder, but not a translucency data set (it holds no zarr.json)"),
        (["evaluate", "{mesh data}", "{model}"], "swapped? evaluate takes MODEL DATA"),
        (["evaluate", "{model}", "{model}"], "is a model file, not a data set"),
        (["evaluate", "{model}", "{mesh data}", "--compare", "{mesh data}"], "--compare"),
        (["evaluate", "{model}", "{mesh data}", "--truth", "{model}"], "--truth"),
        (["render", "{mesh data}"], "is a mesh data set, not a model file; fit a model to it with"),
        (
            ["acquire", "planar", "--volume", "{mesh}", "--out", "{tmp}/v.zarr"],
            "a mesh is the object's surface",
        ),
        (
            ["acquire", "mesh", "--mesh", "{mesh data}", "--out", "{tmp}/v.zarr"],
            "is a mesh data set, not a mesh",
        ),
        (["acquire", "mesh", "--volume", "{model}", "--out", "{tmp}/v.zarr"], "--volume"),
    ],
)
def test_a_path_of_another_kind_is_named(kinds, tmp_path, args, expected):
    """Before: `not a readable Zarr data set (GroupNotFoundError)`, `not a zip archive` and the like."""
    fill = {**{k: str(v) for k, v in kinds.items()}, "tmp": str(tmp_path)}
    line = error_line([a.format(**fill) for a in args])
    assert expected.format(**fill) in line, line
    assert "GroupNotFoundError" not in line and "zip archive" not in line
    assert not (tmp_path / "v.zarr").exists() and not (tmp_path / "x.model.zip").exists()


@pytest.mark.parametrize(
    ("args", "start"),
    [
        (["fit", "{mesh data}", "-o", "{tmp}/x.model.zip", "--terms", "9"], "error: --terms: "),
        (["fit", "{mesh data}", "-o", "{tmp}/x.model.zip", "--colour", "rgb"], "error: --colour: "),
        (
            ["acquire", "planar", "--material", "homogeneous:wood", "--out", "{tmp}/v.zarr"],
            "error: --material: ",
        ),
        (["render", "{mesh model}", "--light", "point:1,2", "--out", "{tmp}/img"], "error: --light: "),
    ],
)
def test_library_messages_name_the_flag(kinds, ball_model, tmp_path, args, start):
    """`terms: n must be …`, `light: expected …`: the command line names its own flag."""
    fill = {**{k: str(v) for k, v in kinds.items()}, "mesh model": str(ball_model), "tmp": str(tmp_path)}
    assert error_line([a.format(**fill) for a in args]).startswith(start)
