"""How a run of the library goes (:mod:`translucency.resources.run`), as the command line reaches it: the
:class:`Reporter` it hears, the runs under way that a failure or Ctrl-C ends, a summary made strict JSON."""

from ..resources.run import Reporter, Run, failed, interrupted, jsonable

__all__ = ["Reporter", "Run", "failed", "interrupted", "jsonable"]
