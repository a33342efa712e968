"""Start Dr.Jit / Mitsuba 3 on the right backend.

On the CPU, Dr.Jit's LLVM backend needs a libLLVM >= 16.  We take it from the
``karellen-llvm-core`` wheel (PyPI), so nothing has to come from apt:
``DRJIT_LIBLLVM_PATH`` must point at it *before* drjit is imported.  A CUDA
device, when present, is used automatically (``TRANSLUCENCY_BACKEND=llvm`` or
``=cuda`` forces one).
"""

from __future__ import annotations

import os
from functools import lru_cache
from importlib.metadata import PackageNotFoundError, distribution, version

from .._validate import TranslucencyError


def _find_libllvm() -> str | None:
    """Path of libLLVM.so shipped by the karellen-llvm-core wheel, if installed."""
    try:
        dist = distribution("karellen-llvm-core")
    except PackageNotFoundError:
        return None
    for f in dist.files or ():
        if f.name.startswith("libLLVM") and ".so" in f.name:
            path = os.path.realpath(dist.locate_file(f))
            if os.path.exists(path):
                return path
    return None


#: the oldest libLLVM that compiles every kernel of the package (15 aborts on ``fminimum``)
MIN_LLVM = (16,)


def prepare_libllvm() -> None:
    """Point Dr.Jit at the wheel's libLLVM (``DRJIT_LIBLLVM_PATH``) unless the user chose one.

    Called when translucency is imported, so that a later ``import mitsuba`` in the same process
    loads the right library too; it has no effect once Dr.Jit has loaded one.

    Examples
    --------
    >>> from unittest import mock
    >>> with mock.patch.dict(os.environ, DRJIT_LIBLLVM_PATH="/opt/llvm/libLLVM.so"):
    ...     prepare_libllvm()   # the user's choice stays
    ...     print(os.environ["DRJIT_LIBLLVM_PATH"])
    /opt/llvm/libLLVM.so
    """
    if "DRJIT_LIBLLVM_PATH" not in os.environ:
        lib = _find_libllvm()
        if lib:
            os.environ["DRJIT_LIBLLVM_PATH"] = lib


@lru_cache(maxsize=1)
def mitsuba(variant: str | None = None):
    """Import Mitsuba 3 with a suitable variant and return the module.

    ``variant`` defaults to ``cuda_ad_rgb`` when a CUDA device works and to
    ``llvm_ad_rgb`` otherwise.

    Examples
    --------
    >>> mi = mitsuba()
    >>> mi.variant() in ("llvm_ad_rgb", "cuda_ad_rgb"), mitsuba() is mi   # loaded once, then cached
    (True, True)
    """
    prepare_libllvm()
    try:  # imported here: DRJIT_LIBLLVM_PATH must be set first, and loading Dr.Jit/Mitsuba takes seconds
        import drjit as dr
        import mitsuba as mi
    except ImportError as exc:  # pragma: no cover - dependency missing
        raise TranslucencyError(f"mitsuba/drjit not importable ({exc}); reinstall translucency") from None
    forced = os.environ.get("TRANSLUCENCY_BACKEND", "").lower()
    if variant is None:
        cuda_ok = forced != "llvm" and dr.has_backend(dr.JitBackend.CUDA)
        if forced == "cuda" and not cuda_ok:
            raise TranslucencyError("TRANSLUCENCY_BACKEND=cuda, but no CUDA device is available")
        variant = "cuda_ad_rgb" if cuda_ok else "llvm_ad_rgb"
    if variant.startswith("llvm") and not dr.has_backend(dr.JitBackend.LLVM):
        raise TranslucencyError(
            "Dr.Jit's LLVM backend is unavailable: libLLVM >= 16 not found "
            "(install karellen-llvm-core or set DRJIT_LIBLLVM_PATH)"
        )
    llvm = getattr(getattr(dr, "detail", None), "llvm_version", lambda: None)()
    if variant.startswith("llvm") and llvm is not None and tuple(llvm) < MIN_LLVM:
        # an older libLLVM aborts the whole process on some of our kernels (fminimum): say so instead
        raise TranslucencyError(
            f"Dr.Jit already runs on libLLVM {'.'.join(map(str, llvm))}, which cannot compile our kernels "
            f"(needs {MIN_LLVM[0]}+): Mitsuba or Dr.Jit was imported before translucency; import "
            f"translucency first, or start Python with "
            f"DRJIT_LIBLLVM_PATH={_find_libllvm() or '<libLLVM 16+>'}"
        )
    mi.set_variant(variant)
    return mi


def engine_versions() -> dict:
    """Versions of Mitsuba and Dr.Jit (for provenance in data sets).

    Examples
    --------
    >>> v = engine_versions()
    >>> sorted(v), v["mitsuba"].split(".")[0]   # Mitsuba 3
    (['drjit', 'mitsuba'], '3')
    """
    out = {}
    for pkg in ("mitsuba", "drjit"):
        try:
            out[pkg] = version(pkg)
        except PackageNotFoundError:
            out[pkg] = "unknown"
    return out


def drjit():
    """The ``drjit`` module, loaded (with Mitsuba) by :func:`mitsuba` on the libLLVM chosen there.

    Examples
    --------
    >>> dr = drjit()
    >>> float(dr.sum(dr.arange(mitsuba().Float, 4))[0])   # 0 + 1 + 2 + 3 on the chosen backend
    6.0
    """
    mitsuba()
    import drjit as dr  # after mitsuba(): Dr.Jit must load with the libLLVM chosen there

    return dr
