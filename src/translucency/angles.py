r"""The angle axes of a mesh data set: the directions light arrives from, and the bins it leaves by.

The paper's data are diffuse: :math:`R_d(x_i, x_o)` for a beam entering along the normal, the exits
counted whatever their direction.  Light from behind an object enters obliquely and leaves toward the
side a camera sees, and both angles move a back-lit picture by tens of percent (docs/lean.md, "Why:
which angle matters").  A mesh data set may therefore hold two more axes; both live in the frame of the
surface, so they mean the same on any mesh:

**Incidence** (:class:`Incidence`): besides the normal beam, beams arriving at polar angles
:math:`\theta_i` from the normal at :math:`n_\phi` azimuths :math:`\phi_k = 2\pi k / n_\phi` of each
incident point's tangent frame :math:`(t, b, n)` (:func:`translucency.geometry.tangent_frames`).  A
direction is stored as :math:`\omega_i` *toward the light*, local coordinates
:math:`(\sin\theta_i\cos\phi, \sin\theta_i\sin\phi, \cos\theta_i)`; the beam flies along
:math:`-\omega_i` and is reflected and refracted at the surface
(:func:`translucency.acquire.mesh_walk.mesh_random_walk`).

**Exit bins** (:class:`ExitBins`): each exit's direction :math:`\omega_o` (in the air, outwards) in
:math:`n_\theta` polar bins of equal projected solid angle — edges at :math:`\cos^2\theta = 1 - j /
n_\theta` — times two azimuthal halves: *away* from the incident point (the tangent component of
:math:`\omega_o` along that of :math:`x_o - x_i`) or *back* toward it.  Every bin then has

.. math:: \Omega'_b = \int_b \cos\theta\, d\omega = \pi / (2 n_\theta),

so the part :math:`R_{d,b}` of :math:`R_d` that left through bin b is the radiance there
:math:`L_b = R_{d,b} / \Omega'_b` (mm⁻² sr⁻¹ per unit power), and a Lambertian exit reads the same
:math:`R_d / \pi` in every bin.  The exit law a camera needs to turn radiance into exitance is
:math:`f_b = \pi L_b / R_d` (1 for Lambertian; :meth:`ExitBins.law`).

Units: angles in degrees at the API, directions unit vectors; R_d in mm⁻².
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ._validate import TranslucencyError

#: a beam farther than this from its incident point's normal (degrees) is oblique: the paper's model, fitted
#: to normal beams, does not describe it (``import object`` and ``fit`` say so)
OBLIQUE_DEG = 10.0


def polar_deg(toward: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """Polar angles (degrees) of unit directions ``toward`` the light from unit ``normals``, row by row.

    Examples
    --------
    >>> polar_deg(np.array([[0.0, 0.5, np.sqrt(0.75)]]), np.array([[0.0, 0.0, 1.0]])).round(6).tolist()
    [30.0]
    """
    cos = np.einsum("pk,pk->p", np.asarray(toward, np.float64), np.asarray(normals, np.float64))
    return np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))


@dataclass(frozen=True)
class Incidence:
    """The directions the beams of each incident point arrive from: the normal, then
    ``len(polar_deg) * azimuths`` oblique ones.

    Examples
    --------
    >>> inc = Incidence(polar_deg=(60.0,), azimuths=4)
    >>> inc.count, inc.local()[1].round(3).tolist()   # the normal first; then (θ 60°, φ 0°)
    (5, [0.866, 0.0, 0.5])
    >>> Incidence().count   # old data sets: the normal beam only
    1
    """

    polar_deg: tuple[float, ...] = ()
    azimuths: int = 4

    def __post_init__(self):
        for t in self.polar_deg:
            if not 0.0 < float(t) < 90.0:
                raise TranslucencyError(f"incidence: polar angles must lie in (0, 90) degrees, got {t:g}")
        if self.polar_deg and not 1 <= int(self.azimuths) <= 64:
            raise TranslucencyError(f"incidence azimuths: need 1 to 64, got {self.azimuths}")

    @property
    def count(self) -> int:
        """Directions per incident point, the normal included."""
        return 1 + len(self.polar_deg) * int(self.azimuths)

    def local(self) -> np.ndarray:
        """(count, 3) unit directions toward the light in the tangent frame (t, b, n); row 0 the normal."""
        rows = [(0.0, 0.0, 1.0)]
        for t in self.polar_deg:
            th = np.radians(float(t))
            for k in range(int(self.azimuths)):
                ph = 2.0 * np.pi * k / int(self.azimuths)
                rows.append((np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)))
        return np.asarray(rows, dtype=np.float64)

    def world(self, frames: np.ndarray) -> np.ndarray:
        """(P, count, 3) directions toward the light in object space for incident frames (P, 3, 3) whose
        rows are (t, b, n)."""
        return np.einsum("dk,pkj->pdj", self.local(), np.asarray(frames, dtype=np.float64))

    def describe(self) -> dict:
        """The header's record (JSON)."""
        return {"polar_deg": [float(t) for t in self.polar_deg], "azimuths": int(self.azimuths)}

    @classmethod
    def from_header(cls, record: dict | None) -> Incidence:
        """From a header's record; None (a data set made before the axis existed): the normal only."""
        if not record:
            return cls()
        return cls(tuple(float(t) for t in record.get("polar_deg", ())), int(record.get("azimuths", 4)))


@dataclass(frozen=True)
class ExitBins:
    r"""Exit directions in ``polar`` bins of equal projected solid angle × ``slants`` azimuthal sectors about
    the direction away from the incident point; bin index ``slants · j + k`` (j polar from the normal, k the
    sector).  The sector is the azimuth φ between the exit's tangent part and the tangent pointing away from
    the hit, in ``slants`` equal parts of [0, π] (left and right of that axis alike): with the default 2 the
    two halves, away (k = 0) and back toward it (k = 1).

    Examples
    --------
    >>> bins = ExitBins(polar=2)
    >>> bins.count, round(bins.projected_solid_angle * bins.count / np.pi, 12)   # they tile the hemisphere
    (4, 1.0)
    >>> bins.edges_cos.round(4).tolist()   # cos θ at the edges: cos² θ = 1, 1/2, 0
    [1.0, 0.7071, 0.0]
    >>> fine = ExitBins(polar=2, slants=4)   # sectors of 45° either side of the away axis
    >>> fine.sector(np.array([0.9, 0.5, -0.2, -0.9])).tolist()
    [0, 1, 2, 3]
    """

    polar: int = 3
    slants: int = 2

    def __post_init__(self):
        if not 1 <= int(self.polar) <= 16:
            raise TranslucencyError(f"exit bins: need 1 to 16 polar bins, got {self.polar}")
        if not 2 <= int(self.slants) <= 16:
            raise TranslucencyError(f"exit bins: need 2 to 16 azimuthal sectors, got {self.slants}")

    @property
    def count(self) -> int:
        return int(self.slants) * int(self.polar)

    @property
    def edges_cos(self) -> np.ndarray:
        """cos θ at the polar edges, from the normal (1) to the horizon (0)."""
        return np.sqrt(1.0 - np.arange(int(self.polar) + 1) / int(self.polar))

    @property
    def projected_solid_angle(self) -> float:
        r""":math:`\Omega'_b = \pi / (n_\theta n_\varphi)`, the same for every bin, sr."""
        return np.pi / self.count

    def polar_index(self, mu: np.ndarray) -> np.ndarray:
        """The polar bin j of exits at cosines ``mu`` to the normal (at or below the horizon: the last)."""
        cos2 = np.clip(np.asarray(mu, dtype=np.float64), 0.0, 1.0) ** 2
        return np.minimum(((1.0 - cos2) * int(self.polar)).astype(np.int64), int(self.polar) - 1)

    def sector(self, cos_phi: np.ndarray) -> np.ndarray:
        """The azimuthal sector k of exits whose tangent part makes the angle φ with the away axis, given
        cos φ (1: straight away, −1: straight back; 0 counts as away, as the halves always did)."""
        c = np.clip(np.asarray(cos_phi, dtype=np.float64), -1.0, 1.0)
        if int(self.slants) == 2:  # the two halves, exactly as data sets made before the sectors read them
            return (c < 0.0).astype(np.int64)
        k = (np.arccos(c) / np.pi * int(self.slants)).astype(np.int64)
        return np.minimum(k, int(self.slants) - 1)

    def bin_of(self, mu: np.ndarray, cos_phi: np.ndarray) -> np.ndarray:
        """The bin of exits at cosines ``mu`` to the normal and azimuths cos φ from the away axis."""
        return int(self.slants) * self.polar_index(mu) + self.sector(cos_phi)

    def index(self, omega: np.ndarray, normal: np.ndarray, away: np.ndarray) -> np.ndarray:
        """The bin of each exit: directions ``omega`` (n, 3) outwards, the surface's unit normals there
        (n, 3), and ``away`` (n, 3) the direction from the incident point to the exit (any length; its
        tangent component sets the azimuth's axis; at the incident point itself every exit is sector 0)."""
        omega, normal = np.asarray(omega, np.float64), np.asarray(normal, np.float64)
        mu = np.einsum("nk,nk->n", omega, normal)
        a = np.asarray(away, np.float64)
        a_t = a - np.einsum("nk,nk->n", a, normal)[:, None] * normal  # tangent component of x_o − x_i
        w_t = omega - mu[:, None] * normal  # the exit's tangent component
        norms = np.linalg.norm(a_t, axis=1) * np.linalg.norm(w_t, axis=1)
        dot = np.einsum("nk,nk->n", w_t, a_t)
        cos_phi = np.divide(dot, norms, out=np.ones_like(dot), where=norms > 0)  # at the hit: away
        return self.bin_of(mu, cos_phi)

    def radiance(self, R_d_bins: np.ndarray) -> np.ndarray:
        r"""Radiance per unit power in each bin, :math:`L_b = R_{d,b} / \Omega'_b` (mm⁻² sr⁻¹); the bins
        on the last axis."""
        return np.asarray(R_d_bins) / self.projected_solid_angle

    def law(self, R_d_bins: np.ndarray, floor: float = 0.0) -> np.ndarray:
        r"""The exit law :math:`f_b = \pi L_b / R_d` per bin (1 everywhere for a Lambertian exit); NaN
        where :math:`R_d \le` ``floor``."""
        R = np.asarray(R_d_bins, dtype=np.float64)
        total = R.sum(axis=-1, keepdims=True)
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(total > floor, np.pi * self.radiance(R) / total, np.nan)

    def describe(self) -> dict:
        record = {
            "polar": int(self.polar),
            "azimuth": ["away", "back"],
            "edges_cos": [round(float(c), 6) for c in self.edges_cos],
            "projected_solid_angle_sr": float(self.projected_solid_angle),
        }
        if int(self.slants) != 2:  # sectors of φ from the away axis (records of the halves stay as they were)
            record["azimuth"] = f"{int(self.slants)} sectors of 180/{int(self.slants)} degrees from away"
            record["slants"] = int(self.slants)
        return record

    @classmethod
    def from_header(cls, record: dict | None) -> ExitBins | None:
        """From a header's record; None where the data set has no exit bins."""
        return cls(int(record["polar"]), int(record.get("slants", 2))) if record else None


def angle_record(incidence: Incidence | None, exit_bins: ExitBins | None) -> dict:
    """The header's (and the request's) ``angles`` record of a data set: empty where it has neither axis, so
    that data sets made before the axes existed read and resume as they were."""
    record = {}
    if incidence is not None and incidence.count > 1:
        record["incidence"] = incidence.describe()
    if exit_bins is not None:
        record["exit_bins"] = exit_bins.describe()
    return record


def angle_arrays(record: dict | None, P: int, per_beam: tuple[int, ...]) -> list[tuple[str, tuple]]:
    """The arrays an ``angles`` record announces, with their shapes, for P incident points whose beams are
    tallied over ``per_beam`` (a mesh's (V,), a planar window's (H, W)); D directions, B exit bins:

    ``R_d_oblique`` (P, D − 1, *per_beam, 3), ``specular_oblique`` (P, D − 1, 3) and ``exit_bins``
    (P, D, *per_beam, 3, B) — none for a record without the axes.

    Examples
    --------
    >>> record = angle_record(Incidence((60.0,), 4), ExitBins(3))
    >>> [(name, shape) for name, shape in angle_arrays(record, 8, (5, 5))][::2]
    [('R_d_oblique', (8, 4, 5, 5, 3)), ('exit_bins', (8, 5, 5, 5, 3, 6))]
    """
    record = record or {}
    D = Incidence.from_header(record.get("incidence")).count
    bins = ExitBins.from_header(record.get("exit_bins"))
    arrays = []
    if D > 1:
        arrays += [("R_d_oblique", (P, D - 1, *per_beam, 3)), ("specular_oblique", (P, D - 1, 3))]
    if bins is not None:
        arrays += [("exit_bins", (P, D, *per_beam, 3, bins.count))]
    return arrays


class AngleAxes:
    """The angle axes of a data set whose header carries an ``angles`` record (mixed into the mesh and the
    planar data sets): the normal beam only and no exit bins where it has none."""

    header: dict

    @property
    def incidence(self) -> Incidence:
        """The directions of the beams at each incident point (the normal only for a data set without the
        axis)."""
        return Incidence.from_header((self.header.get("angles") or {}).get("incidence"))

    @property
    def exit_bins(self) -> ExitBins | None:
        """The exit bins the tally counted in, or None."""
        return ExitBins.from_header((self.header.get("angles") or {}).get("exit_bins"))
