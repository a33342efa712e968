r"""Time before work: how long a command will take on this machine, and its calibration.

Every command that works prints "about N s" before it starts: the seconds per unit of work of
:data:`TIME_TERMS` (measured on the development machine) times this machine's factor for the command
— the median of its own latest runs here of a similar size (:func:`record_time`, within
:data:`SIMILAR_SIZE` of this run's formula seconds), cached in :func:`timing_file`.  Without such runs
(a first run on this machine, or work of another size) the factor comes from a probe of the machine's
speed and the estimate says it is uncalibrated: a noisy probe, a material that walks faster or slower
than the formula's, Mitsuba compiling its kernels into an empty ``~/.drjit`` — none of these is
known before a run here.  The clock runs from the estimate to the end of the work; the seconds the
command had spent before it (imports, reading the mesh, generating the filling) are stated beside it.

Examples
--------
>>> est = TimeEstimate(90.0, "calibrated on this machine by 3 earlier runs")
>>> est.text()
'about 90 s (calibrated on this machine by 3 earlier runs)'
"""

from __future__ import annotations

import json
import math
import os
import platform
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..io.atomic import atomic_path
from .memory import transport_pairs

#: seconds per unit of work of each command, measured on the development machine (2 shared cores); each
#: machine calibrates its own factor on top of them (:func:`estimate_time`)
TIME_TERMS = {
    # photon_steps: Σ over points, photons and channels of the steps of a walk, counted by a probe of the
    # walk on the volume (translucency.acquire.estimate_seconds at one step a second); points: each point's
    # window and its writes.  Before a first run, the probe's own seconds a step set the factor.
    "acquire planar": {"overhead": 0.4, "points": 0.015, "photon_steps": 2.7e-7, "pixels": 2e-6},
    # photons: points x photons x 3 channels; point_vertices: each point's tally over the mesh;
    # first_run: an empty ~/.drjit (Dr.Jit compiles the walk's kernels)
    "acquire mesh": {
        "overhead": 0.8,
        "points": 0.05,
        "photons": 1.5e-5,
        "point_vertices": 2e-7,
        "first_run": 1.5,
    },
    # "fit <family>": each model family states its own (``Family.time_terms``, registered by
    # translucency.fit.families through :func:`register_terms`)
    # point_pixels: points x window pixels x data sets (2 with --truth); model_pixels: the same per model;
    # param_pixels: Σ over models of parameters a point x points x pixels x data sets; models: their figures
    "evaluate": {
        "overhead": 1.2,
        "point_pixels": 2e-7,
        "model_pixels": 3e-7,
        "param_pixels": 3e-8,
        "models": 0.5,
    },
    # pairs: points x vertices x data sets x models of a mesh evaluation; models: each one's figure and sums
    "evaluate mesh": {"overhead": 1.5, "pairs": 1.5e-6, "models": 1.0},
    # pairs: vertex pairs of the transport; samples: picture pixels x 16; reference_samples: 2 x pixels x spp.
    # first_run: the seconds a run adds while the kernel caches are cold (a fresh clone: Numba compiles
    # the transport's kernels, measured 8-10 s here; Dr.Jit its own into an empty ~/.drjit, 1-2 s)
    "render": {
        "overhead": 1.5,
        "vertices": 2e-4,
        "pairs": 5e-7,
        "samples": 3e-7,
        "reference_samples": 2e-6,
        "first_run": 9.0,
    },
    # render --scene: pairs of the transports; paths: vertices x samples x passes (path-traced irradiance);
    # samples: picture pixels x spp; reference_samples: 2 x pixels x spp x 3 channels (volpath; the
    # filling's albedo moves it by 10x, marble measured); first_run: Dr.Jit compiles the integrator
    "render scene": {
        "overhead": 2.0,
        "vertices": 2e-4,
        "pairs": 5e-7,
        "paths": 1.5e-6,
        "samples": 3e-7,
        "reference_samples": 5e-5,
        "first_run": 5.0,
    },
}


def register_terms(terms: dict) -> None:
    """Add the seconds per unit of work of further commands to :data:`TIME_TERMS` (``{command: terms}``).

    The stage that defines a kind of work states its cost (e.g. each fit family its seconds per
    point-pixel) so that adding a family touches its own module only.
    """
    TIME_TERMS.update({command: dict(t) for command, t in terms.items()})


#: seconds the machine probe took on the development machine
PROBE_REFERENCE_S = 0.45
#: the cache's key of the probe's seconds (a new key whenever the probe's work changes: a cached value
#: of another probe would scale every first estimate by the wrong factor)
PROBE_KEY = "probe_v2_s"
#: how many of a command's latest runs calibrate it
CALIBRATION_RUNS = 5
#: runs whose formula seconds lie within this factor of a new run's calibrate it (a run 20x smaller is
#: dominated by other terms than a large one: its factor says little about it)
SIMILAR_SIZE = 8.0
#: the cache's key of the recorded runs, [formula seconds, actual/formula] each (a key of its own: the bare
#: factors of older versions, without their size, stay under "runs" and are not read)
RUNS_KEY = "sized_runs"
#: what an estimate without a calibrating run says
UNCALIBRATED = "uncalibrated"


@dataclass
class TimeEstimate:
    """The time a command is expected to take, and where its calibration came from.

    Examples
    --------
    >>> TimeEstimate(150.0, "uncalibrated: first run here").text()   # minutes from 120 s on
    'about 2 min (uncalibrated: first run here)'
    >>> TimeEstimate(30.0, "calibrated on this machine by 2 earlier runs", startup=5.0).text()
    'about 35 s in all (5 s of it so far; calibrated on this machine by 2 earlier runs)'
    """

    seconds: float
    source: str
    #: seconds the process had already spent when the estimate was made (imports, reading the inputs,
    #: generating a sample): shown in the text, which states the whole command's time (what a user
    #: measures), not counted in ``seconds``
    startup: float = 0.0

    def text(self) -> str:
        if self.startup < 1.0:
            return f"about {_amount(self.seconds)} ({self.source})"
        total = _amount(self.seconds + self.startup)
        return f"about {total} in all ({self.startup:.0f} s of it so far; {self.source})"

    def as_dict(self) -> dict:
        out = {"seconds": round(self.seconds, 3), "source": self.source}
        return {**out, "startup_seconds": round(self.startup, 3)} if self.startup else out


def _amount(s: float) -> str:
    return f"{s:.0f} s" if s < 120 else f"{s / 60:.0f} min" if s < 7200 else f"{s / 3600:.1f} h"


def process_seconds() -> float:
    """Seconds since this process started (Linux: from ``/proc``; 0 where that is not known)."""
    try:
        after_name = Path("/proc/self/stat").read_text().rsplit(")", 1)[1].split()
        started = int(after_name[19]) / os.sysconf("SC_CLK_TCK")  # field 22: start time after boot
        uptime = float(Path("/proc/uptime").read_text().split()[0])
    except (OSError, ValueError, IndexError, AttributeError):
        return 0.0
    return max(0.0, uptime - started)


def timing_file() -> Path:
    """The time calibration per machine: ``$TRANSLUCENCY_CACHE/timing.json`` (default ``~/.cache/...``)."""
    root = os.environ.get("TRANSLUCENCY_CACHE") or Path.home() / ".cache" / "translucency"
    return Path(root) / "timing.json"


def _machine() -> str:
    return f"{platform.node()}|{platform.machine()}|{os.cpu_count()}"


def _read_timing() -> dict:
    try:
        data = json.loads(timing_file().read_text())
    except (OSError, ValueError):
        return {}
    entry = data.get(_machine()) if isinstance(data, dict) else None
    return entry if isinstance(entry, dict) else {}


def _write_timing(entry: dict) -> None:
    """Store this machine's calibration (atomically; a cache that cannot be written is skipped)."""
    path = timing_file()
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        try:
            data = json.loads(path.read_text())
            data = data if isinstance(data, dict) else {}
        except (OSError, ValueError):
            data = {}
        data[_machine()] = entry
        with atomic_path(path) as tmp:
            tmp.write_text(json.dumps(data, indent=1))
    except OSError:
        pass


def _probe_seconds() -> float:
    """A short probe of this machine's speed (≈ 0.45 s on the development machine): the kind of array
    work the commands do (exponentials, sums, a small matrix product), best of three."""
    x = np.linspace(0.0, 5.0, 400_000)
    a = np.random.default_rng(0).random((160, 160))
    best = math.inf
    for _ in range(3):
        t = time.perf_counter()
        for _ in range(8):
            y = np.exp(-x) * x
            float(y.sum())
            a = a @ a
            a /= np.abs(a).max()
        best = min(best, time.perf_counter() - t)
    return best * 3


def _raw_seconds(command: str, units: dict) -> float:
    terms = TIME_TERMS[command]
    return terms.get("overhead", 0.0) + sum(terms[k] * float(v) for k, v in units.items())


def kernel_caches_cold() -> bool:
    """Whether a run now compiles kernels that later runs load: Dr.Jit's cache (``~/.drjit``) is empty,
    or Numba has cached none of the package's functions (beside its modules, or in ``NUMBA_CACHE_DIR``)."""
    try:
        drjit_cold = not any((Path.home() / ".drjit").iterdir())
    except OSError:
        drjit_cold = True
    where = os.environ.get("NUMBA_CACHE_DIR")
    root = Path(where) if where else Path(__file__).resolve().parents[1]  # the package: its __pycache__
    numba_cold = next(root.rglob("*.nbi"), None) is None
    return drjit_cold or numba_cold


def _first_run(command: str, cold: bool) -> float:
    """The seconds of compiling kernels that a run of ``command`` adds while the caches are ``cold``."""
    return TIME_TERMS[command].get("first_run", 0.0) if cold else 0.0


def estimate_time(
    command: str, units: dict, first: tuple[float, str] | None = None, *, cold: bool = False
) -> TimeEstimate:
    """The time ``command`` will take on this machine for ``units`` of work (keys of :data:`TIME_TERMS`).

    The formula's rates (measured on the development machine) times this machine's factor for the
    command: the median of actual/formula over its latest :data:`CALIBRATION_RUNS` runs here whose
    formula seconds are within :data:`SIMILAR_SIZE` of this one's (:func:`record_time`), or, without
    such runs, ``first`` (a factor and where it came from: the command's own probe of its work, as
    ``acquire planar``'s timed walk) or else the ratio of a 0.45 s probe of the machine's speed to the
    development machine's (cached in :func:`timing_file`) — an estimate that says it is uncalibrated.

    Examples
    --------
    >>> TimeEstimate(42.0, "calibrated on this machine by 3 earlier runs").text()
    'about 42 s (calibrated on this machine by 3 earlier runs)'
    """
    raw = _raw_seconds(command, units)
    compiling = _first_run(command, cold)
    entry = _read_timing()
    runs = _runs(entry, command)
    similar = [(abs(math.log(size / raw)), ratio) for size, ratio in runs if raw > 0]
    similar = [r for d, r in sorted(similar[-4 * CALIBRATION_RUNS :]) if d <= math.log(SIMILAR_SIZE)]
    if similar:
        ratios = sorted(similar[:CALIBRATION_RUNS])
        factor = ratios[len(ratios) // 2]
        n = f"{len(ratios)} earlier run{'s' if len(ratios) > 1 else ''}"
        source = f"calibrated on this machine by {n}"
        return TimeEstimate((raw + compiling) * factor, source + _compiling(compiling))
    why = "first run here" if not runs else "earlier runs here were of another size"
    if first is not None and math.isfinite(first[0]) and first[0] > 0:
        return TimeEstimate((raw + compiling) * first[0], first[1] + _compiling(compiling))
    probe = entry.get(PROBE_KEY)
    if not isinstance(probe, (int, float)) or not probe > 0:
        probe = _probe_seconds()
        _write_timing({**entry, PROBE_KEY: probe})
    source = f"from a probe of this machine's speed; {UNCALIBRATED}: {why}{_compiling(compiling)}"
    return TimeEstimate((raw + compiling) * probe / PROBE_REFERENCE_S, source)


def _compiling(seconds: float) -> str:
    return f"; with about {seconds:.0f} s of compiling kernels on a first run" if seconds else ""


def _runs(entry: dict, command: str) -> list[tuple[float, float]]:
    """(formula seconds, actual/formula) of the command's recorded runs (oldest first)."""
    runs = entry.get(RUNS_KEY) if isinstance(entry.get(RUNS_KEY), dict) else {}
    kept = []
    for r in runs.get(command, []) if isinstance(runs.get(command), list) else []:
        if isinstance(r, list) and len(r) == 2 and all(isinstance(v, (int, float)) and v > 0 for v in r):
            kept.append((float(r[0]), float(r[1])))
    return kept


def record_time(command: str, units: dict, seconds: float, *, cold: bool = False) -> None:
    """Calibrate ``command`` on this machine with the ``seconds`` a run of ``units`` really took (``cold``:
    the run compiled its kernels: their :data:`TIME_TERMS` ``first_run`` seconds are part of it).

    Examples
    --------
    >>> import os, tempfile
    >>> from unittest import mock
    >>> units = {"pairs": 1e6, "models": 1}   # ``evaluate mesh``: 1.5 s + 1.5e-6 s × 10⁶ + 1 s = 4 s here
    >>> with tempfile.TemporaryDirectory() as cache, mock.patch.dict(os.environ, TRANSLUCENCY_CACHE=cache):
    ...     record_time("evaluate mesh", units, 8.0)   # this machine took twice the formula's time
    ...     estimate = estimate_time("evaluate mesh", units)
    >>> estimate.text()   # the next run of that size: 4 s × 2
    'about 8 s (calibrated on this machine by 1 earlier run)'
    """
    raw = _raw_seconds(command, units) + _first_run(command, cold)
    if not (raw > 0 and math.isfinite(seconds) and seconds > 0):
        return
    entry = _read_timing()
    runs = entry.get(RUNS_KEY) if isinstance(entry.get(RUNS_KEY), dict) else {}
    kept = [list(r) for r in _runs(entry, command)][-(4 * CALIBRATION_RUNS - 1) :]
    runs[command] = kept + [[raw, seconds / raw]]
    _write_timing({**entry, RUNS_KEY: runs})


def probe_factor(command: str, term: str, seconds_per_unit: float) -> float:
    """The factor of ``command`` on this machine from a probe of its own work: the probe's seconds per
    unit of ``term`` over the development machine's (a first estimate before any run here)."""
    return seconds_per_unit / TIME_TERMS[command][term]


# -- the units of work of each command (the keys of TIME_TERMS) -----------------------------------------
def planar_acquisition_units(*, points: int, photon_steps: float, pixels: int) -> dict:
    """``acquire planar``: P points, the probe's photon steps (Σ over points, photons and channels) and the
    P·n² pixels of the windows."""
    return {"points": points, "photon_steps": photon_steps, "pixels": pixels}


def mesh_acquisition_units(*, points: int, photons: int, vertices: int) -> dict:
    """``acquire mesh``: P points (those left to acquire), N photons a point and channel, V vertices."""
    return {"points": points, "photons": 3 * points * photons, "point_vertices": points * vertices}


def fit_units(*, points: int, pixels: int, rounds: int) -> dict:
    """``fit``: P points x J window pixels (or vertices) x rounds (a chosen structure's candidates are in
    the "fit auto" terms)."""
    return {"point_pixels": points * pixels * rounds}


def evaluation_units(*, points: int, pixels: int, params: list[int], datasets: int = 1) -> dict:
    """``evaluate``: P points of J pixels, models of π_p parameters a point, d data sets (2: ``--truth``)."""
    d = datasets
    return {
        "point_pixels": points * pixels * d,
        "model_pixels": len(params) * points * pixels * d,
        "param_pixels": sum(params) * points * pixels * d,
        "models": len(params),
    }


def mesh_evaluation_units(*, points: int, vertices: int, models: int, datasets: int = 1) -> dict:
    """``evaluate`` on a mesh data set: pairs = points x vertices x data sets (2: ``--truth``) x models."""
    return {"pairs": points * vertices * datasets * models, "models": models}


def rendering_units(
    *,
    vertices: int,
    surface_mm2: float,
    radius_mm: float,
    width: int,
    height: int,
    reference: bool,
    spp_reference: int,
    max_pairs: float,
) -> dict:
    """``render``: V vertices, the transport's pairs within the radius, a W x H picture (16 samples a pixel),
    and the two path-traced references of ``spp_reference`` samples a pixel with ``--reference``."""
    return {
        "vertices": vertices,
        "pairs": transport_pairs(
            vertices=vertices, surface_mm2=surface_mm2, radius_mm=radius_mm, max_pairs=max_pairs
        ),
        "samples": 16 * width * height,
        "reference_samples": 2 * width * height * spp_reference if reference else 0,
    }
