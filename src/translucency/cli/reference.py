"""The command line's reference page, docs/reference/cli.md, written from the commands' own help.

Every command and its options as ``--help`` shows them: the usage line, the command's help, and a table of
its arguments and options (metavar, default, help).  The page depends only on the commands' declarations,
never on the terminal's width, so that a test can hold the page to the commands::

    python -m translucency.cli.reference > docs/reference/cli.md
"""

from __future__ import annotations

import re
import sys

import typer

from .app import app

#: the page's name in the repository and the command that writes it
PAGE = "docs/reference/cli.md"
COMMAND = f"python -m translucency.cli.reference > {PAGE}"

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


def _command(command, ctx, path: str) -> list[str]:
    """A leaf command's section: its usage, help and tables."""
    usage = " ".join([path, *command.collect_usage_pieces(ctx)])
    lines = ["```text", usage, "```", "", _paragraphs(command.help), ""]
    rows = [(p.param_type_name, _row(p, ctx)) for p in command.get_params(ctx)]
    arguments = [row for kind, row in rows if row is not None and kind == "argument"]
    options = [row for kind, row in rows if row is not None and kind != "argument"]
    if arguments:
        lines += ["| argument | default | meaning |", "| --- | --- | --- |"]
        lines += [f"| {name} | {_escape(d)} | {_escape(h)} |" for name, _, d, h in arguments] + [""]
    if options:
        lines += ["| option | value | default | meaning |", "| --- | --- | --- | --- |"]
        lines += [f"| {n} | {_escape(m)} | {_escape(d)} | {_escape(h)} |" for n, m, d, h in options] + [""]
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
        The page: a table of the commands, then one section per command with its usage line, its help
        and a table of its arguments and options.

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


if __name__ == "__main__":
    sys.stdout.reconfigure(encoding="utf-8")
    sys.stdout.write(markdown())
