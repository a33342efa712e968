"""A user's Mitsuba scene: read it (an XML file or a scene dict), its shapes by id and their triangles,
segments tested against it, and the same scene with media in place of chosen shapes (the reference).

Mitsuba's own messages for a file it cannot read are kept, with the file and line, on one line.  The
reference scene is the user's scene with each fitted shape replaced by a ``ply`` of the same triangles
holding a medium behind a given boundary, and the integrator replaced; for an XML file the document is
edited (:mod:`xml.etree.ElementTree`) and loaded with the file's folder first on Mitsuba's search path,
so that its relative paths still resolve; volumes travel as Mitsuba ``.vol`` files in a temporary folder.
"""

from __future__ import annotations

import copy
import re
import tempfile
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from .._validate import TranslucencyError
from ._engine import mitsuba
from .scenes import write_ply

#: Mitsuba plugin types whose XML tag is not the default ``bsdf`` — what :func:`_element` writes
_TAGS = {
    "heterogeneous": "medium",
    "homogeneous": "medium",
    "gridvolume": "volume",
    "constvolume": "volume",
    "hg": "phase",
    "isotropic": "phase",
    "ply": "shape",
    "obj": "shape",
    "volpath": "integrator",
    "path": "integrator",
}
#: integrator plugins a scene dict may hold (replaced in the reference)
_INTEGRATORS = {
    "path",
    "volpath",
    "volpathmis",
    "direct",
    "prb",
    "prbvolpath",
    "aov",
    "moment",
    "depth",
    "ptracer",
}


def _mitsuba_message(exc: Exception, source) -> str:
    """Mitsuba's message for a scene it could not load, on one line, without its C++ source location."""
    text = " ".join(str(exc).split())
    text = re.sub(r"\[[\w.]+:\d+\]\s*", "", text)
    return f"{source}: {text}" if str(source) not in text else text


def load_user_scene(source):
    """A Mitsuba scene from an XML file (path) or a scene dict; one line naming the file (and Mitsuba's
    line and column) where Mitsuba cannot read it."""
    mi = mitsuba()
    if isinstance(source, dict):
        try:
            return mi.load_dict(source)
        except RuntimeError as exc:  # Mitsuba's own message says what is wrong with the dict
            raise TranslucencyError(_mitsuba_message(exc, "scene dict")) from None
    path = Path(source)
    if not path.is_file():
        raise TranslucencyError(f"{path}: no such scene file")
    try:
        return mi.load_file(str(path))
    except RuntimeError as exc:  # a parse error or a plugin that failed: Mitsuba says where
        raise TranslucencyError(_mitsuba_message(exc, path)) from None


def shapes_by_id(scene) -> dict:
    """The scene's shapes by their ids (shapes without an id in the file get Mitsuba's generated one)."""
    return {shape.id(): shape for shape in scene.shapes()}


def mesh_buffers(shape) -> tuple[np.ndarray, np.ndarray]:
    """(vertices (V, 3), faces (F, 3)) of a Mitsuba mesh shape, in the scene's frame."""
    params = mitsuba().traverse(shape)
    vertices = np.asarray(params["vertex_positions"], dtype=np.float64).reshape(-1, 3)
    faces = np.asarray(params["faces"], dtype=np.int64).reshape(-1, 3)
    return vertices, faces


def segments_hit(scene, start: np.ndarray, end: np.ndarray, *, skip=(), margin: float = 1e-4) -> np.ndarray:
    """For segments start → end (N, 3): the index into ``scene.shapes()`` of a shape the open segment
    crosses, not one of ``skip`` (shapes), or −1; the ends' ``margin`` (relative to each length) is
    left out so that touching is not crossing."""
    mi = mitsuba()
    start, end = np.asarray(start, np.float64), np.asarray(end, np.float64)
    d = end - start
    length = np.linalg.norm(d, axis=1)
    keep = length > 0
    out = np.full(len(start), -1, dtype=np.int64)
    if not keep.any():
        return out
    shapes = scene.shapes()
    skip_ptrs = [mi.ShapePtr(s) for s in skip]
    skip_ids = {s.id() for s in skip}
    todo = np.flatnonzero(keep)
    o = start[todo] + d[todo] * margin
    w = d[todo] / length[todo, None]
    tmax = length[todo] * (1 - 2 * margin)
    for _ in range(8):  # past skipped shapes, a few times
        if len(todo) == 0:
            break
        ray = mi.Ray3f(
            mi.Point3f(*(o[:, j].astype(np.float32) for j in range(3))),
            mi.Vector3f(*(w[:, j].astype(np.float32) for j in range(3))),
        )
        ray.maxt = mi.Float(tmax.astype(np.float32))
        si = scene.ray_intersect(ray)
        valid = np.asarray(si.is_valid())
        skipped = np.zeros(len(todo), bool)
        for ptr in skip_ptrs:
            skipped |= np.asarray(si.shape == ptr)
        for k, shape in enumerate(shapes):
            if shape.id() in skip_ids:
                continue
            on = valid & ~skipped & np.asarray(si.shape == mi.ShapePtr(shape))
            out[todo[on]] = k
        t = np.asarray(si.t, np.float64)
        again = valid & skipped
        step = np.where(again, t + 1e-5 * np.maximum(length[todo], 1e-9), 0.0)
        o, tmax, todo, w = (o + w * step[:, None])[again], (tmax - step)[again], todo[again], w[again]
    return out


def _value_element(name: str, value, folder: Path) -> ET.Element:
    """One property of a plugin as Mitsuba XML (numbers, strings, booleans, transforms, tensors as .vol
    files, nested plugins)."""
    mi = mitsuba()
    if isinstance(value, dict):
        el = _element(value, folder)
        el.set("name", name)
        return el
    if isinstance(value, bool):
        return ET.Element("boolean", name=name, value="true" if value else "false")
    if isinstance(value, int):
        return ET.Element("integer", name=name, value=str(value))
    if isinstance(value, float):
        return ET.Element("float", name=name, value=repr(value))
    if isinstance(value, str):
        return ET.Element("string", name=name, value=value)
    if isinstance(value, mi.ScalarTransform4f):
        el = ET.Element("transform", name=name)
        m = np.asarray(value.matrix, dtype=np.float64).reshape(4, 4)
        ET.SubElement(el, "matrix", value=" ".join(repr(float(x)) for x in m.ravel()))
        return el
    if isinstance(value, mi.TensorXf):
        path = folder / f"grid{len(list(folder.glob('*.vol')))}.vol"
        mi.VolumeGrid(np.asarray(value, dtype=np.float32)).write(str(path))
        return ET.Element("string", name="filename", value=str(path))
    raise TypeError(f"no XML for {name}={value!r}")  # our own dicts only: a programming error


def _element(description: dict, folder: Path) -> ET.Element:
    kind = description["type"]
    el = ET.Element(_TAGS.get(kind, "bsdf"), type=kind)
    for key, value in description.items():
        if key != "type":
            el.append(_value_element(key, value, folder))
    return el


def user_scene_with_media(source, replace: dict, integrator: dict, frame=None):
    """The scene ``source`` (XML path or dict) with each shape id in ``replace`` swapped for a ``ply`` of
    the triangles ``replace[id]["mesh"]`` = (vertices, faces) in the scene's frame, holding
    ``replace[id]["interior"]`` (a medium dict) behind ``replace[id]["bsdf"]`` (a BSDF dict), and its
    integrator replaced by ``integrator``; loaded and returned.  With ``frame`` (a
    :class:`~.scene_frame.SceneFrame`) the user's scene is first carried into it, and ``replace``'s
    meshes and media are given in it."""
    mi = mitsuba()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        shapes = {}
        for key, what in replace.items():
            path = folder / f"{len(shapes)}.ply"
            write_ply(path, *what["mesh"])
            shapes[key] = {
                "type": "ply",
                "filename": str(path),
                "bsdf": what["bsdf"],
                "interior": what["interior"],
            }
        if isinstance(source, dict):
            scene = {
                k: v for k, v in source.items() if not (isinstance(v, dict) and v.get("type") in _INTEGRATORS)
            }
            scene = frame.dict(scene, keep=shapes) if frame is not None else copy.copy(scene)
            scene.update(shapes)
            scene["integrator"] = integrator
            return load_user_scene(scene)
        path = Path(source)
        try:  # Mitsuba reads more than XML allows (a "--" inside a comment); the rewrite needs real XML
            tree = ET.parse(path)
        except ET.ParseError as exc:
            raise TranslucencyError(
                f"{path}: not well-formed XML ({exc}); the reference rewrites the file"
            ) from None
        root = tree.getroot()
        for child in list(root):
            if child.tag == "integrator" or (child.tag == "shape" and child.get("id") in shapes):
                root.remove(child)
        if frame is not None:
            frame.xml(root, source=path)
        root.insert(0, _element(integrator, folder))
        for key, shape in shapes.items():
            el = _element(shape, folder)
            el.set("id", key)
            root.append(el)
        resolver = mi.file_resolver()
        before = [str(resolver[i]) for i in range(len(resolver))]
        resolver.prepend(str(path.resolve().parent))
        try:
            return mi.load_string(ET.tostring(root, encoding="unicode"))
        except RuntimeError as exc:  # what Mitsuba says of the edited scene, naming the user's file
            raise TranslucencyError(_mitsuba_message(exc, path)) from None
        finally:
            resolver.clear()
            for folder_before in before:
                resolver.append(folder_before)
