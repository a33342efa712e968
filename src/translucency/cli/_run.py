"""How a command shows a library run: Rich progress bars and information lines on stderr, then the summary.

The library runs every stage (:class:`translucency.workflow.run.Run`: checks, estimates, claims, clock);
a command hands it a :class:`RichReporter` and prints what it returns (:func:`._common.finish`).  Ctrl-C
ends a command with one line saying what is kept and how to resume, exit status 130.
"""

from __future__ import annotations

import contextlib
import functools
from collections.abc import Callable, Iterator

import typer

from ..workflow import run as library
from ..workflow.run import bytes_at, kept_chunks
from ._common import err_console, finish, info, progress

__all__ = ["Run", "RichReporter", "bytes_at", "failed", "interrupted", "keeping", "kept_chunks"]


class RichReporter:
    """A :class:`translucency.workflow.run.Reporter` on stderr: information lines and Rich progress bars
    (none of either with ``quiet``)."""

    def __init__(self, quiet: bool):
        self.quiet = quiet

    def info(self, text: str) -> None:
        info(self.quiet, text)

    @contextlib.contextmanager
    def progress(self, description: str, total: int | None) -> Iterator[Callable[..., None]]:
        with progress(self.quiet) as bar:
            task = bar.add_task(description, total=total, item="")
            yield functools.partial(bar.update, task)


class Run(library.Run):
    """A library run shown on the terminal, ended by :meth:`finish` (its summary printed or as JSON)."""

    def __init__(self, command: str, *, max_memory: str | None, quiet: bool, timer: str | None = None):
        super().__init__(command, max_memory=max_memory, reporter=RichReporter(quiet), timer=timer)
        self.quiet = quiet

    def finish(self, as_json: bool, summary: dict, lines=()) -> None:
        """The summary with the estimates and the seconds, as one JSON object (``--json``) or ``lines``."""
        finish(as_json, self.quiet, self.summary(summary), lines)


def failed() -> None:
    """A command failed: the runs under way remove what they added."""
    library.failed()


def interrupted() -> None:
    """Ctrl-C: one line saying what is kept and how to resume (or that nothing is kept)."""
    _say_interrupted(library.interrupted())


@contextlib.contextmanager
def keeping(kept: Callable[[], str]):
    """A block of work outside a run whose Ctrl-C says ``kept()`` (one line, exit status 130)."""
    try:
        yield
    except KeyboardInterrupt:
        _say_interrupted([library.kept_note(kept)])
        raise typer.Exit(130) from None


def _say_interrupted(notes: list[str]) -> None:
    err_console.print(
        f"[bold red]interrupted:[/] {'; '.join(notes) or 'nothing written'}", highlight=False, soft_wrap=True
    )
