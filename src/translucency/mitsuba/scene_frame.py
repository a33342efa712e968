r"""A user's scene carried into millimetres around its fitted objects: the frame the reference is traced in.

Mitsuba moves every ray it spawns from a surface off that surface by
:math:`(1 + \max_i |p_i|)\,\epsilon` scene units (ε = :data:`RAY_EPSILON`, single precision).  In a scene
written in metres that is 0.09 mm of the object, whatever its size; in a millimetre scene whose object
sits a metre from the origin, the same.  ``volpath`` then skips the first 0.09 mm of a medium behind a
``null`` boundary (skin's blue loses ~10 % of an optical depth: the picture turns brown), and a shadow
ray restarted past a boundary keeps its old length and overshoots into a nearby area lamp, which then
shadows itself (80 % of its light lost).  Our own renderer does not trace through the medium, so only
the reference depends on the scene's unit.

The reference is therefore traced in the frame :math:`x' = k\,(x - c)` — k millimetres a scene unit, c the
centre of the fitted objects' boxes — where the offset is that of a millimetre scene at the origin.  The
similarity :math:`M = S_k T_{-c}` carries every length:

* shapes, instances and the user's own volumes: ``to_world`` ← M · ``to_world`` (an analytic shape's
  centre, radius and ends live inside its ``to_world``);
* sensors, spots and points (rigid frames; Mitsuba refuses a scaled camera): ← M · ``to_world`` ·
  :math:`S_{1/k}`, an orthographic camera M · ``to_world`` (its scale is its extent); near and far clip,
  focus distance and aperture radius × k; a point's ``position`` ← M position;
* a point's or spot's intensity × k² (the same irradiance per mm² at k times the distance);
* the user's own media: ``scale`` × 1/k (their coefficients are per scene unit);
* area emitters' radiance, directional lights, environment maps: unchanged (radiance does not depend on the
  frame, and M turns nothing).

The picture is the same picture; only the numbers Mitsuba traces with change.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np

from .._validate import TranslucencyError
from ._engine import mitsuba

#: Mitsuba's relative ray offset in single precision (``math::RayEpsilon<float>``)
RAY_EPSILON = 8.940697e-5
#: sensor plugins (all rigid but the orthographic camera, whose scale is its extent)
_SENSORS = {"perspective", "thinlens", "radiancemeter", "orthographic"}
#: emitters whose frame and intensity carry lengths
_POINT_LIKE = {"point", "spot", "projector"}
#: emitters with nothing to carry
_FRAMELESS = {"area", "directional", "envmap", "constant", "sunsky", "directionalarea"}
#: sensor lengths (name, Mitsuba's default in scene units or None)
_SENSOR_LENGTHS = (
    ("near_clip", 1e-2),
    ("far_clip", 1e4),
    ("focus_distance", None),
    ("aperture_radius", None),
)
#: top-level plugins that hold no length
_LENGTHLESS = {"bsdf", "texture", "integrator", "sampler", "film", "rfilter", "phase", "spectrum", "rgb"}


class SceneFrame:
    r"""The similarity :math:`x' = k\,(x - c)` into millimetres around ``centre`` (module docstring), and
    what it does to a scene's XML document or dict.

    Parameters
    ----------
    unit_mm : float
        k, millimetres a scene unit.
    centre : array_like, shape (3,)
        c, scene units.

    Examples
    --------
    >>> frame = SceneFrame(1000.0, [0.0, 0.0, 1.0])   # a scene in metres, the object 1 m up
    >>> frame.points([[0.0, 0.0, 1.015]]).round(6).tolist()
    [[0.0, 0.0, 15.0]]
    """

    def __init__(self, unit_mm: float, centre):
        self.k = float(unit_mm)
        self.c = np.asarray(centre, dtype=np.float64).reshape(3)

    @property
    def matrix(self) -> np.ndarray:
        """M (4 × 4)."""
        M = np.diag([self.k, self.k, self.k, 1.0])
        M[:3, 3] = -self.k * self.c
        return M

    def points(self, x) -> np.ndarray:
        """Points (N, 3) carried into the frame, mm."""
        return self.k * (np.asarray(x, dtype=np.float64) - self.c)

    # -- an XML document ---------------------------------------------------------------------------
    def xml(self, root: ET.Element, *, source="scene") -> ET.Element:
        """The scene document ``root`` carried into the frame, in place (and returned); ``source`` names
        the file in the one line for a length we cannot carry (a ``$parameter``)."""
        for el in list(root):
            kind = el.get("type", "")
            if el.tag == "sensor":
                self._xml_frame(el, rigid=kind != "orthographic", source=source)
                named = {c.get("name"): c for c in el if c.tag == "float"}
                for name, default in _SENSOR_LENGTHS:
                    if name in named:
                        _times(named[name], self.k, source)
                    elif default is not None:
                        ET.SubElement(el, "float", name=name, value=repr(default * self.k))
            elif el.tag == "emitter" and kind in _POINT_LIKE:
                for c in el:
                    if c.get("name") == "intensity":
                        _times(c, self.k**2, source)
                    elif c.get("name") == "position":
                        self._xml_point(c, source)
                if any(c.tag == "transform" for c in el) or kind != "point":
                    self._xml_frame(el, rigid=True, source=source)
            elif el.tag == "emitter" and kind not in _FRAMELESS:
                raise TranslucencyError(f"{source}: emitter '{kind}' cannot be carried into millimetres")
            elif el.tag == "shape" and kind != "shapegroup":
                self._xml_frame(el, rigid=False, source=source)
            if el.tag not in _LENGTHLESS:
                self._xml_media(el, source)
        return root

    def _xml_frame(self, el, *, rigid: bool, source) -> None:
        """``to_world`` ← M · to_world (· S_{1/k} for a rigid frame); one is made where there is none."""
        t = next((c for c in el if c.tag == "transform" and c.get("name") == "to_world"), None)
        if t is None:
            t = ET.SubElement(el, "transform", name="to_world")
        if rigid:  # the first element acts first (rightmost)
            t.insert(0, ET.Element("scale", value=repr(1.0 / self.k)))
        x, y, z = (-self.c).tolist()
        t.append(ET.Element("translate", x=repr(x), y=repr(y), z=repr(z)))
        t.append(ET.Element("scale", value=repr(self.k)))

    def _xml_point(self, el, source) -> None:
        if el.get("value") is not None:
            p = _numbers(el, source)
            el.set("value", ", ".join(repr(v) for v in self.points([p])[0]))
        else:
            p = [float(_checked(el.get(a, "0"), el, source)) for a in "xyz"]
            for a, v in zip("xyz", self.points([p])[0]):
                el.set(a, repr(float(v)))

    def _xml_media(self, el, source) -> None:
        """The user's own media nested anywhere below ``el``: coefficients per mm; their volumes placed."""
        for medium in el.iter("medium"):
            s = next((c for c in medium if c.get("name") == "scale"), None)
            if s is None:
                ET.SubElement(medium, "float", name="scale", value=repr(1.0 / self.k))
            else:
                _times(s, 1.0 / self.k, source)
            for volume in medium.iter("volume"):
                if any(c.tag == "transform" for c in volume):
                    self._xml_frame(volume, rigid=False, source=source)

    # -- a scene dict ------------------------------------------------------------------------------
    def dict(self, scene: dict, *, keep=()) -> dict:
        """A copy of the scene dict carried into the frame; the entries named in ``keep`` (replaced by the
        caller) are passed as they are.  A loaded Mitsuba object among the others is refused in one line."""
        mi = mitsuba()
        M = mi.ScalarTransform4f(self.matrix.tolist())
        S_inv = mi.ScalarTransform4f().scale(1.0 / self.k)
        out = {}
        for key, value in scene.items():
            if key in keep or not isinstance(value, dict):
                if key not in keep and isinstance(value, mi.Object):
                    raise TranslucencyError(
                        f"scene dict: '{key}' is a loaded Mitsuba object; the reference cannot carry it into "
                        "millimetres — give it as a plugin dict"
                    )
                out[key] = value
                continue
            value = dict(value)
            kind = value.get("type", "")
            T = value.get("to_world", mi.ScalarTransform4f())
            if kind in _SENSORS:
                value["to_world"] = M @ T @ (S_inv if kind != "orthographic" else mi.ScalarTransform4f())
                for name, default in _SENSOR_LENGTHS:
                    if name in value or default is not None:
                        value[name] = float(value.get(name, default)) * self.k
            elif kind in _POINT_LIKE:
                if "position" in value:
                    value["position"] = self.points([value["position"]])[0].tolist()
                else:
                    value["to_world"] = M @ T @ S_inv
                if "intensity" in value:
                    value["intensity"] = _scaled(value["intensity"], self.k**2)
            elif kind in _FRAMELESS or kind in _LENGTHLESS or kind in ("scene", "shapegroup"):
                pass
            elif kind in ("homogeneous", "heterogeneous"):
                value["scale"] = float(value.get("scale", 1.0)) / self.k
            else:  # a shape (analytic or a file), an instance
                value["to_world"] = M @ T
                for side in ("interior", "exterior"):
                    if isinstance(value.get(side), dict):
                        value[side] = {**value[side], "scale": float(value[side].get("scale", 1.0)) / self.k}
            out[key] = value
        return out


def _scaled(value, f: float):
    """An intensity (a number or an ``rgb``/``spectrum`` dict of a number or three) times f."""
    if isinstance(value, dict):
        v = value.get("value")
        return {**value, "value": (np.asarray(v, dtype=np.float64) * f).tolist()}
    return float(value) * f


def _checked(text: str, el, source) -> str:
    if text.strip().startswith("$"):
        raise TranslucencyError(
            f'{source}: <{el.tag} name="{el.get("name")}"> is the parameter {text.strip()}; the reference '
            "needs its value to carry it into millimetres (write the number)"
        )
    return text


def _numbers(el, source) -> list[float]:
    return [float(v) for v in _checked(el.get("value"), el, source).replace(",", " ").split()]


def _times(el, f: float, source) -> None:
    """An element's ``value`` (one number or several) times f, in place."""
    el.set("value", ", ".join(repr(v * f) for v in _numbers(el, source)))


__all__ = ["SceneFrame", "RAY_EPSILON"]
