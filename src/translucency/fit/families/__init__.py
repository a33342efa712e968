"""The model families of the fit, one object per family behind one protocol (:class:`Family`).

A new family is one module here (a :class:`Family` subclass) and one :func:`register` line below
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

#: the model families by name, in the order the CLI lists them (filled by :func:`register`)
FAMILIES: dict[str, Family] = {}


def register(family: Family) -> Family:
    """Make ``family`` a choice of ``fit`` (``--model NAME``, ``model=NAME``): add it to :data:`FAMILIES`
    and its seconds per point-pixel to the time estimates of ``translucency fit --model NAME``.

    Parameters
    ----------
    family : Family
        An instance; its ``name`` is the key (a family of the same name is replaced).

    Returns
    -------
    Family
        ``family`` itself.

    Examples
    --------
    A variant of the isotropic family, registered and then taken out again:

    >>> from translucency.resources.timing import TIME_TERMS
    >>> class Toy(IsoFamily):
    ...     name = "toy"
    ...     time_terms = {"overhead": 0.1, "point_pixels": 2e-6}
    >>> register(Toy())
    <Toy 'toy'>
    >>> FAMILIES["toy"].params_per_point(1, 1, "shared"), TIME_TERMS["fit toy"]["point_pixels"]
    (4, 2e-06)
    >>> _ = FAMILIES.pop("toy"), TIME_TERMS.pop("fit toy")
    """
    FAMILIES[family.name] = family
    register_terms({f"fit {family.name}": family.time_terms})
    return family


def describe_families() -> str:
    """The choices of ``fit --model`` as its help lists them: each registered family's name, with its
    ``summary`` in parentheses where it has one, in the order of :data:`FAMILIES`.

    Examples
    --------
    >>> print(describe_families())  # doctest: +NORMALIZE_WHITESPACE
    iso | aniso (the paper's; planar data sets only) | dipole | burley | pbd (photon beam diffusion) |
    ddipole (directional dipole at normal incidence).
    """
    return " | ".join(f"{f.name} ({f.summary})" if f.summary else f.name for f in FAMILIES.values()) + "."


register(IsoFamily())
register(AnisoFamily())
register(DipoleFamily())
register(BurleyFamily())
register(PBDFamily())
register(DirectionalDipoleFamily())

__all__ = ["AUTO_DIRECTIONS", "AUTO_TERMS", "FAMILIES", "Family", "describe_families", "register"]
