"""The walked transport (transport/walk.py): the near part's share in closed form, the surface filter, the
walk's power bookkeeping against photons that cannot be lost, and the two parts splitting the pairs."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from scipy.integrate import quad

from translucency.acquire.volume import Volume
from translucency.geometry import vertex_areas
from translucency.mitsuba import mesh_scene
from translucency.render import DirectionalLight
from translucency.transport.irradiance import vertex_irradiance
from translucency.transport.walk import _gathered, _planar_share, walk_crossed


def test_planar_share_is_the_profiles_energy_within_the_radius():
    """Σ_k c_k ∫_0^R 2π r e^{d_k r} dr over the same to ∞, against numerical quadrature."""
    rng = np.random.default_rng(2)
    c = rng.uniform(0.01, 1.0, (4, 3, 3))
    d = -rng.uniform(0.05, 5.0, (4, 3, 3))
    for R in (0.3, 2.0, 11.0):
        got = _planar_share(c, d, R)
        for v in range(4):
            for ch in range(3):
                cc, dd = c[v, ch], d[v, ch]
                prof = lambda r, cc=cc, dd=dd: 2 * np.pi * r * np.sum(cc * np.exp(dd * r))  # noqa: E731
                want = quad(prof, 0, R, limit=200)[0] / quad(prof, 0, np.inf, limit=200)[0]
                assert got[v, ch] == pytest.approx(want, rel=1e-6)


def test_the_gather_is_exact_for_a_constant_field_and_keeps_a_thin_parts_sides_apart():
    """Exits splatted in proportion to the vertices' areas (a constant radiance over a face) come back as that
    radiance wherever they are gathered from, however wide the gather; the two faces of a plate 1 mm thick
    stay apart (each gathers from the vertices that face its way)."""
    box = trimesh.creation.box(extents=(20.0, 20.0, 1.0)).subdivide().subdivide().subdivide()
    v, area = np.asarray(box.vertices), vertex_areas(box)
    inner = np.abs(v[:, :2]).max(axis=1) < 10.0 - 4.0  # away from the rim (its normals are averaged)
    top, bottom = inner & (v[:, 2] > 0), inner & (v[:, 2] < 0)
    lit = (v[:, 2] > 0).astype(float)  # radiance 1.5 (and 0.2 in blue) on top only, 1 mm above a dark face
    splat = area[:, None] * lit[:, None] * np.array([1.5, 1.5, 0.2])
    for gather in (1, 40, 10_000):  # a vertex's own exits, a few neighbours', every neighbour's it may reach
        L = _gathered(box, splat, lit * 20.0, gather)
        np.testing.assert_allclose(L[top], [[1.5, 1.5, 0.2]] * int(top.sum()), rtol=1e-12)
        np.testing.assert_allclose(L[bottom], 0.0, atol=1e-12)


def test_a_walk_without_absorption_returns_all_the_power():
    """σ_a = 0 in a ball 10 mm across at σ_s = 6 mm⁻¹: every photon that enters leaves, and all but the few
    that graze a sliver at the terminator leave scattered (counted: 0.4–0.6 % here), so the exitance's power,
    Σ_o π L_o A_o (no camera: every exit counts; split 0: every pair crossed), is the power that entered,
    Σ_j E_j A_j, less that sliver — within 1 %, never more."""
    ball = trimesh.creation.icosphere(3, radius=5.0)
    medium = Volume.homogeneous((22, 22, 22), 0.5, [6.0] * 3, [0.0] * 3, eta=1.0)
    sun = DirectionalLight((0.3, -0.2, -1.0), irradiance=2.0)
    scene = mesh_scene(ball)
    L = walk_crossed(ball, medium, sun, scene, split=0.0, photons=20_000, seed=3, gather=0)
    area = vertex_areas(ball)
    w = -np.asarray(sun.direction)
    E = vertex_irradiance(ball, scene, sun)  # E cos θ, its own shadow at the terminator
    lit = np.asarray(ball.vertex_normals) @ w > 0.1
    np.testing.assert_allclose(E[lit], 2.0 * np.asarray(ball.vertex_normals)[lit] @ w, rtol=1e-6)
    power_in = float(E @ area)
    power_out = (np.pi * L * area[:, None]).sum(axis=0)
    assert (power_out <= power_in).all() and (power_out > 0.99 * power_in).all()
    # the gather (a density estimate) moves light between vertices: within a few per cent of it in all
    gathered = walk_crossed(ball, medium, sun, scene, split=0.0, photons=20_000, seed=3)
    np.testing.assert_allclose((np.pi * gathered * area[:, None]).sum(axis=0), power_out, rtol=0.03)
    # and the light leaves on every side of the ball: the unlit half gets a share
    unlit = np.asarray(ball.vertex_normals) @ w < -0.2
    assert (L[unlit].mean(axis=0) > 0.01 * L[~unlit].mean(axis=0)).all()


def test_the_split_leaves_the_near_pairs_out_of_the_walk():
    """With the split radius larger than the ball, every exit on the lit side is near its entry and only the
    light that crossed to a side facing away is walked; with split 0 all of it is."""
    ball = trimesh.creation.icosphere(3, radius=5.0)
    medium = Volume.homogeneous((22, 22, 22), 0.5, [2.0] * 3, [0.01] * 3, eta=1.0)
    sun = DirectionalLight((0.0, 0.0, -1.0), irradiance=1.0)
    scene = mesh_scene(ball)
    all_of_it = walk_crossed(ball, medium, sun, scene, split=0.0, photons=10_000, seed=4, gather=0)
    crossed = walk_crossed(ball, medium, sun, scene, split=100.0, photons=10_000, seed=4, gather=0)
    n = np.asarray(ball.vertex_normals)
    assert (crossed <= all_of_it + 1e-12).all()
    # an exit's face must face away from its entry's normal to be crossed: the top cap (entries with n·z near
    # 1, exits there face the same way) keeps none of it
    cap = n[:, 2] > 0.95
    assert crossed[cap].max() < 0.05 * all_of_it[cap].mean()
    assert crossed[n[:, 2] < -0.5].mean() > 0.5 * all_of_it[n[:, 2] < -0.5].mean()


@pytest.fixture
def box_model(tmp_path):
    """A random per-vertex model on a box (10 × 6 × 4 mm) carrying a medium that varies from point to point,
    saved; and the same model without its medium (fitted before the estimate existed)."""
    from helpers import random_exponential_model
    from translucency import save_model

    rng = np.random.default_rng(7)
    box = trimesh.creation.box(extents=(10.0, 6.0, 4.0)).subdivide().subdivide()
    points = rng.choice(len(box.vertices), 12, replace=False)
    model = random_exponential_model(rng, geometry="mesh", mesh=box, points=points)
    model.faces = np.asarray(box.faces)
    medium = np.stack([rng.uniform(0.5, 2.0, (12, 3)), rng.uniform(0.01, 0.2, (12, 3))], axis=1)
    model.measured = {"medium": medium}
    with_medium = save_model(model, tmp_path / "box.model.zip")
    model.measured = {}
    return with_medium, save_model(model, tmp_path / "old.model.zip")


def test_render_draws_a_walked_kind_by_name_and_refuses_in_one_line(box_model, tmp_path):
    """``render --transport KIND``: a walked kind (registered small here) draws a finite, non-negative picture
    whose summary names it; a model without a medium, --paper beside it and an unknown kind each get one
    line and exit status 2."""
    import json

    from typer.testing import CliRunner

    from helpers import error_line
    from translucency.cli.app import app
    from translucency.transport.kinds import TRANSPORTS, register_transport
    from translucency.transport.walk import WalkedTransport

    path, old = box_model
    register_transport(WalkedTransport(name="walked-small", photons=4000))
    try:
        res = CliRunner().invoke(
            app,
            ["render", str(path), "--out", str(tmp_path / "r"), "--transport", "walked-small",
             "--light", "directional@back,10", "--resolution", "32", "24", "--json", "-q"],
        )  # fmt: skip
        assert res.exit_code == 0, res.output
        summary = json.loads(res.stdout)
        from translucency.mitsuba import mitsuba as mi_of

        picture = np.array(mi_of().Bitmap(str(tmp_path / "r" / "ours.exr")))
        assert np.isfinite(picture).all() and picture.min() >= 0 and picture.max() > 0
        assert summary["command"] == "render"
    finally:
        del TRANSPORTS["walked-small"]
    line = error_line(["render", old, "--out", tmp_path / "o", "--transport", "walked"])
    assert (
        line
        == "error: transport walked: the model holds no estimated medium (fit it again with this version)"
    )
    line = error_line(["render", path, "--out", tmp_path / "p", "--transport", "walked", "--paper"])
    assert line == "error: --paper draws the paper's model; --transport walked: choose one"
    line = error_line(["render", path, "--out", tmp_path / "n", "--transport", "nonsense"])
    assert line.startswith("error: transport: 'nonsense' is not one of default, paper, walked")
