"""Figures and numbers of docs/validation.md: the virtual DISCO against independent references.

1. Total reflectance of homogeneous slabs against iadpython (adding-doubling).
2. Radial profile of a thick homogeneous marble slab against the dipole.

Run: ``python benchmarks/validation_report.py`` (about 30 s); writes docs/figures/.
"""

from __future__ import annotations

from pathlib import Path

import iadpython as iad
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from translucency.acquire import Volume, make_sample  # noqa: E402
from translucency.acquire.transport import TOP, random_walk  # noqa: E402
from translucency.model import dipole_R_d, material  # noqa: E402

FIG = Path(__file__).resolve().parents[1] / "docs" / "figures"


def iad_table():
    print("| albedo a | optical thickness b | g | n | iadpython UR1 | virtual DISCO | std. err. | z |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    for a, b, g, n in [
        (0.9, 2.0, 0.5, 1.3),
        (0.99, 8.0, 0.0, 1.4),
        (0.5, 1.0, 0.8, 1.0),
        (0.95, 4.0, -0.3, 1.5),
    ]:
        ur1 = float(iad.Sample(a=a, b=b, g=g, d=1.0, n=n, n_above=1.0, n_below=1.0, quad_pts=16).rt()[0])
        vol = Volume.homogeneous((4, 400, 400), 0.25, [a * b] * 3, [(1 - a) * b] * 3, g=g, eta=n)
        N = 1_000_000
        res = random_walk(vol, 0, np.array([[50.0, 50.0]]), N, seed=11)
        R = np.mean((res.code == TOP) | (res.code == -1))
        se = np.sqrt(R * (1 - R) / N)
        print(f"| {a} | {b} | {g} | {n} | {ur1:.5f} | {R:.5f} | {se:.5f} | {(R - ur1) / se:+.2f} |")


def dipole_figure():
    m, ch = material("marble"), 1
    vol = make_sample("homogeneous:marble", (40, 40, 20), 1.0)
    N = 2_000_000
    res = random_walk(vol, ch, np.array([[20.0, 20.0]]), N, seed=21)
    top = res.code == TOP
    r = np.hypot(res.x[top] - 20.0, res.y[top] - 20.0)
    edges = np.linspace(0, 8, 81)
    ring = np.pi * np.diff(edges**2)
    mc = np.histogram(r, edges)[0] / N / ring
    c = 0.5 * (edges[1:] + edges[:-1])
    fine = np.linspace(0, 8, 8001)
    df = dipole_R_d(fine, m.sigma_a[ch], m.sigma_s_prime[ch], 1.3)
    dip = (
        np.array(
            [
                np.trapezoid((df * fine)[(fine >= a) & (fine <= b)], fine[(fine >= a) & (fine <= b)])
                for a, b in zip(edges[:-1], edges[1:])
            ]
        )
        * 2
        * np.pi
        / ring
    )
    mfp = 1 / (m.sigma_a[ch] + m.sigma_s_prime[ch])
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 3.8))
    a1.semilogy(c, mc, "ko", ms=3, label="virtual DISCO (2 M photons)")
    a1.semilogy(c, dip, "g-", label="dipole (Jensen 2001)")
    a1.set_xlabel("r [mm]")
    a1.set_ylabel("$R_d$ [mm$^{-2}$]")
    a1.legend()
    a1.grid(alpha=0.3, which="both")
    a2.plot(c, mc / dip - 1, "k.-")
    a2.axvline(2 * mfp, color="gray", ls="--", label="2 transport mfp")
    a2.axhspan(-0.1, 0.1, color="green", alpha=0.1, label="±10 %")
    a2.set_xlabel("r [mm]")
    a2.set_ylabel("MC / dipole − 1")
    a2.legend()
    a2.grid(alpha=0.3)
    fig.suptitle("Thick homogeneous marble (green, g = 0, η = 1.3): photon transport against the dipole")
    fig.tight_layout()
    FIG.mkdir(parents=True, exist_ok=True)
    fig.savefig(FIG / "dipole_vs_mc.png", dpi=110)
    far = (c > 2 * mfp) & (c < 4)
    near = c < 0.5 * mfp
    print(
        f"dipole vs MC: max |rel| for 2 mfp < r < 4 mm: {np.max(np.abs(mc[far] / dip[far] - 1)):.3f}; "
        f"r < 0.5 mfp: MC/dipole = {(mc[near] / dip[near]).round(3).tolist()}"
    )


if __name__ == "__main__":
    iad_table()
    dipole_figure()
