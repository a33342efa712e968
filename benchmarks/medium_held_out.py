"""Does the medium estimated from a scan reproduce the scan where it was not fitted?

The estimate (:func:`translucency.medium.estimate_medium`) reads the even incident points of a mesh data set;
the odd points are scanned virtually in it (:func:`translucency.medium.scan.virtual_scan`, the data set's own
photons per point) and each point's energy :math:`\\sum_o A_o R_d` per band of distance (on the beam's own
side, :math:`n_i \\cdot n_o > 0`) and through the body (:math:`n_i \\cdot n_o \\le 0`) is compared with the
data's.  Beside each band's relative RMS error over the points and channels stands the noise the two
photon counts give it (binomial: :math:`\\sigma^2 = E (1 - E) / N` of each), and their ratio — 1 where the
estimate reproduces the data within its own noise.  Where the filling is one of the generators', its
coefficients are printed beside the estimate's (a check of the estimate; never its input)::

    python benchmarks/medium_held_out.py DATA.zarr [DATA.zarr ...] [--json OUT.json]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from translucency.geometry import vertex_areas
from translucency.io.mesh_dataset import open_mesh_dataset
from translucency.medium import estimate_medium
from translucency.medium.scan import virtual_scan

#: bands of distance from the beam, mm (the beam's own side), then the light through the body
BANDS = ((0.0, 2.0), (2.0, 4.0), (4.0, 8.0), (8.0, 16.0), (16.0, np.inf))


def band_energies(mesh, incident, R) -> np.ndarray:
    """(n, bands + 1, 3): each point's Σ A_o R_d per band of its own side, then through the body."""
    v, n, area = np.asarray(mesh.vertices), np.asarray(mesh.vertex_normals), vertex_areas(mesh)
    out = np.zeros((len(incident), len(BANDS) + 1, 3))
    for k, i in enumerate(incident):
        r = np.linalg.norm(v - v[i], axis=1)
        same = n @ n[i] > 0
        for b, (lo, hi) in enumerate(BANDS):
            sel = same & (r >= lo) & (r < hi)
            out[k, b] = area[sel] @ R[k][sel]
        out[k, -1] = area[~same] @ R[k][~same]
    return out


def held_out(path: Path) -> dict:
    ds = open_mesh_dataset(path)
    mesh = ds.mesh()
    incident = np.asarray(ds.group["incident"][...])
    photons = int(ds.header["photons"])
    seen, unseen = np.arange(0, len(incident), 2), np.arange(1, len(incident), 2)
    medium = estimate_medium(ds, points=seen)
    R_data = np.stack([np.asarray(ds.group["R_d"][int(p)], dtype=np.float64) for p in unseen])
    R_scan = virtual_scan(mesh, medium.volume(mesh), incident[unseen], photons, seed=11)
    E_data, E_scan = (
        band_energies(mesh, incident[unseen], R_data),
        band_energies(mesh, incident[unseen], R_scan),
    )
    var = (E_data * (1 - E_data) + E_scan * (1 - E_scan)) / photons  # both tallies' binomial noise
    rows = {}
    names = [f"{lo:g}-{hi:g} mm" for lo, hi in BANDS] + ["through the body"]
    for b, name in enumerate(names):
        d, s, sd = E_data[:, b], E_scan[:, b], np.sqrt(var[:, b])
        ok = d > 0
        err = float(np.sqrt(np.mean(((s - d)[ok] / d[ok]) ** 2)))
        noise = float(np.sqrt(np.mean((sd[ok] / d[ok]) ** 2)))
        rows[name] = {"rel_rms": err, "noise": noise, "ratio": err / noise, "data_mean": float(d.mean())}
    summary = medium.summary()
    truth = _truth(ds.header)
    return {"data": path.name, "points_seen": len(seen), "points_held_out": len(unseen), "photons": photons,
            "bands": rows, "estimate": summary, "truth": truth}  # fmt: skip


def _truth(header: dict) -> dict | None:
    """The generator's filling (mean σ_s', σ_a per channel), where the data set records one: printed beside
    the estimate, never read by it."""
    try:
        from translucency.acquire.samples import sample_of_dataset

        vol = sample_of_dataset(header)
    except Exception:  # noqa: BLE001 — a lab's data set or a user's filling file: no truth to print
        return None
    return {
        "sigma_s_prime_mean": (vol.sigma_s * (1 - vol.g)).mean(axis=(0, 1, 2)).round(5).tolist(),
        "sigma_a_mean": vol.sigma_a.mean(axis=(0, 1, 2)).round(5).tolist(),
    }


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("data", type=Path, nargs="+", help="mesh data sets (acquire mesh, import object)")
    ap.add_argument("--json", type=Path, help="write the results here too")
    args = ap.parse_args()
    out = []
    for path in args.data:
        res = held_out(path)
        out.append(res)
        print(f"{path.name}: estimated from {res['points_seen']} points, scanned at {res['points_held_out']} "
              f"others, {res['photons']} photons each")  # fmt: skip
        for name, row in res["bands"].items():
            print(
                f"  {name:<18} rel RMS {row['rel_rms']:.4f}  noise {row['noise']:.4f}"
                f"  ratio {row['ratio']:.2f}"
            )
        est = res["estimate"]
        print(f"  estimate: sigma_s median {[c[1] for c in est['sigma_s']]}  sigma_a median "
              f"{[c[1] for c in est['sigma_a']]} mm^-1")  # fmt: skip
        if res["truth"]:
            t = res["truth"]
            print(f"  the filling (not read): sigma_s' mean {t['sigma_s_prime_mean']}  sigma_a mean "
                  f"{t['sigma_a_mean']} mm^-1")  # fmt: skip
    if args.json:
        args.json.write_text(json.dumps(out, indent=2))
        print(f"written: {args.json}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
