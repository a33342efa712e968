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
    "batch_photons": "--batch",
    "max_memory": "--max-memory",
    "exit_law": "--exit-law",
    "family": "--model",
    "float16": "--float16",
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
    "spp": "--spp",
    "radius": "--radius",
    "size": "--size",
    "view": "--view",
    "exposure": "--exposure",
    "incidence": "--incidence",
    "samples": "--samples",
    "passes": "--passes",
    "roughness": "--roughness",
    "eta": "--eta",
    "ply": "--ply",
    "gltf": "--gltf",
    "truth": "--truth",
    "compare": "--compare",
    "report": "--report",
    "json_out": "--json-out",
    "scheduler": "--scheduler",
    "bands": "--bands",
    "port": "--port",
    "sky": "--sky",
    "export": "--export",
    "reference_render": "--reference",
}

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
    return _LEADING.sub(leading, text)
