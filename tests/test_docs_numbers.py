"""One fact, one number: a measured number on a page comes from a data file (``docs/*.json``) through a
mkdocs-macros expression (``{{ data.gallery.figure2.flip_mean_object | f3 }}``), never typed.

A number is looked for as pages write it: 2 to 4 decimals, 3 and 4 significant digits, per cent with one
or two decimals; literals of fewer than three digits past ``0.`` or of one significant digit (0.2, 1.5, 0.06,
0.004) and integers are left out, as they collide with ordinary prose.  What a page writes is read outside
``{{ … }}``, ``{% … %}``, fenced and inline code, HTML comments and the sections a benchmark script writes
between its markers.  A page (docs/, and README.md, which is not rendered and carries no measured number)
fails, page:line:number, where

* it types a number that an expression of any page reads from a data file (the facts the site states:
  every literal of them, alone), or
* one of its lines types two numbers of one record of a data file (a row copied: a relative RMSE and a
  FLIP of one case), one of them of three significant digits or more.  accuracy.json is left out of this
  rule: its band and noise breakdowns of seven samples (3,000 numbers of 0.0x) match almost any pair of
  planar errors by chance; its numbers reach the pages through benchmarks/accuracy_table.py's section.
"""

from __future__ import annotations

import collections
import importlib.util
import json
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"

#: a fenced code block (``` or ~~~, indented or not) to its closing fence
FENCE = re.compile(r"^([ \t]*)(`{3,}|~{3,})[^\n]*\n.*?^[ \t]*\2[ \t]*$", re.M | re.S)
#: a macros expression or statement, an HTML comment, inline code
SKIPPED = re.compile(r"\{\{.*?\}\}|\{%.*?%\}|<!--.*?-->|`[^`\n]+`", re.S)
#: a section a benchmark script writes between its markers (tables from the run it measured)
MARKED = re.compile(r"<!-- ([^\n]*?): begin -->.*?<!-- \1: end -->", re.S)
#: a decimal number as a page types it
NUMBER = re.compile(r"(?<![\w.])(\d+\.\d+)(?![\w]|\.\d)")
#: data files left out of the row rule (the module's docstring says why)
NOT_ROWS = {"accuracy.json"}

#: typed copies of a number a data file holds, not yet written as expressions (page → literals): the test
#: lets these pass and fails on any other, and on an entry the page no longer types (the list only shrinks)
PENDING: dict[str, set[str]] = {}

#: other measurements whose digits equal a number of a data file that an expression reads (page → literals),
#: not copies of it: a typed table of another run (the lean's 0.114 against the medium's 4–8 mm noise), a
#: time, a ratio, a range's end (validation/object-rig.md's energy ratios 1.01–1.29 against the unlit hues).
#: Each reading of a data file by an expression adds the pages' other numbers of its digits here; the test
#: fails on an entry the page no longer types as an offender, as for PENDING
COINCIDENT = {
    "docs/fitting.md": set("1.04 1.13 8.21 18.9".split()),
    "docs/glossary.md": set("0.998".split()),
    "docs/how-to/choose-a-model.md": set("48.2".split()),
    "docs/how-to/choose-a-transport.md": set("0.078 0.189 1.11 3.20".split()),
    "docs/how-to/run-on-a-cluster.md": set("1.76".split()),
    "docs/incidence.md": set("0.078 0.093 0.112 0.138 1.02 1.044 1.11 1.16".split()),
    "docs/lean.md": set(
        """
        0.041 0.043 0.044 0.051 0.053 0.063 0.075 0.079 0.095 0.097 0.114 0.131 0.150 0.161 0.193 0.201
        0.221 0.255 0.273 0.288 0.293 0.335 0.336 0.367 0.3680 0.390 0.448 0.475 0.482 0.756 0.899 0.900
        0.902 0.960 0.970 0.990 0.995 0.996 1.031 1.04 1.05 1.050 1.11 1.13 1.16 1.21 1.29 3.20
        """.split()
    ),
    "docs/near-field.md": set("0.061 0.063 0.078 0.082 0.114 0.138 0.211 0.970 1.031".split()),
    "docs/reference/object-rig.md": set("1.01 1.02".split()),
    "docs/reliability.md": set("1.04 1.10 11.2".split()),
    "docs/scaling.md": set("1.76 9.55 33.8".split()),
    "docs/scenes.md": set("0.053 0.061 0.075 0.096 0.112 0.114 0.254 1.007".split()),
    "docs/through-body.md": set(
        """
        0.061 0.062 0.075 0.088 0.096 0.097 0.112 0.130 0.161 0.169 0.189 0.221 0.223 0.273 0.286 0.293
        0.335 0.355 0.356 0.360 0.386 0.756 0.765 0.820 0.899 0.930 0.990 0.995 0.996 0.997 1.01 1.010 1.015
        1.02 1.031 1.04 1.042 1.05 1.09 1.10 1.21 1.22
        """.split()
    ),
    "docs/validation.md": set("0.043 0.169 0.286 0.980 0.994 1.003 1.01 1.05 21.1 36.8 76.1".split()),
    "docs/validation/object-rig.md": set(
        """
        0.032 0.041 0.050 0.075 0.131 0.211 0.221 0.229 0.386 0.388 0.998 1.01 1.02 1.03 1.04 1.05 1.09 1.10
        1.11 1.13 1.16 1.21 1.22 1.29 1.76
        """.split()
    ),
    "docs/validation/planar-rig.md": set("0.023 0.043 0.086 0.097 0.293".split()),
    "docs/viewer.md": set("0.048 0.095 0.096 0.138 16.9 18.5".split()),
}


def _numbers():
    """The site's numbers module (docs/_ext/numbers.py: the data files, the filters)."""
    spec = importlib.util.spec_from_file_location("docs_numbers", DOCS / "_ext" / "numbers.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def leaves(value, path="") -> list[tuple[str, float]]:
    """The numeric leaves of a JSON value with their paths; integers, booleans and vectors left out."""
    if isinstance(value, dict):
        return [leaf for k, v in value.items() for leaf in leaves(v, f"{path}.{k}")]
    if isinstance(value, list):
        if all(isinstance(v, (int, float)) for v in value):  # a vector (a hue, an estimate): no record
            return []
        return [leaf for i, v in enumerate(value) for leaf in leaves(v, f"{path}[{i}]")]
    if isinstance(value, float) and value == value and abs(value) != float("inf"):
        return [(path, value)]
    return []


def _kept(literal: str) -> bool:
    """Whether a literal is distinctive: three digits past a leading ``0.``, two significant ones."""
    digits = literal.removeprefix("0.").replace(".", "")
    round_number = literal.rstrip("0").endswith(".")  # 1.00, 2.000: ordinary prose
    return len(digits) >= 3 and len(digits.lstrip("0")) >= 2 and not round_number


def literals(value: float) -> set[str]:
    """The ways a page may type ``value``: 2–4 decimals, 3 and 4 significant digits, per cent."""
    sig = _numbers().sig
    v = abs(value)
    if v == 0 or v >= 1e6:
        return set()
    forms = {f"{v:.{d}f}" for d in (2, 3, 4)} | {sig(v, 3), sig(v, 4)}
    if v < 10:
        forms |= {f"{100 * v:.1f}", f"{100 * v:.2f}"}
    return {f for f in forms if "." in f and _kept(f)}


def _record(path: str) -> str:
    """The record a leaf belongs to: its path less the last key."""
    return re.sub(r"(\.[^.\[]+|\[\d+\])$", "", path)


class Known:
    """The data files' literals: those the pages' expressions read, and every record's."""

    def __init__(self, docs: Path = DOCS, read: dict[str, float] | None = None):
        self.read = {}  # literal → data path, for the leaves an expression reads
        for where, value in (read or {}).items():
            for lit in literals(value):
                self.read.setdefault(lit, where)
        self.records = collections.defaultdict(set)  # literal → records holding it
        for path in sorted(docs.glob("*.json")):
            if path.name in NOT_ROWS:
                continue
            for where, value in leaves(json.loads(path.read_text())):
                for lit in literals(value):
                    self.records[lit].add(f"{path.name}:{_record(where)}")

    def offenders(self, text: str) -> list[tuple[int, str, str]]:
        """(line, literal, why) for each number of ``text`` that a data file holds."""
        for pattern in (FENCE, MARKED, SKIPPED):
            text = pattern.sub(lambda m: re.sub(r"[^\n]", " ", m.group(0)), text)
        out = []
        for i, line in enumerate(text.split("\n"), 1):
            typed = [m.group(1) for m in NUMBER.finditer(line)]
            by_record = collections.defaultdict(set)
            for lit in typed:
                for record in self.records.get(lit, ()):
                    by_record[record].add(lit)
            rows = {r: lits for r, lits in by_record.items() if len(lits) >= 2 and max(map(_sig, lits)) >= 3}
            for lit in dict.fromkeys(typed):
                if lit in self.read:
                    out.append((i, lit, f"read by an expression: {self.read[lit]}"))
                else:
                    row = sorted(r for r, lits in rows.items() if lit in lits)
                    if row:
                        out.append((i, lit, f"a row of {row[0]}"))
        return out


def _sig(literal: str) -> int:
    return len(literal.replace(".", "").lstrip("0"))


class _Traced(dict):
    """A data file's dict that records the numbers read from it (path → value) as a page renders."""

    def __init__(self, value: dict, path: str, seen: dict):
        super().__init__(value)
        self._path, self._seen = path, seen

    def __getitem__(self, key):
        return _trace(dict.__getitem__(self, key), f"{self._path}.{key}", self._seen)

    def get(self, key, default=None):
        return self[key] if key in self else default

    def items(self):
        return [(k, self[k]) for k in self]

    def values(self):
        return [self[k] for k in self]


class _TracedList(list):
    def __init__(self, value: list, path: str, seen: dict):
        super().__init__(value)
        self._path, self._seen = path, seen

    def __getitem__(self, i):
        return _trace(list.__getitem__(self, i), f"{self._path}[{i}]", self._seen)

    def __iter__(self):
        return (self[i] for i in range(len(self)))


def _trace(value, path: str, seen: dict):
    if isinstance(value, dict):
        return _Traced(value, path, seen)
    if isinstance(value, list):
        return _TracedList(value, path, seen)
    if isinstance(value, float):
        seen[path] = value
    return value


def render(text: str, seen: dict | None = None, docs: Path = DOCS) -> str:
    """A page's Markdown as mkdocs-macros renders it (``data``, the site's filters, ``fmt``, ``pick``); the
    numbers its expressions read go into ``seen``."""
    jinja2 = pytest.importorskip("jinja2")
    numbers = _numbers()
    env = jinja2.Environment(undefined=jinja2.StrictUndefined, **numbers.J2)
    env.filters.update(numbers.FILTERS)
    data = _trace(numbers.load_data(docs), "data", {} if seen is None else seen)
    env.globals.update(fmt=numbers.fmt, pick=numbers.pick, data=data)
    return env.from_string(text).render()


def pages(docs: Path = DOCS, root: Path = ROOT) -> list[Path]:
    """The pages of the site and the README."""
    site = [p for p in sorted(docs.rglob("*.md")) if not p.relative_to(docs).parts[0].startswith("_")]
    return [*site, root / "README.md"]


def offences() -> dict[str, dict[str, list[str]]]:
    """Every page's typed numbers that a data file holds: page → literal → [(line, why)]."""
    seen = {}
    for page in pages()[:-1]:
        render(page.read_text(), seen)
    known = Known(read=seen)
    found = collections.defaultdict(lambda: collections.defaultdict(list))
    for page in pages():
        for line, lit, why in known.offenders(page.read_text()):
            found[str(page.relative_to(ROOT))][lit].append((line, why))
    return found


def stale(exempt: dict[str, set[str]], found: dict) -> list[str]:
    """The entries of ``exempt`` (page → literals) that their page no longer types as an offender."""
    gone = [f"{p}:{lit}" for p, lits in exempt.items() for lit in lits if lit not in found.get(p, ())]
    return sorted(gone)


def test_no_page_types_a_number_a_data_file_holds():
    found = offences()
    bad = [
        f"{page}:{line}:{lit} ({why})"
        for page, lits in found.items()
        for lit, wheres in lits.items()
        for line, why in wheres
        if lit not in PENDING.get(page, set()) | COINCIDENT.get(page, set())
    ]
    bad.sort(key=lambda s: (s.split(":")[0], int(s.split(":")[1])))
    why = "numbers typed on pages that a data file holds (write {{ data.… | f3 }}):\n"
    assert not bad, why + "\n".join(bad)


def test_every_exemption_is_still_needed():
    """PENDING and COINCIDENT only shrink: an entry whose page no longer types that number as an offender
    (written as an expression, reworded, or no longer equal to a number read) is taken off."""
    found = offences()
    gone = stale(PENDING, found) + stale(COINCIDENT, found)
    assert not gone, "take these off PENDING / COINCIDENT in tests/test_docs_numbers.py:\n" + "\n".join(gone)


def test_a_stale_exemption_is_caught():
    found = {"docs/a.md": {"0.080": [(3, "read by an expression: data.bench.pig.flip")]}}
    assert stale({"docs/a.md": {"0.080"}}, found) == []
    exempt = {"docs/a.md": {"0.080", "0.061"}, "docs/b.md": {"0.997"}}
    assert stale(exempt, found) == ["docs/a.md:0.061", "docs/b.md:0.997"]


def test_a_planted_number_is_caught(tmp_path):
    """The test of the test: a data file's number typed on a page (in prose, not in code or an expression)
    is caught alone once an expression reads it, and as a copied row otherwise."""
    docs = tmp_path / "docs"
    docs.mkdir()
    run = {"pig": {"flip": 0.08012, "rel_rmse": 0.06147, "brightness": 0.9971}}
    (docs / "bench.json").write_text(json.dumps({"source": "python benchmarks/x.py", **run}))
    page = (
        "# A page\n\nThe pig's FLIP is {{ data.bench.pig.flip | f3 }}.\n\n"
        "```sh\nflip 0.080 in a code block, `0.080` inline\n```\n\nTyped: FLIP 0.080 over the object.\n"
        "A row: 0.061 / 0.997, and 0.062 / 0.996 (no such row).\n"
    )
    seen = {}
    assert "FLIP is 0.080." in render(page, seen, docs)
    assert seen == {"data.bench.pig.flip": 0.08012}
    found = Known(docs, read=seen).offenders(page)
    assert [(line, lit) for line, lit, _ in found] == [(9, "0.080"), (10, "0.061"), (10, "0.997")]
    assert Known(docs).offenders("FLIP 0.080 over the object.") == []  # alone and not read: prose


def test_literals_leave_out_short_numbers():
    assert {"0.080", "8.01", "0.0801"} <= literals(0.08012)  # 3 decimals, per cent, 3 significant digits
    assert not literals(0.2) & {"0.2", "0.20"} and "1.5" not in literals(1.5)
    assert "1.00" not in literals(0.997) and "0.004" not in literals(0.0041)


def test_macros_render_a_page_from_its_data_file():
    """The gallery's caption and the home page's picture read the demo's FLIP from docs/gallery.json."""
    gallery = json.loads((DOCS / "gallery.json").read_text())
    flip = f"{gallery['figure2']['flip_mean_object']:.3f}"
    for name in ("gallery.md", "index.md"):
        text = (DOCS / name).read_text()
        assert "{{ data.gallery.figure2.flip_mean_object | f3 }}" in text, name
        assert "data.gallery.figure2.flip_mean_object" not in render(text), name
        assert flip in render(text), name


def test_every_page_renders():
    """Every expression of every page resolves (a wrong path fails here before ``make docs``)."""
    for page in pages()[:-1]:
        render(page.read_text())


def test_the_built_site_shows_the_data_file_values():
    """After ``make docs``: the gallery's page says the FLIP that docs/gallery.json holds."""
    built = ROOT / "build" / "site" / "gallery" / "index.html"
    data = DOCS / "gallery.json"
    if not built.is_file() or built.stat().st_mtime < data.stat().st_mtime:
        pytest.skip("no built site newer than docs/gallery.json (make docs)")
    gallery = json.loads(data.read_text())
    html = built.read_text()
    assert "data.gallery" not in html
    assert f"FLIP {gallery['figure2']['flip_mean_object']:.3f}" in html
