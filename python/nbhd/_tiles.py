"""The work of one tile (python/DASK.md): gather the tile's points and its halo from the tile
store, run nbhd on them, keep the rows of the owned points. Plain numpy and nbhd, no Dask: every
function here runs inside one Dask task (nbhd/dask.py builds the task graph).

The tile store is a directory of ``.npy`` pieces. A piece holds points of one tile in ascending
caller (global) index: ``pts`` (m, 3) float32/float64 and either ``idx`` (m,) int64 (a Dask
array's chunk sorted into grid tiles) or a ``start`` (a file: the caller's rows
``start .. start+m``). A tile is its pieces plus the tight box ``(lo, hi)`` of its points; it
*owns* them. Everything a task needs travels as plain lists
and dicts (:class:`Spec`), so tasks run on any worker that sees the store's directory.
"""

from __future__ import annotations

import os
import pickle
from dataclasses import dataclass, field

import numpy as np

from ._nbhd import KdTree


def piece_path(store: str, c: int, t: int) -> str:
    """The files of input chunk ``c``'s points in grid tile ``t`` (``.pts.npy``, ``.idx.npy``)."""
    return os.path.join(store, f"piece_c{c:06d}_t{t:06d}")


@dataclass
class Tile:
    """One tile: the tight box of its points, their count, and where they are — the input
    chunks that have points in it (grid tile ``grid_id`` of a Dask array), or one file's points
    (``file``, the caller's rows ``start .. start+count``). Kept small: every task reads the
    list of all tiles."""

    lo: list
    hi: list
    count: int
    grid_id: int = -1
    chunks: list = field(default_factory=list)
    file: str | None = None
    start: int = 0

    def pieces(self, store: str):
        """``(idx, pts)`` of each piece, memory-mapped, in ascending caller index."""
        if self.file is not None:
            pts = np.load(self.file, mmap_mode="r")
            yield np.arange(self.start, self.start + len(pts), dtype=np.int64), pts
            return
        for c in self.chunks:
            base = piece_path(store, int(c), self.grid_id)
            yield np.load(base + ".idx.npy", mmap_mode="r"), np.load(base + ".pts.npy", mmap_mode="r")


@dataclass
class Spec:
    """What every task reads: the cloud's size and type, the store, every tile's box."""

    n: int
    dtype: str
    tiles: list
    scale: float  # the largest |coordinate|: the rounding margins are relative to it
    store: str = ""
    # ``non_finite="skip"``: files of the rows with a NaN or infinite coordinate (``idx``,
    # ``pts``), which are in no tile; only the robust smoothing takes such a cloud
    holes: list = field(default_factory=list)


BATCH = 32_768  # queries answered at a time in a tile (memory, not results, depends on it)


def margin(width: float, spec: Spec, dtype=None) -> float:
    """``width`` widened by far more than the rounding of a distance in ``dtype``: a halo only
    ever needs to be a superset, so the margin costs a few points and keeps exactness."""
    eps = float(np.finfo(dtype or spec.dtype).eps)
    return width * (1 + 64 * eps) + 64 * eps * spec.scale


def owned(spec: Spec, t: int) -> np.ndarray:
    """The caller indices the tile owns, ascending."""
    parts = [np.asarray(idx) for idx, _ in spec.tiles[t].pieces(spec.store)]
    return np.concatenate(parts).astype(np.int64) if parts else np.empty(0, np.int64)


def gather(spec: Spec, t: int, width: float, dtype=None):
    """The points within ``width`` of tile ``t``'s box (closed), its own included: ``(idx,
    pts)`` in ascending caller index (so ties by index order as on one machine), ``pts`` in
    ``dtype`` (default: the cloud's)."""
    tile = spec.tiles[t]
    a = np.asarray(tile.lo, np.float64) - width
    b = np.asarray(tile.hi, np.float64) + width
    idx_parts, pts_parts = [], []
    for u in spec.tiles:
        if u.count == 0 or np.any(np.asarray(u.hi) < a) or np.any(np.asarray(u.lo) > b):
            continue
        for idx, pts in u.pieces(spec.store):
            inside = np.all((pts >= a) & (pts <= b), axis=1)
            sel = np.flatnonzero(inside)
            idx_parts.append(np.asarray(idx[sel], np.int64))
            pts_parts.append(np.asarray(pts[sel]))
    idx = np.concatenate(idx_parts)
    pts = np.concatenate(pts_parts)
    order = np.argsort(idx, kind="stable")
    pts = pts[order]
    if dtype is not None:
        pts = pts.astype(dtype)
    return idx[order], np.ascontiguousarray(pts)


def _drop_self(glob, lens, own):
    """CSR rows (``glob`` caller indices, ``lens`` row lengths) of the queries ``own``: each
    query's own entry removed, or, when it is not in its row (more than the row's length of
    exact copies with smaller indices), the row's last entry. Returns the kept mask."""
    m = len(lens)
    row_of = np.repeat(np.arange(m), lens)
    is_own = glob == own[row_of]
    has_own = np.zeros(m, bool)
    has_own[row_of[is_own]] = True
    drop = is_own.copy()
    ends = np.cumsum(lens) - 1
    last = np.flatnonzero(~has_own & (lens > 0))
    drop[ends[last]] = True
    return ~drop


def _write(path, **arrays):
    tmp = path + ".tmp.npz"
    np.savez(tmp, **arrays)
    os.replace(tmp, path)


def knn_rows(
    spec: Spec, t: int, k: int, width: float, dtype=None, tree_options=None, threads=0,
    batch=BATCH,
):
    """The ``k`` nearest *other* points of tile ``t``'s points, exact: the halo starts at
    ``width`` and doubles until every owned point's k-th distance is strictly below its
    distance to the halo's outer border (every point as near as the k-th, ties included, was
    searched). Returns ``(owned idx, indices (m, k'), sq_dists (m, k'), halo)``."""
    tree_options = tree_options or {}
    own = owned(spec, t)
    n = spec.n
    width_k = min(k, n - 1)
    dt = np.dtype(dtype or spec.dtype)
    feps = float(np.finfo(dt).eps)
    lo = np.asarray(spec.tiles[t].lo, np.float64)
    hi = np.asarray(spec.tiles[t].hi, np.float64)
    m = len(own)
    while True:
        idx, pts = gather(spec, t, width, dt)
        at = np.searchsorted(idx, own)
        kk = min(k + 1, len(idx))
        full = len(idx) == n
        if kk - 1 < width_k and not full:  # fewer than k other points in reach: grow
            width *= 2.0
            continue
        tree = KdTree(pts, threads=threads, **tree_options)
        out_i = np.empty((m, width_k), np.uint32)
        out_d = None
        exact = True
        # queries in batches: the temporaries stay small beside the tile's own arrays
        for s in range(0, m, batch):
            e = min(s + batch, m)
            q = pts[at[s:e]]
            local, d2 = tree.knn(q, kk, threads=threads)
            glob = idx[local.astype(np.int64)]
            keep = _drop_self(glob.reshape(-1), np.full(e - s, kk), own[s:e]).reshape(e - s, kk)
            glob = glob[keep].reshape(e - s, kk - 1)[:, :width_k]
            d2 = d2[keep].reshape(e - s, kk - 1)[:, :width_k]
            if out_d is None:
                out_d = np.empty((m, width_k), d2.dtype)
            out_i[s:e] = glob
            out_d[s:e] = d2
            if full:
                continue
            qd = q.astype(np.float64)
            border = np.minimum(qd - (lo - width), (hi + width) - qd).min(axis=1)
            kth = np.sqrt(d2[:, -1].astype(np.float64)) if width_k else np.zeros(e - s)
            # strictly inside, with a margin far above the rounding of d2 and of the border
            if not np.all(kth * (1 + 64 * feps) + 64 * feps * spec.scale < border):
                exact = False
                break
        if exact:
            if out_d is None:
                out_d = np.empty((0, width_k), dt)
            return own, out_i, out_d, width
        width *= 2.0


def knn_tile(
    spec: Spec, t: int, k: int, width: float, out: str, tree_options=None, threads=0, batch=BATCH
):
    """Task: the tile's rows of ``KdTree(points).neighborhoods(k=k)`` written to ``out``."""
    own, glob, d2, used = knn_rows(spec, t, k, width, None, tree_options, threads, batch)
    m, w = glob.shape
    offsets = np.arange(m + 1, dtype=np.uint64) * np.uint64(w)
    _write(out, idx=own, offsets=offsets, indices=glob.reshape(-1), sq_dists=d2.reshape(-1))
    del glob, d2
    return {"tile": t, "path": out, "rows": m, "halo": used}


def radius_tile(
    spec: Spec, t: int, k, radius: float, out: str, tree_options=None, threads=0, batch=BATCH
):
    """Task: the tile's rows of ``KdTree(points).neighborhoods(radius=radius)`` (``k`` None)
    or ``(k=k, radius=radius)`` (the ε-k-neighbourhood), written to ``out``. Halo: ε, known in
    advance (the radius is inclusive, the halo box closed, widened by a rounding margin)."""
    tree_options = tree_options or {}
    own = owned(spec, t)
    halo = margin(radius, spec)
    idx, pts = gather(spec, t, halo)
    at = np.searchsorted(idx, own)
    tree = KdTree(pts, threads=threads, **tree_options)
    lens_all, ind_parts, sq_parts = [], [], []
    for s in range(0, len(own), batch):
        e = min(s + batch, len(own))
        q = pts[at[s:e]]
        if k is None:
            table = tree.radius(q, radius, threads=threads)
        else:
            table = tree.knn_radius(q, k + 1, radius, threads=threads)
        lens = np.diff(table.offsets).astype(np.int64)
        glob = idx[table.indices.astype(np.int64)]
        # rows of k + 1 lose their own entry or their last: at most k remain, as on one machine
        keep = _drop_self(glob, lens, own[s:e])
        row_of = np.repeat(np.arange(e - s), lens)
        lens_all.append(np.bincount(row_of[keep], minlength=e - s).astype(np.uint64))
        ind_parts.append(glob[keep].astype(np.uint32))
        sq_parts.append(table.sq_dists[keep])
    offsets = np.concatenate([[0], np.cumsum(np.concatenate(lens_all))]).astype(np.uint64)
    _write(
        out,
        idx=own,
        offsets=offsets,
        indices=np.concatenate(ind_parts),
        sq_dists=np.concatenate(sq_parts),
    )
    return {"tile": t, "path": out, "rows": len(own), "halo": halo}


def nearest_tile(spec: Spec, t: int, width: float, out: str, threads=0):
    """Task: every owned point's squared distance to its nearest other point, computed in f64
    as the smoothing's spacing estimate does (the library converts to f64 first). Written as
    two ``.npy`` files (``out`` + ``.idx.npy`` / ``.nearest.npy``) that the summing tasks map
    and slice without reading them whole."""
    own, _, d2, used = knn_rows(spec, t, 1, width, dtype=np.float64, threads=threads)
    np.save(out + ".idx.npy", own)
    np.save(out + ".nearest.npy", d2[:, 0] if d2.shape[1] else np.zeros(len(own)))
    return {"tile": t, "path": out, "rows": len(own), "halo": used}


def geometry_tile(spec: Spec, t: int, what: str, halo: float, out: str, kwargs: dict):
    """Task: ``nbhd.normals``/``curvatures``/``smooth`` on the tile plus a halo of ``halo``
    (lengths already absolute), the owned points' results written to ``out``."""
    import nbhd

    own = owned(spec, t)
    idx, pts = gather(spec, t, margin(halo, spec, np.float64), np.float64)
    at = np.searchsorted(idx, own)
    arrays = {"idx": own}
    if what == "normals":
        normals, curvature, flags = nbhd.normals(pts, **kwargs)
        arrays.update(normals=normals[at], surface_variation=curvature[at], flags=flags[at])
    elif what == "curvatures":
        r = nbhd.curvatures(pts, **kwargs)
        for key, v in r.items():
            if isinstance(v, np.ndarray):
                arrays[key] = v[at]
    elif what == "smooth":
        r = nbhd.smooth(pts, **kwargs)
        arrays["points"] = r["points"][at]
        for key, v in (r["outputs"] or {}).items():
            arrays["outputs." + key] = v[at]
    else:  # pragma: no cover - the callers name one of the three
        raise ValueError(what)
    _write(out, **arrays)
    return {"tile": t, "path": out, "rows": len(own), "halo": halo, "points": len(idx)}


def outlier_tile(
    spec: Spec, t: int, k: int, width: float, out: str, tree_options=None, threads=0,
    batch=BATCH,
):
    """Task: the first pass of the statistical outlier filter over tile ``t``: every owned
    point's mean distance to its ``k`` nearest other points (exact kNN halos,
    ``nbhd.mean_distances``), written to ``out`` with the owned indices; returns the tile's
    exact sum of them (``nbhd.ExactSum``), which the client merges into the mean."""
    import nbhd

    own, _, d2, used = knn_rows(spec, t, k, width, None, tree_options, threads, batch)
    d = nbhd.mean_distances(d2) if len(own) else np.empty(0)
    _write(out, idx=own, d=d)
    total = nbhd.ExactSum()
    total.add(d)
    return {"tile": t, "path": out, "rows": len(own), "halo": used, "sum": total}


def outlier_spread(path: str, mean: float):
    """Task: the tile's exact ``Σ (d_i − mean)²`` over the mean distances ``outlier_tile``
    wrote (``nbhd.squared_deviation_sum``)."""
    import nbhd

    with np.load(path) as z:
        return nbhd.squared_deviation_sum(z["d"], mean)


def select_tile(spec: Spec, t: int, removed, kept_path: str, threshold: float, store: str):
    """Task: tile ``t``'s points whose mean distance (``kept_path``, from ``outlier_tile``) is
    at most ``threshold``, renumbered as rows of the kept points (an index less the number of
    ``removed`` indices below it) and written as the one piece of tile ``t`` in ``store``.
    Returns ``(t, count, lo, hi)``."""
    pts = np.concatenate([np.asarray(p) for _, p in spec.tiles[t].pieces(spec.store)])
    with np.load(kept_path) as z:
        idx, keep = z["idx"], z["d"] <= threshold
    idx, pts = idx[keep], pts[keep]
    return write_piece(store, t, idx - np.searchsorted(removed, idx), pts)


def write_piece(store: str, t: int, idx, pts):
    """Writes ``(idx, pts)`` (ascending caller indices) as the one piece of tile ``t`` of a new
    store (chunk 0); returns ``(t, count, lo, hi)``, which :func:`nbhd.dask` makes a tile of."""
    base = piece_path(store, 0, t)
    np.save(base + ".pts.npy", pts)
    np.save(base + ".idx.npy", idx)
    if len(pts) == 0:
        return t, 0, [0.0] * 3, [0.0] * 3
    return t, len(pts), pts.min(axis=0).tolist(), pts.max(axis=0).tolist()


def voxel_tile(spec: Spec, t: int, leaf, min_points: int, low, mul, out: str, threads=0):
    """Task: the voxels tile ``t`` owns — those whose smallest caller index is one of its
    points — computed by ``nbhd.voxel_grid`` on the tile plus a halo of one voxel edge (every
    point of such a voxel lies within an edge of that point, so the voxel is whole: the same
    members, summed in the same order, as on one machine). Written to ``out`` in ascending
    linear index of the whole cloud's grid (``low``, ``mul``: its lowest voxel numbers and
    multipliers): ``centroids``, ``nearest``, ``counts``, ``members`` (caller indices),
    ``cells``, and the keys in ``out + ".key.npy"`` (mapped by the ranks' tasks). Returns the counts and a sample of the keys (for the ranks)."""
    import nbhd

    own = owned(spec, t)
    idx, pts = gather(spec, t, margin(max(leaf), spec))
    g = nbhd.voxel_grid(pts, leaf, min_points_per_voxel=min_points, threads=threads)
    off = g["offsets"].astype(np.int64)
    first = idx[g["members"][off[:-1]].astype(np.int64)]
    at = np.minimum(np.searchsorted(own, first), len(own) - 1)
    mine = own[at] == first
    counts = np.diff(off)[mine]
    members = idx[g["members"].astype(np.int64)][np.repeat(mine, np.diff(off))]
    cells = g["cells"][mine]
    # the grid's order is the last coordinate first, as the whole cloud's: keys ascend
    key = ((cells - np.asarray(low, np.int64)).astype(np.uint64)
           * np.asarray(mul, np.uint64)).sum(axis=1, dtype=np.uint64)
    centroids = g["centroids"][mine]
    _write(out, centroids=centroids, nearest=idx[g["nearest"][mine].astype(np.int64)],
           counts=counts.astype(np.uint64), members=members.astype(np.uint32), cells=cells)
    np.save(out + ".key.npy", key)
    step = max(1, len(key) // 64)
    return {"tile": t, "path": out, "rows": len(own), "halo": max(leaf), "voxels": len(key),
            "sample": key[::step].tolist()}


def voxel_ranks(paths, lo_key, hi_key, start: int, out: str):
    """Task: the ranks in the whole cloud of the voxels whose keys lie in ``[lo_key, hi_key)``
    (``start`` voxels have smaller keys): each tile's slice of them, in key order, written
    one after the other in tile order to ``out`` (``.ranks.npy``, with ``.toff.npy`` the
    slices' offsets)."""
    keys = []
    for p in paths:
        k = np.load(p + ".key.npy", mmap_mode="r")
        a, b = np.searchsorted(k, [lo_key, hi_key])
        keys.append(np.asarray(k[a:b]))
    lens = [len(k) for k in keys]
    keys = np.concatenate(keys)
    order = np.argsort(keys, kind="stable")
    rank = np.empty(len(keys), np.int64)
    rank[order] = start + np.arange(len(keys))
    np.save(out + ".ranks.npy", rank)  # tile by tile: each tile's slice in its key order
    np.save(out + ".toff.npy", np.concatenate([[0], np.cumsum(lens)]))


def voxel_piece(path: str, t: int, bucket_paths, store: str):
    """Task: tile ``t``'s voxels as one piece of a new store: their centroids, with their
    ranks (from every bucket, in key order) as caller indices. Returns ``(t, count, lo, hi)``."""
    with np.load(path) as z:
        centroids = z["centroids"]
    parts = []
    for b in bucket_paths:
        toff = np.load(b + ".toff.npy")
        parts.append(np.load(b + ".ranks.npy", mmap_mode="r")[toff[t]:toff[t + 1]])
    ranks = np.concatenate(parts) if parts else np.empty(0, np.int64)
    return write_piece(store, t, ranks, centroids)


def nearest_of_rows(parts, a: int, b: int):
    """The nearest squared distances the tiles' ``parts`` wrote for the caller rows ``a .. b``
    (each row from the one tile that owns it), NaN for a row no tile wrote."""
    x = np.full(b - a, np.nan)
    for p in parts:
        idx = np.load(p["path"] + ".idx.npy", mmap_mode="r")
        i, j = np.searchsorted(idx, [a, b])
        if j > i:
            near = np.load(p["path"] + ".nearest.npy", mmap_mode="r")
            x[np.asarray(idx[i:j]) - a] = near[i:j]
    return x


def partial_sum(parts, a: int, b: int, carry: float) -> float:
    """The sum ``carry + x_a + ... + x_{b-1}`` of the square roots of the nearest squared
    distances, added one by one in caller order as the library's spacing estimate adds them
    (``np.add.accumulate`` is a sequential loop: the same roundings)."""
    x = np.sqrt(nearest_of_rows(parts, a, b))
    acc = np.add.accumulate(np.concatenate([[carry], x]))
    return float(acc[-1])


# --- the robust smoothing: one task per tile and round, holding nothing between rounds ------


def gather_robust(spec: Spec, t: int, width: float):
    """Tile ``t`` with a halo of ``width`` for the robust smoothing: ``(idx, pts, owner, at,
    lo, hi)`` — the points inside the closed box (tile box ± width) in ascending caller index,
    as float64; for each, the tile that owns it and its position in that tile's owned order
    (where that tile writes its positions); and the region the library checks the rows
    against: the box, unbounded on the sides where no point of the cloud lies beyond it."""
    tile = spec.tiles[t]
    a = np.asarray(tile.lo, np.float64) - width
    b = np.asarray(tile.hi, np.float64) + width
    cloud_lo = np.min([u.lo for u in spec.tiles], axis=0)
    cloud_hi = np.max([u.hi for u in spec.tiles], axis=0)
    lo = np.where(a <= cloud_lo, -np.inf, a)
    hi = np.where(b >= cloud_hi, np.inf, b)
    idx_p, pts_p, own_p, at_p = [], [], [], []
    for u_i, u in enumerate(spec.tiles):
        if np.any(np.asarray(u.hi) < a) or np.any(np.asarray(u.lo) > b):
            continue
        base = 0
        for idx, pts in u.pieces(spec.store):
            sel = np.flatnonzero(np.all((pts >= a) & (pts <= b), axis=1))
            idx_p.append(np.asarray(idx[sel], np.int64))
            pts_p.append(np.asarray(pts[sel], np.float64))
            own_p.append(np.full(len(sel), u_i, np.int64))
            at_p.append(sel.astype(np.int64) + base)
            base += len(idx)
    idx = np.concatenate(idx_p)
    order = np.argsort(idx, kind="stable")
    pts = np.ascontiguousarray(np.concatenate(pts_p)[order])
    owner = np.concatenate(own_p)[order]
    at = np.concatenate(at_p)[order]
    return idx[order], pts, owner, at, lo.tolist(), hi.tolist()


def gathered_robust(spec: Spec, t: int, width: float, out: str):
    """:func:`gather_robust` of tile ``t`` with a halo of ``width``, kept in the tile's rows
    directory by the first round that gathers it and read from there by the later rounds
    (a read of the tile's own points in place of a pass over its neighbours' pieces); a
    wider halo gathers and keeps anew."""
    path = os.path.join(rows_dir(out, t), "gather.pickle")
    try:
        with open(path, "rb") as f:
            kept = pickle.load(f)
        if kept[0] == width:
            return kept[1:]
    except (OSError, EOFError, pickle.UnpicklingError, IndexError, TypeError):
        pass  # absent or torn: gathered again below
    idx, pts, owner, at, lo, hi = gather_robust(spec, t, width)
    os.makedirs(os.path.dirname(path), exist_ok=True)
    tmp = path + ".tmp"
    with open(tmp, "wb") as f:
        pickle.dump((width, idx, pts, owner, at, lo, hi), f, protocol=5)
    os.replace(tmp, path)
    return idx, pts, owner, at, lo, hi


def generation_path(out: str, g: int, t: int, what: str = "points") -> str:
    """Where tile ``t`` keeps its owned points' positions after ``g`` steps (``what``
    ``"points"``), or the normals of the step into them (``"normals"``), in owned order."""
    return os.path.join(out, f"gen_{g:04d}", f"{what}_{t:06d}.npy")


def rows_dir(out: str, t: int) -> str:
    """Where tile ``t`` keeps the rows it searched (``nbhd.RobustTile.keep_rows_in``): every
    later round of the tile reads them instead of searching again; a wider halo's rows
    replace them."""
    return os.path.join(out, "rows", f"tile_{t:06d}")


def values_path(out: str, t: int) -> str:
    """Where tile ``t`` keeps its owned values of the last round (for the exact median)."""
    return os.path.join(out, "values", f"tile_{t:06d}.npy")


def _save(path: str, array) -> None:
    """``array`` written to ``path`` complete or not at all (a temporary name, then renamed)."""
    os.makedirs(os.path.dirname(path), exist_ok=True)
    tmp = path + ".tmp.npy"
    np.save(tmp, array)
    os.replace(tmp, path)


def _validity(valid: np.ndarray) -> dict:
    """Whether every owned point's value of a round is the cloud's, and how many are not."""
    return {"valid": bool(valid.all()), "invalid": int((~valid).sum())}


class RobustGather:
    """Tile ``t`` of a robust run gathered with a halo of ``width`` into an
    ``nbhd.RobustTile``, given what the round it is made for reads besides the input: the
    positions of the round's generation, those its rows shrank on, and before the finish the
    last step's normals, each read from the owners' generation files; ``threads`` its worker
    threads (``nbhd.RobustTile``'s). A task makes one per round and keeps nothing afterwards,
    so a worker holds one tile's working set at a time, however large the cloud."""

    def __init__(self, spec: Spec, t: int, width: float, options, threads: int, out: str,
                 round=None):
        import nbhd

        idx, pts, self.owner, self.at, lo, hi = gathered_robust(spec, t, width, out)
        self.t, self.out, self.width, self.gathered = t, out, width, len(idx)
        mine = self.owner == t
        self.own = idx[mine]
        self.tile = nbhd.RobustTile(pts, mine, lo, hi, options, threads=threads)
        self.tile.keep_rows_in(rows_dir(out, t))
        if round is None:
            return
        g = round["generation"]
        if g:
            self.tile.set_current(g, self._of_owners(g))
        at = round.get("shrunk_at")
        if round.get("rows") == "shrunk" and at != g:
            self.tile.set_shrink(at, self._of_owners(at) if at else pts)
        if round["kind"] == "finish" and g:
            self.tile.set_normals(self._of_owners(g, "normals"))

    def _of_owners(self, g: int, what: str = "points"):
        """Generation ``g``'s ``what`` of every gathered point, from their owners' files."""
        values = np.empty((len(self.owner), 3), np.float64)
        for u in np.flatnonzero(np.bincount(self.owner)):
            sel = self.owner == u
            path = generation_path(self.out, g, int(u), what)
            values[sel] = np.load(path, mmap_mode="r")[self.at[sel]]
        return values


def robust_nearest(spec: Spec, t: int, width: float, options, threads: int, out: str) -> dict:
    """Task: the owned points' nearest squared distances, written for the spacing's sums."""
    tile = RobustGather(spec, t, width, options, threads, out)
    near, valid = tile.tile.nearest()
    base = os.path.join(out, f"nearest_{t:06d}")
    np.save(base + ".idx.npy", tile.own)
    np.save(base + ".nearest.npy", near)
    return {"tile": t, "path": base, "halo": width, "rows": len(tile.own), **_validity(valid)}


def robust_round(spec: Spec, t: int, width: float, options, threads: int, out: str,
                 round) -> dict:
    """Task: one round of tile ``t``. Its owned values go to its values file, a step's
    positions and normals to the next generation's files; returns the part's summary with
    the first digit counts of its values."""
    import nbhd

    tile = RobustGather(spec, t, width, options, threads, out, round)
    part = tile.tile.round(round)
    values = part["values"]
    _save(values_path(out, t), values)
    if round["kind"] == "step":
        g = round["generation"] + 1
        _save(generation_path(out, g, t), tile.tile.owned_points())
        _save(generation_path(out, g, t, "normals"), tile.tile.owned_normals())
    return {
        "tile": t, **_validity(part["valid"]), "rows": len(tile.own),
        "halo": width, "count": part["count"], "max_len": part["max_len"],
        "min_narrow": part["min_narrow"], "moved_sq": part["moved_sq"].to_bytes(),
        "n_values": len(values),
        "counts": nbhd.RankSearch(0).digit_counts(values).to_bytes(),
    }


def robust_counts(out: str, t: int, search: bytes) -> bytes:
    """Task: tile ``t``'s digit counts of its last values for the search state ``search``."""
    import nbhd

    values = np.load(values_path(out, t), mmap_mode="r")
    return nbhd.RankSearch.from_bytes(search).digit_counts(values).to_bytes()


def robust_matching(out: str, t: int, search: bytes):
    """Task: tile ``t``'s last values in the bucket of the search state ``search``."""
    import nbhd

    values = np.load(values_path(out, t), mmap_mode="r")
    return nbhd.RankSearch.from_bytes(search).matching_values(values)


def robust_finish(spec: Spec, t: int, width: float, options, threads: int, out: str, round):
    """Task: the last round, the owned points' points, normals and outputs written to
    ``out/tile_<t>.npz``."""
    path = os.path.join(out, f"tile_{t:06d}.npz")
    tile = RobustGather(spec, t, width, options, threads, out, round)
    r = tile.tile.finish(round)
    arrays = {"idx": tile.own, "points": r["points"], "normals": r["normals"]}
    for key, v in (r["outputs"] or {}).items():
        arrays["outputs." + key] = v
    _write(path, **arrays)
    return {"tile": t, "path": path, "rows": len(tile.own), "halo": width,
            "points": tile.gathered, **_validity(r["valid"])}


def partial_sum_finite(parts, a: int, b: int, carry):
    """:func:`partial_sum` over a cloud with holes: ``carry = (sum, count)`` continued with the
    square roots of the nearest squared distances of the caller rows ``a .. b`` that have one
    (holes and points without a neighbour are NaN or absent), added one by one in caller
    order as the library's spacing estimate adds them."""
    x = nearest_of_rows(parts, a, b)
    x = np.sqrt(x[~np.isnan(x)])
    acc = np.add.accumulate(np.concatenate([[carry[0]], x]))
    return float(acc[-1]), carry[1] + len(x)
