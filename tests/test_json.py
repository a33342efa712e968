"""``--json`` that scripts can use: every command's output against its documented schema (docs/json.md),
numbers as numbers, nothing cut; ``evaluate --json`` a flag like the others, its old path form kept for
one release."""

import functools
import json
from pathlib import Path

import numpy as np
import pytest
import trimesh
from json_schemas import COMMAND, SCHEMAS, check, markdown, schema_of
from typer.testing import CliRunner

from translucency.cli.app import app
from translucency.workflow import demo as workflow_demo

runner = CliRunner()
DOCS = Path(__file__).resolve().parents[1] / "docs" / "json.md"

PLANAR = ["acquire", "planar", "--material", "marble", "--grid", "2", "--span", "2", "--photons", "300"]
PLANAR += ["--size", "6", "6", "3", "--voxel", "0.5", "--window", "2", "--pitch", "0.5"]


def _json(args) -> dict:
    res = runner.invoke(app, [*map(str, args), "--json"])
    assert res.exit_code in (0, 1), res.output  # info: 1 for a model that is not physical
    return json.loads(res.stdout, parse_constant=lambda c: pytest.fail(f"{c} in JSON"))


@pytest.fixture(scope="module")
def outputs(tmp_path_factory):
    """One output of every command that has --json (a tiny planar and a tiny mesh pipeline)."""
    tmp = tmp_path_factory.mktemp("json")
    trimesh.creation.icosphere(1, radius=4.0).export(tmp / "ball.ply")
    out = {}
    out["acquire planar"] = _json([*PLANAR, "--out", tmp / "a.zarr", "-q"])
    out["acquire mesh"] = _json(
        ["acquire", "mesh", "--mesh", tmp / "ball.ply", "--material", "homogeneous:marble", "--voxel", "1"]
        + ["--points", "2", "--photons", "500", "--chunk", "2", "--out", tmp / "b.zarr", "-q"]
    )
    out["fit"] = _json(["fit", tmp / "a.zarr", "-o", tmp / "a.model.zip", "--rounds", "1", "-q"])
    out["fit (mesh)"] = _json(["fit", tmp / "b.zarr", "-o", tmp / "b.model.zip", "--rounds", "1", "-q"])
    out["evaluate"] = _json(["evaluate", tmp / "a.model.zip", tmp / "a.zarr", "--report", tmp / "rep", "-q"])
    out["evaluate (mesh)"] = _json(
        ["evaluate", tmp / "b.model.zip", tmp / "b.zarr", "--report", tmp / "mrep", "-q"]
    )
    out["render"] = _json(
        ["render", tmp / "b.model.zip", "--out", tmp / "img", "--resolution", "24", "16", "-q"]
    )
    out["export"] = _json(
        ["export", tmp / "b.model.zip", "--ply", tmp / "object.ply", "--gltf", tmp / "object.glb", "-q"]
    )
    (tmp / "scene.xml").write_text(SCENE)
    out["render (scene)"] = _json(
        [
            "render",
            "scene",
            tmp / "scene.xml",
            "--object",
            f"ball={tmp / 'b.model.zip'}",
            "--out",
            tmp / "scn",
        ]
        + ["--irradiance-samples", "4", "--picture-spp", "2", "--reference", "--reference-spp", "2", "-q"]
    )
    for name in ("a.zarr", "b.zarr", "a.model.zip", "b.model.zip"):
        out[f"info {name}"] = _json(["info", tmp / name])
    out["materials"] = _json(["materials"])
    out["view"] = _json(["view", tmp / "b.model.zip", "--export", tmp / "page", "--bands", "2", "-q"])
    out["acquire photographs"] = _json([*PHOTOGRAPHS, "--out", tmp / "shots", "-q"])
    shots = tmp / "shots"
    out["import images"] = _json(
        ["import", "images", shots, "-p", shots / "positions.csv", "-c", shots / "calibration.json"]
        + ["--gain", "1e5", "--window", "2", "--pitch", "0.5", "-o", tmp / "i.zarr", "-q"]
    )
    out["acquire object-photographs"] = _json(
        [*OBJECT_PHOTOGRAPHS, "--mesh", tmp / "ball.ply", "--out", tmp / "rig", "-q"]
    )
    with pytest.MonkeyPatch.context() as patch:  # the main job itself runs in make demo; here its printing
        job = functools.wraps(workflow_demo.main_job)(lambda out_dir, **kw: _demo_outputs(out_dir))
        patch.setattr(workflow_demo, "main_job", job)
        out["demo"] = _json(["demo", "--out", tmp / "results", "-q"])
    out["tmp"] = tmp
    return out


def _demo_outputs(out_dir) -> dict:
    """What the main job returns (translucency.pipeline.run_demo): where each output is."""
    names = (
        "baselines.png",
        "baselines.json",
        "dipole_fits.model.zip",
        "fits",
        "pig.zarr",
        "report/index.html",
    )
    return dict(zip(("figure", "summary", "model", "fits", "pig", "report"), (out_dir / n for n in names)))


#: tiny photographs of a slab and of a ball (acquire photographs, acquire object-photographs)
PHOTOGRAPHS = ["acquire", "photographs", "--material", "homogeneous:skin1", "--grid", "1", "--span", "1"]
PHOTOGRAPHS += ["--size", "8", "8", "3", "--voxel", "1", "--spp", "4"]
OBJECT_PHOTOGRAPHS = ["acquire", "object-photographs", "--material", "homogeneous:skin1", "--points", "2"]
OBJECT_PHOTOGRAPHS += ["--cameras", "3", "--resolution", "32", "32", "--spp", "4", "--index-matched"]


#: a small scene around the mesh of b.model.zip (render scene)
SCENE = """<scene version="3.0.0">
  <sensor type="perspective"><float name="fov" value="40"/>
    <transform name="to_world"><lookat origin="0, -30, 10" target="0, 0, 0" up="0, 0, 1"/></transform>
    <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="12"/></film>
  </sensor>
  <shape type="ply" id="ball"><string name="filename" value="object.ply"/></shape>
  <emitter type="constant"><rgb name="radiance" value="0.1, 0.1, 0.1"/></emitter>
</scene>
"""

NAMES = [
    "acquire planar",
    "acquire mesh",
    "fit",
    "fit (mesh)",
    "evaluate",
    "evaluate (mesh)",
    "render",
    "render (scene)",
    "export",
    "materials",
    "view",
    "acquire photographs",
    "import images",
    "acquire object-photographs",
    "demo",
]
NAMES += ["info a.zarr", "info b.zarr", "info a.model.zip", "info b.model.zip"]


@pytest.mark.parametrize("name", NAMES)
def test_output_follows_its_documented_schema(outputs, name):
    summary = outputs[name]
    assert check(summary, schema_of(summary)) == []


#: schemas whose command takes long enough to be checked by a slow test (test_import_object_json)
SLOW = {"import object"}


def test_every_schema_is_exercised(outputs):
    used = {id(schema_of(outputs[name])) for name in NAMES}
    assert {name for name, s in SCHEMAS.items() if id(s) not in used} == SLOW


@pytest.mark.slow  # the import's near-peak model and walks: about a minute on two cores
def test_import_object_json(outputs):
    tmp = outputs["tmp"]
    summary = _json(["import", "object", tmp / "rig", "-o", tmp / "o.zarr", "-q"])
    assert check(summary, schema_of(summary)) == []
    assert summary["estimate"]["dominated_by"].startswith("a chunk")


def test_docs_page_is_the_schemas():
    """docs/json.md is generated from docs/_gen/json_schemas.py: regenerate it when a schema changes."""
    assert DOCS.read_text() == markdown(), f"run: {COMMAND}"


def test_info_json_is_typed_and_whole(outputs):
    """info --json: numbers as numbers, booleans as booleans, objects as objects, meta not cut short."""
    planar, model = outputs["info a.zarr"], outputs["info a.model.zip"]
    assert isinstance(planar["size_bytes"], int) and planar["size_bytes"] > 0
    assert planar["complete"] is True and planar["damaged"] == {} and isinstance(planar["sample"], dict)
    assert planar["window_px"] == [5, 5] and planar["pitch_mm"] == 0.5
    assert isinstance(model["valid"], bool) and isinstance(model["physical"]["ok"], bool)
    fit = model["meta"]["fit"]  # the structure chosen by default, and what was fitted
    assert fit["model"] == fit["structure"]["chosen"]["model"] and isinstance(
        model["meta"]["objective_per_round"], list
    )
    assert model["n_points"] == 4 and len(model["total_reflectance_mean"]) == 3


def test_info_prints_the_bounds_of_a_mesh_object(outputs):
    """info on a mesh data set and on a per-vertex model: the object's bounds and centre in mm (a light
    or a camera is placed relative to them)."""
    for name in ("b.zarr", "b.model.zip"):
        fields = outputs[f"info {name}"]
        lo, hi = fields["bounds_mm"]
        assert lo == pytest.approx([-4, -4, -4], abs=0.01) and hi == pytest.approx([4, 4, 4], abs=0.01)
        assert fields["centre_mm"] == pytest.approx([0, 0, 0], abs=0.01)
        res = runner.invoke(app, ["info", str(outputs["tmp"] / name)], env={"COLUMNS": "200"})
        assert "bounds" in res.output and "x -4 … 4, y -4 … 4, z -4 … 4 mm" in res.output, res.output
        assert "centre" in res.output
    assert "bounds_mm" not in outputs["info a.model.zip"]  # a planar sample has no object to place


def test_render_json_names_the_light_as_an_object(outputs):
    """The default light (point@key) as placed on the 8 mm ball seen from (1, -1.6, 0.7): the view's azimuth
    turned 28 deg, its elevation raised 20 deg, 1.5 sizes (the box's diagonal) out, I = 1 W/mm^2 x d^2."""
    light = outputs["render"]["light"]
    view = np.array([1.0, -1.6, 0.7]) / np.linalg.norm([1.0, -1.6, 0.7])
    az, el = np.arctan2(view[1], view[0]) + np.radians(28.0), np.arcsin(view[2]) + np.radians(20.0)
    d = 1.5 * np.sqrt(3 * 8.0**2)
    u = [np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)]
    assert light["kind"] == "point" and light["position"] == pytest.approx(d * np.array(u), abs=0.01)
    assert light["intensity"] == pytest.approx(d * d, rel=1e-3)


def test_materials_json(outputs):
    marble = outputs["materials"]["materials"]["marble"]
    assert marble["sigma_s_prime"] == [2.19, 2.62, 3.00] and len(marble["R_d_dipole"]) == 3


def test_evaluate_json_is_a_flag_and_json_out_writes_the_same(outputs):
    """evaluate --json prints the summary on stdout like every other command; --json-out PATH writes the
    same object."""
    tmp = outputs["tmp"]
    args = ["evaluate", str(tmp / "a.model.zip"), str(tmp / "a.zarr"), "-q"]
    res = runner.invoke(
        app, [*args, "--report", str(tmp / "r1"), "--json", "--json-out", str(tmp / "x.json")]
    )
    assert res.exit_code == 0, res.output
    assert json.loads(res.stdout)["rel_l2"] == json.loads((tmp / "x.json").read_text())["rel_l2"]
    res = runner.invoke(app, ["evaluate", "--json", *args[1:], "--report", str(tmp / "r4")])
    assert res.exit_code == 0 and res.stderr == "", res.output  # the flag before the arguments
    assert json.loads(res.stdout)["command"] == "evaluate"


#: the commands whose --max-memory is checked against an estimate of their own (the others' in
#: tests/test_resources.py): their arguments, with {tmp} the fixture's folder, and the output they must
#: not write
MAX_MEMORY = {
    "demo": (["demo", "--out", "{tmp}/m-demo"], "m-demo"),
    "acquire photographs": ([*PHOTOGRAPHS, "--out", "{tmp}/m-shots"], "m-shots"),
    "acquire object-photographs": (
        [*OBJECT_PHOTOGRAPHS, "--mesh", "{tmp}/ball.ply", "--out", "{tmp}/m-rig"],
        "m-rig",
    ),
    "import images": (
        ["import", "images", "{tmp}/shots", "-p", "{tmp}/shots/positions.csv", "-c"]
        + ["{tmp}/shots/calibration.json", "--gain", "1e5", "-o", "{tmp}/m.zarr"],
        "m.zarr",
    ),
    "import object": (["import", "object", "{tmp}/rig", "-o", "{tmp}/mo.zarr"], "mo.zarr"),
    "export": (["export", "{tmp}/b.model.zip", "--gltf", "{tmp}/m.glb"], "m.glb"),
    "view": (["view", "{tmp}/b.model.zip", "--export", "{tmp}/m-page"], "m-page"),
}


@pytest.mark.parametrize("name", list(MAX_MEMORY))
def test_max_memory_is_checked_before_any_work(outputs, name):
    """--max-memory below a command's estimate: one line naming it, exit status 2, nothing written."""
    args, written = MAX_MEMORY[name]
    tmp = outputs["tmp"]
    res = runner.invoke(app, [a.format(tmp=tmp) for a in args] + ["--max-memory", "1M"])
    assert res.exit_code == 2, res.output
    assert res.stderr.startswith("error: ") and "more than --max-memory (1 MiB)" in res.stderr, res.stderr
    assert len(res.stderr.strip().splitlines()) == 1 and not (tmp / written).exists()
