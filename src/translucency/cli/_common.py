"""What every command shares: the consoles, one-line errors, the progress bar, the common options and the
end of a working command (its result lines, or one JSON object with ``--json``)."""

from __future__ import annotations

import contextlib
import functools
import json
import signal
import threading
import warnings

import typer
from rich.console import Console
from rich.markup import escape
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

from .._validate import TranslucencyError
from ..workflow import run as library
from ..workflow.run import jsonable
from ._flags import cli_words

console = Console()
err_console = Console(stderr=True)


def _say_interrupted(notes: list[str]) -> None:
    """Ctrl-C: one line saying what is kept and how to resume (or that nothing is kept)."""
    err_console.print(
        f"[bold red]interrupted:[/] {'; '.join(notes) or 'nothing written'}", highlight=False, soft_wrap=True
    )


def user_errors(func):
    """Turn a :class:`TranslucencyError` into one ``error:`` line and exit status 2; a warning is one
    ``warning:`` line on stderr."""

    def one_line(message, category, *args, **kwargs):
        warn(cli_words(" ".join(str(message).split())))

    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        with _ctrl_c_watched() as ctrl_c:
            try:
                with warnings.catch_warnings():
                    warnings.showwarning = one_line
                    return func(*args, **kwargs)
            except TranslucencyError as exc:
                library.failed()  # a failed run: the runs under way remove what they added
                line = f"[bold red]error:[/] {escape(cli_words(str(exc)))}"  # [..] is text, not markup
                err_console.print(line, highlight=False, soft_wrap=True)
                raise typer.Exit(2) from None
            except KeyboardInterrupt:
                _say_interrupted(library.interrupted())  # what is kept and how to resume, in one line
                raise typer.Exit(130) from None
            except (typer.Exit, typer.Abort):
                raise
            except Exception as exc:
                if ctrl_c.seen or from_ctrl_c(exc):  # a Ctrl-C a library re-raised as an error of its own
                    _say_interrupted(library.interrupted())
                    raise typer.Exit(130) from None
                library.failed()
                raise

    return wrapper


def from_ctrl_c(exc: BaseException | None) -> bool:
    """Whether ``exc`` is a Ctrl-C or was raised from one: Dr.Jit re-raises a ``KeyboardInterrupt`` that
    lands inside a traced loop's body (``dr.while_loop``) as a ``RuntimeError`` caused by it.

    Examples
    --------
    >>> try:
    ...     try:
    ...         raise KeyboardInterrupt
    ...     except KeyboardInterrupt as ki:
    ...         raise RuntimeError("dr.while_loop(): encountered an exception") from ki
    ... except RuntimeError as exc:
    ...     from_ctrl_c(exc)
    True
    >>> from_ctrl_c(ValueError("no"))
    False
    """
    seen = set()
    while exc is not None and id(exc) not in seen:
        if isinstance(exc, KeyboardInterrupt):
            return True
        seen.add(id(exc))
        exc = exc.__cause__ or exc.__context__
    return False


class _CtrlC:
    seen = False


@contextlib.contextmanager
def _ctrl_c_watched():
    """While a command runs, note a Ctrl-C as it arrives, before Python raises it where the program happens
    to be: a library that catches the ``KeyboardInterrupt`` and raises an error of its own (without a
    cause) still ends the command as an interrupt. Outside the main thread (no signal handler there) or
    where SIGINT is not Python's to handle, nothing changes."""
    state = _CtrlC()
    if threading.current_thread() is not threading.main_thread():
        yield state
        return
    previous = signal.getsignal(signal.SIGINT)
    if not callable(previous):  # SIG_IGN, SIG_DFL, or a handler not set from Python
        yield state
        return

    def noted(signum, frame):
        state.seen = True
        previous(signum, frame)  # Python's own raises KeyboardInterrupt here

    signal.signal(signal.SIGINT, noted)
    try:
        yield state
    finally:
        signal.signal(signal.SIGINT, previous)


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


# -- the panels of --help ------------------------------------------------------------------------------
# Each command's --help (and docs/reference/cli.md) lists its essentials under "Options", then the rest
# under these headings, in the order of the command's first option of each; one name per kind of option,
# the same in every command.
#: the sample or object simulated: its size or the mesh's units and up axis, voxels, scattering, boundary
PANEL_SAMPLE = "Sample"
#: where light enters and what is recorded around it: incident points, beam, windows, angles, exit bins
PANEL_SCAN = "Scan"
#: cameras and their pictures: position, field of view, resolution, samples per pixel, exposures, masks
PANEL_CAMERA = "Camera"
#: the fitted model's structure: terms, directions, colour
PANEL_MODEL = "Model structure"
#: how a fit weighs and uses the data: weighting, exclusion, rounds, alpha's pooling
PANEL_FITTING = "Fitting"
#: the light a model is seen under
PANEL_LIGHT = "Light"
#: how many samples and bounces a picture or a light takes (render scene)
PANEL_SAMPLING = "Sampling"
#: the transport a model is drawn with: near radius, lean, light basis
PANEL_TRANSPORT = "Transport"
#: what a model is compared with: a truth, other models, a path-traced reference
PANEL_COMPARISON = "Comparison"
#: how the output is stored and what else is written: number formats, reports, summaries to files
PANEL_OUTPUT = "Output"
#: how the command runs and prints, the same in every command: --overwrite, --chunk, --scheduler,
#: --max-memory, --quiet, --json
PANEL_RUN = "Run"


# -- options shared by several commands ---------------------------------------------------------------
def eta_option(own: str):
    """``--eta``: the boundary's index (acquire planar|mesh|object-photographs); ``own``: what the
    sample's own index is in that command."""
    return typer.Option(
        None,
        "--eta",
        help=f"The boundary's relative index of refraction: 1 index-matched, > 1 a smooth dielectric. "
        f"Default: the sample's own ({own}).",
        rich_help_panel=PANEL_SAMPLE,
    )


def index_matched_option():
    """``--index-matched``: ``--eta 1`` (acquire planar|mesh|object-photographs)."""
    return typer.Option(
        False,
        "--index-matched",
        help="No Fresnel reflection at the boundary: the same as --eta 1.",
        rich_help_panel=PANEL_SAMPLE,
    )


def boundary_eta(eta: float | None, index_matched: bool) -> float | None:
    """The boundary's η of ``--eta`` and ``--index-matched`` (None: the sample's own); both given, one line.

    Examples
    --------
    >>> boundary_eta(None, True), boundary_eta(1.4, False), boundary_eta(None, False)
    (1.0, 1.4, None)
    """
    if index_matched and eta is not None and eta != 1.0:
        raise TranslucencyError(f"--index-matched is --eta 1: give one of them, not --eta {eta:g} too")
    return 1.0 if index_matched else eta


def scheduler_option():
    """``--scheduler``: where work runs (acquire planar|mesh, fit, evaluate, import images)."""
    return typer.Option(
        "threads",
        "--scheduler",
        metavar="WHERE",
        help="Where work runs: threads (this process), local:N (N Dask worker processes started for this "
        "command) or tcp://HOST:PORT (a running Dask cluster; the data set's path must be visible to its "
        "workers). Results are identical whichever.",
        rich_help_panel=PANEL_RUN,
    )


def max_memory_option():
    return typer.Option(
        None,
        "--max-memory",
        metavar="SIZE",
        help="Most memory the command may use, e.g. 4G or 512M (default: the machine's available memory); "
        "a larger estimate is refused before any work.",
        rich_help_panel=PANEL_RUN,
    )


def quiet_option():
    return typer.Option(
        False,
        "--quiet",
        "-q",
        help="No progress and no information lines; errors still shown.",
        rich_help_panel=PANEL_RUN,
    )


def json_option():
    return typer.Option(
        False,
        "--json",
        help="Print a summary as one JSON object on stdout (for scripts).",
        rich_help_panel=PANEL_RUN,
    )


def chunk_option(default: int):
    """``--chunk`` of the commands that write a resumable data set: one rule, its default by geometry."""
    return typer.Option(
        default,
        "--chunk",
        help="Incident points (laser shots) per chunk, the unit of resuming and of the memory at work: 16 "
        "on a slab (acquire planar, import images); 8 on an object (acquire mesh, import object), where a "
        "chunk holds R_d at every vertex and all its photons (or its shots' photographs) at once.",
        rich_help_panel=PANEL_RUN,
    )


def voxel_option(default: float):
    """``--voxel`` of the commands that generate a sample: one rule, its default by what is simulated."""
    return typer.Option(
        default,
        "--voxel",
        help="Voxel size of the generated sample or filling, mm: 0.25 on a measured slab (acquire planar: "
        "its default --pitch); 0.5 where a filling spans an object or Mitsuba photographs it (acquire "
        "mesh, photographs, object-photographs), its voxels costing memory and time.",
        rich_help_panel=PANEL_SAMPLE,
    )


def dataset_overwrite_option():
    """``--overwrite`` of a command that writes a resumable data set (acquire planar|mesh)."""
    return typer.Option(
        False,
        "--overwrite",
        help="Replace a data set of translucency made with other arguments (never anything else).",
        rich_help_panel=PANEL_RUN,
    )


def overwrite_option():
    return typer.Option(
        False,
        "--overwrite",
        help="Replace an earlier output of translucency at --out (never anything else).",
        rich_help_panel=PANEL_RUN,
    )


# -- the end of a working command ---------------------------------------------------------------------
def finish(as_json: bool, quiet: bool, summary: dict, lines=()) -> None:
    """The end of a working command: one JSON object on stdout (``--json``), or its result lines."""
    if as_json:
        print(json.dumps(jsonable(summary), allow_nan=False))
    elif not quiet:
        for line in lines:
            console.print(line)
