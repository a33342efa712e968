import os
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import settings

from helpers import FUZZ
from translucency.acquire import PlanarSetup, acquire_planar, make_sample

# The documentation's generators (docs/_gen: cli_reference writes docs/reference/cli.md and docs/api.md's
# option lists, json_schemas holds the schemas of --json and writes docs/json.md): plain modules outside the
# installed package, imported by the tests that hold the pages and the outputs to them.
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "docs" / "_gen"))

# Hypothesis profiles.  "default": Hypothesis's own budget for the property tests, while the fuzz suite
# (tests/test_fuzz.py) keeps to a few derandomised examples per reader so the fast suite stays fast;
# "long" (`make test-slow`: TRANSLUCENCY_HYPOTHESIS_PROFILE=long, or `--hypothesis-profile=long`) gives
# every test, the fuzz suite included, 200 random examples.
settings.register_profile("long", max_examples=200, **FUZZ)
if os.environ.get("TRANSLUCENCY_HYPOTHESIS_PROFILE"):
    settings.load_profile(os.environ["TRANSLUCENCY_HYPOTHESIS_PROFILE"])


@pytest.fixture
def rng():
    return np.random.default_rng(12345)


@pytest.fixture(autouse=True)
def _in_a_scratch_folder(tmp_path, monkeypatch):
    """Every test runs in its own empty folder with its own reference cache: outputs never land in
    the checkout."""
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("TRANSLUCENCY_CACHE", str(tmp_path / "cache"))  # never the user's own cache


@pytest.fixture(scope="session")
def planar_scan(tmp_path_factory):
    """The planar photon scans of the tests, each acquired once per session.

    ``planar_scan(sample, side=, span=, photons=, seed=, volume_seed=seed)`` → the data set of side × side
    incident points over span mm (one chunk), 6 mm windows of 0.25 mm, ``photons`` per point and channel
    with photon seed ``seed``, on a 12 × 12 × 6 mm volume of ``sample`` at 0.25 mm (generator seed
    ``volume_seed``).  The same arguments give the same (read-only) data set.
    """
    volumes, scans = {}, {}

    def scan(sample, *, side, span, photons, seed, volume_seed=None):
        volume_seed = seed if volume_seed is None else volume_seed
        key = (sample, side, span, photons, seed, volume_seed)
        if key not in scans:
            if (sample, volume_seed) not in volumes:
                volumes[sample, volume_seed] = make_sample(sample, (12.0, 12.0, 6.0), 0.25, seed=volume_seed)
            setup = PlanarSetup(grid=(side, side), span=(span, span), pitch=0.25, window=6.0, photons=photons,
                                seed=seed, chunk_points=side * side)  # fmt: skip
            folder = tmp_path_factory.mktemp(sample.replace(":", "_"))
            scans[key] = acquire_planar(volumes[sample, volume_seed], setup, folder / "scan.zarr")
        return scans[key]

    return scan
