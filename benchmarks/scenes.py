"""Fitted objects in users' scenes against the volpath reference of the same scene (issue 25's three
scenes), with the time of a relight and the speed against volpath at equal error.

Each case writes a Mitsuba XML scene (the fitted object's mesh from ``translucency export --ply``, placed by
``to_world``), renders it with the fitted model (:class:`translucency.scene.FittedScene`), path-traces the
same scene with the object's volume in place twice (``volpath``; their noise measured), and prints the
errors over the object, over the pixels the object lights and over the rest, the reference's noise, the
seconds of a relight (the two passes and a 16-spp picture, after the one-off transport; the comparison
uses a picture of ``--picture-spp``) and volpath's seconds at the error ours has:

    python benchmarks/scenes.py WORK --meshes ../shared/meshes [--case pig|cow|spot ...] [--unit MM ...]

``--unit 1000`` writes the same scenes in metres (every length / 1000, a point or spot's intensity / 10⁶)
and renders them with ``scene_unit_mm`` 1000: ours and the reference should not move.

Cases (models acquired and fitted into WORK on first use, index-matched, isotropic):

* ``pig``: the procedural pig in marble (96 points x 8,000 photons; or ``--pig-model``, e.g. the demo's
  ``results/fits/pig_iso.model.zip``) on a diffuse floor under an area light, a bar between them casting
  its shadow across the pig's back;
* ``cow``: the cow (``cow.obj`` x 8, skin, 128 x 4,000) in a Cornell box lit by its ceiling lamp;
* ``spot``: spot (``spot.obj`` x 30, skin, 128 x 4,000) under an environment map (a synthetic sky with a
  sun) on a grey floor, a diffuse sphere beside it.

Equal error: a volpath render of s samples a pixel has the error ε₁ √(S/s) against the converged mean,
ε₁ the measured error of one of the two S-sample halves; ours has e (against the reference, its noise
removed in quadrature); volpath matches it at s* = S (ε₁/e)² samples, in t_S s*/S seconds (at least one
sample a pixel).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import subprocess
import sys
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from translucency.mitsuba import mitsuba
from translucency.mitsuba.scene_frame import SceneFrame
from translucency.render.tonemap import auto_exposure, save_images, tonemap
from translucency.scene import FittedScene
from translucency.scene.compare import lit_pixels, object_pixels, scene_errors
from translucency.scene.reference import converged_scene_reference

TL = [sys.executable, "-m", "translucency"]

#: name: (mesh file or None for the pig, mm per unit, up, material, points, photons)
ACQUISITIONS = {
    "pig": (None, 1.0, "z", "marble", 96, 8000),
    "cow": ("cow.obj", 8.0, "z", "skin", 128, 4000),
    "spot": ("spot.obj", 30.0, "y", "skin", 128, 4000),
}

SENSOR = """<sensor type="perspective">
    <float name="fov" value="{fov}"/>
    <transform name="to_world"><lookat origin="{origin}" target="{target}" up="0, 0, 1"/></transform>
    <film type="hdrfilm"><integer name="width" value="{w}"/><integer name="height" value="{h}"/>
      <rfilter type="box"/></film>
  </sensor>"""


def _model(case: str, work: Path, meshes: Path, given: Path | None) -> Path:
    if given is not None:
        return given
    model = work / f"{case}.model.zip"
    if model.exists():
        return model
    mesh, scale, up, material, points, photons = ACQUISITIONS[case]
    data = work / f"{case}.zarr"
    args = ["acquire", "mesh", "--out", str(data), "--material", material, "--points", str(points)]
    args += ["--photons", str(photons), "--index-matched", "--seed", "3", "--voxel", "1", "--quiet"]
    if mesh is not None:
        args += ["--mesh", str(meshes / mesh), "--scale", str(scale), "--up", up]
    subprocess.run(TL + args, check=True)
    subprocess.run(TL + ["fit", str(data), "--out", str(model), "--quiet"], check=True)
    return model


def _bounds(model: Path):
    from translucency.io.model_file import load_model

    v = np.asarray(load_model(model).alpha.vertices)
    return v.min(axis=0), v.max(axis=0)


def _sky(path: Path) -> None:
    """A latitude-longitude sky: a blue gradient above, a dim ground below, and a warm sun."""
    H, W = 64, 128
    theta = (np.arange(H) + 0.5) / H * np.pi  # from the map's +Y (turned to the scene's +Z below)
    phi = (np.arange(W) + 0.5) / W * 2 * np.pi
    T, P = np.meshgrid(theta, phi, indexing="ij")
    up = np.cos(T)
    sky = np.where(up[..., None] > 0, [0.25, 0.35, 0.6] * (0.4 + 0.6 * up[..., None]), [0.05, 0.05, 0.05])
    sun = np.exp(-(((T - 0.7) / 0.08) ** 2 + ((P - 1.2) / 0.08) ** 2))[..., None] * [60.0, 50.0, 35.0]
    mitsuba().Bitmap((sky + sun).astype(np.float32)).write(str(path))


def scene_xml(case: str, folder: Path, size) -> str:
    """The case's scene (the object's mesh is ``object.ply`` in ``folder``)."""
    lo, hi = _bounds(folder / "model.zip")
    centre = 0.5 * (lo + hi)
    ext = float(np.linalg.norm(hi - lo))
    w, h = size
    # the object stands on z = 0, its centre over the origin
    place = f'<translate x="{-centre[0]:.4f}" y="{-centre[1]:.4f}" z="{-lo[2] + 0.05:.4f}"/>'
    zc = hi[2] - lo[2]
    obj = (
        f'<shape type="ply" id="object"><string name="filename" value="object.ply"/>'
        f'<transform name="to_world">{place}</transform></shape>'
    )
    if case == "pig":
        sensor = SENSOR.format(
            fov=38, origin=f"{0.9 * ext}, {-1.7 * ext}, {1.0 * ext}", target=f"0, 0, {0.35 * zc}", w=w, h=h
        )
        rest = f"""
  <shape type="rectangle" id="floor"><transform name="to_world"><scale value="{2.5 * ext}"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.6, 0.6, 0.6"/></bsdf></shape>
  <shape type="cube" id="bar"><transform name="to_world">
    <scale x="{0.07 * ext}" y="{0.8 * ext}" z="{0.02 * ext}"/>
    <translate x="{0.0 * ext}" z="{1.3 * zc + 0.05 * ext}"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.2, 0.2, 0.2"/></bsdf></shape>
  <shape type="rectangle" id="lamp"><transform name="to_world"><scale value="{0.12 * ext}"/>
    <rotate x="1" angle="180"/>
    <translate x="{-0.1 * ext}" y="{-0.15 * ext}" z="{2.2 * zc + 0.4 * ext}"/></transform>
    <emitter type="area"><rgb name="radiance" value="40, 40, 40"/></emitter></shape>"""
    elif case == "cow":
        s = 0.75 * ext  # the box's half side
        sensor = SENSOR.format(fov=40, origin=f"0, {-3.6 * s}, {s}", target=f"0, 0, {s}", w=w, h=h)
        walls = [
            ("floor", f'<scale value="{s}"/>', "0.7, 0.7, 0.7"),
            (
                "ceiling",
                f'<scale value="{s}"/><rotate x="1" angle="180"/><translate z="{2 * s}"/>',
                "0.7, 0.7, 0.7",
            ),
            (
                "back",
                f'<scale value="{s}"/><rotate x="1" angle="90"/><translate y="{s}" z="{s}"/>',
                "0.7, 0.7, 0.7",
            ),
            (
                "left",
                f'<scale value="{s}"/><rotate y="1" angle="90"/><translate x="{-s}" z="{s}"/>',
                "0.63, 0.065, 0.05",
            ),
            (
                "right",
                f'<scale value="{s}"/><rotate y="1" angle="-90"/><translate x="{s}" z="{s}"/>',
                "0.14, 0.45, 0.09",
            ),
        ]
        rest = "".join(
            f'\n  <shape type="rectangle" id="{name}"><transform name="to_world">{tf}</transform>'
            f'<bsdf type="diffuse"><rgb name="reflectance" value="{rgb}"/></bsdf></shape>'
            for name, tf, rgb in walls
        )
        rest += f"""
  <shape type="rectangle" id="lamp"><transform name="to_world"><scale value="{0.25 * s}"/>
    <rotate x="1" angle="180"/><translate z="{2 * s - 0.01 * s}"/></transform>
    <emitter type="area"><rgb name="radiance" value="30, 27, 22"/></emitter></shape>"""
    else:
        _sky(folder / "sky.exr")
        sensor = SENSOR.format(
            fov=42,
            origin=f"{0.3 * ext}, {-1.9 * ext}, {0.7 * ext}",
            target=f"{0.15 * ext}, 0, {0.35 * zc}",
            w=w,
            h=h,
        )
        r = 0.18 * ext
        rest = f"""
  <emitter type="envmap"><string name="filename" value="sky.exr"/>
    <transform name="to_world"><rotate x="1" angle="90"/></transform></emitter>
  <shape type="rectangle" id="floor"><transform name="to_world"><scale value="{3 * ext}"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.4, 0.4, 0.4"/></bsdf></shape>
  <shape type="sphere" id="ball"><point name="center" x="{0.55 * ext}" y="{0.1 * ext}" z="{r + 0.01}"/>
    <float name="radius" value="{r}"/>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.5, 0.45, 0.4"/></bsdf></shape>"""
    return f'<scene version="3.0.0">\n  {sensor}\n  {obj}{rest}\n</scene>\n'


def scene_folder(case: str, folder: Path, model: Path, size, unit_mm: float = 1.0) -> Path:
    """``folder`` with the case's scene: the model (linked), its mesh (``export --ply``) and
    ``scene.xml`` at ``size``, written with ``unit_mm`` millimetres a unit (every length / unit_mm, a
    point or spot's intensity / unit_mm²: the same picture); returns the scene file."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "model.zip").unlink(missing_ok=True)
    (folder / "model.zip").symlink_to(model.resolve())
    subprocess.run(
        TL + ["export", str(model), "--ply", str(folder / "object.ply"), "--overwrite", "--quiet"], check=True
    )
    text = scene_xml(case, folder, size)
    if unit_mm != 1.0:  # the millimetre scene carried into the unit (the inverse of the reference's frame)
        root = SceneFrame(1.0 / unit_mm, (0.0, 0.0, 0.0)).xml(ET.fromstring(text))
        text = ET.tostring(root, encoding="unicode")
    (folder / "scene.xml").write_text(text)
    return folder / "scene.xml"


def run_case(
    case: str,
    work: Path,
    meshes: Path,
    size,
    spp_ref: int,
    samples: int,
    pig_model,
    picture_spp: int = 64,
    unit_mm: float = 1.0,
) -> dict:
    folder = work / (case if unit_mm == 1.0 else f"{case}-unit{unit_mm:g}")
    model = _model(case, work, meshes, pig_model if case == "pig" else None)
    scene_folder(case, folder, model, size, unit_mm)
    t = time.perf_counter()
    fs = FittedScene(folder / "scene.xml", {"object": model}, samples=samples, scene_unit_mm=unit_mm)
    fs.prepare()
    t_prepare = time.perf_counter() - t
    fs.light(seed=0)  # the first pass compiles the kernels
    fs.render(spp=16)
    t = time.perf_counter()
    fs.light(seed=1)
    t_light = time.perf_counter() - t
    t = time.perf_counter()
    fs.render(spp=16, seed=1)
    t_draw = time.perf_counter() - t
    ours = fs.render(spp=picture_spp, seed=1)  # compared at more samples: our picture's noise apart
    dark = fs.render(spp=picture_spp, seed=1, glowing=False)
    objects = object_pixels(fs)
    lit = lit_pixels(ours, dark, objects)
    reference, ref = _reference(fs, folder, spp_ref, objects)
    noise, single, (t_a, t_b) = ref["noise"], ref["single"], ref["seconds"]
    errors = scene_errors(reference, ours, objects, lit)
    errors.pop("flip_map")
    # volpath at equal error (module docstring)
    e = errors["object"]["rel_rmse"]
    ours_true = float(np.sqrt(max(e**2 - noise**2, 1e-12)))
    s_star = max(spp_ref * (single / ours_true) ** 2, 1.0)
    t_volpath = 0.5 * (t_a + t_b) * s_star / spp_ref
    scale = auto_exposure(reference, objects)
    save_images(ours, folder / "ours", scale)
    save_images(reference, folder / "reference_tonemapped", scale)
    _figure(tonemap(reference, scale), tonemap(ours, scale), errors, noise, folder / f"{case}.png", case)
    row = {
        "case": case,
        "unit_mm": unit_mm,
        "vertices": fs.vertices,
        "size": list(size),
        "errors": errors,
        "reference_noise": noise,
        "reference_spp": spp_ref,
        "picture_spp": picture_spp,
        "samples": samples,
        "prepare_s": t_prepare,
        "relight_s": t_light,
        "draw_s": t_draw,
        "reference_s": t_a + t_b,
        "volpath_equal_error_spp": s_star,
        "speedup_equal_error": t_volpath / (t_light + t_draw),
    }
    (folder / f"{case}.json").write_text(json.dumps(row, indent=2))
    return row


def _reference(fs, folder: Path, spp_ref: int, objects):
    """The mean of two volpath renders and its numbers, kept in ``folder`` (``reference.exr``,
    ``reference.json``) for the same scene file and samples: a rerun of ours does not render it again."""
    mi = mitsuba()
    key = {"scene_sha256": hashlib.sha256((folder / "scene.xml").read_bytes()).hexdigest(), "spp": spp_ref}
    meta = folder / "reference.json"
    if meta.is_file() and (folder / "reference.exr").is_file():
        kept = json.loads(meta.read_text())
        if all(kept.get(k) == v for k, v in key.items()):
            return np.asarray(mi.Bitmap(str(folder / "reference.exr")), dtype=np.float64)[..., :3], kept
    mean, ref = converged_scene_reference(fs, objects, spp=spp_ref)
    info = {**key, "noise": ref["noise"], "single": ref["single"], "seconds": ref["seconds_each"]}
    mi.Bitmap(mean.astype(np.float32)).write(str(folder / "reference.exr"))
    meta.write_text(json.dumps(info, indent=2))
    return mean, info


def _figure(ref, ours, errors, noise, path, case):
    from translucency._plotting import pyplot

    plt = pyplot()
    fig, ax = plt.subplots(1, 3, figsize=(12, 3.4))
    diff = np.abs(ours - ref).mean(axis=2)
    ax[0].imshow(ref)
    ax[0].set_title(f"{case}: volpath of the volume in the scene (noise {noise:.3f})", fontsize=8)
    ax[1].imshow(ours)
    o, lit = errors["object"], errors["lit"]
    ax[1].set_title(
        f"ours: object rel. RMSE {o['rel_rmse']:.3f}, FLIP {o['flip']:.3f}; lit by it "
        + (f"{lit['rel_rmse']:.3f}" if lit.get("pixels") else "-"),
        fontsize=8,
    )
    im = ax[2].imshow(diff, cmap="magma", vmin=0, vmax=max(float(np.quantile(diff, 0.99)), 1e-6))
    ax[2].set_title("|ours - reference| (tone-mapped)", fontsize=8)
    fig.colorbar(im, ax=ax[2], shrink=0.8)
    for a in ax:
        a.axis("off")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("work", type=Path)
    ap.add_argument("--meshes", type=Path, default=Path("../shared/meshes"))
    ap.add_argument("--case", action="append", choices=sorted(ACQUISITIONS))
    ap.add_argument("--size", type=int, nargs=2, default=(160, 120))
    ap.add_argument("--spp-reference", type=int, default=128)
    ap.add_argument("--samples", type=int, default=32)
    ap.add_argument("--picture-spp", type=int, default=64, help="our picture's samples for the comparison")
    ap.add_argument("--pig-model", type=Path, default=None)
    ap.add_argument(
        "--unit", type=float, action="append", help="mm a scene unit (repeat: 1000 metres, 10 cm, 25.4 in)"
    )
    args = ap.parse_args()
    args.work.mkdir(parents=True, exist_ok=True)
    for case, unit in ((c, u) for c in args.case or sorted(ACQUISITIONS) for u in args.unit or [1.0]):
        row = run_case(
            case,
            args.work,
            args.meshes,
            tuple(args.size),
            args.spp_reference,
            args.samples,
            args.pig_model,
            args.picture_spp,
            unit,
        )
        o, lit, rest = row["errors"]["object"], row["errors"]["lit"], row["errors"]["rest"]
        print(
            f"{case} (unit {unit:g} mm): object rel. RMSE {o['rel_rmse']:.3f} FLIP {o['flip']:.3f} "
            f"brightness {o['brightness']:.3f} | lit by it {lit.get('rel_rmse', float('nan')):.3f} "
            f"({lit['pixels']} px) | rest {rest['rel_rmse']:.3f} | "
            f"reference noise {row['reference_noise']:.3f} at 2 x {row['reference_spp']} spp | relight "
            f"{row['relight_s']:.2f} s + picture {row['draw_s']:.2f} s | "
            f"reference {row['reference_s']:.0f} s | "
            f"volpath at equal error {row['volpath_equal_error_spp']:.1f} spp: "
            f"{row['speedup_equal_error']:.0f}x slower",
            flush=True,
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
