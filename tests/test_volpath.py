"""The photon tally against Mitsuba 3's own ``volpath`` (translucency.validate.volpath).

Fast tests pin down the set-up that the comparison rests on — which image
pixel sees which point of the slab, that Mitsuba's grid holds our voxels the
right way round, the spot's irradiance — and the slow test compares the two
estimates of the radiance leaving a heterogeneous slab.
"""

import numpy as np
import pytest

from translucency import TranslucencyError
from translucency.acquire import Volume, make_sample
from translucency.acquire.transport import TOP, random_walk
from translucency.mitsuba import mitsuba, slab_medium_dict
from translucency.validate import (
    PixelWindow,
    SpotBeam,
    compare,
    pixel_centres,
    render_volpath_spot,
    sample_spot_entries,
    spot_irradiance,
    spot_power,
    spot_profile,
    tally_radiance,
)


def test_pixel_centres_follow_the_window_and_the_rendered_image():
    """Pixel centres read from Mitsuba's sensor form the requested grid, and a rendered, off-centre
    emitting rectangle lights exactly the pixels whose centres lie on it (image [row, col] ↔ centres)."""
    mi = mitsuba()
    window = PixelWindow((3.0, 5.0), n_pixels=8, pitch_mm=0.25)
    x, y = pixel_centres(window)
    # a regular grid of the requested pitch, centred on the window (axes' signs are Mitsuba's business)
    assert np.allclose(np.abs(np.diff(x, axis=1)), 0.25, atol=1e-5) and np.allclose(
        np.diff(x, axis=0), 0, atol=1e-5
    )
    assert np.allclose(np.abs(np.diff(y, axis=0)), 0.25, atol=1e-5) and np.allclose(
        np.diff(y, axis=1), 0, atol=1e-5
    )
    assert np.allclose([x.mean(), y.mean()], window.centre_xy, atol=1e-5)
    # the rectangle covers 3 x 2 pixels, off-centre; its edges lie on pixel edges of the window
    x0, y0 = 3.0 - 1.0 + 0.25, 5.0 - 1.0 + 1.0  # window's lower-left corner + (1, 4) pixels
    rect = mi.ScalarTransform4f().translate([x0 + 0.375, y0 + 0.25, 0.0]) @ mi.ScalarTransform4f().scale(
        [0.375, 0.25, 1.0]
    )
    scene = mi.load_dict(
        {
            "type": "scene",
            "integrator": {"type": "direct"},
            "camera": window.sensor_dict(spp=4),
            "patch": {"type": "rectangle", "to_world": rect, "emitter": {"type": "area", "radiance": 1.0}},
        }
    )
    image = np.array(mi.render(scene, spp=4, seed=0))[..., 0]
    inside = (x > x0) & (x < x0 + 0.75) & (y > y0) & (y < y0 + 0.5)
    assert inside.sum() == 6
    np.testing.assert_allclose(image, inside.astype(float), atol=1e-5)


def test_mitsuba_medium_holds_our_voxels_the_right_way_round():
    """Mitsuba's heterogeneous medium, built from an asymmetric volume, returns at random points
    the σ_s and σ_t of the voxel [iz, iy, ix] that our walk looks up there (z index 0 on top)."""
    mi = mitsuba()
    import drjit as dr  # after mitsuba(): Dr.Jit must load with the libLLVM chosen there

    rng = np.random.default_rng(4)
    shape = (3, 4, 5)  # Z, Y, X all different
    vol = Volume(rng.uniform(0.5, 5.0, shape + (3,)), rng.uniform(0.0, 0.5, shape + (3,)), 0.5, g=0.3)
    W, H, T = vol.size_mm
    n = 2000
    p = rng.uniform([0, 0, -T], [W, H, 0], (n, 3)).astype(np.float32)
    ix = np.minimum((p[:, 0] / 0.5).astype(int), 4)
    iy = np.minimum((p[:, 1] / 0.5).astype(int), 3)
    iz = np.minimum((-p[:, 2] / 0.5).astype(int), 2)
    for c in range(3):
        medium = mi.load_dict(slab_medium_dict(vol, c))
        mei = dr.zeros(mi.MediumInteraction3f, n)
        mei.p = mi.Point3f(p[:, 0], p[:, 1], p[:, 2])
        sigma_s, _, sigma_t = medium.get_scattering_coefficients(mei)
        np.testing.assert_allclose(np.asarray(sigma_t[0]), vol.sigma_t[iz, iy, ix, c], rtol=1e-5)
        np.testing.assert_allclose(np.asarray(sigma_s[0]), vol.sigma_s[iz, iy, ix, c], rtol=1e-5)


def test_spot_irradiance_as_mitsuba_renders_it():
    """Mitsuba's spot gives I/D² on the axis, follows the falloff formula up to float32 angle rounding,
    and the entry points we draw follow 2πρ E(ρ)."""
    beam = SpotBeam((4.0, 4.0), radius_mm=0.5, distance_mm=100.0)
    rho, E = spot_profile(beam)
    assert E[0] == pytest.approx(1.0 / 100.0**2, rel=1e-6)
    exact = spot_irradiance(beam, rho)
    assert np.max(np.abs(E - exact)) < 0.03 * E[0]  # float32 cos θ near 1 quantises θ by ~1e-5 rad
    fine = np.linspace(0, 0.52, 200_001)
    assert spot_power(rho, E) == pytest.approx(spot_power(fine, spot_irradiance(beam, fine)), rel=5e-3)
    assert E[rho > beam.radius_mm * 1.001].max() == 0.0
    # the sampled entries: radial histogram against the integral of 2πρE over each ring
    n = 400_000
    xy = sample_spot_entries(beam, n, seed=3, profile=(rho, E))
    r = np.hypot(xy[:, 0] - 4.0, xy[:, 1] - 4.0)
    edges = np.linspace(0.0, 0.5, 11)
    counts = np.histogram(r, edges)[0]
    dens = 2 * np.pi * rho * E
    expect = (
        np.array(
            [
                np.trapezoid(dens[(rho >= a) & (rho <= b)], rho[(rho >= a) & (rho <= b)])
                for a, b in zip(edges[:-1], edges[1:])
            ]
        )
        / spot_power(rho, E)
        * n
    )
    assert np.all(np.abs(counts - expect) < 4 * np.sqrt(expect) + 0.002 * expect)


def test_walk_reports_exit_cosines_for_top_exits():
    vol = make_sample("homogeneous:marble", (10, 10, 3), 0.5)
    for index_matched in (True, False):
        res = random_walk(vol, 1, np.array([[5.0, 5.0]]), 20_000, seed=7, index_matched=index_matched)
        top = res.code == TOP
        assert top.sum() > 1000
        assert np.all((res.cos_exit[top] > 0) & (res.cos_exit[top] <= 1)) and np.all(res.cos_exit[~top] == 0)
        # light leaving a thick scattering slab is roughly Lambertian: P(θ < 30°) ≈ sin² 30° = 1/4
        assert 0.15 < np.mean(res.cos_exit[top] > np.cos(np.radians(30))) < 0.35


def test_bad_reference_setups_are_named():
    vol = make_sample("homogeneous:marble", (4, 4, 2), 0.5)
    with pytest.raises(TranslucencyError, match="cutoff"):
        SpotBeam((2.0, 2.0), radius_mm=0.01)
    with pytest.raises(TranslucencyError, match="window"):
        tally_radiance(vol, SpotBeam((2.0, 2.0)), PixelWindow((2.0, 2.0), 40, 0.25), 10)
    with pytest.raises(TranslucencyError, match="beam"):
        render_volpath_spot(vol, SpotBeam((0.2, 2.0)), PixelWindow((2.0, 2.0), 4, 0.25), 4)
    with pytest.raises(TranslucencyError, match="channels"):
        tally_radiance(vol, SpotBeam((2.0, 2.0)), PixelWindow((2.0, 2.0), 4, 0.25), 10, channels=(3,))
    with pytest.raises(TranslucencyError, match="spp"):
        render_volpath_spot(vol, SpotBeam((2.0, 2.0)), PixelWindow((2.0, 2.0), 4, 0.25), 1)


@pytest.mark.slow
@pytest.mark.parametrize("sample,g", [("marble", 0.0), ("skin", 0.5)])
def test_tally_matches_volpath_on_a_heterogeneous_slab(sample, g):
    """Radiance leaving an 8 × 8 × 4 mm heterogeneous slab along +z around a 0.5 mm spot, all three
    channels: 4 M photons per channel (10° cone) against 1024 volpath samples per pixel.

    Per pixel, z = (tally − volpath)/σ must look standard normal, allowing for volpath's right-skewed
    pixel estimates at this sample count (which shift the mean of z up by ~0.1–0.2 and fatten the
    tails); the ring averages (many samples each, so close to normal) must agree with χ²/dof < 2
    (p ≈ 0.002 for 24 rings × channels) and no ring off by 4σ.  Marble (weak veins) is the default
    sample; skin (absorbing epidermis, pores, freckles, g = 0.5) also checks depth order, HG's sign
    and the pore layout: a flipped z, negated g or swapped x/y fails here.
    """
    vol = make_sample(sample, (8.0, 8.0, 4.0), 0.25, g=g, seed=1)
    beam = SpotBeam((4.0, 4.0), radius_mm=0.5)
    window = PixelWindow((4.0, 4.0), n_pixels=16, pitch_mm=0.25)
    ref = render_volpath_spot(vol, beam, window, spp=1024, seed=1)
    ours, _ = tally_radiance(vol, beam, window, 4_000_000, seed=2, cone_deg=10.0)
    agreement = compare(ours, ref, beam.centre_xy, np.arange(0.0, 2.0 + 1e-9, 0.25))
    s = agreement.summary()
    assert s["pixels"] == 16 * 16 * 3
    assert abs(s["z_mean"]) < 0.3, s
    assert 0.8 < s["z_std"] < 1.3, s
    assert s["frac_abs_z_gt_3"] < 0.03, s
    assert s["ring_chi2_per_dof"] < 2.0, s
    assert np.all(np.abs(agreement.ring_z) < 4.0), agreement.ring_z
