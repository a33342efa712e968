"""Retired option names (:data:`translucency.cli._vocabulary.RENAMED`) rewritten to their new names before
the command line is parsed, with one ``warning:`` line each, so that the commands know only the new names.

An old name may stand for a new name and a value (``fit --float16`` is ``fit --dtype float16``); its value,
if it takes one, follows it as before (``--spp 8``, ``--spp=8``).
"""

from __future__ import annotations

from ._common import warn
from ._vocabulary import RENAMED


def renamed(group, args: list[str]) -> list[str]:
    """``args`` of the top command ``group`` with every retired option name of the command they name replaced
    by its new words, one warning line per retired name used.

    Examples
    --------
    >>> import typer
    >>> from translucency.cli.app import app
    >>> top = typer.main.get_command(app)
    >>> renamed(top, ["render", "scene", "s.xml", "--samples=8", "--spp", "4"])
    ['render', 'scene', 's.xml', '--irradiance-samples', '8', '--reference-spp', '4']
    >>> renamed(top, ["acquire", "mesh", "--spp", "4", "--", "--float16"])   # not a name of acquire mesh
    ['acquire', 'mesh', '--spp', '4', '--', '--float16']
    """
    found = _command(group, args)
    if found is None:
        return args
    name, start = found
    table, told = RENAMED.get(name, {}), set()
    out = args[:start]
    for i, word in enumerate(args[start:], start):
        if word == "--":  # what follows is positional
            out += args[i:]
            break
        old = next((o for o in table if word == o or word.startswith(o + "=")), None)
        if old is None:
            out.append(word)
            continue
        new = table[old]
        if old not in told:
            told.add(old)
            warn(f"translucency {name} {old} is now {' '.join(new)}")
        value = word[len(old) + 1 :] if word != old else None
        out += [*new, *([value] if value is not None else [])]
    return out


def _command(group, args: list[str]) -> tuple[str, int] | None:
    """(``"render scene"``, where its own words begin) of the command ``args`` name, or None."""
    path: list[str] = []
    i = 0
    while i < len(args):
        word = args[i]
        if word.startswith("-"):  # an option of a group (--help, --version): it takes no value
            i += 1
            continue
        commands = getattr(group, "commands", {})
        two = f"{word} {args[i + 1]}" if i + 1 < len(args) else None
        if two in commands:  # a command of two words (render scene)
            return " ".join([*path, two]), i + 2
        command = commands.get(word)
        if command is None:
            return None
        path.append(word)
        if not hasattr(command, "commands"):
            return " ".join(path), i + 1
        group = command
        i += 1
    return None
