/*
 * The C ABI seen from C: every export of nbhd.h is called, results are checked against a brute
 * force written here, and every error path is walked. Run by tests/c_abi.rs (also under
 * valgrind). Exits 0 when every check passed; prints each failed check and a summary.
 */
/* fork, setrlimit, sysconf (POSIX) for the out-of-memory check, with -std=c99. */
#define _POSIX_C_SOURCE 200809L
#include "nbhd.h"
#include "check.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---------------------------------------------------------------------------------------- */
/* A small cloud with exact ties: coordinates are multiples of 1/64, so they are exact in     */
/* float and double, and many squared distances are equal; some points are exact duplicates. */

#define N 240
#define DIM 3
#define NQ 24
#define CAP (N + 8)

static double pts[N * DIM];
static float ptsf[N * DIM];
static double queries[NQ * DIM];

static uint64_t rng_state = 0x2545F4914F6CDD1DULL;

static uint64_t next_u64(void) {
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return rng_state;
}

/* A multiple of 1/64 in [lo, lo + span / 64). */
static double grid(double lo, unsigned span) {
    return lo + (double)(next_u64() % span) / 64.0;
}

static void make_cloud(void) {
    size_t i, j;
    for (i = 0; i < N; i++) {
        for (j = 0; j < DIM; j++) {
            pts[i * DIM + j] = grid(0.0, 64);
        }
        if (i % 37 == 5) { /* an exact duplicate of the previous point */
            for (j = 0; j < DIM; j++) {
                pts[i * DIM + j] = pts[(i - 1) * DIM + j];
            }
        }
    }
    for (i = 0; i < N * DIM; i++) {
        ptsf[i] = (float)pts[i];
    }
    for (i = 0; i < NQ * DIM; i++) {
        queries[i] = grid(-0.125, 80);
    }
}

/* ---------------------------------------------------------------------------------------- */
/* Brute force, computing squared distances exactly as the library does: in the tree's type, */
/* coordinate by coordinate, (q - p)^2 summed from 0.                                        */

typedef struct {
    double d; /* squared distance, converted exactly from the tree's type */
    uint32_t i;
} cand;

static int cand_cmp(const void *a, const void *b) {
    const cand *x = (const cand *)a, *y = (const cand *)b;
    if (x->d < y->d) return -1;
    if (x->d > y->d) return 1;
    return (x->i > y->i) - (x->i < y->i);
}

static double sq_dist(int f32, const double *q, size_t i) {
    size_t j;
    if (f32) {
        float s = 0.0f;
        for (j = 0; j < DIM; j++) {
            float t = (float)q[j] - ptsf[i * DIM + j];
            s = s + t * t;
        }
        return (double)s;
    } else {
        double s = 0.0;
        for (j = 0; j < DIM; j++) {
            double t = q[j] - pts[i * DIM + j];
            s = s + t * t;
        }
        return s;
    }
}

/* The squared radius as the library compares it: radius rounded to the tree's type, squared in it. */
static double sq_radius(int f32, double r) {
    if (f32) {
        float rf = (float)r;
        return (double)(rf * rf);
    }
    return r * r;
}

/* Expected neighbourhood: k = 0 means unlimited, r < 0 means no radius. `skip[i]` marks points
 * the tree does not hold; `exclude` is an index to leave out or -1. Returns the count. */
static size_t brute(int f32, const double *q, size_t k, double r, long exclude, const int *skip,
                    cand *out) {
    cand all[N];
    size_t n = 0, i, m;
    double rr = r >= 0 ? sq_radius(f32, r) : INFINITY;
    for (i = 0; i < N; i++) {
        double d;
        if ((long)i == exclude || (skip && skip[i])) continue;
        d = sq_dist(f32, q, i);
        if (d <= rr) {
            all[n].d = d;
            all[n].i = (uint32_t)i;
            n++;
        }
    }
    qsort(all, n, sizeof all[0], cand_cmp);
    m = (k > 0 && k < n) ? k : n;
    memcpy(out, all, m * sizeof all[0]);
    return m;
}

/* Compares a result (indices + distances in the tree's type) with the brute force. */
static int same_result(int f32, const uint32_t *idx, const void *dists, size_t count,
                       const cand *want, size_t nwant) {
    size_t i;
    if (count != nwant) {
        fprintf(stderr, "  count %lu, brute force %lu\n", (unsigned long)count,
                (unsigned long)nwant);
        return 0;
    }
    for (i = 0; i < count; i++) {
        double d = f32 ? (double)((const float *)dists)[i] : ((const double *)dists)[i];
        if (idx[i] != want[i].i || d != want[i].d) {
            fprintf(stderr, "  at %lu: (%u, %.17g), brute force (%u, %.17g)\n", (unsigned long)i,
                    idx[i], d, want[i].i, want[i].d);
            return 0;
        }
    }
    return 1;
}

/* ---------------------------------------------------------------------------------------- */

static nbhd_points describe(int f32) {
    nbhd_points p;
    p.data = f32 ? (const void *)ptsf : (const void *)pts;
    p.count = N;
    p.dim = DIM;
    p.stride = 0;
    p.scalar_type = f32 ? NBHD_SCALAR_TYPE_F32 : NBHD_SCALAR_TYPE_F64;
    return p;
}

/* Query coordinates in the tree's type. */
typedef union {
    float f[DIM];
    double d[DIM];
} coords;

static coords query_coords(int f32, const double *q) {
    coords c;
    size_t j;
    for (j = 0; j < DIM; j++) {
        if (f32) {
            c.f[j] = (float)q[j];
        } else {
            c.d[j] = q[j];
        }
    }
    return c;
}

/* Result buffers of either type. */
static uint32_t idx_buf[CAP];
static double dist_buf_d[CAP];
static float dist_buf_f[CAP];

static void *dist_buf(int f32) {
    return f32 ? (void *)dist_buf_f : (void *)dist_buf_d;
}

/* Runs every single query kind at `q` (coordinates) and at stored point `stored` against the
 * brute force. */
static void check_queries(const nbhd_tree *tree, int f32, const int *skip) {
    static const size_t ks[] = {1, 2, 5, 16, N - 1, N, N + 5};
    static const double radii[] = {0.0, 0.0625, 0.125, 0.25, 2.0};
    cand want[N];
    size_t qi, a, b, count, nwant;
    for (qi = 0; qi < NQ; qi++) {
        const double *q = &queries[qi * DIM];
        coords c = query_coords(f32, q);
        for (a = 0; a < sizeof ks / sizeof ks[0]; a++) {
            size_t k = ks[a];
            size_t cap = k < CAP ? k : CAP;
            CHECK_STATUS(nbhd_tree_knn(tree, &c, k, idx_buf, dist_buf(f32), cap, &count),
                         NBHD_STATUS_OK);
            nwant = brute(f32, q, k, -1.0, -1, skip, want);
            CHECK(same_result(f32, idx_buf, dist_buf(f32), count, want, nwant));
            for (b = 0; b < sizeof radii / sizeof radii[0]; b++) {
                double r = radii[b];
                CHECK_STATUS(
                    nbhd_tree_knn_radius(tree, &c, k, r, idx_buf, dist_buf(f32), cap, &count),
                    NBHD_STATUS_OK);
                nwant = brute(f32, q, k, r, -1, skip, want);
                CHECK(same_result(f32, idx_buf, dist_buf(f32), count, want, nwant));
            }
        }
        for (b = 0; b < sizeof radii / sizeof radii[0]; b++) {
            double r = radii[b];
            CHECK_STATUS(nbhd_tree_radius(tree, &c, r, idx_buf, dist_buf(f32), CAP, &count),
                         NBHD_STATUS_OK);
            nwant = brute(f32, q, 0, r, -1, skip, want);
            CHECK(same_result(f32, idx_buf, dist_buf(f32), count, want, nwant));
        }
    }
    /* Around stored points, with and without the point itself (duplicates stay). */
    for (qi = 0; qi < N; qi += 7) {
        const double *q = &pts[qi * DIM];
        int excl;
        if (skip && skip[qi]) continue;
        for (excl = 0; excl <= 1; excl++) {
            long ex = excl ? (long)qi : -1;
            for (a = 0; a < sizeof ks / sizeof ks[0]; a++) {
                size_t k = ks[a];
                size_t cap = k < CAP ? k : CAP;
                CHECK_STATUS(nbhd_tree_knn_index(tree, qi, excl != 0, k, idx_buf, dist_buf(f32),
                                                 cap, &count),
                             NBHD_STATUS_OK);
                nwant = brute(f32, q, k, -1.0, ex, skip, want);
                CHECK(same_result(f32, idx_buf, dist_buf(f32), count, want, nwant));
                CHECK_STATUS(nbhd_tree_knn_radius_index(tree, qi, excl != 0, k, 0.125, idx_buf,
                                                        dist_buf(f32), cap, &count),
                             NBHD_STATUS_OK);
                nwant = brute(f32, q, k, 0.125, ex, skip, want);
                CHECK(same_result(f32, idx_buf, dist_buf(f32), count, want, nwant));
            }
            for (b = 0; b < sizeof radii / sizeof radii[0]; b++) {
                CHECK_STATUS(nbhd_tree_radius_index(tree, qi, excl != 0, radii[b], idx_buf,
                                                    dist_buf(f32), CAP, &count),
                             NBHD_STATUS_OK);
                nwant = brute(f32, q, 0, radii[b], ex, skip, want);
                CHECK(same_result(f32, idx_buf, dist_buf(f32), count, want, nwant));
            }
        }
    }
    /* Distances are optional. */
    {
        coords c = query_coords(f32, &queries[0]);
        CHECK_STATUS(nbhd_tree_knn(tree, &c, 4, idx_buf, NULL, 4, &count), NBHD_STATUS_OK);
        nwant = brute(f32, &queries[0], 4, -1.0, -1, skip, want);
        CHECK(count == nwant && idx_buf[0] == want[0].i && idx_buf[3] == want[3].i);
    }
}

static void test_version_and_strings(void) {
    char expected[64];
    int s;
    CHECK(nbhd_version() == NBHD_VERSION);
    CHECK(NBHD_VERSION == NBHD_VERSION_MAJOR * 1000000 + NBHD_VERSION_MINOR * 1000 +
                              NBHD_VERSION_PATCH);
    sprintf(expected, "%d.%d.%d", NBHD_VERSION_MAJOR, NBHD_VERSION_MINOR, NBHD_VERSION_PATCH);
    CHECK(strcmp(nbhd_version_string(), expected) == 0);
    for (s = NBHD_STATUS_OK; s <= NBHD_STATUS_OUTSIDE_PERIOD; s++) { /* the last status */
        const char *text = nbhd_status_string((nbhd_status)s);
        CHECK(text != NULL && text[0] != '\0' && strcmp(text, "unknown status") != 0);
    }
    CHECK(strcmp(nbhd_status_string(NBHD_STATUS_INVALID_K), "k must be at least 1") == 0);
    CHECK(strcmp(nbhd_status_string((nbhd_status)-1), "unknown status") == 0);
    CHECK(strcmp(nbhd_status_string((nbhd_status)(NBHD_STATUS_OUTSIDE_PERIOD + 1)),
                 "unknown status") == 0);
    CHECK(strcmp(nbhd_status_string((nbhd_status)(1 << 30)), "unknown status") == 0);
    /* Before any failure the message is empty, never NULL. */
    CHECK(nbhd_last_error_message() != NULL && nbhd_last_error_message()[0] == '\0');
}

static void test_defaults(void) {
    nbhd_build_options o = nbhd_build_options_default();
    nbhd_table_options t = nbhd_table_options_default();
    CHECK(o.pivot == NBHD_PIVOT_POLICY_SLIDING_MIDPOINT);
    CHECK(o.median == NBHD_MEDIAN_ALGORITHM_FLOYD_RIVEST);
    CHECK(o.leaf_size == 12);
    CHECK(o.non_finite == NBHD_NON_FINITE_POLICY_REJECT);
    CHECK(o.threads == 0);
    CHECK(t.exclude_self == true);
    CHECK(t.threads == 0);
}

/* Every pivot policy with every median algorithm, both scalar types, several leaf sizes and
 * thread counts: stats are sane and every query matches the brute force. */
static void test_builds_and_queries(void) {
    static const nbhd_pivot_policy pivots[] = {
        NBHD_PIVOT_POLICY_CYCLIC_MEDIAN, NBHD_PIVOT_POLICY_SPREAD_MEDIAN,
        NBHD_PIVOT_POLICY_CLOSEST_TO_MIDDLE, NBHD_PIVOT_POLICY_SLIDING_MIDPOINT};
    static const nbhd_median_algorithm medians[] = {
        NBHD_MEDIAN_ALGORITHM_PRESORTED, NBHD_MEDIAN_ALGORITHM_SORT,
        NBHD_MEDIAN_ALGORITHM_QUICKSELECT, NBHD_MEDIAN_ALGORITHM_FLOYD_RIVEST,
        NBHD_MEDIAN_ALGORITHM_MEDIAN_OF_MEDIANS};
    size_t p, m;
    int f32;
    for (f32 = 0; f32 <= 1; f32++) {
        for (p = 0; p < 4; p++) {
            for (m = 0; m < 5; m++) {
                nbhd_points pts_desc = describe(f32);
                nbhd_build_options o = nbhd_build_options_default();
                nbhd_tree *tree = NULL;
                nbhd_stats st;
                o.pivot = pivots[p];
                o.median = medians[m];
                o.leaf_size = (p + m) % 3 == 0 ? 1 : 1 + 5 * m;
                o.threads = m % 3; /* shared pool, on the caller, a pool of 2 */
                CHECK_STATUS(nbhd_tree_build(&pts_desc, &o, &tree), NBHD_STATUS_OK);
                if (tree == NULL) continue;
                CHECK(nbhd_last_error_message()[0] == '\0');
                CHECK_STATUS(nbhd_tree_stats(tree, &st), NBHD_STATUS_OK);
                CHECK(st.points == N && st.source_points == N && st.dim == DIM);
                CHECK(st.scalar_type == (f32 ? NBHD_SCALAR_TYPE_F32 : NBHD_SCALAR_TYPE_F64));
                CHECK(st.leaves >= 1 && st.nodes >= st.leaves && st.bytes > 0);
                CHECK(st.max_leaf_points >= 1 && st.max_leaf_points <= o.leaf_size);
                CHECK(st.depth < N);
                /* The full query sweep on a few configurations, a smaller one on the others. */
                if ((p == 3 && m == 3) || (p == 0 && m == 0) || (p == 2 && m == 4)) {
                    check_queries(tree, f32, NULL);
                } else {
                    cand want[N];
                    size_t count, nwant;
                    coords c = query_coords(f32, &queries[3 * DIM]);
                    CHECK_STATUS(
                        nbhd_tree_knn(tree, &c, 9, idx_buf, dist_buf(f32), CAP, &count),
                        NBHD_STATUS_OK);
                    nwant = brute(f32, &queries[3 * DIM], 9, -1.0, -1, NULL, want);
                    CHECK(same_result(f32, idx_buf, dist_buf(f32), count, want, nwant));
                }
                nbhd_tree_free(tree);
            }
        }
    }
}

/* A PCL-like layout (x, y, z, padding; 16-byte stride) gives the same tree answers as the
 * packed array; options may be NULL. */
typedef struct {
    float x, y, z, pad;
} point_xyz;

static void test_strided_points(void) {
    point_xyz *cloud = (point_xyz *)malloc(N * sizeof *cloud);
    nbhd_points desc;
    nbhd_tree *tree = NULL;
    size_t i;
    for (i = 0; i < N; i++) {
        cloud[i].x = ptsf[i * 3];
        cloud[i].y = ptsf[i * 3 + 1];
        cloud[i].z = ptsf[i * 3 + 2];
        cloud[i].pad = NAN; /* never read */
    }
    desc.data = cloud;
    desc.count = N;
    desc.dim = 3;
    desc.stride = sizeof(point_xyz);
    desc.scalar_type = NBHD_SCALAR_TYPE_F32;
    CHECK_STATUS(nbhd_tree_build(&desc, NULL, &tree), NBHD_STATUS_OK);
    free(cloud); /* the tree keeps its own copy */
    if (tree != NULL) {
        check_queries(tree, 1, NULL);
    }
    nbhd_tree_free(tree);
}

/* Tables: every row against the brute force, accessors against nbhd_neighborhoods_row, the
 * same bytes for 1 and 2 threads, and batches of query points. */
static void check_table(const nbhd_neighborhoods *t, int f32, const nbhd_neighborhood_spec *spec,
                        int exclude_self, const double *qs, size_t rows) {
    const size_t *off = nbhd_neighborhoods_offsets(t);
    const uint32_t *ids = nbhd_neighborhoods_indices(t);
    const void *dists = nbhd_neighborhoods_sq_dists(t);
    size_t r;
    CHECK(nbhd_neighborhoods_rows(t) == rows);
    CHECK(off != NULL && ids != NULL && dists != NULL);
    if (off == NULL) return;
    CHECK(off[0] == 0 && off[rows] == nbhd_neighborhoods_total(t));
    for (r = 0; r < rows; r++) {
        cand want[N];
        const uint32_t *row_ids = NULL;
        const void *row_d = NULL;
        size_t len = 99, nwant;
        size_t k = spec->kind == NBHD_NEIGHBORHOOD_KIND_RADIUS ? 0 : spec->k;
        double rad = spec->kind == NBHD_NEIGHBORHOOD_KIND_KNN ? -1.0 : spec->radius;
        nwant = brute(f32, &qs[r * DIM], k, rad, exclude_self ? (long)r : -1, NULL, want);
        CHECK_STATUS(nbhd_neighborhoods_row(t, r, &row_ids, &row_d, &len), NBHD_STATUS_OK);
        CHECK(len == off[r + 1] - off[r]);
        CHECK(row_ids == ids + off[r]);
        CHECK((const char *)row_d ==
              (const char *)dists + off[r] * (f32 ? sizeof(float) : sizeof(double)));
        CHECK(same_result(f32, row_ids, row_d, len, want, nwant));
    }
}

static void test_tables(void) {
    int f32;
    for (f32 = 0; f32 <= 1; f32++) {
        nbhd_points desc = describe(f32);
        nbhd_tree *tree = NULL;
        nbhd_neighborhood_spec specs[3];
        size_t s;
        specs[0].kind = NBHD_NEIGHBORHOOD_KIND_KNN;
        specs[0].k = 8;
        specs[0].radius = 0.0;
        specs[1].kind = NBHD_NEIGHBORHOOD_KIND_RADIUS;
        specs[1].k = 0;
        specs[1].radius = 0.125;
        specs[2].kind = NBHD_NEIGHBORHOOD_KIND_KNN_RADIUS;
        specs[2].k = 5;
        specs[2].radius = 0.1875;
        CHECK_STATUS(nbhd_tree_build(&desc, NULL, &tree), NBHD_STATUS_OK);
        if (tree == NULL) continue;
        for (s = 0; s < 3; s++) {
            nbhd_table_options one = nbhd_table_options_default();
            nbhd_table_options two = nbhd_table_options_default();
            nbhd_neighborhoods *t1 = NULL, *t2 = NULL, *tq = NULL, *tin = NULL;
            nbhd_points qdesc;
            one.threads = 1;
            two.threads = 2;
            CHECK_STATUS(nbhd_tree_neighborhoods(tree, &specs[s], &one, &t1), NBHD_STATUS_OK);
            CHECK_STATUS(nbhd_tree_neighborhoods(tree, &specs[s], &two, &t2), NBHD_STATUS_OK);
            if (t1 && t2) {
                size_t total = nbhd_neighborhoods_total(t1);
                check_table(t1, f32, &specs[s], 1, pts, N);
                CHECK(total == nbhd_neighborhoods_total(t2));
                CHECK(memcmp(nbhd_neighborhoods_offsets(t1), nbhd_neighborhoods_offsets(t2),
                             (N + 1) * sizeof(size_t)) == 0);
                CHECK(memcmp(nbhd_neighborhoods_indices(t1), nbhd_neighborhoods_indices(t2),
                             total * sizeof(uint32_t)) == 0);
                CHECK(memcmp(nbhd_neighborhoods_sq_dists(t1), nbhd_neighborhoods_sq_dists(t2),
                             total * (f32 ? sizeof(float) : sizeof(double))) == 0);
            }
            /* Self included, default options through NULL... */
            {
                nbhd_table_options incl = nbhd_table_options_default();
                incl.exclude_self = false;
                CHECK_STATUS(nbhd_tree_neighborhoods(tree, &specs[s], &incl, &tin),
                             NBHD_STATUS_OK);
                if (tin) check_table(tin, f32, &specs[s], 0, pts, N);
            }
            /* ... and a batch of query points, given as doubles whatever the tree's type. */
            qdesc.data = queries;
            qdesc.count = NQ;
            qdesc.dim = DIM;
            qdesc.stride = DIM * sizeof(double);
            qdesc.scalar_type = NBHD_SCALAR_TYPE_F64;
            CHECK_STATUS(nbhd_tree_neighborhoods_of(tree, &qdesc, &specs[s], NULL, &tq),
                         NBHD_STATUS_OK);
            if (tq) check_table(tq, f32, &specs[s], 0, queries, NQ);
            nbhd_neighborhoods_free(t1);
            nbhd_neighborhoods_free(t2);
            nbhd_neighborhoods_free(tin);
            /* A table does not refer to its tree: free the tree first in the last round. */
            if (s == 2) {
                nbhd_tree_free(tree);
                tree = NULL;
                if (tq) CHECK(nbhd_neighborhoods_rows(tq) == NQ);
            }
            nbhd_neighborhoods_free(tq);
        }
        nbhd_tree_free(tree);
    }
}

/* Points with NaN and infinite coordinates: rejected naming the first, or skipped. */
static void test_non_finite(void) {
    double bad[N * DIM];
    int skip[N];
    nbhd_points desc;
    nbhd_build_options o = nbhd_build_options_default();
    nbhd_tree *tree = (nbhd_tree *)&o; /* a non-NULL sentinel: must become NULL on error */
    size_t i, count;
    memcpy(bad, pts, sizeof bad);
    memset(skip, 0, sizeof skip);
    bad[17 * DIM + 1] = NAN;
    skip[17] = 1;
    bad[42 * DIM + 2] = INFINITY;
    skip[42] = 1;
    bad[43 * DIM + 0] = -INFINITY;
    skip[43] = 1;
    desc.data = bad;
    desc.count = N;
    desc.dim = DIM;
    desc.stride = 0;
    desc.scalar_type = NBHD_SCALAR_TYPE_F64;
    CHECK_STATUS(nbhd_tree_build(&desc, &o, &tree), NBHD_STATUS_NON_FINITE);
    CHECK(tree == NULL);
    CHECK_MESSAGE("nbhd_tree_build");
    CHECK_MESSAGE("point 17");
    CHECK_MESSAGE("coordinate 1");

    /* Only an infinity: its index and coordinate are named. */
    bad[17 * DIM + 1] = 0.5;
    CHECK_STATUS(nbhd_tree_build(&desc, &o, &tree), NBHD_STATUS_NON_FINITE);
    CHECK_MESSAGE("point 42");
    CHECK_MESSAGE("coordinate 2");
    bad[17 * DIM + 1] = NAN;

    /* The same in a float cloud. */
    {
        float badf[N * DIM];
        nbhd_points df = describe(1);
        memcpy(badf, ptsf, sizeof badf);
        badf[200 * DIM] = NAN;
        df.data = badf;
        CHECK_STATUS(nbhd_tree_build(&df, NULL, &tree), NBHD_STATUS_NON_FINITE);
        CHECK_MESSAGE("point 200");
    }

    o.non_finite = NBHD_NON_FINITE_POLICY_SKIP;
    CHECK_STATUS(nbhd_tree_build(&desc, &o, &tree), NBHD_STATUS_OK);
    if (tree != NULL) {
        nbhd_stats st;
        nbhd_neighborhood_spec spec;
        nbhd_neighborhoods *t = NULL;
        cand want[N];
        size_t nwant;
        const uint32_t *row_ids = NULL;
        size_t len = 99;
        CHECK_STATUS(nbhd_tree_stats(tree, &st), NBHD_STATUS_OK);
        CHECK(st.points == N - 3 && st.source_points == N);
        /* The cloud with its points removed is what the brute force sees. */
        check_queries(tree, 0, skip);
        count = 99;
        CHECK_STATUS(nbhd_tree_knn_index(tree, 42, true, 3, idx_buf, NULL, 3, &count),
                     NBHD_STATUS_SKIPPED_POINT);
        CHECK(count == 0);
        CHECK_MESSAGE("point 42");
        CHECK_STATUS(nbhd_tree_radius_index(tree, 17, false, 0.1, idx_buf, NULL, 3, &count),
                     NBHD_STATUS_SKIPPED_POINT);
        CHECK_STATUS(nbhd_tree_knn_radius_index(tree, 43, false, 2, 0.1, idx_buf, NULL, 3,
                                                &count),
                     NBHD_STATUS_SKIPPED_POINT);
        /* The tree's copy of a point: exactly the caller's coordinates; none for a skipped
           point or an index past the points; nothing written on an error. */
        {
            double xyz[DIM] = {7.0, 7.0, 7.0};
            CHECK_STATUS(nbhd_tree_point(tree, 41, xyz), NBHD_STATUS_OK);
            CHECK(memcmp(xyz, &bad[41 * DIM], sizeof xyz) == 0);
            xyz[0] = 7.0;
            CHECK_STATUS(nbhd_tree_point(tree, 42, xyz), NBHD_STATUS_SKIPPED_POINT);
            CHECK_MESSAGE("point 42");
            CHECK(xyz[0] == 7.0);
            CHECK_STATUS(nbhd_tree_point(tree, N, xyz), NBHD_STATUS_INDEX_OUT_OF_RANGE);
            CHECK_STATUS(nbhd_tree_point(tree, (size_t)-1, xyz), NBHD_STATUS_INDEX_OUT_OF_RANGE);
            CHECK(xyz[0] == 7.0);
            CHECK_STATUS(nbhd_tree_point(NULL, 41, xyz), NBHD_STATUS_NULL_POINTER);
            CHECK_STATUS(nbhd_tree_point(tree, 41, NULL), NBHD_STATUS_NULL_POINTER);
            CHECK_STATUS(nbhd_tree_point(tree, 41, (char *)xyz + 1),
                         NBHD_STATUS_MISALIGNED_POINTER);
        }
        spec.kind = NBHD_NEIGHBORHOOD_KIND_KNN;
        spec.k = 4;
        spec.radius = 0.0;
        CHECK_STATUS(nbhd_tree_neighborhoods(tree, &spec, NULL, &t), NBHD_STATUS_OK);
        CHECK(nbhd_neighborhoods_rows(t) == N);
        CHECK_STATUS(nbhd_neighborhoods_row(t, 42, &row_ids, NULL, &len), NBHD_STATUS_OK);
        CHECK(len == 0);
        CHECK_STATUS(nbhd_neighborhoods_row(t, 41, &row_ids, NULL, &len), NBHD_STATUS_OK);
        nwant = brute(0, &bad[41 * DIM], 4, -1.0, 41, skip, want);
        CHECK(len == nwant);
        for (i = 0; i < len && i < nwant; i++) CHECK(row_ids[i] == want[i].i);
        nbhd_neighborhoods_free(t);
        nbhd_tree_free(tree);
    }

    /* Every point skipped: a tree of no point, with a row per index, all empty. */
    for (i = 0; i < N * DIM; i += DIM) bad[i] = NAN;
    tree = NULL;
    CHECK_STATUS(nbhd_tree_build(&desc, &o, &tree), NBHD_STATUS_OK);
    if (tree != NULL) {
        nbhd_stats st;
        nbhd_neighborhood_spec spec = {NBHD_NEIGHBORHOOD_KIND_KNN, 3, 0.0};
        nbhd_neighborhoods *t = NULL;
        double q[DIM] = {0.5, 0.5, 0.5};
        CHECK_STATUS(nbhd_tree_stats(tree, &st), NBHD_STATUS_OK);
        CHECK(st.points == 0 && st.source_points == N);
        count = 99;
        CHECK_STATUS(nbhd_tree_knn(tree, q, 3, idx_buf, NULL, 3, &count), NBHD_STATUS_OK);
        CHECK(count == 0);
        CHECK_STATUS(nbhd_tree_knn_index(tree, 4, false, 3, idx_buf, NULL, 3, &count),
                     NBHD_STATUS_SKIPPED_POINT);
        CHECK_STATUS(nbhd_tree_neighborhoods(tree, &spec, NULL, &t), NBHD_STATUS_OK);
        CHECK(nbhd_neighborhoods_rows(t) == N && nbhd_neighborhoods_total(t) == 0);
        nbhd_neighborhoods_free(t);
        nbhd_tree_free(tree);
    }
}

/* No point is a valid set: a tree of no point (data may then be NULL) finds nothing, has
   tables of no row, saves and loads back as one. */
static void test_empty_tree(void) {
    nbhd_points desc = describe(1);
    nbhd_tree *tree = NULL, *back = NULL;
    nbhd_stats st;
    nbhd_neighborhood_spec spec = {NBHD_NEIGHBORHOOD_KIND_RADIUS, 0, 10.0};
    nbhd_neighborhoods *t = NULL;
    float q[DIM] = {0.5f, 0.5f, 0.5f};
    unsigned char buf[1024];
    size_t count = 99, size = 0;
    desc.count = 0;
    desc.data = NULL;
    CHECK_STATUS(nbhd_tree_build(&desc, NULL, &tree), NBHD_STATUS_OK);
    if (tree == NULL) return;
    CHECK_STATUS(nbhd_tree_stats(tree, &st), NBHD_STATUS_OK);
    CHECK(st.points == 0 && st.source_points == 0 && st.leaves == 1);
    CHECK_STATUS(nbhd_tree_knn(tree, q, 5, idx_buf, NULL, 5, &count), NBHD_STATUS_OK);
    CHECK(count == 0);
    count = 99;
    CHECK_STATUS(nbhd_tree_radius(tree, q, 10.0, idx_buf, NULL, 5, &count), NBHD_STATUS_OK);
    CHECK(count == 0);
    CHECK_STATUS(nbhd_tree_knn_index(tree, 0, false, 3, idx_buf, NULL, 3, &count),
                 NBHD_STATUS_INDEX_OUT_OF_RANGE);
    CHECK_STATUS(nbhd_tree_neighborhoods(tree, &spec, NULL, &t), NBHD_STATUS_OK);
    CHECK(nbhd_neighborhoods_rows(t) == 0 && nbhd_neighborhoods_total(t) == 0);
    CHECK(nbhd_neighborhoods_offsets(t) != NULL && nbhd_neighborhoods_offsets(t)[0] == 0);
    nbhd_neighborhoods_free(t);
    CHECK_STATUS(nbhd_tree_save_to_buffer(tree, buf, sizeof buf, &size), NBHD_STATUS_OK);
    CHECK_STATUS(nbhd_tree_load_from_buffer(buf, size, &back), NBHD_STATUS_OK);
    if (back != NULL) {
        CHECK_STATUS(nbhd_tree_stats(back, &st), NBHD_STATUS_OK);
        CHECK(st.points == 0 && st.source_points == 0);
        nbhd_tree_free(back);
    }
    nbhd_tree_free(tree);
    /* A subset listing no index (NULL allowed then): no point, a row per index of the set. */
    desc = describe(1);
    tree = NULL;
    CHECK_STATUS(nbhd_tree_build_indices(&desc, NULL, 0, NULL, &tree), NBHD_STATUS_OK);
    if (tree != NULL) {
        CHECK_STATUS(nbhd_tree_stats(tree, &st), NBHD_STATUS_OK);
        CHECK(st.points == 0 && st.source_points == N);
        nbhd_tree_free(tree);
    }
}

/* Every argument error of building a tree. */
static void test_build_errors(void) {
    nbhd_points desc = describe(0);
    nbhd_build_options o = nbhd_build_options_default();
    nbhd_tree *tree = (nbhd_tree *)&o;
    char raw[64];
    int bad_enum = 7;

    CHECK_STATUS(nbhd_tree_build(NULL, NULL, &tree), NBHD_STATUS_NULL_POINTER);
    CHECK(tree == NULL);
    CHECK_MESSAGE("points");
    CHECK_STATUS(nbhd_tree_build(&desc, NULL, NULL), NBHD_STATUS_NULL_POINTER);
    CHECK_MESSAGE("out_tree");
    /* A misaligned out-pointer. */
    CHECK_STATUS(nbhd_tree_build(&desc, NULL, (nbhd_tree **)(void *)(raw + 1)),
                 NBHD_STATUS_MISALIGNED_POINTER);
    CHECK_MESSAGE("out_tree");

    desc.data = NULL;
    CHECK_STATUS(nbhd_tree_build(&desc, NULL, &tree), NBHD_STATUS_NULL_POINTER);
    CHECK_MESSAGE("points->data");

    desc = describe(0);
    desc.count = 1;
    desc.data = NULL;
    CHECK_STATUS(nbhd_tree_build(&desc, NULL, &tree), NBHD_STATUS_NULL_POINTER);
    CHECK_MESSAGE("points->data");
    desc = describe(0);
    desc.dim = 0;
    desc.count = 0;
    CHECK_STATUS(nbhd_tree_build(&desc, NULL, &tree), NBHD_STATUS_ZERO_DIMENSION);
    CHECK_MESSAGE("dimension");

    desc = describe(0);
    desc.dim = 0;
    CHECK_STATUS(nbhd_tree_build(&desc, NULL, &tree), NBHD_STATUS_ZERO_DIMENSION);
    CHECK_MESSAGE("dimension");

    /* Sizes that overflow the address space: named with the values passed. */
    desc = describe(0);
    desc.dim = SIZE_MAX / 4; /* times 8 bytes overflows */
    CHECK_STATUS(nbhd_tree_build(&desc, NULL, &tree), NBHD_STATUS_INVALID_ARGUMENT);
    CHECK_MESSAGE("points: dim ");
    CHECK_MESSAGE("times 8 bytes per coordinate");
    CHECK_MESSAGE("overflows the address space");
    desc = describe(0);
    desc.stride = SIZE_MAX / 2;
    CHECK_STATUS(nbhd_tree_build(&desc, NULL, &tree), NBHD_STATUS_INVALID_ARGUMENT);
    CHECK_MESSAGE("count 240 and stride ");
    CHECK_MESSAGE("overflows the address space");

    desc = describe(0);
    desc.stride = 16; /* one point of 3 doubles is 24 bytes */
    CHECK_STATUS(nbhd_tree_build(&desc, NULL, &tree), NBHD_STATUS_STRIDE_TOO_SMALL);
    CHECK_MESSAGE("stride 16");
    CHECK_MESSAGE("24 bytes");

#if SIZE_MAX > UINT32_MAX
    desc = describe(0);
    desc.count = (size_t)UINT32_MAX + 1; /* refused before any point is read */
    CHECK_STATUS(nbhd_tree_build(&desc, NULL, &tree), NBHD_STATUS_TOO_MANY_POINTS);
    CHECK_MESSAGE("4294967296");
#endif

    /* An enum field holding no value of its enum (as C allows). */
    desc = describe(0);
    memcpy(&desc.scalar_type, &bad_enum, sizeof bad_enum);
    CHECK_STATUS(nbhd_tree_build(&desc, NULL, &tree), NBHD_STATUS_INVALID_ARGUMENT);
    CHECK_MESSAGE("points->scalar_type is 7");

    desc = describe(0);
    o.leaf_size = 0;
    CHECK_STATUS(nbhd_tree_build(&desc, &o, &tree), NBHD_STATUS_INVALID_OPTION);
    CHECK_MESSAGE("leaf_size");
    o = nbhd_build_options_default();
    bad_enum = 42;
    memcpy(&o.pivot, &bad_enum, sizeof bad_enum);
    CHECK_STATUS(nbhd_tree_build(&desc, &o, &tree), NBHD_STATUS_INVALID_OPTION);
    CHECK_MESSAGE("pivot");
    o = nbhd_build_options_default();
    bad_enum = -1;
    memcpy(&o.median, &bad_enum, sizeof bad_enum);
    CHECK_STATUS(nbhd_tree_build(&desc, &o, &tree), NBHD_STATUS_INVALID_OPTION);
    CHECK_MESSAGE("median");
    o = nbhd_build_options_default();
    bad_enum = 2;
    memcpy(&o.non_finite, &bad_enum, sizeof bad_enum);
    CHECK_STATUS(nbhd_tree_build(&desc, &o, &tree), NBHD_STATUS_INVALID_OPTION);
    CHECK_MESSAGE("non_finite");
    CHECK(tree == NULL);

    /* Freeing NULL is a no-op. */
    nbhd_tree_free(NULL);
    nbhd_neighborhoods_free(NULL);

    /* Stats. */
    {
        nbhd_stats st;
        CHECK_STATUS(nbhd_tree_stats(NULL, &st), NBHD_STATUS_NULL_POINTER);
        CHECK_MESSAGE("tree");
        desc = describe(0);
        CHECK_STATUS(nbhd_tree_build(&desc, NULL, &tree), NBHD_STATUS_OK);
        CHECK_STATUS(nbhd_tree_stats(tree, NULL), NBHD_STATUS_NULL_POINTER);
        CHECK_MESSAGE("out_stats");
        nbhd_tree_free(tree);
    }
}

/* Every argument error of the single queries. */
static void test_query_errors(void) {
    nbhd_points desc = describe(0);
    nbhd_tree *tree = NULL;
    double q[DIM] = {0.5, 0.5, 0.5};
    double nanq[DIM] = {0.5, NAN, 0.5};
    double raw[DIM + 2];
    cand want[N];
    size_t count = 99, needed, nwant;
    CHECK_STATUS(nbhd_tree_build(&desc, NULL, &tree), NBHD_STATUS_OK);
    if (tree == NULL) return;

    /* NULL pointers: the tree, the query, the count, the indices when there is capacity. */
    CHECK_STATUS(nbhd_tree_knn(NULL, q, 3, idx_buf, dist_buf_d, 3, &count),
                 NBHD_STATUS_NULL_POINTER);
    CHECK(count == 0);
    CHECK_MESSAGE("nbhd_tree_knn: argument tree is NULL");
    CHECK_STATUS(nbhd_tree_knn(tree, NULL, 3, idx_buf, dist_buf_d, 3, &count),
                 NBHD_STATUS_NULL_POINTER);
    CHECK_MESSAGE("query");
    CHECK_STATUS(nbhd_tree_knn(tree, q, 3, idx_buf, dist_buf_d, 3, NULL),
                 NBHD_STATUS_NULL_POINTER);
    CHECK_MESSAGE("count");
    CHECK_STATUS(nbhd_tree_knn(tree, q, 3, NULL, dist_buf_d, 3, &count),
                 NBHD_STATUS_NULL_POINTER);
    CHECK_MESSAGE("indices");
    CHECK_STATUS(nbhd_tree_radius(tree, NULL, 0.1, idx_buf, NULL, 3, &count),
                 NBHD_STATUS_NULL_POINTER);
    CHECK_STATUS(nbhd_tree_knn_radius(tree, NULL, 3, 0.1, idx_buf, NULL, 3, &count),
                 NBHD_STATUS_NULL_POINTER);
    CHECK_STATUS(nbhd_tree_knn_index(NULL, 0, true, 3, idx_buf, NULL, 3, &count),
                 NBHD_STATUS_NULL_POINTER);
    CHECK_STATUS(nbhd_tree_radius_index(tree, 0, true, 0.1, idx_buf, NULL, 3, NULL),
                 NBHD_STATUS_NULL_POINTER);
    CHECK_STATUS(nbhd_tree_knn_radius_index(tree, 0, true, 3, 0.1, NULL, NULL, 3, &count),
                 NBHD_STATUS_NULL_POINTER);

    /* Misaligned pointers: a query and distances one byte off a double. */
    memcpy((char *)raw + 1, q, sizeof q);
    CHECK_STATUS(nbhd_tree_knn(tree, (char *)raw + 1, 3, idx_buf, NULL, 3, &count),
                 NBHD_STATUS_MISALIGNED_POINTER);
    CHECK_MESSAGE("query");
    CHECK_MESSAGE("not aligned to 8 bytes");
    CHECK_STATUS(nbhd_tree_knn(tree, q, 3, idx_buf, (char *)raw + 1, 3, &count),
                 NBHD_STATUS_MISALIGNED_POINTER);
    CHECK_MESSAGE("sq_dists");
    CHECK_STATUS(nbhd_tree_knn(tree, q, 3, (uint32_t *)(void *)((char *)raw + 2), NULL, 3,
                               &count),
                 NBHD_STATUS_MISALIGNED_POINTER);
    CHECK_MESSAGE("indices");

    /* k = 0; k > n gives every point. */
    CHECK_STATUS(nbhd_tree_knn(tree, q, 0, idx_buf, NULL, 3, &count), NBHD_STATUS_INVALID_K);
    CHECK_MESSAGE("k must be at least 1");
    CHECK_STATUS(nbhd_tree_knn_radius(tree, q, 0, 0.5, idx_buf, NULL, 3, &count),
                 NBHD_STATUS_INVALID_K);
    CHECK_STATUS(nbhd_tree_knn_index(tree, 3, true, 0, idx_buf, NULL, 3, &count),
                 NBHD_STATUS_INVALID_K);
    CHECK_STATUS(nbhd_tree_knn(tree, q, N + 100, idx_buf, dist_buf_d, CAP, &count),
                 NBHD_STATUS_OK);
    CHECK(count == N);
    CHECK_STATUS(nbhd_tree_knn_index(tree, 3, true, (size_t)-1, idx_buf, dist_buf_d, CAP,
                                     &count),
                 NBHD_STATUS_OK);
    CHECK(count == N - 1);

    /* Negative, NaN and infinite radii. */
    CHECK_STATUS(nbhd_tree_radius(tree, q, -0.5, idx_buf, NULL, CAP, &count),
                 NBHD_STATUS_INVALID_RADIUS);
    CHECK_MESSAGE("radius -0.5");
    CHECK_STATUS(nbhd_tree_radius(tree, q, NAN, idx_buf, NULL, CAP, &count),
                 NBHD_STATUS_INVALID_RADIUS);
    CHECK_MESSAGE("NaN");
    CHECK_STATUS(nbhd_tree_radius(tree, q, INFINITY, idx_buf, NULL, CAP, &count),
                 NBHD_STATUS_INVALID_RADIUS);
    CHECK_STATUS(nbhd_tree_knn_radius(tree, q, 3, -1.0, idx_buf, NULL, CAP, &count),
                 NBHD_STATUS_INVALID_RADIUS);
    CHECK_STATUS(nbhd_tree_radius_index(tree, 1, false, NAN, idx_buf, NULL, CAP, &count),
                 NBHD_STATUS_INVALID_RADIUS);
    CHECK_STATUS(nbhd_tree_knn_radius_index(tree, 1, false, 2, -INFINITY, idx_buf, NULL, CAP,
                                            &count),
                 NBHD_STATUS_INVALID_RADIUS);

    /* A NaN query coordinate. */
    CHECK_STATUS(nbhd_tree_knn(tree, nanq, 3, idx_buf, NULL, 3, &count),
                 NBHD_STATUS_NON_FINITE_QUERY);
    CHECK_MESSAGE("coordinate");

    /* Stored indices out of range, including beyond uint32_t. */
    CHECK_STATUS(nbhd_tree_knn_index(tree, N, true, 3, idx_buf, NULL, 3, &count),
                 NBHD_STATUS_INDEX_OUT_OF_RANGE);
    CHECK_MESSAGE("point index 240");
    CHECK_STATUS(nbhd_tree_radius_index(tree, (size_t)-1, true, 0.1, idx_buf, NULL, 3, &count),
                 NBHD_STATUS_INDEX_OUT_OF_RANGE);

    /* Buffers too small: the size needed comes back in *count, nothing is written. */
    idx_buf[0] = 12345;
    CHECK_STATUS(nbhd_tree_radius(tree, q, 0.3, idx_buf, dist_buf_d, 2, &count),
                 NBHD_STATUS_BUFFER_TOO_SMALL);
    CHECK_MESSAGE("needed");
    needed = count;
    nwant = brute(0, q, 0, 0.3, -1, NULL, want);
    CHECK(needed == nwant && needed > 2);
    CHECK(idx_buf[0] == 12345);
    /* Asking for the size alone: no buffers, capacity 0. */
    CHECK_STATUS(nbhd_tree_radius(tree, q, 0.3, NULL, NULL, 0, &count),
                 NBHD_STATUS_BUFFER_TOO_SMALL);
    CHECK(count == needed);
    CHECK_STATUS(nbhd_tree_radius(tree, q, 0.3, idx_buf, dist_buf_d, needed, &count),
                 NBHD_STATUS_OK);
    CHECK(same_result(0, idx_buf, dist_buf_d, count, want, nwant));
    CHECK_STATUS(nbhd_tree_knn(tree, q, 5, idx_buf, dist_buf_d, 4, &count),
                 NBHD_STATUS_BUFFER_TOO_SMALL);
    CHECK(count == 5);
    CHECK_STATUS(nbhd_tree_radius_index(tree, 0, true, 0.3, idx_buf, NULL, 1, &count),
                 NBHD_STATUS_BUFFER_TOO_SMALL);
    CHECK(count > 1);
    /* An empty result needs no buffer at all. */
    CHECK_STATUS(nbhd_tree_radius(tree, q, 0.0, NULL, NULL, 0, &count), NBHD_STATUS_OK);
    CHECK(count == 0);

    /* A success clears the message. */
    CHECK(nbhd_last_error_message()[0] == '\0');
    nbhd_tree_free(tree);
}

/* Every argument error of the tables and their accessors. */
static void test_table_errors(void) {
    nbhd_points desc = describe(1);
    nbhd_tree *tree = NULL;
    nbhd_neighborhood_spec spec;
    nbhd_table_options opt = nbhd_table_options_default();
    nbhd_neighborhoods *t = NULL;
    nbhd_neighborhoods *sentinel = (nbhd_neighborhoods *)&opt;
    const uint32_t *ids = NULL;
    const void *d = NULL;
    size_t len = 99;
    int bad_enum = 9;
    double q2[2 * 2] = {0.1, 0.2, 0.3, 0.4};
    double qnan[2 * DIM] = {0.1, 0.2, 0.3, 0.4, INFINITY, 0.6};
    nbhd_points qd;
    CHECK_STATUS(nbhd_tree_build(&desc, NULL, &tree), NBHD_STATUS_OK);
    if (tree == NULL) return;
    spec.kind = NBHD_NEIGHBORHOOD_KIND_KNN;
    spec.k = 3;
    spec.radius = 0.0;

    t = sentinel;
    CHECK_STATUS(nbhd_tree_neighborhoods(NULL, &spec, NULL, &t), NBHD_STATUS_NULL_POINTER);
    CHECK(t == NULL);
    CHECK_STATUS(nbhd_tree_neighborhoods(tree, NULL, NULL, &t), NBHD_STATUS_NULL_POINTER);
    CHECK_MESSAGE("spec");
    CHECK_STATUS(nbhd_tree_neighborhoods(tree, &spec, NULL, NULL), NBHD_STATUS_NULL_POINTER);
    CHECK_MESSAGE("out_table");
    spec.k = 0;
    CHECK_STATUS(nbhd_tree_neighborhoods(tree, &spec, &opt, &t), NBHD_STATUS_INVALID_K);
    spec.kind = NBHD_NEIGHBORHOOD_KIND_RADIUS;
    spec.radius = -2.0;
    CHECK_STATUS(nbhd_tree_neighborhoods(tree, &spec, &opt, &t), NBHD_STATUS_INVALID_RADIUS);
    spec.kind = NBHD_NEIGHBORHOOD_KIND_KNN_RADIUS;
    spec.k = 2;
    spec.radius = NAN;
    CHECK_STATUS(nbhd_tree_neighborhoods(tree, &spec, &opt, &t), NBHD_STATUS_INVALID_RADIUS);
    memcpy(&spec.kind, &bad_enum, sizeof bad_enum);
    CHECK_STATUS(nbhd_tree_neighborhoods(tree, &spec, &opt, &t), NBHD_STATUS_INVALID_ARGUMENT);
    CHECK_MESSAGE("spec->kind is 9");
    CHECK(t == NULL);

    spec.kind = NBHD_NEIGHBORHOOD_KIND_KNN;
    spec.k = 3;
    /* Query points of another dimension, with a non-finite coordinate, or badly described. */
    qd.data = q2;
    qd.count = 2;
    qd.dim = 2;
    qd.stride = 0;
    qd.scalar_type = NBHD_SCALAR_TYPE_F64;
    CHECK_STATUS(nbhd_tree_neighborhoods_of(tree, &qd, &spec, NULL, &t),
                 NBHD_STATUS_DIMENSION_MISMATCH);
    CHECK_MESSAGE("dimension 2");
    qd.data = qnan;
    qd.dim = DIM;
    CHECK_STATUS(nbhd_tree_neighborhoods_of(tree, &qd, &spec, NULL, &t),
                 NBHD_STATUS_NON_FINITE_QUERY);
    CHECK_MESSAGE("query point 1 has a NaN or infinite coordinate (coordinate 1)");
    /* A radius finite as a double but not as the float tree's type, or whose square is not. */
    spec.kind = NBHD_NEIGHBORHOOD_KIND_RADIUS;
    spec.radius = 1e300;
    CHECK_STATUS(nbhd_tree_neighborhoods(tree, &spec, NULL, &t), NBHD_STATUS_INVALID_RADIUS);
    CHECK_MESSAGE("radius 1e300 is too large for a tree of f32");
    spec.radius = 1e20;
    CHECK_STATUS(nbhd_tree_neighborhoods(tree, &spec, NULL, &t), NBHD_STATUS_INVALID_RADIUS);
    CHECK_MESSAGE("radius 1e20 is too large");
    spec.radius = 1e19; /* its square, 1e38, is a float */
    CHECK_STATUS(nbhd_tree_neighborhoods(tree, &spec, NULL, &t), NBHD_STATUS_OK);
    CHECK(nbhd_neighborhoods_total(t) == (size_t)N * (N - 1));
    nbhd_neighborhoods_free(t);
    t = NULL;
    spec.kind = NBHD_NEIGHBORHOOD_KIND_KNN;
    qd.count = 0; /* no query: a table of no row */
    CHECK_STATUS(nbhd_tree_neighborhoods_of(tree, &qd, &spec, NULL, &t), NBHD_STATUS_OK);
    CHECK(nbhd_neighborhoods_rows(t) == 0 && nbhd_neighborhoods_total(t) == 0);
    nbhd_neighborhoods_free(t);
    t = NULL;
    CHECK_STATUS(nbhd_tree_neighborhoods_of(tree, NULL, &spec, NULL, &t),
                 NBHD_STATUS_NULL_POINTER);
    CHECK_MESSAGE("queries");
    qd.count = 1;
    qd.data = NULL;
    CHECK_STATUS(nbhd_tree_neighborhoods_of(tree, &qd, &spec, NULL, &t),
                 NBHD_STATUS_NULL_POINTER);
    CHECK_MESSAGE("queries->data");
    CHECK(t == NULL);

    /* Accessors on NULL answer 0 / NULL; a row out of range or NULL out-pointers fail. */
    CHECK(nbhd_neighborhoods_rows(NULL) == 0);
    CHECK(nbhd_neighborhoods_total(NULL) == 0);
    CHECK(nbhd_neighborhoods_offsets(NULL) == NULL);
    CHECK(nbhd_neighborhoods_indices(NULL) == NULL);
    CHECK(nbhd_neighborhoods_sq_dists(NULL) == NULL);
    CHECK_STATUS(nbhd_neighborhoods_row(NULL, 0, &ids, &d, &len), NBHD_STATUS_NULL_POINTER);
    CHECK(len == 0 && ids == NULL && d == NULL);
    CHECK_STATUS(nbhd_tree_neighborhoods(tree, &spec, NULL, &t), NBHD_STATUS_OK);
    CHECK_STATUS(nbhd_neighborhoods_row(t, N, &ids, &d, &len), NBHD_STATUS_INVALID_ARGUMENT);
    CHECK_MESSAGE("row 240 is out of range");
    CHECK_STATUS(nbhd_neighborhoods_row(t, 0, NULL, &d, &len), NBHD_STATUS_NULL_POINTER);
    CHECK_MESSAGE("indices");
    ids = idx_buf; /* not NULL: must be reset even though the call fails on `len` */
    CHECK_STATUS(nbhd_neighborhoods_row(t, 0, &ids, &d, NULL), NBHD_STATUS_NULL_POINTER);
    CHECK_MESSAGE("len");
    CHECK(ids == NULL && d == NULL);
    CHECK_STATUS(nbhd_neighborhoods_row(t, N - 1, &ids, NULL, &len), NBHD_STATUS_OK);
    CHECK(len == 3);
    nbhd_neighborhoods_free(t);
    nbhd_tree_free(tree);
}

#if defined(__linux__)
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

/* The address space this process uses now, in bytes (from /proc/self/statm). */
static size_t address_space_now(void) {
    unsigned long pages = 0;
    FILE *f = fopen("/proc/self/statm", "r");
    if (f != NULL) {
        if (fscanf(f, "%lu", &pages) != 1) pages = 0;
        fclose(f);
    }
    return (size_t)pages * (size_t)sysconf(_SC_PAGESIZE);
}

/* In a forked child limited to its current address space plus 768 MB (RLIMIT_AS): tables
 * and smoothing whose output cannot fit return OUT_OF_MEMORY with the bytes needed, never
 * abort; afterwards the library still works in the same process. */
static void oom_child(void) {
    enum { M = 300000 };
    float *p = malloc((size_t)M * 3 * sizeof *p);
    nbhd_points desc;
    nbhd_tree *tree = NULL;
    nbhd_neighborhood_spec spec;
    nbhd_neighborhoods *t = NULL;
    nbhd_smooth_options so = nbhd_smooth_options_default();
    struct rlimit lim;
    size_t i;
    for (i = 0; i < (size_t)M * 3; i++) p[i] = (float)(next_u64() % 1000000) * 1e-6f;
    desc.data = p;
    desc.count = M;
    desc.dim = 3;
    desc.stride = 0;
    desc.scalar_type = NBHD_SCALAR_TYPE_F32;
    CHECK_STATUS(nbhd_tree_build(&desc, NULL, &tree), NBHD_STATUS_OK);
    lim.rlim_cur = lim.rlim_max = address_space_now() + ((rlim_t)768 << 20);
    CHECK(setrlimit(RLIMIT_AS, &lim) == 0);

    spec.kind = NBHD_NEIGHBORHOOD_KIND_RADIUS; /* covers every point: 9e10 entries */
    spec.k = 0;
    spec.radius = 10.0;
    CHECK_STATUS(nbhd_tree_neighborhoods(tree, &spec, NULL, &t), NBHD_STATUS_OUT_OF_MEMORY);
    CHECK_MESSAGE("out of memory: the neighbour table");
    CHECK_MESSAGE(" bytes (");
    CHECK(t == NULL);
    spec.kind = NBHD_NEIGHBORHOOD_KIND_KNN_RADIUS;
    spec.k = 1000000000;
    CHECK_STATUS(nbhd_tree_neighborhoods(tree, &spec, NULL, &t), NBHD_STATUS_OUT_OF_MEMORY);
    spec.k = SIZE_MAX;
    CHECK_STATUS(nbhd_tree_neighborhoods(tree, &spec, NULL, &t), NBHD_STATUS_OUT_OF_MEMORY);
    spec.kind = NBHD_NEIGHBORHOOD_KIND_KNN; /* known in advance: 300000 x 299999 entries */
    CHECK_STATUS(nbhd_tree_neighborhoods(tree, &spec, NULL, &t), NBHD_STATUS_OUT_OF_MEMORY);
    CHECK_MESSAGE("needs 719997600000 bytes (720.0 GB)");
    spec.kind = NBHD_NEIGHBORHOOD_KIND_RADIUS;
    CHECK_STATUS(nbhd_tree_neighborhoods_of(tree, &desc, &spec, NULL, &t),
                 NBHD_STATUS_OUT_OF_MEMORY);
    CHECK(t == NULL);
    so.k = SIZE_MAX;
    so.epsilon = 1e300;
    so.epsilon_units = NBHD_UNITS_ABSOLUTE;
    CHECK_STATUS(nbhd_smooth(&desc, &so, p, NULL, NULL), NBHD_STATUS_OUT_OF_MEMORY);
    CHECK_MESSAGE("bytes");
    /* The process is unharmed: a table that fits still works. */
    spec.kind = NBHD_NEIGHBORHOOD_KIND_KNN;
    spec.k = 8;
    CHECK_STATUS(nbhd_tree_neighborhoods(tree, &spec, NULL, &t), NBHD_STATUS_OK);
    CHECK(nbhd_neighborhoods_total(t) == (size_t)M * 8);
    nbhd_neighborhoods_free(t);
    nbhd_tree_free(tree);
    free(p);
}

static void test_out_of_memory(void) {
    const char *preload = getenv("LD_PRELOAD");
    pid_t pid;
    int status = 0;
    if (preload != NULL && strstr(preload, "vgpreload") != NULL) {
        printf("abi_test: out-of-memory checks skipped under valgrind (it needs the address space)\n");
        return;
    }
#if defined(__SANITIZE_ADDRESS__)
    /* AddressSanitizer maps terabytes of shadow memory: an address-space limit breaks it. */
    printf("abi_test: out-of-memory checks skipped under AddressSanitizer\n");
    return;
#endif
    fflush(stdout);
    pid = fork();
    if (pid == 0) {
        oom_child();
        printf("abi_test (out-of-memory child): %d checks, %d failed\n", checks, failures);
        fflush(stdout);
        _exit(failures == 0 ? 0 : 1);
    }
    CHECK(pid > 0);
    CHECK(waitpid(pid, &status, 0) == pid);
    /* Exit 0: no abort (SIGABRT), no check failed. */
    CHECK(WIFEXITED(status) && WEXITSTATUS(status) == 0);
}
#else
static void test_out_of_memory(void) {}
#endif

int main(void) {
    /* First, before any parallel call: a child forked after one would find rayon's global
     * pool gone (see the header's thread-safety notes). */
    test_out_of_memory();
    make_cloud();
    test_version_and_strings();
    test_defaults();
    test_builds_and_queries();
    test_strided_points();
    test_tables();
    test_non_finite();
    test_empty_tree();
    test_build_errors();
    test_query_errors();
    test_table_errors();
    printf("abi_test: %d checks, %d failed\n", checks, failures);
    return failures == 0 ? 0 : 1;
}
