"""One vocabulary: an option name means one thing in every command (cli/_vocabulary.py holds each name's
meaning and metavar), and an old name (cli/_renamed.py) still works for one release with one warning line,
landing on its new option."""

import re
import typing
from pathlib import Path

import pytest
import typer
from typer.testing import CliRunner

from translucency.cli import _renamed, _vocabulary
from translucency.cli.app import app

runner = CliRunner()


def _commands(group=None, prefix=()):
    group = group or typer.main.get_command(app)
    for name, command in group.commands.items():
        if hasattr(command, "commands"):  # a group (acquire, import)
            yield from _commands(command, (*prefix, name))
        else:
            yield " ".join((*prefix, name)), command


#: names whose values differ in type with one meaning: fit's --terms also takes the word auto, demo's a number
OTHER_TYPE = {"--terms"}


def _kind(param) -> tuple:
    """What a value of the option is: flag or not, values per use, its type (a repeatable option's
    element type: --light is one light in export, one per use in render)."""
    annotation = param.type_descriptor.annotation
    annotation = typing.get_args(annotation)[0] if typing.get_origin(annotation) is list else annotation
    return (bool(getattr(param, "is_flag", False)), param.nargs, str(annotation))


def _long_names(param) -> list[str]:
    return [
        o for o in (*param.opts, *param.secondary_opts) if o.startswith("--") and not o.startswith("--no-")
    ]


def _options():
    """(command, long name, the option) for every option of every command (the top's --version too)."""
    top = typer.main.get_command(app)
    for param in top.params:
        for name in _long_names(param):
            yield "translucency", name, param
    for command_name, command in _commands():
        for param in command.params:
            if param.param_type_name == "option":
                for name in _long_names(param):
                    yield command_name, name, param


def test_every_option_name_is_in_the_vocabulary():
    missing = sorted({f"{c} {n}" for c, n, _ in _options() if n not in _vocabulary.VOCABULARY})
    assert not missing, f"options without a meaning in translucency/cli/_vocabulary.py: {missing}"


def test_an_option_name_has_one_kind_of_value_in_every_command():
    """A name whose value is a flag in one command and a path in another, two numbers in one and three in
    another (render's pixels against acquire's millimetres), has two meanings."""
    kinds: dict[str, dict[tuple, list[str]]] = {}
    for command, name, param in _options():
        if name in ("--help", *OTHER_TYPE):
            continue
        kinds.setdefault(name, {}).setdefault(_kind(param), []).append(command)
    twice = {name: by for name, by in kinds.items() if len(by) > 1}
    assert not twice, f"one name, several kinds of value: {twice}"


def test_help_shows_the_vocabulary_metavar():
    """--help shows each option's metavar from the vocabulary (so one name reads alike everywhere)."""
    wrong = []
    for command, name, param in _options():
        if name in ("--help", "--version"):
            continue
        expected = _vocabulary.METAVARS[name] if name in _vocabulary.METAVARS else "?"
        shown = "" if getattr(param, "is_flag", False) else param.metavar
        if shown != expected:
            wrong.append(f"{command} {name}: {shown!r}, the vocabulary says {expected!r}")
    assert not wrong, wrong


def test_a_short_option_is_one_long_option_everywhere():
    """-m is --material in every command that has it (and so is every other short name)."""
    wrong = []
    for command, _, param in _options():
        for short in (o for o in param.opts if re.fullmatch(r"-\w", o)):
            long = _long_names(param)[0]
            if _vocabulary.SHORT.get(short) != long:
                wrong.append(f"{command} {short} is {long}, the vocabulary: {_vocabulary.SHORT.get(short)}")
    assert not wrong, wrong


def test_the_test_sees_a_second_meaning():
    """The walk above catches a name given a second meaning: render's pixels as --size beside acquire's
    millimetres."""
    kinds = {}
    for command, name, param in _options():
        if name == "--size" or (command == "render" and name == "--resolution"):
            kinds.setdefault(_kind(param), []).append(f"{command} {name}")
    assert len(kinds) == 2  # (W H T floats) and (W H integers): --size for the pixels would be flagged


#: words of a help text that tell the history of the tool rather than what an option does
HISTORY = (
    r"\bformer\b|previous default|\(was\b|\bwas (the )?default|\bmade before\b|\bno longer\b|\bdeprecated\b"
)


def test_no_help_text_carries_history_or_type_names():
    """--help of every command: no history ("the former", "was") and no Typer type names (<path>, <bool>,
    <list[float]>)."""
    bad = []
    for command, _ in [("", None), ("acquire", None), ("import", None), *_commands()]:
        args = [*command.split(), "--help"]
        output = runner.invoke(app, args, terminal_width=200, env={"COLUMNS": "200"}).output
        text = " ".join(re.sub(r"[│╭╮╰╯─]", " ", output).split())  # one line: a phrase may wrap
        pattern = rf"<(path|bool|int|float|text|list|tuple)\b|{HISTORY}"
        bad += [
            f"{command or 'translucency'}: …{text[m.start() - 40 : m.end() + 20]}…"
            for m in re.finditer(pattern, text)
        ]
    assert not bad, bad


# -- the old names ------------------------------------------------------------------------------------
#: command, an old option with a value, the new option, the parameter it lands on, the value there
OLD = [
    ("render", ["--size", "64", "48"], "--resolution", "resolution", (64, 48)),
    ("render", ["--incidence", "normal"], "--incidence-law", "incidence_law", "normal"),
    ("render", ["--incidence=normal"], "--incidence-law", "incidence_law", "normal"),
    ("render", ["--model", "pig=p.model.zip"], "--object", "objects", ["pig=p.model.zip"]),
    ("import images", ["--view", "a,b,c"], "--extra-camera", "extra_camera", ["a,b,c"]),
    ("import images", ["--scale", "2.5"], "--gain", "gain", 2.5),
    ("evaluate", ["--points", "0,17"], "--profiles", "profiles", "0,17"),
    ("fit", ["-m", "4"], "--directions", "directions", "4"),
    ("fit", ["-m8"], "--directions", "directions", "8"),
    ("view", ["--reference", "r"], "--reference-render", "reference_render", Path("r")),
]
#: each command's required arguments and options, to reach its parsing
REQUIRED = {
    "render": ["m.model.zip"],
    "import images": ["f", "-p", "p.csv", "-c", "c.json", "-o", "o.zarr"],
    "evaluate": ["m.model.zip", "d.zarr"],
    "fit": ["d.zarr", "-o", "m.model.zip"],
    "view": ["m.model.zip"],
}


@pytest.mark.parametrize("command,old,new,param,value", OLD, ids=[f"{c} {o[0]}" for c, o, *_ in OLD])
def test_an_old_name_still_works_with_one_warning_line(monkeypatch, command, old, new, param, value):
    seen = {}

    def parsed(self, ctx, args):  # the command's parse, recorded, then stopped before any work
        original(self, ctx, args)
        seen.update(ctx.params)
        raise typer.Exit(0)

    original = typer.core.TyperCommand.parse_args
    monkeypatch.setattr(typer.core.TyperCommand, "parse_args", parsed)
    res = runner.invoke(app, [*command.split(), *REQUIRED[command], *old])
    assert res.exit_code == 0, res.output
    name = old[0].split("=")[0] if old[0].startswith("--") else "-m"
    assert res.stderr == (
        f"warning: translucency {command} {name} is renamed {new}; the old name goes in the next release\n"
    )
    got = seen[param]
    assert (tuple(got) if isinstance(value, tuple) else got) == value


def test_an_old_name_warns_once_however_often_it_is_given():
    args = _renamed.renamed(
        typer.main.get_command(app), ["render", "--scene", "s.xml", "--model", "a=1", "--model", "b=2"]
    )
    assert args == ["render", "--scene", "s.xml", "--object", "a=1", "--object", "b=2"]


def test_old_names_are_rewritten_only_in_their_command():
    """acquire's --incidence (degrees), --size (mm) and -m (--material) stay as they are; the words after
    ``--`` are positional."""
    top = typer.main.get_command(app)
    args = ["acquire", "planar", "-m", "marble", "--size", "6", "6", "3", "--incidence", "30"]
    assert _renamed.renamed(top, args) == args
    assert _renamed.renamed(top, ["render", "--", "--size"]) == ["render", "--", "--size"]


def test_fit_m_is_no_longer_short_for_directions():
    fit = dict(_commands())["fit"]
    assert not any("-m" in p.opts for p in fit.params)
    assert _renamed.RENAMED["fit"] == {"-m": "--directions"}


def test_the_old_library_keywords_still_work_with_a_deprecation_warning():
    import translucency as tl

    with pytest.warns(DeprecationWarning, match="size= is renamed resolution="):
        with pytest.raises(tl.TranslucencyError, match="resolution: must be >= 1"):
            tl.render_model("m.model.zip", size=(0, 10))
    with pytest.raises(tl.TranslucencyError, match="give resolution alone"):
        tl.render_model("m.model.zip", size=(8, 6), resolution=(8, 6))
