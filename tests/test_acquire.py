"""Virtual DISCO against references that no one here wrote, and its contracts
(determinism, resuming, bad input)."""

import numpy as np
import pytest

from translucency import TranslucencyError
from translucency.acquire import PlanarSetup, Volume, acquire_planar, load_volume, make_sample
from translucency.acquire.transport import TOP, random_walk
from translucency.io.dataset import open_dataset
from translucency.model import dipole_R_d, material

iad = pytest.importorskip("iadpython")


@pytest.mark.parametrize(
    "a,b,g,n", [(0.9, 2.0, 0.5, 1.3), (0.99, 8.0, 0.0, 1.4), (0.5, 1.0, 0.8, 1.0), (0.95, 4.0, -0.3, 1.5)]
)
def test_total_reflectance_matches_adding_doubling(a, b, g, n):
    """Slab of albedo a, optical thickness b, anisotropy g, index n: MC total reflectance
    (specular + diffuse) against iadpython's UR1 within 3 standard errors."""
    d = 1.0  # mm
    ur1 = float(iad.Sample(a=a, b=b, g=g, d=d, n=n, n_above=1.0, n_below=1.0, quad_pts=16).rt()[0])
    sigma_t = b / d
    # laterally 100 mm: side losses are negligible for a 1 mm slab
    vol = Volume.homogeneous((4, 400, 400), 0.25, [a * sigma_t] * 3, [(1 - a) * sigma_t] * 3, g=g, eta=n)
    N = 200_000
    res = random_walk(vol, 0, np.array([[50.0, 50.0]]), N, seed=11)
    R = np.mean((res.code == TOP) | (res.code == -1))
    se = np.sqrt(R * (1 - R) / N)
    assert abs(R - ur1) < 3 * se, (R, ur1, se)


def test_specular_fraction_is_fresnel_at_normal_incidence():
    vol = make_sample("homogeneous:skin1", (10, 10, 2), 0.5)
    res = random_walk(vol, 0, np.array([[5.0, 5.0]]), 100_000, seed=5)
    spec = np.mean(res.code == -1)
    expect = ((1.3 - 1) / (1.3 + 1)) ** 2
    assert abs(spec - expect) < 4 * np.sqrt(expect * (1 - expect) / 100_000)


def test_radial_profile_against_dipole_beyond_two_mfp():
    """Thick homogeneous marble (g = 0, η = 1.3): the radial profile agrees with the dipole
    within 10 % for 2 mfp < r < 4 mm; closer in the dipole is off (the paper's motivation)."""
    m = material("marble")
    ch = 1
    vol = make_sample("homogeneous:marble", (40, 40, 20), 1.0)
    N = 600_000
    res = random_walk(vol, ch, np.array([[20.0, 20.0]]), N, seed=21)
    top = res.code == TOP
    r = np.hypot(res.x[top] - 20.0, res.y[top] - 20.0)
    mfp = 1.0 / (m.sigma_a[ch] + m.sigma_s_prime[ch])
    edges = np.linspace(0.0, 4.0, 41)
    counts = np.histogram(r, edges)[0]
    ring_area = np.pi * np.diff(edges**2)
    mc = counts / N / ring_area
    centre = 0.5 * (edges[1:] + edges[:-1])
    # ring average of the dipole (its curvature matters near x_i)
    fine = np.linspace(0, 4, 4001)
    dip_fine = dipole_R_d(fine, m.sigma_a[ch], m.sigma_s_prime[ch], 1.3)
    dip = np.array(
        [
            np.trapezoid(
                dip_fine[(fine >= a) & (fine <= b)] * fine[(fine >= a) & (fine <= b)],
                fine[(fine >= a) & (fine <= b)],
            )
            * 2
            * np.pi
            / ar
            for a, b, ar in zip(edges[:-1], edges[1:], ring_area)
        ]
    )
    far = centre > 2 * mfp
    rel = mc[far] / dip[far] - 1
    assert np.max(np.abs(rel)) < 0.10, rel
    near = centre < 0.5 * mfp
    assert np.max(np.abs(mc[near] / dip[near] - 1)) > 0.10  # the near field is where the dipole fails


def test_hg_mean_cosine_is_g():
    # one scattering event in an infinite-like medium: check via a thin, purely scattering slab is
    # indirect; instead sample the phase function through the walk's helper directly
    import drjit as dr

    from translucency.acquire.transport import _hg_sample
    from translucency.mitsuba import mitsuba

    mi = mitsuba()
    n = 200_000
    rng = np.random.default_rng(0)
    d = mi.Vector3f(0.0, 0.0, 1.0)
    for g in (-0.5, 0.0, 0.3, 0.9):
        new = _hg_sample(mi, dr, d, g, mi.Float(rng.random(n)), mi.Float(rng.random(n)))
        cos = np.asarray(new.z)
        assert abs(cos.mean() - g) < 4 * cos.std() / np.sqrt(n)
        assert np.allclose(np.asarray(new.x) ** 2 + np.asarray(new.y) ** 2 + cos**2, 1, atol=1e-5)


SMALL = PlanarSetup(grid=(3, 3), span=(4.0, 4.0), pitch=0.5, window=6.0, photons=2000, seed=3, chunk_points=4)


def test_deterministic_and_resumable(tmp_path):
    vol = make_sample("marble", (12, 12, 4), 0.5, seed=1)
    full = acquire_planar(vol, SMALL, tmp_path / "a.zarr")
    again = acquire_planar(vol, SMALL, tmp_path / "b.zarr")
    np.testing.assert_array_equal(full["R_d"], again["R_d"])

    class Stop(Exception):
        pass

    def interrupt(done, total):
        if done >= 4:
            raise Stop

    with pytest.raises(Stop):
        acquire_planar(vol, SMALL, tmp_path / "c.zarr", progress=interrupt)
    partial = open_dataset(tmp_path / "c.zarr")
    assert partial["chunk_done"].tolist() == [True, False, False]
    resumed = acquire_planar(vol, SMALL, tmp_path / "c.zarr")
    assert resumed.complete()
    for key in ("R_d", "variance", "mask", "specular", "total_diffuse"):
        np.testing.assert_array_equal(resumed[key], full[key])
    # other arguments on the same path are refused, not mixed in
    with pytest.raises(TranslucencyError, match="made with other arguments"):
        acquire_planar(vol, PlanarSetup(**{**SMALL.__dict__, "seed": 4}), tmp_path / "c.zarr")


def test_dataset_content_is_consistent(tmp_path):
    vol = make_sample("homogeneous:skin2", (12, 12, 4), 0.5)
    ds = acquire_planar(vol, SMALL, tmp_path / "s.zarr")
    R, var, mask = ds["R_d"], ds["variance"], ds["mask"]
    n = ds.window[0]
    assert n % 2 == 1 and R.shape == (9, n, n, 3)
    # the window sum never exceeds all light leaving the top
    inside = R.sum(axis=(1, 2)) * ds.pitch**2
    assert (inside <= ds["total_diffuse"] + 1e-6).all()
    # binomial variance, and the brightest pixel is the one under the beam
    N = ds.header["acquisition"]["photons"]
    np.testing.assert_allclose(var, R * (1 / ds.pitch**2 - R) / N, rtol=1e-5, atol=1e-12)
    peak = np.unravel_index(R[4, ..., 1].argmax(), (n, n))
    assert peak == (n // 2, n // 2)
    assert mask.all()  # the windows fit on this sample


def _reduced(name):
    """(σ_s', σ_a) of a Jensen 2001 material in mm⁻¹, as float32 like the volumes."""
    m = material(name)
    return np.float32(m.sigma_s_prime), np.float32(m.sigma_a)


def _marble(v):
    """Body voxels are the marble material; veins absorb more and scatter 40 % less."""
    s, a = v.sigma_s, v.sigma_a
    ss, sa = _reduced("marble")
    np.testing.assert_allclose(s.max(axis=(0, 1, 2)), ss, rtol=1e-6)  # pure body somewhere
    np.testing.assert_allclose(a.min(axis=(0, 1, 2)), sa, rtol=1e-6)
    assert (s.min(axis=(0, 1, 2)) >= 0.6 * ss * (1 - 1e-6)).all() and (s.min(axis=(0, 1, 2)) < 0.7 * ss).all()
    assert (a.max(axis=(0, 1, 2)) > 5 * sa).all()  # the veins


def _apple_slice(v):
    """Apple flesh, a core scattering half as much, five absorbing seeds, little scattering outside."""
    s, a = v.sigma_s, v.sigma_a
    ss, sa = _reduced("apple")
    seeds = (a == np.float32([0.8, 1.2, 1.6])).all(axis=-1)
    assert seeds.any() and (s[seeds] == 2.0).all()
    np.testing.assert_allclose(a[~seeds], np.broadcast_to(sa, a[~seeds].shape), rtol=1e-6)
    centre = s[:, 15:17, 15:17]  # r < 0.2 of the 4 mm radius: the core
    assert (centre <= 0.5 * 1.15 * ss).all() and (s[:, 8, 16] > 0.6 * ss).all()  # flesh at r = 0.47
    assert (s[:, 0, 0] <= 0.05 * 1.15 * ss).all()  # a corner lies outside the slice


def _skin(v):
    """An absorbing epidermis (skin1, 3× σ_a, freckles 4× more) over dermis (skin2), with pores."""
    s, a = v.sigma_s, v.sigma_a
    (epi_s, epi_a), (der_s, der_a) = _reduced("skin1"), _reduced("skin2")
    assert (a[0] >= 3 * epi_a * (1 - 1e-6)).all() and np.isclose(a[0].max(axis=(0, 1)), 12 * epi_a).all()
    assert set(np.unique(s[0, ..., 0])) == {np.float32(epi_s[0]), np.float32(epi_s[0]) * np.float32(0.2)}
    assert (a[1:] == der_a).all() and (s[2:] == der_s).all()  # dermis below 0.5 mm: no pores there
    assert (s[1] < der_s).any()  # the pores reach into the dermis


def _fibers(v):
    """Clear lamellae (σ_s ≈ 0.3 mm⁻¹) and a scattering matrix (≈ 8 mm⁻¹): varying across y, never along x."""
    s = v.sigma_s
    assert np.ptp(s, axis=2).max() == 0 and np.ptp(v.sigma_a, axis=2).max() == 0
    np.testing.assert_allclose(np.unique(s[..., 0]), [0.30, 7.5], rtol=1e-6)
    assert 0.3 < np.mean(s[..., 0] < 1.0) < 0.7  # 50 % fill


def _banded(v):
    """Skin2 bulk crossed by cream bands (4–7× its scattering) and an absorbing disc (20× σ_a)."""
    s, a = v.sigma_s, v.sigma_a
    (bulk_s, bulk_a), (cream_s, _) = _reduced("skin2"), _reduced("cream")
    np.testing.assert_allclose(s.min(axis=(0, 1, 2)), bulk_s, rtol=0.02)  # between the bands: the bulk
    np.testing.assert_allclose(s.max(axis=(0, 1, 2)), cream_s, rtol=0.02)  # inside a band: cream
    assert 0.3 < np.mean(s[..., 0] > 0.5 * (bulk_s[0] + cream_s[0])) < 0.7  # 1.5 mm bands, 3 mm pitch
    assert (a.max(axis=(0, 1, 2)) > 10 * bulk_a).all()  # the disc
    assert (a[-1] <= bulk_a * (1 + 1e-6)).all()  # the disc is 1 mm deep


def _layered(v):
    """A clear layer (skim milk at a fifth of its scattering) over a dense bulk (3× whole milk)."""
    s = v.sigma_s
    clear, dense = 0.2 * _reduced("skimmilk")[0], 3 * _reduced("wholemilk")[0]
    assert (s[0] < s[-1]).all() and (s >= clear * (1 - 1e-6)).all() and (s <= dense * (1 + 1e-6)).all()
    np.testing.assert_allclose(s[-1], np.broadcast_to(dense, s[-1].shape), rtol=1e-4)
    assert (s[0] < 0.6 * dense).all()


def _homogeneous_apple(v):
    """One material everywhere: apple's coefficients."""
    ss, sa = _reduced("apple")
    assert (v.sigma_s == ss).all() and (v.sigma_a == sa).all()


#: generator → what its docstring says it holds, checked on an 8 × 8 × 3 mm volume of 0.25 mm voxels
STRUCTURE = {
    "marble": _marble,
    "apple-slice": _apple_slice,
    "skin": _skin,
    "fibers": _fibers,
    "banded": _banded,
    "layered": _layered,
    "homogeneous:apple": _homogeneous_apple,
}


@pytest.mark.parametrize("name", list(STRUCTURE))
def test_generators_make_valid_volumes(name):
    """Physical coefficients (finite, σ_s, σ_a ≥ 0, albedo < 1), the stated materials and structure, the
    anisotropy g entering as σ_s = σ_s'/(1 − g), and the seed: the same seed the same volume."""
    v = make_sample(name, (8, 8, 3), 0.25, seed=2)
    assert v.shape == (12, 32, 32) and v.sigma_s.shape == v.sigma_a.shape == (12, 32, 32, 3)
    assert v.sigma_s.dtype == v.sigma_a.dtype == np.float32
    assert np.isfinite(v.sigma_s).all() and np.isfinite(v.sigma_a).all()
    assert (v.sigma_s >= 0).all() and (v.sigma_a > 0).all() and (v.sigma_t > 0).all()
    albedo = v.sigma_s / (v.sigma_s + v.sigma_a)
    assert (albedo < 1).all() and (albedo > 0).all()
    assert v.voxel_mm == 0.25 and v.size_mm == (8.0, 8.0, 3.0)
    assert v.g == 0.0 and -1 < v.g < 1 and v.eta == 1.3
    assert v.description["generator"] == name
    STRUCTURE[name](v)
    again = make_sample(name, (8, 8, 3), 0.25, seed=2)
    np.testing.assert_array_equal(v.sigma_s, again.sigma_s)
    np.testing.assert_array_equal(v.sigma_a, again.sigma_a)
    if name in ("marble", "apple-slice", "skin", "banded", "layered"):  # noise or positions from the seed
        other = make_sample(name, (8, 8, 3), 0.25, seed=3)
        assert not np.array_equal(v.sigma_s, other.sigma_s) or not np.array_equal(v.sigma_a, other.sigma_a)
    # forward scattering: the same reduced scattering σ_s (1 − g), the same absorption
    fwd = make_sample(name, (8, 8, 3), 0.25, g=0.5, seed=2)
    assert fwd.g == 0.5 and fwd.description["g"] == 0.5
    np.testing.assert_array_equal(fwd.sigma_a, v.sigma_a)
    scaled = ~(v.sigma_a == np.float32([0.8, 1.2, 1.6])).all(axis=-1)  # apple's seeds: σ_s = 2 mm⁻¹ for any g
    np.testing.assert_allclose((fwd.sigma_s * 0.5)[scaled], v.sigma_s[scaled], rtol=1e-6)


def test_fibers_spread_light_farther_along_x():
    vol = make_sample("fibers", (20, 20, 6), 0.1, seed=0)
    res = random_walk(vol, 1, np.array([[10.05, 10.05]]), 100_000, seed=2)
    top = res.code == TOP
    sx = np.sqrt(np.mean((res.x[top] - 10.05) ** 2))
    sy = np.sqrt(np.mean((res.y[top] - 10.05) ** 2))
    assert sx > 1.3 * sy


def test_banded_runs_diagonally_and_layered_changes_with_depth():
    """The two samples of issue 13's accuracy table: bands at 45° (constant along x − y, varying along
    x + y) with an absorbing disc; a clear layer whose interface depth varies across the sample."""
    v = make_sample("banded", (12, 12, 3), 0.25, seed=1)
    s = v.sigma_s[0, ..., 1]  # top layer, green
    i = np.arange(48)
    across = s[i[:-1], i[1:]]  # y − x = const: across the bands
    along = s[i[:24], 24 - i[:24]]  # y + x = const: along one band
    assert along.std() < 0.5 * across.std()
    a = v.sigma_a[0, ..., 1]
    assert a.max() > 15 * np.median(a)  # the disc absorbs 20× more
    w = make_sample("layered", (12, 12, 3), 0.25, seed=1)
    top, bottom = w.sigma_s[0, ..., 1], w.sigma_s[-1, ..., 1]
    assert (top < 0.25 * bottom).all() and np.median(top) < 0.05 * np.median(
        bottom
    )  # clear above, dense below
    interface = (w.sigma_s[..., 1] < 0.5 * bottom).sum(axis=0) * 0.25  # clear depth per column, mm
    assert 0.25 <= interface.min() and interface.max() <= 1.5 and interface.max() - interface.min() > 0.4


def test_bad_volumes_are_named(tmp_path):
    good = np.ones((2, 3, 3, 3), np.float32)
    with pytest.raises(TranslucencyError, match=r"sigma_a: negative value -1 at index \(0, 0, 0, 0\)"):
        Volume(good, -good, 0.5)
    bad = good.copy()
    bad[1, 2, 0, 1] = np.nan
    with pytest.raises(TranslucencyError, match=r"sigma_s: non-finite value at voxel \(1, 2, 0, 1\)"):
        Volume(bad, good, 0.5)
    with pytest.raises(TranslucencyError, match="empty volume"):
        Volume(np.ones((0, 3, 3, 3)), np.ones((0, 3, 3, 3)), 0.5)
    with pytest.raises(TranslucencyError, match="g: "):
        Volume(good, good, 0.5, g=1.0)
    p = tmp_path / "v.npz"
    np.savez(p, sigma_s=good, sigma_a=good)
    with pytest.raises(TranslucencyError, match="v.npz: missing array 'voxel_mm'"):
        load_volume(p)
    np.savez(p, sigma_s=good, sigma_a=good[..., :2], voxel_mm=0.5)
    with pytest.raises(TranslucencyError, match=r"v.npz: sigma_a: expected shape \(Z, Y, X, 3\)"):
        load_volume(p)
    np.savez(p, sigma_s=good, sigma_a=good * 0.01, voxel_mm=0.5, g=0.2)
    assert load_volume(p).g == pytest.approx(0.2)


def test_bad_setups_are_refused_before_work():
    vol = make_sample("homogeneous:marble", (10, 10, 2), 0.5)
    for kwargs, needle in [
        ({"window": 12.0}, "window: 12.0 mm is larger than the sample"),
        ({"pitch": -1.0}, "pitch"),
        ({"photons": 0}, "photons"),
        ({"span": (20.0, 4.0)}, "span"),
        ({"theta_inc_deg": 95.0}, "angle"),
    ]:
        with pytest.raises(TranslucencyError, match=needle):
            PlanarSetup(**{**SMALL.__dict__, **kwargs}).check(vol)
    from translucency.acquire.transport import check_memory

    with pytest.raises(TranslucencyError, match="GiB"):
        check_memory(10**12, vol, 8 * 2**30)


@pytest.mark.slow
@pytest.mark.parametrize("a,b,g,n", [(0.9, 2.0, 0.5, 1.3), (0.99, 8.0, 0.0, 1.4), (0.95, 4.0, -0.3, 1.5)])
def test_total_reflectance_matches_adding_doubling_precisely(a, b, g, n):
    """As above with 2 M photons: standard errors ~4e-4, still within 3 of them."""
    ur1 = float(iad.Sample(a=a, b=b, g=g, d=1.0, n=n, n_above=1.0, n_below=1.0, quad_pts=16).rt()[0])
    vol = Volume.homogeneous((4, 400, 400), 0.25, [a * b] * 3, [(1 - a) * b] * 3, g=g, eta=n)
    N = 2_000_000
    res = random_walk(vol, 0, np.array([[50.0, 50.0]]), N, seed=99)
    R = np.mean((res.code == TOP) | (res.code == -1))
    assert abs(R - ur1) < 3 * np.sqrt(R * (1 - R) / N)
