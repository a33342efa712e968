"""Mitsuba scenes built from our arrays: ray wavefronts, meshes, media from volumes, and every scene.

One home for handing our data to Mitsuba 3 (every ``load_dict`` of the package is here), used by the
acquisition (photon walks in a mesh), the renderer (shadow rays, :func:`vertex_radiance_scene` for our
picture, :func:`object_volpath_scene` for the reference), the validation harness and the virtual rig
(:func:`slab_scene`: the slab under ``volpath``; :func:`markers_scene` and :func:`checkerboard_scene`,
its calibration targets).  Units: mm, coefficients in mm⁻¹.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np

from ._engine import mitsuba
from .sensors import look_at

#: an rr_depth that ``volpath`` never reaches: Russian roulette off (see :func:`slab_scene`)
NO_ROULETTE = 1 << 30
#: Mitsuba's ``spot`` emitter: full intensity up to this fraction of the cutoff angle (its default
#: ``beam_width``), then falling linearly in angle to 0 at the cutoff
SPOT_BEAM_FRACTION = 0.75


def rays(origins: np.ndarray, directions: np.ndarray, maxt: np.ndarray | None = None):
    """A Mitsuba ``Ray3f`` wavefront from (N, 3) origins and directions (mm), optionally ending at
    ``maxt``.

    Examples
    --------
    >>> ray = rays(np.array([[0.0, 0, 5], [1, 0, 5]]), np.array([[0.0, 0, -1], [0, 0, -1]]), maxt=[10.0, 3.0])
    >>> ray.o.z.numpy().tolist(), ray.maxt.numpy().tolist()   # two rays (float32) in one wavefront
    ([5.0, 5.0], [10.0, 3.0])
    """
    mi = mitsuba()
    ray = mi.Ray3f(
        mi.Point3f(*(np.ascontiguousarray(origins[:, j]).astype(np.float32) for j in range(3))),
        mi.Vector3f(*(np.ascontiguousarray(directions[:, j]).astype(np.float32) for j in range(3))),
    )
    if maxt is not None:
        ray.maxt = mi.Float(np.asarray(maxt, dtype=np.float32))
    return ray


def write_ply(
    path: Path,
    vertices: np.ndarray,
    faces: np.ndarray,
    colour: np.ndarray | None = None,
    comment: str | None = None,
) -> None:
    """A binary PLY with float positions and (optionally) float r, g, b per vertex (Mitsuba's
    vertex_color); ``comment``: one header line (``comment ...``).

    Examples
    --------
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     write_ply(Path(tmp) / "t.ply", np.eye(3), np.array([[0, 1, 2]]), comment="comment one triangle")
    ...     head, body = (Path(tmp) / "t.ply").read_bytes().split(b"end_header\\n")
    >>> head.decode().splitlines()[2:4]
    ['comment one triangle', 'element vertex 3']
    >>> len(body)   # 3 vertices × 3 float32 + one face: a count byte and 3 int32
    49
    """
    props = "property float x\nproperty float y\nproperty float z\n"
    cols = [np.asarray(vertices)]
    if colour is not None:
        props += "property float r\nproperty float g\nproperty float b\n"
        cols.append(np.asarray(colour))
    note = f"{comment}\n" if comment else ""
    head = (
        f"ply\nformat binary_little_endian 1.0\n{note}element vertex {len(vertices)}\n{props}"
        f"element face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n"
    )
    face = np.zeros(len(faces), dtype=[("n", "u1"), ("i", "<i4", 3)])
    face["n"], face["i"] = 3, faces
    with open(path, "wb") as f:
        f.write(head.encode())
        f.write(np.concatenate(cols, axis=1).astype("<f4").tobytes())
        f.write(face.tobytes())


def load_with_mesh(mesh, scene: dict, *, key: str = "object", colour: np.ndarray | None = None):
    """``mi.load_dict(scene)`` with ``scene[key]`` completed as a ``ply`` shape holding ``mesh``.

    The mesh travels through a temporary binary PLY (positions, optionally
    ``vertex_color``); the entries already in ``scene[key]`` (BSDF, emitter,
    interior medium, ``face_normals``) are kept.

    ``mesh``: anything with ``vertices`` and ``faces`` (a :class:`trimesh.Trimesh`).

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> tetra = SimpleNamespace(vertices=np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]),
    ...                         faces=np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]))
    >>> shape = load_with_mesh(tetra, {"type": "scene"}).shapes()[0]
    >>> shape.vertex_count(), shape.face_count()
    (4, 4)
    """
    mi = mitsuba()
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "object.ply"
        write_ply(path, np.asarray(mesh.vertices), np.asarray(mesh.faces), colour)
        scene = {**scene, key: {"type": "ply", "filename": str(path), **scene.get(key, {})}}
        return mi.load_dict(scene)


def mesh_scene(mesh):
    """A Mitsuba scene holding only the mesh, with face normals (for ray tests and boundary hits).

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> tetra = SimpleNamespace(vertices=np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]),
    ...                         faces=np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]))
    >>> hit = mesh_scene(tetra).ray_intersect(rays(np.array([[0.2, 0.2, 5.0], [2, 2, 5]]),
    ...                                            np.array([[0.0, 0, -1], [0, 0, -1]])))
    >>> hit.is_valid().numpy().tolist(), round(float(hit.t.numpy()[0]), 4)  # face x + y + z = 1 at z = 0.6
    ([True, False], 4.4)
    """
    return load_with_mesh(mesh, {"type": "scene", "object": {"face_normals": True}})


def _grid_dict(data_zyx: np.ndarray, to_world) -> dict:
    """A one-channel nearest-neighbour ``gridvolume`` over the box from our (Z, Y, X) layout.

    Mitsuba indexes the grid [z, y, x] from local z = 0, which ``to_world``
    puts at the bottom of the box; our index 0 is the top layer, so z is flipped.
    """
    mi = mitsuba()
    grid = np.ascontiguousarray(data_zyx[::-1, :, :, None], dtype=np.float32)
    return {"type": "gridvolume", "data": mi.TensorXf(grid), "filter_type": "nearest", "to_world": to_world}


def slab_medium_dict(
    volume, channel: int, top_corner=(0.0, 0.0, 0.0), *, placed=None, unit_mm: float = 1.0
) -> dict:
    """Mitsuba ``heterogeneous`` medium equal to one channel of ``volume`` (grey, mm⁻¹).

    σ_t = σ_s + σ_a and the albedo σ_s/σ_t are nearest-neighbour grids; the
    phase function is Henyey–Greenstein with the volume's g.  The volume's box
    spans x from ``top_corner[0]``, y from ``top_corner[1]`` and z downwards
    from ``top_corner[2]`` (slabs: the origin; objects: (lo.x, lo.y, hi.z)).  ``placed`` (4 × 4) carries
    that box into a scene whose unit is ``unit_mm`` millimetres (the coefficients scaled to per scene unit).

    Examples
    --------
    >>> from translucency.acquire import Volume
    >>> slab = Volume.homogeneous((4, 8, 8), 0.5, sigma_s=[1.0] * 3, sigma_a=[0.01] * 3, g=0.3)
    >>> medium = slab_medium_dict(slab, 0)
    >>> medium["type"], medium["phase"], medium["sigma_t"]["data"].shape   # grids (Z, Y, X, 1)
    ('heterogeneous', {'type': 'hg', 'g': 0.3}, (4, 8, 8, 1))
    >>> round(float(medium["albedo"]["data"].numpy().max()), 4)   # σ_s / σ_t = 1 / 1.01
    0.9901
    """
    mi = mitsuba()
    W, H, T = volume.size_mm
    x0, y0, z_top = (float(v) for v in top_corner)
    box = mi.ScalarTransform4f().translate([x0, y0, z_top - T]) @ mi.ScalarTransform4f().scale([W, H, T])
    if placed is not None:
        box = mi.ScalarTransform4f(np.asarray(placed, dtype=np.float64).tolist()) @ box
    sigma_t = volume.sigma_t[..., channel].astype(np.float64)
    albedo = np.divide(volume.sigma_s[..., channel], sigma_t, out=np.zeros_like(sigma_t), where=sigma_t > 0)
    return {
        "type": "heterogeneous",
        "sigma_t": _grid_dict(sigma_t, box),
        "albedo": _grid_dict(albedo, box),
        "scale": float(unit_mm),
        "has_spectral_extinction": False,
        "phase": {"type": "hg", "g": volume.g},
    }


def spot_dict(position, target, cutoff_deg: float, intensity: float = 1.0, up=None) -> dict:
    """Mitsuba ``spot`` emitter at ``position`` aimed at ``target`` (mm); intensity in W/sr.

    The beam width is :data:`SPOT_BEAM_FRACTION` of the cutoff, stated here for every spot of the package.

    Examples
    --------
    >>> spot = spot_dict((0, 0, 100), (0, 0, 0), cutoff_deg=2.0)
    >>> spot["type"], spot["cutoff_angle"], spot["beam_width"]   # full intensity to ¾ of the cutoff
    ('spot', 2.0, 1.5)
    """
    return {
        "type": "spot",
        "intensity": float(intensity),
        "cutoff_angle": float(cutoff_deg),
        "beam_width": SPOT_BEAM_FRACTION * float(cutoff_deg),
        "to_world": look_at(position, target, up),
    }


def slab_shape_dict(volume, channel: int) -> dict:
    """The slab of ``volume`` as a Mitsuba ``cube`` over [0, W] × [0, H] × [−T, 0] with a ``null`` BSDF
    (index-matched boundary) holding one channel of the volume (:func:`slab_medium_dict`).

    A dielectric boundary would render black under a delta light (next-event estimation cannot pass a
    smooth interface), hence the index-matched slab of the virtual photographs and of ``validate``.
    """
    mi = mitsuba()
    W, H, T = volume.size_mm
    box = mi.ScalarTransform4f().translate([W / 2, H / 2, -T / 2]) @ mi.ScalarTransform4f().scale(
        [W / 2, H / 2, T / 2]
    )
    return {
        "type": "cube",
        "to_world": box,
        "bsdf": {"type": "null"},
        "interior": slab_medium_dict(volume, channel),
    }


def marker_dict(x: float, y: float, radius: float, radiance: float = 1.0, z: float = 1e-3) -> dict:
    """A glowing disc marker of ``radius`` (mm) lying on the plane z ≈ 0 at (x, y), facing +z (calibration
    targets of the virtual rig)."""
    mi = mitsuba()
    to_world = mi.ScalarTransform4f().translate(
        [float(x), float(y), float(z)]
    ) @ mi.ScalarTransform4f().scale([float(radius), float(radius), 1.0])
    return {"type": "disk", "to_world": to_world, "emitter": {"type": "area", "radiance": float(radiance)}}


def load_plugin(description: dict):
    """One Mitsuba object (an emitter, a sensor, …) from its dictionary, outside any scene.

    Examples
    --------
    >>> load_plugin({"type": "constant"}).is_environment()   # an environment emitter
    True
    >>> load_plugin(spot_dict((0, 0, 100), (0, 0, 0), 2.0)).is_environment()
    False
    """
    return mitsuba().load_dict(description)


def vertex_radiance_scene(mesh, sensor: dict, *, eta: float = 1.0, environment: dict | None = None):
    """Our picture's scene: ``mesh`` as an area emitter of its ``vertex_color`` (zero, set later), seen by
    ``sensor`` through Mitsuba's ``direct`` integrator.

    η ≠ 1 gives the surface a ``plastic`` BSDF with no diffuse part (Fresnel reflection off a smooth
    dielectric); ``environment``, an emitter dictionary, is seen behind the object and in that reflection.

    Examples
    --------
    >>> from translucency.mitsuba import perspective_camera_dict
    >>> from types import SimpleNamespace
    >>> tetra = SimpleNamespace(vertices=np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]),
    ...                         faces=np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]))
    >>> camera = perspective_camera_dict((3, 3, 3), (0, 0, 0), 30.0, 16, 16)
    >>> scene = vertex_radiance_scene(tetra, camera)
    >>> scene.shapes()[0].is_emitter(), len(scene.emitters())   # the object glows; nothing else does
    (True, 1)
    >>> len(vertex_radiance_scene(tetra, camera, eta=1.5, environment={"type": "constant"}).emitters())
    2
    """
    bsdf = (
        {"type": "diffuse", "reflectance": 0.0}
        if eta == 1.0
        else {"type": "plastic", "diffuse_reflectance": 0.0, "int_ior": float(eta), "ext_ior": 1.0}
    )
    scene = {
        "type": "scene",
        "integrator": {"type": "direct"},
        "object": {
            "bsdf": bsdf,
            "emitter": {"type": "area", "radiance": {"type": "mesh_attribute", "name": "vertex_color"}},
        },
        "camera": sensor,
    }
    if environment is not None:
        scene["sky"] = environment
    return load_with_mesh(mesh, scene, colour=np.zeros((len(mesh.vertices), 3)))


def object_volpath_scene(mesh, volume, channel: int, emitter: dict, sensor: dict, *, eta: float = 1.0):
    """The reference's scene: ``mesh`` filled with one channel of ``volume`` (over its bounding box),
    behind a ``null`` (η = 1) or smooth ``dielectric`` boundary, lit by ``emitter``, path-traced by
    ``volpath`` without depth limit or Russian roulette before depth 100,000.

    Examples
    --------
    >>> from translucency.mitsuba import perspective_camera_dict
    >>> from types import SimpleNamespace
    >>> from translucency.acquire import Volume
    >>> tetra = SimpleNamespace(vertices=np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]),
    ...                         faces=np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]),
    ...                         bounds=np.array([[0.0, 0, 0], [1, 1, 1]]))
    >>> filling = Volume.homogeneous((2, 2, 2), 0.5, sigma_s=[1.0] * 3, sigma_a=[0.01] * 3)
    >>> scene = object_volpath_scene(tetra, filling, 0, spot_dict((0, 0, 100), (0, 0, 0), 2.0),
    ...                              perspective_camera_dict((3, 3, 3), (0, 0, 0), 30.0, 16, 16), eta=1.3)
    >>> shape = scene.shapes()[0]
    >>> shape.interior_medium() is not None, str(shape.bsdf()).split("[")[0]   # filled, behind glass
    (True, 'SmoothDielectric')
    """
    boundary = (
        {"type": "null"} if eta == 1.0 else {"type": "dielectric", "int_ior": float(eta), "ext_ior": 1.0}
    )
    lo, hi = mesh.bounds
    return load_with_mesh(
        mesh,
        {
            "type": "scene",
            "integrator": {"type": "volpath", "max_depth": -1, "rr_depth": 100_000},
            "object": {
                "bsdf": boundary,
                "interior": slab_medium_dict(volume, channel, (lo[0], lo[1], hi[2])),
            },
            "light": emitter,
            "camera": sensor,
        },
    )


def object_window_scene(mesh, window, volume, channel: int, emitter: dict, sensor: dict, *, eta: float):
    """:func:`object_volpath_scene` behind a smooth ``dielectric`` of index ``eta`` with a **window**: the
    faces ``window`` (bool per face) index-matched (``null``), the rest dielectric, one medium inside both.

    A spot outside cannot light a medium behind a smooth dielectric in ``volpath`` (camera paths inside
    reach the light by next-event estimation, which a delta refraction stops); through a window over the
    laser's disc they do.  What the window changes, light leaving through it unrefracted, stays within
    the window (the laser's spot, which the import sets aside).

    Examples
    --------
    >>> import trimesh
    >>> from translucency.mitsuba import perspective_camera_dict
    >>> from translucency.acquire import Volume
    >>> box = trimesh.creation.box((2.0, 2.0, 2.0))  # 12 faces; the first two make one square side
    >>> scene = object_window_scene(box, np.arange(12) < 2, Volume.homogeneous((4, 4, 4), 0.5, [1.0] * 3,
    ...                             [0.01] * 3), 0, spot_dict((0, 0, 100), (0, 0, 0), 2.0),
    ...                             perspective_camera_dict((5, 5, 5), (0, 0, 0), 30.0, 16, 16), eta=1.4)
    >>> sorted((s.face_count(), str(s.bsdf()).split("[")[0]) for s in scene.shapes())
    [(2, 'Null'), (10, 'SmoothDielectric')]
    >>> len({id(s.interior_medium()) for s in scene.shapes()})  # one medium
    1
    """
    mi = mitsuba()
    lo, hi = mesh.bounds
    medium = mi.load_dict(slab_medium_dict(volume, channel, (lo[0], lo[1], hi[2])))
    verts, faces = np.asarray(mesh.vertices), np.asarray(mesh.faces)
    window = np.asarray(window, dtype=bool)
    parts = {
        "object": (faces[~window], {"type": "dielectric", "int_ior": float(eta), "ext_ior": 1.0}),
        "window": (faces[window], {"type": "null"}),
    }
    with tempfile.TemporaryDirectory() as tmp:
        scene = {
            "type": "scene",
            "integrator": {"type": "volpath", "max_depth": -1, "rr_depth": 100_000},
            "light": emitter,
            "camera": sensor,
        }
        for key, (f, bsdf) in parts.items():
            path = Path(tmp) / f"{key}.ply"
            write_ply(path, verts, f)
            scene[key] = {"type": "ply", "filename": str(path), "bsdf": bsdf, "interior": medium}
        return mi.load_dict(scene)


def slab_scene(
    volume, channel: int, emitter: dict, sensor: dict, *, rr_depth: int = NO_ROULETTE, moment=False
):
    """The index-matched slab of one channel of ``volume`` (:func:`slab_shape_dict`) lit by ``emitter`` and
    seen by ``sensor``, path-traced by ``volpath`` (unbounded depth, roulette from ``rr_depth``).

    ``moment``: ``volpath`` nested in the ``moment`` integrator, which also records each pixel's second
    moment (the variance of the validation harness).

    Examples
    --------
    >>> from translucency.mitsuba import perspective_camera_dict
    >>> from translucency.acquire import Volume
    >>> slab = Volume.homogeneous((4, 8, 8), 0.5, sigma_s=[1.0] * 3, sigma_a=[0.01] * 3)   # 4 × 4 × 2 mm
    >>> scene = slab_scene(slab, 0, spot_dict((2, 2, 100), (2, 2, 0), 1.0),
    ...                    perspective_camera_dict((2, 2, 50), (2, 2, 0), 10.0, 8, 8))
    >>> box = scene.bbox()
    >>> list(box.min), list(box.max)   # [0, W] × [0, H] × [−T, 0]
    ([0.0, 0.0, -2.0], [4.0, 4.0, 0.0])
    """
    integrator = {"type": "volpath", "max_depth": -1, "rr_depth": int(rr_depth)}
    if moment:
        integrator = {"type": "moment", "nested": integrator}
    return mitsuba().load_dict(
        {
            "type": "scene",
            "integrator": integrator,
            "slab": slab_shape_dict(volume, channel),
            "spot": emitter,
            "camera": sensor,
        }
    )


def markers_scene(sensor: dict, markers_mm, radius_mm: float):
    """Glowing disc markers (:func:`marker_dict`) at ``markers_mm`` (N, 2) on z ≈ 0, seen by ``sensor``
    through the ``direct`` integrator.

    Examples
    --------
    >>> from translucency.mitsuba import perspective_camera_dict
    >>> camera = perspective_camera_dict((0, 0, 100), (0, 0, 0), 30.0, 16, 16)
    >>> scene = markers_scene(camera, [[0, 0], [5, 0], [0, 5]], radius_mm=1.0)
    >>> len(scene.emitters()), [round(v, 3) for v in scene.bbox().max]   # three discs of radius 1 mm
    (3, [6.0, 6.0, 0.001])
    """
    scene = {"type": "scene", "integrator": {"type": "direct"}, "camera": sensor}
    for k, (x, y) in enumerate(np.asarray(markers_mm, float)):
        scene[f"marker{k}"] = marker_dict(x, y, radius_mm)
    return mitsuba().load_dict(scene)


def checkerboard_scene(
    sensor: dict,
    board_to_world: np.ndarray,
    inner: tuple[int, int],
    square_mm: float,
    pixels_per_square: int = 16,
):
    """A flat glowing checkerboard seen by ``sensor`` through the ``direct`` integrator (no light needed).

    The board has (inner[0] + 1) × (inner[1] + 1) squares of side s = ``square_mm`` (mm); in the board's
    own frame (mm) its inner corner (i, j) lies at (s i, s j, 0), so the squares reach one square beyond
    the corner grid on every side, and the square (a, b) over x ∈ [s(a − 1), s a], y ∈ [s(b − 1), s b]
    (0 ≤ a ≤ inner[0], 0 ≤ b ≤ inner[1]) is white (radiance 1) for a + b even, else black (0).
    ``board_to_world`` (4 × 4) maps the board's frame to the scene's.  The board is a ``rectangle`` whose
    surface is an area emitter of a nearest-neighbour bitmap, ``pixels_per_square`` texels to a square's
    side; it glows on its +z side only.

    Examples
    --------
    >>> from translucency.mitsuba import perspective_camera_dict
    >>> camera = perspective_camera_dict((10, 5, 100), (10, 5, 0), 30.0, 16, 16)
    >>> box = checkerboard_scene(camera, np.eye(4), inner=(3, 2), square_mm=10.0).bbox()
    >>> list(box.min), list(box.max)   # 4 × 3 squares of 10 mm, one square beyond the inner corners
    ([-10.0, -10.0, 0.0], [30.0, 20.0, 0.0])
    """
    mi = mitsuba()
    nx, ny = (int(v) + 1 for v in inner)  # squares along the board's x and y
    s = float(square_mm)
    # texel [row, column] = square (b, a): the rectangle's v (texel rows) grows with the board's y
    b, a = np.indices((ny, nx))
    squares = ((a + b) % 2 == 0).astype(np.float32)
    k = int(pixels_per_square)
    texels = np.ascontiguousarray(np.repeat(np.repeat(squares, k, axis=0), k, axis=1)[..., None])
    # the rectangle [−1, 1]² onto the squares' extent [−s, (nx − 1) s] × [−s, (ny − 1) s]
    centre = [0.5 * s * (nx - 2), 0.5 * s * (ny - 2), 0.0]
    to_world = (
        mi.ScalarTransform4f(np.asarray(board_to_world, dtype=np.float64).tolist())
        @ mi.ScalarTransform4f().translate(centre)
        @ mi.ScalarTransform4f().scale([0.5 * s * nx, 0.5 * s * ny, 1.0])
    )
    pattern = {
        "type": "bitmap",
        "data": mi.TensorXf(texels),
        "filter_type": "nearest",
        "wrap_mode": "clamp",
        "raw": True,
    }
    board = {
        "type": "rectangle",
        "to_world": to_world,
        "bsdf": {"type": "diffuse", "reflectance": 0.0},
        "emitter": {"type": "area", "radiance": pattern},
    }
    return mi.load_dict({"type": "scene", "integrator": {"type": "direct"}, "board": board, "camera": sensor})
