"""Model-file size for an isotropic n = 3 model of 100,000 surface points with α.

Target (issue 2, after the paper's "final models are small, typically on the
order of 1 MB"): <= 1 MB with float16 storage.

The parameters are realistic rather than random: the coefficients of a
heterogeneous slab vary smoothly (a marble/skin2 mixture whose fraction follows
a smooth noise field over a 316 x 317 grid of incident points), each level is a
3-term exponential fit of its dipole profile, and every point gets 1 % of
independent multiplicative "fit noise" so that neighbouring points are not
identical (which would flatter the compression).  The baseline is the same
arrays written uncompressed in float32 with ``numpy.savez``.

Run: ``python benchmarks/model_size.py``
"""

from __future__ import annotations

import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from translucency import ExponentialModel, PlanarAlpha, load_model, save_model
from translucency.fit import fit_exponential_profile
from translucency.model import dipole_R_d, material


def realistic_model(
    n_side_x=316, n_side_y=317, pitch=0.25, levels=24, noise=0.01, seed=0
) -> ExponentialModel:
    rng = np.random.default_rng(seed)
    yy, xx = np.mgrid[0:n_side_y, 0:n_side_x] * pitch
    t = 0.5 + 0.25 * np.sin(xx / 7.0 + 2 * np.sin(yy / 11.0)) + 0.25 * np.cos(yy / 5.0) * np.sin(xx / 13.0)
    t = np.clip(t, 0, 1).ravel()
    a, b = material("marble"), material("skin2")
    r = np.linspace(0.05, 20, 300)
    grid = np.linspace(0, 1, levels)
    c_lv, d_lv, sg_lv, sb_lv = [], [], [], []
    for f in grid:
        sa = (1 - f) * a.sigma_a + f * b.sigma_a
        sp = (1 - f) * a.sigma_s_prime + f * b.sigma_s_prime
        prof = dipole_R_d(r[:, None], sa, sp, 1.3)
        fit = fit_exponential_profile(r, prof[:, 0], 3)
        c_lv.append(fit.c)
        d_lv.append(fit.d)
        # shared fall-off: colour scales from the ratio of total reflectances
        sg_lv.append(prof[:, 1].sum() / prof[:, 0].sum())
        sb_lv.append(prof[:, 2].sum() / prof[:, 0].sum())
    interp = lambda v: np.stack([np.interp(t, grid, np.asarray(v)[:, k]) for k in range(3)], -1)  # noqa: E731
    jitter = lambda shape: 1 + noise * rng.standard_normal(shape)  # noqa: E731
    n = t.size
    c = (interp(c_lv) * jitter((n, 3)))[:, None, None, :]
    d = (interp(d_lv) * jitter((n, 3)))[:, None, None, :]
    s_g = np.interp(t, grid, sg_lv) * jitter(n)
    s_b = np.interp(t, grid, sb_lv) * jitter(n)
    x_i = np.stack([xx.ravel(), yy.ravel()], 1)
    alpha = (1 + 0.1 * np.sin(xx / 3.0) * np.cos(yy / 4.0)) * jitter(xx.shape)
    return ExponentialModel(x_i, c, d, PlanarAlpha(alpha, (-pitch / 2, -pitch / 2), pitch), s_g=s_g, s_b=s_b)


def main() -> int:
    model = realistic_model()
    n = model.n_points
    print(f"isotropic n=3 model, {n:,} incident points, alpha on {model.alpha.shape} pixels")
    tmp = Path(tempfile.mkdtemp())
    base = tmp / "baseline.npz"
    t0 = time.perf_counter()
    np.savez(
        base,
        x_i=model.x_i.astype(np.float32),
        c=model.c.astype(np.float32),
        d=model.d.astype(np.float32),
        s_g=model.s_g.astype(np.float32),
        s_b=model.s_b.astype(np.float32),
        alpha=model.alpha.values.astype(np.float32),
    )
    t_base = time.perf_counter() - t0
    base_size = os.path.getsize(base)
    print(f"{'file':<34}{'bytes':>12}{'MB':>8}{'vs baseline':>13}{'write s':>9}{'read s':>8}")
    print(
        f"{'baseline: numpy.savez float32':<34}{base_size:>12,}{base_size / 1e6:>8.3f}"
        f"{1.0:>13.3f}{t_base:>9.3f}{'':>8}"
    )
    ok = True
    for dtype in ("float32", "float16"):
        path = tmp / f"m_{dtype}.model.zip"
        t0 = time.perf_counter()
        save_model(model, path, dtype=dtype)
        t_w = time.perf_counter() - t0
        t0 = time.perf_counter()
        back = load_model(path)
        t_r = time.perf_counter() - t0
        size = os.path.getsize(path)
        err = np.max(np.abs(back.c - model.c) / model.c)
        print(
            f"{'translucency ' + dtype:<34}{size:>12,}{size / 1e6:>8.3f}"
            f"{size / base_size:>13.3f}{t_w:>9.3f}{t_r:>8.3f}"
            f"   max rel. error of c: {err:.1e}"
        )
        if dtype == "float16":
            ok = size <= 1_000_000
            print(f"target: float16 model <= 1 MB -> {'met' if ok else 'MISSED'} ({size / 1e6:.3f} MB)")
    # how the size depends on the per-point noise of the parameters (fit noise is data entropy)
    print("float16 size against the per-point parameter noise:")
    for noise in (0.0, 0.003, 0.01, 0.03):
        path = tmp / f"noise_{noise}.model.zip"
        save_model(realistic_model(noise=noise), path, dtype="float16")
        print(f"  noise {100 * noise:4.1f} %: {os.path.getsize(path) / 1e6:.3f} MB")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
