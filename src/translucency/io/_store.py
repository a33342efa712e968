"""What the two chunked data-set stores share: opening and checking, lazy reads, the chunks of points,
the damage checks, the ``info`` record.

A store is a Zarr v3 group whose per-point arrays are chunked along their first axis in chunks of
``chunk_points`` incident points, with a ``chunk_done`` flag per chunk written last (the resume marker).
:class:`~translucency.io.dataset.PlanarDataset` and :class:`~translucency.io.mesh_dataset.MeshDataset`
derive from :class:`ChunkedStore`, each naming its header, its arrays and its own checks
(:meth:`ChunkedStore.from_group`); their formats are their own modules'.  :func:`open_store` opens a
path once, tells which kind of data set it holds and returns it opened as that kind.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar

import numpy as np

from .._validate import TranslucencyError, check_undamaged
from .outputs import DATASET_KEYS


@dataclass
class ChunkedStore(ABC):
    """An opened chunked store; arrays are read lazily from the Zarr group."""

    path: Path
    header: dict
    group: object

    #: the kind of data set, as :data:`~translucency.io.outputs.KINDS` names it
    KIND: ClassVar[str]
    #: the root group's attribute holding the header, and the header's ``format`` and ``version``
    HEADER_KEY: ClassVar[str]
    FORMAT: ClassVar[str]
    VERSION: ClassVar[int]
    #: the arrays ``store[name]`` reads
    ARRAYS: ClassVar[tuple[str, ...]] = ()
    #: the per-point arrays written chunk by chunk, checked for each finished chunk of points
    PER_POINT: ClassVar[tuple[str, ...]] = ()
    #: what one index of the arrays' first axis is, as read errors name it
    ROW: ClassVar[str] = "row"

    @classmethod
    @abstractmethod
    def from_group(cls, path: Path, header: dict, group) -> ChunkedStore:
        """The data set of the opened Zarr ``group`` whose ``header`` is of this kind (format and version
        checked by :func:`open_store`): the kind's header fields and arrays checked, one line a fault."""

    @property
    def n_points(self) -> int:
        return int(self.header["n_points"])

    @property
    @abstractmethod
    def chunk_points(self) -> int:
        """Incident points per chunk (per ``chunk_done`` flag)."""

    def check_complete(self) -> None:
        """Refuse, in one line, a data set that is damaged (missing or undecodable chunks: re-running the
        acquisition with the same arguments repairs exactly those) or unfinished (an interrupted
        acquisition: re-running it finishes it)."""
        check_undamaged(self)
        done = np.asarray(self.group["chunk_done"][...], dtype=bool)  # decodes: checked with the damage
        if not done.all():
            raise TranslucencyError(
                f"{self.path}: unfinished acquisition ({int(done.sum())}/{len(done)} chunks done); re-run "
                "the same `translucency acquire` command to finish it"
            )

    def __getitem__(self, key: str) -> np.ndarray:
        if key not in self.ARRAYS:
            raise KeyError(key)
        return self.read(key)

    def read(self, key: str, s: int | None = None, e: int | None = None) -> np.ndarray:
        """Rows s..e of an array (all by default); a chunk that cannot be decoded is one line naming it."""
        try:
            return np.asarray(self.group[key][s:e])
        except Exception as exc:  # noqa: BLE001 — codec and I/O faults are the file's, said in one line
            raise TranslucencyError(
                f"{self.path}: array {key!r} near {self.ROW} {0 if s is None else s} cannot be read "
                f"({type(exc).__name__}: {(str(exc).splitlines() or [''])[0][:80]}); "
                "re-run the acquisition to repair it"
            ) from None

    def complete(self) -> bool:
        """Every chunk of points finished, and none of their files missing (see :meth:`damaged_chunks`)."""
        return bool(np.all(self["chunk_done"])) and not self.damaged_chunks(decode=False)

    def damaged_chunks(self, *, decode: bool = True) -> dict:
        """Chunks whose data are missing or do not decode: {array name: [chunk index, ...]}.

        A chunk file that is absent reads as zeros in Zarr, silently; for every finished chunk of points
        this looks for the chunk files of each per-point array that must have them
        (:meth:`_expects_files`) and (``decode``) decodes every per-point array there.  Arrays written
        whole at creation are checked first (:meth:`_damaged_whole`).
        """
        bad = self._damaged_whole(decode)
        k = self.chunk_points
        try:
            done = np.flatnonzero(np.asarray(self.group["chunk_done"][...]))
        except Exception:  # noqa: BLE001 — the done flags themselves do not decode: every chunk is suspect
            bad["chunk_done"] = list(range(-(-self.n_points // k)))
            return bad
        for name in self.PER_POINT:
            arr = self.group[name]
            expect_file = self._expects_files(name)
            per = int(arr.chunks[0])  # points per stored chunk of this array
            rest = "/0" * (len(arr.shape) - 1)
            for chunk in done:
                lo, hi = chunk * k, min(self.n_points, (chunk + 1) * k)
                missing = expect_file and any(
                    not (self.path / name / "c" / f"{j}{rest}").is_file()
                    for j in range(lo // per, -(-hi // per))
                )
                if not missing and decode:
                    try:
                        arr[lo:hi]
                    except Exception:  # noqa: BLE001 — a chunk that does not decode is damaged
                        missing = True
                if missing:
                    bad.setdefault(name, []).append(int(chunk))
        return bad

    def _expects_files(self, name: str) -> bool:
        """Whether every finished chunk of per-point array ``name`` is a file (else it may be absent)."""
        return True

    def _damaged_whole(self, decode: bool) -> dict:
        """The arrays written whole at creation that are missing or do not decode: {name: [0]}."""
        return {}

    def summary(self, **fields) -> dict:
        """The ``translucency info`` record every data set shares — format, points, sample, photons, seed,
        completion, size (bytes) and software — with the kind's own ``fields`` and the damaged chunks
        ({array: [chunk, ...]}, :meth:`damaged_chunks`) in between; numbers as numbers, objects as objects."""
        header, done, damaged = self.header, self["chunk_done"], self.damaged_chunks()
        size = sum(f.stat().st_size for f in Path(self.path).rglob("*") if f.is_file())
        acquisition = header.get("acquisition", header)  # planar headers nest it, mesh headers do not
        return {
            "format": header["format"],
            "version": header["version"],
            "n_points": header["n_points"],
            **fields,
            "damaged": {str(k): [int(c) for c in v] for k, v in damaged.items()},
            "sample": header.get("sample", {}),
            "photons": acquisition.get("photons"),
            "seed": acquisition.get("seed"),
            "chunks_done": int(done.sum()),
            "chunks": int(done.size),
            "complete": bool(done.all()),
            "size_bytes": size,
            "software": header.get("software", {}),
        }


def open_store(path, kinds: tuple[type[ChunkedStore], ...], *, writable: bool = False) -> ChunkedStore:
    """Open the data set at ``path`` once, as the one of ``kinds`` its header names, and check it.

    The checks every kind shares come first — the path exists, a folder holds ``zarr.json``, Zarr opens
    it, its root carries the header of one of ``kinds`` with their format and version — then the kind's
    own (:meth:`ChunkedStore.from_group`).  Each fault is one line naming the path; a data set of
    another kind is named as such.  Read-only unless ``writable`` (used when resuming an acquisition).
    """
    path = Path(path)
    if not path.exists():
        raise TranslucencyError(f"{path}: no such data set")
    import zarr  # heavy: Zarr loads where a store is read or written, not for --help

    if path.is_dir() and not (path / "zarr.json").is_file():
        raise TranslucencyError(f"{path}: a folder, but not a translucency data set (it holds no zarr.json)")
    try:
        group = zarr.open_group(str(path), mode="r+" if writable else "r")
        attrs = dict(group.attrs)
    except Exception as exc:  # noqa: BLE001 — any decoding fault becomes one line
        raise TranslucencyError(f"{path}: not a readable Zarr data set ({type(exc).__name__})") from None
    wanted = kinds[0].KIND if len(kinds) == 1 else "data set"
    kind = next((k for k in kinds if isinstance(attrs.get(k.HEADER_KEY), dict)), None)
    if kind is None:
        other = [k for k, key in DATASET_KEYS.items() if isinstance(attrs.get(key), dict)]
        if other:
            raise TranslucencyError(f"{path}: a {other[0]}, where a {wanted} is needed")
        keys = " or ".join(f"'{k.HEADER_KEY}'" for k in kinds)
        raise TranslucencyError(f"{path}: not a translucency {wanted} (no {keys} header)")
    header = attrs[kind.HEADER_KEY]
    if header.get("format") != kind.FORMAT:
        raise TranslucencyError(f"{path}: not a translucency {kind.KIND} (format {header.get('format')!r})")
    if header.get("version") != kind.VERSION:
        raise TranslucencyError(
            f"{path}: {kind.KIND} version {header.get('version')!r} is not supported "
            f"(this reader knows {kind.VERSION})"
        )
    return kind.from_group(path, header, group)


def check_shapes(path: Path, group, expect: dict) -> None:
    """Refuse, in one line, a store whose array ``name`` is missing, unreadable or not of the shape
    ``expect[name]`` (a tuple; None: any length along that axis)."""
    for name, shape in expect.items():
        try:
            arr = group[name]
        except Exception:  # noqa: BLE001 — absent, or its metadata does not parse
            raise TranslucencyError(f"{path}: missing or unreadable array {name!r}") from None
        if len(arr.shape) != len(shape) or any(w is not None and w != a for w, a in zip(shape, arr.shape)):
            raise TranslucencyError(f"{path}: array {name!r} has shape {tuple(arr.shape)}, expected {shape}")
