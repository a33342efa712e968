"""The angle axes of mesh data (translucency.angles): oblique beams and exit bins, checked against
Chandrasekhar's closed forms for a half-space, and old data sets read as the normal beam alone."""

import numpy as np
import pytest
import trimesh

from translucency._validate import TranslucencyError
from translucency.angles import ExitBins, Incidence


def _slab_with_a_centre_vertex(extents=(60.0, 60.0, 30.0)):
    """A box whose vertex 0 is the centre of its top face (the incident point of a one-point scan)."""
    box = trimesh.creation.box(extents=extents).subdivide()  # the top diagonal's midpoint: the centre
    top = np.array([0.0, 0.0, extents[2] / 2])
    c = int(np.argmin(np.linalg.norm(box.vertices - top, axis=1)))
    assert np.allclose(box.vertices[c], top)
    order = np.r_[c, np.delete(np.arange(len(box.vertices)), c)]
    inverse = np.argsort(order)
    return trimesh.Trimesh(box.vertices[order], inverse[box.faces], process=False)


def _bin_shares(mu0: float, albedo: float, edges_cos: np.ndarray) -> np.ndarray:
    r"""Chandrasekhar's reflected radiance of a half-space lit at :math:`\mu_0` (isotropic scattering,
    index-matched), :math:`I(\mu) \propto H(\mu) / (\mu + \mu_0)`, as the share of the reflected flux in
    each polar bin: :math:`\int_{bin} \mu H(\mu) / (\mu + \mu_0) d\mu` over the whole."""
    from translucency.model.incidence import chandrasekhar_h

    x, w = np.polynomial.legendre.leggauss(64)
    share = []
    for hi, lo in zip(edges_cos[:-1], edges_cos[1:]):
        mu = lo + (hi - lo) * (x + 1) / 2
        share.append(np.sum(w * (hi - lo) / 2 * mu * chandrasekhar_h(mu, albedo) / (mu + mu0)))
    share = np.asarray(share)
    return share / share.sum()


@pytest.mark.slow
def test_a_half_space_s_oblique_albedo_and_exit_bins_match_chandrasekhar(tmp_path):
    """A 30 mm slab (σ_t = 1 mm⁻¹, albedos 0.5 / 0.8 / 0.95: a half-space to < 1 %), index-matched, one
    incident point lit along the normal and at 60° from four azimuths.  The tally's total reflectance
    Σ_v R_d A_v is Chandrasekhar's plane albedo R(μ₀) = 1 − H(μ₀)√(1−a) at μ₀ = 1 and 0.5, and its exits
    fall in the polar bins as :math:`\\int \\mu H(\\mu) / (\\mu + \\mu_0)`; the bins add up to R_d."""
    from translucency.acquire.mesh import acquire_mesh
    from translucency.acquire.volume import Volume
    from translucency.io.mesh_dataset import open_mesh_dataset
    from translucency.model.incidence import plane_albedo

    slab = _slab_with_a_centre_vertex()
    a = np.array([0.5, 0.8, 0.95])
    vol = Volume.homogeneous((6, 12, 12), 5.0, a, 1 - a, 0.0, 1.0)
    N = 40_000
    bins = ExitBins(polar=3)
    out = acquire_mesh(
        slab, vol, tmp_path / "slab.zarr", n_points=1, photons=N, chunk_points=1, index_matched=True,
        incidence=Incidence((60.0,), 4), exit_bins=bins,
    )  # fmt: skip
    ds = open_mesh_dataset(out)
    assert ds.incidence.count == 5 and ds.exit_bins == bins
    area = np.asarray(ds["vertex_area"], np.float64)
    binned = np.asarray(ds["exit_bins"], np.float64)[0]  # (D, V, 3, B)
    for d, mu0 in enumerate([1.0, 0.5, 0.5, 0.5, 0.5]):
        R_d = ds.R_d_toward(d)[0].astype(np.float64)  # (V, 3)
        assert np.allclose(binned[d].sum(-1), R_d, rtol=1e-5, atol=1e-9)
        total = np.einsum("vc,v->c", R_d, area)  # the share of the power reflected
        expect = plane_albedo(mu0, a)
        sigma = np.sqrt(expect * (1 - expect) / N)
        assert np.all(np.abs(total - expect) < 4 * sigma + 0.005), (d, total, expect)
        polar = np.einsum("vcb,v->cb", binned[d], area).reshape(3, bins.polar, 2).sum(-1)  # (channel, polar)
        for c in range(3):
            share = polar[c] / polar[c].sum()
            want = _bin_shares(mu0, a[c], bins.edges_cos)
            n_exit = expect[c] * N
            sigma = np.sqrt(want * (1 - want) / n_exit)
            assert np.all(np.abs(share - want) < 4 * sigma + 0.005), (d, c, share, want)
    assert ds.group["specular_oblique"][...].max() == 0  # index-matched: no Fresnel reflection


def test_the_normal_beam_is_the_same_with_or_without_the_angle_axes_and_old_data_read_as_it(tmp_path):
    """Adding oblique beams and exit bins leaves the normal beam's R_d bit for bit (its photons are drawn
    as before); a data set without the axes reads as one direction without exit bins; a dielectric's
    exit bins add up to R_d; a header that announces axes whose arrays are missing is refused in a line."""
    import shutil

    from translucency.acquire.mesh import acquire_mesh
    from translucency.acquire.volume import Volume
    from translucency.io.mesh_dataset import open_mesh_dataset

    ball = trimesh.creation.icosphere(2, radius=4.0)
    vol = Volume.homogeneous((9, 9, 9), 1.0, [1.0, 1.5, 2.0], [0.01, 0.02, 0.05], 0.0, 1.3)
    kw = dict(n_points=3, photons=500, chunk_points=2)
    plain = open_mesh_dataset(acquire_mesh(ball, vol, tmp_path / "plain.zarr", **kw))
    both = open_mesh_dataset(
        acquire_mesh(
            ball, vol, tmp_path / "both.zarr", incidence=Incidence((45.0,), 2), exit_bins=ExitBins(2), **kw
        )
    )
    assert plain.incidence.count == 1 and plain.exit_bins is None
    assert np.array_equal(plain.R_d_toward(0), plain["R_d"])
    assert np.array_equal(plain["R_d"], both["R_d"])
    assert both.incidence.count == 3 and both["R_d_oblique"].shape == (3, 2, 162, 3)
    assert np.allclose(np.asarray(both["exit_bins"]).sum(-1)[:, 1], both.R_d_toward(1), rtol=1e-5, atol=1e-9)
    assert not np.array_equal(both.R_d_toward(1), both.R_d_toward(2))  # other beams, other photons
    both.check_complete()
    with pytest.raises(TranslucencyError, match="direction 3"):
        both.R_d_toward(3)
    _check_the_tally_s_exit_law(tmp_path / "both.zarr", tmp_path / "plain.zarr")
    # a lost chunk of an angle array is damage, found and acquired again with the same arguments
    bins_before, oblique_before = np.asarray(both["exit_bins"]), np.asarray(both["R_d_oblique"])
    lost = tmp_path / "both.zarr" / "R_d_oblique" / "c" / "1"
    shutil.rmtree(lost)
    assert open_mesh_dataset(tmp_path / "both.zarr").damaged_chunks() == {"R_d_oblique": [1]}
    with pytest.warns(UserWarning, match="R_d_oblique"):
        again = acquire_mesh(
            ball, vol, tmp_path / "both.zarr", incidence=Incidence((45.0,), 2), exit_bins=ExitBins(2), **kw
        )
    again = open_mesh_dataset(again)
    assert not again.damaged_chunks() and np.array_equal(again["exit_bins"], bins_before)
    assert np.array_equal(again["R_d_oblique"][2:], oblique_before[2:])  # the same photons again
    shutil.rmtree(tmp_path / "both.zarr" / "exit_bins")
    with pytest.raises(TranslucencyError, match="exit_bins"):
        open_mesh_dataset(tmp_path / "both.zarr")


def test_exit_bins_tile_the_hemisphere_and_read_a_lambertian_exit_as_one():
    """Cosine-distributed exits (Lambertian) fall evenly in the bins of equal projected solid angle: the
    law is 1 in every bin; an exit grazing or below the horizon is in the last polar bin; the tangent
    component of the way from the incident point decides away or back."""
    rng = np.random.default_rng(3)
    bins = ExitBins(polar=4)
    n = 400_000
    u1, u2 = rng.random(n), rng.random(n)
    r, phi = np.sqrt(u1), 2 * np.pi * u2  # Malley: a cosine-distributed direction about +z
    omega = np.stack([r * np.cos(phi), r * np.sin(phi), np.sqrt(1 - u1)], axis=1)
    normal = np.tile([0.0, 0.0, 1.0], (n, 1))
    away = np.tile([1.0, 0.0, 5.0], (n, 1))  # (its normal component does not count)
    b = bins.index(omega, normal, away)
    counts = np.bincount(b, minlength=bins.count).astype(float)
    law = bins.law(counts)
    assert np.allclose(law, 1.0, atol=4 * np.sqrt(bins.count / n) * 1.2)
    assert np.array_equal(b[omega[:, 0] < 0] % 2, np.ones((omega[:, 0] < 0).sum(), int))
    assert bins.index(np.array([[1.0, 0, -0.1]]), normal[:1], away[:1])[0] == 2 * (bins.polar - 1)
    with pytest.raises(TranslucencyError, match="polar angles"):
        Incidence((90.0,))


def _check_the_tally_s_exit_law(binned, plain):
    """The exit law read from a tally's bins (import object's ``tally:PATH``) keeps energy in every band
    of distance (Σ_b γ_b Ω'_b = π), looks up the bin of a view (cosine, slant, distance) as the tally
    binned it, and a data set without bins is refused in one line."""
    from translucency.rig.object.exit_law import TABLE_EDGES_MM, law_named, tabulated_from_tally

    law = law_named(f"tally:{binned}")
    bins = law.bins
    assert law.gamma.shape == (len(TABLE_EDGES_MM), bins.count, 3)
    assert np.allclose((law.gamma * bins.projected_solid_angle).sum(axis=1), np.pi)
    mu = np.array([0.95, 0.95, 0.3])
    got = law.factor(mu, np.array([0.1, -0.1, 0.2]), np.array([0.2, 0.2, 5.0]))
    band5 = np.searchsorted(TABLE_EDGES_MM, 5.0, side="right") - 1
    want = law.gamma[[0, 0, band5], [0, 1, 2 * (bins.polar - 1)]]
    assert np.array_equal(got, want)
    with pytest.raises(TranslucencyError, match="no exit bins"):
        tabulated_from_tally(plain)


def test_a_planar_scan_s_oblique_beams_and_exit_bins_match_chandrasekhar(tmp_path):
    """``acquire planar --incidence 60 --exit-bins 3`` on a 30 mm index-matched slab (a half-space to < 1 %,
    the mesh test's): each beam's light leaving the top face is the plane albedo R(μ₀) at μ₀ = 1 and 0.5,
    its exits fall in the polar bins as ∫ μ H(μ)/(μ + μ₀), the bins add up to R_d, and each oblique beam's
    light lands downstream of x_i (away from the light's azimuth); the normal beam is the same bit for bit
    as a scan without the axes, which reads as one direction without bins."""
    from translucency.acquire.planar import PlanarSetup, acquire_planar
    from translucency.acquire.volume import Volume
    from translucency.model.incidence import plane_albedo

    a = np.array([0.5, 0.8, 0.95])
    vol = Volume.homogeneous((6, 12, 12), 5.0, a, 1 - a, 0.0, 1.0)
    N, bins, inc = 20_000, ExitBins(polar=3), Incidence((60.0,), 4)
    kw = dict(grid=(1, 1), span=(0.0, 0.0), pitch=1.0, window=41.0, photons=N, index_matched=True)
    ds = acquire_planar(vol, PlanarSetup(**kw, incidence=inc, exit_bins=bins), tmp_path / "angles.zarr")
    plain = acquire_planar(vol, PlanarSetup(**kw), tmp_path / "plain.zarr")
    assert np.array_equal(ds["R_d"], plain["R_d"])
    assert np.array_equal(ds["total_diffuse"], plain["total_diffuse"])
    assert plain.incidence.count == 1 and plain.exit_bins is None and "R_d_oblique" not in plain.group
    assert ds.incidence == inc and ds.exit_bins == bins
    g = ds.group
    R = np.concatenate([g["R_d"][:1][:, None], g["R_d_oblique"][:1]], axis=1)[0]  # (D, n, n, 3)
    top = np.concatenate([g["total_diffuse"][:1][:, None], g["total_diffuse_oblique"][:1]], axis=1)[0]
    binned = np.asarray(g["exit_bins"], np.float64)[0]  # (D, n, n, 3, B)
    n = ds.window[0]
    x = (np.arange(n) - n // 2) * ds.pitch  # pixel centres about x_i (the centre pixel), mm
    for d, (mu0, toward) in enumerate(zip([1.0, 0.5, 0.5, 0.5, 0.5], inc.local())):
        assert np.allclose(binned[d].sum(-1), R[d], rtol=1e-5, atol=1e-9)
        expect = plane_albedo(mu0, a)
        sigma = np.sqrt(expect * (1 - expect) / N)
        assert np.all(np.abs(top[d] - expect) < 4 * sigma + 0.005), (d, top[d], expect)
        polar = binned[d].sum(axis=(0, 1)).reshape(3, bins.polar, 2).sum(-1) * ds.pitch**2  # (channel, polar)
        for c in range(3):
            share, want = polar[c] / polar[c].sum(), _bin_shares(mu0, a[c], bins.edges_cos)
            sigma = np.sqrt(want * (1 - want) / (expect[c] * N))
            assert np.all(np.abs(share - want) < 4 * sigma + 0.005), (d, c, share, want)
        if d:  # the centroid of the reflected light: downstream, against the light's tangential direction
            w = R[d, ..., 2]
            centroid = np.array([np.sum(w * x[None, :]), np.sum(w * x[:, None])]) / w.sum()
            assert centroid @ toward[:2] < -0.1 * np.linalg.norm(toward[:2]), (d, centroid, toward)
    assert np.asarray(g["specular_oblique"]).max() == 0  # index-matched: no Fresnel reflection


def test_acquire_planar_with_the_angle_axes_from_the_command_line(tmp_path):
    """The CLI's --incidence/--azimuths/--exit-bins on a planar scan, a resume with the same arguments, and
    --angle with --incidence refused in one line."""
    from typer.testing import CliRunner

    from helpers import error_line
    from translucency.cli.app import app
    from translucency.io.dataset import open_dataset

    out = tmp_path / "scan.zarr"
    args = ["acquire", "planar", "--out", str(out), "-m", "homogeneous:skin1", "--size", "8", "8", "3",
            "--voxel", "1", "--grid", "2", "--span", "2", "--window", "3", "--pitch", "0.5",
            "--photons", "300", "--incidence", "45", "--azimuths", "2", "--exit-bins", "2", "-q"]  # fmt: skip
    for _ in range(2):  # the second run finds it finished
        res = CliRunner().invoke(app, args)
        assert res.exit_code == 0, res.output
    ds = open_dataset(out)
    assert ds.incidence == Incidence((45.0,), 2) and ds.exit_bins == ExitBins(2)
    assert ds.group["R_d_oblique"].shape == (4, 2, 7, 7, 3)
    assert ds.group["exit_bins"].shape == (4, 3, 7, 7, 3, 4)
    assert not ds.damaged_chunks()
    line = error_line([*args[:3], str(tmp_path / "other.zarr"), *args[4:], "--tilt", "30"])
    assert "--tilt" in line and "--incidence" in line


def _cosine_directions(n: int, rng) -> np.ndarray:
    """Unit directions about +z distributed as cos θ (a Lambertian exit): μ = √u, φ uniform."""
    mu, phi = np.sqrt(rng.random(n)), 2 * np.pi * rng.random(n)
    s = np.sqrt(1 - mu**2)
    return np.stack([s * np.cos(phi), s * np.sin(phi), mu], axis=1)


def test_the_two_halves_are_the_sign_of_the_exit_along_the_away_axis_bit_for_bit():
    """The default two sectors are the halves every data set with exit bins was tallied in: 2 j + h,
    h = 1 where the exit's direction points back toward the incident point (ω · a_t < 0)."""
    rng = np.random.default_rng(3)
    n = np.tile([0.0, 0.0, 1.0], (5000, 1))
    omega = _cosine_directions(5000, rng)
    away = rng.normal(size=(5000, 3))
    away[:50] = [0.0, 0.0, 1.0]  # at the incident point: no tangent part, away
    bins = ExitBins(polar=3)
    a_t = away - away[:, 2:3] * n
    expected = 2 * bins.polar_index(omega[:, 2]) + (np.einsum("ij,ij->i", omega, a_t) < 0)
    assert np.array_equal(bins.index(omega, n, away), expected)


@pytest.mark.parametrize("polar, slants", [(3, 2), (4, 8), (2, 5)])
def test_a_lambertian_exit_fills_every_bin_alike(polar, slants):
    """Bins of equal projected solid angle: cos θ-distributed exits fall into each with the same
    probability 1/count (within 4 σ of the binomial), whatever the away axis."""
    rng = np.random.default_rng(polar * 10 + slants)
    N, bins = 200_000, ExitBins(polar=polar, slants=slants)
    omega = _cosine_directions(N, rng)
    n = np.tile([0.0, 0.0, 1.0], (N, 1))
    theta = 2 * np.pi * rng.random(N)
    away = np.stack([np.cos(theta), np.sin(theta), rng.normal(size=N)], axis=1)  # any tangent axis
    counts = np.bincount(bins.index(omega, n, away), minlength=bins.count)
    p = 1.0 / bins.count
    assert len(counts) == bins.count
    assert np.all(np.abs(counts / N - p) < 4 * np.sqrt(p * (1 - p) / N)), counts / N


def test_the_import_reads_the_bin_the_tally_counted_in():
    """The tabulated exit law (the import's side) looks up each view's bin from its cosine μ and slant
    s = ω · t̂; the tally bins each exit from its direction and the away axis.  Both must name the same bin,
    in the halves and in finer sectors."""
    from translucency.rig.object.exit_law import TABLE_EDGES_MM, Tabulated

    rng = np.random.default_rng(11)
    for bins in (ExitBins(3), ExitBins(4, slants=8)):
        omega = _cosine_directions(20_000, rng)
        n = np.tile([0.0, 0.0, 1.0], (len(omega), 1))
        theta = 2 * np.pi * rng.random(len(omega))
        t_hat = np.stack([np.cos(theta), np.sin(theta), np.zeros_like(theta)], axis=1)  # unit tangent, away
        gamma = np.broadcast_to(
            np.arange(bins.count, dtype=float)[None, :, None], (len(TABLE_EDGES_MM), bins.count, 3)
        )
        law = Tabulated(bins, np.array(gamma), "bin numbers")
        read = law.factor(omega[:, 2], np.einsum("ij,ij->i", omega, t_hat), np.full(len(omega), 3.0))[:, 0]
        assert np.array_equal(read.astype(int), bins.index(omega, n, t_hat))


def test_exit_bins_refuse_too_few_or_too_many_sectors():
    with pytest.raises(TranslucencyError, match="2 to 16 azimuthal sectors"):
        ExitBins(3, slants=1)
    assert ExitBins.from_header(ExitBins(4, slants=8).describe()) == ExitBins(4, slants=8)
    assert ExitBins.from_header(ExitBins(4).describe()) == ExitBins(4)
    assert "slants" not in ExitBins(4).describe()  # the halves' record as data sets always had it
