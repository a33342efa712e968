"""An acquisition that resumes: the data set at its output made with the same arguments, the chunks
done there, what is left, and the start of the information line that says so (``translucency acquire``
keeps the chunks done when stopped and picks up where it stopped).
"""

from __future__ import annotations

from pathlib import Path
from typing import NamedTuple

import numpy as np


class Resumed(NamedTuple):
    """A data set an acquisition resumes: its chunks done, of how many, and the points left to acquire."""

    done: int
    chunks: int
    points_left: int


def _chunks_of(ds) -> tuple[np.ndarray, np.ndarray]:
    """The done flags of a data set's chunks and the points of each."""
    done = np.asarray(ds.group["chunk_done"][...], dtype=bool)
    k, P = ds.chunk_points, ds.n_points
    return done, np.array([min(P, (c + 1) * k) - c * k for c in range(len(done))])


def resumable(out: Path, opener, same) -> Resumed | None:
    """The data set at ``out`` that this acquisition resumes (made with the same arguments: ``same`` of its
    header's request), or None when it starts afresh."""
    try:
        ds = opener(out)
        if not same(ds.header.get("request", {})):
            return None
        done, points = _chunks_of(ds)
    except Exception:  # noqa: BLE001 — no data set, or one that cannot be read: a fresh start (checked later)
        return None
    if not done.any():
        return None
    return Resumed(int(done.sum()), len(done), int(points[~done].sum()))


def to_acquire(state: Resumed | None, points: int) -> int:
    """Incident points left to acquire."""
    return points if state is None else state.points_left


def matches(request: dict, same: dict) -> bool:
    """Whether a data set's ``request`` (its header's) holds every value of ``same``."""
    return all(request.get(k) == v for k, v in same.items())


def resuming(state: Resumed | None) -> str:
    """The start of the information line of a resumed acquisition.

    Examples
    --------
    >>> resuming(Resumed(done=3, chunks=8, points_left=40))
    'resuming (3/8 chunks done, kept): the '
    >>> resuming(None)
    ''
    """
    if state is None:
        return ""
    if state.points_left == 0:
        return f"nothing left to acquire ({state.chunks}/{state.chunks} chunks done): "
    return f"resuming ({state.done}/{state.chunks} chunks done, kept): the "
