"""A Griffe extension for the site's API reference: what the docstrings write in reStructuredText, as
Markdown.  Sphinx roles (``:func:`~a.b```) become code (``b``); ``:math:`` becomes arithmatex's inline
mathematics; a definition list (a line holding only ``literals``, its description indented below) becomes
Markdown's (``def_list``); doctest directives are left out.  mkdocs.yml loads it (mkdocstrings'
``extensions``)."""

from __future__ import annotations

import re

import griffe

#: a Sphinx cross-reference role: :func:`target`, :class:`~a.b.C`, :mod:`.run`
ROLE = re.compile(
    r":(?:py:)?(?:func|class|mod|data|meth|attr|exc|obj|const):`(~?)\.?([^`<]+?)(?:\s*<[^>]*>)?`"
)
#: inline mathematics, :math:`\\vec x_i`, drawn as MathML (pymdownx.arithmatex, docs/_ext/mathml.py)
MATH = re.compile(r":math:`([^`]+)`")
#: a doctest directive at the end of an example's line (``# doctest: +SKIP``): the reader's copy goes without
DIRECTIVE = re.compile(r"[ \t]*# doctest:[^\n]*")
#: a definition list's term: literals only (``baselines.png``, ``a``, ``b``)
TERM = re.compile(r"^(\s*)``[^`]+``(?:\s*,\s*``[^`]+``)*\s*$")


def _indent(line: str) -> int:
    return len(line) - len(line.lstrip())


def definitions(text: str) -> str:
    """``text`` with each reStructuredText definition list written as Markdown's."""
    lines, out, i = text.splitlines(), [], 0
    while i < len(lines):
        term = TERM.match(lines[i])
        below = lines[i + 1] if i + 1 < len(lines) else ""
        if not term or not below.strip() or _indent(below) <= len(term[1]):
            out.append(lines[i])
            i += 1
            continue
        pad = term[1]
        if out and out[-1].strip():
            out.append("")
        out += [lines[i], f"{pad}:   {below.strip()}"]
        i += 2
        while i < len(lines) and lines[i].strip() and _indent(lines[i]) > len(pad):
            out.append(f"{pad}    {lines[i].strip()}")
            i += 1
        out.append("")
    return "\n".join(out)


def plain(text: str) -> str:
    """``text`` with each role replaced by a code span of its target (its last name under ``~``), and its
    mathematics marked for arithmatex (MathML: docs/_ext/mathml.py)."""
    text = MATH.sub(lambda m: f"\\({m[1]}\\)", text)
    return ROLE.sub(lambda m: f"`{m[2].rsplit('.', 1)[-1] if m[1] else m[2]}`", text)


class SphinxRoles(griffe.Extension):
    """Rewrites every docstring as it is loaded."""

    def on_instance(self, *, obj: griffe.Object, **kwargs) -> None:
        if obj.docstring is not None:
            obj.docstring.value = definitions(plain(DIRECTIVE.sub("", obj.docstring.value)))
