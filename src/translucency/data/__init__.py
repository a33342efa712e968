"""Data shipped with the package (regenerate all of it with ``make default-data``:
:func:`translucency.pipeline.write_default_data`, about 10 minutes on 2 quiet cores).

The sample is :func:`translucency.pipeline.demo_volume`: the generated ``marble`` slab (32 × 32 × 10 mm,
0.25 mm voxels, seed 1) with a fibrous band (clear lamellae along x) above y = 17 mm.  The scan: 32 × 32
incident points 0.5 mm apart over the central 16 mm, 0.25 mm pixels, 33 × 33-pixel (8.25 mm) windows,
float16.

``marble_default.zarr``
    The embedded default measurement (the data the main job fits): 20,000 photons per point and channel,
    photon seed 1.
``marble_default_truth.zarr``
    Its held-out truth: the same sample and points, an independent acquisition (photon seed 2) with
    60,000 photons per point and channel.
``marble_default_fine_profiles.npz``
    Ring-averaged R_d(r) on 0.05 mm rings (r < 2 mm) around Figure 1's four profile points, 400,000
    photons per point and channel (photon seed 3): the near-x_i shape the pixels cannot resolve.
"""

from importlib.resources import files
from pathlib import Path

from ..io.dataset import PlanarDataset, open_dataset

DATA_DIR = Path(str(files("translucency") / "data"))


def default_dataset_path() -> Path:
    """Path of the embedded default data set (the fitted scan).

    Examples
    --------
    >>> p = default_dataset_path()
    >>> p.name, p.parent == DATA_DIR, p.is_dir()   # a Zarr store is a folder
    ('marble_default.zarr', True, True)
    """
    return DATA_DIR / "marble_default.zarr"


def default_truth_path() -> Path:
    """Path of the embedded data set's held-out truth (same sample and points, independent photons).

    Examples
    --------
    >>> default_truth_path().name, default_truth_path().is_dir()
    ('marble_default_truth.zarr', True)
    """
    return DATA_DIR / "marble_default_truth.zarr"


def default_fine_profiles_path() -> Path:
    """Path of the fine near-x_i ring profiles of Figure 1 (``.npz``).

    Examples
    --------
    >>> p = default_fine_profiles_path()
    >>> p.suffix, p.is_file()
    ('.npz', True)
    """
    return DATA_DIR / "marble_default_fine_profiles.npz"


def default_dataset() -> PlanarDataset:
    """The embedded default data set, opened (1024 incident points, 33 × 33-pixel windows).

    Examples
    --------
    >>> default_dataset().n_points
    1024
    """
    return open_dataset(default_dataset_path())


def default_truth() -> PlanarDataset:
    """The embedded data set's held-out truth, opened (the same sample and points, independent photons).

    Examples
    --------
    >>> truth, data = default_truth(), default_dataset()
    >>> truth.n_points == data.n_points   # the same points ...
    True
    >>> [(d.header["acquisition"][k]) for d in (data, truth) for k in ("photons", "seed")]   # ... new photons
    [20000, 1, 60000, 2]
    """
    return open_dataset(default_truth_path())
