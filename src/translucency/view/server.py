"""The live viewer: the page served from this machine, with point and spot lights relit here.

:class:`ViewServer` serves the page (:mod:`.page`) at once with what needs no transport (the mesh, the
maps, the profiles: :func:`.surface.surface_data`) and prepares the relighting in a thread; the page
polls ``light.json`` until it is there.  A point or spot light the user moves goes to ``POST /relight``:
the irradiance with shadow rays and the sparse transport (:meth:`.object_page.ObjectView.relight`),
answered as float16 radiance per vertex — of the reduced mesh's vertices only while the light moves
(``draft``), of every vertex once it settles.  Python's own threaded HTTP server: one user on
localhost needs nothing more.
"""

from __future__ import annotations

import errno
import json
import threading
import time
from http import HTTPStatus
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer

import numpy as np

from .page import DATA, SCRIPT, data_json, data_script, page_html, static_text

#: the largest request body read (a light is a few hundred bytes)
MAX_BODY = 1 << 16


class ViewServer:
    """Serve ``surface`` = (meta, arrays) at once and the relighting once ``prepare(say)`` returns an
    :class:`~translucency.view.object_page.ObjectView` (called in a thread; ``say(step)`` is told each
    step, and the page shows it)."""

    def __init__(self, surface: tuple[dict, dict], prepare, *, host: str = "127.0.0.1", port: int = 8080):
        meta, arrays = surface
        live = {**meta, "live": True, "status": "preparing the relighting…"}
        self.files = {
            "/": page_html(meta.get("title", "model")).encode("utf-8"),
            "/" + SCRIPT: static_text("viewer.js").encode("utf-8"),
            "/" + DATA: data_script(live, arrays).encode("ascii"),
        }
        self.light_json: bytes | None = None
        self.view = None
        self.step = "starting"
        self.error: str | None = None
        self.lock = threading.Lock()  # one relight at a time: each uses every core
        self._prepare = prepare
        self.lod_source = arrays.get("lod_source")
        self.httpd, self.port_note = _bind(host, port, self._handler())

    @property
    def url(self) -> str:
        host, port = self.httpd.server_address[:2]
        return f"http://{host}:{port}/"

    def start(self) -> None:
        """Serve in a thread and prepare the relighting in another (none to prepare: ``prepare`` None, the
        page holds its relighting already, as a planar sample's does)."""
        threading.Thread(target=self.httpd.serve_forever, daemon=True).start()
        if self._prepare is not None:
            threading.Thread(target=self._prepare_light, daemon=True).start()

    def stop(self) -> None:
        self.httpd.shutdown()
        self.httpd.server_close()

    def _prepare_light(self) -> None:
        def say(step):
            self.step = step

        try:
            view = self._prepare(say)
            meta, arrays = view.light_data()
            if self.lod_source is not None:  # the draft's coarse transport, prepared before the first drag
                say("the draft transport")
                view.relight(view.light_at("directional", (0.0, 0.0, 1.0)), receivers=self.lod_source)
            self.view = view
            self.light_json = data_json(meta, arrays).encode("ascii")
            self.step = "ready"
        except Exception as exc:  # noqa: BLE001 — any failure of the preparation is shown on the page
            self.error = f"{type(exc).__name__}: {exc}"

    def relight(self, request: dict) -> bytes:
        """float16 radiance (V or the reduced mesh's vertices, × 3) of the light the page describes."""
        view = self.view
        kind = request.get("kind")
        direction = np.asarray(request.get("direction", ()), dtype=np.float64)
        distance = float(request.get("distance", 1.5))
        cutoff = float(request.get("cutoff", 20.0))
        if kind not in ("point", "spot", "directional") or direction.shape != (3,):
            raise ValueError("a light is kind point|spot|directional with a direction x,y,z")
        if not (np.all(np.isfinite(direction)) and np.linalg.norm(direction) > 0 and 0.2 <= distance <= 100):
            raise ValueError(
                "the light's direction must be finite and non-zero, its distance 0.2 to 100 sizes"
            )
        if not 0.5 <= cutoff <= 89:
            raise ValueError("the spot's cone must be 0.5 to 89 degrees")
        light = view.light_at(kind, direction, distance, cutoff)
        receivers = self.lod_source if request.get("draft") else None
        with self.lock:
            L = view.relight(light, receivers)
        return np.asarray(L, np.float16).tobytes()

    def _handler(self):
        server = self

        class Handler(BaseHTTPRequestHandler):
            protocol_version = "HTTP/1.1"  # keep the connection: a drag sends many requests
            disable_nagle_algorithm = True  # headers and body as written (no 40 ms wait for an ACK)

            def log_message(self, *args):  # quiet: the command prints what matters
                pass

            def _send(self, status, body: bytes, kind: str, seconds: float | None = None):
                self.send_response(status)
                if seconds is not None:  # the server's share of an update (the page's stats show it)
                    self.send_header("Server-Timing", f"relight;dur={1000 * seconds:.1f}")
                self.send_header("Content-Type", kind)
                self.send_header("Content-Length", str(len(body)))
                self.send_header("Cache-Control", "no-store")
                self.end_headers()
                self.wfile.write(body)

            def do_GET(self):
                path = self.path.split("?")[0]
                if path in server.files:
                    kind = "text/html; charset=utf-8" if path == "/" else "text/javascript; charset=utf-8"
                    return self._send(HTTPStatus.OK, server.files[path], kind)
                if path == "/light.json":  # the relighting, or what is being done (the page polls)
                    if server.light_json is not None:
                        return self._send(HTTPStatus.OK, server.light_json, "application/json")
                    state = (
                        {"failed": server.error}
                        if server.error
                        else {"pending": f"preparing: {server.step}…"}
                    )
                    return self._send(HTTPStatus.OK, json.dumps(state).encode("utf-8"), "application/json")
                self._send(HTTPStatus.NOT_FOUND, b"not found", "text/plain")

            def do_POST(self):
                if self.path != "/relight":
                    return self._send(HTTPStatus.NOT_FOUND, b"not found", "text/plain")
                if server.view is None:
                    return self._send(HTTPStatus.SERVICE_UNAVAILABLE, b"still preparing", "text/plain")
                try:
                    size = int(self.headers.get("Content-Length", "0"))
                    if not 0 < size <= MAX_BODY:
                        raise ValueError("the request's body is empty or too long")
                    t = time.perf_counter()
                    body = server.relight(json.loads(self.rfile.read(size)))
                except (ValueError, TypeError) as exc:
                    return self._send(HTTPStatus.BAD_REQUEST, str(exc).encode("utf-8"), "text/plain")
                self._send(HTTPStatus.OK, body, "application/octet-stream", time.perf_counter() - t)

        return Handler


def _bind(host: str, port: int, handler) -> tuple[ThreadingHTTPServer, str | None]:
    """The server on ``port``, or (in use) on a port the system gives: (server, a note saying so)."""
    try:
        return ThreadingHTTPServer((host, port), handler), None
    except OSError as exc:
        if exc.errno != errno.EADDRINUSE:
            raise
        httpd = ThreadingHTTPServer((host, 0), handler)
        return httpd, f"port {port} is in use; serving on {httpd.server_address[1]} instead"
