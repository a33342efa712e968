r"""The path-traced reference picture of an object, converged, its own noise measured, cached on disk.

:func:`render_reference` renders the same object, volume, light and camera as our picture with
Mitsuba's ``volpath`` (heterogeneous medium over the bounding box, one grey channel at a time as in
:mod:`translucency.validate.volpath`), behind a ``null`` boundary (index-matched) or a smooth
``dielectric`` one.  A dielectric object can only be path-traced under an environment light: point,
spot and directional lights reach its inside through a delta refraction, a path ``volpath`` cannot
sample.

An object comparison is only as good as its reference: ``volpath`` at S samples per pixel carries
Monte Carlo noise of relative size :math:`\propto 1/\sqrt S`.  :func:`converged_reference` renders the
reference twice with independent seeds (A, B) and returns their mean with its measured noise,

.. math:: \varepsilon_{ref} = \frac{\lVert A - B \rVert}{2\,\lVert (A + B)/2 \rVert}
          \quad\text{(relative RMSE over the object's pixels)},

since each render's error has RMS :math:`\lVert A - B\rVert/\sqrt 2` and the
mean of two halves it again.  The result is cached under a key made of all
that defines it — mesh, volume, light, camera, samples, boundary and the
version of translucency (Mitsuba's is recorded beside it) — in ``$TRANSLUCENCY_CACHE`` (default
``~/.cache/translucency``), and looked up first among the references shipped
with the package (``translucency/data/references``: the main job's).

Units: radiance in W/(mm² sr) for the lights' W/sr (point) or W/mm² (directional).
"""

from __future__ import annotations

import hashlib
import json
import os
import time
from pathlib import Path

import numpy as np

from .._validate import TranslucencyError, plain
from .._version import __version__
from ..io.atomic import atomic_path, write_json
from ..mitsuba import engine_versions, mitsuba, object_volpath_scene, pinhole_sensor_dict
from .camera import Camera
from .compare import rel_rmse


def check_reference(light, eta: float = 1.0) -> None:
    """Refuse, in one line and before any work, a reference ``volpath`` cannot render: a dielectric
    boundary (``eta`` ≠ 1) under a point, spot or directional light (module docstring)."""
    if not hasattr(light, "emitter_dict"):
        raise TranslucencyError(f"light: no reference for {plain(light)}")
    if eta != 1.0 and light.delta:
        raise TranslucencyError(
            "reference: volpath cannot light a dielectric object with a point, spot or "
            "directional light (a delta refraction); use an env light or an index-matched "
            "data set"
        )


def render_reference(
    mesh, volume, light, camera: Camera, *, spp: int = 256, seed: int = 0, eta: float = 1.0
) -> tuple[np.ndarray, float]:
    """The same object path-traced by Mitsuba's ``volpath``; returns (image (H, W, 3), seconds).

    The seconds are the path tracing alone (three grey renders; building the scenes is not counted).

    ``eta`` ≠ 1: a smooth dielectric boundary (environment lights only, see the module docstring).

    Examples
    --------
    >>> import trimesh
    >>> from translucency.acquire import make_sample
    >>> from translucency.render import Camera, EnvironmentLight, PointLight
    >>> from translucency.render.reference import render_reference
    >>> ball = trimesh.creation.icosphere(2, radius=5.0)
    >>> volume = make_sample("homogeneous:marble", (10.0, 10.0, 10.0), 0.5)
    >>> camera = Camera.looking_at(ball, width=32, height=24)
    >>> sky = EnvironmentLight(0.1)
    >>> image, seconds = render_reference(ball, volume, sky, camera, spp=64)
    >>> image.shape
    (24, 32, 3)

    A point light cannot reach the inside of a dielectric object (η ≠ 1) for ``volpath``: refused before
    any work.

    >>> render_reference(ball, volume, PointLight((0.0, 0.0, 50.0)), camera, eta=1.4)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    translucency._validate.TranslucencyError: reference: volpath cannot light a dielectric object with a ...
    """
    mi = mitsuba()
    check_reference(light, eta)
    emitter = light.emitter_dict()
    seconds = 0.0
    channels = []
    for ch in range(3):
        scene = object_volpath_scene(mesh, volume, ch, emitter, pinhole_sensor_dict(camera, spp), eta=eta)
        t = time.perf_counter()
        channels.append(np.asarray(mi.render(scene, seed=3 * seed + ch), dtype=np.float64)[..., ch])
        seconds += time.perf_counter() - t
    return np.stack(channels, axis=2), seconds


#: references shipped with the package (the main job's), looked up before the user's cache
SHIPPED = Path(__file__).resolve().parent.parent / "data" / "references"


def cache_dir() -> Path:
    """The reference cache: ``$TRANSLUCENCY_CACHE/references`` (default ``~/.cache/translucency``)."""
    root = os.environ.get("TRANSLUCENCY_CACHE") or Path.home() / ".cache" / "translucency"
    return Path(root) / "references"


def reference_key(mesh, volume, light, camera: Camera, spp: int, eta: float) -> str:
    """A SHA-256 over everything that defines a reference image (hex, 24 characters)."""
    h = hashlib.sha256()
    # rounded (µm, 3 significant digits) so that the last bits of a generator's arithmetic do not matter
    h.update(np.round(np.asarray(mesh.vertices, np.float64), 3).tobytes())
    h.update(np.asarray(mesh.faces, np.int64).tobytes())
    for a in (volume.sigma_s, volume.sigma_a):
        h.update(np.asarray(a, dtype=np.float16).tobytes())
    spec = {
        "volume": [list(volume.size_mm), volume.voxel_mm, volume.g, volume.eta],
        "light": repr(light),
        "camera": repr(camera),
        "spp": int(spp),
        "eta": float(eta),
        "version": __version__,  # Mitsuba's version is recorded beside the image, not keyed: same physics
    }
    h.update(json.dumps(spec, sort_keys=True).encode())
    return h.hexdigest()[:24]


def _load(folder: Path, key: str):
    exr, meta = folder / f"{key}.exr", folder / f"{key}.json"
    if not (exr.is_file() and meta.is_file()):
        return None
    try:
        image = np.asarray(mitsuba().Bitmap(str(exr)), dtype=np.float64)
        info = json.loads(meta.read_text())
    except (OSError, ValueError, RuntimeError):
        return None  # an unreadable cache entry is simply rendered again
    return image, info


def mean_of_halves(a: np.ndarray, b: np.ndarray, mask: np.ndarray) -> tuple[np.ndarray, float, float]:
    r"""Two independent renders A, B as one: their mean, its relative noise over ``mask`` (module
    docstring) and one render's own error against the mean, :math:`\sqrt 2\, \lVert A - M\rVert/\lVert M
    \rVert` (what a single render of the same samples would err by: volpath at equal error)."""
    mean = 0.5 * (a + b)
    noise = 0.5 * rel_rmse(a, b, mask) * float(np.sqrt(np.mean(b[mask] ** 2) / np.mean(mean[mask] ** 2)))
    return mean, noise, rel_rmse(a, mean, mask) * float(np.sqrt(2.0))


def converged_reference(
    mesh, volume, light, camera: Camera, mask: np.ndarray, *, spp: int = 256, eta: float = 1.0, cache=True
) -> tuple[np.ndarray, dict]:
    """The mean of two independent ``volpath`` renders and its measured relative noise, cached.

    Parameters
    ----------
    mesh, volume, light, camera
        The scene (:func:`render_reference`).
    mask : ndarray of bool, shape (H, W)
        The object's pixels, over which the noise is measured.
    spp : int
        Samples per pixel of *each* of the two renders.
    eta : float
        The boundary (1: index-matched).
    cache : bool or path
        True: the shipped references, then the user's cache (written); a path: that folder; False: none.

    Returns
    -------
    image : ndarray, shape (H, W, 3)
    info : dict
        ``noise`` (relative RMSE of the mean, formula in the module docstring), ``spp`` (of each render),
        ``seconds`` (path tracing), ``key``, ``cached`` (where it came from, or None).

    Examples
    --------
    Two renders of 64 samples a pixel (seconds), their relative noise 5 %; a second call reads the cache
    (here a folder of its own; by default the shipped references, then the user's cache):

    >>> import tempfile, trimesh
    >>> from translucency.acquire import make_sample
    >>> from translucency.render import Camera, EnvironmentLight, coverage
    >>> from translucency.render.reference import converged_reference
    >>> ball = trimesh.creation.icosphere(2, radius=5.0)
    >>> volume = make_sample("homogeneous:marble", (10.0, 10.0, 10.0), 0.5)
    >>> camera = Camera.looking_at(ball, width=32, height=24)
    >>> mask = coverage(ball, camera)
    >>> sky = EnvironmentLight(0.1)
    >>> cache = tempfile.mkdtemp()
    >>> image, info = converged_reference(ball, volume, sky, camera, mask, spp=64, cache=cache)
    >>> image.shape, info["renders"], round(info["noise"], 2), info["cached"]
    ((24, 32, 3), 2, 0.05, None)
    >>> converged_reference(ball, volume, sky, camera, mask, spp=64, cache=cache)[1]["cached"] == cache
    True
    """
    key = reference_key(mesh, volume, light, camera, spp, eta)
    folders = [] if cache is False else ([Path(cache)] if cache is not True else [SHIPPED, cache_dir()])
    for folder in folders:
        hit = _load(folder, key)
        if hit is not None and hit[0].shape[:2] == mask.shape:
            return hit[0], {**hit[1], "cached": str(folder)}
    t = time.perf_counter()
    a, _ = render_reference(mesh, volume, light, camera, spp=spp, seed=0, eta=eta)
    b, _ = render_reference(mesh, volume, light, camera, spp=spp, seed=1, eta=eta)
    mean, noise, _ = mean_of_halves(a, b, mask)
    info = {
        "key": key,
        "spp": int(spp),
        "renders": 2,
        "noise": noise,
        "seconds": time.perf_counter() - t,
        "definition": "noise = ||A - B|| / (2 ||(A + B)/2||) over the object's pixels",
        "engine": engine_versions(),
    }
    if folders:
        folder = folders[-1]
        folder.mkdir(parents=True, exist_ok=True)
        with atomic_path(folder / f"{key}.exr") as tmp:
            mitsuba().Bitmap(mean.astype(np.float32)).write(str(tmp))
        write_json(folder / f"{key}.json", info)
    return mean, {**info, "cached": None}
