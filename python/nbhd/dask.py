"""nbhd on Dask: neighbourhood tables, normals, curvatures and smoothing of clouds larger than
one machine, identical to the one-machine results (python/DASK.md has the user guide and the
halo reasoning).

A cloud — a Dask array ``(n, 3)`` of float32/float64, or a list of LAS/LAZ/PLY files whose
concatenation in list order is the caller's order — is first cut into spatial tiles written to
a *store* directory (:func:`tile_array`, :func:`tile_files`). Every computation then runs one
Dask task per tile: the task reads its tile plus a halo from the store, runs nbhd, writes the
owned points' rows or values to ``.npz`` files and returns a few numbers. A :class:`TileResult`
lists those files and assembles them back in caller order. With ``compute=False`` a method
returns the :class:`TileJob` instead (its futures give progress and cancellation).

Tasks use whatever Dask scheduler is active: a ``distributed.Client`` (a LocalCluster or a real
cluster; the store must then be on storage every worker mounts) or Dask's local schedulers.

Exactness: every tile sees every point its owned points' results read (the halo), in caller
index order, so trees, ties and sums run the same operations on the same numbers as one machine.
Lengths relative to the mean spacing h use the library's h, summed one by one in caller order by
a chain of tasks (:meth:`TiledCloud.spacing`): the same bits.
"""

from __future__ import annotations

import concurrent.futures
import json
import math
import os
import shutil
import threading
import time
from collections import namedtuple
from dataclasses import asdict

import dask
import numpy as np

from . import _tiles
from ._tiles import Spec, Tile, piece_path

__all__ = [
    "TiledCloud", "TileJob", "TileResult", "KeptResult", "VoxelResult", "RobustJob",
    "RobustResult",
    "AssembledTable",
    "tile_array", "tile_files",
    "open_store",
]

AssembledTable = namedtuple("AssembledTable", "offsets indices sq_dists")
AssembledTable.__doc__ = """A table in caller order as compressed rows (the arrays of
:class:`nbhd.Table`): row i is ``indices[offsets[i]:offsets[i+1]]`` with its ``sq_dists``."""


def _grid(n, lo, hi, points_per_tile):
    """Tiles per axis: about ``n / points_per_tile`` tiles of roughly cubic shape over the
    extent; an axis thinner than a tile's side gets one tile (a terrain is cut in x and y)."""
    ext = np.maximum(np.asarray(hi, np.float64) - np.asarray(lo, np.float64), 0.0)
    want = max(1, math.ceil(n / max(1, points_per_tile)))
    live = ext > 0
    while live.any():
        side = (np.prod(ext[live]) / want) ** (1.0 / live.sum())
        thin = live & (ext < side)
        if not thin.any():
            break
        live &= ~thin
    if not live.any() or want == 1:
        return [1] * len(ext)
    return [max(1, int(round(e / side))) if on else 1 for e, on in zip(ext, live)]


def _holes_path(store, c):
    return os.path.join(store, f"holes_c{c:06d}.npz")


def _bucket(chunk, start, lo, hi, grid, store, c, skip=False):
    """Task: the points of one input chunk sorted into grid tiles, one piece file per
    (chunk, tile); returns each piece's tile, count and tight box, and the chunk's holes file
    or None. Rows with a non-finite coordinate are refused, or with ``skip`` written to the
    chunk's holes file (their caller indices and rows) and left out of every tile."""
    pts = np.asarray(chunk)
    if pts.ndim != 2 or pts.shape[1] != 3:
        raise ValueError(f"points must be an (n, 3) array, chunk {c} is {pts.shape}")
    finite = np.all(np.isfinite(pts), axis=1)
    ids = np.arange(start, start + len(pts), dtype=np.int64)
    hole_file = None
    if not finite.all():
        if not skip:
            raise ValueError(f"point {int(ids[~finite][0])} has a non-finite coordinate")
        hole_file = _holes_path(store, c)
        np.savez(hole_file, idx=ids[~finite], pts=pts[~finite])
        pts, ids = pts[finite], ids[finite]
    lo = np.asarray(lo, np.float64)
    size = (np.asarray(hi, np.float64) - lo) / np.asarray(grid)
    size[size == 0] = 1.0
    cell = np.floor((pts.astype(np.float64) - lo) / size).astype(np.int64)
    cell = np.clip(cell, 0, np.asarray(grid) - 1)
    tile = np.ravel_multi_index(tuple(cell.T), tuple(grid))
    order = np.argsort(tile, kind="stable")  # stable: ascending index within a tile
    tile_sorted = tile[order]
    cuts = np.flatnonzero(np.diff(tile_sorted)) + 1
    out = []
    for sel in np.split(order, cuts):
        if len(sel) == 0:
            continue
        t = int(tile[sel[0]])
        base = piece_path(store, c, t)
        p = pts[sel]
        np.save(base + ".pts.npy", p)
        np.save(base + ".idx.npy", ids[sel])
        out.append((t, len(sel), p.min(axis=0).tolist(), p.max(axis=0).tolist(), c))
    return out, hole_file


def _ingest(path, i, store, dtype):
    """Task: one LAS/LAZ/PLY file read with nbhd.read and kept as a piece (the file is a tile)."""
    import nbhd

    pts = np.ascontiguousarray(nbhd.read(path)["positions"], dtype=dtype)
    if len(pts) and not np.all(np.isfinite(pts)):
        raise ValueError(f"{path}: a point has a non-finite coordinate")
    out = os.path.join(store, f"file_{i:06d}.pts.npy")
    np.save(out, pts)
    if len(pts) == 0:
        return 0, [0.0] * 3, [0.0] * 3, out
    return len(pts), pts.min(axis=0).tolist(), pts.max(axis=0).tolist(), out


def tile_array(points, store, *, points_per_tile=250_000, grid=None, non_finite="reject"):
    """Cuts a Dask array ``(n, 3)`` (float32 or float64; rows in any chunks) into spatial tiles
    written under the directory ``store``: one pass for the bounding box, one task per chunk
    sorting its points into tiles. ``grid`` (tiles per axis) overrides ``points_per_tile``.
    A row with a NaN or infinite coordinate is refused (``non_finite="reject"``) or kept aside
    as a hole (``"skip"``: only :meth:`TiledCloud.smooth_robust` takes such a cloud, and skips
    the holes as ``nbhd.smooth_robust(..., non_finite="skip")`` does). Returns the
    :class:`TiledCloud`."""
    import dask.array as da

    if non_finite not in ("reject", "skip"):
        raise ValueError(f"unknown non_finite {non_finite!r}; expected 'reject' or 'skip'")

    points = da.asarray(points)
    if points.ndim != 2 or points.shape[1] != 3:
        raise ValueError(f"points must be an (n, 3) array, not {points.shape}")
    if points.dtype not in (np.float32, np.float64):
        points = points.astype(np.float64)
    os.makedirs(store, exist_ok=True)
    points = points.rechunk({1: -1})
    n = int(points.shape[0])
    if n < 2:
        raise ValueError("a tiled cloud needs at least two points")
    if non_finite == "skip":
        # the box and the scale of the finite rows
        finite = da.isfinite(points).all(axis=1)[:, None]
        lo, hi, big = dask.compute(
            da.where(finite, points, np.inf).min(axis=0),
            da.where(finite, points, -np.inf).max(axis=0),
            da.where(finite, abs(points), 0).max())
        if not np.all(np.isfinite(lo)):
            raise ValueError("a tiled cloud needs at least two finite points")
    else:
        lo, hi, big = dask.compute(points.min(axis=0), points.max(axis=0), abs(points).max())
    lo, hi = np.asarray(lo, np.float64), np.asarray(hi, np.float64)
    grid = list(grid) if grid is not None else _grid(n, lo, hi, points_per_tile)
    starts = np.concatenate([[0], np.cumsum(points.chunks[0])])
    blocks = points.to_delayed().ravel()
    tasks = [
        dask.delayed(_bucket)(b, int(starts[c]), lo.tolist(), hi.tolist(), grid, store, c,
                              non_finite == "skip")
        for c, b in enumerate(blocks)
    ]
    done = dask.compute(*tasks)
    pieces = [p for p, _ in done]
    holes = [h for _, h in done if h is not None]
    tiles = [Tile([0.0] * 3, [0.0] * 3, 0, t) for t in range(int(np.prod(grid)))]
    for chunk in pieces:  # chunks in order: a tile's pieces ascend in caller index
        for t, count, plo, phi, c in chunk:
            tile = tiles[t]
            if tile.count == 0:
                tile.lo, tile.hi = plo, phi
            else:
                tile.lo = np.minimum(tile.lo, plo).tolist()
                tile.hi = np.maximum(tile.hi, phi).tolist()
            tile.count += count
            tile.chunks.append(c)
    spec = Spec(n, np.dtype(points.dtype).name, [t for t in tiles if t.count], float(big), store,
                holes)
    return TiledCloud(spec, store)


def tile_files(paths, store, *, dtype=np.float64):
    """A cloud given as LAS/LAZ/PLY (any format nbhd.read reads) tile files: their points in
    list order are the caller's rows. Each file is read once, by a task, with nbhd's own
    readers and kept in the store as one tile (its points and tight box; files may overlap, the
    halos stay exact). ``dtype``: the type the computations see (float64: the files' own
    coordinates; float32 to compute as with a float32 array)."""
    os.makedirs(store, exist_ok=True)
    dtype = np.dtype(dtype)
    if dtype not in (np.float32, np.float64):
        raise ValueError(f"dtype must be float32 or float64, not {dtype}")
    done = dask.compute(
        *[dask.delayed(_ingest)(os.fspath(p), i, store, dtype) for i, p in enumerate(paths)]
    )
    tiles, start, big = [], 0, 0.0
    for count, lo, hi, out in done:
        if count:
            tiles.append(Tile(lo, hi, count, file=out, start=start))
            big = max(big, max(abs(v) for v in lo + hi))
        start += count
    if start < 2:
        raise ValueError("a tiled cloud needs at least two points")
    return TiledCloud(Spec(start, dtype.name, tiles, big, store), store)


def open_store(store):
    """The :class:`TiledCloud` saved in ``store`` by :meth:`TiledCloud.save`."""
    with open(os.path.join(store, "cloud.json")) as f:
        d = json.load(f)
    tiles = [Tile(**t) for t in d["tiles"]]
    spec = Spec(d["n"], d["dtype"], tiles, d["scale"], store, d.get("holes", []))
    return TiledCloud(spec, store)


def _first_halo(spec, t, k):
    """A first kNN halo: the spacing k points would have if the tile's points filled its box
    evenly, times 2 (it doubles as needed)."""
    tile = spec.tiles[t]
    ext = np.maximum(np.asarray(tile.hi) - np.asarray(tile.lo), 0)
    live = ext[ext > 0]
    if len(live) == 0:
        return max(spec.scale * 1e-6, 1e-12)
    vol = np.prod(live) * max(k, 1) / tile.count
    return float(2.0 * vol ** (1.0 / len(live)))


class TiledCloud:
    """A cloud cut into spatial tiles in a store directory (see the module doc). Its methods
    run one Dask task per tile and return a :class:`TileResult` (with ``compute=False``: the
    unstarted :class:`TileJob`); ``out`` names a directory for the result files (default: a
    new folder in the store)."""

    def __init__(self, spec: Spec, store: str):
        self.spec = spec
        self.store = store
        self._h = None

    @property
    def n(self) -> int:
        return self.spec.n

    @property
    def dtype(self) -> np.dtype:
        return np.dtype(self.spec.dtype)

    @property
    def tiles(self) -> int:
        return len(self.spec.tiles)

    def __repr__(self):
        return (
            f"TiledCloud(n={self.n}, dtype={self.spec.dtype}, tiles={self.tiles}, "
            f"store={self.store!r})"
        )

    def save(self):
        """Writes ``cloud.json`` in the store (:func:`open_store` reads it back)."""
        d = {"n": self.spec.n, "dtype": self.spec.dtype, "scale": self.spec.scale,
             "tiles": [asdict(t) for t in self.spec.tiles], "holes": self.spec.holes}
        with open(os.path.join(self.store, "cloud.json"), "w") as f:
            json.dump(d, f)

    def _spec_node(self):
        """The tile list as one node of the graph, which every tile task depends on: shipped
        to a worker once, not copied into every task (a task holding its own copy of a list of
        thousands of tiles, with hundreds of tasks queued on a worker, fills its memory)."""
        if self.spec.holes:
            raise ValueError("this cloud has holes (tile_array(non_finite='skip')): only "
                             "smooth_robust skips them")
        return dask.delayed(self.spec, pure=False, traverse=False)

    def _out(self, out, name):
        if out is None:
            i = 0
            while os.path.exists(os.path.join(self.store, f"{name}-{i}")):
                i += 1
            out = os.path.join(self.store, f"{name}-{i}")
        os.makedirs(out, exist_ok=True)
        return out

    # --- neighbourhood tables -------------------------------------------------------------

    def knn(self, k, *, threads=0, batch=_tiles.BATCH, out=None, compute=True, **tree_options):
        """Every point's ``k`` nearest other points: ``KdTree(points).neighborhoods(k=k)``,
        byte for byte (halos grow until exact). ``tree_options`` go to each tile's KdTree;
        ``threads`` is each task's nbhd threads (0: all cores), ``batch`` the queries a task
        answers at a time (its memory; the result is the same). ``compute=False`` returns the
        :class:`TileJob` unstarted (progress and cancellation through its futures)."""
        if k < 1:
            raise ValueError("k must be >= 1")
        out = self._out(out, "knn")
        spec = self._spec_node()
        tasks = [
            dask.delayed(_tiles.knn_tile, pure=False)(
                spec, t, k, _first_halo(self.spec, t, k),
                os.path.join(out, f"tile_{t:06d}.npz"), tree_options, threads, batch)
            for t in range(self.tiles)
        ]
        return TileJob("table", self.n, tasks).run(compute)

    def radius(self, radius, *, k=None, threads=0, batch=_tiles.BATCH, out=None, compute=True,
               **tree_options):
        """Every point's other points within ``radius`` (inclusive; absolute units), or with
        ``k`` the ε-k-neighbourhood (the ``k`` nearest of them):
        ``KdTree(points).neighborhoods(radius=radius[, k=k])``, byte for byte (halo: the
        radius)."""
        if not (np.isfinite(radius) and radius >= 0):
            raise ValueError(f"radius {radius} must be finite and >= 0")
        if k is not None and k < 1:
            raise ValueError("k must be >= 1")
        out = self._out(out, "radius")
        spec = self._spec_node()
        tasks = [
            dask.delayed(_tiles.radius_tile, pure=False)(
                spec, t, k, float(radius), os.path.join(out, f"tile_{t:06d}.npz"),
                tree_options, threads, batch)
            for t in range(self.tiles)
        ]
        return TileJob("table", self.n, tasks).run(compute)

    def knn_radius(self, k, radius, *, threads=0, batch=_tiles.BATCH, out=None, compute=True,
                   **tree_options):
        """The ε-k-neighbourhood table (see :meth:`radius`)."""
        return self.radius(radius, k=k, threads=threads, batch=batch, out=out, compute=compute,
                           **tree_options)

    # --- filters ----------------------------------------------------------------------------

    def remove_statistical_outliers(self, *, k=50, std_ratio=1.0, threads=0, batch=_tiles.BATCH,
                                    out=None, **tree_options):
        """``KdTree(points).remove_statistical_outliers(k=k, std_ratio=std_ratio)`` on the
        tiles, identical: a point is kept when its mean distance to its ``k`` nearest other
        points is at most ``mean + std_ratio · σ`` over all points. Three passes: one task per
        tile for the mean distances (exact kNN halos) and their exact sum, merged into the mean;
        one per tile for the exact sum of squared deviations, merged into σ; the threshold then
        applies to each tile's file. Both sums are exact (``nbhd.ExactSum``), as the library's
        own filter takes them, so no order of the tiles changes a bit. Returns a
        :class:`KeptResult` (``assemble()``: the kept caller indices, ascending;
        :meth:`TiledCloud.select` makes the kept points a tiled cloud)."""
        import nbhd

        if not isinstance(k, (int, np.integer)) or k < 1:
            raise ValueError(f"k must be an integer >= 1, not {k!r}")
        if k >= self.n:
            raise ValueError(f"{k} nearest other points need more than {k} points; the cloud "
                             f"holds {self.n}")
        if not np.isfinite(std_ratio):
            raise ValueError(f"std_ratio {std_ratio} is not finite")
        out = self._out(out, "outliers")
        spec = self._spec_node()
        parts = list(dask.compute(*[
            dask.delayed(_tiles.outlier_tile, pure=False)(
                spec, t, int(k), _first_halo(self.spec, t, k),
                os.path.join(out, f"tile_{t:06d}.npz"), tree_options, threads, batch)
            for t in range(self.tiles)]))
        total = nbhd.ExactSum()
        for p in parts:
            total.merge(p.pop("sum"))
        mean = total.value() / self.n
        spread = nbhd.ExactSum()
        for s in dask.compute(*[dask.delayed(_tiles.outlier_spread, pure=False)(p["path"], mean)
                                for p in parts]):
            spread.merge(s)
        threshold = nbhd.outlier_threshold(mean, spread, self.n, float(std_ratio))
        return KeptResult(self.n, parts, threshold)

    def select(self, kept, store=None):
        """The kept points of ``kept`` (a :class:`KeptResult`) as a new :class:`TiledCloud`
        in a new store (default: a folder beside this one): the tiles keep their places, the
        rows their order, so its caller order is ``points[kept.assemble()]``'s and everything
        computed on it equals the one-machine computation on those rows. Each task renumbers
        its tile's points by the removed indices below them (the removed are few: the list
        travels, the kept do not)."""
        if store is None:
            store = self._out(None, "kept")
        os.makedirs(store, exist_ok=True)
        removed = kept.removed()
        node = dask.delayed(removed, pure=False, traverse=False)
        spec = self._spec_node()
        done = dask.compute(*[
            dask.delayed(_tiles.select_tile, pure=False)(spec, t, node, kept.parts[t]["path"],
                                                         kept.threshold, store)
            for t in range(self.tiles)])
        return _cloud_of_pieces(done, self.n - len(removed), self.spec.dtype, store,
                                "points are kept")

    def voxel_grid(self, leaf, *, min_points_per_voxel=0, threads=0, out=None):
        """``nbhd.voxel_grid(points, leaf, ...)`` on the tiles, identical: every occupied voxel's
        centroid (PCL's arithmetic in the cloud's type), members, nearest member and voxel
        numbers. Each tile task computes the voxels whose smallest caller index it owns on the
        tile plus a halo of one voxel edge, so each voxel is whole in exactly one tile. The
        whole cloud's grid (its lowest voxel numbers, and the refusal of a leaf too small for
        its extent, with the one-machine message) comes from the tiles' boxes. Returns a
        :class:`VoxelResult`: ``assemble()`` gives the dict ``nbhd.voxel_grid`` returns,
        ``cloud()`` the centroids as a tiled cloud in that order."""
        import nbhd

        leaf = [float(leaf)] if np.ndim(leaf) == 0 else [float(v) for v in leaf]
        lo = np.min([t.lo for t in self.spec.tiles], axis=0)
        hi = np.max([t.hi for t in self.spec.tiles], axis=0)
        # the grid of the whole cloud: nbhd's own checks and voxel numbers of its box's corners
        corners = nbhd.voxel_grid(np.array([lo, hi], self.dtype), leaf)["cells"]
        low, high = corners.min(axis=0), corners.max(axis=0)
        mul = [1]
        for a in range(len(low) - 1):  # Python integers: no overflow below 2^64 voxels
            mul.append(mul[-1] * (int(high[a]) - int(low[a]) + 1))
        out = self._out(out, "voxels")
        spec = self._spec_node()
        parts = dask.compute(*[
            dask.delayed(_tiles.voxel_tile, pure=False)(
                spec, t, leaf, int(min_points_per_voxel), low.tolist(), mul,
                os.path.join(out, f"tile_{t:06d}.npz"), threads)
            for t in range(self.tiles)])
        return VoxelResult(self, list(parts), out)

    # --- spacing, geometry, smoothing ------------------------------------------------------

    def spacing(self, block: int = 4_000_000) -> float:
        """The mean nearest-neighbour spacing h exactly as nbhd.smooth/normals/curvatures
        compute it (f64, the square roots summed one by one in caller order, divided by n):
        per-tile nearest distances (kNN halos), then a chain of tasks adding them in order,
        ``block`` points each (the running sum passes from one to the next)."""
        if self._h is None:
            out = self._out(None, "nearest")
            spec = self._spec_node()
            parts = dask.compute(*[
                dask.delayed(_tiles.nearest_tile, pure=False)(
                    spec, t, _first_halo(self.spec, t, 1),
                    os.path.join(out, f"tile_{t:06d}"))
                for t in range(self.tiles)])
            block = max(1, min(self.n, int(block)))
            carry = 0.0
            for a in range(0, self.n, block):
                b = min(a + block, self.n)
                carry = dask.delayed(_tiles.partial_sum, pure=False)(list(parts), a, b, carry)
            self._h = float(dask.compute(carry)[0]) / self.n
        return self._h

    def _length(self, v, units):
        if units == "absolute":
            return float(v)
        if units != "relative":
            raise ValueError(f"unknown units {units!r}; expected 'relative' or 'absolute'")
        return float(v) * self.spacing()

    def _curvature(self, v, units):
        if units == "absolute":
            return float(v)
        if units != "relative":
            raise ValueError(f"unknown units {units!r}; expected 'relative' or 'absolute'")
        return float(v) / self.spacing()

    def _geometry(self, what, halo, kwargs, out, compute, epsilon):
        out = self._out(out, what)
        spec = self._spec_node()
        tasks = [
            dask.delayed(_tiles.geometry_tile, pure=False)(
                spec, t, what, halo, os.path.join(out, f"tile_{t:06d}.npz"), kwargs)
            for t in range(self.tiles)
        ]
        return TileJob("arrays", self.n, tasks, epsilon).run(compute)

    @staticmethod
    def _orientation(orientation):
        if orientation.replace("_", "-") == "propagate":
            raise ValueError("orientation 'propagate' is global (a spanning tree over the whole "
                             "cloud) and is not computed per tile")

    def normals(self, *, k=15, epsilon=6.0, epsilon_units="relative", orientation="unoriented",
                orientation_point=(0.0, 0.0, 0.0), threads=0, out=None, compute=True):
        """``nbhd.normals(points, ...)`` tile by tile (halo ε): arrays ``normals``,
        ``surface_variation``, ``flags``, identical to the last bit."""
        self._orientation(orientation)
        eps = self._length(epsilon, epsilon_units)
        kw = dict(k=k, epsilon=eps, epsilon_units="absolute", orientation=orientation,
                  orientation_point=tuple(orientation_point), threads=threads)
        return self._geometry("normals", eps, kw, out, compute, eps)

    def curvatures(self, *, k=15, epsilon=6.0, epsilon_units="relative", orientation="unoriented",
                   orientation_point=(0.0, 0.0, 0.0), density="abs-linear", formula="eq2.25",
                   threads=0, out=None, compute=True):
        """``nbhd.curvatures(points, ...)`` tile by tile (halo ε): its arrays, identical to the
        last bit."""
        self._orientation(orientation)
        eps = self._length(epsilon, epsilon_units)
        kw = dict(k=k, epsilon=eps, epsilon_units="absolute", orientation=orientation,
                  orientation_point=tuple(orientation_point), density=density, formula=formula,
                  threads=threads)
        return self._geometry("curvatures", eps, kw, out, compute, eps)

    def smooth(self, *, method="anisotropic", k=15, epsilon=6.0, epsilon_units="relative",
               steps=None, tau=0.5, weighting=None, lambda_=0.2, lambda_units="relative",
               feature="all", feature_threshold=None, feature_units="relative",
               constrain_interior=None, orientation="unoriented",
               orientation_point=(0.0, 0.0, 0.0), outputs=False, threads=0, out=None,
               compute=True):
        """``nbhd.smooth(points, ...)`` (the faithful method) tile by tile: array ``points``
        and, with ``outputs``, ``outputs.<name>``, identical to the last bit. Halo: steps·ε
        (a step reads only the point's own row, fixed on the input), plus ε for the outputs.
        ``update_neighbors`` is not offered (rows follow the moving points; no halo is proven
        for it); the robust mode is :meth:`smooth_robust`."""
        self._orientation(orientation)
        if steps is None:
            steps = 2 if method == "isotropic" else 3
        eps = self._length(epsilon, epsilon_units)
        lam = self._curvature(lambda_, lambda_units)
        thr = feature_threshold
        if thr is not None and feature in ("principal", "directional"):
            thr = self._curvature(thr, feature_units)
        kw = dict(method=method, k=k, epsilon=eps, epsilon_units="absolute", steps=steps, tau=tau,
                  weighting=weighting, lambda_=lam, lambda_units="absolute", feature=feature,
                  feature_threshold=thr, feature_units="absolute",
                  constrain_interior=constrain_interior, orientation=orientation,
                  orientation_point=tuple(orientation_point), outputs=outputs, threads=threads)
        halo = eps * (steps + (1 if outputs else 0))
        return self._geometry("smooth", halo, kw, out, compute, eps)


    def smooth_robust(self, *, k=24, k_plane=48, epsilon=12.0, epsilon_units="relative",
                      max_iterations=10, tolerance=0.05, inlier_width=5.0, feature_angle=20.0,
                      tau=1.0, noise_scale=None, orientation="unoriented",
                      orientation_point=(0.0, 0.0, 0.0), non_finite="reject", outputs=False,
                      threads=0, out=None, client=None, compute=True, progress=None):
        """``nbhd.smooth_robust(points, ...)`` on the tiles, identical to the last bit: the
        arrays ``points``, ``normals`` and with ``outputs`` ``outputs.<name>``, and the run's
        figures (``noise``, ``moved``, ``dimension``, ``wide_iterations``, ``spacing``,
        ``epsilon``, ``lambda``, ``min_neighbors``) in :meth:`RobustResult.assemble`.

        Needs a ``distributed`` client (``client``, default the current one): the client
        drives the rounds of ``nbhd.RobustRun``; each round is one task per tile, which
        reads the tile and its halo, its rows (gathered and searched by the tile's first
        round, kept in files under ``out``) and the positions of the round's generation
        from the owners' files, so a worker holds one tile at a time
        (its memory is bounded by a tile's working set, not by the cloud); every round's medians are
        reduced exactly (``nbhd.RankSearch`` over the tiles' value files, never gathered). A
        cloud cut with ``non_finite="skip"`` has holes: they are refused here unless
        ``non_finite="skip"``, and then keep their rows with NaN normals and outputs, as on
        one machine. ``threads`` is each task's nbhd threads (0: all cores; 1 with workers of
        one thread each, so a task holds one thread's buffers). ``compute=False`` returns the
        unstarted :class:`RobustJob` (progress, cancellation); ``progress`` is called with the
        job's ``status`` after every tile task."""
        self._orientation(orientation)
        if non_finite not in ("reject", "skip"):
            raise ValueError(f"unknown non_finite {non_finite!r}; expected 'reject' or 'skip'")
        if self.spec.holes and non_finite == "reject":
            first = min(int(np.load(h)["idx"][0]) for h in self.spec.holes)
            raise ValueError(f"point {first} has a non-finite coordinate")
        if client is None:
            import distributed

            client = distributed.get_client()
        import nbhd

        options = nbhd.RobustOptions(
            k=k, k_plane=k_plane, epsilon=epsilon, epsilon_units=epsilon_units,
            max_iterations=max_iterations, tolerance=tolerance, inlier_width=inlier_width,
            feature_angle=feature_angle, tau=tau, noise_scale=noise_scale,
            orientation=orientation, orientation_point=tuple(orientation_point),
            outputs=outputs)
        job = RobustJob(self, options, k_plane, max_iterations, self._out(out, "robust"), client,
                        progress, threads)
        return job.run() if compute else job


# the volume of the unit ball in 1 and 2 dimensions: a segment, a disc
_UNIT_BALL = {1: 2.0, 2: np.pi}


def _cloud_of_pieces(done, n, dtype, store, what):
    """The :class:`TiledCloud` of ``n`` points that ``_tiles.write_piece`` tasks wrote to
    ``store`` (``done``: their ``(t, count, lo, hi)``), one piece per non-empty tile."""
    if n < 2:
        raise ValueError(f"fewer than two {what}: not a tiled cloud")
    tiles = [Tile(lo, hi, count, grid_id=t, chunks=[0]) for t, count, lo, hi in done if count]
    big = max((max(abs(v) for v in t.lo + t.hi) for t in tiles), default=0.0)
    return TiledCloud(Spec(n, dtype, tiles, big, store), store)


def _first_robust_halo(spec, t, k_plane):
    """The first halo of a robust tile: three hops (a step's reach, ``robust/reach.rs``), each
    the radius of a disc holding ``k_plane`` points if the tile's points covered its box's two
    largest extents evenly (a surface: a terrain, a facade), with a third more for the spread
    of the ``k_plane``-th distances in a random sample: 4 radii. The library checks every
    owned point's reach; a tile that fails is gathered again with twice the halo. (The side
    of a square holding ``k_plane`` points, 1.77 radii, gathered 1.8 times a 15,000-point
    terrain tile's points where this gathers 1.55 times.)"""
    tile = spec.tiles[t]
    ext = np.sort(np.maximum(np.asarray(tile.hi) - np.asarray(tile.lo), 0))[::-1][:2]
    live = ext[ext > 0]
    if len(live) == 0:
        return max(spec.scale * 1e-6, 1e-12)
    ball = np.prod(live) * k_plane / (tile.count * _UNIT_BALL[len(live)])
    return float(4.0 * ball ** (1.0 / len(live)))


def _halo_ok(part):
    """Whether a tile's part of a round holds the one-machine values for every owned point
    (the library's check); otherwise the tile is gathered again with twice the halo."""
    return part["valid"]


def _merge_counts(counts):
    import nbhd

    merged = nbhd.DigitCounts.from_bytes(counts[0])
    for c in counts[1:]:
        merged.merge(nbhd.DigitCounts.from_bytes(c))
    return merged


def _exact_rank(job, parts, rank):
    """The value of rank ``rank`` among the values of the tiles' last round, exactly
    (``nbhd.RankSearch``): the first digit counts come with the round's parts; each further
    round is one task per tile reading its values file, for its counts in the bucket found so
    far, and once that bucket is small, for its values in it."""
    import nbhd

    search = nbhd.RankSearch(rank)
    search.feed_counts(_merge_counts([p["counts"] for p in parts]))
    while True:
        step, value = search.step()
        if step == "found":
            return value
        state = search.to_bytes()
        if step == "counts":
            search.feed_counts(_merge_counts(job._each_value(_tiles.robust_counts, state)))
        else:
            search.feed_values(np.concatenate(job._each_value(_tiles.robust_matching, state)))


class RobustJob:
    """One robust run on a tiled cloud (:meth:`TiledCloud.smooth_robust`), driven from the
    client: ``nbhd.RobustRun`` decides every round; each round is one task per tile that
    gathers its tile, computes the round and writes the owned values to files, holding
    nothing afterwards (python/DASK.md). With ``compute=False`` the job is returned
    unstarted: :meth:`submit` starts it in a thread of the client, :attr:`status` says where
    it is (round, tiles done, points/s, an ETA), :meth:`cancel` stops it and :meth:`result`
    waits for the :class:`RobustResult`."""

    def __init__(self, cloud, options, k_plane, max_iterations, out, client, progress=None,
                 threads=0):
        """``options``: the run's ``nbhd.RobustOptions``, made with ``k_plane`` (which sizes
        the first halos) and ``max_iterations`` (which bounds the ETA); ``progress``: called
        with :attr:`status` on the client after every tile task; ``threads``: each tile
        task's nbhd threads."""
        self.cloud, self.options, self.out, self.client = cloud, options, out, client
        self.threads = threads
        spec = cloud.spec
        self.widths = [_first_robust_halo(spec, t, k_plane) for t in range(cloud.tiles)]
        self.max_iterations = max_iterations
        self.progress = progress
        self._cancelled = threading.Event()
        self._lock = threading.Lock()
        self._futures = []
        self._thread = None
        self._outcome = None
        # rounds taken, halos grown, owned values used although their tile said they are not
        # the cloud's (none unless _halo_ok is overridden); the progress figures
        self.status = {"round": None, "generation": 0, "iteration": 0, "grown": 0,
                       "rounds": 0, "invalid": 0, "tiles": cloud.tiles, "tiles_done": 0,
                       "points_per_s": 0.0, "eta_s": None, "cancelled": False}
        self._points = 0  # owned points of the tile tasks finished
        self._rounds_done = 0  # rounds of tile tasks finished (with their selections after)

    # --- running, progress, cancellation ------------------------------------------------

    def submit(self):
        """Starts the run in a thread of the client (once); returns the job."""
        if self._thread is None:
            self._thread = threading.Thread(target=self._main, daemon=True)
            self._thread.start()
        return self

    def _main(self):
        try:
            self._outcome = (True, self.run())
        except BaseException as e:  # handed to result()
            self._outcome = (False, e)

    def cancel(self):
        """Stops the run: the tiles of the current round not yet finished are cancelled and
        no further round starts; :meth:`result` then raises ``CancelledError``. A tile task
        already running finishes its round and writes complete files (the rule of
        :class:`TileJob`)."""
        self._cancelled.set()
        with self._lock:
            futures = list(self._futures)
        if futures:
            self.client.cancel(futures)

    def result(self, timeout=None):
        """The :class:`RobustResult` of a submitted job (waits; raises what the run raised,
        ``CancelledError`` when cancelled), or the run itself when not submitted."""
        if self._thread is None:
            return self.run()
        self._thread.join(timeout)
        if self._thread.is_alive():
            raise TimeoutError(f"the robust run is still going after {timeout} s")
        ok, value = self._outcome
        if not ok:
            raise value
        return value

    def _check(self):
        if self._cancelled.is_set():
            self.status["cancelled"] = True
            raise concurrent.futures.CancelledError("the robust run was cancelled")

    def _tick(self, started, rows):
        """One tile task done: the counts, points/s over the run, and the ETA — the current
        round's remaining tiles at its pace so far, plus at most the rounds the run may still
        take (three an iteration up to ``max_iterations``, and the finish) at the mean pace of
        the rounds done: an upper bound, as the run may stop early."""
        st = self.status
        st["tiles_done"] += 1
        self._points += rows
        now = time.monotonic()
        st["points_per_s"] = self._points / max(now - self._t0, 1e-9)
        spent = now - started
        left = spent / st["tiles_done"] * (st["tiles"] - st["tiles_done"])
        if st["round"] == "finish":
            more = 0
        else:
            more = 3 * max(self.max_iterations - st["iteration"], 0) + 1
            more += st["round"] == "nearest"  # the start round is still to come
        done = self._rounds_done
        mean = (started - self._t0) / done if done else spent
        st["eta_s"] = left + more * mean
        if self.progress is not None:
            self.progress(dict(st))

    # --- the rounds -----------------------------------------------------------------------

    def _each(self, fn, *args):
        """``fn(spec, t, width, options, threads, out, *args)`` as one task per tile; a tile
        whose part fails :func:`_halo_ok` is gathered again with twice the halo and run again."""
        import distributed

        self._check()
        st = self.status
        st["tiles_done"], started = 0, time.monotonic()

        def submit(t):
            return self.client.submit(fn, self._spec, t, self.widths[t], self.options,
                                      self.threads, self.out, *args, pure=False)

        tile_of = {}
        with self._lock:
            for t in range(self.cloud.tiles):
                f = submit(t)
                tile_of[f.key] = t
                self._futures.append(f)
        parts = [None] * self.cloud.tiles
        pending = distributed.as_completed(list(self._futures))
        for f in pending:
            self._check()
            part = f.result()
            t = tile_of[f.key]
            if not _halo_ok(part):
                self.widths[t] *= 2.0
                st["grown"] += 1
                g = submit(t)
                tile_of[g.key] = t
                with self._lock:
                    self._futures.append(g)
                pending.add(g)
                continue
            st["invalid"] += part["invalid"]
            parts[t] = part
            self._tick(started, part["rows"])
        with self._lock:
            self._futures = []
        self._rounds_done += 1
        return parts

    def _each_value(self, fn, search):
        """``fn(out, t, search)`` as one task per tile (a step of an exact selection)."""
        self._check()
        with self._lock:
            self._futures = [self.client.submit(fn, self.out, t, search, pure=False)
                             for t in range(self.cloud.tiles)]
            futures = list(self._futures)
        values = self.client.gather(futures)
        with self._lock:
            self._futures = []
        return values

    def _spacing(self):
        """h as ``smooth_robust`` computes it: every owned point's nearest squared distance
        (the tiles' plain rows), summed in caller order by a chain of tasks."""
        self.status.update(round="nearest")
        parts = self._each(_tiles.robust_nearest)
        # blocks of 500,000 rows: a task's arrays stay a few MB, far below a worker's limit
        n, block, carry = self.cloud.n, 500_000, (0.0, 0)
        for a in range(0, n, block):
            carry = dask.delayed(_tiles.partial_sum_finite, pure=False)(
                parts, a, min(a + block, n), carry)
        total, count = self.client.compute(carry).result()
        for p in parts:
            for suffix in (".idx.npy", ".nearest.npy"):
                os.remove(p["path"] + suffix)
        return total / count if count else 0.0

    def run(self):
        """Runs every round here (see :meth:`submit` for a run in the background)."""
        import nbhd

        self._t0 = time.monotonic()
        # the tiles' kept gathers and rows are this run's: none of an earlier run in `out`
        shutil.rmtree(os.path.join(self.out, "rows"), ignore_errors=True)
        self._spec = self.client.scatter(self.cloud.spec, broadcast=True)
        run = nbhd.RobustRun(self._spacing(), self.options)
        while (r := run.round())["kind"] != "finish":
            self.status.update(round=r["kind"], generation=r["generation"])
            parts = self._each(_tiles.robust_round, r)
            total = sum(p["n_values"] for p in parts)
            median = _exact_rank(self, parts, run.median_rank(total)) if total else None
            moved = nbhd.ExactSum()
            for p in parts:
                moved.merge(nbhd.ExactSum.from_bytes(p["moved_sq"]))
            run.feed(r, count=sum(p["count"] for p in parts),
                     max_len=max(p["max_len"] for p in parts),
                     min_narrow=min(p["min_narrow"] for p in parts),
                     median=median, moved_sq=moved)
            self.status["rounds"] += 1
            if r["kind"] == "step":
                self.status["iteration"] += 1
                if run.round().get("shrunk_at") != r["generation"]:
                    self._drop_generation(r["generation"])
        self.status.update(round="finish", generation=r["generation"])
        parts = self._each(_tiles.robust_finish, r)
        for g in range(r["generation"] + 1):
            self._drop_generation(g)
        for kept in ("values", "rows"):
            shutil.rmtree(os.path.join(self.out, kept), ignore_errors=True)
        result = RobustResult(self.cloud.spec, parts, run.report())
        result.status = self.status
        return result

    def _drop_generation(self, g):
        """Generation ``g``'s files, read by no later round."""
        shutil.rmtree(os.path.join(self.out, f"gen_{g:04d}"), ignore_errors=True)


class TileJob:
    """The tile tasks of one computation, not yet run (a method's ``compute=False``): one
    ``dask.delayed`` per tile in ``tasks``. On a ``distributed`` cluster, :meth:`submit` starts
    them and returns their futures — ``distributed.progress(futures)`` shows the progress,
    :meth:`cancel` (or ``client.cancel(futures)``) cancels the tiles not yet finished — and
    :meth:`result` waits for them and returns the :class:`TileResult`.

    A cancelled tile that was already running finishes its nbhd call on its worker (a task is
    not interrupted) and its file is written; a tile file appears only once complete (written
    under another name, then renamed), so a cancelled run leaves complete files only."""

    def __init__(self, kind, n, tasks, epsilon=None):
        self.kind = kind
        self.n = n
        self.tasks = tasks
        self.epsilon = epsilon
        self.futures = None

    def run(self, compute):
        return self.result() if compute else self

    def submit(self, client=None):
        """Starts the tasks on ``client`` (default: the current ``distributed`` client) and
        returns their futures, one per tile."""
        if self.futures is None:
            if client is None:
                import distributed

                client = distributed.get_client()
            self.futures = client.compute(self.tasks)
        return self.futures

    def cancel(self):
        """Cancels the submitted tiles not yet finished (nothing when not submitted)."""
        if self.futures:
            self.futures[0].client.cancel(self.futures)

    def result(self):
        """The :class:`TileResult`: waits for the submitted futures (raising
        ``CancelledError`` when cancelled), or runs the tasks on the active scheduler."""
        if self.futures is not None:
            parts = self.futures[0].client.gather(self.futures) if self.futures else []
        else:
            parts = dask.compute(*self.tasks)
        r = TileResult(self.kind, self.n, list(parts))
        r.epsilon = self.epsilon
        return r


class TileResult:
    """The per-tile result files of one computation (``parts``: one dict per tile with its
    ``path``, ``rows`` and ``halo``) and their assembly in caller order."""

    def __init__(self, kind, n, parts):
        self.kind = kind
        self.n = n
        self.parts = parts
        self.epsilon = None

    @property
    def halos(self):
        return [p["halo"] for p in self.parts]

    @property
    def paths(self):
        return [p["path"] for p in self.parts]

    def assemble(self):
        """The result in caller order, in memory: an :class:`AssembledTable` for tables, a dict
        of arrays otherwise (as the one-machine call returns them)."""
        if self.kind == "table":
            return self._table()
        out = {}
        for p in self.parts:
            with np.load(p["path"]) as z:
                idx = z["idx"]
                for key in z.files:
                    if key == "idx":
                        continue
                    v = z[key]
                    if key not in out:
                        out[key] = np.empty((self.n,) + v.shape[1:], v.dtype)
                    out[key][idx] = v
        return out

    def _table(self):
        lens = np.zeros(self.n, np.uint64)
        loaded = []
        for p in self.parts:
            z = np.load(p["path"])
            lens[z["idx"]] = np.diff(z["offsets"])
            loaded.append(z)
        offsets = np.concatenate([[0], np.cumsum(lens)]).astype(np.uint64)
        total = int(offsets[-1])
        indices = np.empty(total, np.uint32)
        sq = None
        for z in loaded:
            idx, loff = z["idx"], z["offsets"].astype(np.int64)
            d2 = z["sq_dists"]
            if sq is None:
                sq = np.empty(total, d2.dtype)
            rl = np.diff(loff)
            dest = np.repeat(offsets[idx].astype(np.int64) - loff[:-1], rl) + np.arange(loff[-1])
            indices[dest] = z["indices"]
            sq[dest] = d2
            z.close()
        if sq is None:
            sq = np.empty(0, np.float64)
        return AssembledTable(offsets, indices, sq)


class KeptResult(TileResult):
    """What a filter over the tiles keeps: per tile its owned indices and their mean
    distances (``parts``) and the ``threshold`` they are held to."""

    def __init__(self, n, parts, threshold):
        super().__init__("kept", n, parts)
        self.threshold = threshold

    def _each(self, keep):
        out = []
        for p in self.parts:
            with np.load(p["path"]) as z:
                idx, d = z["idx"], z["d"]
                out.append(idx[(d <= self.threshold) == keep])
        return np.sort(np.concatenate(out)) if out else np.empty(0, np.int64)

    def assemble(self):
        """The kept caller indices, ascending (uint32, as the one-machine filter returns)."""
        return self._each(True).astype(np.uint32)

    def removed(self):
        """The caller indices not kept, ascending."""
        return self._each(False).astype(np.int64)


class VoxelResult(TileResult):
    """The voxels of :meth:`TiledCloud.voxel_grid`, per tile (``parts``: ``path``, ``voxels``)."""

    def __init__(self, cloud, parts, out):
        super().__init__("voxels", sum(p["voxels"] for p in parts), parts)
        self._cloud = cloud
        self._out = out

    def assemble(self):
        """The dict ``nbhd.voxel_grid(points, ...)`` returns, in memory: ``centroids``,
        ``nearest``, ``offsets``, ``members``, ``cells``, in ascending linear voxel index."""
        loaded = [dict(np.load(p["path"])) for p in self.parts]
        key = np.concatenate([np.load(p["path"] + ".key.npy") for p in self.parts])
        order = np.argsort(key, kind="stable")
        counts = np.concatenate([z["counts"] for z in loaded])
        starts = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
        members = np.concatenate([z["members"] for z in loaded])
        runs = [members[starts[v]:starts[v + 1]] for v in order]
        return {
            "centroids": np.concatenate([z["centroids"] for z in loaded])[order],
            "nearest": np.concatenate([z["nearest"] for z in loaded])[order].astype(np.uint32),
            "offsets": np.concatenate([[0], np.cumsum(counts[order])]).astype(np.uint64),
            "members": (np.concatenate(runs) if runs else members).astype(np.uint32),
            "cells": np.concatenate([z["cells"] for z in loaded])[order],
        }

    def cloud(self, store=None, buckets=None):
        """The centroids as a new :class:`TiledCloud` (default store: a folder beside the
        cloud's) whose caller order is the voxels' — ``assemble()["centroids"]``'s — without
        gathering them: the voxels' ranks come from a sort over ``buckets`` ranges of keys
        (default: one per tile), cut at quantiles of the tiles' key samples, one task each,
        then one task per tile writes its piece."""
        cloud = self._cloud
        if store is None:
            store = cloud._out(None, "voxel-cloud")
        os.makedirs(store, exist_ok=True)
        paths = [p["path"] for p in self.parts]
        sample = np.sort(np.concatenate([np.asarray(p["sample"], np.uint64)
                                         for p in self.parts]))
        b = max(1, min(buckets or len(paths), len(sample)))
        cuts = [int(c) for c in np.unique(sample[(np.arange(1, b) * len(sample)) // b])]
        bounds = [0] + cuts + [2**64]
        starts = self._starts(cuts)
        ranks = [os.path.join(self._out, f"bucket_{i:06d}") for i in range(len(bounds) - 1)]
        dask.compute(*[
            dask.delayed(_tiles.voxel_ranks, pure=False)(paths, bounds[i], bounds[i + 1],
                                                         starts[i], ranks[i])
            for i in range(len(ranks))])
        done = dask.compute(*[
            dask.delayed(_tiles.voxel_piece, pure=False)(paths[t], t, ranks, store)
            for t in range(len(paths))])
        return _cloud_of_pieces(done, self.n, cloud.spec.dtype, store, "voxels")

    def _starts(self, cuts):
        """The number of voxels below each bucket's first key: each tile's keys counted below
        every cut (its key file mapped, not read)."""
        below = np.zeros(len(cuts), np.int64)
        for p in self.parts:
            k = np.load(p["path"] + ".key.npy", mmap_mode="r")
            below += np.searchsorted(k, np.asarray(cuts, np.uint64))
        return [0] + below.tolist()


class RobustResult(TileResult):
    """The result files of :meth:`TiledCloud.smooth_robust` and the run's figures
    (``report``); :meth:`assemble` gives the dict ``nbhd.smooth_robust`` returns."""

    def __init__(self, spec, parts, report):
        super().__init__("arrays", spec.n, parts)
        self.holes = spec.holes
        self.report = report
        self.epsilon = report["epsilon"]

    def assemble(self):
        import nbhd

        arrays = super().assemble()
        out = dict(self.report)
        if self.holes:
            holes = [np.load(h) for h in self.holes]
            idx = np.concatenate([h["idx"] for h in holes])
            arrays["points"][idx] = np.concatenate([h["pts"] for h in holes])
            arrays["normals"][idx] = np.nan
            if "outputs.normals" in arrays:
                for key, v in nbhd._nbhd._skipped_outputs(len(idx)).items():
                    arrays["outputs." + key][idx] = v
        out["points"] = arrays.pop("points")
        out["normals"] = arrays.pop("normals")
        out["outputs"] = {k[len("outputs."):]: v for k, v in arrays.items()} or None
        return out
