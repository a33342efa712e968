r"""The triangle mesh of a model file, compressed: Google's Draco (edgebreaker connectivity, positions
quantised on a grid and predicted along the mesh) through DracoPy.

Draco renumbers the vertices as it walks the mesh; a model's per-vertex arrays (α, the parameters, the
measured near field) are indexed by the original numbering, so each vertex carries its original index
as a generic attribute and :func:`decode_mesh` puts the vertices back in that order (the triangles keep
their orientation; their order is Draco's).

The quantisation step is 1 % of the median edge (``STEP_OF_EDGE``), on a grid of
:math:`2^b` cells over the mesh's largest extent, :math:`b` between ``MIN_BITS`` and ``MAX_BITS``:
the positions move by at most half a step, far below what a picture or the transport can tell
(a model renders within 0.005 of its uncompressed self; ``tests/test_model_file.py``).  A mesh with
triangles far smaller than its median edge (marching cubes puts vertices nanometres apart) would lose
or turn the normals of their vertices on that grid: then the fewest bits (bisected up to ``MAX_BITS``,
float32's own precision) that keep every vertex normal within ``NORMAL_TURN_DEG`` of its own.  A mesh Draco
would change (vertices it would merge or drop, a degenerate triangle it would skip) is not
compressed: :func:`encode_mesh` returns None and the model file keeps the arrays as they are.
"""

from __future__ import annotations

import numpy as np

from ..geometry import same_triangles

#: quantisation step as a fraction of the median edge length
STEP_OF_EDGE = 0.01
#: bounds on the quantisation bits per coordinate
MIN_BITS, MAX_BITS = 11, 24
#: the most a vertex normal may turn on the grid (else more bits: :func:`encode_mesh`), degrees
NORMAL_TURN_DEG = 60.0
#: Draco's compression level (0 fastest … 10 smallest; 10 costs ~0.1 µs a vertex more than 7)
LEVEL = 10


def quantization_bits(vertices: np.ndarray, faces: np.ndarray) -> int:
    """Bits per coordinate that make the grid step at most ``STEP_OF_EDGE`` of the median edge."""
    v = np.asarray(vertices, np.float64)
    f = np.asarray(faces)
    edges = np.linalg.norm(v[f[:, [1, 2, 0]]] - v[f], axis=2).ravel()
    step = STEP_OF_EDGE * float(np.median(edges[edges > 0])) if (edges > 0).any() else 1.0
    extent = float(np.ptp(v, axis=0).max()) or 1.0
    return int(np.clip(np.ceil(np.log2(extent / step)), MIN_BITS, MAX_BITS))


def encode_mesh(vertices: np.ndarray, faces: np.ndarray):
    """Draco bytes of the mesh and the (vertices (V, 3) float32, faces (F, 3) int32) they decode to, in
    the original vertex order; None where Draco would change the mesh (module docstring).

    Examples
    --------
    >>> import trimesh
    >>> ball = trimesh.creation.icosphere(3)
    >>> data, v, f = encode_mesh(ball.vertices, ball.faces)
    >>> len(data) < (ball.vertices.nbytes // 2 + ball.faces.nbytes // 2) // 4  # float32 + int32 arrays
    True
    >>> bool(np.abs(v - ball.vertices).max() < 1e-3)
    True
    """
    import DracoPy  # compiled codec: loads where a model file with a mesh is written or read

    v = np.ascontiguousarray(vertices, np.float32)
    f = np.ascontiguousarray(faces, np.uint32)
    if len(v) == 0 or len(f) == 0 or len(v) >= 2**32:
        return None
    index = np.arange(len(v), dtype=np.uint32)[:, None]
    normals = _area_normals(v, f)
    tried = {}

    def attempt(bits):
        """(bytes, vertices, faces) at ``bits``; None where Draco changes the mesh, False where the
        normals do not hold."""
        if bits not in tried:
            try:
                data = DracoPy.encode(
                    v, f, quantization_bits=bits, compression_level=LEVEL, generic_attributes={"index": index}
                )
                dv, df = decode_mesh(data)
            except Exception:  # noqa: BLE001 — any codec failure: the mesh is stored as it is
                dv, df, data = None, None, None
            if dv is None or dv.shape != v.shape or not same_triangles(df, f):
                tried[bits] = None
            else:
                tried[bits] = (data, dv, df) if _normals_kept(normals, _area_normals(dv, f)) else False
        return tried[bits]

    # the fewest bits that keep the normals: the edge's grid, else bisected up to MAX_BITS
    lo = quantization_bits(v, f)
    if attempt(lo) is not False:
        return tried[lo]
    if not attempt(MAX_BITS):
        return None
    hi = MAX_BITS
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if attempt(mid) is None:
            return None
        lo, hi = (mid, hi) if attempt(mid) is False else (lo, mid)
    return tried[hi]


def _area_normals(v: np.ndarray, f: np.ndarray) -> np.ndarray:
    """(V, 3) each vertex's sum of its triangles' area vectors (unnormalised)."""
    v = np.asarray(v, np.float64)
    c = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    n = np.zeros((len(v), 3))
    for corner in range(3):
        for axis in range(3):
            n[:, axis] += np.bincount(f[:, corner], c[:, axis], minlength=len(v))
    return n


def _normals_kept(before: np.ndarray, after: np.ndarray) -> bool:
    """Whether every vertex normal that was defined stays defined and within ``NORMAL_TURN_DEG`` — a
    mesh with triangles a few nanometres across (marching cubes, then subdivided) turns or loses the
    normals of their vertices on a grid a hundredth of an edge fine, and takes more bits."""
    lb, la = np.linalg.norm(before, axis=1), np.linalg.norm(after, axis=1)
    defined = lb > 0
    cos = np.einsum("vk,vk->v", before, after)[defined] / np.maximum(lb * la, 1e-300)[defined]
    return bool((cos >= np.cos(np.radians(NORMAL_TURN_DEG))).all())


def decode_mesh(data: bytes):
    """(vertices (V, 3) float32, faces (F, 3) int32) of Draco bytes from :func:`encode_mesh`, in the
    original vertex order."""
    import DracoPy  # compiled codec (encode_mesh)

    mesh = DracoPy.decode(bytes(data))
    index = np.asarray(mesh.get_attribute_by_name("index")["data"]).reshape(-1).astype(np.int64)
    points = np.asarray(mesh.points, np.float32).reshape(-1, 3)
    if len(index) != len(points) or not np.array_equal(np.sort(index), np.arange(len(points))):
        raise ValueError("the vertices' original indices are not a permutation")
    vertices = np.empty_like(points)
    vertices[index] = points  # decoded vertex k was the original vertex index[k]
    faces = index[np.asarray(mesh.faces, np.int64).reshape(-1, 3)].astype(np.int32)
    return vertices, faces
