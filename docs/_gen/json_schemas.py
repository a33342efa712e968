"""The JSON summaries of the commands (``--json``): one schema per command, the checker, the page.

Each schema is JSON Schema (the subset :func:`check` reads: ``type``, ``properties``, ``required``,
``additionalProperties``, ``items``, ``enum``) with two annotations of its own: ``unit`` (mm, bytes,
seconds, ...) and ``description``.  The same data make docs/json.md (:func:`markdown`;
``python docs/_gen/json_schemas.py > docs/json.md``) and the test that runs every command and checks
its output against its schema (tests/test_json.py), so the page and the output cannot drift apart.
A documentation generator, not part of the installed package: nothing the command line runs imports it.

Examples
--------
>>> check({"command": "materials", "eta": 1.3, "materials": {}}, SCHEMAS["materials"])
[]
>>> check({"command": "materials", "eta": "1.3", "materials": {}}, SCHEMAS["materials"])
["eta: expected number, got str '1.3'"]
"""

from __future__ import annotations

#: the page's name in the repository and the command that writes it
PAGE = "docs/json.md"
COMMAND = f"python docs/_gen/json_schemas.py > {PAGE}"

#: JSON type → the Python types that hold it (``bool`` is not a number here)
_TYPES = {
    "object": (dict,),
    "array": (list,),
    "string": (str,),
    "integer": (int,),
    "number": (int, float),
    "boolean": (bool,),
    "null": (type(None),),
}


def field(type_, description: str, unit: str | None = None, **more) -> dict:
    """A leaf of a schema: its JSON type(s), what it is and its unit."""
    out = {"type": type_, "description": description, **more}
    if unit is not None:
        out["unit"] = unit
    return out


def record(description: str, properties: dict, *, optional=(), nullable: bool = False, extra=None) -> dict:
    """An object of known keys (all required but ``optional``); ``extra``: a schema every other key
    follows (an object keyed by names, e.g. materials or models), else no other key is allowed."""
    return {
        "type": ["object", "null"] if nullable else "object",
        "description": description,
        "properties": properties,
        "required": [k for k in properties if k not in optional],
        "additionalProperties": False if extra is None else extra,
    }


def array(description: str, items: dict, unit: str | None = None, nullable: bool = False) -> dict:
    return field(["array", "null"] if nullable else "array", description, unit, items=items)


NUMBER = {"type": "number"}
NUMBER_OR_NULL = {"type": ["number", "null"]}
INTEGER = {"type": "integer"}
RGB = array("red, green, blue", NUMBER)
XYZ = array("x, y, z", NUMBER)

# -- pieces several commands share --------------------------------------------------------------------
ESTIMATE = record(
    "What the command was estimated to need before it started.",
    {
        "memory_bytes": field("integer", "Peak memory.", "bytes"),
        "disk_bytes": field("integer", "Disk space written.", "bytes"),
        "dominated_by": field("string", "What the memory is mostly, and the option that lowers it."),
    },
)
TIME_ESTIMATE = record(
    "How long the command was estimated to take.",
    {
        "seconds": field("number", "Estimated time.", "s"),
        "source": field("string", "Where the estimate comes from (the local calibration, a probe, ...)."),
        "startup_seconds": field(
            "number", "Seconds already spent before the estimate (imports, checks).", "s"
        ),
    },
    optional=("startup_seconds",),
)
_WORKING = {
    "estimate": ESTIMATE,
    "time_estimate": TIME_ESTIMATE,
    "seconds": field("number", "Time the work took.", "s"),
}
BOUNDS = {
    "bounds_mm": array("The object's axis-aligned bounds: [[x, y, z] min, [x, y, z] max].", XYZ, "mm"),
    "centre_mm": field("array", "The centre of those bounds, x, y, z.", "mm", items=NUMBER),
}


def _command(name: str) -> dict:
    return field("string", "The command.", enum=[name])


# -- acquire ------------------------------------------------------------------------------------------
_ACQUIRED = {
    "out": field("string", "The data set written (a Zarr folder)."),
    "points": field("integer", "Incident points."),
    "photons": field("integer", "Photons per incident point and channel."),
    "seed": field("integer", "Random seed of the photons."),
    "complete": field("boolean", "Every chunk of points is acquired."),
}
_ACQUIRED_ANGLES = {
    "directions": field("integer", "Directions of incidence per point, the normal included."),
    "exit_bins": field("integer", "Exit direction bins per exit point (0: none; --exit-bins)."),
}
ACQUIRE_PLANAR = record(
    "`translucency acquire planar --json`: the planar data set written.",
    {
        "command": _command("acquire planar"),
        **_ACQUIRED,
        "window_pixels": array("Window height, width around each incident point.", INTEGER, "pixels"),
        **_ACQUIRED_ANGLES,
        **_WORKING,
    },
)
ACQUIRE_MESH = record(
    "`translucency acquire mesh --json`: the mesh data set written.",
    {
        "command": _command("acquire mesh"),
        **_ACQUIRED,
        "vertices": field("integer", "Vertices of the mesh (the outgoing points)."),
        **_ACQUIRED_ANGLES,
        **_WORKING,
    },
)

# -- fit ----------------------------------------------------------------------------------------------
_CANDIDATE = record(
    "One candidate of an axis: its value, held-out error and its distance to the axis's best.",
    {
        "value": field(["string", "integer"], "The axis's value (colour name, n or m)."),
        "held_out": field("number", "Held-out relative L2 error on the data's own photons.", "fraction"),
        "delta": field(
            "number", "Its squared error minus the best candidate's, of the data's squared norm.", "fraction"
        ),
        "se": field("number", "The standard error of that difference over the incident points.", "fraction"),
    },
)
_STRUCTURE = record(
    "The structure chosen by held-out error (--model auto, or an axis given as auto); null when given.",
    {
        "chosen": record(
            "The structure fitted.",
            {
                "colour": field("string", "shared or per-channel.", enum=["shared", "per-channel"]),
                "n_terms": field("integer", "Exponential terms n per profile."),
                "n_directions": field("integer", "Directions m (1: isotropic)."),
                "model": field("string", "The family fitted: iso or aniso.", enum=["iso", "aniso"]),
                "label": field("string", "The structure in words."),
            },
        ),
        "held_out": field(
            "number", "The chosen structure's held-out error on the points it was chosen on.", "fraction"
        ),
        "noise": field(
            ["number", "null"],
            "The held-out pairs' own noise sqrt(sum of variance / sum R_d^2): what a perfect model scores "
            "there (null where the data set records no variance).",
            "fraction",
        ),
        "ratio_to_noise": field(
            ["number", "null"],
            "held_out / noise, the figure the command prints first: 1 is the best any model can score.",
        ),
        "ratio_se": field(["number", "null"], "The standard error of that ratio over the incident points."),
        "axes": record(
            "Per axis searched (colour, n_terms, n_directions), its candidates simplest first.",
            {},
            extra=array("The candidates tried (a search stops after two that lower nothing).", _CANDIDATE),
        ),
        "guard": record(
            "The choice against the base structure (isotropic, n = 3, per channel) on the same halves.",
            {
                "base": field("string", "The base structure."),
                "delta": field("number", "The choice's squared error minus the base's.", "fraction"),
                "se": field("number", "Its standard error over the points.", "fraction"),
                "kept": field("string", "base: the choice lost by more than the split's noise."),
            },
            optional=("kept",),
            nullable=True,
        ),
        "margins": record(
            "Per axis where a richer value was kept: what it won over and by how much.",
            {},
            extra=record(
                "The richer value's win over the best simpler candidate of its axis.",
                {
                    "over": field(["string", "integer"], "The simpler value it won over."),
                    "delta": field(
                        "number", "The simpler one's squared error minus the chosen one's.", "fraction"
                    ),
                    "se": field("number", "Its standard error over the points.", "fraction"),
                    "held_out": field("number", "The difference of their held-out errors.", "fraction"),
                },
            ),
        ),
        "runner_up": record(
            "The best candidate not chosen, on any axis.",
            {
                "label": field("string", "Its structure in words."),
                "held_out": field("number", "Its held-out error.", "fraction"),
                "axis": field("string", "The axis it differs on."),
            },
            nullable=True,
        ),
        "points": field("integer", "Incident points the candidates were fitted and scored on."),
        "of_points": field("integer", "Incident points of the data set."),
        "seconds": field("number", "Time of the choice (the final fit's own time not included).", "s"),
        "rule": field("string", "How the choice is made."),
        "summary": field("string", "The choice in one line, as the command prints it."),
    },
    nullable=True,
)
FIT = record(
    "`translucency fit --json`: the model file written.",
    {
        "command": _command("fit"),
        "model": field("string", "The model file written (.model.zip)."),
        "dataset": field("string", "The data set fitted (as given)."),
        "kind": field("string", "Model family: exponential, dipole, burley, pbd, ddipole."),
        "geometry": field("string", "planar or mesh.", enum=["planar", "mesh"]),
        "n_points": field("integer", "Incident points of the model."),
        "rounds": field("integer", "Alternation rounds run (parameters, then alpha)."),
        "objective_per_round": array("The fit's objective after each round.", NUMBER),
        "flagged_points": array("Incident points without usable data (planar fits).", INTEGER),
        "unphysical_points": array("Incident points that break a physical bound (see `info`).", INTEGER),
        "structure": _STRUCTURE,
        **_WORKING,
    },
)

# -- evaluate -----------------------------------------------------------------------------------------
_BANDS = "all (every valid pair), near (< 1 mm), mid (1-4 mm), far (> 4 mm); null where a band is empty"
_BY_BAND = record(
    f"By distance band: {_BANDS}.",
    {k: field(["number", "null"], f"{k} band.", "fraction") for k in ("all", "near", "mid", "far")},
)
_ERRORS = {
    "rel_l2": field("number", "Relative L2 error over every valid pair (definition.rel_l2).", "fraction"),
    "rel_l2_near": field(["number", "null"], "The same over r < 1 mm.", "fraction"),
    "rel_l2_mid": field(["number", "null"], "The same over 1 mm <= r < 4 mm.", "fraction"),
    "rel_l2_far": field(["number", "null"], "The same over r >= 4 mm.", "fraction"),
    "noise_floor": _BY_BAND,
    "beyond_noise": record(
        "The error left after the truth's own noise, by band; null in-sample.",
        _BY_BAND["properties"],
        nullable=True,
    ),
    "energy_error": record(
        "Relative error of each point's energy, by band, over the window and in total.",
        {
            k: field(["number", "null"], f"{k}.", "fraction")
            for k in ("near", "mid", "far", "window", "total")
        },
    ),
    "energy_noise": record(
        "The reference's noise of those energies.",
        {k: field(["number", "null"], f"{k}.", "fraction") for k in ("near", "mid", "far", "window")},
    ),
    "per_point": record(
        "Per-incident-point relative error.",
        {
            "median": field(["number", "null"], "Median."),
            "p95": field(["number", "null"], "95th percentile."),
        },
    ),
    "flagged_points": array("Points the fit flagged (left out of the errors).", INTEGER),
    "physics": field("object", "The model's physical check (as `info --json`'s `physical`, without ok)."),
}
_MODEL_ERRORS = record(
    "One model's errors.",
    {**_ERRORS, "in_sample": field("object", "The same numbers against the fitted data (with --truth).")},
    optional=("in_sample",),
)
EVALUATE = record(
    "`translucency evaluate --json` (and the file of `--json-out`): the errors of the first model at the "
    "top, every model's under `models`. Paths are relative to the report's folder.",
    {
        "command": _command("evaluate"),
        "report": field("string", "The report page written (index.html)."),
        "written_by": field("string", "translucency and its version."),
        "command_line": field("string", "The command line that wrote the report."),
        "date": field("string", "When, ISO 8601 with the time zone."),
        "dataset": field("string", "The data set evaluated, relative to the report's folder."),
        "truth": field(["string", "null"], "The independent acquisition (--truth), or null."),
        "paths": field("string", "What the paths are relative to."),
        "evaluated_against": field("string", "The fitted data, or the truth."),
        "model": field("string", "The label of the first model (its numbers are at the top)."),
        **_MODEL_ERRORS["properties"],
        "bands_mm": record(
            "The distance bands, [from, to] (to null: no limit).",
            {k: array(f"The {k} band.", NUMBER_OR_NULL, "mm") for k in ("near", "mid", "far")},
        ),
        "models": record("Every model's errors, by its label.", {}, extra=_MODEL_ERRORS),
        "profile_points": array("Incident points of the profile figure.", INTEGER),
        "fine_profiles": field(
            ["object", "null"], "The truth's fine ring profiles (bin_mm, photons), or null."
        ),
        "definition": field("object", "What each number means, in words."),
        "summary": field("string", "What the reader should conclude, in words, generated from the numbers."),
        **_WORKING,
    },
    optional=("in_sample",),
)

# -- evaluate on a mesh data set ---------------------------------------------------------------------
_MEDIUM = record(
    "The medium estimated from the scan alone (measured/medium): per channel R, G, B the "
    "[min, median, max] over the incident points; absent for a model without one.",
    {
        "sigma_s": array("Scattering coefficient σ_s, per channel [min, median, max].", RGB, "mm^-1"),
        "sigma_a": array("Absorption coefficient σ_a, per channel [min, median, max].", RGB, "mm^-1"),
        "albedo": array("Single-scattering albedo σ_s / σ_t, per channel [min, median, max].", RGB),
        "rings_rms_log_residual": field(
            "number", "RMS log residual of the half-space's match over the rings (when stored)."
        ),
        "g": field("number", "The mean cosine assumed: 0 (the similar medium, σ_s = σ_s')."),
        "points": field("integer", "Incident points estimated."),
        "index_matched": field("boolean", "The boundary assumed: index-matched (always true)."),
        "assumed": field("string", "What the estimate assumes, in words."),
    },
    optional=("rings_rms_log_residual",),
)

_SURFACE_BANDS = ("near", "mid", "far", "surface")
_MESH_ERRORS = {
    **{k: v for k, v in _ERRORS.items() if k not in ("energy_error", "energy_noise", "per_point")},
    "energy_error": record(
        "Relative error of each point's energy, by band and over the whole surface.",
        {k: field(["number", "null"], f"{k}.", "fraction") for k in _SURFACE_BANDS},
    ),
    "energy_noise": record(
        "The reference's noise of those energies.",
        {k: field(["number", "null"], f"{k}.", "fraction") for k in _SURFACE_BANDS},
    ),
    "per_point": record(
        "Per-incident-point relative error.",
        {
            "median": field(["number", "null"], "Median."),
            "p95": field(["number", "null"], "95th percentile."),
            "values": array("Each incident point's error (null where flagged).", NUMBER_OR_NULL, "fraction"),
        },
    ),
    "exclusion_mm": field("number", "Pairs closer than this are left out (the own vertex's cell).", "mm"),
    "through": field(
        "boolean",
        "Whether the prediction held the model's through-body table (as render draws it; --paper: not).",
    ),
    "by_distance": record(
        "rel_l2 and the noise floor per ring of r, and the pairs in each ring.",
        {
            "edges_mm": array("The rings' edges.", NUMBER_OR_NULL, "mm"),
            "rel_l2": array("Relative L2 error per ring.", NUMBER_OR_NULL, "fraction"),
            "noise": array("The reference's noise floor per ring.", NUMBER_OR_NULL, "fraction"),
            "pairs": array("Pairs per ring.", INTEGER),
        },
    ),
}
_OBLIQUE = record(
    "With oblique beams in the truth (or the data: acquire mesh --incidence): the model's errors on them, "
    "each beam's total from the model's own incidence law (`translucency.evaluate.oblique_errors`).",
    {
        "paper": field(
            "number", "Relative L2 error of the paper's model (the normal beam's shape).", "fraction"
        ),
        "lean": field(["number", "null"], "With the model's lean; null without one.", "fraction"),
        "noise": field("number", "The data's own noise on that scale.", "fraction"),
        "beams": field("integer", "Oblique beams per incident point."),
        "polar_deg": array("Their polar angles.", NUMBER_OR_NULL, "degrees"),
    },
)
_MESH_MODEL_ERRORS = record(
    "One model's errors.",
    {
        **_MESH_ERRORS,
        "in_sample": field("object", "The same numbers against the fitted data (with --truth)."),
        "oblique": _OBLIQUE,
        "medium": _MEDIUM,
    },
    optional=("in_sample", "oblique", "medium"),
)
EVALUATE_MESH = record(
    "`translucency evaluate --json` on a mesh data set (per-vertex models): the same names as on a planar "
    "data set, per pair (x_i, vertex); energies over the surface instead of the window.",
    {
        **{
            k: v
            for k, v in EVALUATE["properties"].items()
            if k not in (*_ERRORS, "in_sample", "models", "profile_points", "fine_profiles")
        },
        "geometry": field("string", "mesh"),
        "photons": record(
            "Photons per incident point of the data set and of the truth.",
            {
                "dataset": field(["integer", "null"], "The data set's."),
                "truth": field(["integer", "null"], "The truth's."),
            },
            optional=("truth",),
        ),
        **_MESH_ERRORS,
        "oblique": _OBLIQUE,
        "models": record("Every model's errors, by its label.", {}, extra=_MESH_MODEL_ERRORS),
    },
    optional=("in_sample", "summary", "oblique"),
)

# -- render -------------------------------------------------------------------------------------------
RENDER = record(
    "`translucency render --json`: the pictures written and how long each step took.",
    {
        "command": _command("render"),
        "model": field("string", "The model file rendered."),
        "images": field("string", "The folder of ours.exr/.png (and the reference's)."),
        "vertices": field("integer", "Vertices of the object."),
        "transport_nonzeros": field("integer", "Vertex pairs of the sparse transport."),
        "prepare_s": field("number", "Building the transport.", "s"),
        "relight_s": field("number", "Irradiance and relighting.", "s"),
        "draw_s": field("number", "Drawing the picture.", "s"),
        "light": field(
            "object",
            "The light: kind (point, directional, spot, environment) and its parameters (position, "
            "direction, target in mm; intensity W/sr, irradiance W/mm^2, radiance W/(mm^2 sr)).",
        ),
        "eta": field("number", "Relative index of refraction at the surface."),
        "incidence": field(
            "string",
            "The incidence law used (half-space; normal where the object is dielectric or the model carries "
            "no measured totals).",
        ),
        "through": field(
            "boolean",
            "Whether the model's through-body table was drawn (the default where the model holds one; "
            "--paper: not).",
        ),
        "angles": field(
            "boolean",
            "Whether the model's lean toward the light's direction was drawn (--angles: a model fitted "
            "from oblique beams, a light of one direction per vertex).",
        ),
        "rel_rmse": field(
            ["number", "null"], "Relative RMSE of ours against the reference (with --reference)."
        ),
        "flip_mean_object": field("number", "Mean FLIP over the object's pixels (with --reference)."),
        "flip_mean_image": field("number", "Mean FLIP over the image (with --reference)."),
        "exposure": field("number", "Exposure of the PNGs: the linear scale before sRGB (--exposure)."),
        "exposure_rule": field(
            "string", "How the exposure was chosen (fixed: from the object and the light)."
        ),
        "flip_exposure": field(
            "number", "The exposure FLIP compared at (the reference's own, with --reference)."
        ),
        "regions": field("object", "Errors per region of the picture (with --reference)."),
        "reference_s": field("number", "Path tracing the reference.", "s"),
        "reference_noise": field(["number", "null"], "The reference's own noise (with --reference)."),
        "reference_cached": field("boolean", "The reference came from the cache."),
        "reference_spp": field("integer", "Samples per pixel of the reference (--reference-spp)."),
        "speedup_vs_reference": field("number", "Reference time over ours."),
        **_WORKING,
    },
    # with --reference: the comparison's numbers (render/compare.py), each a number
    optional=(
        "rel_rmse",
        "flip_mean_object",
        "flip_mean_image",
        "exposure_rule",
        "flip_exposure",
        "regions",
        "reference_s",
        "reference_noise",
        "reference_cached",
        "reference_spp",
        "speedup_vs_reference",
    ),
    extra={"type": ["number", "null"], "description": "The comparison's numbers (with --reference)."},
)

_SCENE_PART = record(
    "Errors over one set of pixels.",
    {
        "rel_rmse": field("number", "Relative RMSE of ours against the reference."),
        "brightness": field("number", "Mean of ours over the mean of the reference."),
        "pixels": field("integer", "Pixels in the set."),
        "flip": field("number", "Mean FLIP of the tone-mapped pair (objects only)."),
    },
    optional=("rel_rmse", "brightness", "flip"),
)

RENDER_SCENE = record(
    "`translucency render scene SCENE --object ID=FILE --json`: fitted objects in a Mitsuba scene.",
    {
        "command": _command("render"),
        "scene": field("string", "The Mitsuba scene file."),
        "models": field("object", "Shape id -> the model file it is."),
        "images": field("string", "The folder of ours.exr/.png (and reference.exr/.png, scene.png)."),
        "objects": field(
            "object",
            "Per fitted object: vertices, eta, incidence (the law used), angles (the lean drawn), through "
            "(the through-body table drawn).",
        ),
        "prepare_s": field("number", "Building the transports.", "s"),
        "radius_mm": array("Each object's near radius of the transport, as drawn.", NUMBER, "mm"),
        "light_s": field("number", "The light-in and through-the-body passes.", "s"),
        "draw_s": field("number", "Path tracing our picture.", "s"),
        "passes": field("integer", "Light-in / through-the-body passes (--passes)."),
        "samples": field(
            "integer", "Irradiance samples per vertex of the first pass (--irradiance-samples)."
        ),
        "picture_spp": field("integer", "Samples per pixel of our picture (--picture-spp)."),
        "object_pixels": field("integer", "Pixels whose centre ray meets a fitted object."),
        "exposure": field("number", "Exposure of the PNGs: the linear scale before sRGB."),
        "errors": record(
            "Ours against the reference (with --reference): over the objects, over the pixels they light, "
            "over the rest of the picture.",
            {"object": _SCENE_PART, "lit": _SCENE_PART, "rest": _SCENE_PART},
        ),
        "reference_noise": field("number", "The reference's own noise over the objects (with --reference)."),
        "reference_spp": field(
            "integer", "Samples per pixel of each of the reference's two renders (--reference-spp)."
        ),
        "reference_s": field("number", "Path tracing the reference.", "s"),
        "speedup_vs_reference": field("number", "Reference time over our passes and picture."),
        **_WORKING,
    },
    optional=("errors", "reference_noise", "reference_spp", "reference_s", "speedup_vs_reference"),
)

# -- export -------------------------------------------------------------------------------------------
EXPORT = record(
    "`translucency export MODEL --ply OUT.ply --gltf OUT.glb --mitsuba DIR --json`: what was written.",
    {
        "command": _command("export"),
        "model": field("string", "The model file."),
        "ply": field("string", "The mesh written (binary PLY, mm, the model's vertex order; --ply)."),
        "gltf": field("string", "The glTF 2.0 binary written (--gltf)."),
        "colour_scale": field("number", "COLOR_0 = radiance x this (--gltf).", "mm^2 sr / W"),
        "reduction_error_median": field(
            "number",
            "Median over vertices and channels of the Christensen-Burley reduction's error (--gltf).",
        ),
        "reduction_error_p95": field("number", "Its 95th percentile (--gltf)."),
        "mitsuba": field(
            "string",
            "The Mitsuba 3 scene written (DIR/scene.xml, beside object.ply, sigma_t.vol and albedo.vol; "
            "--mitsuba).",
        ),
        "voxels": array("The medium's grid in the scene: voxels along x, y, z (--mitsuba).", INTEGER),
        "voxel_mm": field("number", "The edge of its cubic voxels (--mitsuba).", "mm"),
        "vertices": field("integer", "Vertices of the mesh."),
        "faces": field("integer", "Triangles of the mesh."),
        "angles": field("boolean", "Whether the bake drew the model's lean (--gltf --angles, as render's)."),
        "lean": field(
            "string",
            "With --gltf, one line when the lean is not baked: a model with a lean without --angles, or "
            "--angles for a model without one — the paper's model is baked.",
        ),
        "estimate": ESTIMATE,
        "seconds": field("number", "Time the export took.", "s"),
    },
    optional=(
        "ply",
        "gltf",
        "colour_scale",
        "reduction_error_median",
        "reduction_error_p95",
        "mitsuba",
        "voxels",
        "voxel_mm",
        "angles",
        "lean",
    ),  # fmt: skip
)

# -- photographs, imports, view, demo -----------------------------------------------------------------
_ESTIMATED = {"estimate": ESTIMATE, "seconds": field("number", "Time the work took.", "s")}
ACQUIRE_PHOTOGRAPHS = record(
    "`translucency acquire photographs --json`: the folder of photographs written.",
    {
        "command": _command("acquire photographs"),
        "out": field("string", "The folder written (images, positions.csv, calibration.json)."),
        "photographs": field("integer", "Photographs taken: one per incident point."),
        "rms_px": field("number", "The marked points' fit of the calibration, rms.", "pixels"),
        "homography": array("The true homography from the camera's pose, 3 x 3 (rows).", {"type": "array"}),
        **_ESTIMATED,
    },
)
ACQUIRE_OBJECT_PHOTOGRAPHS = record(
    "`translucency acquire object-photographs --json`: the rig folder written.",
    {
        "command": _command("acquire object-photographs"),
        "out": field("string", "The folder written (object.json, object.ply, cameras, shots)."),
        "points": field("integer", "Laser positions."),
        "cameras": field("integer", "Cameras around the object."),
        "incident": array("The vertex each laser position hits.", INTEGER),
        **_ESTIMATED,
    },
)
IMPORT_IMAGES = record(
    "`translucency import images --json`: the planar data set written.",
    {
        "command": _command("import images"),
        "out": field("string", "The data set written (a Zarr folder)."),
        "points": field("integer", "Laser positions (incident points)."),
        "window_pixels": array("Window height, width around each incident point.", INTEGER, "pixels"),
        "pitch": field("number", "Pixel size of the windows on the sample.", "mm"),
        "rms_px": field(
            ["number", "null"], "The marked points' fit of the calibration (null: none).", "pixels"
        ),
        **_ESTIMATED,
    },
)
_CAMERA = record(
    "One camera of the rig.",
    {
        "name": field("string", "The camera's name in the rig file."),
        "reprojection_px": record(
            "What checked its pose (none of either: a pose given, unchecked).",
            {
                "pose": field("number", "Its marks' reprojection error, rms.", "pixels"),
                "laser_spot": field("number", "Its laser spots' miss, median.", "pixels"),
            },
            optional=("pose", "laser_spot"),
        ),
        "vertices_seen": field("integer", "Vertices it sees."),
    },
)
IMPORT_OBJECT = record(
    "`translucency import object --json`: the mesh data set written.",
    {
        "command": _command("import object"),
        "out": field("string", "The data set written (a Zarr folder)."),
        "points": field("integer", "Laser shots (incident points)."),
        "vertices": field("integer", "Vertices of the mesh."),
        "cameras": array("The cameras and their checks.", _CAMERA),
        "exit_law": record(
            "Radiance to exitance (--exit-law): its name and, estimated from views, its parameters.",
            {"law": field("string", "The law.")},
            extra={"description": "A parameter of the law."},
        ),
        "flags": record(
            "Vertex-shot pairs by what was done with them (unseen, saturated, grazing, spot, ...).",
            {},
            extra=field("integer", "Pairs."),
        ),
        "saturated_views": field("integer", "Cameras' views of a cell dropped for a saturated pixel."),
        "near_peak": field("integer", "Pairs from the near-peak model."),
        "rays_per_pixel": record("Rays per pixel of each camera's map.", {}, extra=field("integer", "Rays.")),
        "energy": array("Per shot, the energy of R_d over the surface, R, G, B.", RGB),
        "energy_sigma": array("Per shot, its uncertainty (1 sigma), R, G, B.", RGB),
        "beam_polar_deg": array("Per shot, the beam's angle from the surface normal.", NUMBER, "degrees"),
        "images_MB": field("number", "Image bytes read.", "MiB"),
        "throughput_MB_s": field("number", "Image bytes read per second.", "MiB/s"),
        **_ESTIMATED,
    },
)
VIEW = record(
    "`translucency view MODEL --json`: the page written (--export) or the address served.",
    {
        "command": _command("view"),
        "model": field("string", "The model file."),
        "url": field("string", "Where the viewer was served."),
        "page": field("string", "The page written (index.html; --export)."),
        "page_mb": field("number", "The page's size (--export).", "MiB"),
        "vertices": field("integer", "Vertices of the mesh (a per-vertex model, --export)."),
        "bands": field("integer", "Bands of the light basis (--bands)."),
        "angles": field("boolean", "Whether the page draws the model's lean (--angles)."),
        "error_vs_render": record(
            "The relighting's relative RMSE against render for the same light, per light.",
            {},
            extra=field("number", "Relative RMSE.", "fraction"),
        ),
        **_ESTIMATED,
    },
    optional=("url", "page", "page_mb", "vertices", "bands", "angles", "error_vs_render", "estimate"),
    extra=field("number", "Seconds of one step of preparing the page (`*_s`).", "s"),
)
DEMO = record(
    "`translucency demo --json`: the demo's outputs (the paper's two figures).",
    {
        "command": _command("demo"),
        "out": field("string", "The output folder."),
        "outputs": record(
            "Where each output is.",
            {
                "figure": field("string", "baselines.png: R_d(r) of the baselines per material."),
                "summary": field("string", "baselines.json."),
                "model": field("string", "dipole_fits.model.zip."),
                "fits": field("string", "The planar fits' model files."),
                "pig": field("string", "Figure 2's mesh data set."),
                "report": field("string", "The report's index.html."),
            },
        ),
    },
)

# -- info ---------------------------------------------------------------------------------------------
_INFO = {
    "command": _command("info"),
    "path": field("string", "The path described (as given)."),
    "what": field("string", "What it is.", enum=["model", "planar data set", "mesh data set"]),
    "format": field("string", "The file's format name."),
    "version": field("integer", "The format's version."),
    "n_points": field("integer", "Incident points."),
    "size_bytes": field("integer", "Size on disk.", "bytes"),
}
INFO_MODEL = record(
    "`translucency info MODEL.model.zip --json` (exit status 1 when not valid).",
    {
        **_INFO,
        "what": field("string", "What it is.", enum=["model"]),
        "kind": field("string", "Model family."),
        "geometry": field("string", "planar or mesh.", enum=["planar", "mesh"]),
        "n_terms": field("integer", "Exponential terms n (exponential models)."),
        "n_directions": field("integer", "Directions m (exponential models; 1: isotropic)."),
        "colour": field("string", "shared or per-channel (exponential models)."),
        "dtype": field("string", "Storage of the parameters: float32 or float16 (fit --dtype)."),
        "meta": field(
            "object", "What the fit recorded (data set, options, objective, acquisition), in full."
        ),
        "valid": field("boolean", "Intact (shapes, dtypes, finiteness, eq. (2), checksum) and physical."),
        "intact": field("boolean", "The file reads back as written."),
        "problem": field(["string", "null"], "Why it is not valid, or null."),
        "physical": record(
            "The physical bounds (`translucency.model.bounds`).",
            {
                "ok": field("boolean", "Every point within the bounds."),
                "description": field("string", "The same in words."),
            },
            extra={"description": "The bounds' numbers (bounds, extremes, points that break them)."},
        ),
        "alpha": record(
            "The modulation texture alpha.",
            {
                "shape": array("Its shape (pixels, or vertices).", INTEGER),
                "min": field("number", "Smallest value."),
                "max": field("number", "Largest value."),
            },
        ),
        "total_reflectance_mean": field("array", "Mean total diffuse reflectance, R, G, B.", items=NUMBER),
        "energy_radius_mm": record(
            "Radius holding 99.9 % of each point's reflected energy, over the points.",
            {"min": field("number", "Smallest.", "mm"), "max": field("number", "Largest.", "mm")},
        ),
        "object_size_mm": field(
            ["number", "null"], "The object's size (bounding diagonal); null: a semi-infinite slab.", "mm"
        ),
        "object": field(["string", "null"], "What the object is (a W x H mm sample, a mesh, a slab)."),
        "beyond_object_max": field(
            "number", "The largest share of a point's energy beyond the object's edge."
        ),
        "beyond_object_bound": field("number", "The share beyond the edge a physical point stays within."),
        "measured": field(
            "array",
            "What a per-vertex model carries from its acquisition: own, total (the near field), through "
            "(the through-body table, drawn by render unless --paper), lean (κ, render --angles), medium "
            "(the medium estimated from the scan); empty for planar models.",
        ),
        "medium": _MEDIUM,
        **BOUNDS,
    },
    optional=(
        "kind",
        "geometry",
        "n_terms",
        "n_directions",
        "colour",
        "dtype",
        "physical",
        "alpha",
        "total_reflectance_mean",
        "energy_radius_mm",
        "object_size_mm",
        "object",
        "beyond_object_max",
        "beyond_object_bound",
        "measured",
        "medium",
        *BOUNDS,
    ),
)
_STORE = {
    "damaged": field(
        "object",
        "Missing or undecodable chunks: {array: [chunk, ...]}; empty when none.",
        additionalProperties=array("Chunk indices.", INTEGER),
    ),
    "sample": field("object", "The sample (or filling) as acquired, in full."),
    "photons": field(["integer", "null"], "Photons per incident point and channel."),
    "seed": field(["integer", "null"], "Random seed of the photons."),
    "chunks_done": field("integer", "Chunks of points acquired."),
    "chunks": field("integer", "Chunks of points in all."),
    "complete": field("boolean", "Every chunk acquired."),
    "software": field("object", "Versions of the software that wrote it."),
}
_INFO_ANGLES = {
    "incidence": record(
        "The beams' directions at each incident point (translucency.angles.Incidence).",
        {
            "polar_deg": array("Polar angles of the oblique beams (none: normal only).", NUMBER, "deg"),
            "azimuths": field("integer", "Azimuths per polar angle."),
            "directions": field("integer", "Directions per point, the normal included."),
        },
    ),
    "exit_bins": field(
        ["integer", "null"],
        "Exit direction bins per exit point (polar x azimuthal sectors, two: away/back); null: none.",
    ),
}
INFO_PLANAR = record(
    "`translucency info PLANAR.zarr --json`.",
    {
        **_INFO,
        "what": field("string", "What it is.", enum=["planar data set"]),
        "window_px": array("Window height, width around each incident point.", INTEGER, "pixels"),
        "pitch_mm": field("number", "Pixel size.", "mm"),
        "dtype": field("string", "Storage of R_d: float32 or float16."),
        **_INFO_ANGLES,
        **_STORE,
    },
)
INFO_MESH = record(
    "`translucency info MESH.zarr --json`.",
    {
        **_INFO,
        "what": field("string", "What it is.", enum=["mesh data set"]),
        "n_vertices": field("integer", "Vertices of the mesh."),
        "n_faces": field("integer", "Triangles of the mesh."),
        "index_matched": field(["boolean", "null"], "No Fresnel reflection at the surface."),
        "reentry": field(
            ["boolean", "null"],
            "A tally: light leaving one part through the air walked on in the next (null: photographs).",
        ),
        "unscattered": field(
            ["array", "null"],
            "A tally: the mean fraction of a beam that left without scattering, kept apart from R_d, R, G, B "
            "(null: counted in R_d, or photographs).",
            items=NUMBER,
        ),
        **_INFO_ANGLES,
        **BOUNDS,
        **_STORE,
    },
)

# -- materials ----------------------------------------------------------------------------------------
MATERIALS = record(
    "`translucency materials --json`: Jensen et al. 2001's measured materials.",
    {
        "command": _command("materials"),
        "eta": field("number", "Relative index of refraction of the dipole's R_d (--eta)."),
        "materials": record(
            "By name.",
            {},
            extra=record(
                "One material.",
                {
                    "sigma_s_prime": field(
                        "array", "Reduced scattering coefficient, R, G, B.", "1/mm", items=NUMBER
                    ),
                    "sigma_a": field("array", "Absorption coefficient, R, G, B.", "1/mm", items=NUMBER),
                    "R_d_dipole": field(
                        "array", "The dipole's total diffuse reflectance at eta.", items=NUMBER
                    ),
                    "R_d_published": field("array", "Jensen's published R_d (2 digits).", items=NUMBER),
                },
            ),
        ),
    },
)

#: the schema of each command's ``--json`` output (``info``: one per kind of path, by its ``what``)
SCHEMAS = {
    "demo": DEMO,
    "acquire planar": ACQUIRE_PLANAR,
    "acquire mesh": ACQUIRE_MESH,
    "acquire photographs": ACQUIRE_PHOTOGRAPHS,
    "acquire object-photographs": ACQUIRE_OBJECT_PHOTOGRAPHS,
    "import images": IMPORT_IMAGES,
    "import object": IMPORT_OBJECT,
    "fit": FIT,
    "evaluate": EVALUATE,
    "evaluate (mesh data set)": EVALUATE_MESH,
    "render": RENDER,
    "render (scene)": RENDER_SCENE,
    "export": EXPORT,
    "view": VIEW,
    "info (model file)": INFO_MODEL,
    "info (planar data set)": INFO_PLANAR,
    "info (mesh data set)": INFO_MESH,
    "materials": MATERIALS,
}
_INFO_BY_WHAT = {"model": INFO_MODEL, "planar data set": INFO_PLANAR, "mesh data set": INFO_MESH}


def schema_of(summary: dict) -> dict:
    """The schema a command's summary follows (by its ``command``, and ``info``'s by its ``what``)."""
    if summary.get("command") == "info":
        return _INFO_BY_WHAT[summary.get("what")]
    if summary.get("command") == "evaluate" and summary.get("geometry") == "mesh":
        return EVALUATE_MESH
    if summary.get("command") == "render" and "scene" in summary:
        return RENDER_SCENE
    return SCHEMAS[summary["command"]]


def check(value, schema: dict, where: str = "") -> list[str]:
    """Where ``value`` breaks ``schema``: one line each (empty: it follows it)."""
    types = schema.get("type")
    types = [types] if isinstance(types, str) else types
    name = where or "(top)"
    if types is not None and not any(_is(value, t) for t in types):
        return [f"{name}: expected {' or '.join(types)}, got {type(value).__name__} {value!r}"[:200]]
    if "enum" in schema and value not in schema["enum"]:
        return [f"{name}: expected one of {schema['enum']}, got {value!r}"]
    errors = []
    if isinstance(value, dict):
        props = schema.get("properties", {})
        errors += [f"{where}.{k}: missing".lstrip(".") for k in schema.get("required", ()) if k not in value]
        extra = schema.get("additionalProperties", True)
        for key, v in value.items():
            path = f"{where}.{key}" if where else key
            if key in props:
                errors += check(v, props[key], path)
            elif extra is False:
                errors.append(f"{path}: not documented (docs/_gen/json_schemas.py, docs/json.md)")
            elif isinstance(extra, dict):
                errors += check(v, extra, path)
    if isinstance(value, list) and "items" in schema:
        for i, v in enumerate(value):
            errors += check(v, schema["items"], f"{where}[{i}]")
    return errors


def _is(value, type_: str) -> bool:
    if isinstance(value, bool) and type_ in ("integer", "number"):
        return False
    return isinstance(value, _TYPES[type_])


# -- docs/json.md -------------------------------------------------------------------------------------
_INTRO = """\
# JSON output of the commands

<!-- written by `python docs/_gen/json_schemas.py > docs/json.md`: edit the schemas there, not this page -->

Every command that takes `--json` prints one JSON object on stdout and nothing else there (progress and
warnings go to stderr): numbers as numbers, booleans as booleans, objects as objects, nothing cut short;
NaN and infinity as `null`. `evaluate --json-out PATH` writes the same object to a file. Errors are one
`error:` line on stderr, exit status 2.

Below, each command's keys, their types and units ("fraction": 0.05 is 5 %). `a.b` is key `b` inside
object `a`; `a.*` any key of an object keyed by names. The tables are written from the same schemas
the test suite checks every command's actual output against.
"""


def _type_text(schema: dict) -> str:
    t = schema.get("type", "any")
    t = " or ".join(t) if isinstance(t, list) else t
    if "items" in schema and isinstance(schema["items"], dict) and "type" in schema["items"]:
        inner = schema["items"]["type"]
        t += f" of {' or '.join(inner) if isinstance(inner, list) else inner}"
    if "enum" in schema:
        t += ": " + ", ".join(f"`{v}`" for v in schema["enum"])
    return t


def _rows(schema: dict, prefix: str = ""):
    for key, sub in schema.get("properties", {}).items():
        name = f"{prefix}{key}"
        optional = key not in schema.get("required", ())
        yield name, _type_text(sub), sub.get("unit", ""), sub.get("description", ""), optional
        if sub.get("properties") or isinstance(sub.get("additionalProperties"), dict):
            yield from _rows(sub, f"{name}.")
    extra = schema.get("additionalProperties")
    if isinstance(extra, dict):
        name = f"{prefix}*"
        yield name, _type_text(extra), extra.get("unit", ""), extra.get("description", ""), True
        if extra.get("properties"):
            yield from _rows(extra, f"{name}.")


def markdown() -> str:
    """docs/json.md: every command's keys, types and units."""
    lines = [_INTRO]
    for name, schema in SCHEMAS.items():
        lines += [
            f"## {name}",
            "",
            schema["description"],
            "",
            "| key | type | unit | meaning |",
            "|---|---|---|---|",
        ]
        for key, type_, unit, text, optional in _rows(schema):
            lines.append(f"| `{key}` | {type_} | {unit} | {text}{' (optional)' if optional else ''} |")
        lines.append("")
    return "\n".join(lines)


if __name__ == "__main__":  # pragma: no cover — writes docs/json.md
    print(markdown(), end="")
