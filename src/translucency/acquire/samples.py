"""Seeded generators of heterogeneous sample volumes.

Every generator takes the slab size in mm, the voxel size and a seed, and
returns a :class:`~translucency.acquire.volume.Volume`.  Coefficients derive
from the measured materials of Jensen et al. 2001 (σ_s' and σ_a in mm⁻¹); with
a Henyey–Greenstein ``g`` the single-scattering coefficient is
σ_s = σ_s' / (1 − g).

===================  ===============================================================
``homogeneous:NAME``  one material of the Jensen 2001 table
``marble``            veins from turbulent noise mixing two marble-like materials
``apple-slice``       radial flesh structure with a core and absorbing seeds
``skin``              thin absorbing epidermis over dermis, with pores and freckles
``fibers``            clear lamellae aligned with x: light spreads farther along x than y
``banded``            skin-like bulk with diagonal cream bands and an absorbing disc
``layered``           a clear, wax-like layer of varying depth over a dense scattering bulk
===================  ===============================================================
"""

from __future__ import annotations

import numpy as np
from scipy.ndimage import gaussian_filter

from .._validate import TranslucencyError
from ..model.materials import ETA, MATERIALS, material
from .names import GENERATORS
from .volume import Volume


def _grid(size_mm, voxel_mm):
    """Voxel-centre coordinates (z, y, x) in mm, each of shape (Z, Y, X)."""
    w, h, t = size_mm
    nx, ny, nz = (max(1, int(round(v / voxel_mm))) for v in (w, h, t))
    z = -(np.arange(nz) + 0.5) * voxel_mm
    y = (np.arange(ny) + 0.5) * voxel_mm
    x = (np.arange(nx) + 0.5) * voxel_mm
    return np.meshgrid(z, y, x, indexing="ij")


def _noise(shape, sigma_vox, rng) -> np.ndarray:
    """Smooth noise in [-1, 1]: Gaussian-filtered white noise, normalised."""
    n = gaussian_filter(rng.standard_normal(shape), sigma_vox, mode="wrap")
    return n / (np.abs(n).max() + 1e-12)


def _turbulence(shape, voxel_mm, rng, scales_mm=(4.0, 2.0, 1.0, 0.5)) -> np.ndarray:
    """Sum of |noise| octaves (Perlin's turbulence) with amplitude halving per octave."""
    out = np.zeros(shape)
    for k, s in enumerate(scales_mm):
        out += np.abs(_noise(shape, max(s / voxel_mm, 0.5), rng)) / 2**k
    return out


def _coeffs(name, g):
    m = material(name)
    return m.sigma_s_prime / (1.0 - g), m.sigma_a


def _mix(weights_and_materials, shape):
    """Per-voxel mixture: Σ_j w_j(voxel) · (σ_s, σ_a)_j."""
    s = np.zeros(shape + (3,), np.float32)
    a = np.zeros(shape + (3,), np.float32)
    for w, (ss, sa) in weights_and_materials:
        s += w[..., None] * np.asarray(ss, np.float32)
        a += w[..., None] * np.asarray(sa, np.float32)
    return s, a


def homogeneous(name: str, size_mm, voxel_mm, g=0.0, seed=0) -> Volume:
    """A slab of one material of the Jensen 2001 table."""
    z, _, _ = _grid(size_mm, voxel_mm)
    ss, sa = _coeffs(name, g)
    return Volume.homogeneous(z.shape, voxel_mm, ss, sa, g, ETA, {"generator": f"homogeneous:{name}", "g": g})


def marble(size_mm, voxel_mm, g=0.0, seed=0) -> Volume:
    """White marble with grey-green veins.

    The vein mask is :math:`v = 1 - |\\sin(k x + 6\\,T(\\vec x))|^{0.3}`, T the
    turbulence; veins absorb ~15× more and scatter 40 % less than the body.
    """
    rng = np.random.default_rng(seed)
    z, y, x = _grid(size_mm, voxel_mm)
    turb = _turbulence(z.shape, voxel_mm, rng)
    phase = 2 * np.pi * (x + 0.6 * y) / 7.0 + 6.0 * turb
    vein = np.clip(1.0 - np.abs(np.sin(phase)) ** 0.3, 0.0, 1.0) ** 2
    body = _coeffs("marble", g)
    vein_mat = (0.6 * body[0], np.array([0.030, 0.022, 0.035]) * 1.5)
    s, a = _mix([(1.0 - vein, body), (vein, vein_mat)], z.shape)
    return Volume(s, a, voxel_mm, g, ETA, {"generator": "marble", "seed": seed, "g": g})


def apple_slice(size_mm, voxel_mm, g=0.0, seed=0) -> Volume:
    """A cross-section of an apple: radial flesh with a core and five seeds.

    Flesh is 'apple' with a radial modulation of scattering (vascular ring at
    40 % of the radius); the core (radius 20 %) scatters less; seeds are
    strongly absorbing brown ellipsoids arranged in a star.
    """
    rng = np.random.default_rng(seed)
    z, y, x = _grid(size_mm, voxel_mm)
    w, h, _ = size_mm
    cx, cy = w / 2, h / 2
    radius = 0.5 * min(w, h)
    r = np.hypot(x - cx, y - cy) / radius
    flesh_ss, flesh_sa = _coeffs("apple", g)
    ring = np.exp(-(((r - 0.4) / 0.03) ** 2))
    texture = 1.0 + 0.15 * _noise(z.shape, max(0.3 / voxel_mm, 0.5), rng)
    scale = (texture * (1.0 - 0.3 * ring))[..., None]
    s = (flesh_ss * scale).astype(np.float32)
    a = np.broadcast_to(np.asarray(flesh_sa, np.float32), s.shape).copy()
    core = r < 0.2
    s[core] *= 0.5
    rot = rng.uniform(0, 2 * np.pi)
    for k in range(5):
        ang = rot + 2 * np.pi * k / 5
        sx, sy = cx + 0.12 * radius * np.cos(ang), cy + 0.12 * radius * np.sin(ang)
        du = (x - sx) * np.cos(ang) + (y - sy) * np.sin(ang)
        dv = -(x - sx) * np.sin(ang) + (y - sy) * np.cos(ang)
        seed_mask = (du / (0.08 * radius)) ** 2 + (dv / (0.04 * radius)) ** 2 + (z / (0.04 * radius)) ** 2 < 1
        a[seed_mask] = [0.8, 1.2, 1.6]
        s[seed_mask] = [2.0, 2.0, 2.0]
    outside = r > 1.0
    s[outside] *= 0.05
    return Volume(s, a, voxel_mm, g, ETA, {"generator": "apple-slice", "seed": seed, "g": g})


def skin(size_mm, voxel_mm, g=0.0, seed=0) -> Volume:
    """Skin: a 0.1 mm epidermis with melanin over dermis, pores and freckles.

    Dermis is 'skin2'; the epidermis is 'skin1' with 3× absorption (melanin),
    freckles multiply its absorption by 4, pores are 0.1 mm wide low-scattering
    cylinders 0.5 mm deep.
    """
    rng = np.random.default_rng(seed)
    z, y, x = _grid(size_mm, voxel_mm)
    dermis = _coeffs("skin2", g)
    epi_ss, epi_sa = _coeffs("skin1", g)
    epidermis = z > -max(0.1, voxel_mm)
    freckle = _noise(z.shape[1:], max(0.6 / voxel_mm, 0.5), rng) > 0.45
    s = np.broadcast_to(np.asarray(dermis[0], np.float32), z.shape + (3,)).copy()
    a = np.broadcast_to(np.asarray(dermis[1], np.float32), z.shape + (3,)).copy()
    s[epidermis] = epi_ss
    a[epidermis] = 3.0 * epi_sa
    fr = epidermis & freckle[None]
    a[fr] *= 4.0
    w, h, _ = size_mm
    n_pores = max(1, int(w * h / 4.0))
    px, py = rng.uniform(0, w, n_pores), rng.uniform(0, h, n_pores)
    for cx, cy in zip(px, py):
        pore = (np.hypot(x - cx, y - cy) < max(0.05, voxel_mm / 2)) & (z > -0.5)
        s[pore] *= 0.2
    return Volume(s, a, voxel_mm, g, ETA, {"generator": "skin", "seed": seed, "g": g})


def fibers(size_mm, voxel_mm, g=0.0, seed=0) -> Volume:
    """Jade- or wood-like structure aligned with x.

    Lamellae of weakly scattering, clear material (σ_s ≈ 0.3 mm⁻¹, 1 mm pitch in
    y, 50 % fill, walls jittered in depth) alternate with a strongly scattering
    matrix (σ_s ≈ 8 mm⁻¹).  The coefficients vary across y but never along x,
    so light channels along the lamellae: the reflectance spreads farther along
    x than along y (about 1.5× in rms radius), the case the anisotropic model
    is for.
    """
    rng = np.random.default_rng(seed)
    z, y, x = _grid(size_mm, voxel_mm)
    pitch = max(1.0, 4 * voxel_mm)
    # wall positions wander slowly with depth and y, never with x
    jitter = 0.1 * _noise(z.shape[:2], max(1.0 / voxel_mm, 0.5), rng)[..., None]
    core = np.cos(2 * np.pi * (y / pitch + jitter)) > 0.0
    fiber = (np.array([0.30, 0.32, 0.28]) / (1 - g), np.array([0.003, 0.002, 0.006]))
    matrix = (np.array([7.5, 8.0, 7.0]) / (1 - g), np.array([0.02, 0.012, 0.03]))
    w = np.broadcast_to(core, z.shape).astype(np.float64)
    s, a = _mix([(w, fiber), (1.0 - w, matrix)], z.shape)
    return Volume(s, a, voxel_mm, g, ETA, {"generator": "fibers", "seed": seed, "g": g})


def banded(size_mm, voxel_mm, g=0.0, seed=0) -> Volume:
    """Skin-like bulk ('skin2') crossed by diagonal bands of 'cream' and an absorbing disc.

    Bands 1.5 mm wide at a 3 mm pitch run at 45° through the whole depth, their
    edges softened over 0.25 mm and wandering by ±0.3 mm; the cream scatters
    4–7× more and absorbs far less than the bulk, so light spreads along the
    bands but differently from the lamellae of ``fibers`` (oblique, wider, and
    brighter rather than clearer).  A disc of radius 2 mm, 1 mm deep, at a
    seeded position near the centre absorbs 20× more (a mole or an inclusion).
    """
    rng = np.random.default_rng(seed)
    z, y, x = _grid(size_mm, voxel_mm)
    wobble = 0.3 * _noise(z.shape[1:], max(2.0 / voxel_mm, 0.5), rng)[None]
    u = (x + y) / np.sqrt(2.0) + wobble  # distance along the bands' normal, mm
    band = 0.5 + 0.5 * np.tanh((0.75 - np.abs((u % 3.0) - 1.5)) / 0.25)
    bulk, cream = _coeffs("skin2", g), _coeffs("cream", g)
    s, a = _mix([(1.0 - band, bulk), (band, cream)], z.shape)
    w, h, _ = size_mm
    cx, cy = w / 2 + rng.uniform(-0.15, 0.15) * w, h / 2 + rng.uniform(-0.15, 0.15) * h
    disc = (np.hypot(x - cx, y - cy) < 2.0) & (z > -1.0)
    a[disc] *= 20.0
    return Volume(s, a, voxel_mm, g, ETA, {"generator": "banded", "seed": seed, "g": g})


def layered(size_mm, voxel_mm, g=0.0, seed=0) -> Volume:
    """A clear, wax-like layer over a dense scattering bulk, its depth varying across the sample.

    The top layer is 'skimmilk' with a fifth of its scattering (a long mean free
    path: light runs sideways in it before it meets the bulk); beneath is
    'wholemilk' with 3× its scattering.  The interface lies 0.3–1.2 mm deep,
    following smooth noise on a 3 mm scale, so the profile's shape (not only
    its scale) changes from point to point: a two-slope fall-off whose knee
    moves with the layer's depth.
    """
    rng = np.random.default_rng(seed)
    z, y, x = _grid(size_mm, voxel_mm)
    depth = 0.75 + 0.45 * _noise(z.shape[1:], max(3.0 / voxel_mm, 0.5), rng)[None]  # mm
    top = 0.5 + 0.5 * np.tanh((z + depth) / max(voxel_mm, 0.05))  # 1 above the interface
    clear = (0.2 * _coeffs("skimmilk", g)[0], material("skimmilk").sigma_a)
    dense = (3.0 * _coeffs("wholemilk", g)[0], material("wholemilk").sigma_a)
    s, a = _mix([(top, clear), (1.0 - top, dense)], z.shape)
    return Volume(s, a, voxel_mm, g, ETA, {"generator": "layered", "seed": seed, "g": g})


def make_sample(name: str, size_mm, voxel_mm: float, *, g: float = 0.0, seed: int = 0) -> Volume:
    """Build a sample volume by generator name (see the module table).

    Examples
    --------
    >>> from translucency import make_sample
    >>> v = make_sample("homogeneous:marble", (4.0, 4.0, 2.0), 0.5)
    >>> v.shape
    (4, 8, 8)
    """
    size_mm = tuple(float(v) for v in size_mm)
    if len(size_mm) != 3 or min(size_mm) <= 0 or not np.isfinite(size_mm).all():
        raise TranslucencyError(
            f"size: expected three positive lengths (width, height, thickness) in mm, got {size_mm}"
        )
    if not (np.isfinite(voxel_mm) and voxel_mm > 0):
        raise TranslucencyError(f"voxel: must be a positive length in mm, got {voxel_mm}")
    if not -1.0 < g < 1.0:
        raise TranslucencyError(f"g: must lie in (-1, 1), got {g}")
    n_vox = np.prod([max(1, round(v / voxel_mm)) for v in size_mm])
    if n_vox > 64_000_000:
        raise TranslucencyError(f"voxel: {voxel_mm} mm gives {n_vox:,.0f} voxels (> 64 M); use larger voxels")
    if name.startswith("homogeneous:"):
        mat = name.split(":", 1)[1]
        if mat.lower() not in MATERIALS:
            raise TranslucencyError(f"material: unknown {mat!r}; choose homogeneous:<{'|'.join(MATERIALS)}>")
        return homogeneous(mat.lower(), size_mm, voxel_mm, g, seed)
    table = {
        "marble": marble,
        "apple-slice": apple_slice,
        "skin": skin,
        "fibers": fibers,
        "banded": banded,
        "layered": layered,
    }
    if name not in table:
        raise TranslucencyError(f"material: unknown sample {name!r}; choose one of {', '.join(GENERATORS)}")
    return table[name](size_mm, voxel_mm, g, seed)


def sample_of_dataset(header: dict) -> Volume:
    """Rebuild the generated sample a data set was acquired from (its header's ``sample``).

    Only generated samples can be rebuilt (their generator, seed, size and voxel
    are recorded); a user's volume cannot.
    """
    s = header.get("sample", {})
    d = s.get("description", {})
    if "generator" not in d or "size_mm" not in s:
        raise TranslucencyError(
            "data set: its sample was not made by a generator here (a user's volume or "
            "data); pass the volume itself"
        )
    return make_sample(d["generator"], s["size_mm"], s["voxel_mm"], g=s.get("g", 0.0), seed=d.get("seed", 0))
