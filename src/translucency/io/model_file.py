"""The translucency model file, format version 1.

A model file is a Zarr v3 store packed in a single zip file (suggested suffix
``.model.zip``); any Zarr v3 reader can open it.  No pickle is involved.

Layout::

    /                     group; attrs["translucency_model"] = header (below)
    x_i                   (N, D) float32   incident points, mm (D = 2 planar, 3 mesh)
    frame                 (N, 3, 3) float32  mesh only: rows tangent, bitangent, normal
    alpha/values          (H, W) planar or (V,) mesh; dtype = header["dtype"] (a mesh's float32: 8 bits kept)
    alpha/vertices        (V, 3) float32   mesh only: vertex positions, mm
    mesh/faces            (F, 3) int32     mesh only, optional: the triangles (the model renders on its own)
    mesh/draco            (B,) uint8       in place of the two above: the mesh compressed (io/mesh_codec.py)
    measured/own          (N, 3) float32   mesh only, optional: R_d over each incident vertex's own area, mm⁻²
    measured/total        (N, 3) float32   mesh only, optional: measured diffuse exitance per unit power
    measured/through      (N, 4, 8, 3) f32 mesh only, optional: the through-body table (model/through.py)
    measured/lean         (N, 2, 3) f32    mesh only, optional: the lean's κ ≥ 0, λ ≥ 0 mm⁻¹ (model/lean.py)
    measured/medium       (N, 2, 3) f32    mesh only, optional: the medium estimated from the scan, σ_s and
                                           σ_a ≥ 0 mm⁻¹ at each incident point (medium/estimate.py)
    params/...            per kind (the model class's ``STORED``), dtype = header["dtype"]:
        exponential:  c, d (N, C, m, n) in mm⁻² and mm⁻¹; s_g, s_b (N,) when C = 1
        dipole, pbd, ddipole:  sigma_a, sigma_s_prime (N, 3) in mm⁻¹ (and ``eta`` in the header)
        burley:       A (N, 3); s (N, 3) in mm⁻¹

Header (JSON): ``format`` = "translucency-model", ``version`` = 1, ``kind``
("exponential" | "dipole" | "burley" | "pbd" | "ddipole"), ``geometry`` ("planar" | "mesh"),
``dtype`` ("float32" | "float16"), ``units``, ``alpha`` ({origin, pitch} for
planar), ``eta`` (dipole, pbd, ddipole), ``g`` (pbd: the medium's mean cosine, 0 when
absent), ``meta`` (free-form provenance; ``meta["flagged_points"]``
lists the points an evaluation leaves out), ``unstorable`` (points whose fitted
values did not fit in the storage type, stored inert and flagged), ``object`` (what
the physical bounds need beyond the arrays, when known: ``extent``, the object
the model describes (:mod:`translucency.model.extent`: a planar sample's
rectangle, a semi-infinite slab), and ``tally_photons``, the photons per point
of the tally it was fitted to), ``physics`` (the per-point bounds of
:mod:`translucency.model.bounds`: the largest total reflectance, share of the
energy beyond the object and energy radius, the bounds, the object's size and
the indices of the points that break a bound), ``software`` and
``mesh_codec`` (``{"name": "draco", "array": "mesh/draco"}`` where the mesh is compressed: its
positions on a grid a hundredth of an edge fine) and
``checksum``: the SHA-256 of every array's decoded bytes in a fixed order, so
that corruption that survives decompression is still caught.

Each model class (:data:`translucency.model.MODEL_KINDS`, by ``kind``) declares what it
stores: its parameter arrays (``STORED``, ``required_params``), its header fields
(``header_fields``), how it is rebuilt (``from_stored``) and how values beyond float32 are
made inert (``store_inert``); this module is the same for every kind.  What becomes of a model's
values on the way to the arrays and back (the casts, inert values, α's bits, the checksum, the checks
of a model built from them) is :mod:`._model_arrays`; this module holds the header and the container.

Arrays are compressed with Blosc (zstd, byte shuffle), one chunk per field (all
points of one parameter, term and direction), which keeps spatially coherent
values together; parameter arrays may be stored as float16 to make models small.  Writes go to a
temporary file in the target directory and are moved into place with an atomic rename.
"""

from __future__ import annotations

import json
import warnings
import zipfile
from pathlib import Path

import numpy as np

from .._validate import TranslucencyError
from .._version import __version__
from ..model import MODEL_KINDS, PlanarAlpha, ReflectanceModel
from ..model.bounds import check_physics
from ._model_arrays import (
    checksum,
    inert_where_unstorable,
    model_arrays,
    model_from_arrays,
    overflow_message,
    required_arrays,
)
from .atomic import atomic_path
from .mesh_codec import decode_mesh, encode_mesh
from .outputs import claim_output

FORMAT = "translucency-model"
VERSION = 1
HEADER_KEY = "translucency_model"
#: the array of a compressed mesh, and the two it stands for
MESH_ARRAY = "mesh/draco"
_MESH_KEYS = ("alpha/vertices", "mesh/faces")

_STORABLE = tuple(MODEL_KINDS.values())


class ModelFileError(TranslucencyError):
    """A model file that cannot be read or is not valid; the message names the file.

    A :class:`~translucency.TranslucencyError`, so one ``except`` catches it with every other
    one-line refusal of the tool.

    Examples
    --------
    >>> from translucency import ModelFileError, TranslucencyError, load_model
    >>> import os, tempfile
    >>> p = os.path.join(tempfile.mkdtemp(), "notes.model.zip")
    >>> _ = open(p, "w").write("not a zip")
    >>> try:
    ...     load_model(p)
    ... except ModelFileError as exc:
    ...     print(str(exc).split(os.sep)[-1])
    notes.model.zip: not a translucency model file (not a zip archive; truncated or corrupted?)
    >>> issubclass(ModelFileError, TranslucencyError)
    True
    """


# -- writing -------------------------------------------------------------------


def save_model(
    model: ReflectanceModel,
    path,
    *,
    dtype: str = "float32",
    meta: dict | None = None,
    overwrite: bool = False,
) -> Path:
    """Write ``model`` to ``path`` atomically.

    Parameters
    ----------
    model : ExponentialModel, DipoleModel, BurleyModel, PBDModel or DirectionalDipoleModel
        The model to store.
    path : str or Path
        Destination; an existing model file is replaced (with ``overwrite``)
        only once the new one is complete; any other existing file is refused
        (:func:`translucency.io.outputs.claim_output`).
    dtype : {"float32", "float16"}
        Storage precision of parameters and α (positions and frames stay
        float32).  float16 halves the size; a value that would not survive the
        cast (overflow, or a d that rounds to 0 and breaks eq. (2)) is refused.
    meta : dict, optional
        JSON-serialisable provenance stored in the header.
    overwrite : bool
        Replace a model file already at ``path``.

    Returns
    -------
    Path
        The written file.

    Examples
    --------
    >>> from translucency import load_model, save_model
    >>> import tempfile, translucency as tl
    >>> m = tl.ExponentialModel([[0.0, 0.0]], [[[[1.0]]]], [[[[-2.0]]]],
    ...                         tl.PlanarAlpha.uniform((2, 2)), s_g=[1.0], s_b=[1.0])
    >>> p = save_model(m, tempfile.mkdtemp() + "/m.model.zip")
    >>> load_model(p).d.ravel()
    array([-2.])
    """
    path = Path(path)
    if dtype not in ("float32", "float16"):
        raise TranslucencyError(f"dtype: expected 'float32' or 'float16', got {dtype!r}")
    if not isinstance(model, _STORABLE):
        raise TranslucencyError(f"model: cannot store a {type(model).__name__}")
    claim_output(path, "model file", overwrite=overwrite)
    try:
        params, unstorable = inert_where_unstorable(model)
    except TranslucencyError as exc:
        raise TranslucencyError(f"{path}: {exc}") from None
    if unstorable:
        meta = dict(meta or {})
        flagged = {int(i) for i in meta.get("flagged_points", [])} | set(unstorable)
        meta["flagged_points"] = sorted(flagged)
        listed = ", ".join(f"{i} ({'/'.join(v)})" for i, v in list(unstorable.items())[:10])
        warnings.warn(
            f"{path}: the fit is unphysical at {len(unstorable)} incident points, whose values exceed "
            f"float32 (3.4e38): {listed}{' …' if len(unstorable) > 10 else ''}; those terms are stored "
            "inert and the points flagged (evaluate leaves them out); more photons or a coarser "
            "--pitch avoid it",
            stacklevel=2,
        )
    arrays = model_arrays(model, dtype, params)
    mesh = None  # the mesh as Draco bytes (io/mesh_codec.py), its arrays replaced by what they decode to
    if "mesh/faces" in arrays:
        mesh = encode_mesh(arrays["alpha/vertices"], arrays["mesh/faces"])
        if mesh is not None:
            arrays["alpha/vertices"], arrays["mesh/faces"] = mesh[1], mesh[2]
    # the stored (cast) values must still form a valid model
    for key, a in arrays.items():
        if not np.isfinite(a).all():
            raise TranslucencyError(f"{path}: {overflow_message(key, a, dtype, model)}")
    try:
        stored = model_from_arrays(arrays, _header(model, dtype, meta, ""))
    except TranslucencyError as exc:
        raise TranslucencyError(f"{path}: not representable in {dtype}: {exc}") from None
    header = _header(model, dtype, meta, checksum(arrays))
    if unstorable:
        header["unstorable"] = {str(i): v for i, v in unstorable.items()}
    header["physics"] = check_physics(stored).summary()  # what the stored values promise (model/bounds.py)
    if mesh is not None:
        header["mesh_codec"] = {"name": "draco", "array": MESH_ARRAY}
        arrays = {k: v for k, v in arrays.items() if k not in _MESH_KEYS}
        arrays[MESH_ARRAY] = np.frombuffer(mesh[0], dtype=np.uint8)
    _write_store(path, header, arrays)
    return path


def _write_store(path: Path, header: dict, arrays: dict[str, np.ndarray]) -> None:
    """Pack a header and arrays into a zipped Zarr v3 store at ``path``, atomically."""
    import zarr  # heavy: Zarr loads where a store is read or written, not for --help
    from zarr.codecs import BloscCodec

    with atomic_path(path) as tmp:
        tmp.unlink()  # ZipStore creates the archive itself
        store = zarr.storage.ZipStore(tmp, mode="w")
        root = zarr.create_group(store, attributes={HEADER_KEY: header})
        compressor = BloscCodec(cname="zstd", clevel=9, shuffle="shuffle")
        for key, a in arrays.items():
            # one chunk per field over all points (e.g. c of term k, direction l): neighbouring
            # points have similar values, which the bit-shuffle + zstd compressor exploits
            chunks = a.shape if key.startswith("alpha/") else (a.shape[0],) + (1,) * (a.ndim - 1)
            root.create_array(key, shape=a.shape, dtype=a.dtype, chunks=chunks, compressors=compressor)[
                ...
            ] = a
        store.close()


def _header(model: ReflectanceModel, dtype: str, meta: dict | None, digest: str) -> dict:
    """The file's JSON header (module docstring), ``digest`` its arrays' checksum."""
    header = {
        "format": FORMAT,
        "version": VERSION,
        "kind": model.kind,
        "geometry": model.geometry,
        "dtype": dtype,
        "units": {"length": "mm", "R_d": "mm^-2", "c": "mm^-2", "d": "mm^-1", "sigma": "mm^-1"},
        "n_points": model.n_points,
        "software": {"translucency": __version__},
        "meta": meta or {},
        "checksum": digest,
    }
    if isinstance(model.alpha, PlanarAlpha):
        header["alpha"] = {"origin": [float(v) for v in model.alpha.origin], "pitch": model.alpha.pitch}
    header.update(model.header_fields())
    record = _object_record(model)
    if record:
        header["object"] = record
    try:
        json.dumps(header)
    except TypeError as exc:
        raise TranslucencyError(f"meta: not JSON-serialisable ({exc})") from None
    return header


def _object_record(model: ReflectanceModel) -> dict:
    """The header's ``object`` field: what the physical bounds need beyond the arrays (empty: nothing)."""
    record = {}
    if model.extent is not None:
        record["extent"] = model.extent.as_dict()
    if model.tally_photons:
        record["tally_photons"] = int(model.tally_photons)
    return record


# -- reading -------------------------------------------------------------------


def read_header(path) -> dict:
    """The JSON header of a model file, checked for format and version.

    Only the header is read (no parameter array is decoded), so this is cheap on a large model.

    Parameters
    ----------
    path : str or Path
        A file written by :func:`save_model`.

    Returns
    -------
    dict
        The header: ``format``, ``version``, ``kind``, ``geometry``, ``dtype``, ``units``, ...

    Raises
    ------
    ModelFileError
        One line naming the file: missing, not a zip, no header, an unknown version or field.

    Examples
    --------
    >>> import tempfile, translucency as tl
    >>> m = tl.ExponentialModel([[0.0, 0.0]], [[[[1.0]]]], [[[[-2.0]]]],
    ...                         tl.PlanarAlpha.uniform((2, 2)), s_g=[1.0], s_b=[1.0])
    >>> h = read_header(save_model(m, tempfile.mkdtemp() + "/m.model.zip", dtype="float16"))
    >>> h["kind"], h["geometry"], h["dtype"], h["version"]
    ('exponential', 'planar', 'float16', 1)
    >>> h["units"]["R_d"], h["units"]["d"]
    ('mm^-2', 'mm^-1')
    """
    return _open(Path(path))[1]


def _open(path: Path):
    import zarr  # heavy: Zarr loads where a store is read or written, not for --help

    if not path.exists():
        raise ModelFileError(f"{path}: no such file")
    if not zipfile.is_zipfile(path):
        raise ModelFileError(
            f"{path}: not a translucency model file (not a zip archive; truncated or corrupted?)"
        )
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            store = zarr.storage.ZipStore(path, mode="r")
            root = zarr.open_group(store, mode="r")
            header = dict(root.attrs).get(HEADER_KEY)
    except Exception as exc:  # noqa: BLE001 — any failure of the container is the file's fault
        raise ModelFileError(
            f"{path}: unreadable model file ({type(exc).__name__}: {_first_line(exc)})"
        ) from None
    if not isinstance(header, dict) or header.get("format") != FORMAT:
        raise ModelFileError(f"{path}: not a translucency model file (no '{HEADER_KEY}' header)")
    version = header.get("version")
    if version != VERSION:
        raise ModelFileError(
            f"{path}: format version {version!r} is not supported (this reader knows {VERSION})"
        )
    for key, allowed in (
        ("kind", tuple(MODEL_KINDS)),
        ("geometry", ("planar", "mesh")),
        ("dtype", ("float32", "float16")),
    ):
        if header.get(key) not in allowed:
            raise ModelFileError(
                f"{path}: header field {key!r} = {header.get(key)!r}, expected one of {allowed}"
            )
    return root, header


def _first_line(exc: Exception) -> str:
    text = str(exc).strip().splitlines()
    return text[0][:200] if text else "no detail"


def load_model(path) -> ReflectanceModel:
    """Read and validate a model file.

    Checks the format name and version, the presence, shapes, dtypes and
    finiteness of every array, eq. (2) and the checksum; any fault raises
    :class:`ModelFileError` with one line naming the file and the fault.

    Parameters
    ----------
    path : str or Path
        A file written by :func:`save_model`.

    Returns
    -------
    ExponentialModel, DipoleModel, BurleyModel, PBDModel or DirectionalDipoleModel
        The model of the file's ``kind``, its arrays as float64.

    Raises
    ------
    ModelFileError
        One line naming the file and its fault.

    Examples
    --------
    A round trip through float16 keeps a one-term fit's total reflectance 2πc/d² (c = 1 mm⁻²,
    d = −2 mm⁻¹: π/2):

    >>> from translucency import load_model, save_model
    >>> import tempfile, translucency as tl
    >>> m = tl.ExponentialModel([[0.0, 0.0]], [[[[1.0]]]], [[[[-2.0]]]],
    ...                         tl.PlanarAlpha.uniform((2, 2)), s_g=[1.0], s_b=[1.0])
    >>> back = load_model(save_model(m, tempfile.mkdtemp() + "/m.model.zip", dtype="float16"))
    >>> back.kind, back.d.dtype, back.total_reflectance().round(4)
    ('exponential', dtype('float64'), array([[1.5708, 1.5708, 1.5708]]))
    """
    return read_model(path)[0]


def read_model(path) -> tuple[ReflectanceModel, dict]:
    """A model file's model and header, the file opened once (:func:`load_model`, :func:`read_header`).

    Examples
    --------
    >>> import tempfile, translucency as tl
    >>> m = tl.ExponentialModel([[0.0, 0.0]], [[[[1.0]]]], [[[[-2.0]]]],
    ...                         tl.PlanarAlpha.uniform((2, 2)), s_g=[1.0], s_b=[1.0])
    >>> model, header = read_model(save_model(m, tempfile.mkdtemp() + "/m.model.zip"))
    >>> header["kind"], header["geometry"], float(model.d[0, 0, 0, 0])
    ('exponential', 'planar', -2.0)
    """
    path = Path(path)
    root, header = _open(path)
    return _read_model(path, root, header), header


def _decoded_mesh(path: Path, root, codec: dict) -> dict[str, np.ndarray]:
    """The vertices and triangles of a compressed mesh (the header's ``mesh_codec``), decoded."""
    if codec.get("name") != "draco" or codec.get("array") != MESH_ARRAY:
        raise ModelFileError(f"{path}: unknown mesh_codec {codec!r} (this version reads draco)")
    try:
        data = np.asarray(root[MESH_ARRAY][...], dtype=np.uint8).tobytes()
    except KeyError:
        raise ModelFileError(f"{path}: missing array {MESH_ARRAY!r}") from None
    except Exception as exc:  # noqa: BLE001 — CRC or codec failures: corrupted data
        raise ModelFileError(f"{path}: array {MESH_ARRAY!r} is corrupted ({_first_line(exc)})") from None
    try:
        vertices, faces = decode_mesh(data)
    except Exception as exc:  # noqa: BLE001 — Draco's own failures on altered bytes
        raise ModelFileError(f"{path}: array {MESH_ARRAY!r} does not decode ({_first_line(exc)})") from None
    return {"alpha/vertices": vertices, "mesh/faces": faces}


def _read_model(path: Path, root, header: dict) -> ReflectanceModel:
    """The model of the opened file at ``path`` (:func:`_open`: its Zarr group and checked header)."""
    want_dtype = np.dtype(header["dtype"])
    arrays = {}
    required = required_arrays(header)
    optional = [f"params/{p}" for p in MODEL_KINDS[header["kind"]].STORED if f"params/{p}" not in required]
    if header["geometry"] == "mesh":
        optional += ["mesh/faces", "measured/own", "measured/total", "measured/through", "measured/lean"]
        optional += ["measured/medium"]
    if header.get("mesh_codec"):  # the vertices and triangles as one Draco array (io/mesh_codec.py)
        arrays.update(_decoded_mesh(path, root, header["mesh_codec"]))
        required = [k for k in required if k not in _MESH_KEYS]
        optional = [k for k in optional if k not in _MESH_KEYS]
    for key in required + optional:
        try:
            arr = root[key]
        except KeyError:
            if key in required:
                raise ModelFileError(f"{path}: missing array {key!r}") from None
            continue
        except Exception as exc:  # noqa: BLE001
            raise ModelFileError(f"{path}: unreadable array {key!r} ({_first_line(exc)})") from None
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                a = np.asarray(arr[...])
        except Exception as exc:  # noqa: BLE001 — CRC or codec failures: corrupted data
            raise ModelFileError(
                f"{path}: array {key!r} is corrupted ({type(exc).__name__}: {_first_line(exc)})"
            ) from None
        expect = (
            np.int32
            if key == "mesh/faces"
            else np.float32
            if key in ("x_i", "frame", "alpha/vertices") or key.startswith("measured/")
            else want_dtype
        )
        if a.dtype != expect:
            raise ModelFileError(f"{path}: array {key!r} has dtype {a.dtype}, expected {np.dtype(expect)}")
        if not np.isfinite(a).all():
            idx = tuple(int(v) for v in np.argwhere(~np.isfinite(a))[0])
            raise ModelFileError(f"{path}: array {key!r} holds a non-finite value at index {idx}")
        arrays[key] = a
    if checksum(arrays) != header.get("checksum"):
        raise ModelFileError(f"{path}: checksum mismatch: the file's arrays were altered or corrupted")
    try:
        return model_from_arrays({k: v.astype(np.float64) for k, v in arrays.items()}, header)
    except (TranslucencyError, KeyError, TypeError) as exc:
        raise ModelFileError(f"{path}: invalid model: {_first_line(exc)}") from None
