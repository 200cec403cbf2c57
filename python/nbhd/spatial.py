"""scipy.spatial's k-d tree classes on nbhd's tree: switch with one import.

    from nbhd.spatial import cKDTree, KDTree   # instead of: from scipy.spatial import ...

:class:`cKDTree` and :class:`KDTree` take scipy's constructor arguments, keep scipy's
attributes and answer every method with scipy's arguments, return types and shapes
(``scipy.spatial.cKDTree`` 1.17). This module only presents: every neighbour is found by
:class:`nbhd.KdTree` (Rust, the GIL released), and this file converts arguments and results —
squared or p-th power keys to plain distances, nbhd's uint32 indices to ``intp``, rows to
scipy's lists, sets and sparse matrices. scipy's own test suite
(``scipy/spatial/tests/test_kdtree.py``) runs on these classes in nbhd's tests
(``python/tests/test_scipy_suite.py``).

What differs from scipy, on purpose:

- **The tree itself.** nbhd splits with ``left ≤ split ≤ right`` (scipy: ``< split`` left), and
  it splits identical points by index like any others, so every leaf holds at most
  ``leafsize`` points (scipy makes a node of identical points one leaf of any size). The node
  objects (:attr:`cKDTree.tree`, :class:`cKDTreeNode`) describe nbhd's tree as it is; a test
  that pins scipy's layout of identical points (``test_kdtree_duplicated_inputs``) fails.
  ``balanced_tree=True`` builds with nbhd's "spread-median" pivot (the median of the widest
  axis, as scipy), ``False`` with "sliding-midpoint"; ``compact_nodes`` is accepted and has no
  effect (nbhd keeps no node boxes). The answers do not depend on either flag.
- **Rows are always in ascending index order**: ``query_ball_point``'s rows for any
  ``return_sorted`` (so a batch and single queries agree), ``query_ball_tree``'s rows as scipy.
- **Complex input raises TypeError** in both classes (scipy's ``cKDTree`` casts it to real
  with a warning).
- **A negative radius raises** ``NbhdValueError`` (a ``ValueError``) in ``query_ball_point``,
  ``query_ball_tree``, ``query_pairs`` and ``sparse_distance_matrix``; ``count_neighbors``
  counts nothing for it, as scipy.
- ``copy_data``: nbhd's tree always holds its own copy of the points, so later changes of the
  caller's array never change an answer; ``data`` is the caller's array itself when it is
  already C-contiguous float64 and ``copy_data=False``, as in scipy.
"""

from __future__ import annotations

import importlib
import operator
import os
from typing import Any, Literal, Optional, Sequence, Union

import numpy as np
import numpy.typing as npt

from ._nbhd import MAX_THREADS, KdTree, Table

__all__ = ["cKDTree", "KDTree", "cKDTreeNode"]

ArrayLike = npt.ArrayLike


def _threads(workers: Optional[int]) -> int:
    """scipy's ``workers``: None is one thread, -1 one per CPU (``os.cpu_count()`` at call
    time), n ≥ 1 n threads (at most nbhd's ``MAX_THREADS``); anything else raises."""
    if workers is None:
        return 1
    workers = operator.index(workers)
    if workers == -1:
        cpus = os.cpu_count()
        if cpus is None:
            raise NotImplementedError(
                "Cannot determine the number of cpus using os.cpu_count(), "
                "cannot use -1 for the number of workers"
            )
        return min(cpus, MAX_THREADS)
    if workers < 1:
        raise ValueError(f"Invalid number of workers {workers}, must be -1 or > 0")
    return min(workers, MAX_THREADS)


def _distances(keys: np.ndarray, p: float) -> np.ndarray:
    """Plain distances from nbhd's keys (``nbhd::Metric::distance_of``, the operations scipy
    applies to its own keys): the square root for p = 2, the keys themselves for p = 1 and ∞,
    the p-th root otherwise."""
    keys = np.asarray(keys, dtype=np.float64)
    if p == 2:
        out: np.ndarray = np.sqrt(keys)
    elif p == 1 or np.isinf(p):
        out = keys.copy()
    else:
        out = np.power(keys, 1.0 / p)
    return out


def _row_ids(table: Table) -> np.ndarray:
    """The row of every entry of ``table`` (intp)."""
    lengths = np.diff(table.offsets).astype(np.intp)
    return np.repeat(np.arange(len(lengths), dtype=np.intp), lengths)


def _rows_as_lists(offsets: np.ndarray, indices: np.ndarray) -> list[list[int]]:
    """Compressed rows as Python lists of ints (one conversion of all indices, then slices)."""
    flat = indices.tolist()
    starts = offsets.tolist()
    return [flat[a:b] for a, b in zip(starts[:-1], starts[1:])]


class cKDTreeNode:
    """One node of nbhd's tree, as scipy's ``cKDTreeNode`` describes one of scipy's.

    ``level`` (edges from the root), ``split_dim`` (-1 for a leaf), ``split`` (the left
    subtree's points have coordinate ≤ ``split`` in ``split_dim``, the right subtree's ≥), the
    number of points ``children``, their tree positions ``start_idx``..``end_idx``, the
    children ``lesser`` and ``greater`` (None for a leaf), and the points themselves as
    ``indices`` (rows of the tree's ``data``) and ``data_points``. ``cKDTreeNode()`` is an empty
    leaf that belongs to no tree.
    """

    def __init__(self) -> None:
        self._tree: Optional[cKDTree] = None
        self._at = 0
        self._lesser: Optional[cKDTreeNode] = None
        self._greater: Optional[cKDTreeNode] = None

    @classmethod
    def _of(cls, tree: cKDTree, at: int) -> cKDTreeNode:
        node = cls()
        node._tree = tree
        node._at = at
        return node

    def _column(self, name: str, default: Any) -> Any:
        if self._tree is None:
            return default
        return self._tree._nodes[name][self._at].item()

    @property
    def level(self) -> int:
        return int(self._column("level", 0))

    @property
    def split_dim(self) -> int:
        return int(self._column("split_dim", -1))

    @property
    def split(self) -> float:
        return float(self._column("split", 0.0))

    @property
    def start_idx(self) -> int:
        return int(self._column("start", 0))

    @property
    def end_idx(self) -> int:
        return int(self._column("end", 0))

    @property
    def children(self) -> int:
        return self.end_idx - self.start_idx

    def _child(self, side: str) -> Optional[cKDTreeNode]:
        at = int(self._column(side, -1))
        if at < 0 or self._tree is None:
            return None
        return cKDTreeNode._of(self._tree, at)

    @property
    def lesser(self) -> Optional[cKDTreeNode]:
        if self._lesser is None:
            self._lesser = self._child("left")
        return self._lesser

    @property
    def greater(self) -> Optional[cKDTreeNode]:
        if self._greater is None:
            self._greater = self._child("right")
        return self._greater

    @property
    def indices(self) -> np.ndarray:
        if self._tree is None:
            return np.empty(0, dtype=np.intp)
        rows: np.ndarray = self._tree.indices[self.start_idx : self.end_idx]
        return rows

    @property
    def data_points(self) -> np.ndarray:
        if self._tree is None:
            return np.empty((0, 0))
        points: np.ndarray = self._tree.data[self.indices]
        return points


class cKDTree:
    """scipy's ``cKDTree`` on nbhd's tree (``scipy.spatial.cKDTree``'s arguments, attributes,
    methods and results; what differs is listed in this module's docstring).

    Attributes: ``data`` (n, m), ``n``, ``m``, ``leafsize``, ``maxes``, ``mins`` (the data's
    bounds; zeros for n = 0), ``indices`` (the caller's indices in tree order), ``size`` (nodes),
    ``boxsize`` (per axis, or None), ``tree`` (the root :class:`cKDTreeNode`).
    """

    def __init__(
        self,
        data: ArrayLike,
        leafsize: int = 16,
        compact_nodes: bool = True,
        copy_data: bool = False,
        balanced_tree: bool = True,
        boxsize: Union[None, float, Sequence[float], np.ndarray] = None,
    ) -> None:
        raw = np.asarray(data)
        if np.iscomplexobj(raw):
            raise TypeError(f"{type(self).__name__} does not work with complex data")
        points = np.array(raw, dtype=np.float64, order="C", copy=True if copy_data else None)
        if points.ndim != 2:
            raise ValueError(
                "data must be of shape (n, m), where there are n points of dimension m"
            )
        if not np.isfinite(points).all():
            raise ValueError("data must be finite, check for nan or inf values")
        leafsize = operator.index(leafsize)
        if leafsize < 1:
            raise ValueError("leafsize must be at least 1")
        self.data = points
        self.n, self.m = (int(s) for s in points.shape)
        self.leafsize = leafsize
        self._flags = (bool(compact_nodes), bool(balanced_tree))
        self.boxsize: Optional[np.ndarray] = None
        period = None
        if boxsize is not None:
            self.boxsize = np.array(np.broadcast_to(boxsize, (self.m,)), dtype=np.float64)
            if (self.boxsize > 0).any():
                # scipy: an axis of size ≤ 0 is not periodic; nbhd names an open axis 0
                period = np.where(self.boxsize > 0, self.boxsize, 0.0).tolist()
        pivot: Literal["spread-median", "sliding-midpoint"] = (
            "spread-median" if balanced_tree else "sliding-midpoint"
        )
        self._tree = KdTree(points, pivot=pivot, leaf_size=leafsize, boxsize=period)
        self.indices = self._tree.tree_order.astype(np.intp)
        if self.n:
            self.maxes = np.amax(points, axis=0)
            self.mins = np.amin(points, axis=0)
        else:
            self.maxes = np.zeros(self.m)
            self.mins = np.zeros(self.m)
        self._node_columns: Optional[dict[str, np.ndarray]] = None
        self._root: Optional[cKDTreeNode] = None

    def __reduce__(self) -> tuple[Any, ...]:
        # Rebuilt from the constructor's arguments: nbhd's build is deterministic, so the
        # unpickled tree has the same nodes and answers every query with the same bits; the
        # pickle holds the data once (not the data and the tree's own copy of it).
        compact, balanced = self._flags
        return (type(self), (self.data, self.leafsize, compact, False, balanced, self.boxsize))

    @property
    def size(self) -> int:
        """Number of nodes of the tree."""
        return int(self._tree.stats()["nodes"])

    @property
    def _nodes(self) -> dict[str, np.ndarray]:
        if self._node_columns is None:
            self._node_columns = {
                name: np.asarray(column) for name, column in self._tree.nodes().items()
            }
        return self._node_columns

    @property
    def tree(self) -> cKDTreeNode:
        """The root node of nbhd's tree (nodes are made as they are visited)."""
        if self._root is None:
            self._root = cKDTreeNode._of(self, 0)
        return self._root

    # ---- arguments --------------------------------------------------------------------

    def _queries(self, x: ArrayLike) -> tuple[np.ndarray, tuple[int, ...]]:
        """``x`` of shape (..., m) as an (N, m) C-contiguous float64 array and its leading
        shape."""
        raw = np.asarray(x)
        if np.iscomplexobj(raw):
            raise TypeError(f"{type(self).__name__} does not work with complex data")
        q = np.asarray(raw, dtype=np.float64)
        if q.ndim == 0 or q.shape[-1] != self.m:
            raise ValueError(
                f"x must consist of vectors of length {self.m} but has shape {np.shape(q)}"
            )
        if not np.isfinite(q).all():
            raise ValueError("'x' must be finite, check for nan or inf values")
        lead = tuple(int(s) for s in q.shape[:-1])
        return np.ascontiguousarray(q.reshape(-1, self.m)), lead

    def _other(self, other: Any, method: str) -> KdTree:
        if not isinstance(other, cKDTree):
            raise TypeError(f"{method}: other must be a cKDTree or KDTree of nbhd.spatial")
        if other.m != self.m:
            raise ValueError(f"Trees passed to {method} have different dimensionality")
        return other._tree

    # ---- k nearest ----------------------------------------------------------------------

    def query(
        self,
        x: ArrayLike,
        k: Union[int, Sequence[int]] = 1,
        eps: float = 0.0,
        p: float = 2.0,
        distance_upper_bound: float = np.inf,
        workers: Optional[int] = None,
    ) -> tuple[Any, Any]:
        """The k nearest neighbours of each point of ``x`` (shape (..., m)): ``(d, i)`` of shape
        ``x.shape[:-1] + (k,)`` (the last axis dropped for k = 1; Python scalars for one point
        and k = 1). ``k`` as a sequence selects those ranks (1-based). Missing neighbours are
        distance ``inf`` and index ``n``; only points at distance < ``distance_upper_bound``
        are returned. ``eps``: the i-th neighbour is within (1 + eps) of the true i-th."""
        if k is None:
            raise ValueError("k must be an integer or a sequence of integers")
        q, lead = self._queries(x)
        ranks = np.asarray(k)
        squeeze = ranks.ndim == 0 and int(ranks) == 1
        if ranks.ndim == 0:
            ranks = np.arange(1, int(ranks) + 1, dtype=np.intp)
        ranks = ranks.astype(np.intp).ravel()
        if ranks.size == 0 or ranks.min() < 1:
            raise ValueError("k must be at least 1")
        threads = _threads(workers)
        kmax = int(ranks.max())
        d, i = self._nearest(q, kmax, eps, p, distance_upper_bound, threads)
        if len(ranks) != kmax or (ranks != np.arange(1, kmax + 1)).any():
            d, i = d[:, ranks - 1], i[:, ranks - 1]
        d = d.reshape(lead + (len(ranks),))
        i = i.reshape(lead + (len(ranks),))
        if squeeze:
            d, i = d[..., 0], i[..., 0]
            if not lead:
                return float(d), int(i)
        return d, i

    def _nearest(
        self, q: np.ndarray, kmax: int, eps: float, p: float, bound: float, threads: int
    ) -> tuple[np.ndarray, np.ndarray]:
        """The kmax nearest of each row of q, padded with (inf, n): (N, kmax) arrays."""
        rows = len(q)
        if rows and self.n >= kmax and np.isinf(bound) and bound > 0:
            # every row full: nbhd's arrays, converted in place where they can be
            found, keys = self._tree.knn(q, kmax, p=p, eps=eps, threads=threads)
            if p == 2:
                return np.sqrt(keys, out=keys), found.astype(np.intp)
            return _distances(keys, p), found.astype(np.intp)
        d = np.full((rows, kmax), np.inf)
        i = np.full((rows, kmax), self.n, dtype=np.intp)
        if rows == 0 or self.n == 0 or not bound > 0:
            return d, i
        if np.isinf(bound):
            found, keys = self._tree.knn(q, kmax, p=p, eps=eps, threads=threads)
            width = found.shape[1]
            i[:, :width] = found
            d[:, :width] = _distances(keys, p)
            return d, i
        table = self._tree.knn_radius(q, kmax, bound, p=p, eps=eps, strict=True, threads=threads)
        assert isinstance(table, Table)  # a batch's rows (2-D queries)
        at = _row_ids(table)
        column = np.arange(len(at), dtype=np.intp) - table.offsets[at].astype(np.intp)
        i[at, column] = table.indices
        d[at, column] = _distances(table.sq_dists, p)
        return d, i

    # ---- radius -------------------------------------------------------------------------

    def query_ball_point(
        self,
        x: ArrayLike,
        r: ArrayLike,
        p: float = 2.0,
        eps: float = 0.0,
        workers: Optional[int] = None,
        return_sorted: Optional[bool] = None,
        return_length: bool = False,
    ) -> Any:
        """The points within ``r`` (inclusive; ``r`` broadcast to ``x.shape[:-1]``) of each
        point of ``x``: an object array of lists of indices (a list for one point), always in
        ascending index order (``return_sorted`` is accepted for scipy's signature); with
        ``return_length`` their numbers instead (intp, an int for one point). ``eps``: every
        point within r / (1 + eps) is returned and none beyond r (1 + eps)."""
        q, lead = self._queries(x)
        radii = np.asarray(r, dtype=np.float64)
        if radii.ndim:
            radii = np.broadcast_to(radii, lead).ravel()
        offsets, indices = self._ball_rows(q, radii, p, eps, _threads(workers), return_length)
        if return_length:
            lengths = np.diff(offsets).astype(np.intp).reshape(lead)
            return int(lengths) if not lead else lengths
        rows = _rows_as_lists(offsets, indices)
        if not lead:
            return rows[0]
        out = np.empty(len(rows), dtype=object)
        out[:] = rows
        return out.reshape(lead)

    def _ball_rows(
        self,
        q: np.ndarray,
        radii: np.ndarray,
        p: float,
        eps: float,
        threads: int,
        lengths_only: bool,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Rows (offsets, indices ascending) of the points within radii[j] of q[j] (radii a
        scalar array: the one radius of every query): one batch query per distinct radius."""
        if radii.ndim == 0:
            table = self._tree.radius(q, float(radii), sorted=False, p=p, eps=eps, threads=threads)
            assert isinstance(table, Table)  # a batch's rows (2-D queries)
            offsets = table.offsets.astype(np.intp)
            if lengths_only or not len(table.indices):
                return offsets, np.empty(0, dtype=np.intp)
            index = table.indices.astype(np.intp)
            order = np.lexsort((index, _row_ids(table)))
            return offsets, index[order]
        lengths = np.zeros(len(q), dtype=np.intp)
        parts: list[tuple[np.ndarray, np.ndarray]] = []
        for radius in np.unique(radii):
            chosen = np.flatnonzero(radii == radius)
            table = self._tree.radius(
                q[chosen], float(radius), sorted=False, p=p, eps=eps, threads=threads
            )
            assert isinstance(table, Table)  # a batch's rows (2-D queries)
            lengths[chosen] = np.diff(table.offsets)
            if not lengths_only:
                parts.append((chosen[_row_ids(table)], table.indices.astype(np.intp)))
        offsets = np.zeros(len(q) + 1, dtype=np.intp)
        np.cumsum(lengths, out=offsets[1:])
        if lengths_only or not parts:
            return offsets, np.empty(0, dtype=np.intp)
        row = np.concatenate([a for a, _ in parts])
        index = np.concatenate([b for _, b in parts])
        order = np.lexsort((index, row))
        return offsets, index[order]

    def query_ball_tree(
        self, other: cKDTree, r: float, p: float = 2.0, eps: float = 0.0
    ) -> list[list[int]]:
        """For each point of this tree, the ascending indices of ``other``'s points within
        ``r`` of it (inclusive; ``eps`` as ``query_ball_point``)."""
        table = self._tree.pairs_with(self._other(other, "query_ball_tree"), r, p=p, eps=eps)
        return _rows_as_lists(table.offsets, table.indices)

    def query_pairs(
        self, r: float, p: float = 2.0, eps: float = 0.0, output_type: str = "set"
    ) -> Any:
        """Every pair ``(i, j)``, i < j, of points within ``r`` of each other (inclusive): a
        set of tuples, or with ``output_type='ndarray'`` an (n_pairs, 2) intp array ordered
        by (i, j)."""
        if output_type not in ("set", "ndarray"):
            raise ValueError("Invalid output type")
        table = self._tree.pairs(r, p=p, eps=eps)
        if output_type == "set":
            i, j = table.coordinates()
            return set(zip(i.tolist(), j.tolist()))
        return table.coordinates(stacked=True)

    # ---- counts and distances between two trees ----------------------------------------------

    def count_neighbors(
        self,
        other: cKDTree,
        r: ArrayLike,
        p: float = 2.0,
        weights: Any = None,
        cumulative: bool = True,
    ) -> Any:
        """The number of pairs (x1 of this tree, x2 of ``other``) within each radius of ``r``
        (a scalar or a 1-D array: an int, or an intp array of r's shape). ``cumulative=False``
        counts the pairs in (r[i-1], r[i]] (r non-decreasing). ``weights``: a tuple (this
        tree's, other's; either may be None) or, when ``other`` is this tree, one array for
        both: the sums of the weight products instead (float64)."""
        tree = self._other(other, "count_neighbors")
        radii = np.asarray(r, dtype=np.float64)
        if radii.ndim > 1:
            raise ValueError("r must be either a single value or a one-dimensional array of values")
        flat = np.atleast_1d(radii)
        if not cumulative and (np.diff(flat) < 0).any():
            raise ValueError("r must be non-decreasing")
        w_self, w_other = self._pair_weights(other, weights)
        weighted = w_self is not None or w_other is not None
        unique, first, inverse = np.unique(flat, return_index=True, return_inverse=True)
        counts = np.zeros(len(unique), dtype=np.float64 if weighted else np.intp)
        if len(unique):
            counts[:] = self._tree.count_pairs(
                tree,
                unique.tolist(),
                cumulative=cumulative,
                weights=w_self,
                other_weights=w_other,
                p=p,
            )
        if cumulative:
            result = counts[inverse.ravel()]
        else:
            # of equal radii the first gets the count (scipy's rule)
            result = np.zeros(len(flat), dtype=counts.dtype)
            result[first] = counts
        if radii.ndim == 0:
            return result[0].item()
        return result

    def _pair_weights(
        self, other: cKDTree, weights: Any
    ) -> tuple[Optional[list[float]], Optional[list[float]]]:
        if weights is None:
            return None, None
        if isinstance(weights, tuple):
            this, theirs = weights
        else:
            if other is not self:
                raise ValueError(
                    "Two different trees are used. Specify weights for both in a tuple."
                )
            this = theirs = weights

        def values(w: Any) -> Optional[list[float]]:
            return None if w is None else np.asarray(w, dtype=np.float64).ravel().tolist()

        return values(this), values(theirs)

    def _build_weights(self, weights: ArrayLike) -> np.ndarray:
        """The sum of ``weights`` (one per point) over each node, in the nodes' order
        (``nbhd.KdTree.node_weights``)."""
        w = np.asarray(weights, dtype=np.float64).ravel()
        return np.asarray(self._tree.node_weights(w.tolist()))

    def sparse_distance_matrix(
        self,
        other: cKDTree,
        max_distance: float,
        p: float = 2.0,
        output_type: str = "dok_matrix",
    ) -> Any:
        """The distances of every pair (x1 of this tree, x2 of ``other``) at most
        ``max_distance`` apart (zero distances included), of shape (self.n, other.n):
        ``output_type`` 'dok_matrix' (default), 'coo_matrix', 'dict' {(i, j): d} or 'ndarray'
        (a record array of fields i, j, v)."""
        if output_type not in ("dok_matrix", "coo_matrix", "dict", "ndarray"):
            raise ValueError("Invalid output type")
        table = self._tree.pairs_with(self._other(other, "sparse_distance_matrix"), max_distance, p=p)
        i, j = table.coordinates()
        v = table.sq_dists
        v = np.sqrt(v, out=v) if p == 2 else _distances(v, p)  # the table is this call's own
        if output_type == "dict":
            return dict(zip(zip(i.tolist(), j.tolist()), v.tolist()))
        if output_type == "ndarray":
            dtype = np.dtype([("i", np.intp), ("j", np.intp), ("v", np.float64)], align=True)
            out = np.empty(len(v), dtype=dtype)
            out["i"], out["j"], out["v"] = i, j, v
            return out
        sparse = importlib.import_module("scipy.sparse")  # scipy: needed for these two only
        coo = sparse.coo_matrix((v, (i, j)), shape=(self.n, other.n))
        return coo if output_type == "coo_matrix" else coo.todok()


class KDTree(cKDTree):
    """scipy's ``KDTree`` on nbhd's tree: :class:`cKDTree` with scipy's ``KDTree`` defaults
    (``leafsize=10``), ``np.intp`` indices for one point and ``tree`` as ``KDTree.node``
    objects (``leafnode``: ``idx``, ``children``; ``innernode``: ``split_dim``, ``split``,
    ``children``, ``less``, ``greater``), each wrapping a :class:`cKDTreeNode` (``_node``)."""

    class node:
        """A node of the tree, ordered by identity (as scipy's)."""

        @staticmethod
        def _create(ckdtree_node: Optional[cKDTreeNode] = None) -> KDTree.node:
            if ckdtree_node is None:
                return KDTree.node(ckdtree_node)
            if ckdtree_node.split_dim == -1:
                return KDTree.leafnode(ckdtree_node)
            return KDTree.innernode(ckdtree_node)

        def __init__(self, ckdtree_node: Optional[cKDTreeNode] = None) -> None:
            self._node = cKDTreeNode() if ckdtree_node is None else ckdtree_node

        def __lt__(self, other: Any) -> bool:
            return id(self) < id(other)

        def __gt__(self, other: Any) -> bool:
            return id(self) > id(other)

        def __le__(self, other: Any) -> bool:
            return id(self) <= id(other)

        def __ge__(self, other: Any) -> bool:
            return id(self) >= id(other)

        def __eq__(self, other: Any) -> bool:
            return id(self) == id(other)

        __hash__ = object.__hash__

        @property
        def children(self) -> int:
            """The number of points below this node."""
            return self._node.children

    class leafnode(node):
        @property
        def idx(self) -> np.ndarray:
            """The indices of the leaf's points (rows of ``data``)."""
            return self._node.indices

    class innernode(node):
        def __init__(self, ckdtreenode: cKDTreeNode) -> None:
            if not isinstance(ckdtreenode, cKDTreeNode):
                raise TypeError("an innernode wraps a cKDTreeNode")
            super().__init__(ckdtreenode)
            self.less = KDTree.node._create(ckdtreenode.lesser)
            self.greater = KDTree.node._create(ckdtreenode.greater)

        @property
        def split_dim(self) -> int:
            return self._node.split_dim

        @property
        def split(self) -> float:
            return self._node.split

    def __init__(
        self,
        data: ArrayLike,
        leafsize: int = 10,
        compact_nodes: bool = True,
        copy_data: bool = False,
        balanced_tree: bool = True,
        boxsize: Union[None, float, Sequence[float], np.ndarray] = None,
    ) -> None:
        super().__init__(data, leafsize, compact_nodes, copy_data, balanced_tree, boxsize)
        self._wrapped_root: Optional[KDTree.node] = None

    @property
    def tree(self) -> Any:
        """The root as a ``KDTree.innernode`` or ``KDTree.leafnode``."""
        if self._wrapped_root is None:
            self._wrapped_root = KDTree.node._create(super().tree)
        return self._wrapped_root

    def query(
        self,
        x: ArrayLike,
        k: Union[int, Sequence[int]] = 1,
        eps: float = 0.0,
        p: float = 2.0,
        distance_upper_bound: float = np.inf,
        workers: Optional[int] = None,
    ) -> tuple[Any, Any]:
        """As :meth:`cKDTree.query`; one point's index (k = 1) as ``np.intp``."""
        d, i = super().query(x, k, eps, p, distance_upper_bound, workers)
        if isinstance(i, int):
            i = np.intp(i)
        return d, i
