/*
 * Box queries, the spacing estimate and the filters from C: each result is checked against a
 * brute-force answer computed here, and each bad input against its status.
 */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>

#include "check.h"

#define N 500
#define DIM 3

static double pts[N * DIM];
static float ptsf[N * DIM];

/* A seeded grid-ish set: coordinates on a grid of step 0.25 (many points on box faces). */
static void make_points(void) {
    uint64_t s = 12345;
    size_t i;
    for (i = 0; i < N * DIM; i++) {
        s = s * 6364136223846793005ULL + 1442695040888963407ULL;
        pts[i] = (double)((s >> 33) % 17) * 0.25;
        ptsf[i] = (float)pts[i];
    }
}

static nbhd_tree *build(int f32) {
    nbhd_points p;
    nbhd_build_options o = nbhd_build_options_default();
    nbhd_tree *tree = NULL;
    p.data = f32 ? (const void *)ptsf : (const void *)pts;
    p.count = N;
    p.dim = DIM;
    p.stride = 0;
    p.scalar_type = f32 ? NBHD_SCALAR_TYPE_F32 : NBHD_SCALAR_TYPE_F64;
    o.leaf_size = 4;
    CHECK_STATUS(nbhd_tree_build(&p, &o, &tree), NBHD_STATUS_OK);
    return tree;
}

/* Brute force: ascending indices inside the closed box. */
static size_t brute_box(const double *lo, const double *hi, uint32_t *out) {
    size_t i, j, n = 0;
    for (i = 0; i < N; i++) {
        int in = 1;
        for (j = 0; j < DIM; j++) {
            double x = pts[i * DIM + j];
            if (!(lo[j] <= x && x <= hi[j])) in = 0;
        }
        if (in) out[n++] = (uint32_t)i;
    }
    return n;
}

static void test_boxes(int f32) {
    nbhd_tree *tree = build(f32);
    static const double boxes[3][2 * DIM] = {
        {0.5, 0.25, 1.0, 2.0, 3.0, 2.5},  /* faces through grid points */
        {1.0, 0.0, 0.0, 1.0, 4.0, 4.0},   /* zero extent in x */
        {9.0, 9.0, 9.0, 10.0, 10.0, 10.0} /* outside: empty */
    };
    double allf[3 * 2 * DIM];
    float boxesf[3 * 2 * DIM];
    uint32_t want[N], got[N], batch[3 * N];
    size_t offsets[4], count = 99, total = 99, b, i, expect_total = 0;
    nbhd_box_options bo = nbhd_box_options_default();
    CHECK(bo.threads == 0);
    for (b = 0; b < 3; b++) {
        for (i = 0; i < 2 * DIM; i++) {
            allf[b * 2 * DIM + i] = boxes[b][i];
            boxesf[b * 2 * DIM + i] = (float)boxes[b][i];
        }
    }
    for (b = 0; b < 3; b++) {
        size_t n = brute_box(boxes[b], boxes[b] + DIM, want);
        const void *lo = f32 ? (const void *)(boxesf + b * 2 * DIM) : (const void *)boxes[b];
        const void *hi = f32 ? (const void *)(boxesf + b * 2 * DIM + DIM)
                             : (const void *)(boxes[b] + DIM);
        expect_total += n;
        CHECK_STATUS(nbhd_tree_in_box(tree, lo, hi, got, N, &count), NBHD_STATUS_OK);
        CHECK(count == n);
        CHECK(n == 0 || memcmp(got, want, n * sizeof(uint32_t)) == 0);
        if (n > 1) {
            /* too small: the size needed, nothing written */
            got[0] = 777;
            CHECK_STATUS(nbhd_tree_in_box(tree, lo, hi, got, 1, &count),
                         NBHD_STATUS_BUFFER_TOO_SMALL);
            CHECK(count == n && got[0] == 777);
            CHECK_STATUS(nbhd_tree_in_box(tree, lo, hi, NULL, 0, &count),
                         NBHD_STATUS_BUFFER_TOO_SMALL);
            CHECK(count == n);
        }
    }
    CHECK(expect_total > 0);
    /* the batch: same rows, any thread count */
    for (i = 1; i <= 3; i += 2) {
        const void *all = f32 ? (const void *)boxesf : (const void *)allf;
        bo.threads = i;
        CHECK_STATUS(nbhd_tree_in_boxes(tree, all, 3, &bo, offsets, batch, 3 * N, &total),
                     NBHD_STATUS_OK);
        CHECK(total == expect_total && offsets[0] == 0 && offsets[3] == total);
        for (b = 0; b < 3; b++) {
            size_t n = brute_box(boxes[b], boxes[b] + DIM, want);
            CHECK(offsets[b + 1] - offsets[b] == n);
            CHECK(n == 0 || memcmp(batch + offsets[b], want, n * sizeof(uint32_t)) == 0);
        }
        CHECK_STATUS(nbhd_tree_in_boxes(tree, all, 3, &bo, offsets, NULL, 0, &total),
                     NBHD_STATUS_BUFFER_TOO_SMALL);
        CHECK(total == expect_total);
    }
    CHECK_STATUS(nbhd_tree_in_boxes(tree, NULL, 0, NULL, offsets, NULL, 0, &total), NBHD_STATUS_OK);
    CHECK(total == 0 && offsets[0] == 0);
    /* bad boxes */
    {
        double lo[DIM] = {1.0, 0.0, 0.0}, hi[DIM] = {0.0, 1.0, 1.0};
        float lof[DIM] = {1.0f, 0.0f, 0.0f}, hif[DIM] = {0.0f, 1.0f, 1.0f};
        const void *l = f32 ? (const void *)lof : (const void *)lo;
        const void *h = f32 ? (const void *)hif : (const void *)hi;
        CHECK_STATUS(nbhd_tree_in_box(tree, l, h, got, N, &count), NBHD_STATUS_INVALID_BOX);
        CHECK(count == 0);
        CHECK_MESSAGE("min > max");
        lo[0] = NAN;
        lof[0] = NAN;
        hi[0] = 1.0;
        hif[0] = 1.0f;
        CHECK_STATUS(nbhd_tree_in_box(tree, l, h, got, N, &count), NBHD_STATUS_INVALID_BOX);
        CHECK_MESSAGE("NaN");
        CHECK_STATUS(nbhd_tree_in_box(tree, NULL, h, got, N, &count), NBHD_STATUS_NULL_POINTER);
        CHECK_STATUS(nbhd_tree_in_box(NULL, l, h, got, N, &count), NBHD_STATUS_NULL_POINTER);
        CHECK_STATUS(nbhd_tree_in_box(tree, l, h, got, N, NULL), NBHD_STATUS_NULL_POINTER);
        CHECK_STATUS(nbhd_tree_in_box(tree, (const char *)l + 1, h, got, N, &count),
                     NBHD_STATUS_MISALIGNED_POINTER);
        {
            /* two boxes, the second inverted in y */
            double inv[4 * DIM] = {0, 0, 0, 1, 1, 1, 0, 1, 0, 1, 0, 1};
            float invf[4 * DIM] = {0, 0, 0, 1, 1, 1, 0, 1, 0, 1, 0, 1};
            CHECK_STATUS(nbhd_tree_in_boxes(tree, f32 ? (const void *)invf : (const void *)inv, 2,
                                         NULL, offsets, batch, N, &total),
                         NBHD_STATUS_INVALID_BOX);
            CHECK_MESSAGE("box 1");
            CHECK(total == 0);
        }
        CHECK_STATUS(nbhd_tree_in_boxes(tree, l, 0, NULL, offsets, batch, N, &total), NBHD_STATUS_OK);
        CHECK_STATUS(nbhd_tree_in_boxes(tree, NULL, 1, NULL, offsets, batch, N, &total),
                     NBHD_STATUS_NULL_POINTER);
        CHECK_STATUS(nbhd_tree_in_boxes(tree, f32 ? (const void *)boxesf : (const void *)allf, 1, NULL, NULL, batch, N, &total),
                     NBHD_STATUS_NULL_POINTER);
        bo.threads = 5000;
        CHECK_STATUS(nbhd_tree_in_boxes(tree, f32 ? (const void *)boxesf : (const void *)allf, 1, &bo, offsets, batch, N, &total),
                     NBHD_STATUS_INVALID_OPTION);
        CHECK_MESSAGE("5000");
        CHECK_STATUS(nbhd_tree_in_boxes(tree, allf, 1, (const nbhd_box_options *)((const char *)&bo + 1), offsets, batch, N, &total),
                     NBHD_STATUS_MISALIGNED_POINTER);
        CHECK_STATUS(nbhd_tree_in_boxes(tree, allf, SIZE_MAX / 2, NULL, offsets, batch, N, &total),
                     NBHD_STATUS_INVALID_ARGUMENT);
    }
    nbhd_tree_free(tree);
}

/* The spacing against brute-force nearest distances (mean in index order, median). */
static int cmp_double(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static void test_spacing(int f32) {
    nbhd_tree *tree = build(f32);
    nbhd_spacing s, s1;
    nbhd_spacing_options so = nbhd_spacing_options_default();
    static double nearest[N];
    double sum = 0.0, median;
    size_t i, j, k;
    for (i = 0; i < N; i++) {
        double best = INFINITY;
        for (j = 0; j < N; j++) {
            double d2 = 0.0;
            if (i == j) continue;
            for (k = 0; k < DIM; k++) {
                double t = pts[i * DIM + k] - pts[j * DIM + k];
                d2 += t * t;
            }
            if (d2 < best) best = d2;
        }
        nearest[i] = sqrt(best);
        sum += nearest[i];
    }
    qsort(nearest, N, sizeof(double), cmp_double);
    median = N % 2 ? nearest[N / 2] : 0.5 * (nearest[N / 2 - 1] + nearest[N / 2]);
    CHECK(so.threads == 0);
    CHECK_STATUS(nbhd_tree_spacing(tree, NULL, &s), NBHD_STATUS_OK);
    so.threads = 3;
    CHECK_STATUS(nbhd_tree_spacing(tree, &so, &s1), NBHD_STATUS_OK);
    /* the grid coordinates are exact in float too, so every distance is the same */
    CHECK(s.points == N && s.mean == sum / N && s.median == median);
    CHECK(s1.mean == s.mean && s1.median == s.median && s1.points == s.points);
    CHECK_STATUS(nbhd_tree_spacing(NULL, NULL, &s), NBHD_STATUS_NULL_POINTER);
    CHECK(s.points == 0 && s.mean == 0.0);
    CHECK_STATUS(nbhd_tree_spacing(tree, NULL, NULL), NBHD_STATUS_NULL_POINTER);
    so.threads = 5000;
    CHECK_STATUS(nbhd_tree_spacing(tree, &so, &s), NBHD_STATUS_INVALID_OPTION);
    CHECK_MESSAGE("5000");
    CHECK_STATUS(nbhd_tree_spacing(tree, (const nbhd_spacing_options *)((const char *)&so + 1), &s),
                 NBHD_STATUS_MISALIGNED_POINTER);
    nbhd_tree_free(tree);
    {
        /* one point: no spacing */
        double one[3] = {1.0, 2.0, 3.0};
        nbhd_points p;
        nbhd_build_options o = nbhd_build_options_default();
        p.data = one;
        p.count = 1;
        p.dim = 3;
        p.stride = 0;
        p.scalar_type = NBHD_SCALAR_TYPE_F64;
        CHECK_STATUS(nbhd_tree_build(&p, &o, &tree), NBHD_STATUS_OK);
        CHECK_STATUS(nbhd_tree_spacing(tree, NULL, &s), NBHD_STATUS_INVALID_OPTION);
        CHECK_MESSAGE("at least two");
        nbhd_tree_free(tree);
    }
}

/* Outlier removal against brute force from the definitions (distances in double from the
   double points; the grid's distances are exact in float too). */
static void test_outliers(int f32) {
    nbhd_tree *tree = build(f32);
    static double dmean[N];
    uint32_t kept[N], want[N];
    uint8_t mask[N];
    size_t count = 0, nwant = 0, nwant2 = 0, i, j, c, kk;
    const size_t K = 4;
    double sum = 0.0, sq = 0.0, mean, sd;
    nbhd_statistical_outlier_options so = nbhd_statistical_outlier_options_default();
    nbhd_radius_outlier_options ro = nbhd_radius_outlier_options_default();
    /* the defaults: PCL's tutorial values, and the CLI's two neighbours */
    CHECK(so.k == 50 && so.std_ratio == 1.0 && so.threads == 0);
    CHECK(ro.min_neighbors == 2 && ro.threads == 0);
    for (i = 0; i < N; i++) {
        double best[4] = {INFINITY, INFINITY, INFINITY, INFINITY};
        double s = 0.0;
        for (j = 0; j < N; j++) {
            double d2 = 0.0;
            if (i == j) continue;
            for (c = 0; c < DIM; c++) {
                double t = pts[i * DIM + c] - pts[j * DIM + c];
                d2 += t * t;
            }
            for (kk = 0; kk < K; kk++) {
                if (d2 < best[kk]) {
                    double tmp = best[kk];
                    best[kk] = d2;
                    d2 = tmp;
                }
            }
        }
        for (kk = 0; kk < K; kk++) s += sqrt(best[kk]);
        dmean[i] = s / (double)K;
        sum += dmean[i];
    }
    mean = sum / N;
    for (i = 0; i < N; i++) sq += (dmean[i] - mean) * (dmean[i] - mean);
    sd = sqrt(sq / (N - 1));
    for (i = 0; i < N; i++)
        if (dmean[i] <= mean + 0.5 * sd) want[nwant++] = (uint32_t)i;
    CHECK(nwant > 0 && nwant < N);
    so.k = K;
    so.std_ratio = 0.5;
    so.threads = 2;
    CHECK_STATUS(nbhd_remove_statistical_outliers(tree, &so, kept, N, &count, mask),
                 NBHD_STATUS_OK);
    CHECK(count == nwant && memcmp(kept, want, nwant * sizeof(uint32_t)) == 0);
    for (i = 0, c = 0; i < N; i++) c += mask[i];
    CHECK(c == nwant && mask[want[0]] == 1);
    so.threads = 0;
    CHECK_STATUS(nbhd_remove_statistical_outliers(tree, &so, NULL, 0, &count, NULL),
                 NBHD_STATUS_BUFFER_TOO_SMALL);
    CHECK(count == nwant);
    /* NULL options are the defaults (k = 50, alpha = 1) */
    {
        uint32_t kept2[N];
        size_t count2 = 0;
        nbhd_statistical_outlier_options d = nbhd_statistical_outlier_options_default();
        CHECK_STATUS(nbhd_remove_statistical_outliers(tree, NULL, kept, N, &count, NULL),
                     NBHD_STATUS_OK);
        CHECK_STATUS(nbhd_remove_statistical_outliers(tree, &d, kept2, N, &count2, NULL),
                     NBHD_STATUS_OK);
        CHECK(count > 0 && count == count2 && memcmp(kept, kept2, count * sizeof(uint32_t)) == 0);
    }
    so.k = 0;
    CHECK_STATUS(nbhd_remove_statistical_outliers(tree, &so, kept, N, &count, NULL),
                 NBHD_STATUS_INVALID_K);
    CHECK(count == 0);
    so.k = N;
    CHECK_STATUS(nbhd_remove_statistical_outliers(tree, &so, kept, N, &count, NULL),
                 NBHD_STATUS_INVALID_OPTION);
    so.k = K;
    so.std_ratio = NAN;
    CHECK_STATUS(nbhd_remove_statistical_outliers(tree, &so, kept, N, &count, NULL),
                 NBHD_STATUS_INVALID_OPTION);
    so.std_ratio = 0.5;
    so.threads = 5000;
    CHECK_STATUS(nbhd_remove_statistical_outliers(tree, &so, kept, N, &count, NULL),
                 NBHD_STATUS_INVALID_OPTION);
    CHECK_MESSAGE("5000");
    so.threads = 0;
    CHECK_STATUS(nbhd_remove_statistical_outliers(
                     tree, (const nbhd_statistical_outlier_options *)((const char *)&so + 1), kept,
                     N, &count, NULL),
                 NBHD_STATUS_MISALIGNED_POINTER);
    CHECK_STATUS(nbhd_remove_statistical_outliers(NULL, &so, kept, N, &count, NULL),
                 NBHD_STATUS_NULL_POINTER);
    CHECK_STATUS(nbhd_remove_statistical_outliers(tree, &so, kept, N, NULL, NULL),
                 NBHD_STATUS_NULL_POINTER);
    /* radius: at least 3 other points within 0.25 (grid step: points on the sphere count) */
    nwant = 0;
    for (i = 0; i < N; i++) {
        size_t n = 0;
        for (j = 0; j < N; j++) {
            double d2 = 0.0;
            if (i == j) continue;
            for (c = 0; c < DIM; c++) {
                double t = pts[i * DIM + c] - pts[j * DIM + c];
                d2 += t * t;
            }
            if (d2 <= 0.25 * 0.25) n++;
        }
        if (n >= 3) want[nwant++] = (uint32_t)i;
        if (n >= 2) nwant2++;
    }
    CHECK(nwant > 0 && nwant < N);
    ro.min_neighbors = 3;
    ro.threads = 3;
    CHECK_STATUS(nbhd_remove_radius_outliers(tree, 0.25, &ro, kept, N, &count, mask),
                 NBHD_STATUS_OK);
    CHECK(count == nwant && memcmp(kept, want, nwant * sizeof(uint32_t)) == 0);
    for (i = 0, c = 0; i < N; i++) c += mask[i];
    CHECK(c == nwant);
    ro.min_neighbors = 0;
    ro.threads = 0;
    CHECK_STATUS(nbhd_remove_radius_outliers(tree, 0.25, &ro, kept, N, &count, NULL),
                 NBHD_STATUS_OK);
    CHECK(count == N);
    ro.min_neighbors = 3;
    CHECK_STATUS(nbhd_remove_radius_outliers(tree, -1.0, &ro, kept, N, &count, NULL),
                 NBHD_STATUS_INVALID_RADIUS);
    CHECK_STATUS(nbhd_remove_radius_outliers(tree, NAN, &ro, kept, N, &count, NULL),
                 NBHD_STATUS_INVALID_RADIUS);
    /* NULL options: the default of at least 2 other points within the radius */
    CHECK_STATUS(nbhd_remove_radius_outliers(tree, 0.25, NULL, kept, N, &count, NULL),
                 NBHD_STATUS_OK);
    CHECK(count == nwant2);
    ro.threads = 5000;
    CHECK_STATUS(nbhd_remove_radius_outliers(tree, 0.25, &ro, kept, N, &count, NULL),
                 NBHD_STATUS_INVALID_OPTION);
    ro.threads = 0;
    CHECK_STATUS(nbhd_remove_radius_outliers(tree, 0.25, &ro, kept, 1, &count, NULL),
                 NBHD_STATUS_BUFFER_TOO_SMALL);
    CHECK(count == nwant);
    CHECK_STATUS(nbhd_remove_radius_outliers(NULL, 0.25, &ro, kept, N, &count, NULL),
                 NBHD_STATUS_NULL_POINTER);
    CHECK_STATUS(nbhd_remove_radius_outliers(
                     tree, 0.25, (const nbhd_radius_outlier_options *)((const char *)&ro + 1),
                     kept, N, &count, NULL),
                 NBHD_STATUS_MISALIGNED_POINTER);
    nbhd_tree_free(tree);
}

/* Voxel grid, leaf 1 (exact): voxel = floor(x) - floor(min) per axis, linear index x fastest;
 * centroids summed in ascending index in the points' type; nearest member, ties by index. */
static void test_voxel(int f32) {
    nbhd_points p;
    static double cen[N * DIM], wsum[125 * DIM];
    static float wsumf[125 * DIM];
    uint32_t near[N];
    size_t wcount[125], count = 99, i, v, c, nv = 0;
    double lo[DIM] = {INFINITY, INFINITY, INFINITY};
    double leaf = 1.0, bad = 0.0;
    int vox[N];
    nbhd_voxel_grid_options vo = nbhd_voxel_grid_options_default();
    p.data = f32 ? (const void *)ptsf : (const void *)pts;
    p.count = N;
    p.dim = DIM;
    p.stride = 0;
    p.scalar_type = f32 ? NBHD_SCALAR_TYPE_F32 : NBHD_SCALAR_TYPE_F64;
    for (i = 0; i < N; i++)
        for (c = 0; c < DIM; c++)
            if (pts[i * DIM + c] < lo[c]) lo[c] = pts[i * DIM + c];
    for (v = 0; v < 125 * DIM; v++) { wsum[v] = 0.0; wsumf[v] = 0.0f; }
    for (v = 0; v < 125; v++) wcount[v] = 0;
    for (i = 0; i < N; i++) {
        int id = 0, mul = 1;
        for (c = 0; c < DIM; c++) {
            id += (int)(floor(pts[i * DIM + c]) - floor(lo[c])) * mul;
            mul *= 5; /* coordinates 0 .. 4 */
        }
        vox[i] = id;
        wcount[id]++;
        for (c = 0; c < DIM; c++) {
            wsum[id * DIM + c] += pts[i * DIM + c];
            wsumf[id * DIM + c] += ptsf[i * DIM + c];
        }
    }
    CHECK(vo.min_points_per_voxel == 0 && vo.threads == 0);
    vo.threads = 2;
    CHECK_STATUS(nbhd_voxel_grid(&p, &leaf, 1, &vo, cen, near, N, &count), NBHD_STATUS_OK);
    for (v = 0; v < 125; v++) {
        size_t best = N;
        double bd = INFINITY, want[DIM];
        if (wcount[v] == 0) continue;
        for (c = 0; c < DIM; c++)
            want[c] = f32 ? (double)(wsumf[v * DIM + c] / (float)wcount[v])
                          : wsum[v * DIM + c] / (double)wcount[v];
        for (i = 0; i < N; i++) {
            double d2 = 0.0;
            if (vox[i] != (int)v) continue;
            for (c = 0; c < DIM; c++) {
                double t = pts[i * DIM + c] - want[c];
                d2 += t * t;
            }
            if (d2 < bd) { bd = d2; best = i; }
        }
        if (nv < count) {
            for (c = 0; c < DIM; c++) CHECK(cen[nv * DIM + c] == want[c]);
            CHECK(near[nv] == best);
        }
        nv++;
    }
    CHECK(count == nv);
    /* one per voxel with at least 5 points; NULL outputs count only */
    {
        size_t n5 = 0;
        for (v = 0; v < 125; v++) n5 += wcount[v] >= 5;
        vo.min_points_per_voxel = 5;
        vo.threads = 1;
        CHECK_STATUS(nbhd_voxel_grid(&p, &leaf, 1, &vo, NULL, NULL, N, &count), NBHD_STATUS_OK);
        CHECK(count == n5);
        vo.threads = 5000;
        CHECK_STATUS(nbhd_voxel_grid(&p, &leaf, 1, &vo, NULL, NULL, N, &count),
                     NBHD_STATUS_INVALID_OPTION);
        CHECK_MESSAGE("5000");
        CHECK_STATUS(nbhd_voxel_grid(&p, &leaf, 1,
                                     (const nbhd_voxel_grid_options *)((const char *)&vo + 1),
                                     NULL, NULL, N, &count),
                     NBHD_STATUS_MISALIGNED_POINTER);
    }
    /* too small: the size needed in *count */
    CHECK_STATUS(nbhd_voxel_grid(&p, &leaf, 1, NULL, cen, near, 3, &count),
                 NBHD_STATUS_BUFFER_TOO_SMALL);
    CHECK(count == nv);
    CHECK_STATUS(nbhd_voxel_grid(&p, &bad, 1, NULL, cen, near, N, &count),
                 NBHD_STATUS_INVALID_OPTION);
    CHECK(count == 0);
    bad = NAN;
    CHECK_STATUS(nbhd_voxel_grid(&p, &bad, 1, NULL, cen, near, N, &count),
                 NBHD_STATUS_INVALID_OPTION);
    /* A leaf count other than 1 or the dimension is refused before `leaf` is read: here one
       value is readable, and AddressSanitizer (scripts/sanitize-test.sh) saw the library read
       two before refusing them. */
    CHECK_STATUS(nbhd_voxel_grid(&p, &leaf, 2, NULL, cen, near, N, &count),
                 NBHD_STATUS_INVALID_OPTION);
    CHECK_STATUS(nbhd_voxel_grid(&p, &leaf, SIZE_MAX, NULL, cen, near, N, &count),
                 NBHD_STATUS_INVALID_OPTION);
    CHECK_STATUS(nbhd_voxel_grid(&p, NULL, 1, NULL, cen, near, N, &count),
                 NBHD_STATUS_NULL_POINTER);
    CHECK_STATUS(nbhd_voxel_grid(NULL, &leaf, 1, NULL, cen, near, N, &count),
                 NBHD_STATUS_NULL_POINTER);
}

int main(void) {
    make_points();
    test_boxes(0);
    test_boxes(1);
    test_spacing(0);
    test_spacing(1);
    test_outliers(0);
    test_outliers(1);
    test_voxel(0);
    test_voxel(1);
    printf("features_test: %d checks, %d failures\n", checks, failures);
    return failures == 0 ? 0 : 1;
}
