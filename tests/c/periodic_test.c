/*
 * Periodic trees from C (nbhd_tree_build_periodic, nbhd_dynamic_create_periodic,
 * nbhd_tree_boxsize): every search under every metric against a brute force computed here
 * with nearest images (min(t, L - t) per axis, the query wrapped into [0, L)), on a grid of
 * step L/4 (ties everywhere, points at exactly L/2 across the edge) with an open axis beside
 * two periodic ones; queries outside the box; radii beyond L/2; tables; every error's status.
 */
#define N 300
#define DIM 3
#define CAP N

#include "brute.h"

/* axes 0 and 2 periodic (L = 2), axis 1 open */
static const double boxsize[DIM] = {2.0, 0.0, 2.0};

static void make_points(void) {
    uint64_t s = 1234567;
    size_t i;
    for (i = 0; i < N * DIM; i++) {
        s = s * 6364136223846793005ULL + 1442695040888963407ULL;
        pts[i] = (double)((s >> 33) % 4) * 0.5; /* 0, 0.5, 1, 1.5: in [0, 2) */
        ptsf[i] = (float)pts[i];
    }
}

/* x wrapped into [0, L) as the library does (fmod is exact). */
static double wrap_d(double x, double l) {
    double r;
    if (l == 0.0 || (x >= 0.0 && x < l)) return x;
    r = fmod(x, l);
    if (r < 0.0) r = r + l;
    return r < l ? r : 0.0;
}

static float wrap_f(float x, float l) {
    float r;
    if (l == 0.0f || (x >= 0.0f && x < l)) return x;
    r = fmodf(x, l);
    if (r < 0.0f) r = r + l;
    return r < l ? r : 0.0f;
}

static double key_d(const nbhd_query_options *o, const double *q, const double *x) {
    double s = 0.0;
    size_t j;
    for (j = 0; j < DIM; j++) {
        double t = fabs(wrap_d(q[j], boxsize[j]) - x[j]);
        if (boxsize[j] > 0.0 && boxsize[j] - t < t) t = boxsize[j] - t;
        s = term_d(o, s, t);
    }
    return s;
}

static float key_f(const nbhd_query_options *o, const float *q, const float *x) {
    float s = 0.0f;
    size_t j;
    for (j = 0; j < DIM; j++) {
        float l = (float)boxsize[j];
        float t = fabsf(wrap_f(q[j], l) - x[j]);
        if (l > 0.0f && l - t < t) t = l - t;
        s = term_f(o, s, t);
    }
    return s;
}

static void test_searches(int f32) {
    nbhd_points p = points_of(f32);
    nbhd_tree *tree = NULL;
    nbhd_dynamic_tree *dyn = NULL;
    nbhd_build_options b = nbhd_build_options_default();
    nbhd_points half = p;
    uint32_t first = 0;
    double got[DIM];
    bool periodic = false;
    /* inside, on the edges, outside the box by less and more than a box */
    static const double qs[4][DIM] = {
        {0.0, 0.7, 0.0}, {1.9, 1.0, 1.0}, {-0.25, -3.0, 2.0}, {5.5, 0.2, -4.0}};
    static const nbhd_metric metrics[4] = {NBHD_METRIC_EUCLIDEAN, NBHD_METRIC_MANHATTAN,
                                           NBHD_METRIC_CHEBYSHEV, NBHD_METRIC_MINKOWSKI};
    static const double ps[4] = {2.0, 1.0, INFINITY, 3.0};
    size_t m, s, qi;
    b.leaf_size = 4;
    CHECK_STATUS(nbhd_tree_build_periodic(&p, &b, boxsize, DIM, &tree), NBHD_STATUS_OK);
    CHECK_STATUS(nbhd_dynamic_create_periodic(DIM, p.scalar_type, &b, boxsize, DIM, &dyn),
                 NBHD_STATUS_OK);
    half.count = N / 2;
    CHECK_STATUS(nbhd_dynamic_insert(dyn, &half, &first), NBHD_STATUS_OK);
    half.data = f32 ? (const void *)(ptsf + N / 2 * DIM) : (const void *)(pts + N / 2 * DIM);
    CHECK_STATUS(nbhd_dynamic_insert(dyn, &half, &first), NBHD_STATUS_OK);
    CHECK_STATUS(nbhd_tree_boxsize(tree, got, DIM, &periodic), NBHD_STATUS_OK);
    CHECK(periodic && got[0] == 2.0 && got[1] == 0.0 && got[2] == 2.0);
    CHECK_STATUS(nbhd_dynamic_boxsize(dyn, got, DIM, NULL), NBHD_STATUS_OK);
    CHECK(got[0] == 2.0 && got[1] == 0.0 && got[2] == 2.0);
    for (m = 0; m < 4; m++) {
        nbhd_query_options o = nbhd_query_options_default();
        nbhd_neighborhood_spec specs[3];
        o.metric = metrics[m];
        o.p = ps[m];
        specs[0].kind = NBHD_NEIGHBORHOOD_KIND_KNN;
        specs[0].k = 9;
        specs[0].radius = 0.0;
        specs[1].kind = NBHD_NEIGHBORHOOD_KIND_RADIUS;
        specs[1].k = 0;
        specs[1].radius = 1.25; /* beyond L/2 */
        specs[2].kind = NBHD_NEIGHBORHOOD_KIND_KNN_RADIUS;
        specs[2].k = 5;
        specs[2].radius = 0.5;
        for (s = 0; s < 3; s++) {
            for (qi = 0; qi < 4; qi++) {
                check_search(tree, NULL, f32, &o, &specs[s], qs[qi]);
                check_search(NULL, dyn, f32, &o, &specs[s], qs[qi]);
            }
        }
    }
    nbhd_dynamic_free(dyn);
    nbhd_tree_free(tree);
}

/* The plain queries and tables of a periodic tree are periodic too. */
static void test_plain_and_table(void) {
    nbhd_points p = points_of(0);
    nbhd_tree *tree = NULL;
    nbhd_neighborhoods *table = NULL;
    nbhd_neighborhood_spec spec;
    nbhd_table_options t = nbhd_table_options_default();
    nbhd_query_options d = nbhd_query_options_default();
    static entry want[N];
    uint32_t idx[8];
    double key[8];
    size_t count = 0, n, i, j;
    const size_t *off;
    const uint32_t *ind;
    const double *keys;
    static const double q[DIM] = {-0.1, 0.3, 1.95};
    CHECK_STATUS(nbhd_tree_build_periodic(&p, NULL, boxsize, DIM, &tree), NBHD_STATUS_OK);
    CHECK_STATUS(nbhd_tree_knn(tree, q, 8, idx, key, 8, &count), NBHD_STATUS_OK);
    n = brute(&d, 0, q, 8, -1.0, want);
    CHECK(count == n);
    for (i = 0; i < n; i++) CHECK(idx[i] == want[i].index && key[i] == want[i].key);
    spec.kind = NBHD_NEIGHBORHOOD_KIND_KNN;
    spec.k = 6;
    spec.radius = 0.0;
    t.threads = 2;
    t.exclude_self = true;
    CHECK_STATUS(nbhd_tree_neighborhoods(tree, &spec, &t, &table), NBHD_STATUS_OK);
    off = nbhd_neighborhoods_offsets(table);
    ind = nbhd_neighborhoods_indices(table);
    keys = (const double *)nbhd_neighborhoods_sq_dists(table);
    for (i = 0; i < N; i += 11) {
        size_t w = 0;
        n = brute(&d, 0, pts + i * DIM, 7, -1.0, want);
        CHECK(off[i + 1] - off[i] == 6);
        for (j = 0; j < n && w < 6; j++) {
            if (want[j].index == i) continue;
            CHECK(ind[off[i] + w] == want[j].index && keys[off[i] + w] == want[j].key);
            w++;
        }
    }
    nbhd_neighborhoods_free(table);
    nbhd_tree_free(tree);
}

static void test_errors(void) {
    nbhd_points p = points_of(0);
    nbhd_tree *tree = NULL;
    nbhd_dynamic_tree *dyn = NULL;
    static const double bad[DIM] = {1.0, 0.0, 2.0}; /* coordinate 0 reaches 1.5 >= 1 */
    static const double negative[1] = {-1.0};
    static const double one_box[1] = {2.0};
    static const double outside[DIM] = {0.5, 0.5, 2.0};
    nbhd_points o = p;
    double got[DIM];
    uint32_t first = 0;
    CHECK_STATUS(nbhd_tree_build_periodic(&p, NULL, bad, DIM, &tree), NBHD_STATUS_OUTSIDE_PERIOD);
    CHECK(tree == NULL);
    CHECK_MESSAGE("outside");
    CHECK_STATUS(nbhd_tree_build_periodic(&p, NULL, negative, 1, &tree), NBHD_STATUS_INVALID_OPTION);
    CHECK_MESSAGE("boxsize");
    CHECK_STATUS(nbhd_tree_build_periodic(&p, NULL, boxsize, 2, &tree), NBHD_STATUS_INVALID_OPTION);
    CHECK_STATUS(nbhd_tree_build_periodic(&p, NULL, NULL, DIM, &tree), NBHD_STATUS_NULL_POINTER);
    CHECK_STATUS(nbhd_tree_build_periodic(&p, NULL, one_box, 1, NULL), NBHD_STATUS_NULL_POINTER);
    /* one size for every axis */
    CHECK_STATUS(nbhd_tree_build_periodic(&p, NULL, one_box, 1, &tree), NBHD_STATUS_OK);
    CHECK_STATUS(nbhd_tree_boxsize(tree, got, DIM - 1, NULL), NBHD_STATUS_BUFFER_TOO_SMALL);
    CHECK_STATUS(nbhd_tree_boxsize(tree, NULL, DIM, NULL), NBHD_STATUS_NULL_POINTER);
    nbhd_tree_free(tree);
    /* a tree that is not periodic says so */
    CHECK_STATUS(nbhd_tree_build(&p, NULL, &tree), NBHD_STATUS_OK);
    {
        bool periodic = true;
        CHECK_STATUS(nbhd_tree_boxsize(tree, got, DIM, &periodic), NBHD_STATUS_OK);
        CHECK(!periodic && got[0] == 0.0 && got[2] == 0.0);
    }
    nbhd_tree_free(tree);
    /* a batch with a point outside is refused whole */
    CHECK_STATUS(nbhd_dynamic_create_periodic(DIM, NBHD_SCALAR_TYPE_F64, NULL, boxsize, DIM, &dyn),
                 NBHD_STATUS_OK);
    o.data = outside;
    o.count = 1;
    CHECK_STATUS(nbhd_dynamic_insert(dyn, &o, &first), NBHD_STATUS_OUTSIDE_PERIOD);
    CHECK_MESSAGE("outside");
    nbhd_dynamic_free(dyn);
    CHECK_STATUS(nbhd_dynamic_create_periodic(DIM, NBHD_SCALAR_TYPE_F64, NULL, negative, 1, &dyn),
                 NBHD_STATUS_INVALID_OPTION);
    CHECK(dyn == NULL);
}

int main(void) {
    make_points();
    test_searches(0);
    test_searches(1);
    test_plain_and_table();
    test_errors();
    printf("periodic_test: %d checks, %d failures\n", checks, failures);
    return failures == 0 ? 0 : 1;
}
