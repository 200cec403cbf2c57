"""Neighbourhoods against scipy's cKDTree and a numpy brute force.

Bridging the conventions: cKDTree returns distances, nbhd squared distances (compared as
d**2 against sq_dists, and exactly against a brute force computed the same way); both radii are
inclusive (cKDTree's query_ball_point keeps ‖p − q‖ ≤ r, nbhd too); cKDTree does not promise an
order among equal distances, nbhd orders ties by index, so sets are compared with cKDTree and
orders with the brute force."""

import numpy as np
import pytest
from scipy.spatial import cKDTree

import nbhd

PIVOTS = ["sliding-midpoint", "cyclic-median", "spread-median", "closest-to-middle"]
MEDIANS = ["floyd-rivest", "presorted", "sort", "quickselect", "median-of-medians"]


def brute(points, q, k=None, r=None):
    """Rows of the brute force: every point's squared distance computed as nbhd does (sum of
    squared coordinate differences in order), ordered by (sq_dist, index)."""
    d2 = ((points - q) ** 2).sum(axis=1)
    order = np.lexsort((np.arange(len(points)), d2))
    if r is not None:
        order = order[d2[order] <= r * r]
    if k is not None:
        order = order[:k]
    return order, d2[order]


def test_knn_single_matches_ckdtree_and_brute_force(cloud, rng):
    tree = nbhd.KdTree(cloud)
    ref = cKDTree(cloud)
    for q in rng.random((20, 3)):
        idx, d2 = tree.knn(q, 10)
        dist, ridx = ref.query(q, 10)
        assert set(idx.tolist()) == set(ridx.tolist())
        np.testing.assert_allclose(d2, dist**2, rtol=1e-12)
        bidx, bd2 = brute(cloud, q, k=10)
        np.testing.assert_array_equal(idx, bidx)
        np.testing.assert_array_equal(d2, bd2)


def test_knn_batch_is_dense_and_matches_ckdtree(cloud, rng):
    tree = nbhd.KdTree(cloud)
    qs = rng.random((300, 3))
    idx, d2 = tree.knn(qs, 7)
    assert idx.shape == (300, 7) and d2.shape == (300, 7)
    assert idx.dtype == np.uint32 and d2.dtype == np.float64
    dist, ridx = cKDTree(cloud).query(qs, 7)
    np.testing.assert_allclose(d2, dist**2, rtol=1e-12)
    for a, b in zip(idx, ridx):
        assert set(a) == set(b)
    # rows are the single queries' answers
    for i in (0, 151, 299):
        si, sd = tree.knn(qs[i], 7)
        np.testing.assert_array_equal(idx[i], si)
        np.testing.assert_array_equal(d2[i], sd)


def test_k_larger_than_the_set_gives_every_point():
    pts = np.arange(12.0).reshape(4, 3)
    idx, d2 = nbhd.KdTree(pts).knn(pts[1], 10)
    np.testing.assert_array_equal(idx, [1, 0, 2, 3])
    idx, _ = nbhd.KdTree(pts).knn(pts, 10)
    assert idx.shape == (4, 4)


def test_radius_is_inclusive_like_query_ball_point():
    # integer lattice: many points at exactly distance 1 and sqrt(2) of a lattice query
    g = np.stack(np.meshgrid(*[np.arange(6.0)] * 3, indexing="ij"), -1).reshape(-1, 3)
    tree = nbhd.KdTree(g)
    ref = cKDTree(g)
    for q, r in [((2, 2, 2), 1.0), ((0, 0, 0), 2.0**0.5), ((3, 1, 4), 2.0), ((2.5, 2, 2), 0.5)]:
        q = np.array(q, float)
        idx, d2 = tree.radius(q, r)
        assert sorted(idx.tolist()) == sorted(ref.query_ball_point(q, r))
        bidx, bd2 = brute(g, q, r=r)
        np.testing.assert_array_equal(idx, bidx)  # ties ordered by index
        np.testing.assert_array_equal(d2, bd2)
        assert np.all(d2 <= r * r)
    # the six lattice neighbours at distance exactly 1 are in, in index order
    idx, d2 = tree.radius(np.array([2.0, 2, 2]), 1.0)
    assert len(idx) == 7 and np.all(np.diff(idx[1:].astype(int)) > 0)


def test_radius_batch_table_matches_query_ball_point(cloud, rng):
    tree = nbhd.KdTree(cloud)
    qs = rng.random((200, 3))
    table = tree.radius(qs, 0.08)
    assert isinstance(table, nbhd.Table) and len(table) == 200
    balls = cKDTree(cloud).query_ball_point(qs, 0.08)
    for i in range(200):
        idx, d2 = table.row(i)
        assert sorted(idx.tolist()) == sorted(balls[i])
        assert np.all(np.diff(d2) >= 0)
    np.testing.assert_array_equal(table.row_lengths(), [len(b) for b in balls])
    assert table.offsets[0] == 0 and table.offsets[-1] == len(table.indices)


def test_unsorted_radius_is_the_same_set(cloud):
    tree = nbhd.KdTree(cloud)
    q = cloud[5]
    a, _ = tree.radius(q, 0.15)
    b, _ = tree.radius(q, 0.15, sorted=False)
    assert sorted(a.tolist()) == sorted(b.tolist())


def test_knn_radius_is_the_knn_cut_to_the_radius(cloud, rng):
    tree = nbhd.KdTree(cloud)
    for q in rng.random((30, 3)):
        idx, d2 = tree.knn_radius(q, 8, 0.1)
        bidx, bd2 = brute(cloud, q, k=8, r=0.1)
        np.testing.assert_array_equal(idx, bidx)
        np.testing.assert_array_equal(d2, bd2)
    table = tree.knn_radius(rng.random((50, 3)), 8, 0.1)
    assert max(table.row_lengths()) <= 8


def test_all_point_table_matches_ckdtree_without_self(cloud):
    tree = nbhd.KdTree(cloud)
    table = tree.neighborhoods(k=6)
    dist, ridx = cKDTree(cloud).query(cloud, 7)
    assert len(table) == len(cloud)
    np.testing.assert_array_equal(table.offsets, np.arange(len(cloud) + 1) * 6)
    rows = table.indices.reshape(-1, 6)
    for i in range(len(cloud)):
        assert set(rows[i]) == set(ridx[i, 1:]) and i not in rows[i]
    np.testing.assert_allclose(table.sq_dists.reshape(-1, 6), dist[:, 1:] ** 2, rtol=1e-12)
    with_self = tree.neighborhoods(k=6, exclude_self=False)
    np.testing.assert_array_equal(with_self.indices.reshape(-1, 6)[:, 0], np.arange(len(cloud)))


def test_radius_table_to_csr_matches_sparse_distance_matrix(cloud):
    tree = nbhd.KdTree(cloud)
    table = tree.neighborhoods(radius=0.07)
    csr = table.to_csr(distances=True)
    ref = cKDTree(cloud)
    sdm = ref.sparse_distance_matrix(ref, 0.07).tocsr()
    sdm.setdiag(0)
    sdm.eliminate_zeros()  # scipy drops the self-pairs at distance 0; so does exclude_self
    assert csr.shape == (len(cloud), len(cloud))
    a = csr.tocoo()
    b = sdm.tocoo()
    assert set(zip(a.row, a.col)) == set(zip(b.row, b.col))
    np.testing.assert_allclose(csr.toarray(), sdm.toarray(), rtol=1e-12)
    sq = table.to_csr()
    np.testing.assert_array_equal(sq.data, table.sq_dists)


def test_table_coordinates_are_the_entries_row_by_row(cloud):
    table = nbhd.KdTree(cloud).neighborhoods(radius=0.07)
    rows, cols = table.coordinates()
    assert rows.dtype == np.intp and cols.dtype == np.intp
    want = [(i, j) for i in range(len(table)) for j in table.row(i)[0].tolist()]
    assert list(zip(rows.tolist(), cols.tolist())) == want
    stacked = table.coordinates(stacked=True)
    assert stacked.shape == (len(want), 2) and stacked.dtype == np.intp
    np.testing.assert_array_equal(stacked, np.array(want).reshape(-1, 2))
    csr = table.to_csr()
    np.testing.assert_array_equal(csr.tocoo().row, rows)  # the same order as scipy's COO
    empty = nbhd.KdTree(cloud).radius(cloud[:0], 0.07)
    assert [a.shape for a in empty.coordinates()] == [(0,), (0,)]
    assert empty.coordinates(stacked=True).shape == (0, 2)


@pytest.mark.parametrize("pivot", PIVOTS)
def test_every_pivot_and_median_gives_the_same_rows(cloud, pivot):
    ref = nbhd.KdTree(cloud).neighborhoods(k=9)
    for median in MEDIANS:
        for leaf in (1, 12):
            t = nbhd.KdTree(cloud, pivot=pivot, median=median, leaf_size=leaf)
            assert t.options()["pivot"] == pivot and t.options()["median"] == median
            got = t.neighborhoods(k=9)
            np.testing.assert_array_equal(got.indices, ref.indices)
            np.testing.assert_array_equal(got.sq_dists, ref.sq_dists)


def test_duplicates_tie_by_index():
    pts = np.zeros((10, 3))
    pts[5:] = 1.0
    idx, d2 = nbhd.KdTree(pts, leaf_size=1).knn(np.zeros(3), 7)
    np.testing.assert_array_equal(idx, [0, 1, 2, 3, 4, 5, 6])
    np.testing.assert_array_equal(d2, [0, 0, 0, 0, 0, 3, 3])


def test_tables_identical_for_any_thread_count(cloud, rng):
    tree = nbhd.KdTree(cloud, threads=1)
    for other in (2, 3):
        assert np.array_equal(nbhd.KdTree(cloud, threads=other).tree_order, tree.tree_order)
    qs = rng.random((500, 3))
    for spec in (dict(k=12), dict(radius=0.09), dict(k=12, radius=0.09)):
        one = tree.neighborhoods(threads=1, **spec)
        for t in (2, 4):
            many = tree.neighborhoods(threads=t, **spec)
            assert many.indices.tobytes() == one.indices.tobytes()
            assert many.sq_dists.tobytes() == one.sq_dists.tobytes()
            assert many.offsets.tobytes() == one.offsets.tobytes()
    a = tree.knn(qs, 5, threads=1)
    b = tree.knn(qs, 5, threads=3)
    assert a[0].tobytes() == b[0].tobytes() and a[1].tobytes() == b[1].tobytes()


def test_skipped_points_keep_their_indices():
    pts = np.array([[0, 0, 0], [np.nan, 0, 0], [1, 0, 0], [0, 2, 0], [np.inf, 1, 1.0]])
    tree = nbhd.KdTree(pts, non_finite="skip")
    assert tree.size == 3 and tree.n == 5 and len(tree) == 5
    idx, _ = tree.knn(np.array([0.1, 0, 0]), 5)
    np.testing.assert_array_equal(idx, [0, 2, 3])
    table = tree.neighborhoods(k=2)
    np.testing.assert_array_equal(table.row_lengths(), [2, 0, 2, 2, 0])


def test_higher_dimensions_match_ckdtree(rng):
    pts = rng.random((800, 6))
    qs = rng.random((40, 6))
    idx, d2 = nbhd.KdTree(pts).knn(qs, 5)
    dist, ridx = cKDTree(pts).query(qs, 5)
    np.testing.assert_allclose(d2, dist**2, rtol=1e-12)
    for a, b in zip(idx, ridx):
        assert set(a) == set(b)
    table = nbhd.KdTree(pts).neighborhoods(k=4)
    assert len(table.indices) == 800 * 4


def test_stats_describe_the_tree(cloud):
    t = nbhd.KdTree(cloud, leaf_size=1, pivot="cyclic-median")
    s = t.stats()
    assert s["points"] == 2000 and s["dim"] == 3 and s["max_leaf_points"] == 1
    assert s["leaves"] == 2000 and s["depth"] == 11  # balanced: ceil(log2(2000))
    assert sorted(t.tree_order.tolist()) == list(range(2000))
    assert t.m == 3 and t.dtype_name == "float64"
