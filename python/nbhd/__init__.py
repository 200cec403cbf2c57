"""nbhd — exact neighbourhoods in point clouds, and the smoothing that needs them.

Python bindings of the Rust library nbhd (k-d trees with the build variants of M. Skrodzki's
thesis *Neighborhood Computation of Point Set Surfaces*, exact k-nearest, radius and ε-k
queries, PCA normals, curvatures and point-set smoothing). Every computation runs in Rust with
the GIL released.

Conventions (as in the Rust library): indices are the caller's row indices; a radius is a plain
Euclidean radius and inclusive (‖p − q‖ ≤ r); distances come back squared (``sq_dists``);
results are ordered by (sq_dist, index) and identical for any number of threads.
"""

from ._errors import (
    CancelledError,
    DegenerateError,
    NbhdError,
    NbhdIOError,
    NbhdMemoryError,
    NbhdValueError,
)
from ._nbhd import (
    MAX_THREADS,
    DigitCounts,
    DynamicKdTree,
    ExactSum,
    KdTree,
    RankSearch,
    RobustOptions,
    RobustRun,
    RobustTile,
    Table,
    __version__,
    aerial_tile,
    curvatures,
    mean_distances,
    normals,
    outlier_threshold,
    read,
    smooth,
    smooth_robust,
    squared_deviation_sum,
    voxel_grid,
    write,
)

__all__ = [
    "KdTree",
    "DynamicKdTree",
    "Table",
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
    "MAX_THREADS",
    "NbhdError",
    "NbhdValueError",
    "DegenerateError",
    "NbhdMemoryError",
    "NbhdIOError",
    "CancelledError",
    "__version__",
]
