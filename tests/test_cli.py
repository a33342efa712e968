"""The command line: help everywhere, the main job, info, one-line errors."""

import json
import re

import numpy as np
import pytest
import typer
from typer.testing import CliRunner

from helpers import flat, random_exponential_model
from translucency import load_model, save_model
from translucency.cli.app import app
from translucency.io.dataset import dataset_identity, open_dataset
from translucency.io.model_file import read_header

runner = CliRunner()


def _commands(command, path=()):
    """(path, command) of the command line and of every command and subcommand under it."""
    yield list(path), command
    for name, sub in getattr(command, "commands", {}).items():
        yield from _commands(sub, (*path, name))


COMMANDS = list(_commands(typer.main.get_command(app)))


@pytest.mark.parametrize(
    ("path", "command"), COMMANDS, ids=[" ".join(p) or "translucency" for p, _ in COMMANDS]
)
def test_help(path, command):
    """Every command and subcommand: ``--help`` exits 0 and shows its description, every option (each of
    its names) and argument with its own help text, and every subcommand."""
    res = runner.invoke(app, [*path, "--help"], env={"COLUMNS": "240"})
    assert res.exit_code == 0, res.output
    assert "Usage" in res.output and "Traceback" not in res.output
    out = flat(res.output)
    assert command.help, f"{path}: no description"
    assert flat(command.help.split("\n\n")[0]) in out, path
    for param in command.params:
        assert param.help, f"{path}: {param.name} has no help text"
        assert flat(param.help) in out, (path, param.name)
        if param.param_type_name == "option":
            assert all(f" {name} " in f" {out} " for name in param.opts + param.secondary_opts), param.opts
    for name, sub in getattr(command, "commands", {}).items():
        assert not sub.hidden and f" {name} " in out, (path, name)
    assert len(command.params) + len(getattr(command, "commands", {})) > 0, f"{path}: nothing to list"


def test_help_lists_commands():
    out = runner.invoke(app, ["--help"]).output
    for cmd in ("demo", "info", "materials", "acquire", "fit", "evaluate"):
        assert cmd in out


def test_info_on_valid_model(tmp_path, rng):
    path = save_model(
        random_exponential_model(rng, n_points=5, m=8), tmp_path / "m.model.zip", dtype="float16"
    )
    res = runner.invoke(app, ["info", str(path)])
    assert res.exit_code == 0, res.output
    assert "exponential" in res.output and "float16" in res.output and "yes" in res.output
    assert f"{path.stat().st_size:,} bytes" in res.output


def test_info_on_garbage_is_one_line(tmp_path):
    bad = tmp_path / "junk.model.zip"
    bad.write_bytes(b"\x00" * 100)
    res = runner.invoke(app, ["info", str(bad)])
    assert res.exit_code == 2
    lines = [ln for ln in res.output.strip().splitlines() if ln.strip()]
    assert (
        len(lines) == 1 and lines[0].startswith("error:") and "junk.model.zip" in res.output.replace("\n", "")
    )
    assert "Traceback" not in res.output


# The main job's tests are slow (`make test-slow`): its one run took 283 s of a 24-min fast suite on a loaded
# machine (173 s cold on 2 quiet cores), two thirds of it Figure 2's pig (96 points x 8000 photons, which
# its thresholds were measured at).  test_demo_baselines_follow_the_dipole keeps its first stage fast.
@pytest.fixture(scope="module")
def demo_out(tmp_path_factory):
    """The main job, run once for the tests that read its outputs."""
    out = tmp_path_factory.mktemp("demo")
    res = runner.invoke(app, ["demo", "--out", str(out)])
    assert res.exit_code == 0, res.output
    return out


def test_demo_baselines_follow_the_dipole():
    """The main job's first stage (baselines.json, dipole_fits.model.zip) without the rest of it: for every
    material of Jensen's table the 3-term exponential fit follows the dipole better than Burley's shape."""
    from translucency.evaluate.baselines import fits_model, material_profiles
    from translucency.model import MATERIALS

    profiles = [material_profiles(mat, n_terms=3) for mat in MATERIALS.values()]
    summary = {p.material.name: p.summary() for p in profiles}
    assert len(summary) == 12
    for name, row in summary.items():
        assert max(row["exp_fit_rel_rms_vs_dipole"]) < 0.15, name
        assert np.mean(row["exp_fit_rel_rms_vs_dipole"]) < np.mean(row["burley_fit_rel_rms_vs_dipole"]), name
    model = fits_model(profiles)
    assert model.n_points == 12 and model.colour == "per-channel"


@pytest.mark.slow
def test_demo_writes_real_outputs(demo_out):
    tmp_path = demo_out
    png = (tmp_path / "baselines.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 50_000
    summary = json.loads((tmp_path / "baselines.json").read_text())["materials"]
    assert len(summary) == 12
    # the 3-term fit follows the dipole far better than the 2-exponential Burley shape
    for name, row in summary.items():
        assert max(row["exp_fit_rel_rms_vs_dipole"]) < 0.15, name
        assert np.mean(row["exp_fit_rel_rms_vs_dipole"]) < np.mean(row["burley_fit_rel_rms_vs_dipole"]), name
    model = load_model(tmp_path / "dipole_fits.model.zip")
    assert model.n_points == 12 and model.colour == "per-channel"
    assert not [p for p in tmp_path.iterdir() if ".tmp-" in p.name]


@pytest.mark.slow
def test_demo_fits_the_embedded_measurement(demo_out):
    tmp_path = demo_out
    rep = json.loads((tmp_path / "report" / "report.json").read_text())
    iso, default, paper, dip = (rep["models"][k] for k in ("iso", "default", "paper", "dipole"))
    noise = rep["noise_floor"]
    # held out against an independent acquisition of the same sample (the shipped truth): what is left of
    # the exponential sums' error beyond the truth's own noise is well under the dipole's near x_i, and the
    # anisotropic model wins on the sample's fibrous band
    assert rep["truth"]
    assert iso["rel_l2"] < dip["rel_l2"] and iso["rel_l2_near"] < 0.7 * dip["rel_l2_near"]
    assert iso["beyond_noise"]["near"] < 0.6 * dip["beyond_noise"]["near"]
    assert noise["near"] < iso["rel_l2_near"]
    # the default's structure, chosen on the data's own photons, is closer to the truth than iso and the
    # paper's (anisotropic, shared colour), both of which it could have chosen
    assert default["rel_l2"] <= min(iso["rel_l2"], paper["rel_l2"])
    fit = read_header(tmp_path / "fits" / "default.model.zip")["meta"]["fit"]
    assert fit["structure"]["chosen"]["n_directions"] > 1  # the fibrous band's directions won held out
    for label in ("default", "paper", "iso", "dipole", "burley"):
        assert load_model(tmp_path / "fits" / f"{label}.model.zip").n_points == 1024
    # every planar model the demo fitted is in the report, with finite held-out errors within [0, 1]
    planar = {p.name.removesuffix(".model.zip") for p in (tmp_path / "fits").glob("*.model.zip")}
    planar = {
        label for label in planar if load_model(tmp_path / "fits" / f"{label}.model.zip").geometry == "planar"
    }
    assert set(rep["models"]) == planar and {"default", "paper", "iso", "dipole", "burley"} <= planar
    for label, row in [("report", rep), *rep["models"].items()]:
        held_out = [row[k] for k in ("rel_l2", "rel_l2_near", "rel_l2_mid", "rel_l2_far")]
        held_out += [row["beyond_noise"][band] for band in ("all", "near", "mid", "far")]
        assert all(np.isfinite(e) and 0 <= e <= 1 for e in held_out), (label, held_out)
    assert rep["model"] in rep["models"] and rep["rel_l2"] == rep["models"][rep["model"]]["rel_l2"]


@pytest.mark.slow
def test_every_model_file_of_the_demo_is_valid(demo_out):
    """`info` calls every model file the demo writes valid (exit 0): the planar fits on the data set's
    32 mm sample, the pig's per-vertex model, and Jensen's materials as semi-infinite slabs."""
    files = sorted((demo_out / "fits").glob("*.model.zip")) + [demo_out / "dipole_fits.model.zip"]
    assert {p.name.removesuffix(".model.zip") for p in files} == {
        "default", "paper", "iso", "dipole", "burley", "pig_iso", "dipole_fits"
    }  # fmt: skip
    for path in files:
        res = runner.invoke(app, ["info", str(path)])
        assert res.exit_code == 0, (path.name, res.output)
    rep = json.loads((demo_out / "report" / "report.json").read_text())
    for label, row in rep["models"].items():  # the report lists no unphysical point either
        assert row["physics"]["over_albedo"] == [] and row["physics"]["beyond_object"] == [], label


def _png_size(path):
    """(width, height) of a PNG file whose every chunk checks out (its CRCs, its end)."""
    from PIL import Image  # Pillow comes with matplotlib

    with Image.open(path) as im:
        assert im.format == "PNG", path
        im.verify()
    with Image.open(path) as im:
        im.load()
        return im.size


@pytest.mark.slow
def test_demo_report_shows_every_figure(demo_out):
    """index.html shows every figure of the report, and each is a PNG that decodes and is not empty."""
    report = demo_out / "report"
    shown = re.findall(r'<img src="([^"]+)"', (report / "index.html").read_text())
    assert len(shown) == len(set(shown))
    # the figures of Figure 1 (profiles, error maps, α, parameters), the relighting and Figure 2
    assert {"profiles.png", "error_maps.png", "error_ratios.png", "alpha.png", "params.png"} <= set(shown)
    assert {"relight.png", "figure2.png"} <= set(shown)
    # every other picture of the folder is one that Figure 2 puts side by side
    assert {p.name for p in report.glob("*.png")} - set(shown) <= {"ours.png", "reference.png"}
    for name in {*shown, "ours.png", "reference.png"}:
        width, height = _png_size(report / name)
        assert width > 0 and height > 0 and (report / name).stat().st_size > 0, name


@pytest.mark.slow
def test_demo_makes_figure_2(demo_out):
    fig = json.loads((demo_out / "report" / "figure2.json").read_text())
    # the fitted pig beside its converged volpath reference (2 x 256 spp, its own noise 0.043): measured
    # 0.083 / 0.114 with the measured near field (0.50 / 0.43 before it, 0.17 / 0.28 without it)
    assert fig["reference_noise"] < 0.05
    for key in ("rel_rmse", "flip_mean_object", "flip_mean_image", "reference_noise"):
        assert np.isfinite(fig[key]) and 0 <= fig[key] <= 1, key
    assert all(np.isfinite(r["rel_rmse"]) and r["rel_rmse"] >= 0 for r in fig["regions"].values())
    assert fig["rel_rmse"] < 0.12 and fig["flip_mean_object"] < 0.15
    assert all(
        fig["regions"][k]["pixels"] > 0 for k in ("thin", "thick", "shadow edge", "unlit", "silhouette")
    )
    assert load_model(demo_out / "fits" / "pig_iso.model.zip").geometry == "mesh"
    assert (demo_out / "report" / "figure2.png").stat().st_size > 10_000


def test_acquire_planar_cli(tmp_path):
    out = tmp_path / "m.zarr"
    args = [
        "acquire",
        "planar",
        "--material",
        "marble",
        "--out",
        str(out),
        "--grid",
        "2",
        "--photons",
        "500",
        "--size",
        "10",
        "10",
        "3",
        "--voxel",
        "0.5",
        "--window",
        "4",
        "--pitch",
        "0.5",
    ]
    res = runner.invoke(app, args)
    assert res.exit_code == 0, res.output
    # what the flags asked for: 2 × 2 points, 4 mm windows of 0.5 mm pixels, 500 photons; R_d a density
    ds = open_dataset(out)
    n = ds.window[0]
    assert ds["x_i"].shape == (4, 2) and ds.pitch == 0.5 and n % 2 == 1 and abs(n * 0.5 - 4) <= 0.5
    assert ds.header["acquisition"]["photons"] == 500 and ds.complete()
    R = np.asarray(ds["R_d"])
    assert R.shape == (4, n, n, 3) and np.isfinite(R).all() and (R >= 0).all() and (R.sum((1, 2)) > 0).all()
    assert (R.sum(axis=(1, 2)) * 0.5**2 <= np.asarray(ds["total_diffuse"]) + 1e-6).all()
    info = runner.invoke(app, ["info", str(out)])
    assert info.exit_code == 0 and "translucency-dataset v1" in info.output and "1/1 chunks" in info.output
    bad = runner.invoke(app, args[:-2] + ["--window", "40"])
    assert bad.exit_code == 2 and "error: window: 40.0 mm is larger than the sample" in bad.output
    both = runner.invoke(app, ["acquire", "planar", "--out", str(out)])
    assert both.exit_code == 2 and "exactly one of --material" in both.output


def _tiny_planar(out, seed=0):
    args = ["acquire", "planar", "--material", "marble", "--out", str(out), "--grid", "2", "--span", "2"]
    args += ["--photons", "300", "--size", "6", "6", "3", "--voxel", "0.5", "--window", "2", "--pitch", "0.5"]
    return args + ["--seed", str(seed)]


def test_quiet_and_json_for_scripts(tmp_path):
    """--quiet prints nothing on success; --json prints one strict JSON object on stdout (issue 14)."""
    res = runner.invoke(app, [*_tiny_planar(tmp_path / "a.zarr"), "--quiet"])
    assert res.exit_code == 0 and res.output.strip() == "", res.output
    res = runner.invoke(app, [*_tiny_planar(tmp_path / "b.zarr"), "--json", "--quiet"])
    summary = json.loads(res.stdout)
    assert summary["complete"] and summary["points"] == 4 and summary["estimate"]["memory_bytes"] > 0
    res = runner.invoke(
        app, ["fit", str(tmp_path / "a.zarr"), "-o", str(tmp_path / "a.model.zip"), "--json", "-q"]
    )
    fit = json.loads(res.stdout)
    assert res.exit_code == 0 and fit["kind"] == "exponential" and fit["rounds"] >= 1
    res = runner.invoke(
        app,
        ["evaluate", str(tmp_path / "a.model.zip"), str(tmp_path / "a.zarr"), "--report", str(tmp_path / "r")]
        + ["--json", "--quiet"],
    )
    ev = json.loads(res.stdout, parse_constant=lambda c: pytest.fail(f"{c} in JSON"))
    assert res.exit_code == 0 and ev["command"] == "evaluate" and 0 < ev["rel_l2"] < 10
    bad = runner.invoke(app, ["fit", str(tmp_path / "nowhere.zarr"), "-o", "m.model.zip", "--quiet"])
    assert bad.exit_code == 2 and bad.output.startswith("error:")  # errors still printed


def test_evaluate_on_another_sample_warns(tmp_path):
    """A model fitted on one sample, evaluated on a data set of another (here: another generated marble)."""
    for name, seed in (("a", 0), ("b", 5)):
        assert runner.invoke(app, _tiny_planar(tmp_path / f"{name}.zarr", seed)).exit_code == 0
    res = runner.invoke(app, ["fit", str(tmp_path / "a.zarr"), "-o", str(tmp_path / "a.model.zip"), "-q"])
    assert res.exit_code == 0, res.output
    same = runner.invoke(
        app,
        [
            "evaluate",
            str(tmp_path / "a.model.zip"),
            str(tmp_path / "a.zarr"),
            "--report",
            str(tmp_path / "r1"),
        ],
    )
    assert same.exit_code == 0 and "another sample" not in same.output
    other = runner.invoke(
        app,
        [
            "evaluate",
            str(tmp_path / "a.model.zip"),
            str(tmp_path / "b.zarr"),
            "--report",
            str(tmp_path / "r2"),
        ],
    )
    warnings = [
        ln for ln in other.output.splitlines() if ln.startswith("warning:") and "another sample" in ln
    ]
    assert other.exit_code == 0 and len(warnings) == 1, other.output


def test_usage_errors_are_one_line():
    res = runner.invoke(app, ["acquire", "planar", "--grid", "abc", "--out", "x.zarr"])
    lines = [ln for ln in res.output.splitlines() if ln.strip()]
    assert res.exit_code == 2 and len(lines) == 1 and lines[0].startswith("error:") and "--grid" in lines[0]


def test_a_truth_of_the_same_sample_with_another_photon_seed(tmp_path):
    """--sample-seed keeps the generated sample while --seed draws other photons: the two data sets are one
    sample (no warning), differ in their photons, and the second serves as the first's held-out truth."""
    for name, seed in (("data", 1), ("truth", 2)):
        res = runner.invoke(app, [*_tiny_planar(tmp_path / f"{name}.zarr", seed), "--sample-seed", "7"])
        assert res.exit_code == 0, res.output
    data, truth = (open_dataset(tmp_path / f"{n}.zarr") for n in ("data", "truth"))
    assert dataset_identity(data.header) == dataset_identity(truth.header)
    assert not np.array_equal(np.asarray(data.group["R_d"][0]), np.asarray(truth.group["R_d"][0]))
    res = runner.invoke(app, ["fit", str(tmp_path / "data.zarr"), "-o", str(tmp_path / "m.model.zip"), "-q"])
    assert res.exit_code == 0, res.output
    res = runner.invoke(
        app,
        ["evaluate", str(tmp_path / "m.model.zip"), str(tmp_path / "data.zarr")]
        + ["--truth", str(tmp_path / "truth.zarr"), "--report", str(tmp_path / "r")],
    )
    assert res.exit_code == 0 and "another sample" not in res.output, res.output
