"""α's disc pool on a mesh's vertices (fit/_vertex_pool.py): through cells on a scan finer than the disc, the
same sums as every pair within the radius, to within the cells at the rim — and memory that does not grow
with the disc's vertex count."""

from __future__ import annotations

import numpy as np
import trimesh

from translucency.fit._vertex_pool import VertexDiscPool
from translucency.fit.mesh import ALPHA_RADIUS_MM, alpha_pool_radius


def test_the_pool_through_cells_sums_the_disc_as_every_pair_does():
    ball = trimesh.creation.icosphere(5, radius=15.0)  # 10,242 vertices, edges ~0.8 mm
    v = np.asarray(ball.vertices)
    exact = VertexDiscPool(v, 4.0)
    cells = VertexDiscPool(v, 4.0, max_entries=0)
    assert not exact.cells and cells.cells
    count = exact(np.ones(len(v)))
    assert np.abs(cells(np.ones(len(v))) / count - 1).max() < 0.15  # the rim's cells in or out
    # a smooth statistic's pooled ratio (what α is: Σ num / Σ den) agrees closely
    rng = np.random.default_rng(0)
    num, den = 1.0 + 0.3 * v[:, 0] / 15.0 + 0.05 * rng.standard_normal(len(v)), np.ones(len(v))
    assert np.abs(cells(num) / cells(den) - exact(num) / exact(den)).max() < 0.02
    # the cells' operator holds a few dozen entries a vertex whatever the resolution (here 60 against the
    # disc's 180; on the 338 k-vertex pig 60 against 2,000)
    held = (cells._M.nnz + cells._S.nnz) / len(v)
    assert held < 80 and held < 0.5 * exact.matrix.nnz / len(v), (held, exact.matrix.nnz / len(v))


def test_the_default_alpha_disc_does_not_shrink_with_the_scan():
    assert alpha_pool_radius(1.0) == 12.0  # 12 edges on a coarse mesh
    assert alpha_pool_radius(0.18) == ALPHA_RADIUS_MM  # a scan finer than the pig's keeps the disc in mm
