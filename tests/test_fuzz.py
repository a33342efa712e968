"""Fuzzing every reader and every numeric option (issue 14): whatever a user feeds the tool, the answer is
success or one ``error:`` line with exit status 2 — never a traceback, a signal, a hang, a NaN in an
output, or a changed input file.

(a) Byte flips, truncations, zeroed runs and appended garbage in every file kind the tool reads: planar
data set chunks and ``zarr.json``, mesh data sets, model files, volume ``.npz``, mesh ``.ply``/``.obj``.
(b) Random values (negative, zero, NaN, inf, huge, wrong type) for every numeric option of every command.

The fast suite runs a few derandomised examples per case; ``make test-slow`` runs 200 random ones each
(``TRANSLUCENCY_HYPOTHESIS_PROFILE=long``).
"""

import hashlib
import json
import shutil
import signal
from pathlib import Path

import numpy as np
import pytest
import trimesh
from hypothesis import given
from hypothesis import strategies as st
from typer.testing import CliRunner

from helpers import fuzz_settings
from translucency import load_model
from translucency.cli.app import app
from translucency.io.dataset import open_dataset

runner = CliRunner()
TINY_PLANAR = ["--grid", "2", "--span", "2", "--photons", "200", "--window", "2", "--pitch", "0.5"]
TINY_MESH = ["--points", "2", "--photons", "100", "--voxel", "1", "--material", "homogeneous:marble"]


def _run(args, seconds=120):
    """The CLI in-process, with an alarm as the hang detector."""

    def hang(signum, frame):
        raise TimeoutError(f"hung for {seconds} s: {args}")

    old = signal.signal(signal.SIGALRM, hang)
    signal.alarm(seconds)
    try:
        return runner.invoke(app, [str(a) for a in args])
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)


def _hashes(path: Path) -> dict:
    files = [path] if path.is_file() else sorted(p for p in path.rglob("*") if p.is_file())
    return {str(p): hashlib.sha256(p.read_bytes()).hexdigest() for p in files}


def _strict_json(text: str):
    def refuse(token):
        raise AssertionError(f"non-finite {token} in JSON output")

    return json.loads(text, parse_constant=refuse)


def check(res, names, *, allow_invalid=False):
    """Success, or one ``error:`` line naming one of ``names``; never a traceback.

    ``allow_invalid``: ``info`` on a model it can open but not validate answers with its table, the
    ``valid`` row saying no, and exit status 1."""
    out = res.output
    assert not isinstance(res.exception, TimeoutError), res.exception
    assert res.exception is None or isinstance(res.exception, SystemExit), (
        f"{type(res.exception).__name__}: {res.exception}\n{out}"
    )
    assert "Traceback" not in out, out
    if allow_invalid and res.exit_code == 1:
        assert "no —" in out, out
        return "invalid"
    assert res.exit_code in (0, 2), (res.exit_code, out)
    errors = [ln for ln in out.splitlines() if ln.startswith("error:")]
    if res.exit_code == 2:
        assert len(errors) == 1, out
        assert any(n in errors[0] for n in names), (names, errors[0])
        return "error"
    assert not errors, out
    return "ok"


def mutate(path: Path, op: str, where: float, byte: int, length: int) -> None:
    data = bytearray(path.read_bytes())
    at = min(len(data), int(where * len(data)))
    if op == "flip" and data:
        at = min(at, len(data) - 1)
        data[at] ^= byte or 0xFF
    elif op == "truncate":
        data = data[:at]
    elif op == "zero":
        data[at : at + length] = bytes(len(data[at : at + length]))
    elif op == "garbage":
        data[at:at] = bytes((byte + 37 * i) % 256 for i in range(length))
    elif op == "delete":
        path.unlink()
        return
    path.write_bytes(bytes(data))


damage = st.tuples(
    st.sampled_from(["flip", "truncate", "zero", "garbage", "delete"]),
    st.floats(0.0, 1.0),
    st.integers(0, 255),
    st.integers(1, 64),
)

#: what each kind of outcome counted to, for the report at the end (pytest -s shows it)
OUTCOMES: dict = {}


def tally(case: str, outcome: str) -> None:
    OUTCOMES.setdefault(case, {}).setdefault(outcome, 0)
    OUTCOMES[case][outcome] += 1


@pytest.fixture(scope="module", autouse=True)
def _report_outcomes():
    yield
    for case, counts in sorted(OUTCOMES.items()):
        print(f"fuzz {case}: {counts}")


@pytest.fixture(scope="module")
def pristine(tmp_path_factory):
    """Tiny inputs of every kind, made once: planar and mesh data sets, their models, a volume, meshes."""
    root = tmp_path_factory.mktemp("pristine")
    res = runner.invoke(
        app,
        [
            "acquire",
            "planar",
            "--material",
            "marble",
            "--size",
            "6",
            "6",
            "3",
            "--voxel",
            "0.5",
            "--chunk",
            "2",
        ]
        + TINY_PLANAR
        + ["--out", str(root / "d.zarr")],
    )
    assert res.exit_code == 0, res.output
    res = runner.invoke(
        app, ["fit", str(root / "d.zarr"), "--out", str(root / "d.model.zip"), "--rounds", "1"]
    )
    assert res.exit_code == 0, res.output
    ball = trimesh.creation.icosphere(1, radius=3.0)
    ball.export(root / "ball.ply")
    ball.export(root / "ball.obj")
    res = runner.invoke(
        app,
        ["acquire", "mesh", "--mesh", str(root / "ball.ply"), "--chunk", "1", "--out", str(root / "b.zarr")]
        + TINY_MESH,
    )
    assert res.exit_code == 0, res.output
    res = runner.invoke(
        app, ["fit", str(root / "b.zarr"), "--out", str(root / "b.model.zip"), "--rounds", "1"]
    )
    assert res.exit_code == 0, res.output
    s = np.full((6, 12, 12, 3), 2.0)
    np.savez(root / "v.npz", sigma_s=s, sigma_a=0.01 * s, voxel_mm=np.float64(0.5), g=np.float64(0.0))
    return root


def _fresh(pristine: Path, tmp: Path, name: str) -> Path:
    src = pristine / name
    dst = tmp / name
    (shutil.copytree if src.is_dir() else shutil.copy2)(src, dst)
    return dst


def _store_files(pristine: Path, name: str) -> list[str]:
    root = pristine / name
    return sorted(str(p.relative_to(root)) for p in root.rglob("*") if p.is_file())


def _finite_outputs(tmp: Path) -> None:
    """No NaN in what a successful command wrote: model files load (finiteness is checked on load)."""
    for model in tmp.glob("out*.model.zip"):
        load_model(model)


# -- (a) damaged files ---------------------------------------------------------------------------------
@fuzz_settings(5)
@given(data=st.data())
def test_damaged_planar_data_set(pristine, tmp_path_factory, data):
    tmp = tmp_path_factory.mktemp("planar")
    ds = _fresh(pristine, tmp, "d.zarr")
    model = _fresh(pristine, tmp, "d.model.zip")
    target = ds / data.draw(st.sampled_from(_store_files(pristine, "d.zarr")), label="file")
    mutate(target, *data.draw(damage, label="damage"))
    before = _hashes(ds) | _hashes(model)
    names = ["d.zarr", "--out"]
    outcome = check(_run(["info", ds]), names)
    res = _run(["fit", ds, "--out", tmp / "out.model.zip", "--rounds", "1", "--quiet"])
    check(res, names)
    res = _run(["evaluate", model, ds, "--report", tmp / "rep", "--json", "--quiet"])
    if check(res, names) == "ok":
        _strict_json(res.stdout)
    _finite_outputs(tmp)
    assert _hashes(ds) | _hashes(model) == before
    tally(f"planar data set {target.name}", outcome)


@fuzz_settings(6)
@given(data=st.data())
def test_damaged_mesh_data_set(pristine, tmp_path_factory, data):
    tmp = tmp_path_factory.mktemp("mesh")
    ds = _fresh(pristine, tmp, "b.zarr")
    target = ds / data.draw(st.sampled_from(_store_files(pristine, "b.zarr")), label="file")
    mutate(target, *data.draw(damage, label="damage"))
    before = _hashes(ds)
    outcome = check(_run(["info", ds]), ["b.zarr"])
    check(_run(["fit", ds, "--out", tmp / "out.model.zip", "--rounds", "1", "--quiet"]), ["b.zarr"])
    _finite_outputs(tmp)
    assert _hashes(ds) == before
    tally("mesh data set", outcome)


@fuzz_settings(8)
@given(which=st.sampled_from(["d.model.zip", "b.model.zip"]), how=damage)
def test_damaged_model_file(pristine, tmp_path_factory, which, how):
    tmp = tmp_path_factory.mktemp("model")
    model = _fresh(pristine, tmp, which)
    mutate(model, *how)
    before = _hashes(model) if model.exists() else {}
    outcome = check(_run(["info", model]), [which], allow_invalid=True)
    if which == "d.model.zip":
        res = _run(["evaluate", model, pristine / "d.zarr", "--report", tmp / "rep", "--json", "-q"])
        if check(res, [which]) == "ok":
            _strict_json(res.stdout)
    assert (_hashes(model) if model.exists() else {}) == before
    tally(f"model file ({how[0]})", outcome)


@fuzz_settings(5)
@given(how=damage)
def test_damaged_volume(pristine, tmp_path_factory, how):
    tmp = tmp_path_factory.mktemp("volume")
    vol = _fresh(pristine, tmp, "v.npz")
    mutate(vol, *how)
    before = _hashes(vol) if vol.exists() else {}
    res = _run(["acquire", "planar", "--volume", vol, *TINY_PLANAR, "--out", tmp / "out.zarr", "-q"])
    outcome = check(res, ["v.npz", "--volume", "--window", "--span", "--pitch"])
    if outcome == "ok":
        assert np.isfinite(open_dataset(tmp / "out.zarr")["R_d"]).all()
    assert (_hashes(vol) if vol.exists() else {}) == before
    tally("volume .npz", outcome)


@fuzz_settings(5)
@given(which=st.sampled_from(["ball.ply", "ball.obj"]), how=damage)
def test_damaged_mesh_file(pristine, tmp_path_factory, which, how):
    tmp = tmp_path_factory.mktemp("meshfile")
    mesh = _fresh(pristine, tmp, which)
    mutate(mesh, *how)
    before = _hashes(mesh) if mesh.exists() else {}
    res = _run(["acquire", "mesh", "--mesh", mesh, *TINY_MESH, "--out", tmp / "out.zarr", "-q"])
    outcome = check(res, [which, "--mesh"])
    assert (_hashes(mesh) if mesh.exists() else {}) == before
    tally(f"mesh file {which}", outcome)


# -- (b) option values ---------------------------------------------------------------------------------
values = st.one_of(
    st.sampled_from(
        ["-1", "0", "-0", "nan", "inf", "-inf", "1e308", "1e20", "99999999999", "abc", "", "0x10"]
    ),
    st.integers(-(10**12), 10**12).map(str),
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
)

#: every numeric option of every command, with arguments that otherwise run in a second or two
OPTIONS = {
    "acquire planar": (
        [
            "acquire",
            "planar",
            "--material",
            "marble",
            "--size",
            "6",
            "6",
            "3",
            "--voxel",
            "0.5",
            *TINY_PLANAR,
        ],
        [
            "--photons",
            "--seed",
            "--grid",
            "--span",
            "--pitch",
            "--window",
            "--voxel",
            "--g",
            "--tilt",
            "--chunk",
        ],
    ),
    "acquire mesh": (
        ["acquire", "mesh", "--mesh", "ball.ply", *TINY_MESH],
        ["--scale", "--voxel", "--points", "--photons", "--seed", "--g", "--chunk"],
    ),
    "fit planar": (
        ["fit", "d.zarr", "--rounds", "1"],
        ["--terms", "--directions", "--exclusion", "--rounds", "--chunk"],
    ),
    "fit mesh": (["fit", "b.zarr", "--rounds", "1"], ["--terms", "--exclusion", "--rounds"]),
    "evaluate": (["evaluate", "d.model.zip", "d.zarr", "--json"], ["--profiles"]),
    "materials": (["materials"], ["--eta"]),
    "demo": (["demo", "--help"], ["--terms"]),
}
CASES = [(cmd, opt) for cmd, (_, opts) in OPTIONS.items() for opt in opts]


@fuzz_settings(24)
@given(case=st.sampled_from(CASES), value=values)
def test_option_values(pristine, tmp_path_factory, case, value):
    command, option = case
    tmp = tmp_path_factory.mktemp("option")
    for name in ("d.zarr", "d.model.zip", "b.zarr", "ball.ply"):
        _fresh(pristine, tmp, name)
    base, _ = OPTIONS[command]
    args = [str(tmp / a) if (tmp / a).exists() else a for a in base]
    if command.startswith(("acquire", "fit")):
        args += ["--out", tmp / ("out.model.zip" if command.startswith("fit") else "out.zarr"), "-q"]
    if command == "evaluate":
        args += ["--report", tmp / "rep", "-q"]
        value = ",".join([value, value])  # --profiles takes a list
    before = {n: _hashes(tmp / n) for n in ("d.zarr", "d.model.zip", "b.zarr", "ball.ply")}
    res = _run([*args, option, value])
    outcome = check(res, [option, option.lstrip("-") + ":", "--points", "--out"])
    if outcome == "ok" and command == "evaluate":
        _strict_json(res.stdout)
    _finite_outputs(tmp)
    assert {n: _hashes(tmp / n) for n in before} == before
    tally(f"option {command} {option}", outcome)


def test_max_memory_values():
    for text in ("lots", "-1G", "0", "nan", "1e400G", "12Q"):
        res = runner.invoke(
            app, ["acquire", "planar", "--material", "marble", "--out", "x.zarr", "--max-memory", text]
        )
        assert check(res, ["--max-memory"]) == "error" and not Path("x.zarr").exists(), res.output


# -- (c) render: environment maps and numeric options ----------------------------------------------------
@pytest.fixture(scope="module")
def renderable(tmp_path_factory):
    """A per-vertex model that carries its mesh (162 vertices: a render takes about a second) and two
    environment maps, EXR and HDR."""
    from helpers import random_exponential_model
    from translucency import save_model
    from translucency.mitsuba import mitsuba

    root = tmp_path_factory.mktemp("renderable")
    ball = trimesh.creation.icosphere(2, radius=5.0)
    rng = np.random.default_rng(3)
    terms = (((2.0, 3.0), (0.2, 0.5)), ((0.3, 0.6), (0.01, 0.05)))
    model = random_exponential_model(
        rng, geometry="mesh", mesh=ball, points=np.arange(0, 162, 11), terms=terms
    )
    model.faces = np.asarray(ball.faces)
    save_model(model, root / "r.model.zip")
    sky = np.zeros((16, 32, 3), np.float32)
    sky[:] = np.linspace(0.3, 0.02, 16)[:, None, None]
    sky[3:5, 20:22] = 40.0
    for name in ("sky.exr", "sky.hdr"):
        mitsuba().Bitmap(sky).write(str(root / name))
    return root


RENDER_BASE = ["--resolution", "24", "18", "-q"]


def _rendered_finite(out: Path) -> None:
    """A successful render wrote finite pictures and JSON."""
    from translucency.mitsuba import mitsuba

    pixels = np.asarray(mitsuba().Bitmap(str(out / "ours.exr")))
    assert np.isfinite(pixels).all() and (pixels >= 0).all()
    _strict_json((out / "render.json").read_text())


def _map_with(path: Path, how: str) -> Path:
    """A map of the wrong kind: NaN/inf/negative pixels, one pixel, grey, black."""
    from translucency.mitsuba import mitsuba

    img = np.full((8, 16, 3), 0.2, np.float32)
    if how == "nan":
        img[3, 5, 1] = np.nan
    elif how == "inf":
        img[0, 0, 0] = np.inf
    elif how == "negative":
        img[7, 15, 2] = -1.0
    elif how == "one pixel":
        img = img[:1, :1]
    elif how == "grey":
        img = img[..., :1]
    elif how == "black":
        img[:] = 0.0
    mitsuba().Bitmap(img).write(str(path))
    return path


@fuzz_settings(6)
@given(
    which=st.sampled_from(["sky.exr", "sky.hdr"]),
    how=st.one_of(
        damage.map(lambda d: ("bytes", d)),
        st.sampled_from(["nan", "inf", "negative", "one pixel", "grey", "black"]).map(
            lambda k: ("pixels", k)
        ),
    ),
    scale=st.sampled_from(["", ",1", ",0", ",1e30", ",-1", ",nan"]),
)
def test_damaged_environment_map(renderable, tmp_path_factory, which, how, scale):
    tmp = tmp_path_factory.mktemp("envmap")
    model = _fresh(renderable, tmp, "r.model.zip")
    if how[0] == "bytes":
        env = _fresh(renderable, tmp, which)
        mutate(env, *how[1])
    else:
        env = _map_with(tmp / ("odd.exr" if how[1] == "grey" else which.replace("sky", "odd")), how[1])
    before = _hashes(env) if env.exists() else {}
    res = _run(["render", model, "--light", f"env:{env}{scale}", "--out", tmp / "r", *RENDER_BASE])
    outcome = check(res, [env.name, "scale"])
    if outcome == "ok":
        _rendered_finite(tmp / "r")
    assert (_hashes(env) if env.exists() else {}) == before
    tally(f"environment map ({how[0]}: {how[1] if how[0] == 'pixels' else how[1][0]})", outcome)


number = st.one_of(
    st.sampled_from(["-1", "0", "-0", "nan", "inf", "1e308", "1e-320", "1e20", "1e21", "abc", ""]),
    st.floats(-1e6, 1e6, allow_nan=False).map(repr),
)
#: the light templates, a number drawn into each slot
LIGHTS = [
    "point:{},-30,30,{}",
    "directional:{},1,-1,{}",
    "spot:0,-30,30,{},0,0,{},{}",
    "env:{}",
]
RENDER_OPTIONS = ["--resolution", "--radius", "--reference-spp", "--view"]


@fuzz_settings(12)
@given(
    case=st.one_of(
        st.sampled_from(RENDER_OPTIONS).map(lambda o: ("option", o)),
        st.sampled_from(LIGHTS).map(lambda t: ("light", t)),
    ),
    values=st.lists(number, min_size=3, max_size=3),
)
def test_render_option_values(renderable, tmp_path_factory, case, values):
    tmp = tmp_path_factory.mktemp("renderopt")
    model = _fresh(renderable, tmp, "r.model.zip")
    before = _hashes(model)
    kind, what = case
    args = ["render", model, "--out", tmp / "r", *RENDER_BASE]
    if kind == "light":
        args += ["--light", what.format(*values[: what.count("{}")])]
        names = ["light"]
    elif what == "--resolution":
        args += ["--resolution", values[0], values[1]]
        names = ["--resolution"]
    elif what == "--view":
        args += ["--view", ",".join(values)]
        names = ["--view"]
    else:
        args += [what, values[0]]
        names = [what]
    res = _run(args)
    outcome = check(res, [*names, "--max-memory", "memory"])
    if outcome == "ok":
        _rendered_finite(tmp / "r")
    assert _hashes(model) == before
    tally(f"render {what}", outcome)
