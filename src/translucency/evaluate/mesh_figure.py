"""The figure of a mesh evaluation: error against distance, and the error per vertex on the object."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .._plotting import pyplot
from .labels import noise_label


def plot_mesh_errors(errors: dict, vertices, faces, incident, out_path, *, held_out: bool) -> Path:
    """Write ``out_path`` (PNG): left, every model's relative error of R_d per ring of r = |v − x_i| with the
    reference's noise floor; right, the first model's error per outgoing vertex (pairs with r below its
    ``map_radius``) on the object's triangles (``faces``, each the mean of its corners) seen from the front
    (−y) and the back (+y), incident vertices marked.

    ``errors``: label -> :class:`~translucency.evaluate.mesh_errors.MeshErrors`; ``held_out``: the
    reference is an independent truth (captions say so), else the fitted data.
    """
    plt = pyplot()
    vertices = np.asarray(vertices, dtype=np.float64)
    faces = np.asarray(faces)
    incident = np.asarray(incident)
    fig = plt.figure(figsize=(13.5, 4.4), layout="constrained")
    grid = fig.add_gridspec(1, 3, width_ratios=[1.0, 1.25, 1.25])
    first = next(iter(errors.values()))
    _distance_panel(fig.add_subplot(grid[0]), errors, first, held_out)
    label = next(iter(errors))
    values = 100 * first.per_vertex
    finite = values[np.isfinite(values)]
    vmax = float(np.percentile(finite, 95)) if finite.size else 1.0
    cmap = plt.get_cmap("magma").with_extremes(bad="0.85")
    corners = vertices[faces]  # (F, 3, 3)
    normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    face_value = values[faces].mean(axis=1)  # NaN where a corner has no pair within map_radius
    for k, (side, sign) in enumerate((("seen from −y", 1.0), ("seen from +y", -1.0))):
        axm = fig.add_subplot(grid[k + 1])
        seen = np.flatnonzero(sign * normal[:, 1] < 0)  # the triangles facing this viewer
        seen = seen[np.argsort(-sign * corners[seen, :, 1].mean(axis=1))]  # painter's order: nearest last
        shade = _object_panel(axm, corners[seen], face_value[seen], cmap, vmax, sign)
        lit = incident[np.isin(incident, faces[seen])]  # incident vertices on a triangle facing the viewer
        axm.plot(sign * vertices[lit, 0], vertices[lit, 2], "c+", ms=6, mew=1.0)
        axm.autoscale_view()
        axm.set_aspect("equal")
        axm.set_xlabel("x (mm)" if sign > 0 else "−x (mm)")
        axm.set_ylabel("z (mm)")
        axm.set_title(f"error per vertex, {side}\n{label}", fontsize=10)
    fig.colorbar(
        shade, ax=axm, shrink=0.85, label=f"relative error (%), pairs with r < {first.map_radius:g} mm"
    )
    fig.text(
        0.99,
        0.01,
        f"grey: no incident point within {first.map_radius:g} mm; +: incident points on that side",
        ha="right",
        fontsize=8,
    )
    out_path = Path(out_path)
    fig.savefig(out_path, dpi=110)
    plt.close(fig)
    return out_path


def _distance_panel(ax, errors: dict, first, held_out: bool) -> None:
    """Every model's relative error (%) per ring of r against the geometric ring centre (mm), noise dashed."""
    reference = "the truth" if held_out else "the fitted data"
    edges = first.distance["edges_mm"]
    mid = np.sqrt(np.maximum(edges[:-1], edges[1] / 2) * edges[1:])  # geometric ring centres, mm
    for name, e in errors.items():
        ax.plot(mid, 100 * e.distance["rel_l2"], "o-", ms=3, label=name)
    ax.plot(mid, 100 * first.distance["noise"], "k--", lw=1, label=noise_label(held_out))
    for b in (1.0, 4.0):
        ax.axvline(b, color="0.8", lw=0.8, zorder=0)
    ax.set_xscale("log")
    ax.set_xlabel("r = |v − x_i| (mm)")
    ax.set_ylabel(f"relative L2 error of R_d against {reference} (%)")
    ax.set_title("error against distance (rings)")
    ax.legend(fontsize=8)


def _object_panel(axm, corners, face_value, cmap, vmax: float, sign: float):
    """The facing triangles (x, z in mm, x mirrored from behind) coloured by their error (%), 0 to vmax."""
    from matplotlib.collections import PolyCollection  # heavy: matplotlib loads only where a figure is drawn

    polygons = np.stack([sign * corners[:, :, 0], corners[:, :, 2]], axis=-1)
    shade = PolyCollection(polygons, cmap=cmap, linewidths=0, antialiased=False)
    shade.set_array(np.ma.masked_invalid(face_value))
    shade.set_clim(0, vmax)
    axm.add_collection(shade)
    return shade
