r"""Memory and disk before work: what a command will need, estimated from its options alone.

Every command that works (``acquire planar``, ``acquire mesh``, ``fit``, ``evaluate``, ``render``)
states its peak memory and its output size here, from the sizes its options and inputs imply, and
refuses in one line what exceeds ``--max-memory`` (default: the machine's available memory) or the
free space of the disk it writes to — before it allocates or writes anything
(:func:`check_resources`).  ``--grid 100000`` or ``--pitch 0.0001`` end here (or in the options'
bounds) in a second, not in the kernel's out-of-memory killer an hour later.

The estimates are of the peak resident memory of the whole process: a fixed part (Python, NumPy,
Zarr; with Mitsuba and Dr.Jit's JIT for the commands that trace rays) plus the arrays the work holds
at its peak, each formula in its function's docstring.  The per-element byte counts are measured
(``tests/test_resources.py`` runs small cases in fresh processes, reads their peak resident memory
and asserts each estimate within a factor of 2 of it).  The output sizes are upper bounds: the
uncompressed bytes of every array written (Blosc-zstd usually stores far less).

Examples
--------
>>> parse_size("--max-memory", "4G")
4294967296
>>> need = planar_acquisition(grid=8, pitch=0.25, window=8.0, photons=10_000, chunk=16,
...                           voxels=80 * 80 * 32, dtype="float32")
>>> 0.2 < need.memory / 2**30 < 2
True
"""

from __future__ import annotations

import math
import shutil
from pathlib import Path

import numpy as np

from .._validate import TranslucencyError
from ..io.outputs import check_writable

# the record, the units and the machine's memory (:mod:`.machine`), importable from here as before
from .machine import (
    BASE,
    BASE_MITSUBA,
    GiB,
    MiB,
    Need,
    available_memory,
    memory_limit,
    parse_size,
    total_memory,
)


def free_disk(path) -> int | None:
    """Free bytes on the file system that ``path`` (or its nearest existing parent) lives on."""
    p = Path(path).absolute()
    while not p.exists() and p != p.parent:
        p = p.parent
    try:
        return int(shutil.disk_usage(p).free)
    except OSError:
        return None


def _size(n: float) -> str:
    for unit, scale in (("TiB", 2**40), ("GiB", GiB), ("MiB", MiB)):
        if n >= scale:
            return f"{n / scale:.3g} {unit}"
    return f"{n / 2**10:.3g} KiB"


def check_resources(command: str, need: Need, max_memory: int | None, out=None) -> Need:
    """Refuse, in one line, a ``need`` beyond ``max_memory`` (default: available memory) or the free disk.

    Called before the command allocates or writes anything.  Returns ``need``.

    Examples
    --------
    >>> need = Need(memory=3 * GiB, disk=0, what="the transport")
    >>> check_resources("render", need, max_memory=4 * GiB) is need
    True
    >>> check_resources("render", need, max_memory=parse_size("--max-memory", "2G"))  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    translucency._validate.TranslucencyError: render: needs about 3 GiB of memory (the transport), ...
    """
    limit = max_memory if max_memory is not None else available_memory()
    if limit is not None and need.memory > limit:
        source = "--max-memory" if max_memory is not None else "the available memory"
        raise TranslucencyError(
            f"{command}: needs about {_size(need.memory)} of memory ({need.what}), more than "
            f"{source} ({_size(limit)}); use smaller options or raise --max-memory"
        )
    if out is not None:
        check_writable(out, option=None)  # a folder that takes no files is not a lack of disk space
        free = free_disk(out)
        if free is not None and need.disk > free:
            raise TranslucencyError(
                f"{command}: the output needs up to {_size(need.disk)} on disk, only {_size(free)} free "
                f"where {out} goes"
            )
    return need


def planar_window_pixels(window: float, pitch: float) -> int:
    """Pixels per window side, as :meth:`translucency.acquire.PlanarSetup.window_pixels` (odd)."""
    n = max(1, int(min(round(window / pitch), 10**9)))  # beyond 10⁹ the estimate is refused anyway
    return n if n % 2 == 1 else n + 1


def planar_acquisition(
    *,
    grid: int | tuple[int, int],
    pitch: float,
    window: float,
    photons: int,
    chunk: int,
    voxels: float,
    dtype: str = "float32",
    batch_photons: int = 4_000_000,
    directions: int = 1,
    exit_bins: int = 0,
) -> Need:
    r"""``acquire planar``: P = grid² = nx·ny, windows of n × n pixels (n = window/pitch, odd), k a chunk;
    with the angle axes D beam directions and B exit bins (the chunk's counts hold B bins a pixel, one
    direction at a time; the disk D times R_d, plus B bins of each).

    .. math::
        M = M_{mi} + 100\,V_{vox} + 140\,b + 40 \cdot 3\,k n^2,
        \qquad b = \min(k, \max(1, B/N))\,N

    with V_vox voxels (the generators' noise fields and σ_s, σ_a: measured 52 bytes a voxel for a
    homogeneous slab, 94 for marble, 106 for the apple slice), b photons in flight per launch
    (B = 4·10⁶; measured 140 bytes each: the wavefront's state and its tally), and the chunk's float64
    counts, estimate, variance and their casts (measured 38 bytes per pixel and channel).  Output:
    :math:`D = P n^2 (3 \cdot 2\,s + 1) + 40 P` bytes (R_d and variance of ``s`` bytes, the mask).
    """
    n = planar_window_pixels(window, pitch)
    gx, gy = (grid, grid) if np.isscalar(grid) else grid  # one number for both axes, or (nx, ny)
    P = gx * gy
    k = min(chunk, P)
    b = min(k, max(1, batch_photons // photons)) * photons
    parts = {
        "the volume: --size / --voxel": 100 * voxels,
        "photons in flight: --photons": 140 * b,
        "a chunk of windows: --chunk x (--window / --pitch)^2": 40 * 3 * k * n * n * (1 + exit_bins),
    }
    s = 2 if dtype == "float16" else 4
    disk = P * n * n * (3 * 2 * s + 1) + 40 * P + (directions - 1) * P * (n * n * 3 * s + 24)
    disk += directions * P * n * n * 3 * s * exit_bins
    return Need(BASE_MITSUBA + sum(parts.values()), disk, max(parts, key=parts.get))


def slab_voxels(size, voxel: float) -> float:
    """Voxels of a generated sample of ``size`` (mm) at ``voxel`` mm (as ``make_sample``)."""
    return float(math.prod(max(1, round(v / voxel)) for v in size))


def object_voxels(extents, voxel: float) -> float:
    """Voxels of the filling of an object with bounding box ``extents`` (mm) at ``voxel`` mm (as
    ``translucency.acquire.mesh.object_volume``)."""
    return float(np.prod([math.ceil(e / voxel) for e in extents]))


def mesh_acquisition(
    *,
    vertices: int,
    faces: int,
    points: int,
    photons: int,
    chunk: int,
    voxels: float,
    directions: int = 1,
    exit_bins: int = 0,
) -> Need:
    r"""``acquire mesh``: V vertices, F faces, P incident points, k a chunk, N photons, D directions of
    incidence, B exit bins (0: none).

    .. math::
        M = M_{mi} + 100\,V_{vox} + 400\,k N + 40\,k V + 24\,k V B + 300\,(V + F)

    the volume as above, all k·N photons of a chunk in flight at once (one channel and direction; their
    state, exits and barycentric splat: measured 370 bytes each), the chunk's R_d and counts (float32 +
    float64 per vertex and channel), its exit bins (float32 × 3 channels + float64 counts per vertex and
    bin) and the mesh with its ray-tracing scene.  Output:
    :math:`D (12 P V + 20 P) + 12 P V D B + 40 (V + F)` (exit bins uncompressed: far from the beam they
    are zeros, which Zstandard keeps small).
    """
    k = min(chunk, points)
    parts = {
        "the filling: --voxel": 100 * voxels,
        "photons in flight: --chunk x --photons": 400 * k * photons,
        "a chunk of R_d: --chunk x vertices": 40 * k * vertices,
        "a chunk's exit bins: --chunk x vertices x --exit-bins": 24 * k * vertices * exit_bins,
        "the mesh": 300 * (vertices + faces),
    }
    disk = directions * (12 * points * vertices * (1 + exit_bins) + 20 * points)
    return Need(BASE_MITSUBA + sum(parts.values()), disk + 40 * (vertices + faces), max(parts, key=parts.get))


def photographs(
    *, voxels: float, width: int, height: int, spp: int, files: int, mesh_elements: int = 0
) -> Need:
    r"""``acquire photographs`` and ``acquire object-photographs``: a filling of V_vox voxels that Mitsuba's
    volpath photographs, one W × H render of s samples a pixel at a time, ``files`` images written; E
    vertices and faces of an object's mesh.

    .. math:: M = M_{mi} + 100\,V_{vox} + W H\,(64 + 10\,s) + 300\,E

    the filling (as the acquisitions: about 100 bytes a voxel), the film and the render's samples in
    flight (as ``render``'s reference: 64 bytes a pixel, 10 a sample) and the mesh with its ray-tracing
    scene (as ``acquire mesh``).  Output: :math:`D = 12\,W H` bytes a file (float32 RGB) + 1 MiB.
    """
    pixels = width * height
    parts = {
        "the filling: --voxel": 100 * voxels,
        "a render: --resolution x --spp": pixels * (64 + 10 * spp),
        "the mesh": 300 * mesh_elements,
    }
    return Need(BASE_MITSUBA + sum(parts.values()), 12 * pixels * files + MiB, max(parts, key=parts.get))


def photograph_import(
    *, positions: int, chunk: int, images: int, pixels: int, cells: int, mitsuba: bool = False
) -> Need:
    r"""``import images`` and ``import object``: N laser positions, k a chunk, each with I = ``images``
    photographs (every camera's frames) of P pixels, and C cells of the output a position (a planar
    window's pixels, an object's vertices).

    .. math:: M = M_0 + 24\,k\,I\,P + 40 \cdot 3\,k\,C

    the process (:data:`BASE`, :data:`BASE_MITSUBA` with ``mitsuba``: an object's import traces its
    cameras' rays), a chunk's photographs read (float32 RGB) with their dark- and flat-corrected copy,
    and the chunk's R_d, variance and counts per cell and channel (as the acquisitions: 40 bytes).
    Output: the R_d and variance (float32 RGB) and a mask byte of every cell, :math:`D = 25\,N C`
    (uncompressed).
    """
    parts = {
        "a chunk of photographs: --chunk": 24 * chunk * images * pixels,
        "a chunk of R_d: --chunk": 40 * 3 * chunk * cells,
    }
    base = BASE_MITSUBA if mitsuba else BASE
    return Need(base + sum(parts.values()), 25 * positions * cells, max(parts, key=parts.get))


def relighting(*, vertices: int, faces: int, pairs: float, coefficients: int = 0) -> Need:
    r"""``export``'s bake and ``view``'s relighting: a mesh of V vertices and F faces, its transport of
    p vertex pairs (none: the mesh alone), and with ``view`` its transfer of K coefficients per vertex and
    channel.

    .. math:: M = M_{mi} + 300\,(V + F) + 300\,p + 4600\,V + 4 \cdot 3\,K V

    the mesh with its ray-tracing scene (as ``acquire mesh``), the transport's pairs and per-vertex arrays
    (as ``render``) and the transfer (float32).  Output: :math:`D = 100\,V + 25\,F` (a PLY or glTF's
    positions, colours and attributes) + 1 MiB.
    """
    parts = {"the mesh": 300 * (vertices + faces)}
    if pairs:
        parts["the transport"] = PAIR_BYTES * pairs + VERTEX_BYTES * vertices
    if coefficients:
        parts["the transfer: --bands"] = 12 * coefficients * vertices
    base = BASE_MITSUBA if pairs else BASE
    return Need(base + sum(parts.values()), 100 * vertices + 25 * faces + MiB, max(parts, key=parts.get))


def planar_fit(
    *, points: int, pixels: int, chunk: int, workers: int, params: int, block: int, cache: float = 512 * MiB
) -> Need:
    r"""``fit`` of a planar data set: P points, J = H·W pixels a window, k points fitted together, w threads.

    .. math:: M = M_0 + \min(C, 30\,P J) + w\,(30\,k + 110\,\min(k, b)) J + 8\,P\,\pi_p

    the decoded data kept between rounds (y, variance, mask, geometry ≈ 30 bytes a pixel, at most the
    cache C = 512 MiB), each thread's chunk at work — its data as read (≈ 30 bytes a pixel) and the
    working arrays of the b = ``block`` points computed at a time (``translucency.fit.FIT_BLOCK``; casts,
    weights, model values, residuals: measured ≈ 100 bytes a pixel) — and the π_p parameters of every
    point.  Output: the model file, at most
    :math:`D = 4 P \pi_p + 4 J P + 2^{16}` (parameters and α).
    """
    k = min(chunk, points)
    w = max(1, min(workers, -(-points // max(k, 1))))
    parts = {
        "the data cache": min(cache, 30 * points * pixels),
        "the chunks at work: --chunk": w * (30 * k + 110 * min(k, block)) * pixels,
        "the parameters": 8 * points * params,
    }
    disk = 4 * points * params + 4 * pixels * points + 2**16
    return Need(BASE + sum(parts.values()), disk, max(parts, key=parts.get))


def mesh_fit(*, points: int, vertices: int, chunk: int, workers: int, params: int) -> Need:
    r"""``fit`` of a mesh data set: P points, V vertices, k = 32 points a chunk, w threads.

    .. math:: M = M_0 + \min(C, 30\,P V) + 110\,w\,k V + 300\,V + 8\,P\,\pi_p

    as the planar fit with the vertices as pixels, plus the vertex pooling of α (neighbour pairs) and
    the mesh.  Output: :math:`D = 4 P \pi_p + 40 V + 2^{16}`.
    """
    k = min(chunk, points)
    w = max(1, min(workers, -(-points // max(k, 1))))
    parts = {
        "the data cache": min(512 * MiB, 30 * points * vertices),
        "the chunks at work": 110 * w * k * vertices,
        "the mesh": 300 * vertices,
        "the parameters": 8 * points * params,
    }
    disk = 4 * points * params + 40 * vertices + 2**16
    return Need(BASE + sum(parts.values()), disk, max(parts, key=parts.get))


def evaluation(*, points: int, pixels: int, params: list[int], datasets: int = 1) -> Need:
    r"""``evaluate``: P points of J pixels, models of π_p parameters a point, d data sets (2: ``--truth``).

    .. math:: M = M_0 + P J\,d\,\Big(60 + \sum_{\text{models}} (100 + 20\,\pi_p)\Big) + 80\,\mathrm{MiB}

    the data read whole (R_d, variance, mask: ≈ 60 bytes a pixel), each model's values and errors on
    every pixel (measured 330 bytes a pixel for iso n = 3 per channel, π_p = 18; 2,500 for aniso
    m = 8, π_p = 144) and the figures.  Output: the report's figures and HTML and the JSON (≈ 4 MiB a
    model).
    """
    per_pixel = 60 + sum(100 + 20 * p for p in params)
    data = points * pixels * datasets
    parts = {"the data and model values": per_pixel * data, "the figures": 80 * MiB}
    return Need(BASE + sum(parts.values()), 4 * MiB * max(1, len(params)), max(parts, key=parts.get))


def mesh_evaluation(*, points: int, vertices: int, faces: int, models: int, chunk: int = 16) -> Need:
    r"""``evaluate`` on a mesh data set: P points of V vertices (F faces), ``models`` per-vertex models.

    .. math:: M = M_0 + 400\,k V + 200\,(V + F) + 80\,\mathrm{MiB}

    a chunk of k points read and evaluated at a time (R_d, the model's values, distances and the sums:
    ≈ 400 bytes a pair), the surface and the per-vertex sums, and the figure.  Output: the figure, the
    page and the JSON (≈ 2 MiB a model, the per-point errors listed).
    """
    pairs = min(chunk, points) * vertices
    parts = {"a chunk of pairs": 400 * pairs, "the surface": 200 * (vertices + faces), "the figure": 80 * MiB}
    return Need(BASE + sum(parts.values()), 2 * MiB * max(1, models), max(parts, key=parts.get))


def rendering(
    *,
    vertices: int,
    surface_mm2: float,
    radius_mm: float,
    width: int,
    height: int,
    reference: bool,
    max_pairs: float,
    spp_reference: int = 32,
) -> Need:
    r"""``render``: V vertices on A mm² of surface, transport radius r, a W × H picture.

    .. math::
        M = M_{mi} + 300\,\min(p_{max}, V^2, V + V^2 \pi r^2 / A) + 4600\,V + W H\,(64 + 10 \cdot 16)
            \;[+\, 2 \cdot 10\,W H s_{ref}]

    the sparse transport's vertex pairs (indices, distances, profile values and the CSR matrices:
    measured 240–330 bytes each; at most p_max pairs, ``translucency.render.MAX_PAIRS``), the per-vertex
    arrays (``VERTEX_BYTES``: the blended parameters, the far field's clusters, the irradiance's rays,
    the mesh in Mitsuba), the film and the picture's 16 samples a pixel and, with ``--reference``, the
    two path-traced references.
    Output: :math:`D = 60\,W H` per picture (EXR + PNG; three with the reference) + 1 MiB.
    """
    pairs = transport_pairs(
        vertices=vertices, surface_mm2=surface_mm2, radius_mm=radius_mm, max_pairs=max_pairs
    )
    pixels = width * height
    parts = {
        "the transport: --radius": PAIR_BYTES * pairs,
        "the vertices": VERTEX_BYTES * vertices,
        "the picture: --resolution": pixels * (64 + 10 * 16),
    }
    if reference:
        parts["the reference: --resolution x --spp"] = 2 * 10 * pixels * spp_reference
    disk = pixels * 60 * (3 if reference else 1) + MiB
    return Need(BASE_MITSUBA + sum(parts.values()), disk, max(parts, key=parts.get))


def scene_rendering(
    *,
    pairs: float,
    paths: int,
    pixels: int,
    spp: int,
    reference: bool,
    spp_reference: int,
    vertices: int = 0,
) -> Need:
    r"""``render --scene``: the transports' vertex pairs, the objects' ``vertices`` (as ``render``'s), the
    irradiance's wavefront of ``paths`` paths (as traced: whole vertices' samples, at most 2¹⁹ paths unless
    one a vertex), a picture of ``pixels`` at ``spp`` and, with the reference, its two renders.

    .. math:: M = M_{mi} + 300\,p + 4600\,V + 400\,P + 100\,W H s \;[+\, 100\,W H s_{ref}]

    (a path of the wavefront holds its ray, throughput, interaction and sampler, about 400 bytes;
    a camera sample about 100).  Output: three EXR + PNG pictures and the summary.
    """
    parts = {
        "the transport: --radius": PAIR_BYTES * pairs,
        "the vertices": VERTEX_BYTES * vertices,
        "the irradiance: --samples": 400 * paths,
        "the picture: --picture-spp": 100 * pixels * spp,
    }
    if reference:
        parts["the reference: --spp"] = 100 * pixels * spp_reference
    disk = pixels * 60 * (3 if reference else 1) + MiB
    return Need(BASE_MITSUBA + sum(parts.values()), disk, max(parts, key=parts.get))


#: bytes a vertex of ``render`` holds beside its pairs: the 338 k-vertex scan peaked 1.5 GiB above the
#: pairs' and the picture's estimate (``benchmarks/large_scan.py``)
VERTEX_BYTES = 4600
#: bytes a vertex pair of the render transport holds at its peak (indices, distances, profile values, the
#: CSR matrices; measured 330 for the 14.0 M pairs of a 34,839-vertex bunny: 4.56 GiB peak)
PAIR_BYTES = 300
#: the share of the memory (``--max-memory``, default the available memory) the default transport
#: radius of ``render`` may fill: the rest for the picture, the reference and the machine's other work
TRANSPORT_SHARE = 0.25


def transport_budget(limit: int | None) -> float:
    r"""Vertex pairs the default transport radius of ``render`` may hold: :data:`TRANSPORT_SHARE` of
    ``limit`` bytes (None: the machine's physical memory — not the memory free at the moment, so that the
    same command renders the same picture) after the process itself, at :data:`PAIR_BYTES` each.

    Examples
    --------
    >>> round(transport_budget(4 * GiB) / 1e6, 1)
    3.3
    """
    limit = limit if limit is not None else total_memory()
    if limit is None:
        return math.inf
    return TRANSPORT_SHARE * max(0.0, limit - BASE_MITSUBA) / PAIR_BYTES


def transport_pairs(*, vertices: int, surface_mm2: float, radius_mm: float, max_pairs: float) -> float:
    r"""Vertex pairs of the sparse transport within ``radius_mm`` on ``surface_mm2`` of V vertices.

    .. math:: p = \min(p_{max}, V^2, V + V^2 \pi r^2 / A)

    each vertex with itself, and the others within r of it on a uniformly covered surface; at most
    p_max (``translucency.render.MAX_PAIRS``, beyond which the transport refuses).

    Examples
    --------
    >>> transport_pairs(vertices=100, surface_mm2=1e4, radius_mm=1e300, max_pairs=2.5e7)
    10000
    """
    r = min(float(radius_mm), 1e9)  # beyond any object: every pair (and no float overflow at 1e308)
    return min(max_pairs, vertices**2, vertices + vertices**2 * math.pi * r**2 / max(surface_mm2, 1e-12))


__all__ = [
    "BASE",
    "BASE_MITSUBA",
    "GiB",
    "MiB",
    "PAIR_BYTES",
    "TRANSPORT_SHARE",
    "VERTEX_BYTES",
    "Need",
    "available_memory",
    "check_resources",
    "evaluation",
    "free_disk",
    "memory_limit",
    "mesh_acquisition",
    "mesh_evaluation",
    "mesh_fit",
    "object_voxels",
    "parse_size",
    "photograph_import",
    "photographs",
    "planar_acquisition",
    "planar_fit",
    "planar_window_pixels",
    "relighting",
    "rendering",
    "scene_rendering",
    "slab_voxels",
    "total_memory",
    "transport_budget",
    "transport_pairs",
]
