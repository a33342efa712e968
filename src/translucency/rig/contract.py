"""The importers' contract: a setup → chunks of laser shots → a data set, resumable chunk by chunk.

Both importers — :mod:`.planar.importer` (photographs of a flat sample → a planar data set) and
:mod:`.object.importer` (multi-view photographs of an object → a mesh data set) — are an
:class:`Importer`, made from a setup that is read and checked before any work (``from_setup``: its
laser shots, and the data set's header with the ``request`` a re-run compares).  :func:`run_import`
drives one under the output's lock:

1. **create** the data set at ``out``, or reopen it: the same request resumes, another is refused
   unless ``overwrite``;
2. **import the chunks** not done yet, ``chunk_points`` laser shots each (the unit of resuming and of
   memory), each written with its ``chunk_done`` flag last;
3. **finish**: what the import returns, once every chunk is in.

Progress is counted in laser shots, the chunks done before included.  Both requests record their input
files by :func:`sha256_file`.
"""

from __future__ import annotations

import hashlib
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Protocol

import numpy as np

from ..io.outputs import output_lock


@dataclass(frozen=True)
class Chunk:
    """Chunk ``index`` of an import: the laser shots ``lo`` … ``hi`` − 1.

    Examples
    --------
    >>> c = Chunk(index=2, lo=16, hi=20)  # the last, short chunk of 20 shots at 8 a chunk
    >>> c.hi - c.lo
    4
    >>> c.lo = 0
    Traceback (most recent call last):
    dataclasses.FrozenInstanceError: cannot assign to field 'lo'
    """

    index: int
    lo: int
    hi: int


class Importer(Protocol):
    """An import whose setup is read and checked: its chunks of laser shots → its data set.

    Examples
    --------
    A toy importer of 5 shots, 2 a chunk, whose data set lives in memory; run again, it finds every
    chunk done and imports nothing (progress is counted in shots, those done before included):

    >>> import tempfile
    >>> from types import SimpleNamespace
    >>> ds = SimpleNamespace(group={"chunk_done": np.zeros(3, bool)}, values=np.zeros(5, int))
    >>> class Squares:
    ...     n_points, chunk_points = 5, 2
    ...     def create(self, out, *, overwrite):
    ...         return ds
    ...     def import_chunks(self, ds, todo):
    ...         for c in todo:
    ...             ds.values[c.lo : c.hi] = np.arange(c.lo, c.hi) ** 2
    ...             ds.group["chunk_done"][c.index] = True  # written last
    ...             yield c
    ...     def finish(self, ds, done):
    ...         return ds.values.tolist()
    >>> out = Path(tempfile.mkdtemp()) / "toy"
    >>> show = lambda done, total: print(done, "of", total)
    >>> run_import(Squares(), out, progress=show)
    2 of 5
    4 of 5
    5 of 5
    [0, 1, 4, 9, 16]
    >>> run_import(Squares(), out, progress=show)
    5 of 5
    [0, 1, 4, 9, 16]
    """

    @property
    def n_points(self) -> int:
        """Laser shots P."""

    @property
    def chunk_points(self) -> int:
        """Laser shots per chunk."""

    def create(self, out: Path, *, overwrite: bool):
        """The data set at ``out`` (its ``group`` holds ``chunk_done``), made or reopened to resume."""

    def import_chunks(self, ds, todo: Sequence[Chunk]) -> Iterator[Chunk]:
        """Import ``todo`` into ``ds``, each chunk's done flag written last; yield each chunk once written."""

    def finish(self, ds, done: Sequence[Chunk]):
        """What the import returns, every chunk written (``done``: the chunks written by an earlier run)."""


def run_import(
    importer: Importer, out, *, overwrite: bool = False, progress: Callable[[int, int], None] | None = None
):
    """Run ``importer`` into the data set at ``out``: the chunks not done, then its ``finish``.

    Examples
    --------
    >>> import tempfile
    >>> from translucency.rig.planar.calibration import Calibration
    >>> from translucency.rig.planar.importer import PlanarImport
    >>> from translucency.rig.planar.setup import ImportSetup
    >>> from translucency.rig.shared.homography import Homography
    >>> from translucency.rig.shared.hdr import write_pfm
    >>> d = Path(tempfile.mkdtemp())
    >>> write_pfm(d / "a.pfm", np.full((64, 64, 3), 2.0, np.float32))
    >>> write_pfm(d / "b.pfm", np.full((64, 64, 3), 2.0, np.float32))
    >>> _ = (d / "pos.csv").write_text("file,x,y\\na.pfm,3.2,3.2\\nb.pfm,3.2,2.2\\n")
    >>> cal = Calibration(Homography.from_matrix([[10, 0, 0], [0, 10, 0], [0, 0, 1]]), scale=4.0)
    >>> setup = ImportSetup(pitch=0.5, window=2.5, chunk_points=1)
    >>> importer = PlanarImport.from_setup(d, d / "pos.csv", cal, setup)
    >>> out = Path(tempfile.mkdtemp()) / "out.zarr"
    >>> ds = run_import(importer, out, progress=lambda done, total: print(done, "of", total))
    1 of 2
    2 of 2
    >>> ds = run_import(importer, out, progress=lambda done, total: print(done, "of", total))  # resumed: done
    2 of 2
    """
    with output_lock(out):
        ds = importer.create(out, overwrite=overwrite)
        flags = np.asarray(ds.group["chunk_done"][...])
        P, k = importer.n_points, importer.chunk_points
        chunks = [Chunk(c, c * k, min(P, (c + 1) * k)) for c in range(len(flags))]
        todo = [c for c in chunks if not flags[c.index]]
        finished = P - sum(c.hi - c.lo for c in todo)  # shots of the chunks done before
        if progress and finished:
            progress(finished, P)
        for chunk in importer.import_chunks(ds, todo):
            finished += chunk.hi - chunk.lo
            if progress:
                progress(finished, P)
        return importer.finish(ds, [c for c in chunks if flags[c.index]])


def sha256_file(path, block: int = 1 << 22) -> str:
    """The SHA-256 of a file's bytes (hex), read ``block`` bytes at a time."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        while chunk := f.read(block):
            h.update(chunk)
    return h.hexdigest()
