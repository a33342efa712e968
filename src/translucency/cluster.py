"""Where work runs: threads in this process, or a Dask cluster (the one home of that choice).

One option names it, the same string on the command line (``--scheduler``) and in the Python API
(``scheduler=``):

``"threads"`` (default)
    this process, chunks in threads — what the tool always did;
``"local:N"``
    a :class:`distributed.LocalCluster` of N worker processes (one thread each), started by the call
    and closed when it returns;
``"tcp://HOST:PORT"``
    an existing Dask cluster (``dask scheduler`` + ``dask worker``); the data set's path must be
    visible to the workers under the same name (a shared file system).

The last two need Dask's distributed scheduler, the ``cluster`` extra (``pip install
"translucency[cluster]"``); without it they are refused in one line where the option is read.

Tasks carry paths, index ranges and parameters, never the data: each worker reads and writes its own
chunks of the store.  Results come back to this process, which reduces them in chunk order, so a
result does not depend on where or in which order the tasks ran (docs/scaling.md).  A worker that dies
mid-task is replaced and its task run again (Dask's ``allowed-failures``); tasks are pure functions of
their arguments, so the result does not change.

Examples
--------
>>> parse_scheduler("local:2")
SchedulerSpec(kind='local', workers=2, address=None)
>>> with open_cluster("threads") as cluster:
...     print(cluster)
None
"""

from __future__ import annotations

import logging
import os
import re
from collections.abc import Callable, Iterable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass

import numpy as np

from ._extras import require
from ._validate import TranslucencyError

#: the default: this process, chunks in threads
THREADS = "threads"
#: seconds to wait for a scheduler at a tcp:// address before saying that none answers
CONNECT_TIMEOUT_S = 5.0
#: the most worker processes ``local:N`` starts
MAX_LOCAL_WORKERS = 1024
#: chunks a driver lets run ahead of the oldest unfinished one, per worker (:func:`in_order_window`) ...
IN_FLIGHT_PER_WORKER = 4
#: ... and at least
IN_FLIGHT_MIN = 16
_TCP = re.compile(r"^tcp://(?P<host>[A-Za-z0-9_.\-]+|\[[0-9A-Fa-f:.]+\]):(?P<port>[0-9]{1,5})$")


@dataclass(frozen=True)
class SchedulerSpec:
    """A parsed ``--scheduler`` value: ``kind`` "threads", "local" (``workers`` processes) or "tcp".

    Examples
    --------
    >>> spec = SchedulerSpec("local", workers=4)
    >>> str(spec), parse_scheduler(str(spec)) == spec   # its string is the option that names it
    ('local:4', True)
    """

    kind: str
    workers: int | None = None
    address: str | None = None

    def __str__(self) -> str:
        return {"threads": THREADS, "local": f"local:{self.workers}"}.get(self.kind, self.address or "")


def parse_scheduler(spec) -> SchedulerSpec:
    """Check a scheduler option and say what it names; a bad one is one line naming the option.

    Parameters
    ----------
    spec : str, SchedulerSpec, Cluster or None
        ``"threads"`` (``None`` too), ``"local:N"`` or ``"tcp://HOST:PORT"``; or an open :class:`Cluster`.

    Examples
    --------
    >>> parse_scheduler("tcp://10.0.0.5:8786").address
    'tcp://10.0.0.5:8786'
    >>> parse_scheduler("local:0")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    translucency._validate.TranslucencyError: scheduler: local:N needs 1 to 1024 worker processes, ...
    """
    if spec is None:
        return SchedulerSpec(THREADS)
    if isinstance(spec, SchedulerSpec):
        return spec
    if isinstance(spec, Cluster):  # an open cluster, shared between calls
        return spec.spec
    if not isinstance(spec, str):
        raise TranslucencyError(f"scheduler: expected a string, got {type(spec).__name__}")
    text = spec.strip()
    if text.lower() == THREADS:
        return SchedulerSpec(THREADS)
    if text.lower().startswith("local:"):
        n = text[6:]
        if not n.isdigit() or not 1 <= int(n) <= MAX_LOCAL_WORKERS:
            raise TranslucencyError(
                f"scheduler: local:N needs 1 to {MAX_LOCAL_WORKERS} worker processes, got {spec!r}"
            )
        return _with_dask(SchedulerSpec("local", workers=int(n)))
    match = _TCP.match(text)
    if match:
        if not 1 <= int(match["port"]) <= 65535:
            raise TranslucencyError(f"scheduler: port {match['port']} of {spec!r} is not 1-65535")
        return _with_dask(SchedulerSpec("tcp", address=text))
    raise TranslucencyError(f"scheduler: expected 'threads', 'local:N' or 'tcp://HOST:PORT', got {spec!r}")


def _with_dask(spec: SchedulerSpec) -> SchedulerSpec:
    """``spec``, once Dask's distributed (the cluster extra) is found: a missing extra is one line, before
    any work."""
    require("cluster", what=f"scheduler={str(spec)!r}")
    return spec


class Cluster:
    """An open Dask client (and the LocalCluster it started, if any), with the few calls the tool uses.

    Make one with :func:`open_cluster`; pass it as ``scheduler=`` to several calls to share it.

    Examples
    --------
    >>> spec = parse_scheduler("tcp://10.0.0.5:8786")
    >>> cluster = Cluster(client=None, spec=spec)   # (open_cluster passes a connected Dask client)
    >>> parse_scheduler(cluster) is spec   # a cluster passed as ``scheduler=`` names itself
    True
    """

    def __init__(self, client, spec: SchedulerSpec, local=None):
        self.client, self.spec, self._local = client, spec, local

    def __repr__(self) -> str:
        return f"Cluster({self.spec}, workers={self.n_workers})"

    @property
    def n_workers(self) -> int:
        return len(self.client.scheduler_info(n_workers=-1).get("workers", {}))

    @property
    def address(self) -> str:
        return self.client.scheduler.address

    def keep(self, value):
        """Place ``value`` on the cluster once (a future the tasks take as an argument).

        Kept as the result of a task rather than scattered, so that a worker's death loses nothing:
        the scheduler recomputes it on another worker.
        """
        return self.client.submit(_same, value, pure=False)

    def run(
        self,
        fn: Callable,
        tasks: Sequence[tuple],
        *,
        shared: tuple = (),
        name: str | None = None,
        window: int | None = None,
    ) -> Iterator[tuple[int, object]]:
        """Run ``fn(*shared, *tasks[i])`` for every i on the cluster; yield (i, result) as they finish.

        ``shared``: futures from :meth:`keep` (or small values) every task takes first.  ``window``:
        task i is submitted only once every task before i − ``window`` + 1 has finished, so that a
        caller that reduces the results in index order holds at most ``window`` − 1 of them out of
        order (:func:`in_order_window`); ``None``: all at once.  A task that raises ends the iteration
        with its error (a :class:`TranslucencyError` stays one); a task that killed the workers it ran
        on more than Dask's ``allowed-failures`` times is one line.
        """
        from distributed import as_completed  # loaded by open_cluster already (the cluster extra)
        from distributed.scheduler import KilledWorker

        prefix = name or getattr(fn, "__name__", "task")
        n = len(tasks)
        width = n if window is None else max(1, int(window))
        futures: dict = {}
        finished: set = set()
        low = submitted = 0  # every task before ``low`` has finished; tasks before ``submitted`` are out
        stream = as_completed([], loop=self.client.loop)

        def submit() -> None:
            nonlocal submitted
            while submitted < n and submitted < low + width:
                i = submitted
                fut = self.client.submit(fn, *shared, *tasks[i], key=f"{prefix}-{i}-{_token()}", pure=False)
                futures[fut] = i
                stream.add(fut)
                submitted += 1

        submit()
        try:
            for fut in stream:
                i = futures.pop(fut)
                try:
                    result = fut.result()
                except TranslucencyError:
                    raise
                except KilledWorker as exc:
                    raise TranslucencyError(
                        f"scheduler {self.spec}: task {i} of {prefix} killed its workers repeatedly ({exc})"
                    ) from None
                fut.release()
                finished.add(i)
                while low in finished:
                    finished.discard(low)
                    low += 1
                submit()  # before handing the result over: the cluster works while the caller does
                yield i, result
        finally:
            if futures:  # an error or an abandoned iteration: cancel what waits, let what runs end
                self._stop(list(futures))

    def _stop(self, futures: list) -> None:
        """Cancel the tasks not yet on a worker and wait for those that are: a task that writes to the
        store ends before the caller (holding the output's lock) returns."""
        try:
            states = self.client.run_on_scheduler(_task_states, keys=[f.key for f in futures])
        except Exception:  # noqa: BLE001 — the scheduler is gone: nothing runs any more
            return
        running = [f for f in futures if states.get(f.key) == "processing"]
        self.client.cancel([f for f in futures if states.get(f.key) != "processing"])
        for fut in running:
            try:
                fut.result()
            except Exception:  # noqa: BLE001 — a task that fails now fails in a run already abandoned
                pass

    def close(self) -> None:
        self.client.close()
        if self._local is not None:
            self._local.close()


def _task_states(keys, dask_scheduler=None) -> dict:
    """On the scheduler: the state of each task ("processing": sent to a worker)."""
    tasks = dask_scheduler.tasks
    return {k: tasks[k].state for k in keys if k in tasks}


def _same(value):
    """The value itself (a task whose result :meth:`Cluster.keep` places on a worker)."""
    return value


def _token() -> str:
    import uuid  # only for task names

    return uuid.uuid4().hex[:12]


_TRIM = "MALLOC_TRIM_THRESHOLD_"


@contextmanager
def _without_env(name: str):
    """``name`` absent from this process's environment for the block, restored after (Dask's nanny
    copies its pre-spawn variables into the parent's environment, where later workers inherit them;
    glibc read this process's own setting at start, so removing it here changes nothing here)."""
    old = os.environ.pop(name, None)
    try:
        yield
    finally:
        if old is not None:
            os.environ[name] = old


def worker_environ() -> dict:
    """The environment Dask's nanny gives a new worker process, less ``MALLOC_TRIM_THRESHOLD_``.

    Dask sets it (to 64 KiB) so that workers hand freed memory back to the system at once.  Setting it
    also switches off glibc's adaptive mmap threshold, so every large NumPy temporary is mapped afresh
    and its pages faulted in again: the fit ran 1.85× slower in a worker than in this process (6.5 s
    against 3.5 s for the same chunks; 6.7 s in this process with the variable set).  Without it the
    worker's peak memory is what the chunk needs (measured in ``benchmarks/scale_out.py``).  Workers
    of a ``tcp://`` cluster are started by their owner: start them without it (docs/scaling.md).

    Examples
    --------
    >>> "MALLOC_TRIM_THRESHOLD_" in worker_environ()
    False
    """
    import dask  # loaded with the cluster extra (open_cluster asks for it first)

    env = dict(dask.config.get("distributed.nanny.pre-spawn-environ", default={}) or {})
    env.pop(_TRIM, None)
    return env


@contextmanager
def open_cluster(
    scheduler=None,
    *,
    memory_limit: str | float | None = "auto",
    connect_timeout: float | None = None,
) -> Iterator[Cluster | None]:
    """Start or connect to what ``scheduler`` names for the duration of a ``with`` block.

    Yields ``None`` for ``"threads"`` (the caller's own thread pool), or a :class:`Cluster`.  A
    ``local:N`` cluster is started here and closed on leaving; a ``tcp://`` client is closed, the
    cluster left running; a :class:`Cluster` passed in is used as it is and left open.

    Parameters
    ----------
    scheduler : str, SchedulerSpec, Cluster or None
        See :func:`parse_scheduler`.
    memory_limit : str or float, optional
        Memory limit of each local worker (Dask's: ``"auto"`` shares the machine's memory, bytes,
        or "2GiB"); the worker spills, pauses, and is restarted beyond it.
    connect_timeout : float, optional
        Seconds to wait for a ``tcp://`` scheduler (default :data:`CONNECT_TIMEOUT_S`).

    Examples
    --------
    >>> with open_cluster("threads") as cluster:   # this process's threads: no cluster
    ...     print(cluster)
    None
    >>> shared = Cluster(None, parse_scheduler("local:2"))   # an open cluster is used as it is
    >>> with open_cluster(shared) as cluster:
    ...     print(cluster is shared)
    True
    """
    timeout = CONNECT_TIMEOUT_S if connect_timeout is None else float(connect_timeout)
    if isinstance(scheduler, Cluster):
        yield scheduler
        return
    spec = parse_scheduler(scheduler)
    if spec.kind == THREADS:
        yield None
        return
    distributed = require("cluster", what=f"scheduler={str(spec)!r}")  # threads need no Dask
    import dask  # installed with distributed (the cluster extra, found above)

    if spec.kind == "local":
        with dask.config.set({"distributed.nanny.pre-spawn-environ": worker_environ()}), _without_env(_TRIM):
            local = distributed.LocalCluster(
                n_workers=spec.workers,
                threads_per_worker=1,
                processes=True,
                memory_limit=memory_limit,
                dashboard_address=None,
                silence_logs=logging.ERROR,
            )
        client = distributed.Client(local, set_as_default=False)
        cluster = Cluster(client, spec, local)
    else:
        try:
            client = distributed.Client(spec.address, timeout=timeout, set_as_default=False)
        except (OSError, TimeoutError) as exc:
            reason = str(exc).splitlines()[0][:120] if str(exc) else type(exc).__name__
            raise TranslucencyError(
                f"scheduler {spec.address}: no Dask scheduler answers within {timeout:g} s ({reason})"
            ) from None
        cluster = Cluster(client, spec)
    try:
        yield cluster
    finally:
        cluster.close()


def ordered_sum(parts: Iterable[tuple[int, np.ndarray]], n: int) -> np.ndarray:
    """Σ of ``n`` partial arrays given as (index, array) in any order, summed in index order.

    Floating-point addition is not associative: adding the parts as they arrive would make the
    result depend on which worker finished first.  Held until all are in, they are added 0, 1, 2, …

    Examples
    --------
    >>> ordered_sum([(1, np.array([1e16])), (0, np.array([1.0])), (2, np.array([-1e16]))], 3)
    array([0.])
    """
    held = dict(parts)
    if sorted(held) != list(range(n)):
        raise ValueError(f"ordered_sum: expected parts 0..{n - 1}, got {sorted(held)}")
    total = np.array(held[0], dtype=np.float64, copy=True)
    for i in range(1, n):
        total += held[i]
    return total


def in_order_window(workers: int) -> int:
    """How far ahead of the oldest unfinished chunk a driver lets its chunks run: wide enough to keep
    ``workers`` busy past a slow chunk, narrow enough that the results it must hold until the chunks
    before them are in (to reduce them in order) stay a few per worker.

    Examples
    --------
    >>> in_order_window(1), in_order_window(8)   # at least 16, else 4 per worker
    (16, 32)
    """
    return max(IN_FLIGHT_MIN, IN_FLIGHT_PER_WORKER * max(1, int(workers)))


def compact(a: np.ndarray) -> tuple[tuple[slice, ...], np.ndarray]:
    """The smallest box of ``a`` holding every non-zero value: (slices, values), for sending back.

    ``expand`` restores ``a`` exactly (outside the box ``a`` is zero), e.g. a chunk's α statistics,
    non-zero only under its windows.

    Examples
    --------
    >>> box = compact(np.array([[0.0, 0.0], [0.0, 2.0]]))
    >>> expand(box, (2, 2)).tolist()
    [[0.0, 0.0], [0.0, 2.0]]
    """
    nz = np.nonzero(a)
    if not len(nz[0]):
        box = tuple(slice(0, 0) for _ in a.shape)
    else:
        box = tuple(slice(int(i.min()), int(i.max()) + 1) for i in nz)
    return box, np.ascontiguousarray(a[box])


def expand(packed: tuple[tuple[slice, ...], np.ndarray], shape, dtype=np.float64) -> np.ndarray:
    """The array that :func:`compact` packed.

    Examples
    --------
    >>> a = np.zeros((4, 5)); a[1:3, 2] = [1.0, 2.0]
    >>> box, values = compact(a)
    >>> values.shape   # only the 2 × 1 box travels
    (2, 1)
    >>> bool((expand((box, values), a.shape) == a).all())
    True
    """

    box, values = packed
    out = np.zeros(shape, dtype=dtype)
    out[box] = values
    return out
