"""How a command shows a library run: Rich progress bars and information lines on stderr, then the summary.

The library runs every stage (:class:`translucency.resources.run.Run`: checks, estimates, claims, clock);
a command hands it a :class:`RichReporter` and prints what it returns (:func:`._common.finish`).  A failure
and Ctrl-C (one line saying what is kept and how to resume, exit status 130): :func:`._common.user_errors`.
"""

from __future__ import annotations

import contextlib
import functools
from collections.abc import Callable, Iterator

from rich.markup import escape

from ._common import info, progress

__all__ = ["RichReporter"]


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
