"""Options renamed so that one name means one thing in every command (cli/_vocabulary.py): an old name
still works for one release, with one ``warning:`` line, and is rewritten to its new name before the
command line is parsed, so the commands themselves know only the new names."""

from __future__ import annotations

from ._common import warn

#: command → {old name: new name}; the old names go in the next release
RENAMED: dict[str, dict[str, str]] = {
    "render": {"--size": "--resolution", "--incidence": "--incidence-law", "--model": "--object"},
    "import images": {"--view": "--extra-camera", "--scale": "--gain"},
    "evaluate": {"--points": "--profiles"},
    "fit": {"-m": "--directions"},
    "view": {"--reference": "--reference-render"},
}


def renamed(group, args: list[str]) -> list[str]:
    """``args`` of the top command ``group`` with every old option name of the command they name replaced
    by its new one (``--size 64 48``, ``--size=64``, ``-m8``), one warning line per old name used."""
    found = _command(group, args)
    if found is None:
        return args
    name, command, start = found
    table, told = RENAMED.get(name, {}), set()
    out = args[:start]
    for i, word in enumerate(args[start:], start):
        if word == "--":  # what follows is positional
            out += args[i:]
            break
        old, new = _old_name(word, table)
        if old is None:
            out.append(word)
            continue
        if old not in told:
            told.add(old)
            warn(f"translucency {name} {old} is renamed {new}; the old name goes in the next release")
        rest = word[len(old) :]
        out += [new, rest.removeprefix("=")] if rest else [new]
    return out[:start] + _former_json(name, command, out[start:])


def _old_name(word: str, table: dict[str, str]) -> tuple[str | None, str | None]:
    """The old name ``word`` begins with (``--size``, ``--size=64``; a short one also ``-m8``)."""
    for old, new in table.items():
        if word == old or word.startswith(old + "=") or (len(old) == 2 and word.startswith(old)):
            return old, new
    return None, None


def _command(group, args: list[str]):
    """(``"import images"``, the command, where its own words begin) of the command ``args`` name."""
    path = []
    for i, word in enumerate(args):
        if word.startswith("-"):  # an option of a group (--help, --version): it takes no value
            continue
        command = getattr(group, "commands", {}).get(word)
        if command is None:
            return None
        path.append(word)
        if not hasattr(command, "commands"):
            return " ".join(path), command, i + 1
        group = command
    return None


def _former_json(name: str, command, args: list[str]) -> list[str]:
    """``evaluate``'s own words ``args`` with ``--json PATH`` (a third positional word: the command takes
    two, MODEL DATA) and ``--json=PATH`` read as ``--json-out PATH``, ``--json -`` as ``--json``."""
    if name != "evaluate":
        return args
    flags = {"--help"} | {
        f for p in command.params if getattr(p, "is_flag", False) for f in (*p.opts, *p.secondary_opts)
    }
    arguments = sum(1 for p in command.params if p.param_type_name == "argument")
    positional, i = [], 0
    while i < len(args):  # the indices of the positional words (each option's value skipped)
        word = args[i]
        if word == "--":
            positional += range(i + 1, len(args))
            break
        if word.startswith("-") and word != "-":
            i += 1 if word in flags or "=" in word else 2
            continue
        positional.append(i)
        i += 1
    out, i = [], 0
    while i < len(args):
        word, after = args[i], args[i + 1] if i + 1 < len(args) else None
        if word.startswith("--json="):
            after, word = word.split("=", 1)[1], "--json"
            i -= 1  # the value was part of this word
        elif (
            word != "--json"
            or after is None
            or not (after == "-" or (i + 1 in positional and len(positional) > arguments))
        ):
            out.append(word)
            i += 1
            continue
        if after == "-":
            warn("translucency evaluate --json - is renamed --json; the old form goes in the next release")
            out.append("--json")
        else:
            warn(
                "translucency evaluate --json PATH is renamed --json-out PATH; the old form goes in the "
                "next release"
            )
            out += ["--json-out", after]
        i += 2
    return out
