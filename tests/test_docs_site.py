"""The documentation site (mkdocs.yml, docs/): every page the navigation names is there and every page is
in it, the generated pages are current, the API reference covers the package's public names, no page
speaks of issue numbers, and every relative link of the pages and the README reaches a file (and, where
the target is a plain page, its heading).  ``make docs`` builds the site itself (mkdocs build --strict);
the slow test here does the same where mkdocs is installed."""

import doctest
import importlib
import os
import re
import subprocess
import sys
import unicodedata
from pathlib import Path

import pytest
from cli_reference import COMMAND, markdown

import translucency
from translucency.cli._common import PANEL_RUN

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
#: the site's own build helpers and the pages' generators under docs/ (mkdocs.yml's exclude_docs), not pages
NOT_PAGES = ("_ext", "_gen")
#: the most the gallery's pictures may weigh together, bytes
GALLERY_BYTES = 2_000_000


def nav_pages() -> list[str]:
    """The pages mkdocs.yml's navigation names, relative to docs/."""
    text = (ROOT / "mkdocs.yml").read_text()
    nav = text[text.index("\nnav:") :]
    return re.findall(r"^\s*-\s+(?:[^:\n]+:\s+)?(\S+\.md)\s*$", nav, flags=re.MULTILINE)


def pages() -> list[Path]:
    """Every Markdown page under docs/."""
    return sorted(p for p in DOCS.rglob("*.md") if p.relative_to(DOCS).parts[0] not in NOT_PAGES)


def _unfenced(text: str) -> str:
    """``text`` without its fenced code blocks."""
    return re.sub(r"^(```|~~~).*?^\1", "", text, flags=re.MULTILINE | re.DOTALL)


def _prose(text: str) -> str:
    """``text`` without its fenced code blocks and code spans (links there are examples, not links)."""
    return re.sub(r"`[^`\n]*`", "", _unfenced(text))


def links(path: Path) -> list[str]:
    """The relative link targets of a Markdown file (pictures included), without web and mail links."""
    found = re.findall(r"\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)", _prose(path.read_text()))
    return [t for t in found if not re.match(r"^[a-z][a-z0-9+.-]*:", t)]


def slug(heading: str) -> str:
    """A heading's anchor as mkdocs makes it (Python-Markdown's toc slugify)."""
    text = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", heading)  # a link: its text
    text = re.sub(r"[`*]|<[^>]+>", "", text)
    text = unicodedata.normalize("NFKD", text).encode("ascii", "ignore").decode("ascii")
    text = re.sub(r"[^\w\s-]", "", text).strip().lower()
    return re.sub(r"[-\s]+", "-", text)


def anchors(path: Path) -> set[str] | None:
    """The anchors of a plain page (its headings, explicit ``{#id}``, HTML ids); None for a page made by
    mkdocstrings (``:::``), whose anchors only the build knows."""
    text = _unfenced(path.read_text())
    if re.search(r"^::: ", text, flags=re.MULTILINE):
        return None
    found, seen = set(re.findall(r"\{#([\w.-]+)", text)) | set(re.findall(r"\bid=\"([^\"]+)\"", text)), {}
    for heading in re.findall(r"^#{1,6}\s+(.+?)\s*#*\s*$", text, flags=re.MULTILINE):
        base = slug(re.sub(r"\s*\{[^}]*\}\s*$", "", heading))
        count = seen.get(base, 0)
        seen[base] = count + 1
        found.add(base if count == 0 else f"{base}_{count}")
    return found


def broken(path: Path, root: Path) -> list[str]:
    """The links of ``path`` that reach no file under ``root`` or no heading of their page."""
    out, root = [], root.resolve()
    for target in links(path):
        file, _, anchor = target.partition("#")
        dest = (path.parent / file).resolve() if file else path
        if root not in dest.parents and dest != root:
            out.append(f"{target} (outside {root.name}/: not on the site)")
        elif not dest.exists():
            out.append(f"{target} (no such file)")
        elif anchor and dest.suffix == ".md" and (known := anchors(dest)) is not None and anchor not in known:
            out.append(f"{target} (no heading #{anchor} in {dest.name})")
    return out


def test_every_page_of_the_navigation_exists():
    named = nav_pages()
    assert len(named) > 20, "mkdocs.yml's nav not read"
    missing = [p for p in named if not (DOCS / p).is_file()]
    assert not missing, f"mkdocs.yml names pages that are not in docs/: {missing}"


def test_every_page_is_in_the_navigation():
    named = set(nav_pages())
    left_out = [str(p.relative_to(DOCS)) for p in pages() if str(p.relative_to(DOCS)) not in named]
    assert not left_out, f"pages in docs/ that mkdocs.yml's nav does not name: {left_out}"


def test_command_line_reference_is_current():
    """docs/reference/cli.md is written from the commands' help: regenerate it when an option changes."""
    page = DOCS / "reference" / "cli.md"
    assert page.read_text() == markdown(), f"run: {COMMAND}"


def test_command_line_reference_does_not_depend_on_the_terminal(monkeypatch):
    first = markdown()
    monkeypatch.setenv("COLUMNS", "40")
    monkeypatch.setenv("TERM", "dumb")
    assert markdown() == first


def test_command_line_reference_lists_every_command_and_option():
    """Each command's section has a row for each option --help shows, by name."""
    import typer.main  # only here: the test walks the commands itself

    from translucency.cli.app import app

    page = markdown()
    top = typer.main.get_command(app)
    stack = [(top, top.context_class(top, info_name="translucency"), "translucency")]
    commands = 0
    while stack:
        group, ctx, path = stack.pop()
        for name in group.list_commands(ctx):
            command = group.get_command(ctx, name)
            sub_ctx = command.context_class(command, info_name=name, parent=ctx)
            if hasattr(command, "commands"):
                stack.append((command, sub_ctx, f"{path} {name}"))
                continue
            commands += 1
            section = page.split(f"# {path} {name}\n", 1)[1].split("\n#", 1)[0]
            assert f"{path} {name} [OPTIONS]" in section
            for param in command.get_params(ctx):
                if param.name != "help" and not param.hidden and param.param_type_name == "option":
                    assert f"`{max(param.opts, key=len)}`" in section, f"{path} {name}: {param.opts}"
    assert commands >= 14


def test_command_line_reference_groups_the_options_as_help_does():
    """A command's options are under the panels of its --help: the essentials under Options first, the
    rest under their own headings, how it runs and prints (--quiet, --json, ...) under Run."""
    fit = markdown().split("## translucency fit\n", 1)[1].split("\n## ", 1)[0]
    assert fit.index("**Options**") < fit.index("**Model structure**") < fit.index(f"**{PANEL_RUN}**")
    options, run = fit.split("**Options**", 1)[1].split("\n**", 1)[0], fit.split(f"**{PANEL_RUN}**", 1)[1]
    assert "`--out`" in options and "`--terms`" not in options and "`--quiet`" not in options
    assert "`--quiet`" in run and "`--scheduler`" in run and "`--out`" not in run


@pytest.mark.parametrize("name", ["cli_reference", "json_schemas"])
def test_the_page_generators_examples_hold(name):
    """The examples of docs/_gen's generators run here (the doctests cover src/translucency alone)."""
    result = doctest.testmod(importlib.import_module(name), optionflags=doctest.ELLIPSIS)
    assert result.attempted and not result.failed, f"docs/_gen/{name}.py: {result.failed} examples failed"


def _api_targets() -> list[str]:
    return [
        target
        for page in sorted((DOCS / "reference" / "api").glob("*.md"))
        for target in re.findall(r"^::: ([\w.]+)\s*$", page.read_text(), flags=re.MULTILINE)
    ]


def _resolve(dotted: str):
    parts = dotted.split(".")
    for n in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:n]))
        except ImportError:
            continue
        for name in parts[n:]:
            obj = getattr(obj, name)
        return obj
    raise ImportError(dotted)


def test_api_reference_covers_every_public_name():
    """Every ``:::`` block of docs/reference/api names an object that exists, and together they hold every
    name of ``translucency.__all__``."""
    documented = []
    for target in _api_targets():
        try:
            documented.append(_resolve(target))
        except (ImportError, AttributeError) as exc:
            pytest.fail(f"docs/reference/api names {target}, which does not import ({exc})")
    missing = [
        name
        for name in translucency.__all__
        if name != "__version__" and not any(getattr(translucency, name) is obj for obj in documented)
    ]
    assert not missing, f"public names without a ::: block in docs/reference/api: {missing}"


def test_no_page_speaks_of_issue_numbers():
    offenders = [
        f"{path.relative_to(ROOT)}:{n}"
        for path in [ROOT / "README.md", *pages()]
        for n, line in enumerate(path.read_text().splitlines(), 1)
        if re.search(r"issue [0-9]", line, flags=re.IGNORECASE)
    ]
    assert not offenders, f"issue numbers a reader cannot open: {offenders}"


def test_links_of_the_pages_reach_their_files_and_headings():
    offenders = [f"{p.relative_to(ROOT)}: {b}" for p in pages() for b in broken(p, DOCS)]
    assert not offenders, "broken links:\n  " + "\n  ".join(offenders)


def test_links_of_the_readme_reach_their_files_and_headings():
    offenders = broken(ROOT / "README.md", ROOT)
    assert not offenders, "broken links in README.md:\n  " + "\n  ".join(offenders)


def test_link_check_finds_a_broken_link_and_a_missing_heading(tmp_path):
    """The checks above can fail: a page with a missing file, a missing heading and a link off the site."""
    (tmp_path / "docs").mkdir()
    (tmp_path / "docs" / "b.md").write_text("# B page\n\n## Its `part`\n")
    page = tmp_path / "docs" / "a.md"
    page.write_text(
        "# A\n[ok](b.md#its-part) [gone](c.md) [no heading](b.md#nothing) [off](../x.md) "
        "[web](https://example.org) `[code](d.md)`\n\n```\n[fenced](e.md)\n```\n"
    )
    (tmp_path / "x.md").write_text("")
    found = broken(page, tmp_path / "docs")
    assert [f.split(" ")[0] for f in found] == ["c.md", "b.md#nothing", "../x.md"]


def test_gallery_pictures_exist_and_stay_small():
    text = (DOCS / "gallery.md").read_text()
    assert "<!-- benchmarks/gallery.py: begin -->" in text and "<!-- benchmarks/gallery.py: end -->" in text
    shown = {DOCS / t for t in links(DOCS / "gallery.md") if t.startswith("gallery/")}
    assert shown, "the gallery shows no picture: python benchmarks/gallery.py RESULTS docs/gallery"
    assert all(p.is_file() for p in shown)
    weight = sum(p.stat().st_size for p in (DOCS / "gallery").glob("*.png"))
    assert weight <= GALLERY_BYTES, f"docs/gallery weighs {weight / 1e6:.2f} MB"


@pytest.mark.slow
def test_site_builds_without_a_warning(tmp_path):
    """mkdocs build --strict: any warning (a broken link or anchor, a page outside the nav, a docstring
    mkdocstrings cannot read) fails."""
    pytest.importorskip("mkdocs")
    pytest.importorskip("mkdocstrings")
    env = {**os.environ, "NO_MKDOCS_2_WARNING": "1"}
    cmd = [sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(tmp_path / "site")]
    done = subprocess.run(cmd, cwd=ROOT, env=env, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-4000:]
    assert (tmp_path / "site" / "reference" / "api" / "fit" / "index.html").is_file()
