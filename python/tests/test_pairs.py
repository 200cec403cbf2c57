"""Pair queries (KdTree/DynamicKdTree .pairs, .pairs_with, .count_pairs) against scipy's
cKDTree, which defines the semantics: query_pairs (pairs i < j within r, inclusive),
query_ball_tree (rows of the other tree's indices, sorted), sparse_distance_matrix (plain
distances, zero distances included) and count_neighbors (cumulative or not, weighted or not),
for p in {1, 1.5, 2, 3, inf}, plain and periodic trees.

Bridging the conventions: cKDTree returns plain distances, nbhd the metric's key (squared for
p = 2, the distance for p = 1 and inf, sum |x_j - q_j|^p otherwise; Table.to_csr(distances=True)
converts as scipy does). The points lie on a grid of step 1/4, so many pairs are exactly on the
radius and many distances tie: every index set is compared exactly."""

import numpy as np
import pytest
from scipy.spatial import cKDTree

import nbhd

PS = [1.0, 1.5, 2.0, 3.0, np.inf]
BOXES = [None, 1.0, [1.0, 0.0, 1.0]]


def grid_points(rng, n):
    return rng.integers(0, 4, size=(n, 3)) / 4.0


def growing(points, boxsize):
    tree = nbhd.DynamicKdTree(3, dtype="float64", boxsize=boxsize)
    tree.insert(points[: len(points) // 2])
    tree.insert(points[len(points) // 2 :])
    return tree


MAKERS = [lambda pts, b: nbhd.KdTree(pts, leaf_size=3, boxsize=b), growing]


def rows(table):
    return [table.row(i)[0].tolist() for i in range(len(table))]


@pytest.mark.parametrize("p", PS)
@pytest.mark.parametrize("box", BOXES)
@pytest.mark.parametrize("make", MAKERS)
def test_pairs_match_query_pairs(rng, p, box, make):
    pts = grid_points(rng, 300)
    tree, ref = make(pts, box), cKDTree(pts, boxsize=box)
    for r in [0.25, 0.5]:
        table = tree.pairs(r, p=p, threads=2)
        got = {(i, j) for i, row in enumerate(rows(table)) for j in row}
        assert got == ref.query_pairs(r, p=p)
        assert all(row == sorted(row) for row in rows(table))


@pytest.mark.parametrize("p", PS)
@pytest.mark.parametrize("box", BOXES)
@pytest.mark.parametrize("make", MAKERS)
def test_pairs_with_match_query_ball_tree_and_sparse_distance_matrix(rng, p, box, make):
    a, b = grid_points(rng, 200), grid_points(rng, 120)
    ta, tb = make(a, box), make(b, box)
    ra, rb = cKDTree(a, boxsize=box), cKDTree(b, boxsize=box)
    table = ta.pairs_with(tb, 0.5, p=p)
    assert rows(table) == ra.query_ball_tree(rb, 0.5, p=p)
    got = table.to_csr(distances=True).tocoo()
    want = ra.sparse_distance_matrix(rb, 0.5, p=p, output_type="coo_matrix")
    assert got.shape == want.shape == (200, 120)
    g = sorted(zip(got.row.tolist(), got.col.tolist(), got.data.tolist()))
    w = sorted(zip(want.row.tolist(), want.col.tolist(), want.data.tolist()))
    assert [e[:2] for e in g] == [e[:2] for e in w]
    np.testing.assert_allclose([e[2] for e in g], [e[2] for e in w], rtol=1e-14, atol=0)
    assert min(e[2] for e in g) == 0.0  # duplicates: zero distances are entries


@pytest.mark.parametrize("p", PS)
@pytest.mark.parametrize("box", BOXES)
def test_count_pairs_match_count_neighbors(rng, p, box):
    a, b = grid_points(rng, 150), grid_points(rng, 90)
    ta, tb = nbhd.KdTree(a, boxsize=box), nbhd.KdTree(b, boxsize=box)
    ra, rb = cKDTree(a, boxsize=box), cKDTree(b, boxsize=box)
    radii = [0.0, 0.25, 0.25, 0.5, 0.75, np.inf]
    for cumulative in [True, False]:
        got = ta.count_pairs(tb, radii, cumulative=cumulative, p=p)
        want = ra.count_neighbors(rb, radii, p=p, cumulative=cumulative)
        assert got.dtype == np.uint64 and got.tolist() == list(want)
        wa, wb = rng.random(150), rng.random(90)
        got = ta.count_pairs(tb, radii, cumulative=cumulative, weights=wa, other_weights=wb, p=p)
        want = ra.count_neighbors(rb, radii, p=p, weights=(wa, wb), cumulative=cumulative)
        np.testing.assert_allclose(got, want, rtol=1e-12)
        got = ta.count_pairs(ta, radii, cumulative=cumulative, weights=wa, other_weights=wa, p=p)
        want = ra.count_neighbors(ra, radii, p=p, weights=wa, cumulative=cumulative)
        np.testing.assert_allclose(got, want, rtol=1e-12)


def test_eps_pairs_keep_scipys_contract(rng):
    # scipy's test_query_pairs_eps: points whose distances round just above r are pairs with
    # eps = 0.1 (24 of them), as with r * 1.01
    s = np.sqrt(2)
    xy = np.array([(x, y) for x in np.linspace(0, 3 * s, 4) for y in np.linspace(0, 3 * s, 4)])
    tree = nbhd.KdTree(xy)
    count = lambda t: int(t.row_lengths().sum())  # noqa: E731
    assert count(tree.pairs(s, eps=0.1)) == 24 == count(tree.pairs(s * 1.01))
    pts = rng.random((400, 3))
    tree, ref = nbhd.KdTree(pts), cKDTree(pts)
    for p in PS:
        got = {(i, j) for i, row in enumerate(rows(tree.pairs(0.2, p=p, eps=0.5))) for j in row}
        assert ref.query_pairs(0.2 / 1.5, p=p) <= got <= ref.query_pairs(0.2 * 1.5, p=p)


def test_threads_and_flavours_agree(rng):
    pts = grid_points(rng, 400)
    tree, grown = nbhd.KdTree(pts), growing(pts, None)
    one = tree.pairs(0.5, threads=1)
    for t in [tree.pairs(0.5, threads=2), grown.pairs(0.5, threads=2)]:
        assert np.array_equal(t.indices, one.indices) and np.array_equal(t.offsets, one.offsets)
    assert tree.pairs_with(grown, 0.5).to_csr().nnz == grown.pairs_with(tree, 0.5).to_csr().nnz


def test_empty_and_bad_input():
    empty = nbhd.KdTree(np.empty((0, 3)))
    some = nbhd.KdTree(np.zeros((4, 3)))
    assert len(empty.pairs(1.0)) == 0
    assert some.pairs(0.0).row_lengths().tolist() == [3, 2, 1, 0]  # copies pair at distance 0
    assert len(some.pairs_with(empty, 1.0)) == 4 and some.pairs_with(empty, 1.0).to_csr().nnz == 0
    assert some.count_pairs(empty, [1.0, np.inf]).tolist() == [0, 0]
    assert empty.count_pairs(some, [1.0], weights=[]).tolist() == [0.0]
    with pytest.raises(nbhd.NbhdValueError):
        some.pairs(-1.0)
    with pytest.raises(nbhd.NbhdValueError):
        some.pairs(np.nan)
    with pytest.raises(nbhd.NbhdValueError):
        some.count_pairs(some, [np.nan])
    with pytest.raises(nbhd.NbhdValueError):
        some.count_pairs(some, [2.0, 1.0], cumulative=False)
    with pytest.raises(nbhd.NbhdValueError):
        some.count_pairs(some, [1.0], weights=[1.0, 2.0])
    with pytest.raises(nbhd.NbhdValueError):
        some.count_pairs(some, [1.0], weights=[1.0, np.nan, 1.0, 1.0])
    with pytest.raises(nbhd.NbhdValueError):
        some.pairs_with(nbhd.KdTree(np.zeros((2, 2))), 1.0)
    with pytest.raises(nbhd.NbhdValueError):
        some.pairs_with(nbhd.KdTree(np.zeros((2, 3), dtype=np.float32)), 1.0)
    with pytest.raises(TypeError):
        some.pairs_with(np.zeros((2, 3)), 1.0)
    with pytest.raises(nbhd.NbhdValueError):
        some.pairs(1.0, p=0.5)
    with pytest.raises(nbhd.NbhdValueError):
        nbhd.KdTree(np.array([[0.0, np.nan, 0.0]]))
