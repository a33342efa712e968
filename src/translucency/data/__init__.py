"""Data shipped with the package.

``marble_default.zarr`` — the embedded default measurement: a virtual DISCO
scan of the generated ``marble`` sample (32 × 32 × 10 mm slab, 0.25 mm voxels,
seed 1): 32 × 32 incident points over the central 16 mm, 0.25 mm pixels,
49 × 49-pixel (12.25 mm) windows, 20,000 photons per point and channel,
stored as float16 (9 MB).  Regenerate with ``make default-data``.
"""

from importlib.resources import files
from pathlib import Path


def default_dataset_path() -> Path:
    """Path of the embedded default marble data set."""
    return Path(str(files("translucency") / "data" / "marble_default.zarr"))
