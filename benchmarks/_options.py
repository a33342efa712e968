"""What the small benchmark scripts share: ``--key=value`` options over typed defaults, and the example mesh
sized and centred (``from _options import options, sized_mesh``: the scripts' own folder is on the path)."""

from __future__ import annotations

from pathlib import Path

import trimesh

from translucency.io.mesh import load_mesh

#: the example mesh the scripts default to when ../shared is beside the repository (never needed to run)
SPOT = Path(__file__).resolve().parents[2] / "shared" / "meshes" / "spot.obj"


def options(argv: list[str], defaults: dict) -> tuple[str | None, dict]:
    """(the positional argument or None, ``defaults`` updated from ``--key=value``, typed as the default)."""
    opts, positional = dict(defaults), None
    for a in argv[1:]:
        if a.startswith("--") and "=" in a:
            k, v = a[2:].split("=", 1)
            k = k.replace("-", "_")
            if k not in opts:
                raise SystemExit(f"unknown option --{k}; known: {', '.join(sorted(opts))}")
            opts[k] = type(opts[k])(v)
        elif not a.startswith("--"):
            positional = a
    return positional, opts


def sized_mesh(path, size: float, up: str = "z") -> trimesh.Trimesh:
    """``path`` (default: spot.obj where it is, else a 2,562-vertex icosphere) scaled so that its longest side
    is ``size`` mm and centred on the origin."""
    path = path or (SPOT if SPOT.is_file() else None)
    m = trimesh.creation.icosphere(4, radius=size / 2) if path is None else load_mesh(path, up=up)
    m.apply_scale(size / float(m.extents.max()))
    m.apply_translation(-m.bounds.mean(axis=0))
    return m
