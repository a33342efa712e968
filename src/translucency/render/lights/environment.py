"""The environment light: a constant sky of radiance L (W/(mm² sr)), or a latitude–longitude map scaled
by it; its irradiance estimated by rays towards the sky."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..._validate import TranslucencyError
from ...geometry import tangent_frames
from ...mitsuba import drjit, load_plugin, mitsuba, rays
from ...model.boundary import fresnel_transmittance
from ...transport import sh
from .light import MAX_POWER, Light

#: rays of the sky's visibility in one wavefront (Dr.Jit's and NumPy's arrays of a batch: ~1 GB)
RAYS_PER_BATCH = 1 << 21


@dataclass(frozen=True)
class EnvironmentLight(Light):
    """Light from every direction: a constant radiance L (W/(mm² sr)), or an environment map.

    With ``filename`` a latitude–longitude image (EXR, HDR, PNG; linear RGB) read by
    Mitsuba's ``envmap`` emitter, scaled by ``radiance``; the map's up axis (+Y)
    is turned to the scene's +Z, the same for the irradiance, our picture and
    the reference.

    Examples
    --------
    >>> import trimesh
    >>> from translucency.mitsuba import mesh_scene
    >>> ball = trimesh.creation.icosphere(2, radius=5.0)
    >>> sky = EnvironmentLight(0.5)  # W/(mm² sr) from every direction
    >>> E = sky.irradiance_at(mesh_scene(ball), ball.vertices, ball.vertex_normals, extent=10.0)
    >>> round(float(E.min()), 6), round(float(E.max()), 6)  # every vertex sees half the sky: π L
    (1.570796, 1.570796)
    >>> sky.emitter_dict(), round(sky.irradiance_scale(100.0), 6), sky.delta
    ({'type': 'constant', 'radiance': 0.5}, 1.570796, False)
    """

    kind = "environment"
    prefix = "env"
    forms = "env:L, env:MAP.exr[,scale]"
    counts, power_index = (1,), 0
    distant = True
    delta = False

    radiance: float = 0.1
    samples: int = 64  # visibility rays per vertex (cosine-weighted, or by the map's importance)
    filename: str | None = None

    @classmethod
    def parse(cls, text: str, rest: str) -> EnvironmentLight:
        """``env:L`` or ``env:MAP[,scale]`` (a first part that is not a number names a map)."""
        if rest:
            try:
                float(rest.split(",")[0])
            except ValueError:  # not a number: the name of an environment map
                return _environment_map(rest)
        return super().parse(text, rest)

    @classmethod
    def of_numbers(cls, text: str, v: list) -> EnvironmentLight:
        return cls(v[0])

    def emitter_dict(self) -> dict:
        if self.filename is None:
            return {"type": "constant", "radiance": float(self.radiance)}
        return {
            "type": "envmap",
            "filename": str(self.filename),
            "scale": float(self.radiance),
            "to_world": mitsuba().ScalarTransform4f().rotate([1.0, 0.0, 0.0], 90.0),
        }

    def radiance_at(self, directions: np.ndarray) -> np.ndarray:
        """Radiance (N, 3), W/(mm² sr), arriving from unit ``directions`` (N, 3) (pointing to the sky):
        the constant, or the map through Mitsuba's ``envmap`` (its orientation and filtering)."""
        w = np.asarray(directions, dtype=np.float64)
        if self.filename is None:
            return np.full((len(w), 3), float(self.radiance))
        mi = mitsuba()
        emitter = load_plugin(self.emitter_dict())
        si = mi.SurfaceInteraction3f()
        si.wi = mi.Vector3f(*(np.ascontiguousarray(-w[:, j], dtype=np.float32) for j in range(3)))
        value = emitter.eval(si)
        return np.stack([np.asarray(value[j], dtype=np.float64) for j in range(3)], axis=1)

    def irradiance_scale(self, distance: float) -> float:
        """Irradiance (W/mm²) on an open surface (seeing half the sky) at any distance: π L, with L the
        map's mean radiance over the sphere (solid-angle weighted) times its scale."""
        if self.filename is None:
            return float(np.pi * self.radiance)
        pixels = np.asarray(mitsuba().Bitmap(str(self.filename)), dtype=np.float64)
        grey = pixels.reshape(pixels.shape[0], pixels.shape[1], -1)[..., :3].mean(axis=2)
        rows = np.sin((np.arange(grey.shape[0]) + 0.5) / grey.shape[0] * np.pi)  # a row's solid angle
        mean = float((grey.mean(axis=1) * rows).sum() / rows.sum())
        return float(np.pi * self.radiance * mean)

    def irradiance_at(self, scene, x, n, extent: float, eta: float = 1.0, incidence=None) -> np.ndarray:
        r"""Estimate :math:`E = \int L(\omega) V(\omega) \cos\theta\, F(\cos\theta)\, d\omega` with K =
        :attr:`samples` rays per point (F: the incidence law's factor, 1 without one).

        Constant sky: cosine-weighted directions, :math:`E \approx \pi L \langle V F \rangle`.
        Map: directions drawn by the ``envmap`` emitter in proportion to its luminance,
        :math:`E \approx \langle (L/p)\, V \cos^+\theta\, F \rangle` (RGB).

        The points go in batches of :data:`RAYS_PER_BATCH` rays (a 338 k-vertex scan's 43 M rays in one
        wavefront held 16 GB); the random numbers are drawn point by point, so the estimate does not
        depend on the batching.
        """

        def batch(v0, v1, w, weight, cos_i):
            F = None if incidence is None else incidence.at(np.arange(v0, v1)).factor(cos_i)  # (V, K, 3)
            if F is not None:
                return (weight * F).mean(axis=1)
            E = weight.mean(axis=1)
            return E[:, 0] if self.filename is None else E

        return np.concatenate(list(self._batches(scene, x, n, extent, eta, batch)), axis=0)

    def mean_over_arrivals(self, scene, x, n, extent: float, f, eta: float = 1.0) -> np.ndarray:
        r"""The irradiance-weighted mean of ``f`` over the light arriving at each point,
        :math:`\int L V \cos\theta\, f(\omega)\, d\omega / E` (grey: the channels' mean weight), from the
        same rays as :meth:`irradiance_at`; ``f(w, n)`` maps directions toward the sky (M, 3) and the
        points' normals (M, 3) to values (M, k).  (V, k); 0 where no light arrives."""

        def batch(v0, v1, w, weight, cos_i):
            grey = weight.mean(axis=2)  # (V, K)
            V, K = grey.shape
            values = np.asarray(f(w.reshape(-1, 3), np.repeat(n[v0:v1], K, axis=0)), np.float64)
            values = values.reshape(V, K, -1)
            total = grey.sum(axis=1)[:, None]
            return np.divide(np.einsum("vk,vkj->vj", grey, values), total, out=np.zeros((V, values.shape[2])),
                             where=total > 0)  # fmt: skip

        return np.concatenate(list(self._batches(scene, x, n, extent, eta, batch)), axis=0)

    def _batches(self, scene, x, n, extent: float, eta: float, reduce):
        """``reduce(v0, v1, w, weight, cos_i)`` over batches of points v0 … v1 − 1 with their K rays:
        directions toward the sky w (V, K, 3), weights (V, K, C) — L cos / p with the visibility and the
        boundary's transmission — and cosines (V, K) (:meth:`_arrivals`)."""
        K = int(self.samples)
        rng = np.random.default_rng(0)
        step = max(1, RAYS_PER_BATCH // K)
        for v0 in range(0, len(x), step):
            v1 = min(v0 + step, len(x))
            u = rng.random((v1 - v0, K, 2))  # (points, rays, 2): the same stream whatever the batch
            yield reduce(v0, v1, *self._arrivals(scene, x[v0:v1], n[v0:v1], u, extent, eta))

    def _arrivals(self, scene, x, n, u, extent: float, eta: float):
        """The rays of one batch of points, ``u`` (points, K, 2) its uniform numbers (:meth:`_batches`)."""
        K = u.shape[1]
        u1, u2 = u[..., 0], u[..., 1]
        mi = mitsuba()
        o = np.repeat(x + n * 5e-4 * extent, K, axis=0)
        if self.filename is None:
            r, phi = np.sqrt(u1), 2 * np.pi * u2
            local = np.stack([r * np.cos(phi), r * np.sin(phi), np.sqrt(1 - u1)], axis=-1)  # cosine-weighted
            frame = tangent_frames(n)  # rows t, b, n
            w = np.einsum("vkj,vji->vki", local, frame).reshape(-1, 3)
            weight = np.full((len(w), 1), np.pi * self.radiance)  # L cos / p with p = cos/π
        else:
            emitter = load_plugin(self.emitter_dict())
            it = drjit().zeros(mi.Interaction3f, len(o))
            it.p = mi.Point3f(*(o[:, j].astype(np.float32) for j in range(3)))
            ds, spec = emitter.sample_direction(
                it, mi.Point2f(u1.ravel().astype(np.float32), u2.ravel().astype(np.float32))
            )
            w = np.stack([np.asarray(ds.d.x), np.asarray(ds.d.y), np.asarray(ds.d.z)], axis=1).astype(
                np.float64
            )
            weight = np.stack([np.asarray(spec[j]) for j in range(3)], axis=1)  # L / p, times cos⁺ below
        cos_i = np.einsum("vkj,vj->vk", w.reshape(len(x), K, 3), n).reshape(-1)
        if self.filename is not None:
            weight = weight * np.maximum(cos_i, 0.0)[:, None]
        open_sky = ~np.asarray(scene.ray_test(rays(o, w)))
        weight = (
            weight * (open_sky * fresnel_transmittance(cos_i, eta) / fresnel_transmittance(1.0, eta))[:, None]
        )
        return w.reshape(len(x), K, 3), weight.reshape(len(x), K, -1), cos_i.reshape(len(x), K)

    def sh_coefficients(self, bands: int) -> np.ndarray:
        r""":math:`L_k = \int L\, Y_k\, d\omega` over :meth:`radiance_at` (:func:`.sh.project_environment`,
        a Fibonacci lattice's quadrature)."""
        return sh.project_environment(self.radiance_at, bands)


def _environment_map(rest: str) -> EnvironmentLight:
    """``MAP[,scale]`` of ``env:``: the file must exist and Mitsuba must read it."""
    name, _, scale = rest.partition(",")
    path = Path(name.strip())
    if not path.is_file():
        raise TranslucencyError(f"light: environment map {path} does not exist")
    try:
        s = float(scale) if scale.strip() else 1.0
    except ValueError:
        raise TranslucencyError(f"light: cannot read the scale {scale!r} of env:{rest}") from None
    if not (np.isfinite(s) and 0 <= s <= MAX_POWER):
        raise TranslucencyError(f"light: the scale of env:{rest} must lie in [0, {MAX_POWER:g}]")
    light = EnvironmentLight(s, filename=str(path.resolve()))
    try:
        pixels = np.asarray(mitsuba().Bitmap(str(path.resolve())), dtype=np.float64)
        load_plugin(light.emitter_dict())
    except Exception as exc:  # noqa: BLE001 — Mitsuba's message is long; one line names the file
        text = (str(exc).strip().splitlines() or [type(exc).__name__])[0]
        raise TranslucencyError(f"light: {path} is not a readable environment map ({text[:120]})") from None
    _check_map_pixels(path, pixels, s)
    return light


def _check_map_pixels(path: Path, pixels: np.ndarray, scale: float) -> None:
    """An environment map's pixels: a latitude–longitude image of finite, non-negative radiance."""
    if pixels.ndim not in (2, 3) or min(pixels.shape[:2]) < 1 or (pixels.ndim == 3 and pixels.shape[2] > 4):
        raise TranslucencyError(
            f"light: {path} is not a latitude-longitude image (pixel array of shape {pixels.shape})"
        )
    bad = ~np.isfinite(pixels)
    if bad.any():
        row, col = (int(x) for x in np.argwhere(bad)[0][:2])
        raise TranslucencyError(
            f"light: {path} holds {int(bad.sum())} non-finite values (NaN or infinity), the first at pixel "
            f"row {row}, column {col}"
        )
    if (pixels < 0).any():
        row, col = (int(x) for x in np.argwhere(pixels < 0)[0][:2])
        raise TranslucencyError(
            f"light: {path} holds negative radiance ({pixels.min():.3g} at pixel row {row}, column {col})"
        )
    if not pixels.max(initial=0.0) > 1e-30:  # Mitsuba's importance sampling of a black map divides by 0
        raise TranslucencyError(f"light: {path} is black (no pixel above 1e-30): it lights nothing")
    if pixels.max(initial=0.0) * scale > MAX_POWER:
        raise TranslucencyError(
            f"light: {path} times its scale reaches a radiance of {pixels.max() * scale:.3g}, more than "
            f"{MAX_POWER:g}"
        )
