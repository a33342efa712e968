"""What every command shares: the consoles, one-line errors, the progress bar, the common options and the
end of a working command (its result lines, or one JSON object with ``--json``)."""

from __future__ import annotations

import functools
import json
import warnings

import typer
from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

from .._validate import TranslucencyError
from ..workflow.run import jsonable
from ._flags import cli_words

console = Console()
err_console = Console(stderr=True)


def user_errors(func):
    """Turn a :class:`TranslucencyError` into one ``error:`` line and exit status 2; a warning is one
    ``warning:`` line on stderr."""

    def one_line(message, category, *args, **kwargs):
        warn(cli_words(" ".join(str(message).split())))

    from . import _run  # _run imports this module: the runs under way are asked at call time

    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        try:
            with warnings.catch_warnings():
                warnings.showwarning = one_line
                return func(*args, **kwargs)
        except TranslucencyError as exc:
            _run.failed()  # a failed run leaves nothing behind
            err_console.print(f"[bold red]error:[/] {cli_words(str(exc))}", highlight=False, soft_wrap=True)
            raise typer.Exit(2) from None
        except KeyboardInterrupt:
            _run.interrupted()  # what is kept and how to resume, in one line
            raise typer.Exit(130) from None
        except (typer.Exit, typer.Abort):
            raise
        except Exception:
            _run.failed()
            raise

    return wrapper


def warn(text: str) -> None:
    """One ``warning:`` line on stderr (``text`` may carry Rich markup)."""
    err_console.print(f"[yellow]warning:[/] {text}", highlight=False, soft_wrap=True)


def progress(quiet: bool = False) -> Progress:
    """A Rich progress bar on stderr (none with ``quiet``)."""
    return Progress(
        TextColumn("[bold]{task.description}"),
        BarColumn(),
        TextColumn("{task.completed}/{task.total}"),
        TextColumn("{task.fields[item]}"),
        TimeElapsedColumn(),
        TextColumn("left"),
        TimeRemainingColumn(),  # from the measured rate of the steps done so far
        console=err_console,
        transient=False,
        disable=quiet,
    )


def info(quiet: bool, text: str) -> None:
    """An information line on stderr, unless ``quiet``."""
    if not quiet:
        err_console.print(text, highlight=False)


# -- options shared by several commands ---------------------------------------------------------------
def scheduler_option():
    """``--scheduler``: where work runs (acquire planar|mesh, fit, evaluate, import images)."""
    return typer.Option(
        "threads",
        "--scheduler",
        metavar="WHERE",
        help="Where work runs: threads (this process), local:N (N Dask worker processes started for this "
        "command) or tcp://HOST:PORT (a running Dask cluster; the data set's path must be visible to its "
        "workers). Results are identical whichever.",
    )


def max_memory_option():
    return typer.Option(
        None,
        "--max-memory",
        metavar="SIZE",
        help="Most memory the command may use, e.g. 4G or 512M (default: the machine's available memory); "
        "a larger estimate is refused before any work.",
    )


def quiet_option():
    return typer.Option(
        False, "--quiet", "-q", help="No progress and no information lines; errors still shown."
    )


def json_option():
    return typer.Option(False, "--json", help="Print a summary as one JSON object on stdout (for scripts).")


def dataset_overwrite_option():
    """``--overwrite`` of a command that writes a resumable data set (acquire planar|mesh)."""
    return typer.Option(
        False,
        "--overwrite",
        help="Replace a data set of translucency made with other arguments (never anything else).",
    )


def overwrite_option():
    return typer.Option(
        False, "--overwrite", help="Replace an earlier output of translucency at --out (never anything else)."
    )


# -- the end of a working command ---------------------------------------------------------------------
def finish(as_json: bool, quiet: bool, summary: dict, lines=()) -> None:
    """The end of a working command: one JSON object on stdout (``--json``), or its result lines."""
    if as_json:
        print(json.dumps(jsonable(summary), allow_nan=False))
    elif not quiet:
        for line in lines:
            console.print(line)
