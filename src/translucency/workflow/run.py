"""How a run of the library goes (:mod:`translucency.resources.run`), as the command line reaches it: the
:class:`Reporter` it hears, the runs under way that a failure or Ctrl-C ends, a summary made strict JSON."""

from ..resources.run import (
    Reporter,
    Run,
    Silent,
    Work,
    bytes_at,
    failed,
    interrupted,
    jsonable,
    kept_chunks,
    kept_note,
)

__all__ = [
    "Reporter",
    "Run",
    "Silent",
    "Work",
    "bytes_at",
    "failed",
    "interrupted",
    "jsonable",
    "kept_chunks",
    "kept_note",
]
