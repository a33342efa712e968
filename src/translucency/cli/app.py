"""The ``translucency`` command (Typer + Rich): the top command and its commands, one module each.

Every subcommand has ``--help``.  A user's mistake (bad file, bad parameter)
prints one line starting with ``error:`` and exits with status 2 — never a
traceback.  A new command is a new module here and one registration line below.
"""

from __future__ import annotations

import inspect
import sys

import typer

from .._version import __version__
from . import (
    acquire,
    acquire_object,
    demo,
    evaluate,
    examples,
    export,
    fit,
    import_object,
    imports,
    info,
    materials,
    render,
    render_scene,
    view,
)
from ._common import console, err_console
from ._renamed import renamed
from ._vocabulary import METAVARS


def _plain_kinds(params: list, ctx) -> list:
    """``params`` with --help naming the kind of each value as the options' metavars do (PATH, INT), never
    Typer's type names (<path>, <bool> after --help)."""
    for param in params:
        shown = param.display_type_rich(ctx=ctx)
        if shown and shown.startswith("<"):
            kind = "" if shown == "<bool>" else shown.strip("<>").upper()
            param.display_type_rich = lambda ctx=None, kind=kind: kind
    return params


class _Group(typer.core.TyperGroup):
    """A group of commands (acquire, import) whose --help shows no Typer type names."""

    def get_params(self, ctx):
        return _plain_kinds(super().get_params(ctx), ctx)


class _Command(typer.core.TyperCommand):
    """A command whose --help shows no Typer type names."""

    def get_params(self, ctx):
        return _plain_kinds(super().get_params(ctx), ctx)


class _OneLineErrors(_Group):
    """The top command: a usage error (unknown option, a value of the wrong type) is one ``error:`` line
    naming the option, exit status 2, like every other error — not Click's usage box.  A retired option
    name (cli/_vocabulary.py's RENAMED) is read as its new one, with one warning line."""

    def resolve_command(self, ctx, args):
        """``render scene ...`` is the command ``render scene`` (its own command, listed as such): two
        words, where a one-word command takes one."""
        if len(args) > 1 and f"{args[0]} {args[1]}" in self.commands:
            return super().resolve_command(ctx, [f"{args[0]} {args[1]}", *args[2:]])
        return super().resolve_command(ctx, args)

    def main(self, args=None, prog_name=None, complete_var=None, standalone_mode=True, **extra):
        args = renamed(self, list(sys.argv[1:] if args is None else args))
        if not standalone_mode:
            return super().main(args, prog_name, complete_var, standalone_mode=False, **extra)
        try:
            rv = super().main(args, prog_name, complete_var, standalone_mode=False, **extra)
        except typer._click.exceptions.ClickException as exc:
            if type(exc).__name__ == "NoArgsIsHelpError":  # the help text is the answer
                exc.show()
            else:
                text = " ".join(exc.format_message().split())
                err_console.print(f"[bold red]error:[/] {text}", highlight=False, soft_wrap=True, markup=True)
            sys.exit(exc.exit_code)
        except typer.Abort:
            err_console.print("aborted", highlight=False)
            sys.exit(1)
        sys.exit(rv if isinstance(rv, int) else 0)


app = typer.Typer(
    cls=_OneLineErrors,
    help="Measure, fit, evaluate and render heterogeneous translucent materials "
    "(empirical sum-of-exponentials model of Fuchs et al.). Units: mm, R_d in mm^-2.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)


def _version(value: bool) -> None:
    if value:
        console.print(f"translucency {__version__}")
        raise typer.Exit()


@app.callback()
def _main(
    version: bool = typer.Option(
        False, "--version", callback=_version, is_eager=True, help="Print the version and exit."
    ),
) -> None:
    """Measure, fit, evaluate and render heterogeneous translucent materials."""


# -- the commands, in the order of `translucency --help` ------------------------------------------------
app.command("demo")(demo.demo)
app.command("examples")(examples.examples)
app.command("materials")(materials.materials)
app.command("info")(info.info)
app.command("fit")(fit.fit)
app.command("render")(render.render)
app.command("render scene")(render_scene.render_scene)
app.command("evaluate")(evaluate.evaluate)
app.command("export")(export.export)
app.command("view")(view.view)
acquire.app.command("object-photographs")(acquire_object.acquire_object_photographs_cmd)
imports.app.command("object")(import_object.import_object_cmd)
app.add_typer(acquire.app, name="acquire", cls=_Group)
app.add_typer(imports.app, name="import", cls=_Group)


def _name_metavars(*typer_apps) -> None:
    """Give every option and argument of every command a real metavar (FLOAT, PATH, ...) unless it has one:
    the option's from the vocabulary (cli/_vocabulary.py), an argument its name in capitals (Typer would
    print <float>, <path>, ...)."""
    for typer_app in typer_apps:
        for command in typer_app.registered_commands:
            if command.cls in (None, typer.core.TyperCommand):
                command.cls = _Command
            for param in inspect.signature(command.callback).parameters.values():
                info = param.default
                if isinstance(info, typer.models.OptionInfo) and info.metavar is None:
                    decls = info.param_decls or ("--" + param.name.replace("_", "-"),)
                    info.metavar = METAVARS.get(decls[0].split("/")[0])  # none: the test names it
                elif isinstance(info, typer.models.ArgumentInfo) and info.metavar is None:
                    info.metavar = param.name.upper()


_name_metavars(app, acquire.app, imports.app)


def main() -> None:
    """Console entry point."""
    app()


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
