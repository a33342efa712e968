"""The medium estimated from a scan alone (src/translucency/medium): the half-space match against the shipped
table, the estimate of a homogeneous ball against the material it was filled with, that it never reads the
data set's record of the filling, the model file's ``measured/medium``, the virtual scan's energy against an
independent acquisition, and ``translucency info``'s statement of the estimate.

One small acquisition serves most tests (:func:`potato_ball`): an icosphere of radius 10 mm (642 vertices)
filled with Jensen's potato (g = 0), 16 incident points, 2000 photons per point and channel, index-matched.
"""

from __future__ import annotations

import json
import re
import shutil
import zipfile
from pathlib import Path

import numpy as np
import pytest
import trimesh
from json_schemas import check, schema_of
from typer.testing import CliRunner

from translucency import TranslucencyError, load_model, save_model
from translucency.acquire.mesh import acquire_mesh, object_volume
from translucency.cli.app import app
from translucency.fit.mesh import fit_mesh  # (before medium: fit.mesh and medium.estimate import each other)
from translucency.geometry import vertex_areas
from translucency.io.mesh_dataset import HEADER_KEY, open_mesh_dataset
from translucency.medium import estimate_medium, medium_of
from translucency.medium.estimate import ASSUMED, RINGS, SIGMA_T_GRID, _match, _profile_grid
from translucency.medium.scan import virtual_scan
from translucency.model.half_space import half_space_R_d
from translucency.model.materials import material
from translucency.workflow.inspecting import MEDIUM_ASSUMED, describe

#: (σ_t mm⁻¹, albedo) of the half-spaces matched: on and between the table's albedos, across its range
HALF_SPACES = [
    (0.3, 0.6),
    (1.3, 0.8),
    (2.0, 0.9),
    (1.0, 0.95),
    (3.0, 0.97),
    (0.5, 0.99),
    (0.7, 0.995),
    (2.6, 0.998),
]
#: the ball's filling (a material of translucency.model.materials)
FILLING = "potato"


def _within_grid(grid, sigma_t, albedo, got_t, got_albedo, steps=1.5):
    """Whether (σ_t, α) found lie within ``steps`` of the searched grid's spacing of the truth: σ_t's
    log-spacing, and the albedo grid's spacing in log(1 − α) around the truth (the wider of its two
    neighbouring steps)."""
    step_t = np.log(SIGMA_T_GRID[1] / SIGMA_T_GRID[0])
    u = np.sort(np.log1p(-grid[0]))
    k = int(np.clip(np.searchsorted(u, np.log1p(-albedo)), 1, len(u) - 1))
    step_a = max(u[k] - u[k - 1], u[min(k + 1, len(u) - 1)] - u[k])
    off_t = abs(np.log(got_t / sigma_t)) / step_t
    off_a = abs(np.log((1 - got_albedo) / (1 - albedo))) / step_a
    return off_t <= steps and off_a <= steps, (round(off_t, 2), round(off_a, 2))


def test_half_space_match_recovers_the_table_from_its_rings():
    """The half-space match alone, on rings whose energies are the shipped table's profile integrated over
    each ring (2π r R_d(r) by quadrature, not the grid's values at the rings' centres), finds σ_t and α
    within 1.5 steps of its grid (σ_t 4.2 %, 1 − α 3.6–11 %).  Measured: σ_t within 3.3 %, 1 − α within
    one albedo step (the profile is matched at the rings' geometric centres, not averaged over them)."""
    edges = np.geomspace(0.3, 16.0, RINGS + 1)
    grid = _profile_grid(np.sqrt(edges[:-1] * edges[1:]))  # at the rings' geometric centres
    area = np.pi * np.diff(edges**2)
    for sigma_t, albedo in HALF_SPACES:
        energy = np.empty(RINGS)
        for b in range(RINGS):
            r = np.geomspace(edges[b], edges[b + 1], 2001)
            energy[b] = np.trapezoid(2 * np.pi * r * half_space_R_d(r, sigma_t, albedo), r)
        a, s, residual = _match(grid, area, energy)
        ok, off = _within_grid(grid, sigma_t, albedo, SIGMA_T_GRID[s], grid[0][a])
        assert ok, (sigma_t, albedo, "found", SIGMA_T_GRID[s], grid[0][a], "grid steps off", off)
        assert residual < 0.05  # one half-space fits the rings of one half-space


def _plate(radius: float, pitch: float) -> trimesh.Trimesh:
    """A flat square of side 2 ``radius`` mm triangulated on a ``pitch`` mm grid, its normals +z."""
    n = int(round(2 * radius / pitch))
    xs = np.linspace(-radius, radius, n + 1)
    X, Y = np.meshgrid(xs, xs, indexing="ij")
    v = np.stack([X.ravel(), Y.ravel(), np.zeros(X.size)], axis=1)
    idx = np.arange(len(v)).reshape(n + 1, n + 1)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    return trimesh.Trimesh(v, np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)]), process=False)


class _Scan:
    """The part of a mesh data set the estimate reads: its group's ``incident`` and ``R_d``, its mesh."""

    def __init__(self, mesh, incident, R_d):
        self._mesh, self.group = mesh, {"incident": np.asarray(incident), "R_d": R_d}

    def mesh(self):
        return self._mesh


@pytest.mark.xfail(
    strict=True,
    reason="rounds=0 matches each ring's vertex-sampled mean with the profile at one radius per ring "
    "(the area-weighted geometric mean of its vertices' distances); on a plate of 0.5 mm pitch the inner "
    "rings hold a few vertices over a steep profile, and the match misses the table's own half-space by "
    "more than the grid's steps.  The virtual-scan rounds absorb it on a real object.",
)
def test_half_space_match_recovers_a_flat_plates_half_space():
    """The estimate with ``rounds=0`` on a flat plate (48 × 48 mm, 0.5 mm pitch) whose R_d at each vertex is
    the shipped table's profile at its distance from the beam: the half-space it was made from, within 1.5
    steps of the grid."""
    plate = _plate(24.0, 0.5)
    v = np.asarray(plate.vertices)
    centre = int(np.argmin(np.linalg.norm(v, axis=1)))
    r = np.linalg.norm(v - v[centre], axis=1)
    R = np.stack([np.repeat(half_space_R_d(r, t, a)[:, None], 3, axis=1) for t, a in HALF_SPACES])
    medium = estimate_medium(_Scan(plate, [centre] * len(HALF_SPACES), R), rounds=0)
    grid = _profile_grid(np.geomspace(1.0, 16.0, RINGS))  # (only its albedos are read)
    missed = []
    for k, (sigma_t, albedo) in enumerate(HALF_SPACES):
        ok, off = _within_grid(grid, sigma_t, albedo, medium.sigma_t[k, 0], medium.albedo[k, 0])
        if not ok:
            missed.append((sigma_t, albedo, off))
    assert not missed, missed


@pytest.fixture(scope="module")
def potato_ball(tmp_path_factory):
    """(ball, filling, data set path): the small acquisition of the module notes (about 5 s)."""
    ball = trimesh.creation.icosphere(3, radius=10.0)
    filling = object_volume(f"homogeneous:{FILLING}", ball, 1.0)
    path = acquire_mesh(
        ball, filling, tmp_path_factory.mktemp("medium") / "potato.zarr", n_points=16, photons=2000, seed=2,
        chunk_points=16, index_matched=True,
    )  # fmt: skip
    return ball, filling, path


@pytest.fixture(scope="module")
def estimates(potato_ball):
    """The estimate with its default rounds and the half-space match alone (rounds=0)."""
    ds = open_mesh_dataset(potato_ball[2])
    return {"default": estimate_medium(ds), 0: estimate_medium(ds, rounds=0)}


def test_a_homogeneous_ball_is_estimated_as_its_material(estimates):
    """The estimate of the potato ball, with its default rounds: the median over the 16 points of σ_s (the
    similar medium's, g = 0) within 15 % of the truth's σ_s', and of σ_a within per-channel bounds set from
    what this acquisition and 11 others alike gave (seeds 2 and 10–20; this one is seed 2):

    =======  =========  ================  ===================  =========================
    channel  truth σ_a  median σ_a/truth  median σ_s/σ_s' − 1  bound on median σ_a/truth
    =======  =========  ================  ===================  =========================
    R        0.0024     0.37 – 0.69       −5 % … −1 %          0.3 – 1.15
    G        0.0090     0.70 – 0.85       −7 % … +3 %          0.6 – 1.15
    B        0.12       0.89 – 0.98       −11 % … +1 %         0.85 – 1.15
    =======  =========  ================  ===================  =========================

    Weak absorption is underestimated, the red's most (a known limit of the estimate).  More rounds move
    σ_a toward the truth in every channel (rounds=0: medians about 0.3, 0.09 and 0.5 of the truth).
    Each point's own σ_s lies within a factor 3 of σ_s' (measured 0.40 – 1.52 over the 12; rounds=0 has
    points at 6×)."""
    truth = material(FILLING)
    s_true, a_true = np.asarray(truth.sigma_s_prime), np.asarray(truth.sigma_a)
    medium = estimates["default"]
    assert medium.sigma_s.shape == (16, 3) and medium.g == 0.0
    s_ratio = np.median(medium.sigma_s, axis=0) / s_true
    a_ratio = np.median(medium.sigma_a, axis=0) / a_true
    np.testing.assert_array_less(np.abs(s_ratio - 1), 0.15)
    lo, hi = np.array([0.3, 0.6, 0.85]), np.array([1.15, 1.15, 1.15])
    assert ((a_ratio >= lo) & (a_ratio <= hi)).all(), a_ratio
    plain = np.median(estimates[0].sigma_a, axis=0) / a_true
    np.testing.assert_array_less(np.abs(np.log(a_ratio)), np.abs(np.log(plain)))
    # every point's own estimate: a medium of the truth's order (no point lost to a corner of the grid)
    point_ratio = medium.sigma_s / s_true
    assert point_ratio.min() > 1 / 3 and point_ratio.max() < 3.0, point_ratio
    assert (medium.sigma_a > 0).all()


def _scrubbed_copy(src: Path, dst: Path) -> dict:
    """A copy of a mesh data set without its record of the filling (the header's ``sample``, ``g``,
    ``filling`` and the request's ``volume`` and ``volume_grid``), as a lab's object has none; its header."""
    shutil.copytree(src, dst)
    meta_path = dst / "zarr.json"
    meta = json.loads(meta_path.read_text())
    header = meta["attributes"][HEADER_KEY]
    for key in ("sample", "g", "filling"):
        header.pop(key, None)
    for key in ("volume", "volume_grid"):
        header["request"].pop(key, None)
    meta_path.write_text(json.dumps(meta))
    return open_mesh_dataset(dst).header


FIT = dict(model="iso", n_terms=2, colour="per-channel", max_rounds=2)


@pytest.fixture(scope="module")
def fitted(potato_ball, tmp_path_factory):
    """The ball's fit (with its estimate of the medium) and its model file, saved without meta."""
    result = fit_mesh(potato_ball[2], **FIT)
    path = save_model(result.model, tmp_path_factory.mktemp("fitted") / "potato.model.zip")
    return result.model, path


def test_the_estimate_never_reads_the_record_of_the_filling(potato_ball, fitted, tmp_path):
    """A copy of the data set without its record of the filling, fitted alike: the model file holds the same
    ``measured/medium`` to the byte, and — the paper's model not reading the record either — every entry of
    the file is the same bytes (only the zip's time stamps and the order of its entries differ: Zarr's
    ZipStore writes the chunks as they come, each stamped with the time it was written).  The fit does
    read the header's ``g`` (and ``eta``) for the baselines (``fit/mesh.py`` FitContext: PBD's g, the
    dipoles' η); neither the estimate nor the paper's model fitted here reads them."""
    _, original = fitted
    header = _scrubbed_copy(Path(potato_ball[2]), tmp_path / "lab.zarr")
    assert not {"sample", "g", "filling"} & header.keys() and "volume" not in header["request"]
    scrubbed = save_model(fit_mesh(tmp_path / "lab.zarr", **FIT).model, tmp_path / "lab.model.zip")
    a, b = load_model(original).measured["medium"], load_model(scrubbed).measured["medium"]
    assert a.shape == (16, 2, 3) and a.tobytes() == b.tobytes()
    with zipfile.ZipFile(original) as za, zipfile.ZipFile(scrubbed) as zb:
        assert sorted(za.namelist()) == sorted(zb.namelist())
        different = [n for n in za.namelist() if za.read(n) != zb.read(n)]
    assert different == []


def test_model_file_keeps_the_medium_and_refuses_a_wrong_one(fitted, tmp_path):
    """``measured/medium`` reads back as written (float32) and as the fit's :class:`Medium`; a wrong shape or
    a negative coefficient is refused in one line before anything is written."""
    model, path = fitted
    stored = model.measured["medium"]
    back = load_model(path)
    np.testing.assert_array_equal(back.measured["medium"], stored.astype(np.float32))
    medium = medium_of(back)
    np.testing.assert_array_equal(medium.sigma_s, stored[:, 0].astype(np.float32))
    np.testing.assert_array_equal(medium.sigma_a, stored[:, 1].astype(np.float32))
    np.testing.assert_allclose(medium.x, back.x_i)
    bad = {
        "wrong shape": (stored[:, 0], r"measured/medium: expected .* got \(16, 3\)"),
        "negative": (
            stored * np.where(np.arange(3) == 1, -1.0, 1.0),
            "measured/medium: values must be finite",
        ),
    }
    try:
        for name, (value, message) in bad.items():
            model.measured["medium"] = value
            with pytest.raises(TranslucencyError, match=message) as exc:
                save_model(model, tmp_path / f"{name}.model.zip")
            assert "\n" not in str(exc.value)
            assert not (tmp_path / f"{name}.model.zip").exists()
    finally:
        model.measured["medium"] = stored


def test_virtual_scan_conserves_energy_as_an_acquisition_does(potato_ball):
    """The virtual scan of the ball's own filling at the acquisition's incident points: each point's total
    diffuse reflectance Σ_o A_o R_d is a whole number of photons over N (every exit shared out whole, none
    counted twice) and ≤ 1; and it matches the acquisition's (another seed) within photon noise: per point
    and channel |z| < 4, the 48 z² averaging below 1.8 (measured: 0.93, largest |z| 2.0)."""
    ball, filling, path = potato_ball
    ds = open_mesh_dataset(path)
    incident = np.asarray(ds["incident"])
    photons = 2000
    R = virtual_scan(ball, filling, incident, photons, seed=5)
    total = np.einsum("pvc,v->pc", R, vertex_areas(ball))
    np.testing.assert_allclose(total * photons, np.round(total * photons), atol=1e-6)
    assert (total <= 1.0).all() and (total > 0.2).all()
    measured = np.einsum(
        "pvc,v->pc", np.asarray(ds["R_d"], np.float64), np.asarray(ds["vertex_area"], np.float64)
    )
    p = 0.5 * (total + measured)
    z = (total - measured) / np.sqrt(2 * p * (1 - p) / photons)
    assert np.abs(z).max() < 4 and np.mean(z**2) < 1.8, z.round(2)


def test_info_states_the_estimate(fitted, tmp_path):
    """``translucency info MODEL``: the estimate's per-channel min / median / max of σ_s, σ_a and the albedo
    and what it assumes, in the table and in the JSON (its documented schema); a model without an estimate
    says nothing of a medium."""
    model, path = fitted
    record = describe(path)
    want = medium_of(load_model(path)).summary()
    got = record["medium"]
    for key in ("sigma_s", "sigma_a", "albedo"):
        np.testing.assert_allclose(got[key], want[key])
        assert np.array(got[key]).shape == (3, 3)
    assert got["assumed"] == MEDIUM_ASSUMED == ASSUMED == "g = 0 assumed (similar medium), index-matched"
    assert got["g"] == 0.0 and got["index_matched"] is True and got["points"] == 16
    runner = CliRunner()
    res = runner.invoke(app, ["info", str(path), "--json"])
    assert res.exit_code == 0, res.output
    out = json.loads(res.stdout)
    assert check(out, schema_of(out)) == []
    assert out["medium"]["sigma_a"] == want["sigma_a"]
    res = runner.invoke(app, ["info", str(path)], env={"COLUMNS": "300"})
    assert res.exit_code == 0, res.output
    # the table's cells may wrap (the console's width is the first test's): its words, borders and breaks out
    words = " ".join(re.sub(r"[│┃┆┌┐└┘├┤┬┴┼─]", " ", res.output).split())
    assert MEDIUM_ASSUMED in words and "medium σ_s" in words and "medium σ_a" in words
    assert f"{want['sigma_a'][2][1]:.4g}" in words  # the blue channel's median σ_a
    stored = model.measured.pop("medium")
    try:
        plain = save_model(model, tmp_path / "plain.model.zip")
    finally:
        model.measured["medium"] = stored
    out = json.loads(runner.invoke(app, ["info", str(plain), "--json"]).stdout)
    assert "medium" not in out and "medium" not in out["measured"] and check(out, schema_of(out)) == []
    text = runner.invoke(app, ["info", str(plain)], env={"COLUMNS": "300"}).output
    assert "similar medium" not in text and "medium σ" not in text


def test_info_on_a_model_with_a_medium_loads_no_engine(fitted):
    """Stating the estimate loads what ``info`` may load (tests/test_startup.py): no Mitsuba, Dr.Jit, Dask."""
    from test_startup import _RUN_CLI, NOT_FOR_INFO, _loaded

    out = _loaded(_RUN_CLI.format(args=["info", str(fitted[1]), "--json"]), NOT_FOR_INFO)
    assert out["code"] == 0 and out["loaded"] == []
