"""Records as strict JSON: what a summary holds (NumPy numbers, paths, tuples, NaN) made writable."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

__all__ = ["jsonable"]


def jsonable(value):
    """``value`` with every NaN or infinity as null (strict JSON), tuples and paths as lists and strings.

    Examples
    --------
    >>> import numpy as np
    >>> from pathlib import Path
    >>> jsonable({"rel_l2": np.float32(0.5), "noise": float("nan"), "out": Path("a/b"), "n": (np.int64(2),)})
    {'rel_l2': 0.5, 'noise': None, 'out': 'a/b', 'n': [2]}
    """
    if isinstance(value, dict):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [jsonable(v) for v in value]
    if isinstance(value, (np.floating, float)):
        return float(value) if math.isfinite(value) else None
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, np.ndarray):
        return jsonable(value.tolist())
    if isinstance(value, Path):
        return str(value)
    return value
