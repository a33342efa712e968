"""Photographs of a scanned laser spot → a planar data set (the same format as ``acquire planar``).

For each laser position (incident point x_i) the rig provides one HDR image (or several repeated
frames, or a bracket of LDR exposures).  Each image becomes one window of R_d on the sample-plane
grid around x_i:

1. **read** the image(s) (:mod:`translucency.rig.shared.hdr`); repeated frames are averaged, brackets merged;
2. **correct** in the image: subtract the dark frame, divide by the flat field and the vignetting
   fall-off, divide by the exposure time (s) and the laser power (W);
3. **resample** to the window's pixels on the sample plane: each output pixel is the mean over
   s × s points spread evenly over its area *on the sample* (so the mean is area-weighted there), each
   point read bilinearly at its image position H·(x, y, 1); a ``flux`` camera's values are first
   multiplied by the area Jacobian |det ∂(u, v)/∂(x, y)| (pixels per mm²) so that they become a density;
4. **scale** by the calibration's radiometric scale (pixel value per unit exitance):
   R_d = value / (scale · power · exposure), in mm⁻².

The **variance** follows the stated noise model of the sensor, Var = gain · value + read_noise² per raw
frame (or, with repeated frames, their spread / n), carried through the same corrections; the mean of
s × s interpolated values of n_eff independent image pixels has variance ≈ mean Var / max(1, n_eff),
n_eff = pitch² · pixels per mm².

The **mask** drops window pixels that touch (through their bilinear footprint) an image pixel that is
saturated (at or above the calibration's ``saturation`` in any channel, grown by ``dilate`` pixels for
blooming), under-exposed (below ``floor`` after the dark frame, or in no exposure of a bracket), not
finite, outside the image, or within ``specular_radius`` mm of x_i (the laser's direct reflection and
the blinding entry spot).

Work runs in chunks of points with the data set's ``chunk_done`` flags: a re-run with the same inputs
(file hashes included) resumes; other inputs are refused without ``overwrite``.

The steps' homes: :mod:`.positions` (the table of laser positions), :mod:`.setup` (the import's
arguments), :mod:`.frames` (steps 1–2), :mod:`.resample` (step 3), :mod:`.beam` (the beam-width
correction), :mod:`.provenance` (hashes, header, resume request); this module runs the chunks as
:class:`PlanarImport`, the importers' contract of :mod:`translucency.rig.contract`.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterator
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..._validate import TranslucencyError
from ...cluster import open_cluster, parse_scheduler
from ...io.dataset import PlanarDataset, create_dataset
from ..contract import Chunk, run_import
from .beam import beam_correction
from .calibration import Calibration
from .frames import image_shape, load_frame, pfm_shape
from .positions import Shot, read_positions
from .provenance import import_header
from .resample import crop_calibration, resample_window, window_region
from .setup import ImportSetup


def import_images(
    folder,
    positions,
    calibration: Calibration,
    out,
    setup: ImportSetup | None = None,
    *,
    overwrite: bool = False,
    inputs=(),
    progress: Callable[[int, int], None] | None = None,
    workers: int | None = None,
    views=(),
    scheduler: str | None = "threads",
) -> PlanarDataset:
    """Import a rig's photographs as a planar data set at ``out`` (resumable, chunk by chunk).

    Parameters
    ----------
    folder : path
        The images.
    positions : path or list of Shot
        The table of laser positions (:func:`read_positions`), or its rows.
    calibration : Calibration
        Homography, radiometric scale, corrections, noise model.
    out : path
        Zarr directory; an unfinished import of the same inputs resumes.
    setup : ImportSetup
        Output grid, window, masks, chunking.
    workers : int, optional
        Images read and resampled at once (threads; default min(4, CPUs)).
    scheduler : str, optional
        Where the chunks run: ``"threads"`` (this process, default), ``"local:N"`` or
        ``"tcp://HOST:PORT"`` (:mod:`translucency.cluster`): each chunk a task that reads its images and
        writes its part of the store and its done flag; the same bytes either way.  The images and the
        output must be visible to the workers at the same paths.
    views : sequence of (folder, positions, Calibration), optional
        The same laser positions photographed by further cameras (one row per position, in the same
        order; the laser positions are the first table's).  Each view is resampled onto the same windows
        with its own calibration and the views are averaged where all of them are valid: two cameras at
        opposite azimuths cancel the part of the exit radiance that leans away from the beam, which one
        oblique camera sees as a strong gradient across the window (see docs/validation/planar-rig.md).

    Returns
    -------
    PlanarDataset

    Examples
    --------
    >>> import tempfile
    >>> from translucency.rig.shared.hdr import write_pfm
    >>> from translucency.rig.shared.homography import Homography
    >>> d = Path(tempfile.mkdtemp())
    >>> write_pfm(d / "a.pfm", np.full((64, 64, 3), 2.0, np.float32))
    >>> _ = (d / "pos.csv").write_text("file,x,y\\na.pfm,3.2,3.2\\n")
    >>> cal = Calibration(Homography.from_matrix([[10, 0, 0], [0, 10, 0], [0, 0, 1]]), scale=4.0)
    >>> out = Path(tempfile.mkdtemp()) / "out.zarr"
    >>> ds = import_images(d, d / "pos.csv", cal, out, ImportSetup(pitch=0.5, window=2.5))
    >>> ds.window, float(ds["R_d"][0, 2, 2, 0])
    ((5, 5), 0.5)
    """
    importer = PlanarImport.from_setup(
        folder,
        positions,
        calibration,
        setup,
        inputs=inputs,
        workers=workers,
        views=views,
        scheduler=scheduler,
    )
    return run_import(importer, out, overwrite=overwrite, progress=progress)


@dataclass
class PlanarImport:
    """An import of photographs, its setup read and checked: the :class:`~translucency.rig.contract.Importer`
    of a planar data set (arguments as :func:`import_images`'s).

    Examples
    --------
    One photograph of value 2 at 10 px per mm, 4 pixel values per unit exitance: R_d = 2 / 4 = 0.5 mm⁻²
    over the window, whose origin lies on the pitch's lattice around x_i:

    >>> import tempfile
    >>> from translucency.rig.shared.hdr import write_pfm
    >>> from translucency.rig.shared.homography import Homography
    >>> d = Path(tempfile.mkdtemp())
    >>> write_pfm(d / "a.pfm", np.full((64, 64, 3), 2.0, np.float32))
    >>> _ = (d / "pos.csv").write_text("file,x,y\\na.pfm,3.2,3.2\\n")
    >>> cal = Calibration(Homography.from_matrix(np.diag([10.0, 10.0, 1.0])), scale=4.0)
    >>> imp = PlanarImport.from_setup(d, d / "pos.csv", cal, ImportSetup(pitch=0.5, window=2.5))
    >>> imp.n_points, imp.chunk_points, imp.header["window"]
    (1, 16, [5, 5])
    >>> ds = imp.create(Path(tempfile.mkdtemp()) / "out.zarr", overwrite=False)
    >>> [c.index for c in imp.import_chunks(ds, [Chunk(0, 0, 1)])]
    [0]
    >>> float(ds.group["R_d"][0, 2, 2, 0]), ds.group["window_origin"][0].tolist()
    (0.5, [2.0, 2.0])

    Images of another size are refused before any work:

    >>> write_pfm(d / "b.pfm", np.ones((32, 32, 3), np.float32))
    >>> _ = (d / "two.csv").write_text("file,x,y\\na.pfm,3.2,3.2\\nb.pfm,3.2,2.2\\n")
    >>> try:
    ...     PlanarImport.from_setup(d, d / "two.csv", cal)
    ... except TranslucencyError as exc:
    ...     print(str(exc).split("/")[-1])
    b.pfm: image of 32 x 32 pixels among images of 64 x 64 pixels
    """

    job: _ImportJob
    header: dict
    inputs: list  # the inputs the data set is made from (compared on resume)
    workers: int
    scheduler: str | None
    n_points: int
    chunk_points: int

    @classmethod
    def from_setup(
        cls,
        folder,
        positions,
        calibration: Calibration,
        setup: ImportSetup | None = None,
        *,
        inputs=(),
        workers: int | None = None,
        views=(),
        scheduler: str | None = "threads",
    ) -> PlanarImport:
        """Read the laser positions, check the images' sizes and the calibrations, hash the files."""
        setup = setup or ImportSetup()
        setup.check()
        parse_scheduler(scheduler)  # a bad option is one line before any work
        folder = Path(folder)
        table = None
        if not isinstance(positions, list | tuple):
            table = Path(positions)
            positions = read_positions(table, folder)
        shots = list(positions)
        if not shots:
            raise TranslucencyError("positions: no laser positions")
        shape = image_shape(shots[0])
        calibration.check(shape)
        for s in shots:  # PFM sizes from their headers, before any work (other formats: when read)
            for f in s.files:
                got = pfm_shape(f)
                if got is not None and got != shape[:2]:
                    raise TranslucencyError(
                        f"{f}: image of {got[1]} x {got[0]} pixels "
                        f"among images of {shape[1]} x {shape[0]} pixels"
                    )
        H = calibration.homography
        others = []
        for v_folder, v_positions, v_calib in views:
            v_folder = Path(v_folder)
            v_table = None if isinstance(v_positions, list | tuple) else Path(v_positions)
            v_shots = list(v_positions) if v_table is None else read_positions(v_table, v_folder)
            if len(v_shots) != len(shots):
                raise TranslucencyError(
                    f"views: {v_folder} has {len(v_shots)} laser positions, the first view {len(shots)}"
                )
            v_shape = image_shape(v_shots[0])
            v_calib.check(v_shape)
            others.append((v_folder, v_table, v_shots, v_calib, v_shape))
        x_i = np.array(
            [s.position if s.units == "mm" else H.to_sample([s.position])[0] for s in shots], dtype=np.float64
        )
        n, p = setup.window_pixels(), setup.pitch
        centre = (np.floor(x_i / p) + 0.5) * p  # the window's centre pixel on the lattice of the acquisition
        origin = centre - p * n / 2.0
        workers = max(1, int(workers or min(4, os.cpu_count() or 1)))
        header = import_header(
            folder, table, shots, calibration, setup, x_i, views=[o[:4] for o in others], workers=workers
        )
        job = _ImportJob(shots, calibration, shape, [o[2:] for o in others], setup, x_i, origin)
        inputs = [folder, table, *(q for o in others for q in o[:2]), *inputs]
        return cls(job, header, inputs, workers, scheduler, len(shots), setup.chunk_points)

    def create(self, out, *, overwrite: bool) -> PlanarDataset:
        """The planar data set at ``out`` with the laser positions and the windows' origins."""
        ds = create_dataset(out, self.header, overwrite=overwrite, inputs=self.inputs)
        g = ds.group
        g["x_i"][...] = self.job.x_i.astype(np.float32)
        g["window_origin"][...] = self.job.origin.astype(np.float32)
        return ds

    def import_chunks(self, ds: PlanarDataset, todo: list[Chunk]) -> Iterator[Chunk]:
        """The chunks on the scheduler: in this process chunk after chunk, a chunk's images in threads; on
        a cluster a task per chunk, each reading its images and writing its part of the store and its flag."""
        with open_cluster(self.scheduler) as cluster:
            if cluster is None:
                with ThreadPoolExecutor(self.workers) as pool:
                    for chunk in todo:
                        _import_chunk(self.job, ds, chunk.index, chunk.lo, chunk.hi, pool)
                        yield chunk
            else:
                tasks = [(ds, c.index, c.lo, c.hi) for c in todo]
                for i, _ in cluster.run(_import_chunk, tasks, shared=(cluster.keep(self.job),)):
                    yield todo[i]

    def finish(self, ds: PlanarDataset, done: list[Chunk]) -> PlanarDataset:
        """The data set, every chunk written."""
        return ds


@dataclass
class _ImportJob:
    """What every chunk of an import needs besides its index range (sent to a cluster once)."""

    shots: list  # the first view's laser positions (Shot)
    calibration: Calibration
    shape: tuple  # its images' shape
    others: list  # further views: (shots, calibration, image shape)
    setup: ImportSetup
    x_i: np.ndarray  # (P, 2) laser positions, mm
    origin: np.ndarray  # (P, 2) window origins, mm

    def view(self, j: int, shot: Shot, calib: Calibration, shape) -> tuple:
        """One image → its window of R_d, variance and mask, normalised by scale and laser power."""
        side = self.setup.window_pixels() * self.setup.pitch
        region = window_region(calib, self.origin[j], side, shape)
        frame = load_frame(shot, calib, self.setup, shape, region)
        val, var, mask = resample_window(
            frame, crop_calibration(calib, region), self.setup, self.x_i[j], self.origin[j]
        )
        norm = (np.asarray(calib.scale, np.float64) * shot.power).astype(np.float32)
        return val / norm, var / (norm * norm), mask

    def point(self, j: int) -> tuple:
        """Laser position j → the mean of its views where all of them are valid."""
        val, var, mask = self.view(j, self.shots[j], self.calibration, self.shape)
        for v_shots, v_calib, v_shape in self.others:
            v_val, v_var, v_mask = self.view(j, v_shots[j], v_calib, v_shape)
            val, var, mask = val + v_val, var + v_var, mask & v_mask
        k = 1 + len(self.others)
        val, var = val / k, var / (k * k)
        if self.setup.beam_rms > 0:
            val = beam_correction(val, mask, self.x_i[j], self.origin[j], self.setup)
        return val, var, mask


def _import_chunk(job: _ImportJob, ds: PlanarDataset, chunk: int, lo: int, hi: int, pool=None) -> None:
    """Import chunk ``chunk`` (laser positions lo..hi), write it, then its done flag.

    A pure function of the images and its arguments: in this process (its images read in ``pool``'s
    threads) or as a task on a worker, it writes the same bytes.
    """
    setup, g = job.setup, ds.group
    n, p = setup.window_pixels(), setup.pitch
    R = np.zeros((hi - lo, n, n, 3), np.float32)
    V = np.zeros_like(R)
    M = np.zeros((hi - lo, n, n), bool)
    results = pool.map(job.point, range(lo, hi)) if pool is not None else map(job.point, range(lo, hi))
    for j, (val, var, mask) in zip(range(lo, hi), results):
        R[j - lo], V[j - lo], M[j - lo] = val, var, mask
    g["R_d"][lo:hi] = R.astype(setup.dtype)
    g["variance"][lo:hi] = V.astype(setup.dtype)
    g["mask"][lo:hi] = M
    g["specular"][lo:hi] = np.zeros((hi - lo, 3), np.float32)  # not measured by a camera
    total = np.where(M[..., None], R, 0).sum(axis=(1, 2)) * p * p
    g["total_diffuse"][lo:hi] = total.astype(np.float32)
    g["chunk_done"][chunk] = True  # last: the chunk is complete
