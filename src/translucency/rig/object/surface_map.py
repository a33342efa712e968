r"""Photographs resampled onto the mesh's vertices: visibility once per camera, a sparse map per camera.

Where the per-vertex value is defined: as :mod:`translucency.acquire.mesh` tallies it, the
:math:`\phi_v`-weighted mean over the vertex's cell,

.. math:: R_d(x_i, v) = \frac{\int \phi_v(y)\, R_d(x_i, y)\, dA(y)}{\int \phi_v\, dA},

with :math:`\phi_v` the barycentric hat function of v.  A camera samples the surface at the points
:math:`y_p` its pixel centres' rays hit first (Mitsuba ray casting against the mesh: depth-tested by
construction), each standing for the footprint :math:`a_p = \Omega_p d_p^2/\mu_p` (the pixel's solid
angle Ω_p, the distance d_p, the cosine μ_p between the view and the face normal), so

.. math:: \hat R_d(x_i, v) = \frac{\sum_p \phi_v(y_p)\, a_p\, M(y_p)}{\sum_p \phi_v(y_p)\, a_p}

is the same integral by quadrature over the part of the cell the camera sees — the import and the
tally agree by construction where the cell is seen whole (``coverage`` = Σ φ_v a_p / A_v near 1).
Pixels on back faces (μ ≤ 0) do not occur for a closed mesh; pixels at grazing views (μ below
cos ``grazing_deg``) are left out and counted.  The map is the sparse matrix
:math:`W_{vp} = \phi_v(y_p) a_p` (V × pixels), built once per camera; every photograph is then a
sparse product.
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


def surface_map(mesh, camera: Camera, *, grazing_deg: float = GRAZING_DEG, scene=None) -> SurfaceMap:
    """Cast a ray through every pixel centre of ``camera`` against ``mesh`` (Mitsuba) and build its map.

    Refuses, in one line, a camera that sees no vertex of the mesh.

    Examples
    --------
    >>> import trimesh
    >>> mesh = trimesh.creation.icosphere(subdivisions=2, radius=5.0)
    >>> cam = Camera.looking_at((0.0, 0.0, 40.0), (0.0, 0.0, 0.0), 64, 64, fov_deg=20.0)
    >>> m = surface_map(mesh, cam)
    >>> bool(m.den[np.argmax(mesh.vertices[:, 2])] > 0), bool(m.den[np.argmin(mesh.vertices[:, 2])] > 0)
    (True, False)
    """
    import trimesh  # heavy: trimesh loads only where a surface is mapped

    scene = scene if scene is not None else mesh_scene(mesh)
    origins, directions, omega = camera.pixel_rays()
    n_pix = len(directions)
    si = scene.ray_intersect(rays(origins, directions))
    hit = np.asarray(si.is_valid(), dtype=bool)
    face = np.asarray(si.prim_index, dtype=np.int64)[hit]
    t = np.asarray(si.t, dtype=np.float64)[hit]
    faces = np.asarray(mesh.faces)
    verts = np.asarray(mesh.vertices, dtype=np.float64)
    p = origins[hit] + t[:, None] * directions[hit]  # the hit in float64 from the ray's distance
    fn = np.asarray(mesh.face_normals, dtype=np.float64)[face]
    mu_hit = -np.einsum("ij,ij->i", directions[hit], fn)
    position = np.full((n_pix, 3), np.nan)
    position[hit] = p
    normal = np.full((n_pix, 3), np.nan)
    normal[hit] = fn
    mu = np.zeros(n_pix)
    mu[hit] = np.clip(mu_hit, 0.0, 1.0)
    tri = faces[face]
    bary = trimesh.triangles.points_to_barycentric(verts[tri], p)
    bary = np.clip(np.nan_to_num(bary, nan=1.0 / 3.0), 0.0, None)
    bary /= np.maximum(bary.sum(axis=1, keepdims=True), 1e-12)
    cos_min = np.cos(np.radians(grazing_deg))
    use = mu_hit > cos_min
    area = omega[hit] * t**2 / np.maximum(mu_hit, 1e-6)  # the footprint a_p, mm²
    pix = np.flatnonzero(hit)
    V = len(verts)
    rows = tri[use].ravel()
    cols = np.repeat(pix[use], 3)
    vals = (bary[use] * area[use, None]).ravel()
    W = sp.csr_matrix((vals, (rows, cols)), shape=(V, n_pix))
    W2 = sp.csr_matrix((vals**2, (rows, cols)), shape=(V, n_pix))
    den = np.asarray(W.sum(axis=1)).ravel()
    if not (den > 0).any():
        raise TranslucencyError(f"{camera.name}: sees no vertex of the mesh (check its pose and the mesh)")
    touched = np.zeros(V, dtype=bool)
    touched[tri.ravel()] = True
    grazing = touched & (den <= 0)
    with np.errstate(invalid="ignore", divide="ignore"):
        mu_v = np.where(den > 0, (W @ mu) / den, 0.0)
    return SurfaceMap(camera, W, W2, mu, position, normal, -directions, den, grazing, mu_v)


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


__all__ = ["SurfaceMap", "surface_map", "projects_inside", "GRAZING_DEG"]
