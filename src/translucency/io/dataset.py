"""Planar measurement data sets (format version 1): a chunked Zarr v3 directory.

What a DISCO-style acquisition produces — for each incident point x_i, a
window of pixels around it holding R_d(x_i, x_o) per channel — in a layout
that scales out (chunks of incident points) and that any Zarr reader opens.

Layout (P incident points, windows of H × W pixels, 3 channels)::

    /                  group; attrs["translucency_dataset"] = header (below)
    x_i                (P, 2) float32   incident points, mm
    window_origin      (P, 2) float32   corner (x, y) of each window, mm; pixel [row, col]
                                        is centred at origin + pitch * (col + 1/2, row + 1/2)
    R_d                (P, H, W, 3)     diffuse reflectance, mm⁻² per unit incident power
    variance           (P, H, W, 3)     variance estimate of R_d, mm⁻⁴
    mask               (P, H, W) bool   pixel lies on the sample (valid measurement)
    specular           (P, 3) float32   Fresnel reflection at entry (fraction of the power), not in R_d
    total_diffuse      (P, 3) float32   all light leaving the top face, inside the window or not
    chunk_done         (n_chunks,) bool written last for each chunk of points: resume marker

With the angle axes (``acquire planar --incidence/--exit-bins``, header ``angles``; D directions, the
normal first, and B exit bins: :mod:`translucency.angles`)::

    R_d_oblique           (P, D-1, H, W, 3)    R_d of the oblique beams (their variance: Poisson, from
                                               the photon count, as the normal beam's)
    specular_oblique      (P, D-1, 3) float32  their Fresnel reflection at entry
    total_diffuse_oblique (P, D-1, 3) float32  all their light leaving the top face
    exit_bins             (P, D, H, W, 3, B)   the part of each R_d (normal, then oblique) that left
                                               through each exit bin

Header (JSON): ``format`` = "translucency-dataset", ``version`` = 1,
``units`` ({length: mm, R_d: mm^-2, variance: mm^-4}), ``pitch_mm``,
``window`` [H, W], ``n_points``, ``chunk_points``, ``dtype``, ``sample``
(size, voxel, g, eta, generator description), ``acquisition`` (photons per
point, seed, angle of incidence, index matching), ``software`` (versions),
and ``request``: the arguments that define the data, compared on resume.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np

from .._validate import TranslucencyError, as_float_array
from .._version import __version__
from ..angles import AngleAxes, Incidence, angle_arrays
from ._store import ChunkedStore, check_shapes, open_store
from .outputs import claim_output, reopen_or_clear

FORMAT = "translucency-dataset"
VERSION = 1
HEADER_KEY = "translucency_dataset"
_ARRAYS = ("x_i", "window_origin", "R_d", "variance", "mask", "specular", "total_diffuse", "chunk_done")
_ANGLES = ("R_d_oblique", "specular_oblique", "total_diffuse_oblique", "exit_bins")


def _planar_angle_arrays(header: dict) -> list[tuple[str, tuple]]:
    """The angle axes' arrays a planar header announces, with their shapes (none without ``angles``)."""
    P, (H, W) = header["n_points"], header["window"]
    arrays = angle_arrays(header.get("angles"), P, (H, W))
    D = Incidence.from_header((header.get("angles") or {}).get("incidence")).count
    return arrays + ([("total_diffuse_oblique", (P, D - 1, 3))] if D > 1 else [])


class PlanarDataset(AngleAxes, ChunkedStore):
    """An opened data set; arrays are read lazily from the Zarr group."""

    KIND = "planar data set"
    HEADER_KEY = HEADER_KEY
    FORMAT = FORMAT
    VERSION = VERSION
    ARRAYS = (*_ARRAYS, *_ANGLES)
    ROW = "incident point"

    @property
    def PER_POINT(self) -> tuple[str, ...]:  # noqa: N802 — the store's name for it
        angles = (name for name in _ANGLES if name in self.group)
        return ("R_d", "variance", "mask", "specular", "total_diffuse", *angles)

    @property
    def pitch(self) -> float:
        return float(self.header["pitch_mm"])

    @property
    def window(self) -> tuple[int, int]:
        return tuple(self.header["window"])

    @property
    def chunk_points(self) -> int:
        return int(self.header["chunk_points"])

    @classmethod
    def from_group(cls, path: Path, header: dict, group) -> PlanarDataset:
        units = header.get("units", {})
        if units.get("length") != "mm" or units.get("R_d") != "mm^-2":
            raise TranslucencyError(f"{path}: units {units} are not mm / mm^-2")
        P, window, k = header.get("n_points"), header.get("window"), header.get("chunk_points")
        if not (
            isinstance(P, int)
            and P >= 1
            and isinstance(k, int)
            and k >= 1
            and isinstance(window, list)
            and len(window) == 2
            and all(isinstance(v, int) and v >= 1 for v in window)
            and isinstance(header.get("pitch_mm"), (int, float))
            and np.isfinite(header["pitch_mm"])
            and header["pitch_mm"] > 0
        ):
            raise TranslucencyError(
                f"{path}: header fields n_points {P!r}, window {window!r}, chunk_points {k!r} or pitch_mm "
                f"{header.get('pitch_mm')!r} are not valid"
            )
        H, W = window
        check_shapes(
            path,
            group,
            {
                "x_i": (P, 2),
                "window_origin": (P, 2),
                "R_d": (P, H, W, 3),
                "variance": (P, H, W, 3),
                "mask": (P, H, W),
                "specular": (P, 3),
                "total_diffuse": (P, 3),
                "chunk_done": (-(-P // k),),
            },
        )
        for name, shape in _planar_angle_arrays(header):  # the angle axes the header announces
            if name not in group:
                raise TranslucencyError(f"{path}: header has angles but array {name!r} is missing")
            if tuple(group[name].shape) != shape:
                raise TranslucencyError(
                    f"{path}: array {name!r} has shape {tuple(group[name].shape)}, expected {shape}"
                )
        return cls(path, header, group)

    def _expects_files(self, name: str) -> bool:
        # chunks holding only the fill value may be absent by design in older stores (Zarr does not
        # write them); R_d and the mask of a finished chunk never are, nor any chunk of a store
        # written with every chunk as a file (its header says so)
        return name in ("R_d", "mask", *_ANGLES) or self.header.get("chunk_files") == "every"


def create_dataset(path, header: dict, *, overwrite: bool = False, inputs=(), resume: bool = True):
    """Create (or reopen for resuming) a data set at ``path``.

    If ``path`` holds a data set with the same ``request``, it is reopened so
    that finished chunks are kept (unless ``resume`` is False: data written
    whole); a data set made with other arguments is
    replaced only with ``overwrite``; anything that is not a translucency data
    set, and the command's ``inputs``, are never replaced
    (:func:`translucency.io.outputs.claim_output`).
    """

    path = Path(path)
    old = reopen_or_clear(
        path,
        "planar data set",
        header["request"],
        lambda p: open_dataset(p, writable=True),
        overwrite=overwrite,
        inputs=inputs,
        resume=resume,
    )
    if old is not None:  # the same acquisition: resume, and redo the chunks whose data are damaged
        damaged = sorted({chunk for chunks in old.damaged_chunks().values() for chunk in chunks})
        for chunk in damaged:
            old.group["chunk_done"][chunk] = False
        if damaged:
            warnings.warn(
                f"{path}: chunks {damaged} were missing or damaged; acquiring them again", stacklevel=2
            )
        return old
    P = header["n_points"]
    H, W = header["window"]
    k = header["chunk_points"]
    n_chunks = -(-P // k)
    dtype = header["dtype"]
    import zarr  # heavy: Zarr loads where a store is read or written, not for --help
    from zarr.codecs import BloscCodec

    root = zarr.create_group(
        str(path), attributes={HEADER_KEY: header}, overwrite=False
    )  # never clears a folder
    comp = BloscCodec(cname="zstd", clevel=5, shuffle="shuffle")
    specs = {
        "x_i": ((P, 2), "float32", (P, 2)),
        "window_origin": ((P, 2), "float32", (P, 2)),
        "R_d": ((P, H, W, 3), dtype, (k, H, W, 3)),
        "variance": ((P, H, W, 3), dtype, (k, H, W, 3)),
        "mask": ((P, H, W), "bool", (k, H, W)),
        "specular": ((P, 3), "float32", (k, 3)),
        "total_diffuse": ((P, 3), "float32", (k, 3)),
        "chunk_done": ((n_chunks,), "bool", (1,)),
    }
    for name, shape in _planar_angle_arrays(header):  # by points, one direction a chunk
        specs[name] = (shape, "float32" if name.endswith("_oblique") and len(shape) == 3 else dtype,
                       (k, 1, *shape[2:]))  # fmt: skip
    for name, (shape, dt, chunks) in specs.items():
        root.create_array(
            name,
            shape=shape,
            dtype=dt,
            chunks=chunks,
            compressors=comp,
            fill_value=0,
            config={"write_empty_chunks": True},  # every written chunk is a file: a missing one is damage
        )
    return PlanarDataset(path, header, root)


def write_dataset(
    path,
    x_i,
    window_origin,
    R_d,
    pitch: float,
    *,
    variance=None,
    mask=None,
    eta: float = 1.3,
    photons: int | None = None,
    description: dict | None = None,
    dtype: str = "float32",
    chunk_points: int = 64,
    overwrite: bool = False,
) -> PlanarDataset:
    """Write measured windows (a real rig's, or any other) as a planar data set.

    Parameters
    ----------
    path : path
        Zarr directory to create.
    x_i : array_like, shape (P, 2)
        Incident points, mm.
    window_origin : array_like, shape (P, 2)
        Corner (x, y) of each window, mm.
    R_d : array_like, shape (P, H, W, 3)
        Diffuse reflectance per unit incident power, mm⁻², linear RGB.
    pitch : float
        Pixel size, mm.
    variance : array_like, shape (P, H, W, 3), optional
        Variance of R_d, mm⁻⁴ (default 0: noise-free).
    mask : array_like of bool, shape (P, H, W), optional
        Valid pixels (default all).
    eta : float
        Relative index of refraction of the sample (the dipole baseline uses it).
    photons : int, optional
        Photons per incident point, if the data are photon counts (the fitter
        then uses the Poisson variance of its model).

    Returns
    -------
    PlanarDataset

    Examples
    --------
    >>> import tempfile
    >>> ds = write_dataset(Path(tempfile.mkdtemp()) / "d.zarr", [[1.0, 1.0]], [[0.0, 0.0]],
    ...                    np.full((1, 8, 8, 3), 0.01), 0.25)
    >>> ds.n_points, ds.window, ds.complete()
    (1, (8, 8), True)
    """

    R_d = np.asarray(R_d, dtype=np.float64)  # NaN allowed: unmeasured pixels, flagged by the fitter
    if R_d.ndim != 4 or R_d.shape[3] != 3:
        raise TranslucencyError(f"R_d: expected shape (P, H, W, 3), got {R_d.shape}")
    P, H, W, _ = R_d.shape
    x_i = as_float_array("x_i", x_i, shape=(P, 2))
    window_origin = as_float_array("window_origin", window_origin, shape=(P, 2))
    variance = np.zeros_like(R_d) if variance is None else np.asarray(variance, dtype=np.float64)
    if variance.shape != R_d.shape:
        raise TranslucencyError(f"variance: expected shape {R_d.shape}, got {variance.shape}")
    if (variance < 0).any():
        raise TranslucencyError("variance: negative values")
    mask = np.ones((P, H, W), bool) if mask is None else np.asarray(mask, dtype=bool)
    if mask.shape != (P, H, W):
        raise TranslucencyError(f"mask: expected shape {(P, H, W)}, got {mask.shape}")
    if not pitch > 0:
        raise TranslucencyError(f"pitch: must be > 0 mm, got {pitch}")
    header = {
        "format": FORMAT,
        "version": VERSION,
        "units": {"length": "mm", "R_d": "mm^-2", "variance": "mm^-4"},
        "pitch_mm": float(pitch),
        "window": [H, W],
        "n_points": P,
        "chunk_points": int(chunk_points),
        "dtype": dtype,
        "sample": {"eta": float(eta), "description": description or {"source": "user data"}},
        "acquisition": {"photons": photons},
        "software": {"translucency": __version__},
        "request": {"written_by": "write_dataset"},
    }
    claim_output(path, "planar data set", overwrite=overwrite)
    ds = create_dataset(path, header, overwrite=True, resume=False)
    g = ds.group
    g["x_i"][...] = x_i.astype(np.float32)
    g["window_origin"][...] = window_origin.astype(np.float32)
    g["R_d"][...] = R_d.astype(dtype)
    g["variance"][...] = variance.astype(dtype)
    g["mask"][...] = mask
    g["total_diffuse"][...] = (np.nansum(R_d, axis=(1, 2)) * pitch**2).astype(np.float32)
    g["chunk_done"][...] = True
    return ds


def open_dataset(path, *, writable: bool = False) -> PlanarDataset:
    """Open a planar data set and check its header and arrays; one-line errors name the fault
    (:func:`~translucency.io._store.open_store`).

    Read-only unless ``writable`` (used when resuming an acquisition).
    """
    return open_store(path, (PlanarDataset,), writable=writable)


def dataset_identity(header: dict) -> dict:
    """What names the sample a data set (planar or mesh) measured, and where — not how (photons, seed of the
    photon streams, chunking): two acquisitions of one sample share it.

    Planar: the volume's fingerprint (SHA-256 of σ_s, σ_a; shape, voxel, g, η), else the header's sample
    description (user data); mesh: the filling's description and grid, the mesh's bounds and size.
    A model file records it (``meta["dataset_identity"]``) so that ``evaluate`` can tell a data set of
    another sample.
    """
    request = header.get("request") if isinstance(header.get("request"), dict) else {}
    if header.get("format") == "translucency-mesh-dataset":
        keys = ("volume", "volume_grid", "bounds", "vertices", "faces", "index_matched")
        return {"kind": "mesh", **{k: request.get(k) for k in keys}}
    volume = request.get("volume")
    return {"kind": "planar", "sample": volume if isinstance(volume, dict) else header.get("sample")}


def describe(ds: PlanarDataset) -> dict:
    """What ``translucency info`` reports of a planar data set (JSON-ready: docs/json.md)."""
    h = ds.header
    return ds.summary(
        window_px=[int(v) for v in h["window"]],
        pitch_mm=float(h["pitch_mm"]),
        dtype=h["dtype"],
        incidence={**ds.incidence.describe(), "directions": ds.incidence.count},
        exit_bins=None if ds.exit_bins is None else ds.exit_bins.count,
    )
