"""The documentation's gallery: the main job's figures, picked from a demo's output folder and made small.

Reads the figures ``make demo`` (``translucency demo --out RESULTS``) writes, scales each to at most
:data:`MAX_WIDTH` pixels wide with a palette of 256 colours, writes them into DOCS_GALLERY, the run's
numbers into the data file ``DOCS_GALLERY.json`` (``figure2``, ``paper``, ``relight``: the demo's
``figure2.json``, ``figure2_paper.json`` and ``relight.json``; ``command``, ``software``) and the page's
captions, which read those numbers (``{{ data.gallery.figure2.flip_mean_object | f3 }}``, the site's macros:
docs/_ext/numbers.py), into the gallery page (``DOCS_GALLERY.md`` beside the folder, between this script's
markers).  Every page that states these numbers (the home page's picture among them) reads them from there:

    make demo && python benchmarks/gallery.py results docs/gallery
"""

from __future__ import annotations

import argparse
import json
from dataclasses import dataclass
from pathlib import Path

from PIL import Image

from accuracy_table import write_between_markers

#: the widest picture of the gallery, pixels (the page's column is narrower; a click shows it whole)
MAX_WIDTH = 1400
#: the most the gallery's pictures may weigh together, bytes
MAX_TOTAL = 2_000_000


@dataclass(frozen=True)
class Figure:
    """One figure of a demo folder: where it is, its name in the gallery, its title and caption."""

    source: str  # relative to the demo folder
    name: str  # the file in the gallery folder
    title: str
    caption: str  # may name the run's numbers as the site's macros do: {{ data.gallery.figure2.… | f3 }}


FIGURES = (
    Figure(
        "report/figure2.png",
        "figure2.png",
        "An object rendered from its fitted model",
        "The procedural pig filled with veined marble (the `marble` generator), path-traced through its "
        "volume by Mitsuba's volpath (left) and rendered from the per-vertex model fitted to its virtual "
        "acquisition, as `fit` and `render` do by default (middle); right, their difference (FLIP). Over the "
        "object: FLIP {{ data.gallery.figure2.flip_mean_object | f3 }}, relative RMSE "
        "{{ data.gallery.figure2.rel_rmse | f3 }}; preparing and drawing the model's picture took "
        "{{ data.gallery.figure2.speedup_vs_reference | times(0) }} less time than path-tracing the "
        "reference.",
    ),
    Figure(
        "report/paper/figure2_paper.png",
        "figure2_paper.png",
        "The same object with the paper's model",
        "The same data fitted with the paper's choice (isotropic, n = 3, one fall-off scaled per colour "
        "channel) and drawn from each point's radial profile alone (`render --paper`): FLIP "
        "{{ data.gallery.paper.flip_mean_object | f3 }}, relative RMSE "
        "{{ data.gallery.paper.rel_rmse | f3 }} over the object.",
    ),
    Figure(
        "report/profiles.png",
        "profiles.png",
        "Profiles of a planar sample (Figure 1, left)",
        "The embedded marble scan with a fibrous band: ring-averaged R_d around chosen incident points "
        "(green channel, log scale) for every fitted model against the held-out truth, an independent "
        "acquisition of the same points; beneath each, model / truth − 1 with the truth's noise (grey). "
        "The lower rows: the truth on 0.05 mm rings near the incident point against each model.",
    ),
    Figure(
        "report/error_maps.png",
        "error_maps.png",
        "Where each model errs (Figure 1, right)",
        "Relative error per outgoing pixel within 4 mm and per incident point, raw and beyond the truth's "
        "noise (black: within the noise), one logarithmic colour scale per row shared by the models. "
        "Segments on an anisotropic model's map: its fitted direction of farthest spread.",
    ),
    Figure(
        "report/error_ratios.png",
        "error_ratios.png",
        "Error per incident point against the default fit",
        "Each model's error per incident point over the default fit's (blue: lower, red: higher).",
    ),
    Figure(
        "report/alpha.png",
        "alpha.png",
        "The modulation texture α",
        "α(x_o) of every model on one colour scale: the spatial variation the per-point profiles leave.",
    ),
    Figure(
        "report/params.png",
        "params.png",
        "The fitted parameters over the sample",
        "Every model's parameters over the incident points, with their units (G: the green channel).",
    ),
    Figure(
        "report/relight.png",
        "relight.png",
        "Relighting the sample",
        "The sample under a 2 mm stripe of light: photon transport (the reference) against the fitted "
        "models, each the superposition of its R_d over the lit cells (green channel); below, a profile "
        "across the stripe and each model's difference. Relative L2 error: "
        "{% for name, error in data.gallery.relight.rel_l2.items() %}{{ ', ' if not loop.first }}{{ name }} "
        "{{ error | pct }} %{% endfor %}.",
    ),
    Figure(
        "baselines.png",
        "baselines.png",
        "The measured materials",
        "R_d(r) of Jensen et al.'s measured materials: the dipole, its 3-term exponential fit and "
        "Christensen–Burley fitted to it (green channel); the titles give the rms relative differences.",
    ),
)


def numbers(results: Path, gallery: Path) -> dict:
    """The run's numbers the captions name, from its JSON files: the gallery's data file."""
    report = results / "report"
    run = json.loads((report / "report.json").read_text())
    return {
        "source": f"make demo && python benchmarks/gallery.py RESULTS {gallery}",
        "command": run["command_line"],
        "software": run["written_by"],
        "figure2": json.loads((report / "figure2.json").read_text()),
        "paper": json.loads((report / "paper" / "figure2_paper.json").read_text()),
        "relight": json.loads((report / "relight.json").read_text()),
    }


def shrink(source: Path, target: Path) -> int:
    """``source`` at most :data:`MAX_WIDTH` wide, 256 colours, written to ``target``; its size in bytes."""
    with Image.open(source) as image:
        image = image.convert("RGB")
        if image.width > MAX_WIDTH:
            image = image.resize((MAX_WIDTH, round(image.height * MAX_WIDTH / image.width)), Image.LANCZOS)
        image.quantize(256, method=Image.Quantize.MEDIANCUT).save(target, optimize=True)
    return target.stat().st_size


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("results", type=Path, help="A demo's output folder (translucency demo --out RESULTS).")
    ap.add_argument("gallery", type=Path, help="The gallery's folder of pictures (docs/gallery).")
    ap.add_argument("--page", type=Path, default=None, help="The page (default: GALLERY.md beside it).")
    args = ap.parse_args()
    page = args.page or args.gallery.with_suffix(".md")
    missing = [f.source for f in FIGURES if not (args.results / f.source).is_file()]
    if missing:
        raise SystemExit(f"error: {args.results}: not a demo's output folder (no {', '.join(missing)})")
    values = numbers(args.results, args.gallery)
    args.gallery.mkdir(parents=True, exist_ok=True)
    total, sections = 0, []
    for figure in FIGURES:
        size = shrink(args.results / figure.source, args.gallery / figure.name)
        total += size
        print(f"{figure.name:20s} {size / 1e3:7.1f} kB", flush=True)
        link = f"{args.gallery.name}/{figure.name}"
        sections += [f"## {figure.title}", "", f"[![{figure.title}]({link})]({link})", ""]
        sections += [figure.caption, ""]
    if total > MAX_TOTAL:
        raise SystemExit(f"error: the gallery weighs {total / 1e6:.2f} MB, more than {MAX_TOTAL / 1e6:g} MB")
    text = "\n".join(
        [
            # the command that writes this section is in the page's "Reproducing these pictures", after it
            "From the output of `{{ data.gallery.command }}` ({{ data.gallery.software }}), made small for "
            "this page ([Reproducing these pictures](#reproducing-these-pictures)); its numbers: "
            f"`{page.with_suffix('.json').name}`.",
            "",
            *sections,
        ]
    ).rstrip("\n")
    write_between_markers(page, text, "benchmarks/gallery.py")
    data = page.with_suffix(".json")
    data.write_text(json.dumps(values, indent=2) + "\n")
    print(f"{len(FIGURES)} figures, {total / 1e6:.2f} MB, into {args.gallery}, {page} and {data}")


if __name__ == "__main__":
    main()
