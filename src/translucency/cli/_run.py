"""How a command shows a library run: Rich progress bars and information lines on stderr, then the summary.

The library runs every stage (:class:`translucency.resources.run.Run`: checks, estimates, claims, clock);
a command hands it a :class:`RichReporter` and prints what it returns (:func:`._common.finish`).  Ctrl-C
ends a command with one line saying what is kept and how to resume, exit status 130.
"""

from __future__ import annotations

import contextlib
import functools
from collections.abc import Callable, Iterator

from rich.markup import escape

from ..workflow import run as library
from ._common import err_console, info, progress

__all__ = ["RichReporter", "failed", "interrupted"]


class RichReporter:
    """A :class:`translucency.resources.run.Reporter` on stderr: information lines and Rich progress bars
    (none of either with ``quiet``)."""

    def __init__(self, quiet: bool):
        self.quiet = quiet

    def info(self, text: str) -> None:
        info(self.quiet, escape(text))  # the library's lines are text: "[flip]" is not markup

    @contextlib.contextmanager
    def progress(self, description: str, total: int | None) -> Iterator[Callable[..., None]]:
        with progress(self.quiet) as bar:
            task = bar.add_task(description, total=total, item="")
            yield functools.partial(bar.update, task)


def failed() -> None:
    """A command failed: the runs under way remove what they added."""
    library.failed()


def interrupted() -> None:
    """Ctrl-C: one line saying what is kept and how to resume (or that nothing is kept)."""
    _say_interrupted(library.interrupted())


def _say_interrupted(notes: list[str]) -> None:
    err_console.print(
        f"[bold red]interrupted:[/] {'; '.join(notes) or 'nothing written'}", highlight=False, soft_wrap=True
    )
