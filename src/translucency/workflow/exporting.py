"""Export as functions: a per-vertex model taken to other tools.

:func:`export_ply` writes its mesh as a PLY for a Mitsuba scene (``render_scene``), in the model's
millimetres and vertex order; :func:`export_gltf` writes glTF 2.0 for Blender and three.js: the mesh, the
exitance under a light baked as vertex colours (the render stage's chain) and each vertex's profile reduced
to Christensen–Burley's albedo and mean free path per channel (with the reduction's error).
:func:`export_model` is ``translucency export``: any of these, every check before any file is written, and
with ``mitsuba=DIR`` the medium estimated from the scan filling the mesh as a Mitsuba 3 scene
(:func:`translucency.render.medium_scene.write_mitsuba_scene`).
Units: mm (glTF positions in metres), radiance in W/(mm² sr), linear RGB.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from .. import resources
from .._validate import TranslucencyError
from ..io.atomic import atomic_path
from ..io.gltf import MM_PER_GLTF_UNIT, write_glb
from ..io.inputs import expect_input
from ..io.outputs import PLY_COMMENT, claim_output
from ..model.burley import burley_of_exponentials, burley_shape
from ..model.lean import NO_LEAN, has_lean
from ..render import boundary_eta, object_of_model
from ..render.lights import DEFAULT_LIGHT, Placement, parse_light, place_light
from ..resources.memory import transport_pairs
from ..resources.run import Run
from ..transport import PreparedObject, TransportOptions
from ..transport.parameters import vertex_parameters
from ._arguments import as_path, model_and_record

__all__ = ["DEFAULT_LIGHT", "export_gltf", "export_model", "export_ply"]


def export_model(
    model,
    *,
    ply=None,
    gltf=None,
    mitsuba=None,
    light: str = DEFAULT_LIGHT,
    angles: bool = False,
    transport: TransportOptions | None = None,
    overwrite: bool = False,
    max_memory: str | int | None = None,
) -> dict:
    """Take a per-vertex model to other tools: its mesh as PLY, glTF with the bake, its medium as a
    Mitsuba 3 scene.

    ``translucency export MODEL [--ply OUT.ply] [--gltf OUT.glb] [--mitsuba DIR]`` is this function: the
    names and the model checked before any file is written, then the PLY, then the glTF, then the scene.

    Parameters
    ----------
    model : FitResult, ReflectanceModel or path
        A per-vertex model (a fit on a mesh data set) that carries its mesh.
    ply : str or Path, optional
        Write the model's mesh here (binary PLY, mm, the model's vertex order): the shape a Mitsuba scene
        places with its ``to_world`` for :func:`render_scene`.
    gltf : str or Path, optional
        Write glTF 2.0 binary here (``.glb``, metres): see :func:`export_gltf`.
    mitsuba : str or Path, optional
        Write a Mitsuba 3 scene into this folder: ``scene.xml`` (``volpath``, the shape filled with a
        ``heterogeneous`` medium behind an index-matched ``null`` boundary, a default camera and the light
        ``light``), ``object.ply`` and the medium estimated from the scan as grid volumes ``sigma_t.vol``
        and ``albedo.vol`` (mm⁻¹, RGB): :func:`translucency.render.medium_scene.write_mitsuba_scene`.  The
        model must carry the estimate (fitted with this version).
    light : str
        With ``gltf``: the light baked (as :func:`render_model`'s); with ``mitsuba``: the scene's emitter.
    angles : bool
        With ``gltf`` and a model that has a lean: bake it (the transport leaned toward the light, as
        ``render --angles``); otherwise the paper's model is baked and ``lean`` says so in one line.
    transport : TransportOptions, optional
        The bake's transport as one object (:class:`translucency.transport.TransportOptions`, e.g. a
        variant registered by name); ``angles`` is laid over it.
    overwrite : bool
        Replace an earlier mesh file of translucency at ``ply`` or ``gltf``, or the files of a scene
        folder translucency wrote at ``mitsuba`` (never anything else).
    max_memory : str or int, optional
        Most memory the export may use; a larger estimate (the bake's transport) is refused before any
        file is written.

    Returns
    -------
    dict
        The summary of ``translucency export --json``: ``model``, ``vertices``, ``faces``, and ``ply``,
        ``gltf`` with the bake's ``colour_scale``, ``angles`` (whether the lean was baked) and the Burley
        reduction's ``reduction_error_median``, ``reduction_error_p95``, ``mitsuba`` (the ``scene.xml``
        written) with the grid's ``voxels`` (x, y, z) and ``voxel_mm`` for what was written.

    Raises
    ------
    TranslucencyError
        Nothing to write, a wrong file name, a planar model, a model without an estimated medium for
        ``mitsuba``, an output that is not translucency's.

    Examples
    --------
    The example model the package ships, as a PLY and a glTF at once:

    >>> import tempfile
    >>> from pathlib import Path
    >>> import translucency as tl
    >>> out = Path(tempfile.mkdtemp())
    >>> done = tl.export_model(tl.data.example_path("spot_coarse.model.zip"), ply=out / "spot.ply",
    ...                        gltf=out / "spot.glb")
    >>> done["vertices"], done["faces"], sorted(p.name for p in out.iterdir())
    (402, 800, ['spot.glb', 'spot.ply'])
    """
    if ply is None and gltf is None and mitsuba is None:
        raise TranslucencyError("say what to write: ply=OUT.ply, gltf=OUT.glb or mitsuba=DIR")
    ply = None if ply is None else _named("ply", ply, ".ply", "")
    gltf = None if gltf is None else _named("gltf", gltf, ".glb", " (binary glTF)")
    mitsuba = None if mitsuba is None else as_path("mitsuba", mitsuba)
    run = Run("export", max_memory=max_memory)
    fitted, mesh, acquisition, inputs = _object(model)
    if mitsuba is not None:  # the model's medium and the folder, checked before any file is written
        from ..render.medium_scene import medium_or_refuse

        name = str(model) if inputs else "model"
        medium_or_refuse(fitted, name)
        claim_output(mitsuba, "output folder", overwrite=overwrite, inputs=inputs, option="mitsuba")
        for option, path in (("ply", ply), ("gltf", gltf)):
            if path is not None and mitsuba.resolve() in path.resolve().parents:
                raise TranslucencyError(
                    f"{option} {path}: lies inside the scene's folder mitsuba={mitsuba}; give another path"
                )
        scene_light = place_light(parse_light(light), Placement.of(mesh, (1.0, -1.6, 0.7)))  # as the bake's
    V, F = len(mesh.vertices), len(mesh.faces)
    lean = has_lean(fitted)
    # the bake's object, prepared as render's: its transport's near radius chosen once, here
    prepared = PreparedObject(
        fitted,
        mesh,
        eta=boundary_eta(acquisition),
        options=TransportOptions.of(transport, angles=angles and lean),
    )
    pairs = 0.0
    if gltf is not None:
        radius, limit = prepared.radius, prepared.options.max_pairs
        pairs = transport_pairs(vertices=V, surface_mm2=float(mesh.area), radius_mm=radius, max_pairs=limit)
    run.check(resources.memory.relighting(vertices=V, faces=F, pairs=pairs))  # (the files are small)
    summary = {"command": "export", "model": model, "vertices": V, "faces": F}
    if ply is not None:
        claim_output(ply, "mesh file", overwrite=overwrite, inputs=inputs, option="ply")
        _write_ply(mesh, ply)
        summary["ply"] = ply
    if gltf is not None:
        claim_output(gltf, "mesh file", overwrite=overwrite, inputs=inputs, option="gltf")
        record = _bake(prepared, gltf, light)
        summary.update(gltf=gltf, **record)
        if lean and not angles:  # one line: what the bake draws
            summary["lean"] = "not baked: the glTF draws the paper's model (--angles bakes the lean)"
        elif angles and not lean:
            summary["lean"] = NO_LEAN
    if mitsuba is not None:
        summary.update(_write_scene(fitted, mesh, mitsuba, scene_light, overwrite, inputs, name))
    return run.summary(summary)  # with the estimate and the seconds


def export_ply(model, out, *, overwrite: bool = False) -> Path:
    """Write a per-vertex model's mesh as a binary PLY (mm, the model's vertex order).

    The shape a Mitsuba scene places with its ``to_world`` for :func:`render_scene`.

    Parameters
    ----------
    model : FitResult, ReflectanceModel or path
        A per-vertex model that carries its mesh.
    out : str or Path
        The PLY to write (``.ply``).
    overwrite : bool
        Replace an earlier mesh file of translucency at ``out`` (never anything else).

    Returns
    -------
    Path
        ``out``.

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> import translucency as tl
    >>> model = tl.data.example_path("spot_coarse.model.zip")
    >>> out = tl.export_ply(model, Path(tempfile.mkdtemp()) / "spot.ply")
    >>> out.name, out.stat().st_size > 0
    ('spot.ply', True)
    """
    return export_model(model, ply=as_path("out", out), overwrite=overwrite)["ply"]


def export_gltf(
    model, out, *, light: str = DEFAULT_LIGHT, angles: bool = False, overwrite: bool = False
) -> dict:
    """Write a per-vertex model as glTF 2.0 binary (``.glb``) for Blender and three.js.

    The mesh (metres, +Y up), the exitance under ``light`` baked as vertex colours (``COLOR_0``, linear,
    scaled into [0, 1]: the scale in the file's extras) and per-vertex attributes ``_ALBEDO``,
    ``_MFP_MM``, ``_BURLEY_S`` (Christensen–Burley per channel) and ``_REDUCTION_ERROR``.

    Parameters
    ----------
    model : FitResult, ReflectanceModel or path
        A per-vertex model that carries its mesh.
    out : str or Path
        The file to write (``.glb``).
    light : str
        The light baked, in the object's frame (as :func:`render_model`'s).
    angles : bool
        Bake the model's lean, if it has one (as ``render --angles``).
    overwrite : bool
        Replace an earlier mesh file of translucency at ``out`` (never anything else).

    Returns
    -------
    dict
        ``gltf``, ``colour_scale``, ``angles`` and the Burley reduction's ``reduction_error_median`` and
        ``reduction_error_p95`` (with the mesh's ``vertices`` and ``faces``).

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> import translucency as tl
    >>> model = tl.data.example_path("spot_coarse.model.zip")
    >>> done = tl.export_gltf(model, Path(tempfile.mkdtemp()) / "spot.glb")
    >>> done["gltf"].name, bool(0 <= done["reduction_error_median"] <= done["reduction_error_p95"] < 1)
    ('spot.glb', True)
    """
    return export_model(model, gltf=as_path("out", out), light=light, angles=angles, overwrite=overwrite)


def _named(name: str, path, suffix: str, what: str) -> Path:
    """``path`` as a Path whose name ends in ``suffix``, or one line naming the argument."""
    path = as_path(name, path)
    if path.suffix.lower() != suffix:
        raise TranslucencyError(f"{name} {path}: the file name must end in {suffix}{what}")
    return path


def _object(model):
    """(the model, its mesh, its acquisition, the inputs an output must stay out of) of a per-vertex
    model, or one line why it has no mesh to export."""
    is_path = isinstance(model, (str, os.PathLike))
    if is_path:
        expect_input(Path(model), ("model file",))
    fitted, record = model_and_record("model", model)
    if getattr(fitted, "geometry", None) != "mesh":
        raise TranslucencyError(
            f"{model if is_path else 'model'}: a planar model has no mesh to export; export takes a "
            "per-vertex model"
        )
    mesh, acquisition = object_of_model(fitted, {"meta": record})
    return fitted, mesh, acquisition, [model] if is_path else []


def _write_ply(mesh, path: Path) -> None:
    """The mesh as a binary PLY, written atomically."""
    from ..mitsuba import write_ply  # Mitsuba's scene helpers: loaded only to write

    with atomic_path(path) as tmp:
        write_ply(tmp, mesh.vertices, mesh.faces, comment=PLY_COMMENT)


def _write_scene(fitted, mesh, folder: Path, light, overwrite: bool, inputs, name: str) -> dict:
    """Write the Mitsuba scene of the model's medium into ``folder`` under ``light`` (placed); what the
    summary states."""
    from ..render.medium_scene import scene_volume, write_mitsuba_scene  # Mitsuba loads only to export

    scene = write_mitsuba_scene(
        fitted, mesh, folder, light=light, overwrite=overwrite, inputs=inputs, option="mitsuba", name=name
    )
    volume = scene_volume(fitted, mesh, name=name)
    return {"mitsuba": scene, "voxels": list(volume.shape[::-1]), "voxel_mm": volume.voxel_mm}


def _bake(prepared, path, light_text: str) -> dict:
    """Write ``path`` (glTF) and return what the summary states (the reduction's error, the colour's
    scale, whether the lean was baked)."""
    mesh, angles = prepared.mesh, prepared.options.angles
    albedo, mfp, burley_s, error = _burley(prepared.model, mesh)
    radiance = _baked_radiance(prepared, light_text)
    top = float(np.quantile(radiance, 0.99)) if np.any(radiance > 0) else 1.0
    scale = 1.0 / top if top > 0 else 1.0
    extras = {
        "written_by": "translucency",
        "units": {"positions": "m", "_MFP_MM": "mm", "_BURLEY_S": "1/mm"},
        "up": "+Y, our +z: (x, y, z) -> (x, z, -y)",
        "colour": "COLOR_0 = radiance x colour_scale (linear; Lambertian exit), clipped to 1",
        "colour_scale": scale,
        "light": light_text,
        "angles": angles,
        "burley": "R(r) = A s (exp(-s r) + exp(-s r/3)) / (8 pi r); _MFP_MM = searchlight s~(A) / s",
        "mm_per_unit": MM_PER_GLTF_UNIT,
    }
    attributes = {
        "_ALBEDO": albedo,
        "_MFP_MM": np.nan_to_num(mfp, nan=0.0, posinf=0.0),
        "_BURLEY_S": np.nan_to_num(burley_s, nan=0.0, posinf=0.0),
        "_REDUCTION_ERROR": np.nan_to_num(error, nan=1.0),
    }
    write_glb(path, mesh.vertices, mesh.faces, radiance * scale, attributes, extras)
    finite = error[np.isfinite(error)]
    return {
        "colour_scale": scale,
        "angles": angles,
        "reduction_error_median": float(np.median(finite)) if finite.size else float("nan"),
        "reduction_error_p95": float(np.quantile(finite, 0.95)) if finite.size else float("nan"),
    }


def _burley(model, mesh):
    """Each vertex's profile (α × colour scale × the blended sum of exponentials, render's blend) reduced
    to Christensen–Burley: (albedo, mean free path mm, s 1/mm, the reduction's error), each (V, 3)."""
    c, d, s = vertex_parameters(model, mesh)
    alpha = np.asarray(model.alpha.values, dtype=np.float64)
    A, burley_s, error = burley_of_exponentials(c, d)  # (V, C)
    A = A if A.shape[1] == 3 else np.repeat(A, 3, axis=1)
    burley_s = burley_s if burley_s.shape[1] == 3 else np.repeat(burley_s, 3, axis=1)
    error = error if error.shape[1] == 3 else np.repeat(error, 3, axis=1)
    albedo = np.clip(alpha[:, None] * s * A, 0.0, None)
    mfp = burley_shape(np.clip(albedo, 0.0, 1.0), 1.0) / burley_s  # ℓ = s̃(A)/s, mm (searchlight)
    return albedo, mfp, burley_s, error


def _baked_radiance(prepared, light_text: str) -> np.ndarray:
    """The exitance under the light, W/(mm² sr) per vertex: the prepared object's irradiance with shadows
    and its transport (render's chain, a Lambertian exit; with the lean drawn, leaned toward the light)."""
    mesh = prepared.mesh
    lit = place_light(parse_light(light_text), Placement.of(mesh, (1.0, -1.6, 0.7)))
    E = prepared.irradiance(lit)
    return prepared.through(E, lit, eye=mesh.centroid).astype(np.float64)
