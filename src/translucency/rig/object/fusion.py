r"""Fusion of the cameras' cell means into one exitance per vertex, and its flags (steps 5–6 of
:mod:`.importer`).

A camera counts for a vertex where it sees at least ``min_coverage`` of the cell with usable pixels, at
least :data:`FUSED_COVERAGE` of what the best camera covers, and lost none of it to saturated pixels (a
cell averaged over its unsaturated part only would read low: that camera's view of it is dropped and
counted; a cell one camera saw saturated counts as measured only where another saw it whole); the
weights
:math:`w_c = n_c\,\gamma_c` (:math:`n_c` the cell's effective number of pixels) do not depend on the
measured values.  R in mm⁻² per unit incident power, its variance in mm⁻⁴; the flag bits
(:data:`UNSEEN`, :data:`SATURATED`, :data:`GRAZING`, :data:`SPOT`) say what kept a pair from being
measured: a cell no camera measured because of saturation is :data:`SATURATED` (recovered near the
hit by :mod:`.near_peak`), one no camera saw well is :data:`UNSEEN` (filled, :mod:`.fill`).
"""

from __future__ import annotations

import numpy as np

from .setup import ObjectRig
from .views import CameraView

#: flag bits of ``flags`` (P, V) uint8
UNSEEN, SATURATED, GRAZING, SPOT = 1, 2, 4, 8

#: a camera's view of a cell is fused only where it covers at least this fraction of what the best
#: camera covers: a view of part of a cell measures the mean over that part, not the cell's mean
FUSED_COVERAGE = 0.9


#: a camera's view of a cell that lost more than this fraction of its weight to saturated pixels is dropped
SATURATED_LOSS = 1e-6


def fuse(per_cam, cameras: list[CameraView], area, rig: ObjectRig):
    """Exitance per vertex fused over cameras (steps 4–5 of :mod:`.importer`): R (V, 3), variance (V, 3),
    flags (V,), the number of cameras' views of a cell dropped for saturated pixels, and the least value
    the clipped pixels over each cell allow (V, 3; 0 where none clipped): the most any camera's clipped
    pixels hold over the part of the cell they cover, per unit of the cell's area (the rest at least 0)."""
    V = len(area)
    num = np.zeros((V, 3))
    den = np.zeros(V)
    var = np.zeros((V, 3))
    flags = np.zeros(V, np.uint8)
    grazing = np.zeros(V, dtype=bool)
    saturated = np.zeros(V, dtype=bool)
    weights = []
    dropped = 0
    whole = np.zeros(V, dtype=bool)  # some camera measured the cell whole, unsaturated
    bound = np.full((V, 3), np.nan)  # the least value clipped pixels allow
    best = np.zeros(V)  # the largest usable coverage of each cell by any camera
    for cm in per_cam:
        if cm is not None:
            best = np.maximum(best, cm[2] / np.maximum(area, 1e-30))
    for cam, cm in zip(cameras, per_cam):
        if cm is None:
            continue
        M, vM, used, gamma, clipped_sum = cm
        bound = np.fmax(bound, clipped_sum / np.maximum(area, 1e-30)[:, None])
        m = cam.map
        grazing |= m.grazing
        seen = m.den / np.maximum(area, 1e-30) >= rig.min_coverage
        cover = used / np.maximum(area, 1e-30)
        lost = seen & (m.den - used > SATURATED_LOSS * m.den)  # a saturated pixel covers part of the cell
        good = seen & ~lost & (cover >= rig.min_coverage)
        saturated |= lost
        dropped += int(lost.sum())
        good &= cover >= FUSED_COVERAGE * np.minimum(best, 1.0)
        w = np.where(good, m.n_eff * np.nan_to_num(gamma).mean(axis=1), 0.0)
        M = np.where(good[:, None], np.nan_to_num(M), 0.0)
        vM = np.where(good[:, None], np.nan_to_num(vM), 0.0)
        num += w[:, None] * M
        den += w
        whole |= good & (cover >= FUSED_COVERAGE)
        weights.append((w, vM))
    # a cell some camera saw saturated is measured only where another saw it whole: a part of it seen
    # unsaturated is its dimmer part
    measured = (den > 0) & (~saturated | whole)
    with np.errstate(invalid="ignore", divide="ignore"):
        R = np.where(measured[:, None], num / den[:, None], 0.0)
        for w, vM in weights:
            var += (w[:, None] ** 2) * vM
        var = np.where(measured[:, None], var / (den**2)[:, None], np.nan)
    flags[~measured & saturated] |= SATURATED
    flags[~measured & ~saturated] |= UNSEEN
    flags[~measured & grazing] |= GRAZING
    return R, var, flags, dropped, np.nan_to_num(bound)
