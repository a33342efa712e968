"""The built documentation site works offline: served from this folder alone, in headless Chromium, with every
request to another host refused and recorded, its formulas are drawn (MathML), its search finds pages and its
pictures load.  ``make docs`` builds build/site and runs this file on it (TRANSLUCENCY_SITE=build/site); the
fast suite, which runs before the site is built, skips it.  TRANSLUCENCY_SITE_SHOTS=FOLDER keeps a screenshot
of each formula page there."""

from __future__ import annotations

import functools
import http.server
import os
import re
import threading
from pathlib import Path

import pytest

from helpers import chromium_executable

SITE, SHOTS = (
    Path(os.environ[name]).resolve() if os.environ.get(name) else None
    for name in ("TRANSLUCENCY_SITE", "TRANSLUCENCY_SITE_SHOTS")
)

pytestmark = pytest.mark.skipif(
    SITE is None,
    reason="no built site given: `make docs` builds build/site and tests it (TRANSLUCENCY_SITE=build/site)",
)

#: what a page loads: a script, a stylesheet or icon, a picture, a frame; @import and url() in styles
LOADS = re.compile(
    r"<(?:script|img|iframe|source|audio|video|embed)\b[^>]*\bsrc=[\"']?(https?:)?//"
    r"|<link\b[^>]*\bhref=[\"']?(https?:)?//"
    r"|@import\s+(?:url\()?[\"']?(https?:)?//"
    r"|url\(\s*[\"']?(https?:)?//",
    re.I,
)


def test_the_site_is_there():
    assert (SITE / "index.html").is_file(), f"{SITE}: no index.html (build the site first: make docs)"


def test_no_page_or_style_loads_from_another_host():
    found = []
    for path in [*SITE.rglob("*.html"), *SITE.rglob("*.css")]:
        text = path.read_text(encoding="utf-8", errors="replace")
        where = path.relative_to(SITE)
        found += [f"{where}: {text[m.start() : m.start() + 120]!r}" for m in LOADS.finditer(text)]
    assert not found, "\n".join(found)


class _Quiet(http.server.SimpleHTTPRequestHandler):
    def log_message(self, *args) -> None:
        pass


@pytest.fixture(scope="module")
def server():
    """build/site served on a free local port: its base URL."""
    httpd = http.server.ThreadingHTTPServer(("127.0.0.1", 0), functools.partial(_Quiet, directory=str(SITE)))
    thread = threading.Thread(target=httpd.serve_forever, daemon=True)
    thread.start()
    yield f"http://127.0.0.1:{httpd.server_address[1]}/"
    httpd.shutdown()
    httpd.server_close()


@pytest.fixture(scope="module")
def browser():
    playwright = pytest.importorskip("playwright.sync_api")
    exe = chromium_executable()
    if exe is None:
        pytest.skip("no Chromium installed (apt-get install chromium)")
    with playwright.sync_playwright() as p:
        # any host name but the local server's fails to resolve: nothing leaves the machine even if a request
        # escaped the routing below
        rules = "--host-resolver-rules=MAP * ~NOTFOUND, EXCLUDE 127.0.0.1"
        b = p.chromium.launch(executable_path=exe, args=[rules])
        yield b
        b.close()


@pytest.fixture
def offline(browser, server):
    """A browser context whose requests to any host but the local server are aborted and recorded; after the
    test, none may have been made, and no local file may be missing."""
    context = browser.new_context(viewport={"width": 1200, "height": 900}, service_workers="block")
    remote, missing, errors = [], [], []

    def route(r):
        url = r.request.url
        if url.startswith(server):
            r.continue_()
        else:
            remote.append(url)
            r.abort()

    context.route("**/*", route)
    local = (server, "data:", "blob:")
    context.on("request", lambda q: None if q.url.startswith(local) else remote.append(q.url))
    context.on("response", lambda a: missing.append(f"{a.status} {a.url}") if a.status >= 400 else None)
    context.on("weberror", lambda e: errors.append(str(e.error)))

    def open_page(path: str):
        page = context.new_page()
        page.goto(server + path, wait_until="load")
        return page

    yield open_page
    context.close()
    assert not remote, f"the site tried the network: {sorted(set(remote))}"
    assert not missing, f"files missing from the site: {missing}"
    assert not errors, f"errors in the page: {errors}"


def _formula_pages() -> list[str]:
    return sorted(
        str(p.relative_to(SITE).parent).replace(os.sep, "/") + "/"
        for p in SITE.rglob("index.html")
        if "<math" in p.read_text(encoding="utf-8")
    )


def test_formulas_are_drawn(offline):
    pages = _formula_pages()
    assert "reference/api/model/" in pages, f"no MathML on the model's API page; pages with formulas: {pages}"
    for path in pages:
        page = offline(path)
        text = page.locator("article").inner_text()
        assert "\\(" not in text and "\\[" not in text, f"{path}: raw TeX left in the page"
        sizes = page.eval_on_selector_all(
            "article math",
            "ms => ms.map(m => { const r = m.getBoundingClientRect(); return [r.width, r.height]; })",
        )
        assert sizes and all(w > 0 and h > 0 for w, h in sizes), f"{path}: a formula with no size: {sizes}"
        # MathML laid out as mathematics, not as a line of text: a fraction's numerator above its denominator
        fractions = page.eval_on_selector_all(
            "article mfrac",
            "fs => fs.map(f => [f.children[0].getBoundingClientRect().bottom,"
            " f.children[1].getBoundingClientRect().top])",
        )
        assert all(num <= den + 1 for num, den in fractions), f"{path}: fractions not drawn: {fractions}"
        if SHOTS is not None:
            SHOTS.mkdir(parents=True, exist_ok=True)
            page.locator("article math").first.scroll_into_view_if_needed()
            page.screenshot(path=SHOTS / (path.strip("/").replace("/", "_") + ".png"))


def test_search_finds_pages(offline):
    page = offline("")
    box = page.locator("input.md-search__input")
    box.click()
    box.press_sequentially("dipole")
    results = page.locator(".md-search-result__item")
    results.first.wait_for(state="visible", timeout=15_000)
    assert results.count() > 0
    assert "dipole" in results.first.inner_text().lower()


@pytest.mark.parametrize("path", ["", "gallery/"])
def test_pictures_load(offline, path):
    page = offline(path)
    page.eval_on_selector_all("article img", "is => is.forEach(i => { i.loading = 'eager'; })")
    page.wait_for_function(
        "[...document.querySelectorAll('article img')].every(i => i.complete)", timeout=15_000, polling=100
    )
    sizes = page.eval_on_selector_all(
        "article img", "is => is.map(i => [i.getAttribute('src'), i.naturalWidth])"
    )
    assert sizes, f"{path or 'index'}: no pictures"
    assert all(w > 0 for _, w in sizes), f"{path or 'index'}: pictures that did not load: {sizes}"


def test_a_formula_without_mathml_fails_the_build():
    pytest.importorskip("latex2mathml")
    import importlib.util

    from mkdocs.exceptions import PluginError

    spec = importlib.util.spec_from_file_location("mathml", Path(__file__).parents[1] / "docs/_ext/mathml.py")
    hook = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(hook)

    class Page:
        class file:  # noqa: N801
            src_uri = "page.md"

        toc = []

    ok = hook.on_page_content('<p><span class="arithmatex">\\(a &lt; \\frac{1}{2}\\)</span></p>', page=Page)
    assert "<mfrac>" in ok and "<mo>&#x0003C;</mo>" in ok and "\\(" not in ok
    for bad in ("\\frac{1}{", "\\notacommand x"):
        with pytest.raises(PluginError, match=r"page\.md: the formula .* has no MathML"):
            hook.on_page_content(f'<div class="arithmatex">\\[{bad}\\]</div>', page=Page)
