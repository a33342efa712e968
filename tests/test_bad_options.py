"""Every numeric option is checked at the boundary: NaN, inf, zero, negative and absurd values end in one
``error:`` line naming the option and exit status 2, before any work (issue 14, item 4)."""

import pytest
from typer.testing import CliRunner

from translucency import TranslucencyError
from translucency.cli.app import app
from translucency.render.lights import parse_light

runner = CliRunner()

PLANAR = ["acquire", "planar", "--material", "marble", "--out", "x.zarr"]
MESH = ["acquire", "mesh", "--out", "x.zarr"]
FIT = ["fit", "data.zarr", "--out", "m.model.zip"]
RENDER = ["render", "m.model.zip"]

CASES = [
    (PLANAR, "--photons", "0"),
    (PLANAR, "--seed", "-1"),
    (PLANAR, "--grid", "100000"),
    (PLANAR, "--pitch", "nan"),
    (PLANAR, "--voxel", "0"),
    (PLANAR, "--g", "1"),
    (PLANAR, "--chunk", "0"),
    (MESH, "--photons", "-5"),
    (MESH, "--points", "0"),
    (MESH, "--scale", "inf"),
    (MESH, "--voxel", "-1"),
    (FIT, "--rounds", "0"),
    (FIT, "--exclusion", "-1"),
    (FIT, "--chunk", "0"),
    (RENDER, "--reference-spp", "0"),
    (RENDER, "--reference-spp", "-3"),
    (RENDER, "--radius", "-1"),
    (["materials"], "--eta", "0"),
    (["materials"], "--eta", "nan"),
]


@pytest.mark.parametrize("command,option,value", CASES)
def test_bad_numbers_are_one_line_naming_the_option(command, option, value):
    res = runner.invoke(app, [*command, option, value])
    lines = [ln for ln in res.output.strip().splitlines() if ln.strip()]
    assert res.exit_code == 2, res.output
    assert len(lines) == 1 and lines[0].startswith("error:") and option in lines[0], res.output


def test_render_size_is_checked():
    res = runner.invoke(app, [*RENDER, "--resolution", "0", "10"])
    assert res.exit_code == 2 and "--resolution" in res.output


@pytest.mark.parametrize(
    "text,match",
    [
        ("point:0,0,10,nan", "finite"),
        ("point:0,0,10,-5", ">= 0"),
        ("directional:0,0,-1,inf", "finite"),
        ("spot:1,2,3,1,2,3,20", "aimed at its own position"),
        ("spot:0,0,10,0,0,0,20,-1", ">= 0"),
        ("directional:0,0,0", "non-zero direction"),
    ],
)
def test_degenerate_lights_are_refused(text, match):
    with pytest.raises(TranslucencyError, match=match):
        parse_light(text)


@pytest.mark.parametrize(
    "command",
    [
        ["demo"],
        ["materials"],
        ["info"],
        ["acquire", "planar"],
        ["acquire", "mesh"],
        ["fit"],
        ["render"],
        ["evaluate"],
    ],
)
def test_help_names_the_kind_of_every_value(command):
    out = runner.invoke(app, [*command, "--help"], terminal_width=200).output
    for placeholder in ("<float>", "<int>", "<str>", "<path>  Output", "<bool>  Replace"):
        assert placeholder not in out, (command, placeholder)


def test_version():
    from translucency import __version__

    res = runner.invoke(app, ["--version"])
    assert res.exit_code == 0 and res.output.strip() == f"translucency {__version__}"
