"""nbhd.spatial against scipy.spatial on the same data: every method of cKDTree and KDTree for
p ∈ {1, 1.5, 2, 3, ∞}, without a box, with a periodic box on every axis and on some axes
(0 on the others), with and without eps. With eps = 0 the indices are equal exactly (the data
are random, without ties) and the distances to the last bits scipy's summation order allows;
with eps > 0 both keep scipy's documented guarantee. The tree itself is nbhd's (node objects,
pickling) and is checked for what it promises."""

import pickle

import numpy as np
import pytest
import scipy.spatial

from nbhd import spatial

PS = [1, 1.5, 2, 3, np.inf]
BOXES = {"open": None, "periodic": 1.0, "mixed": [1.0, 0.0, 1.0]}


def data(n=400, seed=5):
    return np.random.default_rng(seed).random((n, 3))


def queries(box, n=60, seed=6):
    """Points in the unit cube, moved by whole periods on the periodic axes (every query is
    wrapped into the box)."""
    q = np.random.default_rng(seed).random((n, 3))
    if box is not None:
        shift = np.random.default_rng(seed + 1).integers(-2, 3, size=q.shape).astype(float)
        q = q + shift * (np.broadcast_to(box, (3,)) > 0)
    return q


def pair(box, leafsize=8, n=400):
    x = data(n)
    return x, spatial.cKDTree(x, leafsize=leafsize, boxsize=box), scipy.spatial.cKDTree(
        x, leafsize=leafsize, boxsize=box
    )


@pytest.mark.parametrize("box", BOXES.values(), ids=BOXES.keys())
@pytest.mark.parametrize("p", PS)
def test_query_equals_scipy(p, box):
    _, ours, theirs = pair(box)
    q = queries(box)
    for k in (1, 5, [1, 3, 8]):
        d, i = ours.query(q, k=k, p=p)
        e, j = theirs.query(q, k=k, p=p)
        assert i.dtype == j.dtype and i.shape == j.shape
        np.testing.assert_array_equal(i, j)
        np.testing.assert_allclose(d, e, rtol=1e-14, atol=0)
    # a strict upper bound: missing neighbours are (inf, n)
    d, i = ours.query(q, k=12, p=p, distance_upper_bound=0.1)
    e, j = theirs.query(q, k=12, p=p, distance_upper_bound=0.1)
    np.testing.assert_array_equal(i, j)
    np.testing.assert_allclose(d, e, rtol=1e-14, atol=0)
    assert (i == ours.n).any() and np.isinf(d[i == ours.n]).all()


@pytest.mark.parametrize("box", BOXES.values(), ids=BOXES.keys())
@pytest.mark.parametrize("p", PS)
def test_ball_queries_equal_scipy(p, box):
    x, ours, theirs = pair(box)
    q = queries(box)
    r = 0.15
    got = ours.query_ball_point(q, r, p=p)
    want = theirs.query_ball_point(q, r, p=p)
    assert got.shape == want.shape == (len(q),)
    assert [sorted(a) for a in got] == [sorted(b) for b in want]
    assert all(a == sorted(a) for a in got)
    np.testing.assert_array_equal(
        ours.query_ball_point(q, r, p=p, return_length=True),
        theirs.query_ball_point(q, r, p=p, return_length=True),
    )
    radii = np.linspace(0.05, 0.2, len(q))
    assert [sorted(a) for a in ours.query_ball_point(q, radii, p=p)] == [
        sorted(b) for b in theirs.query_ball_point(q, radii, p=p)
    ]
    assert ours.query_pairs(0.1, p=p) == theirs.query_pairs(0.1, p=p)
    other = data(150, seed=9)
    o1 = spatial.cKDTree(other, boxsize=box)
    o2 = scipy.spatial.cKDTree(other, boxsize=box)
    assert ours.query_ball_tree(o1, r, p=p) == theirs.query_ball_tree(o2, r, p=p)
    got = ours.sparse_distance_matrix(o1, r, p=p, output_type="dict")
    want = theirs.sparse_distance_matrix(o2, r, p=p, output_type="dict")
    assert got.keys() == want.keys()
    np.testing.assert_allclose(
        [got[key] for key in sorted(got)], [want[key] for key in sorted(want)], rtol=1e-14
    )


@pytest.mark.parametrize("box", BOXES.values(), ids=BOXES.keys())
@pytest.mark.parametrize("p", [1, 2, np.inf])
def test_counts_equal_scipy(p, box):
    _, ours, theirs = pair(box)
    other = data(150, seed=9)
    o1 = spatial.cKDTree(other, boxsize=box)
    o2 = scipy.spatial.cKDTree(other, boxsize=box)
    r = [0.3, 0.05, 0.1, 0.1, 0.2]
    np.testing.assert_array_equal(
        ours.count_neighbors(o1, r, p=p), theirs.count_neighbors(o2, r, p=p)
    )
    rising = sorted(r)
    np.testing.assert_array_equal(
        ours.count_neighbors(o1, rising, p=p, cumulative=False),
        theirs.count_neighbors(o2, rising, p=p, cumulative=False),
    )
    w1 = np.random.default_rng(1).random(ours.n)
    w2 = np.random.default_rng(2).random(o1.n)
    for weights in [(w1, w2), (w1, None), (None, w2)]:
        np.testing.assert_allclose(
            ours.count_neighbors(o1, rising, p=p, weights=weights, cumulative=False),
            theirs.count_neighbors(o2, rising, p=p, weights=weights, cumulative=False),
            rtol=1e-12,
        )
    assert ours.count_neighbors(ours, 0.1, p=p) == theirs.count_neighbors(theirs, 0.1, p=p)
    np.testing.assert_allclose(
        ours.count_neighbors(ours, 0.1, p=p, weights=w1),
        theirs.count_neighbors(theirs, 0.1, p=p, weights=w1),
        rtol=1e-12,
    )


@pytest.mark.parametrize("box", BOXES.values(), ids=BOXES.keys())
@pytest.mark.parametrize("p", PS)
def test_eps_keeps_scipys_guarantee(p, box):
    x, ours, theirs = pair(box)
    q = queries(box)
    eps = 0.5
    true_d, _ = theirs.query(q, k=6, p=p)
    d, i = ours.query(q, k=6, p=p, eps=eps)
    assert (d <= true_d * (1 + eps) * (1 + 1e-12)).all()
    # the returned distances are those of the returned points
    exact_d = np.take_along_axis(theirs.query(q, k=len(x), p=p)[0], np.argsort(
        theirs.query(q, k=len(x), p=p)[1], axis=1), axis=1)
    np.testing.assert_allclose(np.take_along_axis(exact_d, i, axis=1), d, rtol=1e-13)
    r = 0.15
    inner = theirs.query_ball_point(q, r / (1 + eps), p=p)
    outer = theirs.query_ball_point(q, r * (1 + eps) * (1 + 1e-12), p=p)
    for got, near, far in zip(ours.query_ball_point(q, r, p=p, eps=eps), inner, outer):
        assert set(near) <= set(got) <= set(far)
    pairs = ours.query_pairs(r, p=p, eps=eps)
    assert theirs.query_pairs(r / (1 + eps), p=p) <= pairs
    assert pairs <= theirs.query_pairs(r * (1 + eps) * (1 + 1e-12), p=p)


def test_shapes_scalars_and_output_types_are_scipys():
    x, ours, theirs = pair(None)
    q = np.random.default_rng(3).random((2, 4, 3))
    for k in (1, 3, [2]):
        d, i = ours.query(q, k=k)
        e, j = theirs.query(q, k=k)
        assert d.shape == e.shape and i.shape == j.shape and i.dtype == np.intp
    d, i = ours.query(q[0, 0])
    assert type(d) is float and type(i) is int
    d, i = spatial.KDTree(x).query(q[0, 0])
    assert type(d) is float and isinstance(i, np.intp)
    assert type(ours.query_ball_point(q[0, 0], 0.2)) is list
    assert type(ours.query_ball_point(q[0, 0], 0.2, return_length=True)) is int
    assert ours.query_ball_point(q, 0.2).shape == (2, 4)
    arr = ours.query_pairs(0.1, output_type="ndarray")
    assert arr.dtype == np.intp and arr.shape[1] == 2
    assert set(map(tuple, arr.tolist())) == theirs.query_pairs(0.1)
    rec = ours.sparse_distance_matrix(ours, 0.1, output_type="ndarray")
    assert rec.dtype == theirs.sparse_distance_matrix(theirs, 0.1, output_type="ndarray").dtype
    coo = ours.sparse_distance_matrix(ours, 0.1, output_type="coo_matrix")
    want = theirs.sparse_distance_matrix(theirs, 0.1, output_type="coo_matrix")
    np.testing.assert_allclose(coo.toarray(), want.toarray(), rtol=1e-14)
    assert type(ours.count_neighbors(ours, 0.1)) is int
    for bad in ("list", "csr_matrix"):
        with pytest.raises(ValueError, match="Invalid output type"):
            ours.sparse_distance_matrix(ours, 0.1, output_type=bad)
        with pytest.raises(ValueError, match="Invalid output type"):
            ours.query_pairs(0.1, output_type=bad)


def test_attributes_are_scipys():
    x, ours, theirs = pair([1.0, 0.0, 1.0])
    for name in ("n", "m", "leafsize"):
        assert getattr(ours, name) == getattr(theirs, name)
        assert type(getattr(ours, name)) is int
    for name in ("maxes", "mins", "boxsize"):
        np.testing.assert_array_equal(getattr(ours, name), getattr(theirs, name))
    assert ours.data is x
    assert sorted(ours.indices) == list(range(len(x)))
    assert spatial.cKDTree(x, copy_data=True).data is not x
    assert spatial.cKDTree(x).boxsize is None
    assert spatial.KDTree(x).leafsize == 10 and spatial.cKDTree(x).leafsize == 16


def test_nodes_describe_nbhds_tree():
    x = data(300)
    t = spatial.cKDTree(x, leafsize=5)
    seen = 0
    stack = [t.tree]
    while stack:
        node = stack.pop()
        seen += 1
        np.testing.assert_array_equal(node.indices, t.indices[node.start_idx : node.end_idx])
        np.testing.assert_array_equal(node.data_points, x[node.indices])
        assert node.children == node.end_idx - node.start_idx
        if node.split_dim == -1:
            assert node.lesser is None and node.greater is None and node.children <= 5
            continue
        lo, hi = node.lesser, node.greater
        assert lo.level == hi.level == node.level + 1
        assert (lo.start_idx, lo.end_idx, hi.end_idx) == (node.start_idx, hi.start_idx, node.end_idx)
        assert (lo.data_points[:, node.split_dim] <= node.split).all()
        assert (hi.data_points[:, node.split_dim] >= node.split).all()
        stack += [hi, lo]
    assert seen == t.size
    weights = np.arange(len(x), dtype=float)
    sums = t._build_weights(weights)
    assert len(sums) == t.size and sums[0] == weights.sum()
    with pytest.raises(ValueError):
        t._build_weights(weights[:-1])
    kd = spatial.KDTree(x, leafsize=5)
    assert isinstance(kd.tree, spatial.KDTree.innernode)
    assert kd.tree.children == len(x) == kd.tree.less.children + kd.tree.greater.children
    empty = spatial.cKDTreeNode()
    assert (empty.split_dim, empty.children, empty.lesser) == (-1, 0, None)


def test_identical_points_are_split_by_index_the_documented_difference():
    x = np.ones((64, 2))
    x[32:] = 2
    t = spatial.cKDTree(x, leafsize=1)
    assert t.size > 3  # scipy: 3 (two leaves of 32 identical points)
    stack = [t.tree]
    while stack:
        node = stack.pop()
        if node.split_dim == -1:
            assert node.children <= 1
        else:
            stack += [node.lesser, node.greater]
    d, i = t.query([[1.0, 1.0]], k=3)
    np.testing.assert_array_equal(i, [[0, 1, 2]])  # ties by index


@pytest.mark.parametrize("cls", [spatial.cKDTree, spatial.KDTree])
@pytest.mark.parametrize("box", BOXES.values(), ids=BOXES.keys())
def test_pickle_rebuilds_the_same_tree(cls, box):
    x = data(200)
    t = cls(x, leafsize=3, balanced_tree=False, boxsize=box)
    back = pickle.loads(pickle.dumps(t))
    assert type(back) is cls and back.leafsize == 3
    np.testing.assert_array_equal(back.indices, t.indices)
    assert back.size == t.size
    q = queries(box)
    for a, b in zip(t.query(q, k=4, p=3), back.query(q, k=4, p=3)):
        np.testing.assert_array_equal(a, b)


def test_bad_input_is_refused_as_scipy_does():
    x = data(50)
    t = spatial.cKDTree(x)
    for cls in (spatial.cKDTree, spatial.KDTree):
        with pytest.raises(TypeError, match="complex data"):
            cls(x.astype(complex))
        with pytest.raises(ValueError, match="must be finite"):
            cls(np.vstack([x, [np.nan, 0, 0]]))
    with pytest.raises(ValueError, match="must be finite"):
        t.query([np.inf, 0, 0])
    with pytest.raises(ValueError):
        t.query(np.zeros(2))
    with pytest.raises(ValueError):
        spatial.cKDTree(x, leafsize=0)
    with pytest.raises(ValueError):
        spatial.cKDTree(x + 1.0, boxsize=1.0)
    with pytest.raises(ValueError, match="Invalid number of workers"):
        t.query(x, workers=0)
    with pytest.raises(ValueError, match="non-decreasing"):
        t.count_neighbors(t, [0.2, 0.1], cumulative=False)
    with pytest.raises(ValueError, match="Two different trees"):
        t.count_neighbors(spatial.cKDTree(x), 0.1, weights=np.ones(50))
    with pytest.raises(ValueError, match="different dimensionality"):
        t.query_ball_tree(spatial.cKDTree(x[:, :2]), 0.1)
