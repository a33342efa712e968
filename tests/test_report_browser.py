"""The report page in a real browser (headless Chromium, where it is installed): it loads, every figure
decodes, no table cell wraps or overflows, the page does not overflow sideways, and a full-page
screenshot is as tall as the page and not blank."""

from __future__ import annotations

import html
import json
import re
import shutil
import subprocess

import numpy as np
import pytest

from test_report import _three_models
from translucency.evaluate.report import write_report

CHROMIUM = shutil.which("chromium")
pytestmark = pytest.mark.skipif(CHROMIUM is None, reason="no chromium on this machine")
WIDTH = 1400

#: run on load: what the page looks like to a reader, written into the DOM for --dump-dom to read
CHECK = """<script>
window.addEventListener("load", () => {
  const images = [...document.images].map((i) => [i.getAttribute("src"), i.complete && i.naturalWidth > 0]);
  const wrapped = [], overflow = [];
  for (const td of document.querySelectorAll("td")) {
    const range = document.createRange();
    range.selectNodeContents(td);
    const lines = new Set([...range.getClientRects()].map((r) => Math.round(r.top)));
    if (lines.size > 1) wrapped.push(td.textContent);
    if (td.scrollWidth > td.clientWidth) overflow.push(td.textContent);
  }
  const root = document.documentElement;
  const out = {title: document.title, images, wrapped, overflow, width: root.clientWidth,
    scroll: root.scrollWidth, height: root.scrollHeight,
    summary: (document.getElementById("summary") || {}).textContent || ""};
  const pre = document.createElement("pre");
  pre.id = "browser-check";
  pre.textContent = JSON.stringify(out);
  document.body.appendChild(pre);
});
</script>"""


def _chromium(tmp_path, *args) -> str:
    profile = tmp_path / "chromium-profile"
    profile.mkdir(exist_ok=True)
    flags = [
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--disable-quic",
        "--no-first-run",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
        f"--user-data-dir={profile}",
    ]
    done = subprocess.run([CHROMIUM, *flags, *args], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr[-2000:]
    return done.stdout


@pytest.mark.parametrize("held_out", [True, False], ids=["held-out", "in-sample"])
def test_the_report_page_in_a_browser(tmp_path, held_out):
    from PIL import Image  # matplotlib's own dependency: reads the screenshot

    models, fitted, truth = _three_models(tmp_path)
    out = tmp_path / "rep"
    write_report(models, fitted, out, truth=truth if held_out else None, command="translucency evaluate x")
    page = out / "check.html"  # beside index.html: the same figures, with the check run on load
    page.write_text((out / "index.html").read_text().replace("</body>", CHECK + "</body>"))
    dom = _chromium(tmp_path, f"--window-size={WIDTH},1000", "--dump-dom", page.as_uri())
    found = re.search(r'<pre id="browser-check">(.*?)</pre>', dom, re.S)
    assert found, "the page did not load (no check output in the DOM)"
    seen = json.loads(html.unescape(found.group(1)))
    assert seen["title"] == "translucency report"
    assert seen["summary"].startswith("Held out" if held_out else "In-sample")
    assert len(seen["images"]) == 5 and all(ok for _, ok in seen["images"]), seen["images"]
    assert seen["wrapped"] == [] and seen["overflow"] == [], (seen["wrapped"], seen["overflow"])
    assert seen["scroll"] <= seen["width"]  # nothing runs off the page sideways
    # a full-page screenshot: as tall as the page, and drawn down to its end
    shot = tmp_path / "page.png"
    height = int(seen["height"])
    _chromium(
        tmp_path, f"--window-size={WIDTH},{height}", f"--screenshot={shot}", (out / "index.html").as_uri()
    )
    image = np.asarray(Image.open(shot).convert("L"), dtype=np.float64)
    assert image.shape == (height, WIDTH)
    assert image.std() > 20  # not blank
    for part in np.array_split(image, 4):  # every quarter of the page shows something
        assert (part < 128).mean() > 0.002
