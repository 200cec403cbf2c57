"""Tiles with halos (python/nbhd/tiling.py) reproduce the one-machine k-nearest table byte for
byte: the halo criterion makes every tile's rows exact, ties included."""

import numpy as np
import pytest

import nbhd
from nbhd.tiling import knn_table_by_tiles


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
@pytest.mark.parametrize("tiles", [2, 3, 5])
def test_tiled_knn_table_is_identical_to_one_tree(rng, dtype, tiles):
    pts = rng.random((20_000, 3)).astype(dtype)
    pts[:, 2] *= 0.1  # a flat slab: tiles of very different densities along z
    ref = nbhd.KdTree(pts).neighborhoods(k=12)
    offsets, indices, sq, halos = knn_table_by_tiles(pts, 12, tiles)
    assert offsets.tobytes() == ref.offsets.tobytes()
    assert indices.tobytes() == ref.indices.tobytes()
    assert sq.tobytes() == ref.sq_dists.tobytes()
    assert len(halos) == tiles**3


def test_duplicates_and_a_halo_that_must_grow(rng):
    # clusters of exact copies straddling tile borders, and a first halo far too small
    base = rng.random((500, 3))
    pts = np.repeat(base, 6, axis=0)
    pts[::7] = 0.5  # many copies exactly on the middle faces
    ref = nbhd.KdTree(pts).neighborhoods(k=9)
    offsets, indices, sq, halos = knn_table_by_tiles(pts, 9, 2, halo=1e-6)
    assert indices.tobytes() == ref.indices.tobytes()
    assert sq.tobytes() == ref.sq_dists.tobytes()
    assert max(halos) > 1e-6  # it had to grow


def test_a_sparse_outlier_pulls_in_the_whole_cloud(rng):
    pts = np.vstack([rng.random((3000, 3)), [[50.0, 50.0, 50.0]]])
    ref = nbhd.KdTree(pts).neighborhoods(k=4)
    _, indices, sq, _ = knn_table_by_tiles(pts, 4, 3)
    assert indices.tobytes() == ref.indices.tobytes()
    assert sq.tobytes() == ref.sq_dists.tobytes()
