/*
 * Queries under a Minkowski metric from C (nbhd_tree_search, nbhd_dynamic_search and tables
 * with nbhd_table_options.query): each result against a brute force computed here with the
 * library's arithmetic (keys folded over the axes in order, no fused multiply-adds), on a grid
 * where many points lie exactly on the radius; strict radii; every bad option's status.
 */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>

#include "check.h"

#define N 400
#define DIM 3
#define CAP N

static double pts[N * DIM];
static float ptsf[N * DIM];

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
    for (j = 0; j < DIM; j++) {
        double t = fabs(q[j] - x[j]);
        switch (o->metric) {
        case NBHD_METRIC_EUCLIDEAN: s = s + t * t; break;
        case NBHD_METRIC_MANHATTAN: s = s + t; break;
        case NBHD_METRIC_CHEBYSHEV: s = t > s ? t : s; break;
        default: s = s + pow(t, o->p); break;
        }
    }
    return s;
}

static float key_f(const nbhd_query_options *o, const float *q, const float *x) {
    float s = 0.0f;
    size_t j;
    for (j = 0; j < DIM; j++) {
        float t = fabsf(q[j] - x[j]);
        switch (o->metric) {
        case NBHD_METRIC_EUCLIDEAN: s = s + t * t; break;
        case NBHD_METRIC_MANHATTAN: s = s + t; break;
        case NBHD_METRIC_CHEBYSHEV: s = t > s ? t : s; break;
        default: s = s + powf(t, (float)o->p); break;
        }
    }
    return s;
}

/* The key of a radius r in the metric (in the tree's type for f32). */
static double radius_key(const nbhd_query_options *o, double r, int f32) {
    switch (o->metric) {
    case NBHD_METRIC_EUCLIDEAN: return f32 ? (double)((float)r * (float)r) : r * r;
    case NBHD_METRIC_MANHATTAN:
    case NBHD_METRIC_CHEBYSHEV: return r;
    default: return f32 ? (double)powf((float)r, (float)o->p) : pow(r, o->p);
    }
}

typedef struct {
    double key;
    uint32_t index;
} entry;

static int by_key(const void *a, const void *b) {
    const entry *x = a, *y = b;
    if (x->key != y->key) return x->key < y->key ? -1 : 1;
    return x->index < y->index ? -1 : (x->index > y->index);
}

/* Brute force: the k (or all, k = 0) points with key within the radius's (below it if
 * strict; no radius if r < 0), by (key, index). */
static size_t brute(const nbhd_query_options *o, int f32, const double *q, size_t k, double r,
                    entry *out) {
    size_t i, n = 0;
    double bound = r < 0 ? INFINITY : radius_key(o, r, f32);
    float qf[DIM];
    for (i = 0; i < DIM; i++) qf[i] = (float)q[i];
    for (i = 0; i < N; i++) {
        double key = f32 ? (double)key_f(o, qf, ptsf + i * DIM) : key_d(o, q, pts + i * DIM);
        if (o->strict ? key < bound : key <= bound) {
            out[n].key = key;
            out[n].index = (uint32_t)i;
            n++;
        }
    }
    qsort(out, n, sizeof(entry), by_key);
    return k > 0 && n > k ? k : n;
}

static nbhd_points points_of(int f32) {
    nbhd_points p;
    p.data = f32 ? (const void *)ptsf : (const void *)pts;
    p.count = N;
    p.dim = DIM;
    p.stride = 0;
    p.scalar_type = f32 ? NBHD_SCALAR_TYPE_F32 : NBHD_SCALAR_TYPE_F64;
    return p;
}

/* One search of either flavour, compared with the brute force. */
static void check_search(const nbhd_tree *tree, const nbhd_dynamic_tree *dyn, int f32,
                         const nbhd_query_options *o, const nbhd_neighborhood_spec *spec,
                         const double *q) {
    static entry want[N];
    uint32_t idx[CAP];
    double dd[CAP];
    float df[CAP];
    float qf[DIM];
    size_t i, count = 0, n;
    const void *query = q;
    void *keys = f32 ? (void *)df : (void *)dd;
    size_t k = spec->kind == NBHD_NEIGHBORHOOD_KIND_RADIUS ? 0 : spec->k;
    double r = spec->kind == NBHD_NEIGHBORHOOD_KIND_KNN ? -1.0 : spec->radius;
    for (i = 0; i < DIM; i++) qf[i] = (float)q[i];
    if (f32) query = qf;
    n = brute(o, f32, q, k, r, want);
    if (tree) {
        CHECK_STATUS(nbhd_tree_search(tree, query, spec, o, idx, keys, CAP, &count), NBHD_STATUS_OK);
    } else {
        CHECK_STATUS(nbhd_dynamic_search(dyn, query, spec, o, idx, keys, CAP, &count), NBHD_STATUS_OK);
    }
    CHECK(count == n);
    for (i = 0; i < n && i < count; i++) {
        double key = f32 ? (double)df[i] : dd[i];
        if (idx[i] != want[i].index || key != want[i].key) {
            failures++;
            fprintf(stderr, "metric %d p %g strict %d kind %d f32 %d: entry %zu is (%u, %g), brute (%u, %g)\n",
                    (int)o->metric, o->p, (int)o->strict, (int)spec->kind, f32, i, idx[i], key,
                    want[i].index, want[i].key);
            break;
        }
    }
    checks++;
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
