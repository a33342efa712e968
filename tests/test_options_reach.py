"""Every option of every command reaches the library: the command is run (``typer.testing.CliRunner`` on
``translucency.cli.app.app``) with the library function it calls replaced by a recorder, once with the
required arguments only (record A) and once per option with a value other than its default (record B), and
B must differ from A.  An option that is parsed but dropped, or whose value never gets to the function,
fails; one mapped to a keyword the function does not take fails too (the recorder binds each call to the
real function's signature).

The commands are walked from the Click object (groups, and the two-word commands such as ``render scene``,
whichever exist), the library functions found in each command's own body (its ``from ..workflow.X import
f``: the commands import them lazily), the values made from each Click parameter (flag: flipped; int,
float, tuple: another number; choices: another choice; path: a temporary path; str: :data:`VALUES`).
Nothing here runs the library: the whole module takes seconds.
"""

from __future__ import annotations

import ast
import functools
import importlib
import inspect
import sys
import textwrap
import typing
from pathlib import Path

import pytest
import typer
from typer.testing import CliRunner

from translucency.cli.app import app

ROOT = typer.main.get_command(app)

#: options that act before any command runs, so nothing of theirs can reach the library (the test checks
#: that each is eager: Click handles it while parsing, and exits)
BEFORE_THE_COMMAND = {
    "--help": "eager: prints the command's help and exits before the command runs",
    "--version": "the top command's eager flag: prints the version and exits before any command is chosen",
}

#: options that change only how a command shows its run: they must change the library's reporter
#: (``RichReporter(quiet)``) or what the command prints, not necessarily the library's arguments
PRINTING = {
    "--quiet": "no progress or information lines: the reporter the library is given, and the result lines",
    "--json": "one JSON object on stdout instead of the result lines (a summary the library returns)",
}

#: the value given to an option whose words must be valid (the command line parses them, or a word of a
#: vocabulary); every other option's value is made from its type (:func:`_other_value`)
VALUES = {
    "--light": "point@camera",  # render, export: a light relative to the object (render.py's grammar)
    "--exposure": "auto",  # render: fixed | fixed±STOPS | auto | a factor
    "--view": "0,0,1",  # render: x,y,z towards the camera
    "--sky": "env:0.5",  # view: a constant sky
    "--object": "cow={tmp}/cow.model.zip",  # render scene: ID=FILE, parsed by the command
    # import images: FOLDER,POSITIONS,CALIBRATION
    "--extra-camera": "{tmp}/cam2,{tmp}/cam2.csv,{tmp}/cam2.json",
    "--sample-size": "20,20",  # import images: width,height mm
    "--profiles": "0,3",  # evaluate: incident points
    "--scheduler": "local:2",  # threads | local:N | tcp://HOST:PORT
    "--transport": "walked",  # render: a registered transport's name
    "--max-memory": "4G",
    "--model": "iso",  # fit: a model family
    "--terms": "2",  # fit: 1-4 or auto (demo's --terms is an int: this value is valid there too)
    "--directions": "4",
    "--weighting": "relative",
    "--colour": "shared",
    "--incidence-law": "normal",
    "--material": "skin",  # a generator or a measured material (`translucency materials`)
    "--up": "y",
    "--unscattered": "counted",
    "--format": "exr",
    "--dtype": "float16",
    "--exposures": "single",
    "--exit-law": "dielectric",
    "--incidence": "45",  # acquire planar|mesh: a polar angle, degrees
}

#: what record A needs beyond the arguments and the required options for the command to reach its library
#: function at all (a command refuses to run without one of them, or does nothing)
BASE = {
    "acquire planar": ["--material", "marble"],  # exactly one of --material or --volume
    "acquire photographs": ["--material", "marble"],
    "render scene": ["--object", "pig={tmp}/pig.model.zip"],  # at least one object
    "export": ["--ply", "{tmp}/model.ply"],  # without --ply or --gltf there is nothing to export
}

#: an option that stands in for another of record A (the command takes one of the two)
INSTEAD_OF = {"--volume": "--material"}


class Anything(dict):
    """What a replaced library function returns: every attribute, item, call, number and format a command
    reads from a result is there (empty as a mapping or a sequence, "0" formatted), so the command runs to
    its end and prints (a JSON object with ``--json``)."""

    def __missing__(self, key):
        return Anything()

    def __getattr__(self, name):
        if name.startswith("__"):
            raise AttributeError(name)
        return Anything()

    def __call__(self, *args, **kwargs):
        return Anything()

    def __format__(self, spec):
        return "0"

    def _other(self, other):
        return Anything()

    __truediv__ = __rtruediv__ = __mul__ = __rmul__ = __add__ = __radd__ = __sub__ = __rsub__ = _other

    def _no(self, other):
        return False

    __lt__ = __le__ = __gt__ = __ge__ = _no


def _commands(group=ROOT, prefix=()):
    """(name, command) of every command and group under ``group``, groups too (their own options)."""
    yield " ".join(prefix), group
    for name, command in group.commands.items():
        if hasattr(command, "commands"):
            yield from _commands(command, (*prefix, name))
        else:
            yield " ".join((*prefix, name)), command


def _shown(command) -> list:
    """The parameters ``--help`` shows, ``--help`` included."""
    return [p for p in command.get_params(typer.Context(command)) if not getattr(p, "hidden", False)]


def _long(param) -> str:
    return next((o for o in param.opts if o.startswith("--")), param.opts[0])


COMMANDS = dict(_commands())

CASES = [
    (name, _long(param))
    for name, command in _commands()
    for param in _shown(command)
    if param.param_type_name == "option" and _long(param) not in BEFORE_THE_COMMAND
]


def test_every_command_has_its_options_here():
    """Every leaf command is walked, and the exception table holds only options that act before it runs."""
    names = {name for name, command in _commands() if not hasattr(command, "commands")}
    assert {"fit", "render", "acquire planar", "import object", "view", "info"} <= names
    assert {name for name, _ in CASES} == names  # a group has no option of its own but --help
    for _, command in _commands():
        for param in _shown(command):
            if param.param_type_name == "option" and _long(param) in BEFORE_THE_COMMAND:
                assert param.is_eager, f"{_long(param)} is not eager: it belongs in a test case"


# -- the command run with its library function recorded -------------------------------------------------
@functools.cache
def _library_functions(name: str) -> list[tuple[object, str]]:
    """(module, name) of each library function the command ``name``'s body imports (``from ..workflow.x
    import f``; constants it imports beside them are not functions)."""
    function = inspect.unwrap(COMMANDS[name].callback)
    tree = ast.parse(textwrap.dedent(inspect.getsource(function)))
    package = function.__module__.rpartition(".")[0]
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.level >= 2:  # outside the cli package: the library
            module = importlib.import_module(
                importlib.util.resolve_name("." * node.level + node.module, package)
            )
            found += [(module, a.name) for a in node.names if inspect.isfunction(getattr(module, a.name))]
    assert found, f"{function.__module__}.{function.__name__} imports no library function in its body"
    return found


def _plain(value):
    """A value as comparable data: paths as text, a reporter as its type and fields."""
    if value is None or isinstance(value, (str, int, float, bool)):
        return value
    if isinstance(value, Path):
        return str(value)
    if isinstance(value, (list, tuple)):
        return tuple(_plain(v) for v in value)
    if isinstance(value, dict):
        return tuple(sorted((str(k), _plain(v)) for k, v in value.items()))
    if hasattr(value, "__dict__"):
        return (type(value).__name__, _plain(vars(value)))
    return repr(value)


class _Recorded:
    """The command ``name`` runnable with its library functions replaced by recorders."""

    runner = CliRunner()

    def __init__(self, name, command, monkeypatch, folder):
        self.name, self.command, self.tmp = name, command, folder
        self.calls: list = []
        for module, function in _library_functions(name):
            recorder = self._recorder(f"{module.__name__}.{function}", getattr(module, function))
            monkeypatch.setattr(module, function, recorder)

    def _recorder(self, qualified, function):
        signature = inspect.signature(function)

        def recorder(*args, **kwargs):
            try:  # a keyword the function does not take is an option mapped to nothing
                bound = signature.bind(*args, **kwargs)
            except TypeError as exc:
                raise AssertionError(f"translucency {self.name} calls {qualified} wrongly: {exc}") from None
            arguments = dict(bound.arguments)
            for p in signature.parameters.values():  # **setup: its keywords as the function's own
                if p.kind is p.VAR_KEYWORD:
                    arguments.update(arguments.pop(p.name, {}))
            self.calls.append((qualified, {k: _plain(v) for k, v in sorted(arguments.items())}))
            return Anything()

        return recorder

    def run(self, words: list[str]):
        """The calls of the library and what the command printed, for the command line ``words``.

        The command object is built once (``CliRunner.invoke`` would build it again for every run) and run
        in the runner's isolation: stdout and stderr captured, an exception raised as it is."""
        self.calls.clear()
        argv = [*self.name.split(), *words]
        with self.runner.isolation() as (stdout, stderr, _):
            try:
                ROOT.main(args=argv, prog_name="translucency")
            except SystemExit as exit:
                code = exit.code
            sys.stdout.flush()
            sys.stderr.flush()
            printed, said = stdout.getvalue().decode(), stderr.getvalue().decode()
        assert code == 0, f"translucency {' '.join(argv)}: exit {code}\n{said}"
        assert self.calls, f"translucency {' '.join(argv)} called none of its library functions"
        return list(self.calls), printed

    def word(self, text: str) -> str:
        return text.format(tmp=self.tmp)

    def base(self) -> list[tuple[str, list[str]]]:
        """Record A's command line as (option or "", its words): the arguments (each a path, the only
        kind the commands take), the required options, and :data:`BASE`'s."""
        line = []
        for param in self.command.params:
            if param.param_type_name == "argument":
                line.append(("", [str(self._path(param, param.name))]))
            elif param.required:
                line.append((_long(param), self._words(param, _base_value(param, self))))
        extra = [self.word(w) for w in BASE.get(self.name, [])]
        for i in range(0, len(extra), 2):
            line.append((extra[i], [extra[i + 1]]))
        return line

    def _path(self, param, name: str) -> Path:
        """A path under the test's folder; one that must exist is made (a file, or a folder)."""
        path = self.tmp / name
        info = param.type_descriptor.parameter_info
        if getattr(info, "exists", False):
            if getattr(info, "file_okay", True):
                path.touch()
            else:
                path.mkdir(exist_ok=True)
        return path

    @staticmethod
    def _words(param, value) -> list[str]:
        return [str(v) for v in value] if isinstance(value, (tuple, list)) else [str(value)]


def _base_value(param, recorded: _Recorded):
    """A required option's value (the commands' are paths)."""
    return recorded._path(param, param.name)


def _kinds(param) -> tuple[type, int | None]:
    """The type of one value of ``param`` and, for a tuple, its length."""
    annotation = param.type_descriptor.annotation
    args = typing.get_args(annotation)
    if typing.get_origin(annotation) is list:
        return args[0], None
    if typing.get_origin(annotation) is tuple:
        return args[0], len(args)
    return annotation, None


def _other_number(kind: type, default, param):
    """A number other than ``default`` within the option's range."""
    low, high = getattr(param, "min", None), getattr(param, "max", None)
    if kind is int:
        value = 2 if default is None else default + 1
        if high is not None and value > high:
            value = default - 1
    else:
        value = 1.5 if default is None else (0.5 if default == 0 else 1.5 * default)
    assert (low is None or value >= low) and (high is None or value <= high), (param.name, value)
    return value


def _other_value(param, recorded: _Recorded) -> list[str]:
    """The command-line words of ``param`` set to a value other than its default."""
    option = _long(param)
    if getattr(param, "is_flag", False):
        if param.default:  # --reentry/--no-reentry, default on: the off switch
            assert param.secondary_opts, f"{option}: a flag on by default needs an off switch"
            return [param.secondary_opts[0]]
        return [option]
    if option in VALUES:
        return [option, recorded.word(VALUES[option])]
    descriptor = param.type_descriptor
    if descriptor.is_choice:
        return [option, str(next(c for c in descriptor.choices if c != param.default))]
    kind, arity = _kinds(param)
    if arity:  # a tuple: each number another
        return [option, *(str(_other_number(kind, d, param)) for d in param.default)]
    if isinstance(kind, type) and issubclass(kind, Path):
        return [option, str(recorded._path(param, f"other-{param.name}"))]
    if kind in (int, float):
        default = None if param.multiple else param.default
        return [option, str(_other_number(kind, default, param))]
    return [option, "other"]  # a str outside VALUES: passed on as it is


def _line(base, without=()) -> list[str]:
    return [
        w for option, words in base if option not in without for w in ([option] if option else []) + words
    ]


#: an option whose library argument shares no word with it (every other one does: --terms → n_terms,
#: --exclusion → exclusion_mm, --chunk → chunk_points)
ARGUMENT = {
    "--material": "sample",  # the sample (a generator's name, or a --volume file)
    "--volume": "sample",
    "--model": "family",  # fit: the model family
    "--tilt": "angle",  # acquire planar: the scan's one beam tilted by this angle
    "--index-matched": "eta",  # acquire planar|mesh|object-photographs: eta=1
    "--dtype": ("dtype", "float16"),  # acquire and import: dtype; fit: float16=True
}


def _changed(calls_a, calls_b) -> set[str]:
    """The arguments whose values differ between two runs' calls (of the same functions)."""
    if [f for f, _ in calls_a] != [f for f, _ in calls_b]:
        return {f for f, _ in calls_b}  # another function: named by itself (render → render_scene)
    changed = set()
    for (_, a), (_, b) in zip(calls_a, calls_b):
        changed |= {k for k in {*a, *b} if a.get(k, "(not given)") != b.get(k, "(not given)")}
    return changed


def _named_alike(option: str, argument: str) -> bool:
    """Whether ``argument`` is the library's name for ``option``: a word in common, or :data:`ARGUMENT`."""
    words = {w.removesuffix("s") for w in option.lstrip("-").split("-")}  # --object → objects
    names = {w.removesuffix("s") for w in argument.rpartition(".")[2].split("_")}
    library = ARGUMENT.get(option, ())
    return argument in ((library,) if isinstance(library, str) else library) or bool(words & names)


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    """One folder for every run, so that record A of a command is the same for all its options."""
    return tmp_path_factory.mktemp("options")


#: record A of each command (the same in every test of its options)
_RECORD_A: dict = {}


@pytest.mark.parametrize("name,option", CASES, ids=[f"{n}:{o}" for n, o in CASES])
def test_the_option_reaches_the_library(name, option, monkeypatch, folder):
    command = COMMANDS[name]
    param = next(p for p in _shown(command) if _long(p) == option)
    recorded = _Recorded(name, command, monkeypatch, folder)
    base = recorded.base()
    if name not in _RECORD_A:
        _RECORD_A[name] = recorded.run(_line(base))
    calls_a, printed_a = _RECORD_A[name]
    # the option replaces its own value in record A's line (a required option), or the one it stands for
    words = _other_value(param, recorded)
    line = _line(base, without={*param.opts, INSTEAD_OF.get(option)}) + words
    calls_b, printed_b = recorded.run(line)
    if option in PRINTING:
        assert (calls_b, printed_b) != (calls_a, printed_a), (
            f"translucency {name} {' '.join(words)}: neither the reporter nor the printing changed"
        )
    else:
        assert calls_b != calls_a, (
            f"translucency {name} {' '.join(words)}: the library was called as without it: {calls_a}"
        )
        changed = _changed(calls_a, calls_b)
        assert any(_named_alike(option, argument) for argument in changed), (
            f"translucency {name} {' '.join(words)}: changed {sorted(changed)}, none of them its argument"
        )
    for short in (o for o in param.opts if not o.startswith("--")):  # -o, -n, -q: the same option
        aliased = [short if w == option else w for w in line]
        assert recorded.run(aliased) == (calls_b, printed_b), f"translucency {name}: {short} is not {option}"
