"""The pages are for users of the installed package: they name no source file.

A module is named as it is imported (``translucency.io.mesh``, or the public function, linked to its API
reference), a test by what it checks ("the test suite checks that …"), a benchmark by "the benchmark of
this page" with a link to the page's section that reproduces the measurement.  The rule: no page under
docs/ (the generators' folders left out) shows a path ending in ``.py`` (``src/translucency/io/mesh.py``,
``io/mesh.py``, ``tests/test_x.py``, ``benchmarks/x.py``) except

* in a fenced code block of a section whose heading begins with "Reproducing" ("Reproducing these
  measurements", at the end of a page: the commands that reproduce a measurement from a source checkout,
  the section's text says so), at any depth below that heading, and
* in an HTML comment (``<!-- … -->``: not shown; the generators' markers and notes to whoever edits the
  page).

docs/architecture.md, the contributors' map of the code, follows the same rule: it names modules
(``translucency.fit.mesh``), which is enough there.  The pages the generators write (docs/json.md,
docs/reference/cli.md, docs/api.md's lists) follow it through their generators (docs/_gen), and the
sections a benchmark writes between its markers (accuracy.md, objects.md, gallery.md) through that
benchmark."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

DOCS = Path(__file__).resolve().parents[1] / "docs"
#: the site's build helpers and the pages' generators (mkdocs.yml's exclude_docs), not pages
NOT_PAGES = ("_ext", "_gen")
#: pages left out for now, to be emptied: their numbers are being rewritten, and their words after that
NOT_YET: set[str] = set()
#: a path that ends in .py (``benchmarks/x.py``, ``io/mesh.py``, ``mesh.py``, ``cli/*.py``)
PY_PATH = re.compile(r"[\w/.*…-]*[\w*]\.py\b")
#: a heading of a section where the fenced commands reproduce a measurement
REPRODUCING = re.compile(r"^reproduc", re.IGNORECASE)
#: an HTML comment
COMMENT = re.compile(r"<!--.*?-->", re.DOTALL)
#: a heading, and a fence's opening or closing line
HEADING = re.compile(r"^(#{1,6})\s+(.*?)\s*#*\s*$")
FENCE = re.compile(r"^\s*(`{3,}|~{3,})")


def pages() -> list[Path]:
    """Every Markdown page under docs/."""
    return sorted(p for p in DOCS.rglob("*.md") if p.relative_to(DOCS).parts[0] not in NOT_PAGES)


def source_files_named(text: str) -> list[tuple[int, str]]:
    """(line, path) of each path ending in ``.py`` that ``text`` shows outside the places allowed."""
    # comments blanked, their line breaks kept so that the line numbers stay the file's
    text = COMMENT.sub(lambda m: "\n" * m.group(0).count("\n"), text)
    found = []
    headings: list[tuple[int, str]] = []  # the open sections: (level, title)
    fence = None  # the open fence's marker
    for number, line in enumerate(text.splitlines(), 1):
        marker = FENCE.match(line)
        if fence is None and marker:
            fence = marker.group(1)
            continue
        if fence is not None:
            closing = marker and line.strip() == marker.group(1)
            if closing and marker.group(1)[0] == fence[0] and len(marker.group(1)) >= len(fence):
                fence = None
                continue
            if any(REPRODUCING.match(title) for _, title in headings):
                continue
        else:
            heading = HEADING.match(line)
            if heading:
                level = len(heading.group(1))
                headings = [(lv, t) for lv, t in headings if lv < level] + [(level, heading.group(2))]
                continue
        found += [(number, match.group(0)) for match in PY_PATH.finditer(line)]
    return found


def test_the_rule():
    """Prose, inline code and other sections' fences count; a Reproducing section's fences and comments
    do not; module names and ``.pyplot`` are no paths."""
    page = (
        "See `io/mesh.py` and `translucency.io.mesh`, matplotlib.pyplot, `cli/*.py`.\n"  # 1
        "<!-- benchmarks/x.py: begin -->\n"  # 2
        "```\npython benchmarks/a.py\n```\n"  # 3-5
        "## Reproducing these measurements\n\n"  # 6-7
        "From a source checkout, `benchmarks/b.py` reproduces it:\n\n"  # 8-9
        "### One case\n\n````\npython benchmarks/c.py\n"  # 10-13
        "```\nstill in the fence: benchmarks/d.py\n````\n"  # 14-16
        "## Next\n\n```\npython benchmarks/e.py\n```\n"  # 17-21
    )
    assert source_files_named(page) == [
        (1, "io/mesh.py"),
        (1, "cli/*.py"),
        (4, "benchmarks/a.py"),
        (8, "benchmarks/b.py"),
        (20, "benchmarks/e.py"),
    ]


@pytest.mark.parametrize("page", pages(), ids=lambda p: str(p.relative_to(DOCS)))
def test_pages_name_no_source_file(page):
    name = str(page.relative_to(DOCS))
    found = source_files_named(page.read_text())
    if name in NOT_YET:
        pytest.skip(f"{name}: left out for now ({len(found)} source files named)")
    lines = [f"{name}:{number}: {path}" for number, path in found]
    assert not lines, (
        "a page names a source file (name the module as imported, the test by what it checks, the "
        "benchmark in the page's 'Reproducing these measurements' section):\n" + "\n".join(lines)
    )


def test_the_pages_left_out_are_pages():
    """Each page of NOT_YET exists (a renamed or finished page leaves the list)."""
    assert all((DOCS / name).is_file() for name in NOT_YET)
