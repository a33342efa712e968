"""The main job's relighting check in numbers: each planar model's exitance under a stripe of light
against photon transport of the same light, as ``make demo`` measured it (``RESULTS/report/relight.json``).

Reads the JSON the demo wrote and writes its table into docs/accuracy.md (section "The relighting check"):

    translucency demo --out results && python benchmarks/relight_table.py results --out docs/accuracy.md
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from accuracy_table import write_between_markers


def table(relight: dict) -> str:
    """The Markdown table of one ``relight.json``: per model, the image's relative L2 and the total light.

    >>> print(table({"rel_l2": {"iso": 0.185}, "total_ratio": {"iso": 0.926}, "photons_per_entry": 1000,
    ...              "pattern": "stripe"}).splitlines()[-1])
    | iso | 18.5 % | 0.93 |
    """
    rows = [
        f"| {name} | {100 * err:.1f} % | {relight['total_ratio'][name]:.2f} |"
        for name, err in relight["rel_l2"].items()
    ]
    source = (
        # the command is in the page's own "Reproducing these measurements" section, at its end
        "from `results/report/relight.json` of a `make demo` folder "
        "([Reproducing these measurements](#reproducing-these-measurements)):"
    )
    return "\n".join(
        [
            f"The {relight['pattern']} against photon transport "
            f"({relight['photons_per_entry']:,} photons per entry point of a lit cell), {source}",
            "",
            "| model | relative L2 of the exitance image (`rel_l2`) | total light / the reference's "
            "(`total_ratio`) |",
            "| --- | --- | --- |",
            *rows,
        ]
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("results", type=Path, help="A demo's output folder.")
    ap.add_argument("--out", type=Path, default=None, help="Markdown file to write the section into.")
    args = ap.parse_args()
    text = table(json.loads((args.results / "report" / "relight.json").read_text()))
    print(text)
    if args.out:
        write_between_markers(args.out, text, "benchmarks/relight_table.py")


if __name__ == "__main__":
    main()
