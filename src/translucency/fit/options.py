"""The options of a fit (checked at the API boundary) and its result; what every chunk shares is
:mod:`.context`."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .._validate import TranslucencyError
from .families import AUTO_DIRECTIONS, AUTO_TERMS, FAMILIES

__all__ = [
    "AUTO_DIRECTIONS",
    "AUTO_TERMS",
    "KINDS",
    "WEIGHTINGS",
    "FitResult",
    "check_fit_options",
]

#: the built-in model families' names: isotropic and anisotropic sums of exponentials, and the baselines
#: (:data:`FAMILIES` is the registry: a family registered later is a choice too)
KINDS = tuple(FAMILIES)
#: the weightings: w⁻² = αP/(N p²) (the model's Poisson variance), or (ρ αP)² + αP/(N p²)
WEIGHTINGS = ("poisson", "relative")


@dataclass
class FitResult:
    """Result of :func:`translucency.fit.fit_planar` or :func:`translucency.fit.fit_mesh`.

    Attributes
    ----------
    model : ReflectanceModel
        The fitted model (α included).
    flagged : ndarray of bool, shape (P,)
        Incident points without usable data (all masked, NaN or zero); their
        parameters are inert (zero reflectance) and the report lists them.
    history : list of float
        Objective Φ of each round's state (parameters and α), every round under
        the same weights (those of round 1's model; with one round, round 1's own).
    seconds : float
        Wall time of the fit.
    options : dict
        The options used (stored in the model file).
    best_round : int
        The round whose state is returned (1-based): the lowest Φ under the common weights.
    acquisition : dict, optional
        The data set's header (mesh fits): what was acquired, so that a model
        file can rebuild its reference without the data set.

    Examples
    --------
    >>> result = FitResult(model=None, flagged=np.array([False, True, False]), history=[2.5, 1.25],
    ...                    seconds=3.14159, options={"model": "iso"}, best_round=2)
    >>> meta = result.metadata("scan.zarr")
    >>> meta["flagged_points"], meta["objective_per_round"], meta["seconds"]   # indices; Φ per round; s
    ([1], [2.5, 1.25], 3.14)
    """

    model: object
    flagged: np.ndarray
    history: list
    seconds: float
    options: dict = field(default_factory=dict)
    acquisition: dict | None = None
    best_round: int = 1

    def metadata(self, dataset_path) -> dict:
        """The fit's record stored beside the model: data set, options, Φ per round, time, flagged points.

        Parameters
        ----------
        dataset_path : path
            The data set that was fitted (stored as a string).

        Returns
        -------
        dict
            ``dataset``, ``fit`` (the options), ``objective_per_round``,
            ``best_round`` (the round returned), ``seconds`` (rounded to 0.01 s),
            ``flagged_points`` (indices) and, for mesh fits, ``acquisition`` (the data set's header).
        """
        meta = {
            "dataset": str(dataset_path),
            "fit": self.options,
            "objective_per_round": self.history,
            "best_round": self.best_round,
            "seconds": round(self.seconds, 2),
            "flagged_points": np.flatnonzero(self.flagged).tolist(),
        }
        if self.acquisition is not None:
            meta["acquisition"] = self.acquisition
        return meta


def check_fit_options(
    model: str,
    n_terms: int = 3,
    n_directions: int = 8,
    colour: str = "per-channel",
    rel_sigma: float = 0.05,
    weighting: str = "poisson",
) -> None:
    """Refuse bad fit options with one line naming the option (before any work).

    Examples
    --------
    >>> check_fit_options("aniso", n_terms="auto", n_directions=8)   # good options: nothing to say
    >>> check_fit_options("iso", n_terms=5)
    Traceback (most recent call last):
    ...
    translucency._validate.TranslucencyError: terms: n must be between 1 and 4 or 'auto', got 5
    >>> check_fit_options("iso", n_directions="auto")
    Traceback (most recent call last):
    ...
    translucency._validate.TranslucencyError: directions: 'auto' needs the anisotropic model, got model 'iso'
    """
    if model not in FAMILIES:
        raise TranslucencyError(f"model: expected one of {', '.join(FAMILIES)}, got {model!r}")
    if n_terms != "auto" and not 1 <= _as_count(n_terms) <= 4:
        raise TranslucencyError(f"terms: n must be between 1 and 4 or 'auto', got {n_terms!r}")
    directional = FAMILIES[model].directional
    if n_directions == "auto":
        if not directional:
            raise TranslucencyError(f"directions: 'auto' needs the anisotropic model, got model {model!r}")
    elif directional and _as_count(n_directions) < 2:
        raise TranslucencyError(f"directions: the anisotropic model needs m >= 2, got {n_directions}")
    if colour not in ("shared", "per-channel", "auto"):
        raise TranslucencyError(f"colour: expected 'shared', 'per-channel' or 'auto', got {colour!r}")
    if not (rel_sigma > 0 and np.isfinite(rel_sigma)):
        raise TranslucencyError(f"rel_sigma: must be > 0, got {rel_sigma}")
    if weighting not in WEIGHTINGS:
        raise TranslucencyError(f"weighting: expected one of {', '.join(WEIGHTINGS)}, got {weighting!r}")


def _as_count(v) -> int:
    """An integer option as int, or −1 when it is not one (so that the range checks name it)."""
    try:
        return int(v)
    except (TypeError, ValueError):
        return -1
