"""Queries under a Minkowski metric (p=), approximate (eps=) and strict (strict=) against scipy's
cKDTree, which takes the same p, eps and (for query) a strict distance_upper_bound.

Bridging the conventions: cKDTree returns plain distances, nbhd the metric's key (squared for
p = 2, the distance for p = 1 and ∞, sum |x_j - q_j|^p otherwise), so distances are compared as
key ** (1/p); on random points there are no ties, so indices compare exactly."""

import numpy as np
import pytest
from scipy.spatial import cKDTree

import nbhd

PS = [1.0, 1.5, 2.0, 3.0, np.inf]


def distance(key, p):
    return np.sqrt(key) if p == 2 else key if p in (1, np.inf) else key ** (1.0 / p)


def growing(points):
    tree = nbhd.DynamicKdTree(points.shape[1], dtype="float64")
    tree.insert(points[: len(points) // 2])
    tree.insert(points[len(points) // 2 :])
    return tree


@pytest.mark.parametrize("p", PS)
@pytest.mark.parametrize("make", [nbhd.KdTree, growing])
def test_knn_and_radius_match_ckdtree(cloud, rng, p, make):
    tree = make(cloud)
    ref = cKDTree(cloud)
    queries = rng.random((30, 3))
    idx, keys = tree.knn(queries, 8, p=p)
    dist, ridx = ref.query(queries, 8, p=p)
    np.testing.assert_array_equal(idx, ridx)
    np.testing.assert_allclose(distance(keys, p), dist, rtol=1e-12)
    table = tree.radius(queries, 0.2, p=p)
    want = ref.query_ball_point(queries, 0.2, p=p)
    for i, row in enumerate(want):
        assert sorted(table.row(i)[0].tolist()) == sorted(row)
    one, _ = tree.knn_radius(queries[0], 4, 0.2, p=p)
    assert one.tolist() == [j for j in ridx[0][:4] if dist[0][ridx[0].tolist().index(j)] <= 0.2]


@pytest.mark.parametrize("p", PS)
def test_strict_bound_is_distance_upper_bound(cloud, rng, p):
    tree = nbhd.KdTree(cloud)
    ref = cKDTree(cloud)
    for q in rng.random((10, 3)):
        dist, ridx = ref.query(q, 6, p=p)
        bound = dist[3]  # the 4th neighbour's distance
        rdist, ridx2 = ref.query(q, 6, p=p, distance_upper_bound=bound)
        idx, keys = tree.knn_radius(q, 6, bound, p=p, strict=True)
        assert idx.tolist() == ridx2[np.isfinite(rdist)].tolist()
        if p in (1, np.inf):
            # keys are the distances: the 4th lies exactly on the bound and is left out (for
            # other p its key and bound**p may round either way, the same way in both)
            assert idx.tolist() == ridx[:3].tolist()


@pytest.mark.parametrize("p", PS)
def test_eps_keeps_the_guarantee(cloud, rng, p):
    tree = nbhd.KdTree(cloud)
    ref = cKDTree(cloud)
    eps = 0.5
    queries = rng.random((50, 3))
    _, keys = tree.knn(queries, 5, p=p, eps=eps)
    exact, _ = ref.query(queries, 5, p=p)
    assert np.all(distance(keys, p) <= (1 + eps) * exact * (1 + 1e-12))


def test_tables_take_the_metric(cloud):
    tree = nbhd.KdTree(cloud)
    table = tree.neighborhoods(k=5, p=1.0, threads=2)
    ref = cKDTree(cloud)
    _, ridx = ref.query(cloud, 6, p=1.0)
    np.testing.assert_array_equal(table.indices.reshape(-1, 5), ridx[:, 1:])


@pytest.mark.parametrize("bad", [{"p": 0.5}, {"p": float("nan")}, {"eps": -1.0}])
def test_bad_metric_options_raise(cloud, bad):
    tree = nbhd.KdTree(cloud)
    with pytest.raises(nbhd.NbhdValueError, match="p|eps"):
        tree.knn(cloud[0], 3, **bad)
