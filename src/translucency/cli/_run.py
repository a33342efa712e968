"""The sequence every working command runs (``acquire planar|mesh``, ``fit``, ``evaluate``, ``render``).

check what needs no work (options, inputs) → estimate its memory and disk (refused in one line beyond
``--max-memory`` or the free disk) → claim its output (a folder through :meth:`Run.claim_folder`, left as
it was if the command fails or is interrupted) → estimate its time (of the work left: the seconds already
spent starting up and preparing are stated with it) → work
under a progress bar → teach this machine's calibration how long the work took → its summary (result
lines, or one JSON object with the estimates and the seconds).  Ctrl-C ends it with one line saying what
is kept and how to resume (``Run.kept``), exit status 130.

Examples
--------
A new working command::

    run = Run("render", max_memory=max_memory, quiet=quiet)
    check_everything_that_needs_no_work(...)                  # options, inputs: one line, before all else
    run.check(resources.memory.rendering(...), out)
    run.claim_folder(out, overwrite=overwrite)  # removed again if the command fails or is interrupted
    timing = run.time(resources.timing.rendering_units(...))  # the clock starts
    run.info(f"render ...; time {timing.text()}")
    with run.work("render", total=3) as work:
        do_it(progress=lambda done, total, name: work.update(completed=done, item=name))
    run.finish(as_json, {"command": "render", ...}, ["images: ..."])
"""

from __future__ import annotations

import contextlib
import dataclasses
import functools
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import typer

from ..io.atomic import write_json
from ..io.outputs import claim_folder, release_output
from ..resources import Need, TimeEstimate, check_resources, estimate_time, memory_limit, record_time
from ..resources.timing import kernel_caches_cold, process_seconds
from ._common import err_console, finish, info, jsonable, progress

#: the runs under way in this process (the innermost last): :func:`interrupted` and :func:`failed` ask them
_ACTIVE: list[Run] = []


def bytes_at(path: Path) -> int:
    """Bytes already at an output path (what a resumed or replaced output frees or keeps)."""
    if path.is_file():
        return path.stat().st_size
    if path.is_dir():
        return sum(f.stat().st_size for f in path.rglob("*") if f.is_file())
    return 0


@dataclass
class Work:
    """The work under way: ``update(**fields)`` moves its progress bar (Rich's ``Progress.update`` of its
    task); ``fresh = False`` keeps a run that reused earlier work out of the calibration."""

    update: Callable[..., None]
    fresh: bool = True


class Run:
    """One run of a working command: its ``--max-memory``, its estimates, its clock.

    ``command`` names it in refusals and summaries; ``timer`` (default ``command``) is its entry of
    :data:`translucency.resources.TIME_TERMS` (``fit iso``, ``fit aniso``, ...).
    """

    def __init__(self, command: str, *, max_memory: str | None, quiet: bool, timer: str | None = None):
        self.command, self.timer, self.quiet = command, timer or command, quiet
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
        """Refuse ``need`` beyond ``--max-memory`` or the free disk where ``out`` goes (``resumed``: the
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
        """An information line on stderr, unless ``--quiet``."""
        info(self.quiet, text)

    @contextlib.contextmanager
    def work(self, description: str | None = None, *, total=None, fresh: bool = True):
        """A progress bar named ``description`` (none if None); on success, record the seconds since the
        estimate in this machine's calibration unless the run reused earlier work (``fresh``)."""
        if description is None:
            work = Work(update=lambda **fields: None, fresh=fresh)
            yield work
        else:
            with progress(self.quiet) as bar:
                task = bar.add_task(description, total=total, item="")
                work = Work(update=functools.partial(bar.update, task), fresh=fresh)
                yield work
        if work.fresh:
            record_time(self.timer, self.units, time.perf_counter() - self.t0, cold=self.cold)

    def seconds(self) -> float:
        """Seconds since the estimate (rounded to a millisecond, as the summaries state them)."""
        return round(time.perf_counter() - self.t0, 3)

    def finish_report(self, as_json: bool, summary: dict, report: Path, table, json_out=None) -> None:
        """An evaluation's summary: the report's page first, written to ``json_out`` too when asked
        (``--json-out``), then :meth:`finish` with the table and where the report is."""
        summary = {"command": summary.get("command", "evaluate"), "report": report / "index.html", **summary}
        summary = {**summary, "estimate": self.need.as_dict(), "time_estimate": self.timing.as_dict()}
        summary["seconds"] = self.seconds()
        if json_out is not None:  # --json-out: the object --json prints
            write_json(json_out, jsonable(summary))
        self.finish(as_json, summary, [table, f"report: {report / 'index.html'}"])

    def finish(self, as_json: bool, summary: dict, lines=()) -> None:
        """The summary: ``summary`` with the estimates and the seconds (where it states none of its own)
        as one JSON object (``--json``), or the result ``lines``."""
        self.created.clear()  # done: the outputs stay
        if self in _ACTIVE:
            _ACTIVE.remove(self)
        extra = {"estimate": self.need.as_dict(), "time_estimate": self.timing.as_dict()}
        summary = {**summary, **{k: v for k, v in extra.items() if k not in summary}}
        summary.setdefault("seconds", self.seconds())
        finish(as_json, self.quiet, summary, lines)


def failed() -> None:
    """A command failed (a one-line error or a crash): the runs under way remove what they added."""
    while _ACTIVE:
        _ACTIVE.pop().abandon()


def interrupted() -> None:
    """Ctrl-C: one line saying what is kept and how to resume (or that nothing is kept)."""
    notes = []
    while _ACTIVE:
        run = _ACTIVE.pop()
        run.abandon()
        if run.kept is not None:
            notes.append(_note(run.kept))
    _say_interrupted(notes)


@contextlib.contextmanager
def keeping(kept: Callable[[], str]):
    """A block of work outside a :class:`Run` whose Ctrl-C says ``kept()`` (one line, exit status 130)."""
    try:
        yield
    except KeyboardInterrupt:
        _say_interrupted([_note(kept)])
        raise typer.Exit(130) from None


def kept_chunks(out: Path, opener) -> str:
    """What an interrupted chunked write keeps at ``out`` (a data set ``opener`` reads) and how to go on."""
    try:
        done = np.asarray(opener(out).group["chunk_done"][...], dtype=bool)
    except Exception:  # noqa: BLE001 — nothing readable written yet
        return "nothing kept; re-run the same command to start again"
    return f"{int(done.sum())}/{len(done)} chunks kept in {out}; re-run the same command to resume"


def _note(kept: Callable[[], str]) -> str:
    try:
        return kept()
    except Exception:  # noqa: BLE001 — the note reads the output; an unreadable one is said as such
        return "what was written could not be read back"


def _say_interrupted(notes: list[str]) -> None:
    err_console.print(
        f"[bold red]interrupted:[/] {'; '.join(notes) or 'nothing written'}", highlight=False, soft_wrap=True
    )
