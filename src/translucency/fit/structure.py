r"""A fit's structure chosen by held-out error: what ``fit`` does unless it is told the structure.

A *structure* is what a fit holds fixed while it solves for the parameters (:class:`Structure`): the
colour (the paper's (1, s_g, s_b) scale of one fall-off, or one fall-off per channel), the number n of
exponential terms, and the directions m (1: the isotropic model; m ≥ 2 the paper's anisotropic blend, on
planar data).  Each default the project could pick would be right on its own samples and wrong on some
user's, so the fit measures instead, on the data's own photons.

**Estimator.**  A candidate c is fitted on one half of the pairs (incident point, pixel or vertex) and
scored on the other (:mod:`.held_out`): per incident point i its held-out squared error
:math:`e_i(c)` and data norm :math:`y_i`, and the relative held-out error

.. math:: E(c) = \sqrt{\textstyle\sum_i e_i(c) / \sum_i y_i}.

The held-out half's own noise is in it (a model fitted on the other half cannot follow it), so :math:`E`
never falls below the noise of those pairs, :math:`N = \sqrt{\textstyle\sum_i v_i / \sum_i y_i}` with
:math:`v_i` the point's summed variance (:mod:`.held_out`), and the ratio :math:`E / N` is what the fit
prints first: 1 is the best any model can score on those photons, :math:`\sqrt 2 \approx 1.41` a model
that misses as much as the noise (:math:`E^2 = N^2 + B^2`, B the model's own error); with
:math:`\rho = E / N` its standard error over the points is
:math:`\sqrt{P}\,\mathrm{std}_i(e_i - \rho^2 v_i) / (2 \rho \sum_i v_i)`.

Two candidates b, c fitted and scored on the same halves differ by
:math:`\Delta = \sum_i (e_i(c) - e_i(b)) / \sum_i y_i`, whose standard error over the points,
:math:`\mathrm{SE} = \sqrt{P}\, \mathrm{std}_i(e_i(c) - e_i(b)) / \sum_i y_i`, is the split's noise.

**Rule** (after the one-standard-error rule of cross-validated λ in glmnet).  Along each axis the
candidates are nested, simplest first — shared ⊂ per-channel colour, n = 2 ⊂ 3 ⊂ 4 terms, m = 1 ⊂ 2 ⊂ 4 ⊂ 8 ⊂
16 directions (a blend of equal directions is the isotropic profile).  Each axis has a prior value, the
base structure's: one fall-off per channel (the colour of light that crossed a body), n = 3 (the paper's),
m = 1.  The prior is kept unless the best candidate beats it by more than one SE; otherwise the candidate
within one SE of the best nearest to the prior is chosen.  So a structure departs from the prior only
where the data say so beyond the split's noise, and the record says by how much.  The bias guard: a
choice worse than a simpler candidate of its axis by more than their difference's SE gives way to that
simpler one.  The axes are taken in the order of :data:`AXES`, each with what the earlier ones chose; an
axis the caller fixes is not searched.  A last guard compares the choice with the base structure on the
same halves and keeps the base unless the choice wins there too (:func:`choose`).

**Cost.**  The candidates run on a subset of the incident points (:func:`selection_points`: a share
:data:`SELECT_SHARE`, at least :data:`SELECT_MIN_POINTS`, spread by a fixed seed), as many side by side
as there are workers, each fitted
as the final fit will be (the same rounds: after one round the richer structures still hold what α
takes in the next, and won where they lose after three); an axis stops after :data:`PATIENCE`
candidates in a row that lower nothing; and the choice is then fitted on every point;
``benchmarks/structure_choice.py`` times the choice against one fit.  Units: errors are relative
(fractions; 0.05 is 5 %).
"""

from __future__ import annotations

import os
import tempfile
import time
import warnings
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

import numpy as np

from .._validate import TranslucencyError
from ..io.point_subset import point_subset
from ..resources.timing import register_terms
from .families import FAMILIES

__all__ = [
    "AXES",
    "Choice",
    "Structure",
    "choose",
    "fit_chosen",
    "free_axes",
    "resolve_structure",
    "selection_points",
]

#: the axes searched, in order, and each one's candidates from simplest to richest (one term is not
#: among them: on every sample measured it missed by far more than the noise, 37 % against 28 % held out
#: on the main job's data, 25 % against 12 % on a ball)
AXES = {
    "colour": ("shared", "per-channel"),
    "n_terms": (2, 3, 4),
    "n_directions": (1, 2, 4, 8, 16),
}
#: a candidate is as good as the best when its held-out squared error is within this many standard errors
#: of the best one's (the one-standard-error rule)
SELECT_SE = 1.0
#: the rule in words, as the record states it
RULE = (
    f"each axis keeps its prior (per-channel, n=3, m=1) unless the best candidate beats it by more than "
    f"{SELECT_SE:g} standard error; then the candidate within that of the best nearest the prior"
)
#: a held-out error at most this far above its noise (a ratio up to 1.05), or within one standard error of
#: it, is said to be at the noise
AT_NOISE = 0.05
#: the share of the incident points the candidates are fitted on ...
SELECT_SHARE = 0.0625
#: ... and at least this many (all of them when the data set has fewer)
SELECT_MIN_POINTS = 32
#: the seconds of a fit whose structure is chosen (``fit --model auto``'s time estimate, before this
#: machine's own runs calibrate it): the candidates cost about one anisotropic fit beside the final one
#: (benchmarks/structure_choice.py), and their fixed costs (a subset written, ~8 fits started) ~1 s
TIME_TERMS = {"overhead": 1.0, "point_pixels": 6.4e-6}
register_terms({"fit auto": TIME_TERMS})
#: an axis's search stops after this many candidates in a row that do not lower its best held-out error
#: (richer ones are not fitted: on a homogeneous sample m = 8 and 16 cost more than the rest together)
PATIENCE = 2


@dataclass(frozen=True)
class Structure:
    """What a fit holds fixed: the colour, n terms and m directions (1: isotropic).

    Examples
    --------
    >>> Structure().label, Structure(n_directions=8, colour="shared").label
    ('iso n=3 per-channel', 'aniso n=3 m=8 shared')
    >>> Structure(n_directions=8).options(planar=True)
    {'model': 'aniso', 'n_terms': 3, 'colour': 'per-channel', 'n_directions': 8}
    """

    colour: str = "per-channel"
    n_terms: int = 3
    n_directions: int = 1

    @property
    def model(self) -> str:
        """The family: ``"iso"`` for one direction, ``"aniso"`` for more."""
        return "iso" if self.n_directions == 1 else "aniso"

    @property
    def label(self) -> str:
        m = f" m={self.n_directions}" if self.n_directions > 1 else ""
        return f"{self.model} n={self.n_terms}{m} {self.colour}"

    def options(self, *, planar: bool) -> dict:
        """The fit's arguments for this structure (a mesh fit takes no directions)."""
        out = {"model": self.model, "n_terms": self.n_terms, "colour": self.colour}
        if planar:
            out["n_directions"] = max(self.n_directions, 2)
        return out


@dataclass
class Choice:
    """What :func:`choose` found: the structure, and every candidate's held-out error per axis.

    ``axes[axis]`` lists the candidates, simplest first, each a dict with ``value``, ``held_out`` and
    ``delta``, ``se`` (fractions of the squared norm: the candidate's squared error minus the best
    one's, and its standard error over the points).  ``noise`` is the chosen structure's held-out pairs'
    own noise (NaN where the scores gave no variance), ``ratio_se`` the standard error of held_out / noise.
    """

    structure: Structure
    axes: dict
    held_out: float = float("nan")  # the chosen structure's held-out error (fraction)
    guard: dict | None = None
    margins: dict = field(default_factory=dict)  # per axis where a richer value won: over what, by how much
    points: int = 0
    of_points: int = 0
    seconds: float = 0.0
    noise: float = float("nan")  # the held-out pairs' own noise, sqrt(Σ variance / Σ y²) (fraction)
    ratio_se: float = float("nan")  # the standard error of held_out / noise over the points
    pairs: str = "pairs"  # what a held-out pair's outgoing end is called: pixels (planar), vertices (mesh)

    @property
    def ratio(self) -> float:
        """The held-out error over the held-out pairs' own noise: 1 is the best a model can score there
        (NaN where the noise is not known, inf where the data set records none)."""
        if not self.noise > 0:
            return float("inf") if self.noise == 0 else float("nan")
        return self.held_out / self.noise

    def record(self) -> dict:
        """The choice as stored in the model file and printed by ``--json``."""
        return {
            "chosen": {
                **asdict(self.structure),
                "model": self.structure.model,
                "label": self.structure.label,
            },
            "held_out": self.held_out,
            "noise": self.noise,
            "ratio_to_noise": self.ratio,
            "ratio_se": self.ratio_se,
            "axes": self.axes,
            "guard": self.guard,
            "margins": self.margins,
            "runner_up": self.runner_up(),
            "points": self.points,
            "of_points": self.of_points,
            "seconds": round(self.seconds, 2),
            "rule": RULE,
            "summary": self.summary_line(),
        }

    def runner_up(self) -> dict | None:
        """The best candidate not chosen, on any axis: its structure's label, held-out error and axis."""
        rows = [
            {**row, "axis": axis}
            for axis, table in self.axes.items()
            for row in table
            if row["value"] != asdict(self.structure)[axis]
        ]
        if not rows:
            return None
        best = min(rows, key=lambda row: row["held_out"])
        label = replace(self.structure, **{best["axis"]: best["value"]}).label
        return {"label": label, "held_out": best["held_out"], "axis": best["axis"]}

    def summary_line(self) -> str:
        """One line for the run's summary: the held-out error over its own noise (:meth:`held_out_words`),
        the structure and, per axis where a richer value was kept, by how much it won over the best
        simpler one (or that the simpler one was within the noise).

        Examples
        --------
        >>> print(Choice(Structure(), {}, held_out=0.25, noise=0.2, ratio_se=0.03, points=16).summary_line())
        held-out error 1.25 × the data's own noise (± 0.03; 1 is the best any model can score): 25.0 % on \
the pairs the fit did not see, where their noise alone is 20.0 %; beyond the noise the model misses 15.0 %; \
structure iso n=3 per-channel (16 points; nothing richer than the simplest candidates)
        """
        said = []
        for axis, m in self.margins.items():
            value, gain = asdict(self.structure)[axis], 100 * m["held_out"]
            units = f", {abs(m['delta']) / m['se']:.1f} standard errors" if m["se"] > 0 else ""
            if m["delta"] > SELECT_SE * m["se"]:  # won beyond the split's noise
                said.append(f"{axis} {value} over {m['over']} by {gain:.2f} pt{units}")
            else:  # the prior, kept: the simpler value was within the noise
                said.append(f"{axis} {value} kept, {m['over']} within the noise ({-gain:+.2f} pt{units})")
        how = "; ".join(said) if said else "nothing richer than the simplest candidates"
        second = self.runner_up()
        runner = f"; runner-up {second['label']} {100 * second['held_out']:.2f} %" if second else ""
        return (
            f"{self.held_out_words()}; structure {self.structure.label} ({self.points} points; {how}{runner})"
        )

    def held_out_words(self) -> str:
        """The held-out error in words: its ratio to the held-out pairs' own noise first (1 is the best any
        model can score), then both percentages, and whether the model is at the noise or what it misses
        beyond it, √(E² − N²) (the held-out noise is independent of the model: their squares add).

        Examples
        --------
        >>> choice = Choice(Structure(), {}, held_out=0.8378, noise=0.829, ratio_se=0.02, pairs="pixels")
        >>> print(choice.held_out_words())
        held-out error 1.01 × the data's own noise (± 0.02; 1 is the best any model can score): 83.8 % on \
the pixels the fit did not see, where their noise alone is 82.9 %; the model is at the noise
        >>> print(Choice(Structure(), {}, held_out=0.1, noise=0.0).held_out_words())
        held-out error 10.0 % on the pairs the fit did not see (the data set records no noise to \
compare it with)
        """
        error = f"{100 * self.held_out:.1f} % on the {self.pairs} the fit did not see"
        if not self.noise > 0:
            none = " (the data set records no noise to compare it with)" if self.noise == 0 else ""
            return f"held-out error {error}{none}"
        ratio, se = self.ratio, self.ratio_se
        spread = f"± {se:.2f}; " if np.isfinite(se) else ""
        at_noise = ratio - 1 <= max(SELECT_SE * (se if np.isfinite(se) else 0.0), AT_NOISE)
        beyond = 100 * np.sqrt(max(self.held_out**2 - self.noise**2, 0.0))  # E² = N² + the model's own²
        verdict = (
            "the model is at the noise" if at_noise else f"beyond the noise the model misses {beyond:.1f} %"
        )
        return (
            f"held-out error {ratio:.2f} × the data's own noise ({spread}1 is the best any model can score): "
            f"{error}, where their noise alone is {100 * self.noise:.1f} %; {verdict}"
        )


def free_axes(model: str, n_terms, n_directions, colour, *, planar: bool):
    """The axes to choose and the base structure, from the fit's options (``None`` or ``"auto"``: choose).

    ``model="auto"`` chooses every axis not given; a named exponential family chooses only the axes given
    as ``"auto"`` and fills the others with the family's defaults (n = 3, m = 8, one fall-off per
    channel); a baseline family has no structure to choose.

    Returns
    -------
    (tuple of str, Structure)
        The free axes (in :data:`AXES` order; empty: nothing to choose) and the base structure (the
        fixed values, and the priors for the free ones: per channel, n = 3, m = 1).

    Examples
    --------
    >>> free_axes("auto", None, None, None, planar=True)
    (('colour', 'n_terms', 'n_directions'), Structure(colour='per-channel', n_terms=3, n_directions=1))
    >>> free_axes("aniso", 3, "auto", "shared", planar=True)
    (('n_directions',), Structure(colour='shared', n_terms=3, n_directions=1))
    >>> free_axes("auto", None, None, "shared", planar=False)
    (('n_terms',), Structure(colour='shared', n_terms=3, n_directions=1))
    """
    given = {"colour": colour, "n_terms": n_terms, "n_directions": n_directions}
    if model != "auto":
        if model not in FAMILIES or not FAMILIES[model].shared_colour:  # a baseline: checked by the fit
            return (), Structure()
        defaults = {
            "colour": "per-channel",
            "n_terms": 3,
            "n_directions": 8 if FAMILIES[model].directional else 1,
        }
        given = {axis: defaults[axis] if v is None else v for axis, v in given.items()}
        m = given["n_directions"]
        if model == "aniso" and m != "auto" and _count("n_directions", m) < 2:
            raise TranslucencyError(f"directions: the anisotropic model needs m >= 2, got {n_directions}")
    if not planar:
        given["n_directions"] = 1
    free = tuple(axis for axis in AXES if given[axis] is None or given[axis] == "auto")
    fixed = {
        axis: (_count(axis, v) if axis != "colour" else v) for axis, v in given.items() if axis not in free
    }
    return free, Structure(**fixed)


def _count(axis: str, value) -> int:
    """A fixed n or m as an int; anything else is refused in one line naming the option."""
    try:
        if isinstance(value, bool) or int(value) != float(value):
            raise ValueError
        return int(value)
    except (TypeError, ValueError):
        name = {"n_terms": "terms", "n_directions": "directions"}[axis]
        raise TranslucencyError(f"{name}: expected a whole number or 'auto', got {value!r}") from None


def resolve_structure(model: str, n_terms, n_directions, colour, *, planar: bool):
    """The fit's options with the structure's defaults filled, the free axes and the base structure.

    Returns ``(model, n_terms, n_directions, colour, free, base)``: the family to check the options with
    (``"auto"`` resolves to ``"aniso"`` where directions are chosen or given, else ``"iso"``), the options
    (``"auto"`` where an axis is chosen), and :func:`free_axes`'s two values.

    Examples
    --------
    >>> resolve_structure("auto", None, None, None, planar=True)[:4]
    ('aniso', 'auto', 'auto', 'auto')
    >>> resolve_structure("iso", None, None, None, planar=True)[:4]
    ('iso', 3, 1, 'per-channel')
    >>> resolve_structure("dipole", None, None, None, planar=False)[:5]
    ('dipole', 3, 1, 'per-channel', ())
    """
    free, base = free_axes(model, n_terms, n_directions, colour, planar=planar)
    if model == "auto":
        model = "aniso" if "n_directions" in free or base.n_directions > 1 else "iso"
    exponential = model in FAMILIES and FAMILIES[model].shared_colour
    values = {}
    for axis, given in (("n_terms", n_terms), ("n_directions", n_directions), ("colour", colour)):
        if axis in free:
            values[axis] = "auto"
        elif exponential:
            values[axis] = getattr(base, axis)
        elif given is None or (axis == "n_terms" and given == "auto"):  # a baseline has no terms
            values[axis] = getattr(Structure(), axis)
        else:
            values[axis] = given  # a baseline's: checked by the fit (its directions' "auto" refused there)
    if model == "aniso" and values["n_directions"] == 1:
        model = "iso"
    return model, values["n_terms"], values["n_directions"], values["colour"], free, base


def selection_points(n_points: int) -> np.ndarray:
    """The incident points the candidates are fitted on: :data:`SELECT_SHARE` of them, at least
    :data:`SELECT_MIN_POINTS`, drawn by a fixed seed (so a fit is repeatable), in ascending order.

    Examples
    --------
    >>> len(selection_points(1024)), len(selection_points(100)), len(selection_points(25))
    (64, 32, 25)
    """
    k = min(n_points, max(SELECT_MIN_POINTS, int(np.ceil(SELECT_SHARE * n_points))))
    if k == n_points:
        return np.arange(n_points)
    return np.sort(np.random.default_rng(0).choice(n_points, size=k, replace=False))


def choose(score: Callable[[Structure], tuple], base: Structure, free: tuple, *, workers: int = 1) -> Choice:
    """Choose the structure along the ``free`` axes by the one-standard-error rule (module docstring).

    Parameters
    ----------
    score : callable
        ``score(structure) -> (e, y)`` or ``(e, y, v)``: per incident point the held-out squared error, data
        norm and (optionally) summed variance, (P,) each, of the structure fitted on one half of the pairs
        (:func:`.held_out.held_out_terms`); with v the choice knows its noise floor.
    base : Structure
        The fixed axes' values, and where the search starts.
    free : tuple of str
        The axes to search, a subset of :data:`AXES` (in its order).
    workers : int
        Candidates fitted side by side (threads; ``score`` must allow it).  The choice is the same.

    Returns
    -------
    Choice

    Examples
    --------
    Three points; one direction misses 10 % more than eight on every point (a clear win), and two
    directions gain less than their noise: eight are chosen (16 is tried, and loses).

    >>> e = {1: np.array([1.1, 1.2, 1.0]), 2: np.array([1.0, 1.3, 0.95]), 4: np.array([1.1, 1.2, 1.0]),
    ...      8: np.array([1.0, 1.09, 0.91]), 16: np.array([1.1, 1.2, 1.0])}
    >>> choice = choose(lambda s: (e[s.n_directions], np.full(3, 10.0)), Structure(), ("n_directions",))
    >>> choice.structure.n_directions
    8
    """
    scored: dict[Structure, tuple] = {}

    def terms(*structures: Structure) -> list:
        """The scores of ``structures``, those not yet scored fitted side by side (``workers`` at once)."""
        todo = [c for c in dict.fromkeys(structures) if c not in scored]
        results = pool.map(score, todo) if len(todo) > 1 else map(score, todo)
        for c, result in zip(todo, results, strict=True):
            scored[c] = tuple(np.asarray(a, dtype=np.float64) for a in result)
        return [scored[c] for c in structures]

    current, axes, margins = base, {}, {}
    with ThreadPoolExecutor(max_workers=max(1, workers)) as pool:
        for axis in (a for a in AXES if a in free):
            candidates, scores, best, worse = [], [], np.inf, 0
            values = list(AXES[axis])
            while values and worse < PATIENCE:  # simplest first, until PATIENCE in a row lower nothing
                batch = []  # the next candidates, up to ``workers`` of them still to fit
                while values and sum(c not in scored for c in batch) < max(1, workers):
                    batch.append(replace(current, **{axis: values.pop(0)}))
                for c, (e, y, *_) in zip(batch, terms(*batch), strict=True):
                    if worse >= PATIENCE:
                        break
                    candidates.append(c)
                    scores.append((e, y))
                    err = e.sum() / max(y.sum(), 1e-300)
                    worse = 0 if err < best else worse + 1
                    best = min(best, err)
            current, axes[axis], margin = _one_se(candidates, scores, axis, getattr(base, axis))
            if margin is not None:
                margins[axis] = margin
        (e_base, e_current) = terms(base, current)
    guard = None
    if current != base and free:  # the last guard: the choice against the base, on the same halves
        delta, se = _difference(e_current, e_base)
        guard = {"base": base.label, "delta": delta, "se": se}
        if delta > SELECT_SE * se:  # worse than the base by more than the split's noise: keep the base
            guard["kept"] = "base"
            current, margins = base, {}
    chosen = e_base if current == base else e_current
    e, y = chosen[:2]
    choice = Choice(current, axes, float(np.sqrt(e.sum() / max(y.sum(), 1e-300))), guard, margins)
    if len(chosen) > 2:
        choice.noise, choice.ratio_se = _noise(*chosen)
    return choice


def _noise(e: np.ndarray, y: np.ndarray, v: np.ndarray) -> tuple[float, float]:
    """The held-out pairs' noise N = sqrt(Σv / Σy) and the standard error over the points of E / N.

    Examples
    --------
    >>> n, se = _noise(np.array([1.0, 1.2, 0.8]), np.full(3, 100.0), np.ones(3))
    >>> round(n, 3), round(se, 3)
    (0.1, 0.058)
    """
    sy, sv = float(y.sum()), float(v.sum())
    if not (sy > 0 and sv > 0):
        return (0.0 if sy > 0 else float("nan")), float("nan")
    ratio2 = float(e.sum()) / sv  # (E / N)²
    d = (e - ratio2 * v)[y > 0]  # a ratio estimator's residuals, per point with held-out data
    se2 = np.sqrt(len(d)) * float(np.std(d, ddof=1)) / sv if len(d) > 1 else float("nan")
    return float(np.sqrt(sv / sy)), float(se2 / (2 * np.sqrt(ratio2))) if ratio2 > 0 else float("nan")


def _difference(a: tuple, b: tuple) -> tuple[float, float]:
    """Δ = Σ(e_a − e_b) / Σy and its standard error over the points (both relative, of the squared norm)."""
    (e_a, y_a), (e_b, y_b) = a[:2], b[:2]
    y = 0.5 * (y_a.sum() + y_b.sum())
    if not y > 0:  # no held-out data at all: nothing tells the candidates apart
        return 0.0, 0.0
    d = (e_a - e_b)[(y_a > 0) | (y_b > 0)]  # the points with held-out data
    se = np.sqrt(len(d)) * float(np.std(d, ddof=1)) / y if len(d) > 1 else 0.0
    return float(d.sum() / y), float(se)


def _one_se(candidates: list, terms: list, axis: str, prior):
    """The axis's choice, its table (see :class:`Choice`) and the margin of a richer choice over its best
    simpler candidate (None when nothing simpler was tried).

    ``prior`` (the base structure's value) is kept unless the best candidate beats it by more than one
    standard error; otherwise the candidate within one standard error of the best nearest to ``prior``
    (the simpler at equal distance) is chosen.  The bias guard: a choice worse than a simpler candidate by
    more than their own difference's standard error gives way to the best of those simpler ones."""
    errors = [float(np.sqrt(e.sum() / max(y.sum(), 1e-300))) for e, y, *_ in terms]
    best = int(np.argmin(errors))
    table, near_best = [], []
    for k, (t, err) in enumerate(zip(terms, errors, strict=True)):
        delta, se = _difference(t, terms[best])
        table.append({"value": getattr(candidates[k], axis), "held_out": err, "delta": delta, "se": se})
        if delta <= SELECT_SE * se:
            near_best.append(k)
    values = [row["value"] for row in table]
    home = values.index(prior) if prior in values else 0
    pick = home if home in near_best else min(near_best, key=lambda k: (abs(k - home), k))
    against = {k: _difference(terms[pick], terms[k]) for k in range(pick)}  # (Δ, SE) to each simpler one
    beaten = [k for k, (delta, se) in against.items() if delta > SELECT_SE * se]
    if beaten:  # the bias guard
        pick = min(beaten, key=lambda k: errors[k])
    margin = None
    if pick > 0:  # a richer structure kept: by how much it won over the best simpler one
        k = min(range(pick), key=lambda j: errors[j])
        delta, se = _difference(terms[k], terms[pick])
        margin = {"over": table[k]["value"], "delta": delta, "se": se, "held_out": errors[k] - errors[pick]}
    return candidates[pick], table, margin


def fit_chosen(fit: Callable, ds, score_terms: Callable, *, free: tuple, base: Structure, planar: bool,
               progress=None, **kw):  # fmt: skip
    """Choose the structure on a subset of ``ds``'s points (:func:`choose`), then fit it on all of them.

    Parameters
    ----------
    fit : callable
        :func:`translucency.fit.fit_planar` or :func:`translucency.fit.fit_mesh`.
    ds : PlanarDataset or MeshDataset
        The data set (finished).
    score_terms : callable
        ``score_terms(fit_result, subset) -> (e, y, v)`` per point (:mod:`.held_out`; v, the summed
        variance, may be left out).
    free, base :
        From :func:`free_axes`.
    planar : bool
        Planar data (directions may be chosen) or a mesh.
    progress : callable, optional
        ``progress(done, total, message)``: one step per candidate, then the final fit's own.
    **kw
        The fit's other options, the same for the candidates and the final fit.

    Returns
    -------
    FitResult
        The chosen structure's fit on every point; ``options["structure"]`` holds :meth:`Choice.record`.
    """
    t0 = time.perf_counter()
    points = selection_points(ds.n_points)
    n_candidates = sum(len(AXES[a]) for a in free)
    done = [0]
    workers = kw.get("workers") or os.cpu_count() or 1
    selection_kw = {k: v for k, v in kw.items() if k != "checkpoint"}
    with tempfile.TemporaryDirectory(prefix="translucency-structure-") as tmp:
        sub = ds if len(points) == ds.n_points else point_subset(ds, points, Path(tmp) / "points.zarr")

        def score(structure: Structure):
            result = fit(sub.path, **structure.options(planar=planar), half=0, **selection_kw)
            done[0] += 1
            if progress is not None:
                progress(done[0], n_candidates, f"structure: {structure.label}")
            return score_terms(result, sub)

        with warnings.catch_warnings():  # the final fit says what the data set's fits should hear
            warnings.simplefilter("ignore")
            choice = choose(score, base, free, workers=workers)
    choice.points, choice.of_points, choice.seconds = len(points), ds.n_points, time.perf_counter() - t0
    choice.pairs = "pixels" if planar else "vertices"
    result = fit(ds.path, **choice.structure.options(planar=planar), progress=progress, **kw)
    result.options["structure"] = choice.record()
    result.seconds += choice.seconds
    return result
