"""Every public function and class carries a runnable NumPy ``Examples`` section (issue item 6).

What counts as public (read dynamically, so that renames elsewhere need no edit here):

* the names in ``__all__`` of the top-level package and of each stage's package (:data:`SURFACES`);
* for a package or module of :data:`SURFACES` without ``__all__`` (``translucency.data``, ``.geometry``,
  ``.cluster``, ``.view``): its names without a leading underscore whose function or class is defined in
  that module itself;
* of those, only functions and classes (``lru_cache``'d functions included; a class counts by its own
  docstring, not an inherited one); constants, modules and instances are left out, and one object that
  several packages export (``fit_exponentials_batched`` from ``fit`` and ``solvers``) counts once.

A package or a lazy name that fails to import (its module being moved) is skipped with a warning that
names it.  At least :data:`MIN_SHARE` of what is left must have an ``Examples`` section holding a
``>>>`` line; the examples themselves run as doctests (``--doctest-modules``).  ``python
tests/test_examples.py`` prints the share per package and the names without one.
"""

import importlib
import inspect
import re
import sys
import types
import warnings

#: the packages (and top-level modules) whose public surface is counted
SURFACES = (
    "translucency",
    "translucency.model",
    "translucency.acquire",
    "translucency.fit",
    "translucency.fit.families",
    "translucency.evaluate",
    "translucency.render",
    "translucency.scene",
    "translucency.view",
    "translucency.rig",
    "translucency.io",
    "translucency.validate",
    "translucency.mitsuba",
    "translucency.solvers",
    "translucency.resources",
    "translucency.data",
    "translucency.pipeline",
    "translucency.geometry",
    "translucency.cluster",
    "translucency.workflow",
)

#: the least share of public functions and classes with a runnable example
MIN_SHARE = 0.80

_EXAMPLES = re.compile(r"^\s*Examples\s*\n\s*-{3,}\s*$", re.MULTILINE)


def _is_api(obj) -> bool:
    """A function (``lru_cache``'d ones too) or a class."""
    return inspect.isclass(obj) or inspect.isroutine(inspect.unwrap(obj))


def _public_names(module) -> list[str]:
    names = getattr(module, "__all__", None)
    if names is not None:
        return list(names)
    return [
        name
        for name, value in vars(module).items()
        if not name.startswith("_")
        and _is_api(value)
        and getattr(value, "__module__", None) == module.__name__
    ]


def has_example(obj) -> bool:
    """``obj``'s own docstring has a NumPy ``Examples`` section with at least one ``>>>`` line."""
    doc = inspect.cleandoc(obj.__doc__ or "")  # not inspect.getdoc: a class must not inherit its base's
    match = _EXAMPLES.search(doc)
    return match is not None and ">>>" in doc[match.end() :]


def public_surface(packages=SURFACES) -> tuple[dict[str, list[tuple[str, object]]], list[str]]:
    """``{package: [(name, object), ...]}`` of the public functions and classes, and what was skipped."""
    surface, skipped = {}, []
    for package in packages:
        try:
            module = importlib.import_module(package)
        except Exception as exc:  # noqa: BLE001 — a package being moved: skip it, say so
            skipped.append(f"{package}: not importable ({type(exc).__name__}: {exc})")
            continue
        entries = []
        for name in _public_names(module):
            try:
                obj = getattr(module, name)
            except Exception as exc:  # noqa: BLE001 — a lazy name whose module fails to import
                skipped.append(f"{package}.{name}: not importable ({type(exc).__name__}: {exc})")
                continue
            if _is_api(obj):
                entries.append((name, obj))
        surface[package] = entries
    return surface, skipped


def share(surface) -> tuple[int, int, list[str]]:
    """(with an example, counted, names without one) over distinct objects."""
    seen, done, missing = set(), 0, []
    for package, entries in surface.items():
        for name, obj in entries:
            if id(obj) in seen:
                continue
            seen.add(id(obj))
            if has_example(obj):
                done += 1
            else:
                missing.append(f"{package}.{name}")
    return done, len(seen), missing


def test_public_surface_has_examples():
    surface, skipped = public_surface()
    for message in skipped:
        warnings.warn(f"test_examples: skipped {message}", stacklevel=1)
    done, total, missing = share(surface)
    assert total, "no public functions or classes found"
    assert done / total >= MIN_SHARE, (
        f"only {done} of {total} ({done / total:.1%}) public functions and classes have an Examples section "
        f"with a >>> line (need {MIN_SHARE:.0%}); missing:\n  " + "\n  ".join(missing)
    )


def test_the_rule(monkeypatch):
    """What the count reads: ``__all__``, a lazy name that fails is skipped, a class's own docstring."""

    def documented():
        """Twice.

        Examples
        --------
        >>> 2 * 2
        4
        """

    def bare():
        """No example."""

    class Base:
        """A base.

        Examples
        --------
        >>> Base()  # doctest: +ELLIPSIS
        <...>
        """

    class Child(Base):
        pass

    fake = types.ModuleType("fake_surface")
    fake.__all__ = ["documented", "bare", "Base", "Child", "CONSTANT", "moved"]
    fake.documented, fake.bare, fake.Base, fake.Child, fake.CONSTANT = documented, bare, Base, Child, 3

    def lazy(name):
        raise ImportError(f"cannot import {name} (its module moved)")

    fake.__getattr__ = lazy
    monkeypatch.setitem(sys.modules, "fake_surface", fake)
    surface, skipped = public_surface(("fake_surface", "fake_surface_gone"))
    assert [name for name, _ in surface["fake_surface"]] == ["documented", "bare", "Base", "Child"]
    assert skipped[0].startswith("fake_surface.moved: not importable (ImportError")
    assert skipped[1].startswith("fake_surface_gone: not importable (ModuleNotFoundError")
    assert share(surface) == (2, 4, ["fake_surface.bare", "fake_surface.Child"])


if __name__ == "__main__":  # the share per package
    surface, skipped = public_surface()
    for message in skipped:
        print("skipped", message)
    for package, entries in surface.items():
        lacking = [name for name, obj in entries if not has_example(obj)]
        print(f"{package}: {len(entries) - len(lacking)}/{len(entries)}", " ".join(lacking))
    done, total, _ = share(surface)
    print(f"overall: {done}/{total} = {done / total:.1%} (distinct objects)")
