r"""A model and the arrays of its file (:mod:`.model_file`): the arrays cast for storage, values beyond
float32 made inert, a scan's α rounded to :data:`ALPHA_BITS` mantissa bits, the checksum over them, and
the model built back from them (and so checked), with its optional mesh and measured near field.

Every array is keyed by its path in the store (``x_i``, ``alpha/values``, ``params/c``, …; the layout is
in :mod:`.model_file`).  Units: mm, R_d in mm⁻², σ in mm⁻¹.
"""

from __future__ import annotations

import hashlib

import numpy as np

from .._validate import TranslucencyError
from ..model import MODEL_KINDS, PlanarAlpha, ReflectanceModel, VertexAlpha
from ..model.extent import extent_from_dict
from ..model.lean import KAPPA_MAX, LAMBDA_MAX
from ..model.through import COS_EDGES, R_EDGES

#: mantissa bits a per-vertex α keeps (float32 keeps 23): a relative change ≤ 2⁻⁹ ≈ 0.2 %, below the
#: percent-level photon noise of a fitted α, and — the picture being linear in α — a render's change too
ALPHA_BITS = 8


# -- a model → its arrays ------------------------------------------------------
def _through_shape(model) -> tuple:
    """The shape of a model's through-body table: (N, cos cells, r cells, 3)."""
    return (model.n_points, len(COS_EDGES) - 1, len(R_EDGES) - 1, 3)


def model_arrays(model: ReflectanceModel, dtype: str, params: dict | None = None) -> dict[str, np.ndarray]:
    """Every array of the file, keyed by its path in the store, already cast."""
    if params is None:
        params = model.stored()
    with np.errstate(over="ignore"):  # overflow in the cast is reported by save_model
        return _cast_arrays(model, params, dtype)


def _points_over(value: np.ndarray, dtype) -> np.ndarray:
    """Per incident point (axis 0): does any value of ``value`` overflow ``dtype``?"""
    with np.errstate(over="ignore", invalid="ignore"):
        bad = ~np.isfinite(np.asarray(value, dtype=np.float64).astype(dtype))
    return bad.reshape(len(bad), -1).any(axis=1) if bad.ndim else np.array([bool(bad)])


def inert_where_unstorable(model: ReflectanceModel) -> tuple[dict, dict]:
    """The parameters to store, with every value that overflows float32 made inert, and those points.

    A noisy fit can reach amplitudes beyond float32 (a term c e^{d r} with d ≈ −2000 mm⁻¹ and
    c ≈ 10¹³⁰ mm⁻² that spikes inside the excluded centre pixel): not a storage problem but an
    unphysical fit.  Such terms are stored inert (the model class's ``store_inert``: c = 0,
    d = −1 mm⁻¹; for Burley A = 0, s = 1), which changes R_d only where the spike exceeded every
    float; the point is flagged.  Returns ``(params, {point: [names]})``.  The (σ_a, σ_s') families
    have no inert setting: refused.
    """
    params = model.stored()
    params = {k: None if v is None else np.array(v, dtype=np.float64) for k, v in params.items()}
    over = {k: _points_over(v, np.float32) for k, v in params.items() if v is not None}
    points = sorted({int(i) for v in over.values() for i in np.flatnonzero(v)})
    if not points:
        return params, {}
    names = {i: [k for k, v in over.items() if v[i]] for i in points}
    if not model.store_inert(params, over, points):
        listed = ", ".join(f"{i} ({'/'.join(names[i])})" for i in points[:10])
        raise TranslucencyError(
            f"the {model.kind} fit is unphysical at incident points {listed}"
            f"{' …' if len(points) > 10 else ''}: values beyond float32 (3.4e38 mm^-1); "
            "refit with more photons or a coarser --pitch"
        )
    return params, names


def _cast_arrays(model: ReflectanceModel, params: dict, dtype: str) -> dict[str, np.ndarray]:
    arrays = {"x_i": model.x_i.astype(np.float32)}
    if model.frame is not None:
        arrays["frame"] = model.frame.astype(np.float32)
    arrays["alpha/values"] = model.alpha.values.astype(dtype)
    if isinstance(model.alpha, VertexAlpha):
        arrays["alpha/vertices"] = model.alpha.vertices.astype(np.float32)
        if dtype == "float32":  # a scan's α: its trailing bits are noise (ALPHA_BITS)
            arrays["alpha/values"] = bit_rounded(arrays["alpha/values"], ALPHA_BITS)
    for name, value in params.items():
        if value is not None:
            arrays[f"params/{name}"] = value.astype(dtype)
    if model.faces is not None:
        arrays["mesh/faces"] = np.asarray(model.faces).astype(np.int32)
    for name, value in (model.measured or {}).items():
        arrays[f"measured/{name}"] = np.asarray(value).astype(np.float32)
    return arrays


def bit_rounded(values: np.ndarray, keep: int) -> np.ndarray:
    """float32 ``values`` rounded to the nearest number with ``keep`` mantissa bits, the rest zero: a
    relative change of at most :math:`2^{-(keep+1)}`, and runs of zero bits the byte shuffle and zstd
    then store in almost nothing.

    Examples
    --------
    >>> bit_rounded(np.array([1.0, 1.2345678, 3.0e-3], np.float32), 8)
    array([1.        , 1.234375  , 0.00299835], dtype=float32)
    """
    bits = np.ascontiguousarray(values, np.float32).view(np.uint32)
    drop = 23 - int(keep)
    half, mask = np.uint32(1 << (drop - 1)), np.uint32((0xFFFFFFFF << drop) & 0xFFFFFFFF)
    return ((bits + half) & mask).view(np.float32)


def checksum(arrays: dict[str, np.ndarray]) -> str:
    h = hashlib.sha256()
    for key in sorted(arrays):
        a = np.ascontiguousarray(arrays[key])
        h.update(f"{key}:{a.dtype.str}:{a.shape}".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def overflow_message(key: str, cast: np.ndarray, dtype: str, model: ReflectanceModel) -> str:
    """What overflowed where, and what to do (only float16, or a non-parameter array, gets here)."""
    where = np.argwhere(~np.isfinite(cast))
    if key.startswith("params/") or key in ("x_i", "frame"):
        points = sorted({int(i) for i in where[:, 0]})
        place = f"incident points {points[:10]}{' …' if len(points) > 10 else ''}"
    else:
        place = f"index {tuple(int(v) for v in where[0])}"
    if dtype == "float16":
        return (
            f"{key} overflows float16 (largest 65504) at {place}; store as float32 "
            "(without --float16, or dtype='float32')"
        )


# -- its arrays → a model ------------------------------------------------------
def model_from_arrays(arrays: dict[str, np.ndarray], header: dict) -> ReflectanceModel:
    """Build (and so validate) a model from decoded arrays and the header."""
    x_i = arrays["x_i"]
    frame = arrays.get("frame")
    if header["geometry"] == "planar":
        a = header["alpha"]
        alpha = PlanarAlpha(arrays["alpha/values"], np.asarray(a["origin"]), a["pitch"])
    else:
        alpha = VertexAlpha(arrays["alpha/values"], arrays["alpha/vertices"])
    cls = MODEL_KINDS[header["kind"]]
    model = cls.from_stored(
        x_i, {name: arrays.get(f"params/{name}") for name in cls.STORED}, alpha, frame, header
    )
    _attach_surface(model, arrays)
    record = header.get("object") or {}
    if "extent" in record:
        model.extent = extent_from_dict(record["extent"])
    if record.get("tally_photons"):
        model.tally_photons = int(record["tally_photons"])
    return model


def _attach_surface(model: ReflectanceModel, arrays: dict[str, np.ndarray]) -> None:
    """The optional mesh and measured near field of a mesh model, checked (one-line errors)."""
    faces = arrays.get("mesh/faces")
    if faces is not None:
        V = len(model.alpha.values)
        if model.geometry != "mesh" or faces.ndim != 2 or faces.shape[1] != 3 or len(faces) == 0:
            raise TranslucencyError(
                f"mesh/faces: expected (F, 3) triangles of a mesh model, got {faces.shape}"
            )
        if faces.min() < 0 or faces.max() >= V:
            raise TranslucencyError(f"mesh/faces: vertex indices outside 0..{V - 1}")
        model.faces = faces.astype(np.int64)
    measured = {k.split("/", 1)[1]: v for k, v in arrays.items() if k.startswith("measured/")}
    if measured:
        N = model.n_points
        shapes = {
            "own": (N, 3),
            "total": (N, 3),
            "through": _through_shape(model),
            "lean": (N, 2, 3),
            "medium": (N, 2, 3),
        }
        for name, value in measured.items():
            if name not in shapes or value.shape != shapes[name]:
                raise TranslucencyError(
                    f"measured/{name}: expected 'own' or 'total' of shape ({N}, 3), 'lean' or 'medium' "
                    f"({N}, 2, 3) or "
                    f"'through' {_through_shape(model)}, got {value.shape}"
                )
            if not (np.isfinite(value).all() and (value >= 0).all()):
                raise TranslucencyError(f"measured/{name}: values must be finite and >= 0")
        if "lean" in measured and (
            measured["lean"][:, 0].max() > KAPPA_MAX or measured["lean"][:, 1].max() > LAMBDA_MAX
        ):
            raise TranslucencyError(
                f"measured/lean: κ must lie in [0, {KAPPA_MAX:g}] and λ in [0, {LAMBDA_MAX:g}] mm⁻¹"
            )
        model.measured = {k: v.astype(np.float64) for k, v in measured.items()}


def required_arrays(header: dict) -> list[str]:
    keys = ["x_i", "alpha/values"]
    if header["geometry"] == "mesh":
        keys += ["frame", "alpha/vertices"]
    return keys + [f"params/{p}" for p in MODEL_KINDS[header["kind"]].required_params(header)]
