"""The main job's Figure 1 in numbers: every planar fit of ``make demo`` against the embedded truth.

Reads the fits a demo wrote (``RESULTS/fits/*.model.zip``, the default data set's), scores each against
the embedded held-out truth (an independent acquisition of the same sample and points) and against the data
it was fitted to, and writes the table and the per-region medians (veined marble below y = 17 mm, the
fibrous band above) into docs/accuracy.md:

    translucency demo --out results && python benchmarks/figure1_table.py results --out docs/accuracy.md
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from accuracy_table import pct, table_rows, write_between_markers
from translucency.data import default_dataset_path, default_truth_path
from translucency.evaluate.errors import planar_errors
from translucency.evaluate.labels import model_label
from translucency.io.dataset import open_dataset
from translucency.io.model_file import load_model, read_header
from translucency.pipeline import DEMO_FITS

#: where the fibrous band begins, mm (pipeline.demo_volume)
BAND_Y_MM = 17.0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("results", type=Path, help="A demo's output folder.")
    ap.add_argument("--out", type=Path, default=None, help="Markdown file to write the section into.")
    args = ap.parse_args()
    data, truth = open_dataset(default_dataset_path()), open_dataset(default_truth_path())
    band = data["x_i"][:, 1].astype(np.float64) >= BAND_Y_MM
    fits, regions, labels = {}, {}, {}
    for label in DEMO_FITS:
        path = args.results / "fits" / f"{label}.model.zip"
        model, meta = load_model(path), read_header(path)["meta"]
        flagged = np.zeros(model.n_points, dtype=bool)
        flagged[meta.get("flagged_points", [])] = True
        held = planar_errors(model, truth, flagged=flagged)
        inside = planar_errors(model, data, flagged=flagged)
        chosen = (meta["fit"].get("structure") or {}).get("chosen", {}).get("label")
        shape = chosen or (model_label(model) if model.kind == "exponential" else None)
        labels[label] = f"{label} ({shape})" if shape and label != shape else label
        fits[labels[label]] = {**held.summary(), "in_sample": inside.summary()}
        regions[labels[label]] = [
            (np.nanmedian(held.per_point[where]), np.nanmedian(held.per_point_beyond[where]))
            for where in (~band, band)
        ]
        print(f"{labels[label]:40s} held-out {100 * held.rel_l2:6.2f} %", flush=True)
    head = (
        "| model | all | near | mid | far | beyond noise all | beyond noise near | E near | E mid | ρ total "
    )
    text = "\n".join(
        [
            # the command is in the page's own "Reproducing these measurements" section, at its end
            "Held out, % (RGB summed; from a `make demo` folder, "
            "[Reproducing these measurements](#reproducing-these-measurements)):",
            "",
            head + "| in-sample all |",
            "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |",
            *table_rows(fits),
            "",
            f"By region (median per-point error, raw held-out / beyond the truth's noise, %; the band is "
            f"y ≥ {BAND_Y_MM:g} mm):",
            "",
            "| model | veined marble | fibrous band |",
            "| --- | --- | --- |",
            *[
                f"| {label} | " + " | ".join(f"{pct(raw)} / {pct(beyond)}" for raw, beyond in r) + " |"
                for label, r in regions.items()
            ],
            "",
        ]
    )
    print(text)
    if args.out:
        write_between_markers(args.out, text, "benchmarks/figure1_table.py")


if __name__ == "__main__":
    main()
