"""The library's messages in the command line's words.

A :class:`~translucency._validate.TranslucencyError` (or warning) raised by the library names the Python
argument at fault (``overwrite=True``, ``scale_mm=1000``, ``out /data/x.zarr: …``); the command prints
it with the flag a user types instead (``--overwrite``, ``--scale 1000``, ``--out /data/x.zarr: …``).
:data:`FLAGS` is the one table of Python argument → flag; :func:`cli_words` applies it.
"""

from __future__ import annotations

import re

#: Python argument → the flag of the command line that sets it (only names that a library message reaching
#: the command line uses as an argument: a header field such as ``chunk_points`` must stay as it is)
FLAGS = {
    "overwrite": "--overwrite",
    "out": "--out",
    "out_dir": "--out",
    "scale_mm": "--scale",
    "n_terms": "--terms",
    "n_directions": "--directions",
    "max_rounds": "--rounds",
    "exclusion_mm": "--exclusion",
    "alpha_radius": "--alpha-radius",
    "max_memory": "--max-memory",
    "exit_law": "--exit-law",
    "family": "--model",
    "float16": "--dtype float16",
    "max_depth": "--max-depth",
    "picture_spp": "--picture-spp",
    "scene_unit": "--scene-unit",
    # options whose library name is the flag's word (``terms: …``, ``light: …``); not ``model``, which
    # library messages also use for the model file
    "terms": "--terms",
    "directions": "--directions",
    "colour": "--colour",
    "weighting": "--weighting",
    "material": "--material",
    "light": "--light",
    "points": "--points",
    "size": "--size",
    "view": "--view",
    "incidence": "--incidence",
    "spp": "--spp",
    "radius": "--radius",
    "exposure": "--exposure",
    "samples": "--irradiance-samples",
    "passes": "--passes",
    "roughness": "--roughness",
    "eta": "--eta",
    "ply": "--ply",
    "gltf": "--gltf",
    "mitsuba": "--mitsuba",
    "truth": "--truth",
    "compare": "--compare",
    "report": "--report",
    "json_out": "--json-out",
    "scheduler": "--scheduler",
    "bands": "--bands",
    "port": "--port",
    "sky": "--sky",
    "export": "--export",
    "reference_render": "--reference-render",
    "objects": "--object",
    "profiles": "--profiles",
    "gain": "--gain",
    "extra_cameras": "--extra-camera",
}

#: arguments translated only where a message begins with them and a colon (``chunk_points: …``), the place
#: a message names the argument at fault: they are also fields of a file or a data set's header
#: (``chunk_points``, ``voxel_mm``) or words that begin other sentences (``format version …``, ``up to …``)
AT_START = {
    "photons": "--photons",
    "seed": "--seed",
    "grid": "--grid",
    "pitch": "--pitch",
    "voxel": "--voxel",
    "g": "--g",
    "angle": "--tilt",
    "chunk": "--chunk",
    "dtype": "--dtype",
    "up": "--up",
    "unscattered": "--unscattered",
    "scale": "--scale",
    "fov": "--fov",
    "resolution": "--resolution",
    "cameras": "--cameras",
    "supersample": "--supersample",
    "dilate": "--dilate",
    "eta": "--eta",
    "chunk_points": "--chunk",
    "voxel_mm": "--voxel",
    "sample_seed": "--sample-seed",
    "image_format": "--format",
    "beam_mm": "--beam",
    "specular_radius": "--specular-radius",
    "beam_rms": "--beam-rms",
    "sample_size": "--sample-size",
}

#: arguments that are paths: translated where a message begins with the argument and its path
#: (``mesh /data/ball.ply: …``); a library ``sample`` given as a path is the command line's ``--volume``
PATHS = {"mesh": "--mesh", "volume": "--volume", "sample": "--volume", "calibration": "--calibration"}

#: arguments that are also plain words ("out", "scale"): translated only where a message begins with
#: them, the place a message names the argument at fault (``out PATH: …``)
_WORDS = {name for name in FLAGS if "_" not in name}

# ``name=True`` → ``--flag``; ``name=VALUE`` → ``--flag VALUE`` (quotes of a string value dropped)
_ASSIGNED = re.compile(r"(?<![\w./-])([a-z][a-z0-9_]*)=(True\b|'[^']*'|\"[^\"]*\"|[^\s,;:)]+)")
# a bare argument with an underscore (``n_terms``), not part of a longer name or path, nor a file's field
# in backquotes (`scale_mm` of a rig file)
_BARE = re.compile(r"(?<![\w./`-])([a-z][a-z0-9]*(?:_[a-z0-9]+)+)(?![\w/=-]|\.\w)")
# the argument a message begins with: ``out PATH: …`` or ``name: …``
_LEADING = re.compile(r"^([a-z][a-z0-9_]*)(?=[ :])")
# an argument of AT_START a message begins with: ``name: …``
_NAMED = re.compile(r"^([a-z][a-z0-9_]*)(?=:)")
# a path argument a message begins with: ``mesh PATH: …`` (a path: a word with a slash or a dot)
_PATH = re.compile(r"^([a-z][a-z0-9_]*)(?= \S*[/.]\S*:)")


def cli_words(message: str) -> str:
    """``message`` with every Python argument of :data:`FLAGS` replaced by its flag.

    Examples
    --------
    >>> cli_words("out /tmp/m.model.zip: already there; choose another path or pass overwrite=True")
    '--out /tmp/m.model.zip: already there; choose another path or pass --overwrite'
    >>> cli_words("ball.ply: the object is 0.2 mm across at scale_mm=1 mm per unit — scale_mm=1000?")
    'ball.ply: the object is 0.2 mm across at --scale 1 mm per unit — --scale 1000?'
    >>> cli_words("n_terms: must be between 1 and 4; the output stays as it is")
    '--terms: must be between 1 and 4; the output stays as it is'
    >>> cli_words("chunk_points: must be >= 1, got 0; header fields n_points 3, chunk_points 4")
    '--chunk: must be >= 1, got 0; header fields n_points 3, chunk_points 4'
    >>> cli_words("mesh /data/ball: is a folder, not a mesh file")
    '--mesh /data/ball: is a folder, not a mesh file'
    """

    def assigned(match: re.Match) -> str:
        name, value = match.groups()
        if name not in FLAGS:
            return match.group(0)
        return FLAGS[name] if value == "True" else f"{FLAGS[name]} {value.strip(chr(39) + chr(34))}"

    def bare(match: re.Match) -> str:
        return FLAGS.get(match.group(1), match.group(1))

    def leading(match: re.Match) -> str:
        return FLAGS[match.group(1)] if match.group(1) in _WORDS else match.group(1)

    text = _ASSIGNED.sub(assigned, message)
    text = _BARE.sub(bare, text)
    text = _PATH.sub(lambda match: PATHS[match.group(1)] if match.group(1) in PATHS else match.group(1), text)
    text = _NAMED.sub(lambda match: AT_START.get(match.group(1), match.group(1)), text)
    return _LEADING.sub(leading, text)
