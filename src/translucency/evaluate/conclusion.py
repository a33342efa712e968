"""The report's conclusion: a few sentences, generated from its numbers, that say what to take away.

Which model is closest to the reference and by how much, against the reference's own noise; whether an
anisotropic model's directions earn their parameters (only an independent truth can tell: in-sample,
more parameters always fit at least as well); and what the physics checks flag.  Errors are the
report's relative L2 over all pairs, RGB summed (``rel_l2``, ``beyond_noise["all"]``).
"""

from __future__ import annotations

import math

from .labels import noise_label

#: an anisotropic model's directions earn their parameters when, held out, its error beyond the truth's
#: noise is at least this fraction below the best isotropic exponential model's
EARNS = 0.10


def _finite(v) -> bool:
    return isinstance(v, (int, float)) and math.isfinite(v)


def _pc(v) -> str:
    return f"{100 * v:.2f} %" if _finite(v) else "–"


def _points(k: int) -> str:
    return f"{k} point" if k == 1 else f"{k} points"


def _beyond(s: dict):
    return (s.get("beyond_noise") or {}).get("all")


def _ranking(per_model: dict) -> list[str]:
    """Model names, lowest rel_l2 first (a model without a finite error last)."""
    return sorted(
        per_model, key=lambda n: per_model[n]["rel_l2"] if _finite(per_model[n]["rel_l2"]) else math.inf
    )


def _others(per_model: dict, order: list[str], held_out: bool) -> str:
    """The models after the first, with their errors (and beyond the noise, held out)."""
    parts = []
    for k, n in enumerate(order[1:]):
        s = per_model[n]
        beyond = f" ({_pc(_beyond(s))}{' beyond the noise' if k == 0 else ''})" if held_out else ""
        parts.append(f"{n} at {_pc(s['rel_l2'])}{beyond}")
    return ", ".join(parts)


def _coefficients(model) -> int | None:
    """Exponential coefficients (c and d) per incident point."""
    try:
        return (model.c.size + model.d.size) // model.n_points
    except AttributeError:
        return None


def _aniso_iso(per_model: dict, models: dict):
    """The best anisotropic and the best isotropic exponential model (None where there is none)."""

    def best_of(anisotropic: bool):
        names = [
            n
            for n in _ranking(per_model)
            if getattr(models.get(n), "kind", None) == "exponential"
            and (models[n].n_directions > 1) == anisotropic
        ]
        return names[0] if names else None

    return best_of(True), best_of(False)


def _held_out(per_model: dict, models: dict) -> list[str]:
    """Which model is closest to the truth, by how much beyond the truth's noise, and whether the
    anisotropic model's directions earn their parameters."""
    order = _ranking(per_model)
    best, s = order[0], per_model[order[0]]
    b = _beyond(s)
    beyond = "within" if _finite(b) and b == 0.0 else f"{_pc(b)} beyond"
    out = [
        f"Held out, against an independent acquisition: {best} is closest to the truth, "
        f"{_pc(s['rel_l2'])} relative L2 error, {beyond} {noise_label(True)} (a noise floor of "
        f"{_pc(s['noise_floor']['all'])}: what a perfect model would score)."
    ]
    if len(order) > 1:
        out.append(f"Next: {_others(per_model, order, True)}.")
    aniso, iso = _aniso_iso(per_model, models)
    pair = aniso is not None and iso is not None
    nxt = order[1] if len(order) > 1 else None
    bn = None if nxt is None else _beyond(per_model[nxt])
    if (
        nxt is not None
        and not (pair and {best, nxt} == {aniso, iso})
        and _finite(b)
        and _finite(bn)
        and bn > 0
    ):
        out.append(f"Beyond the noise {best}'s error is {100 * (1 - b / bn):.0f} % below {nxt}'s.")
    if pair:
        ba, bi = _beyond(per_model[aniso]), _beyond(per_model[iso])
        ka, ki = _coefficients(models[aniso]), _coefficients(models[iso])
        cost = f" with {ka} coefficients per point against {ki}" if ka and ki else ""
        if _finite(ba) and _finite(bi) and bi == 0.0:
            out.append(
                f"{iso} is already within the truth's noise: {aniso}'s directions have nothing to earn."
            )
        elif _finite(ba) and _finite(bi):
            gain = 1.0 - ba / bi
            if gain >= EARNS:
                verdict = "earn their parameters"
            elif gain > 0:
                verdict = "gain little for their parameters"
            else:
                verdict = "do not earn their parameters"
            how = f"{100 * gain:.0f} % below" if gain > 0 else f"{100 * -gain:.0f} % above"
            out.append(
                f"The anisotropic model's directions {verdict}: beyond the noise {aniso}'s error is {how} "
                f"{iso}'s ({_pc(ba)} against {_pc(bi)}){cost}."
            )
    return out


def _in_sample(per_model: dict, models: dict) -> list[str]:
    """Which model scores lowest in-sample, and why that says little."""
    order = _ranking(per_model)
    best, s = order[0], per_model[order[0]]
    others = f"; next {_others(per_model, order, False)}" if len(order) > 1 else ""
    out = [
        f"In-sample, against the data the models were fitted to (no independent truth given): {best} scores "
        f"lowest, {_pc(s['rel_l2'])} relative L2 error, where {noise_label(False)} alone gives "
        f"{_pc(s['noise_floor']['all'])} (the noise floor){others}."
    ]
    aniso, iso = _aniso_iso(per_model, models)
    ka = None if aniso is None else _coefficients(models[aniso])
    ki = None if iso is None else _coefficients(models[iso])
    directions = (
        " nor whether the anisotropic model's directions earn their parameters"
        + (f" ({ka} coefficients per point against {ki})" if ka and ki else "")
        if aniso is not None and iso is not None
        else ""
    )
    out.append(
        "In-sample, a model that follows the noise scores well and more parameters always fit at least as "
        f"well, so neither this ranking{directions} can be read from it: evaluate against an independent "
        "acquisition (evaluate --truth)."
    )
    return out


def _physics(per_model: dict, n_points: int) -> list[str]:
    """What the physics checks (:func:`translucency.model.bounds.check_physics`) and the fits flagged."""
    over, beyond, clean = [], [], []
    for name, s in per_model.items():
        ph = s.get("physics") or {}
        n_over, n_beyond = len(ph.get("over_albedo") or []), len(ph.get("beyond_object") or [])
        rho = ph.get("max_total_reflectance")
        if n_over:
            over.append(f"{_points(n_over)} of {name}" + (f" (up to {rho:.3g})" if _finite(rho) else ""))
        if n_beyond:
            beyond.append(f"{_points(n_beyond) if not beyond else n_beyond} of {name}")
        if not (n_over or n_beyond):
            clean.append(name)
    if not (over or beyond):
        out = [
            "Physics checks: every model reflects at most the light it receives and keeps most of its "
            "energy within the sample at every point."
        ]
    else:
        parts = []
        if over:
            parts.append(f"more light out than in (total reflectance > 1) at {', '.join(over)}")
        if beyond:
            parts.append(f"over half of a point's energy beyond the sample at {', '.join(beyond)}")
        text = f"Physics checks (of {n_points} points): " + "; ".join(parts)
        if clean:
            text += f"; {', '.join(clean)} {'passes' if len(clean) == 1 else 'pass'} every check"
        out = [text + "."]
    flagged = {n: len(s.get("flagged_points") or []) for n, s in per_model.items()}
    if any(flagged.values()):
        listed = ", ".join(f"{n} {k}" for n, k in flagged.items() if k)
        out.append(f"Points the fits flagged, left out of the errors: {listed}.")
    return out


def conclusion(per_model: dict, models: dict, *, held_out: bool, n_points: int) -> str:
    """The report's summary in a few sentences (``report.json`` ``"summary"``, the top of the page).

    Parameters
    ----------
    per_model : dict
        Label -> the model's numbers (``report.json`` ``"models"``: rel_l2, noise_floor, beyond_noise,
        physics, flagged_points).
    models : dict
        Label -> the fitted model (its family and number of directions).
    held_out : bool
        Whether the numbers are against an independent truth (else in-sample, against the fitted data).
    n_points : int
        Incident points of the data set.

    Examples
    --------
    >>> s = {"rel_l2": 0.1, "noise_floor": {"all": 0.06}, "beyond_noise": {"all": 0.08}}
    >>> conclusion({"dipole": s}, {}, held_out=True, n_points=4)[:64]
    'Held out, against an independent acquisition: dipole is closest '
    """
    errors = _held_out(per_model, models) if held_out else _in_sample(per_model, models)
    return " ".join([*errors, *_physics(per_model, n_points)])
