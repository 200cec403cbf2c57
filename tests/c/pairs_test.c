/*
 * Pair queries from C (nbhd_tree_pairs, nbhd_tree_pairs_with, nbhd_tree_count_pairs,
 * nbhd_tree_weigh_pairs and their nbhd_dynamic_* twins) against a brute force over every pair
 * computed here (tests/c/brute.h's keys), under every metric, on a plain and a periodic tree
 * (axes 0 and 2 of size 2, axis 1 open), on a grid of step 0.5 (exact ties, pairs exactly on
 * the radius and across the box's edge); counts cumulative and not, weighted; every error's
 * status.
 */
#define N 120
#define DIM 3
#define CAP N
#define M 50 /* points of the second tree */

#include "brute.h"

static const double boxsize[DIM] = {2.0, 0.0, 2.0};
static int periodic = 0;
static double other_pts[M * DIM];

static void make_points(void) {
    uint64_t s = 42424242;
    size_t i;
    for (i = 0; i < N * DIM; i++) {
        s = s * 6364136223846793005ULL + 1442695040888963407ULL;
        pts[i] = (double)((s >> 33) % 4) * 0.5;
        ptsf[i] = (float)pts[i];
    }
    for (i = 0; i < M * DIM; i++) {
        s = s * 6364136223846793005ULL + 1442695040888963407ULL;
        other_pts[i] = (double)((s >> 33) % 4) * 0.5;
    }
}

/* The key from q to x, at the nearest image on the periodic axes when `periodic` (points and
 * queries lie in the box). */
static double key_d(const nbhd_query_options *o, const double *q, const double *x) {
    double s = 0.0;
    size_t j;
    for (j = 0; j < DIM; j++) {
        double t = fabs(q[j] - x[j]);
        if (periodic && boxsize[j] > 0.0 && boxsize[j] - t < t) t = boxsize[j] - t;
        s = term_d(o, s, t);
    }
    return s;
}

static float key_f(const nbhd_query_options *o, const float *q, const float *x) {
    float s = 0.0f;
    size_t j;
    for (j = 0; j < DIM; j++) s = term_f(o, s, fabsf(q[j] - x[j]));
    return s;
}

static nbhd_points other_points(void) {
    nbhd_points p = points_of(0);
    p.data = other_pts;
    p.count = M;
    return p;
}

/* Row i of `table` holds exactly the points j (j > i when `upper`) of `b` (count nb) whose key
 * to point i is within r, j ascending, with that key. */
static void check_rows(const nbhd_neighborhoods *table, const nbhd_query_options *o, double r,
                       const double *b, size_t nb, int upper) {
    const size_t *off = nbhd_neighborhoods_offsets(table);
    const uint32_t *ind = nbhd_neighborhoods_indices(table);
    const double *key = (const double *)nbhd_neighborhoods_sq_dists(table);
    double bound = radius_key(o, r, 0);
    size_t i, j, w, bad = 0;
    CHECK(nbhd_neighborhoods_rows(table) == N);
    for (i = 0; i < N && !bad; i++) {
        w = off[i];
        for (j = upper ? i + 1 : 0; j < nb; j++) {
            double k = key_d(o, b + j * DIM, pts + i * DIM);
            if (k > bound) continue;
            if (w >= off[i + 1] || ind[w] != j || key[w] != k) bad = 1;
            w++;
        }
        if (w != off[i + 1]) bad = 1;
        if (bad)
            fprintf(stderr, "metric %d periodic %d r %g upper %d: row %zu differs\n",
                    (int)o->metric, periodic, r, upper, i);
    }
    CHECK(!bad);
}

/* Brute-force count of pairs (i of pts, j of b) with key in (lo, hi] and their weight sum. */
static void brute_count(const nbhd_query_options *o, const double *b, size_t nb, double lo,
                        double hi, const double *wa, const double *wb, uint64_t *n, double *s) {
    size_t i, j;
    *n = 0;
    *s = 0.0;
    for (i = 0; i < N; i++) {
        for (j = 0; j < nb; j++) {
            double k = key_d(o, b + j * DIM, pts + i * DIM);
            if (k > lo && k <= hi) {
                *n += 1;
                *s += wa[i] * wb[j];
            }
        }
    }
}

static void check_counts(const nbhd_tree *a, const nbhd_tree *b, const nbhd_table_options *t) {
    static const double radii[4] = {0.0, 0.5, 0.5, 1.0};
    static double wa[N], wb[M];
    uint64_t cum[4], non[4], n;
    double wcum[4], wnon[4], s, prev = -1.0;
    nbhd_pair_weights w;
    size_t k;
    for (k = 0; k < N; k++) wa[k] = (double)(k % 3) * 0.5;
    for (k = 0; k < M; k++) wb[k] = (double)(k % 4 + 1);
    w.tree_weights = wa;
    w.tree_count = N;
    w.other_weights = wb;
    w.other_count = M;
    CHECK_STATUS(nbhd_tree_count_pairs(a, b, radii, 4, true, t, cum), NBHD_STATUS_OK);
    CHECK_STATUS(nbhd_tree_count_pairs(a, b, radii, 4, false, t, non), NBHD_STATUS_OK);
    CHECK_STATUS(nbhd_tree_weigh_pairs(a, b, radii, 4, true, &w, t, wcum), NBHD_STATUS_OK);
    CHECK_STATUS(nbhd_tree_weigh_pairs(a, b, radii, 4, false, &w, t, wnon), NBHD_STATUS_OK);
    for (k = 0; k < 4; k++) {
        double hi = radius_key(&t->query, radii[k], 0);
        brute_count(&t->query, other_pts, M, -1.0, hi, wa, wb, &n, &s);
        CHECK(cum[k] == n && wcum[k] == s);
        if (k > 0 && radii[k] == radii[k - 1]) {
            CHECK(non[k] == 0 && wnon[k] == 0.0);
        } else {
            brute_count(&t->query, other_pts, M, prev, hi, wa, wb, &n, &s);
            CHECK(non[k] == n && wnon[k] == s);
        }
        prev = hi;
    }
}

static void test_pairs(void) {
    static const nbhd_metric metrics[4] = {NBHD_METRIC_EUCLIDEAN, NBHD_METRIC_MANHATTAN,
                                           NBHD_METRIC_CHEBYSHEV, NBHD_METRIC_MINKOWSKI};
    static const double ps[4] = {2.0, 1.0, INFINITY, 3.0};
    nbhd_points p = points_of(0), q = other_points();
    size_t m, r;
    for (periodic = 0; periodic < 2; periodic++) {
        nbhd_tree *a = NULL, *b = NULL;
        nbhd_dynamic_tree *da = NULL, *db = NULL;
        uint32_t first = 0;
        if (periodic) {
            CHECK_STATUS(nbhd_tree_build_periodic(&p, NULL, boxsize, DIM, &a), NBHD_STATUS_OK);
            CHECK_STATUS(nbhd_tree_build_periodic(&q, NULL, boxsize, DIM, &b), NBHD_STATUS_OK);
        } else {
            CHECK_STATUS(nbhd_tree_build(&p, NULL, &a), NBHD_STATUS_OK);
            CHECK_STATUS(nbhd_tree_build(&q, NULL, &b), NBHD_STATUS_OK);
        }
        CHECK_STATUS(nbhd_dynamic_create(DIM, NBHD_SCALAR_TYPE_F64, NULL, &da), NBHD_STATUS_OK);
        CHECK_STATUS(nbhd_dynamic_create(DIM, NBHD_SCALAR_TYPE_F64, NULL, &db), NBHD_STATUS_OK);
        CHECK_STATUS(nbhd_dynamic_insert(da, &p, &first), NBHD_STATUS_OK);
        CHECK_STATUS(nbhd_dynamic_insert(db, &q, &first), NBHD_STATUS_OK);
        for (m = 0; m < 4; m++) {
            nbhd_table_options t = nbhd_table_options_default();
            static const double radii[3] = {0.0, 0.5, 1.0};
            t.query.metric = metrics[m];
            t.query.p = ps[m];
            t.threads = 2;
            for (r = 0; r < 3; r++) {
                nbhd_neighborhoods *table = NULL;
                CHECK_STATUS(nbhd_tree_pairs(a, radii[r], &t, &table), NBHD_STATUS_OK);
                if (table) check_rows(table, &t.query, radii[r], pts, N, 1);
                nbhd_neighborhoods_free(table);
                CHECK_STATUS(nbhd_tree_pairs_with(a, b, radii[r], &t, &table), NBHD_STATUS_OK);
                if (table) check_rows(table, &t.query, radii[r], other_pts, M, 0);
                nbhd_neighborhoods_free(table);
                if (!periodic) {
                    /* the growing trees (not periodic here) give the same rows */
                    CHECK_STATUS(nbhd_dynamic_pairs(da, radii[r], &t, &table), NBHD_STATUS_OK);
                    if (table) check_rows(table, &t.query, radii[r], pts, N, 1);
                    nbhd_neighborhoods_free(table);
                    CHECK_STATUS(nbhd_dynamic_pairs_with(da, db, radii[r], &t, &table),
                                 NBHD_STATUS_OK);
                    if (table) check_rows(table, &t.query, radii[r], other_pts, M, 0);
                    nbhd_neighborhoods_free(table);
                }
            }
            check_counts(a, b, &t);
            if (!periodic) {
                uint64_t c1[2], c2[2];
                double s1[2], s2[2];
                static const double rr[2] = {0.5, INFINITY};
                CHECK_STATUS(nbhd_tree_count_pairs(a, b, rr, 2, true, &t, c1), NBHD_STATUS_OK);
                CHECK_STATUS(nbhd_dynamic_count_pairs(da, db, rr, 2, true, &t, c2), NBHD_STATUS_OK);
                CHECK(c1[0] == c2[0] && c1[1] == c2[1] && c1[1] == (uint64_t)N * M);
                CHECK_STATUS(nbhd_tree_weigh_pairs(a, b, rr, 2, true, NULL, &t, s1), NBHD_STATUS_OK);
                CHECK_STATUS(nbhd_dynamic_weigh_pairs(da, db, rr, 2, true, NULL, &t, s2),
                             NBHD_STATUS_OK);
                CHECK(s1[0] == (double)c1[0] && s2[0] == s1[0] && s2[1] == (double)N * M);
            }
        }
        nbhd_dynamic_free(da);
        nbhd_dynamic_free(db);
        nbhd_tree_free(a);
        nbhd_tree_free(b);
    }
    periodic = 0;
}

static void test_errors(void) {
    nbhd_points p = points_of(0), f = points_of(1), line = points_of(0);
    nbhd_tree *a = NULL, *single = NULL, *flat = NULL;
    nbhd_neighborhoods *table = (nbhd_neighborhoods *)&table;
    nbhd_table_options t = nbhd_table_options_default();
    static const double down[2] = {1.0, 0.5}, nan_r[1] = {NAN};
    double bad_w[2] = {1.0, 2.0}, sums[2];
    uint64_t counts[2] = {7, 7};
    nbhd_pair_weights w;
    line.dim = 1;
    CHECK_STATUS(nbhd_tree_build(&p, NULL, &a), NBHD_STATUS_OK);
    CHECK_STATUS(nbhd_tree_build(&f, NULL, &single), NBHD_STATUS_OK);
    CHECK_STATUS(nbhd_tree_build(&line, NULL, &flat), NBHD_STATUS_OK);
    CHECK_STATUS(nbhd_tree_pairs(a, -1.0, NULL, &table), NBHD_STATUS_INVALID_RADIUS);
    CHECK(table == NULL);
    CHECK_STATUS(nbhd_tree_pairs(a, NAN, NULL, &table), NBHD_STATUS_INVALID_RADIUS);
    CHECK_STATUS(nbhd_tree_pairs(NULL, 1.0, NULL, &table), NBHD_STATUS_NULL_POINTER);
    CHECK_STATUS(nbhd_tree_pairs(a, 1.0, NULL, NULL), NBHD_STATUS_NULL_POINTER);
    CHECK_STATUS(nbhd_tree_pairs_with(a, NULL, 1.0, NULL, &table), NBHD_STATUS_NULL_POINTER);
    CHECK_STATUS(nbhd_tree_pairs_with(a, flat, 1.0, NULL, &table), NBHD_STATUS_DIMENSION_MISMATCH);
    CHECK_STATUS(nbhd_tree_pairs_with(a, single, 1.0, NULL, &table), NBHD_STATUS_INVALID_OPTION);
    CHECK_MESSAGE("scalar type");
    CHECK_STATUS(nbhd_tree_count_pairs(a, a, down, 2, false, NULL, counts),
                 NBHD_STATUS_INVALID_OPTION);
    CHECK(counts[0] == 7);
    CHECK_STATUS(nbhd_tree_count_pairs(a, a, down, 2, true, NULL, counts), NBHD_STATUS_OK);
    CHECK(counts[0] >= counts[1] && counts[1] >= N);
    CHECK_STATUS(nbhd_tree_count_pairs(a, a, nan_r, 1, true, NULL, counts),
                 NBHD_STATUS_INVALID_RADIUS);
    CHECK_STATUS(nbhd_tree_count_pairs(a, a, NULL, 2, true, NULL, counts), NBHD_STATUS_NULL_POINTER);
    CHECK_STATUS(nbhd_tree_count_pairs(a, a, down, 2, true, NULL, NULL), NBHD_STATUS_NULL_POINTER);
    CHECK_STATUS(nbhd_tree_count_pairs(a, a, NULL, 0, true, NULL, NULL), NBHD_STATUS_OK);
    t.query.eps = 0.5;
    CHECK_STATUS(nbhd_tree_count_pairs(a, a, down, 2, true, &t, counts), NBHD_STATUS_INVALID_OPTION);
    CHECK_MESSAGE("eps");
    w.tree_weights = bad_w;
    w.tree_count = 2; /* not one per point */
    w.other_weights = NULL;
    w.other_count = 0;
    CHECK_STATUS(nbhd_tree_weigh_pairs(a, a, down, 2, true, &w, NULL, sums),
                 NBHD_STATUS_INVALID_OPTION);
    CHECK_MESSAGE("weights");
    CHECK_STATUS(nbhd_tree_weigh_pairs(a, a, down, 2, true, NULL, NULL, NULL),
                 NBHD_STATUS_NULL_POINTER);
    nbhd_tree_free(a);
    nbhd_tree_free(single);
    nbhd_tree_free(flat);
}

int main(void) {
    make_points();
    test_pairs();
    test_errors();
    printf("pairs_test: %d checks, %d failures\n", checks, failures);
    return failures == 0 ? 0 : 1;
}
