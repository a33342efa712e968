"""Transitional: the alternation now lives in :mod:`._rounds` and the modules beside it.

Only ``translucency._resources`` still imports :data:`FIT_BLOCK` from here; once it imports
``translucency.fit.FIT_BLOCK`` this module goes.
"""

from ._chunk import FIT_BLOCK

__all__ = ["FIT_BLOCK"]
