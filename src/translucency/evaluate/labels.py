"""Short names the report, its figures and the command line show: of fitted models, and of the noise
the errors are measured against."""

from __future__ import annotations


def model_label(model) -> str:
    """A short name: 'iso n=3 (shared colour)', 'aniso m=8 n=3', 'dipole', 'burley'."""
    if model.kind != "exponential":
        return model.kind
    shape = "iso" if model.n_directions == 1 else f"aniso m={model.n_directions}"
    return f"{shape} n={model.n_terms}" + (" (shared colour)" if model.colour == "shared" else "")


def noise_label(held_out: bool) -> str:
    """The noise of the reference the errors are measured against: an independent truth's (held out), or
    the fitted data's own (in-sample, no truth given).

    Examples
    --------
    >>> noise_label(True), noise_label(False)
    ("the truth's noise", "the data's own noise")
    """
    return "the truth's noise" if held_out else "the data's own noise"


def labelled_models(models) -> dict:
    """``models`` as a dict label -> model: a dict as given; a model or a sequence of them by
    :func:`model_label`."""
    if isinstance(models, dict):
        return models
    models = list(models) if isinstance(models, (list, tuple)) else [models]
    return {model_label(m): m for m in models}
