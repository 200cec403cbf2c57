/*
 * Queries under a Minkowski metric from C (nbhd_tree_search, nbhd_dynamic_search and tables
 * with nbhd_table_options.query): each result against a brute force computed here with the
 * library's arithmetic (keys folded over the axes in order, no fused multiply-adds), on a grid
 * where many points lie exactly on the radius; strict radii; every bad option's status.
 */
#define N 400
#define DIM 3
#define CAP N

#include "brute.h"

/* A seeded grid of step 0.5: exact ties, and distances of exactly 1 in every metric. */
static void make_points(void) {
    uint64_t s = 987654321;
    size_t i;
    for (i = 0; i < N * DIM; i++) {
        s = s * 6364136223846793005ULL + 1442695040888963407ULL;
        pts[i] = (double)((s >> 33) % 7) * 0.5;
        ptsf[i] = (float)pts[i];
    }
}

/* The key of q - x in the metric, in double or float as the tree's type. */
static double key_d(const nbhd_query_options *o, const double *q, const double *x) {
    double s = 0.0;
    size_t j;
    for (j = 0; j < DIM; j++) s = term_d(o, s, fabs(q[j] - x[j]));
    return s;
}

static float key_f(const nbhd_query_options *o, const float *q, const float *x) {
    float s = 0.0f;
    size_t j;
    for (j = 0; j < DIM; j++) s = term_f(o, s, fabsf(q[j] - x[j]));
    return s;
}

static void test_metrics(int f32) {
    nbhd_points p = points_of(f32);
    nbhd_tree *tree = NULL;
    nbhd_dynamic_tree *dyn = NULL;
    nbhd_build_options b = nbhd_build_options_default();
    nbhd_points half = p;
    uint32_t first = 0;
    static const double qs[3][DIM] = {{1.0, 1.0, 1.0}, {0.3, 2.2, 1.7}, {3.0, 0.0, 1.5}};
    static const nbhd_metric metrics[5] = {NBHD_METRIC_EUCLIDEAN, NBHD_METRIC_MANHATTAN,
                                           NBHD_METRIC_CHEBYSHEV, NBHD_METRIC_MINKOWSKI,
                                           NBHD_METRIC_MINKOWSKI};
    static const double ps[5] = {2.0, 1.0, INFINITY, 3.0, 1.5};
    size_t m, s, qi, strict;
    b.leaf_size = 4;
    CHECK_STATUS(nbhd_tree_build(&p, &b, &tree), NBHD_STATUS_OK);
    CHECK_STATUS(nbhd_dynamic_create(DIM, p.scalar_type, &b, &dyn), NBHD_STATUS_OK);
    half.count = N / 2;
    CHECK_STATUS(nbhd_dynamic_insert(dyn, &half, &first), NBHD_STATUS_OK);
    half.data = f32 ? (const void *)(ptsf + N / 2 * DIM) : (const void *)(pts + N / 2 * DIM);
    CHECK_STATUS(nbhd_dynamic_insert(dyn, &half, &first), NBHD_STATUS_OK);
    CHECK(first == N / 2);
    for (m = 0; m < 5; m++) {
        for (strict = 0; strict < 2; strict++) {
            nbhd_query_options o = nbhd_query_options_default();
            nbhd_neighborhood_spec specs[3];
            o.metric = metrics[m];
            o.p = ps[m];
            o.strict = strict != 0;
            specs[0].kind = NBHD_NEIGHBORHOOD_KIND_KNN;
            specs[0].k = 9;
            specs[0].radius = 0.0;
            specs[1].kind = NBHD_NEIGHBORHOOD_KIND_RADIUS;
            specs[1].k = 0;
            specs[1].radius = 1.0;
            specs[2].kind = NBHD_NEIGHBORHOOD_KIND_KNN_RADIUS;
            specs[2].k = 5;
            specs[2].radius = 1.0;
            for (s = 0; s < 3; s++) {
                for (qi = 0; qi < 3; qi++) {
                    check_search(tree, NULL, f32, &o, &specs[s], qs[qi]);
                    check_search(NULL, dyn, f32, &o, &specs[s], qs[qi]);
                }
            }
        }
    }
    nbhd_dynamic_free(dyn);
    nbhd_tree_free(tree);
}

/* NULL options are the defaults: the answer of nbhd_tree_knn. */
static void test_defaults(void) {
    nbhd_points p = points_of(0);
    nbhd_tree *tree = NULL;
    nbhd_neighborhood_spec spec;
    nbhd_query_options d = nbhd_query_options_default();
    uint32_t a[16], b[16];
    double da[16], db[16];
    size_t na = 0, nb = 0, i;
    static const double q[DIM] = {0.7, 1.2, 2.9};
    CHECK(d.metric == NBHD_METRIC_EUCLIDEAN && d.p == 2.0 && d.eps == 0.0 && !d.strict);
    CHECK_STATUS(nbhd_tree_build(&p, NULL, &tree), NBHD_STATUS_OK);
    spec.kind = NBHD_NEIGHBORHOOD_KIND_KNN;
    spec.k = 16;
    spec.radius = 0.0;
    CHECK_STATUS(nbhd_tree_search(tree, q, &spec, NULL, a, da, 16, &na), NBHD_STATUS_OK);
    CHECK_STATUS(nbhd_tree_knn(tree, q, 16, b, db, 16, &nb), NBHD_STATUS_OK);
    CHECK(na == 16 && nb == 16);
    for (i = 0; i < 16; i++) CHECK(a[i] == b[i] && da[i] == db[i]);
    nbhd_tree_free(tree);
}

/* A table under a metric holds each point's search result (its own point left out). */
static void test_table(void) {
    nbhd_points p = points_of(0);
    nbhd_tree *tree = NULL;
    nbhd_neighborhoods *table = NULL;
    nbhd_neighborhood_spec spec;
    nbhd_table_options t = nbhd_table_options_default();
    const size_t *off;
    const uint32_t *ind;
    const double *key;
    size_t i, j;
    CHECK(t.query.metric == NBHD_METRIC_EUCLIDEAN && t.query.eps == 0.0 && !t.query.strict);
    CHECK_STATUS(nbhd_tree_build(&p, NULL, &tree), NBHD_STATUS_OK);
    spec.kind = NBHD_NEIGHBORHOOD_KIND_KNN;
    spec.k = 6;
    spec.radius = 0.0;
    t.query.metric = NBHD_METRIC_CHEBYSHEV;
    t.threads = 2;
    CHECK_STATUS(nbhd_tree_neighborhoods(tree, &spec, &t, &table), NBHD_STATUS_OK);
    off = nbhd_neighborhoods_offsets(table);
    ind = nbhd_neighborhoods_indices(table);
    key = (const double *)nbhd_neighborhoods_sq_dists(table);
    CHECK(nbhd_neighborhoods_rows(table) == N);
    for (i = 0; i < N; i += 13) {
        static entry want[N];
        size_t n = brute(&t.query, 0, pts + i * DIM, 7, -1.0, want), w = 0;
        CHECK(off[i + 1] - off[i] == 6);
        for (j = 0; j < n && w < 6; j++) {
            if (want[j].index == i) continue; /* the point itself */
            CHECK(ind[off[i] + w] == want[j].index && key[off[i] + w] == want[j].key);
            w++;
        }
    }
    nbhd_neighborhoods_free(table);
    t.query.metric = NBHD_METRIC_MINKOWSKI;
    t.query.p = 0.5;
    CHECK_STATUS(nbhd_tree_neighborhoods(tree, &spec, &t, &table), NBHD_STATUS_INVALID_OPTION);
    CHECK(table == NULL);
    nbhd_tree_free(tree);
}

/* Every bad option has its status and a message naming it. */
static void test_errors(void) {
    nbhd_points p = points_of(0);
    nbhd_tree *tree = NULL;
    nbhd_neighborhood_spec spec;
    nbhd_query_options o;
    uint32_t idx[4];
    size_t count = 7;
    static const double q[DIM] = {0.0, 0.0, 0.0};
    int bad_metric = 99;
    CHECK_STATUS(nbhd_tree_build(&p, NULL, &tree), NBHD_STATUS_OK);
    spec.kind = NBHD_NEIGHBORHOOD_KIND_KNN;
    spec.k = 4;
    spec.radius = 0.0;
    o = nbhd_query_options_default();
    o.metric = NBHD_METRIC_MINKOWSKI;
    o.p = 0.5;
    CHECK_STATUS(nbhd_tree_search(tree, q, &spec, &o, idx, NULL, 4, &count), NBHD_STATUS_INVALID_OPTION);
    CHECK_MESSAGE("p");
    CHECK(count == 0);
    o.p = NAN;
    CHECK_STATUS(nbhd_tree_search(tree, q, &spec, &o, idx, NULL, 4, &count), NBHD_STATUS_INVALID_OPTION);
    o = nbhd_query_options_default();
    o.eps = -1.0;
    CHECK_STATUS(nbhd_tree_search(tree, q, &spec, &o, idx, NULL, 4, &count), NBHD_STATUS_INVALID_OPTION);
    CHECK_MESSAGE("eps");
    o = nbhd_query_options_default();
    memcpy(&o.metric, &bad_metric, sizeof bad_metric);
    CHECK_STATUS(nbhd_tree_search(tree, q, &spec, &o, idx, NULL, 4, &count), NBHD_STATUS_INVALID_OPTION);
    CHECK_MESSAGE("nbhd_metric");
    CHECK_STATUS(nbhd_tree_search(tree, q, NULL, NULL, idx, NULL, 4, &count), NBHD_STATUS_NULL_POINTER);
    CHECK_STATUS(nbhd_tree_search(NULL, q, &spec, NULL, idx, NULL, 4, &count), NBHD_STATUS_NULL_POINTER);
    CHECK_STATUS(nbhd_tree_search(tree, q, &spec, NULL, idx, NULL, 4, NULL), NBHD_STATUS_NULL_POINTER);
    /* a radius whose key overflows: refused inclusive, no bound when strict */
    o = nbhd_query_options_default();
    o.metric = NBHD_METRIC_MINKOWSKI;
    o.p = 100.0;
    spec.kind = NBHD_NEIGHBORHOOD_KIND_KNN_RADIUS;
    spec.radius = 1e10;
    CHECK_STATUS(nbhd_tree_search(tree, q, &spec, &o, idx, NULL, 4, &count), NBHD_STATUS_INVALID_RADIUS);
    o.strict = true;
    CHECK_STATUS(nbhd_tree_search(tree, q, &spec, &o, idx, NULL, 4, &count), NBHD_STATUS_OK);
    CHECK(count == 4);
    nbhd_tree_free(tree);
}

int main(void) {
    make_points();
    test_metrics(0);
    test_metrics(1);
    test_defaults();
    test_table();
    test_errors();
    printf("metric_test: %d checks, %d failures\n", checks, failures);
    return failures == 0 ? 0 : 1;
}
