"""End to end (slow): photographs rendered by Mitsuba of a virtual object → ``import object`` → the same
per-vertex data, energy and picture as the photon tally of the same object (issue 23).

The photographs (:mod:`translucency.rig.object.photographs`) are Mitsuba's ``volpath``, the tally our
photon walk: two independent estimators of one experiment.  The photographs' own noise floor is measured
with a second, independent set of photographs (:mod:`translucency.pipeline.object_rig_check`).  Figures
at larger settings: ``python benchmarks/object_rig.py sphere|torus|pig`` (docs/reference/object-rig.md).
"""

from __future__ import annotations

import json

import numpy as np
import pytest
import trimesh

from translucency.acquire.mesh import object_volume
from translucency.pipeline.object_rig_check import object_rig_check

pytestmark = pytest.mark.slow


def _show(out: dict) -> dict:
    print(json.dumps({k: v for k, v in out.items() if k != "exit_law"}))  # the figures, with -s
    return out


@pytest.fixture(scope="module")
def sphere(tmp_path_factory):
    """A 6 mm sphere of skin: 3 laser shots, 6 cameras, photographed twice, imported, tallied, rendered."""
    mesh = trimesh.creation.icosphere(subdivisions=4, radius=6.0)
    volume = object_volume("homogeneous:skin1", mesh, 0.5, seed=1)
    folder = tmp_path_factory.mktemp("sphere-rig")
    return _show(
        object_rig_check(
            mesh,
            volume,
            folder,
            points=3,
            cameras=6,
            resolution=(80, 80),
            spp=128,
            photons=50_000,
            reference_spp=32,
        )
    )


def _recovered(out: dict) -> None:
    # per pair: the photographs recover the tally as closely as two sets of photographs agree
    assert out["pairs_compared"] > 100, out
    assert out["recovery"] <= 1.5 * out["noise_floor"], out
    # the energy each laser shot puts into the object's exitance: median within 20 % of the tally's
    ratio = np.asarray(out["energy_ratio"])
    assert abs(np.median(ratio) - 1) < 0.2, ratio


def test_sphere_of_skin_photographed_and_imported(sphere):
    _recovered(sphere)


def test_sphere_render_from_photographs_within_1_25x_of_the_tally(sphere):
    """The render from photographs within 1.25x the tally path's error against volpath (measured 0.90x:
    0.217 against 0.240, the reference's noise 0.106; 1.6x before the default transport and the near peak's
    walks, docs/validation/object-rig.md)."""
    assert sphere["render_ratio"] <= 1.25, sphere


def test_torus_of_layered_skin_photographed_and_imported(tmp_path):
    """A second mesh (not convex: the object hides parts of itself) and a heterogeneous material."""
    mesh = trimesh.creation.torus(major_radius=8.0, minor_radius=3.5, major_sections=64, minor_sections=24)
    volume = object_volume("skin", mesh, 0.5, seed=1)
    out = object_rig_check(
        mesh,
        volume,
        tmp_path,
        points=2,
        cameras=6,
        resolution=(72, 72),
        spp=128,
        photons=50_000,
        render=False,
    )
    _recovered(_show(out))
