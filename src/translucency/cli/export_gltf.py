"""``export --gltf``: the bake (the exitance under a light, as ``render`` computes it) and the per-vertex
Christensen–Burley reduction of each vertex's profile, written as glTF (:mod:`translucency.io.gltf`)."""

from __future__ import annotations

import numpy as np

from ..io.gltf import MM_PER_GLTF_UNIT, write_glb
from ..model.burley import burley_of_exponentials, burley_shape
from ..render import boundary_eta, relight_vertices, transport_matrices, vertex_irradiance
from ..render.lights import Placement, parse_light, place_light
from ..render.parameters import vertex_parameters


def export_gltf(model, mesh, acquisition: dict, path, light_text: str) -> dict:
    """Write ``path`` and return what the summary states (the reduction's error, the colour's scale)."""
    from ..mitsuba import mesh_scene  # Mitsuba loads only to bake

    # each vertex's profile: α × colour scale × the blended sum of exponentials (render's blend)
    c, d, s = vertex_parameters(model, mesh)
    alpha = np.asarray(model.alpha.values, dtype=np.float64)
    A, burley_s, error = burley_of_exponentials(c, d)  # (V, C)
    A = A if A.shape[1] == 3 else np.repeat(A, 3, axis=1)
    burley_s = burley_s if burley_s.shape[1] == 3 else np.repeat(burley_s, 3, axis=1)
    error = error if error.shape[1] == 3 else np.repeat(error, 3, axis=1)
    albedo = np.clip(alpha[:, None] * s * A, 0.0, None)
    mfp = burley_shape(np.clip(albedo, 0.0, 1.0), 1.0) / burley_s  # ℓ = s̃(A)/s, mm (searchlight)
    # the bake: the irradiance with shadows and the transport (render's chain, a Lambertian exit)
    eta = boundary_eta(acquisition)
    transport = transport_matrices(model, mesh)
    lit = place_light(parse_light(light_text), Placement.of(mesh, (1.0, -1.6, 0.7)))
    law = transport.incidence("half-space", eta)
    E = vertex_irradiance(mesh, mesh_scene(mesh), lit, eta, law)
    radiance = relight_vertices(transport, E).astype(np.float64)  # W/(mm² sr)
    top = float(np.quantile(radiance, 0.99)) if np.any(radiance > 0) else 1.0
    scale = 1.0 / top if top > 0 else 1.0
    extras = {
        "written_by": "translucency",
        "units": {"positions": "m", "_MFP_MM": "mm", "_BURLEY_S": "1/mm"},
        "up": "+Y, our +z: (x, y, z) -> (x, z, -y)",
        "colour": "COLOR_0 = radiance x colour_scale (linear; Lambertian exit), clipped to 1",
        "colour_scale": scale,
        "light": light_text,
        "burley": "R(r) = A s (exp(-s r) + exp(-s r/3)) / (8 pi r); _MFP_MM = searchlight s~(A) / s",
        "mm_per_unit": MM_PER_GLTF_UNIT,
    }
    attributes = {
        "_ALBEDO": albedo,
        "_MFP_MM": np.nan_to_num(mfp, nan=0.0, posinf=0.0),
        "_BURLEY_S": np.nan_to_num(burley_s, nan=0.0, posinf=0.0),
        "_REDUCTION_ERROR": np.nan_to_num(error, nan=1.0),
    }
    write_glb(path, mesh.vertices, mesh.faces, radiance * scale, attributes, extras)
    finite = error[np.isfinite(error)]
    return {
        "colour_scale": scale,
        "reduction_error_median": float(np.median(finite)) if finite.size else float("nan"),
        "reduction_error_p95": float(np.quantile(finite, 0.95)) if finite.size else float("nan"),
    }
