"""A mkdocs hook (mkdocs.yml's ``hooks``): the site's mathematics as MathML, written when the site is built.

pymdownx.arithmatex marks the formulas of the pages and of the docstrings that mkdocstrings renders,
``\\( … \\)`` inline and ``\\[ … \\]`` displayed; this hook converts each one with latex2mathml and the
browser draws it (Chromium, Firefox and Safari render MathML themselves) in the font the site serves
(stylesheets/mathml.css): no script, no network.
A formula that does not convert, or that holds a command latex2mathml does not know (which it would
otherwise pass through as text), fails the build with one line naming the page and the formula.
"""

from __future__ import annotations

import html
import re

from latex2mathml.converter import convert
from mkdocs.exceptions import PluginError

#: arithmatex's generic output: the TeX, HTML-escaped, between its delimiters, in a span or a div
FORMULA = re.compile(
    r'<(?P<tag>span|div) class="arithmatex">\s*'
    r"(?:\\\((?P<inline>.*?)\\\)|\\\[(?P<block>.*?)\\\])\s*</(?P=tag)>",
    re.S,
)
#: a backslash left in the MathML's text: a TeX command latex2mathml passed through unconverted
UNCONVERTED = re.compile(r">([^<]*\\[^<]*)<")
#: an inline formula in plain text (a heading's title in the table of contents)
TEXT = re.compile(r"\\\((.*?)\\\)", re.S)
#: TeX's spacing where the browser's operator dictionary differs: ``/`` and ``|`` are ordinary symbols
#: (``1/|d|``, no space around them)
ORDINARY = re.compile(r'<mo( stretchy="false")?>(&#x0002F;|/|&#x0007C;|\||&#x02016;)</mo>')
#: a closing bracket, as latex2mathml writes it: ) ] } | ‖ ⟩
CLOSING = r"&#x00029;|\)|&#x0005D;|\]|&#x0007D;|\}|&#x0007C;|\||&#x02016;|&#x027E9;"
#: a minus or plus that follows an operator, an opening bracket, a relation or a comma is a sign
#: (``(-\pi, \pi]``, ``= -x``): no space after it; after a closing bracket it stays binary (``f(x) - 1``)
SIGN = re.compile(rf"(<mo(?: [^>]*)?>(?!(?:{CLOSING})</mo>)[^<]*</mo>)<mo>(&#x02212;|&#x0002B;)</mo>")
#: an operator name (``\max``, ``\operatorname{erf}``): no space before it, a thin one after (``\max(0, x)``)
NAMED = re.compile(r'<mo( movablelimits="true")?>([A-Za-z]{2,})</mo>')
#: a function name (``\log``, ``\exp``) before its argument: TeX's thin space between them (``\log x``)
FUNCTION = re.compile(r"(<mi>[A-Za-z]{2,}</mi>)(?=<mi|<mn)")
#: a prime as a superscript (``\sigma_s'``, ``f'``): the font's prime is drawn raised already, so
#: stylesheets/mathml.css lowers it (class "prime") back to where TeX puts it
PRIME = re.compile(r"<mi>(&#x02032;|&#x02033;|&#x02034;)</mi>(?=(?:</mrow>)?</msu(?:p|bsup)>)")
#: ``\sim``, which latex2mathml writes as an ASCII tilde: the relation ∼
SIM = "<mi>&#x0007E;</mi>"


def tex_spacing(mathml: str) -> str:
    """``mathml`` (latex2mathml's) spaced as TeX would, where the browser's operator dictionary differs."""
    mathml = ORDINARY.sub(r'<mo\1 lspace="0em" rspace="0em">\2</mo>', mathml)
    mathml = SIGN.sub(r'\1<mo lspace="0em" rspace="0em">\2</mo>', mathml)
    mathml = NAMED.sub(r'<mo\1 lspace="0em" rspace="0.1667em">\2</mo>', mathml)
    mathml = PRIME.sub(r'<mi class="prime">\1</mi>', mathml.replace(SIM, "<mo>&#x0223C;</mo>"))
    return FUNCTION.sub(r'\1<mspace width="0.1667em" />', mathml)


def mathml(tex: str, *, display: str = "inline") -> str:
    """``tex`` (plain TeX, not HTML-escaped) as a ``<math>`` element; ValueError when it does not convert."""
    try:
        out = convert(tex.strip(), display=display)
    except Exception as e:  # noqa: BLE001 (latex2mathml raises its own errors, and IndexError on bad input)
        raise ValueError(f"{type(e).__name__}: {e}".rstrip(": ")) from None
    left = UNCONVERTED.search(out)
    if left:
        raise ValueError(f"unknown command {left[1].strip()!r}")
    return tex_spacing(out)


def _toc(items):
    for item in items:
        yield item
        yield from _toc(item.children)


def on_page_content(html_text: str, page, **kwargs) -> str:
    """Each arithmatex formula of the page converted to MathML (the search index then holds its text)."""

    def one(m: re.Match) -> str:
        display = "inline" if m["inline"] is not None else "block"
        tex = html.unescape(m["inline"] if m["inline"] is not None else m["block"])
        try:
            return f'<{m["tag"]} class="arithmatex">{mathml(tex, display=display)}</{m["tag"]}>'
        except ValueError as e:
            raise PluginError(f"{page.file.src_uri}: the formula {tex.strip()!r} has no MathML: {e}") from e

    out = FORMULA.sub(one, html_text)
    for item in _toc(page.toc or []):  # a heading's formulas in the table of contents (its plain text)
        try:
            item.title = TEXT.sub(lambda m: mathml(html.unescape(m[1])), item.title)
        except ValueError as e:
            raise PluginError(f"{page.file.src_uri}: the heading {item.title!r} has no MathML: {e}") from None
    stray = re.search(r'class="arithmatex">\s*\\[(\[]', out)
    if stray:
        left = out[stray.start() : stray.end() + 60]
        raise PluginError(f"{page.file.src_uri}: a formula left unconverted: {left!r}")
    return out
