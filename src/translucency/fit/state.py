r"""The state of a fit between chunks and rounds, and its checkpoint.

With a checkpoint the state (running sums and the next chunk to add included)
is saved as chunks are added — at most :data:`CHECKPOINT_SHARE` of the time —
and at the end of every round; an interrupted fit resumes from it bit for bit.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar

import numpy as np

from ..io.atomic import atomic_path

#: the most of the driver's time the checkpoints written within a round may take: a checkpoint holds
#: every point's parameters (O(points)), so after one that took t the next waits (1/share − 1)·t; the
#: chunks added since the last one are fitted again on resume (the same bits: a chunk's task is a pure
#: function of the round's start state).  The state at the end of a round is always written.
CHECKPOINT_SHARE = 0.1


@dataclass
class Params:
    """One parameter set of a fit (the current, the reference or the best state).

    Every family reads the arrays it uses: the exponential families c, a (and s for
    the shared colour), the two-parameter baselines p; α is the modulation texture.

    Examples
    --------
    >>> P = Params(c=np.zeros((2, 1, 1, 1)), a=np.ones((2, 1, 1, 1)), p=np.ones((2, 3, 2)),
    ...            s=np.ones((2, 3)), alpha=np.ones((4, 4)))
    >>> q = P.copy()
    >>> q.c += 1.0                 # a copy is independent
    >>> float(P.c.sum()), float(q.c.sum())
    (0.0, 2.0)
    >>> row = P.rows(1, 2)         # views: a write reaches P; α is shared
    >>> row.c[...] = 7.0
    >>> P.c.ravel().tolist(), row.alpha is P.alpha
    ([0.0, 7.0], True)
    >>> P.assign(q)
    >>> P.c.ravel().tolist()
    [1.0, 1.0]
    """

    #: the arrays of a set, in checkpoint order
    NAMES: ClassVar[tuple] = ("c", "a", "p", "s", "alpha")

    c: np.ndarray  # (P, C, m, n) amplitudes of Σ_k c_k e^{−a_k r}, mm⁻²
    a: np.ndarray  # (P, C, m, n) rates, mm⁻¹
    p: np.ndarray  # (P, 3, 2) a baseline's two parameters per channel: (σ_a, σ_s') or Burley's (A, s)
    s: np.ndarray  # (P, 3) colour scale (1, s_g, s_b) of the shared-colour model
    alpha: np.ndarray | None  # the modulation texture α (the source's shape)

    def copy(self) -> Params:
        """An independent copy."""
        return Params(*(getattr(self, k).copy() for k in self.NAMES))

    def assign(self, other: Params) -> None:
        """Copy ``other``'s values into this set's arrays (in place)."""
        for k in self.NAMES:
            getattr(self, k)[...] = getattr(other, k)

    def rows(self, s: int, e: int, *, copy: bool = False) -> Params:
        """Points s..e (views, or copies with ``copy``), this set's α shared."""
        pick = (lambda x: x[s:e].copy()) if copy else (lambda x: x[s:e])
        return Params(pick(self.c), pick(self.a), pick(self.p), pick(self.s), self.alpha)


def _current(name: str) -> property:
    """``state.<name>``: the current set's array."""
    return property(
        lambda self: getattr(self.now, name),
        lambda self, value: setattr(self.now, name, value),
        doc=f"the current parameters' ``{name}`` (``now.{name}``)",
    )


class FitState:
    """Everything a fit carries between chunks and rounds (and saves in a checkpoint).

    P incident points, C colour rows (1: shared colour scale, 3: per channel),
    m directions, n exponential terms; α has the source's shape.  Three
    :class:`Params`: the current state ``now`` (also reached as ``state.c``, ``state.alpha``, …),
    the *reference* state ``ref`` whose model gives the common weights of rounds 2, 3, …
    (set once, after round 1), and the *best* state found so far, ``best``, with its
    objective under those weights (``best_score``).

    Parameters
    ----------
    P, C, m, n : int
        Incident points, colour rows, directions and exponential terms.
    alpha_shape : tuple of int
        The shape of α (the source's).
    n_chunks : int
        Chunks of a round (one Φ each).

    Examples
    --------
    >>> import pathlib, tempfile
    >>> st = FitState(P=4, C=1, m=1, n=2, alpha_shape=(3, 3))
    >>> st.c.shape, st.p.shape, st.alpha.shape
    ((4, 1, 1, 2), (4, 3, 2), (3, 3))
    >>> st.c[1] = 0.5
    >>> st.keep("best")
    >>> st.c[1] = 9.0
    >>> st.restore_best()
    >>> float(st.c[1].max())
    0.5

    A checkpoint is taken back only by the same request with the same shapes:

    >>> path = pathlib.Path(tempfile.mkdtemp()) / "fit.ckpt.npz"
    >>> st.save(path, "request A")
    >>> back = FitState(4, 1, 1, 2, (3, 3))
    >>> back.load(path, "request B"), back.load(path, "request A"), float(back.c[1].max())
    (False, True, 0.5)
    >>> FitState(5, 1, 1, 2, (3, 3)).load(path, "request A")
    False

    Chunks are added in order only:

    >>> st.add(1, None, 0, 1, 0.0, 0.0, None, None)
    Traceback (most recent call last):
    ValueError: chunk 1 added out of order (next: 0)
    """

    #: the parameters of one incident point each, and its other arrays (copied per chunk, committed back)
    POINT_PARAMS = ("c", "a", "p", "s")
    POINT_EXTRA = ("c_iso", "a_iso", "ready", "flagged")
    PER_POINT = (*POINT_PARAMS, *POINT_EXTRA)
    #: the running arrays of a checkpoint besides the parameter sets, in file order
    RUNNING = (
        "num",
        "den",
        "added",
        "phi",
        "phi_ref",
        "c_iso",
        "a_iso",
        "ready",
        "flagged",
        "history",
        "round",
    )
    #: the arrays of a checkpoint, in file order
    SAVED = (
        *Params.NAMES,
        *RUNNING,
        *(f"ref_{k}" for k in Params.NAMES),
        *(f"best_{k}" for k in Params.NAMES),
        "best",
    )

    c = _current("c")
    a = _current("a")
    p = _current("p")
    s = _current("s")
    alpha = _current("alpha")

    def __init__(self, P: int, C: int, m: int, n: int, alpha_shape, n_chunks: int = 1):
        self.now = Params(
            # exponential families: Σ_k c_k e^{−a_k r} per point, colour row and direction (a in 1/mm)
            c=np.zeros((P, C, m, n)),
            a=np.ones((P, C, m, n)),
            p=np.ones((P, 3, 2)),  # dipole (σ_a, σ_s') or Burley (A, s) per point and channel
            s=np.ones((P, 3)),  # colour scale (1, s_g, s_b) of the shared-colour model
            alpha=np.ones(alpha_shape),  # the modulation texture α
        )
        # the isotropic fit each direction starts from (anisotropic model): the tails' anchor
        self.c_iso = np.zeros((P, C, n))
        self.a_iso = np.ones((P, C, n))
        # this round's α statistics Σ w²Py, Σ w²P² of chunks 0 .. added − 1: running sums in chunk
        # order, one sample grid whatever the number of chunks (a chunk that finishes early waits in
        # ``held`` until the chunks before it are in); per chunk (scalars), Φ with the new parameters
        # and the round's α and, in round 2, Φ of the reference state itself
        self.num = np.zeros(alpha_shape)
        self.den = np.zeros(alpha_shape)
        self.added = np.zeros(1, dtype=np.int64)  # the next chunk to add (chunks before it are done)
        self.phi = np.zeros(n_chunks)
        self.phi_ref = np.zeros(n_chunks)
        self.held: dict = {}  # finished chunks waiting for earlier ones: {chunk: result} (not saved)
        self.ready = np.zeros(P, dtype=bool)  # the point's parameters have been fitted once
        self.flagged = np.zeros(P, dtype=bool)  # the point has no usable data
        self.history = np.zeros(0)  # Φ of each round's state (parameters and α)
        self.round = np.zeros(1, dtype=np.int64)  # rounds finished
        self.ref = self.now.copy()  # the reference (weights) and the best state: copies of the parameters
        self.best = self.now.copy()
        self.best_score = np.array([np.inf, -1.0])  # (Φ, round index) of the best state so far

    #: the first point held: 0, or s of a :meth:`part` (points s..e only)
    offset = 0

    @classmethod
    def of_points(cls, arrays: dict, alpha) -> FitState:
        """A state of some points alone: ``arrays`` holds every :data:`PER_POINT` array, α as given."""
        sub = cls.__new__(cls)
        sub.now = Params(*(arrays[k] for k in cls.POINT_PARAMS), alpha)
        for k in cls.POINT_EXTRA:
            setattr(sub, k, arrays[k])
        return sub

    def points(self, s: int, e: int) -> FitState:
        """A private copy of points s..e (α shared, read-only during a round)."""
        return FitState.of_points(
            {k: getattr(self, k)[s - self.offset : e - self.offset].copy() for k in self.PER_POINT},
            self.alpha,
        )

    def reference(self, s: int, e: int) -> Params:
        """The reference state's points s..e (read-only: its model gives the common weights)."""
        return self.ref.rows(s - self.offset, e - self.offset)

    def part(self, s: int, e: int) -> FitState:
        """Points s..e alone with their reference parameters: what a task on a worker needs besides
        α (sent once per round) and the store (read by the worker); :meth:`points` and
        :meth:`reference` of it take absolute indices."""
        sub = FitState.of_points({k: getattr(self, k)[s:e].copy() for k in self.PER_POINT}, None)
        sub.ref = self.ref.rows(s, e, copy=True)
        sub.ref.alpha = None  # sent once per round
        sub.offset = s
        return sub

    def keep(self, which: str) -> None:
        """Copy the current parameters and α into the ``which`` ("ref" or "best") state."""
        getattr(self, which).assign(self.now)

    def restore_best(self) -> None:
        """Make the best state the current one."""
        self.now.assign(self.best)

    def commit(self, sub: FitState, s: int, e: int) -> None:
        """Write the points of ``sub`` (from :meth:`points`) back as points s..e."""
        for k in self.PER_POINT:
            getattr(self, k)[s:e] = getattr(sub, k)

    def add(self, ci: int, sub: FitState, s: int, e: int, phi: float, phi_ref: float, num, den) -> None:
        """Take chunk ``ci`` (points s..e), the next in chunk order: its points' new parameters, its Φ,
        and its α statistics (boxes from :func:`._pixels.pixel_sums`) added to the running sums."""
        if ci != int(self.added[0]):
            raise ValueError(f"chunk {ci} added out of order (next: {int(self.added[0])})")
        self.commit(sub, s, e)
        for total, (box, values) in ((self.num, num), (self.den, den)):
            total[box] += values  # outside the box the chunk's sums are 0: the same as adding them
        self.phi[ci], self.phi_ref[ci] = phi, phi_ref
        self.added[0] = ci + 1

    def _saved(self) -> dict:
        """The arrays of a checkpoint by name (:data:`SAVED`, in its order)."""
        arrays = {k: getattr(self.now, k) for k in Params.NAMES}
        arrays.update({k: getattr(self, k) for k in self.RUNNING})
        for which in ("ref", "best"):
            arrays.update({f"{which}_{k}": getattr(getattr(self, which), k) for k in Params.NAMES})
        arrays["best"] = self.best_score
        return arrays

    def save(self, path: Path, request: str) -> None:
        """Write the state and the request it belongs to (an ``.npz`` file, atomically)."""
        with atomic_path(path) as tmp:
            with open(tmp, "wb") as f:
                np.savez(f, request=np.array(request), **self._saved())

    def load(self, path: Path, request: str) -> bool:
        """Take the state from a checkpoint of the same request and shapes; False (and unchanged) if not."""
        try:
            with np.load(path) as z:
                if str(z["request"]) != request:
                    return False
                loaded = {k: z[k] for k in self.SAVED}
        except Exception:  # noqa: BLE001 — an unreadable checkpoint is simply not used
            return False
        mine = self._saved()
        if any(loaded[k].shape != mine[k].shape for k in self.SAVED if k != "history"):
            return False
        self.now = Params(*(loaded[k] for k in Params.NAMES))
        for k in self.RUNNING:
            setattr(self, k, loaded[k])
        for which in ("ref", "best"):
            setattr(self, which, Params(*(loaded[f"{which}_{k}"] for k in Params.NAMES)))
        self.best_score = loaded["best"]
        return True
