import numpy as np
import pytest

from translucency.model import ExponentialModel, PlanarAlpha, VertexAlpha


def random_exponential_model(rng, n_points=4, m=1, n=3, colour="shared", geometry="planar"):
    """A valid random model; parameters exactly representable in float16 (so round trips are exact)."""
    C = 1 if colour == "shared" else 3
    c = rng.uniform(0.01, 2.0, (n_points, C, m, n))
    d = -rng.uniform(0.2, 6.0, (n_points, C, m, n))
    s_g = rng.uniform(0.3, 1.2, n_points) if C == 1 else None
    s_b = rng.uniform(0.3, 1.2, n_points) if C == 1 else None
    f16 = lambda a: None if a is None else a.astype(np.float16).astype(np.float64)  # noqa: E731
    if geometry == "planar":
        x_i = rng.uniform(0, 8, (n_points, 2)).astype(np.float32).astype(float)
        alpha = PlanarAlpha(f16(rng.uniform(0.5, 1.5, (16, 16))), np.array([0.0, 0.0]), 0.5)
        frame = None
    else:
        verts = rng.normal(size=(20, 3)).astype(np.float32).astype(float)
        x_i = verts[:n_points]
        alpha = VertexAlpha(f16(rng.uniform(0.5, 1.5, 20)), verts)
        q, _ = np.linalg.qr(rng.normal(size=(n_points, 3, 3)))
        frame = np.transpose(q, (0, 2, 1)).astype(np.float32).astype(float)
    return ExponentialModel(x_i, f16(c), f16(d), alpha, s_g=f16(s_g), s_b=f16(s_b), frame=frame)


@pytest.fixture
def rng():
    return np.random.default_rng(12345)


@pytest.fixture(autouse=True)
def _in_a_scratch_folder(tmp_path, monkeypatch):
    """Every test runs in its own empty folder: default outputs (``render/``, ``report/``) never land in the checkout."""
    monkeypatch.chdir(tmp_path)
