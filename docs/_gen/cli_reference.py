"""The command line's reference pages, written from the commands themselves: docs/reference/cli.md from
their help, and docs/api.md's option → argument lists from their options and the library's signatures.

Every command and its options as ``--help`` shows them: the usage line, the command's help, and a table of
its arguments and one of its options per panel of ``--help`` (Options, then Sample, Scan, ..., Run: the
``rich_help_panel`` of each option, cli/_common.py's ``PANEL_*``), each row an option's metavar, default
and help.  The page depends only on the commands' declarations, never on the terminal's width, so that a
test can hold the page to the commands (tests/test_docs_site.py, tests/test_commands.py)::

    python docs/_gen/cli_reference.py > docs/reference/cli.md
    python docs/_gen/cli_reference.py --api docs/api.md     # the block between its markers

A documentation generator, not part of the installed package: nothing the command line runs imports it.
"""

from __future__ import annotations

import inspect
import re
import sys
from pathlib import Path

import typer

from translucency import workflow
from translucency.cli import _flags
from translucency.cli.app import app

#: the page's name in the repository and the command that writes it
PAGE = "docs/reference/cli.md"
COMMAND = f"python docs/_gen/cli_reference.py > {PAGE}"
#: the command that rewrites docs/api.md's block
API_COMMAND = "python docs/_gen/cli_reference.py --api docs/api.md"

#: docs/api.md: its table names each command's library function; the block between the markers is written
API_PAGE = "docs/api.md"
API_BEGIN, API_END = "<!-- options: begin -->", "<!-- options: end -->"
#: a row of that table: | `translucency CMD` | `tl.function` (, `tl.other`) | …
_API_ROW = re.compile(r"^\|\s*`translucency ([a-z -]+?)`\s*\|\s*([^|]+)\|")
#: the panel of ``--help`` an option without a ``rich_help_panel`` is listed under (Typer's, in English
#: whatever the locale)
DEFAULT_PANEL = "Options"
#: options that are the command line's own (how it prints), not the library's
PRINTING = {"--help", "--quiet", "--json", "--version"}
#: the library's ``sample`` takes a generator's name (``--material``) as well as a volume's file
ALIASES = {
    "--material": {"sample"},
    "--dtype": {"float16"},  # fit: float16=True
    "--reference-spp": {"spp"},  # render, render scene: the reference's spp
    "--index-matched": {"eta"},  # eta=1 (acquire planar and mesh also take index_matched=True)
}

#: a code span, kept as it is; Markdown's specials are escaped only outside one
_CODE = re.compile(r"(`[^`]*`)")
#: the end of a sentence: a full stop after a word, then a capital ("et al. 2001" goes on)
_SENTENCE = re.compile(r"(?<=[a-z)\]]\.)\s+(?=[A-Z])")


def _escape(text: str, cell: bool = True) -> str:
    """``text`` as Markdown: one line (in a table cell), ``<`` and ``|`` escaped outside code spans."""
    text = " ".join(text.split()) if cell else text

    def plain(part: str) -> str:
        part = part.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")
        return part.replace("|", "\\|") if cell else part

    return "".join(p if _CODE.fullmatch(p) else plain(p) for p in _CODE.split(text))


def _paragraphs(help_text: str | None) -> str:
    """A command's help as Markdown paragraphs (Click's ``\\b`` no-rewrap markers dropped)."""
    lines = [line for line in (help_text or "").splitlines() if line.strip() != "\b"]
    return _escape("\n".join(lines).strip(), cell=False)


def _dashes(option: str) -> int:
    """Short options first (``-o, --out``), as ``--help`` lists them."""
    return len(option) - len(option.lstrip("-"))


def _row(param, ctx) -> tuple[str, str, str, str] | None:
    """One parameter as (names, metavar, default, help), from the record ``--help`` prints; None if hidden."""
    record = param.get_help_record(ctx)
    if record is None or param.name == "help":
        return None
    shown, text = record
    own = (param.help or "").strip()
    extra = text.strip()[len(own) :].strip()
    notes = extra[1:-1].split("; ") if extra.startswith("[") and extra.endswith("]") else []
    default = next((n[len("default: ") :] for n in notes if n.startswith("default: ")), "")
    default = default.replace(", ", " ") if param.nargs > 1 else default  # typed as --resolution 64 64
    default = "required" if "required" in notes else default
    more = [n for n in notes if n != "required" and not n.startswith("default: ")]
    if param.param_type_name == "argument":
        return shown.split(" ")[0], "", default, " ".join([own, *(f"({n})" for n in more)])
    tokens = shown.split(" / ")[0].split(" ")
    while tokens and tokens[0].rstrip(",") in param.opts:
        tokens.pop(0)
    both = (param.opts, param.secondary_opts)
    names = " / ".join(", ".join(f"`{o}`" for o in sorted(opts, key=_dashes)) for opts in both if opts)
    return names, " ".join(tokens), default, " ".join([own, *(f"({n})" for n in more)])


def panels(params) -> dict[str, list]:
    """``params`` (options) by the panel of ``--help`` they are listed under, as Typer orders them: the
    default panel first, then each panel where its first option comes.

    Examples
    --------
    >>> from types import SimpleNamespace as Option
    >>> found = panels([Option(name="a", rich_help_panel="Run"), Option(name="b"), Option(name="c")])
    >>> {panel: [p.name for p in params] for panel, params in found.items()}
    {'Options': ['b', 'c'], 'Run': ['a']}
    """
    found = {DEFAULT_PANEL: []}
    for param in params:
        found.setdefault(getattr(param, "rich_help_panel", None) or DEFAULT_PANEL, []).append(param)
    return found


def _command(command, ctx, path: str) -> list[str]:
    """A leaf command's section: its usage, help, its arguments' table and a table per panel of options."""
    usage = " ".join([path, *command.collect_usage_pieces(ctx)])
    lines = ["```text", usage, "```", "", _paragraphs(command.help), ""]
    params = command.get_params(ctx)
    arguments = [r for p in params if p.param_type_name == "argument" and (r := _row(p, ctx)) is not None]
    if arguments:
        lines += ["**Arguments**", "", "| argument | default | meaning |", "| --- | --- | --- |"]
        lines += [f"| {name} | {_escape(d)} | {_escape(h)} |" for name, _, d, h in arguments] + [""]
    for panel, members in panels(p for p in params if p.param_type_name != "argument").items():
        options = [row for p in members if (row := _row(p, ctx)) is not None]
        if options:
            lines += [f"**{_escape(panel)}**", "", "| option | value | default | meaning |"]
            lines += ["| --- | --- | --- | --- |"]
            lines += [f"| {n} | {_escape(m)} | {_escape(d)} | {_escape(h)} |" for n, m, d, h in options]
            lines += [""]
    return lines


def _walk(command, ctx, path: str, depth: int):
    """(path, command, context, heading depth) of every command under ``command``, in ``--help``'s order."""
    for name in command.list_commands(ctx):
        sub = command.get_command(ctx, name)
        if sub is None or getattr(sub, "hidden", False):
            continue
        sub_ctx = sub.context_class(sub, info_name=name, parent=ctx)
        yield f"{path} {name}", sub, sub_ctx, depth
        if hasattr(sub, "commands"):  # a group (acquire, import): Typer vendors Click, so no isinstance
            yield from _walk(sub, sub_ctx, f"{path} {name}", depth + 1)


def _summary(help_text: str | None) -> str:
    """The first sentence of a command's help."""
    first = " ".join((help_text or "").strip().split("\n\n")[0].split())
    return _SENTENCE.split(first)[0].rstrip(".") + "."


def markdown(typer_app: typer.Typer = app, prog: str = "translucency") -> str:
    """The reference page of ``typer_app``'s commands, as Markdown.

    Parameters
    ----------
    typer_app : typer.Typer
        The command line (default: ``translucency``'s).
    prog : str
        Its name on the command line.

    Returns
    -------
    str
        The page: a table of the commands, then one section per command with its usage line, its help,
        a table of its arguments and a table of its options per panel of its ``--help``.

    Examples
    --------
    >>> page = markdown()
    >>> page.splitlines()[0]
    '# Command line'
    >>> "## translucency fit" in page and "| `-o`, `--out` | PATH |" in page
    True
    """
    top = typer.main.get_command(typer_app)
    ctx = top.context_class(top, info_name=prog)
    found = list(_walk(top, ctx, prog, 2))
    lines = [
        "# Command line",
        "",
        f"<!-- written by `{COMMAND}`: edit the commands' help, not this page -->",
        "",
        _paragraphs(top.help),
        "",
        f"Every command below takes `--help`, which prints the same as its section here. `{prog} --version` "
        "prints the version.",
        "",
        "| command | what it does |",
        "| --- | --- |",
    ]
    slug = {path: re.sub(r"[^\w\- ]", "", path).strip().lower().replace(" ", "-") for path, *_ in found}
    lines += [f"| [`{path}`](#{slug[path]}) | {_escape(_summary(c.help))} |" for path, c, _, _ in found]
    lines.append("")
    for path, command, command_ctx, depth in found:
        lines += ["#" * depth + f" {path}", ""]
        if hasattr(command, "commands"):
            lines += [_paragraphs(command.help), ""]
        else:
            lines += _command(command, command_ctx, path)
    return "\n".join(lines).rstrip("\n") + "\n"


def library_functions(page: str) -> dict[str, list[str]]:
    """Each command's library functions, read from the table of docs/api.md (the text ``page``).

    Examples
    --------
    >>> library_functions("| `translucency fit` | `tl.fit_model` | `Fitting` |")
    {'fit': ['fit_model']}
    """
    rows = {}
    for line in page.splitlines():
        match = _API_ROW.match(line)
        if match:
            rows[match.group(1).strip()] = re.findall(r"`tl\.(\w+)`", match.group(2))
    return rows


def python_names(option: str, param) -> set[str]:
    """The Python arguments an option may set: its parameter's name, its own word, and every argument the
    messages' tables translate to it (``cli/_flags.py``)."""
    tables = [_flags.FLAGS, _flags.AT_START, _flags.PATHS]
    names = {param.name, option.lstrip("-").replace("-", "_")} | ALIASES.get(option, set())
    return names | {py for table in tables for py, flag in table.items() if flag == option}


def library_argument(param, functions, position: int) -> str:
    """The library argument a command's parameter sets: a command's argument the function's at its
    ``position``; an option the argument it names (``name (a field of **setup)`` for a keyword a function
    takes through ``**``); empty where none does."""
    signatures = [inspect.signature(f).parameters for f in functions]
    if param.param_type_name == "argument":
        kinds = (inspect.Parameter.POSITIONAL_ONLY, inspect.Parameter.POSITIONAL_OR_KEYWORD)
        positional = [name for name, p in signatures[0].items() if p.kind in kinds]
        return positional[position] if position < len(positional) else ""
    options = [o for o in param.opts if o.startswith("--")]
    names = set().union(*(python_names(o, param) for o in options))
    for parameters in signatures:
        for name in parameters:  # the signature's order: the first that the option may set
            if name in names and parameters[name].kind is not inspect.Parameter.VAR_KEYWORD:
                return name
    for f, parameters in zip(functions, signatures, strict=True):
        var = [p.name for p in parameters.values() if p.kind is p.VAR_KEYWORD]
        documented = set(re.findall(r"``(\w+)``", f.__doc__ or ""))
        found = sorted(names & documented)
        if var and found:
            return f"{found[0]} (a field of **{var[0]})"
    return ""


def api_options(page: str, typer_app: typer.Typer = app, prog: str = "translucency") -> str:
    """docs/api.md's block: for each command, each of its options → the library argument it sets.

    Parameters
    ----------
    page : str
        The text of docs/api.md (its table names each command's functions).
    typer_app : typer.Typer
        The command line.
    prog : str
        Its name.

    Returns
    -------
    str
        One section per command: ``OPTION → `argument```, in ``--help``'s order; an option no argument of
        the functions takes reads ``→ (none)``, which tests/test_commands.py refuses.

    Examples
    --------
    >>> block = api_options("| `translucency fit` | `tl.fit_model` | `Fitting` |")
    >>> block.splitlines()[0]
    '### `translucency fit` → `tl.fit_model`'
    >>> "DATA → `dataset`" in block and "--model → `family`" in block and "--quiet" not in block
    True
    """
    table = library_functions(page)
    top = typer.main.get_command(typer_app)
    ctx = top.context_class(top, info_name=prog)
    lines = []
    for path, command, command_ctx, _ in _walk(top, ctx, prog, 2):
        name = path[len(prog) + 1 :]
        if hasattr(command, "commands") or name not in table:
            continue
        functions = [getattr(workflow, f) for f in table[name]]
        pairs, position = [], 0
        for param in command.get_params(command_ctx):
            options = [o for o in param.opts if o.startswith("--")]
            is_argument = param.param_type_name == "argument"
            if not is_argument and (not options or set(options) & PRINTING):
                continue
            shown = (param.metavar or param.name.upper()) if is_argument else options[0]
            argument = library_argument(param, functions, position)
            position += is_argument
            pairs.append(f"{shown} → `{argument}`" if argument else f"{shown} → (none)")
        names = ", ".join(f"`tl.{f}`" for f in table[name])
        lines += [f"### `{path}` → {names}", "", ", ".join(pairs), ""]
    return "\n".join(lines).rstrip("\n")


def write_api(path: Path | str = API_PAGE) -> Path:
    """Rewrite the block between docs/api.md's markers from the commands (the prose around it stays)."""
    path = Path(path)
    old = path.read_text()
    if API_BEGIN not in old or API_END not in old:
        raise SystemExit(f"{path}: no {API_BEGIN} ... {API_END} markers")
    head, rest = old.split(API_BEGIN, 1)
    path.write_text(f"{head}{API_BEGIN}\n{api_options(old)}\n{API_END}{rest.split(API_END, 1)[1]}")
    return path


if __name__ == "__main__":
    sys.stdout.reconfigure(encoding="utf-8")
    if sys.argv[1:2] == ["--api"]:
        print(write_api(*sys.argv[2:3]))
    else:
        sys.stdout.write(markdown())
