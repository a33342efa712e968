"""Few public examples are skipped: every other one runs as a doctest (``--doctest-modules``) on the data the
package ships (``translucency.data``: the embedded scan, ``examples/``), so a reader can paste it.

A docstring may skip (``# doctest: +SKIP``) only an example that takes minutes; :data:`BUDGET` bounds how
many public docstrings in ``src/translucency`` do (the command line's modules hold help text, not examples,
and are left out).  A public docstring: a module's, or a function's or class's whose name and enclosing
names have no leading underscore.
"""

import ast
import re
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src" / "translucency"

#: the most public docstrings that may hold a skipped example
BUDGET = 10

_SKIP = re.compile(r"#\s*doctest:.*\+SKIP")


def skipped_docstrings(root: Path = SRC) -> dict[str, int]:
    """``{"module.path:Qualified.name": skipped example lines}`` of the public docstrings under ``root``."""
    found = {}
    for path in sorted(root.rglob("*.py")):
        rel = path.relative_to(root)
        if rel.parts[0] == "cli":
            continue
        module = ".".join(("translucency", *rel.with_suffix("").parts)).removesuffix(".__init__")

        def visit(node, names, module=module):
            doc = ast.get_docstring(node, clean=False) if not isinstance(node, ast.Assign) else None
            if doc and not any(n.startswith("_") for n in names):
                count = sum(1 for line in doc.splitlines() if _SKIP.search(line))
                if count:
                    found[f"{module}:{'.'.join(names) or '(module)'}"] = count
            for child in getattr(node, "body", []):
                if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                    visit(child, [*names, child.name])

        visit(ast.parse(path.read_text(encoding="utf-8")), [])
    return found


def test_few_public_examples_are_skipped():
    found = skipped_docstrings()
    listed = "\n".join(f"  {name}: {n} line(s)" for name, n in sorted(found.items()))
    assert len(found) <= BUDGET, (
        f"{len(found)} public docstrings skip examples (at most {BUDGET}); make them run on the shipped "
        f"data (translucency.data, examples/spot_coarse.model.zip) or smaller:\n{listed}"
    )


def test_the_count_reads_public_docstrings_only(tmp_path):
    pkg = tmp_path / "pkg"
    (pkg / "cli").mkdir(parents=True)
    (pkg / "cli" / "app.py").write_text('def f():\n    """>>> f()  # doctest: +SKIP"""\n')
    (pkg / "mod.py").write_text(
        '"""Module.\n\n>>> 1  # doctest: +SKIP\n"""\n\n'
        "class A:\n"
        '    """>>> A()  # doctest: +SKIP\n    >>> 2  # doctest: +ELLIPSIS +SKIP\n    """\n\n'
        "    def _hidden(self):\n"
        '        """>>> 3  # doctest: +SKIP"""\n\n'
        "def _private():\n"
        '    """>>> 4  # doctest: +SKIP"""\n\n'
        "def runs():\n"
        '    """>>> 5\n    5\n    """\n'
    )
    assert skipped_docstrings(pkg) == {"translucency.mod:(module)": 1, "translucency.mod:A": 2}
