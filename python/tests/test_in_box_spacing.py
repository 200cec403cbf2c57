"""Box queries and the spacing on both tree classes, against brute force in numpy."""

import numpy as np
import pytest

import nbhd


def cloud(n: int, dtype: str) -> np.ndarray:
    rng = np.random.default_rng(7)
    pts = rng.integers(0, 6, size=(n, 3)).astype(dtype)  # a grid: many points on box faces
    pts[: n // 10] = pts[0]  # duplicates
    return pts


def inside(pts: np.ndarray, lo, hi) -> np.ndarray:
    lo = np.asarray(lo, dtype=pts.dtype)
    hi = np.asarray(hi, dtype=pts.dtype)
    return np.flatnonzero(np.all((pts >= lo) & (pts <= hi), axis=1)).astype(np.uint32)


def trees(pts: np.ndarray, dtype: str):
    dyn = nbhd.DynamicKdTree(3, dtype=dtype)
    dyn.insert(pts)
    return [nbhd.KdTree(pts), dyn]


@pytest.mark.parametrize("dtype", ["float32", "float64"])
def test_in_box_equals_brute_force_closed_boxes(dtype):
    pts = cloud(2000, dtype)
    rng = np.random.default_rng(3)
    lo = rng.integers(-1, 5, size=(40, 3)).astype(np.float64)
    hi = lo + rng.integers(0, 4, size=(40, 3))
    lo[0, 0] = -np.inf  # a slab
    hi[1] = lo[1]  # zero extent: the points on a plane
    for tree in trees(pts, dtype):
        offsets, idx = tree.in_box(lo, hi, threads=2)
        assert offsets.dtype == np.uint64 and idx.dtype == np.uint32 and len(offsets) == 41
        for i in range(40):
            want = inside(pts, lo[i], hi[i])
            np.testing.assert_array_equal(idx[offsets[i] : offsets[i + 1]], want)
            np.testing.assert_array_equal(tree.in_box(lo[i], hi[i]), want)
        one_thread = tree.in_box(lo, hi, threads=1)
        np.testing.assert_array_equal(one_thread[0], offsets)
        np.testing.assert_array_equal(one_thread[1], idx)


def test_in_box_of_a_growing_tree_leaves_removed_points_out():
    pts = cloud(500, "float64")
    dyn = nbhd.DynamicKdTree(3, dtype="float64")
    dyn.insert(pts)
    gone = np.arange(0, 500, 3)
    dyn.remove(gone.tolist())
    want = np.setdiff1d(inside(pts, [0, 0, 0], [3, 3, 3]), gone).astype(np.uint32)
    np.testing.assert_array_equal(dyn.in_box([0, 0, 0], [3, 3, 3]), want)


def test_in_box_refuses_bad_boxes():
    tree = nbhd.KdTree(cloud(100, "float64"))
    with pytest.raises(nbhd.NbhdValueError):
        tree.in_box([1, 1, 1], [0, 2, 2])  # min > max
    with pytest.raises(nbhd.NbhdValueError):
        tree.in_box([np.nan, 0, 0], [1, 1, 1])
    with pytest.raises(nbhd.NbhdValueError):
        tree.in_box([0, 0], [1, 1])  # wrong dimension
    with pytest.raises(nbhd.NbhdValueError):
        tree.in_box(np.zeros((2, 3)), np.ones((3, 3)))  # shapes differ
    empty = tree.in_box(np.zeros((0, 3)), np.zeros((0, 3)))
    assert len(empty[0]) == 1 and len(empty[1]) == 0


@pytest.mark.parametrize("dtype", ["float32", "float64"])
def test_spacing_equals_brute_force(dtype):
    rng = np.random.default_rng(11)
    pts = rng.random((400, 3)).astype(dtype)
    pts[1] = pts[0]  # a duplicate: its nearest distance is 0
    diff = pts[:, None, :].astype(np.float64) - pts[None, :, :].astype(np.float64)
    d2 = np.einsum("ijk,ijk->ij", diff, diff)
    np.fill_diagonal(d2, np.inf)
    nearest = np.sqrt(d2.min(axis=1))
    for tree in trees(pts, dtype):
        s = tree.spacing(threads=2)
        assert s["points"] == 400
        # the library measures in the points' type, then sums in f64
        np.testing.assert_allclose(s["mean"], nearest.mean(), rtol=1e-5 if dtype == "float32" else 1e-12)
        np.testing.assert_allclose(s["median"], np.median(nearest), rtol=1e-5 if dtype == "float32" else 1e-12)
        assert tree.spacing(threads=1) == s


def test_spacing_of_a_growing_tree_equals_the_static_tree_of_its_live_points():
    pts = cloud(300, "float64") + np.random.default_rng(5).random((300, 3))
    dyn = nbhd.DynamicKdTree(3, dtype="float64")
    dyn.insert(pts)
    dyn.remove(list(range(0, 300, 4)))
    live = np.array([i for i in range(300) if i % 4 != 0])
    assert dyn.spacing() == nbhd.KdTree(pts[live]).spacing()


def test_spacing_needs_two_points():
    with pytest.raises(nbhd.NbhdValueError):
        nbhd.KdTree(np.zeros((1, 3))).spacing()
