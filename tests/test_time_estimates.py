"""Time before work (issue 14, item 7): every long command prints "about N s" before it starts, from
formulas whose rates this machine calibrates (a probe of its speed at first, then the commands' own runs,
cached in ``$TRANSLUCENCY_CACHE/timing.json``); the estimate of a run after a calibrating run of another
size is within 2x of its wall time."""

import json
import subprocess
import sys

import numpy as np
import pytest
import trimesh
from typer.testing import CliRunner

from translucency.cli.app import app
from translucency.resources import timing as resources

runner = CliRunner()
PLANAR = [
    "acquire",
    "planar",
    "--material",
    "homogeneous:marble",
    "--size",
    "10",
    "10",
    "4",
    "--voxel",
    "0.5",
]


def run_json(args) -> dict:
    """The command in a fresh process, as a user runs it (its own imports and kernel caches)."""
    cmd = [sys.executable, "-m", "translucency", *map(str, args), "--json", "-q"]
    res = subprocess.run(cmd, capture_output=True, text=True)
    assert res.returncode == 0, res.stderr[-2000:]
    return json.loads(res.stdout)


def within_2x(summary) -> float:
    est, actual = summary["time_estimate"]["seconds"], summary["seconds"]
    ratio = actual / est
    assert 0.5 <= ratio <= 2.0, (summary["command"], summary["time_estimate"], actual)
    return ratio


def calibrated(runs, attempts: int = 3) -> float:
    """Run ``runs()`` (calibrating runs, then the one measured) until the measured run's estimate is
    within 2x of its wall time; further attempts forgive runs slowed by other work on the machine
    (the tests share two cores), and calibrates on more runs.  Returns actual / estimate."""
    for attempt in range(attempts):
        summary = runs(attempt)
        ratio = summary["seconds"] / summary["time_estimate"]["seconds"]
        print(summary["command"], summary["time_estimate"], "actual", summary["seconds"])
        if 0.5 <= ratio <= 2.0 or attempt == attempts - 1:
            return within_2x(summary)


# slow (19 s): test_planar_estimates_across_materials[scattering] keeps the time estimate in the fast suite
@pytest.mark.slow
def test_planar_acquisition_and_fit_estimates_within_2x(tmp_path):
    """A first run calibrates; a run of another size is then estimated within 2x of its wall time."""

    def acquisitions(k):
        first = run_json([*PLANAR, "--grid", "3", "--photons", "2000", "--out", tmp_path / f"a{k}.zarr"])
        assert k or first["time_estimate"]["source"] == "from a probe of the walk on this sample"
        return run_json([*PLANAR, "--grid", "5", "--photons", "4000", "--out", tmp_path / f"b{k}.zarr"])

    calibrated(acquisitions)

    def fits(k):
        run_json(["fit", tmp_path / "a0.zarr", "--out", tmp_path / f"a{k}.model.zip"])
        fit = run_json(["fit", tmp_path / "b0.zarr", "--out", tmp_path / f"b{k}.model.zip"])
        assert fit["time_estimate"]["source"].startswith("calibrated on this machine")
        return fit

    calibrated(fits)

    def evaluations(k):
        run_json(
            ["evaluate", tmp_path / "a0.model.zip", tmp_path / "a0.zarr", "--report", tmp_path / f"r{k}"]
        )
        return run_json(
            ["evaluate", tmp_path / "b0.model.zip", tmp_path / "b0.zarr", "--report", tmp_path / f"s{k}"]
        )

    calibrated(evaluations)
    cache = json.loads(resources.timing_file().read_text())
    (runs,) = [entry[resources.RUNS_KEY] for entry in cache.values()]
    assert len(runs["acquire planar"]) >= 2 and len(runs["fit auto"]) >= 2 and len(runs["evaluate"]) >= 2


@pytest.mark.parametrize(
    "order",
    [("skimmilk", "marble"), pytest.param(("skimmilk", "marble", "ketchup"), marks=pytest.mark.slow)],
    ids=["scattering", "with-absorbing"],
)
def test_planar_estimates_across_materials(tmp_path, monkeypatch, order):
    """The photon steps are counted by a probe of the walk on the sample itself, so materials of very
    different scattering (skim milk, marble: 30 and 65 steps a photon and channel here; ketchup: 1.5)
    are each estimated within 2x, calibrated on another material or on none (with ketchup: 24 s, slow)."""
    slab = ["--size", "20", "20", "8", "--voxel", "0.5", "--grid", "3", "--photons", "20000"]

    def acquisitions(k):
        worst = None
        for n, names in enumerate((order, order[::-1])):  # each first (the probe alone) and calibrated
            monkeypatch.setenv("TRANSLUCENCY_CACHE", str(tmp_path / f"cache{k}{n}"))
            for name in names:
                args = ["acquire", "planar", "--material", f"homogeneous:{name}", *slab]
                summary = run_json([*args, "--out", tmp_path / f"{name}{k}{n}.zarr"])
                print(name, summary["time_estimate"], "actual", summary["seconds"])
                ratio = summary["seconds"] / summary["time_estimate"]["seconds"]
                if worst is None or abs(np.log(ratio)) > abs(np.log(worst[0])):
                    worst = (ratio, summary)
        return worst[1]

    calibrated(acquisitions)


def test_estimate_is_printed_before_work(tmp_path):
    res = runner.invoke(app, [*PLANAR, "--grid", "2", "--photons", "200", "--out", str(tmp_path / "a.zarr")])
    assert res.exit_code == 0, res.output
    text = " ".join(res.output.split())
    assert "time about" in text and "probe of the walk on this sample" in text


def test_calibration_uses_the_median_of_recent_runs(tmp_path):
    units = {"point_pixels": 1e6}
    raw = resources.estimate_time("fit iso", units).seconds  # from the probe
    assert raw > 0 and resources.timing_file().exists()
    base = resources._raw_seconds("fit iso", units)
    for factor in (3.0, 100.0, 3.0, 3.0, 2.0, 4.0):  # one outlier among recent runs
        resources.record_time("fit iso", units, factor * base)
    est = resources.estimate_time("fit iso", units)
    assert est.seconds == pytest.approx(3.0 * base) and "5 earlier runs" in est.source
    resources.timing_file().write_text("{not json")  # a damaged cache is recalibrated, never an error
    assert resources.estimate_time("fit iso", units).source.startswith("from a probe")


@pytest.mark.slow
def test_mesh_acquisition_fit_and_render_estimates_within_2x(tmp_path):
    for sub, name in ((2, "s2.ply"), (3, "s3.ply")):
        trimesh.creation.icosphere(sub, radius=8.0).export(tmp_path / name)
    mesh = ["acquire", "mesh", "--voxel", "1", "--material", "homogeneous:marble", "--index-matched"]

    def acquisitions(k):
        run_json([*mesh, "--mesh", tmp_path / "s2.ply", "--points", "8", "--photons", "2000", "--out",
                  tmp_path / f"a{k}.zarr"])  # fmt: skip
        return run_json([*mesh, "--mesh", tmp_path / "s3.ply", "--points", "16", "--photons", "4000",
                         "--out", tmp_path / f"b{k}.zarr"])  # fmt: skip

    def fits(k):
        run_json(["fit", tmp_path / "a0.zarr", "--out", tmp_path / f"a{k}.model.zip"])
        return run_json(["fit", tmp_path / "b0.zarr", "--out", tmp_path / f"b{k}.model.zip"])

    def renders(k):
        run_json(
            ["render", tmp_path / "a0.model.zip", "--out", tmp_path / f"r{k}", "--resolution", "64", "48"]
        )
        return run_json(
            ["render", tmp_path / "b0.model.zip", "--out", tmp_path / f"s{k}", "--resolution", "160", "120"]
        )

    ratios = [calibrated(acquisitions), calibrated(fits), calibrated(renders)]
    assert np.all(np.isfinite(ratios))
