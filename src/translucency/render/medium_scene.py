r"""The estimated medium as a Mitsuba 3 scene a user can path-trace (``translucency export --mitsuba DIR``).

:func:`write_mitsuba_scene` writes into a folder:

``object.ply``
    The model's mesh (binary PLY, mm, the model's vertex order).
``sigma_t.vol``, ``albedo.vol``
    The medium (:meth:`Medium.volume <translucency.medium.estimate.Medium.volume>`: cubic voxels over the
    mesh's bounding box) as Mitsuba grid volumes, written by Mitsuba's own ``VolumeGrid.write``: the
    extinction :math:`\sigma_t = \sigma_s + \sigma_a` (mm⁻¹, RGB) and the single-scattering albedo
    :math:`\sigma_s / \sigma_t` (RGB).
``scene.xml``
    A Mitsuba 3 scene: a ``volpath`` integrator (no depth limit, no Russian roulette: the reference's),
    the shape with the ``heterogeneous`` medium inside it (Henyey–Greenstein phase with the estimate's
    g = 0, nearest-neighbour lookups as the walks read the grid) behind a ``null`` boundary
    (index-matched, η = 1: the estimate's) or a smooth ``dielectric`` one (η ≠ 1), and a default camera
    and light — ``translucency render``'s — so that ``mitsuba scene.xml`` renders the object on its own.
    ``$spp``, ``$resx`` and ``$resy`` are the scene's parameters (``mitsuba -Dspp=256 scene.xml``).

Placement: the grids' ``to_world`` is the one of the project's own volpath reference
(:func:`translucency.mitsuba.scenes.slab_medium_dict` at the top corner (lo.x, lo.y, hi.z)): voxel
[iz, iy, ix] of the Volume covers x in lo.x + [ix, ix + 1)·vox, y in lo.y + [iy, iy + 1)·vox and
z in hi.z − (iz + 1, iz]·vox (z index 0 at the top), and since Mitsuba's grids start at local z = 0 at the
bottom of the box, the grids are stored flipped in z.  The grids and their placement are taken from that
function itself, so the exported scene and the reference render (:func:`translucency.render.render_reference`)
cannot place the medium differently.  Units: mm, coefficients in mm⁻¹ (the medium's ``scale`` is 1).

The XML is written with :mod:`xml.etree` (Mitsuba 3.9 has no ``mitsuba.xml.dict_to_xml``; its parser's
writer, ``mi.parser.write_string``, stamps the file with the running version and keeps no comments):
``version="3.0.0"``, files
named relative to the scene (Mitsuba resolves them from the XML's folder), comments that say what to keep
and what to replace.  Every file is written atomically; the folder is an output folder of translucency
(:func:`translucency.io.outputs.claim_folder`): new or empty, or one it wrote before and only with
``overwrite``, where only these four files are replaced; a run that fails removes what it added.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from .._validate import TranslucencyError
from .._version import __version__
from ..io.atomic import atomic_path
from ..io.outputs import PLY_COMMENT, claim_folder, release_output
from ..medium.estimate import VOXELS, medium_of
from ..mitsuba.scenes import NO_ROULETTE

__all__ = ["FILES", "medium_or_refuse", "scene_volume", "write_mitsuba_scene"]

#: the files written into the folder, by role
FILES = {"scene": "scene.xml", "mesh": "object.ply", "sigma_t": "sigma_t.vol", "albedo": "albedo.vol"}
#: the scene's own defaults of its parameters ``$spp``, ``$resx``, ``$resy`` (``mitsuba -Dspp=...``)
DEFAULT_SPP = 64
DEFAULT_RESOLUTION = (320, 240)


def medium_or_refuse(model, name: str = "model"):
    """The :class:`~translucency.medium.estimate.Medium` ``model`` carries, or one line naming ``name``."""
    medium = medium_of(model)
    if medium is None:
        raise TranslucencyError(f"{name}: holds no estimated medium; fit it again with this version")
    return medium


def scene_volume(model, mesh, *, voxels: int = VOXELS, name: str = "model"):
    """The :class:`~translucency.acquire.volume.Volume` the scene holds: the model's medium over ``mesh``'s
    bounding box (:meth:`Medium.volume <translucency.medium.estimate.Medium.volume>`)."""
    return medium_or_refuse(model, name).volume(mesh, voxels=voxels)


def write_mitsuba_scene(
    model,
    mesh,
    out_dir,
    *,
    eta: float = 1.0,
    light=None,
    camera=None,
    voxels: int = VOXELS,
    overwrite: bool = False,
    inputs=(),
    option: str = "out_dir",
    name: str = "model",
) -> Path:
    """Write the medium a fitted per-vertex model carries, filling its mesh, as a Mitsuba 3 scene.

    Parameters
    ----------
    model : ReflectanceModel
        A per-vertex model fitted with this version (``model.measured["medium"]``,
        :func:`translucency.medium.medium_of`).
    mesh : trimesh.Trimesh
        Its mesh, mm (:func:`translucency.render.object_of_model`).
    out_dir : str or Path
        The folder to write (module docstring: ``scene.xml``, ``object.ply``, ``sigma_t.vol``,
        ``albedo.vol``).
    eta : float
        The boundary's relative index: 1 (default, the estimate's: index-matched, a ``null`` BSDF) or a
        smooth ``dielectric`` of ``int_ior`` η.  The estimate folds the data's own boundary into its
        coefficients, so a dielectric adds a boundary the estimate does not expect.
    light : Light, optional
        The scene's emitter (:func:`translucency.render.parse_light`, placed); default ``translucency
        render``'s light (``point@key``: beside and above the camera).  With η ≠ 1 a point, spot or
        directional light cannot reach the inside for ``volpath`` (a delta refraction): refused.
    camera : Camera, optional
        The scene's sensor (:class:`translucency.render.Camera`); default ``Camera.looking_at(mesh)``
        (``translucency render``'s view).  Its ``width`` and ``height`` become ``$resx``, ``$resy``.
    voxels : int
        Voxels along the longest side of the grids.
    overwrite : bool
        Replace the files of a folder translucency wrote before (never anything else).
    inputs : iterable of path
        The inputs the folder must stay out of (the model file).
    option, name : str
        The argument and the model named in messages.

    Returns
    -------
    Path
        The ``scene.xml`` written.

    Raises
    ------
    TranslucencyError
        The model holds no medium, the folder is not one translucency may write, a dielectric under a
        delta light.

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> import translucency as tl
    >>> from translucency.render import object_of_model
    >>> model = tl.load_model(tl.data.example_path("spot_coarse.model.zip"))   # the example object
    >>> mesh, _ = object_of_model(model, {})
    >>> from translucency.render.medium_scene import write_mitsuba_scene
    >>> out = write_mitsuba_scene(model, mesh, Path(tempfile.mkdtemp()) / "spot-mitsuba")
    >>> out.name, sorted(p.name for p in out.parent.glob("[!.]*"))
    ('scene.xml', ['albedo.vol', 'object.ply', 'scene.xml', 'sigma_t.vol'])
    """
    from ..mitsuba import mitsuba, slab_medium_dict, write_ply  # Mitsuba loads only to write
    from . import Camera, parse_light
    from .lights import DEFAULT_LIGHT, Placement, place_light
    from .reference import check_reference

    eta = float(eta)
    if not (np.isfinite(eta) and eta > 0):
        raise TranslucencyError(f"eta: expected a relative index > 0, got {eta!r}")
    volume = scene_volume(model, mesh, voxels=voxels, name=name)
    camera = camera or Camera.looking_at(mesh, width=DEFAULT_RESOLUTION[0], height=DEFAULT_RESOLUTION[1])
    if light is None:  # render's light, placed for this camera
        view = np.subtract(camera.origin, camera.target)
        light = place_light(parse_light(DEFAULT_LIGHT), Placement.of(mesh, view))
    check_reference(light, eta)  # a dielectric under a delta light: volpath renders its inside black
    mi = mitsuba()
    # the reference's own grids (flipped in z) and placement, one channel at a time: stacked into RGB here
    lo, hi = (np.asarray(b, dtype=np.float64) for b in mesh.bounds)
    channels = [slab_medium_dict(volume, c, (lo[0], lo[1], hi[2])) for c in range(3)]
    grids = {
        key: np.ascontiguousarray(
            np.concatenate([np.asarray(ch[key]["data"], dtype=np.float32) for ch in channels], axis=-1)
        )
        for key in ("sigma_t", "albedo")
    }
    to_world = np.asarray(channels[0]["sigma_t"]["to_world"].matrix, dtype=np.float64)
    xml = _scene_xml(volume, to_world, eta, light, camera, name)

    out_dir = Path(out_dir)
    before = {p.name for p in out_dir.iterdir()} if out_dir.is_dir() else None
    claim_folder(out_dir, overwrite=overwrite, inputs=inputs, option=option)
    try:
        with atomic_path(out_dir / FILES["mesh"]) as tmp:
            write_ply(tmp, np.asarray(mesh.vertices), np.asarray(mesh.faces), comment=PLY_COMMENT)
        for key in ("sigma_t", "albedo"):
            with atomic_path(out_dir / FILES[key]) as tmp:
                mi.VolumeGrid(grids[key]).write(str(tmp))
        with atomic_path(out_dir / FILES["scene"]) as tmp:
            tmp.write_bytes(xml)
    except BaseException:
        release_output(out_dir, before)  # only what this call added; files it replaced stay replaced
        raise
    return out_dir / FILES["scene"]


def _scene_xml(volume, to_world: np.ndarray, eta: float, light, camera, name: str) -> bytes:
    """The scene file's bytes (module docstring)."""
    scene = ET.Element("scene", version="3.0.0")
    for key, value in (("spp", DEFAULT_SPP), ("resx", camera.width), ("resy", camera.height)):
        ET.SubElement(scene, "default", name=key, value=str(int(value)))
    scene.append(
        ET.Comment(
            " volpath without depth limit and without Russian roulette: Mitsuba's roulette keeps a path "
            "with a chance of at most 0.95 a bounce, which over the hundreds of bounces of a medium of "
            "albedo near 1 gives fireflies. The medium is chromatic (RGB grids): use an RGB variant, "
            "and many samples (volpath's spectral MIS converges more slowly in it than in a grey medium) "
        )
    )
    integrator = ET.SubElement(scene, "integrator", type="volpath")
    _value(integrator, "max_depth", -1)
    _value(integrator, "rr_depth", NO_ROULETTE)

    scene.append(
        ET.Comment(
            " The default camera and light (translucency render's view and light): keep them, or replace "
            "them with your scene's sensor and emitters "
        )
    )
    sensor = ET.SubElement(scene, "sensor", type="perspective", id="camera")
    _value(sensor, "fov", float(camera.fov))
    transform = ET.SubElement(sensor, "transform", name="to_world")
    ET.SubElement(
        transform, "lookat", origin=_csv(camera.origin), target=_csv(camera.target), up=_csv(camera.up)
    )
    sampler = ET.SubElement(sensor, "sampler", type="independent")
    ET.SubElement(sampler, "integer", name="sample_count", value="$spp")
    film = ET.SubElement(sensor, "film", type="hdrfilm")
    ET.SubElement(film, "integer", name="width", value="$resx")
    ET.SubElement(film, "integer", name="height", value="$resy")
    ET.SubElement(film, "string", name="pixel_format", value="rgb")
    ET.SubElement(film, "rfilter", type="box")
    scene.append(_plugin("emitter", light.emitter_dict(), id="light"))

    scene.append(
        ET.Comment(
            f" The object: its mesh ({FILES['mesh']}, mm) filled with the medium estimated from its scan "
            "(similar medium: g = 0; the data's boundary folded into the coefficients, behind an "
            "index-matched boundary). Units: mm and mm^-1. To move the object, append the same rotate / "
            "translate to the shape's to_world and after the matrix of both grids' to_world. Keep the scene "
            "in millimetres: in metres, Mitsuba's ray offsets skip about 0.1 mm of the medium behind the "
            "boundary (if you must, scale the shape and both grids by 0.001 and give the medium a scale of "
            "1000). "
        )
    )
    shape = ET.SubElement(scene, "shape", type="ply", id="object")
    ET.SubElement(shape, "string", name="filename", value=FILES["mesh"])
    if eta == 1.0:
        ET.SubElement(shape, "bsdf", type="null")
    else:
        bsdf = ET.SubElement(shape, "bsdf", type="dielectric")
        _value(bsdf, "int_ior", eta)
        _value(bsdf, "ext_ior", 1.0)
    medium = ET.SubElement(shape, "medium", type="heterogeneous", name="interior", id="medium")
    for key, what in (("sigma_t", "extinction sigma_s + sigma_a, mm^-1"), ("albedo", "sigma_s / sigma_t")):
        medium.append(ET.Comment(f" {what}, RGB "))
        grid = ET.SubElement(medium, "volume", type="gridvolume", name=key)
        ET.SubElement(grid, "string", name="filename", value=FILES[key])
        ET.SubElement(grid, "string", name="filter_type", value="nearest")
        _transform(grid, to_world)
    _value(medium, "scale", 1.0)
    phase = ET.SubElement(medium, "phase", type="hg")
    _value(phase, "g", float(volume.g))

    ET.indent(scene, space="    ")
    head = (
        f"<?xml version='1.0' encoding='utf-8'?>\n"
        f"<!-- Written by translucency {__version__} from {_comment_safe(name)}: the medium estimated "
        f"from its scan, {volume.shape[2]} x {volume.shape[1]} x {volume.shape[0]} voxels of "
        f"{volume.voxel_mm:.6g} mm. Render: mitsuba scene.xml (or -Dspp=256 -Dresx=640 -Dresy=480). -->\n"
    )
    return head.encode() + ET.tostring(scene, encoding="unicode").encode() + b"\n"


def _csv(values) -> str:
    return ", ".join(repr(float(v)) for v in values)


def _comment_safe(text) -> str:
    """``text`` for an XML comment (no ``--``)."""
    return str(text).replace("--", "- -")


def _value(parent, name: str, value) -> None:
    """A ``<float>``, ``<integer>``, ``<boolean>`` or ``<string>`` property."""
    if isinstance(value, bool):
        ET.SubElement(parent, "boolean", name=name, value=str(value).lower())
    elif isinstance(value, (int, np.integer)):
        ET.SubElement(parent, "integer", name=name, value=str(int(value)))
    elif isinstance(value, (float, np.floating)):
        ET.SubElement(parent, "float", name=name, value=repr(float(value)))
    else:
        ET.SubElement(parent, "string", name=name, value=str(value))


def _transform(parent, matrix: np.ndarray, name: str = "to_world") -> None:
    """A ``<transform>`` holding a 4 × 4 ``matrix`` (row by row, full precision)."""
    transform = ET.SubElement(parent, "transform", name=name)
    ET.SubElement(transform, "matrix", value=" ".join(repr(float(v)) for v in np.ravel(matrix)))


#: the XML tag of a nested plugin, by the property that holds it
_TAGS = {"rfilter": "rfilter", "sampler": "sampler", "film": "film", "bsdf": "bsdf"}


def _plugin(tag: str, description: dict, **attrs) -> ET.Element:
    """An element ``<tag type=...>`` from a Mitsuba dictionary (a light's ``emitter_dict``): numbers,
    strings, ``position`` (a point), ``direction`` (a vector), other triples as RGB, transforms as
    matrices."""
    element = ET.Element(tag, type=str(description["type"]), **attrs)
    for key, value in description.items():
        if key == "type":
            continue
        if isinstance(value, dict):
            element.append(_plugin(_TAGS.get(key, key), value, name=key))
        elif hasattr(value, "matrix"):  # a ScalarTransform4f
            _transform(element, np.asarray(value.matrix, dtype=np.float64), key)
        elif isinstance(value, (list, tuple, np.ndarray)) and len(value) == 3:
            x, y, z = (repr(float(v)) for v in value)
            if key == "position":
                ET.SubElement(element, "point", name=key, x=x, y=y, z=z)
            elif key == "direction":
                ET.SubElement(element, "vector", name=key, x=x, y=y, z=z)
            else:
                ET.SubElement(element, "rgb", name=key, value=f"{x}, {y}, {z}")
        else:
            _value(element, key, value)
    return element
