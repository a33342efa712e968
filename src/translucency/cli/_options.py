"""Options shared by several commands (:mod:`.app` and :mod:`.rig`)."""

from __future__ import annotations

import typer


def scheduler_option():
    """``--scheduler``: where work runs (acquire planar|mesh, fit, evaluate, import images)."""
    return typer.Option(
        "threads",
        "--scheduler",
        metavar="WHERE",
        help="Where work runs: threads (this process), local:N (N Dask worker processes started for this "
        "command) or tcp://HOST:PORT (a running Dask cluster; the data set's path must be visible to its "
        "workers). Results are identical whichever.",
    )
