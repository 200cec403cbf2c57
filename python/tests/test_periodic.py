"""Periodic trees (boxsize=) against scipy's cKDTree(boxsize=...), which defines the semantics:
points in [0, L) on each periodic axis, 0 for an open axis, queries anywhere (wrapped into the
box), every axis difference taken at its nearest image (each point once, even for a radius
beyond L/2).

Bridging the conventions: cKDTree returns plain distances, nbhd the metric's key (squared for
p = 2, the distance for p = 1 and inf, sum |x_j - q_j|^p otherwise), so distances are compared
as key ** (1/p); on random points there are no ties, so indices compare exactly."""

import numpy as np
import pytest
from scipy.spatial import cKDTree

import nbhd

PS = [1.0, 1.5, 2.0, 3.0, np.inf]
BOXES = [1.0, [1.0, 0.0, 2.0]]


def distance(key, p):
    return np.sqrt(key) if p == 2 else key if p in (1, np.inf) else key ** (1.0 / p)


def points_in(box, rng, n=1500):
    size = np.broadcast_to(np.asarray(box, dtype=float), (3,))
    pts = rng.random((n, 3)) * np.where(size > 0, size, 3.0)
    # a point exactly at 0 and one just below L on the periodic axes
    pts[0] = np.where(size > 0, 0.0, pts[0])
    pts[1] = np.where(size > 0, np.nextafter(size, 0), pts[1])
    return pts


def growing(points, boxsize):
    tree = nbhd.DynamicKdTree(3, dtype="float64", boxsize=boxsize)
    tree.insert(points[: len(points) // 2])
    tree.insert(points[len(points) // 2 :])
    return tree


@pytest.mark.parametrize("p", PS)
@pytest.mark.parametrize("box", BOXES)
@pytest.mark.parametrize("make", [lambda pts, b: nbhd.KdTree(pts, boxsize=b), growing])
def test_knn_and_radius_match_ckdtree(rng, p, box, make):
    pts = points_in(box, rng)
    tree = make(pts, box)
    ref = cKDTree(pts, boxsize=box)
    # queries inside, on the edges and outside the box (wrapped by both)
    queries = np.vstack([rng.random((40, 3)) * 5.0 - 2.0, [[0.0, 0.0, 0.0], [1.0, 1.0, 2.0]]])
    idx, keys = tree.knn(queries, 8, p=p)
    dist, ridx = ref.query(queries, 8, p=p)
    np.testing.assert_array_equal(idx, ridx)
    np.testing.assert_allclose(distance(keys, p), dist, rtol=1e-12, atol=1e-15)
    for r in (0.15, 0.8):  # 0.8 is beyond half of a box of 1
        table = tree.radius(queries, r, p=p)
        want = ref.query_ball_point(queries, r, p=p)
        for i, row in enumerate(want):
            assert sorted(table.row(i)[0].tolist()) == sorted(row), (r, i)


@pytest.mark.parametrize("box", BOXES)
def test_tables_and_float32(rng, box):
    pts = points_in(box, rng, 800)
    ref = cKDTree(pts, boxsize=box)
    table = nbhd.KdTree(pts, boxsize=box).neighborhoods(k=6, exclude_self=True, threads=2)
    _, ridx = ref.query(pts, 7)
    for i in range(0, len(pts), 37):
        assert table.row(i)[0].tolist() == [j for j in ridx[i] if j != i][:6]
    # float32: the points round before they are checked (the point just below L rounds to L
    # in float32 and is refused, as scipy refuses a point at L); the others find themselves
    with pytest.raises(nbhd.NbhdValueError, match="point 1 lies outside"):
        nbhd.KdTree(pts.astype(np.float32), boxsize=box)
    t32 = nbhd.KdTree(pts[2:].astype(np.float32), boxsize=box)
    assert t32.boxsize == list(np.broadcast_to(np.asarray(box, float), (3,)))
    idx, _ = t32.knn(pts[2:52], 1)
    assert idx[:, 0].tolist() == list(range(50))


def test_boxsize_errors_follow_scipy(rng):
    pts = rng.random((50, 2))
    pts[7, 1] = 1.0  # not below L
    with pytest.raises(ValueError):
        cKDTree(pts, boxsize=1.0)
    with pytest.raises(nbhd.NbhdValueError, match="point 7 lies outside the periodic box"):
        nbhd.KdTree(pts, boxsize=1.0)
    pts[7, 1] = -0.25
    with pytest.raises(ValueError):
        cKDTree(pts, boxsize=1.0)
    with pytest.raises(nbhd.NbhdValueError, match="point 7"):
        nbhd.KdTree(pts, boxsize=1.0)
    # the axis open: accepted by both; boxsize 0 is a tree that is not periodic
    assert nbhd.KdTree(pts, boxsize=[1.0, 0.0]).boxsize == [1.0, 0.0]
    assert nbhd.KdTree(pts, boxsize=0.0).boxsize is None
    # nbhd refuses a negative size (scipy takes it as open) and a wrong length
    cKDTree(pts, boxsize=[1.0, -1.0])
    with pytest.raises(nbhd.NbhdValueError, match="boxsize"):
        nbhd.KdTree(pts, boxsize=-1.0)
    with pytest.raises(nbhd.NbhdValueError, match="boxsize"):
        nbhd.KdTree(pts, boxsize=[1.0, 1.0, 1.0])
    grow = nbhd.DynamicKdTree(2, boxsize=1.0)
    with pytest.raises(nbhd.NbhdValueError, match="outside the periodic box"):
        grow.insert(np.array([[0.5, 0.5], [0.5, 1.5]]))
    assert grow.size == 0 and grow.boxsize == [1.0, 1.0]


@pytest.mark.parametrize("p", PS)
def test_csr_distances_are_the_metrics(rng, p):
    pts = points_in(1.0, rng, 600)
    table = nbhd.KdTree(pts, boxsize=1.0).neighborhoods(k=4, exclude_self=True, p=p)
    dist, idx = cKDTree(pts, boxsize=1.0).query(pts, 5, p=p)
    csr = table.to_csr(distances=True)
    for i in range(0, len(pts), 29):
        np.testing.assert_allclose(csr[i, idx[i, 1:]].toarray()[0], dist[i, 1:], rtol=1e-12)
