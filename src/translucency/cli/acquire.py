"""``translucency acquire planar|mesh|photographs``: measurements simulated by photon transport (virtual
DISCO: a planar sample, a 3D object) and a virtual rig's photographs for ``translucency import images``.

Each command is one call of :mod:`translucency.workflow.acquiring` (``acquire_planar``, ``acquire_mesh``,
``acquire_photographs``) and prints its summary."""

from __future__ import annotations

from pathlib import Path

import typer

from .._validate import TranslucencyError
from ..workflow import GENERATORS
from ._common import (
    PANEL_CAMERA,
    PANEL_OUTPUT,
    PANEL_RUN,
    PANEL_SAMPLE,
    PANEL_SCAN,
    boundary_eta,
    chunk_option,
    dataset_overwrite_option,
    eta_option,
    finish,
    index_matched_option,
    json_option,
    max_memory_option,
    quiet_option,
    scheduler_option,
    user_errors,
    voxel_option,
)
from ._run import RichReporter

#: the sample generators, as --help lists them (the one list make_sample refuses others with)
SAMPLES = ", ".join(GENERATORS) + " (<name>: one of `translucency materials`)"
#: what the sample's own index of refraction is (--eta's default)
OWN_ETA = "1.3 for the generated materials; a volume file's eta"

app = typer.Typer(
    help="Virtual DISCO: simulate measurements by photon transport (Mitsuba 3 / Dr.Jit).",
    no_args_is_help=True,
)


def _one_sample(material: str | None, volume: Path | None):
    """The sample of ``--material NAME`` or ``--volume FILE.npz``: exactly one of them."""
    if (material is None) == (volume is None):
        raise TranslucencyError("give exactly one of --material NAME or --volume FILE.npz")
    return material if volume is None else volume


class PhotographsOptions:
    """The options of ``acquire photographs``."""

    out = typer.Option(..., "--out", "-o", help="Output folder: images, positions.csv, calibration.json.")
    material = typer.Option(
        None,
        "--material",
        "-m",
        help=f"Sample generator: {SAMPLES}.",
    )
    volume = typer.Option(None, "--volume", help="A user's volume (.npz, as acquire planar).")
    grid = typer.Option(
        2, "--grid", help="Incident points per axis (grid x grid).", rich_help_panel=PANEL_SCAN
    )
    span = typer.Option(
        4.0,
        "--span",
        help="Side of the incident grid, mm (centred on the sample).",
        rich_help_panel=PANEL_SCAN,
    )
    size = typer.Option(
        (12.0, 12.0, 4.0),
        "--size",
        help="Generated slab: width height thickness, mm.",
        rich_help_panel=PANEL_SAMPLE,
    )
    voxel = voxel_option(0.5)
    camera = typer.Option(
        (0.0, -8.0, 11.0),
        "--camera",
        help="Camera position relative to the sample's centre, mm.",
        rich_help_panel=PANEL_CAMERA,
    )
    fov = typer.Option(40.0, "--fov", help="Horizontal field of view, degrees.", rich_help_panel=PANEL_CAMERA)
    resolution = typer.Option(
        (64, 64), "--resolution", help="Image width and height, pixels.", rich_help_panel=PANEL_CAMERA
    )
    spp = typer.Option(
        64,
        "--spp",
        help="Samples per pixel of the path-traced photographs (Mitsuba's volpath).",
        rich_help_panel=PANEL_CAMERA,
    )
    seed = typer.Option(0, "--seed", help="Random seed of the sample, renders and sensor noise.")
    image_format = typer.Option("pfm", "--format", help="pfm or exr.", rich_help_panel=PANEL_OUTPUT)
    overwrite = typer.Option(
        False,
        "--overwrite",
        help="Replace an earlier output folder of translucency (never anything else).",
        rich_help_panel=PANEL_RUN,
    )
    max_memory = max_memory_option()
    quiet = quiet_option()
    as_json = json_option()


@app.command("photographs")
@user_errors
def acquire_photographs_cmd(
    out: Path = PhotographsOptions.out,
    material: str = PhotographsOptions.material,
    volume: Path = PhotographsOptions.volume,
    grid: int = PhotographsOptions.grid,
    span: float = PhotographsOptions.span,
    size: tuple[float, float, float] = PhotographsOptions.size,
    voxel: float = PhotographsOptions.voxel,
    camera: tuple[float, float, float] = PhotographsOptions.camera,
    fov: float = PhotographsOptions.fov,
    resolution: tuple[int, int] = PhotographsOptions.resolution,
    spp: int = PhotographsOptions.spp,
    seed: int = PhotographsOptions.seed,
    image_format: str = PhotographsOptions.image_format,
    overwrite: bool = PhotographsOptions.overwrite,
    max_memory: str = PhotographsOptions.max_memory,
    quiet: bool = PhotographsOptions.quiet,
    as_json: bool = PhotographsOptions.as_json,
):
    """Photograph a virtual sample with Mitsuba 3 (narrow beam per point, oblique perspective camera,
    sensor noise, dark offset, vignetting, saturation): a lab's hand-over for `translucency import images`."""
    from ..workflow.photographing import acquire_photographs  # heavy: Mitsuba loads only when it runs

    shots = acquire_photographs(
        _one_sample(material, volume),
        out,
        grid=grid,
        span=span,
        size=size,
        voxel_mm=voxel,
        camera=camera,
        fov=fov,
        resolution=resolution,
        spp=spp,
        seed=seed,
        image_format=image_format,
        overwrite=overwrite,
        max_memory=max_memory,
        reporter=RichReporter(quiet),
    )
    s = shots.summary
    line = f"photographs: {out} (markers fit to {s['rms_px']:.3f} px rms; true homography {s['homography']})"
    finish(as_json, quiet, s, [line])


class AngleOptions:
    """The angle axes' options, shared by ``acquire planar`` and ``acquire mesh`` (translucency.angles)."""

    incidence = typer.Option(
        [],
        "--incidence",
        help="Oblique beams besides the normal one: also beams arriving at this polar angle (degrees from "
        "the normal), at --azimuths azimuths about it (a mesh point's tangent frame; a slab's x, y), stored "
        "beside the normal beam's R_d; repeat for more angles. Cost: photons x directions.",
        rich_help_panel=PANEL_SCAN,
    )
    azimuths = typer.Option(
        4, "--azimuths", help="Azimuths per --incidence angle.", rich_help_panel=PANEL_SCAN
    )
    exit_bins = typer.Option(
        0,
        "--exit-bins",
        help="Also tally each exit by direction: this many polar bins of equal projected solid angle x "
        "2 halves (away from / back toward the incident point); 0: none.",
        rich_help_panel=PANEL_SCAN,
    )


class PlanarOptions:
    """The options of ``acquire planar`` (a class of their own keeps the command short)."""

    out = typer.Option(..., "--out", "-o", help="Output data set (Zarr directory).")
    material = typer.Option(
        None,
        "--material",
        "-m",
        help=f"Sample generator: {SAMPLES}.",
    )
    volume = typer.Option(
        None, "--volume", help="A user's volume: .npz with sigma_s, sigma_a (Z,Y,X,3) in 1/mm, voxel_mm."
    )
    photons = typer.Option(20_000, "--photons", "-N", help="Photons per incident point and channel.")
    seed = typer.Option(
        0, "--seed", help="Random seed of the photons (results are deterministic for a seed)."
    )
    sample_seed = typer.Option(
        None,
        "--sample-seed",
        help="Seed of the generated sample (default: --seed). A held-out truth of the same sample: "
        "the same --sample-seed, another --seed.",
        rich_help_panel=PANEL_SAMPLE,
    )
    grid = typer.Option(
        8, "--grid", help="Incident points per axis (grid x grid).", rich_help_panel=PANEL_SCAN
    )
    span = typer.Option(
        8.0,
        "--span",
        help="Side of the incident grid, mm (centred on the sample).",
        rich_help_panel=PANEL_SCAN,
    )
    pitch = typer.Option(0.25, "--pitch", help="Pixel size, mm.", rich_help_panel=PANEL_SCAN)
    window = typer.Option(
        8.0, "--window", help="Window side around each incident point, mm.", rich_help_panel=PANEL_SCAN
    )
    size = typer.Option(
        (20.0, 20.0, 8.0),
        "--size",
        help="Generated slab: width height thickness, mm.",
        rich_help_panel=PANEL_SAMPLE,
    )
    voxel = voxel_option(0.25)
    g = typer.Option(
        0.0, "--g", help="Henyey-Greenstein anisotropy of generated samples.", rich_help_panel=PANEL_SAMPLE
    )
    tilt = typer.Option(
        0.0,
        "--tilt",
        help="Tilt the scan's one beam: every incident point lit at this angle from the normal instead of "
        "along it, degrees (the data set is of that angle alone; oblique beams besides the normal one: "
        "--incidence).",
        rich_help_panel=PANEL_SCAN,
    )
    incidence = AngleOptions.incidence
    azimuths = AngleOptions.azimuths
    exit_bins = AngleOptions.exit_bins
    eta = eta_option(OWN_ETA)
    index_matched = index_matched_option()
    chunk = chunk_option(16)
    dtype = typer.Option(
        "float32",
        "--dtype",
        help="Storage of R_d and variance: float32 or float16.",
        rich_help_panel=PANEL_OUTPUT,
    )
    overwrite = dataset_overwrite_option()
    scheduler = scheduler_option()
    max_memory = max_memory_option()
    quiet = quiet_option()
    as_json = json_option()


@app.command("planar")
@user_errors
def acquire_planar_cmd(
    out: Path = PlanarOptions.out,
    material: str = PlanarOptions.material,
    volume: Path = PlanarOptions.volume,
    photons: int = PlanarOptions.photons,
    seed: int = PlanarOptions.seed,
    sample_seed: int = PlanarOptions.sample_seed,
    grid: int = PlanarOptions.grid,
    span: float = PlanarOptions.span,
    pitch: float = PlanarOptions.pitch,
    window: float = PlanarOptions.window,
    size: tuple[float, float, float] = PlanarOptions.size,
    voxel: float = PlanarOptions.voxel,
    g: float = PlanarOptions.g,
    tilt: float = PlanarOptions.tilt,
    incidence: list[float] = PlanarOptions.incidence,
    azimuths: int = PlanarOptions.azimuths,
    exit_bins: int = PlanarOptions.exit_bins,
    eta: float = PlanarOptions.eta,
    index_matched: bool = PlanarOptions.index_matched,
    dtype: str = PlanarOptions.dtype,
    chunk: int = PlanarOptions.chunk,
    overwrite: bool = PlanarOptions.overwrite,
    scheduler: str = PlanarOptions.scheduler,
    max_memory: str = PlanarOptions.max_memory,
    quiet: bool = PlanarOptions.quiet,
    as_json: bool = PlanarOptions.as_json,
):
    """Scan a pencil beam over a planar sample and record R_d around each incident point."""
    from ..workflow.acquiring import acquire_planar  # heavy: Mitsuba, Dask and SciPy load only when it runs

    if tilt and incidence:
        raise TranslucencyError(TILT_AND_INCIDENCE)
    ds = acquire_planar(
        _one_sample(material, volume),
        out,
        grid=grid,
        span=span,
        pitch=pitch,
        window=window,
        photons=photons,
        seed=seed,
        sample_seed=sample_seed,
        size=size,
        voxel_mm=voxel,
        g=g,
        angle=tilt,
        incidence=incidence,
        azimuths=azimuths,
        exit_bins=exit_bins,
        eta=boundary_eta(eta, index_matched),
        chunk_points=chunk,
        dtype=dtype,
        overwrite=overwrite,
        scheduler=scheduler,
        max_memory=max_memory,
        reporter=RichReporter(quiet),
    )
    finish(as_json, quiet, ds.summary, [f"data set: {out}"])


#: --tilt tilts the scan's one beam; --incidence adds oblique beams beside the normal one: not both
TILT_AND_INCIDENCE = "--tilt and --incidence: oblique beams begin with the normal one; leave --tilt at 0"


class MeshOptions:
    """The options of ``acquire mesh``."""

    out = typer.Option(..., "--out", "-o", help="Output mesh data set (Zarr directory).")
    mesh = typer.Option(None, "--mesh", help="A closed mesh (OBJ/PLY/STL); default: the procedural pig.")
    scale = typer.Option(1.0, "--scale", help="Millimetres per mesh unit.", rich_help_panel=PANEL_SAMPLE)
    material = typer.Option(
        None,
        "--material",
        "-m",
        help=f"Filling (in object space): {SAMPLES}; default marble.",
    )
    volume = typer.Option(
        None,
        "--volume",
        help="A user's filling: .npz with sigma_s, sigma_a (Z,Y,X,3) in 1/mm, voxel_mm, over the mesh's "
        "bounding box (z index 0 at the top).",
    )
    up = typer.Option(
        "z", "--up", help="The mesh file's up axis (z, y or x), turned to +z.", rich_help_panel=PANEL_SAMPLE
    )
    voxel = voxel_option(0.5)
    points = typer.Option(
        64,
        "--points",
        help="Incident points (farthest-point sample of the vertices). On small objects more points with "
        "fewer photons each, for the same time, render closer (documentation: 'Light through the body').",
        rich_help_panel=PANEL_SCAN,
    )
    photons = typer.Option(20_000, "--photons", "-N", help="Photons per incident point and channel.")
    seed = PlanarOptions.seed
    sample_seed = PlanarOptions.sample_seed
    g = typer.Option(0.0, "--g", help="Henyey-Greenstein anisotropy.", rich_help_panel=PANEL_SAMPLE)
    chunk = chunk_option(8)
    eta = eta_option(OWN_ETA)
    index_matched = index_matched_option()
    reentry = typer.Option(
        True,
        "--reentry/--no-reentry",
        help="Light leaving one part through the air into another (a horn by the head) walks on there.",
        rich_help_panel=PANEL_SAMPLE,
    )
    unscattered = typer.Option(
        "apart",
        "--unscattered",
        help="Light that leaves without scattering (a beam through a thin part, seen only head-on): apart "
        "(kept out of R_d, its fraction stored) or counted (in R_d).",
        rich_help_panel=PANEL_SCAN,
    )
    incidence = AngleOptions.incidence
    azimuths = AngleOptions.azimuths
    exit_bins = AngleOptions.exit_bins
    overwrite = dataset_overwrite_option()
    scheduler = scheduler_option()
    max_memory = max_memory_option()
    quiet = quiet_option()
    as_json = json_option()


@app.command("mesh")
@user_errors
def acquire_mesh_cmd(
    out: Path = MeshOptions.out,
    mesh: Path = MeshOptions.mesh,
    scale: float = MeshOptions.scale,
    material: str = MeshOptions.material,
    volume: Path = MeshOptions.volume,
    up: str = MeshOptions.up,
    voxel: float = MeshOptions.voxel,
    points: int = MeshOptions.points,
    photons: int = MeshOptions.photons,
    seed: int = MeshOptions.seed,
    sample_seed: int = MeshOptions.sample_seed,
    g: float = MeshOptions.g,
    chunk: int = MeshOptions.chunk,
    eta: float = MeshOptions.eta,
    index_matched: bool = MeshOptions.index_matched,
    reentry: bool = MeshOptions.reentry,
    unscattered: str = MeshOptions.unscattered,
    incidence: list[float] = MeshOptions.incidence,
    azimuths: int = MeshOptions.azimuths,
    exit_bins: int = MeshOptions.exit_bins,
    overwrite: bool = MeshOptions.overwrite,
    scheduler: str = MeshOptions.scheduler,
    max_memory: str = MeshOptions.max_memory,
    quiet: bool = MeshOptions.quiet,
    as_json: bool = MeshOptions.as_json,
):
    """Pencil beams at surface points of a 3D object; exits tallied per vertex (R_d in mm^-2)."""
    from ..workflow.acquiring import acquire_mesh  # heavy: Mitsuba, Dask and trimesh load only when it runs

    if material is not None and volume is not None:
        raise TranslucencyError("give one of --material NAME or --volume FILE.npz, not both")
    ds = acquire_mesh(
        mesh,
        out,
        volume or material or "marble",
        voxel_mm=voxel,
        g=g,
        points=points,
        photons=photons,
        seed=seed,
        sample_seed=sample_seed,
        chunk_points=chunk,
        eta=boundary_eta(eta, index_matched),
        reentry=reentry,
        unscattered=unscattered,
        incidence=incidence,
        azimuths=azimuths,
        exit_bins=exit_bins,
        scale_mm=scale,
        up=up,
        overwrite=overwrite,
        scheduler=scheduler,
        max_memory=max_memory,
        reporter=RichReporter(quiet),
    )
    finish(as_json, quiet, ds.summary, [f"mesh data set: {out}"])
