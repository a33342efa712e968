"""The page's camera and light by default, and the lights' strengths: a directional light of
:data:`IRRADIANCE`, a point light as bright at :data:`POINT_DISTANCE` object sizes.

Directions are (azimuth, elevation) in degrees about +z; lengths in mm.
"""

from __future__ import annotations

import math

#: the default camera: as ``render --view 1,-1.6,0.7`` (azimuth, elevation in degrees)
DEFAULT_VIEW = (math.degrees(math.atan2(-1.6, 1.0)), math.degrees(math.atan2(0.7, math.hypot(1.0, 1.6))))
#: the default light: directional, from this azimuth and elevation (degrees)
DEFAULT_LIGHT = (-30.0, 40.0)
#: a directional light's irradiance (W/mm²); point lights get the intensity that gives it at the
#: default distance
IRRADIANCE = 1.0
#: a point light's distance by default, object sizes (as ``render``'s relative lights)
POINT_DISTANCE = 1.5


def point_intensity(size: float) -> float:
    """I (W/sr) of a point light that gives the directional light's irradiance at the default distance
    from an object of ``size`` mm.

    Examples
    --------
    >>> point_intensity(10.0)  # (1.5 × 10 mm)² × 1 W/mm²
    225.0
    """
    return IRRADIANCE * (POINT_DISTANCE * size) ** 2


def direction(az: float, el: float) -> tuple:
    """The unit vector toward azimuth ``az`` and elevation ``el`` (degrees; +z up).

    Examples
    --------
    >>> [round(v, 6) for v in direction(90.0, 0.0)]
    [0.0, 1.0, 0.0]
    """
    a, e = math.radians(az), math.radians(el)
    return (math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e))
