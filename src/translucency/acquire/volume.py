"""A planar slab filled with a voxel volume of scattering coefficients.

Geometry (mm): the slab occupies ``0 <= x <= width``, ``0 <= y <= height``,
``-thickness <= z <= 0``; light arrives from +z onto the top face z = 0.
Voxel ``[iz, iy, ix]`` covers ``x in [ix, ix+1) * voxel_mm``,
``y in [iy, iy+1) * voxel_mm`` and ``z in (-(iz+1), -iz] * voxel_mm`` — z index
0 is the lit top layer.  Per voxel and channel: scattering ``sigma_s`` and
absorption ``sigma_a`` in mm⁻¹ (RGB); one Henyey–Greenstein anisotropy ``g``
and one relative index ``eta`` for the whole slab.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .._validate import TranslucencyError, check_nonnegative


@dataclass(frozen=True, eq=False)
class Volume:
    """Heterogeneous slab: per-voxel, per-channel coefficients in mm⁻¹.

    Parameters
    ----------
    sigma_s, sigma_a : ndarray, shape (Z, Y, X, 3)
        Scattering and absorption coefficients in mm⁻¹.
    voxel_mm : float
        Edge length of the (cubic) voxels in mm.
    g : float
        Henyey–Greenstein anisotropy in (-1, 1).
    eta : float
        Relative index of refraction of the slab (1 = index-matched boundary).
    description : dict
        JSON-serialisable description of how the volume was made.

    Examples
    --------
    >>> v = Volume.homogeneous((4, 8, 8), 0.5, sigma_s=[1.0, 1.0, 1.0], sigma_a=[0.01] * 3)
    >>> v.size_mm
    (4.0, 4.0, 2.0)
    """

    sigma_s: np.ndarray
    sigma_a: np.ndarray
    voxel_mm: float
    g: float = 0.0
    eta: float = 1.3
    description: dict = field(default_factory=dict)

    def __post_init__(self):
        for name in ("sigma_s", "sigma_a"):
            a = np.asarray(getattr(self, name), dtype=np.float32)
            if a.ndim != 4 or a.shape[3] != 3:
                raise TranslucencyError(f"{name}: expected shape (Z, Y, X, 3), got {a.shape}")
            if a.size == 0 or min(a.shape[:3]) < 1:
                raise TranslucencyError(f"{name}: empty volume of shape {a.shape}")
            bad = ~np.isfinite(a)
            if bad.any():
                idx = tuple(int(i) for i in np.argwhere(bad)[0])
                raise TranslucencyError(f"{name}: non-finite value at voxel {idx}")
            check_nonnegative(name, a)
            object.__setattr__(self, name, a)
        if self.sigma_s.shape != self.sigma_a.shape:
            raise TranslucencyError(
                f"sigma_a: shape {self.sigma_a.shape} differs from sigma_s {self.sigma_s.shape}"
            )
        if not (self.sigma_s + self.sigma_a > 0).any(axis=(0, 1, 2)).all():
            raise TranslucencyError("sigma_s, sigma_a: a channel is empty (all coefficients zero)")
        for name, lo, hi in (("voxel_mm", 0.0, np.inf), ("g", -1.0, 1.0), ("eta", 0.0, np.inf)):
            v = getattr(self, name)
            if not (isinstance(v, (int, float, np.floating)) and np.isfinite(v) and lo < v < hi):
                raise TranslucencyError(f"{name}: {v!r} is outside ({lo}, {hi})")
            object.__setattr__(self, name, float(v))

    @classmethod
    def homogeneous(cls, shape, voxel_mm, sigma_s, sigma_a, g=0.0, eta=1.3, description=None) -> Volume:
        """A volume of ``shape`` (Z, Y, X) voxels with the same RGB coefficients everywhere."""
        shape = tuple(int(s) for s in shape) + (3,)
        return cls(
            np.broadcast_to(np.asarray(sigma_s, np.float32), shape).copy(),
            np.broadcast_to(np.asarray(sigma_a, np.float32), shape).copy(),
            voxel_mm,
            g,
            eta,
            description or {"generator": "homogeneous"},
        )

    @property
    def shape(self) -> tuple[int, int, int]:
        """(Z, Y, X) voxels."""
        return self.sigma_s.shape[:3]

    @property
    def size_mm(self) -> tuple[float, float, float]:
        """(width, height, thickness) in mm."""
        z, y, x = self.shape
        return (x * self.voxel_mm, y * self.voxel_mm, z * self.voxel_mm)

    @property
    def sigma_t(self) -> np.ndarray:
        """Extinction σ_t = σ_s + σ_a in mm⁻¹, shape (Z, Y, X, 3)."""
        return self.sigma_s + self.sigma_a

    def majorant(self) -> np.ndarray:
        """Per-channel maximum of σ_t (the delta-tracking majorant), mm⁻¹."""
        return self.sigma_t.max(axis=(0, 1, 2))

    def nbytes(self) -> int:
        return self.sigma_s.nbytes + self.sigma_a.nbytes


def load_volume(path) -> Volume:
    """Read a user's volume from ``.npz``.

    Required arrays: ``sigma_s`` and ``sigma_a`` of shape (Z, Y, X, 3) in mm⁻¹
    (z index 0 at the lit top surface) and scalar ``voxel_mm``; optional
    scalars ``g`` (default 0) and ``eta`` (default 1.3).

    Examples
    --------
    >>> import tempfile
    >>> sigma = np.ones((2, 4, 6, 3))   # Z, Y, X, channels
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     np.savez(f"{tmp}/v.npz", sigma_s=sigma, sigma_a=0.01 * sigma, voxel_mm=0.5)
    ...     v = load_volume(f"{tmp}/v.npz")
    >>> v.size_mm, v.g, v.eta   # (W, H, T) mm; the defaults of g and η
    ((3.0, 2.0, 1.0), 0.0, 1.3)
    """
    path = Path(path)
    if not path.exists():
        raise TranslucencyError(f"{path}: no such volume file")
    try:
        with np.load(path, allow_pickle=False) as f:
            data = {k: f[k] for k in f.files}
    except Exception as exc:  # noqa: BLE001 — any failure to parse is the file's fault
        raise TranslucencyError(f"{path}: not a readable .npz volume ({type(exc).__name__})") from None
    for key in ("sigma_s", "sigma_a", "voxel_mm"):
        if key not in data:
            raise TranslucencyError(f"{path}: missing array {key!r} (need sigma_s, sigma_a, voxel_mm)")
    scalars = {}
    for key, default in (("voxel_mm", None), ("g", 0.0), ("eta", 1.3)):
        if key in data:
            if data[key].size != 1:
                raise TranslucencyError(f"{path}: {key} must be a scalar, got shape {data[key].shape}")
            scalars[key] = float(data[key].reshape(()))
        else:
            scalars[key] = default
    try:
        return Volume(
            data["sigma_s"],
            data["sigma_a"],
            scalars["voxel_mm"],
            scalars["g"],
            scalars["eta"],
            {"generator": "file", "path": str(path)},
        )
    except TranslucencyError as exc:
        raise TranslucencyError(f"{path}: {exc}") from None
