r"""The alternation shared by the planar and the per-vertex mesh fit: its rounds over chunks of points.

A fit has incident points :math:`\vec x_i` and outgoing 'pixels' j (window
pixels of a planar data set, or vertices of a mesh), data
:math:`y_{ij\lambda} \approx R_d(\vec x_i, \vec x_j)` per channel λ and the model

.. math:: R_d(\vec x_i, \vec x_j) = \alpha_j\, P_{i\lambda}(\vec x_j),

with the modulation texture α per pixel and :math:`P_i` the per-point profile
of a family in :data:`~translucency.fit.families.FAMILIES` (:mod:`translucency.fit.planar`
lists them).  A *source* (the windows of a planar data set in :mod:`.planar`, the
vertices of a mesh data set in :mod:`.mesh`) reads the data of points s..e and
says where α lives; the objective and its weights are in :mod:`.chunk`.

**Alternation.**  Each round (1) fits every point's parameters with α fixed,
batched over all points (the family's :meth:`~.families.Family.fit`:
:mod:`translucency.solvers` (VarPro for exponentials, LM for the baselines); radii grouped
exactly as in :mod:`._windows`); (2) for the shared-colour model solves
:math:`s_\lambda` per point in closed form; (3) solves α per pixel in closed form,
:math:`\alpha_j = \sum w^2 P y / \sum w^2 P^2` (pooled over neighbours on
meshes), and normalises mean α = 1 over the observed pixels, the profiles'
amplitudes taking the scale so that αP (and Φ) are unchanged (the dipole has no
free amplitude: its α keeps the scale; :mod:`._alpha`).  Rounds stop when Φ
falls by less than ``tol`` relatively or rises; the state of lowest Φ is
returned (:attr:`FitResult.best_round`).  Cold starts pool fixed blocks of 16
points by absolute index and every sum runs in chunk order, so the result does
not depend on the chunking.  The anisotropic model updates its directions by
block coordinate descent (:mod:`.families.aniso`), regularised by
:mod:`._regularise`.

Work runs in chunks of incident points read from the store, so a data set
larger than memory can be fitted.  α's statistics are one running sum per
statistic, added in chunk order (a chunk that finishes early waits until the
chunks before it are in), so they take one sample grid whatever the number of
chunks.  With a checkpoint the state (:mod:`.state`) is saved as chunks are
added and at the end of every round; an interrupted fit resumes from it bit for bit.
"""

from __future__ import annotations

import os
import threading
import time
from concurrent.futures import FIRST_COMPLETED, ThreadPoolExecutor, wait
from dataclasses import replace
from pathlib import Path

import numpy as np

from ..cluster import in_order_window, open_cluster
from ._alpha import update_alpha
from ._block import fit_chunk as _fit_chunk  # looked up here at each call (a test slows chunks down)
from .context import FitContext
from .options import FitResult
from .state import CHECKPOINT_SHARE, FitState


def alternate(
    ctx: FitContext,
    options: dict,
    request: str,
    *,
    max_rounds: int,
    tol: float,
    chunk_points: int,
    workers: int | None,
    checkpoint,
    progress,
    t0: float,
    scheduler=None,
) -> FitResult:
    """The rounds of the alternation over all chunks of points (shared by planar and mesh fits).

    Round 1 weights by ring means of the data; its result becomes the reference
    state whose model weights every later round (module docstring).  Each
    round's state is scored by Φ under those common weights; the rounds stop
    when Φ falls by less than ``tol`` relatively (or rises), and the best state
    is returned.  ``request`` identifies the fit in a checkpoint; ``t0`` is the
    start time (:func:`time.perf_counter`) for :attr:`FitResult.seconds`.  ``scheduler``: where
    the chunks run (:mod:`translucency.cluster`); the result is the same bit for bit.
    """
    with open_cluster(scheduler) as cluster:
        return _alternate(
            ctx, options, request, max_rounds, tol, chunk_points, workers, checkpoint, progress, t0, cluster
        )


def _alternate(
    ctx, options, request, max_rounds, tol, chunk_points, workers, checkpoint, progress, t0, cluster
):
    """:func:`alternate` with its cluster open (``None``: threads)."""
    P = len(ctx.x_i)
    chunks = [(s, min(s + chunk_points, P)) for s in range(0, P, chunk_points)]
    state = FitState(P, ctx.C, ctx.m, ctx.n, ctx.source.alpha_shape, len(chunks))
    ckpt = Path(checkpoint) if checkpoint else None
    if ckpt is not None and ckpt.exists() and state.load(ckpt, request) and progress:
        progress(0, 0, f"resuming from {ckpt.name}: round {int(state.round[0]) + 1}")
    total = max_rounds * len(chunks)
    lock = threading.Lock()
    workers = max(1, min(int(workers or os.cpu_count() or 1), len(chunks)))
    # the context goes to the cluster once (its source holds paths, not data)
    ctx_task = cluster.keep((os.urandom(8).hex(), ctx)) if cluster is not None else None
    while state.round[0] < max_rounds:
        rnd = int(state.round[0])
        if rnd == 1 and state.added[0] == 0:  # round 1's result weights every later round
            state.keep("ref")
        todo = list(range(int(state.added[0]), len(chunks)))  # the chunks before are added
        # chunks in parallel threads (NumPy releases the GIL) or tasks on a cluster; each works on a
        # private copy of its points and hands back its α statistics, so results do not depend on timing
        if cluster is None:
            results = _thread_chunks(ctx, state, chunks, todo, workers)
        else:
            results = _cluster_chunks(cluster, ctx_task, state, chunks, todo)
        _add_in_order(state, results, chunks, lock, ckpt, request, progress, rnd, total)
        if state.held or state.added[0] != len(chunks):  # pragma: no cover - a runner lost a chunk
            raise RuntimeError(
                f"fit: chunks {sorted(state.held)} finished but {int(state.added[0])} is missing"
            )
        _close_round(ctx, state, rnd, max_rounds, tol)
        if ckpt is not None:
            state.save(ckpt, request)
    if progress:
        progress(total, total, "done")
    state.restore_best()
    fitted = _build_model(ctx, state)
    if ckpt is not None and ckpt.exists():
        ckpt.unlink()
    return FitResult(
        fitted,
        state.flagged.copy(),
        [float(v) for v in state.history],
        time.perf_counter() - t0,
        options,
        best_round=int(state.best_score[1]) + 1,
    )


def _add_in_order(state, results, chunks, lock, ckpt, request, progress, rnd: int, total: int) -> None:
    """Add a round's chunk results to ``state`` in chunk order, checkpointing and telling progress."""
    next_save = 0.0  # perf_counter time of the next checkpoint (the round's first addition: at once)
    for ci, result in results:
        # in chunk order (float sums are not associative): a chunk that finished early is held
        # until every chunk before it is in, then added and dropped
        state.held[ci] = result
        first = int(state.added[0])
        with lock:
            while int(state.added[0]) in state.held:
                nxt = int(state.added[0])
                state.add(nxt, *_with_range(state.held.pop(nxt), chunks[nxt]))
            if ckpt is not None and state.added[0] > first and time.perf_counter() >= next_save:
                t_save = time.perf_counter()
                state.save(ckpt, request)
                now = time.perf_counter()
                next_save = now + (now - t_save) * (1 - CHECKPOINT_SHARE) / CHECKPOINT_SHARE
        if progress:
            for done in range(first + 1, int(state.added[0]) + 1):
                progress(rnd * len(chunks) + done, total, f"round {rnd + 1}")


def _close_round(ctx, state, rnd: int, max_rounds: int, tol: float) -> None:
    """End round ``rnd``: α's update, Φ's history, the best state kept, the sums reset, convergence."""
    # α in closed form (the scale fixed by mean α = 1), and Φ of the new state (parameters and α):
    # Φ with the round's α, plus what the α step changed (exact: Φ is quadratic in each α_j)
    change = update_alpha(state, ctx.family, getattr(ctx.source, "smooth_alpha", None))
    phi = float(state.phi.sum()) + change  # summed in chunk order: deterministic
    if rnd == 1:  # round 1's own state, scored under the common weights it defines
        state.history = np.array([float(state.phi_ref.sum())])
        state.best_score[:] = (state.history[0], 0)  # the best arrays hold round 1's state already
    state.history = np.append(state.history, phi)
    if phi < state.best_score[0] or rnd == 0:
        state.best_score[:] = (phi, rnd)
        state.keep("best")
    state.phi[:] = 0.0
    state.phi_ref[:] = 0.0
    state.added[0] = 0
    state.round[0] = rnd + 1
    h = state.history
    if rnd >= 1 and h[-2] - h[-1] <= tol * h[-2]:  # converged, or Φ rose: the best state is kept
        state.round[0] = max_rounds


def _with_range(result, chunk):
    """A chunk's result (sub, Φ, Φ_ref, num, den) as the arguments of :meth:`FitState.add`."""
    sub, phi, phi_ref, num, den = result
    return sub, *chunk, phi, phi_ref, num, den


def _thread_chunks(ctx, state, chunks, todo, workers):
    """(chunk index, :func:`_fit_chunk`'s result) of the chunks ``todo``, run in threads, as they finish.

    Chunk i starts only once every chunk before i − window + 1 has finished (:func:`in_order_window`),
    so that the results held until the chunks before them are in stay a few per thread; a finished
    future is dropped at once (its result is the caller's).
    """
    window = in_order_window(workers)
    with ThreadPoolExecutor(workers) as pool:
        running: dict = {}
        finished: set = set()
        low = nxt = 0  # todo[:low] finished; todo[:nxt] submitted
        while True:
            while nxt < len(todo) and nxt < low + window:
                running[pool.submit(_fit_chunk, ctx, state, *chunks[todo[nxt]])] = nxt
                nxt += 1
            if not running:
                return
            done, _ = wait(running, return_when=FIRST_COMPLETED)
            for fut in sorted(done, key=running.get):
                i = running.pop(fut)
                finished.add(i)
                while low in finished:
                    finished.discard(low)
                    low += 1
                yield todo[i], fut.result()


def _cluster_chunks(cluster, ctx_task, state, chunks, todo):
    """The same as :func:`_thread_chunks`, the chunks run as tasks on a Dask cluster: each task takes its
    points' parameters and reads its data from the store; α goes out once per round, and a chunk's α
    statistics come back as the box under its windows."""
    shared = cluster.keep((state.alpha.copy(), state.ref.alpha.copy(), state.round.copy()))
    tasks = _Parts(state, [chunks[ci] for ci in todo])
    window = in_order_window(cluster.n_workers)
    for i, result in cluster.run(_fit_task, tasks, shared=(ctx_task, shared), window=window):
        yield todo[i], result


class _Parts:
    """The tasks of :func:`_cluster_chunks`, made as they are submitted: (points' state, s, e)."""

    def __init__(self, state: FitState, ranges: list):
        self.state, self.ranges = state, ranges

    def __len__(self) -> int:
        return len(self.ranges)

    def __getitem__(self, i: int):
        s, e = self.ranges[i]
        return self.state.part(s, e), s, e


#: per worker process: the context of the fit running there, with its own cache of decoded chunks
_LIVE: dict = {}
_LIVE_LOCK = threading.Lock()


def _fit_task(kept, shared, part: FitState, s: int, e: int):
    """:func:`_fit_chunk` on a worker: ``part`` (:meth:`FitState.part`) with the round's α from ``shared``.

    ``kept`` = (token, context): the context as sent stays as it is (a worker that fetches it from
    another gets no cache with it); the worker's working copy caches its chunks between rounds.
    """
    token, ctx = kept
    with _LIVE_LOCK:
        if token not in _LIVE:
            _LIVE.clear()  # one fit's cache per process
            _LIVE[token] = replace(ctx, cache={})
        live = _LIVE[token]
    part.alpha, part.ref.alpha, part.round = shared
    sub, phi, phi_ref, num, den = _fit_chunk(live, part, s, e)
    sub.alpha = None  # the caller has it
    return sub, phi, phi_ref, num, den


def _build_model(ctx: FitContext, state: FitState):
    """The fitted reflectance model of the family, with the source's α and frames."""
    alpha = ctx.source.make_alpha(state.alpha)
    frame = getattr(ctx.source, "frame", None)
    return ctx.family.build(ctx, state, alpha, frame)
