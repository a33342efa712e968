"""Photon transport throughput and the cost of the embedded default data set.

Prints photon steps per second (free-flight events, null collisions included)
of the Dr.Jit wavefront walk on the active backend for a homogeneous and a
heterogeneous slab, the throughput of a plain NumPy implementation of the
same walk (the baseline, run on fewer photons) and their ratio, and the time
to make the default data set (``--default`` runs the full acquisition,
about a minute on 2 cores).

Run: ``python benchmarks/photon_transport.py [--default]``
"""

from __future__ import annotations

import sys
import tempfile
import time

import numpy as np

from translucency.acquire import PlanarSetup, acquire_planar, make_sample
from translucency.acquire.transport import random_walk
from translucency.mitsuba import mitsuba


def numpy_walk(volume, channel, x0, y0, n, seed=0, max_steps=100_000):
    """The same analog walk (delta tracking, isotropic phase for g = 0, index-matched
    boundary) vectorised in NumPy: the baseline.  Returns the number of steps."""
    rng = np.random.default_rng(seed)
    W, H, T = volume.size_mm
    Z, Y, X = volume.shape
    st = volume.sigma_t[..., channel]
    ss = volume.sigma_s[..., channel]
    maj = float(st.max())
    pos = np.tile([x0, y0, 0.0], (n, 1))
    d = np.tile([0.0, 0.0, -1.0], (n, 1))
    alive = np.ones(n, bool)
    steps = 0
    for _ in range(max_steps):
        idx = np.flatnonzero(alive)
        if idx.size == 0:
            break
        steps += idx.size
        t = -np.log1p(-rng.random(idx.size)) / maj
        p = pos[idx] + d[idx] * t[:, None]
        out = (p[:, 0] < 0) | (p[:, 0] > W) | (p[:, 1] < 0) | (p[:, 1] > H) | (p[:, 2] > 0) | (p[:, 2] < -T)
        alive[idx[out]] = False
        keep = idx[~out]
        p = p[~out]
        pos[keep] = p
        ix = np.clip((p[:, 0] / volume.voxel_mm).astype(int), 0, X - 1)
        iy = np.clip((p[:, 1] / volume.voxel_mm).astype(int), 0, Y - 1)
        iz = np.clip((-p[:, 2] / volume.voxel_mm).astype(int), 0, Z - 1)
        xi = rng.random(keep.size) * maj
        scat = xi < ss[iz, iy, ix]
        absorb = ~scat & (xi < st[iz, iy, ix])
        alive[keep[absorb]] = False
        k = keep[scat]
        mu = 1 - 2 * rng.random(k.size)
        phi = 2 * np.pi * rng.random(k.size)
        s = np.sqrt(1 - mu**2)
        d[k] = np.stack([s * np.cos(phi), s * np.sin(phi), mu], 1)
    return steps


def rate(fn, *args, repeat=2, **kw):
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        res = fn(*args, **kw)
        best = min(best, time.perf_counter() - t0)
    return res, best


def main() -> int:
    mi = mitsuba()
    print(f"backend: {mi.variant()}")
    print(f"{'slab':<32}{'ours M steps/s':>16}{'NumPy M steps/s':>17}{'ratio':>8}")
    for name in ("homogeneous:marble", "marble"):
        vol = make_sample(name, (32, 32, 10), 0.25, seed=1)
        res, t = rate(random_walk, vol, 1, np.array([[16.0, 16.0]]), 1_000_000, seed=1, index_matched=True)
        ours = res.steps / t / 1e6
        steps_np, t_np = rate(numpy_walk, vol, 1, 16.0, 16.0, 20_000, repeat=1)
        base = steps_np / t_np / 1e6
        print(f"{name:<32}{ours:>16.1f}{base:>17.2f}{ours / base:>8.1f}")
    if "--default" in sys.argv:
        vol = make_sample("marble", (32, 32, 10), 0.25, seed=1)
        setup = PlanarSetup(
            grid=(32, 32),
            span=(16, 16),
            pitch=0.25,
            window=12,
            photons=20_000,
            seed=1,
            chunk_points=64,
            dtype="float16",
        )
        t0 = time.perf_counter()
        acquire_planar(vol, setup, tempfile.mkdtemp() + "/d.zarr")
        print(
            f"default data set (1024 points x 20,000 photons x 3 channels): {time.perf_counter() - t0:.1f} s"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
