"""Short names the report, its figures and the command line show: of fitted models, and of the noise
the errors are measured against; and the words under the error table (:func:`table_caption`)."""

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


def table_caption(held_out: bool, where: str = "pixels") -> str:
    """What the error table's distance bands and its noise row mean, and which figure says how good a
    model is: the words ``evaluate`` prints under its table and the report's page under its own.

    ``where``: what a pair's outgoing end is, ``"pixels"`` (planar) or ``"vertices"`` (mesh).

    Examples
    --------
    >>> print(table_caption(True).split("; ")[-1])
    a model at the floor is as good as these photons can show.
    """
    bands = (
        f"near / mid / far: the {where} under 1 mm, 1-4 mm and over 4 mm from where the light enters (far is "
        "the faint tail, where photon noise dominates). "
    )
    if held_out:
        return bands + (
            f"Last row: {noise_label(True)}, the floor a perfect model would score; a model at the floor "
            "is as good as these photons can show."
        )
    return bands + (
        f"Last row: {noise_label(False)}, the floor a perfect model would score. In-sample the fit has seen "
        "this noise and can follow it, so matching the floor shows the fit converged, not that the model is "
        "right: for that, read the held-out error against its noise that the fit prints (the model file "
        "keeps it), or run evaluate --truth on an independent acquisition."
    )


def labelled_models(models) -> dict:
    """``models`` as a dict label -> model: a dict as given; a model or a sequence of them by
    :func:`model_label`."""
    if isinstance(models, dict):
        return models
    models = list(models) if isinstance(models, (list, tuple)) else [models]
    return {model_label(m): m for m in models}
