"""The site's measured numbers: every ``docs/*.json`` data file as a variable of the pages, and the
filters that format them (mkdocs-macros, ``module_name`` in mkdocs.yml).

A page writes ``{{ data.gallery.figure2.flip_mean_object | f3 }}`` where it would type ``0.080``: the number
lives in one data file, written by the script that measures it (each file's ``written_by`` or ``source``
names the command), and every page that states it reads it from there.  ``tests/test_docs_numbers.py``
fails when a page types a number that a data file holds.

Variables
    ``data.NAME``: the JSON of ``docs/NAME.json`` (``data.walked_transport``, ``data.accuracy`` …); keys
    that are not identifiers by subscript: ``data.accuracy["apple-slice"].default.rel_l2``.
Filters
    ``f1`` … ``f4`` (that many decimals: ``0.0801 | f3`` → ``0.080``), ``fmt(x, 3)`` (the same, as a
    function too), ``pct`` (per cent: ``0.1803 | pct`` → ``18.0``; ``pct(2)`` two decimals), ``sig(3)``
    (significant digits), ``times`` (a ratio: ``0.99 | times`` → ``0.99×``, ``21.4 | times(0)`` → ``21×``),
    ``thousands`` (``27370`` → ``27,370``), ``rfb`` (a row's relative RMSE / FLIP / brightness),
    ``slash`` (a vector: ``[0.86, 1.01, 1.21] | slash`` → ``0.86 / 1.01 / 1.21``).
Functions
    ``pick(rows, case="pig", transport="default")``: the one row of a list whose fields match.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

#: the folder of the pages and of their data files
DOCS = Path(__file__).resolve().parents[1]


def load_data(docs: Path = DOCS) -> dict:
    """Every ``docs/*.json`` data file, by its name without ``.json``.

    >>> data = load_data()
    >>> "walked_transport" in data and "accuracy" in data
    True
    """
    return {p.stem: json.loads(p.read_text()) for p in sorted(Path(docs).glob("*.json"))}


def fmt(x, decimals: int = 3) -> str:
    """``x`` with ``decimals`` decimals.

    >>> fmt(0.08012, 3), fmt(1.0, 2)
    ('0.080', '1.00')
    """
    return f"{float(x):.{decimals}f}"


def pct(x, decimals: int = 1) -> str:
    """``x`` (a fraction) in per cent, without the sign.

    >>> pct(0.18034), pct(0.05316, 2)
    ('18.0', '5.32')
    """
    return f"{100 * float(x):.{decimals}f}"


def sig(x, digits: int = 3) -> str:
    """``x`` to ``digits`` significant digits (trailing zeros kept).

    >>> sig(0.0801234), sig(21.43, 2), sig(1.0, 3)
    ('0.0801', '21', '1.00')
    """
    x = float(x)
    if x == 0:
        return f"{0:.{digits - 1}f}"
    decimals = max(digits - 1 - math.floor(math.log10(abs(x))), 0)
    return f"{x:.{decimals}f}"


def times(x, decimals: int = 2) -> str:
    """A ratio: ``x`` with ``decimals`` decimals and ×.

    >>> times(0.987), times(21.4, 0)
    ('0.99×', '21×')
    """
    return f"{float(x):.{decimals}f}×"


def thousands(x) -> str:
    """An integer with thousands separators.

    >>> thousands(27370)
    '27,370'
    """
    return f"{round(float(x)):,}"


def pick(rows, **match):
    """The one row of ``rows`` whose fields equal ``match``.

    >>> pick([{"case": "pig", "flip": 0.08}, {"case": "cow", "flip": 0.1}], case="pig")["flip"]
    0.08
    """
    found = [r for r in rows if all(r.get(k) == v for k, v in match.items())]
    if len(found) != 1:
        raise KeyError(f"{len(found)} rows match {match}")
    return found[0]


#: Jinja's comment delimiters on the pages (mkdocs.yml's j2_comment_*): attr_list's anchors are ``{#id}``
J2 = {"comment_start_string": "{##", "comment_end_string": "##}"}

def rfb(row) -> str:
    """A comparison's relative RMSE / FLIP / brightness, 3 decimals each (the pages' tables).

    >>> rfb({"rel_rmse": 0.0615, "flip": 0.0801, "brightness": 0.9971})
    '0.061 / 0.080 / 0.997'
    """
    return " / ".join(fmt(row[k]) for k in ("rel_rmse", "flip", "brightness"))


def slash(values, decimals: int = 2) -> str:
    """A vector (a hue, R / G / B) with ``decimals`` decimals.

    >>> slash([0.86, 1.01, 1.214])
    '0.86 / 1.01 / 1.21'
    """
    return " / ".join(fmt(v, decimals) for v in values)


FILTERS = {
    "fmt": fmt,
    "slash": slash,
    "rfb": rfb,
    "f1": lambda x: fmt(x, 1),
    "f2": lambda x: fmt(x, 2),
    "f3": lambda x: fmt(x, 3),
    "f4": lambda x: fmt(x, 4),
    "pct": pct,
    "sig": sig,
    "times": times,
    "thousands": thousands,
}


def define_env(env) -> None:
    """mkdocs-macros' hook: the data files as ``data``, the filters, ``fmt`` and ``pick`` as functions."""
    env.variables["data"] = load_data(Path(env.conf["docs_dir"]))
    for name, function in FILTERS.items():
        env.filter(function, name)
    env.macro(fmt, "fmt")
    env.macro(pick, "pick")
