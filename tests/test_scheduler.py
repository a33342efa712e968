"""Where work runs (translucency.cluster): a Dask cluster gives the same bytes as one process.

One 2-worker LocalCluster serves the whole module (starting one takes seconds); the calls reach it by
its tcp:// address, as they would reach a cluster on other machines.
"""

import os
import time

import numpy as np
import pytest

from translucency import TranslucencyError
from translucency import cluster as cluster_mod
from translucency.acquire import PlanarSetup, acquire_planar, make_sample
from translucency.acquire.mesh import acquire_mesh, object_volume
from translucency.cluster import open_cluster, ordered_sum, parse_scheduler
from translucency.fit import fit_mesh, fit_planar
from translucency.io.dataset import open_dataset
from translucency.io.mesh_dataset import open_mesh_dataset

distributed = pytest.importorskip("distributed")

SETUP = PlanarSetup(grid=(8, 8), span=(6.0, 6.0), pitch=0.5, window=6.0, photons=1500, seed=3, chunk_points=8)
ARRAYS = ("x_i", "window_origin", "R_d", "variance", "mask", "specular", "total_diffuse", "chunk_done")
FIT = {"max_rounds": 2, "chunk_points": 16}


@pytest.fixture(scope="module")
def address():
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None, silence_logs=40
    ) as local:
        yield local.scheduler_address


@pytest.fixture(scope="module")
def volume():
    return make_sample("marble", (12, 12, 4), 0.5, seed=1)


@pytest.fixture(scope="module")
def threads_run(tmp_path_factory, volume):
    """The single-process acquisition and fit: the reference every cluster run must equal."""
    path = tmp_path_factory.mktemp("threads") / "d.zarr"
    ds = acquire_planar(volume, SETUP, path)
    return ds, fit_planar(ds, "iso", **FIT)


def _same_fit(a, b):
    np.testing.assert_array_equal(a.model.c, b.model.c)
    np.testing.assert_array_equal(a.model.d, b.model.d)
    np.testing.assert_array_equal(a.model.alpha.values, b.model.alpha.values)
    np.testing.assert_array_equal(a.flagged, b.flagged)
    assert a.history == b.history and a.best_round == b.best_round


def test_acquisition_on_a_cluster_is_bit_identical_and_resumes(address, volume, threads_run, tmp_path):
    ref, _ = threads_run

    class Stop(Exception):
        pass

    def interrupt(done, total):
        raise Stop

    with pytest.raises(Stop):  # stopped after the first finished chunk: the rest resumes on the cluster
        acquire_planar(volume, SETUP, tmp_path / "c.zarr", scheduler=address, progress=interrupt)
    assert not open_dataset(tmp_path / "c.zarr").complete()
    ds = acquire_planar(volume, SETUP, tmp_path / "c.zarr", scheduler=address)
    assert ds.complete()
    for key in ARRAYS:
        np.testing.assert_array_equal(ds[key], ref[key], err_msg=key)


def test_fit_on_a_cluster_is_bit_identical(address, threads_run):
    ds, ref = threads_run
    _same_fit(fit_planar(ds, "iso", scheduler=address, **FIT), ref)


def test_a_fit_interrupted_on_a_cluster_resumes_identically(address, threads_run, tmp_path):
    """Stopped in round 2: the checkpoint holds α's running sums (one grid, not one per chunk) and the
    next chunk to add; the fit resumed on the cluster equals the threads run bit for bit."""
    ds, ref = threads_run
    ckpt = tmp_path / "fit.partial.npz"

    class Stop(Exception):
        pass

    def interrupt(done, total, message):
        if done == 5:  # 4 chunks per round: round 2's first chunk is in
            raise Stop

    with pytest.raises(Stop):
        fit_planar(ds, "iso", scheduler=address, checkpoint=ckpt, progress=interrupt, **FIT)
    with np.load(ckpt) as z:
        assert z["num"].shape == z["den"].shape == ref.model.alpha.values.shape
        # round 2 (index 1) under way: how many of its chunks were added before the stop depends on
        # which workers finished first (on a loaded machine all 4 may be in before the callback
        # runs); the resumed fit must not care
        assert 1 <= int(z["added"][0]) <= 4 and int(z["round"][0]) == 1
    _same_fit(fit_planar(ds, "iso", scheduler=address, checkpoint=ckpt, **FIT), ref)
    assert not ckpt.exists()


def test_mesh_acquisition_and_fit_on_a_cluster_are_bit_identical(address, tmp_path):
    import trimesh

    ball = trimesh.creation.icosphere(2, radius=5.0)
    vol = object_volume("skin", ball, 1.0, seed=2)
    args = {"n_points": 12, "photons": 800, "seed": 5, "chunk_points": 4, "index_matched": True}
    here = acquire_mesh(ball, vol, tmp_path / "t.zarr", **args)
    there = acquire_mesh(ball, vol, tmp_path / "c.zarr", scheduler=address, **args)
    a, b = (open_mesh_dataset(p).group for p in (here, there))
    for key in ("R_d", "specular", "chunk_done", "incident"):
        np.testing.assert_array_equal(np.asarray(a[key][...]), np.asarray(b[key][...]), err_msg=key)
    options = {"max_rounds": 2, "chunk_points": 4}
    _same_fit(fit_mesh(here, "iso", scheduler=address, **options), fit_mesh(here, "iso", **options))


def test_a_worker_killed_during_a_fit_changes_nothing(address, threads_run, tmp_path):
    """A worker exits mid-task (a plugin ends its process as its first fit task starts executing): Dask
    runs the task again on another worker, the nanny starts a new worker, and the fit is unchanged."""
    ds, ref = threads_run
    flag = str(tmp_path / "killed")

    class DieOnce(distributed.WorkerPlugin):  # local class: pickled by value to the workers
        name = "translucency-test-die-once"

        def transition(self, key, start, finish, **kwargs):
            if finish != "executing" or not str(key).startswith("_fit_task"):
                return
            try:
                os.close(os.open(flag, os.O_CREAT | os.O_EXCL))  # the first task anywhere, once
            except FileExistsError:
                return
            os._exit(1)  # the task has started and will never finish here

    with distributed.Client(address, set_as_default=False) as client:
        client.register_plugin(DieOnce())
        try:
            fit = fit_planar(ds, "iso", scheduler=address, **FIT)
        finally:
            client.unregister_worker_plugin(DieOnce.name)
    assert os.path.exists(flag)  # a worker did die
    _same_fit(fit, ref)


def test_a_scheduler_that_does_not_answer_is_one_line(threads_run, monkeypatch):
    ds, _ = threads_run
    monkeypatch.setattr(cluster_mod, "CONNECT_TIMEOUT_S", 1.0)
    t0 = time.perf_counter()
    with pytest.raises(TranslucencyError, match=r"scheduler tcp://127\.0\.0\.1:9: no Dask scheduler") as err:
        fit_planar(ds, "iso", scheduler="tcp://127.0.0.1:9", **FIT)
    assert "\n" not in str(err.value)
    assert time.perf_counter() - t0 < 10


@pytest.mark.parametrize("bad", ["local:0", "local:x", "local:", "tcp://host", "tcp://h:99999", "dask", 3])
def test_bad_scheduler_options_are_one_line(bad):
    with pytest.raises(TranslucencyError, match="scheduler") as err:
        parse_scheduler(bad)
    assert "\n" not in str(err.value)


def test_parse_and_threads():
    assert str(parse_scheduler("local:3")) == "local:3"
    assert str(parse_scheduler(None)) == "threads" == str(parse_scheduler("Threads"))
    assert parse_scheduler("tcp://[::1]:8786").kind == "tcp"
    with open_cluster("threads") as c:
        assert c is None


def test_ordered_sum_does_not_depend_on_arrival():
    rng = np.random.default_rng(0)
    parts = [rng.normal(size=5) * 10.0 ** rng.integers(-8, 8) for _ in range(20)]
    expect = ordered_sum(enumerate(parts), 20)
    shuffled = list(enumerate(parts))
    rng.shuffle(shuffled)
    np.testing.assert_array_equal(ordered_sum(shuffled, 20), expect)
    with pytest.raises(ValueError):
        ordered_sum(enumerate(parts[:3]), 4)


def test_a_window_keeps_results_near_the_oldest_unfinished_task(address):
    """``Cluster.run(window=w)`` submits task i only when every task before i − w + 1 has finished: with
    the first task slow, no more than w − 1 later results can arrive before it."""

    def task(i):  # local: pickled by value to the workers
        import time as _time

        _time.sleep(1.0 if i == 0 else 0.01)
        return i

    with open_cluster(address) as cluster:
        order = [i for i, _ in cluster.run(task, [(i,) for i in range(8)], window=3)]
        assert sorted(order) == list(range(8))
        assert order.index(0) <= 2  # at most tasks 1 and 2 ran ahead of task 0
        assert [r for _, r in cluster.run(task, [(i,) for i in range(4)])] != []  # no window: all at once


def test_evaluate_on_a_cluster_is_identical(address, threads_run):
    """The errors' chunks as tasks that read their own chunks, summed in chunk order: the same numbers."""
    from translucency.evaluate.errors import planar_errors

    ds, ref = threads_run
    here = planar_errors(ref.model, ds, chunk_points=3)
    there = planar_errors(ref.model, ds, chunk_points=3, scheduler=address)
    assert here.rel_l2 == there.rel_l2 and here.bands == there.bands and here.energy == there.energy
    np.testing.assert_array_equal(here.per_point, there.per_point)
    np.testing.assert_array_equal(here.per_pixel, there.per_pixel)
    np.testing.assert_array_equal(here.per_pixel_noise, there.per_pixel_noise)


def _malloc_trim():
    return os.environ.get("MALLOC_TRIM_THRESHOLD_")


def test_local_workers_keep_glibc_adaptive_malloc():
    """Dask's nanny sets MALLOC_TRIM_THRESHOLD_, which switches off glibc's adaptive mmap threshold: every
    large NumPy temporary is mapped and faulted in afresh, and the fit ran 1.85× slower in a worker
    (benchmarks/scale_out.py). ``local:N`` workers start without it, with the rest of Dask's settings."""
    assert cluster_mod.worker_environ().get("OMP_NUM_THREADS") == 1
    with open_cluster("local:1", memory_limit="1GiB") as c:
        assert set(c.client.run(_malloc_trim).values()) == {None}
