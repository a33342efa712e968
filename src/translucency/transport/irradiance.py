r"""Irradiance at the vertices: what a light brings to every vertex of the object, shadows included.

.. math:: E_v = \int L(\omega)\, V_v(\omega)\, \cos^+\theta_i\, \frac{F_t(\theta_i)}{F_t(0)}\,
          F_v(\cos\theta_i)\, d\omega \qquad \text{(W/mm²)},

with :math:`V_v` the visibility (shadow rays traced by Mitsuba) and :math:`\theta_i` the angle of arrival
to the vertex normal; each light evaluates it its own way
(:meth:`translucency.render.lights.Light.irradiance_at`: one direction for a point, spot or directional
light, K sampled directions for a constant sky or an environment map, importance-sampled by Mitsuba's
``envmap`` emitter).

**Boundary.**  For an object acquired behind a dielectric boundary (index η) the measured R_d already holds
the transmission of the normally incident calibration beam, :math:`F_t(0)`; a light arriving at
:math:`\theta_i` is therefore scaled by :math:`F_t(\theta_i)/F_t(0)` (1 for index-matched objects, η = 1).
The exit side is :func:`translucency.transport.relight.exit_fresnel`.

**Incidence.**  The data's beams arrive normally; light arriving at :math:`\theta_i` enters shallower and
more of it comes back.  With an incidence law (:mod:`translucency.model.incidence`, ``half-space`` by
default) each arriving direction is weighted by Chandrasekhar's :math:`F_v = F(\cos\theta_i; R_{1,v}) =
R(\cos\theta_i)/R(1)` per vertex and channel, R_1 the vertex's measured total
(:attr:`translucency.transport.relight.Transport.reflectance`), so the irradiance becomes (V, 3): the
*effective* irradiance.
"""

from __future__ import annotations

import numpy as np


def vertex_irradiance(mesh, scene, light, eta: float = 1.0, incidence=None, at=None) -> np.ndarray:
    r"""Irradiance E (W/mm²) at every vertex, with shadows (Mitsuba ``ray_test``).

    (V,) for the grey lights, (V, 3) for an environment map or with an incidence law.  With ``eta`` ≠ 1
    each arriving direction is weighted by :math:`F_t(\theta_i)/F_t(0)` (module docstring).
    ``incidence`` (:class:`~translucency.model.incidence.HalfSpaceIncidence`, or None / ``NormalIncidence``:
    none) weights each arriving direction by how much more a point sends back of light arriving at
    :math:`\theta_i` than of the normal incidence its data were measured with, per channel
    (:mod:`translucency.model.incidence`).
    ``at``: the vertices (indices) to compute it at (all by default; ``incidence`` then holds those).
    Raises a one-line error for a point light inside the object.

    Examples
    --------
    >>> import trimesh
    >>> from translucency.mitsuba import mesh_scene
    >>> from translucency.render import DirectionalLight
    >>> ball = trimesh.creation.icosphere(2, radius=5.0)
    >>> sun = DirectionalLight((0.0, 0.0, -1.0), irradiance=2.0)  # from straight above
    >>> E = vertex_irradiance(ball, mesh_scene(ball), sun)
    >>> E.shape, bool(np.allclose(E, 2.0 * np.maximum(ball.vertex_normals[:, 2], 0.0)))  # E cos⁺θ
    ((162,), True)
    >>> top = int(np.argmax(ball.vertices[:, 2]))
    >>> vertex_irradiance(ball, mesh_scene(ball), sun, eta=1.4, at=[top])  # normal incidence: F_t(0)/F_t(0)
    array([2.])
    >>> roof = trimesh.creation.box(extents=(30.0, 30.0, 1.0)).apply_translation((0.0, 0.0, 20.0))
    >>> float(vertex_irradiance(ball, mesh_scene(trimesh.util.concatenate([ball, roof])), sun).max())
    0.0
    """
    v = np.asarray(mesh.vertices, dtype=np.float64)
    n = np.asarray(mesh.vertex_normals, dtype=np.float64)
    if at is not None:
        v, n = v[at], n[at]
    return light.irradiance_at(scene, v, n, float(np.max(mesh.extents)), eta, incidence)
