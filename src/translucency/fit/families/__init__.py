"""The model families of the fit, one object per family behind one protocol (:class:`Family`).

A new family is one module here (a :class:`Family` subclass) and one line in :data:`FAMILIES`
(with its import); a new kind of model also needs its model class in :mod:`translucency.model`
(with its storage, :data:`translucency.model.MODEL_KINDS`).
"""

from ...resources.timing import register_terms
from ._base import AUTO_DIRECTIONS, AUTO_TERMS, Family
from .aniso import AnisoFamily
from .burley import BurleyFamily
from .ddipole import DirectionalDipoleFamily
from .dipole import DipoleFamily
from .iso import IsoFamily
from .pbd import PBDFamily

#: the model families by name, in the order the CLI lists them
FAMILIES: dict[str, Family] = {
    f.name: f
    for f in (
        IsoFamily(),
        AnisoFamily(),
        DipoleFamily(),
        BurleyFamily(),
        PBDFamily(),
        DirectionalDipoleFamily(),
    )
}

# each family's seconds per point-pixel for the time estimate of ``translucency fit --model NAME``
register_terms({f"fit {name}": family.time_terms for name, family in FAMILIES.items()})

__all__ = ["AUTO_DIRECTIONS", "AUTO_TERMS", "FAMILIES", "Family"]
