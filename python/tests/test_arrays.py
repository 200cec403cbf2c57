"""Input layouts and types: float32 and float64 arrays, C-contiguous or strided, read in place
where the rows allow and copied otherwise, with the same answers either way."""

import numpy as np
import pytest

import nbhd
from nbhd._nbhd import _reads_in_place


def answers(tree, qs):
    idx, d2 = tree.knn(qs, 6)
    t = tree.neighborhoods(k=6)
    return idx, d2, t.indices, t.sq_dists


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_layouts_in_place_or_copied_give_the_same_rows(rng, dtype):
    base = rng.random((1500, 3)).astype(dtype)
    qs = rng.random((100, 3)).astype(dtype)
    ref = answers(nbhd.KdTree(base), qs)

    wide = np.zeros((1500, 4), dtype)  # a PCL PointXYZ-like record: x y z and padding
    wide[:, :3] = base
    every_other = np.zeros((3000, 3), dtype)
    every_other[::2] = base
    layouts = {
        "C order": (base, True),
        "column prefix of (n, 4) records": (wide[:, :3], True),
        "every other row": (every_other[::2], True),
        "Fortran order": (np.asfortranarray(base), False),
        "transposed (3, n) storage": (np.ascontiguousarray(base.T).T, False),
    }
    for name, (arr, in_place) in layouts.items():
        assert _reads_in_place(arr) is in_place, name
        got = answers(nbhd.KdTree(arr), qs)
        for a, b in zip(got, ref):
            np.testing.assert_array_equal(a, b, err_msg=name)


def test_negative_strides_are_copied_and_keep_caller_indices(rng):
    base = rng.random((300, 3))
    rev = base[::-1]
    assert not _reads_in_place(rev)
    idx, _ = nbhd.KdTree(rev).knn(base[10], 1)
    assert idx[0] == 299 - 10


def test_a_stride_of_zero_between_rows_is_copied():
    row = np.array([[1.0, 2.0, 3.0]])
    rep = np.broadcast_to(row, (5, 3))
    assert not _reads_in_place(rep)
    idx, d2 = nbhd.KdTree(rep).knn(row[0], 5)
    np.testing.assert_array_equal(idx, [0, 1, 2, 3, 4])
    np.testing.assert_array_equal(d2, 0)


def test_float32_tree_computes_in_float32(rng):
    pts = rng.random((1000, 3)).astype(np.float32)
    tree = nbhd.KdTree(pts)
    assert tree.dtype_name == "float32"
    q = pts[3].astype(np.float64)  # queries are converted to the tree's type
    idx, d2 = tree.knn(q, 4)
    assert d2.dtype == np.float32
    exp = ((pts - pts[3]) ** 2).sum(axis=1, dtype=np.float32)
    order = np.lexsort((np.arange(1000), exp))[:4]
    np.testing.assert_array_equal(idx, order)
    table = tree.neighborhoods(radius=0.1)
    assert table.sq_dists.dtype == np.float32


def test_integers_and_lists_become_float64():
    pts = [[0, 0, 0], [1, 0, 0], [0, 3, 0]]
    tree = nbhd.KdTree(pts)
    assert tree.dtype_name == "float64"
    idx, d2 = tree.knn([0, 1, 0], 2)
    np.testing.assert_array_equal(idx, [0, 1])
    np.testing.assert_array_equal(d2, [1.0, 2.0])
    tree16 = nbhd.KdTree(np.array(pts, dtype=np.float16))
    assert tree16.dtype_name == "float64"


def test_the_tree_keeps_its_own_copy(rng):
    pts = rng.random((200, 3))
    q = pts[0].copy()
    tree = nbhd.KdTree(pts)
    before = tree.knn(q, 5)
    pts[:] = 0.0
    after = tree.knn(q, 5)
    np.testing.assert_array_equal(before[0], after[0])
    np.testing.assert_array_equal(before[1], after[1])


def test_geometry_accepts_float32_and_strided(rng):
    from conftest import sphere

    p = sphere(800)
    a = nbhd.normals(p)[0]
    wide = np.zeros((800, 4))
    wide[:, :3] = p
    np.testing.assert_array_equal(nbhd.normals(wide[:, :3])[0], a)
    b = nbhd.normals(p.astype(np.float32))[0]
    assert np.all(np.abs(np.abs((a * b).sum(1)) - 1) < 1e-4)
