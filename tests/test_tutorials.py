"""The tutorials run as written.

Every ``$ `` line of the ```` ```console ```` blocks of ``docs/tutorials/*.md`` runs, in the page's order, in
a folder of its own per page (bash, with this environment's ``translucency`` first on PATH), exits with
status 0, and leaves the files the page tells the reader to look at (``<!-- test: files A B -->``, each
also named in the page's text). A block after ``<!-- test: skip (why) -->`` is not run (the install, the
main job); its lines are still parsed.

Fast: every ``translucency …`` line of the tutorials — in a console block or in the text — names a command
and options that exist under their current names (the command line's own parser reads each console line,
without running it): a renamed or removed option fails here in a second, not after minutes of running.
"""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import pytest
import typer
from typer._click.core import Context, Parameter  # Typer's own Click, whose objects its commands are
from typer._click.exceptions import ClickException

from translucency.cli.app import app

TUTORIALS = Path(__file__).resolve().parents[1] / "docs" / "tutorials"
PAGES = sorted(TUTORIALS.glob("*.md"))
#: pages whose commands take more than ~20 s on 2 cores (the objects' acquisitions and renders, the
#: photographs): run by `make test-slow`; each page's time shown by `pytest -s` (per command) or
#: `--durations=0`. planar-sample stays in the fast suite (about 15 s).
SLOW = {
    "first-hour",
    "object-from-mesh",
    "lab-photographs",
    "mitsuba-scene",
    "viewer-and-blender",
}
#: the longest one command may take (a rig's photographs on a loaded machine)
COMMAND_TIMEOUT_S = 1800

BLOCK = re.compile(r"^```console[ \t]*\n(.*?)^```[ \t]*$", re.S | re.M)
SKIP = re.compile(r"<!--\s*test:\s*skip\b[^>]*-->\s*\Z")
FILES = re.compile(r"<!--\s*test:\s*files\s+(.*?)-->", re.S)
INLINE = re.compile(r"`([a-z][a-z-]*(?: [^`]+)?)`")  # `translucency view M --export page`, `render scene`


@dataclass(frozen=True)
class Command:
    line: str  # the command as bash reads it (continuation lines joined)
    skipped: bool  # in a block after a skip marker


def commands(text: str) -> list[Command]:
    """The ``$ `` lines of the page's console blocks, in order; a line ending in a backslash continues on
    the next. Lines without ``$ `` are the commands' output and are not run."""
    out = []
    for block in BLOCK.finditer(text):
        skipped = bool(SKIP.search(text[: block.start()].rstrip() + "\n"))
        lines, current = block.group(1).splitlines(), None
        for raw in lines:
            if current is not None:  # a continuation of the line above
                current += " " + raw.strip()
            elif raw.startswith("$ "):
                current = raw[2:].strip()
            else:
                continue
            if current.endswith("\\"):
                current = current[:-1].rstrip()
            else:
                out.append(Command(current, skipped))
                current = None
        assert current is None, f"a console block ends inside a continued line: {current!r}"
    return out


def files_to_look_at(text: str) -> list[str]:
    """The files a page's ``<!-- test: files … -->`` markers name."""
    return [name for marker in FILES.finditer(text) for name in marker.group(1).split()]


def _page_id(page: Path):
    marks = [pytest.mark.slow] if page.stem in SLOW else []
    return pytest.param(page, marks=marks, id=page.stem)


# -- fast: the pages' structure, and every command line against the parser ------------------------------


def test_every_page_has_commands_and_files_to_look_at():
    assert PAGES, f"no tutorials under {TUTORIALS}"
    stems = {p.stem for p in PAGES}
    assert SLOW <= stems, f"SLOW names pages that do not exist: {SLOW - stems}"
    for page in PAGES:
        text = page.read_text()
        run = [c for c in commands(text) if not c.skipped]
        assert run, f"{page.name}: no command that the test runs"
        files = files_to_look_at(text)
        assert files, f"{page.name}: no <!-- test: files ... --> marker: nothing to check after running it"
        prose = FILES.sub("", text)
        for name in files:
            assert f"`{name}`" in prose or f"`{name} " in prose, (
                f"{page.name}: the marker names {name}, which the page's text does not name in `...`"
            )


def test_the_block_reader_joins_continued_lines_and_honours_skips():
    text = (
        "<!-- test: skip (slow) -->\n```console\n$ make demo\n```\n\n"
        "```console\n$ translucency fit a.zarr \\\n    --out a.model.zip\nmodel: a.model.zip\n$ ls\n```\n"
    )
    assert commands(text) == [
        Command("make demo", True),
        Command("translucency fit a.zarr --out a.model.zip", False),
        Command("ls", False),
    ]


def _resolve(words: list[str]):
    """(the command's name, the Click command, its own words) of ``translucency WORDS``."""
    command, path, rest = typer.main.get_command(app), ["translucency"], list(words)
    while hasattr(command, "commands") and rest and not rest[0].startswith("-"):
        name = rest.pop(0)
        if rest and f"{name} {rest[0]}" in command.commands:  # a command of two words (render scene)
            name = f"{name} {rest.pop(0)}"
        sub = command.get_command(Context(command), name)
        assert sub is not None, f"`{' '.join(path)}` has no command {name!r}"
        command, path = sub, [*path, name]
    return " ".join(path), command, rest


def _options(command) -> dict[str, Parameter]:
    return {name: p for p in command.params for name in (*p.opts, *p.secondary_opts) if name.startswith("-")}


def _check_option_names(name: str, command, words: list[str]) -> None:
    """Every option word names a visible option of the command (an old name kept for one release is not
    the name a tutorial teaches)."""
    known = _options(command) | {"--help": None}
    for word in words:
        if not word.startswith("-") or word == "-" or re.fullmatch(r"-?[0-9.]+(e-?[0-9]+)?(,.*)?", word):
            continue  # a value: a file on stdout, a negative number, a list of numbers
        option = word.split("=", 1)[0]
        assert option in known, f"`{name}` has no option {option}"
        assert known[option] is None or not getattr(known[option], "hidden", False), (
            f"`{name} {option}` is a hidden (old) name"
        )


def _parse(line: str) -> None:
    words = shlex.split(line, comments=True)
    assert words[0] == "translucency"
    name, command, rest = _resolve(words[1:])
    _check_option_names(name, command, rest)
    if "--help" in rest or "--version" in rest:
        return
    try:  # the command's own parser: arguments, option values and their types, without running it
        command.make_context(name, rest, resilient_parsing=False)
    except typer.Exit as done:
        assert done.exit_code == 0, f"`{line}` exits {done.exit_code} while parsing"
    except ClickException as exc:
        pytest.fail(f"`{line}` does not parse: {exc.format_message()}")


def _tutorial_lines() -> list[tuple[str, str]]:
    lines = []
    for page in PAGES:
        for command in commands(page.read_text()):
            if command.line.startswith("translucency"):
                lines.append((page.name, command.line))
    return lines


def test_every_command_line_of_the_tutorials_parses():
    lines = _tutorial_lines()
    assert lines, "no translucency command in the tutorials"
    for page, line in lines:
        try:
            _parse(line)
        except AssertionError as exc:
            raise AssertionError(f"{page}: {exc}") from None


def test_every_command_named_in_the_text_exists_with_its_options():
    """The commands quoted in the text — `translucency view MODEL --export page`, or without the program's
    name, `render scene`, `import images --extra-camera F,P,C`: the command exists and its options do
    (the placeholders are not parsed)."""
    commands_ = set(typer.main.get_command(app).commands)
    checked = 0
    for page in PAGES:
        prose = BLOCK.sub("", page.read_text())
        for quoted in INLINE.findall(prose):
            words = shlex.split(quoted)
            if words[0] in commands_:
                words = ["translucency", *words]
            if words[0] != "translucency":
                continue  # code of another kind: a file, a field, a Python name
            checked += 1
            try:
                name, command, rest = _resolve(words[1:])
                _check_option_names(name, command, rest)
            except AssertionError as exc:
                raise AssertionError(f"{page.name}: `{quoted}`: {exc}") from None
    assert checked, "no command quoted in the tutorials' text"


def test_the_parse_check_catches_a_wrong_option():
    with pytest.raises(AssertionError, match="no option --size"):
        _parse("translucency render m.model.zip --size 64 48")
    with pytest.raises(AssertionError, match="no command"):
        _parse("translucency acquire planet --out a.zarr")
    with pytest.raises(pytest.fail.Exception, match="does not parse"):
        _parse("translucency acquire planar --grid many --out a.zarr")


# -- each page, run ------------------------------------------------------------------------------------


@pytest.mark.parametrize("page", [_page_id(p) for p in PAGES])
def test_tutorial_runs_as_written(page: Path, tmp_path):
    bin_dir = Path(sys.executable).parent
    assert (bin_dir / "translucency").exists(), f"no translucency beside {sys.executable}"
    env = {**os.environ, "PATH": f"{bin_dir}{os.pathsep}{os.environ.get('PATH', '')}"}
    text = page.read_text()
    times = []
    for command in commands(text):
        if command.skipped:
            continue
        start = time.perf_counter()
        done = subprocess.run(
            command.line,
            shell=True,
            executable="/bin/bash",
            cwd=tmp_path,
            env=env,
            capture_output=True,
            text=True,
            timeout=COMMAND_TIMEOUT_S,
        )
        times.append(f"{time.perf_counter() - start:7.1f} s  {command.line}")
        assert done.returncode == 0, (
            f"{page.name}: `{command.line}` exited {done.returncode}\n"
            f"stdout:\n{done.stdout[-3000:]}\nstderr:\n{done.stderr[-3000:]}\nthe page's commands:\n"
            + "\n".join(times)
        )
    missing = [name for name in files_to_look_at(text) if not (tmp_path / name).exists()]
    assert not missing, f"{page.name}: the page says to look at {missing}, which its commands did not write"
    empty = [
        name
        for name in files_to_look_at(text)
        if (tmp_path / name).is_file() and not (tmp_path / name).stat().st_size
    ]
    assert not empty, f"{page.name}: the page says to look at {empty}, which its commands left empty"
    print(f"\n{page.name}:\n" + "\n".join(times))


# -- the README and the other pages: their command lines -----------------------------------------------

README = TUTORIALS.parents[1] / "README.md"
#: a shell block of the README or a page (no ``$ `` prompt: every line is a command, # starts a comment)
SHELL = re.compile(r"^```(?:sh|bash|console|shell)[ \t]*\n(.*?)^```[ \t]*$", re.S | re.M)


def shell_lines(text: str, heading: str | None = None) -> list[str]:
    """The ``translucency …`` and other command lines of the shell blocks of ``text`` (of its section
    ``heading`` alone if given), continuation lines joined, ``$ `` prompts and output lines dropped."""
    if heading is not None:
        text = text.split(f"\n## {heading}\n", 1)[1].split("\n## ", 1)[0]
    out = []
    for block in SHELL.finditer(text):
        current = None
        for raw in block.group(1).splitlines():
            line = raw.strip().removeprefix("$ ")
            if current is not None:
                current += " " + line
            elif re.match(r"(translucency|make|pip|python) ", line):
                current = line
            else:
                continue
            if current.endswith("\\"):
                current = current[:-1].rstrip()
            else:
                out.append(current)
                current = None
    return out


def test_every_command_line_of_the_readme_and_the_other_pages_parses():
    pages = [README, *sorted(p for p in TUTORIALS.parent.rglob("*.md") if TUTORIALS not in p.parents)]
    checked = 0
    for page in pages:
        for line in shell_lines(page.read_text()):
            if line.startswith("translucency "):
                checked += 1
                try:
                    _parse(line)
                except AssertionError as exc:
                    raise AssertionError(f"{page.name}: {exc}") from None
    assert checked >= 20, f"only {checked} command lines found in the README and the pages"


def _run_lines(lines: list[str], folder: Path) -> None:
    bin_dir = Path(sys.executable).parent
    env = {**os.environ, "PATH": f"{bin_dir}{os.pathsep}{os.environ.get('PATH', '')}"}
    for line in lines:
        done = subprocess.run(
            line, shell=True, executable="/bin/bash", cwd=folder, env=env, capture_output=True, text=True
        )
        assert done.returncode == 0, f"README: `{line}` exited {done.returncode}\n{done.stderr[-3000:]}"


def test_the_readmes_first_result_runs_as_written(tmp_path):
    """The README's first result (about 20 s on 2 cores): a scan, a fit, a truth, a report."""
    lines = shell_lines(README.read_text(), "A first result in five minutes")
    assert [line.split()[1] for line in lines] == ["acquire", "fit", "acquire", "evaluate"], lines
    _run_lines(lines, tmp_path)
    report = tmp_path / "report"
    assert (report / "index.html").stat().st_size and (report / "report.json").stat().st_size


@pytest.mark.slow
def test_the_readmes_three_paths_run_as_written(tmp_path):
    """The README's three paths, after its first result (their inputs): a planar sample, an object, a
    lab's photographs."""
    text = README.read_text()
    first = shell_lines(text, "A first result in five minutes")
    _run_lines(first + shell_lines(text, "Three paths"), tmp_path)
    written = ("paper.model.zip", "spot.model.zip", "render/ours.png", "scene", "shots.zarr", "spot-rig.zarr")
    for name in written:
        assert (tmp_path / name).exists(), name
