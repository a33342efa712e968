"""The viewer: spherical harmonics, the precomputed transfer against the full relight, the drafts, the page's
files, the live server, and both pages in a real headless Chromium (skipped where none is installed)."""

from __future__ import annotations

import base64
import json
import math
import socket
import subprocess
import sys
import time
import urllib.request

import numpy as np
import pytest
import trimesh
from typer.testing import CliRunner

from helpers import chromium_executable, random_exponential_model
from translucency.cli.app import app
from translucency.transport import sh

runner = CliRunner()


# ---------------------------------------------------------------------------------------------------------
# spherical harmonics against SciPy's complex ones, and their turn about +z


def _scipy_real_sh(l: int, m: int, w: np.ndarray) -> np.ndarray:
    """Real SH from SciPy's complex :math:`Y_l^m` (with the Condon–Shortley phase, removed here)."""
    from scipy.special import sph_harm_y

    theta, phi = np.arccos(np.clip(w[:, 2], -1, 1)), np.arctan2(w[:, 1], w[:, 0])
    Y = sph_harm_y(l, abs(m), theta, phi) * (-1) ** abs(m)
    if m == 0:
        return Y.real
    return math.sqrt(2) * (Y.real if m > 0 else Y.imag)


def test_basis_matches_scipy_and_is_orthonormal():
    rng = np.random.default_rng(0)
    w = rng.normal(size=(200, 3))
    w /= np.linalg.norm(w, axis=1, keepdims=True)
    Y = sh.basis(w, 5)
    for l in range(5):
        for m in range(-l, l + 1):
            np.testing.assert_allclose(Y[:, l * (l + 1) + m], _scipy_real_sh(l, m, w), atol=1e-10)
    lattice = sh.sphere_directions(20000)
    Yl = sh.basis(lattice, 4)
    gram = Yl.T @ Yl * (4 * np.pi / len(lattice))
    np.testing.assert_allclose(gram, np.eye(16), atol=2e-3)


def test_turning_about_z_is_projecting_the_turned_light():
    def sky(w, turn=0.0):  # a smooth, lopsided sky
        phi = np.arctan2(w[:, 1], w[:, 0]) - turn
        g = np.exp(2 * w[:, 2]) * (1.5 + np.cos(phi) + 0.5 * np.sin(2 * phi))
        return np.stack([g, 0.5 * g, 0.2 * g], axis=1)

    c = sh.project_environment(sky, 4)
    turned = sh.project_environment(lambda w: sky(w, 0.7), 4)
    np.testing.assert_allclose(sh.rotate_z(c, 0.7), turned, atol=2e-3 * np.abs(c).max())


# ---------------------------------------------------------------------------------------------------------
# a small object: a ball and a thin "ear" beside it


def _body_and_ear():
    body = trimesh.creation.icosphere(2, radius=5.0)
    ear = trimesh.creation.icosphere(2, radius=1.0)
    ear.apply_scale((3.0, 0.35, 3.0))  # 0.7 mm thick
    ear.apply_translation((9.0, 0.0, 0.0))
    return trimesh.util.concatenate([body, ear])


@pytest.fixture(scope="module")
def small_model(tmp_path_factory):
    """A per-vertex model on a ball and a thin ear (324 vertices) carrying its mesh, saved."""
    from translucency import save_model

    mesh = _body_and_ear()
    terms = (((1.2, 2.0), (0.05, 0.1)), ((0.5, 0.8), (0.005, 0.01)))
    model = random_exponential_model(
        np.random.default_rng(5),
        geometry="mesh",
        mesh=mesh,
        points=np.arange(0, len(mesh.vertices), 5),
        terms=terms,
    )
    model.faces = np.asarray(mesh.faces)
    path = tmp_path_factory.mktemp("view") / "small.model.zip"
    save_model(model, path)
    return path


@pytest.fixture(scope="module")
def prepared(small_model):
    from translucency.io.model_file import load_model, read_header
    from translucency.render import object_of_model
    from translucency.transport import PreparedObject
    from translucency.view.object_page import viewed_object

    m = load_model(small_model)
    mesh, _ = object_of_model(m, read_header(small_model))
    return viewed_object(PreparedObject(m, mesh), name="small", directions=512)


def test_transfer_under_a_constant_sky_is_the_closed_form(prepared):
    """On two convex bodies (nothing shadows anything but the far sides... and each other little), a
    constant sky L gives every vertex E = π L <F> (the incidence law's cosine mean): the transfer's
    radiance is the transport of that."""
    from translucency.model.incidence import HalfSpaceIncidence, cosine_mean
    from translucency.render.lights import EnvironmentLight
    from translucency.transport.relight import relight_vertices
    from translucency.transport.transfer import transfer_vectors

    view = prepared
    L = 0.2
    R1 = np.random.default_rng(1).uniform(0.2, 0.8, (len(view.mesh.vertices), 3))
    law = HalfSpaceIncidence(R1)  # oblique light comes back more: <F> > 1
    transfer = transfer_vectors(view.transport, view.mesh, view.scene, law, directions=512)
    ours = transfer.radiance(EnvironmentLight(L).sh_coefficients(transfer.bands))
    E = math.pi * L * cosine_mean(R1)
    assert E.min() > 1.02 * math.pi * L
    # the ear is 4 mm from the ball: it hides a little of the sky from the ball's +x side and back
    v = np.asarray(view.mesh.vertices)
    far = np.linalg.norm(v - (9.0, 0, 0), axis=1) > 7.0
    expected = relight_vertices(view.transport, E)
    err = np.abs(ours - expected)[far] / expected[far]
    assert np.median(err) < 0.01 and err.max() < 0.05


def test_directional_light_page_formula_is_close_to_the_full_relight(prepared):
    """The page's formula (the rest through the basis, the local part exact) against the full relight."""
    assert all(np.isfinite(e) for e in prepared.errors.values())
    assert prepared.errors["environment"] < 0.05
    assert prepared.errors["directional (default)"] < 0.15
    assert max(prepared.errors.values()) < 0.35


def test_coarse_transport_on_every_vertex_is_the_transport(prepared):
    from translucency.transport.irradiance import vertex_irradiance
    from translucency.transport.relight import relight_vertices

    view = prepared
    light = view.light_at("point", (0.3, -1.0, 0.5))
    E = vertex_irradiance(view.mesh, view.scene, light, 1.0, view.law)
    full = relight_vertices(view.transport, E)
    everyone = np.arange(len(view.mesh.vertices))
    coarse = view.transport.coarse(view.mesh.vertices, everyone)
    np.testing.assert_allclose(relight_vertices(coarse, E), full, rtol=1e-4, atol=1e-7 * full.max())
    some = everyone[::7]
    np.testing.assert_allclose(
        relight_vertices(view.transport.rows(some), E), full[some], rtol=1e-5, atol=1e-9
    )

    def draft_error(receivers):  # cells of the receivers: a coarser quadrature, closer as they shrink
        d = view.relight(light, receivers=receivers)
        return np.sqrt(((d - full[receivers]) ** 2).sum() / (full[receivers] ** 2).sum())

    assert draft_error(everyone[::2]) < draft_error(some)  # the pig's: 1-2 % (benchmarks/view_speed.py)


def test_page_files_round_trip(prepared, tmp_path):
    from translucency.view.page import write_page

    meta, arrays = prepared.page_data()
    sizes = write_page(tmp_path, meta, arrays)
    assert set(sizes) == {"index.html", "viewer.js", "data.js"}
    text = (tmp_path / "data.js").read_text()
    data = json.loads(text.removeprefix("window.TL_DATA = ").removesuffix(";\n"))
    for name, a in arrays.items():
        got = np.frombuffer(base64.b64decode(data["arrays"][name]["b64"]), dtype=a.dtype)
        np.testing.assert_array_equal(got, np.ascontiguousarray(a).ravel())
    assert data["meta"]["vertices"] == len(prepared.mesh.vertices)
    assert 'src="data.js"' in (tmp_path / "index.html").read_text()


# ---------------------------------------------------------------------------------------------------------
# the command: bad input in one line, the static page


def test_view_refuses_bad_input_in_one_line(small_model, tmp_path):
    from translucency import save_model

    not_a_model = tmp_path / "notes.txt"
    not_a_model.write_text("hello")
    planar = save_model(random_exponential_model(np.random.default_rng(1)), tmp_path / "planar.model.zip")
    res = runner.invoke(app, ["export", str(planar), "--gltf", str(tmp_path / "p.glb")])  # a mesh is needed
    assert res.exit_code == 2 and "planar" in res.output and "Traceback" not in res.output
    for args, names in (
        ([str(not_a_model)], "notes.txt"),
        ([str(small_model), "--bands", "9"], "--bands"),
        ([str(small_model), "--sky", "point:1,2,3"], "--sky"),
    ):
        res = runner.invoke(app, ["view", *args, "--no-browser"])
        assert res.exit_code == 2, res.output
        assert names in res.output and "Traceback" not in res.output


def test_view_export_writes_a_page_and_states_its_error(small_model, tmp_path):
    out = tmp_path / "page"
    res = runner.invoke(app, ["view", str(small_model), "--export", str(out), "--json", "-q"])
    assert res.exit_code == 0, res.output
    summary = json.loads(res.output)
    assert summary["page_mb"] < 1 and summary["error_vs_render"]["environment"] < 0.05
    assert (out / "index.html").is_file()
    again = runner.invoke(app, ["view", str(small_model), "--export", str(out), "-q"])
    assert again.exit_code == 2 and "--overwrite" in again.output  # nothing replaced unasked


# ---------------------------------------------------------------------------------------------------------
# the live server, without a browser


def _get(url, data=None):
    with urllib.request.urlopen(urllib.request.Request(url, data=data), timeout=60) as r:
        return r.status, r.read()


def test_server_serves_the_page_and_relights(prepared):
    from translucency.view.server import ViewServer
    from translucency.view.surface import surface_data

    view = prepared
    surface = surface_data(view.model, view.mesh, name="small")
    server = ViewServer(surface, lambda say: view, port=0)
    server.start()
    try:
        assert _get(server.url)[0] == 200 and b"viewer.js" in _get(server.url)[1]
        for _ in range(200):
            state = json.loads(_get(server.url + "light.json")[1])
            if "meta" in state:
                break
            time.sleep(0.05)
        assert state["meta"]["bands"] == view.transfer.bands
        request = {"kind": "point", "direction": [0.3, -1.0, 0.5], "distance": 1.5}
        status, body = _get(server.url + "relight", json.dumps(request).encode())
        got = np.frombuffer(body, np.float16).reshape(-1, 3).astype(np.float64)
        want = view.relight(view.light_at("point", (0.3, -1.0, 0.5), 1.5))
        np.testing.assert_allclose(got, want, rtol=2e-3, atol=1e-3 * want.max())
        with pytest.raises(urllib.error.HTTPError) as bad:
            _get(server.url + "relight", b'{"kind": "laser"}')
        assert bad.value.code == 400
    finally:
        server.stop()


def test_a_port_in_use_takes_another_and_says_which(prepared):
    from translucency.view.server import ViewServer
    from translucency.view.surface import surface_data

    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        server = ViewServer(
            surface_data(prepared.model, prepared.mesh, name="s"), lambda say: prepared, port=port
        )
        try:
            assert server.port_note and str(port) in server.port_note
            assert server.httpd.server_address[1] != port
        finally:
            server.httpd.server_close()


# ---------------------------------------------------------------------------------------------------------
# both pages in a real browser


@pytest.fixture(scope="module")
def browser():
    playwright = pytest.importorskip("playwright.sync_api")
    exe = chromium_executable()
    if exe is None:
        pytest.skip("no Chromium installed (apt-get install chromium)")
    with playwright.sync_playwright() as p:
        b = p.chromium.launch(executable_path=exe)
        yield b
        b.close()


def _open(browser, url):
    page = browser.new_page(viewport={"width": 900, "height": 600})
    errors = []
    page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.goto(url)
    page.wait_for_function("window.TL !== undefined && TL.ready", timeout=120_000, polling=200)
    return page, errors


def _halves(page, light: dict) -> tuple[float, float, int]:
    """Mean brightness of the object's pixels in the left (ball) and right (ear) halves of the picture under
    ``light``, and how many pixels are not background."""
    import io

    from PIL import Image

    page.evaluate(f"TL.setLight({json.dumps(light)})")
    page.wait_for_timeout(400)  # the full mesh and, for a point light, the full relight
    page.evaluate("TL.frame()")
    png = page.locator("#canvas").screenshot()
    rgb = np.asarray(Image.open(io.BytesIO(png)).convert("RGB"), dtype=np.float64)
    background = np.array([29, 31, 33])
    obj = np.abs(rgb - background).sum(axis=2) > 12
    grey = rgb.mean(axis=2)
    w = rgb.shape[1]
    left, right = obj[:, : w // 2], obj[:, w // 2 :]
    mean = lambda g, m: float(g[m].mean()) if m.any() else 0.0  # noqa: E731
    return mean(grey[:, : w // 2], left), mean(grey[:, w // 2 :], right), int(obj.sum())


def _looks_right(page, light_kind: str) -> None:
    """The object appears; lit from the camera's side it is brighter than lit from behind; lit from behind,
    the thin ear glows and the thick ball does not."""
    page.evaluate("TL.cam.az = -90; TL.cam.el = 0")  # the camera on −y, the ear to the right
    front = _halves(page, {"kind": light_kind, "az": -90, "el": 20})
    back = _halves(page, {"kind": light_kind, "az": 90, "el": 0})
    assert front[2] > 2000  # the object is there
    assert front[0] > 2 * back[0]  # the ball: its lit side brighter
    assert back[1] > 2 * back[0]  # back-lit, the thin ear glows more than the ball


def test_static_page_in_chromium(browser, small_model, tmp_path):
    out = tmp_path / "page"
    assert runner.invoke(app, ["view", str(small_model), "--export", str(out), "-q"]).exit_code == 0
    page, errors = _open(browser, (out / "index.html").as_uri())
    _looks_right(page, "directional")
    env = _halves(page, {"kind": "environment", "envRot": 30})
    assert env[2] > 2000 and env[0] > 0
    page.evaluate("TL.cam.az = -90; TL.cam.el = 0; TL.frame()")
    box = page.locator("#canvas").bounding_box()
    vertex = page.evaluate(f"TL.pickAt({box['x'] + box['width'] * 0.3}, {box['y'] + box['height'] / 2})")
    assert vertex is not None and "incident point" in page.locator("#profile-note").inner_text()
    assert not errors, errors
    page.close()


def test_live_viewer_in_chromium(browser, small_model):
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "translucency",
            "view",
            str(small_model),
            "--no-browser",
            "--port",
            "0",
            "--seconds",
            "120",
        ],
        stderr=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        url = None
        for line in proc.stderr:
            if "viewer: http" in line:
                url = line.split("viewer: ")[1].split()[0]
                break
        assert url, "the command printed no address"
        page, errors = _open(browser, url)
        _looks_right(page, "point")
        assert page.evaluate("TL.stats.updates") >= 2  # the server relit it
        assert not errors, errors
        page.close()
    finally:
        proc.terminate()
        proc.wait(timeout=30)


def test_planar_model_page_and_its_relit_sample(tmp_path):
    """A planar model: the sample's mesh over its α grid, its maps, and the relit sample is exactly α ρ / π
    times the irradiance (a flat index-matched sample: no shadows, one sky for every point)."""
    from translucency import save_model
    from translucency.transport import sh
    from translucency.view.planar_page import planar_page_data

    model = random_exponential_model(np.random.default_rng(2), n_points=6)
    meta, arrays = planar_page_data(model, name="p")
    H, W = model.alpha.shape
    assert meta["vertices"] == H * W and arrays["index"].shape == (2 * (H - 1) * (W - 1), 3)
    np.testing.assert_allclose(arrays["map_alpha"], model.alpha.values.ravel(), rtol=1e-3)
    # under a constant sky L every point gets E = π L: the page's Σ_k L_k Ē_k (only k = 0 survives)
    bands = meta["bands"]
    K, kq = bands * bands, meta["kq"]
    q = arrays["transfer"][: meta["vertices"] * meta["stride"] * 4].reshape(-1, 4, kq * 4)
    Ebar = q[0, 3, :K] / 127.0 * meta["irradiance_scale"]
    sky = sh.project_environment(lambda w: np.full((len(w), 3), 0.3), bands)[:, 0]
    assert abs(Ebar @ sky - np.pi * 0.3) < 0.01 * np.pi * 0.3  # 8 bits
    rho = model.total_reflectance()
    assert arrays["local"].astype(float).max() <= (1.5 * rho.max() / np.pi) * 1.01  # α ≤ 1.5 here
    path = save_model(model, tmp_path / "p.model.zip")
    res = runner.invoke(app, ["view", str(path), "--export", str(tmp_path / "page"), "-q"])
    assert res.exit_code == 0, res.output
    assert (tmp_path / "page" / "data.js").stat().st_size > 1000


def test_gltf_opens_in_three_js(browser, small_model, tmp_path):
    """The exported glTF loads in three.js: viser's client (three.js with three-stdlib's GLTFLoader) draws it
    — the picture changes where the model stands — with no error in the console."""
    import io

    from PIL import Image

    viser = pytest.importorskip("viser")
    glb = tmp_path / "small.glb"
    assert runner.invoke(app, ["export", str(small_model), "--gltf", str(glb), "-q"]).exit_code == 0
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    server = viser.ViserServer(host="127.0.0.1", port=port, verbose=False)
    try:
        server.initial_camera.position = (0.0, -0.6, 0.25)
        server.initial_camera.look_at = (0.0, 0.0, 0.0)
        page, errors = browser.new_page(viewport={"width": 640, "height": 480}), []
        page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
        page.on("pageerror", lambda e: errors.append(str(e)))
        page.goto(f"http://127.0.0.1:{port}/")
        page.wait_for_timeout(4000)

        def picture():
            return np.asarray(Image.open(io.BytesIO(page.screenshot())).convert("L"), dtype=np.float64)

        empty = picture()
        # metres: the 19 mm object drawn 20× larger to fill the view
        server.scene.add_glb("/small", glb.read_bytes(), scale=20.0)
        page.wait_for_timeout(3000)
        drawn = picture()
        Image.fromarray(drawn.astype(np.uint8)).save(tmp_path / "three.png")
        changed = np.abs(drawn - empty)[160:, :300] > 10  # below the notice, left of the scene-tree panel
        assert changed.sum() > 1000, changed.sum()  # the ball alone covers about 7,000 pixels there
        assert not errors, errors
        page.close()
    finally:
        server.stop()


def _other_fit(small_model, tmp_path, seed: int):
    """A second model on the small model's mesh (other profiles), saved."""
    from translucency import save_model

    mesh = _body_and_ear()
    terms = (((1.0, 1.6), (0.05, 0.1)), ((0.3, 0.5), (0.005, 0.01)))
    model = random_exponential_model(
        np.random.default_rng(seed),
        geometry="mesh",
        mesh=mesh,
        points=np.arange(0, len(mesh.vertices), 5),
        terms=terms,
    )
    model.faces = np.asarray(mesh.faces)
    return save_model(model, tmp_path / f"other{seed}.model.zip")


def test_compare_needs_the_same_mesh(small_model, tmp_path):
    from translucency import save_model

    ball = trimesh.creation.icosphere(2, radius=5.0)
    other = random_exponential_model(
        np.random.default_rng(1), geometry="mesh", mesh=ball, points=np.arange(0, 162, 9)
    )
    other.faces = np.asarray(ball.faces)
    path = save_model(other, tmp_path / "ball.model.zip")
    res = runner.invoke(
        app, ["view", str(small_model), "--compare", str(path), "--export", str(tmp_path / "p")]
    )
    assert res.exit_code == 2 and "another mesh" in res.output and "Traceback" not in res.output


def test_two_models_side_by_side_and_their_difference_in_chromium(browser, small_model, tmp_path):
    """--compare: model B, the two side by side and |B − A| / A; against itself the difference is nil."""
    import io

    from PIL import Image

    other = _other_fit(small_model, tmp_path, 6)
    means = {}
    for name, b in (("other", other), ("itself", small_model)):
        out = tmp_path / name
        res = runner.invoke(app, ["view", str(small_model), "--compare", str(b), "--export", str(out), "-q"])
        assert res.exit_code == 0, res.output
        page, errors = _open(browser, (out / "index.html").as_uri())
        page.evaluate("TL.cam.az = -90; TL.cam.el = 0; TL.setLight({kind: 'directional', az: -90, el: 30})")
        page.evaluate("TL.setShow('compare_diff')")
        page.wait_for_timeout(400)
        page.evaluate("TL.frame()")
        rgb = np.asarray(
            Image.open(io.BytesIO(page.locator("#canvas").screenshot())).convert("RGB"), np.float64
        )
        obj = np.abs(rgb - np.array([29, 31, 33])).sum(axis=2) > 12
        means[name] = float(rgb[obj].mean()) if obj.any() else 0.0  # viridis: brighter for larger differences
        page.evaluate("TL.setShow('compare_side')")
        page.wait_for_timeout(400)
        page.evaluate("TL.frame()")
        side = np.asarray(
            Image.open(io.BytesIO(page.locator("#canvas").screenshot())).convert("L"), np.float64
        )
        assert (side > 40).sum() > 2000  # two objects drawn
        assert not errors, errors
        page.close()
    assert means["other"] > means["itself"] + 10


def test_reference_error_map_beside_the_model(browser, small_model, tmp_path):
    """--reference: a render folder's error map against its volpath reference (reference | ours | FLIP, as
    render wrote it) and its numbers on the page; a folder without one is refused in one line."""
    from PIL import Image

    render = tmp_path / "render"
    render.mkdir()
    Image.new("RGB", (90, 30), (200, 40, 40)).save(render / "render.png")
    summary = {"rel_rmse": 0.0612, "flip_mean_object": 0.072, "reference_noise": 0.043, "light": "point"}
    (render / "render.json").write_text(json.dumps(summary))
    out = tmp_path / "page"
    res = runner.invoke(
        app, ["view", str(small_model), "--reference-render", str(render), "--export", str(out), "-q"]
    )
    assert res.exit_code == 0, res.output
    page, errors = _open(browser, (out / "index.html").as_uri())
    assert page.evaluate("document.getElementById('reference-img').naturalWidth") == 90
    assert "0.061" in page.locator("#reference-note").inner_text()
    assert not errors, errors
    page.close()
    (render / "render.json").write_text(json.dumps({"light": "point"}))  # a render without a reference
    res = runner.invoke(
        app, ["view", str(small_model), "--reference-render", str(render), "--export", str(tmp_path / "q")]
    )
    assert res.exit_code == 2 and "--reference-render" in res.output and "Traceback" not in res.output
