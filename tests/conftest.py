import os

import numpy as np
import pytest
from hypothesis import settings

from helpers import FUZZ

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
