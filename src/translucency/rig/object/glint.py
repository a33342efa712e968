r"""The laser's specular glint on a dielectric boundary, found and set aside (step 3 of :mod:`.importer`).

Behind a boundary of index η > 1 part of the beam, :math:`F(\theta)` (2.8 % at η = 1.4 and normal
incidence), is reflected at the hit without entering.  A smooth boundary sends it along the mirror
direction :math:`m = 2(n\cdot l)\,n - l` of the direction :math:`l` toward the laser; a real surface
spreads it into a lobe about m.  A camera whose direction to the hit lies within ``glint_deg`` of m
sees the hit's pixels lit by the glint on top of the light that crossed the object — light that is no
part of R_d and whose share no model of the import knows (it depends on the surface's roughness).  Those
pixels are **set aside** in that camera: not used, and no lower bound where they clip; the other cameras
see the same cells, and where none does the near-peak model fills them (:mod:`.near_peak`).

The pixels set aside are those within ``radius_px`` of the hit's projection (a disc of the laser's spot
and the pixel's own footprint).  Units: degrees, pixels.
"""

from __future__ import annotations

import numpy as np

#: the default half-angle (degrees) about the mirror direction within which a camera sees the glint
GLINT_DEG = 30.0
#: the default radius (pixels) about the hit's projection set aside in such a camera
GLINT_RADIUS_PX = 2.0


def mirror(normal: np.ndarray, toward_laser: np.ndarray) -> np.ndarray:
    """The mirror direction of the beam at a surface of unit ``normal``: 2 (n · l) n − l (unit).

    Examples
    --------
    >>> mirror(np.array([0.0, 0, 1]), np.array([0.0, 0.6, 0.8])).round(3).tolist()
    [0.0, -0.6, 0.8]
    """
    l = np.asarray(toward_laser, dtype=np.float64)
    n = np.asarray(normal, dtype=np.float64)
    m = 2.0 * float(n @ l) * n - l
    return m / np.linalg.norm(m)


def glint_pixels(camera, used: np.ndarray, hit, normal, toward_laser, *, glint_deg=GLINT_DEG,
                 radius_px=GLINT_RADIUS_PX) -> np.ndarray:  # fmt: skip
    """Which of a camera's ``used`` pixels (flat indices, row by row) the glint may light (bool, len(used)).

    None are when the camera's direction to ``hit`` lies more than ``glint_deg`` from the mirror direction
    (:func:`mirror`), or the hit projects outside its image; else those within ``radius_px`` of where it
    projects.

    Examples
    --------
    A camera looking straight down at a hit lit from straight above sees the glint; one 60° off does not:

    >>> from translucency.rig.object.cameras import Camera
    >>> above = Camera.looking_at((0.0, 0, 100), (0.0, 0, 0), 64, 48, fov_deg=20)
    >>> side = Camera.looking_at((0.0, 86.6, 50), (0.0, 0, 0), 64, 48, fov_deg=20)
    >>> used = np.arange(64 * 48)
    >>> n = np.array([0.0, 0, 1])
    >>> above.project(np.zeros((1, 3))).round(2).tolist()  # between four pixels' centres
    [[31.5, 23.5]]
    >>> int(glint_pixels(above, used, np.zeros(3), n, n).sum())  # the centres within 2 px of it
    12
    >>> int(glint_pixels(side, used, np.zeros(3), n, n).sum())
    0
    """
    hit = np.asarray(hit, dtype=np.float64)
    to_cam = camera.centre - hit
    to_cam /= np.linalg.norm(to_cam)
    aside = np.zeros(len(used), dtype=bool)
    if float(to_cam @ mirror(normal, toward_laser)) < np.cos(np.radians(glint_deg)):
        return aside
    u, v = camera.project(hit[None])[0]
    if not (-radius_px <= u < camera.width + radius_px and -radius_px <= v < camera.height + radius_px):
        return aside
    row, col = np.divmod(np.asarray(used), camera.width)
    return (col - u) ** 2 + (row - v) ** 2 <= radius_px**2
