"""One vocabulary: an option name means one thing in every command (cli/_vocabulary.py holds each name's
meaning and metavar)."""

import re
import typing

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
def test_fit_m_is_no_longer_short_for_directions():
    fit = dict(_commands())["fit"]
    assert not any("-m" in p.opts for p in fit.params)


def test_an_old_name_before_the_first_release_is_an_unknown_option():
    """No release shipped the names changed before 0.1.0 (docs/changelog.md): they are not read as others."""
    res = runner.invoke(app, ["render", "m.model.zip", "--size", "8", "6"])
    assert res.exit_code == 2
    assert "--size" in res.output


# -- retired names: they still work, with one warning line naming the new one ---------------------------
#: command, a retired option (with its value), the new words, the parameter it lands on, the value there
RETIRED = [
    ("acquire planar", ["--angle", "30"], "--tilt", "tilt", 30.0),
    ("acquire planar", ["--angle=30"], "--tilt", "tilt", 30.0),
    ("fit", ["--float16"], "--dtype float16", "dtype", "float16"),
    ("render", ["--spp", "8"], "--reference-spp", "reference_spp", 8),
    ("render scene", ["--spp", "8"], "--reference-spp", "reference_spp", 8),
    ("render scene", ["--samples", "12"], "--irradiance-samples", "irradiance_samples", 12),
]
#: each command's required arguments and options, to reach its parsing
REQUIRED = {
    "acquire planar": ["-m", "marble", "-o", "d.zarr"],
    "fit": ["d.zarr", "-o", "m.model.zip"],
    "render": ["m.model.zip"],
    "render scene": ["s.xml", "--object", "a=m.model.zip"],
}


@pytest.mark.parametrize("command,old,new,param,value", RETIRED, ids=[f"{c} {o[0]}" for c, o, *_ in RETIRED])
def test_a_retired_name_still_works_with_one_warning_line(monkeypatch, command, old, new, param, value):
    seen = {}

    def parsed(self, ctx, args):  # the command's parse, recorded, then stopped before any work
        original(self, ctx, args)
        seen.update(ctx.params)
        raise typer.Exit(0)

    original = typer.core.TyperCommand.parse_args
    monkeypatch.setattr(typer.core.TyperCommand, "parse_args", parsed)
    res = runner.invoke(app, [*command.split(), *REQUIRED[command], *old])
    assert res.exit_code == 0, res.output
    assert res.stderr == f"warning: translucency {command} {old[0].split('=')[0]} is now {new}\n"
    assert seen[param] == value


def test_a_retired_name_warns_once_and_only_in_its_command():
    """Given twice: one line; acquire's --spp (its photographs') and the words after ``--`` stay."""
    top = typer.main.get_command(app)
    args = ["render", "scene", "s.xml", "--samples", "4", "--samples=8"]
    assert _renamed.renamed(top, args)[3:] == ["--irradiance-samples", "4", "--irradiance-samples", "8"]
    args = ["acquire", "photographs", "--spp", "4", "--", "--angle"]
    assert _renamed.renamed(top, args) == args
    options = {}
    for command, name, _ in _options():
        options.setdefault(command, set()).add(name)
    for command, table in _vocabulary.RENAMED.items():  # a retired name is no option of its command
        assert not set(table) & options[command], command


def test_index_matched_is_eta_1_and_both_at_odds_is_one_line(tmp_path):
    """acquire planar|mesh|object-photographs: --index-matched is --eta 1; with another --eta, one line."""
    commands = (["acquire", "planar", "-m", "marble"], ["acquire", "mesh"], ["acquire", "object-photographs"])
    for command in commands:
        res = runner.invoke(app, [*command, "-o", str(tmp_path / "x"), "--index-matched", "--eta", "1.4"])
        assert res.exit_code == 2 and res.output.count("\n") == 1, res.output
        assert "--index-matched is --eta 1" in res.output


def test_tilt_with_oblique_beams_and_demo_terms_beyond_the_model_are_one_line(tmp_path):
    res = runner.invoke(app, ["acquire", "planar", "-m", "marble", "-o", str(tmp_path / "d.zarr"), "--tilt",
                              "30", "--incidence", "45"])  # fmt: skip
    assert res.exit_code == 2 and "--tilt and --incidence" in res.output and res.output.count("\n") == 1
    res = runner.invoke(app, ["demo", "--terms", "5", "-o", str(tmp_path / "r")])
    assert res.exit_code == 2 and "--terms: must be a whole number between 1 and 4, got 5" in res.output
    res = runner.invoke(app, ["fit", str(tmp_path / "d.zarr"), "-o", str(tmp_path / "m"), "--dtype", "int8"])
    assert res.exit_code == 2 and "--dtype: expected float32 or float16, got 'int8'" in res.output
