"""Held-out accuracy table of the planar fits on virtual-DISCO data (issue 4, item 4; issue 13, item 1).

For each sample (marble, apple-slice, skin, fibers, homogeneous marble) two virtual acquisitions of the
same generated volume (volume seed 1) and the same incident points are made, cached under --cache: the
data the models are fitted to (photon seed 1) and an independent truth (photon seed 2, --truth-factor
times the photons).  The isotropic (per-channel and the paper's shared colour), anisotropic (m = 8),
dipole, Burley, photon beam diffusion and directional dipole models are fitted with α to the first and
evaluated against the truth: relative L2 error overall and per distance band, the error beyond the
truth's own noise, energy-weighted errors, the truth's noise, and the in-sample error beside.  Writes
docs/accuracy.md (the definitions, the table, the targets and whether each is met) and a JSON file.

    python benchmarks/accuracy_table.py --out docs/accuracy.md
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

from translucency.acquire import PlanarSetup, acquire_planar, make_sample
from translucency.evaluate.errors import finite_or_null, planar_errors
from translucency.fit.planar import fit_planar

SAMPLES = ["marble", "apple-slice", "skin", "fibers", "homogeneous:marble", "banded", "layered"]
FITS = {  # label -> fit_planar arguments
    "default": dict(),  # the structure chosen by held-out error (fit's default)
    "iso": dict(model="iso"),
    "iso shared colour": dict(model="iso", colour="shared"),
    "aniso m=8": dict(model="aniso", n_directions=8),
    "aniso m=8 shared (the paper's)": dict(model="aniso", n_directions=8, colour="shared"),
    "dipole": dict(model="dipole"),
    "burley": dict(model="burley"),
    "pbd": dict(model="pbd"),
    "directional dipole": dict(model="ddipole"),
}


def acquire(
    sample: str, cache: Path, photons: int, grid: int, photon_seed: int, volume_seed: int = 1
) -> Path:
    """One acquisition of ``sample``: the volume is ``volume_seed`` (1: the table's samples), ``photon_seed``
    seeds the photon streams only."""
    vol_tag = "" if volume_seed == 1 else f"_v{volume_seed}"
    path = cache / f"{sample.replace(':', '_')}{vol_tag}_{grid}x{grid}_{photons}_s{photon_seed}.zarr"
    vol = make_sample(sample, (20.0, 20.0, 8.0), 0.25, g=0.0, seed=volume_seed)
    setup = PlanarSetup(
        grid=(grid, grid),
        span=(6.0, 6.0),
        pitch=0.25,
        window=8.0,
        photons=photons,
        seed=photon_seed,
        chunk_points=grid * grid,
    )
    acquire_planar(vol, setup, path)  # resumes / reuses a finished data set made with the same arguments
    return path


def pct(v) -> str:
    return "–" if v is None or v != v else f"{100 * v:.2f}"


def targets(results: dict) -> list[str]:
    """The targets, each with the numbers and met / not met (held-out, and beyond the noise)."""
    out = []

    def line(ok: bool, text: str) -> None:
        out.append(f"* {'**met**' if ok else '**not met**'} — {text}")

    for sample, fits in results.items():
        iso, dip = fits["iso"], fits["dipole"]
        ok = iso["rel_l2_near"] <= 0.5 * dip["rel_l2_near"]
        okb = iso["beyond_noise"]["near"] <= 0.5 * dip["beyond_noise"]["near"]
        verdict = {(True, True): "met", (False, True): "met beyond the noise, not in the raw held-out error"}
        out.append(
            f"* **{verdict.get((ok, okb), 'not met')}** — {sample}: iso near-band ≤ 0.5 × dipole: "
            "beyond noise "
            f"{pct(iso['beyond_noise']['near'])} vs 0.5 × {pct(dip['beyond_noise']['near'])} %; raw held-out "
            f"{pct(iso['rel_l2_near'])} vs 0.5 × {pct(dip['rel_l2_near'])} % (both contain the truth's "
            f"{pct(iso['noise_floor']['near'])} % noise)"
        )
        others = ("burley", "pbd", "directional dipole")
        ok = all(iso["rel_l2"] < fits[k]["rel_l2"] for k in others)
        line(
            ok,
            f"{sample}: iso overall below Burley, PBD, directional dipole: {pct(iso['rel_l2'])} vs "
            + ", ".join(f"{pct(fits[k]['rel_l2'])}" for k in others)
            + " %",
        )
    if "fibers" in results:
        iso = results["fibers"]["iso"]
        label = min(("aniso m=8", "default"), key=lambda k: results["fibers"][k]["rel_l2"])
        an = results["fibers"][label]
        line(
            an["rel_l2"] <= 0.6 * iso["rel_l2"],
            f"fibers: aniso (the better of m = 8 and the default: {label}) ≤ 0.6 × iso overall: "
            f"{pct(an['rel_l2'])} "
            f"vs 0.6 × {pct(iso['rel_l2'])} % (ratio {an['rel_l2'] / iso['rel_l2']:.2f}; beyond noise "
            f"{pct(an['beyond_noise']['all'])} vs {pct(iso['beyond_noise']['all'])} %)",
        )
    for sample in results:
        if not sample.startswith("homogeneous"):
            continue
        iso, an = results[sample]["iso"], results[sample]["aniso m=8"]
        noise = iso["noise_floor"]["all"]
        line(
            abs(an["rel_l2"] - iso["rel_l2"]) <= noise,
            f"{sample}: aniso within the truth's noise of iso: |{pct(an['rel_l2'])} − {pct(iso['rel_l2'])}| "
            f"≤ {pct(noise)} %",
        )
        # in-sample, a model with 8× the parameters may gain their share of the noise, not more: on
        # 33 × 33 × 3 values per window, 144 − 18 extra parameters are 3.9 % of χ², 2 % of the L2 error
        line(
            an["in_sample"]["rel_l2"] >= 0.98 * iso["in_sample"]["rel_l2"],
            f"{sample}: aniso does not fit the noise in-sample: {pct(an['in_sample']['rel_l2'])} vs iso "
            f"{pct(iso['in_sample']['rel_l2'])} % (at least 0.98 × iso's)",
        )
    return out


def table_rows(fits: dict, first: str = "") -> list[str]:
    """The table's rows of one sample's fits (label -> errors), the truth's noise last; ``first`` is put
    before each row (the sample's cell)."""
    rows = []
    for label, s in fits.items():
        b, en = s["beyond_noise"], s["energy_error"]
        rows.append(
            f"{first}| {label} | {pct(s['rel_l2'])} | {pct(s['rel_l2_near'])} | "
            f"{pct(s['rel_l2_mid'])} | {pct(s['rel_l2_far'])} | {pct(b['all'])} | {pct(b['near'])} | "
            f"{pct(en['near'])} | {pct(en['mid'])} | {pct(en['total'])} | "
            f"{pct(s['in_sample']['rel_l2'])} |"
        )
    s = next(iter(fits.values()))
    nf, ne = s["noise_floor"], s["energy_noise"]
    rows.append(
        f"{first}| *truth noise* | {pct(nf['all'])} | {pct(nf['near'])} | {pct(nf['mid'])} | "
        f"{pct(nf['far'])} | 0 | 0 | {pct(ne['near'])} | {pct(ne['mid'])} | | "
        f"*{pct(s['in_sample']['noise_floor']['all'])}* |"
    )
    return rows


def markdown(results: dict, args) -> str:
    head = [
        "# Accuracy of the planar fits (held-out)",
        "",
        # the command is in the page's own "Reproducing these measurements" section, at its end
        "Measured by the benchmark of this page, "
        "[Reproducing these measurements](#reproducing-these-measurements).",
        "",
        f"Virtual DISCO data: {args.grid}×{args.grid} incident points over 6 mm, 8 mm windows of 0.25 mm "
        "pixels; slab 20×20×8 mm, 0.25 mm voxels, g = 0, η = 1.3, each generator's volume seed 1. "
        f"Each model is fitted with α to one acquisition ({args.photons:,} photons per point and channel, "
        "photon seed 1) and evaluated against an **independent acquisition of the same sample and the same "
        f"incident points** ({args.photons * args.truth_factor:,} photons, photon seed 2): the truth.",
        "",
        "What each column means (all relative, %, RGB summed; pairs with r < one pixel are left out, "
        "as in the fit):",
        "",
        "* **all / near / mid / far** — held-out relative L2 error ‖model − truth‖ / ‖truth‖ over all "
        "pairs (x_i, x_o) / r < 1 mm / 1–4 mm / > 4 mm.  It contains the truth's own noise.",
        "* **beyond noise (all, near)** — sqrt(max(‖model − truth‖² − Σσ², 0)) / ‖truth‖: the error left "
        "after the truth's noise (independent of the model, so it adds in quadrature), an estimate of the "
        "error against the noise-free material; 0 when a model is within the noise.",
        "* **E near / E mid** — energy-weighted: per incident point the energy ∫R_d dA over the band "
        "(Σ R_d p²), model against truth, relative L2 over the points.  What a renderer sees of each band.",
        "* **ρ total** — the total diffuse reflectance per point, the model's closed-form ∫R_d dA (× mean "
        "α) against the truth's tally of every exit (also outside the window).",
        "* **in-sample** — the same 'all' error against the fitted data; a model that follows the noise "
        "scores well here and not against the truth.",
        "* ***truth noise*** — the error a perfect model would score: sqrt(Σσ²)/‖truth‖ per band, and the "
        "noise of the band energies.",
        "",
        "| sample | model | all | near | mid | far | beyond noise all | beyond noise near | E near | "
        "E mid | ρ total | in-sample all |",
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    rows = [row for sample, fits in results.items() for row in table_rows(fits, f"| {sample} ")]
    tail = [
        "",
        "The *truth noise* row's last cell is the fitted data's own noise (the in-sample floor).",
        "",
        "## Targets",
        "",
        "iso near-band ≤ 0.5 × dipole; iso lower than Burley, PBD and the directional dipole overall; "
        "aniso ≤ 0.6 × iso on fibers; aniso within the truth's noise of iso on the homogeneous sample. "
        "Checked on the held-out numbers above; the near-band target compares model errors, so it is judged "
        "on the error beyond the truth's noise (the raw held-out errors of both models contain the same "
        "noise, which pulls their ratio towards 1), the raw ratio stated beside it:",
        "",
        *targets(results),
        "",
    ]
    return "\n".join(head + rows + tail)


def write_between_markers(path: Path, text: str, name: str = "benchmarks/accuracy_table.py") -> None:
    """Replace what lies between the markers of script ``name`` in ``path`` (the prose around it stays),
    add the section at the end of a page without them, or write a new page."""
    BEGIN, END = f"<!-- {name}: begin -->", f"<!-- {name}: end -->"  # noqa: N806 — the markers
    block = f"{BEGIN}\n{text}\n{END}\n"
    old = path.read_text() if path.exists() else ""
    if BEGIN in old and END in old:
        head, rest = old.split(BEGIN, 1)
        block = head + block + "\n" + rest.split(END, 1)[1].lstrip("\n")
    elif old:  # a page without this script's section yet: it is added at the end
        block = old.rstrip("\n") + "\n\n" + block
    path.write_text(block)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--photons", type=int, default=40_000, help="Photons of the fitted acquisition.")
    ap.add_argument("--truth-factor", type=int, default=3, help="The truth's photons / the fitted data's.")
    ap.add_argument("--grid", type=int, default=5)
    ap.add_argument("--cache", type=Path, default=Path("bench_data"))
    ap.add_argument("--samples", default=",".join(SAMPLES))
    ap.add_argument("--out", type=Path, default=None, help="Markdown file (and .json beside it).")
    ap.add_argument("--from-json", type=Path, default=None, help="Only rewrite the Markdown from this JSON.")
    args = ap.parse_args()
    if args.from_json is not None:
        text = markdown(json.loads(args.from_json.read_text()), args)
        print(text)
        if args.out:
            write_between_markers(args.out, text)
        return
    args.cache.mkdir(parents=True, exist_ok=True)
    results = {}
    t0 = time.perf_counter()
    for sample in args.samples.split(","):
        t = time.perf_counter()
        ds = acquire(sample, args.cache, args.photons, args.grid, photon_seed=1)
        truth = acquire(sample, args.cache, args.photons * args.truth_factor, args.grid, photon_seed=2)
        print(f"{sample}: data {time.perf_counter() - t:.0f} s", flush=True)
        results[sample] = {}
        for label, kw in FITS.items():
            t = time.perf_counter()
            fit = fit_planar(ds, **kw)
            held = planar_errors(fit.model, truth, flagged=fit.flagged)
            inside = planar_errors(fit.model, ds, flagged=fit.flagged)
            results[sample][label] = {
                **held.summary(),
                "in_sample": inside.summary(),
                "seconds": time.perf_counter() - t,
            }
            print(
                f"  {label:18s} held-out {100 * held.rel_l2:6.2f} %  near {100 * held.bands['near']:6.2f} %"
                f"  beyond noise {100 * held.beyond_noise['all']:6.2f} %"
                f"  in-sample {100 * inside.rel_l2:6.2f} %",
                flush=True,
            )
    print(f"total {time.perf_counter() - t0:.0f} s")
    text = markdown(results, args)
    print(text)
    if args.out:
        write_between_markers(args.out, text)
        args.out.with_suffix(".json").write_text(json.dumps(finite_or_null(results), indent=2) + "\n")


if __name__ == "__main__":
    main()
