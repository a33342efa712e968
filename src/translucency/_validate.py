"""Input validation at the API boundary.

Every user mistake becomes one :class:`TranslucencyError` whose message is a
single line naming the file, parameter or point at fault.  The CLI prints that
line and exits with status 2; library callers can catch the exception.
"""

from __future__ import annotations

import dataclasses

import numpy as np


class TranslucencyError(ValueError):
    """A user-facing error: one line that names what is wrong and where.

    Examples
    --------
    >>> from translucency.model import material
    >>> try:
    ...     material("jade")
    ... except ValueError as exc:   # a ValueError: callers that catch those catch it
    ...     print(type(exc).__name__, "|", str(exc).split(";")[0])
    TranslucencyError | material: unknown name 'jade'
    """


def plain(value, digits: int = 4) -> str:
    """``value`` as a message shows it, without Python's internals (``np.float64(…)``, ``array(…)``):
    numbers to ``digits`` significant digits, sequences and arrays as ``(x, y, z)``, a dataclass (a light)
    as ``Name(field=value, …)``.

    Examples
    --------
    >>> plain((np.float64(-5.0), np.float64(0.25), 120))
    '(-5, 0.25, 120)'
    >>> plain(np.array([1e-7, 2.0]))
    '(1e-07, 2)'
    """
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        fields = ", ".join(
            f"{f.name}={plain(getattr(value, f.name), digits)}" for f in dataclasses.fields(value)
        )
        return f"{type(value).__name__}({fields})"
    if isinstance(value, (str, bytes)) or value is None:
        return str(value)
    if isinstance(value, (bool, np.bool_)):
        return str(bool(value))
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    if isinstance(value, (float, np.floating)):
        return f"{float(value):.{digits}g}"
    if isinstance(value, (tuple, list, np.ndarray)):
        return "(" + ", ".join(plain(v, digits) for v in np.asarray(value, dtype=object).ravel()) + ")"
    return str(value)


def as_float_array(name: str, value, *, ndim: int | None = None, shape=None) -> np.ndarray:
    """Convert ``value`` to a float64 array and check its rank, shape and finiteness.

    Parameters
    ----------
    name : str
        The parameter's name, used in the error message.
    value : array_like
        The value to check.
    ndim : int, optional
        Required number of dimensions.
    shape : tuple, optional
        Required shape; ``None`` entries match any length.

    Examples
    --------
    >>> as_float_array("pitch", [0.25]).shape
    (1,)
    """
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise TranslucencyError(f"{name}: expected numbers, got {type(value).__name__}") from None
    if ndim is not None and arr.ndim != ndim:
        raise TranslucencyError(f"{name}: expected {ndim} dimensions, got shape {arr.shape}")
    if shape is not None:
        if arr.ndim != len(shape) or any(s is not None and s != a for s, a in zip(shape, arr.shape)):
            want = ", ".join("*" if s is None else str(s) for s in shape)
            want = f"({want},)" if len(shape) == 1 else f"({want})"
            raise TranslucencyError(f"{name}: expected shape {want}, got {arr.shape}")
    check_finite(name, arr)
    return arr


def check_finite(name: str, arr: np.ndarray) -> None:
    """Raise if ``arr`` holds a NaN or an infinity, naming the first bad index."""
    bad = ~np.isfinite(arr)
    if bad.any():
        idx = tuple(int(i) for i in np.argwhere(bad)[0])
        raise TranslucencyError(f"{name}: non-finite value {arr[idx]} at index {idx}")


def check_nonnegative(name: str, arr: np.ndarray) -> None:
    """Raise if ``arr`` holds a negative entry, naming the first one."""
    bad = arr < 0
    if bad.any():
        idx = tuple(int(i) for i in np.argwhere(bad)[0])
        raise TranslucencyError(f"{name}: negative value {arr[idx]:g} at index {idx}; must be >= 0")


def check_positive(name: str, arr: np.ndarray) -> None:
    """Raise if ``arr`` holds an entry <= 0, naming the first one."""
    bad = ~(arr > 0)
    if bad.any():
        idx = tuple(int(i) for i in np.argwhere(bad)[0])
        raise TranslucencyError(f"{name}: value {arr[idx]:g} at index {idx}; must be > 0")


def as_index_array(name: str, value, n: int) -> np.ndarray:
    """Convert ``value`` to an int64 index array with entries in ``[0, n)``."""
    arr = np.asarray(value)
    if arr.dtype.kind not in "iu":
        raise TranslucencyError(f"{name}: expected integer indices, got dtype {arr.dtype}")
    arr = arr.astype(np.int64)
    bad = (arr < 0) | (arr >= n)
    if bad.any():
        idx = tuple(int(i) for i in np.argwhere(bad)[0])
        raise TranslucencyError(f"{name}: index {arr[idx]} at {idx} out of range [0, {n})")
    return arr


def check_option(name: str, value, *, lo=None, hi=None, open_lo: bool = False, open_hi: bool = False):
    """A number given on the command line or to an API boundary: finite and within [lo, hi].

    ``open_lo``/``open_hi`` exclude the bound itself.  Raises one line naming the option: the Python
    argument in the library (``spp: must be >= 1, got 0``), the flag on the command line (``--spp``).
    Returns ``value`` unchanged (None passes: "not given").

    Examples
    --------
    >>> check_option("spp", 16, lo=1)
    16
    >>> check_option("eta", 0.0, lo=0, open_lo=True)
    Traceback (most recent call last):
    ...
    translucency._validate.TranslucencyError: eta: must be > 0, got 0.0
    """
    if value is None:
        return value
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise TranslucencyError(f"{name}: expected a number, got {value!r}") from None
    if not np.isfinite(v):
        raise TranslucencyError(f"{name}: must be a finite number, got {value!r}")
    if lo is not None and (v <= lo if open_lo else v < lo):
        raise TranslucencyError(f"{name}: must be {'>' if open_lo else '>='} {lo:g}, got {value!r}")
    if hi is not None and (v >= hi if open_hi else v > hi):
        raise TranslucencyError(f"{name}: must be {'<' if open_hi else '<='} {hi:g}, got {value!r}")
    return value


def check_undamaged(dataset) -> None:
    """Refuse a data set with missing or undecodable chunks (``dataset.damaged_chunks()``) in one line;
    re-running the acquisition with the same arguments repairs exactly those chunks."""
    damaged = dataset.damaged_chunks()
    if damaged:
        listed = ", ".join(f"{k!r} chunks {v}" for k, v in damaged.items())
        raise TranslucencyError(
            f"{dataset.path}: damaged data set ({listed} missing or undecodable); the acquisition is "
            "unfinished: re-run it with the same arguments to repair those chunks"
        )
