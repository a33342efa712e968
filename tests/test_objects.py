"""Objects for issue 5: the procedural pig and reading a user's mesh."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import trimesh

from translucency._validate import TranslucencyError
from translucency.acquire.objects import make_pig, pig_sdf
from translucency.io.mesh import load_mesh


def test_pig_is_a_closed_figurine_of_the_right_size():
    pig = make_pig()
    assert pig.is_watertight and pig.is_winding_consistent and pig.volume > 0
    assert 20_000 <= len(pig.vertices) <= 50_000
    assert pig.euler_number == 2  # one closed surface of genus 0
    length, width, height = pig.extents
    assert 75 < length < 90 and 30 < width < 40 and 40 < height < 55
    # the surface is the zero set of the field: vertices lie on it to a fraction of the grid
    assert np.abs(pig_sdf(pig.vertices)).max() < 0.3
    # normals point out: a step along the normal leaves the pig
    assert (pig_sdf(pig.vertices + 0.5 * pig.vertex_normals) > 0).mean() > 0.99


def test_load_mesh_scales_and_checks(tmp_path):
    p = tmp_path / "ball.obj"
    trimesh.creation.icosphere(3, radius=1.0).export(p)
    m = load_mesh(p, scale_mm=10.0)
    assert m.is_watertight and m.extents[0] == pytest.approx(20.0, rel=1e-6)
    assert m.volume == pytest.approx(4 / 3 * np.pi * 1000, rel=0.02)


def test_load_mesh_refuses_open_and_missing(tmp_path):
    ball = trimesh.creation.icosphere(3)
    keep = np.ones(len(ball.faces), bool)
    keep[:40] = False  # a large hole that fill_holes cannot close
    open_mesh = trimesh.Trimesh(ball.vertices, ball.faces[keep], process=False)
    p = tmp_path / "open.ply"
    open_mesh.export(p)
    with pytest.raises(TranslucencyError, match="not closed"):
        load_mesh(p)
    with pytest.raises(TranslucencyError, match="no such mesh file"):
        load_mesh(tmp_path / "none.obj")
    bad = tmp_path / "junk.obj"
    bad.write_text("this is not a mesh\n")
    with pytest.raises(TranslucencyError, match="junk.obj"):
        load_mesh(bad)


def test_load_mesh_repairs_small_defects_with_a_warning(tmp_path):
    ball = trimesh.creation.icosphere(2)
    faces = np.vstack([ball.faces[1:], [[0, 0, 1]]])  # one triangle missing, one degenerate
    p = tmp_path / "dented.ply"
    trimesh.Trimesh(ball.vertices, faces, process=False).export(p)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        m = load_mesh(p)
    assert m.is_watertight
    text = " ".join(str(w.message) for w in caught)
    assert "degenerate" in text and "holes were filled" in text
