"""Objects for issue 5: the procedural pig and reading a user's mesh."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import trimesh

from translucency import TranslucencyError
from translucency.acquire.objects import make_pig, pig_sdf
from translucency.io.mesh import load_mesh


def test_pig_is_a_closed_figurine_of_the_right_size():
    pig = make_pig()
    assert pig.is_watertight and pig.is_winding_consistent and pig.volume > 0
    assert 20_000 <= len(pig.vertices) <= 50_000
    assert pig.euler_number == 2  # one closed surface of genus 0
    length, width, height = pig.extents
    assert 75 < length < 90 and 30 < width < 40 and 40 < height < 55
    # the surface is the zero set of the field: vertices lie on it to a fraction of the grid
    assert np.abs(pig_sdf(pig.vertices)).max() < 0.3
    # normals point out: a step along the normal leaves the pig
    assert (pig_sdf(pig.vertices + 0.5 * pig.vertex_normals) > 0).mean() > 0.99


def test_load_mesh_scales_and_checks(tmp_path):
    p = tmp_path / "ball.obj"
    trimesh.creation.icosphere(3, radius=1.0).export(p)
    m = load_mesh(p, scale_mm=10.0)
    assert m.is_watertight and m.extents[0] == pytest.approx(20.0, rel=1e-6)
    assert m.volume == pytest.approx(4 / 3 * np.pi * 1000, rel=0.02)


def test_load_mesh_refuses_open_and_missing(tmp_path):
    ball = trimesh.creation.icosphere(3)
    keep = np.ones(len(ball.faces), bool)
    keep[:40] = False  # a large hole that fill_holes cannot close
    open_mesh = trimesh.Trimesh(ball.vertices, ball.faces[keep], process=False)
    p = tmp_path / "open.ply"
    open_mesh.export(p)
    with pytest.raises(TranslucencyError, match="not closed"):
        load_mesh(p)
    with pytest.raises(TranslucencyError, match="no such mesh file"):
        load_mesh(tmp_path / "none.obj")
    bad = tmp_path / "junk.obj"
    bad.write_text("this is not a mesh\n")
    with pytest.raises(TranslucencyError, match="junk.obj"):
        load_mesh(bad)


def test_load_mesh_repairs_small_defects_with_a_warning(tmp_path):
    ball = trimesh.creation.icosphere(2)
    faces = np.vstack([ball.faces[1:], [[0, 0, 1]]])  # one triangle missing, one degenerate
    p = tmp_path / "dented.ply"
    trimesh.Trimesh(ball.vertices, faces, process=False).export(p)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        m = load_mesh(p)
    assert m.is_watertight
    text = " ".join(str(w.message) for w in caught)
    assert "degenerate" in text and "holes were filled" in text


def _fraction_z(a, b, n):
    """z-score of the difference of two binomial fractions from n trials each."""
    p = (a + b) / 2
    return (a - b) / np.sqrt(2 * p * (1 - p) / n)


@pytest.mark.parametrize("index_matched", [False, True])
def test_mesh_walk_in_a_box_matches_the_slab_walk(index_matched):
    """The same slab as a triangle mesh traced by Mitsuba and as the analytic box: same transport."""
    from translucency.acquire.mesh_walk import EXIT, mesh_random_walk
    from translucency.acquire.samples import make_sample
    from translucency.acquire.transport import OTHER_FACE, TOP, random_walk
    from translucency.mitsuba import mesh_scene

    vol = make_sample("marble", (8.0, 8.0, 4.0), 0.25, seed=2)
    W, H, T = vol.size_mm
    box = trimesh.creation.box(extents=(W, H, T))
    box.apply_translation((W / 2, H / 2, -T / 2))
    N = 100_000
    r = mesh_random_walk(
        mesh_scene(box),
        box.bounds,
        vol,
        1,
        np.array([[W / 2, H / 2, 0.0]]),
        np.array([[0.0, 0.0, 1.0]]),
        N,
        seed=11,
        index_matched=index_matched,
    )
    s = random_walk(vol, 1, np.array([[W / 2, H / 2]]), N, seed=12, index_matched=index_matched)
    top_mesh = ((r.code == EXIT) & (np.abs(r.position[:, 2]) < 1e-3)).mean()
    assert abs(_fraction_z((r.code == EXIT).mean(), np.isin(s.code, [TOP, OTHER_FACE]).mean(), N)) < 4
    assert abs(_fraction_z(top_mesh, (s.code == TOP).mean(), N)) < 4
    if not index_matched:
        assert abs(_fraction_z((r.code == -1).mean(), (s.code == -1).mean(), N)) < 4
    else:
        assert (r.code == -1).sum() == 0
    assert (r.code == 4).sum() == 0  # no photon escaped through a crack


def test_an_oblique_beam_crosses_a_clear_sheet_along_its_direction():
    """A beam entering a 1 mm sheet of pure absorber (σ_a = 0.5 mm⁻¹) at 60° from the normal: every photon
    that leaves does so on the far face, L = T / cos 60° = 2 mm along the beam from the entry, with
    probability e^{−σ_a L} (Beer–Lambert), and its recorded path length is L."""
    from translucency.acquire.mesh_walk import EXIT, mesh_random_walk
    from translucency.acquire.volume import Volume
    from translucency.mitsuba import mesh_scene

    sheet = trimesh.creation.box(extents=(20.0, 20.0, 1.0))
    vol = Volume.homogeneous((4, 40, 40), 0.5, [0.0] * 3, [0.5] * 3, 0.0, 1.0)
    theta = np.radians(60.0)
    d = np.array([[np.sin(theta), 0.0, -np.cos(theta)]])
    N = 100_000
    r = mesh_random_walk(
        mesh_scene(sheet), sheet.bounds, vol, 0, np.array([[0.0, 0.0, 0.5]]), np.array([[0.0, 0.0, 1.0]]), N,
        seed=4, index_matched=True, incoming=d,
    )  # fmt: skip
    out = r.code == EXIT
    p = np.exp(-0.5 * 2.0)
    assert abs(out.mean() - p) < 4 * np.sqrt(p * (1 - p) / N)
    assert np.allclose(r.position[out], [np.tan(theta), 0.0, -0.5], atol=5e-3)  # (less the ray offset)
    assert np.allclose(r.length[out], 2.0, atol=5e-3)


def test_an_oblique_beam_is_reflected_by_fresnel_and_refracted_by_snell():
    """The same sheet at η = 1.5: a beam at 60° is reflected with Fresnel's share F(60°) (0.0918, the
    closed form of unpolarised Fresnel) and refracted to θ_t = asin(sin 60° / 1.5); the photons that cross
    straight through leave the far face at x = T tan θ_t after L = T / cos θ_t, with probability
    (1 − F) e^{−σ_a L} (1 − F') (F' = F by Stokes' relations at the far face)."""
    from translucency.acquire.mesh_walk import EXIT, mesh_random_walk
    from translucency.acquire.volume import Volume
    from translucency.mitsuba import mesh_scene

    sheet = trimesh.creation.box(extents=(20.0, 20.0, 1.0))
    vol = Volume.homogeneous((4, 40, 40), 0.5, [0.0] * 3, [0.5] * 3, 0.0, 1.5)
    theta = np.radians(60.0)
    theta_t = np.arcsin(np.sin(theta) / 1.5)
    c, ct = np.cos(theta), np.cos(theta_t)  # Fresnel's unpolarised reflectance, written out
    F = 0.5 * (((c - 1.5 * ct) / (c + 1.5 * ct)) ** 2 + ((1.5 * c - ct) / (1.5 * c + ct)) ** 2)
    d = np.array([[np.sin(theta), 0.0, -np.cos(theta)]])
    N = 200_000
    r = mesh_random_walk(
        mesh_scene(sheet), sheet.bounds, vol, 0, np.array([[0.0, 0.0, 0.5]]), np.array([[0.0, 0.0, 1.0]]), N,
        seed=5, incoming=d,
    )  # fmt: skip
    spec = (r.code == -1).mean()
    assert abs(spec - F) < 4 * np.sqrt(F * (1 - F) / N)
    straight = (r.code == EXIT) & (np.abs(r.position[:, 0] - np.tan(theta_t)) < 5e-3) & (r.position[:, 2] < 0)
    L = 1.0 / ct
    p = (1 - F) * np.exp(-0.5 * L) * (1 - F)
    assert abs(straight.mean() - p) < 4 * np.sqrt(p * (1 - p) / N)
    assert np.allclose(r.length[straight], L, atol=5e-3)


def test_mesh_walk_conserves_energy_in_a_non_absorbing_sphere():
    from translucency.acquire.mesh_walk import EXIT, mesh_random_walk
    from translucency.acquire.volume import Volume
    from translucency.mitsuba import mesh_scene

    sphere = trimesh.creation.icosphere(4, radius=3.0)
    vol = Volume.homogeneous((24, 24, 24), 0.25, [2.0] * 3, [0.0] * 3, 0.0, 1.4)
    top = int(np.argmax(sphere.vertices[:, 2]))
    r = mesh_random_walk(
        mesh_scene(sphere),
        sphere.bounds,
        vol,
        0,
        sphere.vertices[[top]],
        sphere.vertex_normals[[top]],
        40_000,
        seed=3,
    )
    # every photon leaves (diffusely or by Fresnel reflection at entry); cracks lose at most a few
    assert (r.code == 3).sum() == 0
    assert ((r.code == EXIT) | (r.code == -1)).mean() > 1 - 2e-4
    # exits lie on the sphere
    out = r.position[r.code == EXIT]
    assert np.abs(np.linalg.norm(out, axis=1) - 3.0).max() < 0.02


def _interface_chain(F: float, start: int, n: int = 4) -> tuple[float, float]:
    """A photon between plane interfaces 1..n (each reflecting F at normal incidence), moving right just
    past interface ``start``: the chances it finally leaves to the left of 1 and to the right of n.
    A plain Markov chain: x[k, d] = P(escape right | moving in d towards interface k)."""
    # unknowns: moving right towards k (k = 2..n), moving left towards k (k = 1..n-1)
    right = {k: i for i, k in enumerate(range(2, n + 1))}
    left = {k: len(right) + i for i, k in enumerate(range(1, n))}
    A = np.eye(len(right) + len(left))
    b = np.zeros(len(A))
    for k, i in right.items():  # at k: through (on right, or out at n), or back left towards k-1
        if k == n:
            b[i] += 1 - F
        else:
            A[i, right[k + 1]] -= 1 - F
        A[i, left[k - 1]] -= F
    for k, i in left.items():  # at k: through (on left, or out at 1), or back right towards k+1
        if k > 1:
            A[i, left[k - 1]] -= 1 - F
        A[i, right[k + 1]] -= F
    p_right = float(np.linalg.solve(A, b)[right[start + 1]])
    return 1.0 - p_right, p_right


@pytest.mark.parametrize("eta", [1.0, 1.5])
def test_reentry_carries_light_across_a_gap_into_the_next_part(eta):
    """Two boxes 2 mm apart, a clear medium (no collision), a beam entering the first along x: with
    re-entry every photon crosses the gap and leaves through the second box's far face, in the shares a
    plain chain of four Fresnel interfaces at normal incidence gives; without it, it leaves at the first
    box's far face."""
    from translucency.acquire.mesh_walk import EXIT, mesh_random_walk
    from translucency.acquire.volume import Volume
    from translucency.mitsuba import mesh_scene

    a = trimesh.creation.box(bounds=[[0.0, 0.0, 0.0], [10.0, 6.0, 6.0]])
    b = trimesh.creation.box(bounds=[[12.0, 0.0, 0.0], [22.0, 6.0, 6.0]])
    pair = trimesh.util.concatenate([a, b])
    vol = Volume.homogeneous((6, 6, 22), 1.0, [0.0] * 3, [1e-7] * 3, 0.0, eta)
    N = 40_000
    runs = {
        reentry: mesh_random_walk(
            mesh_scene(pair),
            pair.bounds,
            vol,
            0,
            np.array([[0.0, 3.0, 3.0]]),
            np.array([[-1.0, 0.0, 0.0]]),
            N,
            seed=5,
            index_matched=eta == 1.0,
            reentry=reentry,
        )  # fmt: skip
        for reentry in (False, True)
    }
    F = ((eta - 1) / (eta + 1)) ** 2
    for reentry, r in runs.items():
        assert (r.code == 4).sum() == 0 and set(np.unique(r.code)) <= {-1, EXIT}
        x = r.position[r.code == EXIT, 0]
        faces = [np.isclose(x, v, atol=1e-3) for v in (0.0, 10.0, 22.0)]
        assert np.all(faces[0] | faces[1] | faces[2])  # only through the faces the beam's line crosses
        entered = (r.code != -1).sum()
        shares = [f.sum() / entered for f in faces]
        left, right = _interface_chain(F, 1, n=4 if reentry else 2)
        expect = [left, 0.0, right] if reentry else [left, right, 0.0]
        for got, want in zip(shares, expect):
            sigma = np.sqrt(max(want * (1 - want), 1e-6) / entered)
            assert abs(got - want) <= 4 * sigma + 1e-9, (shares, expect)


def test_reentry_changes_nothing_on_a_convex_mesh_and_keeps_every_photon():
    """On a sphere no ray from the surface outwards meets it again: with re-entry the walk is the same bit
    for bit (an escaping photon draws no random number); between two close spheres every photon of a
    non-absorbing medium still leaves (none lost in the air), some through the other sphere."""
    from translucency.acquire.mesh_walk import EXIT, mesh_random_walk
    from translucency.acquire.volume import Volume
    from translucency.mitsuba import mesh_scene

    sphere = trimesh.creation.icosphere(3, radius=3.0)
    vol = Volume.homogeneous((14, 14, 14), 0.5, [1.5] * 3, [0.05] * 3, 0.0, 1.4)
    top = int(np.argmax(sphere.vertices[:, 2]))
    N = 30_000
    r0, r1 = (
        mesh_random_walk(
            mesh_scene(sphere),
            sphere.bounds,
            vol,
            0,
            sphere.vertices[[top]],
            sphere.vertex_normals[[top]],
            N,
            seed=1,
            reentry=re,
        )  # fmt: skip
        for re in (False, True)
    )
    assert np.array_equal(r0.code, r1.code) and np.array_equal(r0.position, r1.position)
    assert (r0.code == EXIT).mean() > 0.5

    pair = trimesh.util.concatenate([sphere, sphere.copy().apply_translation((6.3, 0.0, 0.0))])
    clear = Volume.homogeneous((14, 14, 28), 0.5, [1.5] * 3, [0.0] * 3, 0.0, 1.4)
    side = int(np.argmin(sphere.vertices[:, 0]))
    r = mesh_random_walk(
        mesh_scene(pair), pair.bounds, clear, 0, sphere.vertices[[side]], sphere.vertex_normals[[side]], N,
        seed=3, reentry=True,
    )  # fmt: skip
    assert (r.code == 4).sum() == 0 and ((r.code == EXIT) | (r.code == -1)).all()
    far = r.position[r.code == EXIT, 0] > 3.15  # left through the second sphere
    assert far.mean() > 0.01  # some light crossed the 0.3 mm gap and walked on in the other sphere


def test_unscattered_light_is_kept_apart_from_R_d(tmp_path):
    """A beam crosses a 1 mm sheet (σ_s = 0.8, σ_a = 0.2 mm⁻¹, index-matched) straight through without
    scattering with probability e^{−σ_t T} (Beer–Lambert): that is the ``unscattered`` fraction, within
    its binomial noise, and it is not in R_d. The same photons counted in R_d (the data sets made before)
    give R_d's total exactly the unscattered fraction more (one seed: the same walks)."""
    from translucency.acquire.mesh import acquire_mesh
    from translucency.acquire.volume import Volume
    from translucency.geometry import vertex_areas
    from translucency.io.mesh_dataset import open_mesh_dataset

    sheet = trimesh.creation.box(extents=(16.0, 16.0, 1.0)).subdivide().subdivide()
    centre = int(np.argmin(np.linalg.norm(sheet.vertices - [0.0, 0.0, 0.5], axis=1)))  # the top face's
    order = np.r_[centre, np.delete(np.arange(len(sheet.vertices)), centre)]  # first: the incident point
    sheet = trimesh.Trimesh(sheet.vertices[order], np.argsort(order)[sheet.faces], process=False)
    assert np.allclose(sheet.vertices[0], [0.0, 0.0, 0.5]) and np.allclose(sheet.vertex_normals[0], [0, 0, 1])
    vol = Volume.homogeneous((4, 34, 34), 0.5, [0.8] * 3, [0.2] * 3, 0.0, 1.0)
    N = 20_000
    runs = {
        how: open_mesh_dataset(
            acquire_mesh(
                sheet,
                vol,
                tmp_path / f"{how}.zarr",
                n_points=1,
                photons=N,
                seed=5,
                index_matched=True,
                unscattered=how,
            )
        )  # fmt: skip
        for how in ("apart", "counted")
    }
    apart, counted = runs["apart"], runs["counted"]
    assert "unscattered" not in counted.group and counted.header["request"].get("unscattered") is None
    p = np.exp(-1.0 * 1.0)
    direct = np.asarray(apart.group["unscattered"][...], dtype=np.float64)  # (P, 3)
    assert np.all(np.abs(direct - p) < 4 * np.sqrt(p * (1 - p) / N)), direct
    area = vertex_areas(sheet)
    total = {
        k: np.einsum("pvc,v->pc", np.asarray(d.group["R_d"][...], np.float64), area) for k, d in runs.items()
    }
    assert np.allclose(total["counted"] - total["apart"], direct, atol=1e-5)


def test_acquire_mesh_cli_on_the_pig_and_a_users_mesh(tmp_path):
    import zarr
    from typer.testing import CliRunner

    from translucency.cli.app import app

    runner = CliRunner()
    out = tmp_path / "pig.zarr"
    args = [
        "acquire",
        "mesh",
        "--out",
        str(out),
        "--material",
        "homogeneous:skimmilk",
        "--voxel",
        "2",
        "--points",
        "4",
        "--photons",
        "2000",
        "--chunk",
        "2",
    ]
    res = runner.invoke(app, args)
    assert res.exit_code == 0, res.output
    g = zarr.open_group(str(out), mode="r")
    R, A = g["R_d"][...], g["vertex_area"][...]
    total = (R * A[None, :, None]).sum(axis=1) + g["specular"][...]
    assert R.shape[0] == 4 and g["chunk_done"][...].all()
    assert ((total > 0.3) & (total <= 1.0 + 1e-6)).all()  # light leaves, none is created
    # the light comes out near where it went in
    v, inc = g["vertices"][...], g["incident"][...]
    r = np.linalg.norm(v[None] - v[inc][:, None], axis=2)
    assert ((R[..., 1] * A * (r < 10)).sum(1) > 0.5 * (R[..., 1] * A).sum(1)).all()
    # the same arguments resume (nothing to do), other arguments are refused
    assert runner.invoke(app, args).exit_code == 0
    res = runner.invoke(app, args[:-4] + ["--chunk", "4", "--photons", "2000"])
    assert res.exit_code == 2 and "other arguments" in res.output
    ball = tmp_path / "ball.obj"
    trimesh.creation.icosphere(2, radius=0.5).export(ball)
    res = runner.invoke(
        app,
        [
            "acquire",
            "mesh",
            "--out",
            str(tmp_path / "b.zarr"),
            "--mesh",
            str(ball),
            "--scale",
            "10",
            "--voxel",
            "1",
            "--points",
            "2",
            "--photons",
            "500",
        ],
    )
    assert res.exit_code == 0, res.output
    res = runner.invoke(
        app, ["acquire", "mesh", "--out", str(tmp_path / "c.zarr"), "--mesh", str(tmp_path / "no.obj")]
    )
    assert res.exit_code == 2 and "no such mesh file" in res.output


# slow (78 s of the fast suite, 2,562 vertices at 40 k photons): other per-vertex fits stay fast
@pytest.mark.slow
def test_fit_mesh_per_vertex(tmp_path):
    """Per-vertex isotropic fit of a photon-transport scan of an object, beside the dipole."""
    from translucency.acquire.mesh import acquire_mesh, object_volume
    from translucency.fit.mesh import fit_mesh
    from translucency.model import VertexAlpha

    ball = trimesh.creation.icosphere(4, radius=8.0)
    vol = object_volume("homogeneous:marble", ball, 1.0)
    out = acquire_mesh(ball, vol, tmp_path / "ball.zarr", n_points=6, photons=40_000, chunk_points=6)
    g = __import__("zarr").open_group(str(out), mode="r")
    R, V, inc = g["R_d"][...], g["vertices"][...], g["incident"][...]
    r = np.linalg.norm(V[None] - V[inc][:, None], axis=2)
    errs = {}
    # the paper's shared colour scale, and per channel like the dipole (a like-for-like comparison: marble's
    # channels fall off at different rates, which one shared fall-off cannot follow)
    for label, kind, colour in (
        ("iso", "iso", "shared"),
        ("iso per channel", "iso", "per-channel"),
        ("dipole", "dipole", "per-channel"),
    ):
        fit = fit_mesh(out, kind, colour=colour)
        m = fit.model
        assert m.geometry == "mesh" and isinstance(m.alpha, VertexAlpha) and not fit.flagged.any()
        pred = np.stack([m.R_d(np.full(len(V), i), V) for i in range(len(inc))])
        sel = (r > 0.5) & (r < 6.0)
        errs[label] = np.linalg.norm(pred[sel] - R[sel]) / np.linalg.norm(R[sel])
    assert errs["iso"] < 0.15 and errs["iso per channel"] < errs["dipole"]
    with pytest.raises(TranslucencyError, match="isotropic"):
        fit_mesh(out, "aniso")
    with pytest.raises(TranslucencyError, match="none.zarr: no such data set"):
        fit_mesh(tmp_path / "none.zarr")
