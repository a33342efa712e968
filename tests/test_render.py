"""Rendering fitted objects: the sparse transport against a plain double loop, irradiance and shadows,
bad lights and cameras, and the Mitsuba picture of per-vertex radiance."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from scipy.spatial import cKDTree

from helpers import random_exponential_model
from translucency import TranslucencyError
from translucency.geometry import tangent_frames, vertex_areas
from translucency.mitsuba import mesh_scene
from translucency.model import ExponentialModel, VertexAlpha
from translucency.render import Camera, DirectionalLight, PointLight, parse_light, render_vertex_radiance
from translucency.render.picture import coverage
from translucency.transport import default_radius, relight_vertices, transport_matrices, vertex_irradiance


@pytest.fixture(scope="module")
def ball():
    return trimesh.creation.icosphere(2, radius=5.0)


#: the profiles of the rendering tests: a steep and a shallow term
TWO_TERMS = (((2.0, 3.0), (0.2, 0.5)), ((0.3, 0.6), (0.01, 0.05)))


def _model_on(mesh, rng, points):
    return random_exponential_model(rng, geometry="mesh", mesh=mesh, points=points, terms=TWO_TERMS)


def test_transport_equals_a_plain_double_loop(ball):
    """T E against Σ_i A_i E_i R_d(x_i, x_o)/π evaluated pair by pair with every vertex an incident point."""
    rng = np.random.default_rng(1)
    V = len(ball.vertices)
    model = _model_on(ball, rng, np.arange(V))
    r_min = 0.3
    mats = transport_matrices(model, ball, radius=4.0, r_min=r_min, far_field=False)  # the near sum alone
    E = rng.uniform(0, 1, V)
    L = relight_vertices(mats, E)
    area = vertex_areas(ball)
    ref = np.zeros((V, 3))
    for o in range(V):
        for i in range(V):
            r = np.linalg.norm(ball.vertices[o] - ball.vertices[i])
            if r > 4.0:
                continue
            prof = (model.c[i, 0, 0] * np.exp(model.d[i, 0, 0] * max(r, r_min))).sum() * model.colour_scale[i]
            ref[o] += area[i] * E[i] * model.alpha.values[o] * prof / np.pi
    np.testing.assert_allclose(L, ref, rtol=2e-5)


def test_three_channels_on_one_set_of_pairs_against_a_plain_loop():
    """A fall-off per channel: three matrices on the same pairs go through one pass (the pairs read once,
    three values each), three on different pairs through one product each; both are L_c = Σ_i T_c,oi E_i,c
    summed pair by pair."""
    import scipy.sparse as sp

    from translucency.transport.relight import Transport

    rng = np.random.default_rng(7)
    V = 60
    pattern = sp.random(V, V, density=0.2, random_state=3, format="csr", dtype=np.float32)
    shared = []
    for _ in range(3):
        T = pattern.copy()
        T.data = rng.uniform(0, 1, T.nnz).astype(np.float32)
        shared.append(T)
    apart = [sp.random(V, V, density=0.2, random_state=s, format="csr", dtype=np.float32) for s in (4, 5, 6)]
    E = rng.uniform(0, 1, (V, 3)).astype(np.float32)
    for matrices, one in ((shared, True), (apart, False)):
        transport = Transport(matrices=matrices)
        assert transport.one_pattern is one
        ref = np.zeros((V, 3))
        for c, T in enumerate(matrices):
            dense = T.toarray()
            for o in range(V):
                for i in range(V):
                    ref[o, c] += dense[o, i] * E[i, c]
        np.testing.assert_allclose(relight_vertices(transport, E), ref, rtol=1e-5)


def test_profiles_are_blended_not_parameters(ball):
    """Between incident points the profile is the weighted mean of their profiles (no new exponential)."""
    from translucency.transport.parameters import vertex_parameters

    rng = np.random.default_rng(2)
    model = _model_on(ball, rng, np.array([0, 5, 9, 40]))
    c, d, s = vertex_parameters(model, ball.vertices)
    r = np.linspace(0.5, 8, 20)
    for v in (0, 77, 120):
        blend = (c[v, 0][None] * np.exp(d[v, 0][None] * r[:, None])).sum(1)
        own = [(model.c[j, 0, 0] * np.exp(model.d[j, 0, 0] * r[:, None])).sum(1) for j in range(4)]
        assert (
            blend.min() >= min(o.min() for o in own) * 0.999 and (blend <= np.max(own, axis=0) * 1.001).all()
        )
    assert np.allclose(
        (c[0, 0][None] * np.exp(d[0, 0][None] * r[:, None])).sum(1),
        (model.c[0, 0, 0] * np.exp(model.d[0, 0, 0] * r[:, None])).sum(1),
    )


def test_irradiance_cosine_and_shadows():
    box = trimesh.creation.box(extents=(10, 10, 10))
    scene = mesh_scene(box)
    E = vertex_irradiance(box, scene, DirectionalLight((0.0, 0.0, -1.0), 2.0))
    n = box.vertex_normals
    np.testing.assert_allclose(E, 2.0 * np.maximum(n[:, 2], 0), rtol=1e-6)
    # a second box between the light and the first one casts a shadow
    two = trimesh.util.concatenate(
        [box, trimesh.creation.box(extents=(30, 30, 1)).apply_translation((0, 0, 20))]
    )
    shadowed = vertex_irradiance(box, mesh_scene(two), DirectionalLight((0.0, 0.0, -1.0), 2.0))
    assert shadowed.max() == 0
    p = vertex_irradiance(box, scene, PointLight((0.0, 0.0, 50.0), 100.0))
    top = np.argmax(box.vertices[:, 2] + 0 * box.vertices[:, 0])
    d = np.array([0, 0, 50.0]) - box.vertices[top]
    assert p[top] == pytest.approx(100.0 * (d / np.linalg.norm(d)) @ n[top] / (d @ d), rel=1e-6)


def test_bad_lights_and_cameras(ball):
    with pytest.raises(TranslucencyError, match="inside the object"):
        vertex_irradiance(ball, mesh_scene(ball), PointLight((0.0, 0.0, 0.0)))
    with pytest.raises(TranslucencyError, match="light:"):
        parse_light("laser:1,2")
    away = Camera(origin=(0.0, 0.0, 100.0), target=(0.0, 0.0, 200.0), up=(0, 1, 0), width=32, height=24)
    with pytest.raises(TranslucencyError, match="sees nothing"):
        coverage(ball, away)


def test_vertex_radiance_picture(ball):
    """A uniform radiance per vertex draws as that radiance wherever the object is seen."""
    cam = Camera.looking_at(ball, width=48, height=36)
    img = render_vertex_radiance(ball, np.tile([0.2, 0.4, 0.8], (len(ball.vertices), 1)), cam, spp=4)
    seen = coverage(ball, cam)
    assert 0.05 < seen.mean() < 0.9
    inner = img[
        seen & np.roll(seen, 1, 0) & np.roll(seen, -1, 0) & np.roll(seen, 1, 1) & np.roll(seen, -1, 1)
    ]
    np.testing.assert_allclose(inner, np.tile([0.2, 0.4, 0.8], (len(inner), 1)), rtol=1e-4)
    assert img[~seen].max() < 0.8
    # a prepared picture repaints: a second radiance replaces the first, pixel for pixel
    from translucency.render import VertexPicture

    pic = VertexPicture(ball, cam, spp=4)
    pic.draw(np.ones((len(ball.vertices), 3)))
    np.testing.assert_allclose(
        pic.draw(np.tile([0.2, 0.4, 0.8], (len(ball.vertices), 1))), img, rtol=1e-5, atol=1e-7
    )
    with pytest.raises(TranslucencyError, match="per vertex"):
        pic.draw(np.ones((3, 3)))


def test_fit_and_render_cli_on_a_mesh(tmp_path):
    from typer.testing import CliRunner

    from translucency.cli.app import app

    runner = CliRunner()
    mesh = tmp_path / "ball.ply"
    trimesh.creation.icosphere(3, radius=6.0).export(mesh)
    data, model = tmp_path / "ball.zarr", tmp_path / "ball.model.zip"
    res = runner.invoke(
        app,
        [
            "acquire",
            "mesh",
            "--out",
            str(data),
            "--mesh",
            str(mesh),
            "--material",
            "homogeneous:marble",
            "--voxel",
            "1",
            "--points",
            "12",
            "--photons",
            "4000",
            "--index-matched",
        ],
    )
    assert res.exit_code == 0, res.output
    res = runner.invoke(app, ["fit", str(data), "--out", str(model)])
    assert res.exit_code == 0, res.output
    res = runner.invoke(
        app,
        [
            "render",
            str(model),
            "--out",
            str(tmp_path / "r"),
            "--resolution",
            "64",
            "48",
            "--reference",
            "--reference-spp",
            "8",
        ],
    )
    assert res.exit_code == 0, res.output
    import json

    fig = json.loads((tmp_path / "r" / "render.json").read_text())
    assert fig["rel_rmse"] < 1.0 and 0 <= fig["flip_mean_object"] < 0.8
    for name in ("ours.exr", "ours.png", "reference.exr", "render.png"):
        assert (tmp_path / "r" / name).stat().st_size > 500
    bad = runner.invoke(app, ["render", str(model), "--light", "point:0,0,0"])
    assert bad.exit_code == 2 and "inside the object" in bad.output
    assert fig["incidence"] == "half-space"  # an index-matched object with measured totals
    from translucency.transport import TransportOptions

    with pytest.raises(TranslucencyError, match="transport: 'oblique' is not one of default, paper"):
        TransportOptions(kind="oblique")


def test_spot_and_environment_irradiance(ball):
    from translucency.render import EnvironmentLight, SpotLight

    scene = mesh_scene(ball)
    pos = (0.0, 0.0, 40.0)
    point = vertex_irradiance(ball, scene, PointLight(pos, 100.0))
    spot = vertex_irradiance(ball, scene, SpotLight(pos, (0.0, 0.0, 0.0), 6.0, 100.0))
    theta = np.degrees(
        np.arccos(
            (np.array(pos) - ball.vertices)[:, 2] / np.linalg.norm(np.array(pos) - ball.vertices, axis=1)
        )
    )
    inner, outer = theta < 0.75 * 6.0 - 0.01, theta > 6.0
    np.testing.assert_allclose(spot[inner], point[inner], rtol=1e-9)
    assert (spot[outer] == 0).all() and inner.any() and outer.any() and (spot <= point + 1e-12).all()
    # a convex object sees the whole sky from every vertex: E = π L exactly
    env = vertex_irradiance(ball, scene, EnvironmentLight(0.3, samples=16))
    np.testing.assert_allclose(env, np.pi * 0.3, rtol=1e-12)
    # under a plate, the box's top sees no sky straight up: less than π L
    box = trimesh.creation.box(extents=(10, 10, 10))
    two = trimesh.util.concatenate(
        [box, trimesh.creation.box(extents=(200, 200, 1)).apply_translation((0, 0, 7))]
    )
    shaded = vertex_irradiance(box, mesh_scene(two), EnvironmentLight(0.3, samples=256))
    top = box.vertex_normals[:, 2] > 0.5
    assert (shaded[top] < 0.5 * np.pi * 0.3).all()
    assert isinstance(parse_light("spot:0,0,40,0,0,0,10"), SpotLight) and isinstance(
        parse_light("env:0.2"), EnvironmentLight
    )


def test_the_skys_irradiance_does_not_depend_on_its_batches(monkeypatch):
    """The sky's rays go in batches (a 338 k-vertex scan in one wavefront held 16 GB): a batch of 7 points
    gives the estimate of one batch for all, bit for bit, with an incidence law held per vertex; and the
    box under a plate keeps its shadow."""
    from translucency.model.incidence import HalfSpaceIncidence
    from translucency.render import EnvironmentLight
    from translucency.render.lights import environment

    box = trimesh.creation.box(extents=(10, 10, 10))
    two = trimesh.util.concatenate(
        [box, trimesh.creation.box(extents=(200, 200, 1)).apply_translation((0, 0, 7))]
    )
    scene, sky = mesh_scene(two), EnvironmentLight(0.3, samples=64)
    law = HalfSpaceIncidence(np.random.default_rng(1).uniform(0.2, 0.8, (len(box.vertices), 3)))
    one = (vertex_irradiance(box, scene, sky), vertex_irradiance(box, scene, sky, incidence=law))
    monkeypatch.setattr(environment, "RAYS_PER_BATCH", 7 * 64)
    many = (vertex_irradiance(box, scene, sky), vertex_irradiance(box, scene, sky, incidence=law))
    for a, b in zip(one, many):
        assert a.shape == b.shape and np.array_equal(a, b)
    assert (one[0][box.vertex_normals[:, 2] > 0.5] < 0.5 * np.pi * 0.3).all()


def _sky_map(path, sun=True):
    """A latitude–longitude map (rows from the map's +Y pole down): a blue-grey sky and an optional sun."""
    from translucency.mitsuba import mitsuba

    H, W = 32, 64
    theta = (np.arange(H) + 0.5) / H * np.pi
    img = np.zeros((H, W, 3), np.float32)
    img[:] = (0.05 + 0.2 * np.clip(np.cos(theta), 0, None))[:, None, None] * np.array([0.6, 0.8, 1.0])
    if sun:
        img[5:8, 40:44] = [60.0, 50.0, 40.0]
    mitsuba().Bitmap(img).write(str(path))
    return path


def test_environment_map_irradiance_matches_mitsuba_direct_lighting(ball, tmp_path):
    """A white diffuse ball under a sky with a sun: ρE/π per vertex, drawn, against Mitsuba's own path
    tracer."""
    from translucency.mitsuba import mitsuba, write_ply
    from translucency.render import EnvironmentLight

    mi = mitsuba()
    light = parse_light(f"env:{_sky_map(tmp_path / 'sky.exr')},2")
    assert isinstance(light, EnvironmentLight) and light.radiance == 2.0
    light = EnvironmentLight(2.0, samples=256, filename=light.filename)
    E = vertex_irradiance(ball, mesh_scene(ball), light)
    assert E.shape == (len(ball.vertices), 3) and np.isfinite(E).all()
    rho = 0.8
    cam = Camera.looking_at(ball, direction=(0.3, -1.0, 0.2), width=64, height=48)
    ours = render_vertex_radiance(ball, rho * E / np.pi, cam, spp=4, light=light)
    write_ply(tmp_path / "ball.ply", np.asarray(ball.vertices), np.asarray(ball.faces))
    ref = np.asarray(
        mi.render(
            mi.load_dict(
                {
                    "type": "scene",
                    "integrator": {"type": "path", "max_depth": 2},
                    "ball": {
                        "type": "ply",
                        "filename": str(tmp_path / "ball.ply"),
                        "bsdf": {"type": "diffuse", "reflectance": rho},
                    },
                    "sky": light.emitter_dict(),
                    "camera": cam.sensor_dict(512),
                }
            ),
            seed=1,
        ),
        dtype=np.float64,
    )
    seen = coverage(ball, cam)
    inner = seen & np.roll(seen, 1, 0) & np.roll(seen, -1, 0) & np.roll(seen, 1, 1) & np.roll(seen, -1, 1)
    ratio = ours[inner].mean(axis=0) / ref[inner].mean(axis=0)
    np.testing.assert_allclose(ratio, 1.0, atol=0.04)
    # the sun's side is the bright side in both (the map's orientation is the same)
    lum_o, lum_r = ours[inner].sum(1), ref[inner].sum(1)
    assert np.corrcoef(lum_o, lum_r)[0, 1] > 0.95
    # behind the object both show the same sky
    np.testing.assert_allclose(ours[~seen].mean(0), ref[~seen].mean(0), rtol=0.05)


def test_uniform_map_is_the_constant_sky(ball, tmp_path):
    from translucency.mitsuba import mitsuba
    from translucency.render import EnvironmentLight

    mitsuba().Bitmap(np.full((16, 32, 3), 0.25, np.float32)).write(str(tmp_path / "flat.exr"))
    E = vertex_irradiance(ball, mesh_scene(ball), EnvironmentLight(1.0, 128, str(tmp_path / "flat.exr")))
    np.testing.assert_allclose(E.mean(axis=0), np.pi * 0.25, rtol=0.015)
    np.testing.assert_allclose(E, np.pi * 0.25, rtol=0.4)


def test_fresnel_factors_against_closed_forms():
    from translucency.model import fresnel_diffuse_reflectance
    from translucency.model.boundary import diffuse_transmittance, fresnel_transmittance

    eta = 1.3
    # normal incidence: 1 − ((η − 1)/(η + 1))²
    np.testing.assert_allclose(fresnel_transmittance(1.0, eta), 1 - ((eta - 1) / (eta + 1)) ** 2, rtol=1e-6)
    assert fresnel_transmittance(0.0, eta) < 1e-6 and fresnel_transmittance(0.7, 1.0) == 1.0
    # cosine-weighted transmittance from outside = η² (1 − F_dr) with Jensen's internal F_dr (reciprocity)
    np.testing.assert_allclose(
        diffuse_transmittance(eta), eta**2 * (1 - fresnel_diffuse_reflectance(eta)), rtol=0.015
    )


def test_bad_environment_maps_and_dielectric_references(ball, tmp_path):
    from translucency.render.reference import render_reference

    with pytest.raises(TranslucencyError, match="does not exist"):
        parse_light(f"env:{tmp_path / 'none.exr'}")
    (tmp_path / "junk.exr").write_text("not an image")
    with pytest.raises(TranslucencyError, match="not a readable environment map"):
        parse_light(f"env:{tmp_path / 'junk.exr'}")
    with pytest.raises(TranslucencyError, match="scale"):
        parse_light(f"env:{_sky_map(tmp_path / 'sky.exr')},x")
    cam = Camera.looking_at(ball, width=16, height=12)
    with pytest.raises(TranslucencyError, match="dielectric object"):
        render_reference(ball, None, PointLight((0.0, 0.0, 40.0)), cam, eta=1.3)


def test_parameters_follow_the_surface_not_the_gap():
    """Two blocks 0.3 mm apart: a vertex on one takes no parameters from the other (geodesic
    neighbours), while straight-line neighbours would mix them; graph distances on a ball
    approximate great-circle arcs."""
    from translucency.transport.parameters import geodesic_neighbours, vertex_parameters

    a = trimesh.creation.box(extents=(10, 10, 2)).subdivide().subdivide()
    b = a.copy().apply_translation((0, 0, 2.3))
    two = trimesh.util.concatenate([a, b])
    top_a = np.flatnonzero(np.isclose(two.vertices[:, 2], 1.0))[:1]  # a vertex on a's upper face
    centre = np.argmin(np.linalg.norm(two.vertices - [0, 0, 1.0], axis=1))
    below = np.argmin(np.linalg.norm(two.vertices - [0, 0, 1.3], axis=1))  # on b, across the gap
    corners = [np.argmin(np.linalg.norm(two.vertices - p, axis=1)) for p in ([5, 5, -1], [-5, -5, -1])]
    pts = np.array([below, *corners, top_a[0]])
    x_i = two.vertices[pts]
    c = np.zeros((len(pts), 1, 1, 1))
    c[:, 0, 0, 0] = [100.0, 1.0, 1.0, 1.0]  # only the point across the gap is bright
    model = ExponentialModel(
        x_i,
        c,
        -np.ones_like(c),
        VertexAlpha(np.ones(len(two.vertices)), two.vertices),
        s_g=np.ones(len(pts)),
        s_b=np.ones(len(pts)),
        frame=tangent_frames(two.vertex_normals[pts]),
    )
    cg = vertex_parameters(model, two, k=2)[0][centre]
    ce = vertex_parameters(model, two.vertices, k=2)[0][centre]
    assert cg.sum() < 2.0 and ce.sum() > 10.0
    # on a ball, graph distance ≈ arc length (edge paths zig-zag: here up to 21 % longer)
    ball = trimesh.creation.icosphere(3, radius=5.0)
    d, i = geodesic_neighbours(ball, np.array([0]), 1, limit=np.inf)
    u = ball.vertices / 5.0
    arc = 5.0 * np.arccos(np.clip(u @ u[0], -1, 1))
    far = arc > 2.0
    chord = np.linalg.norm(ball.vertices - ball.vertices[0], axis=1)
    assert np.all(d[far, 0] >= chord[far]) and np.all(d[far, 0] <= arc[far] * 1.25) and np.all(i == 0)


def test_thickness_and_region_errors():
    """Thickness along −n of a box is its extent across that face; region errors are relative RMSEs."""
    from translucency.render.compare import region_errors, vertex_thickness

    box = trimesh.creation.box(extents=(8.0, 20.0, 30.0)).subdivide().subdivide()
    scene = mesh_scene(box)
    t = vertex_thickness(box, scene)
    n = np.asarray(box.vertex_normals)
    for axis, extent in enumerate((8.0, 20.0, 30.0)):
        face = np.abs(n[:, axis]) > 0.999  # vertices inside a face (not on its edges)
        np.testing.assert_allclose(t[face], extent, rtol=1e-3)
    cam = Camera.looking_at(box, width=48, height=36)
    seen = coverage(box, cam)
    E = vertex_irradiance(box, scene, DirectionalLight((0.0, 0.0, -1.0)))  # from above: only the top is lit
    ref = np.where(seen[..., None], 2.0, 0.0) * np.ones(3)
    regions = region_errors(box, scene, cam, E, ref, 1.1 * ref, seen)
    assert regions["all"]["pixels"] == seen.sum() and regions["thin"]["pixels"] > 0  # the 8 mm sides
    assert (
        regions["thick"]["pixels"] > 0
        and regions["shadow edge"]["pixels"] > 0
        and regions["unlit"]["pixels"] > 0
    )
    for r in regions.values():
        assert r["rel_rmse"] == pytest.approx(0.1, rel=1e-9)


def test_default_radius_shrinks_where_vertices_crowd_and_a_given_one_is_refused():
    """A mesh whose vertices crowd in one part (a cap subdivided twice): the default radius, which
    assumes them evenly spread, would hold more pairs than allowed; the transport shrinks it until they
    fit.  A radius the user gave is refused
    with one line that says so."""
    rng = np.random.default_rng(3)
    ball = trimesh.creation.icosphere(3, radius=5.0)
    for _ in range(2):
        top = np.where(ball.vertices[ball.faces].mean(axis=1)[:, 2] > 3.5)[0]
        ball = trimesh.Trimesh(*trimesh.remesh.subdivide(ball.vertices, ball.faces, face_index=top))
    V = len(ball.vertices)
    model = random_exponential_model(
        rng, geometry="mesh", mesh=ball, points=np.arange(0, V, 7), terms=TWO_TERMS
    )
    limit = 40 * V
    wanted = default_radius(model, ball, max_pairs=limit)
    pairs = 2 * len(cKDTree(ball.vertices).query_pairs(wanted)) + V
    assert pairs > limit  # the even-spread assumption underestimates here
    T = transport_matrices(model, ball, max_pairs=limit)
    assert T.matrices[0].nnz <= limit
    with pytest.raises(TranslucencyError, match=r"radius: .* vertex pairs .*lower --radius"):
        transport_matrices(model, ball, radius=wanted, max_pairs=limit)
