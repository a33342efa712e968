"""The page's per-vertex maps: values in float16 with their colour range, and the physics flags."""

from __future__ import annotations

import numpy as np


def page_maps(values: dict, flagged: np.ndarray, legend: str, arrays: dict) -> list:
    """Describe ``values`` {key: (title, unit, (V,) values)} and the per-vertex ``flagged`` (bool) for the
    page, putting each into ``arrays`` as float16; the colour range of a map spans its 2nd to 98th
    percentile (outliers at the ends of the bar)."""
    out = []
    for key, (title, unit, v) in values.items():
        v = np.asarray(v, np.float64)
        fin = v[np.isfinite(v)]
        lo, hi = np.quantile(fin, [0.02, 0.98]) if fin.size else (0.0, 1.0)
        arrays[key] = v.astype(np.float16)
        out.append(
            {"key": key, "name": title, "unit": unit, "lo": float(lo), "hi": float(max(hi, lo + 1e-9))}
        )
    arrays["map_flags"] = np.asarray(flagged, bool).astype(np.float16)
    out.append(
        {
            "key": "map_flags",
            "name": "physics flags",
            "unit": "",
            "lo": 0.0,
            "hi": 1.0,
            "flags": True,
            "legend": legend,
        }
    )
    return out
