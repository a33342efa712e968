"""Virtual DISCO on a planar slab: a grid of pencil beams, a window of pixels around each.

For every incident point x_i of a regular grid and every channel, photons
are traced by :func:`~translucency.acquire.transport.random_walk` and those
leaving through the top face are counted per pixel of the window around x_i:

    R_d = n_px / (N · pitch²)  [mm⁻²],   Var(R_d) = p̂ (1 − p̂) / (N · pitch⁴),  p̂ = n_px / N.

Incident points are snapped to pixel centres of one lattice over the sample
(pixel [row, col] centred at pitch · (col + 1/2, row + 1/2)), and windows have
an odd number of pixels with x_i at the centre pixel, so windows of different
points align on the same outgoing pixels (what the modulation-texture fit
needs).  Work runs in chunks of incident points; each finished chunk is
flagged in the data set, and a re-run with the same arguments resumes.
"""

from __future__ import annotations

import hashlib
import json
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass

import numpy as np

from .._validate import TranslucencyError
from .._version import __version__
from ..angles import ExitBins, Incidence, angle_record
from ..cluster import open_cluster, parse_scheduler
from ..io.dataset import FORMAT, VERSION, PlanarDataset, create_dataset
from ..io.outputs import output_lock
from ..mitsuba import engine_versions
from .transport import KILLED, TOP, check_memory, random_walk
from .volume import Volume


@dataclass(frozen=True)
class PlanarSetup:
    """Arguments of a planar acquisition (lengths in mm).

    ``grid``: incident points (nx, ny); ``span``: extent (mm) of the incident
    grid, centred on the slab; ``pitch``: pixel size; ``window``: window side.

    Examples
    --------
    >>> from translucency.acquire import Volume
    >>> slab = Volume.homogeneous((4, 16, 16), 0.25, sigma_s=[1.0] * 3, sigma_a=[0.01] * 3)   # 4 × 4 × 1 mm
    >>> setup = PlanarSetup(grid=(2, 1), span=(2.0, 2.0), pitch=0.25, window=2.0)
    >>> setup.window_pixels()   # 2 mm / 0.25 mm = 8, made odd: x_i in the centre pixel
    9
    >>> setup.incident_points(slab).tolist()   # centred on the slab, snapped to pixel centres
    [[1.625, 2.125], [2.625, 2.125]]
    """

    grid: tuple[int, int] = (8, 8)
    span: tuple[float, float] = (8.0, 8.0)
    pitch: float = 0.25
    window: float = 8.0
    photons: int = 10_000
    seed: int = 0
    theta_inc_deg: float = 0.0
    index_matched: bool = False
    chunk_points: int = 16
    dtype: str = "float32"
    incidence: Incidence = Incidence()  # oblique beams besides the normal one (angles.py)
    exit_bins: ExitBins | None = None  # the exits tallied by direction too

    def check(self, volume: Volume) -> None:
        """Refuse bad arguments before any work, naming the parameter."""
        W, H, _ = volume.size_mm
        if min(self.grid) < 1:
            raise TranslucencyError(f"grid: need at least one incident point per axis, got {self.grid}")
        if not (np.isfinite(self.pitch) and self.pitch > 0):
            raise TranslucencyError(f"pitch: must be a positive length in mm, got {self.pitch}")
        if not (np.isfinite(self.window) and self.window >= self.pitch):
            raise TranslucencyError(
                f"window: must be at least one pixel ({self.pitch} mm), got {self.window}"
            )
        if self.window > min(W, H):
            raise TranslucencyError(f"window: {self.window} mm is larger than the sample ({W:g} x {H:g} mm)")
        if any(not (0 <= s <= lim) for s, lim in zip(self.span, (W, H))):
            raise TranslucencyError(
                f"span: incident grid {self.span} mm does not fit on the {W:g} x {H:g} mm sample"
            )
        if self.photons < 1:
            raise TranslucencyError(f"photons: must be >= 1, got {self.photons}")
        if not 0 <= self.theta_inc_deg < 90:
            raise TranslucencyError(f"angle: must lie in [0, 90) degrees, got {self.theta_inc_deg}")
        if self.theta_inc_deg != 0 and self.incidence.count > 1:
            raise TranslucencyError(
                f"angle: must be 0 with oblique beams (incidence), whose first beam is the normal one; got "
                f"{self.theta_inc_deg:g}"
            )
        if self.dtype not in ("float32", "float16"):
            raise TranslucencyError(f"dtype: expected float32 or float16, got {self.dtype!r}")
        if self.chunk_points < 1:
            raise TranslucencyError(f"chunk: must be >= 1, got {self.chunk_points}")

    def window_pixels(self) -> int:
        """Odd number of pixels per window side (x_i sits in the centre pixel)."""
        n = max(1, int(round(self.window / self.pitch)))
        return n if n % 2 == 1 else n + 1

    def incident_points(self, volume: Volume) -> np.ndarray:
        """Incident points (P, 2) in mm: a grid centred on the slab, snapped to pixel centres."""
        W, H, _ = volume.size_mm
        nx, ny = self.grid
        sx, sy = self.span
        xs = W / 2 - sx / 2 + (np.arange(nx) + 0.5) * sx / nx
        ys = H / 2 - sy / 2 + (np.arange(ny) + 0.5) * sy / ny
        snap = lambda v: (np.floor(v / self.pitch) + 0.5) * self.pitch  # noqa: E731
        gx, gy = np.meshgrid(snap(xs), snap(ys))
        return np.stack([gx.ravel(), gy.ravel()], axis=1)


@dataclass(frozen=True)
class WalkProbe:
    """What a short probe of the random walk found on a volume (:func:`probe_walk`).

    ``steps_per_photon``: loop iterations of one photon, summed over the three channels (free flights,
    null collisions included); ``photons``: photons traced per channel; ``seconds``: its wall time
    (kernel compilation included); ``killed``: photons cut short by the probe's step cap (then the
    steps are a lower bound); ``seconds_per_step``: this machine's speed at the walk, from the last pass
    run again with its kernel compiled (no start-up).

    Examples
    --------
    >>> from translucency.acquire import Volume
    >>> slab = Volume.homogeneous((4, 16, 16), 0.25, sigma_s=[1.0] * 3, sigma_a=[0.01] * 3)
    >>> probe = WalkProbe(steps_per_photon=30.0, photons=64, seconds=0.1)   # as probe_walk reports it
    >>> setup = PlanarSetup(grid=(8, 8), photons=10_000, span=(2.0, 2.0), window=2.0)
    >>> estimate_seconds(slab, setup, steps_per_second=1, probe=probe)   # photon steps: 64 × 10⁴ × 30
    19200000.0
    """

    steps_per_photon: float
    photons: int
    seconds: float
    killed: int = 0
    seconds_per_step: float = float("nan")


def probe_walk(volume: Volume, setup: PlanarSetup, *, budget_steps: float = 2e6) -> WalkProbe:
    """Trace a few incident points of the acquisition with a few hundred photons per channel.

    The walk's own kernel on the user's own volume, so the number of scattering events per photon (what
    differs most between materials: a few for ketchup, tens for marble, hundreds in a thick slab of
    cream) is counted, not guessed.  Nothing is written.  A first pass traces the centre point with
    ``min(photons, 64)`` photons (at most 20,000 steps each); a second traces up to 4 points spread over
    the grid with as many photons (``--photons`` at most, so that its kernel is the acquisition's own) as
    ``budget_steps`` allows; that pass runs twice, the second time timed without its kernel's
    compilation (``seconds_per_step``): about 0.1–0.6 s in all on 2 shared cores.

    Examples
    --------
    >>> from translucency.acquire import Volume
    >>> slab = Volume.homogeneous((4, 16, 16), 0.25, sigma_s=[1.0] * 3, sigma_a=[0.01] * 3)
    >>> setup = PlanarSetup(grid=(2, 1), span=(2.0, 2.0), window=2.0, photons=50)
    >>> probe = probe_walk(slab, setup, budget_steps=1e3)   # 50 photons a channel at the centre point
    >>> probe.photons, probe.killed, probe.steps_per_photon > 3   # at least a step a channel, 3 channels
    (50, 0, True)
    """
    x_i = setup.incident_points(volume)
    walk = dict(seed=setup.seed, theta_inc_deg=setup.theta_inc_deg, index_matched=setup.index_matched)
    t0 = time.perf_counter()

    def trace(points, n, **cap):
        res = [random_walk(volume, ch, points, n, first_point=0, **walk, **cap) for ch in range(3)]
        killed = sum(int(np.count_nonzero(r.code == KILLED)) for r in res)
        return sum(r.steps for r in res), killed

    n1 = min(setup.photons, 64)
    last = (x_i[len(x_i) // 2 : len(x_i) // 2 + 1], n1, {"max_steps": 20_000})  # the centre point
    steps, killed = trace(*last[:2], **last[2])
    photons = n1
    k = min(len(x_i), 4)
    n2 = int(min(setup.photons, budget_steps / (k * max(steps / n1, 1.0))))
    if k * n2 >= 4 * n1 and not killed:  # a better average: more photons, several points
        last = (x_i[np.linspace(0, len(x_i) - 1, k).round().astype(int)], n2, {})
        more, killed = trace(*last[:2], **last[2])
        steps, photons = steps + more, photons + k * n2
    seconds = time.perf_counter() - t0
    t1 = time.perf_counter()
    again, _ = trace(*last[:2], **last[2])  # the same kernels, now compiled: the walk's own speed
    per_step = (time.perf_counter() - t1) / max(again, 1)
    return WalkProbe(steps / photons, photons, seconds + time.perf_counter() - t1, killed, per_step)


def estimate_seconds(
    volume: Volume, setup: PlanarSetup, steps_per_second: float = 3e7, probe: WalkProbe | None = None
) -> float:
    """Run time of the photon walks: points × photons × steps per photon (a probe's) / throughput.

    The steps per photon (all three channels) are counted by :func:`probe_walk` on ``volume`` itself
    (pass ``probe`` to reuse one); with ``steps_per_second=1`` this is the number of photon steps, which
    ``translucency.resources.estimate_time`` turns into seconds calibrated on this machine.  The
    diffusion guess used before (a path of 1/√(3 σ_a σ_t)) was off by up to 4× between materials.

    Examples
    --------
    >>> from translucency.acquire import Volume
    >>> slab = Volume.homogeneous((4, 16, 16), 0.25, sigma_s=[1.0] * 3, sigma_a=[0.01] * 3)
    >>> setup = PlanarSetup(grid=(8, 8), span=(2.0, 2.0), window=2.0, photons=10_000)
    >>> probe = WalkProbe(steps_per_photon=30.0, photons=64, seconds=0.1)
    >>> estimate_seconds(slab, setup, probe=probe)   # 64 points × 10⁴ photons × 30 steps at 3·10⁷ a second
    0.64
    """
    probe = probe if probe is not None else probe_walk(volume, setup)
    n = setup.grid[0] * setup.grid[1] * setup.photons
    return float(n * probe.steps_per_photon / steps_per_second)


def acquire_planar(
    volume: Volume,
    setup: PlanarSetup,
    out,
    *,
    overwrite: bool = False,
    inputs=(),
    progress: Callable[[int, int], None] | None = None,
    batch_photons: int = 4_000_000,
    memory_limit: float = 8 * 2**30,
    scheduler: str | None = "threads",
) -> PlanarDataset:
    """Run a virtual DISCO acquisition of ``volume`` and write the data set to ``out``.

    Parameters
    ----------
    volume : Volume
        The slab.
    setup : PlanarSetup
        Grid, pixels, window, photons, seed, angle.
    out : path
        Zarr directory; an unfinished data set with the same arguments is resumed.
    overwrite : bool
        Replace a data set made with other arguments (never anything else).
    inputs : iterable of path
        Files the command reads (a volume): never written over.
    progress : callable(done_points, total_points), optional
        Called after each chunk.
    batch_photons : int
        Photons traced per Dr.Jit launch (memory).
    scheduler : str, optional
        Where the chunks are traced: ``"threads"`` (default: this process), ``"local:N"`` or
        ``"tcp://HOST:PORT"`` (:mod:`translucency.cluster`): each chunk a task that writes its
        part of the store and its done flag (``out`` must be visible to the workers).  The data
        are the same bit for bit, and an interrupted run resumes either way.

    Returns
    -------
    PlanarDataset

    Examples
    --------
    >>> import tempfile
    >>> from translucency.acquire import Volume
    >>> slab = Volume.homogeneous((4, 16, 16), 0.25, sigma_s=[1.0] * 3, sigma_a=[0.01] * 3)
    >>> setup = PlanarSetup(grid=(2, 1), span=(2.0, 2.0), pitch=0.25, window=2.0, photons=50, chunk_points=2)
    >>> with tempfile.TemporaryDirectory() as tmp:   # 2 points × 50 photons × 3 channels
    ...     ds = acquire_planar(slab, setup, f"{tmp}/scan.zarr")
    ...     R_d = np.asarray(ds.group["R_d"][...], dtype=np.float64)
    ...     total = np.asarray(ds.group["total_diffuse"][...], dtype=np.float64)
    >>> ds.n_points, R_d.shape   # (P, n, n, 3) windows of R_d, mm⁻²
    (2, (2, 9, 9, 3))
    >>> in_window = R_d.sum(axis=(1, 2)) * 0.25**2   # Σ R_d dA over each window: a part of the total
    >>> bool((R_d >= 0).all()), bool((in_window <= total + 1e-6).all())
    (True, True)
    """

    setup.check(volume)
    parse_scheduler(scheduler)  # a bad option is one line before any work
    check_memory(min(batch_photons, setup.photons * setup.chunk_points), volume, memory_limit)
    mi_versions = engine_versions()
    x_i = setup.incident_points(volume)
    n = setup.window_pixels()
    P = len(x_i)
    origin = x_i - setup.pitch * n / 2.0
    request = {**setup_request(setup), "volume": _volume_fingerprint(volume)}
    header = _header(volume, setup, n, P, request, mi_versions)
    with output_lock(out):  # one writer at a time
        ds = create_dataset(out, header, overwrite=overwrite, inputs=inputs)
        g = ds.group
        _every_chunk(g)("x_i")[...] = x_i.astype(np.float32)
        _every_chunk(g)("window_origin")[...] = origin.astype(np.float32)
        _scan_chunks(ds, volume, setup, x_i, origin, batch_photons, scheduler, progress)
        return ds


def _header(volume: Volume, setup: PlanarSetup, n: int, P: int, request: dict, mi_versions: dict) -> dict:
    """The data set's header: units, windows of n × n pixels, the sample, the acquisition and the request."""
    return {
        "format": FORMAT,
        "version": VERSION,
        "units": {"length": "mm", "R_d": "mm^-2", "variance": "mm^-4"},
        "pitch_mm": setup.pitch,
        "window": [n, n],
        "n_points": P,
        "chunk_points": setup.chunk_points,
        "dtype": setup.dtype,
        "sample": {
            "size_mm": list(volume.size_mm),
            "voxel_mm": volume.voxel_mm,
            "g": volume.g,
            "eta": volume.eta,
            "description": volume.description,
        },
        "acquisition": {
            "photons": setup.photons,
            "seed": setup.seed,
            "theta_inc_deg": setup.theta_inc_deg,
            "index_matched": setup.index_matched,
            "estimator": "analog photon tally, delta tracking",
        },
        "software": {"translucency": __version__, **mi_versions},
        "request": request,
        **({"angles": request["angles"]} if "angles" in request else {}),
        # every chunk of every array is a file (all-zero ones too, :func:`_every_chunk`): a missing
        # file is damage; stores made before say nothing here and may lack their all-zero chunks
        "chunk_files": "every",
    }


def _scan_chunks(
    ds, volume: Volume, setup: PlanarSetup, x_i, origin, batch_photons: int, scheduler, progress
):
    """Acquire the chunks not yet done, here or on a cluster, reporting the points finished."""
    P = len(x_i)
    done = np.asarray(ds.group["chunk_done"][...])
    k = setup.chunk_points
    todo = [(c, c * k, min(P, (c + 1) * k)) for c in range(len(done)) if not done[c]]
    finished = P - sum(hi - lo for _, lo, hi in todo)  # points of the chunks done before
    if progress and finished:
        progress(finished, P)
    with open_cluster(scheduler) as cluster:
        if cluster is None:  # this process, chunk after chunk (Dr.Jit uses every core)
            for c, lo, hi in todo:
                _acquire_chunk(volume, setup, ds, c, lo, hi, x_i[lo:hi], origin[lo:hi], batch_photons)
                finished += hi - lo
                if progress:
                    progress(finished, P)
        else:  # a task per chunk: each writes its part of the store and its done flag
            tasks = [(ds, c, lo, hi, x_i[lo:hi], origin[lo:hi], batch_photons) for c, lo, hi in todo]
            shared = (cluster.keep(volume), setup)
            for i, _ in cluster.run(_acquire_chunk, tasks, shared=shared):
                finished += todo[i][2] - todo[i][1]
                if progress:
                    progress(finished, P)


def setup_request(setup: PlanarSetup) -> dict:
    """The setup as a data set's ``request`` records it (JSON: tuples become lists, so that a resume
    compares like with like): ``setup`` and, only where there are any, the angle axes (``angles``: a data
    set made before them resumes as it was)."""
    fields = {k: v for k, v in asdict(setup).items() if k not in ("incidence", "exit_bins")}
    angles = angle_record(setup.incidence, setup.exit_bins)
    return json.loads(json.dumps({"setup": fields, **({"angles": angles} if angles else {})}))


def _acquire_chunk(
    volume: Volume,
    setup: PlanarSetup,
    ds: PlanarDataset,
    c: int,
    lo: int,
    hi: int,
    x_i: np.ndarray,
    origin: np.ndarray,
    batch_photons: int,
) -> None:
    """Trace chunk ``c`` (points lo..hi at ``x_i``, windows at ``origin``), write it, then its done flag.

    A pure function of its arguments (photon streams seeded by absolute point index): run here or on
    a worker, again after an interruption, it writes the same bytes.
    """
    g = ds.group
    W, H, _ = volume.size_mm
    n = setup.window_pixels()
    # pixel centres on the sample?
    cx = origin[:, 0, None, None] + setup.pitch * (np.arange(n)[None, None, :] + 0.5)
    cy = origin[:, 1, None, None] + setup.pitch * (np.arange(n)[None, :, None] + 0.5)
    mask = (cx >= 0) & (cx <= W) & (cy >= 0) & (cy <= H)
    out = _every_chunk(g)
    toward = setup.incidence.local()  # the slab's tangent frame is (x, y, z)
    for d in range(setup.incidence.count):
        beam = (d, None if d == 0 else toward[d])
        R_d, var, spec, top, binned = _tally_beam(volume, setup, lo, hi, x_i, origin, batch_photons, *beam)
        if d == 0:
            out("R_d")[lo:hi] = R_d.astype(setup.dtype)
            out("variance")[lo:hi] = var.astype(setup.dtype)
            out("mask")[lo:hi] = mask
            out("specular")[lo:hi] = spec.astype(np.float32)
            out("total_diffuse")[lo:hi] = top.astype(np.float32)
        else:  # (the variance of an oblique beam is the same Poisson estimate: not stored)
            out("R_d_oblique")[lo:hi, d - 1] = R_d.astype(setup.dtype)
            out("specular_oblique")[lo:hi, d - 1] = spec.astype(np.float32)
            out("total_diffuse_oblique")[lo:hi, d - 1] = top.astype(np.float32)
        if binned is not None:
            out("exit_bins")[lo:hi, d] = binned.astype(setup.dtype)
    out("chunk_done")[c] = True  # last: the chunk is complete


def _tally_beam(volume, setup, lo, hi, x_i, origin, batch_photons, d, toward_light):
    """One beam direction of points lo..hi (direction ``d`` of the setup's incidence; ``toward_light`` None:
    the setup's own angle): R_d and its variance (points, n, n, 3), the specular and top-face shares
    (points, 3) and, with exit bins, R_d split by exit bin (points, n, n, 3, B).  Direction 0 draws the same
    photons as before the angle axes existed; direction d another stream."""
    n = setup.window_pixels()
    area = setup.pitch**2
    bins = setup.exit_bins
    B = 1 if bins is None else bins.count
    counts = np.zeros((hi - lo, n, n, 3, B))
    spec = np.zeros((hi - lo, 3))
    top = np.zeros((hi - lo, 3))
    per_launch = max(1, batch_photons // setup.photons)
    for ch in range(3):
        for b0 in range(lo, hi, per_launch):
            b1 = min(hi, b0 + per_launch)
            res = random_walk(
                volume,
                ch,
                x_i[b0 - lo : b1 - lo],
                setup.photons,
                seed=setup.seed + 104_729 * d,
                first_point=b0,
                theta_inc_deg=setup.theta_inc_deg,
                toward_light=None if toward_light is None else tuple(float(v) for v in toward_light),
                index_matched=setup.index_matched,
            )
            m = b1 - b0
            off = b0 - lo  # first row of this launch within the chunk
            local = np.arange(m).repeat(setup.photons)  # launch-local point of each photon
            spec[off : off + m, ch] = np.bincount(local, weights=res.code == -1, minlength=m)
            is_top = res.code == TOP
            pt = local[is_top]
            top[off : off + m, ch] = np.bincount(pt, minlength=m)
            # pixel of each exit in its own window
            col = np.floor((res.x[is_top] - origin[b0 - lo + pt, 0]) / setup.pitch).astype(np.int64)
            row = np.floor((res.y[is_top] - origin[b0 - lo + pt, 1]) / setup.pitch).astype(np.int64)
            inside = (col >= 0) & (col < n) & (row >= 0) & (row < n)
            b = np.zeros(int(inside.sum()), np.int64)
            if bins is not None:  # the exit's direction in the air, and away from x_i or back toward it
                xy = res.exit_xy[is_top][inside]
                omega = np.column_stack([xy, res.cos_exit[is_top][inside]])
                away = np.column_stack(
                    [res.x[is_top][inside] - x_i[b0 - lo + pt[inside], 0],
                     res.y[is_top][inside] - x_i[b0 - lo + pt[inside], 1], np.zeros(len(b))]
                )  # fmt: skip
                b = bins.index(omega, np.broadcast_to([0.0, 0.0, 1.0], omega.shape), away)
            flat = (((off + pt[inside]) * n + row[inside]) * n + col[inside]) * B + b
            counts[..., ch, :] += np.bincount(flat, minlength=(hi - lo) * n * n * B).reshape(hi - lo, n, n, B)
    N = float(setup.photons)
    p_hat = counts.sum(axis=-1) / N
    R_d = p_hat / area
    var = p_hat * (1.0 - p_hat) / (N * area**2)
    binned = None if bins is None else counts / (N * area)
    return R_d, var, spec / N, top / N, binned


def _every_chunk(group):
    """The group's arrays as writers that store every chunk as a file, all-zero ones included.

    Zarr's ``write_empty_chunks`` is a runtime setting, not saved with the array: a store opened again
    would skip chunks holding only the fill value (an index-matched slab's ``specular``, a dark window's
    ``variance``), and a missing chunk file would then be indistinguishable from one deleted.
    """
    every = {"write_empty_chunks": True}
    return lambda name: group[name].with_config(every)


def _volume_fingerprint(volume: Volume) -> dict:

    h = hashlib.sha256()
    for a in (volume.sigma_s, volume.sigma_a):
        h.update(np.ascontiguousarray(a).tobytes())
    return {
        "sha256": h.hexdigest(),
        "shape": list(volume.shape),
        "voxel_mm": volume.voxel_mm,
        "g": volume.g,
        "eta": volume.eta,
    }
