"""The command line only parses and prints: each command calls one library function (docs/api.md's table),
and each of its options is an argument of that function, so a Python user can do what the command does."""

from pathlib import Path

import pytest
import typer

import translucency as tl
from translucency.cli import reference
from translucency.cli.app import app

API = Path(__file__).resolve().parents[1] / "docs" / "api.md"

PRINTING = reference.PRINTING


def _table() -> dict[str, list[str]]:
    return reference.library_functions(API.read_text())


def _commands(group=None, prefix=()):
    group = group or typer.main.get_command(app)
    for name, command in group.commands.items():
        if hasattr(command, "commands"):
            yield from _commands(command, (*prefix, name))
        else:
            yield " ".join((*prefix, name)), command


def test_every_command_is_in_the_table():
    commands = {name for name, _ in _commands()}
    table = _table()
    assert commands <= set(table), f"commands missing from docs/api.md: {sorted(commands - set(table))}"
    assert set(table) <= commands, f"docs/api.md names no such command: {sorted(set(table) - commands)}"


@pytest.mark.parametrize("name,command", list(_commands()), ids=[n for n, _ in _commands()])
def test_every_option_is_an_argument_of_the_library_function(name, command):
    functions = [getattr(tl, f) for f in _table()[name]]
    assert functions, f"docs/api.md names no library function for translucency {name}"
    missing, position = [], 0
    for param in command.params:  # each argument by position, each option by its names (cli/reference.py)
        options = [o for o in param.opts if o.startswith("--")]
        if param.param_type_name != "argument" and set(options) & PRINTING:
            continue
        if not reference.library_argument(param, functions, position):
            missing.append(options[0] if options else param.name.upper())
        position += param.param_type_name == "argument"
    assert not missing, f"translucency {name}: no Python argument of {_table()[name]} for {missing}"


def test_the_pages_option_lists_are_written_from_the_commands():
    """docs/api.md's option → argument lists are the commands' and the signatures' own: a renamed option or
    argument changes them (``python -m translucency.cli.reference --api docs/api.md``)."""
    page = API.read_text()
    block = page.split(reference.API_BEGIN, 1)[1].split(reference.API_END, 1)[0].strip("\n")
    assert block == reference.api_options(page), "run: python -m translucency.cli.reference --api docs/api.md"
    assert "(none)" not in block and "→ `out`" in block and "--resolution → `resolution`" in block
