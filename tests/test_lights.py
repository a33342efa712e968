"""Lights and exposure a user can place: the light forms and their help, lights placed relative to the
object (azimuth, elevation, distance; camera and back), one exposure for every render of one object
under lights of one power, and the render summary's name."""

from __future__ import annotations

import json

import numpy as np
import pytest
import trimesh
from typer.testing import CliRunner

from helpers import random_exponential_model
from translucency import TranslucencyError
from translucency.cli.app import app
from translucency.render.lights import (
    DEFAULT_DISTANCE,
    DEFAULT_INTENSITY,
    DEFAULT_IRRADIANCE,
    DEFAULT_LIGHT,
    DirectionalLight,
    Placement,
    PointLight,
    RelativeLight,
    SpotLight,
    parse_light,
    place_light,
)
from translucency.render.tonemap import Exposure, parse_exposure

runner = CliRunner()

#: a box 20 × 20 × 20 mm with its centre at (0, 0, 10), seen from −y
BOX = Placement(((-10.0, -10.0, 0.0), (10.0, 10.0, 20.0)), view=(0.0, -1.0, 0.0))


def test_render_help_states_every_default_unit_and_direction():
    out = " ".join(runner.invoke(app, ["render", "--help"], terminal_width=300).output.split())
    assert "[default: point@key]" in out  # the light's default, hidden before
    assert "[default: fixed]" in out and "--exposure" in out
    assert "TRAVELS" in out and "+z up" in out and "mm" in out and "W/sr" in out and "W/mm^2" in out
    for form in ("point@AZ,EL", "spot@AZ,EL", "directional@AZ,EL", "env:MAP.exr", "camera", "back"):
        assert form in out, form


def test_relative_lights_are_placed_around_the_object():
    centre, size = np.array(BOX.centre), BOX.size
    assert BOX.centre == (0.0, 0.0, 10.0) and size == pytest.approx(np.sqrt(3) * 20)
    # azimuth from +x towards +y, elevation above the xy plane; the distance in mm or object sizes
    east = parse_light("point@0,0,50,1e3", BOX)
    assert isinstance(east, PointLight) and east.intensity == 1e3
    np.testing.assert_allclose(east.position, centre + [50.0, 0, 0], atol=1e-12)
    north = parse_light("point@90,0,2x", BOX)
    np.testing.assert_allclose(north.position, centre + [0, 2 * size, 0], atol=1e-9)
    above = parse_light("point@123,90", BOX)  # the default distance and power
    np.testing.assert_allclose(above.position, centre + [0, 0, DEFAULT_DISTANCE * size], atol=1e-9)
    # with no power given, I brings DEFAULT_IRRADIANCE to the centre: E = I / d² at d = 1.5 sizes
    assert above.intensity / (DEFAULT_DISTANCE * size) ** 2 == pytest.approx(DEFAULT_IRRADIANCE, rel=1e-12)
    assert parse_light("point:0,0,100").intensity == DEFAULT_INTENSITY  # a position in mm: the fixed default
    far = parse_light("point@123,90,100", BOX)  # 100 mm: E = 1 there too, whatever the size
    assert far.irradiance_scale(100.0) == pytest.approx(DEFAULT_IRRADIANCE, rel=1e-12)
    # a directional light comes FROM its angles: it travels the other way
    sun = parse_light("directional@45,30,2", BOX)
    u = np.array([np.cos(np.radians(30)) * np.cos(np.radians(45))] * 2 + [np.sin(np.radians(30))])
    assert isinstance(sun, DirectionalLight) and sun.irradiance == 2.0
    np.testing.assert_allclose(sun.direction, -u, atol=1e-12)
    # a spot stands at its distance, aimed at the object's centre
    spot = parse_light("spot@0,45,100,15,5e3", BOX)
    assert isinstance(spot, SpotLight) and spot.target == BOX.centre and spot.cutoff_deg == 15
    assert np.linalg.norm(np.subtract(spot.position, centre)) == pytest.approx(100.0)
    # from the camera's side, or behind the object
    np.testing.assert_allclose(parse_light("point@camera,30", BOX).position, centre + [0, -30, 0], atol=1e-12)
    np.testing.assert_allclose(parse_light("point@back,30", BOX).position, centre + [0, 30, 0], atol=1e-12)
    np.testing.assert_allclose(parse_light("directional@back", BOX).direction, [0, -1, 0], atol=1e-12)
    # the key light (the default light): the view (azimuth -90, elevation 0 here) turned 28° about +z and
    # raised 20°, written out by hand
    az, el = np.radians(-90.0 + 28.0), np.radians(20.0)
    key = parse_light(DEFAULT_LIGHT, BOX)
    assert DEFAULT_LIGHT == "point@key" and isinstance(key, PointLight)
    from translucency.cli import export, render  # their copies, kept so that --help loads no renderer

    assert render.DEFAULT_LIGHT == export.DEFAULT_LIGHT == DEFAULT_LIGHT
    u = np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])
    np.testing.assert_allclose(key.position, centre + DEFAULT_DISTANCE * size * u, atol=1e-9)
    steep = Placement(BOX.bounds, view=(0.0, 0.0, 1.0))  # from straight above: raised no further than 85°
    np.testing.assert_allclose(parse_light("directional@key", steep).direction[2], -np.sin(np.radians(85.0)))
    # without a placement the text is checked and kept until the object is known
    later = parse_light("point@-60,40")
    assert isinstance(later, RelativeLight)
    assert place_light(later, BOX) == parse_light("point@-60,40", BOX)
    assert place_light(east, BOX) is east
    # plain floats: no NumPy scalars in a light's text (the summary, the messages)
    for light in (north, sun, spot, parse_light("directional:0,0,-2")):
        assert "np." not in repr(light), repr(light)


@pytest.mark.parametrize(
    "text,part",
    [
        ("point@x,30", "azimuth"),
        ("point@10,y", "elevation"),
        ("point@10,95", "elevation"),
        ("point@10", "azimuth and an elevation"),
        ("point@10,20,-3", "distance"),
        ("point@10,20,0x", "distance"),
        ("point@10,20,far", "distance"),
        ("spot@10,20,2x,95", "cutoff"),
        ("point@10,20,2x,-1", "intensity"),
        ("directional@10,20,nan", "finite"),
        ("point@10,20,1,2,3", "at most 2"),
        ("env@10,20", "cannot be placed"),
        ("point:1,2", "takes 3 or 4 numbers"),
        ("point:1,q,3", "number 2 'q'"),
    ],
)
def test_bad_lights_name_the_part_in_one_line(text, part):
    with pytest.raises(TranslucencyError, match="light:") as err:
        parse_light(text, BOX)
    assert part in str(err.value) and "\n" not in str(err.value), str(err.value)


def test_camera_and_back_need_the_view():
    with pytest.raises(TranslucencyError, match="camera"):
        parse_light("point@camera", Placement(BOX.bounds))


def test_the_light_error_lists_every_form():
    with pytest.raises(TranslucencyError) as err:
        parse_light("laser:1,2")
    for form in (
        "point:x,y,z[,I]",
        "spot:x,y,z,tx,ty,tz,cutoff[,I]",
        "directional:dx,dy,dz[,E]",
        "env:L",
        "env:MAP.exr[,scale]",
        "point@AZ,EL",
        "spot@AZ,EL",
        "directional@AZ,EL",
    ):
        assert form in str(err.value), form


def test_exposure_texts():
    assert parse_exposure("fixed") == Exposure("fixed")
    assert parse_exposure("auto") == Exposure("auto")
    assert parse_exposure("fixed+1.5") == Exposure("fixed", stops=1.5)
    assert parse_exposure("fixed-2") == Exposure("fixed", stops=-2.0)
    assert parse_exposure("3.25") == Exposure("scale", scale=3.25)
    for bad in ("bright", "0", "-1", "nan", "fixed+x", "fixed+100", "inf"):
        with pytest.raises(TranslucencyError, match="^--exposure: expected fixed"):
            parse_exposure(bad, name="--exposure")
    # R E / π shown at 0.5: a stop more doubles it
    assert Exposure("fixed").fixed(reflectance=0.5, irradiance=np.pi) == pytest.approx(1.0)
    assert Exposure("fixed", stops=1).fixed(reflectance=0.5, irradiance=np.pi) == pytest.approx(2.0)


@pytest.fixture(scope="module")
def ball_model(tmp_path_factory):
    """A per-vertex model on a 162-vertex ball that carries its mesh (a render takes about a second)."""
    from translucency import save_model

    ball = trimesh.creation.icosphere(2, radius=5.0)
    rng = np.random.default_rng(3)
    model = random_exponential_model(rng, geometry="mesh", mesh=ball, points=np.arange(0, 162, 11))
    model.faces = np.asarray(ball.faces)
    path = tmp_path_factory.mktemp("lights") / "ball.model.zip"
    save_model(model, path)
    return model, ball, path


def _png(path):
    import matplotlib.image as mpimg

    return np.asarray(mpimg.imread(path))[..., :3]


def test_two_lights_on_one_object_share_one_exposure(ball_model, tmp_path):
    """Fixed (the default): one exposure for both lights, stated in render.json; auto: one per picture."""
    from translucency.render import Camera
    from translucency.render.still import render_still
    from translucency.render.tonemap import tonemap
    from translucency.transport import PreparedObject

    model, ball, _ = ball_model
    camera = Camera.looking_at(ball, width=48, height=36)
    place = Placement.of(ball, (1.0, -1.6, 0.7))
    summary = {}
    # one power (1e4 W/sr) at two distances: one fixed exposure (a relative light without a power would
    # get the I that brings 1 W/mm² from where it stands: another power)
    for name, text in (("front", "point@-60,40,1.5x,1e4"), ("side", "point@60,10,2x,1e4")):
        for how in ("fixed", "auto"):
            out = tmp_path / f"{name}-{how}"
            render_still(
                PreparedObject(model, ball), parse_light(text, place), out, camera=camera, spp=1, exposure=how
            )
            assert not (out / "figure2.json").exists()
            summary[name, how] = json.loads((out / "render.json").read_text())
            # the PNG is the linear picture at the stated exposure
            from translucency.mitsuba import mitsuba

            linear = np.asarray(mitsuba().Bitmap(str(out / "ours.exr")), dtype=np.float64)
            np.testing.assert_allclose(
                _png(out / "ours.png"), tonemap(linear, summary[name, how]["exposure"]), atol=1 / 255
            )
    assert summary["front", "fixed"]["exposure"] == summary["side", "fixed"]["exposure"]
    assert summary["front", "fixed"]["exposure_rule"].startswith("fixed:")
    assert summary["front", "auto"]["exposure"] != summary["side", "auto"]["exposure"]
    assert "exposure_rule" not in summary["front", "auto"]
    # a light of twice the power: a stop less
    double = tmp_path / "double"
    render_still(
        PreparedObject(model, ball), parse_light("point@-60,40,1.5x,2e4", place), double, camera=camera, spp=1
    )
    half = json.loads((double / "render.json").read_text())["exposure"]
    assert half == pytest.approx(summary["front", "fixed"]["exposure"] / 2)
    # a black light has no fixed exposure: auto, and the rule says why
    dark = tmp_path / "dark"
    render_still(
        PreparedObject(model, ball), parse_light("point@-60,40,1.5x,0", place), dark, camera=camera, spp=1
    )
    assert json.loads((dark / "render.json").read_text())["exposure_rule"].startswith("auto: no fixed")
    # Figure 2 keeps its names and its auto exposure (no rule stated)
    fig = tmp_path / "fig"
    render_still(
        PreparedObject(model, ball),
        PointLight((30.0, -40.0, 60.0), 2e4),
        fig,
        camera=camera,
        spp=1,
        exposure="auto",
        name="figure2",
    )
    assert (fig / "figure2.json").exists() and "exposure_rule" not in json.loads(
        (fig / "figure2.json").read_text()
    )


def test_render_writes_render_json_and_places_the_light(ball_model, tmp_path):
    _, _, path = ball_model
    out = tmp_path / "r"
    render = ["render", str(path), "--out", str(out), "--resolution", "24", "18"]
    res = runner.invoke(app, [*render, "--light", "spot@back,3x,25,1e3"])
    assert res.exit_code == 0, res.output
    assert "object: centre (" in res.output and "size" in res.output  # where the object sits
    assert (out / "render.json").exists() and not (out / "figure2.json").exists()
    summary = json.loads((out / "render.json").read_text())
    assert summary["light"].startswith("SpotLight(") and summary["exposure_rule"].startswith("fixed")
    res = runner.invoke(app, [*render, "--exposure", "auto", "--overwrite"])
    assert res.exit_code == 0, res.output
    assert "exposure_rule" not in json.loads((out / "render.json").read_text())
    res = runner.invoke(app, [*render, "--exposure", "3.5", "--overwrite"])
    assert res.exit_code == 0, res.output
    assert json.loads((out / "render.json").read_text())["exposure"] == 3.5


@pytest.mark.parametrize(
    "option,value,named",
    [
        ("--exposure", "bright", "--exposure"),
        ("--light", "point@10,95", "elevation"),
        ("--light", "torch:1,2,3", "env:MAP.exr[,scale]"),
    ],
)
def test_bad_light_or_exposure_is_one_line_and_writes_nothing(ball_model, tmp_path, option, value, named):
    _, _, path = ball_model
    out = tmp_path / "r"
    res = runner.invoke(app, ["render", str(path), "--out", str(out), option, value])
    lines = [ln for ln in res.output.strip().splitlines() if ln.strip()]
    assert res.exit_code == 2 and len(lines) == 1 and lines[0].startswith("error:"), res.output
    assert named in lines[0] and not out.exists(), res.output


def test_the_help_states_the_default_distance_of_the_constant():
    """``render --help`` writes the default distance as text (the command module stays cheap to import):
    it must be the one :data:`DEFAULT_DISTANCE` places lights at."""
    from typer.testing import CliRunner

    from translucency.cli.app import app

    help_text = CliRunner().invoke(app, ["render", "--help"], terminal_width=400).output
    text = " ".join(help_text.replace("│", " ").split())  # (the words, whatever the box's wrapping)
    assert f"default {DEFAULT_DISTANCE:g}x" in text


@pytest.mark.parametrize(("name", "scale"), [("spot.obj", 1.0), ("cow.obj", 1.0), ("spot.obj", 0.1)])
def test_the_default_light_exposes_every_example_object(name, scale, tmp_path):
    """The default render of each example mesh, as shipped and ten times smaller:
    at most 2 % of the object's pixels clipped, its median pixel between 60 and 220 of 255 — the default
    light (point@key, I = E d²) and the fixed exposure together, whatever the object's size."""
    from translucency import render_model, save_model
    from translucency.data import example_path
    from translucency.io.mesh import load_mesh
    from translucency.mitsuba import mitsuba

    mesh = load_mesh(example_path(name), scale_mm=scale)
    rng = np.random.default_rng(5)
    # a physical random model (total reflectance < 1, fall-off within 6 mm) on every 20th vertex
    model = random_exponential_model(
        rng, geometry="mesh", mesh=mesh, points=np.arange(0, len(mesh.vertices), 20)
    )
    model.faces = np.asarray(mesh.faces)
    path = tmp_path / "m.model.zip"
    save_model(model, path)
    out = tmp_path / "render"
    render_model(path, out, resolution=(80, 60))
    linear = np.asarray(mitsuba().Bitmap(str(out / "ours.exr")), dtype=np.float64)
    on = linear.sum(axis=2) > 0  # the object's pixels (the background is black)
    pixels = np.round(_png(out / "ours.png")[on] * 255)
    assert on.mean() > 0.1, on.mean()  # the object fills the picture
    clipped, median = (pixels >= 255).any(axis=1).mean(), float(np.median(pixels.mean(axis=1)))
    assert clipped <= 0.02 and 60 <= median <= 220, (clipped, median)
