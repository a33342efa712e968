r"""The transfer as the page holds it: 8 bits a coefficient, float16 scales (:func:`encode_transfer`),
and the transfer the page decodes from them (:func:`quantised`).

Per vertex four runs — the rest :math:`r = t - a \bar E` of R, G, B, then :math:`\bar E`
(:mod:`translucency.transport.transfer`: sharp lights) — packed into RGBA texels of a texture
:data:`TEXTURE_WIDTH` wide.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..transport.transfer import Transfer

#: texels per row of the transfer texture (WebGL2 guarantees 2048 at least; 4096 everywhere we know)
TEXTURE_WIDTH = 2048


def _runs(transfer: Transfer) -> np.ndarray:
    r"""(V, 4, K): the rest :math:`r = t - a \bar E` of each channel, then :math:`\bar E`."""
    t = transfer.coefficients.astype(np.float64)
    E = transfer.irradiance.astype(np.float64)
    rest = t - transfer.local.astype(np.float64)[:, None, :] * E[:, :, None]  # (V, K, 3)
    return np.concatenate([rest.transpose(0, 2, 1), E[:, None, :]], axis=1)


def encode_transfer(transfer: Transfer) -> tuple[dict, dict]:
    """(meta, arrays): the transfer as the page holds it, in 8 bits.

    Per vertex four runs of ⌈K/4⌉ RGBA texels — the rest r = t − a Ē of R, G, B, then Ē
    (:mod:`translucency.transport.transfer`: sharp lights) — each value over its run's largest magnitude;
    the runs' scales in float16 per vertex (``transfer_run``, ``irradiance_run``) over one global scale
    each (``transfer_scale``, ``irradiance_scale``); ``local`` a in float16.  The page adds a Ē back for
    the sky.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> t = Transfer(coefficients=rng.random((5, 9, 3)), irradiance=rng.random((5, 9)),
    ...              local=rng.random((5, 3)), bands=3, directions=64)
    >>> meta, arrays = encode_transfer(t)
    >>> meta["kq"], meta["stride"], arrays["transfer"].dtype, arrays["transfer"].size
    (3, 12, dtype('int8'), 8192)
    """
    runs = _runs(transfer)  # (V, 4, K)
    V, _, K = runs.shape
    run_scale = np.max(np.abs(runs), axis=2)  # (V, 4)
    kq = -(-K // 4)
    q = np.zeros((V, 4, kq * 4), dtype=np.int8)
    with np.errstate(invalid="ignore", divide="ignore"):
        q[:, :, :K] = np.nan_to_num(np.round(127.0 * runs / run_scale[:, :, None]), nan=0.0).astype(np.int8)
    rows = -(-q.size // (4 * TEXTURE_WIDTH))
    tex = np.zeros(rows * TEXTURE_WIDTH * 4, dtype=np.int8)
    tex[: q.size] = q.ravel()
    scale_t = float(np.max(run_scale[:, :3])) or 1.0
    scale_e = float(np.max(run_scale[:, 3])) or 1.0
    arrays = {
        "transfer": tex,
        "transfer_run": (run_scale[:, :3] / scale_t).astype(np.float16),
        "irradiance_run": (run_scale[:, 3] / scale_e).astype(np.float16),
        "local": transfer.local.astype(np.float16),
    }
    meta = {
        "bands": transfer.bands,
        "stride": 4 * kq,
        "kq": kq,
        "texture_width": TEXTURE_WIDTH,
        "transfer_scale": scale_t,
        "irradiance_scale": scale_e,
    }
    return meta, arrays


def quantised(transfer: Transfer) -> Transfer:
    """The transfer as the page decodes it from :func:`encode_transfer` (8 bits, float16 scales).

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> t = Transfer(coefficients=rng.random((5, 9, 3)), irradiance=rng.random((5, 9)),
    ...              local=rng.random((5, 3)), bands=3, directions=64)
    >>> err = np.abs(quantised(t).coefficients - t.coefficients).max() / np.abs(t.coefficients).max()
    >>> bool(err < 0.02)  # 8 bits a value over its run's largest
    True
    """
    meta, arrays = encode_transfer(transfer)
    V, K, kq = len(transfer.local), transfer.bands**2, meta["kq"]
    # 8-bit SNORM, read as the GPU reads it: q / 127
    q = arrays["transfer"][: V * 4 * kq * 4].reshape(V, 4, kq * 4)[:, :, :K] / 127.0
    run = np.concatenate(
        [
            arrays["transfer_run"].astype(np.float64) * meta["transfer_scale"],
            arrays["irradiance_run"].astype(np.float64)[:, None] * meta["irradiance_scale"],
        ],
        axis=1,
    )
    values = q * run[:, :, None]  # (V, 4, K)
    local = arrays["local"].astype(np.float64)
    return dataclasses.replace(
        transfer,
        coefficients=values[:, :3].transpose(0, 2, 1) + local[:, None, :] * values[:, 3][:, :, None],
        irradiance=values[:, 3],
        local=local,
    )
