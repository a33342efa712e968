"""How fast the viewer relights, measured where the user sees it: a real headless Chromium (issue 26).

1. The static page (``view --export``): frames per second while a directional light turns and while the
   sky turns — the reduced mesh drawn while things move, and the full mesh alone — the page's size, and
   the error against ``render``'s chain for the same light.
2. The live viewer (``view``): the time to the first picture (the maps) and to the relighting; a point
   light dragged for 4 s (an event every 16 ms, as a mouse sends them): updates shown per second and
   the time from an event to the frame that shows it; and each light on its own (event → frame).
3. Beside them, in this process: the full relight of every vertex per light (``render``'s chain, the
   baseline) against the draft the live viewer sends while the light moves, with the ratio.

The model: ``--model FILE``, or (default) the 89,106-vertex pig of ``render_speed.py`` (acquired and fitted
here, about a minute).  Needs Chromium (``apt-get install chromium``) and playwright.

    python benchmarks/view_speed.py [--model pig.model.zip]
"""

from __future__ import annotations

import argparse
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np


def _pig(folder: Path) -> Path:
    """The 89 k-vertex pig: 32 incident points, 4,000 photons, index-matched marble, fitted iso."""
    from translucency.acquire.objects import make_pig

    mesh = folder / "pig89.ply"
    make_pig(0.36).export(mesh)
    data, model = folder / "pig89.zarr", folder / "pig89.model.zip"
    tl = [sys.executable, "-m", "translucency"]
    acquire = ["acquire", "mesh", "--mesh", str(mesh), "-m", "marble", "--points", "32", "-N", "4000"]
    subprocess.run([*tl, *acquire, "--index-matched", "--out", str(data), "-q"], check=True)
    subprocess.run([*tl, "fit", str(data), "--model", "iso", "--out", str(model), "-q"], check=True)
    return model


def _browser(p):
    exe = next(
        (shutil.which(n) for n in ("chromium", "chromium-browser", "google-chrome") if shutil.which(n)), None
    )
    if exe is None:
        sys.exit("no Chromium: apt-get install chromium")
    return p.chromium.launch(executable_path=exe)


def _renderer(page) -> str:
    return page.evaluate(
        "(() => { const gl = document.getElementById('canvas').getContext('webgl2');"
        " const e = gl.getExtension('WEBGL_debug_renderer_info');"
        " return e ? gl.getParameter(e.UNMASKED_RENDERER_WEBGL) : gl.getParameter(gl.RENDERER); })()"
    )


def static_page(p, model: Path, folder: Path) -> dict:
    out = folder / "page"
    t = time.perf_counter()
    res = subprocess.run(
        [sys.executable, "-m", "translucency", "view", str(model), "--export", str(out), "--json", "-q"],
        check=True, capture_output=True, text=True,
    )  # fmt: skip
    import json

    summary = json.loads(res.stdout)
    b = _browser(p)
    page = b.new_page(viewport={"width": 1100, "height": 700})
    page.goto((out / "index.html").as_uri())
    page.wait_for_function("window.TL !== undefined && TL.ready", timeout=120_000)
    page.evaluate("TL.frame()")
    fps = {
        "directional turning (reduced mesh while moving)": page.evaluate("TL.spin(4000)"),
        "directional turning (full mesh every frame)": page.evaluate("TL.spin(4000, 'light', true)"),
        "camera orbiting (reduced mesh while moving)": page.evaluate("TL.spin(4000, 'camera')"),
    }
    page.evaluate("TL.setLight({kind: 'environment'})")
    fps["sky turning (reduced mesh while moving)"] = page.evaluate("TL.spin(4000)")
    info = {
        "renderer": _renderer(page),
        "vertices": summary["vertices"],
        "reduced_vertices": page.evaluate("TL.stats.lastMesh"),
        "page_mb": summary["page_mb"],
        "export_s": time.perf_counter() - t,
        "errors": summary["error_vs_render"],
        "fps": fps,
    }
    b.close()
    return info


def live_viewer(p, model: Path) -> dict:
    t0 = time.perf_counter()
    proc = subprocess.Popen(
        [sys.executable, "-m", "translucency", "view", str(model), "--no-browser", "--port", "0"]
        + ["--seconds", "600"],
        stderr=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        url = next(line.split("viewer: ")[1].split()[0] for line in proc.stderr if "viewer: http" in line)
        b = _browser(p)
        page = b.new_page(viewport={"width": 1100, "height": 700})
        page.goto(url)
        page.wait_for_function("window.TL !== undefined")
        page.evaluate("TL.frame()")
        first = time.perf_counter() - t0
        page.wait_for_function("TL.ready", timeout=600_000, polling=200)
        ready = time.perf_counter() - t0
        page.evaluate("TL.setShow('radiance'); TL.setLight({kind: 'point', az: 0, el: 30, dist: 1.5})")
        page.wait_for_timeout(2000)
        drag = page.evaluate("TL.drag(4000)")
        page.wait_for_timeout(1500)
        single = page.evaluate(
            """(async () => { const out = [];
            for (let i = 0; i < 30; i++) {
              const t = performance.now(); await TL.setLight({az: 40 + 3 * i});
              out.push(performance.now() - t);
            }
            return out; })()"""
        )
        page.wait_for_timeout(1500)
        settle = page.evaluate(
            "(async () => { const t = performance.now(); await TL.setLight({az: 170}); "
            "await new Promise(r => setTimeout(r, 300)); await TL.frame(); return performance.now() - t; })()"
        )
        b.close()
    finally:
        proc.terminate()
        proc.wait(timeout=30)
    lat = drag["latency_ms"]
    return {
        "first_picture_s": first,
        "relighting_ready_s": ready,
        "drag_updates_per_s": drag["updates_per_s"],
        "drag_latency_ms": (statistics.median(lat), float(np.quantile(lat, 0.9)))
        if lat
        else (float("nan"),) * 2,
        "single_updates_per_s": 1000 * len(single) / sum(single),
        "single_latency_ms": statistics.median(single),
        "release_to_full_ms": settle,
    }


def server_side(model: Path) -> dict:
    """The full relight per light (baseline) against the draft on the reduced mesh, in this process."""

    from translucency.io.model_file import load_model, read_header
    from translucency.render import object_of_model
    from translucency.transport import PreparedObject
    from translucency.view.object_page import viewed_object
    from translucency.view.surface import reduced_mesh

    m = load_model(model)
    mesh, _ = object_of_model(m, read_header(model))
    view = viewed_object(PreparedObject(m, mesh), check_error=False)
    _, receivers = reduced_mesh(mesh)  # the page's own reduced mesh
    view.relight(view.light_at("point", (1, 0, 1)), receivers=receivers)  # the draft's transport, once
    full, draft, err = [], [], []
    for az in np.linspace(0, 330, 12):
        a = np.radians(az)
        light = view.light_at("point", (np.cos(a), np.sin(a), 0.6))
        t = time.perf_counter()
        B = view.relight(light)
        full.append(time.perf_counter() - t)
        t = time.perf_counter()
        d = view.relight(light, receivers=receivers)
        draft.append(time.perf_counter() - t)
        err.append(np.sqrt(((d - B[receivers]) ** 2).sum() / (B[receivers] ** 2).sum()))
    return {
        "full_ms": 1000 * statistics.median(full),
        "draft_ms": 1000 * statistics.median(draft),
        "draft_error": float(np.median(err)),
        "receivers": len(receivers),
    }


def main() -> None:
    from playwright.sync_api import sync_playwright

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument(
        "--model", type=Path, help="a per-vertex model (default: the 89 k-vertex pig, built here)"
    )
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        model = args.model or _pig(folder)
        with sync_playwright() as p:
            page = static_page(p, model, folder)
            live = live_viewer(p, model)
        server = server_side(model)
    say = print
    say(f"model: {model.name}, {page['vertices']:,} vertices (reduced mesh: {page['reduced_vertices']:,})")
    say(f"browser: headless Chromium, WebGL2 on {page['renderer']}")
    say(f"\nstatic page: {page['page_mb']:.1f} MB (target <= 20), written in {page['export_s']:.0f} s")
    for k, v in page["fps"].items():
        say(f"  {k}: {v:.1f} frames/s (target >= 30)")
    errors = ", ".join(f"{k} {v:.3f}" for k, v in page["errors"].items())
    say(f"  error against render's chain (relative RMSE, same light and camera): {errors}")
    say("\nlive viewer:")
    first, ready = live["first_picture_s"], live["relighting_ready_s"]
    say(f"  first picture (maps) {first:.1f} s after the command (target <= 20)")
    say(f"  relighting ready {ready:.1f} s")
    median, p90 = live["drag_latency_ms"]
    say(f"  point light dragged (an event every 16 ms): {live['drag_updates_per_s']:.1f} updates/s")
    say(f"    (target >= 15); event -> frame median {median:.0f} ms, 90th percentile {p90:.0f} ms")
    say(f"  one light at a time (event -> frame): {live['single_updates_per_s']:.1f} updates/s, median")
    single, release = live["single_latency_ms"], live["release_to_full_ms"]
    say(f"    {single:.0f} ms; release -> full mesh relit {release:.0f} ms")
    ratio = server["full_ms"] / server["draft_ms"]
    say(f"\nserver side per light: full relight of {page['vertices']:,} vertices (render's chain)")
    say(
        f"  {server['full_ms']:.0f} ms; draft on {server['receivers']:,} vertices {server['draft_ms']:.0f} ms"
    )
    say(f"  ({ratio:.1f}x faster, relative RMSE {server['draft_error']:.3f} at those vertices)")


if __name__ == "__main__":
    main()
