"""Type stubs of the compiled module nbhd._nbhd (python/src/). Conventions: indices are the
caller's row indices (uint32); distances are squared (``sq_dists``) in the tree's type; a radius
is a plain Euclidean radius, inclusive; rows are ordered by (sq_dist, index) and identical for
any thread count."""

import os
from typing import Any, Literal, Optional, Sequence, TypedDict, Union, final, overload

import numpy as np
import numpy.typing as npt

ArrayLike = npt.ArrayLike
F64 = npt.NDArray[np.float64]
Floats = Union[npt.NDArray[np.float32], npt.NDArray[np.float64]]
U32 = npt.NDArray[np.uint32]
Path = Union[str, os.PathLike[str]]

Pivot = Literal["sliding-midpoint", "cyclic-median", "spread-median", "closest-to-middle"]
Median = Literal["floyd-rivest", "presorted", "sort", "quickselect", "median-of-medians"]
NonFinite = Literal["reject", "skip"]
Units = Literal["relative", "absolute"]
OrientationName = Literal["unoriented", "toward-point", "away-from-point", "propagate"]

class Spacing(TypedDict):
    mean: float
    median: float
    points: int

class Nodes(TypedDict):
    """``KdTree.nodes()``: one entry per node, in preorder."""

    level: npt.NDArray[np.int64]
    split_dim: npt.NDArray[np.int64]
    split: F64
    left: npt.NDArray[np.int64]
    right: npt.NDArray[np.int64]
    start: npt.NDArray[np.int64]
    end: npt.NDArray[np.int64]

class VoxelGrid(TypedDict):
    centroids: Floats
    nearest: U32
    offsets: npt.NDArray[np.uint64]
    members: U32
    cells: npt.NDArray[np.int64]

class AerialTile(TypedDict):
    positions: F64
    classification: npt.NDArray[np.uint8]
    return_number: npt.NDArray[np.uint8]
    number_of_returns: npt.NDArray[np.uint8]
    gps_time: F64
    intensity: npt.NDArray[np.uint16]
    point_source_id: npt.NDArray[np.uint16]
    scan_angle: npt.NDArray[np.int16]

__all__ = [
    "KdTree",
    "Table",
    "DynamicKdTree",
    "normals",
    "curvatures",
    "smooth",
    "smooth_robust",
    "RobustOptions",
    "RobustRun",
    "RobustTile",
    "RankSearch",
    "DigitCounts",
    "ExactSum",
    "voxel_grid",
    "mean_distances",
    "squared_deviation_sum",
    "outlier_threshold",
    "aerial_tile",
    "read",
    "write",
    "_reads_in_place",
    "_skipped_outputs",
    "MAX_THREADS",
    "__version__",
]

MAX_THREADS: int
__version__: str

# The classes are PyO3 classes: built by __new__ and not subclassable (final). Defaults the
# compiled module shows as `...` (lists, the library's constants) are `...` here too, with their
# value in a comment; mypy's stubtest checks the rest against the module (scripts/wheel-test.sh).

@final
class Table:
    """Neighbourhoods as compressed rows: row i is ``indices[offsets[i]:offsets[i+1]]`` with
    its ``sq_dists``."""

    offsets: npt.NDArray[np.uint64]
    indices: U32
    sq_dists: Floats
    n_points: int
    def __len__(self) -> int: ...
    def row(self, i: int) -> tuple[U32, Floats]: ...
    @overload
    def coordinates(
        self, *, stacked: Literal[False] = False
    ) -> tuple[npt.NDArray[np.intp], npt.NDArray[np.intp]]:
        """The row and the column of every entry, row after row (scipy.sparse's COO form)."""
    @overload
    def coordinates(self, *, stacked: Literal[True]) -> npt.NDArray[np.intp]:
        """The (entries, 2) array of every entry's (row, column)."""
    def row_lengths(self) -> npt.NDArray[np.uint64]: ...
    def to_csr(self, *, distances: bool = False) -> Any:
        """A ``scipy.sparse.csr_matrix`` (rows, n_points) of the keys (squared distances for
        p = 2), or with ``distances=True`` the distances in the query's metric."""

@final
class KdTree:
    """A k-d tree over the rows of an (n, d) float32/float64 array."""

    def __new__(
        cls,
        points: ArrayLike,
        *,
        pivot: Pivot = "sliding-midpoint",
        median: Median = "floyd-rivest",
        leaf_size: int = ...,  # nbhd::tree::DEFAULT_LEAF_SIZE (12)
        non_finite: NonFinite = "reject",
        threads: int = 0,
        boxsize: Union[float, Sequence[float], None] = None,
    ) -> KdTree: ...
    @property
    def size(self) -> int:
        """Points held (skipped non-finite points not counted)."""
    @property
    def n(self) -> int:
        """Rows of the array the tree was built from."""
    @property
    def m(self) -> int:
        """Dimension."""
    @property
    def dtype_name(self) -> Literal["float32", "float64"]: ...
    @property
    def boxsize(self) -> Optional[list[float]]:
        """The periodic box per axis (0 for an open axis), None if not periodic."""
    @property
    def tree_order(self) -> U32: ...
    def nodes(self) -> Nodes:
        """The nodes in preorder: level, split_dim (-1 leaf), split (left ≤ split ≤ right),
        left/right child positions (-1 leaf), start/end (the node's points are
        ``tree_order[start:end]``)."""
    def node_weights(self, weights: Sequence[float]) -> F64:
        """Per-node sums of ``weights`` (one per row of the array), in the order of ``nodes()``."""
    def stats(self) -> dict[str, int]: ...
    def options(self) -> dict[str, Any]: ...
    def __len__(self) -> int: ...
    def knn(
        self, x: ArrayLike, k: int, *, p: float = 2.0, eps: float = 0.0, threads: int = 0
    ) -> tuple[U32, Floats]:
        """1-D x: (indices, sq_dists) of length min(k, size); 2-D x (m, d): arrays (m, min(k, size)).
        p: Minkowski p-norm (sq_dists hold its key: squared for p = 2); eps: approximate search."""
    def radius(
        self,
        x: ArrayLike,
        radius: float,
        *,
        sorted: bool = True,
        p: float = 2.0,
        eps: float = 0.0,
        strict: bool = False,
        threads: int = 0,
    ) -> Union[tuple[U32, Floats], Table]:
        """1-D x: (indices, sq_dists); 2-D x: a Table with one row per query."""
    def knn_radius(
        self,
        x: ArrayLike,
        k: int,
        radius: float,
        *,
        p: float = 2.0,
        eps: float = 0.0,
        strict: bool = False,
        threads: int = 0,
    ) -> Union[tuple[U32, Floats], Table]:
        """1-D x: (indices, sq_dists); 2-D x: a Table with one row per query."""
    def neighborhoods(
        self,
        *,
        k: Optional[int] = None,
        radius: Optional[float] = None,
        exclude_self: bool = True,
        sorted: bool = True,
        p: float = 2.0,
        eps: float = 0.0,
        strict: bool = False,
        threads: int = 0,
    ) -> Table: ...
    def pairs(
        self,
        radius: float,
        *,
        p: float = 2.0,
        eps: float = 0.0,
        strict: bool = False,
        threads: int = 0,
    ) -> Table:
        """Pairs i < j within radius: row i holds the j > i ascending, with their keys."""
    def pairs_with(
        self,
        other: Union[KdTree, DynamicKdTree],
        radius: float,
        *,
        p: float = 2.0,
        eps: float = 0.0,
        strict: bool = False,
        threads: int = 0,
    ) -> Table:
        """Row i: the indices j of ``other`` within radius of point i, ascending, with keys."""
    def count_pairs(
        self,
        other: Union[KdTree, DynamicKdTree],
        radii: Sequence[float],
        *,
        cumulative: bool = True,
        weights: Optional[Sequence[float]] = None,
        other_weights: Optional[Sequence[float]] = None,
        p: float = 2.0,
        strict: bool = False,
        threads: int = 0,
    ) -> Union[npt.NDArray[np.uint64], F64]:
        """Pair counts per radius (uint64), or weight sums (float64) when weighted."""
    def in_box(
        self, min: npt.ArrayLike, max: npt.ArrayLike, *, threads: int = 0
    ) -> Union[U32, tuple[npt.NDArray[np.uint64], U32]]:
        """1-D bounds: the indices inside the closed box; 2-D: (offsets, indices)."""
    def spacing(self, *, threads: int = 0) -> Spacing: ...
    def remove_statistical_outliers(
        self, *, k: int = 50, std_ratio: float = 1.0, threads: int = 0
    ) -> U32:
        """Indices kept (ascending) by statistical outlier removal (PCL, Open3D's ``ind``)."""
    def remove_radius_outliers(
        self, radius: float, *, min_neighbors: int = 2, threads: int = 0
    ) -> U32:
        """Indices of the points with at least ``min_neighbors`` others within ``radius``."""
    def to_bytes(self) -> bytes:
        """The saved-tree format (docs/tree-file-format.md); what pickle stores."""
    @classmethod
    def from_bytes(cls, data: bytes) -> KdTree: ...

@final
class DynamicKdTree:
    """A k-d tree accepting batch insertions and removals by index (nbhd::DynamicKdTree)."""

    def __new__(
        cls,
        dim: int,
        *,
        dtype: Literal["float32", "float64"] = "float32",
        pivot: str = "sliding-midpoint",
        median: str = "floyd-rivest",
        leaf_size: int = ...,  # nbhd::tree::DEFAULT_LEAF_SIZE (12)
        non_finite: NonFinite = "reject",
        threads: int = 0,
        growth: int = ...,  # nbhd::dynamic::GROWTH (4)
        boxsize: Union[float, Sequence[float], None] = None,
    ) -> DynamicKdTree: ...
    def insert(self, points: ArrayLike) -> int:
        """Inserts a batch; returns the index of its first point."""
    def remove(self, indices: Sequence[int]) -> None: ...
    @property
    def threads(self) -> int:
        """Threads of the builds insert and remove run (0: a thread per core); 0 after from_bytes."""
    @threads.setter
    def threads(self, threads: int) -> None: ...
    @property
    def size(self) -> int:
        """Live points."""
    @property
    def next_index(self) -> int: ...
    @property
    def m(self) -> int: ...
    @property
    def boxsize(self) -> Optional[list[float]]: ...
    @property
    def dtype_name(self) -> Literal["float32", "float64"]: ...
    def is_live(self, index: int) -> bool: ...
    def point(self, index: int) -> Floats: ...
    def stats(self) -> dict[str, Any]: ...
    def __len__(self) -> int: ...
    def knn(
        self, x: ArrayLike, k: int, *, p: float = 2.0, eps: float = 0.0, threads: int = 0
    ) -> tuple[U32, Floats]: ...
    def radius(
        self,
        x: ArrayLike,
        radius: float,
        *,
        sorted: bool = True,
        p: float = 2.0,
        eps: float = 0.0,
        strict: bool = False,
        threads: int = 0,
    ) -> Union[tuple[U32, Floats], Table]: ...
    def knn_radius(
        self,
        x: ArrayLike,
        k: int,
        radius: float,
        *,
        p: float = 2.0,
        eps: float = 0.0,
        strict: bool = False,
        threads: int = 0,
    ) -> Union[tuple[U32, Floats], Table]: ...
    def neighborhoods(
        self,
        *,
        k: Optional[int] = None,
        radius: Optional[float] = None,
        exclude_self: bool = True,
        sorted: bool = True,
        p: float = 2.0,
        eps: float = 0.0,
        strict: bool = False,
        threads: int = 0,
    ) -> Table: ...
    def pairs(
        self,
        radius: float,
        *,
        p: float = 2.0,
        eps: float = 0.0,
        strict: bool = False,
        threads: int = 0,
    ) -> Table:
        """Pairs i < j within radius: row i holds the j > i ascending, with their keys."""
    def pairs_with(
        self,
        other: Union[KdTree, DynamicKdTree],
        radius: float,
        *,
        p: float = 2.0,
        eps: float = 0.0,
        strict: bool = False,
        threads: int = 0,
    ) -> Table:
        """Row i: the indices j of ``other`` within radius of point i, ascending, with keys."""
    def count_pairs(
        self,
        other: Union[KdTree, DynamicKdTree],
        radii: Sequence[float],
        *,
        cumulative: bool = True,
        weights: Optional[Sequence[float]] = None,
        other_weights: Optional[Sequence[float]] = None,
        p: float = 2.0,
        strict: bool = False,
        threads: int = 0,
    ) -> Union[npt.NDArray[np.uint64], F64]:
        """Pair counts per radius (uint64), or weight sums (float64) when weighted."""
    def in_box(
        self, min: npt.ArrayLike, max: npt.ArrayLike, *, threads: int = 0
    ) -> Union[U32, tuple[npt.NDArray[np.uint64], U32]]:
        """1-D bounds: the indices inside the closed box; 2-D: (offsets, indices)."""
    def spacing(self, *, threads: int = 0) -> Spacing: ...
    def remove_statistical_outliers(
        self, *, k: int = 50, std_ratio: float = 1.0, threads: int = 0
    ) -> U32:
        """Indices kept (ascending) by statistical outlier removal (PCL, Open3D's ``ind``)."""
    def remove_radius_outliers(
        self, radius: float, *, min_neighbors: int = 2, threads: int = 0
    ) -> U32:
        """Indices of the points with at least ``min_neighbors`` others within ``radius``."""
    def to_bytes(self) -> bytes: ...
    @classmethod
    def from_bytes(cls, data: bytes) -> DynamicKdTree: ...

class Outputs(TypedDict):
    normals: F64
    k1: F64
    k2: F64
    dir1: F64
    dir2: F64
    mean_curvature: F64
    max_principal_curvature: F64
    surface_variation: F64
    principal_curvature_quotient: F64
    max_covariance: F64
    anisotropic_mean_curvature: F64
    flags: npt.NDArray[np.uint8]
    feature: npt.NDArray[np.bool_]
    interior: npt.NDArray[np.bool_]

class Curvatures(Outputs):
    spacing: float
    epsilon: float
    min_neighbors: int

# "lambda" is a keyword, so this TypedDict is spelt as a call
SmoothResult = TypedDict(
    "SmoothResult",
    {
        "points": F64,
        "spacing": float,
        "epsilon": float,
        "lambda": float,
        "min_neighbors": int,
        "outputs": Optional[Outputs],
    },
)

class RobustResult(SmoothResult):
    normals: F64
    noise: F64
    moved: F64
    dimension: F64
    wide_iterations: int

def normals(
    points: ArrayLike,
    *,
    k: int = 15,
    epsilon: float = 6.0,
    epsilon_units: Units = "relative",
    orientation: OrientationName = "unoriented",
    orientation_point: Sequence[float] = ...,  # (0.0, 0.0, 0.0)
    non_finite: NonFinite = "reject",
    threads: int = 0,
) -> tuple[F64, F64, npt.NDArray[np.uint8]]:
    """(normals (n, 3), surface variation (n,), flags (n,))."""

def curvatures(
    points: ArrayLike,
    *,
    k: int = 15,
    epsilon: float = 6.0,
    epsilon_units: Units = "relative",
    orientation: OrientationName = "unoriented",
    orientation_point: Sequence[float] = ...,  # (0.0, 0.0, 0.0)
    density: Literal["abs-linear", "quadratic"] = "abs-linear",
    formula: Literal["eq2.25", "exact-moments"] = "eq2.25",
    non_finite: NonFinite = "reject",
    threads: int = 0,
) -> Curvatures: ...
def smooth(
    points: ArrayLike,
    *,
    method: Literal["anisotropic", "isotropic"] = "anisotropic",
    k: int = 15,
    epsilon: float = 6.0,
    epsilon_units: Units = "relative",
    steps: Optional[int] = None,
    tau: float = 0.5,
    weighting: Optional[Literal["isotropic", "sharp", "continuous"]] = None,
    lambda_: float = 0.2,
    lambda_units: Units = "relative",
    feature: Literal["all", "edge-quotient", "principal", "directional"] = "all",
    feature_threshold: Optional[float] = None,
    feature_units: Units = "relative",
    constrain_interior: Optional[float] = None,
    update_neighbors: bool = False,
    orientation: OrientationName = "unoriented",
    orientation_point: Sequence[float] = ...,  # (0.0, 0.0, 0.0)
    non_finite: NonFinite = "reject",
    outputs: bool = False,
    threads: int = 0,
) -> SmoothResult: ...
def smooth_robust(
    points: ArrayLike,
    *,
    k: int = 24,
    k_plane: int = 48,
    epsilon: float = 12.0,
    epsilon_units: Units = "relative",
    max_iterations: int = 10,
    tolerance: float = 0.05,
    inlier_width: float = 5.0,
    feature_angle: float = 20.0,
    tau: float = 1.0,
    noise_scale: Optional[bool] = None,
    orientation: OrientationName = "unoriented",
    orientation_point: Sequence[float] = ...,  # (0.0, 0.0, 0.0)
    outputs: bool = False,
    non_finite: NonFinite = "reject",
    threads: int = 0,
) -> RobustResult: ...

# The step API of the robust mode (nbhd::smooth::robust::{RobustRun, RobustTile}) and the exact
# reductions across tiles (RankSearch, ExactSum): what nbhd.dask drives; see python/DASK.md.

RobustRound = TypedDict(
    "RobustRound",
    {
        "kind": Literal["start", "ratio", "measure", "step", "finish", "done"],
        "generation": Optional[int],
        "rows": Optional[Literal["plain", "wide", "shrunk"]],
        "shrunk_at": Optional[int],
        "epsilon": float,
        "sigma": float,
        "k": int,
        "lambda": float,
    },
    total=False,
)

RobustRunReport = TypedDict(
    "RobustRunReport",
    {
        "spacing": float,
        "epsilon": float,
        "lambda": float,
        "min_neighbors": int,
        "noise": F64,
        "moved": F64,
        "dimension": F64,
        "wide_iterations": int,
    },
)

class RobustPart(TypedDict):
    count: int
    valid: npt.NDArray[np.bool_]
    values: F64
    moved_sq: ExactSum
    max_len: int
    min_narrow: int

class RobustTileResult(TypedDict):
    valid: npt.NDArray[np.bool_]
    points: F64
    normals: F64
    outputs: Optional[Outputs]

@final
class RobustOptions:
    """The options of a robust run: ``smooth_robust``'s keywords but ``non_finite`` and
    ``threads`` (one list in python/src/robust_options.rs makes both signatures)."""
    def __new__(
        cls,
        *,
        k: int = 24,
        k_plane: int = 48,
        epsilon: float = 12.0,
        epsilon_units: Units = "relative",
        max_iterations: int = 10,
        tolerance: float = 0.05,
        inlier_width: float = 5.0,
        feature_angle: float = 20.0,
        tau: float = 1.0,
        noise_scale: Optional[bool] = None,
        orientation: OrientationName = "unoriented",
        orientation_point: Sequence[float] = ...,  # (0.0, 0.0, 0.0)
        outputs: bool = False,
    ) -> RobustOptions: ...
    def __getnewargs_ex__(self) -> tuple[tuple[()], dict[str, Any]]: ...

@final
class RobustRun:
    """The state of one robust run between rounds (``nbhd::smooth::robust::RobustRun``)."""
    def __new__(cls, spacing: float, options: RobustOptions) -> RobustRun: ...
    @property
    def epsilon(self) -> float: ...
    def round(self) -> RobustRound: ...
    def feed(
        self,
        round: RobustRound,
        *,
        count: int,
        max_len: int = 0,
        min_narrow: int = 0,
        median: Optional[float] = None,
        moved_sq: Optional[ExactSum] = None,
    ) -> None: ...
    @staticmethod
    def median_rank(count: int) -> int: ...
    def report(self) -> RobustRunReport: ...
    @staticmethod
    def spacing_of_nearest(nearest_sq: ArrayLike) -> float: ...

@final
class RobustTile:
    """One tile of a robust run (``nbhd::smooth::robust::RobustTile``)."""
    def __new__(
        cls,
        points: ArrayLike,
        owned: ArrayLike,
        lo: Sequence[float],
        hi: Sequence[float],
        options: RobustOptions,
        *,
        threads: int = 0,
    ) -> RobustTile: ...
    def keep_rows_in(self, dir: Union[str, os.PathLike[str]]) -> None: ...
    def nearest(self) -> tuple[F64, npt.NDArray[np.bool_]]: ...
    def set_current(self, generation: int, current: ArrayLike) -> None: ...
    def set_shrink(self, at: int, proxy: ArrayLike) -> None: ...
    def set_normals(self, normals: ArrayLike) -> None: ...
    def round(self, round: RobustRound) -> RobustPart: ...
    def owned_points(self) -> F64: ...
    def owned_normals(self) -> F64: ...
    def finish(self, round: RobustRound) -> RobustTileResult: ...

@final
class RankSearch:
    """An exact selection across parts (``nbhd::select::radix::RankSearch`` of f64)."""
    def __new__(cls, rank: int) -> RankSearch: ...
    def step(self) -> tuple[Literal["counts", "values", "found"], Optional[float]]: ...
    def digit_counts(self, values: ArrayLike) -> DigitCounts: ...
    def matching_values(self, values: ArrayLike) -> F64: ...
    def feed_counts(self, counts: DigitCounts) -> None: ...
    def feed_values(self, values: ArrayLike) -> None: ...
    def to_bytes(self) -> bytes: ...
    @staticmethod
    def from_bytes(bytes: bytes) -> RankSearch: ...
    def __reduce__(self) -> tuple[Any, ...]: ...

@final
class DigitCounts:
    """One round's digit counts of a RankSearch (of one part, or merged)."""
    def merge(self, other: DigitCounts) -> None: ...
    @property
    def total(self) -> int: ...
    def to_bytes(self) -> bytes: ...
    @staticmethod
    def from_bytes(bytes: bytes) -> DigitCounts: ...
    def __reduce__(self) -> tuple[Any, ...]: ...

@final
class ExactSum:
    """An exactly rounded, order-independent sum of f64 values (``nbhd::sum::ExactSum``)."""
    def __new__(cls) -> ExactSum: ...
    def add(self, values: ArrayLike) -> None: ...
    def merge(self, other: ExactSum) -> None: ...
    def value(self) -> float: ...
    def to_bytes(self) -> bytes: ...
    @staticmethod
    def from_bytes(bytes: bytes) -> ExactSum: ...
    def __reduce__(self) -> tuple[Any, ...]: ...

def mean_distances(sq_dists: Floats) -> F64:
    """Each row's mean distance (``(1/k) Σ √d²`` in float64) of an (m, k) array of squared distances."""
def squared_deviation_sum(d: F64, mean: float) -> ExactSum:
    """``Σ (d_i − mean)²`` over the mean distances ``d``, exactly summed."""
def outlier_threshold(mean: float, spread: ExactSum, n: int, std_ratio: float) -> float:
    """The statistical outlier threshold ``mean + std_ratio · √(spread / (n − 1))``."""

def _skipped_outputs(count: int) -> Outputs: ...

class CloudFile(TypedDict):
    positions: F64
    normals: Optional[F64]
    scalars: dict[str, F64]
    grid: Optional[tuple[int, int]]
    format: Literal["PLY", "PCD", "OBJ", "LAS", "XYZ"]
    source_precision: Optional[Literal["single", "double"]]
    text_columns: Optional[list[str]]

def aerial_tile(
    x0: float,
    y0: float,
    x1: float,
    y1: float,
    *,
    seed: int = 39,
    density: float = 16.0,
    swath: float = 400.0,
    overlap: float = 0.3,
    noise: float = 0.025,
    strip_offset: float = 0.03,
    outliers: float = 1e-5,
) -> AerialTile:
    """The seeded synthetic aerial survey's points whose pulses fall in [x0, x1) x [y0, y1)."""

def voxel_grid(
    points: ArrayLike,
    leaf: Union[float, Sequence[float]],
    *,
    min_points_per_voxel: int = 0,
    threads: int = 0,
) -> VoxelGrid:
    """The occupied voxels: centroids, each one's row nearest its centroid, and its rows."""

def read(path: Path, *, format: Optional[str] = None, columns: Optional[str] = None) -> CloudFile: ...
def write(
    path: Path,
    positions: ArrayLike,
    *,
    normals: Optional[ArrayLike] = None,
    scalars: Optional[dict[str, ArrayLike]] = None,
    format: Optional[Literal["ply", "pcd", "las", "laz", "xyz"]] = None,
    encoding: Optional[Literal["ascii", "binary", "binary-big-endian", "binary-compressed"]] = None,
    precision: Literal["single", "double", "keep"] = "single",
) -> None: ...
def _reads_in_place(points: ArrayLike) -> bool: ...
