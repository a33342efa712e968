"""Checks at the validation harness's boundary: coordinates, positive numbers, channels, the set-up's fit."""

from __future__ import annotations

import numpy as np

from .._validate import TranslucencyError, as_float_array


def check_point(name: str, value) -> tuple[float, float]:
    """Two finite coordinates (x, y) in mm, or a one-line error."""
    x, y = as_float_array(name, value, shape=(2,))
    return float(x), float(y)


def check_positive(name: str, value, unit: str = "mm") -> float:
    """A finite number > 0, or a one-line error naming ``unit``.

    (``_validate.check_positive`` works on arrays and reports an index; this is its scalar form.)
    """
    try:
        v = float(value)
    except (TypeError, ValueError):
        v = float("nan")
    if not (np.isfinite(v) and v > 0):
        raise TranslucencyError(f"{name}: must be a positive number ({unit}), got {value!r}")
    return v


def check_channels(channels) -> tuple[int, ...]:
    try:
        ch = tuple(int(c) for c in channels)
    except (TypeError, ValueError):
        ch = ()
    if not ch or any(c not in (0, 1, 2) for c in ch):
        raise TranslucencyError(f"channels: expected a non-empty subset of (0, 1, 2), got {channels!r}")
    return ch
