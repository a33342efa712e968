"""The photon tally against Mitsuba's own ``volpath``: agreement, and cost per unit noise.

Both estimate the same image — the radiance leaving the top face of a
heterogeneous slab along +z, per pixel of a window around a narrow spot beam
(:mod:`translucency.validate.volpath`) — side by side in one run:

1. *agreement*: two independent runs of each method are averaged; per-pixel
   z-scores (tally − volpath)/σ, ring profiles around the beam, and the cone
   bias of the tally (window sums with 5°, 20° and 90° cones against 10°);
2. *cost per unit noise*: for each method, the CPU time of one warm run (all
   threads; wall time is printed too) times the relative variance per pixel
   (mean of Var/L² over the pixels within ``--radius`` of the beam, all
   channels) — the work needed for a fixed noise.
   The relative variance is measured twice: from each method's own variance
   estimate (binomial counts; volpath's second moments) and empirically from
   the two independent runs, (A − B)²/2 per pixel.  The cost uses the
   empirical one.  Ratios are volpath / tally.

Timing: each method first runs once on a tiny problem (reported as the first
call: tracing plus JIT compilation, or loading from Dr.Jit's on-disk kernel
cache); the timed runs are warm and interleaved, and a run's time is the
faster of the two (other work on the machine only adds; CPU time is less
sensitive to it than wall time).  Both include everything from the volume to
the image: scene loading, entry sampling, binning.

Run: ``python benchmarks/tally_vs_volpath.py [--sample marble] [--g 0] [--spp 1024]
[--photons 4000000] [--rr-depth none 5] [--figure docs/figures/volpath_vs_tally.png]``
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np

from translucency import TranslucencyError
from translucency.acquire import make_sample
from translucency.mitsuba import mitsuba
from translucency.validate import (
    NO_ROULETTE,
    PixelWindow,
    RadianceImage,
    SpotBeam,
    TopExits,
    compare,
    pixel_index,
    radiance_from_exits,
    render_volpath_spot,
    tally_radiance,
)


def parse(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--sample", default="marble", help="make_sample generator (default marble)")
    p.add_argument(
        "--size", type=float, nargs=3, default=(8.0, 8.0, 4.0), metavar=("W", "H", "T"), help="slab, mm"
    )
    p.add_argument("--voxel", type=float, default=0.25, help="voxel size, mm")
    p.add_argument("--g", type=float, default=0.0, help="Henyey-Greenstein g")
    p.add_argument("--seed", type=int, default=1, help="sample seed")
    p.add_argument("--beam-radius", type=float, default=0.5, help="spot radius on the slab, mm (100 mm away)")
    p.add_argument("--pixels", type=int, default=16, help="window side, pixels")
    p.add_argument("--pitch", type=float, default=0.25, help="pixel size, mm")
    p.add_argument("--photons", type=int, default=4_000_000, help="tally photons per channel and run")
    p.add_argument("--spp", type=int, default=1024, help="volpath samples per pixel, per channel and run")
    p.add_argument("--cone", type=float, default=10.0, help="tally cone half-angle, degrees")
    p.add_argument("--channels", type=int, nargs="+", default=(0, 1, 2))
    p.add_argument(
        "--rr-depth",
        nargs="+",
        default=["none"],
        help="volpath Russian-roulette depths to time ('none' = off; Mitsuba's default is 5)",
    )
    p.add_argument("--radius", type=float, default=1.5, help="pixels within this distance of the beam, mm")
    p.add_argument("--figure", default=None, help="write the profile figure here (PNG)")
    return p.parse_args(argv)


def window_sum_ratio(
    exits: TopExits, x: np.ndarray, y: np.ndarray, pitch_mm: float, cone_deg: float, ref_cone_deg: float
) -> tuple[float, float]:
    """Ratio of the window's summed radiance estimated with ``cone_deg`` to that with ``ref_cone_deg``.

    Measures the cone bias: photons in the narrower cone are a subset of those
    in the wider one, so given the wider count n_w the narrower count is
    binomial with p = n_n/n_w, whence the standard error.  Returns (ratio, standard error).
    """
    n_pix = x.shape[0]
    inside = (pixel_index(exits.x, x[0, :], pitch_mm) >= 0) & (pixel_index(exits.y, y[:, 0], pitch_mm) >= 0)
    narrow, wide = sorted((cone_deg, ref_cone_deg))
    n_n = np.count_nonzero(inside & (exits.cos_exit > np.cos(np.radians(narrow))))
    n_w = np.count_nonzero(inside & (exits.cos_exit > np.cos(np.radians(wide))))
    if n_w == 0 or n_n == 0:
        raise TranslucencyError(f"cone: no photons left the {n_pix}x{n_pix} window within {narrow} deg")
    s = (np.sin(np.radians(wide)) / np.sin(np.radians(narrow))) ** 2  # solid-angle weights of the two cones
    p = n_n / n_w
    ratio, se = p * s, s * np.sqrt(p * (1.0 - p) / n_w)  # L_narrow / L_wide
    if cone_deg == narrow:
        return float(ratio), float(se)
    return float(1.0 / ratio), float(se / ratio**2)


def relative_variance(image: RadianceImage, mask: np.ndarray) -> np.ndarray:
    """Var/L² of the pixels in ``mask`` (n, n) with L > 0, per channel: (pixels, C)."""
    L, V = image.radiance[mask], image.variance[mask]
    return np.where(L > 0, V / np.where(L > 0, L, 1.0) ** 2, np.nan)


def mean_of_runs(a: RadianceImage, b: RadianceImage) -> RadianceImage:
    """Average of two independent runs, with the variance of the average."""
    return RadianceImage(
        0.5 * (a.radiance + b.radiance),
        0.25 * (a.variance + b.variance),
        a.x,
        a.y,
        a.channels,
        a.seconds + b.seconds,
    )


def noise(a: RadianceImage, b: RadianceImage, mask: np.ndarray) -> tuple[float, float]:
    """Mean relative variance of one run over ``mask``: (own estimate, empirical from the two runs)."""
    own = np.nanmean(0.5 * (relative_variance(a, mask) + relative_variance(b, mask)))
    La, Lb = a.radiance[mask], b.radiance[mask]
    mean = 0.5 * (La + Lb)
    emp = np.nanmean(np.where(mean > 0, 0.5 * (La - Lb) ** 2 / np.where(mean > 0, mean, 1.0) ** 2, np.nan))
    return float(own), float(emp)


def timed(fn, *args, **kw):
    """Result, wall seconds and CPU seconds (all threads of this process) of one call."""
    t0, c0 = time.perf_counter(), time.process_time()
    out = fn(*args, **kw)
    return out, time.perf_counter() - t0, time.process_time() - c0


def figure(path, agreement, z, channels, title):
    import matplotlib  # here: only a run with --figure needs matplotlib (and its Agg backend)

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    colours = {0: "tab:red", 1: "tab:green", 2: "tab:blue"}
    fig = plt.figure(figsize=(10, 6.5))
    gs = fig.add_gridspec(2, 2, height_ratios=(2.2, 1), width_ratios=(1.6, 1))
    ax, res, hist = fig.add_subplot(gs[0, 0]), fig.add_subplot(gs[1, 0]), fig.add_subplot(gs[:, 1])
    r = agreement.ring_r
    for k, c in enumerate(channels):
        col = colours.get(c, "k")
        ax.errorbar(
            r - 0.02,
            agreement.ring_ref[:, k],
            2 * np.sqrt(agreement.ring_ref_var[:, k]),
            fmt="o",
            mfc="none",
            color=col,
            capsize=2,
            label=f"volpath, channel {c}",
        )
        ax.errorbar(
            r + 0.02,
            agreement.ring_ours[:, k],
            2 * np.sqrt(agreement.ring_ours_var[:, k]),
            fmt="x",
            color=col,
            capsize=2,
            label=f"photon tally, channel {c}",
        )
        rel = agreement.ring_ours[:, k] / agreement.ring_ref[:, k] - 1
        err = np.sqrt(agreement.ring_ours_var[:, k] + agreement.ring_ref_var[:, k]) / agreement.ring_ref[:, k]
        res.errorbar(r + 0.03 * (k - 1), 100 * rel, 200 * err, fmt="o", color=col, capsize=2, ms=4)
    ax.set_yscale("log")
    ax.set_ylabel("ring-averaged radiance along +z\n(W mm$^{-2}$ sr$^{-1}$ per W sr$^{-1}$)")
    ax.set_title(title, fontsize=9)
    ax.legend(fontsize=7, ncol=2)
    res.axhline(0, color="k", lw=0.8)
    res.set_xlabel("distance of the ring from the beam centre (mm)")
    res.set_ylabel("tally / volpath − 1 (%)\n(error bars: 2σ)")
    bins = np.linspace(-5, 5, 41)
    hist.hist(z, bins, density=True, color="0.6", label=f"{z.size} pixel z-scores")
    g = np.linspace(-5, 5, 201)
    hist.plot(g, np.exp(-0.5 * g**2) / np.sqrt(2 * np.pi), "k", label="N(0, 1)")
    hist.set_xlabel("z = (tally − volpath) / σ per pixel and channel")
    hist.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    print(f"figure: {path}")


def main(argv=None) -> int:
    args = parse(argv)
    mi = mitsuba()
    vol = make_sample(args.sample, args.size, args.voxel, g=args.g, seed=args.seed)
    W, H, T = vol.size_mm
    beam = SpotBeam((W / 2, H / 2), args.beam_radius)
    window = PixelWindow((W / 2, H / 2), args.pixels, args.pitch)
    channels = tuple(args.channels)
    rr_depths = [NO_ROULETTE if d == "none" else int(d) for d in args.rr_depth]
    rr_name = {NO_ROULETTE: "off"}
    print(
        f"backend {mi.variant()}; {args.sample} {W:g} x {H:g} x {T:g} mm, "
        f"voxel {args.voxel} mm, g = {vol.g}; "
        f"spot radius {beam.radius_mm} mm ({beam.cutoff_deg:.3f} deg); window {args.pixels} x {args.pixels} "
        f"px of {args.pitch} mm; channels {channels}"
    )

    # -- first calls: tracing + compilation (or Dr.Jit's disk cache) ----------------------------------
    _, t_first_tally, _ = timed(
        tally_radiance, vol, beam, window, 20_000, seed=99, channels=channels, cone_deg=args.cone
    )
    t_first_vp = {}
    for d in rr_depths:
        _, t_first_vp[d], _ = timed(
            render_volpath_spot, vol, beam, window, 4, seed=99, channels=channels, rr_depth=d
        )

    # -- two independent warm runs of each ---------------------------------------------------------------
    # runs interleaved (tally, volpath..., tally, volpath...) so that changing load hits both
    runs = {"tally": [], **{d: [] for d in rr_depths}}
    for seed in (1, 2):
        runs["tally"].append(
            timed(
                tally_radiance,
                vol,
                beam,
                window,
                args.photons,
                seed=seed,
                channels=channels,
                cone_deg=args.cone,
            )
        )
        for d in rr_depths:
            runs[d].append(
                timed(
                    render_volpath_spot, vol, beam, window, args.spp, seed=seed, channels=channels, rr_depth=d
                )
            )
    (tally_a, exits_a), _, _ = runs["tally"][0]
    (tally_b, _), _, _ = runs["tally"][1]
    # a run's cost: the faster of the two, in wall and in CPU seconds
    t_tally = tuple(min(r[i] for r in runs["tally"]) for i in (1, 2))
    vp = {
        d: (runs[d][0][0], runs[d][1][0], tuple(min(r[i] for r in runs[d]) for i in (1, 2)))
        for d in rr_depths
    }

    # -- agreement (against the first volpath setting) ---------------------------------------------------
    d0 = rr_depths[0]
    tally = mean_of_runs(tally_a, tally_b)
    ref = mean_of_runs(vp[d0][0], vp[d0][1])
    edges = np.arange(0.0, 0.5 * window.side_mm + 1e-9, args.pitch)
    agree = compare(tally, ref, beam.centre_xy, edges)
    s = agree.summary()
    print(
        f"\nagreement ({2 * args.photons:,} photons vs {2 * args.spp} spp per channel, "
        f"roulette {rr_name.get(d0, d0)}):"
    )
    print(
        f"  pixel z-scores: n = {s['pixels']}, mean {s['z_mean']:+.3f}, std {s['z_std']:.3f}, "
        f"|z| > 3: {100 * s['frac_abs_z_gt_3']:.2f} % (normal: 0.27 %)"
    )
    print(
        f"  rings of {args.pitch} mm: chi2/dof = {s['ring_chi2_per_dof']:.2f} "
        f"over {agree.ring_z.size} rings x channels"
    )
    S_t, S_v = tally.radiance.sum(axis=(0, 1)), ref.radiance.sum(axis=(0, 1))
    err = np.sqrt(tally.variance.sum(axis=(0, 1)) + ref.variance.sum(axis=(0, 1))) / S_v
    print(
        "  whole window, tally/volpath - 1: "
        + "   ".join(
            f"ch{c} {100 * (S_t[k] / S_v[k] - 1):+.2f} ± {100 * err[k]:.2f} %" for k, c in enumerate(channels)
        )
    )
    print("  ring   r (mm)  " + "  ".join(f"tally/volpath-1 ch{c} (z)" for c in channels))
    for i, rm in enumerate(agree.ring_r):
        cells = [
            f"{100 * (agree.ring_ours[i, k] / agree.ring_ref[i, k] - 1):+6.1f} % ({agree.ring_z[i, k]:+.1f})"
            for k in range(len(channels))
        ]
        print(f"  {i:>4}  {rm:6.3f}   " + "   ".join(f"{c:>22}" for c in cells))
    print(f"  cone bias (window sums, tally run A; ratio to the {args.cone:g} deg cone, ± standard error):")
    for cone in (5.0, 20.0, 90.0):
        cells = []
        for e in exits_a:
            ratio, se = window_sum_ratio(e, tally.x, tally.y, args.pitch, cone, args.cone)
            cells.append(f"{ratio:.4f} ± {se:.4f}")
        print(f"    {cone:4.0f} deg: " + "   ".join(cells))

    # -- cost per unit noise -----------------------------------------------------------------------------
    mask = np.hypot(tally.x - beam.centre_xy[0], tally.y - beam.centre_xy[1]) <= args.radius
    print(
        f"\ncost per unit noise over the {int(mask.sum())} pixels within {args.radius} mm of the beam, "
        f"{len(channels)} channel(s); warm runs; "
        "relative variance = mean of Var/L^2 over pixels and channels;"
    )
    print(
        "cost = CPU seconds (all threads) x relative variance (from the two runs); "
        "ratio = cost / tally's cost"
    )
    print(
        f"  first calls (trace + JIT or disk cache), wall: tally {t_first_tally:.1f} s; "
        + "; ".join(f"volpath roulette {rr_name.get(d, d)} {t:.1f} s" for d, t in t_first_vp.items())
    )
    own_t, emp_t = noise(tally_a, tally_b, mask)
    cost_t = t_tally[1] * emp_t
    print(
        f"  {'method':<36}{'wall (s)':>9}{'CPU (s)':>9}{'rel.sd own':>12}{'rel.sd runs':>13}{'cost':>10}"
        f"{'ratio':>7}{'ratio(wall)':>12}"
    )

    def row(name, t, own, emp, ref_wall):
        rv = emp if emp is not None else own
        cells = f"{t[0]:>9.2f}{t[1]:>9.2f}{np.sqrt(own):>12.4f}"
        cells += f"{np.sqrt(emp):>13.4f}" if emp is not None else f"{'':>13}"
        cells += f"{t[1] * rv:>10.2e}{t[1] * rv / cost_t:>7.2f}{t[0] * rv / ref_wall:>12.2f}"
        print(f"  {name:<36}{cells}")

    wall_t = t_tally[0] * emp_t
    row(f"tally, {args.photons:,} photons, {args.cone:g} deg", t_tally, own_t, emp_t, wall_t)
    for d, (a, b, t) in vp.items():
        own_v, emp_v = noise(a, b, mask)
        row(f"volpath, {args.spp} spp, roulette {rr_name.get(d, d)}", t, own_v, emp_v, wall_t)
    # the tally's cone only changes its noise (its cost is the walk): same photons, other cones
    for cone in (5.0, 20.0):
        img = [radiance_from_exits(e, tally_a.x, tally_a.y, args.pitch, cone) for e in exits_a]
        im = RadianceImage(
            np.stack([i[0] for i in img], -1),
            np.stack([i[1] for i in img], -1),
            tally_a.x,
            tally_a.y,
            channels,
            0.0,
        )
        row(
            f"tally, same photons, {cone:g} deg cone",
            t_tally,
            float(np.nanmean(relative_variance(im, mask))),
            None,
            wall_t,
        )
    print(
        "  ratio > 1: the tally reaches the same noise for less "
        "(rows without 'rel.sd runs' use their own estimate)"
    )

    if args.figure:
        title = (
            f"{args.sample}, {W:g}×{H:g}×{T:g} mm, g = {vol.g:g}; spot radius {beam.radius_mm} mm; "
            f"{2 * args.photons:,} photons ({args.cone:g}° cone) vs {2 * args.spp} spp per channel\n"
            f"pixel z: mean {s['z_mean']:+.2f}, std {s['z_std']:.2f}; "
            f"ring χ²/dof {s['ring_chi2_per_dof']:.2f}"
        )
        figure(args.figure, agree, agree.z, channels, title)
    return 0


if __name__ == "__main__":
    sys.exit(main())
