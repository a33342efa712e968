"""A Griffe extension for the site's API reference: the docstrings' Sphinx roles (``:func:`~a.b```) shown
as code (``b``), since Markdown has no roles.  mkdocs.yml loads it (mkdocstrings' ``extensions``)."""

from __future__ import annotations

import re

import griffe

#: a Sphinx cross-reference role: :func:`target`, :class:`~a.b.C`, :mod:`.run`
ROLE = re.compile(r":(?:py:)?(?:func|class|mod|data|meth|attr|exc|obj|const):`(~?)\.?([^`<]+?)(?:\s*<[^>]*>)?`")


def plain(text: str) -> str:
    """``text`` with each role replaced by a code span of its target (its last name under ``~``)."""
    return ROLE.sub(lambda m: f"`{m[2].rsplit('.', 1)[-1] if m[1] else m[2]}`", text)


class SphinxRoles(griffe.Extension):
    """Rewrites every docstring as it is loaded."""

    def on_instance(self, *, obj: griffe.Object, **kwargs) -> None:
        if obj.docstring is not None:
            obj.docstring.value = plain(obj.docstring.value)
