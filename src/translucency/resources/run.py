"""The sequence every working function of the library runs (acquire, import, fit, evaluate, render, …):
what a run needs (memory, disk, time) checked before the work, and how it goes told to a reporter.

check what needs no work (arguments, inputs) → estimate its memory and disk (refused in one line beyond
``max_memory`` or the free disk) → claim its output (a folder through :meth:`Run.claim_folder`, left as it
was if the work fails or is interrupted) → estimate its time (of the work left: the seconds already spent
starting up and preparing are stated with it) → work, its progress told to a :class:`Reporter` → teach
this machine's calibration how long the work took → its summary (:meth:`Run.summary`: the caller's record
with the estimates and the seconds).

The library runs every stage; the command line only chooses a :class:`Reporter` that draws progress bars
(``translucency.cli``) and prints the summary.  A Python caller gets the same checks, estimates and
summary, silently by default.

Examples
--------
>>> import tempfile
>>> from pathlib import Path
>>> from translucency.resources import Need
>>> out = Path(tempfile.mkdtemp()) / "render"
>>> run = Run("render", max_memory="4G")
>>> run.check(Need(memory=2**20, disk=0, what="a picture"), out).memory
1048576
>>> _ = run.claim_folder(out, overwrite=False)
>>> units = {"vertices": 10, "pairs": 100, "samples": 1600, "reference_samples": 0}
>>> timing = run.time(units)  # this machine's estimate of that work
>>> with run.work("render", total=1, fresh=False) as work:  # fresh=False: kept out of the calibration
...     work.update(completed=1)
>>> summary = run.summary({"command": "render"})
>>> sorted(summary)
['command', 'estimate', 'seconds', 'time_estimate']
"""

from __future__ import annotations

import contextlib
import dataclasses
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Protocol

import numpy as np

from ..io.outputs import claim_folder, release_output
from ..io.records import jsonable
from .machine import Need, memory_limit
from .memory import check_resources
from .timing import TimeEstimate, estimate_time, kernel_caches_cold, process_seconds, record_time

__all__ = [
    "Reporter",
    "Run",
    "Silent",
    "Work",
    "bytes_at",
    "failed",
    "interrupted",
    "jsonable",
    "kept_chunks",
    "kept_note",
]

#: the runs under way in this process (the innermost last): :func:`failed` and :func:`interrupted` ask them
_ACTIVE: list[Run] = []


class Reporter(Protocol):
    """Where a run tells what it does: information lines and progress.

    ``info(text)`` is one line of information; ``progress(description, total)`` is a context manager that
    yields ``update(**fields)`` (``completed=``, ``total=``, ``item=``: Rich's ``Progress.update`` of a task).

    Examples
    --------
    Any object with the two methods is one (no base class):

    >>> class Printer:
    ...     def info(self, text):
    ...         print(text)
    ...     @contextlib.contextmanager
    ...     def progress(self, description, total):
    ...         print(f"{description}: 0/{total}")
    ...         yield lambda **fields: print(f"{description}: {fields['completed']}/{total} {fields['item']}")
    >>> run = Run("fit", reporter=Printer())
    >>> run.info("3 incident points")
    3 incident points
    >>> with run.work("fit", total=3, fresh=False) as work:  # fresh=False: kept out of the calibration
    ...     work.step()(2, 3, "point 2")
    fit: 0/3
    fit: 2/3 point 2
    """

    def info(self, text: str) -> None: ...

    def progress(self, description: str, total: int | None) -> contextlib.AbstractContextManager: ...


class Silent:
    """A :class:`Reporter` that tells nothing (the library's default).

    Examples
    --------
    >>> with Silent().progress("fit", 3) as update:
    ...     update(completed=1)
    >>> Silent().info("nothing is printed")
    """

    def info(self, text: str) -> None:
        """Drop the line."""

    @contextlib.contextmanager
    def progress(self, description: str, total: int | None) -> Iterator[Callable[..., None]]:
        """A progress that goes nowhere."""
        yield lambda **fields: None


def bytes_at(path: Path) -> int:
    """Bytes already at an output path (what a resumed or replaced output frees or keeps).

    Examples
    --------
    >>> import tempfile
    >>> d = Path(tempfile.mkdtemp())
    >>> _ = (d / "a.bin").write_bytes(b"1234")
    >>> bytes_at(d), bytes_at(d / "a.bin"), bytes_at(d / "none")
    (4, 4, 0)
    """
    if path.is_file():
        return path.stat().st_size
    if path.is_dir():
        return sum(f.stat().st_size for f in path.rglob("*") if f.is_file())
    return 0


@dataclass
class Work:
    """The work under way: ``update(**fields)`` moves its progress (``completed``, ``total``, ``item``);
    ``fresh = False`` keeps a run that reused earlier work out of the calibration."""

    update: Callable[..., None]
    fresh: bool = True

    def step(self) -> Callable[[int, int, str], None]:
        """``progress(done, total, item)`` as the stages call it, moving this work's progress."""
        return lambda done, total, item="": self.update(completed=done, total=total or None, item=item)


class Run:
    """One run of a working function: its ``max_memory``, its estimates, its clock, its outputs.

    ``command`` names it in refusals and summaries; ``timer`` (default ``command``) is its entry of
    :data:`translucency.resources.TIME_TERMS` (``fit iso``, ``fit aniso``, ...); ``reporter`` hears its
    information lines and progress (default :class:`Silent`).

    Examples
    --------
    >>> import tempfile
    >>> from translucency.resources import Need
    >>> Run("render", max_memory="lots")  # a bad size: refused before any work
    Traceback (most recent call last):
    ...
    translucency._validate.TranslucencyError: --max-memory: expected a size such as 4G or 512M, got 'lots'
    >>> Run("render", max_memory="1M").check(Need(memory=2**30, disk=0, what="a picture"))
    ... # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    translucency._validate.TranslucencyError: render: needs about 1 GiB of memory (a picture), more than ...

    A run that fails leaves its output folder as it was (here: absent):

    >>> out = Path(tempfile.mkdtemp()) / "render"
    >>> run = Run("render")
    >>> _ = run.claim_folder(out, overwrite=False)
    >>> _ = (out / "picture.png").write_bytes(b"...")  # the work writes, then fails
    >>> failed()  # every run under way removes what it added
    >>> out.exists()
    False
    """

    def __init__(
        self,
        command: str,
        *,
        max_memory: str | int | None = None,
        reporter: Reporter | None = None,
        timer: str | None = None,
    ):
        self.command, self.timer = command, timer or command
        self.reporter = reporter or Silent()
        self.limit = memory_limit(max_memory)  # a bad size: one line, before any work
        self.need: Need | None = None
        self.units: dict | None = None
        self.timing: TimeEstimate | None = None
        self.cold = False
        self.t0 = time.perf_counter()  # the clock, restarted by the estimate: what it estimates is timed
        #: outputs this run created, removed again if it fails: (path, the entries there before or None)
        self.created: list[tuple[Path, set | None]] = []
        #: what an interrupted run keeps and how to resume it (a callable giving one line), if anything
        self.kept: Callable[[], str] | None = None
        _ACTIVE[:] = [r for r in _ACTIVE if r.command != command] + [self]

    def claim_folder(self, path: Path, **kwargs) -> Path:
        """:func:`translucency.io.outputs.claim_folder`, and remember what this run adds there: a run that
        fails or is interrupted removes it again (only what it added, never what was there before)."""
        path = Path(path)
        before = {p.name for p in path.iterdir()} if path.is_dir() else None
        claim_folder(path, **kwargs)
        self.created.append((path, before))
        return path

    def abandon(self) -> None:
        """Remove what this run added to its output folders (a failed or interrupted run leaves nothing)."""
        for path, before in reversed(self.created):
            release_output(path, before)
        self.created.clear()

    def check(self, need: Need, out: Path | None = None, *, resumed: bool = False) -> Need:
        """Refuse ``need`` beyond ``max_memory`` or the free disk where ``out`` goes (``resumed``: the
        bytes already at ``out`` are kept, not written again)."""
        if resumed:
            need.disk -= bytes_at(out)
        self.need = check_resources(self.command, need, self.limit, out)
        return self.need

    def time(self, units: dict, first: tuple[float, str] | None = None) -> TimeEstimate:
        """The time estimate of ``units`` of work (``first``: a factor before this machine's first run)."""
        self.units = units
        self.cold = kernel_caches_cold()  # a first run compiles the kernels later runs load
        estimate = estimate_time(self.timer, units, first, cold=self.cold)
        # the seconds already spent (imports, reading inputs, generating samples) are said with it
        self.timing = dataclasses.replace(estimate, startup=process_seconds())
        self.t0 = time.perf_counter()
        return self.timing

    def info(self, text: str) -> None:
        """An information line for the reporter."""
        self.reporter.info(text)

    @contextlib.contextmanager
    def work(self, description: str | None = None, *, total=None, fresh: bool = True) -> Iterator[Work]:
        """The work's progress, named ``description`` (none if None); on success, record the seconds since
        the estimate in this machine's calibration unless the run reused earlier work (``fresh``)."""
        if description is None:
            work = Work(update=lambda **fields: None, fresh=fresh)
            yield work
        else:
            with self.reporter.progress(description, total) as update:
                work = Work(update=update, fresh=fresh)
                yield work
        if work.fresh:
            record_time(self.timer, self.units, time.perf_counter() - self.t0, cold=self.cold)

    def seconds(self) -> float:
        """Seconds since the estimate (rounded to a millisecond, as the summaries state them)."""
        return round(time.perf_counter() - self.t0, 3)

    def summary(self, record: dict) -> dict:
        """The run is done (its outputs stay): ``record`` with the estimates (those made) and the seconds,
        where it states none of its own."""
        self.created.clear()
        if self in _ACTIVE:
            _ACTIVE.remove(self)
        estimates = {"estimate": self.need, "time_estimate": self.timing}  # None: a run that estimates none
        extra = {k: v.as_dict() for k, v in estimates.items() if v is not None}
        record = {**record, **{k: v for k, v in extra.items() if k not in record}}
        record.setdefault("seconds", self.seconds())
        return record


def failed() -> None:
    """The work failed (a one-line error or a crash): the runs under way remove what they added.

    Examples
    --------
    >>> failed()  # no run under way: nothing to remove
    """
    while _ACTIVE:
        _ACTIVE.pop().abandon()


def interrupted() -> list[str]:
    """Ctrl-C: every run under way removes what it added; the lines saying what is kept and how to resume.

    Examples
    --------
    >>> interrupted()
    []
    """
    notes = []
    while _ACTIVE:
        run = _ACTIVE.pop()
        run.abandon()
        if run.kept is not None:
            notes.append(kept_note(run.kept))
    return notes


def kept_chunks(out: Path, opener) -> str:
    """What an interrupted chunked write keeps at ``out`` (a data set ``opener`` reads) and how to go on."""
    try:
        done = np.asarray(opener(out).group["chunk_done"][...], dtype=bool)
    except Exception:  # noqa: BLE001 — nothing readable written yet
        return "nothing kept; re-run the same command to start again"
    return f"{int(done.sum())}/{len(done)} chunks kept in {out}; re-run the same command to resume"


def kept_note(kept: Callable[[], str]) -> str:
    """``kept()``, or a line saying that what was written could not be read back."""
    try:
        return kept()
    except Exception:  # noqa: BLE001 — the note reads the output; an unreadable one is said as such
        return "what was written could not be read back"
