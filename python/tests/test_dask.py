"""nbhd.dask on a distributed.LocalCluster of several worker processes reproduces the one-machine
results exactly: tables byte for byte, spacing, normals, curvatures and smoothed points to the
last bit, for float32 and float64, from a Dask array and from LAS/PLY tile files."""

import concurrent.futures
import time

import numpy as np
import pytest

import nbhd

da = pytest.importorskip("dask.array")
distributed = pytest.importorskip("distributed")
ndask = pytest.importorskip("nbhd.dask")

from conftest import sphere  # noqa: E402

N = 100_000


def surface(dtype):
    """A noisy sphere of N points with exact duplicates, some on the middle planes where the
    tiles meet (x = 0, y = 0, z = 0 cut a 2x2x2 grid of the bounding box [-1, 1]^3 nearly there)."""
    p = sphere(N - 2000, noise=0.002)
    dup = p[:1000].copy()
    dup[:300, 0] = 0.0  # on the x = 0 plane
    p = np.vstack([p, dup, p[5000:6000]]).astype(dtype)
    return p


def same(a, b):
    a, b = np.asarray(a), np.asarray(b)
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


def same_table(got, ref):
    return (
        same(got.offsets, ref.offsets)
        and same(got.indices, ref.indices)
        and same(got.sq_dists, ref.sq_dists)
    )


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_tables_from_a_dask_array(client, tmp_path, dtype):
    pts = surface(dtype)
    cloud = ndask.tile_array(da.from_array(pts, chunks=(17_000, 3)), str(tmp_path), grid=(2, 2, 2))
    assert cloud.tiles == 8 and cloud.n == N
    tree = nbhd.KdTree(pts)

    # batch: each task answers its ~12,500 queries 5,000 at a time (memory only)
    knn = cloud.knn(10, batch=5000)
    assert same_table(knn.assemble(), tree.neighborhoods(k=10))
    assert len(knn.parts) == 8

    r = 0.02
    assert same_table(cloud.radius(r, batch=5000).assemble(), tree.neighborhoods(radius=r))
    assert same_table(cloud.knn_radius(12, r).assemble(), tree.neighborhoods(k=12, radius=r))


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_geometry_and_smoothing_from_a_dask_array(client, tmp_path, dtype):
    pts = surface(dtype)
    cloud = ndask.tile_array(da.from_array(pts, chunks=(30_000, 3)), str(tmp_path), grid=(2, 2, 2))

    ref = nbhd.curvatures(pts, k=15, epsilon=6.0)
    # h: the library's mean spacing, summed in caller order by a chain of tasks of 7,919
    # points each (the running sum crosses 13 task boundaries)
    assert cloud.spacing(block=7919) == ref["spacing"]

    got = cloud.curvatures(k=15, epsilon=6.0).assemble()
    assert got.keys() == {k for k, v in ref.items() if isinstance(v, np.ndarray)}
    for key, v in got.items():
        assert same(v, ref[key]), key

    n_ref, c_ref, f_ref = nbhd.normals(pts, k=10, epsilon=4.0, orientation="toward-point",
                                       orientation_point=(0.0, 0.0, 0.0))
    got = cloud.normals(k=10, epsilon=4.0, orientation="toward-point").assemble()
    assert same(got["normals"], n_ref)
    assert same(got["surface_variation"], c_ref)
    assert same(got["flags"], f_ref)

    sref = nbhd.smooth(pts, outputs=True)  # anisotropic, 3 steps, relative ε and λ
    res = cloud.smooth(outputs=True)
    got = res.assemble()
    assert same(got["points"], sref["points"])
    for key, v in sref["outputs"].items():
        assert same(got["outputs." + key], v), key
    assert res.epsilon == sref["epsilon"]
    # the points moved: the comparison is not of the input with itself
    assert not np.array_equal(sref["points"], pts.astype(np.float64))


def test_isotropic_smoothing_with_a_feature_criterion(client, tmp_path):
    pts = surface(np.float64)
    cloud = ndask.tile_array(da.from_array(pts, chunks=(50_000, 3)), str(tmp_path), grid=(3, 2, 1))
    kw = dict(k=12, epsilon=5.0, steps=4, feature="principal", feature_threshold=0.5,
              weighting="continuous", constrain_interior=0.001)
    ref = nbhd.smooth(pts, **kw)
    got = cloud.smooth(**kw).assemble()
    assert same(got["points"], ref["points"])


def test_tile_files(client, tmp_path):
    """LAS and PLY tiles (nbhd.write, read back by the tasks with nbhd.read): tiles along x, and
    one file of points from everywhere (overlapping the others' boxes)."""
    pts = surface(np.float64)
    order = np.argsort(pts[:, 0], kind="stable")
    files = []
    groups = np.array_split(order[: N - 7000], 4) + [order[N - 7000:]]
    for i, g in enumerate(groups):
        path = tmp_path / (f"t{i}.las" if i % 2 else f"t{i}.ply")
        nbhd.write(str(path), pts[g], precision="double")
        files.append(str(path))
    ref_pts = np.vstack([nbhd.read(f)["positions"] for f in files])
    assert len(ref_pts) == N

    for dtype in (np.float64, np.float32):
        p = ref_pts.astype(dtype)
        store = tmp_path / f"store-{np.dtype(dtype).name}"
        cloud = ndask.tile_files(files, str(store), dtype=dtype)
        assert cloud.tiles == 5
        assert same_table(cloud.knn(8).assemble(), nbhd.KdTree(p).neighborhoods(k=8))
        if dtype == np.float64:
            got = cloud.normals(k=12).assemble()
            n_ref, c_ref, f_ref = nbhd.normals(p, k=12)
            assert same(got["normals"], n_ref) and same(got["surface_variation"], c_ref)
            sref = nbhd.smooth(p, method="isotropic")
            assert same(cloud.smooth(method="isotropic").assemble()["points"], sref["points"])


def test_halos_grow_and_refusals(client, tmp_path):
    rng = np.random.default_rng(5)
    pts = np.vstack([rng.random((5000, 3)), [[40.0, 40.0, 40.0]]])  # an isolated outlier
    cloud = ndask.tile_array(da.from_array(pts, chunks=(2000, 3)), str(tmp_path), grid=(3, 3, 3))
    res = cloud.knn(6)
    assert same_table(res.assemble(), nbhd.KdTree(pts).neighborhoods(k=6))
    assert max(res.halos) > 30  # the outlier's tile searched the whole cloud
    cloud.save()  # the store's description, read back by another process or session
    again = ndask.open_store(str(tmp_path))
    assert again.n == cloud.n and again.tiles == cloud.tiles
    assert same_table(again.knn(6).assemble(), nbhd.KdTree(pts).neighborhoods(k=6))
    with pytest.raises(ValueError, match="propagate"):
        cloud.normals(orientation="propagate")
    bad = pts.copy()
    bad[17, 1] = np.nan
    with pytest.raises(ValueError, match="point 17"):
        ndask.tile_array(da.from_array(bad, chunks=(2000, 3)), str(tmp_path / "bad"))


def wait_until_forgotten(client, keys, timeout=60.0):
    """Polls every worker (outside its busy thread, as ``Client.run`` does) until none of ``keys``
    is still waiting, ready or running there."""
    live = {"waiting", "ready", "constrained", "fetch", "flight", "executing", "resumed"}

    def held(dask_worker):
        tasks = dask_worker.state.tasks
        return [k for k in keys if k in tasks and tasks[k].state in live]

    deadline = time.monotonic() + timeout
    while any(client.run(held).values()):
        assert time.monotonic() < deadline, "cancelled tiles still held by a worker"
        time.sleep(0.05)


def test_progress_and_cancel(client, tmp_path):
    """compute=False: the job's futures (what distributed.progress draws) give the same result;
    cancelled before its tiles run, a job writes no file and the cluster stays usable."""
    pts = surface(np.float64)
    cloud = ndask.tile_array(da.from_array(pts, chunks=(25_000, 3)), str(tmp_path), grid=(4, 4, 2))
    job = cloud.knn(10, threads=1, compute=False)
    assert isinstance(job, ndask.TileJob) and len(job.tasks) == cloud.tiles
    futures = job.submit(client)
    distributed.wait(futures)
    assert [f.status for f in futures] == ["finished"] * cloud.tiles
    assert same_table(job.result().assemble(), nbhd.KdTree(pts).neighborhoods(k=10))

    # every worker's only thread held by a gate task, so that no tile can start before the cancel
    started, gate = distributed.Queue(), distributed.Event()

    def hold():
        started.put(1)
        gate.wait()

    workers = list(client.scheduler_info()["workers"])
    holds = [client.submit(hold, workers=[w], pure=False) for w in workers]
    for _ in workers:
        started.get(timeout=60)
    out = tmp_path / "cancelled"
    job = cloud.normals(k=10, epsilon=0.02, epsilon_units="absolute", threads=1, out=str(out),
                        compute=False)
    futures = job.submit()  # the current client
    job.cancel()
    # The scheduler frees a cancelled task on the workers by a message of its own, which can arrive
    # after the gate opens: wait until no worker holds one of the job's tiles ready to run.
    wait_until_forgotten(client, [f.key for f in futures])
    gate.set()
    distributed.wait(holds)
    assert all(f.cancelled() for f in futures)
    with pytest.raises(concurrent.futures.CancelledError):
        job.result()
    assert not any(out.glob("tile_*"))

    got = cloud.normals(k=10, epsilon=0.02, epsilon_units="absolute", threads=1).assemble()
    n_ref, _, _ = nbhd.normals(pts, k=10, epsilon=0.02, epsilon_units="absolute")
    assert same(got["normals"], n_ref)
