r"""Photographs resampled onto the mesh's vertices: visibility once per camera, a sparse map per camera.

Where the per-vertex value is defined: as :mod:`translucency.acquire.mesh` tallies it, the
:math:`\phi_v`-weighted mean over the vertex's cell,

.. math:: R_d(x_i, v) = \frac{\int \phi_v(y)\, R_d(x_i, y)\, dA(y)}{\int \phi_v\, dA},

with :math:`\phi_v` the barycentric hat function of v.  A camera samples the surface at the points
:math:`y_s` its rays hit first (Mitsuba ray casting against the mesh: depth-tested by construction),
``sub`` × ``sub`` rays through each pixel, each standing for its share of the pixel's footprint
:math:`a_s = \Omega_s d_s^2/\mu_s` (the ray's solid angle Ω_s, the distance d_s, the cosine μ_s between
the view and the face normal) and carrying its pixel's value :math:`M_{p(s)}`, so

.. math:: \hat R_d(x_i, v) = \frac{\sum_s \phi_v(y_s)\, a_s\, M_{p(s)}}{\sum_s \phi_v(y_s)\, a_s}

is the same integral by quadrature over the part of the cell the camera sees, of M averaged over a
pixel's footprint — the import and the tally agree where the cell is seen whole (``coverage`` =
Σ φ_v a_s / A_v near 1), and since every pixel's footprint is shared among all the cells it covers,
:math:`\sum_v A_v \hat R_d` = Σ_p a_p M_p keeps a shot's energy whatever the cells' size.  The
resolution rule (:func:`subpixels`): rays enough that the finer cells get :data:`RAYS_PER_CELL` each
(one ray a pixel where cells span several pixels; a cell of a quarter pixel gets 4 × 4 rays a pixel).
Below :data:`MAX_SUB` ² rays a pixel a cell is still measured, by fewer rays.  A cell finer than a pixel
holds its pixels' mean: its value is blurred over a footprint (its energy kept).
Pixels on back faces (μ ≤ 0) do not occur for a closed mesh; rays at grazing views (μ below
cos ``grazing_deg``) are left out and counted.  The map is the sparse matrix
:math:`W_{vp} = \sum_{s \in p} \phi_v(y_s) a_s` (V × pixels), built once per camera; every photograph
is then a sparse product.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..._validate import TranslucencyError
from ...mitsuba import mesh_scene, rays
from .cameras import Camera

#: pixels seen at more than this angle from the normal are not used (degrees)
GRAZING_DEG = 75.0
#: the rays a fine cell should get from a camera (the resolution rule of :func:`subpixels`)
RAYS_PER_CELL = 4
#: the most rays a pixel side (MAX_SUB² a pixel)
MAX_SUB = 6


@dataclass
class SurfaceMap:
    r"""One camera's view of the mesh.

    Attributes
    ----------
    camera : Camera
    W : scipy.sparse.csr_matrix, shape (V, H·W)
        :math:`\phi_v(y_p) a_p` (mm²) for the pixels used; pixels are numbered row by row.
    W2 : scipy.sparse.csr_matrix
        W with squared entries (the variance's weights).
    mu : ndarray, shape (H·W,)
        The cosine of each pixel's view to the face normal (0 where the ray misses).
    position : ndarray, shape (H·W, 3)
        Where each pixel's ray hits (NaN where it misses), mm.
    normal : ndarray, shape (H·W, 3)
        The outward normal of the triangle it hits (NaN where it misses).
    view : ndarray, shape (H·W, 3)
        The unit direction from the hit towards the camera.
    den : ndarray, shape (V,)
        Σ_p W_vp: the part of each vertex's area the camera sees well, mm².
    grazing : ndarray of bool, shape (V,)
        Vertices hit by the camera's rays only at grazing angles.
    mu_v : ndarray, shape (V,)
        The W-weighted mean cosine per vertex (0 where unseen).
    sub : int
        Rays a pixel side that built W (sub² a pixel).
    rays : tuple of ndarray
        The rays that meet the mesh (grazing ones too): their pixel (n,), where they hit (n, 3) mm,
        their solid angle Ω_s (n,) sr, footprint a_s (n,) mm² and face (n,) — a pixel's reading of the
        exitance M of a Lambertian surface is its radiance times π, :math:`\sum_s \Omega_s M(y_s) /
        \sum_s \Omega_s` over its rays that meet the mesh (the silhouette's share divided out,
        ``hit_share``).
    hit_share : ndarray, shape (H·W,)
        The share of each pixel's solid angle whose rays meet the mesh (by its sub-pixel rays; 0 or 1 at
        one ray a pixel): a pixel on the silhouette reads the mean over its whole solid angle, the dark
        background included, so its reading over the surface is the value divided by this share.
    """

    camera: Camera
    W: sp.csr_matrix
    W2: sp.csr_matrix
    mu: np.ndarray
    position: np.ndarray
    normal: np.ndarray
    view: np.ndarray
    den: np.ndarray
    grazing: np.ndarray
    mu_v: np.ndarray
    sub: int = 1
    rays: tuple = ()
    hit_share: np.ndarray | None = None

    def __post_init__(self):
        self._used = np.flatnonzero(np.diff(self.W.tocsc().indptr) > 0)  # the columns W uses
        self._Wu = self.W[:, self._used].tocsr()
        self._W2u = self.W2[:, self._used].tocsr()
        w2 = np.asarray(self.W2.sum(axis=1)).ravel()
        #: each vertex's effective number of pixels (Σ W)² / Σ W² (0 where unseen)
        self.n_eff = np.divide(self.den**2, w2, out=np.zeros_like(self.den), where=w2 > 0)

    def slant(self, hit: np.ndarray, pixels=slice(None)) -> np.ndarray:
        """s = ω·t̂ per pixel (of ``pixels``): the view towards the camera against the unit tangent
        pointing away from the laser's ``hit`` (0 where the ray misses)."""
        n = self.normal[pixels]
        t = self.position[pixels] - hit
        t -= np.einsum("ij,ij->i", t, n)[:, None] * n
        t /= np.maximum(np.linalg.norm(t, axis=1, keepdims=True), 1e-12)
        return np.nan_to_num(np.einsum("ij,ij->i", self.view[pixels], t))

    def sample_pixels(self, pixels: np.ndarray, sub: int, scene, mesh) -> tuple:
        """The rays through ``pixels`` (indices, ascending), ``sub`` × ``sub`` each, that meet the mesh: as
        :attr:`rays` (pixel, point, solid angle, footprint, face)."""
        origins, directions, omega = self.camera.pixel_rays(sub, pixels=pixels)
        cast = _cast(scene, mesh, origins, directions, omega)
        return _ray_readings(np.repeat(np.asarray(pixels), sub * sub)[cast.hit], cast)

    def coverage(self, area: np.ndarray) -> np.ndarray:
        """Σ_p W_vp / A_v: the fraction of each vertex's cell this camera measures."""
        return self.den / np.maximum(area, 1e-30)

    @property
    def used(self) -> np.ndarray:
        """The pixels W uses (indices, row by row): only these need reading from a photograph."""
        return self._used

    def cell_means(self, image: np.ndarray, variance: np.ndarray, usable: np.ndarray):
        """Per-vertex means of a per-pixel quantity over the usable pixels, and their variances: (V, 3)
        each, NaN where no usable pixel covers the vertex; and the usable weight (V,).  ``image``,
        ``variance`` (n, 3) and ``usable`` (n,) hold either every pixel (n = H·W) or the used ones
        (n = len(:attr:`used`))."""
        if len(usable) != len(self._used):
            image, variance, usable = image[self._used], variance[self._used], usable[self._used]
        ok = usable.astype(image.dtype)
        den = np.asarray(self._Wu @ ok, dtype=np.float64)
        with np.errstate(invalid="ignore", divide="ignore"):
            mean = (self._Wu @ (image * ok[:, None])) / den[:, None]
            var = (self._W2u @ (variance * ok[:, None])) / (den**2)[:, None]
        mean[den <= 0] = np.nan
        var[den <= 0] = np.nan
        return mean, var, den


def surface_map(
    mesh, camera: Camera, *, grazing_deg: float = GRAZING_DEG, scene=None, sub: int | None = None
) -> SurfaceMap:
    """Cast rays through ``camera``'s pixels against ``mesh`` (Mitsuba) and build its map.

    The pixels' geometry (``position``, ``normal``, ``mu``) is that of the ray through each pixel centre;
    the map W shares each pixel's footprint among every cell it covers, by ``sub`` × ``sub`` rays a pixel
    (default :func:`subpixels`: enough that the finer cells get :data:`RAYS_PER_CELL` rays).  Refuses,
    in one line, a camera that sees no vertex of the mesh.

    Examples
    --------
    >>> import trimesh
    >>> mesh = trimesh.creation.icosphere(subdivisions=2, radius=5.0)
    >>> cam = Camera.looking_at((0.0, 0.0, 40.0), (0.0, 0.0, 0.0), 64, 64, fov_deg=20.0)
    >>> m = surface_map(mesh, cam)
    >>> bool(m.den[np.argmax(mesh.vertices[:, 2])] > 0), bool(m.den[np.argmin(mesh.vertices[:, 2])] > 0)
    (True, False)
    >>> m.sub  # cells of tens of pixels: one ray a pixel
    1
    """
    scene = scene if scene is not None else mesh_scene(mesh)
    verts = np.asarray(mesh.vertices, dtype=np.float64)
    faces = np.asarray(mesh.faces)
    V = len(verts)
    cos_min = np.cos(np.radians(grazing_deg))
    # the pixel centres: each pixel's point, normal and view
    centre = _cast(scene, mesh, *camera.pixel_rays())
    n_pix = len(centre.hit)
    position = np.full((n_pix, 3), np.nan)
    position[centre.hit] = centre.p
    normal = np.full((n_pix, 3), np.nan)
    normal[centre.hit] = centre.fn
    mu = np.zeros(n_pix)
    mu[centre.hit] = np.clip(centre.mu, 0.0, 1.0)
    view = -centre.directions
    # the footprints: sub × sub rays a pixel, each a_s = Ω_s d_s²/μ_s shared by barycentric weight
    sub = int(sub) if sub is not None else subpixels(mesh, centre, cos_min)
    if sub == 1:
        rays_, hit_share = centre, centre.hit.astype(np.float64)
    else:
        origins, directions, omega = camera.pixel_rays(sub)  # sub² rays a pixel, pixel after pixel
        rays_ = _cast(scene, mesh, origins, directions, omega)
    use = rays_.mu > cos_min
    pixel = np.flatnonzero(rays_.hit) // sub**2
    if sub > 1:  # the share of each pixel's solid angle that meets the mesh (a silhouette's pixel: part)
        met = np.bincount(pixel, weights=rays_.omega, minlength=n_pix)
        hit_share = met / omega.reshape(n_pix, sub**2).sum(axis=1)
    area = rays_.footprint(1e-6)  # a_s, mm² (the rays W uses face the camera)
    tri = faces[rays_.face]
    rows = tri[use].ravel()
    cols = np.repeat(pixel[use], 3)
    vals = (rays_.bary[use] * area[use, None]).ravel()
    W = sp.csr_matrix((vals, (rows, cols)), shape=(V, n_pix))  # duplicates (sub-rays of a pixel) summed
    W2 = W.multiply(W).tocsr()  # the variance's weights: a pixel's value is one reading for its cell
    den = np.asarray(W.sum(axis=1)).ravel()
    if not (den > 0).any():
        raise TranslucencyError(f"{camera.name}: sees no vertex of the mesh (check its pose and the mesh)")
    touched = np.zeros(V, dtype=bool)
    touched[tri.ravel()] = True
    grazing = touched & (den <= 0)
    with np.errstate(invalid="ignore", divide="ignore"):
        mu_v = np.where(den > 0, (W @ mu) / den, 0.0)
    # every ray that meets the mesh, grazing ones too: a pixel reads the solid-angle mean of what its rays see
    rays = _ray_readings(pixel, rays_)
    return SurfaceMap(camera, W, W2, mu, position, normal, view, den, grazing, mu_v, sub, rays, hit_share)


def _ray_readings(pixel, c: _Cast) -> tuple:
    """(pixel, point, solid angle, footprint a_s mm², face) of the rays that met the mesh (a grazing
    ray's footprint long, not infinite: μ held at 0.05 or more)."""
    footprint = c.footprint(0.05).astype(np.float32)
    return pixel, c.p.astype(np.float32), c.omega.astype(np.float32), footprint, c.face


@dataclass
class _Cast:
    """Rays cast against the mesh: which hit (N,), and for the hits the face, distance t (mm), point p,
    face normal, cosine μ to the ray, barycentric coordinates; the rays' directions and solid angles."""

    hit: np.ndarray
    face: np.ndarray
    t: np.ndarray
    p: np.ndarray
    fn: np.ndarray
    mu: np.ndarray
    bary: np.ndarray
    directions: np.ndarray
    omega: np.ndarray

    def footprint(self, mu_floor: float) -> np.ndarray:
        """Each hit's footprint on the surface a_s = Ω t²/μ, mm², μ held at ``mu_floor`` or more."""
        return self.omega * self.t**2 / np.maximum(np.abs(self.mu), mu_floor)


def _cast(scene, mesh, origins, directions, omega) -> _Cast:
    import trimesh  # heavy: trimesh loads only where a surface is mapped

    si = scene.ray_intersect(rays(origins, directions))
    hit = np.asarray(si.is_valid(), dtype=bool)
    face = np.asarray(si.prim_index, dtype=np.int64)[hit]
    t = np.asarray(si.t, dtype=np.float64)[hit]
    p = origins[hit] + t[:, None] * directions[hit]  # the hit in float64 from the ray's distance
    fn = np.asarray(mesh.face_normals, dtype=np.float64)[face]
    mu = -np.einsum("ij,ij->i", directions[hit], fn)
    tri = np.asarray(mesh.faces)[face]
    bary = trimesh.triangles.points_to_barycentric(np.asarray(mesh.vertices, dtype=np.float64)[tri], p)
    bary = np.clip(np.nan_to_num(bary, nan=1.0 / 3.0), 0.0, None)
    bary /= np.maximum(bary.sum(axis=1, keepdims=True), 1e-12)
    return _Cast(hit, face, t, p, fn, mu, bary, directions, omega[hit])


def subpixels(mesh, centre: _Cast, cos_min: float) -> int:
    r"""Rays a pixel side so that the finer cells a camera sees get :data:`RAYS_PER_CELL` rays: the
    resolution rule.

    With :math:`\bar a` the median footprint of a pixel on the surface and :math:`A_{10}` the 10th
    percentile of the seen vertices' cell areas, ``sub`` = ⌈√(RAYS_PER_CELL · ā / A₁₀)⌉, between 1 and
    :data:`MAX_SUB`.  A cell finer than a pixel is then measured by the footprints that cover it, not
    left to the fill."""
    from ...geometry import vertex_areas  # heavy: trimesh loads only where a surface is mapped

    use = centre.mu > cos_min
    if not use.any():
        return 1
    footprint = centre.omega[use] * centre.t[use] ** 2 / centre.mu[use]
    seen = np.unique(np.asarray(mesh.faces)[centre.face[use]].ravel())
    A = np.percentile(vertex_areas(mesh)[seen], 10)
    need = np.sqrt(RAYS_PER_CELL * np.median(footprint) / max(A, 1e-30))
    return int(np.clip(np.ceil(need), 1, MAX_SUB))


def projects_inside(mesh, camera: Camera) -> np.ndarray:
    """Which vertices of ``mesh`` lie in front of ``camera`` and project inside its image (V,) — a mesh
    that is not the one the cameras saw has most vertices outside every image."""
    X = np.asarray(mesh.vertices, dtype=np.float64)
    inside = camera.depth(X) > 0
    if inside.any():  # (OpenCV projects no empty set of points)
        uv = camera.project(X[inside])
        ok = (uv[:, 0] >= -0.5) & (uv[:, 1] >= -0.5)
        ok &= (uv[:, 0] <= camera.width - 0.5) & (uv[:, 1] <= camera.height - 0.5)
        inside[inside] = ok
    return inside


__all__ = [
    "SurfaceMap",
    "surface_map",
    "subpixels",
    "projects_inside",
    "GRAZING_DEG",
    "RAYS_PER_CELL",
    "MAX_SUB",
]
