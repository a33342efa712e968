"""The measured object as a medium: scattering and absorption estimated from the scan alone
(:mod:`.estimate`), for the walk of the light that crosses the body (:mod:`translucency.transport.walk`)
and for a Mitsuba scene a user can path-trace (:mod:`translucency.medium.mitsuba_scene`)."""

from .estimate import Medium, estimate_medium, medium_of

__all__ = ["Medium", "estimate_medium", "medium_of"]
