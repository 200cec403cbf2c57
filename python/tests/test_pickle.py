"""Pickling trees through the library's saved formats (docs/tree-file-format.md), and the
dynamic tree: a pickled and unpickled KdTree / DynamicKdTree answers every query with the same
arrays, bit for bit, as the original; pickle stores exactly `to_bytes()`; damaged or foreign
bytes raise NbhdValueError naming what differs. The DynamicKdTree answers as brute force and as
a static KdTree over its live points, through insertions and removals, and keeps its index
rule across a pickle."""

import pickle

import numpy as np
import pytest

import nbhd


def cloud(n, d=3, seed=0, dtype=np.float64):
    rng = np.random.default_rng(seed)
    # a coarse grid: duplicates and exact distance ties
    return (np.floor(rng.random((n, d)) * 8) / 8).astype(dtype)


def same_pair(a, b):
    assert a[0].dtype == b[0].dtype and a[1].dtype == b[1].dtype
    assert np.array_equal(a[0], b[0])
    assert np.array_equal(a[1], b[1])


def same_table(a, b):
    assert np.array_equal(a.offsets, b.offsets)
    assert np.array_equal(a.indices, b.indices)
    assert a.sq_dists.dtype == b.sq_dists.dtype
    assert np.array_equal(a.sq_dists, b.sq_dists)


def same_answers(a, b, queries):
    for q in queries:
        same_pair(a.knn(q, 7), b.knn(q, 7))
        same_pair(a.radius(q, 0.3), b.radius(q, 0.3))
        same_pair(a.knn_radius(q, 4, 0.25), b.knn_radius(q, 4, 0.25))
    same_pair(a.knn(queries, 5), b.knn(queries, 5))
    same_table(a.radius(queries, 0.2), b.radius(queries, 0.2))
    same_table(a.neighborhoods(k=6), b.neighborhoods(k=6))
    same_table(a.neighborhoods(radius=0.26), b.neighborhoods(radius=0.26))


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_kdtree_pickles_through_its_saved_bytes(dtype):
    pts = cloud(400, seed=1, dtype=dtype)
    pts[17, 1] = np.nan
    tree = nbhd.KdTree(pts, non_finite="skip", leaf_size=5, pivot="cyclic-median")
    data = pickle.dumps(tree)
    back = pickle.loads(data)
    assert isinstance(back, nbhd.KdTree)
    assert back.dtype_name == tree.dtype_name
    assert (back.n, back.m, back.size) == (400, 3, 399)
    assert np.array_equal(back.tree_order, tree.tree_order)
    assert back.options() == tree.options()
    same_answers(tree, back, cloud(25, seed=2, dtype=dtype) + dtype(0.01))
    # the pickle holds exactly the saved-tree bytes, which load back to the same bytes
    saved = tree.to_bytes()
    assert saved[:8] == b"NBHDTREE"
    assert saved in data
    assert back.to_bytes() == saved
    assert nbhd.KdTree.from_bytes(saved).to_bytes() == saved
    # a reduce that pickle (or Dask) can call anywhere: the class method and the bytes
    func, args = tree.__reduce__()
    assert func == nbhd.KdTree.from_bytes and args == (saved,)
    # every protocol
    for protocol in range(2, pickle.HIGHEST_PROTOCOL + 1):
        assert pickle.loads(pickle.dumps(tree, protocol=protocol)).to_bytes() == saved


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_periodic_trees_pickle_with_their_box(dtype):
    pts = cloud(300, seed=4, dtype=dtype)  # in [0, 1): inside a box of 1 on x and y
    pts[:, 2] -= 3.0  # z open
    growing = nbhd.DynamicKdTree(3, dtype=np.dtype(dtype).name, boxsize=[1.0, 1.0, 0.0])
    growing.insert(pts[:200])
    growing.insert(pts[200:])
    growing.remove([5, 250])
    for tree in (nbhd.KdTree(pts, boxsize=[1.0, 1.0, 0.0]), growing):
        back = pickle.loads(pickle.dumps(tree))
        assert back.to_bytes() == tree.to_bytes()
        # queries across the box's edges and outside it (wrapped) answer the same
        q = np.array([[0.99, 0.01, -3.0], [-0.5, 2.25, -2.5], [0.5, 0.5, 0.0]], dtype)
        same_pair(tree.knn(q, 6), back.knn(q, 6))
        same_table(tree.radius(q, 0.3), back.radius(q, 0.3))


def test_bad_bytes_are_refused_with_what_differs():
    tree = nbhd.KdTree(cloud(200, seed=3))
    saved = tree.to_bytes()
    with pytest.raises(nbhd.NbhdValueError, match="truncated"):
        nbhd.KdTree.from_bytes(saved[:-8])
    flipped = bytearray(saved)
    flipped[-20] ^= 0x04
    with pytest.raises(nbhd.NbhdValueError, match="CRC-32"):
        nbhd.KdTree.from_bytes(bytes(flipped))
    version = bytearray(saved)
    version[12:16] = (2).to_bytes(4, "little" if np.little_endian else "big")
    with pytest.raises(nbhd.NbhdValueError, match="format version 2"):
        nbhd.KdTree.from_bytes(bytes(version))
    with pytest.raises(nbhd.NbhdValueError, match="not a saved nbhd tree"):
        nbhd.KdTree.from_bytes(b"ply\nformat ascii 1.0\n" + bytes(200))
    with pytest.raises(nbhd.NbhdValueError, match="trailing|follow the end"):
        nbhd.KdTree.from_bytes(saved + b"\0")
    # the other kind of tree, both ways, named
    dyn = nbhd.DynamicKdTree(3, dtype="float64")
    dyn.insert(cloud(50, seed=4))
    with pytest.raises(nbhd.NbhdValueError, match="a dynamic tree"):
        nbhd.KdTree.from_bytes(dyn.to_bytes())
    with pytest.raises(nbhd.NbhdValueError, match="a static tree"):
        nbhd.DynamicKdTree.from_bytes(saved)
    with pytest.raises(TypeError):
        nbhd.KdTree.from_bytes("not bytes")


def brute(live_pts, live_idx, q, k):
    """k nearest by (sq_dist, index), the squared distance summed coordinate by coordinate in
    the tree's order (x, then y, then z), in float64: exactly the tree's arithmetic."""
    diff = live_pts - q
    d2 = diff[:, 0] * diff[:, 0]
    for j in range(1, live_pts.shape[1]):
        d2 = d2 + diff[:, j] * diff[:, j]
    order = np.lexsort((live_idx, d2))[:k]
    return live_idx[order].astype(np.uint32), d2[order]


def test_dynamic_tree_insert_remove_query_and_pickle():
    rng = np.random.default_rng(7)
    dyn = nbhd.DynamicKdTree(3, dtype="float64", leaf_size=4, non_finite="skip")
    coords = np.empty((0, 3))
    live = np.empty(0, dtype=bool)
    queries = cloud(12, seed=8) + 0.01
    for step in range(10):
        batch = cloud(int(rng.integers(5, 60)), seed=100 + step)
        if step == 3:
            batch[2, 0] = np.nan
        first = dyn.insert(batch)
        assert first == len(coords)
        coords = np.vstack([coords, batch])
        live = np.concatenate([live, np.isfinite(batch).all(axis=1)])
        victims = np.flatnonzero(live & (rng.random(len(live)) < 0.2))
        dyn.remove(victims.tolist())
        live[victims] = False
        assert dyn.size == live.sum() and dyn.next_index == len(coords)
        idx = np.flatnonzero(live)
        for q in queries:
            got = dyn.knn(q, 6)
            want = brute(coords[idx], idx, q, 6)
            assert np.array_equal(got[0], want[0])
            assert np.array_equal(got[1], want[1])
        # and exactly a static tree over the live points (others NaN, skipped)
        masked = np.where(live[:, None], coords, np.nan)
        static = nbhd.KdTree(masked, non_finite="skip")
        same_answers(dyn, static, queries)
        if step % 3 == 2:
            # pickled and unpickled: the same answers, the same bytes; it carries on in place
            data = pickle.dumps(dyn)
            back = pickle.loads(data)
            assert isinstance(back, nbhd.DynamicKdTree)
            assert back.stats() == dyn.stats()
            same_answers(dyn, back, queries)
            assert back.to_bytes() == dyn.to_bytes()
            assert dyn.to_bytes() in data
            dyn = back
    # the index rule survives a pickle: removed indices stay refused, new ones continue
    removed = int(np.flatnonzero(~live)[0])
    back = pickle.loads(pickle.dumps(dyn))
    with pytest.raises(nbhd.NbhdValueError, match="removed|skipped"):
        back.point(removed)
    with pytest.raises(nbhd.NbhdValueError, match="removed|skipped"):
        back.remove([removed])
    assert back.insert(cloud(3, seed=999)) == len(coords)
    assert not back.is_live(removed)


@pytest.mark.parametrize("dtype", ["float32", "float64"])
def test_dynamic_tree_options_and_errors(dtype):
    dyn = nbhd.DynamicKdTree(2, dtype=dtype, growth=4)
    assert dyn.size == 0 and dyn.next_index == 0 and dyn.dtype_name == dtype
    i, d = dyn.knn(np.zeros(2), 3)
    assert len(i) == 0 and len(d) == 0
    assert dyn.insert(np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]])) == 0
    with pytest.raises(nbhd.NbhdValueError, match="non-finite|NaN|finite"):
        dyn.insert(np.array([[0.0, np.nan]]))
    assert dyn.next_index == 3
    with pytest.raises(nbhd.NbhdValueError):
        dyn.insert(np.zeros((2, 3)))
    dyn.remove([1])
    with pytest.raises(nbhd.NbhdValueError, match="removed"):
        dyn.remove([1])
    with pytest.raises(nbhd.NbhdValueError):
        dyn.remove([7])
    idx, d2 = dyn.knn(np.array([1.0, 0.0]), 2)
    assert idx.tolist() == [0, 2] and d2.tolist() == [1.0, 1.0]
    assert dyn.point(2).tolist() == [2.0, 0.0]
    table = dyn.neighborhoods(k=1)
    assert len(table) == 3 and table.row(1)[0].tolist() == []
    with pytest.raises(nbhd.NbhdValueError, match="growth"):
        nbhd.DynamicKdTree(2, growth=1)
    with pytest.raises(nbhd.NbhdValueError, match="dtype"):
        nbhd.DynamicKdTree(2, dtype="int8")
    back = pickle.loads(pickle.dumps(dyn))
    assert back.dtype_name == dtype and back.stats() == dyn.stats()


def test_dynamic_tree_threads_are_set_and_not_taken_from_bytes():
    # Saved bytes are untrusted: a tree read back builds on the default (0), whatever the
    # bytes say, and the count is set on the handle.
    dyn = nbhd.DynamicKdTree(3, threads=3)
    assert dyn.threads == 3
    dyn.insert(np.random.default_rng(1).random((50, 3)))
    back = nbhd.DynamicKdTree.from_bytes(dyn.to_bytes())
    assert back.threads == 0
    back.threads = 1
    assert back.threads == 1
    back.insert(np.zeros((4, 3)))
    with pytest.raises(nbhd.NbhdValueError, match="threads"):
        back.threads = 5000
    assert back.threads == 1
    assert pickle.loads(pickle.dumps(back)).threads == 0
