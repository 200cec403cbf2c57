"""The statistical outlier filter on Dask tiles keeps exactly what `KdTree.remove_statistical_outliers`
keeps on one machine (float32 and float64, duplicates across tile borders, planted outliers), and the
kept points as a new tiled cloud give the one-machine results on `points[kept]` bit for bit."""

import numpy as np
import pytest

import nbhd

da = pytest.importorskip("dask.array")
distributed = pytest.importorskip("distributed")
ndask = pytest.importorskip("nbhd.dask")

from conftest import sphere  # noqa: E402


def noisy(dtype, n=40_000, seed=3):
    """A noisy sphere with duplicates on the tile borders and a few hundred scattered outliers
    (the filter's prey), in an order that mixes them in."""
    rng = np.random.default_rng(seed)
    p = sphere(n - 1500, noise=0.004)
    dup = p[:1000].copy()
    dup[:400, 1] = 0.0  # on the y = 0 plane, where tiles meet
    out = rng.uniform(-1.3, 1.3, size=(500, 3))
    p = np.vstack([p, dup, out])
    return p[rng.permutation(len(p))].astype(dtype)


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_outlier_removal_on_tiles_equals_one_machine(client, tmp_path, dtype):
    pts = noisy(dtype)
    cloud = ndask.tile_array(da.from_array(pts, chunks=(9_000, 3)), str(tmp_path / "s"),
                             grid=(2, 2, 2))
    tree = nbhd.KdTree(pts)
    for k, ratio in [(8, 1.0), (20, 0.0), (3, -0.5)]:
        want = tree.remove_statistical_outliers(k=k, std_ratio=ratio)
        kept = cloud.remove_statistical_outliers(k=k, std_ratio=ratio, batch=4000)
        got = kept.assemble()
        assert got.dtype == want.dtype and np.array_equal(got, want), (k, ratio)
        removed = np.setdiff1d(np.arange(len(pts)), want)
        assert np.array_equal(kept.removed(), removed)
    # the planted outliers are among the removed (a fact of the data, not of the tiling)
    assert len(removed) > 0


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_the_kept_points_as_a_tiled_cloud(client, tmp_path, dtype):
    pts = noisy(dtype, seed=5)
    cloud = ndask.tile_array(da.from_array(pts, chunks=(11_000, 3)), str(tmp_path / "s"),
                             grid=(2, 2, 1))
    kept = cloud.remove_statistical_outliers(k=10, std_ratio=1.0)
    rows = kept.assemble()
    sub = cloud.select(kept, store=str(tmp_path / "kept"))
    assert sub.n == len(rows) and sub.dtype == pts.dtype
    ref_pts = pts[rows]
    table = sub.knn(6).assemble()
    ref = nbhd.KdTree(ref_pts).neighborhoods(k=6)
    assert np.array_equal(table.offsets, ref.offsets)
    assert np.array_equal(table.indices, ref.indices)
    assert table.sq_dists.tobytes() == ref.sq_dists.tobytes()
    normals, variation, flags = nbhd.normals(ref_pts, k=10, epsilon=4.0)
    got = sub.normals(k=10, epsilon=4.0).assemble()
    assert got["normals"].tobytes() == normals.tobytes()
    assert got["surface_variation"].tobytes() == variation.tobytes()
    # the kept cloud's store reopens as it was
    sub.save()
    again = ndask.open_store(str(tmp_path / "kept"))
    assert again.n == sub.n and again.tiles == sub.tiles


def test_outlier_removal_refusals(client, tmp_path):
    pts = noisy(np.float64, n=3000)
    cloud = ndask.tile_array(da.from_array(pts, chunks=(1000, 3)), str(tmp_path / "s"),
                             grid=(2, 1, 1))
    with pytest.raises(ValueError, match="k must be"):
        cloud.remove_statistical_outliers(k=0)
    with pytest.raises(ValueError, match="nearest other points"):
        cloud.remove_statistical_outliers(k=len(pts))
    with pytest.raises(ValueError, match="not finite"):
        cloud.remove_statistical_outliers(k=5, std_ratio=float("nan"))


def test_the_filter_steps_are_the_library_filter(rng):
    """The three steps the tiles take, run on one part, give the library filter's kept set."""
    pts = rng.random((3000, 3))
    tree = nbhd.KdTree(pts)
    table = tree.neighborhoods(k=7)
    sq = table.sq_dists.reshape(-1, 7)
    d = nbhd.mean_distances(sq)
    assert d.shape == (3000,) and d.dtype == np.float64
    total = nbhd.ExactSum()
    total.add(d)
    mean = total.value() / len(d)
    # the spread of two halves merged is the spread of the whole, bit for bit
    a = nbhd.squared_deviation_sum(d[:1234], mean)
    a.merge(nbhd.squared_deviation_sum(d[1234:], mean))
    whole = nbhd.squared_deviation_sum(d, mean)
    assert a.value() == whole.value()
    t = nbhd.outlier_threshold(mean, whole, len(d), 1.5)
    assert np.array_equal(np.flatnonzero(d <= t).astype(np.uint32),
                          tree.remove_statistical_outliers(k=7, std_ratio=1.5))
    with pytest.raises(ValueError):
        nbhd.mean_distances(np.zeros((4, 0)))


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_voxel_grid_on_tiles_equals_one_machine(client, tmp_path, dtype):
    pts = noisy(dtype, n=30_000, seed=9)
    # points exactly on voxel borders and on the tiles' cut planes (x = 0 here)
    pts[:500, 0] = 0.0
    pts[500:800, 2] = np.float32(0.25)
    cloud = ndask.tile_array(da.from_array(pts, chunks=(7_000, 3)), str(tmp_path / "s"),
                             grid=(3, 2, 1))
    for leaf, minimum in [(0.05, 0), ([0.08, 0.03, 0.125], 3)]:
        want = nbhd.voxel_grid(pts, leaf, min_points_per_voxel=minimum)
        res = cloud.voxel_grid(leaf, min_points_per_voxel=minimum)
        got = res.assemble()
        assert got.keys() == want.keys()
        for key in want:
            assert got[key].dtype == want[key].dtype, key
            assert got[key].tobytes() == want[key].tobytes(), (leaf, key)
    # the centroids as a tiled cloud, in the voxels' order: its tables are the one-machine ones
    sub = res.cloud(store=str(tmp_path / "voxels"), buckets=5)
    assert sub.n == len(want["nearest"]) and sub.dtype == pts.dtype
    table = sub.knn(5).assemble()
    ref = nbhd.KdTree(want["centroids"]).neighborhoods(k=5)
    assert np.array_equal(table.offsets, ref.offsets)
    assert np.array_equal(table.indices, ref.indices)
    assert table.sq_dists.tobytes() == ref.sq_dists.tobytes()


def test_voxel_grid_refusals_are_the_library_ones(client, tmp_path):
    pts = noisy(np.float32, n=3000)
    pts[0] = (1e6, 0.0, 0.0)  # an extent that a tiny leaf cannot number in float32
    cloud = ndask.tile_array(da.from_array(pts, chunks=(1000, 3)), str(tmp_path / "s"),
                             grid=(2, 1, 1))
    with pytest.raises(ValueError) as tiled:
        cloud.voxel_grid(1e-3)
    with pytest.raises(ValueError) as one:
        nbhd.voxel_grid(pts, 1e-3)
    assert str(tiled.value) == str(one.value)
    with pytest.raises(ValueError, match="leaf"):
        cloud.voxel_grid(-1.0)
