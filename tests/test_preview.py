"""``acquire object-photographs --preview``: the rehearsal's smaller settings where the command line gives
none, the user's own where it does (what reaches the workflow, read from the call itself)."""

from __future__ import annotations

import tempfile
from pathlib import Path

import pytest
import trimesh
from typer.testing import CliRunner

from translucency.cli.app import app
from translucency.workflow import photographing

runner = CliRunner()


@pytest.fixture
def called(monkeypatch):
    """The keyword arguments the command passes to acquire_object_photographs (which is not run)."""
    seen = {}

    def fake(mesh, out, **kwargs):
        seen.update(kwargs)
        raise SystemExit(0)

    monkeypatch.setattr(photographing, "acquire_object_photographs", fake)
    return seen


def _run(*args):
    return runner.invoke(app, ["acquire", "object-photographs", "--out", "rig", *args])


def test_preview_leaves_to_the_rehearsal_what_is_not_given(called):
    assert _run("--preview").exit_code == 0
    assert called["preview"] is True
    assert all(called[k] is None for k in photographing.PREVIEW)  # the workflow takes PREVIEW's


def test_preview_keeps_what_the_user_gives(called):
    assert _run("--preview", "--cameras", "3", "--spp", "8").exit_code == 0
    assert (called["cameras"], called["spp"], called["points"]) == (3, 8, None)


def test_without_preview_the_defaults_stand(called):
    assert _run().exit_code == 0
    got = {k: called[k] for k in photographing.PREVIEW}
    assert got == photographing.FULL and called["preview"] is False
    full = {"points": 8, "cameras": 6, "resolution": (128, 128), "spp": 64, "voxel_mm": 0.5}
    assert photographing.FULL == full


def test_the_workflow_takes_the_rehearsal_where_none_is_given(monkeypatch):
    """What acquire_object_photographs photographs with: PREVIEW's settings, a given one kept (read where
    the shots are checked, before any rendering)."""
    seen = {}

    def stop(run, out, obj, volume, points, cameras, resolution, spp, exposures):
        seen.update(points=points, cameras=cameras, resolution=resolution, spp=spp, voxel=volume.voxel_mm)
        raise SystemExit(0)

    monkeypatch.setattr(photographing, "_check_object_shots", stop)
    ball = trimesh.creation.icosphere(2, radius=10.0)
    with pytest.raises(SystemExit):
        photographing.acquire_object_photographs(ball, tmp_folder(), preview=True, cameras=3)
    assert seen == {"points": 4, "cameras": 3, "resolution": (48, 36), "spp": 4, "voxel": 1.0}


def tmp_folder() -> Path:
    return Path(tempfile.mkdtemp()) / "rig"
