"""The test suite's shared helpers (a plain module: fixtures stay in conftest.py).

Import them as ``from helpers import random_exponential_model`` (pytest puts tests/ on the path).
"""

import re
import shutil

import numpy as np
from hypothesis import HealthCheck, settings
from typer.testing import CliRunner

from translucency.geometry import tangent_frames
from translucency.model import ExponentialModel, PlanarAlpha, VertexAlpha

#: Hypothesis settings of the fuzz suite and of the "long" profile (conftest.py registers the profiles)
FUZZ = {
    "deadline": None,
    "suppress_health_check": [HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
}


def chromium_executable() -> str | None:
    """The system's headless-capable Chromium (the browser tests drive it through playwright), or None."""
    for name in ("chromium", "chromium-browser", "google-chrome"):
        if shutil.which(name):
            return shutil.which(name)
    return None


def fuzz_settings(fast_examples: int):
    """Settings of a fuzz test: ``fast_examples`` derandomised examples, or the long profile's budget."""
    if settings.default.max_examples >= 200:
        return settings(settings.default, **FUZZ)
    return settings(max_examples=fast_examples, derandomize=True, **FUZZ)


#: (rate range in mm⁻¹, amplitude range in mm⁻²) of three well-separated terms: a fit can tell them apart
SEPARATED_TERMS = (((5.0, 8.0), (0.5, 1.0)), ((1.2, 2.0), (0.05, 0.1)), ((0.3, 0.6), (0.005, 0.01)))


def exponential_terms(rng, P, m=1, C=3, terms=SEPARATED_TERMS):
    """c, d of shape (P, C, m, n), term k drawn from ``terms[k]``; rates first, sorted steepest first."""
    a = np.sort(np.stack([rng.uniform(*rate, (P, C, m)) for rate, _ in terms], axis=-1), axis=-1)[..., ::-1]
    c = np.stack([rng.uniform(*amplitude, (P, C, m)) for _, amplitude in terms], axis=-1)
    return c, -a


def random_exponential_model(
    rng, n_points=4, m=1, n=3, colour="shared", geometry="planar", *, terms=None, mesh=None, points=None
):
    """The test suite's one model factory: a valid random :class:`ExponentialModel`.

    Without ``terms``: physical (each profile's total reflectance 2π Σ c/d² below 1: c_k ≤ d_k²/(2π n),
    times a colour scale ≤ 1.2; its 99.9 % energy radius ≤ 9.3/|d| ≤ 6.2 mm, within the sample or object)
    and exactly representable in float16, so file round trips are exact.  With ``terms`` (see
    :data:`SEPARATED_TERMS`): the given rate and amplitude ranges per term (:func:`exponential_terms`).

    ``geometry="mesh"``: on ``mesh`` (a trimesh) at vertex indices ``points`` with tangent frames and α per
    vertex, or, without a mesh, on 20 random vertices with random frames.
    """
    C = 1 if colour == "shared" else 3
    if mesh is not None:
        n_points = len(points)
    if terms is None:
        d = -rng.uniform(1.5, 6.0, (n_points, C, m, n))
        c = rng.uniform(0.05, 0.8, (n_points, C, m, n)) * d**2 / (2 * np.pi * n * 1.2)
        f16 = lambda a: None if a is None else a.astype(np.float16).astype(np.float64)  # noqa: E731
    else:
        c, d = exponential_terms(rng, n_points, m, C, terms)
        f16 = lambda a: a  # noqa: E731
    s_g = rng.uniform(0.3, 1.2, n_points) if C == 1 else None
    s_b = rng.uniform(0.3, 1.2, n_points) if C == 1 else None
    if geometry == "planar":
        x_i = rng.uniform(0, 8, (n_points, 2)).astype(np.float32).astype(float)
        alpha = PlanarAlpha(f16(rng.uniform(0.5, 1.5, (16, 16))), np.array([0.0, 0.0]), 0.5)
        frame = None
    elif mesh is not None:
        x_i = np.asarray(mesh.vertices)[points]
        alpha = VertexAlpha(rng.uniform(0.8, 1.2, len(mesh.vertices)), np.asarray(mesh.vertices))
        frame = tangent_frames(np.asarray(mesh.vertex_normals)[points])
    else:
        verts = (4 * rng.normal(size=(20, 3))).astype(np.float32).astype(float)
        x_i = verts[:n_points]
        alpha = VertexAlpha(f16(rng.uniform(0.5, 1.5, 20)), verts)
        q, _ = np.linalg.qr(rng.normal(size=(n_points, 3, 3)))
        frame = np.transpose(q, (0, 2, 1)).astype(np.float32).astype(float)
    return ExponentialModel(x_i, f16(c), f16(d), alpha, s_g=f16(s_g), s_b=f16(s_b), frame=frame)


def flat(text: str) -> str:
    """Command output without the boxes' borders and line breaks: words separated by single spaces."""
    return " ".join(re.sub(r"[│╭╮╰╯─]", " ", text).split())


def error_line(args) -> str:
    """The one ``error:`` line of a refused command (exit status 2): no traceback, no NumPy scalar reprs."""
    from translucency.cli.app import app  # the CLI, for the tests that run it

    res = CliRunner().invoke(app, [str(a) for a in args], env={"COLUMNS": "400"})
    lines = [ln for ln in res.output.splitlines() if ln.startswith("error:")]
    assert res.exit_code == 2 and len(lines) == 1, res.output
    assert "Traceback" not in res.output and "np.float64" not in res.output
    assert isinstance(res.exception, (SystemExit, type(None)))
    return lines[0]
