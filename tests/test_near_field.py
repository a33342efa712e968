"""Objects whose near field agrees with their data (issue 12): barycentric tally, the measured own area and
total carried by the model file, the renderer's kernel, and models that render without their data set."""

import json

import numpy as np
import pytest
import trimesh
from typer.testing import CliRunner

from translucency import load_model, save_model
from translucency.acquire.mesh import acquire_mesh, object_volume, splat_exits
from translucency.cli.app import app
from translucency.fit.mesh import fit_mesh
from translucency.geometry import same_triangles, vertex_areas
from translucency.io.mesh_dataset import open_mesh_dataset
from translucency.transport.matrices import transport_matrices
from translucency.transport.relight import relight_vertices

runner = CliRunner()


def test_splat_shares_each_exit_by_barycentric_weight():
    tri = trimesh.Trimesh([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], [[0, 1, 2], [1, 3, 2]], process=False)
    pos = np.array([[0.0, 0, 0], [1 / 3, 1 / 3, 0], [0.5, 0.5, 0], [1.0, 1.0, 0]])
    counts = splat_exits(tri, np.array([0, 0, 1, 1]), np.array([0, 0, 1, 1]), pos, 2)
    np.testing.assert_allclose(counts[0], [1 + 1 / 3, 1 / 3, 1 / 3, 0], atol=1e-12)
    np.testing.assert_allclose(counts[1], [0, 0.5, 0.5, 1.0], atol=1e-12)
    assert counts.sum() == pytest.approx(4.0)  # every exit counted once


def test_no_photon_is_lost_at_a_pole():
    """A beam into an icosphere's pole flies first along the axis through the opposite pole (a vertex): the
    ray can slip between triangles; the photons must still scatter and leave, not be counted as escaped."""
    from translucency.acquire.mesh_walk import EXIT, KILLED, mesh_random_walk
    from translucency.mitsuba import mesh_scene

    ball = trimesh.creation.icosphere(3, radius=5.0)
    pole = int(np.argmin(ball.vertices[:, 2]))
    vol = object_volume("homogeneous:marble", ball, 1.0)
    res = mesh_random_walk(
        mesh_scene(ball),
        ball.bounds,
        vol,
        1,
        ball.vertices[[pole]],
        ball.vertex_normals[[pole]],
        2000,
        index_matched=True,
    )
    assert (res.code == KILLED).sum() == 0 and (res.code == EXIT).mean() > 0.9


@pytest.fixture(scope="module")
def ball_fit(tmp_path_factory):
    root = tmp_path_factory.mktemp("ball")
    ball = trimesh.creation.icosphere(3, radius=5.0)
    vol = object_volume("homogeneous:marble", ball, 1.0)
    data = acquire_mesh(
        ball, vol, root / "ball.zarr", n_points=8, photons=6000, chunk_points=8, index_matched=True
    )
    return ball, data, fit_mesh(data, "iso")


def test_the_model_carries_what_was_measured(ball_fit):
    ball, data, fit = ball_fit
    ds = open_mesh_dataset(data)
    R, area, inc = ds["R_d"], ds["vertex_area"].astype(float), ds["incident"]
    m = fit.model
    np.testing.assert_allclose(m.measured["own"], R[np.arange(len(inc)), inc], rtol=1e-6)
    np.testing.assert_allclose(m.measured["total"], np.einsum("pvc,v->pc", R, area), rtol=1e-5)
    assert (m.measured["total"] <= 1.0).all() and m.faces.shape == (len(ball.faces), 3)


def test_kernel_of_an_incident_vertex_matches_its_acquisition(ball_fit):
    """Unit power into incident vertex i: π L at i is the measured own-area value, Σ A π L the measured
    total."""
    ball, _, fit = ball_fit
    m = fit.model
    T = transport_matrices(m, ball)
    area = vertex_areas(ball)
    src = np.argmin(np.linalg.norm(ball.vertices[:, None] - m.x_i[None], axis=2), axis=0)
    for p, v in enumerate(src[:4]):
        E = np.zeros(len(ball.vertices))
        E[v] = 1.0 / area[v]  # unit power
        M = np.pi * relight_vertices(T, E)  # exitance (V, 3)
        np.testing.assert_allclose(M[v], m.measured["own"][p], rtol=2e-3)
        np.testing.assert_allclose(area @ M, m.measured["total"][p], rtol=2e-3)


def test_uniform_light_total_matches_photon_transport(ball_fit, tmp_path):
    """An independent acquisition (other seed, more points) predicts the exitance under uniform light."""
    ball, _, fit = ball_fit
    T = transport_matrices(fit.model, ball)
    area = vertex_areas(ball)
    rendered = area @ (np.pi * relight_vertices(T, np.ones(len(ball.vertices)))) / area.sum()
    vol = object_volume("homogeneous:marble", ball, 1.0)
    other = open_mesh_dataset(
        acquire_mesh(ball, vol, tmp_path / "o.zarr", n_points=24, photons=3000, seed=9, index_matched=True)
    )
    truth = np.einsum("pvc,v->pc", other["R_d"], other["vertex_area"].astype(float)).mean(axis=0)
    np.testing.assert_allclose(rendered, truth, rtol=0.02)


def test_a_model_renders_after_its_data_set_is_deleted(ball_fit, tmp_path):
    import shutil

    ball, data, fit = ball_fit
    copy = tmp_path / "data.zarr"
    shutil.copytree(data, copy)
    path = save_model(fit.model, tmp_path / "ball.model.zip", meta=fit.metadata(copy.resolve()))
    back = load_model(path)
    assert same_triangles(back.faces, fit.model.faces)  # (in the mesh codec's order)
    np.testing.assert_allclose(back.measured["own"], fit.model.measured["own"], rtol=1e-6)
    shutil.rmtree(copy)
    res = runner.invoke(app, ["render", str(path), "--out", str(tmp_path / "r"), "--resolution", "48", "36"])
    assert res.exit_code == 0, res.output
    assert json.loads((tmp_path / "r" / "render.json").read_text())["vertices"] == len(ball.vertices)
    assert (tmp_path / "r" / "ours.exr").stat().st_size > 500


def test_fits_of_noisy_mesh_data_stay_physical(tmp_path):
    """500 photons per point: no profile reflects more than it receives or spreads beyond the object."""
    from translucency.model import check_physics

    ball = trimesh.creation.icosphere(3, radius=8.0)
    vol = object_volume("skin", ball, 1.0, seed=2)
    data = acquire_mesh(ball, vol, tmp_path / "n.zarr", n_points=24, photons=500, seed=5, index_matched=True)
    fit = fit_mesh(data, "iso")
    check = check_physics(fit.model)
    assert check.ok, check.describe()
    assert (check.radius <= np.linalg.norm(ball.extents)).all() and (check.total <= 1.0 + 1e-9).all()


@pytest.mark.slow
def test_skin_under_a_spot_renders_close_to_its_reference(tmp_path):
    """Issue 12's failing case in kind (a new material and a spot light on a figurine; the user's cow is
    not shipped): within 0.25 of a measured-noise volpath reference (the cow at 128 × 4000: 0.17)."""
    from translucency.acquire.objects import make_pig
    from translucency.mitsuba import mesh_scene
    from translucency.render.camera import Camera
    from translucency.render.compare import compare
    from translucency.render.lights import parse_light
    from translucency.render.picture import VertexPicture, coverage
    from translucency.render.reference import converged_reference
    from translucency.transport.irradiance import vertex_irradiance

    pig = make_pig()
    vol = object_volume("skin", pig, 1.0, seed=3)
    data = acquire_mesh(
        pig, vol, tmp_path / "p.zarr", n_points=96, photons=3000, seed=3, chunk_points=32, index_matched=True
    )
    fit = fit_mesh(data, "iso")
    light = parse_light("spot:-60,70,90,0,0,0,25,3e4")
    camera = Camera.looking_at(pig, (-1.0, 1.2, 0.6), 96, 72)
    mask = coverage(pig, camera)
    E = vertex_irradiance(pig, mesh_scene(pig), light)
    ours = VertexPicture(pig, camera, spp=16).draw(relight_vertices(transport_matrices(fit.model, pig), E))
    reference, info = converged_reference(pig, vol, light, camera, mask, spp=96, cache=tmp_path)
    cmp = compare(reference, ours, mask)
    assert cmp["rel_rmse"] < 0.25 + info["noise"], (cmp["rel_rmse"], info["noise"])
    assert ours[mask].mean() == pytest.approx(reference[mask].mean(), rel=0.1)


def _ripple(mesh, x, sweeps=8):
    """x over its mean of the neighbours within a few rings (graph smoothing), minus 1: the mesh-scale
    ripple of a per-vertex field."""
    e = mesh.edges_unique
    V = len(mesh.vertices)
    import scipy.sparse as sp

    A = sp.coo_matrix((np.ones(2 * len(e)), (np.r_[e[:, 0], e[:, 1]], np.r_[e[:, 1], e[:, 0]])), shape=(V, V))
    A = A.tocsr()
    deg = np.asarray(A.sum(axis=1)).ravel()
    smooth = np.asarray(x, dtype=np.float64).copy()
    for _ in range(sweeps):
        smooth = 0.5 * smooth + 0.5 * (A @ smooth) / deg
    return x / smooth - 1.0


def test_uniform_light_shows_no_rings_of_a_marching_cubes_mesh(tmp_path):
    """Issue 24's rings: on a marching-cubes mesh the cell areas jump between neighbours (terraces), and a
    transport balanced by columns only made each receiver's exitance jump with them (rings on the pig's
    flank).  Under uniform irradiance a homogeneous ball's exitance is smooth: its ripple must stay at the
    per-mille level and be unrelated to the cell areas; the unbalanced transport shows what is caught."""
    from skimage.measure import marching_cubes

    h = 0.5  # mm, the grid
    ax = np.arange(-6.0, 6.0 + h, h)
    X, Y, Z = np.meshgrid(ax, ax, ax, indexing="ij")
    verts, faces, _, _ = marching_cubes(np.sqrt(X**2 + Y**2 + Z**2) - 5.0, level=0.0, spacing=(h,) * 3)
    ball = trimesh.Trimesh(verts - 6.0, faces, process=True)
    ball.update_faces(ball.nondegenerate_faces())
    ball.remove_unreferenced_vertices()
    if ball.volume < 0:
        ball.invert()
    vol = object_volume("homogeneous:marble", ball, 1.0)
    data = acquire_mesh(ball, vol, tmp_path / "mc.zarr", n_points=8, photons=4000, index_matched=True)
    model = fit_mesh(data, "iso").model
    area = vertex_areas(ball)
    assert np.std(_ripple(ball, area)) > 0.15  # the mesh has the terraces this test is about
    one = np.ones(len(ball.vertices))
    ripple = {}
    for balanced in (True, False):
        L = relight_vertices(transport_matrices(model, ball, balance_rows=balanced), one)[:, 1]
        ripple[balanced] = _ripple(ball, L)
    print({k: float(np.std(v)) for k, v in ripple.items()})  # the figures, with -s
    assert np.std(ripple[True]) < 0.003, np.std(ripple[True])
    assert abs(np.corrcoef(ripple[True], _ripple(ball, area))[0, 1]) < 0.3
    assert np.std(ripple[False]) > 3 * np.std(ripple[True])  # the rings this test would see
