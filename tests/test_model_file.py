"""The model file: exact round trips; corrupted, truncated, wrong-version, NaN-bearing
and eq. (2)-violating files are refused with one line naming the file and the fault."""

import json
import zipfile

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from helpers import random_exponential_model
from translucency import ModelFileError, TranslucencyError, load_model, save_model
from translucency.io import model_file as mf
from translucency.io._model_arrays import ALPHA_BITS, bit_rounded, checksum, required_arrays
from translucency.model import (
    MATERIALS,
    BurleyModel,
    DipoleModel,
    DirectionalDipoleModel,
    PBDModel,
    PlanarAlpha,
    VertexAlpha,
    check_physics,
)


def assert_same(a, b, dtype="float32"):
    """Equal, but for a per-vertex α stored at float32, which keeps ALPHA_BITS mantissa bits."""
    assert type(a) is type(b)
    np.testing.assert_array_equal(a.x_i, b.x_i)
    if isinstance(a.alpha, VertexAlpha) and dtype == "float32":
        np.testing.assert_array_equal(b.alpha.values, bit_rounded(a.alpha.values, ALPHA_BITS))
    else:
        np.testing.assert_array_equal(a.alpha.values, b.alpha.values)
    for name in type(a).STORED:
        va, vb = getattr(a, name), getattr(b, name)
        assert (va is None) == (vb is None)
        if va is not None:
            np.testing.assert_array_equal(va, vb)


@pytest.mark.parametrize("dtype", ["float32", "float16"])
@pytest.mark.parametrize(
    "m,colour,geometry",
    [(1, "shared", "planar"), (8, "shared", "planar"), (8, "per-channel", "planar"), (1, "shared", "mesh")],
)
def test_round_trip_is_exact(tmp_path, rng, dtype, m, colour, geometry):
    model = random_exponential_model(rng, n_points=6, m=m, colour=colour, geometry=geometry)
    path = save_model(model, tmp_path / "m.model.zip", dtype=dtype, meta={"sample": "test"})
    back = load_model(path)
    assert_same(model, back, dtype)
    if geometry == "mesh":
        np.testing.assert_array_equal(model.frame, back.frame)
    assert mf.read_header(path)["meta"] == {"sample": "test"}


def test_baseline_models_round_trip(tmp_path):
    mats = [MATERIALS["marble"], MATERIALS["apple"]]
    alpha = PlanarAlpha.uniform((3, 3))
    sa = np.array([m.sigma_a for m in mats]).astype(np.float32).astype(float)
    sp = np.array([m.sigma_s_prime for m in mats]).astype(np.float32).astype(float)
    dip = DipoleModel([[0, 0], [1, 1]], sa, sp, 1.3, alpha)
    bur = BurleyModel([[0, 0], [1, 1]], [[0.5, 0.5, 0.25]] * 2, [[1.0, 2.0, 0.5]] * 2, alpha)
    for model in (dip, bur):
        back = load_model(save_model(model, tmp_path / f"{model.kind}.model.zip"))
        assert_same(model, back)
    assert load_model(tmp_path / "dipole.model.zip").eta == pytest.approx(1.3)


@pytest.mark.parametrize("cls", [PBDModel, DirectionalDipoleModel])
@pytest.mark.parametrize("geometry", ["planar", "mesh"])
def test_new_baselines_round_trip(tmp_path, rng, cls, geometry):
    """Photon beam diffusion and the directional dipole: stored like the dipole (σ_a, σ_s' per point and
    channel, η in the header); the loaded model evaluates to the same R_d and passes the same physics."""
    mats = [MATERIALS["marble"], MATERIALS["apple"], MATERIALS["skin1"]]
    f32 = lambda a: np.asarray(a, float).astype(np.float32).astype(float)  # noqa: E731
    sa, sp = f32([m.sigma_a for m in mats]), f32([m.sigma_s_prime for m in mats])
    if geometry == "planar":
        x_i, frame = f32([[1, 1], [2, 3], [4, 2]]), None
        alpha = PlanarAlpha(f32(rng.uniform(0.5, 1.5, (12, 12))), np.zeros(2), 0.5)
    else:
        verts = f32(10 * rng.normal(size=(9, 3)))
        x_i, alpha = verts[:3], VertexAlpha(f32(rng.uniform(0.5, 1.5, 9)), verts)
        q, _ = np.linalg.qr(rng.normal(size=(3, 3, 3)))
        frame = f32(np.transpose(q, (0, 2, 1)))
    model = cls(x_i, sa, sp, 1.4, alpha, frame=frame)
    path = save_model(model, tmp_path / f"{model.kind}.model.zip", meta={"fit": {"model": model.kind}})
    back = load_model(path)
    assert_same(model, back)
    assert back.kind == model.kind and back.eta == pytest.approx(1.4)
    i, r = np.repeat(np.arange(3), 4), np.tile([0.05, 0.5, 2.0, 8.0], 3)
    np.testing.assert_allclose(back.profile(i, r, 0 * r), model.profile(i, r, 0 * r), rtol=1e-12)
    np.testing.assert_allclose(back.total_reflectance(), model.total_reflectance(), rtol=1e-12)
    header = mf.read_header(path)
    assert header["kind"] == model.kind and header["physics"] == check_physics(back).summary()


def test_new_baselines_in_info(tmp_path):
    from typer.testing import CliRunner

    from translucency.cli.app import app

    m = MATERIALS["marble"]
    f32 = lambda a: np.asarray(a, float).astype(np.float32).astype(float)  # noqa: E731
    for cls in (PBDModel, DirectionalDipoleModel):
        model = cls(
            [[4.0, 4.0]], f32([m.sigma_a]), f32([m.sigma_s_prime]), 1.3, PlanarAlpha.uniform((16, 16))
        )
        path = save_model(model, tmp_path / f"{model.kind}.model.zip")
        res = CliRunner().invoke(app, ["info", str(path), "--json"])
        assert res.exit_code in (0, 1), res.output  # 1: valid, but marble spreads beyond an 8 mm sample
        fields = json.loads(res.stdout)
        assert fields["kind"] == model.kind and len(fields["total_reflectance_mean"]) == 3, fields


def test_overflowing_fit_is_stored_flagged(tmp_path, rng):
    """A noisy fit whose amplitude exceeds float32 (a spike inside the excluded centre pixel) is stored
    with that term inert and the point flagged, with one warning naming the point — not refused with
    a message suggesting the setting already in use."""
    model = random_exponential_model(rng, n_points=4, m=2)
    model.c[2, 0, 1, 0], model.d[2, 0, 1, 0] = 5e131, -2138.0
    with pytest.warns(UserWarning, match=r"unphysical at 1 incident points.*: 2 \(c\).*stored inert"):
        path = save_model(model, tmp_path / "m.model.zip", meta={"flagged_points": [0]})
    back = load_model(path)
    assert back.c[2, 0, 1, 0] == 0.0 and back.d[2, 0, 1, 0] == -1.0
    np.testing.assert_array_equal(back.c[[0, 1, 3]], model.c[[0, 1, 3]])
    header = mf.read_header(path)
    assert header["meta"]["flagged_points"] == [0, 2]
    assert header["unstorable"] == {"2": ["c"]}
    # float16 on top: the message names the points and the setting to change
    model.c[2, 0, 1, 0] = 0.1
    model.c[3, 0, 0, 1] = 1e6
    with pytest.raises(TranslucencyError, match=r"params/c overflows float16 .* at incident points \[3\]"):
        save_model(model, tmp_path / "h.model.zip", dtype="float16")


def test_overflowing_sigma_fit_is_refused_naming_the_point(tmp_path):
    sa = np.array([[0.01] * 3, [1e39, 0.01, 0.01]])
    model = PBDModel([[0.0, 0.0], [1.0, 1.0]], sa, np.ones((2, 3)), 1.3, PlanarAlpha.uniform((3, 3)))
    with pytest.raises(TranslucencyError, match=r"pbd fit is unphysical at incident points 1 \(sigma_a\)"):
        save_model(model, tmp_path / "p.model.zip")
    assert not (tmp_path / "p.model.zip").exists()


def test_float16_refuses_values_it_cannot_hold(tmp_path, rng):
    model = random_exponential_model(rng, n_points=2)
    model.d[0, 0, 0, 0] = -1e-9  # rounds to -0.0 in float16: eq. (2) would break
    with pytest.raises(
        TranslucencyError, match="not representable in float16: eq. \\(2\\) violated at incident point 0"
    ):
        save_model(model, tmp_path / "m.model.zip", dtype="float16")
    model.d[0, 0, 0, 0] = -1.0
    model.c[1, 0, 0, 2] = 1e6
    with pytest.raises(TranslucencyError, match=r"params/c overflows float16 .* at incident points \[1\]"):
        save_model(model, tmp_path / "m.model.zip", dtype="float16")
    assert not (tmp_path / "m.model.zip").exists()
    assert list(tmp_path.iterdir()) == []  # no temporary debris


def test_failed_write_keeps_the_old_file(tmp_path, rng, monkeypatch):
    path = save_model(random_exponential_model(rng), tmp_path / "m.model.zip")
    before = path.read_bytes()

    def boom(*a, **k):
        raise OSError("disk full")

    monkeypatch.setattr(mf, "checksum", lambda arrays: "x")
    import zarr

    monkeypatch.setattr(zarr, "create_group", boom)
    with pytest.raises(OSError):
        save_model(random_exponential_model(rng), path, overwrite=True)
    assert path.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.model.zip"]


@pytest.fixture(scope="module")
def good_file(tmp_path_factory):
    rng = np.random.default_rng(7)
    model = random_exponential_model(rng, n_points=8, m=8)
    path = save_model(model, tmp_path_factory.mktemp("good") / "m.model.zip", dtype="float16")
    return path, model


def _one_line(exc, path):
    msg = str(getattr(exc, "value", exc))
    assert "\n" not in msg
    assert str(path) in msg
    return msg


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_corrupted_byte_is_refused_or_harmless(tmp_path, good_file, data):
    """Flip one byte anywhere: the file is refused with a one-line error, or — when the byte
    was one no reader depends on (a timestamp, say) — loads as exactly the same model."""
    path, model = good_file
    raw = bytearray(path.read_bytes())
    pos = data.draw(st.integers(0, len(raw) - 1))
    raw[pos] ^= data.draw(st.integers(1, 255))
    bad = tmp_path / f"bad-{pos}.model.zip"
    bad.write_bytes(bytes(raw))
    try:
        back = load_model(bad)
    except ModelFileError as exc:
        _one_line(exc, bad)
    else:
        assert_same(model, back)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(frac=st.floats(0.0, 0.999))
def test_truncated_file_is_refused(tmp_path, good_file, frac):
    path, _ = good_file
    raw = path.read_bytes()
    bad = tmp_path / "trunc.model.zip"
    bad.write_bytes(raw[: int(frac * len(raw))])
    with pytest.raises(ModelFileError) as exc:
        load_model(bad)
    _one_line(exc, bad)


def _rewrite(src, dst, edit_header=None, edit_arrays=None, fix_checksum=True):
    """Re-pack a model file with a doctored header or arrays (bypassing save_model's checks)."""
    root, header = mf._open(src)
    arrays = {k: np.asarray(root[k][...]) for k in required_arrays(header)}
    if edit_arrays:
        edit_arrays(arrays)
    if fix_checksum:
        header["checksum"] = checksum(arrays)
    if edit_header:
        edit_header(header)
    mf._write_store(dst, header, arrays)
    return dst


@pytest.mark.parametrize("version", [0, 2, "1", None])
def test_wrong_version_is_refused(tmp_path, good_file, version):
    bad = _rewrite(good_file[0], tmp_path / "v.model.zip", edit_header=lambda h: h.update(version=version))
    with pytest.raises(ModelFileError, match="format version .* is not supported") as exc:
        load_model(bad)
    _one_line(exc, bad)


@pytest.mark.parametrize(
    "key,index",
    [("params/c", (3, 0, 5, 1)), ("params/d", (0, 0, 0, 0)), ("alpha/values", (2, 2)), ("x_i", (1, 0))],
)
def test_nan_is_refused(tmp_path, good_file, key, index):
    def poison(arrays):
        arrays[key] = arrays[key].copy()
        arrays[key][index] = np.nan

    bad = _rewrite(good_file[0], tmp_path / "nan.model.zip", edit_arrays=poison)
    with pytest.raises(ModelFileError, match=f"array '{key}' holds a non-finite value at index") as exc:
        load_model(bad)
    _one_line(exc, bad)


def test_eq2_violation_is_refused(tmp_path, good_file):
    def flip(arrays):
        arrays["params/d"] = arrays["params/d"].copy()
        arrays["params/d"][5, 0, 2, 1] = 0.5

    bad = _rewrite(good_file[0], tmp_path / "eq2.model.zip", edit_arrays=flip)
    with pytest.raises(
        ModelFileError,
        match=r"invalid model: eq. \(2\) violated at incident point 5: "
        r"d\[channel block 0, direction 2, term 1\] = 0.5",
    ) as exc:
        load_model(bad)
    _one_line(exc, bad)


def test_altered_values_fail_the_checksum(tmp_path, good_file):
    def nudge(arrays):
        arrays["params/c"] = arrays["params/c"] * np.float16(1.5)

    bad = _rewrite(good_file[0], tmp_path / "sum.model.zip", edit_arrays=nudge, fix_checksum=False)
    with pytest.raises(ModelFileError, match="checksum mismatch"):
        load_model(bad)


def test_wrong_shape_and_dtype_and_missing_are_refused(tmp_path, good_file):
    def reshape(arrays):
        arrays["params/s_g"] = arrays["params/s_g"][:-1]

    bad = _rewrite(good_file[0], tmp_path / "shape.model.zip", edit_arrays=reshape)
    with pytest.raises(ModelFileError, match=r"invalid model: s_g: expected shape \(8,\), got \(7,\)"):
        load_model(bad)

    def retype(arrays):
        arrays["params/c"] = arrays["params/c"].astype(np.float64)

    bad = _rewrite(good_file[0], tmp_path / "dtype.model.zip", edit_arrays=retype)
    with pytest.raises(ModelFileError, match="array 'params/c' has dtype float64, expected float16"):
        load_model(bad)

    bad = _rewrite(good_file[0], tmp_path / "miss.model.zip", edit_arrays=lambda a: a.pop("params/d"))
    with pytest.raises(ModelFileError, match="missing array 'params/d'"):
        load_model(bad)


def test_not_a_model(tmp_path):
    p = tmp_path / "x.model.zip"
    p.write_text("hello")
    with pytest.raises(ModelFileError, match="not a zip archive"):
        load_model(p)
    with zipfile.ZipFile(p, "w") as z:
        z.writestr("zarr.json", json.dumps({"zarr_format": 3, "node_type": "group", "attributes": {}}))
    with pytest.raises(ModelFileError, match="no 'translucency_model' header"):
        load_model(p)
    with pytest.raises(ModelFileError, match="no such file"):
        load_model(tmp_path / "absent.model.zip")


@pytest.fixture(scope="module")
def fitted_ball(tmp_path_factory):
    """A per-vertex fit on a ball (642 vertices), its mesh in the model."""
    import trimesh

    import translucency as tl

    ball = trimesh.creation.icosphere(3, radius=6.0)
    ds = tl.acquire_mesh(
        ball,
        tmp_path_factory.mktemp("ball") / "ball.zarr",
        "homogeneous:marble",
        voxel_mm=1.0,
        points=8,
        photons=400,
        index_matched=True,
    )
    return tl.fit_model(ds, max_rounds=1).model


def test_compressed_mesh_renders_as_the_full_one(tmp_path, fitted_ball):
    """The mesh is stored by Draco (io/mesh_codec.py): the file is smaller than the raw arrays, every vertex
    moves by less than half a grid step, the triangles are the same, and the loaded model's picture is
    within 0.005 of the uncompressed model's (relative RMSE over the object's pixels)."""
    import translucency as tl
    from translucency.io.mesh_codec import STEP_OF_EDGE

    model = fitted_ball
    path = save_model(model, tmp_path / "ball.model.zip")
    header = mf.read_header(path)
    assert header["mesh_codec"] == {"name": "draco", "array": "mesh/draco"}
    with zipfile.ZipFile(path) as z:
        names = z.namelist()
        stored = sum(i.compress_size for i in z.infolist() if "mesh/draco" in i.filename)
    assert not any(n.startswith("alpha/vertices") or n.startswith("mesh/faces/") for n in names)
    raw = len(model.alpha.vertices) * 12 + len(model.faces) * 12
    assert stored < raw / 3, (stored, raw)
    loaded = load_model(path)
    v, v0 = loaded.alpha.vertices, model.alpha.vertices
    edge = np.median(np.linalg.norm(v0[model.faces[:, 1]] - v0[model.faces[:, 0]], axis=1))
    assert np.abs(v - v0).max() <= 0.5 * STEP_OF_EDGE * edge * 1.01
    as_set = lambda f: np.unique(np.sort(f, axis=1), axis=0)  # noqa: E731 — the triangles, unordered
    assert loaded.faces.shape == model.faces.shape
    np.testing.assert_array_equal(as_set(loaded.faces), as_set(model.faces))
    area = lambda m: np.cross(  # noqa: E731 — oriented area vectors: the winding kept
        m.alpha.vertices[m.faces[:, 1]] - m.alpha.vertices[m.faces[:, 0]],
        m.alpha.vertices[m.faces[:, 2]] - m.alpha.vertices[m.faces[:, 0]],
    ).sum(axis=0)
    assert np.allclose(area(loaded), area(model), atol=1e-3 * np.abs(area(model)).max() + 1e-6)
    change = np.abs(loaded.alpha.values / model.alpha.values - 1)  # α at 8 mantissa bits (ALPHA_BITS)
    assert change.max() <= 2.0**-9 and change.max() > 0
    full = tl.render_model(model, resolution=(64, 48)).picture
    decoded = tl.render_model(loaded, resolution=(64, 48)).picture
    lit = full.mean(axis=2) > 0
    assert lit.sum() > 500
    assert tl.render.rel_rmse(decoded, full, lit) < 0.005


def test_mesh_draco_would_change_is_kept_as_it_is(tmp_path, fitted_ball):
    """A triangle with a repeated corner (Draco would skip it): the mesh is stored uncompressed, exactly."""
    model = fitted_ball
    model_faces = model.faces
    try:
        model.faces = np.vstack([model_faces, [[1, 1, 2]]])
        path = save_model(model, tmp_path / "loose.model.zip")
        assert "mesh_codec" not in mf.read_header(path)
        loaded = load_model(path)
        np.testing.assert_array_equal(loaded.faces, model.faces)
        np.testing.assert_array_equal(loaded.alpha.vertices, model.alpha.vertices.astype(np.float32))
    finally:
        model.faces = model_faces


def test_altered_draco_bytes_are_refused(tmp_path, fitted_ball):
    path = save_model(fitted_ball, tmp_path / "ball.model.zip")
    import zarr

    store = zarr.storage.ZipStore(path, mode="a")
    root = zarr.open_group(store, mode="a")
    data = np.asarray(root["mesh/draco"][...])
    data[len(data) // 2 :] ^= 0x5A
    with pytest.warns(UserWarning):  # zip's duplicate entry
        root["mesh/draco"][...] = data
    store.close()
    with pytest.raises(ModelFileError, match="mesh/draco|checksum"):
        load_model(path)


def test_marching_cubes_triangles_take_more_bits_and_keep_their_normals():
    """The procedural pig subdivided once (marching cubes: vertices nanometres apart beside 0.3 mm
    edges, as a lab's scan at a finer voxel): on the grid a hundredth of the median edge fine some vertex
    normals turn by more than 60°; the codec takes more bits until none does, and none is lost."""
    import DracoPy
    import trimesh

    from translucency.acquire.objects import make_pig
    from translucency.io import mesh_codec as mc

    pig = make_pig(1.0)
    v, f = trimesh.remesh.subdivide(pig.vertices, pig.faces)
    v, f = np.asarray(v, np.float32), np.asarray(f)
    first = mc.quantization_bits(v, f)
    index = {"index": np.arange(len(v), dtype=np.uint32)[:, None]}
    coarse = mc.decode_mesh(
        DracoPy.encode(v, f.astype(np.uint32), quantization_bits=first, generic_attributes=index)
    )
    before = mc._area_normals(v, f)
    assert not mc._normals_kept(before, mc._area_normals(coarse[0], f))
    data, dv, df = mc.encode_mesh(v, f)
    after = mc._area_normals(dv, f)
    cos = (
        np.einsum("vk,vk->v", before, after) / np.linalg.norm(before, axis=1) / np.linalg.norm(after, axis=1)
    )
    assert cos.min() > 0.5 and np.isfinite(cos).all()
    assert len(data) < (v.nbytes + f.astype(np.int32).nbytes) / 3
