"""The page: one HTML file, the viewer's script and the model's data, opening from disk in any browser.

A browser reads no local file through ``fetch`` from a ``file://`` page, so the data travel as a script:
``data.js`` sets ``window.TL_DATA = {meta, arrays}``, every array base64 text with its dtype and shape.
:func:`page_files` gives the three files' text; :func:`write_page` writes them atomically into a folder
(the command claims the folder first: :mod:`translucency.io.outputs`).
"""

from __future__ import annotations

import base64
import json
from importlib import resources
from pathlib import Path

import numpy as np

from ..io.atomic import atomic_path

#: the page's files
PAGE, SCRIPT, DATA = "index.html", "viewer.js", "data.js"
_DTYPES = {
    "int8": np.int8,
    "float32": np.float32,
    "float16": np.float16,
    "uint32": np.uint32,
    "uint16": np.uint16,
    "uint8": np.uint8,
}


def static_text(name: str) -> str:
    """A file of the viewer shipped with the package (``view/static``)."""
    return resources.files("translucency.view").joinpath("static", name).read_text(encoding="utf-8")


def data_script(meta: dict, arrays: dict) -> str:
    """``window.TL_DATA = {meta, arrays}`` (:func:`data_json`): the page's data as a script."""
    return "window.TL_DATA = " + data_json(meta, arrays) + ";\n"


def data_json(meta: dict, arrays: dict) -> str:
    """``{meta, arrays}`` as JSON, each array as little-endian bytes in base64 with its dtype and shape."""
    out = {}
    for name, a in arrays.items():
        a = np.ascontiguousarray(a)
        dtype = a.dtype.name
        if dtype not in _DTYPES:
            raise ValueError(f"{name}: dtype {dtype} has no place on the page")
        out[name] = {
            "dtype": dtype,
            "shape": list(a.shape),
            "b64": base64.b64encode(a.astype(a.dtype.newbyteorder("<")).tobytes()).decode("ascii"),
        }
    return json.dumps({"meta": meta, "arrays": out}, separators=(",", ":"))


def page_html(title: str, data_src: str = DATA, script_src: str = SCRIPT) -> str:
    """The HTML page, naming its data and script files."""
    return (
        static_text("viewer.html")
        .replace("__TITLE__", _escape(title))
        .replace("__DATA_SCRIPTS__", f'<script src="{data_src}"></script>')
        .replace("__VIEWER_JS__", script_src)
    )


def page_files(meta: dict, arrays: dict) -> dict[str, bytes]:
    """The page's three files, by name."""
    return {
        PAGE: page_html(meta.get("title", "model")).encode("utf-8"),
        SCRIPT: static_text("viewer.js").encode("utf-8"),
        DATA: data_script(meta, arrays).encode("ascii"),
    }


def write_page(folder, meta: dict, arrays: dict) -> dict[str, int]:
    """Write the page into ``folder`` (each file atomically); returns the files' sizes in bytes."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    sizes = {}
    for name, content in page_files(meta, arrays).items():
        with atomic_path(folder / name) as tmp:
            Path(tmp).write_bytes(content)
        sizes[name] = len(content)
    return sizes


def _escape(text: str) -> str:
    return text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")
