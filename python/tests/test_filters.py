"""The point filters: statistical and radius outlier removal on both tree classes and the voxel
grid, against brute force in numpy (sequential sums, as the library adds), against the static
tree for a growing one, and against the command-line tool's files."""

import subprocess

import numpy as np
import pytest

import nbhd


def grid_cloud(n: int, dtype: str, seed: int = 5) -> np.ndarray:
    """Integer coordinates: every squared distance is exact in float32 and float64, so the
    brute force decides each comparison as the library does. Duplicates, points exactly on
    the radius, and a few far outliers."""
    rng = np.random.default_rng(seed)
    pts = rng.integers(0, 8, size=(n, 3)).astype(dtype)
    pts[: n // 20] = pts[n // 20]  # duplicates
    pts[-3:] = [[40, 0, 0], [0, 40, 0], [30, 30, 30]]  # outliers
    return pts


def trees(pts: np.ndarray, dtype: str):
    """A KdTree and a DynamicKdTree over the same rows (NaN rows skipped by both)."""
    dyn = nbhd.DynamicKdTree(pts.shape[1], dtype=dtype, non_finite="skip")
    dyn.insert(pts)
    return [nbhd.KdTree(pts, non_finite="skip"), dyn]


def sequential_sum(v: np.ndarray) -> float:
    """The sum added left to right (numpy's sum is pairwise)."""
    return float(np.cumsum(v, dtype=np.float64)[-1]) if len(v) else 0.0


def brute_sor(pts: np.ndarray, k: int, std_ratio: float) -> np.ndarray:
    finite = np.flatnonzero(np.isfinite(pts).all(axis=1))
    x = pts[finite].astype(np.float64)
    d2 = ((x[:, None, :] - x[None, :, :]) ** 2).sum(axis=2)
    np.fill_diagonal(d2, np.inf)
    nearest = np.sort(d2, axis=1)[:, :k]
    d = np.array([sequential_sum(np.sqrt(row)) / k for row in nearest])
    n = len(d)
    mean = sequential_sum(d) / n
    sigma = np.sqrt(sequential_sum((d - mean) * (d - mean)) / (n - 1)) if n > 1 else 0.0
    return finite[d <= mean + std_ratio * sigma].astype(np.uint32)


def brute_ror(pts: np.ndarray, radius: float, min_neighbors: int) -> np.ndarray:
    finite = np.flatnonzero(np.isfinite(pts).all(axis=1))
    x = pts[finite].astype(np.float64)
    d2 = ((x[:, None, :] - x[None, :, :]) ** 2).sum(axis=2)
    others = (d2 <= radius * radius).sum(axis=1) - 1
    return finite[others >= min_neighbors].astype(np.uint32)


@pytest.mark.parametrize("dtype", ["float32", "float64"])
@pytest.mark.parametrize("k,std_ratio", [(1, 1.0), (6, 0.0), (12, -0.2), (50, 1.0)])
def test_statistical_outliers_equal_brute_force(dtype, k, std_ratio):
    pts = grid_cloud(600, dtype)
    pts[7, 1] = np.nan  # skipped: never kept, no part in the mean
    want = brute_sor(pts, k, std_ratio)
    assert 0 < len(want) < 600
    for tree in trees(pts, dtype):
        for threads in (1, 2):
            kept = tree.remove_statistical_outliers(k=k, std_ratio=std_ratio, threads=threads)
            assert kept.dtype == np.uint32
            np.testing.assert_array_equal(kept, want)
    assert 597 not in want and 7 not in want


@pytest.mark.parametrize("dtype", ["float32", "float64"])
@pytest.mark.parametrize("radius,min_neighbors", [(1.0, 2), (1.5, 4), (0.0, 1), (2.0, 0)])
def test_radius_outliers_equal_brute_force(dtype, radius, min_neighbors):
    pts = grid_cloud(600, dtype)
    pts[7, 1] = np.nan
    want = brute_ror(pts, radius, min_neighbors)
    for tree in trees(pts, dtype):
        kept = tree.remove_radius_outliers(radius, min_neighbors=min_neighbors, threads=2)
        assert kept.dtype == np.uint32
        np.testing.assert_array_equal(kept, want)
    assert 7 not in want


def test_filters_default_to_the_rust_options():
    pts = grid_cloud(400, "float64")
    tree = nbhd.KdTree(pts)
    # StatisticalOutlierOptions::default(): k = 50, std_ratio = 1;
    # RadiusOutlierOptions::within(r): min_neighbors = 2
    np.testing.assert_array_equal(tree.remove_statistical_outliers(), brute_sor(pts, 50, 1.0))
    np.testing.assert_array_equal(tree.remove_radius_outliers(1.0), brute_ror(pts, 1.0, 2))


def test_growing_tree_filters_equal_the_static_tree_of_its_live_points():
    pts = grid_cloud(700, "float64", seed=9)
    dyn = nbhd.DynamicKdTree(3, dtype="float64")
    dyn.insert(pts[:300])
    dyn.insert(pts[300:])
    gone = np.arange(0, 700, 4)
    dyn.remove(gone.tolist())
    masked = pts.copy()
    masked[gone] = np.nan
    fixed = nbhd.KdTree(masked, non_finite="skip")
    for k, ratio in [(3, 0.5), (8, 1.0)]:
        a = dyn.remove_statistical_outliers(k=k, std_ratio=ratio)
        np.testing.assert_array_equal(a, fixed.remove_statistical_outliers(k=k, std_ratio=ratio))
        assert np.intersect1d(a, gone).size == 0
    np.testing.assert_array_equal(
        dyn.remove_radius_outliers(1.0, min_neighbors=3),
        fixed.remove_radius_outliers(1.0, min_neighbors=3),
    )
    # k counts the live points: 525 of them
    with pytest.raises(nbhd.NbhdValueError, match="the tree holds 525"):
        dyn.remove_statistical_outliers(k=525)


def test_filters_refuse_bad_input_with_python_names():
    pts = grid_cloud(50, "float64")
    for tree in trees(pts, "float64"):
        with pytest.raises(nbhd.NbhdValueError, match="k must be at least 1"):
            tree.remove_statistical_outliers(k=0)
        with pytest.raises(nbhd.NbhdValueError, match="option k: 50 nearest"):
            tree.remove_statistical_outliers(k=50)
        with pytest.raises(nbhd.NbhdValueError, match="option std_ratio"):
            tree.remove_statistical_outliers(k=3, std_ratio=float("nan"))
        with pytest.raises(nbhd.NbhdValueError, match="radius"):
            tree.remove_radius_outliers(-1.0)
        with pytest.raises(nbhd.NbhdValueError, match="radius"):
            tree.remove_radius_outliers(float("nan"))
        with pytest.raises(nbhd.NbhdValueError, match="threads"):
            tree.remove_radius_outliers(1.0, threads=nbhd.MAX_THREADS + 1)
        with pytest.raises(TypeError):
            tree.remove_statistical_outliers(3)  # keyword-only, as in the stubs
        with pytest.raises(OverflowError):
            tree.remove_radius_outliers(1.0, min_neighbors=-1)


def test_filters_of_an_empty_cloud():
    empty = np.zeros((0, 3))
    dyn = nbhd.DynamicKdTree(3, dtype="float64")
    for tree in [nbhd.KdTree(empty), dyn]:
        kept = tree.remove_radius_outliers(1.0)
        assert kept.dtype == np.uint32 and kept.shape == (0,)
        with pytest.raises(nbhd.NbhdValueError):
            tree.remove_statistical_outliers(k=1)
    g = nbhd.voxel_grid(empty, 1.0)
    assert g["centroids"].shape == (0, 3) and g["nearest"].shape == (0,)
    assert list(g["offsets"]) == [0] and g["members"].shape == (0,)


# --- voxel grid ------------------------------------------------------------------------------


def brute_voxels(pts: np.ndarray, leaf: float, min_points: int = 0):
    """PCL's voxel grid in the points' type: cells floor(x * (1 / leaf)), voxels in ascending
    linear index (x fastest), centroids summed in ascending index, nearest member in f64."""
    t = pts.dtype.type
    finite = np.flatnonzero(np.isfinite(pts).all(axis=1))
    cells = np.floor(pts[finite] * t(1.0 / leaf)).astype(np.int64)
    order = np.lexsort(cells.T)  # the last coordinate most significant
    keys = cells[order]
    starts = [0] + [i for i in range(1, len(keys)) if (keys[i] != keys[i - 1]).any()]
    bounds = list(zip(starts, starts[1:] + [len(keys)]))
    centroids, nearest, members = [], [], []
    for a, b in bounds:
        rows = np.sort(finite[order[a:b]])
        if len(rows) < min_points:
            continue
        total = np.cumsum(pts[rows], axis=0, dtype=pts.dtype)[-1]
        c = total / t(len(rows))
        diff = pts[rows].astype(np.float64) - c.astype(np.float64)
        d2 = diff[:, 0] ** 2 + diff[:, 1] ** 2 + diff[:, 2] ** 2
        centroids.append(c)
        nearest.append(rows[np.argmin(d2)])
        members.append(rows)
    return centroids, nearest, members


@pytest.mark.parametrize("dtype", ["float32", "float64"])
@pytest.mark.parametrize("min_points", [0, 3])
def test_voxel_grid_equals_brute_force(dtype, min_points):
    rng = np.random.default_rng(21)
    pts = (rng.random((1500, 3)) * 4 - 1).astype(dtype)
    pts[:20] = pts[20]  # a crowded voxel
    pts[33] = [np.nan, 0, 0]  # left out
    pts[34] = [np.inf, 0, 0]
    centroids, nearest, members = brute_voxels(pts, 0.5, min_points)
    g = nbhd.voxel_grid(pts, 0.5, min_points_per_voxel=min_points, threads=2)
    assert g["centroids"].dtype == pts.dtype and g["nearest"].dtype == np.uint32
    assert g["offsets"].dtype == np.uint64 and g["members"].dtype == np.uint32
    np.testing.assert_array_equal(g["centroids"], np.array(centroids, dtype=dtype))
    np.testing.assert_array_equal(g["nearest"], np.array(nearest, dtype=np.uint32))
    assert len(g["offsets"]) == len(centroids) + 1
    for v, rows in enumerate(members):
        np.testing.assert_array_equal(g["members"][g["offsets"][v] : g["offsets"][v + 1]], rows)
    assert 33 not in g["members"] and 34 not in g["members"]


def test_voxel_grid_leaf_per_axis_and_errors():
    pts = np.array([[0.1, 0.1, 0.1], [0.9, 0.1, 0.1], [0.1, 2.5, 0.1]])
    g = nbhd.voxel_grid(pts, [2.0, 1.0, 1.0])
    np.testing.assert_array_equal(g["offsets"], [0, 2, 3])
    np.testing.assert_array_equal(g["members"], [0, 1, 2])
    same = nbhd.voxel_grid(pts, np.array([2.0, 1.0, 1.0]))
    np.testing.assert_array_equal(same["centroids"], g["centroids"])
    with pytest.raises(nbhd.NbhdValueError, match="leaf"):
        nbhd.voxel_grid(pts, 0.0)
    with pytest.raises(nbhd.NbhdValueError, match="leaf"):
        nbhd.voxel_grid(pts, float("nan"))
    with pytest.raises(nbhd.NbhdValueError, match="2 leaf sizes"):
        nbhd.voxel_grid(pts, [1.0, 1.0])
    with pytest.raises(nbhd.NbhdValueError, match="leaf must be a number"):
        nbhd.voxel_grid(pts, "big")
    with pytest.raises(nbhd.NbhdValueError, match="2-D"):
        nbhd.voxel_grid(pts[0], 1.0)


# --- against the command-line tool ---------------------------------------------------------


def run(cli, *args):
    subprocess.run([cli, *map(str, args), "--quiet"], check=True, capture_output=True)


def test_filters_equal_the_cli(cli, tmp_path):
    pts = grid_cloud(500, "float64") * 0.25
    src = tmp_path / "in.ply"
    nbhd.write(src, pts, precision="double")
    tree = nbhd.KdTree(pts)
    run(cli, "sor", src, tmp_path / "sor.ply", "--k", 6, "--std-ratio", 0.5)
    kept = tree.remove_statistical_outliers(k=6, std_ratio=0.5)
    np.testing.assert_array_equal(nbhd.read(tmp_path / "sor.ply")["positions"], pts[kept])
    run(cli, "ror", src, tmp_path / "ror.ply", "--radius", 0.25, "--min-neighbors", 3)
    kept = tree.remove_radius_outliers(0.25, min_neighbors=3)
    np.testing.assert_array_equal(nbhd.read(tmp_path / "ror.ply")["positions"], pts[kept])
    run(cli, "voxel", src, tmp_path / "voxel.ply", "--leaf", 0.5, "--nearest")
    g = nbhd.voxel_grid(pts, 0.5)
    np.testing.assert_array_equal(nbhd.read(tmp_path / "voxel.ply")["positions"], pts[g["nearest"]])
