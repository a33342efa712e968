"""What the two chunked data-set stores share: lazy reads, the chunks of points, the damage checks.

A store is a Zarr v3 group whose per-point arrays are chunked along their first axis in chunks of
``chunk_points`` incident points, with a ``chunk_done`` flag per chunk written last (the resume marker).
:class:`~translucency.io.dataset.PlanarDataset` and :class:`~translucency.io.mesh_dataset.MeshDataset`
derive from :class:`ChunkedStore`, each naming its arrays; their formats are their own modules'.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar

import numpy as np

from .._validate import TranslucencyError


@dataclass
class ChunkedStore(ABC):
    """An opened chunked store; arrays are read lazily from the Zarr group."""

    path: Path
    header: dict
    group: object

    #: the arrays ``store[name]`` reads
    ARRAYS: ClassVar[tuple[str, ...]] = ()
    #: the per-point arrays written chunk by chunk, checked for each finished chunk of points
    PER_POINT: ClassVar[tuple[str, ...]] = ()
    #: what one index of the arrays' first axis is, as read errors name it
    ROW: ClassVar[str] = "row"

    @property
    def n_points(self) -> int:
        return int(self.header["n_points"])

    @property
    @abstractmethod
    def chunk_points(self) -> int:
        """Incident points per chunk (per ``chunk_done`` flag)."""

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
