/*
 * nbhd.h: the C API of nbhd, exact neighbourhoods in point clouds with k-d trees.
 *
 * Overview
 *   Describe your points with an nbhd_points (pointer, count, dimension, stride, scalar type),
 *   build a tree with nbhd_tree_build, then ask single queries (nbhd_tree_knn, nbhd_tree_radius,
 *   nbhd_tree_knn_radius, and their _index variants around a stored point) into your own
 *   buffers, or whole tables (nbhd_tree_neighborhoods) as compressed rows.
 *
 * Errors
 *   Every function that can fail returns an nbhd_status; NBHD_STATUS_OK is 0.
 *   nbhd_status_string(status) describes a code; nbhd_last_error_message() gives the reason of the
 *   last failure on the calling thread in words, naming the argument, option or point index at
 *   fault. No function aborts or unwinds into C on bad input: NULL and misaligned pointers,
 *   out-of-range enum values, NaN or infinite coordinates and empty inputs are reported as
 *   statuses, and an internal Rust panic is caught and reported as NBHD_STATUS_INTERNAL.
 *   One rule for an enum field holding no value of its enum: in an options struct
 *   (nbhd_*_options) it is NBHD_STATUS_INVALID_OPTION, like any other option out of range; in
 *   any other struct (nbhd_points, nbhd_neighborhood_spec, nbhd_normals_output) it is
 *   NBHD_STATUS_INVALID_ARGUMENT. The message names the field and the value.
 *
 * Ownership
 *   - nbhd_tree_build, nbhd_tree_load and nbhd_tree_load_from_buffer make an nbhd_tree* that
 *     you free with nbhd_tree_free. nbhd_tree_save_to_buffer writes into your buffer (a call
 *     with capacity 0 tells the size); a saved tree is in the format of docs/tree-file-format.md.
 *   - nbhd_tree_neighborhoods(_of) make an nbhd_neighborhoods* that you free with
 *     nbhd_neighborhoods_free. A table does not refer to its tree; free them in any order.
 *   - Both free functions accept NULL.
 *   - Pointers returned by the table accessors belong to the table and stay valid until it is freed.
 *   - Strings returned by nbhd_version_string and nbhd_status_string are static;
 *     nbhd_last_error_message's string stays valid until the next nbhd call on the same thread.
 *     Never free them.
 *   - nbhd never keeps a pointer to your buffers past the call that receives them: a tree copies
 *     the points it needs.
 *
 * Units and types
 *   - A tree computes in the scalar type of the points it was built from (NBHD_SCALAR_TYPE_F32:
 *     float, NBHD_SCALAR_TYPE_F64: double). Query coordinates (const void*) and squared distances
 *     (void*, or const void* from tables) are in that type; nbhd_stats.scalar_type tells it.
 *   - A radius is a plain Euclidean radius (not squared), passed as a double, inclusive:
 *     |x - q| <= radius, evaluated as squared distance <= radius * radius in the tree's type.
 *   - Distances come back squared.
 *   - Other metrics: nbhd_tree_search, nbhd_dynamic_search and nbhd_table_options.query take
 *     nbhd_query_options (a Minkowski p-norm, eps for approximate searches, strict radii); the
 *     radius is then a distance in that metric and "squared distances" hold its key (see
 *     nbhd_metric). The defaults are the conventions above.
 *   - Range: squared distances must be finite in the tree's type. A radius whose square is not
 *     (float: above about 1.8e19) is refused with NBHD_STATUS_INVALID_RADIUS; keep a float
 *     tree's coordinates below about 5e18 in magnitude (double: 3e153), or distances between
 *     far-apart points overflow. Normals and curvatures are computed in a frame scaled to each
 *     neighbourhood, correct from the smallest to the largest magnitudes within that range.
 *   - SMOOTHING AND NORMAL LENGTHS ARE RELATIVE BY DEFAULT: `epsilon` (and `lambda`) in
 *     nbhd_smooth_options, nbhd_normal_options and nbhd_robust_options are multiples of the mean
 *     spacing h of the points (or of 1/h), not lengths in the points' units, unless their
 *     `*_units` field is NBHD_UNITS_ABSOLUTE. An epsilon so small that no neighbourhood reaches
 *     3 points is refused with NBHD_STATUS_DEGENERATE, whose message gives it in the points'
 *     units; nbhd_smooth_summary reports h and the epsilon used.
 *   - Memory: a result that does not fit (a table with a radius covering every point, k =
 *     SIZE_MAX) is NBHD_STATUS_OUT_OF_MEMORY with the bytes needed, never an abort. k never
 *     usefully exceeds the number of points.
 *   - Results are ordered by (squared distance, index): ties are deterministic, and tables are
 *     identical for any number of threads.
 *
 * Indices
 *   Points are identified by their index in the points given to nbhd_tree_build, as uint32_t: a
 *   tree holds at most 4294967295 (UINT32_MAX) points. Points skipped as non-finite keep their
 *   indices' places (queries by their index fail with NBHD_STATUS_SKIPPED_POINT; tables give them
 *   empty rows).
 *
 * Threads
 *   A built tree is immutable: any number of threads may query one tree at once, without locks.
 *   The same holds for reading a table. Freeing a tree or table while another thread uses it is
 *   undefined. The library's own worker threads (builds and tables with threads = 0) come from
 *   one shared pool with a thread per core.
 *   - The `threads` option of every call is 0 (the shared pool) or 1 .. NBHD_MAX_THREADS (1024);
 *     a larger value fails with NBHD_STATUS_INVALID_OPTION, naming it, before any thread starts.
 *   - A call with threads = n runs on a pool of n threads. The two most recently used such
 *     pools are kept for the next calls if n is at most the number of cores; any other pool is
 *     the call's own, and its threads have exited when the call returns. So nbhd's idle threads
 *     are the shared pool (once threads = 0 was used) plus at most two pools of at most a thread
 *     per core each.
 *   - fork(): a child forked after nbhd ran in the parent may call nbhd. The parent's worker
 *     threads do not exist in the child, so nbhd notices the fork (the process id changed), never
 *     uses or frees a pool made before it, and gives the child pools of its own (threads = 0 then
 *     means a child-owned pool with a thread per core). Trees and tables built before the fork
 *     are plain memory and may be used in the child. As with any library, fork() while another
 *     thread is inside an nbhd call leaves that call's state (its memory) behind in the child.
 *
 * ABI policy
 *   - The SONAME is the ABI version: libnbhd.so.0.MINOR while nbhd is 0.x, libnbhd.so.MAJOR
 *     from 1.0 on. Releases that keep the SONAME keep the ABI: no struct changes size or layout,
 *     no signature changes, no enum value or status code is renumbered or removed. They may add
 *     functions, enum values and status codes, so expect values you do not know from enums the
 *     library returns (treat any status other than NBHD_STATUS_OK as an error and describe it
 *     with nbhd_status_string). A program linked against one release runs with any later
 *     release of the same SONAME.
 *   - Everything else gets a new SONAME: a 0.x minor release (0.1 -> 0.2) or, from 1.0 on, a
 *     major release. The dynamic linker then keeps loading the library a program was built for.
 *   - Option structs (nbhd_build_options, nbhd_table_options and every other nbhd_*_options)
 *     grow: new fields are added at their end, with defaults that keep the previous behaviour,
 *     in releases with a new SONAME (a program compiled against the smaller struct would hand
 *     the library too few bytes). Your source stays compatible across such
 *     releases if you always start from the library's defaults and set fields by name:
 *         nbhd_build_options o = nbhd_build_options_default();
 *         o.threads = 4;
 *     or pass NULL for the defaults. Never fill an options struct from zero (memset, `= {0}`)
 *     or with a positional initializer: a field added later would then be 0, not its default.
 *   - Compare nbhd_version() with NBHD_VERSION at start-up to detect a header/library mismatch.
 *   - Changes are listed in CHANGELOG.md of the source distribution.
 *
 * Linking
 *   Link with -lnbhd (libnbhd.so / libnbhd.dylib / nbhd.dll, or the static libnbhd.a plus the
 *   system libraries `cargo rustc --release -- --print native-static-libs` lists, e.g.
 *   -lpthread -ldl -lm on Linux).
 */


#ifndef NBHD_H
#define NBHD_H

/* Generated by cbindgen from src/ffi of the nbhd crate. Do not edit: run scripts/gen-header.sh. */

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/**
 * Major version of the nbhd library this header belongs to.
 */
#define NBHD_VERSION_MAJOR 0

/**
 * Minor version of the nbhd library this header belongs to.
 */
#define NBHD_VERSION_MINOR 1

/**
 * Patch version of the nbhd library this header belongs to.
 */
#define NBHD_VERSION_PATCH 0

/**
 * The version of this header as one number, `MAJOR * 1000000 + MINOR * 1000 + PATCH`;
 * compare it with `nbhd_version()` to detect a header/library mismatch at run time.
 */
#define NBHD_VERSION (((NBHD_VERSION_MAJOR * 1000000) + (NBHD_VERSION_MINOR * 1000)) + NBHD_VERSION_PATCH)

/**
 * The largest `threads` option a call accepts. A larger value fails with
 * NBHD_STATUS_INVALID_OPTION, naming the value, before any thread is started. (0, a thread
 * per core, is always accepted.)
 */
#define NBHD_MAX_THREADS 1024

/**
 * How a tree node chooses its splitting dimension and pivot (thesis Sections 3.2 and 5.4).
 * Every policy splits by the composite (lexicographic) order, so duplicates never make the
 * tree degenerate.
 */
typedef enum {
    /**
     * Dimensions in turn (depth mod d), split at the median (thesis Algorithm 4). Balanced.
     */
    NBHD_PIVOT_POLICY_CYCLIC_MEDIAN = 0,
    /**
     * Median of the dimension of largest spread (Omohundro). Balanced.
     */
    NBHD_PIVOT_POLICY_SPREAD_MEDIAN = 1,
    /**
     * The point closest to the middle of the most spread dimension (Moore). Not balanced.
     */
    NBHD_PIVOT_POLICY_CLOSEST_TO_MIDDLE = 2,
    /**
     * Sliding midpoint (ANN, nanoflann, FLANN). The default.
     */
    NBHD_PIVOT_POLICY_SLIDING_MIDPOINT = 3,
} nbhd_pivot_policy;

/**
 * How the pivot of a node is found (thesis Section 3.3 and Chapter 6). For one pivot policy
 * every algorithm builds the identical tree; they differ in speed only.
 */
typedef enum {
    /**
     * Lists presorted once per dimension, kept sorted by stable partitions (Algorithm 6).
     */
    NBHD_MEDIAN_ALGORITHM_PRESORTED = 0,
    /**
     * Sort the node's points, then pick.
     */
    NBHD_MEDIAN_ALGORITHM_SORT = 1,
    /**
     * Randomised quickselect with a median-of-three pivot (Algorithm 10).
     */
    NBHD_MEDIAN_ALGORITHM_QUICKSELECT = 2,
    /**
     * Floyd-Rivest selection. The default.
     */
    NBHD_MEDIAN_ALGORITHM_FLOYD_RIVEST = 3,
    /**
     * Deterministic median of medians (Algorithm 11).
     */
    NBHD_MEDIAN_ALGORITHM_MEDIAN_OF_MEDIANS = 4,
} nbhd_median_algorithm;

/**
 * What a build does with points that have a NaN or infinite coordinate.
 */
typedef enum {
    /**
     * Refuse the input with NBHD_STATUS_NON_FINITE; the message names the first such point.
     * The default.
     */
    NBHD_NON_FINITE_POLICY_REJECT = 0,
    /**
     * Leave such points out; the others keep their indices. Queries by the index of a
     * skipped point fail with NBHD_STATUS_SKIPPED_POINT; tables give them empty rows.
     */
    NBHD_NON_FINITE_POLICY_SKIP = 1,
} nbhd_non_finite_policy;

/**
 * What a fallible nbhd function returns. NBHD_STATUS_OK is 0; every other value is an
 * error, described in words for the calling thread by nbhd_last_error_message().
 */
typedef enum {
    /**
     * Success.
     */
    NBHD_STATUS_OK = 0,
    /**
     * A required pointer argument is NULL (the message names it).
     */
    NBHD_STATUS_NULL_POINTER = 1,
    /**
     * A pointer argument is not aligned for the type it points to (the message names it).
     */
    NBHD_STATUS_MISALIGNED_POINTER = 2,
    /**
     * An argument has a value outside its range: an enum field of an argument struct
     * (nbhd_points, nbhd_neighborhood_spec, nbhd_normals_output) holding no value of its
     * enum, a row or index beyond its range, or a points description whose byte size
     * overflows the address space (`dim * sizeof(scalar)` or `(count - 1) * stride`; the
     * message names the argument and the values passed).
     */
    NBHD_STATUS_INVALID_ARGUMENT = 3,
    /**
     * The point set is empty: count 0, or no finite point left after skipping.
     */
    NBHD_STATUS_EMPTY_INPUT = 4,
    /**
     * The dimension of the points is 0.
     */
    NBHD_STATUS_ZERO_DIMENSION = 5,
    /**
     * The stride between points is smaller than one point (`dim * sizeof(scalar)`).
     */
    NBHD_STATUS_STRIDE_TOO_SMALL = 6,
    /**
     * A caller's buffer is too small; for query results the needed size is in `*count`.
     */
    NBHD_STATUS_BUFFER_TOO_SMALL = 7,
    /**
     * A point has a NaN or infinite coordinate (the message names the point's index and
     * the coordinate).
     */
    NBHD_STATUS_NON_FINITE = 8,
    /**
     * A query point has a NaN or infinite coordinate.
     */
    NBHD_STATUS_NON_FINITE_QUERY = 9,
    /**
     * More points than `uint32_t` indices address (UINT32_MAX at most).
     */
    NBHD_STATUS_TOO_MANY_POINTS = 10,
    /**
     * k is 0.
     */
    NBHD_STATUS_INVALID_K = 11,
    /**
     * The radius is negative, NaN or infinite, or too large for the tree's scalar type: its
     * square must be finite there (for a float tree, at most about 1.8e19; the message gives
     * the value passed and the limit).
     */
    NBHD_STATUS_INVALID_RADIUS = 12,
    /**
     * Query points have a different dimension from the tree.
     */
    NBHD_STATUS_DIMENSION_MISMATCH = 13,
    /**
     * A query by stored index names an index the tree was not given.
     */
    NBHD_STATUS_INDEX_OUT_OF_RANGE = 14,
    /**
     * A query by stored index names a point skipped at build time (non-finite).
     */
    NBHD_STATUS_SKIPPED_POINT = 15,
    /**
     * A field of an options struct (nbhd_*_options) is out of range, an enum field holding
     * no value of its enum included (the message names the option and the value).
     */
    NBHD_STATUS_INVALID_OPTION = 16,
    /**
     * A pool of worker threads could not be created.
     */
    NBHD_STATUS_THREAD_POOL = 17,
    /**
     * The operation was cancelled by the caller.
     */
    NBHD_STATUS_CANCELLED = 18,
    /**
     * A bug in nbhd: a Rust panic was caught at the ABI boundary (the message has its text).
     * The objects passed to the call are unchanged and may still be used and freed.
     */
    NBHD_STATUS_INTERNAL = 19,
    /**
     * Every neighbourhood is degenerate, so the normals (and curvatures) would be
     * meaningless: no neighbourhood reached 3 points (the point and two neighbours), or every
     * normal is flagged degenerate. The usual cause is an ε far below the spacing of the
     * points — for example `epsilon = 0.01` meant as 1 cm but left in the default RELATIVE
     * units (0.01 × the mean spacing). The message gives ε resolved to the points' units and
     * the mean spacing h. Nothing is written.
     */
    NBHD_STATUS_DEGENERATE = 20,
    /**
     * The result does not fit in memory: an allocation whose size comes from the input
     * (a table with very many neighbours, a huge k) failed. The message says how many bytes
     * were needed. Nothing is written and the process is unharmed.
     */
    NBHD_STATUS_OUT_OF_MEMORY = 21,
    /**
     * A file could not be opened, read or written (the message names the file and gives
     * the operating system's reason).
     */
    NBHD_STATUS_IO_ERROR = 22,
    /**
     * The bytes are not a saved tree this library reads: not a saved nbhd tree at all, or one
     * of another format version or byte order (the message names what differs: the file's
     * value and this library's).
     */
    NBHD_STATUS_FORMAT_MISMATCH = 23,
    /**
     * A saved tree is damaged: truncated, followed by other bytes, a checksum that does not
     * match, or a field or node structure that is inconsistent (the message says which).
     */
    NBHD_STATUS_CORRUPT_DATA = 24,
    /**
     * An index passed to a dynamic tree names a point already removed (indices are never
     * reused), or is named twice in one removal.
     */
    NBHD_STATUS_REMOVED_POINT = 25,
    /**
     * A query box has a NaN bound or min > max in some coordinate (boxes are closed,
     * min <= x <= max; infinite bounds are allowed). The message names the box and the
     * coordinate.
     */
    NBHD_STATUS_INVALID_BOX = 26,
    /**
     * A point lies outside the box of a periodic tree (nbhd_tree_build_periodic,
     * nbhd_dynamic_new_periodic): on a periodic axis of size L its coordinate is below 0 or
     * not below L. The message names the point, the coordinate, its value and L.
     */
    NBHD_STATUS_OUTSIDE_PERIOD = 27,
} nbhd_status;

/**
 * Coordinate type of a point buffer, of a tree and of its distances.
 */
typedef enum {
    /**
     * 32-bit IEEE 754 `float`.
     */
    NBHD_SCALAR_TYPE_F32 = 0,
    /**
     * 64-bit IEEE 754 `double`.
     */
    NBHD_SCALAR_TYPE_F64 = 1,
} nbhd_scalar_type;

/**
 * The distance a query measures by (nbhd_query_options.metric): a Minkowski p-norm.
 * Distances come back as the metric's key ("sq_dists"): squared for EUCLIDEAN, the distance
 * itself for MANHATTAN and CHEBYSHEV, sum |x_j - q_j|^p for MINKOWSKI.
 */
typedef enum {
    /**
     * p = 2, the default.
     */
    NBHD_METRIC_EUCLIDEAN = 0,
    /**
     * p = 1: the sum of absolute coordinate differences.
     */
    NBHD_METRIC_MANHATTAN = 1,
    /**
     * p = infinity: the largest absolute coordinate difference.
     */
    NBHD_METRIC_CHEBYSHEV = 2,
    /**
     * Any p >= 1, given in nbhd_query_options.p (1, 2 and infinity take the variants above).
     */
    NBHD_METRIC_MINKOWSKI = 3,
} nbhd_metric;

/**
 * Which neighbourhood a table holds for every row.
 */
typedef enum {
    /**
     * The k nearest points (`k` >= 1).
     */
    NBHD_NEIGHBORHOOD_KIND_KNN = 0,
    /**
     * All points within `radius` (inclusive), sorted by (squared distance, index).
     */
    NBHD_NEIGHBORHOOD_KIND_RADIUS = 1,
    /**
     * The k nearest among the points within `radius` (the epsilon-k-neighbourhood).
     */
    NBHD_NEIGHBORHOOD_KIND_KNN_RADIUS = 2,
} nbhd_neighborhood_kind;

/**
 * Whether a length or curvature option is absolute or relative to the mean spacing `h` of
 * the input (the mean distance of a point to its nearest other point, estimated by nbhd).
 */
typedef enum {
    /**
     * A length in multiples of `h`, a curvature in multiples of `1/h`: the same settings suit
     * a metre and a millimetre scan. The default.
     */
    NBHD_UNITS_RELATIVE = 0,
    /**
     * In the points' own units (a curvature in inverse units).
     */
    NBHD_UNITS_ABSOLUTE = 1,
} nbhd_units;

/**
 * The weights `g_ij` of the smoothing step (thesis eq. 2.30–2.32).
 */
typedef enum {
    /**
     * `g = 1`: isotropic Laplacian fairing (eq. 2.16).
     */
    NBHD_WEIGHTING_ISOTROPIC = 0,
    /**
     * `g_sharp` (eq. 2.31): 1 where the directional curvature `|κ_ij|` is below `lambda`, 0
     * from it on. The default.
     */
    NBHD_WEIGHTING_SHARP = 1,
    /**
     * `g_cont` (eq. 2.32): 1 below `lambda`, `λ²/(λ² + 10(|κ| − λ)²)` from it on.
     */
    NBHD_WEIGHTING_CONTINUOUS = 2,
} nbhd_weighting;

/**
 * Which points are smoothed anisotropically (thesis eq. 2.33–2.35); the others are smoothed
 * isotropically.
 */
typedef enum {
    /**
     * Every point. The default.
     */
    NBHD_FEATURE_CRITERION_ALL_POINTS = 0,
    /**
     * Edge quotient Q (eq. 2.33): `min(|k1|,|k2|) / max(|k1|,|k2|) < feature_threshold`.
     */
    NBHD_FEATURE_CRITERION_EDGE_QUOTIENT = 1,
    /**
     * Principal curvature K (eq. 2.34): `max(|k1|,|k2|) > feature_threshold`.
     */
    NBHD_FEATURE_CRITERION_PRINCIPAL_CURVATURE = 2,
    /**
     * Directional curvature D (eq. 2.35): some neighbour has `|κ_ij| > feature_threshold`.
     */
    NBHD_FEATURE_CRITERION_DIRECTIONAL_CURVATURE = 3,
} nbhd_feature_criterion;

/**
 * How the sign-free covariance normals are oriented in the outputs.
 */
typedef enum {
    /**
     * The eigen-solver's sign: arbitrary but deterministic. The default.
     */
    NBHD_ORIENTATION_UNORIENTED = 0,
    /**
     * Every normal points toward `orientation_point` (a scanner's viewpoint).
     */
    NBHD_ORIENTATION_TOWARD_POINT = 1,
    /**
     * Every normal points away from `orientation_point` (outward for star-shaped surfaces).
     */
    NBHD_ORIENTATION_AWAY_FROM_POINT = 2,
    /**
     * One consistent orientation spread over the neighbour graph along smooth paths
     * (Hoppe et al. 1992); in each connected part the highest point's normal has `z >= 0`.
     */
    NBHD_ORIENTATION_PROPAGATE = 3,
} nbhd_orientation;

/**
 * What a smoothing run is doing when it calls the progress callback.
 */
typedef enum {
    /**
     * Neighbourhood search and the spacing estimate.
     */
    NBHD_STAGE_NEIGHBORS = 0,
    /**
     * Normals and curvatures of a step.
     */
    NBHD_STAGE_GEOMETRY = 1,
    /**
     * Moving the points.
     */
    NBHD_STAGE_STEP = 2,
    /**
     * Per-point geometry of the result.
     */
    NBHD_STAGE_OUTPUTS = 3,
    /**
     * Finished (fraction 1).
     */
    NBHD_STAGE_DONE = 4,
} nbhd_stage;

/**
 * A k-d tree that accepts insertions and removals (opaque); see nbhd_dynamic_create.
 *
 * Index rule: the points of each inserted batch get consecutive indices continuing from the
 * previous batch (the first batch gets 0, 1, ...); a point keeps its index until it is
 * removed, and a removed index is never given again (queries and removals naming it fail
 * with NBHD_STATUS_REMOVED_POINT). Every query answers exactly what a static tree
 * (nbhd_tree_build) over the live points, under these indices, answers.
 *
 * Thread safety: any number of threads may query one dynamic tree at once, but
 * nbhd_dynamic_insert and nbhd_dynamic_remove must not run at the same time as any other
 * call on the same tree.
 */
typedef struct nbhd_dynamic_tree nbhd_dynamic_tree;

/**
 * A table of neighbourhoods (opaque): row i holds the neighbours of point i (or of query i),
 * ordered by (squared distance, index). Made by nbhd_tree_neighborhoods or
 * nbhd_tree_neighborhoods_of (or their nbhd_dynamic_* twins), freed by
 * nbhd_neighborhoods_free. It does not refer to the
 * tree: either may be freed first. Immutable: any number of threads may read it at once.
 */
typedef struct nbhd_neighborhoods nbhd_neighborhoods;

/**
 * A built k-d tree (opaque). It holds its own copy of the points, in the scalar type of the
 * points it was built from, and is immutable: any number of threads may query one tree at
 * once. Made by nbhd_tree_build or nbhd_tree_load(_from_buffer), freed by nbhd_tree_free.
 */
typedef struct nbhd_tree nbhd_tree;

/**
 * Everything that shapes a tree. Start from nbhd_build_options_default() and change fields.
 */
typedef struct {
    /**
     * Pivot policy. Default: NBHD_PIVOT_POLICY_SLIDING_MIDPOINT.
     */
    nbhd_pivot_policy pivot;
    /**
     * Median algorithm. Default: NBHD_MEDIAN_ALGORITHM_FLOYD_RIVEST.
     */
    nbhd_median_algorithm median;
    /**
     * Most points in a leaf, 1 to UINT32_MAX. Default: 12.
     */
    size_t leaf_size;
    /**
     * Reject or skip points with NaN or infinite coordinates. Default: reject.
     */
    nbhd_non_finite_policy non_finite;
    /**
     * Worker threads of the build: 0 uses a shared pool with one thread per core, 1 builds
     * on the calling thread, n > 1 uses a pool of n threads made for this call; more than
     * NBHD_MAX_THREADS is NBHD_STATUS_INVALID_OPTION. The tree is identical for every value.
     * Default: 0.
     */
    size_t threads;
} nbhd_build_options;

/**
 * Describes `count` points of dimension `dim` in a caller's buffer, read in place (the tree
 * copies what it needs; the buffer may be freed once nbhd_tree_build returns).
 *
 * Point i starts at byte `i * stride` from `data`; its coordinates are `dim` consecutive
 * values of `scalar_type`. So a packed `float xyz[n][3]` is `{xyz, n, 3, 0, NBHD_SCALAR_TYPE_F32}`
 * and PCL's `PointXYZ` (x, y, z, padding) is `{cloud, n, 3, 16, NBHD_SCALAR_TYPE_F32}`.
 * `data` needs no particular alignment (coordinates are read byte-wise).
 */
typedef struct {
    /**
     * First byte of point 0. Must not be NULL, except for no point (`count` 0).
     */
    const void *data;
    /**
     * Number of points, 0 to 4294967295 (UINT32_MAX): indices are `uint32_t`. No point is a
     * valid set: a tree over it finds nothing, a batch of no query gives a table of no row
     * (functions that need points, such as smoothing, refuse it with EMPTY_INPUT).
     */
    size_t count;
    /**
     * Coordinates per point, at least 1.
     */
    size_t dim;
    /**
     * Bytes from one point to the next, at least `dim * sizeof(scalar)`; 0 means tightly
     * packed (`dim * sizeof(scalar)`).
     */
    size_t stride;
    /**
     * Type of every coordinate. A tree built from these points computes in this type.
     */
    nbhd_scalar_type scalar_type;
} nbhd_points;

/**
 * Shape and memory of a built tree (filled by nbhd_tree_stats).
 */
typedef struct {
    /**
     * Points held (points skipped as non-finite not counted).
     */
    size_t points;
    /**
     * Points the caller passed in, skipped ones included: the range of valid indices and the
     * number of rows of nbhd_tree_neighborhoods.
     */
    size_t source_points;
    /**
     * Dimension.
     */
    size_t dim;
    /**
     * Edges on the longest root-to-leaf path (a single leaf has depth 0).
     */
    size_t depth;
    /**
     * Internal nodes plus leaves.
     */
    size_t nodes;
    /**
     * Leaves.
     */
    size_t leaves;
    /**
     * Most points in one leaf.
     */
    size_t max_leaf_points;
    /**
     * Bytes of coordinates, index map and nodes held by the tree.
     */
    size_t bytes;
    /**
     * Coordinate type of the tree: the type of query coordinates and of squared distances.
     */
    nbhd_scalar_type scalar_type;
} nbhd_stats;

/**
 * One node of a tree, as nbhd_tree_nodes lists them: in preorder (a node, its left subtree,
 * its right subtree; the root at position 0). A split sends coordinates `<= split` left and
 * `>= split` right, so points equal to the split value may lie on both sides; identical
 * points are split by index like any others, so every leaf holds at most the build's
 * `leaf_size` points.
 */
typedef struct {
    /**
     * Edges from the root (the root is level 0).
     */
    size_t level;
    /**
     * An internal node's splitting dimension; 0 for a leaf.
     */
    size_t split_dim;
    /**
     * An internal node's splitting value, as a double whatever the tree's scalar type; 0 for
     * a leaf.
     */
    double split;
    /**
     * The node's points are the tree positions `start .. end - 1`: entries of
     * nbhd_tree_order, which names their caller indices.
     */
    size_t start;
    /**
     * One past the node's last tree position.
     */
    size_t end;
    /**
     * An internal node's children: their positions in the list (`left` is the node's own
     * position plus one); 0 for a leaf (the root, position 0, is no node's child).
     */
    size_t left;
    /**
     * See `left`.
     */
    size_t right;
    /**
     * Whether the node is a leaf.
     */
    bool leaf;
} nbhd_node;

/**
 * How a query measures (nbhd_tree_search, nbhd_dynamic_search, nbhd_table_options.query).
 * Start from nbhd_query_options_default(); all fields zero are the defaults too.
 */
typedef struct {
    /**
     * The distance: a Minkowski p-norm. Results carry its key (see nbhd_metric) and a radius
     * is a distance in it. Default: NBHD_METRIC_EUCLIDEAN.
     */
    nbhd_metric metric;
    /**
     * The p of NBHD_METRIC_MINKOWSKI, in [1, infinity] (read for that metric only; NaN or
     * below 1 is NBHD_STATUS_INVALID_OPTION). Default: 2.
     */
    double p;
    /**
     * Approximation, finite and >= 0 (else NBHD_STATUS_INVALID_OPTION): 0 is exact; eps > 0
     * returns k nearest whose i-th distance is at most (1 + eps) times the true i-th, and
     * for a radius r every point within r / (1 + eps) and none beyond r * (1 + eps), pruning
     * harder (scipy's cKDTree rule). Default: 0.
     */
    double eps;
    /**
     * A radius is exclusive (|x - q| < r, scipy's distance_upper_bound) instead of inclusive;
     * a radius too large for the tree's scalar type is then no bound. Default: false.
     */
    bool strict;
} nbhd_query_options;

/**
 * Which neighbourhood nbhd_tree_neighborhoods computes for every row.
 */
typedef struct {
    /**
     * k nearest, all within a radius, or k nearest within a radius.
     */
    nbhd_neighborhood_kind kind;
    /**
     * Number of neighbours (>= 1) for NBHD_NEIGHBORHOOD_KIND_KNN and _KNN_RADIUS; ignored
     * for _RADIUS. A k larger than the number of points gives all of them.
     */
    size_t k;
    /**
     * Plain (not squared) radius, finite and >= 0, inclusive (Euclidean unless query options
     * name another metric, and exclusive under their `strict`), for _RADIUS and
     * _KNN_RADIUS; ignored for _KNN. Converted to the tree's scalar type.
     */
    double radius;
} nbhd_neighborhood_spec;

/**
 * Options of nbhd_tree_in_boxes. Start from nbhd_box_options_default() and change fields.
 */
typedef struct {
    /**
     * Worker threads: 0 uses a shared pool with one thread per core, n >= 1 a pool of n
     * threads; more than NBHD_MAX_THREADS is NBHD_STATUS_INVALID_OPTION. The rows are the
     * same for every value. Default: 0.
     */
    size_t threads;
} nbhd_box_options;

/**
 * Options of nbhd_tree_spacing. Start from nbhd_spacing_options_default() and change fields.
 */
typedef struct {
    /**
     * Worker threads: 0 uses a shared pool with one thread per core, n >= 1 a pool of n
     * threads; more than NBHD_MAX_THREADS is NBHD_STATUS_INVALID_OPTION. The spacing is the
     * same for every value. Default: 0.
     */
    size_t threads;
} nbhd_spacing_options;

/**
 * The nearest-neighbour spacing of a point set: the distance of each point to its nearest
 * other point, summarised. `mean` is the h of every relative length (epsilon = 6 h).
 */
typedef struct {
    /**
     * Mean nearest-neighbour distance h, summed in index order.
     */
    double mean;
    /**
     * Median nearest-neighbour distance (the mean of the middle two for an even count).
     */
    double median;
    /**
     * Number of points the distances were taken over (the tree's points).
     */
    size_t points;
} nbhd_spacing;

/**
 * Options of nbhd_remove_statistical_outliers. Start from
 * nbhd_statistical_outlier_options_default() and change fields.
 */
typedef struct {
    /**
     * Number of nearest *other* points whose distances are averaged, >= 1 and below the
     * number of points (PCL's setMeanK, Open3D's nb_neighbors). Default: 50.
     */
    size_t k;
    /**
     * A point is kept when its mean distance is at most mean + std_ratio * s (PCL's
     * setStddevMulThresh, Open3D's std_ratio); finite, may be negative. Default: 1.
     */
    double std_ratio;
    /**
     * Worker threads: 0 uses a shared pool with one thread per core, n >= 1 a pool of n
     * threads; more than NBHD_MAX_THREADS is NBHD_STATUS_INVALID_OPTION. The result is the
     * same for every value. Default: 0.
     */
    size_t threads;
} nbhd_statistical_outlier_options;

/**
 * Options of nbhd_remove_radius_outliers (the radius is an argument of its own, as in
 * nbhd_tree_radius). Start from nbhd_radius_outlier_options_default() and change fields.
 */
typedef struct {
    /**
     * A point is kept when at least this many *other* points lie within the radius. PCL's
     * setMinNeighborsInRadius(m) is the same m (its count includes the point itself and keeps
     * counts > m). 0 keeps every point the tree holds. Default: 2.
     */
    size_t min_neighbors;
    /**
     * Worker threads, as in nbhd_statistical_outlier_options. Default: 0.
     */
    size_t threads;
} nbhd_radius_outlier_options;

/**
 * Options of nbhd_voxel_grid (the leaf sizes are arguments of their own). Start from
 * nbhd_voxel_grid_options_default() and change fields.
 */
typedef struct {
    /**
     * Voxels with fewer points are left out (PCL's setMinimumPointsNumberPerVoxel; 0 and 1
     * keep every occupied voxel). Default: 0.
     */
    size_t min_points_per_voxel;
    /**
     * Worker threads, as in nbhd_statistical_outlier_options. Default: 0.
     */
    size_t threads;
} nbhd_voxel_grid_options;

/**
 * Options of nbhd_tree_neighborhoods. Start from nbhd_table_options_default().
 */
typedef struct {
    /**
     * Leave each point out of its own row (its duplicates at distance 0 stay). Applies to
     * nbhd_tree_neighborhoods only. Default: true.
     */
    bool exclude_self;
    /**
     * Worker threads: 0 uses a shared pool with one thread per core, n >= 1 a pool of n
     * threads made for this call; more than NBHD_MAX_THREADS is NBHD_STATUS_INVALID_OPTION.
     * The table is identical for every value. Default: 0.
     */
    size_t threads;
    /**
     * How every row's query measures (metric, eps, strict radius). Default:
     * nbhd_query_options_default(); all zero (as `{true, 2}` leaves it) is the same.
     */
    nbhd_query_options query;
} nbhd_table_options;

/**
 * Size and shape of a dynamic tree.
 */
typedef struct {
    /**
     * Live points.
     */
    size_t live;
    /**
     * Indices given so far (live, removed and skipped points): the index the next inserted
     * point gets, and the number of rows of nbhd_dynamic_neighborhoods.
     */
    size_t next_index;
    /**
     * Static trees in the forest.
     */
    size_t trees;
    /**
     * Removed points still held by the trees (skipped by every query).
     */
    size_t removed_held;
    /**
     * Dimension.
     */
    size_t dim;
    /**
     * The tree's scalar type: of query coordinates and of squared distances.
     */
    nbhd_scalar_type scalar_type;
} nbhd_dynamic_stats;

/**
 * Weights of the points of the two trees of nbhd_tree_weigh_pairs: `tree_weights[i]` for the
 * point with index i of the first tree (`tree_count` values, one per index given to its
 * build or insert), `other_weights[j]` for the second. A NULL array weighs every point 1
 * (its count is then ignored).
 */
typedef struct {
    /**
     * Weights of the first tree's points, or NULL.
     */
    const double *tree_weights;
    /**
     * Number of values at `tree_weights`.
     */
    size_t tree_count;
    /**
     * Weights of the second tree's points, or NULL.
     */
    const double *other_weights;
    /**
     * Number of values at `other_weights`.
     */
    size_t other_count;
} nbhd_pair_weights;

/**
 * A progress callback: `fraction` grows from 0 to 1 over the run; return `true` to go on,
 * `false` to stop the run, which then returns NBHD_STATUS_CANCELLED and writes no output.
 * It is called from the thread that runs the computation (the calling thread when
 * `threads` is 0, otherwise a worker of the call's own pool), never from two threads at
 * once, and must return normally (no longjmp, no C++ exception).
 */
typedef bool (*nbhd_progress_fn)(double fraction, nbhd_stage stage, void *user_data);

/**
 * Options of nbhd_smooth and nbhd_estimate_curvatures (nbhd_estimate_normals has its own,
 * nbhd_normal_options). Start from nbhd_smooth_options_default() and change what you need.
 *
 * UNITS: `epsilon`, `lambda` and a curvature `feature_threshold` are RELATIVE by default —
 * multiples of the mean spacing h of the points (or of 1/h) — not lengths in the points'
 * units. `epsilon = 0.01` means 0.01 h, far below any neighbour, and is refused with
 * NBHD_STATUS_DEGENERATE; for 1 cm in metre coordinates set `epsilon = 0.01` AND
 * `epsilon_units = NBHD_UNITS_ABSOLUTE`. nbhd_smooth_summary reports h and ε resolved.
 *
 * Neighbourhoods are the thesis' ε-k-neighbourhoods (Section 2.1.1): the `k` nearest other
 * points within `epsilon`, computed once on the input and cached (Section 2.1.3) unless
 * `update_neighbors` is set. One step moves every point at once by
 * `p_i += tau * (1/|N_i|) Σ_j g_ij (x_j − p_i)` (eq. 2.16, 2.18, 2.30).
 */
typedef struct {
    /**
     * Maximum valence k (>= 1). Default 15.
     */
    size_t k;
    /**
     * Influence radius ε (> 0), plain (not squared), inclusive. Default 6 (relative: 6h).
     */
    double epsilon;
    /**
     * Units of `epsilon`. Default relative.
     */
    nbhd_units epsilon_units;
    /**
     * Number of smoothing steps (0 only analyses). Default 3.
     */
    size_t steps;
    /**
     * Step size τ = λ·∂t of eq. 2.18 (finite, >= 0). Default 0.5.
     */
    double tau;
    /**
     * The weights g_ij. Default NBHD_WEIGHTING_SHARP.
     */
    nbhd_weighting weighting;
    /**
     * Curvature threshold λ of g_sharp / g_cont (> 0). Default 0.2 (relative: 0.2/h).
     */
    double lambda;
    /**
     * Units of `lambda`. Default relative.
     */
    nbhd_units lambda_units;
    /**
     * Which points are smoothed anisotropically. Default all points.
     */
    nbhd_feature_criterion feature;
    /**
     * Threshold of the feature criterion: the quotient Q (a plain number) for
     * EDGE_QUOTIENT, a curvature for PRINCIPAL_CURVATURE and DIRECTIONAL_CURVATURE.
     * Ignored for ALL_POINTS. Default 0.5.
     */
    double feature_threshold;
    /**
     * Units of a curvature `feature_threshold`. Default relative.
     */
    nbhd_units feature_units;
    /**
     * 'Constrain interior' (thesis Section 7.3): points whose covariance quotient
     * λ0/(λ0 + λ1 + λ2) is below `interior_threshold` are held fixed. Default false.
     */
    bool constrain_interior;
    /**
     * The covariance-quotient threshold of `constrain_interior` (finite). Default 0.01.
     */
    double interior_threshold;
    /**
     * 'Update Neighbors' (Section 7.3): recompute the neighbourhoods before every step.
     * Default false.
     */
    bool update_neighbors;
    /**
     * Orientation of the normals written to the outputs (smoothing itself uses |κ| and does
     * not depend on it). Default unoriented.
     */
    nbhd_orientation orientation;
    /**
     * The point of NBHD_ORIENTATION_TOWARD_POINT / _AWAY_FROM_POINT (finite). Default
     * (0, 0, 0).
     */
    double orientation_point[3];
    /**
     * Worker threads: 0 the shared pool with a thread per core, n >= 1 a pool of n threads
     * made for this call (at most NBHD_MAX_THREADS, else NBHD_STATUS_INVALID_OPTION). Results
     * are identical for every value. Default 0.
     */
    size_t threads;
    /**
     * Called with the progress of the run; NULL for none. Default NULL.
     */
    nbhd_progress_fn progress;
    /**
     * Passed to `progress` unchanged. Default NULL.
     */
    void *progress_user_data;
    /**
     * Points with a NaN or infinite coordinate (the holes of organized scans), as in
     * nbhd_build_options: REJECT (the default) refuses the input with NON_FINITE; SKIP
     * computes on the finite points only, and a skipped point keeps its index, is left
     * unmoved (its coordinates are copied to `out_coords` as they are) and gets NaN geometry
     * with `normal_flags` 8. Default REJECT.
     */
    nbhd_non_finite_policy non_finite;
} nbhd_smooth_options;

/**
 * The per-point geometry the thesis' program colours by (Section 7.3), on the final points.
 * Curvatures are signed relative to the reported normal.
 */
typedef struct {
    /**
     * Unit normal (eq. 2.10), oriented as the options ask.
     */
    double normal[3];
    /**
     * Larger principal curvature k1 (Weingarten estimate, eq. 2.25–2.29).
     */
    double k1;
    /**
     * Smaller principal curvature k2.
     */
    double k2;
    /**
     * Unit principal direction of k1.
     */
    double dir1[3];
    /**
     * Unit principal direction of k2.
     */
    double dir2[3];
    /**
     * 'Mean': (k1 + k2) / 2.
     */
    double mean_curvature;
    /**
     * 'Max Princ': max(|k1|, |k2|).
     */
    double max_principal_curvature;
    /**
     * 'CovQuotient': λ0/(λ0 + λ1 + λ2) of the covariance (0 flat, at most 1/3).
     */
    double covariance_quotient;
    /**
     * 'MeanAni': Σ g κ / Σ g over the neighbours, with the chosen weights (0 if all vanish).
     */
    double anisotropic_mean_curvature;
    /**
     * 'PrincQuotient': min(|k1|,|k2|) / max(|k1|,|k2|) in [0, 1].
     */
    double principal_curvature_quotient;
    /**
     * 'MaxCov': the largest covariance eigenvalue over the neighbourhood size.
     */
    double max_covariance;
    /**
     * Why the normal is not to be trusted, 0 if it is: 1 fewer than 3 points, 2 collinear or
     * coincident points, 4 the normal is not unique (isotropic neighbourhood), 8 the point
     * was skipped for a NaN or infinite coordinate (everything else is NaN then).
     */
    uint8_t normal_flags;
    /**
     * Whether the feature criterion selects the point.
     */
    bool feature;
    /**
     * Whether 'constrain interior' holds the point fixed.
     */
    bool interior;
} nbhd_point_geometry;

/**
 * Scalars a run resolved: the spacing estimate and the absolute thresholds it used.
 */
typedef struct {
    /**
     * Mean nearest-neighbour spacing h of the input.
     */
    double spacing;
    /**
     * The absolute ε used.
     */
    double epsilon;
    /**
     * The absolute λ used.
     */
    double lambda;
    /**
     * 'Min Neighbors': the smallest neighbourhood size |N_i| of the input.
     */
    size_t min_neighbors;
} nbhd_smooth_summary;

/**
 * Options of nbhd_estimate_normals. Start from nbhd_normal_options_default() and change
 * what you need.
 *
 * The neighbourhood of a point is the thesis' ε-k-neighbourhood (Section 2.1.1): its `k`
 * nearest other points within `epsilon`; the normal is the eigenvector of the smallest
 * eigenvalue of the covariance of the point and its neighbourhood (eq. 2.8–2.10), as PCL's
 * NormalEstimation computes it.
 *
 * UNITS: `epsilon` is RELATIVE by default — a multiple of the mean spacing h of the points
 * (the mean distance of a point to its nearest other point), NOT a length in the points'
 * units. The default `epsilon = 6` means 6 h. For a radius in the points' units (say 1 cm in
 * metre coordinates) set BOTH `epsilon = 0.01` and `epsilon_units = NBHD_UNITS_ABSOLUTE`;
 * a relative `epsilon = 0.01` (0.01 h, below any neighbour) is refused with
 * NBHD_STATUS_DEGENERATE, whose message gives ε resolved to the points' units.
 */
typedef struct {
    /**
     * Maximum valence k (>= 1): at most the k nearest other points. Default 15.
     */
    size_t k;
    /**
     * Influence radius ε (> 0), plain (not squared), inclusive; in `epsilon_units`.
     * Default 6 (relative: 6 h).
     */
    double epsilon;
    /**
     * Units of `epsilon`: NBHD_UNITS_RELATIVE (multiples of h, the default) or
     * NBHD_UNITS_ABSOLUTE (the points' own units).
     */
    nbhd_units epsilon_units;
    /**
     * Orientation of the normals. Default unoriented. NBHD_ORIENTATION_TOWARD_POINT with the
     * sensor position is PCL's flipNormalTowardsViewpoint: dot(viewpoint − p, n) >= 0.
     */
    nbhd_orientation orientation;
    /**
     * The point of NBHD_ORIENTATION_TOWARD_POINT / _AWAY_FROM_POINT (finite). Default
     * (0, 0, 0).
     */
    double orientation_point[3];
    /**
     * Points with a NaN or infinite coordinate: REJECT (the default) refuses the input with
     * NON_FINITE; SKIP leaves them out — they keep their index and get a NaN normal (and
     * curvature) and flag 8.
     */
    nbhd_non_finite_policy non_finite;
    /**
     * Worker threads: 0 the shared pool, n >= 1 a pool of n threads made for this call (at
     * most NBHD_MAX_THREADS, else NBHD_STATUS_INVALID_OPTION). Results are identical for
     * every value. Default 0.
     */
    size_t threads;
    /**
     * Called with the progress of the run; NULL for none. Default NULL.
     */
    nbhd_progress_fn progress;
    /**
     * Passed to `progress` unchanged. Default NULL.
     */
    void *progress_user_data;
} nbhd_normal_options;

/**
 * Where nbhd_estimate_normals writes, in the caller's layout: point i's normal (x, y, z) at
 * byte `i * normals_stride` from `normals`, its curvature at byte `i * curvature_stride`
 * from `curvature`, all of `scalar_type`; only these values are written, other bytes of a
 * strided layout are left alone. Strides of 0 mean packed (3 values, 1 value).
 *
 * For `pcl::PointCloud<pcl::Normal> cloud` (float normal_x/y/z, then curvature, 32 bytes):
 * `{&cloud[0].normal_x, sizeof(pcl::Normal), NBHD_SCALAR_TYPE_F32, &cloud[0].curvature,
 * sizeof(pcl::Normal), NULL}`; for `pcl::PointNormal` use `&cloud[0].normal_x`,
 * `&cloud[0].curvature` and `sizeof(pcl::PointNormal)`.
 */
typedef struct {
    /**
     * First byte of point 0's normal. Must not be NULL.
     */
    void *normals;
    /**
     * Bytes from one point's normal to the next: 0 (packed) or at least 3 values.
     */
    size_t normals_stride;
    /**
     * Type of every value written (normals and curvature).
     */
    nbhd_scalar_type scalar_type;
    /**
     * First byte of point 0's curvature, or NULL for none. The curvature is PCL's: the
     * surface variation λ0 / (λ0 + λ1 + λ2) of the covariance eigenvalues (0 on a plane, at
     * most 1/3), as pcl::NormalEstimation writes to `curvature`.
     */
    void *curvature;
    /**
     * Bytes from one point's curvature to the next: 0 (packed) or at least one value.
     */
    size_t curvature_stride;
    /**
     * `points->count` bytes (packed), or NULL: 0 for a well-defined normal, otherwise the
     * bits of nbhd_point_geometry.normal_flags (8: the point was skipped).
     */
    uint8_t *flags;
} nbhd_normals_output;

/**
 * Options of nbhd_smooth_robust. Start from nbhd_robust_options_default(); the defaults are
 * one setting meant for every shape and noise level (all thresholds are multiples of the
 * estimated noise or dimensionless).
 */
typedef struct {
    /**
     * Size k of the umbrella neighbourhood (>= 1). Default 24.
     */
    size_t k;
    /**
     * Size of the wider neighbourhood the candidate planes are fitted and scored on
     * (>= k). Default 48.
     */
    size_t k_plane;
    /**
     * Influence radius ε (> 0) that cuts both neighbourhoods. Default 12 (relative: 12h).
     */
    double epsilon;
    /**
     * Units of `epsilon`. Default relative.
     */
    nbhd_units epsilon_units;
    /**
     * Upper bound on the number of iterations. Default 10.
     */
    size_t max_iterations;
    /**
     * Stopping rule: stop once an iteration lowered the noise estimate by less than this
     * fraction (finite, >= 0; 0 runs max_iterations unless the estimate rises). Default 0.05.
     */
    double tolerance;
    /**
     * Width of the biweight of plane distances, in units of the estimated noise (> 0).
     * Default 5.
     */
    double inlier_width;
    /**
     * Angle in degrees at which a neighbour counts as across a feature (> 0). Default 20.
     */
    double feature_angle;
    /**
     * Step size τ in (0, 1]. Default 1.
     */
    double tau;
    /**
     * Orientation of the normals written to the outputs. Default unoriented.
     */
    nbhd_orientation orientation;
    /**
     * The point of NBHD_ORIENTATION_TOWARD_POINT / _AWAY_FROM_POINT (finite). Default
     * (0, 0, 0).
     */
    double orientation_point[3];
    /**
     * Worker threads: 0 the shared pool, n >= 1 a pool of n threads for this call (at most
     * NBHD_MAX_THREADS, else NBHD_STATUS_INVALID_OPTION). Results are identical for every
     * value. Default 0.
     */
    size_t threads;
    /**
     * Called with the progress of the run; NULL for none. Default NULL.
     */
    nbhd_progress_fn progress;
    /**
     * Passed to `progress` unchanged. Default NULL.
     */
    void *progress_user_data;
    /**
     * Points with a NaN or infinite coordinate: REJECT (the default) or SKIP (left unmoved,
     * NaN geometry with `normal_flags` 8), as nbhd_smooth_options.non_finite.
     */
    nbhd_non_finite_policy non_finite;
    /**
     * Scale from the noise: while the cloud's neighbourhoods read as balls of noise (noise of
     * about two spacings or more), iterate with k and k_plane tripled. Clouds with noise up to
     * about 1.5 spacings are smoothed as without it. Default true.
     */
    bool noise_scale;
} nbhd_robust_options;

#ifdef __cplusplus
extern "C" {
#endif // __cplusplus

/**
 * The version of the library that is linked, as `MAJOR * 1000000 + MINOR * 1000 + PATCH`
 * (compare with `NBHD_VERSION` from the header you compiled against).
 */
uint32_t nbhd_version(void);

/**
 * The version of the library that is linked, as a string such as "0.1.0". The string is
 * static: never free it.
 */
const char *nbhd_version_string(void);

/**
 * A static, human-readable description of a status code, such as "k must be at least 1".
 * Never NULL, never to be freed. Any value is answered safely: one that is no nbhd_status
 * (a status of a later release, `(nbhd_status)-1`) gives "unknown status".
 */
const char *nbhd_status_string(nbhd_status status);

/**
 * The reason the last failed nbhd call on the calling thread failed, in words that name the
 * argument, option or point index at fault, e.g. "nbhd_tree_build: point 7 has a NaN or
 * infinite coordinate (coordinate 2)"; "" if the last status-returning call on this thread
 * succeeded or none was made. Never NULL. Each thread has its own message.
 *
 * The string belongs to nbhd: do not free it. It stays valid until the next nbhd call on the
 * same thread; copy it to keep it.
 */
const char *nbhd_last_error_message(void);

/**
 * The default build options: sliding-midpoint pivots, Floyd-Rivest selection, leaf size 12,
 * non-finite points rejected, the shared thread pool.
 */
nbhd_build_options nbhd_build_options_default(void);

/**
 * Builds a k-d tree over `*points` and stores a new handle in `*out_tree`.
 *
 * The tree computes in `points->scalar_type` and keeps its own copy of the points, so the
 * point buffer may be changed or freed as soon as this returns. `options` may be NULL
 * for the defaults. On any error `*out_tree` is set to NULL (if `out_tree` is not NULL) and
 * nothing needs freeing. No point (count 0, or every point skipped) gives a tree of no
 * point: its queries find nothing and its tables have empty rows.
 *
 * Errors: NULL_POINTER (`points`, `points->data` with a count above 0, `out_tree`),
 * MISALIGNED_POINTER, INVALID_ARGUMENT (`points->scalar_type` not a value of the enum;
 * `points->dim * sizeof (scalar)` or `(count - 1) * stride` overflowing the address space —
 * the message gives the values passed), ZERO_DIMENSION,
 * STRIDE_TOO_SMALL (a stride below one point, with both sizes), TOO_MANY_POINTS, NON_FINITE
 * (the message names the first point and coordinate), INVALID_OPTION (leaf size 0, an enum
 * field out of range), THREAD_POOL. No other status is returned.
 *
 * Ownership: the caller owns `*out_tree` and frees it with nbhd_tree_free.
 *
 * # Safety
 * `points` must describe readable memory (see nbhd_points); `options` must be NULL or point
 * to an nbhd_build_options; `out_tree` must be writable.
 */
nbhd_status nbhd_tree_build(const nbhd_points *points,
                            const nbhd_build_options *options,
                            nbhd_tree **out_tree);

/**
 * Builds a k-d tree over the points `indices[0 .. index_count]` of `*points` only, as PCL's
 * `setInputCloud(cloud, indices)`, and stores a new handle in `*out_tree`. The point buffer
 * is read in place (only the listed points are copied into the tree), and every result names
 * the point's index in `*points`, as for nbhd_tree_build: the tree answers exactly as
 * nbhd_tree_build over the listed points would, in the caller's indices. The order of
 * `indices` does not matter.
 *
 * Queries by index (nbhd_tree_knn_index, ...) take an index of `*points`; one that is not
 * listed fails with SKIPPED_POINT, as a skipped non-finite point does.
 * nbhd_tree_neighborhoods gives a row for every point of `*points` (row i for index i,
 * `nbhd_stats.source_points` = `points->count` rows): the listed points' neighbourhoods among
 * the listed points, and empty rows for the others.
 *
 * Errors: those of nbhd_tree_build (NON_FINITE names the first listed non-finite point unless
 * `options->non_finite` skips them; an `index_count` of 0 gives a tree of no point), plus
 * NULL_POINTER / MISALIGNED_POINTER (`indices`), INDEX_OUT_OF_RANGE (the
 * message names the first index >= `points->count`) and INVALID_ARGUMENT (an index listed
 * twice, named in the message).
 *
 * Ownership: the caller owns `*out_tree` and frees it with nbhd_tree_free; `indices` and
 * the point buffer may be freed once this returns.
 *
 * # Safety
 * As nbhd_tree_build; `indices` must be NULL or point to `index_count` readable uint32_t
 * (NULL is accepted for an `index_count` of 0).
 */
nbhd_status nbhd_tree_build_indices(const nbhd_points *points,
                                    const uint32_t *indices,
                                    size_t index_count,
                                    const nbhd_build_options *options,
                                    nbhd_tree **out_tree);

/**
 * Frees a tree made by nbhd_tree_build(_indices) or nbhd_tree_load(_from_buffer). NULL is
 * ignored. The tree must not be in use by another thread, and must not be used after this call.
 *
 * # Safety
 * `tree` must be NULL or a handle from nbhd_tree_build or nbhd_tree_load(_from_buffer) not
 * freed before.
 */
void nbhd_tree_free(nbhd_tree *tree);

/**
 * Writes the shape and memory of `tree` to `*out_stats`, including its scalar type (the
 * type of query coordinates and of squared distances) and `source_points` (the range of
 * valid indices).
 *
 * Errors: NULL_POINTER, MISALIGNED_POINTER.
 *
 * # Safety
 * `tree` must be NULL or a live handle from nbhd_tree_build; `out_stats` must be NULL or
 * writable.
 */
nbhd_status nbhd_tree_stats(const nbhd_tree *tree, nbhd_stats *out_stats);

/**
 * Copies the coordinates the tree holds for the point with index `index` (an index of the
 * points given to nbhd_tree_build) to `out_coords`: `dim` values of the tree's scalar type
 * (nbhd_stats.scalar_type). A wrapper that answers "around point i" through the index path
 * (nbhd_tree_knn_index, ...) compares them with the caller's current coordinates first, so
 * that a point moved since the build is searched where it is now (as nbhd_pcl.hpp does).
 *
 * Errors: NULL_POINTER (`tree`, `out_coords`), MISALIGNED_POINTER, INDEX_OUT_OF_RANGE
 * (`index` >= nbhd_stats.source_points), SKIPPED_POINT (a point skipped at build time, or
 * not listed to nbhd_tree_build_indices). Nothing is written on an error.
 *
 * # Safety
 * `tree` must be NULL or a live handle; `out_coords` NULL or writable for `dim` values of the
 * tree's scalar type.
 */
nbhd_status nbhd_tree_point(const nbhd_tree *tree, size_t index, void *out_coords);

/**
 * Copies the tree's nodes in preorder into `nodes`: `*count` of them, nbhd_stats.nodes
 * (a tree of no point is one empty leaf). If `capacity` is smaller, nothing is written to
 * `nodes`, `*count` receives the number needed and the status is
 * NBHD_STATUS_BUFFER_TOO_SMALL; `nodes` may be NULL with capacity 0 to ask for the size.
 *
 * Errors: NULL_POINTER (`tree`, `count`, `nodes` when needed), MISALIGNED_POINTER,
 * BUFFER_TOO_SMALL, OUT_OF_MEMORY. On any other error `*count` is 0.
 *
 * # Safety
 * `tree` must be NULL or a live handle; `nodes` NULL or writable for `capacity` structs;
 * `count` NULL or writable.
 */
nbhd_status nbhd_tree_nodes(const nbhd_tree *tree,
                            nbhd_node *nodes,
                            size_t capacity,
                            size_t *count);

/**
 * Copies the caller indices of the tree's points in tree order into `indices`: `*count` of
 * them, nbhd_stats.points (the points of a node, nbhd_node's `start .. end - 1`, are
 * adjacent; skipped points are absent). Too small a `capacity` is BUFFER_TOO_SMALL with the
 * size needed in `*count`, as for nbhd_tree_nodes.
 *
 * Errors: NULL_POINTER (`tree`, `count`, `indices` when needed), MISALIGNED_POINTER,
 * BUFFER_TOO_SMALL. On any other error `*count` is 0.
 *
 * # Safety
 * `tree` must be NULL or a live handle; `indices` NULL or writable for `capacity` values;
 * `count` NULL or writable.
 */
nbhd_status nbhd_tree_order(const nbhd_tree *tree,
                            uint32_t *indices,
                            size_t capacity,
                            size_t *count);

/**
 * The sum of `weights` over each node's points, in the order of nbhd_tree_nodes (scipy's
 * `_build_weights`), into `sums`: `*count` values, nbhd_stats.nodes. `weights` holds one
 * finite value per point given to the build (`weight_count` = nbhd_stats.source_points,
 * skipped points included and never counted). A leaf sums its points in tree order, an
 * internal node adds its left child's sum and its right child's, so the values are the same
 * bits on every run. Too small a `capacity` is BUFFER_TOO_SMALL with the size needed in
 * `*count`, as for nbhd_tree_nodes.
 *
 * Errors: NULL_POINTER (`tree`, `count`, `weights` with a count above 0, `sums` when
 * needed), MISALIGNED_POINTER, INVALID_ARGUMENT (`weight_count` overflowing the address
 * space), INVALID_OPTION (`weight_count` other than nbhd_stats.source_points, a NaN or
 * infinite weight: the message names the point), BUFFER_TOO_SMALL, OUT_OF_MEMORY. On any
 * other error `*count` is 0 and nothing is written.
 *
 * # Safety
 * `tree` must be NULL or a live handle; `weights` NULL or readable for `weight_count`
 * values; `sums` NULL or writable for `capacity` values; `count` NULL or writable.
 */
nbhd_status nbhd_tree_node_weights(const nbhd_tree *tree,
                                   const double *weights,
                                   size_t weight_count,
                                   double *sums,
                                   size_t capacity,
                                   size_t *count);

/**
 * Writes `tree` to the file `path` (created, or truncated if it exists) in the saved-tree
 * format (docs/tree-file-format.md): a versioned header with checksums, then the tree as
 * built. nbhd_tree_load reads it back into a tree that answers every query exactly as
 * `tree` does.
 *
 * Errors: NULL_POINTER (`tree`, `path`), MISALIGNED_POINTER, INVALID_ARGUMENT (an empty
 * `path`; off Unix, a `path` that is not UTF-8), IO_ERROR (the file cannot be created or
 * written; the message names it and gives the system's reason).
 *
 * # Safety
 * `tree` must be NULL or a live handle; `path` NULL or a NUL-terminated string.
 */
nbhd_status nbhd_tree_save(const nbhd_tree *tree, const char *path);

/**
 * Writes `tree` in the saved-tree format into the caller's `buffer` of `capacity` bytes, and
 * the number of bytes the saved tree takes to `*size` — also when the buffer is too small, so
 * a first call with `capacity` 0 (and `buffer` NULL) asks for the size. The bytes are those
 * nbhd_tree_save writes to a file; nbhd_tree_load_from_buffer reads them.
 *
 * Errors: NULL_POINTER (`tree`, `size`, or `buffer` when `capacity` is large enough),
 * MISALIGNED_POINTER, BUFFER_TOO_SMALL (`capacity` < `*size`; nothing is written to
 * `buffer`).
 *
 * # Safety
 * `tree` must be NULL or a live handle; `buffer` NULL or writable for `capacity` bytes;
 * `size` NULL or writable.
 */
nbhd_status nbhd_tree_save_to_buffer(const nbhd_tree *tree,
                                     void *buffer,
                                     size_t capacity,
                                     size_t *size);

/**
 * Loads the tree saved in the file `path` (by nbhd_tree_save or nbhd_tree_save_to_buffer,
 * by any nbhd that writes format version 1) and stores a new handle in `*out_tree`. The tree
 * has the scalar type it was saved with (nbhd_tree_stats tells it) and answers every query
 * exactly as the saved tree did.
 *
 * Nothing in the file is trusted: the header and data are checked (magic, byte order, format
 * version, checksums, every field, the node structure) before a tree is handed out, so a
 * damaged or crafted file is refused, never answered wrong. On any error `*out_tree` is set
 * to NULL (if `out_tree` is not NULL).
 *
 * Errors: NULL_POINTER (`path`, `out_tree`), MISALIGNED_POINTER, INVALID_ARGUMENT (an empty
 * `path`; off Unix, not UTF-8), IO_ERROR (the file cannot be read; the message names it),
 * FORMAT_MISMATCH (not a saved nbhd tree, or one of another format version or byte order: the
 * message names the file's value and this library's), CORRUPT_DATA (truncated, followed by
 * other bytes, a checksum that does not match, an inconsistent field or node structure: the
 * message says which).
 *
 * Ownership: the caller owns `*out_tree` and frees it with nbhd_tree_free.
 *
 * # Safety
 * `path` must be NULL or a NUL-terminated string; `out_tree` NULL or writable.
 */
nbhd_status nbhd_tree_load(const char *path, nbhd_tree **out_tree);

/**
 * Loads the tree saved in the `size` bytes at `data` (as nbhd_tree_save_to_buffer wrote
 * them, or read from a file nbhd_tree_save wrote) and stores a new handle in `*out_tree`. The
 * bytes are copied: `data` may be freed as soon as this returns. Checks and errors as
 * nbhd_tree_load, without IO_ERROR: NULL_POINTER (`data`, `out_tree`), MISALIGNED_POINTER,
 * INVALID_ARGUMENT (`size` above PTRDIFF_MAX), FORMAT_MISMATCH, CORRUPT_DATA. On any error
 * `*out_tree` is set to NULL (if `out_tree` is not NULL).
 *
 * Ownership: the caller owns `*out_tree` and frees it with nbhd_tree_free.
 *
 * # Safety
 * `data` must be NULL or readable for `size` bytes, not written during the call; `out_tree`
 * NULL or writable.
 */
nbhd_status nbhd_tree_load_from_buffer(const void *data, size_t size, nbhd_tree **out_tree);

/**
 * Writes the dynamic tree `tree` to the file `path` (created, or truncated if it exists) in
 * the saved dynamic-tree format (docs/tree-file-format.md, "Dynamic trees"): a versioned
 * header with checksums, the index bitmaps, the kept coordinates and every static tree of the
 * forest as built. nbhd_dynamic_load reads it back into a dynamic tree that answers every
 * query exactly as `tree` does and grows and shrinks the same way.
 *
 * Errors: NULL_POINTER (`tree`, `path`), MISALIGNED_POINTER, INVALID_ARGUMENT (an empty
 * `path`; off Unix, a `path` that is not UTF-8), IO_ERROR (the file cannot be created or
 * written; the message names it and gives the system's reason).
 *
 * # Safety
 * `tree` must be NULL or a live handle not being changed by another thread; `path` NULL or a
 * NUL-terminated string.
 */
nbhd_status nbhd_dynamic_save(const nbhd_dynamic_tree *tree, const char *path);

/**
 * Writes `tree` in the saved dynamic-tree format into the caller's `buffer` of `capacity`
 * bytes, and the number of bytes it takes to `*size` — also when the buffer is too small, so
 * a first call with `capacity` 0 (and `buffer` NULL) asks for the size. The bytes are those
 * nbhd_dynamic_save writes; nbhd_dynamic_load_from_buffer reads them.
 *
 * Errors: NULL_POINTER (`tree`, `size`, or `buffer` when `capacity` is large enough),
 * MISALIGNED_POINTER, BUFFER_TOO_SMALL (`capacity` < `*size`; nothing is written to
 * `buffer`).
 *
 * # Safety
 * `tree` must be NULL or a live handle not being changed by another thread; `buffer` NULL or
 * writable for `capacity` bytes; `size` NULL or writable.
 */
nbhd_status nbhd_dynamic_save_to_buffer(const nbhd_dynamic_tree *tree,
                                        void *buffer,
                                        size_t capacity,
                                        size_t *size);

/**
 * Loads the dynamic tree saved in the file `path` (by nbhd_dynamic_save or
 * nbhd_dynamic_save_to_buffer) and stores a new handle in `*out_tree`. The tree has the
 * scalar type it was saved with (nbhd_dynamic_tree_stats tells it), answers every query
 * exactly as the saved one did, and continues its indices where the saved one stopped.
 *
 * Nothing in the file is trusted: the header, every static tree and what spans them (index
 * ranges, bitmaps, kept coordinates, live count; a dimension whose point would not fit in
 * memory) are checked before a tree is handed out, and the thread count the file states is
 * not obeyed: the loaded tree builds on the shared pool (0) until nbhd_dynamic_set_threads.
 * On any error `*out_tree` is set to NULL (if `out_tree` is not NULL).
 *
 * Errors: NULL_POINTER (`path`, `out_tree`), MISALIGNED_POINTER, INVALID_ARGUMENT (an empty
 * `path`; off Unix, not UTF-8), IO_ERROR (the file cannot be read; the message names it),
 * FORMAT_MISMATCH (not a saved nbhd tree, a saved *static* tree, or one of another format
 * version or byte order: the message names the file's value and this library's),
 * CORRUPT_DATA (truncated, followed by other bytes, a checksum that does not match, an
 * inconsistent field, static tree or cross-tree fact: the message says which).
 *
 * Ownership: the caller owns `*out_tree` and frees it with nbhd_dynamic_free.
 *
 * # Safety
 * `path` must be NULL or a NUL-terminated string; `out_tree` NULL or writable.
 */
nbhd_status nbhd_dynamic_load(const char *path, nbhd_dynamic_tree **out_tree);

/**
 * Loads the dynamic tree saved in the `size` bytes at `data` (as
 * nbhd_dynamic_save_to_buffer wrote them) and stores a new handle in `*out_tree`. The bytes
 * are copied: `data` may be freed as soon as this returns. Checks and errors as
 * nbhd_dynamic_load, without IO_ERROR: NULL_POINTER (`data`, `out_tree`),
 * MISALIGNED_POINTER, INVALID_ARGUMENT (`size` above PTRDIFF_MAX), FORMAT_MISMATCH,
 * CORRUPT_DATA. On any error `*out_tree` is set to NULL (if `out_tree` is not NULL).
 *
 * Ownership: the caller owns `*out_tree` and frees it with nbhd_dynamic_free.
 *
 * # Safety
 * `data` must be NULL or readable for `size` bytes, not written during the call; `out_tree`
 * NULL or writable.
 */
nbhd_status nbhd_dynamic_load_from_buffer(const void *data,
                                          size_t size,
                                          nbhd_dynamic_tree **out_tree);

/**
 * The `k` points of the tree nearest to the point `query`.
 *
 * - `query`: `dim` coordinates in the tree's scalar type (`float` for a tree built from
 *   NBHD_SCALAR_TYPE_F32 points, `double` for F64; see nbhd_stats.scalar_type), aligned for
 *   that type.
 * - `k` >= 1; a k larger than the number of points gives all of them.
 * - Results: `*count` neighbours, nearest first, ordered by (squared distance, index), so ties
 *   are deterministic. `indices` receives the caller's point indices (uint32_t); `sq_dists`,
 *   if not NULL, the squared Euclidean distances, in the tree's scalar type. Both buffers
 *   hold `capacity` values; a capacity of `k` always suffices.
 * - If the result has more than `capacity` neighbours, nothing is written to the buffers,
 *   `*count` receives the number needed and the status is NBHD_STATUS_BUFFER_TOO_SMALL: call
 *   again with buffers that large. `indices` may be NULL when `capacity` is 0, to ask for the
 *   size.
 * - On any other error `*count` is 0.
 *
 * Errors: NULL_POINTER (`tree`, `query`, `count`, `indices` with a capacity > 0),
 * MISALIGNED_POINTER, NON_FINITE_QUERY, INVALID_K (k = 0), BUFFER_TOO_SMALL.
 *
 * Thread safety: any number of threads may query one tree at once.
 *
 * # Safety
 * `tree` must be NULL or a live handle; `query` NULL or `dim` readable values of the tree's
 * scalar type; `indices` and `sq_dists` NULL or writable for `capacity` values each (of
 * uint32_t and of the tree's scalar type); `count` NULL or writable.
 */
nbhd_status nbhd_tree_knn(const nbhd_tree *tree,
                          const void *query,
                          size_t k,
                          uint32_t *indices,
                          void *sq_dists,
                          size_t capacity,
                          size_t *count);

/**
 * All points of the tree within `radius` of the point `query`: `|x - q| <= radius`, with a
 * plain (not squared) radius, finite and >= 0, converted to the tree's scalar type. Results
 * are ordered by (squared distance, index). Their number is not known in advance: if
 * `capacity` is too small, `*count` receives the size needed and the status is
 * NBHD_STATUS_BUFFER_TOO_SMALL. Arguments, results and errors otherwise as nbhd_tree_knn,
 * with INVALID_RADIUS for a negative, NaN or infinite radius.
 *
 * # Safety
 * As nbhd_tree_knn.
 */
nbhd_status nbhd_tree_radius(const nbhd_tree *tree,
                             const void *query,
                             double radius,
                             uint32_t *indices,
                             void *sq_dists,
                             size_t capacity,
                             size_t *count);

/**
 * The epsilon-k-neighbourhood of the point `query`: the `k` nearest among the points within
 * `radius` (plain radius, inclusive). At most `k` results, so a capacity of `k` suffices.
 * Arguments, results and errors as nbhd_tree_knn and nbhd_tree_radius.
 *
 * # Safety
 * As nbhd_tree_knn.
 */
nbhd_status nbhd_tree_knn_radius(const nbhd_tree *tree,
                                 const void *query,
                                 size_t k,
                                 double radius,
                                 uint32_t *indices,
                                 void *sq_dists,
                                 size_t capacity,
                                 size_t *count);

/**
 * The `k` nearest neighbours of the stored point with the caller's index `index` (its index
 * in the points given to nbhd_tree_build). With `exclude_self` the point itself is left out
 * (its duplicates at distance 0 stay), so k = 3 gives its 3 nearest other points. Results
 * and buffers as nbhd_tree_knn.
 *
 * Errors: as nbhd_tree_knn, plus INDEX_OUT_OF_RANGE (`index` >= the number of points given)
 * and SKIPPED_POINT (the point was skipped at build time as non-finite).
 *
 * # Safety
 * As nbhd_tree_knn (there is no `query` pointer).
 */
nbhd_status nbhd_tree_knn_index(const nbhd_tree *tree,
                                size_t index,
                                bool exclude_self,
                                size_t k,
                                uint32_t *indices,
                                void *sq_dists,
                                size_t capacity,
                                size_t *count);

/**
 * All points within `radius` of the stored point `index`, optionally without the point
 * itself. Results and buffers as nbhd_tree_radius; errors as nbhd_tree_knn_index.
 *
 * # Safety
 * As nbhd_tree_knn (there is no `query` pointer).
 */
nbhd_status nbhd_tree_radius_index(const nbhd_tree *tree,
                                   size_t index,
                                   bool exclude_self,
                                   double radius,
                                   uint32_t *indices,
                                   void *sq_dists,
                                   size_t capacity,
                                   size_t *count);

/**
 * The k nearest within `radius` of the stored point `index`, optionally without the point
 * itself. Results and buffers as nbhd_tree_knn_radius; errors as nbhd_tree_knn_index.
 *
 * # Safety
 * As nbhd_tree_knn (there is no `query` pointer).
 */
nbhd_status nbhd_tree_knn_radius_index(const nbhd_tree *tree,
                                       size_t index,
                                       bool exclude_self,
                                       size_t k,
                                       double radius,
                                       uint32_t *indices,
                                       void *sq_dists,
                                       size_t capacity,
                                       size_t *count);

/**
 * The default query options: the exact Euclidean metric, an inclusive radius.
 */
nbhd_query_options nbhd_query_options_default(void);

/**
 * The neighbourhood `*spec` (k nearest, within a radius, or the k nearest within a radius)
 * of the point `query` under `*options` (NULL: the defaults, which answer as nbhd_tree_knn,
 * nbhd_tree_radius and nbhd_tree_knn_radius): any Minkowski metric, an approximate search, a
 * strict radius. The radius is a distance in the metric; `sq_dists` receives each
 * neighbour's key in the metric (squared for Euclidean, the distance for Manhattan and
 * Chebyshev, sum |x_j - q_j|^p for Minkowski p; see nbhd_metric), in the tree's scalar type;
 * results are ordered by (key, index). Arguments, buffers and results otherwise as
 * nbhd_tree_knn.
 *
 * Errors: those of nbhd_tree_knn and nbhd_tree_radius; NULL_POINTER for `spec`;
 * INVALID_OPTION for a metric out of range, a Minkowski p below 1 or NaN, a negative or
 * non-finite eps; INVALID_RADIUS also for a radius whose key overflows the tree's scalar type
 * (not under `strict`).
 *
 * # Safety
 * As nbhd_tree_knn; `spec` NULL or a readable nbhd_neighborhood_spec; `options` NULL or a
 * readable nbhd_query_options.
 */
nbhd_status nbhd_tree_search(const nbhd_tree *tree,
                             const void *query,
                             const nbhd_neighborhood_spec *spec,
                             const nbhd_query_options *options,
                             uint32_t *indices,
                             void *sq_dists,
                             size_t capacity,
                             size_t *count);

/**
 * All points of the tree inside the closed axis-aligned box `min[j] <= x[j] <= max[j]`
 * (every coordinate j).
 *
 * - `min`, `max`: `dim` values each in the tree's scalar type (`float` for a tree built from
 *   NBHD_SCALAR_TYPE_F32 points, `double` for F64), aligned for it. Bounds may be infinite
 *   (a slab, a half-space); min = max in a coordinate is a valid, zero-extent box.
 * - Results: `*count` caller indices (uint32_t) ascending, in `indices` (`capacity` values).
 *   If more than `capacity` points are inside, nothing is written to `indices`, `*count`
 *   receives the number needed and the status is NBHD_STATUS_BUFFER_TOO_SMALL; `indices` may
 *   be NULL with capacity 0 to ask for the size. Points skipped at build time are never
 *   inside. On any other error `*count` is 0.
 *
 * Errors: NULL_POINTER (`tree`, `min`, `max`, `count`, `indices` when needed),
 * MISALIGNED_POINTER, INVALID_BOX (a NaN bound, or min > max in some coordinate: an inverted
 * box is refused, not taken as empty), BUFFER_TOO_SMALL.
 *
 * Thread safety: any number of threads may query one tree at once.
 *
 * # Safety
 * `tree` must be NULL or a live handle; `min` and `max` NULL or `dim` readable values of the
 * tree's scalar type; `indices` NULL or writable for `capacity` values; `count` NULL or
 * writable.
 */
nbhd_status nbhd_tree_in_box(const nbhd_tree *tree,
                             const void *min,
                             const void *max,
                             uint32_t *indices,
                             size_t capacity,
                             size_t *count);

/**
 * All live points of the growing tree inside the closed box `min[j] <= x[j] <= max[j]`; as
 * nbhd_tree_in_box (removed points are never inside).
 *
 * # Safety
 * As nbhd_tree_in_box, with `tree` a live dynamic tree not being changed by another thread.
 */
nbhd_status nbhd_dynamic_in_box(const nbhd_dynamic_tree *tree,
                                const void *min,
                                const void *max,
                                uint32_t *indices,
                                size_t capacity,
                                size_t *count);

/**
 * The default box options: the shared thread pool.
 */
nbhd_box_options nbhd_box_options_default(void);

/**
 * The points inside each box of a batch, computed in parallel; rows in the boxes' order,
 * identical for any thread count.
 *
 * - `boxes`: `n_boxes * 2 * dim` values in the tree's scalar type: box i is its `min`
 *   corner (`dim` values) then its `max` corner. Closed boxes, as nbhd_tree_in_box.
 * - `options`: NULL for the defaults (the shared thread pool).
 * - `offsets`: `n_boxes + 1` values (size_t); row i is `indices[offsets[i] .. offsets[i + 1]]`,
 *   the caller indices inside box i, ascending.
 * - `indices`: `capacity` values; `*total` receives the number of indices over all rows.
 *   If `capacity` is smaller, nothing is written to `offsets` or `indices` and the status is
 *   NBHD_STATUS_BUFFER_TOO_SMALL: call again with `*total` values (`indices` may be NULL
 *   with capacity 0 to ask for the size). On any other error `*total` is 0.
 *
 * Errors: NULL_POINTER (`tree`, `boxes` when n_boxes > 0, `offsets`, `total`, `indices`
 * when needed), MISALIGNED_POINTER, INVALID_BOX (the message names the box), INVALID_OPTION
 * (threads), INVALID_ARGUMENT (n_boxes * 2 * dim overflows), BUFFER_TOO_SMALL, OUT_OF_MEMORY.
 *
 * # Safety
 * `tree` must be NULL or a live handle; `boxes` NULL or `n_boxes * 2 * dim` readable values
 * of the tree's scalar type; `options` NULL or readable; `offsets` NULL or writable for
 * `n_boxes + 1` values; `indices` NULL or writable for `capacity` values; `total` NULL or
 * writable.
 */
nbhd_status nbhd_tree_in_boxes(const nbhd_tree *tree,
                               const void *boxes,
                               size_t n_boxes,
                               const nbhd_box_options *options,
                               size_t *offsets,
                               uint32_t *indices,
                               size_t capacity,
                               size_t *total);

/**
 * The live points of the growing tree inside each box of a batch; as nbhd_tree_in_boxes.
 *
 * # Safety
 * As nbhd_tree_in_boxes, with `tree` a live dynamic tree not being changed by another thread.
 */
nbhd_status nbhd_dynamic_in_boxes(const nbhd_dynamic_tree *tree,
                                  const void *boxes,
                                  size_t n_boxes,
                                  const nbhd_box_options *options,
                                  size_t *offsets,
                                  uint32_t *indices,
                                  size_t capacity,
                                  size_t *total);

/**
 * The default spacing options: the shared thread pool.
 */
nbhd_spacing_options nbhd_spacing_options_default(void);

/**
 * The nearest-neighbour spacing of the tree's points, computed on `options->threads` workers
 * (`options` NULL for the defaults); the same value for any thread count. Points skipped at
 * build time are left out.
 *
 * Errors: NULL_POINTER (`tree`, `out`), MISALIGNED_POINTER, INVALID_OPTION (fewer than two
 * points in the tree, or threads above NBHD_MAX_THREADS). On error `*out` is all zero.
 *
 * # Safety
 * `tree` must be NULL or a live handle; `options` NULL or readable; `out` NULL or writable.
 */
nbhd_status nbhd_tree_spacing(const nbhd_tree *tree,
                              const nbhd_spacing_options *options,
                              nbhd_spacing *out);

/**
 * The spacing of the growing tree's live points; as nbhd_tree_spacing.
 *
 * # Safety
 * As nbhd_tree_spacing, with `tree` a live dynamic tree not being changed by another thread.
 */
nbhd_status nbhd_dynamic_spacing(const nbhd_dynamic_tree *tree,
                                 const nbhd_spacing_options *options,
                                 nbhd_spacing *out);

/**
 * The default statistical outlier options: PCL's tutorial values k = 50, std_ratio = 1,
 * the shared thread pool.
 */
nbhd_statistical_outlier_options nbhd_statistical_outlier_options_default(void);

/**
 * Statistical outlier removal (PCL's StatisticalOutlierRemoval, Open3D's
 * remove_statistical_outlier): for each point its mean distance d_i to its `options->k`
 * nearest other points (PCL's setMeanK(k): PCL searches k + 1 and skips the point itself);
 * over all points the mean m and the sample standard deviation s (n - 1 in the denominator,
 * as PCL); a point is kept when d_i <= m + std_ratio * s. `options` may be NULL for the
 * defaults. Points skipped at build time are never kept and take no part in m and s (PCL 1.13
 * keeps NaN points in its output).
 *
 * - `kept`: `capacity` values (uint32_t); receives the caller indices of the kept points,
 *   ascending, `*count` of them. The number of points given to nbhd_tree_build always
 *   suffices; with less, `*count` receives the number needed and the status is
 *   NBHD_STATUS_BUFFER_TOO_SMALL (nothing written; `kept` may be NULL with capacity 0).
 * - `mask`: NULL, or one byte per point given to nbhd_tree_build: 1 kept, 0 removed.
 *
 * Errors: NULL_POINTER (`tree`, `count`, `kept` when needed), MISALIGNED_POINTER, INVALID_K
 * (k = 0), INVALID_OPTION (k >= the number of points, std_ratio NaN or infinite, threads),
 * BUFFER_TOO_SMALL, OUT_OF_MEMORY. On error `*count` is 0 except for BUFFER_TOO_SMALL.
 *
 * # Safety
 * `tree` must be NULL or a live handle; `options` NULL or readable; `kept` NULL or writable
 * for `capacity` values; `count` NULL or writable; `mask` NULL or writable for the number of
 * points given.
 */
nbhd_status nbhd_remove_statistical_outliers(const nbhd_tree *tree,
                                             const nbhd_statistical_outlier_options *options,
                                             uint32_t *kept,
                                             size_t capacity,
                                             size_t *count,
                                             uint8_t *mask);

/**
 * Statistical outlier removal over the live points of a growing tree: the points kept are
 * those the static tree built on the live points keeps (nbhd_remove_statistical_outliers),
 * `k` must be below the number of live points, and m and s are taken over the live points.
 *
 * - `kept`: the caller indices of the kept live points, ascending (`*count` of them); the
 *   number of live points always suffices as `capacity`.
 * - `mask`: NULL, or one byte per index given so far (nbhd_dynamic_tree_stats' `next_index`
 *   bytes): 1 for a kept point, 0 for a removed outlier and for every index not live
 *   (removed with nbhd_dynamic_remove or skipped as non-finite when inserted).
 *
 * Errors as nbhd_remove_statistical_outliers (INVALID_OPTION for k >= the live points).
 *
 * # Safety
 * As nbhd_remove_statistical_outliers, with `tree` a live dynamic tree not being changed by
 * another thread and `mask` NULL or writable for `next_index` bytes.
 */
nbhd_status nbhd_dynamic_remove_statistical_outliers(const nbhd_dynamic_tree *tree,
                                                     const nbhd_statistical_outlier_options *options,
                                                     uint32_t *kept,
                                                     size_t capacity,
                                                     size_t *count,
                                                     uint8_t *mask);

/**
 * The default radius outlier options: at least 2 other points within the radius, the shared
 * thread pool.
 */
nbhd_radius_outlier_options nbhd_radius_outlier_options_default(void);

/**
 * Radius outlier removal (PCL's RadiusOutlierRemoval, Open3D's remove_radius_outlier): a
 * point is kept when at least `options->min_neighbors` other points lie within `radius`
 * (plain Euclidean, inclusive: |x - p| <= radius). `options` may be NULL for the defaults.
 * Points skipped at build time are never kept. Results as nbhd_remove_statistical_outliers.
 *
 * Errors: NULL_POINTER, MISALIGNED_POINTER, INVALID_RADIUS (negative, NaN, infinite, or too
 * large for the tree's type), INVALID_OPTION (threads), BUFFER_TOO_SMALL, OUT_OF_MEMORY.
 *
 * # Safety
 * As nbhd_remove_statistical_outliers.
 */
nbhd_status nbhd_remove_radius_outliers(const nbhd_tree *tree,
                                        double radius,
                                        const nbhd_radius_outlier_options *options,
                                        uint32_t *kept,
                                        size_t capacity,
                                        size_t *count,
                                        uint8_t *mask);

/**
 * Radius outlier removal over the live points of a growing tree: the points kept are those
 * the static tree built on the live points keeps (nbhd_remove_radius_outliers); removed
 * points are not counted as neighbours. `kept` and `mask` as in
 * nbhd_dynamic_remove_statistical_outliers (the mask has `next_index` bytes, 0 for every
 * index not live).
 *
 * Errors as nbhd_remove_radius_outliers.
 *
 * # Safety
 * As nbhd_dynamic_remove_statistical_outliers.
 */
nbhd_status nbhd_dynamic_remove_radius_outliers(const nbhd_dynamic_tree *tree,
                                                double radius,
                                                const nbhd_radius_outlier_options *options,
                                                uint32_t *kept,
                                                size_t capacity,
                                                size_t *count,
                                                uint8_t *mask);

/**
 * The default voxel-grid options: every occupied voxel kept, the shared thread pool.
 */
nbhd_voxel_grid_options nbhd_voxel_grid_options_default(void);

/**
 * Voxel-grid downsampling (PCL's VoxelGrid, Open3D's voxel_down_sample) of the points
 * `*points` (no tree needed): the occupied voxels of the finite points, in ascending linear
 * voxel index (x fastest), each with its centroid and the index of its point nearest the
 * centroid (ties by the smaller index: an original point, whose attributes the caller keeps).
 * The arithmetic is PCL 1.13's in the points' scalar type: float points give PCL's voxels
 * exactly (centroids summed in ascending index; PCL's order within a voxel is not defined).
 *
 * - `leaf`: `leaf_count` edge lengths, 1 (a cube) or `points->dim`; each finite and > 0.
 * - `options`: NULL for the defaults (every occupied voxel, the shared pool).
 * - `centroids`: NULL, or `capacity * points->dim` doubles: voxel v's centroid at
 *   `centroids[v * dim ..]` (float values converted exactly).
 * - `nearest`: NULL, or `capacity` uint32_t: voxel v's point nearest its centroid.
 * - `*count` receives the number of voxels. The number of points always suffices as
 *   capacity; with less, the status is NBHD_STATUS_BUFFER_TOO_SMALL, `*count` the number
 *   needed, nothing written.
 *
 * Errors: NULL_POINTER (`points`, `leaf`, `count`), MISALIGNED_POINTER, the point-buffer
 * statuses of nbhd_tree_build, INVALID_OPTION (a leaf NaN, <= 0 or infinite, a leaf count
 * other than 1 or dim, a leaf so small for the points' extent that a voxel number passes the
 * exact integers of the type — 2^24 for float — or the box holds more than 2^64 voxels;
 * threads above NBHD_MAX_THREADS), BUFFER_TOO_SMALL, OUT_OF_MEMORY. On error `*count` is 0
 * except for BUFFER_TOO_SMALL.
 *
 * # Safety
 * `points` NULL or a readable description of readable memory; `leaf` NULL or readable for
 * `leaf_count` values; `options` NULL or readable; `centroids`, `nearest` NULL or writable as
 * described; `count` NULL or writable.
 */
nbhd_status nbhd_voxel_grid(const nbhd_points *points,
                            const double *leaf,
                            size_t leaf_count,
                            const nbhd_voxel_grid_options *options,
                            double *centroids,
                            uint32_t *nearest,
                            size_t capacity,
                            size_t *count);

/**
 * The default table options: each point left out of its own row, the shared thread pool.
 */
nbhd_table_options nbhd_table_options_default(void);

/**
 * The neighbourhood `*spec` of every point of `tree`, computed in parallel, as a new table in
 * `*out_table`. Row i belongs to the point with index i in the points given to
 * nbhd_tree_build (so there are nbhd_stats.source_points rows; points skipped at build time
 * get empty rows). `options` may be NULL for the defaults (each point left out of its own
 * row). The table is identical for any number of threads.
 *
 * On any error `*out_table` is set to NULL (if `out_table` is not NULL).
 *
 * Errors: NULL_POINTER (`tree`, `spec`, `out_table`), MISALIGNED_POINTER, INVALID_ARGUMENT
 * (`spec->kind` out of range), INVALID_K, INVALID_RADIUS (also a radius whose square
 * overflows the tree's type, e.g. 1e20 on a float tree; the message gives the value passed),
 * OUT_OF_MEMORY (the table does not fit: a radius covering every point of a large set, k =
 * SIZE_MAX with KNN; the message gives the bytes needed — a KNN table's size is checked
 * before any search), THREAD_POOL.
 *
 * Ownership: the caller owns `*out_table` and frees it with nbhd_neighborhoods_free.
 *
 * # Safety
 * `tree` must be NULL or a live handle; `spec` and `options` NULL or readable; `out_table`
 * NULL or writable.
 */
nbhd_status nbhd_tree_neighborhoods(const nbhd_tree *tree,
                                    const nbhd_neighborhood_spec *spec,
                                    const nbhd_table_options *options,
                                    nbhd_neighborhoods **out_table);

/**
 * The neighbourhood `*spec` of each point of `*queries` in `tree`, computed in parallel, as
 * a new table in `*out_table`: row i belongs to query point i. The query points may be of
 * either scalar type (they are converted to the tree's) but must have the tree's dimension;
 * none may be NaN or infinite. `options` may be NULL; its `exclude_self` does not apply
 * (queries are not stored points). No query (`queries->count` 0) gives a table of no row.
 *
 * On any error `*out_table` is set to NULL (if `out_table` is not NULL).
 *
 * Errors: as nbhd_tree_neighborhoods, plus those of a points description (see
 * nbhd_tree_build), DIMENSION_MISMATCH and NON_FINITE_QUERY (the message names the query's
 * index and coordinate).
 *
 * Ownership: the caller owns `*out_table` and frees it with nbhd_neighborhoods_free.
 *
 * # Safety
 * As nbhd_tree_neighborhoods; `queries` must be NULL or describe readable memory (see
 * nbhd_points).
 */
nbhd_status nbhd_tree_neighborhoods_of(const nbhd_tree *tree,
                                       const nbhd_points *queries,
                                       const nbhd_neighborhood_spec *spec,
                                       const nbhd_table_options *options,
                                       nbhd_neighborhoods **out_table);

/**
 * Frees a table. NULL is ignored. Pointers obtained from its accessors become invalid.
 *
 * # Safety
 * `table` must be NULL or a handle from nbhd_tree_neighborhoods(_of) not freed before.
 */
void nbhd_neighborhoods_free(nbhd_neighborhoods *table);

/**
 * Number of rows (0 for NULL).
 *
 * # Safety
 * `table` must be NULL or a live handle.
 */
size_t nbhd_neighborhoods_rows(const nbhd_neighborhoods *table);

/**
 * Total number of neighbours over all rows: the length of the indices and squared-distance
 * arrays (0 for NULL).
 *
 * # Safety
 * `table` must be NULL or a live handle.
 */
size_t nbhd_neighborhoods_total(const nbhd_neighborhoods *table);

/**
 * The row boundaries: `rows + 1` values, starting at 0, non-decreasing, ending at `total`;
 * row i is `offsets[i] .. offsets[i + 1]` of the indices and squared distances. NULL for a
 * NULL table. The array belongs to the table and lives until nbhd_neighborhoods_free.
 *
 * # Safety
 * `table` must be NULL or a live handle.
 */
const size_t *nbhd_neighborhoods_offsets(const nbhd_neighborhoods *table);

/**
 * The caller's indices of all neighbours, row after row (`total` values). NULL for a NULL
 * table; when `total` is 0 the pointer is not NULL but must not be read. The array belongs
 * to the table and lives until nbhd_neighborhoods_free.
 *
 * # Safety
 * `table` must be NULL or a live handle.
 */
const uint32_t *nbhd_neighborhoods_indices(const nbhd_neighborhoods *table);

/**
 * The squared distances of all neighbours, row after row (`total` values), parallel to the
 * indices, in the scalar type of the tree the table was computed with (`const float*` or
 * `const double*`). NULL for a NULL table; when `total` is 0 the pointer is not NULL but must
 * not be read. The array belongs to the table and lives until nbhd_neighborhoods_free.
 *
 * # Safety
 * `table` must be NULL or a live handle.
 */
const void *nbhd_neighborhoods_sq_dists(const nbhd_neighborhoods *table);

/**
 * One row: `*indices` and `*sq_dists` receive pointers to its first neighbour inside the
 * table's arrays and `*len` its length (0 for an empty row, with pointers not to be read).
 * `sq_dists` may be NULL if the distances are not wanted. The pointers live until
 * nbhd_neighborhoods_free.
 *
 * Errors: NULL_POINTER (`table`, `indices`, `len`), MISALIGNED_POINTER, INVALID_ARGUMENT
 * (`row` >= the number of rows); on error `*len` is 0 and the pointers NULL.
 *
 * # Safety
 * `table` must be NULL or a live handle; `indices`, `sq_dists` and `len` NULL or writable.
 */
nbhd_status nbhd_neighborhoods_row(const nbhd_neighborhoods *table,
                                   size_t row,
                                   const uint32_t **indices,
                                   const void **sq_dists,
                                   size_t *len);

/**
 * Makes an empty dynamic tree of dimension `dim` computing in `scalar_type` (an
 * nbhd_scalar_type value) and stores the handle in `*out_tree`. `options` (NULL for the
 * defaults) shape every static tree of the forest; its `non_finite` decides what inserting a
 * NaN or infinite point does: REJECT refuses the batch, SKIP gives the point its index but
 * leaves it out (queries naming it fail with NBHD_STATUS_SKIPPED_POINT).
 *
 * Errors: NULL_POINTER (`out_tree`), MISALIGNED_POINTER, ZERO_DIMENSION, INVALID_ARGUMENT
 * (`scalar_type` not a value of nbhd_scalar_type; `dim * sizeof(scalar)` overflowing the
 * address space, as nbhd_tree_build refuses such points), INVALID_OPTION. On error
 * `*out_tree` is NULL.
 *
 * Ownership: the caller frees `*out_tree` with nbhd_dynamic_free.
 *
 * # Safety
 * `options` must be NULL or point to an nbhd_build_options; `out_tree` NULL or writable.
 */
nbhd_status nbhd_dynamic_create(size_t dim,
                                nbhd_scalar_type scalar_type,
                                const nbhd_build_options *options,
                                nbhd_dynamic_tree **out_tree);

/**
 * Inserts the points `*points` (of either scalar type, converted to the tree's; of the
 * tree's dimension) as one batch. `*out_first` (may be NULL) receives the index of the
 * first: the batch gets `first .. first + points->count - 1`, in order. The point buffer
 * may be freed as soon as this returns (the tree copies the points). A batch of no point
 * inserts nothing (`*out_first` receives the next index).
 *
 * Errors, with nothing inserted: NULL_POINTER (`tree`, `points`, `points->data` with a
 * count above 0), MISALIGNED_POINTER, the errors of a points description (see
 * nbhd_tree_build: INVALID_ARGUMENT, STRIDE_TOO_SMALL, TOO_MANY_POINTS), DIMENSION_MISMATCH,
 * NON_FINITE (with options.non_finite REJECT; the message names the point's position in the
 * batch), TOO_MANY_POINTS (indices would pass UINT32_MAX - 1 over the tree's life),
 * OUT_OF_MEMORY, THREAD_POOL.
 *
 * # Safety
 * `tree` must be NULL or a live handle not in use by another thread; `points` NULL or a
 * true description of readable memory; `out_first` NULL or writable.
 */
nbhd_status nbhd_dynamic_insert(nbhd_dynamic_tree *tree,
                                const nbhd_points *points,
                                uint32_t *out_first);

/**
 * Removes the live points `indices[0 .. count - 1]` (any order). Their indices are never
 * given again. `indices` may be NULL when `count` is 0 (nothing to do).
 *
 * Errors, with nothing removed: NULL_POINTER, MISALIGNED_POINTER, INVALID_ARGUMENT (`count`
 * larger than an array can be), INDEX_OUT_OF_RANGE (an index not given yet),
 * REMOVED_POINT (an index already removed, or named twice), SKIPPED_POINT (a non-finite
 * point skipped at insertion), THREAD_POOL.
 *
 * # Safety
 * `tree` must be NULL or a live handle not in use by another thread; `indices` NULL or
 * `count` readable `uint32_t`.
 */
nbhd_status nbhd_dynamic_remove(nbhd_dynamic_tree *tree, const uint32_t *indices, size_t count);

/**
 * Sets the worker threads of the builds that later insertions and removals run: 0 the shared
 * pool (a thread per core), 1 serially, n a pool of n threads (at most 1024), as
 * `options->threads` of nbhd_dynamic_create. A loaded tree (nbhd_dynamic_load) starts at 0
 * whatever its file says; this changes it. Answers do not depend on it.
 *
 * Errors, with nothing changed: NULL_POINTER, MISALIGNED_POINTER, INVALID_OPTION (above
 * 1024).
 *
 * # Safety
 * `tree` must be NULL or a live handle not in use by another thread.
 */
nbhd_status nbhd_dynamic_set_threads(nbhd_dynamic_tree *tree, size_t threads);

/**
 * Frees a dynamic tree. NULL is ignored.
 *
 * # Safety
 * `tree` must be NULL or a handle from nbhd_dynamic_create not freed before, in use by no
 * other thread.
 */
void nbhd_dynamic_free(nbhd_dynamic_tree *tree);

/**
 * Writes the size and shape of `tree` to `*out_stats`.
 *
 * Errors: NULL_POINTER, MISALIGNED_POINTER.
 *
 * # Safety
 * `tree` must be NULL or a live handle; `out_stats` NULL or writable.
 */
nbhd_status nbhd_dynamic_tree_stats(const nbhd_dynamic_tree *tree, nbhd_dynamic_stats *out_stats);

/**
 * The `k` live points nearest to the point `query` (`dim` values of the tree's scalar type).
 * Arguments, results, buffers and errors as nbhd_tree_knn; an empty tree gives `*count` 0.
 *
 * # Safety
 * As nbhd_tree_knn, with `tree` a live dynamic tree not being changed by another thread.
 */
nbhd_status nbhd_dynamic_knn(const nbhd_dynamic_tree *tree,
                             const void *query,
                             size_t k,
                             uint32_t *indices,
                             void *sq_dists,
                             size_t capacity,
                             size_t *count);

/**
 * The neighbourhood `*spec` of the point `query` among the live points under `*options`
 * (NULL: the defaults); as nbhd_tree_search.
 *
 * # Safety
 * As nbhd_tree_search, with `tree` a live dynamic tree not being changed by another thread.
 */
nbhd_status nbhd_dynamic_search(const nbhd_dynamic_tree *tree,
                                const void *query,
                                const nbhd_neighborhood_spec *spec,
                                const nbhd_query_options *options,
                                uint32_t *indices,
                                void *sq_dists,
                                size_t capacity,
                                size_t *count);

/**
 * All live points within `radius` of the point `query`; as nbhd_tree_radius.
 *
 * # Safety
 * As nbhd_dynamic_knn.
 */
nbhd_status nbhd_dynamic_radius(const nbhd_dynamic_tree *tree,
                                const void *query,
                                double radius,
                                uint32_t *indices,
                                void *sq_dists,
                                size_t capacity,
                                size_t *count);

/**
 * The `k` nearest among the live points within `radius` of the point `query`; as
 * nbhd_tree_knn_radius.
 *
 * # Safety
 * As nbhd_dynamic_knn.
 */
nbhd_status nbhd_dynamic_knn_radius(const nbhd_dynamic_tree *tree,
                                    const void *query,
                                    size_t k,
                                    double radius,
                                    uint32_t *indices,
                                    void *sq_dists,
                                    size_t capacity,
                                    size_t *count);

/**
 * The `k` nearest neighbours of the live point `index`, optionally without the point itself;
 * as nbhd_tree_knn_index, plus REMOVED_POINT for a removed index.
 *
 * # Safety
 * As nbhd_dynamic_knn (there is no `query` pointer).
 */
nbhd_status nbhd_dynamic_knn_index(const nbhd_dynamic_tree *tree,
                                   size_t index,
                                   bool exclude_self,
                                   size_t k,
                                   uint32_t *indices,
                                   void *sq_dists,
                                   size_t capacity,
                                   size_t *count);

/**
 * All live points within `radius` of the live point `index`; as nbhd_tree_radius_index,
 * plus REMOVED_POINT.
 *
 * # Safety
 * As nbhd_dynamic_knn (there is no `query` pointer).
 */
nbhd_status nbhd_dynamic_radius_index(const nbhd_dynamic_tree *tree,
                                      size_t index,
                                      bool exclude_self,
                                      double radius,
                                      uint32_t *indices,
                                      void *sq_dists,
                                      size_t capacity,
                                      size_t *count);

/**
 * The `k` nearest within `radius` of the live point `index`; as
 * nbhd_tree_knn_radius_index, plus REMOVED_POINT.
 *
 * # Safety
 * As nbhd_dynamic_knn (there is no `query` pointer).
 */
nbhd_status nbhd_dynamic_knn_radius_index(const nbhd_dynamic_tree *tree,
                                          size_t index,
                                          bool exclude_self,
                                          size_t k,
                                          double radius,
                                          uint32_t *indices,
                                          void *sq_dists,
                                          size_t capacity,
                                          size_t *count);

/**
 * The neighbourhood `*spec` of every live point, as a new table in `*out_table`: row i for
 * index i (nbhd_dynamic_stats.next_index rows; rows of removed and skipped points are
 * empty), the bytes a static tree over the live points gives. Options, errors and ownership
 * as nbhd_tree_neighborhoods.
 *
 * # Safety
 * As nbhd_tree_neighborhoods, with `tree` a live dynamic tree not being changed.
 */
nbhd_status nbhd_dynamic_neighborhoods(const nbhd_dynamic_tree *tree,
                                       const nbhd_neighborhood_spec *spec,
                                       const nbhd_table_options *options,
                                       nbhd_neighborhoods **out_table);

/**
 * The neighbourhood `*spec` of each point of `*queries` among the live points, as a new
 * table (row i for query i); as nbhd_tree_neighborhoods_of.
 *
 * # Safety
 * As nbhd_tree_neighborhoods_of, with `tree` a live dynamic tree not being changed.
 */
nbhd_status nbhd_dynamic_neighborhoods_of(const nbhd_dynamic_tree *tree,
                                          const nbhd_points *queries,
                                          const nbhd_neighborhood_spec *spec,
                                          const nbhd_table_options *options,
                                          nbhd_neighborhoods **out_table);

/**
 * Builds a periodic k-d tree (a torus, as scipy's `cKDTree(data, boxsize=...)`) over
 * `*points` and stores a new handle in `*out_tree`. `boxsize[0 .. boxsize_count]` holds the
 * box size L of every axis (`boxsize_count` = the dimension) or one size for every axis
 * (`boxsize_count` = 1); 0 or +infinity makes an axis open (not periodic). On a periodic axis
 * every point must lie in [0, L) (points are not wrapped; scipy refuses them too); every query
 * of the tree is wrapped into [0, L) and measures each axis difference t at its nearest image,
 * min(t, L - t), under any metric, so each point counts once, even for a radius beyond L/2.
 * With no periodic axis this is nbhd_tree_build. Box queries (nbhd_tree_in_box) are not
 * periodic: they take the box in the tree's coordinates.
 *
 * Errors: those of nbhd_tree_build; NULL_POINTER / MISALIGNED_POINTER (`boxsize` with a
 * count above 0); INVALID_OPTION (a size negative, NaN or rounding to 0 in the tree's scalar
 * type, or `boxsize_count` neither 1 nor the dimension); OUTSIDE_PERIOD (a point outside the
 * box: the message names the smallest such index, the coordinate, its value and L).
 *
 * Ownership: as nbhd_tree_build (free with nbhd_tree_free); `boxsize` may be freed once this
 * returns.
 *
 * # Safety
 * As nbhd_tree_build; `boxsize` NULL or readable for `boxsize_count` doubles.
 */
nbhd_status nbhd_tree_build_periodic(const nbhd_points *points,
                                     const nbhd_build_options *options,
                                     const double *boxsize,
                                     size_t boxsize_count,
                                     nbhd_tree **out_tree);

/**
 * Makes an empty periodic dynamic tree (as nbhd_dynamic_create) over the box
 * `boxsize[0 .. boxsize_count]` (as nbhd_tree_build_periodic): every inserted point must lie
 * in the box (nbhd_dynamic_insert refuses a batch holding one outside with OUTSIDE_PERIOD,
 * naming its position in the batch), and every query is wrapped into it.
 *
 * Errors: those of nbhd_dynamic_create; NULL_POINTER / MISALIGNED_POINTER (`boxsize`);
 * INVALID_OPTION (the box, as nbhd_tree_build_periodic).
 *
 * # Safety
 * As nbhd_dynamic_create; `boxsize` NULL or readable for `boxsize_count` doubles.
 */
nbhd_status nbhd_dynamic_create_periodic(size_t dim,
                                         nbhd_scalar_type scalar_type,
                                         const nbhd_build_options *options,
                                         const double *boxsize,
                                         size_t boxsize_count,
                                         nbhd_dynamic_tree **out_tree);

/**
 * Writes the box sizes of `tree` to `out_boxsize[0 .. dim]` (0 for an open axis; all 0 for a
 * tree that is not periodic) and returns whether it is periodic in `*out_periodic` (may be
 * NULL).
 *
 * Errors: NULL_POINTER (`tree`, `out_boxsize`), MISALIGNED_POINTER, BUFFER_TOO_SMALL
 * (`capacity` below the dimension; nothing written).
 *
 * # Safety
 * `tree` NULL or a live handle; `out_boxsize` NULL or writable for `capacity` doubles;
 * `out_periodic` NULL or writable.
 */
nbhd_status nbhd_tree_boxsize(const nbhd_tree *tree,
                              double *out_boxsize,
                              size_t capacity,
                              bool *out_periodic);

/**
 * Writes the box sizes of a dynamic tree; as nbhd_tree_boxsize.
 *
 * # Safety
 * As nbhd_tree_boxsize, with `tree` a live dynamic tree.
 */
nbhd_status nbhd_dynamic_boxsize(const nbhd_dynamic_tree *tree,
                                 double *out_boxsize,
                                 size_t capacity,
                                 bool *out_periodic);

/**
 * Every pair i < j of points of `tree` within `radius` of each other (inclusive, scipy's
 * `query_pairs`) as a new table in `*out_table`: row i (one per index, as
 * nbhd_tree_neighborhoods) holds the j > i in ascending order (not by distance), with the
 * pair's key in the distances (squared for the Euclidean metric, the distance for p = 1 and
 * infinity, the sum of |x_j|^p otherwise). `options` may be NULL; its `query` sets the
 * metric, eps (every pair within radius * (1 + eps): inside scipy's contract, all within
 * radius / (1 + eps) and none beyond radius * (1 + eps)) and a strict radius; `exclude_self`
 * does not apply. Identical for any number of threads.
 *
 * On any error `*out_table` is set to NULL (if `out_table` is not NULL).
 *
 * Errors: NULL_POINTER (`tree`, `out_table`), MISALIGNED_POINTER, INVALID_RADIUS (negative,
 * NaN or infinite, or a key that overflows the tree's type), INVALID_OPTION (the query
 * options), OUT_OF_MEMORY, THREAD_POOL.
 *
 * Ownership: the caller owns `*out_table` and frees it with nbhd_neighborhoods_free.
 *
 * # Safety
 * `tree` NULL or a live handle; `options` NULL or readable; `out_table` NULL or writable.
 */
nbhd_status nbhd_tree_pairs(const nbhd_tree *tree,
                            double radius,
                            const nbhd_table_options *options,
                            nbhd_neighborhoods **out_table);

/**
 * nbhd_tree_pairs for a growing tree (rows for every index ever inserted; removed points
 * have no pair).
 *
 * # Safety
 * As nbhd_tree_pairs.
 */
nbhd_status nbhd_dynamic_pairs(const nbhd_dynamic_tree *tree,
                               double radius,
                               const nbhd_table_options *options,
                               nbhd_neighborhoods **out_table);

/**
 * The pairs (i, j) of a point i of `tree` and a point j of `other` within `radius` of each
 * other (inclusive; scipy's `query_ball_tree` and `sparse_distance_matrix`), measured by
 * `tree` (its metric under `options->query`, its periodic box; `other`'s box is not used), as
 * a new table in `*out_table`: row i (one per index of `tree`) holds `other`'s indices j
 * ascending, with the pair's key (see nbhd_tree_pairs), zero distances included. Both trees
 * must have the same dimension and scalar type. Identical for any number of threads.
 *
 * On any error `*out_table` is set to NULL (if `out_table` is not NULL).
 *
 * Errors: as nbhd_tree_pairs; NULL_POINTER (`other`), DIMENSION_MISMATCH, INVALID_OPTION
 * (trees of different scalar types).
 *
 * Ownership: the caller owns `*out_table` and frees it with nbhd_neighborhoods_free.
 *
 * # Safety
 * As nbhd_tree_pairs; `other` NULL or a live handle.
 */
nbhd_status nbhd_tree_pairs_with(const nbhd_tree *tree,
                                 const nbhd_tree *other,
                                 double radius,
                                 const nbhd_table_options *options,
                                 nbhd_neighborhoods **out_table);

/**
 * nbhd_tree_pairs_with for two growing trees.
 *
 * # Safety
 * As nbhd_tree_pairs_with.
 */
nbhd_status nbhd_dynamic_pairs_with(const nbhd_dynamic_tree *tree,
                                    const nbhd_dynamic_tree *other,
                                    double radius,
                                    const nbhd_table_options *options,
                                    nbhd_neighborhoods **out_table);

/**
 * How many pairs (i, j) of a point of `tree` and a point of `other` lie within each radius of
 * `radii[0 .. radius_count]` (scipy's `count_neighbors`), measured by `tree` as
 * nbhd_tree_pairs_with, written to `counts[0 .. radius_count]`. `other` may be `tree` itself
 * (then each point counts with itself and each pair twice, as scipy). `cumulative`: counts[k]
 * is the number of pairs at distance <= radii[k] (radii in any order); otherwise the number in
 * (radii[k-1], radii[k]] ([0, radii[0]] for k = 0; radii non-decreasing; of equal radii the
 * first gets the count, the others 0). A negative radius counts nothing, +infinity every
 * pair; `options->query.strict` makes every radius exclusive. Exact and identical for any
 * number of threads.
 *
 * Errors: NULL_POINTER (`tree`, `other`, `radii` or `counts` with radius_count > 0),
 * MISALIGNED_POINTER, INVALID_RADIUS (a NaN radius), INVALID_OPTION (decreasing radii when
 * not cumulative, eps > 0: counts are exact, trees of different scalar types),
 * DIMENSION_MISMATCH, THREAD_POOL. `counts` is untouched on error.
 *
 * # Safety
 * `tree`, `other` NULL or live handles; `radii` NULL or readable and `counts` NULL or
 * writable for `radius_count` values; `options` NULL or readable.
 */
nbhd_status nbhd_tree_count_pairs(const nbhd_tree *tree,
                                  const nbhd_tree *other,
                                  const double *radii,
                                  size_t radius_count,
                                  bool cumulative,
                                  const nbhd_table_options *options,
                                  uint64_t *counts);

/**
 * nbhd_tree_count_pairs with weights (scipy's `count_neighbors` with `weights`): each pair
 * (i, j) adds tree_weights[i] * other_weights[j] (see nbhd_pair_weights; `weights` NULL
 * weighs every point 1), and sums[k] is the correctly rounded sum of those products (an exact
 * sum: the same bits for any number of threads).
 *
 * Errors: those of nbhd_tree_count_pairs; INVALID_OPTION (a weight array whose count is not
 * the number of indices of its tree, or a weight that is NaN or infinite).
 *
 * # Safety
 * As nbhd_tree_count_pairs, `sums` for `counts`; `weights` NULL or readable, its arrays NULL
 * or readable for their counts.
 */
nbhd_status nbhd_tree_weigh_pairs(const nbhd_tree *tree,
                                  const nbhd_tree *other,
                                  const double *radii,
                                  size_t radius_count,
                                  bool cumulative,
                                  const nbhd_pair_weights *weights,
                                  const nbhd_table_options *options,
                                  double *sums);

/**
 * nbhd_tree_count_pairs for two growing trees.
 *
 * # Safety
 * As nbhd_tree_count_pairs.
 */
nbhd_status nbhd_dynamic_count_pairs(const nbhd_dynamic_tree *tree,
                                     const nbhd_dynamic_tree *other,
                                     const double *radii,
                                     size_t radius_count,
                                     bool cumulative,
                                     const nbhd_table_options *options,
                                     uint64_t *counts);

/**
 * nbhd_tree_weigh_pairs for two growing trees.
 *
 * # Safety
 * As nbhd_tree_weigh_pairs.
 */
nbhd_status nbhd_dynamic_weigh_pairs(const nbhd_dynamic_tree *tree,
                                     const nbhd_dynamic_tree *other,
                                     const double *radii,
                                     size_t radius_count,
                                     bool cumulative,
                                     const nbhd_pair_weights *weights,
                                     const nbhd_table_options *options,
                                     double *sums);

/**
 * The default smoothing options: the thesis' anisotropic flow with g_sharp at λ = 0.2/h on
 * all points, 3 steps of τ = 0.5, the 15 nearest other points within 6h, no progress
 * callback, the shared thread pool.
 */
nbhd_smooth_options nbhd_smooth_options_default(void);

/**
 * Smooths 3-D points (thesis Chapter 2) and writes the smoothed coordinates to `out_coords`.
 *
 * `out_coords` is laid out like the input: `points->count` points `points->stride` bytes
 * apart (a stride of 0 means packed), three coordinates of `points->scalar_type` each; only
 * the coordinates are written, other bytes in a strided layout are left alone. It may be
 * `points->data` itself, to smooth in place (the input is read completely first).
 * `out_geometry` (`points->count` elements) receives the per-point geometry of the smoothed
 * points and `out_summary` the spacing and thresholds used; either may be NULL, and leaving
 * `out_geometry` NULL skips that work. `options` may be NULL for the defaults.
 *
 * Nothing is written unless the call succeeds. Results are identical for any number of
 * threads.
 *
 * Errors: NULL_POINTER (`points`, `points->data`, `out_coords`), MISALIGNED_POINTER,
 * INVALID_ARGUMENT (dimension other than 3, `points->scalar_type` out of range, a buffer
 * size that overflows), ZERO_DIMENSION (dimension 0), EMPTY_INPUT (also: no finite point
 * left to SKIP), STRIDE_TOO_SMALL, TOO_MANY_POINTS, NON_FINITE (with `non_finite` REJECT;
 * the message names the point), INVALID_K, INVALID_OPTION (an enum field of `options` out of
 * range, ε or λ not > 0, τ negative, relative units on a set without two distinct points,
 * more than NBHD_MAX_THREADS threads, ...), DEGENERATE (no neighbourhood reached 3 points: ε
 * far below the spacing — check `epsilon_units`; the message gives ε in the points' units),
 * OUT_OF_MEMORY (the neighbourhoods of `k` do not fit in memory, e.g. k = SIZE_MAX on a
 * large set), THREAD_POOL, CANCELLED (the progress callback returned false).
 *
 * # Safety
 * `points` must describe readable memory (see nbhd_points); `out_coords` must be writable
 * with the same layout; `out_geometry` and `out_summary` must be NULL or writable for
 * `points->count` elements / one element; `options` must be NULL or readable.
 */
nbhd_status nbhd_smooth(const nbhd_points *points,
                        const nbhd_smooth_options *options,
                        void *out_coords,
                        nbhd_point_geometry *out_geometry,
                        nbhd_smooth_summary *out_summary);

/**
 * Estimates normals and curvatures of every point without moving it: the normal, the
 * principal curvatures and directions of the Weingarten estimate (thesis eq. 2.26–2.29 with
 * 2.25) and the other per-point values of nbhd_point_geometry, over the ε-k-neighbourhoods
 * of `options`. `out_geometry` receives `points->count` elements; `out_summary` (may be NULL)
 * the spacing and thresholds used.
 *
 * Errors: as nbhd_smooth; DEGENERATE also when every normal is flagged degenerate.
 *
 * # Safety
 * `points` must describe readable memory; `out_geometry` must be writable for
 * `points->count` elements; `out_summary` NULL or writable; `options` NULL or readable.
 */
nbhd_status nbhd_estimate_curvatures(const nbhd_points *points,
                                     const nbhd_smooth_options *options,
                                     nbhd_point_geometry *out_geometry,
                                     nbhd_smooth_summary *out_summary);

/**
 * The default normal options: the 15 nearest other points within 6 h (RELATIVE units: h is
 * the mean spacing), unoriented, non-finite points rejected, the shared thread pool, no
 * progress callback.
 */
nbhd_normal_options nbhd_normal_options_default(void);

/**
 * Estimates the normal of every point (thesis eq. 2.8–2.10: the eigenvector of the smallest
 * eigenvalue of the covariance of the point and its ε-k-neighbourhood), oriented as
 * `options->orientation` asks, and writes it into the caller's layout `*out` (see
 * nbhd_normals_output: a packed `double[3 * count]`, or the fields of `pcl::Normal` /
 * `pcl::PointNormal` in place), with PCL's curvature (the surface variation) and the
 * degeneracy flags if asked. Degenerate neighbourhoods give a finite unit vector and a flag,
 * never NaN; skipped points (NBHD_NON_FINITE_POLICY_SKIP) a NaN normal and curvature.
 * `options` may be NULL for the defaults (NOTE: ε is then 6 × the mean spacing, RELATIVE
 * units). Nothing is written unless the call succeeds.
 *
 * Errors: NULL_POINTER (`points`, `points->data`, `out`, `out->normals`),
 * MISALIGNED_POINTER, INVALID_ARGUMENT (dimension other than 3, `out->scalar_type` out of
 * range, an output stride smaller than its values or one that overflows), ZERO_DIMENSION
 * (dimension 0), EMPTY_INPUT, STRIDE_TOO_SMALL, TOO_MANY_POINTS, NON_FINITE (non_finite
 * REJECT), INVALID_K, INVALID_OPTION (an enum field of `options` out of range, ε not > 0,
 * relative units on a set without two distinct points, a non-finite orientation point,
 * more than NBHD_MAX_THREADS threads), DEGENERATE (no neighbourhood reached 3 points, or
 * every normal is flagged: usually ε far too small — check `epsilon_units`; the message
 * gives ε in the points' units), OUT_OF_MEMORY, THREAD_POOL, CANCELLED.
 *
 * # Safety
 * `points` must describe readable memory; `out` must point to a readable
 * nbhd_normals_output whose arrays are writable for `points->count` points in the layout it
 * describes; `options` NULL or readable.
 */
nbhd_status nbhd_estimate_normals(const nbhd_points *points,
                                  const nbhd_normal_options *options,
                                  const nbhd_normals_output *out);

/**
 * The default robust options: 24 neighbours within 12h, planes scored on 48, at most 10
 * iterations stopped when the noise estimate falls by less than 5 %, no callback.
 */
nbhd_robust_options nbhd_robust_options_default(void);

/**
 * Smooths 3-D points with the robust mode and writes the smoothed coordinates to
 * `out_coords`, laid out like the input (it may be `points->data` itself, to smooth in
 * place). `out_geometry` (`points->count` elements, computed with the robust normals) and
 * `out_summary` (its `lambda` is the noise-adapted threshold of the first iteration) may be
 * NULL. `options` may be NULL for the defaults. Nothing is written unless the call succeeds;
 * results are identical for any number of threads.
 *
 * Slower than nbhd_smooth (each iteration searches the wider neighbourhood and fits
 * candidate planes) but keeps sharp edges at noise of about one spacing, where the faithful
 * method cannot tell noise from features.
 *
 * Errors: as nbhd_smooth; INVALID_OPTION also for k_plane < k, a tolerance < 0, a width or
 * angle not > 0, τ outside (0, 1].
 *
 * # Safety
 * As nbhd_smooth.
 */
nbhd_status nbhd_smooth_robust(const nbhd_points *points,
                               const nbhd_robust_options *options,
                               void *out_coords,
                               nbhd_point_geometry *out_geometry,
                               nbhd_smooth_summary *out_summary);

/**
 * nbhd_smooth on the points a built tree holds, with the tree's own search for the
 * neighbourhoods (no second build). `out_coords` receives the smoothed points packed in the
 * caller's index order, three values of the tree's scalar type each; `out_geometry` and
 * `out_summary` as in nbhd_smooth. The result is nbhd_smooth's on the same points.
 *
 * Errors: as nbhd_smooth; NULL_POINTER (`tree`, `out_coords`); INVALID_OPTION when the tree
 * is not 3-D or skipped non-finite points (smooth the points themselves with a SKIP policy
 * instead).
 *
 * # Safety
 * `tree` must be a live tree; `out_coords` writable for 3 × the tree's point count values;
 * `out_geometry`, `out_summary` NULL or writable; `options` NULL or readable.
 */
nbhd_status nbhd_smooth_tree(const nbhd_tree *tree,
                             const nbhd_smooth_options *options,
                             void *out_coords,
                             nbhd_point_geometry *out_geometry,
                             nbhd_smooth_summary *out_summary);

/**
 * nbhd_estimate_curvatures on the points a built tree holds (normals, curvatures and the
 * other per-point geometry, without a second build). Errors: as nbhd_smooth_tree.
 *
 * # Safety
 * `tree` must be a live tree; `out_geometry` writable for the tree's point count;
 * `out_summary` NULL or writable; `options` NULL or readable.
 */
nbhd_status nbhd_estimate_curvatures_tree(const nbhd_tree *tree,
                                          const nbhd_smooth_options *options,
                                          nbhd_point_geometry *out_geometry,
                                          nbhd_smooth_summary *out_summary);

/**
 * nbhd_smooth_robust on the points a built tree holds (its `k_plane` nearest from the tree's
 * own search). Outputs and errors: as nbhd_smooth_tree.
 *
 * # Safety
 * As nbhd_smooth_tree.
 */
nbhd_status nbhd_smooth_robust_tree(const nbhd_tree *tree,
                                    const nbhd_robust_options *options,
                                    void *out_coords,
                                    nbhd_point_geometry *out_geometry,
                                    nbhd_smooth_summary *out_summary);

/**
 * nbhd_smooth with the neighbourhoods of `table` instead of a search: row i of `table`
 * (nbhd_tree_neighborhoods with each point left out of its own row, on the same points) gives
 * the candidates of point i, of which the first k within ε are taken, as from the call's own
 * search; a k-nearest table with at least `options->k` gives exactly nbhd_smooth's result.
 * A float table's rows are re-measured in double. Outputs as nbhd_smooth.
 *
 * Errors: as nbhd_smooth; NULL_POINTER (`table`); INVALID_OPTION when the table does not fit
 * the points (row count, an index out of range, a point in its own row, rows out of order).
 *
 * # Safety
 * As nbhd_smooth; `table` must be a live table.
 */
nbhd_status nbhd_smooth_table(const nbhd_points *points,
                              const nbhd_neighborhoods *table,
                              const nbhd_smooth_options *options,
                              void *out_coords,
                              nbhd_point_geometry *out_geometry,
                              nbhd_smooth_summary *out_summary);

/**
 * nbhd_estimate_curvatures with the neighbourhoods of `table` (see nbhd_smooth_table).
 *
 * # Safety
 * As nbhd_estimate_curvatures; `table` must be a live table.
 */
nbhd_status nbhd_estimate_curvatures_table(const nbhd_points *points,
                                           const nbhd_neighborhoods *table,
                                           const nbhd_smooth_options *options,
                                           nbhd_point_geometry *out_geometry,
                                           nbhd_smooth_summary *out_summary);

/**
 * nbhd_smooth_robust with the neighbourhoods of `table` (the first `k_plane` of each row; see
 * nbhd_smooth_table).
 *
 * # Safety
 * As nbhd_smooth_robust; `table` must be a live table.
 */
nbhd_status nbhd_smooth_robust_table(const nbhd_points *points,
                                     const nbhd_neighborhoods *table,
                                     const nbhd_robust_options *options,
                                     void *out_coords,
                                     nbhd_point_geometry *out_geometry,
                                     nbhd_smooth_summary *out_summary);

#ifdef __cplusplus
}  // extern "C"
#endif  // __cplusplus

#endif  /* NBHD_H */
