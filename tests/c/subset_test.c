/*
 * Trees over an index subset from C (nbhd_tree_build_indices, as PCL's
 * setInputCloud(cloud, indices)): on a PCL-like buffer (x y z pad, stride 16) with NaN holes,
 * a shuffled subset's tree answers every query, by coordinates and by index, exactly as brute
 * force over the listed finite points (the caller's indices, order by (squared distance,
 * index)); the table has a row per buffer point, empty for the unlisted and the skipped; the
 * errors name the bad index. Run by tests/c_abi.rs (also under valgrind).
 */
#include "check.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>

#define N 1500
#define K 8
#define RADIUS 0.12
#define CAP N

typedef struct {
    float x, y, z, pad;
} point4;

static point4 cloud[N];
static int listed_flag[N];
static uint32_t listed[N];
static size_t n_listed = 0;

static uint64_t rng = 0x2545F4914F6CDD1DULL;
static uint32_t next_u32(void) {
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return (uint32_t)(rng >> 32);
}
static float unit(void) { return (float)(next_u32() >> 8) / (float)(1 << 24); }

static int usable(size_t i) {
    return listed_flag[i] && !isnan(cloud[i].x) && !isnan(cloud[i].y) && !isnan(cloud[i].z);
}

static float sq_dist(const float *q, size_t i) {
    float dx = q[0] - cloud[i].x, dy = q[1] - cloud[i].y, dz = q[2] - cloud[i].z;
    return dx * dx + dy * dy + dz * dz;
}

/* Brute force over the usable points: by (sq_dist, index), at most k (k = 0: all), within r2
 * (r2 < 0: no radius), leaving out `skip` (SIZE_MAX: none). Returns the count. */
static size_t brute(const float *q, size_t k, float r2, size_t skip, uint32_t *idx, float *d) {
    size_t i, count = 0;
    for (i = 0; i < N; i++) {
        float s;
        size_t j;
        if (!usable(i) || i == skip) continue;
        s = sq_dist(q, i);
        if (r2 >= 0.0f && s > r2) continue;
        /* insertion by (s, i); i increases, so ties go after equal distances */
        j = count;
        while (j > 0 && d[j - 1] > s) {
            d[j] = d[j - 1];
            idx[j] = idx[j - 1];
            j--;
        }
        d[j] = s;
        idx[j] = (uint32_t)i;
        count++;
    }
    if (k > 0 && count > k) count = k;
    return count;
}

static int same(const uint32_t *a, const float *ad, const uint32_t *b, const float *bd,
                size_t n) {
    size_t i;
    for (i = 0; i < n; i++)
        if (a[i] != b[i] || ad[i] != bd[i]) return 0;
    return 1;
}

int main(void) {
    static uint32_t idx[CAP], want[CAP];
    static float d[CAP], want_d[CAP];
    nbhd_points pts = {cloud, N, 3, sizeof(point4), NBHD_SCALAR_TYPE_F32};
    nbhd_build_options opt = nbhd_build_options_default();
    nbhd_tree *tree = NULL;
    nbhd_stats stats;
    size_t i, count, mismatches = 0, skipped_ok = 0;
    float r2 = (float)RADIUS * (float)RADIUS;

    for (i = 0; i < N; i++) {
        cloud[i].x = unit();
        cloud[i].y = unit();
        cloud[i].z = 0.1f * unit();
        cloud[i].pad = 1.0f;
        if (i % 13 == 0) cloud[i].y = NAN; /* holes, as organized scans have */
    }
    /* Every third point or so, in shuffled order. */
    for (i = 0; i < N; i++) {
        if (next_u32() % 3 == 0) {
            listed[n_listed++] = (uint32_t)i;
            listed_flag[i] = 1;
        }
    }
    for (i = n_listed - 1; i > 0; i--) {
        size_t j = next_u32() % (i + 1);
        uint32_t t = listed[i];
        listed[i] = listed[j];
        listed[j] = t;
    }

    /* NaN holes among the listed points: rejected by default, naming one of them. */
    CHECK_STATUS(nbhd_tree_build_indices(&pts, listed, n_listed, &opt, &tree),
                 NBHD_STATUS_NON_FINITE);
    CHECK(tree == NULL);
    opt.non_finite = NBHD_NON_FINITE_POLICY_SKIP;
    CHECK_STATUS(nbhd_tree_build_indices(&pts, listed, n_listed, &opt, &tree), NBHD_STATUS_OK);
    CHECK_STATUS(nbhd_tree_stats(tree, &stats), NBHD_STATUS_OK);
    CHECK(stats.source_points == N);
    {
        size_t usable_count = 0;
        for (i = 0; i < N; i++) usable_count += (size_t)usable(i);
        CHECK(stats.points == usable_count);
    }

    for (i = 0; i < N; i++) {
        float q[3];
        size_t w;
        if (isnan(cloud[i].y)) continue;
        q[0] = cloud[i].x;
        q[1] = cloud[i].y;
        q[2] = cloud[i].z;
        /* By coordinates, from every finite buffer point, listed or not. */
        CHECK_STATUS(nbhd_tree_knn(tree, q, K, idx, d, CAP, &count), NBHD_STATUS_OK);
        w = brute(q, K, -1.0f, SIZE_MAX, want, want_d);
        if (count != w || !same(idx, d, want, want_d, w)) mismatches++;
        CHECK_STATUS(nbhd_tree_radius(tree, q, RADIUS, idx, d, CAP, &count), NBHD_STATUS_OK);
        w = brute(q, 0, r2, SIZE_MAX, want, want_d);
        if (count != w || !same(idx, d, want, want_d, w)) mismatches++;
        /* By index: listed points answer (self left out), the others are SKIPPED_POINT. */
        if (usable(i)) {
            CHECK_STATUS(nbhd_tree_knn_index(tree, i, true, K, idx, d, CAP, &count),
                         NBHD_STATUS_OK);
            w = brute(q, K, -1.0f, i, want, want_d);
            if (count != w || !same(idx, d, want, want_d, w)) mismatches++;
            CHECK_STATUS(nbhd_tree_radius_index(tree, i, false, RADIUS, idx, d, CAP, &count),
                         NBHD_STATUS_OK);
            w = brute(q, 0, r2, SIZE_MAX, want, want_d);
            if (count != w || !same(idx, d, want, want_d, w)) mismatches++;
        } else if (nbhd_tree_knn_index(tree, i, true, K, idx, d, CAP, &count) ==
                   NBHD_STATUS_SKIPPED_POINT) {
            skipped_ok++;
        } else {
            mismatches++;
        }
    }
    CHECK(mismatches == 0);
    CHECK(skipped_ok > 0);

    /* The table: a row per buffer point; the listed finite points' rows are brute force's. */
    {
        nbhd_neighborhood_spec spec = {NBHD_NEIGHBORHOOD_KIND_KNN, K, 0.0};
        nbhd_table_options to = nbhd_table_options_default();
        nbhd_neighborhoods *table = NULL;
        const size_t *off;
        const uint32_t *ti;
        const float *td;
        size_t bad_rows = 0;
        to.threads = 2;
        CHECK_STATUS(nbhd_tree_neighborhoods(tree, &spec, &to, &table), NBHD_STATUS_OK);
        CHECK(nbhd_neighborhoods_rows(table) == N);
        off = nbhd_neighborhoods_offsets(table);
        ti = nbhd_neighborhoods_indices(table);
        td = (const float *)nbhd_neighborhoods_sq_dists(table);
        for (i = 0; i < N && off != NULL; i++) {
            size_t len = off[i + 1] - off[i], w = 0;
            if (usable(i)) {
                float q[3];
                q[0] = cloud[i].x;
                q[1] = cloud[i].y;
                q[2] = cloud[i].z;
                w = brute(q, K, -1.0f, i, want, want_d);
            }
            if (len != w || !same(ti + off[i], td + off[i], want, want_d, w)) bad_rows++;
        }
        CHECK(bad_rows == 0);
        nbhd_neighborhoods_free(table);
    }
    nbhd_tree_free(tree);

    /* Errors: the index is named, nothing is made. */
    {
        uint32_t out_of_range[3] = {1, N, 2};
        uint32_t dup[4] = {9, 3, 9, 4};
        tree = NULL;
        CHECK_STATUS(nbhd_tree_build_indices(&pts, out_of_range, 3, &opt, &tree),
                     NBHD_STATUS_INDEX_OUT_OF_RANGE);
        CHECK_MESSAGE("1500");
        CHECK(tree == NULL);
        CHECK_STATUS(nbhd_tree_build_indices(&pts, dup, 4, &opt, &tree),
                     NBHD_STATUS_INVALID_ARGUMENT);
        CHECK_MESSAGE("point index 9 is listed more than once");
        /* No index listed: a tree of no point (checked in abi_test.c). */
        CHECK_STATUS(nbhd_tree_build_indices(&pts, dup, 0, &opt, &tree), NBHD_STATUS_OK);
        nbhd_tree_free(tree);
        tree = NULL;
        CHECK_STATUS(nbhd_tree_build_indices(&pts, NULL, 3, &opt, &tree),
                     NBHD_STATUS_NULL_POINTER);
        CHECK_MESSAGE("indices");
        CHECK_STATUS(nbhd_tree_build_indices(NULL, dup, 2, &opt, &tree), NBHD_STATUS_NULL_POINTER);
        CHECK_STATUS(nbhd_tree_build_indices(&pts, dup, 2, &opt, NULL), NBHD_STATUS_NULL_POINTER);
        CHECK(tree == NULL);
        /* Only holes listed, skipped: a tree of no point, a row per index of the cloud. */
        {
            uint32_t holes[2] = {0, 13};
            nbhd_stats st;
            CHECK_STATUS(nbhd_tree_build_indices(&pts, holes, 2, &opt, &tree), NBHD_STATUS_OK);
            CHECK_STATUS(nbhd_tree_stats(tree, &st), NBHD_STATUS_OK);
            CHECK(st.points == 0 && st.source_points == N);
            nbhd_tree_free(tree);
        }
    }

    printf("subset_test: %d checks, %d failures (%zu listed of %d)\n", checks, failures,
           n_listed, N);
    return failures == 0 ? 0 : 1;
}
