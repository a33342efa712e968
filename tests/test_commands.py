"""The command line only parses and prints: each command calls one library function (docs/api.md's table),
and docs/api.md lists its options as that function's arguments.  That each option reaches the function is
tests/test_options_reach.py's: it runs every command with every option."""

from pathlib import Path

import cli_reference as reference
import pytest
import typer

from translucency.cli._common import PANEL_RUN
from translucency.cli.app import app

API = Path(__file__).resolve().parents[1] / "docs" / "api.md"

#: how a command runs and prints: listed under one heading of --help in every command that has them
RUN_OPTIONS = {"--overwrite", "--chunk", "--scheduler", "--max-memory", "--quiet", "--json"}


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
def test_the_run_options_share_one_panel(name, command):
    """--overwrite, --chunk, --scheduler, --max-memory, --quiet and --json are under the same heading of
    --help (cli/_common.py's PANEL_RUN) in every command that has them."""
    elsewhere = [
        option
        for param in command.params
        for option in param.opts
        if option in RUN_OPTIONS and getattr(param, "rich_help_panel", None) != PANEL_RUN
    ]
    assert not elsewhere, f"translucency {name}: {elsewhere} not under --help's {PANEL_RUN!r} panel"


def test_the_pages_option_lists_are_written_from_the_commands():
    """docs/api.md's option → argument lists are the commands' and the signatures' own: a renamed option or
    argument changes them (``python docs/_gen/cli_reference.py --api docs/api.md``)."""
    page = API.read_text()
    block = page.split(reference.API_BEGIN, 1)[1].split(reference.API_END, 1)[0].strip("\n")
    assert block == reference.api_options(page), f"run: {reference.API_COMMAND}"
    assert "(none)" not in block and "→ `out`" in block and "--resolution → `resolution`" in block
