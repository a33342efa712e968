"""Matplotlib on the Agg backend, for every figure the package writes (PNG files, no display)."""

from __future__ import annotations


def pyplot():
    """``matplotlib.pyplot`` with the Agg backend selected.

    Imported on first use, not with the package: matplotlib takes a noticeable
    time to load, and selecting a backend at import time would override the
    choice of a user's interactive session.
    """
    import matplotlib  # heavy, and the backend must be chosen before pyplot is imported

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # after the backend: pyplot reads it when it first loads

    return plt
