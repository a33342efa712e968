"""The measured object as a medium: scattering and absorption estimated from the scan alone
(:mod:`.estimate`), for the walk of the light that crosses the body (:mod:`translucency.transport.walk`)
and for a Mitsuba scene a user can path-trace (:mod:`translucency.render.medium_scene`)."""

from .estimate import Medium, estimate_medium, medium_of
from .scan import Exits, virtual_scan, walk_beams

__all__ = ["Exits", "Medium", "estimate_medium", "medium_of", "virtual_scan", "walk_beams"]
