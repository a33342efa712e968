r"""A lab's object: multi-view HDR photographs of a laser stepped over a scanned mesh → a mesh data set.

``translucency import object RIG`` (:func:`import_object`) writes what ``acquire mesh`` writes —
:math:`R_d(x_i, v)` in mm⁻² per unit incident power for every vertex v of the mesh and every laser
position x_i (snapped to its nearest vertex), in a :mod:`translucency.io.mesh_dataset` — plus, per
pair, its variance (``R_d_var``) and what kept it from being measured (``flags``):

1. **Cameras** (:mod:`.setup`, :mod:`.cameras`, :mod:`.views`): K and distortion given or by OpenCV from
   checkerboards, the pose given or by ``solvePnP`` from marked points; reprojection errors above the
   bound refused; a mesh most of whose vertices project outside every image refused.
2. **Visibility, once per camera** (:mod:`.surface_map`): Mitsuba casts a ray through every pixel
   centre; the map W (vertex × pixel) of barycentric weight × footprint area defines the per-vertex
   value exactly as the tally does.
3. **Radiance per frame**: :math:`L = (Z - \text{dark})/(k\,t\,\text{vig}\,\text{flat})/P`
   (:mod:`.setup`, :mod:`.radiance`); saturated or non-finite pixels are unusable; several frames are combined
   per pixel weighted by exposure time; the variance is the noise model's, or — where two or more
   frames share an exposure — the larger of it and the frames' own scatter (which also holds what the
   noise model does not know, e.g. a renderer's Monte Carlo noise).
4. **Exitance per camera and vertex**: :math:`M_{vc} = \pi \bar L_{vc}/\gamma(\mu_{vc}, r)` with the
   exit's angular law γ (:mod:`.exit_law`: the rig file's ``exit_law``, by default ``lambertian`` for an
   index-matched boundary and ``dielectric`` behind one; ``from-views`` estimates it from the views,
   :mod:`.law_estimate`).
5. **Fusion over cameras** (:mod:`.fusion`) that see at least ``min_coverage`` of the vertex's cell
   with usable pixels: weights :math:`w_c = n_c\,\gamma_c` (:math:`n_c = (\sum_p W)^2/\sum_p W^2` the
   cell's effective number of pixels: with photon noise, Var M ∝ 1/(n γ)), which do not depend on the
   measured values (inverse *measured* variances would favour the camera that read low).
6. **Flags** (bits): :data:`SATURATED` no camera saw the cell without a saturated pixel (each camera's
   view that lost one is dropped, and counted), :data:`SPOT` within ``spot_radius_mm`` of the hit (0:
   none), :data:`UNSEEN` no camera sees the cell well, :data:`GRAZING` only at grazing angles.  The
   saturated and spot cells, and the unseen ones among them, come from a model of the near peak fitted
   to the measured ring around them (:mod:`.near_peak`); the other unseen cells are filled over the mesh
   graph from measured neighbours (harmonic fill: :mod:`.fill`); both carry their variance.  The
   per-vertex fit leaves flagged pairs out; the stored value keeps the energy bookkeeping whole.

The laser hits are snapped to vertices by :mod:`.hits`.  Laser shots are processed in chunks (the
unit of resuming and of memory) by :class:`ObjectImport`, the importers' contract of
:mod:`translucency.rig.contract`; same arguments resume, other arguments are refused unless
``overwrite``.  Units: mm, W, seconds; R_d in mm⁻².
"""

from __future__ import annotations

import json
import time
import warnings
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..._validate import TranslucencyError
from ...angles import OBLIQUE_DEG, polar_deg
from ...geometry import vertex_areas
from ...io.mesh_dataset import MeshDataset, create_mesh_dataset, mesh_header, open_mesh_dataset
from ...io.outputs import remove_dataset
from ...mitsuba import mesh_scene
from ..contract import Chunk, run_import, sha256_file
from .exit_law import ExitLaw, Lambertian, Walked, law_named
from .fill import HarmonicFill
from .fusion import GRAZING, SATURATED, SPOT, UNSEEN, fuse
from .glint import glint_pixels
from .hits import incident_vertices
from .law_estimate import estimate_law
from .near_peak import recover_near_peak
from .radiance import shot_cell_means
from .setup import ObjectRig, calibrated_camera, read_object_rig
from .shape_gain import MeshWalkGain
from .spot_check import check_spots
from .views import CameraView, check_mesh_seen, prepare_view
from .walk_law import ShotWalkLaw


def import_object(
    rig,
    out,
    *,
    chunk_points: int = 8,
    overwrite: bool = False,
    progress: Callable[[int, int], None] | None = None,
    exit_law: str | None = None,
) -> dict:
    """Turn a lab's object rig (``object.json``, :mod:`.setup`) into a mesh data set at ``out``.

    Parameters
    ----------
    rig : path
        The rig file, or the folder holding ``object.json``.
    out : path
        The mesh data set (Zarr directory) to write.
    chunk_points : int
        Laser shots per chunk (the unit of resuming; memory holds one chunk of images).
    exit_law : str, optional
        Overrides the rig file's ``exit_law`` (``"lambertian"``, ``"dielectric"``, ``"from-views"``,
        ``"walk"``).

    Returns
    -------
    dict
        ``path``, ``cameras`` (reprojection errors, vertices seen), ``exit_law``, ``energy`` (per shot:
        Σ_v A_v R_d per channel) and ``energy_sigma`` (its standard deviation, :func:`shot_energy`),
        ``flags`` (counts), ``seconds`` and ``bytes_read`` (image bytes).

    Raises
    ------
    TranslucencyError
        One line: a fault of the rig file, a camera or the mesh, or another import at ``out``.

    Examples
    --------
    A folder without ``object.json`` is refused before anything is written:

    >>> import tempfile
    >>> try:
    ...     import_object(tempfile.mkdtemp(), "unused.zarr")
    ... except TranslucencyError as exc:
    ...     print(str(exc).split("/")[-1])
    object.json: cannot read (No such file or directory)

    A virtual rig's hand-over (:func:`~translucency.rig.object.photographs.photograph_object`, tens of
    seconds) imported (ray casting and reading the images, a minute or more):

    >>> import trimesh
    >>> from pathlib import Path
    >>> from translucency.acquire.mesh import object_volume
    >>> from translucency.rig.object.importer import import_object
    >>> from translucency.rig.object.photographs import photograph_object
    >>> mesh, folder = trimesh.creation.icosphere(subdivisions=2, radius=6.0), Path(tempfile.mkdtemp())
    >>> volume = object_volume("homogeneous:skin1", mesh, 0.5, seed=1)
    >>> _ = photograph_object(mesh, volume, folder / "sphere-rig", n_points=2, n_cameras=3,
    ...                       resolution=(32, 32), spp=4)  # doctest: +SKIP
    >>> info = import_object(folder / "sphere-rig", folder / "sphere.zarr",
    ...                      exit_law="lambertian")  # doctest: +SKIP
    >>> sorted(info["flags"]), len(info["energy"]), len(info["energy"][0])  # doctest: +SKIP
    (['grazing', 'saturated', 'spot', 'unseen'], 2, 3)
    """
    t0 = time.perf_counter()
    importer = ObjectImport.from_setup(rig, chunk_points=chunk_points, exit_law=exit_law)
    fresh = not Path(out).exists() or not any(Path(out).iterdir())  # a refused import removes what it made
    try:
        flag_counts = run_import(importer, out, overwrite=overwrite, progress=progress)
    except (TranslucencyError, KeyboardInterrupt):
        if fresh and Path(out).exists() and not _finished_any(out):
            remove_dataset(out)
        raise
    return {
        "path": str(out),
        "cameras": [
            {
                "name": c.camera.name,
                "reprojection_px": c.camera.reprojection_px,
                "vertices_seen": int((c.map.den > 0).sum()),
            }
            for c in importer.cameras
        ],
        "exit_law": importer.law.describe(),
        "energy": importer.energy.tolist(),
        "energy_sigma": importer.energy_sigma.tolist(),
        "flags": dict(zip(("unseen", "saturated", "grazing", "spot"), flag_counts.tolist())),
        "saturated_views": importer.saturated_views,
        "near_peak": importer.recovered,
        # with exit_law "walk": the shots (of this run's chunks) converted with the walks' law; the others
        # clipped nothing, had no near peak to give a material, and kept π L
        "walked_shots": importer.walked,
        "rays_per_pixel": {c.camera.name: c.map.sub**2 for c in importer.cameras},
        "seconds": time.perf_counter() - t0,
        "bytes_read": importer.bytes_read,
        "incident": importer.incident.tolist(),
        "beam_polar_deg": importer.header["photographs"]["beam_polar_deg"],
    }


@dataclass
class ObjectImport:
    """An object rig read and checked, its cameras posed and mapped, its hits snapped, its exit law chosen:
    the :class:`~translucency.rig.contract.Importer` of a mesh data set.

    Examples
    --------
    >>> try:
    ...     ObjectImport.from_setup("sphere-rig", chunk_points=0)
    ... except TranslucencyError as exc:
    ...     print(exc)
    chunk_points: must be >= 1, got 0

    Read, posed and mapped once (seconds), then run chunk by chunk, resumable:

    >>> from translucency.rig.contract import run_import
    >>> import tempfile, trimesh
    >>> from pathlib import Path
    >>> from translucency.acquire.mesh import object_volume
    >>> from translucency.rig.object.photographs import photograph_object
    >>> mesh, rig = trimesh.creation.icosphere(subdivisions=2, radius=6.0), Path(tempfile.mkdtemp()) / "rig"
    >>> _ = photograph_object(mesh, object_volume("homogeneous:skin1", mesh, 0.5, seed=1), rig, n_points=2,
    ...                       n_cameras=3, resolution=(32, 32), spp=4)  # tens of seconds  # doctest: +SKIP
    >>> imp = ObjectImport.from_setup(rig, chunk_points=1)  # doctest: +SKIP
    >>> imp.n_points, [c.camera.name for c in imp.cameras]  # doctest: +SKIP
    (2, ['cam0', 'cam1', 'cam2'])
    >>> out = tempfile.mkdtemp() + "/sphere.zarr"
    >>> flags = run_import(imp, out)  # pairs unseen, saturated, grazing, spot  # doctest: +SKIP
    >>> flags.shape  # doctest: +SKIP
    (4,)
    """

    setup: ObjectRig
    mesh: object  # trimesh.Trimesh, mm
    scene: object  # its Mitsuba scene (the near peak's walks)
    area: np.ndarray  # (V,) vertex areas A_v, mm²
    cameras: list[CameraView]
    incident: np.ndarray  # (P,) the vertex nearest each hit
    hits: np.ndarray  # (P, 3) where each shot enters, mm
    toward: np.ndarray  # (P, 3) unit direction from each hit toward its laser
    law: ExitLaw
    header: dict
    chunk_points: int
    energy: np.ndarray  # (P, 3) Σ_v A_v R_d per shot
    energy_sigma: np.ndarray  # (P, 3) its standard deviation (shot_energy)
    bytes_read: int = 0  # image bytes read by the chunks imported
    saturated_views: int = 0  # cameras' views of a cell dropped for a saturated pixel (this run's chunks)
    recovered: int = 0  # pairs from the near-peak model (this run's chunks)
    walked: list = field(default_factory=list)  # shots converted with the walks' law (this run's chunks)

    @property
    def n_points(self) -> int:
        return len(self.incident)

    @classmethod
    def from_setup(cls, rig, *, chunk_points: int = 8, exit_law: str | None = None) -> ObjectImport:
        """Read ``object.json`` and the mesh, pose the cameras and map them, snap the hits, choose the law."""
        from ...io.mesh import load_mesh  # heavy: trimesh loads where a mesh is read

        if chunk_points < 1:
            raise TranslucencyError(f"chunk_points: must be >= 1, got {chunk_points}")
        setup = read_object_rig(rig)
        law_name = exit_law or setup.exit_law
        fixed_law = law_named(law_name, setup.eta)
        mesh = load_mesh(setup.mesh_file, scale_mm=setup.scale_mm, up=setup.up)
        scene = mesh_scene(mesh)
        area = vertex_areas(mesh)
        V = len(mesh.vertices)
        posed = [calibrated_camera(c, setup.folder, setup.max_reprojection_px) for c in setup.cameras]
        check_mesh_seen(mesh, posed, setup)  # before the maps: a wrong mesh is named as such, not as a camera
        incident, hits, toward = incident_vertices(setup, mesh, scene)
        beam_polar = polar_deg(toward, np.asarray(mesh.vertex_normals)[incident])
        _say_oblique(setup, beam_polar)
        # the poses checked by the data before the maps: each camera's laser spots against its projected hits
        for camera, miss in zip(posed, _spot_misses(setup, posed, hits, scene)):
            if miss is not None:
                camera.reprojection_px["laser_spot"] = miss
        cameras = [prepare_view(c, cam, setup, mesh, scene) for c, cam in zip(setup.cameras, posed)]
        P = len(incident)
        if fixed_law is None and len(cameras) < 2:
            raise TranslucencyError(
                f"{setup.path}: exit_law 'from-views' needs two cameras or more; "
                "give 'lambertian' or 'dielectric'"
            )
        law = fixed_law
        if law is None:  # estimated from the first shots (reading them once more in the chunks)
            try:
                law = estimate_law(setup, cameras, mesh, scene, hits, area)
            except TranslucencyError as exc:  # too few views of one vertex: say so, and take π L
                # stacklevel 3: the warning names the caller of import_object
                warnings.warn(f"{setup.path}: {exc} — imported with the Lambertian law instead", stacklevel=3)
                law = Lambertian()
        sample = setup.sample or {}
        request = {
            "rig": str(setup.path.resolve()),
            "rig_sha256": sha256_file(setup.path),
            "chunk": int(chunk_points),
            "exit_law": law.describe(),
            "vertices": V,
            "faces": len(mesh.faces),
            "bounds": np.round(mesh.bounds, 6).tolist(),
            "index_matched": setup.eta == 1.0,
            # a virtual rig's filling (so that a reference can be rendered as for `acquire mesh`);
            # a lab has none
            "volume": sample.get("description", {"source": "photographs"}),
            "volume_grid": sample.get("volume_grid"),
        }
        request = json.loads(json.dumps(request))
        header = mesh_header(
            n_points=P,
            n_vertices=V,
            photons=0,  # set from the measured noise once the data are in (the fit's weights)
            seed=0,
            # the medium's index (recorded apart when the boundary is index-matched, as `acquire mesh` does)
            eta=(setup.raw.get("boundary") or {}).get("medium_eta", setup.eta),
            g=sample.get("description", {}).get("g", 0.0),
            sample=sample.get("description", {"source": "photographs"}),
            request=request,
            source="photographs",
            boundary_eta=float(setup.eta),  # what light crosses at the surface (1: index-matched)
            photographs=_provenance(setup, cameras, hits, law, toward, beam_polar),
        )
        E = np.zeros((P, 3))
        return cls(
            setup, mesh, scene, area, cameras, incident, hits, toward, law, header, chunk_points, E, E.copy()
        )

    def create(self, out, *, overwrite: bool) -> MeshDataset:
        """The mesh data set at ``out``: the mesh, its vertex areas and the incident vertices."""
        return create_mesh_dataset(
            out,
            self.header,
            self.mesh,
            self.area,
            self.incident,
            chunk_points=self.chunk_points,
            overwrite=overwrite,
            inputs=self.setup.files,
            measured=True,
        )

    def import_chunks(self, ds: MeshDataset, todo: list[Chunk]) -> Iterator[Chunk]:
        """Per shot: the cameras' cell means, fused, flagged, the unseen filled; per chunk its R_d, variance
        and flags written, then its done flag."""
        setup, mesh, area, law = self.setup, self.mesh, self.area, self.law
        cameras, hits = self.cameras, self.hits
        root, V, energy = ds.group, len(mesh.vertices), self.energy
        fill = HarmonicFill(mesh)
        every = {"write_empty_chunks": True}
        for chunk in todo:
            c, lo, hi = chunk.index, chunk.lo, chunk.hi
            R = np.zeros((hi - lo, V, 3), np.float32)
            var = np.zeros((hi - lo, V, 3), np.float32)
            flags = np.zeros((hi - lo, V), np.uint8)
            for j in range(lo, hi):
                r = np.linalg.norm(mesh.vertices - hits[j], axis=1)
                aside = self._glint(j)
                Rj, vj, fj, missing, least, params = self._convert(j, r, aside)
                for _ in range(WALK_ROUNDS if isinstance(law, Walked) else 0):  # again, at the material found
                    if all(p is None for p in params):
                        break
                    view_law = ShotWalkLaw(
                        mesh, self.scene, hits[j], mesh.vertex_normals[self.incident[j]], params,
                        [cam.camera.centre for cam in cameras], eta=setup.eta, seed=7 + 104729 * j,
                    )  # fmt: skip
                    Rj, vj, fj, missing, least, params = self._convert(j, r, aside, view_law)
                    self.walked.append(j)
                Rj = fill(Rj, missing)
                vj = fill.variance(Rj, vj, missing)
                # a clipped spot away from the hit (the glint's reflected beam lighting another part): its
                # cells hold at least what their clipped pixels show
                far = ((fj & SATURATED) != 0) & (r > near_peak_reach(r, fj))
                Rj = np.where(far[:, None], np.fmax(Rj, np.nan_to_num(least)), Rj)
                R[j - lo], var[j - lo], flags[j - lo] = Rj, vj, fj
                energy[j], self.energy_sigma[j] = shot_energy(Rj, vj, fj, area)
            root["R_d"].with_config(every)[lo:hi] = R
            root["R_d_var"].with_config(every)[lo:hi] = var
            root["flags"].with_config(every)[lo:hi] = flags
            root["specular"].with_config(every)[lo:hi] = np.zeros((hi - lo, 3), np.float32)
            root["chunk_done"][c] = True
            yield chunk

    def _convert(self, j: int, r, aside: dict, view_law=None):
        """Shot ``j``'s photographs to R_d: the cameras' cell means (through ``view_law``, a per-camera law,
        where given), fused and flagged, the near peak recovered; the cells still missing, the clipped
        cells' least values and the near peak's (σ_t, α) per channel."""
        setup = self.setup
        per_cam, views, nbytes = shot_cell_means(
            setup.shots[j], self.cameras, setup, self.law, self.hits[j], pixels=True, aside=aside,
            view_law=view_law,
        )  # fmt: skip
        self.bytes_read += nbytes
        R, var, flags, dropped, least = fuse(per_cam, self.cameras, self.area, setup)
        self.saturated_views += dropped
        if setup.spot_radius_mm > 0:  # within a stated spot; 0: none (the hit vertex is measured)
            flags[r <= setup.spot_radius_mm] |= SPOT
        R, var, missing, params = self._recover(R, var, flags, r, j, least, [v for v in views if v])
        return R, var, flags, missing, least, params

    def _glint(self, j: int) -> dict:
        """Per camera name, the pixels (of its used ones) the laser's glint may light in shot ``j``
        (:mod:`.glint`): none on an index-matched boundary."""
        if self.setup.eta == 1.0 or self.setup.glint_deg <= 0:
            return {}
        normal = self.mesh.vertex_normals[self.incident[j]]
        return {
            cam.setup.name: glint_pixels(
                cam.camera, cam.map.used, self.hits[j], normal, self.toward[j], glint_deg=self.setup.glint_deg
            )
            for cam in self.cameras
        }

    def _recover(self, R, var, flags, r, j, least, views):
        """The cells at the hit that saturated, lie in the stated spot or went unseen there, from the
        near-peak model (:mod:`.near_peak`, fitted to the pixels of ``views`` that see them and their
        ring, the clipped ones as lower bounds); where the model reads short of the clipped pixels as a
        whole (``short``), the clip's value (``least``), with a standard deviation that spreads half
        the light energy conservation leaves unaccounted for over those cells; the cells still missing
        (to fill)."""
        peak = ((flags & (SATURATED | SPOT)) != 0) & (r <= near_peak_reach(r, flags))
        unseen = (flags & UNSEEN) != 0
        if not peak.any():
            return R, var, unseen, [None] * 3
        near = peak | (unseen & (r <= r[peak].max()))
        hit, mesh = self.hits[j], self.mesh
        # the scan's own shape: photon walks on it at the fitted material (seeded by the shot: resumable)
        normal = mesh.vertex_normals[self.incident[j]]
        shape = MeshWalkGain(mesh, self.scene, hit, normal, seed=1 + 104729 * j, eta=self.setup.eta)
        measured = flags == 0
        R, var, ok, short, params = recover_near_peak(
            mesh, hit, R, var, near, measured, self.setup.eta, views, shape, self.scene
        )
        # where the model reads short of the clipped pixels, the peak is steeper than any the ring implies
        # (a horn's tip, a thin part): its cells hold at least the clip's value, and how much more only
        # energy conservation bounds — the light not yet accounted for, Σ_v A_v R_v ≤ 1 per W.  (Elsewhere
        # the fit honoured each clipped pixel as a lower bound on its footprint's mean; a cell's `least` is
        # what its clipped pixels hold over the part of it they cover, per unit of its whole area: their
        # mean alone is no bound on a cell larger than them — it read the flank's shot of spot.obj 2-3x high.)
        below = near[:, None] & (R < least) & short[None, :]
        R = np.where(below, least, R)
        unknown = np.maximum(0.0, 1.0 - self.area @ R)  # (3,)
        share = np.maximum((self.area[:, None] * below).sum(axis=0), 1e-30)
        var = np.where(below, np.maximum(var, (0.5 * unknown / share) ** 2), var)
        if ok:
            self.recovered += int(near.sum())
        return R, var, unseen & ~near if ok else unseen | near, params

    def finish(self, ds: MeshDataset, done: list[Chunk]) -> np.ndarray:
        """The energy of the shots imported before, the photon count equivalent to the measured noise (into
        the header); the pairs of each flag counted (UNSEEN, SATURATED, GRAZING, SPOT)."""
        root, area = ds.group, self.area
        for chunk in done:
            lo, hi = chunk.lo, chunk.hi
            R, var = (np.asarray(root[k][lo:hi], dtype=np.float64) for k in ("R_d", "R_d_var"))
            flags = np.asarray(root["flags"][lo:hi])
            for j in range(lo, hi):
                self.energy[j], self.energy_sigma[j] = shot_energy(
                    R[j - lo], var[j - lo], flags[j - lo], area
                )
        flag_counts = np.zeros(4, dtype=np.int64)
        flags_all = np.asarray(root["flags"][...])
        for b, bit in enumerate((UNSEEN, SATURATED, GRAZING, SPOT)):
            flag_counts[b] = int(((flags_all & bit) != 0).sum())
        self.header["photons"] = _equivalent_photons(root, area, flags_all)
        root.attrs.update({"translucency_mesh_dataset": self.header})
        return flag_counts


#: conversions with the walks' law (``exit_law: "walk"``) after the first with π L, each at the material
#: the one before fitted: under π L the near peak reads skin1's red albedo 0.73-0.82 for 0.96, after one
#: round 0.93-0.96 (spot.obj, three shots); a second round moved the energies by up to 20 % and no nearer
#: (docs/validation/object-rig.md, Limits)
WALK_ROUNDS = 1

#: a gap this wide (mm) in the distances of the clipped cells from the hit ends the hit's own peak
PEAK_GAP_MM = 2.0


def near_peak_reach(r: np.ndarray, flags: np.ndarray) -> float:
    """How far (mm) the hit's own peak reaches: the clipped or spot cells (``flags``) from the hit outward
    until their distances ``r`` leave a gap of :data:`PEAK_GAP_MM`; −1 where none lies within it of the
    hit.  Clipped cells beyond are another bright spot — light the boundary reflected at the hit onto
    another part of the object — which no radial profile about the hit describes.

    Examples
    --------
    >>> r = np.array([0.0, 0.4, 0.9, 1.5, 6.0, 21.0, 22.0])
    >>> near_peak_reach(r, np.array([2, 2, 2, 0, 0, 2, 2], np.uint8))
    0.9
    >>> near_peak_reach(r, np.array([0, 0, 0, 0, 0, 2, 2], np.uint8))
    -1.0
    """
    d = np.sort(r[(flags & (SATURATED | SPOT)) != 0])
    if len(d) == 0 or d[0] > PEAK_GAP_MM:
        return -1.0
    gap = np.flatnonzero(np.diff(d) > PEAK_GAP_MM)
    return float(d[gap[0]] if len(gap) else d[-1])


def shot_energy(R, var, flags, area):
    r"""A shot's energy :math:`E = \sum_v A_v R_v` per channel and its standard deviation.

    The measured cells' errors are independent (photon and read noise): they add in quadrature. The
    flagged cells' come from one model (the near peak) or one fill over their neighbours: their errors
    move together, so their standard deviations add linearly —
    :math:`\sigma_E = \sum_{v\,\text{flagged}} A_v \sigma_v
    + (\sum_{v\,\text{measured}} A_v^2 \sigma_v^2)^{1/2}`.

    It states the noise and the near-peak model's uncertainty, not the systematic errors of measured cells
    (a footprint's blur, a thin part's silhouette): on photographs without a clipped pixel it is 0.2–1.5 %
    where the error measured 1–23 % (docs/validation/object-rig.md).

    Examples
    --------
    >>> area = np.array([1.0, 2.0, 1.0])
    >>> R = np.full((3, 3), 0.1)
    >>> var = np.array([[0.01] * 3, [0.0001] * 3, [0.0001] * 3])
    >>> E, s = shot_energy(R, var, np.array([1, 0, 0], np.uint8), area)
    >>> np.round(E, 3).tolist(), np.round(s, 4).tolist()  # 0.1 + sqrt(4e-4 + 1e-4)
    ([0.4, 0.4, 0.4], [0.1224, 0.1224, 0.1224])
    """
    sd = np.sqrt(np.maximum(np.nan_to_num(var), 0.0))
    flagged = flags != 0
    sigma = area[flagged] @ sd[flagged] + np.sqrt((area[~flagged] ** 2) @ (sd[~flagged] ** 2))
    return area @ R, sigma


def _finished_any(out) -> bool:
    """Whether the data set at ``out`` holds a finished chunk (kept for resuming when interrupted)."""
    try:
        return bool(np.asarray(open_mesh_dataset(out)["chunk_done"][...]).any())
    except TranslucencyError:
        return False


def _equivalent_photons(root, area, flags) -> float:
    r"""The photon count N with Poisson variance R/(N A_v) closest to the measured variance of the pairs
    above 5 σ (median): the per-vertex fit weights its pairs by that model (:mod:`translucency.fit.mesh`)."""
    R = np.asarray(root["R_d"][...], dtype=np.float64).mean(axis=2)
    var = np.asarray(root["R_d_var"][...], dtype=np.float64).mean(axis=2)
    ok = (flags == 0) & (var > 0) & (R > 5 * np.sqrt(np.maximum(var, 0)))
    if not ok.any():
        return 1.0
    A = np.broadcast_to(area[None], R.shape)
    return float(np.median(R[ok] / (var[ok] * A[ok])))


def _spot_misses(setup: ObjectRig, posed: list, hits: np.ndarray, scene) -> list:
    """Each camera's median laser-spot miss (px), or None for a camera that sees no hit."""
    misses = check_spots(setup, posed, hits, scene)
    return [misses.get(camera.name) for camera in posed]


def _say_oblique(rig: ObjectRig, beam_polar: np.ndarray) -> None:
    """One warning line for shots whose laser arrives obliquely at its hit: they are stored with their
    direction (the header's ``photographs.beam_polar_deg``); fit reads each as a normal beam for the profile
    and the lean from its asymmetry (:mod:`translucency.fit.lean_shots`)."""
    oblique = np.flatnonzero(beam_polar > OBLIQUE_DEG)
    if len(oblique):
        shots = ", ".join(str(j) for j in oblique[:6]) + (", …" if len(oblique) > 6 else "")
        warnings.warn(
            f"{rig.path}: {len(oblique)} shot(s) ({shots}) arrive {beam_polar[oblique].min():.0f}–"
            f"{beam_polar[oblique].max():.0f}° off the normal at their hit: stored with their directions, "
            "fit reads the profile as if each were a normal beam and the lean (render --angles) from their "
            "asymmetry — aim the laser along the normal for the profile",
            stacklevel=4,
        )


def _provenance(rig, cameras: list[CameraView], hits, law: ExitLaw, toward, beam_polar) -> dict:
    """The header's ``photographs`` record: where everything came from, each shot's hit, power, files and
    the direction toward its laser (with its polar angle at the incident vertex)."""
    return {
        "rig": str(rig.path.resolve()),
        "mesh": {"file": str(rig.mesh_file.resolve()), "sha256": sha256_file(rig.mesh_file)},
        "cameras": [
            {**c.camera.to_dict(), "name": c.camera.name, "reprojection_px": c.camera.reprojection_px}
            for c in cameras
        ],
        "hits_mm": np.round(hits, 6).tolist(),
        "toward_laser": np.round(toward, 6).tolist(),
        "beam_polar_deg": np.round(beam_polar, 3).tolist(),
        "power_W": [s.power for s in rig.shots],
        "files": [
            {cam: [str(f.file.relative_to(rig.folder)) for f in frames] for cam, frames in s.frames.items()}
            for s in rig.shots
        ],
        "exit_law": law.describe(),
        "boundary_eta": rig.eta,
        "spot_radius_mm": rig.spot_radius_mm,
        "grazing_deg": rig.grazing_deg,
        "min_coverage": rig.min_coverage,
    }


__all__ = ["import_object", "ObjectImport", "shot_energy", "UNSEEN", "SATURATED", "GRAZING", "SPOT"]
