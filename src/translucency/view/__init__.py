"""Looking at a fitted model: a relighting page in the browser, static or served live.

:mod:`.object_page` prepares a per-vertex model (the transport, the precomputed radiance transfer of
:mod:`translucency.transport.transfer`, held in 8 bits by :mod:`.transfer_codec`; the mesh, maps and
profiles of :mod:`.surface`) → :mod:`.page` writes the page (``static/``: one HTML file, the WebGL2
script, the data as a script) → :mod:`.server` serves it live, with point and spot lights relit on the
server.
"""
