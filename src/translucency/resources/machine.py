r"""Sizes and the machine: the :class:`Need` record the estimates return, the byte units, the ``--max-memory``
option's sizes, and the memory the machine has (:mod:`.memory` estimates and checks against them).

Examples
--------
>>> parse_size("--max-memory", "4G")
4294967296
>>> Need(memory=GiB, disk=0, what="the volume").as_dict()["memory_bytes"]
1073741824
"""

from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass

from .._validate import TranslucencyError

MiB = 2**20
GiB = 2**30

#: the process before the work: Python, NumPy, SciPy, Numba, Zarr, Rich (measured 230–245 MiB)
BASE = 240 * MiB
#: ... and with Mitsuba 3 and Dr.Jit loaded, their LLVM JIT and kernel cache (measured 277–285 MiB)
BASE_MITSUBA = 280 * MiB

_UNITS = {"": 1, "B": 1, "K": 2**10, "M": 2**20, "G": 2**30, "T": 2**40}


@dataclass
class Need:
    """What a command needs: peak ``memory`` and ``disk`` (output) in bytes, and what dominates.

    Examples
    --------
    >>> Need(memory=1.5 * GiB, disk=2 * MiB, what="the windows").as_dict()
    {'memory_bytes': 1610612736, 'disk_bytes': 2097152, 'dominated_by': 'the windows'}
    """

    memory: float
    disk: float
    what: str

    def as_dict(self) -> dict:
        return {"memory_bytes": int(self.memory), "disk_bytes": int(self.disk), "dominated_by": self.what}


def parse_size(option: str, text) -> int:
    """A size such as ``4G``, ``512M``, ``1.5GiB``, ``2TB`` or a number of bytes; binary units (G = 2³⁰).

    Examples
    --------
    >>> parse_size("--max-memory", "512M")
    536870912
    >>> parse_size("--max-memory", "lots")
    Traceback (most recent call last):
    ...
    translucency._validate.TranslucencyError: --max-memory: expected a size such as 4G or 512M, got 'lots'
    """
    m = re.fullmatch(r"\s*([0-9]*\.?[0-9]+(?:[eE][+-]?[0-9]+)?)\s*([kKmMgGtT]?)(?:i?[bB])?\s*", str(text))
    if m is None:
        raise TranslucencyError(f"{option}: expected a size such as 4G or 512M, got {text!r}")
    value = float(m.group(1)) * _UNITS[m.group(2).upper()]
    if not (math.isfinite(value) and value >= MiB):
        raise TranslucencyError(f"{option}: must be at least 1M, got {text!r}")
    return int(value)


def memory_limit(text) -> int | None:
    """``--max-memory``: its size in bytes, or None when not given (the machine's available memory).

    Examples
    --------
    >>> memory_limit("4G")
    4294967296
    >>> memory_limit(None) is None
    True
    """
    return None if text is None else parse_size("--max-memory", text)


def _meminfo(field: str, pages: str) -> int | None:
    """A field of ``/proc/meminfo`` in bytes, else ``sysconf(pages)`` pages, else None."""
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith(field + ":"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return int(os.sysconf(pages) * os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):
        return None


def available_memory() -> int | None:
    """The memory the machine can give a new process now (``MemAvailable``), or None if unknown."""
    return _meminfo("MemAvailable", "SC_AVPHYS_PAGES")


def total_memory() -> int | None:
    """The machine's physical memory (``MemTotal``), or None if unknown."""
    return _meminfo("MemTotal", "SC_PHYS_PAGES")
