"""Spatial tiles with halos: the first piece of running nbhd on clouds larger than one machine
(issue 18, part 2; the design is in python/DASK.md).

A cloud is cut into axis-aligned tiles; each tile *owns* the points inside it and searches a
k-d tree over its points plus a *halo* of the points around it. For k nearest neighbours the
halo grows (doubling) until every owned point's k-th distance is strictly below its distance to
the halo's outer border: then every point at least as near as the k-th neighbour lies inside the
searched set, so the rows equal the one-machine rows exactly, ties included (the halo keeps the
points in their global index order, so ties by index order the same way).

Every search is nbhd's (KdTree); this module only selects points and maps indices. A Dask layer
will run :func:`knn_rows_of_tile` as one task per tile; here it runs in a loop.
"""

from __future__ import annotations

import numpy as np

from ._nbhd import KdTree


def tile_boxes(points: np.ndarray, tiles_per_axis: int):
    """Boxes ``(lo, hi)`` of a grid of ``tiles_per_axis`` tiles per axis over the bounding box of
    the finite points, and the tile of every point (a point on a shared face belongs to the
    higher tile; the top faces belong to the last tile)."""
    lo = points.min(axis=0)
    hi = points.max(axis=0)
    size = (hi - lo) / tiles_per_axis
    size[size == 0] = 1.0
    cell = np.minimum(((points - lo) // size).astype(np.int64), tiles_per_axis - 1)
    dims = points.shape[1]
    tile_of = np.ravel_multi_index(tuple(cell.T), (tiles_per_axis,) * dims)
    boxes = []
    for t in range(tiles_per_axis**dims):
        c = np.array(np.unravel_index(t, (tiles_per_axis,) * dims))
        boxes.append((lo + c * size, lo + (c + 1) * size))
    return boxes, tile_of


def knn_rows_of_tile(points, owned, box, k, halo, **tree_options):
    """The k nearest *other* points of the points ``owned`` (global indices, ascending) of one
    tile with box ``(lo, hi)``: ``(indices (len(owned), k'), sq_dists)`` in global indices,
    equal to ``KdTree(points).neighborhoods(k=k)`` restricted to those rows. ``halo`` is the
    first halo width; it doubles until the rows are exact. Returns the rows and the halo used."""
    lo, hi = box
    q = points[owned]
    n = len(points)
    while True:
        inside = np.all((points >= lo - halo) & (points <= hi + halo), axis=1)
        sel = np.flatnonzero(inside)  # ascending: local order = global order
        tree = KdTree(points[sel], **tree_options)
        kk = min(k + 1, len(sel))
        local, d2 = tree.knn(q, kk)
        glob = sel[local.astype(np.int64)]
        # leave each point itself out (its duplicates stay): drop its own entry, or the last
        own = glob == owned[:, None]
        drop = np.where(own.any(axis=1), own.argmax(axis=1), kk - 1)
        keep = np.ones_like(own)
        keep[np.arange(len(owned)), drop] = False
        width = min(k, n - 1)
        glob = glob[keep].reshape(len(owned), kk - 1)[:, :width]
        d2 = d2[keep].reshape(len(owned), kk - 1)[:, :width]
        if len(sel) == n:
            return glob, d2, halo
        if kk - 1 < width:  # fewer than k other points searched: grow
            halo *= 2.0
            continue
        border = np.minimum(q - (lo - halo), (hi + halo) - q).min(axis=1)
        kth = np.sqrt(d2[:, -1].astype(np.float64)) if width else np.zeros(len(owned))
        # strictly inside, with a margin for rounding: only ever makes the halo larger
        if np.all(kth * (1 + 1e-9) + 1e-300 < border):
            return glob, d2, halo
        halo *= 2.0


def knn_table_by_tiles(points, k, tiles_per_axis, halo=None, **tree_options):
    """The table of :meth:`KdTree.neighborhoods` ``(k=k)`` computed tile by tile with halos:
    ``(offsets, indices, sq_dists)`` in the caller's order, and the halo each tile needed."""
    points = np.asarray(points)
    boxes, tile_of = tile_boxes(points, tiles_per_axis)
    n = len(points)
    width = min(k, n - 1)
    indices = np.empty((n, width), np.uint32)
    sq = None
    halos = []
    if halo is None:
        extent = (points.max(axis=0) - points.min(axis=0)).max()
        halo = extent / tiles_per_axis / 8 or 1.0
    for t, box in enumerate(boxes):
        owned = np.flatnonzero(tile_of == t)
        if len(owned) == 0:
            halos.append(0.0)
            continue
        glob, d2, used = knn_rows_of_tile(points, owned, box, k, halo, **tree_options)
        if sq is None:
            sq = np.empty((n, width), d2.dtype)
        indices[owned] = glob
        sq[owned] = d2
        halos.append(used)
    offsets = np.arange(n + 1, dtype=np.uint64) * width
    return offsets, indices.reshape(-1), sq.reshape(-1), halos
