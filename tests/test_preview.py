"""``acquire object-photographs --preview``: the rehearsal's smaller settings where the command line gives
none, the user's own where it does (what reaches the workflow, read from the call itself)."""

from __future__ import annotations

import pytest
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


def test_preview_sets_the_rehearsal_where_nothing_is_given(called):
    assert _run("--preview").exit_code == 0
    got = {k: called[k] for k in photographing.PREVIEW}
    assert got == {"points": 4, "cameras": 4, "resolution": (48, 36), "spp": 4, "voxel_mm": 1.0}


def test_preview_keeps_what_the_user_gives(called):
    assert _run("--preview", "--cameras", "3", "--spp", "8").exit_code == 0
    assert (called["cameras"], called["spp"], called["points"]) == (3, 8, 4)


def test_without_preview_the_defaults_stand(called):
    assert _run().exit_code == 0
    got = {k: called[k] for k in photographing.PREVIEW}
    assert got == {"points": 8, "cameras": 6, "resolution": (128, 128), "spp": 64, "voxel_mm": 0.5}
