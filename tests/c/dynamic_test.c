/*
 * The dynamic tree from C: batches inserted and indices removed in turn, with every query and
 * table compared after each step with a static tree (nbhd_tree_build) over the live points
 * (removed points given as NaN and skipped), which must answer identically; and every status
 * of bad input (unknown, removed, skipped and repeated indices, NaN points, zero points,
 * absurd sizes, NULL and misaligned pointers), each leaving the tree unchanged. Saving and
 * loading: after every step the tree saved to a buffer loads back into one that answers as the
 * static tree too (and from time to time the loaded tree carries on in its place); a file
 * round trip in the scratch directory argv[1]; and every refusal: NULL arguments, a small
 * buffer, a saved static tree (FORMAT_MISMATCH naming it), truncation and a flipped byte
 * (CORRUPT_DATA), a missing file (IO_ERROR).
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"

#define DIM 3
#define POOL 700
#define CAP 1024

static double pool[POOL * DIM];
static float poolf[POOL * DIM];
/* The model: coordinates of every index given, and whether it is live. */
static double coords_d[POOL * DIM];
static float coords_f[POOL * DIM];
static int live[POOL];
static int skipped[POOL];
static size_t given = 0;

static uint64_t rng_state = 0x9E3779B97F4A7C15ULL;

static uint64_t next_u64(void) {
    rng_state ^= rng_state >> 12;
    rng_state ^= rng_state << 25;
    rng_state ^= rng_state >> 27;
    return rng_state * 0x2545F4914F6CDD1DULL;
}

static size_t below(size_t n) { return (size_t)(next_u64() >> 11) % n; }

static void make_pool(void) {
    size_t i, j;
    for (i = 0; i < POOL; i++) {
        for (j = 0; j < DIM; j++) {
            /* a coarse grid: many duplicates and exact distance ties */
            pool[i * DIM + j] = (double)below(6) * 0.25;
        }
    }
    pool[17 * DIM + 1] = NAN;
    pool[333 * DIM + 0] = INFINITY;
    for (i = 0; i < POOL * DIM; i++) poolf[i] = (float)pool[i];
}

static nbhd_points points_of(int f32, const void *base, size_t first, size_t count) {
    nbhd_points p;
    p.data = f32 ? (const void *)((const float *)base + first * DIM)
                 : (const void *)((const double *)base + first * DIM);
    p.count = count;
    p.dim = DIM;
    p.stride = 0;
    p.scalar_type = f32 ? NBHD_SCALAR_TYPE_F32 : NBHD_SCALAR_TYPE_F64;
    return p;
}

/* A static tree over the model: every index given, NaN where not live, skipped. NULL if no
 * point is live. */
static nbhd_tree *static_tree(int f32) {
    static double masked_d[POOL * DIM];
    static float masked_f[POOL * DIM];
    nbhd_build_options o = nbhd_build_options_default();
    nbhd_tree *t = NULL;
    size_t i, j, n_live = 0;
    for (i = 0; i < given; i++) {
        n_live += (size_t)live[i];
        for (j = 0; j < DIM; j++) {
            masked_d[i * DIM + j] = live[i] ? coords_d[i * DIM + j] : NAN;
            masked_f[i * DIM + j] = live[i] ? coords_f[i * DIM + j] : NAN;
        }
    }
    if (n_live == 0) return NULL;
    o.non_finite = NBHD_NON_FINITE_POLICY_SKIP;
    o.leaf_size = 3;
    CHECK_STATUS(nbhd_tree_build(&(nbhd_points){f32 ? (const void *)masked_f
                                                     : (const void *)masked_d,
                                                 given, DIM, 0,
                                                 f32 ? NBHD_SCALAR_TYPE_F32
                                                     : NBHD_SCALAR_TYPE_F64},
                                 &o, &t),
                 NBHD_STATUS_OK);
    return t;
}

static uint32_t ia[CAP], ib[CAP];
static double da[CAP], db[CAP];

/* Same status, count, indices and distances (compared as bytes of the tree's type). */
static void same(nbhd_status sa, size_t ca, nbhd_status sb, size_t cb, int f32) {
    CHECK(sa == sb);
    CHECK(ca == cb);
    if (sa == NBHD_STATUS_OK && ca == cb) {
        CHECK(memcmp(ia, ib, ca * sizeof(uint32_t)) == 0);
        CHECK(memcmp(da, db, ca * (f32 ? sizeof(float) : sizeof(double))) == 0);
    }
}

static int same_table(const nbhd_neighborhoods *a, const nbhd_neighborhoods *b, int f32) {
    size_t rows = nbhd_neighborhoods_rows(a), total = nbhd_neighborhoods_total(a);
    if (rows != nbhd_neighborhoods_rows(b) || total != nbhd_neighborhoods_total(b)) return 0;
    if (memcmp(nbhd_neighborhoods_offsets(a), nbhd_neighborhoods_offsets(b),
               (rows + 1) * sizeof(size_t)) != 0)
        return 0;
    if (total == 0) return 1;
    return memcmp(nbhd_neighborhoods_indices(a), nbhd_neighborhoods_indices(b),
                  total * sizeof(uint32_t)) == 0 &&
           memcmp(nbhd_neighborhoods_sq_dists(a), nbhd_neighborhoods_sq_dists(b),
                  total * (f32 ? sizeof(float) : sizeof(double))) == 0;
}

/* The two outlier filters of `dyn` against those of `st`, the static tree over the live points:
 * the same status, count, kept indices and mask bytes (one per index given, 0 where not live). */
static void compare_filters(const nbhd_dynamic_tree *dyn, const nbhd_tree *st) {
    static unsigned char ma[POOL], mb[POOL];
    nbhd_statistical_outlier_options so = nbhd_statistical_outlier_options_default();
    nbhd_radius_outlier_options ro = nbhd_radius_outlier_options_default();
    double r = 0.25 * (double)below(4);
    size_t ca = 7, cb = 7, i;
    nbhd_status xa, xb;
    so.k = 1 + below(8);
    so.std_ratio = 0.25 * (double)below(8) - 0.5;
    so.threads = below(3);
    memset(ma, 2, sizeof ma);
    memset(mb, 3, sizeof mb);
    xa = nbhd_dynamic_remove_statistical_outliers(dyn, &so, ia, CAP, &ca, ma);
    xb = nbhd_remove_statistical_outliers(st, &so, ib, CAP, &cb, mb);
    CHECK(xa == xb && ca == cb);
    CHECK(xa != NBHD_STATUS_OK ||
          (memcmp(ia, ib, ca * sizeof ia[0]) == 0 && memcmp(ma, mb, given) == 0));
    for (i = 0; xa == NBHD_STATUS_OK && i < given; i++) CHECK(ma[i] <= live[i]);
    CHECK(ma[given] == 2); /* nothing written past next_index */
    ro.min_neighbors = below(5);
    ro.threads = below(3);
    memset(ma, 2, sizeof ma);
    memset(mb, 3, sizeof mb);
    xa = nbhd_dynamic_remove_radius_outliers(dyn, r, &ro, ia, CAP, &ca, ma);
    xb = nbhd_remove_radius_outliers(st, r, &ro, ib, CAP, &cb, mb);
    CHECK(xa == NBHD_STATUS_OK && xb == NBHD_STATUS_OK && ca == cb);
    CHECK(memcmp(ia, ib, ca * sizeof ia[0]) == 0 && memcmp(ma, mb, given) == 0);
    for (i = 0; i < given; i++) CHECK(ma[i] <= live[i]);
}

/* Every query and table of `dyn` against the static tree over the live points. */
static void compare(const nbhd_dynamic_tree *dyn, int f32) {
    nbhd_tree *st = static_tree(f32);
    nbhd_dynamic_stats stats;
    size_t i, ca, cb, n_live = 0;
    CHECK_STATUS(nbhd_dynamic_tree_stats(dyn, &stats), NBHD_STATUS_OK);
    for (i = 0; i < given; i++) n_live += (size_t)live[i];
    CHECK(stats.live == n_live);
    CHECK(stats.next_index == given);
    CHECK(stats.dim == DIM);
    CHECK(stats.scalar_type == (f32 ? NBHD_SCALAR_TYPE_F32 : NBHD_SCALAR_TYPE_F64));
    if (st == NULL) {
        float qf[DIM] = {0.5f, 0.5f, 0.5f};
        double qd[DIM] = {0.5, 0.5, 0.5};
        CHECK_STATUS(nbhd_dynamic_knn(dyn, f32 ? (const void *)qf : (const void *)qd, 4, ia,
                                      da, CAP, &ca),
                     NBHD_STATUS_OK);
        CHECK(ca == 0);
        return;
    }
    for (i = 0; i < 6; i++) {
        float qf[DIM];
        double qd[DIM];
        const void *q = f32 ? (const void *)qf : (const void *)qd;
        size_t j, k = 1 + below(12);
        double r = 0.25 * (double)below(4);
        size_t idx = below(given + 1);
        int ex = (int)below(2);
        nbhd_status sa, sb;
        for (j = 0; j < DIM; j++) {
            qd[j] = 0.125 * (double)below(12);
            qf[j] = (float)qd[j];
        }
        sa = nbhd_dynamic_knn(dyn, q, k, ia, da, CAP, &ca);
        sb = nbhd_tree_knn(st, q, k, ib, db, CAP, &cb);
        same(sa, ca, sb, cb, f32);
        sa = nbhd_dynamic_radius(dyn, q, r, ia, da, CAP, &ca);
        sb = nbhd_tree_radius(st, q, r, ib, db, CAP, &cb);
        same(sa, ca, sb, cb, f32);
        sa = nbhd_dynamic_knn_radius(dyn, q, k, r, ia, da, CAP, &ca);
        sb = nbhd_tree_knn_radius(st, q, k, r, ib, db, CAP, &cb);
        same(sa, ca, sb, cb, f32);
        /* by index: live points answer as the static tree; others by their status */
        sa = nbhd_dynamic_knn_index(dyn, idx, ex, k, ia, da, CAP, &ca);
        if (idx < given && live[idx]) {
            sb = nbhd_tree_knn_index(st, idx, ex, k, ib, db, CAP, &cb);
            same(sa, ca, sb, cb, f32);
            sa = nbhd_dynamic_radius_index(dyn, idx, ex, r, ia, da, CAP, &ca);
            sb = nbhd_tree_radius_index(st, idx, ex, r, ib, db, CAP, &cb);
            same(sa, ca, sb, cb, f32);
            sa = nbhd_dynamic_knn_radius_index(dyn, idx, ex, k, r, ia, da, CAP, &ca);
            sb = nbhd_tree_knn_radius_index(st, idx, ex, k, r, ib, db, CAP, &cb);
            same(sa, ca, sb, cb, f32);
        } else if (idx >= given) {
            CHECK(sa == NBHD_STATUS_INDEX_OUT_OF_RANGE);
        } else if (skipped[idx]) {
            CHECK(sa == NBHD_STATUS_SKIPPED_POINT);
        } else {
            CHECK(sa == NBHD_STATUS_REMOVED_POINT);
            CHECK_STATUS(nbhd_dynamic_radius_index(dyn, idx, ex, r, ia, da, CAP, &ca),
                         NBHD_STATUS_REMOVED_POINT);
            CHECK(ca == 0);
        }
    }
    {
        nbhd_neighborhood_spec spec = {NBHD_NEIGHBORHOOD_KIND_KNN, 5, 0.0};
        nbhd_neighborhood_spec eps = {NBHD_NEIGHBORHOOD_KIND_KNN_RADIUS, 4, 0.3};
        nbhd_table_options two = nbhd_table_options_default();
        nbhd_neighborhoods *a = NULL, *b = NULL;
        nbhd_points qs = points_of(f32, f32 ? (const void *)poolf : (const void *)pool, 0, 40);
        two.threads = 2;
        CHECK_STATUS(nbhd_dynamic_neighborhoods(dyn, &spec, NULL, &a), NBHD_STATUS_OK);
        CHECK_STATUS(nbhd_tree_neighborhoods(st, &spec, NULL, &b), NBHD_STATUS_OK);
        CHECK(a != NULL && b != NULL && same_table(a, b, f32));
        nbhd_neighborhoods_free(a);
        CHECK_STATUS(nbhd_dynamic_neighborhoods(dyn, &eps, &two, &a), NBHD_STATUS_OK);
        nbhd_neighborhoods_free(b);
        CHECK_STATUS(nbhd_tree_neighborhoods(st, &eps, NULL, &b), NBHD_STATUS_OK);
        CHECK(a != NULL && b != NULL && same_table(a, b, f32));
        nbhd_neighborhoods_free(a);
        nbhd_neighborhoods_free(b);
        /* the pool's first points hold a NaN at 17: NON_FINITE_QUERY for both */
        CHECK_STATUS(nbhd_dynamic_neighborhoods_of(dyn, &qs, &spec, NULL, &a),
                     NBHD_STATUS_NON_FINITE_QUERY);
        CHECK(a == NULL);
        qs.count = 17;
        CHECK_STATUS(nbhd_dynamic_neighborhoods_of(dyn, &qs, &spec, &two, &a), NBHD_STATUS_OK);
        CHECK_STATUS(nbhd_tree_neighborhoods_of(st, &qs, &spec, NULL, &b), NBHD_STATUS_OK);
        CHECK(a != NULL && b != NULL && same_table(a, b, f32));
        nbhd_neighborhoods_free(a);
        nbhd_neighborhoods_free(b);
    }
    { /* boxes (one and a batch) and the spacing: the live points, as the static tree's */
        double bd[3 * 2 * DIM];
        float bf[3 * 2 * DIM];
        const void *boxes = f32 ? (const void *)bf : (const void *)bd;
        size_t oa[4], ob[4], ta = 0, tb = 0, b, j;
        nbhd_box_options two = nbhd_box_options_default();
        nbhd_spacing_options one = nbhd_spacing_options_default();
        nbhd_spacing sa, sb;
        nbhd_status xa, xb;
        for (b = 0; b < 3; b++)
            for (j = 0; j < DIM; j++) {
                double lo = 0.125 * (double)below(8);
                bd[b * 2 * DIM + j] = lo;
                bd[b * 2 * DIM + DIM + j] = lo + 0.25 * (double)below(4);
            }
        for (j = 0; j < 3 * 2 * DIM; j++) bf[j] = (float)bd[j];
        xa = nbhd_dynamic_in_box(dyn, boxes, (const char *)boxes + DIM * (f32 ? 4 : 8), ia, CAP,
                                 &ca);
        xb = nbhd_tree_in_box(st, boxes, (const char *)boxes + DIM * (f32 ? 4 : 8), ib, CAP, &cb);
        CHECK(xa == NBHD_STATUS_OK && xb == NBHD_STATUS_OK && ca == cb);
        CHECK(ca == cb && memcmp(ia, ib, ca * sizeof ia[0]) == 0);
        two.threads = 2;
        xa = nbhd_dynamic_in_boxes(dyn, boxes, 3, &two, oa, ia, CAP, &ta);
        xb = nbhd_tree_in_boxes(st, boxes, 3, NULL, ob, ib, CAP, &tb);
        CHECK(xa == NBHD_STATUS_OK && xb == NBHD_STATUS_OK && ta == tb);
        CHECK(ta == tb && memcmp(oa, ob, sizeof oa) == 0 && memcmp(ia, ib, ta * sizeof ia[0]) == 0);
        one.threads = 1;
        xa = nbhd_dynamic_spacing(dyn, &one, &sa);
        xb = nbhd_tree_spacing(st, NULL, &sb);
        CHECK(xa == xb);
        CHECK(xa != NBHD_STATUS_OK ||
              (memcmp(&sa.mean, &sb.mean, sizeof sa.mean) == 0 &&
               memcmp(&sa.median, &sb.median, sizeof sa.median) == 0 && sa.points == sb.points));
    }
    compare_filters(dyn, st);
    nbhd_tree_free(st);
}

/* Random batches and removals, compared after each step. */
static void test_interleaved(int f32) {
    nbhd_build_options o = nbhd_build_options_default();
    nbhd_dynamic_tree *dyn = NULL;
    size_t used = 0, step;
    given = 0;
    o.non_finite = NBHD_NON_FINITE_POLICY_SKIP;
    o.leaf_size = 3;
    o.threads = 1;
    CHECK_STATUS(nbhd_dynamic_create(DIM, f32 ? NBHD_SCALAR_TYPE_F32 : NBHD_SCALAR_TYPE_F64, &o,
                                     &dyn),
                 NBHD_STATUS_OK);
    if (dyn == NULL) return;
    for (step = 0; step < 24; step++) {
        if (below(2) == 0 && used < POOL) {
            size_t m = 1 + below(90), i, j;
            uint32_t first = 12345;
            nbhd_points p;
            if (m > POOL - used) m = POOL - used;
            /* the batch in the other type: converted to the tree's */
            p = points_of(!f32, f32 ? (const void *)pool : (const void *)poolf, used, m);
            CHECK_STATUS(nbhd_dynamic_insert(dyn, &p, &first), NBHD_STATUS_OK);
            CHECK(first == given);
            for (i = 0; i < m; i++, given++) {
                int ok = 1;
                for (j = 0; j < DIM; j++) {
                    double c = f32 ? (double)pool[(used + i) * DIM + j]
                                   : (double)poolf[(used + i) * DIM + j];
                    coords_d[given * DIM + j] = c;
                    coords_f[given * DIM + j] = (float)c;
                    ok &= isfinite(c) != 0;
                }
                live[given] = ok;
                skipped[given] = !ok;
            }
            used += m;
        } else {
            uint32_t victims[64];
            size_t n = 0, tries;
            for (tries = 0; tries < 200 && n < 64 && given > 0; tries++) {
                size_t i = below(given), v;
                int dup = 0;
                for (v = 0; v < n; v++) dup |= victims[v] == i;
                if (live[i] && !dup) victims[n++] = (uint32_t)i;
            }
            CHECK_STATUS(nbhd_dynamic_remove(dyn, victims, n), NBHD_STATUS_OK);
            while (n > 0) live[victims[--n]] = 0;
        }
        compare(dyn, f32);
        {
            /* saved and loaded back: the same answers; sometimes it carries on instead */
            size_t size = 0;
            unsigned char *buf;
            nbhd_dynamic_tree *back = NULL;
            CHECK_STATUS(nbhd_dynamic_save_to_buffer(dyn, NULL, 0, &size),
                         NBHD_STATUS_BUFFER_TOO_SMALL);
            buf = (unsigned char *)malloc(size);
            CHECK(buf != NULL);
            if (buf == NULL) continue;
            CHECK_STATUS(nbhd_dynamic_save_to_buffer(dyn, buf, size, &size), NBHD_STATUS_OK);
            CHECK_STATUS(nbhd_dynamic_load_from_buffer(buf, size, &back), NBHD_STATUS_OK);
            free(buf);
            if (back == NULL) continue;
            compare(back, f32);
            if (step % 5 == 4) {
                nbhd_dynamic_free(dyn);
                dyn = back;
            } else {
                nbhd_dynamic_free(back);
            }
        }
    }
    nbhd_dynamic_free(dyn);
}

/* Saving and loading: a file round trip and every refusal. */
static void test_saved(const char *dir) {
    char path[4096];
    double two[2 * DIM] = {0, 0, 0, 1, 1, 1};
    nbhd_points p = {two, 2, DIM, 0, NBHD_SCALAR_TYPE_F64};
    nbhd_dynamic_tree *dyn = NULL, *back = (nbhd_dynamic_tree *)two;
    nbhd_dynamic_stats sa, sb;
    nbhd_tree *st = NULL;
    unsigned char *buf, *sbuf;
    size_t size = 0, ssize = 0, count = 0;
    uint32_t ids[4];
    double q[DIM] = {0.9, 0.9, 0.9};
    CHECK_STATUS(nbhd_dynamic_create(DIM, NBHD_SCALAR_TYPE_F64, NULL, &dyn), NBHD_STATUS_OK);
    if (dyn == NULL) return;
    CHECK_STATUS(nbhd_dynamic_insert(dyn, &p, NULL), NBHD_STATUS_OK);
    CHECK_STATUS(nbhd_dynamic_insert(dyn, &p, NULL), NBHD_STATUS_OK);
    ids[0] = 1;
    CHECK_STATUS(nbhd_dynamic_remove(dyn, ids, 1), NBHD_STATUS_OK);

    /* a file round trip */
    snprintf(path, sizeof path, "%s/map.nbhdfrst", dir);
    CHECK_STATUS(nbhd_dynamic_save(dyn, path), NBHD_STATUS_OK);
    CHECK_STATUS(nbhd_dynamic_load(path, &back), NBHD_STATUS_OK);
    CHECK(back != NULL);
    if (back != NULL) {
        CHECK_STATUS(nbhd_dynamic_tree_stats(dyn, &sa), NBHD_STATUS_OK);
        CHECK_STATUS(nbhd_dynamic_tree_stats(back, &sb), NBHD_STATUS_OK);
        CHECK(sa.live == sb.live && sa.next_index == sb.next_index && sa.trees == sb.trees &&
              sa.removed_held == sb.removed_held && sb.scalar_type == NBHD_SCALAR_TYPE_F64);
        CHECK_STATUS(nbhd_dynamic_knn(back, q, 2, ids, NULL, 4, &count), NBHD_STATUS_OK);
        /* (1,1,1) is held by indices 1 (removed) and 3 */
        CHECK(count == 2 && ids[0] == 3 && ids[1] == 0);
        CHECK_STATUS(nbhd_dynamic_knn_index(back, 1, false, 1, ids, NULL, 4, &count),
                     NBHD_STATUS_REMOVED_POINT);
        CHECK_STATUS(nbhd_dynamic_insert(back, &p, ids), NBHD_STATUS_OK);
        CHECK(ids[0] == 4);
        nbhd_dynamic_free(back);
    }

    /* NULL arguments, a small buffer, paths */
    CHECK_STATUS(nbhd_dynamic_save(NULL, path), NBHD_STATUS_NULL_POINTER);
    CHECK_STATUS(nbhd_dynamic_save(dyn, NULL), NBHD_STATUS_NULL_POINTER);
    CHECK_STATUS(nbhd_dynamic_save(dyn, ""), NBHD_STATUS_INVALID_ARGUMENT);
    snprintf(path, sizeof path, "%s/no/such/dir/map.nbhdfrst", dir);
    CHECK_STATUS(nbhd_dynamic_save(dyn, path), NBHD_STATUS_IO_ERROR);
    back = (nbhd_dynamic_tree *)two;
    CHECK_STATUS(nbhd_dynamic_load(path, &back), NBHD_STATUS_IO_ERROR);
    CHECK(back == NULL);
    CHECK_MESSAGE("no/such/dir");
    CHECK_STATUS(nbhd_dynamic_load(NULL, &back), NBHD_STATUS_NULL_POINTER);
    CHECK_STATUS(nbhd_dynamic_save_to_buffer(dyn, NULL, 0, NULL), NBHD_STATUS_NULL_POINTER);
    CHECK_STATUS(nbhd_dynamic_save_to_buffer(NULL, NULL, 0, &size), NBHD_STATUS_NULL_POINTER);
    CHECK_STATUS(nbhd_dynamic_save_to_buffer(dyn, NULL, 0, &size), NBHD_STATUS_BUFFER_TOO_SMALL);
    CHECK(size > 128);
    buf = (unsigned char *)malloc(size);
    CHECK(buf != NULL);
    if (buf == NULL) return;
    CHECK_STATUS(nbhd_dynamic_save_to_buffer(dyn, buf, size - 1, &size),
                 NBHD_STATUS_BUFFER_TOO_SMALL);
    CHECK_STATUS(nbhd_dynamic_save_to_buffer(dyn, NULL, size, &size), NBHD_STATUS_NULL_POINTER);
    CHECK_STATUS(nbhd_dynamic_save_to_buffer(dyn, buf, size, &size), NBHD_STATUS_OK);
    CHECK_STATUS(nbhd_dynamic_load_from_buffer(NULL, size, &back), NBHD_STATUS_NULL_POINTER);
    CHECK_STATUS(nbhd_dynamic_load_from_buffer(buf, size, NULL), NBHD_STATUS_NULL_POINTER);
    CHECK_STATUS(nbhd_dynamic_load_from_buffer(buf, SIZE_MAX, &back),
                 NBHD_STATUS_INVALID_ARGUMENT);

    /* truncated, a flipped byte, a static tree where a dynamic one is asked (and back) */
    back = (nbhd_dynamic_tree *)two;
    CHECK_STATUS(nbhd_dynamic_load_from_buffer(buf, size - 8, &back), NBHD_STATUS_CORRUPT_DATA);
    CHECK(back == NULL);
    CHECK_MESSAGE("truncated");
    buf[size - 20] ^= 0x10;
    CHECK_STATUS(nbhd_dynamic_load_from_buffer(buf, size, &back), NBHD_STATUS_CORRUPT_DATA);
    CHECK_MESSAGE("CRC-32");
    buf[size - 20] ^= 0x10;
    CHECK_STATUS(nbhd_tree_load_from_buffer(buf, size, &st), NBHD_STATUS_FORMAT_MISMATCH);
    CHECK_MESSAGE("a dynamic tree");
    CHECK(st == NULL);
    p.count = 2;
    CHECK_STATUS(nbhd_tree_build(&p, NULL, &st), NBHD_STATUS_OK);
    CHECK_STATUS(nbhd_tree_save_to_buffer(st, NULL, 0, &ssize), NBHD_STATUS_BUFFER_TOO_SMALL);
    sbuf = (unsigned char *)malloc(ssize);
    CHECK(sbuf != NULL);
    if (sbuf != NULL) {
        CHECK_STATUS(nbhd_tree_save_to_buffer(st, sbuf, ssize, &ssize), NBHD_STATUS_OK);
        CHECK_STATUS(nbhd_dynamic_load_from_buffer(sbuf, ssize, &back),
                     NBHD_STATUS_FORMAT_MISMATCH);
        CHECK_MESSAGE("a static tree");
        CHECK(back == NULL);
        free(sbuf);
    }
    nbhd_tree_free(st);
    CHECK_STATUS(nbhd_dynamic_load_from_buffer(buf, size, &back), NBHD_STATUS_OK);
    nbhd_dynamic_free(back);
    /* A file stating 1024 threads (saved by a tree created with them) loads, and the loaded
       handle's thread count can be set (tests/dynamic_persist.rs checks that the file's count
       is not obeyed). */
    {
        nbhd_build_options many = nbhd_build_options_default();
        nbhd_dynamic_tree *t = NULL;
        double one[DIM] = {0.5, 0.5, 0.5};
        nbhd_points p1 = {one, 1, DIM, 0, NBHD_SCALAR_TYPE_F64};
        many.threads = 1024;
        CHECK_STATUS(nbhd_dynamic_create(DIM, NBHD_SCALAR_TYPE_F64, &many, &t), NBHD_STATUS_OK);
        if (t != NULL) {
            CHECK_STATUS(nbhd_dynamic_save_to_buffer(t, buf, size, &size), NBHD_STATUS_OK);
            nbhd_dynamic_free(t);
            t = NULL;
            CHECK_STATUS(nbhd_dynamic_load_from_buffer(buf, size, &t), NBHD_STATUS_OK);
            CHECK_STATUS(nbhd_dynamic_set_threads(t, 1), NBHD_STATUS_OK);
            CHECK_STATUS(nbhd_dynamic_insert(t, &p1, NULL), NBHD_STATUS_OK);
            CHECK_STATUS(nbhd_dynamic_set_threads(t, 1025), NBHD_STATUS_INVALID_OPTION);
            CHECK_MESSAGE("threads");
            CHECK_STATUS(nbhd_dynamic_set_threads(NULL, 1), NBHD_STATUS_NULL_POINTER);
            CHECK_STATUS(nbhd_dynamic_set_threads(t, 0), NBHD_STATUS_OK);
            nbhd_dynamic_free(t);
        }
    }
    free(buf);
    nbhd_dynamic_free(dyn);
}

static void test_errors(void) {
    nbhd_build_options o = nbhd_build_options_default();
    nbhd_dynamic_tree *dyn = (nbhd_dynamic_tree *)&o;
    nbhd_dynamic_stats stats;
    double two[2 * DIM] = {0, 0, 0, 1, 1, 1};
    double bad[2 * DIM] = {0, 0, 0, 1, NAN, 1};
    float q[DIM] = {0, 0, 0};
    nbhd_points p = {two, 2, DIM, 0, NBHD_SCALAR_TYPE_F64};
    uint32_t first = 77, ids[3];
    size_t count = 5;

    CHECK_STATUS(nbhd_dynamic_create(0, NBHD_SCALAR_TYPE_F32, NULL, &dyn),
                 NBHD_STATUS_ZERO_DIMENSION);
    CHECK(dyn == NULL);
    /* A value of no nbhd_scalar_type, as C may pass one: refused, never undefined behaviour. */
    CHECK_STATUS(nbhd_dynamic_create(DIM, (nbhd_scalar_type)7, NULL, &dyn),
                 NBHD_STATUS_INVALID_ARGUMENT);
    CHECK_MESSAGE("scalar_type 7 is not a value of nbhd_scalar_type");
    CHECK(dyn == NULL);
    CHECK_STATUS(nbhd_dynamic_create(DIM, (nbhd_scalar_type)-1, NULL, &dyn),
                 NBHD_STATUS_INVALID_ARGUMENT);
    /* A dimension no point of which fits in memory: refused as nbhd_tree_build refuses it. */
    CHECK_STATUS(nbhd_dynamic_create(SIZE_MAX, NBHD_SCALAR_TYPE_F32, NULL, &dyn),
                 NBHD_STATUS_INVALID_ARGUMENT);
    CHECK(dyn == NULL);
    CHECK_MESSAGE("overflows the address space");
    CHECK_STATUS(nbhd_dynamic_create(SIZE_MAX / 8 + 1, NBHD_SCALAR_TYPE_F64, NULL, &dyn),
                 NBHD_STATUS_INVALID_ARGUMENT);
    CHECK(dyn == NULL);
    CHECK_STATUS(nbhd_dynamic_create(DIM, NBHD_SCALAR_TYPE_F32, NULL, NULL),
                 NBHD_STATUS_NULL_POINTER);
    o.leaf_size = 0;
    CHECK_STATUS(nbhd_dynamic_create(DIM, NBHD_SCALAR_TYPE_F32, &o, &dyn),
                 NBHD_STATUS_INVALID_OPTION);
    CHECK_STATUS(nbhd_dynamic_create(DIM, NBHD_SCALAR_TYPE_F32, NULL, &dyn), NBHD_STATUS_OK);
    if (dyn == NULL) return;

    /* an empty tree answers nothing; its indices are out of range */
    CHECK_STATUS(nbhd_dynamic_knn(dyn, q, 3, ids, NULL, 3, &count), NBHD_STATUS_OK);
    CHECK(count == 0);
    CHECK_STATUS(nbhd_dynamic_knn_index(dyn, 0, false, 3, ids, NULL, 3, &count),
                 NBHD_STATUS_INDEX_OUT_OF_RANGE);

    /* inserts: NULL, zero points, dimension, NaN (rejected by default), absurd sizes */
    CHECK_STATUS(nbhd_dynamic_insert(NULL, &p, &first), NBHD_STATUS_NULL_POINTER);
    CHECK_STATUS(nbhd_dynamic_insert(dyn, NULL, &first), NBHD_STATUS_NULL_POINTER);
    p.count = 0; /* no point: nothing inserted, the next index given back */
    first = 77;
    CHECK_STATUS(nbhd_dynamic_insert(dyn, &p, &first), NBHD_STATUS_OK);
    CHECK(first == 0);
    p.data = NULL;
    CHECK_STATUS(nbhd_dynamic_insert(dyn, &p, &first), NBHD_STATUS_OK);
    p.data = two;
    {
        nbhd_neighborhood_spec spec = {NBHD_NEIGHBORHOOD_KIND_KNN, 2, 0.0};
        nbhd_neighborhoods *t = NULL;
        CHECK_STATUS(nbhd_dynamic_neighborhoods_of(dyn, &p, &spec, NULL, &t), NBHD_STATUS_OK);
        CHECK(nbhd_neighborhoods_rows(t) == 0);
        nbhd_neighborhoods_free(t);
    }
    p.count = (size_t)1 << 40;
    CHECK_STATUS(nbhd_dynamic_insert(dyn, &p, &first), NBHD_STATUS_TOO_MANY_POINTS);
    p.count = 2;
    p.stride = SIZE_MAX / 2;
    CHECK_STATUS(nbhd_dynamic_insert(dyn, &p, &first), NBHD_STATUS_INVALID_ARGUMENT);
    p.stride = 0;
    p.dim = 2;
    CHECK_STATUS(nbhd_dynamic_insert(dyn, &p, &first), NBHD_STATUS_DIMENSION_MISMATCH);
    p.dim = DIM;
    p.data = bad;
    CHECK_STATUS(nbhd_dynamic_insert(dyn, &p, &first), NBHD_STATUS_NON_FINITE);
    CHECK_MESSAGE("point 1");
    CHECK_STATUS(nbhd_dynamic_tree_stats(dyn, &stats), NBHD_STATUS_OK);
    CHECK(stats.next_index == 0 && stats.live == 0 && stats.trees == 0);
    p.data = two;
    CHECK_STATUS(nbhd_dynamic_insert(dyn, &p, &first), NBHD_STATUS_OK);
    CHECK(first == 0);
    CHECK_STATUS(nbhd_dynamic_insert(dyn, &p, NULL), NBHD_STATUS_OK);
    CHECK_STATUS(nbhd_dynamic_insert(dyn, &p, &first), NBHD_STATUS_OK);
    CHECK(first == 4);

    /* removals: unknown, repeated, absurd count, NULL, misaligned; nothing removed */
    ids[0] = 1;
    ids[1] = 6;
    CHECK_STATUS(nbhd_dynamic_remove(dyn, ids, 2), NBHD_STATUS_INDEX_OUT_OF_RANGE);
    ids[1] = 1;
    CHECK_STATUS(nbhd_dynamic_remove(dyn, ids, 2), NBHD_STATUS_REMOVED_POINT);
    CHECK_STATUS(nbhd_dynamic_remove(dyn, ids, SIZE_MAX), NBHD_STATUS_INVALID_ARGUMENT);
    CHECK_STATUS(nbhd_dynamic_remove(dyn, NULL, 2), NBHD_STATUS_NULL_POINTER);
    CHECK_STATUS(nbhd_dynamic_remove(dyn, (const uint32_t *)((const char *)ids + 1), 1),
                 NBHD_STATUS_MISALIGNED_POINTER);
    CHECK_STATUS(nbhd_dynamic_remove(NULL, ids, 1), NBHD_STATUS_NULL_POINTER);
    CHECK_STATUS(nbhd_dynamic_tree_stats(dyn, &stats), NBHD_STATUS_OK);
    CHECK(stats.live == 6);
    CHECK_STATUS(nbhd_dynamic_remove(dyn, NULL, 0), NBHD_STATUS_OK);
    CHECK_STATUS(nbhd_dynamic_remove(dyn, ids, 1), NBHD_STATUS_OK);
    CHECK_STATUS(nbhd_dynamic_remove(dyn, ids, 1), NBHD_STATUS_REMOVED_POINT);
    CHECK_MESSAGE("removed");
    CHECK_STATUS(nbhd_dynamic_knn_index(dyn, 1, true, 2, ids, NULL, 3, &count),
                 NBHD_STATUS_REMOVED_POINT);
    CHECK(count == 0);
    /* a removed index is never given again */
    CHECK_STATUS(nbhd_dynamic_insert(dyn, &p, &first), NBHD_STATUS_OK);
    CHECK(first == 6);
    CHECK_STATUS(nbhd_dynamic_knn(dyn, q, 3, ids, NULL, 3, &count), NBHD_STATUS_OK);
    CHECK(count == 3 && ids[0] == 0 && ids[1] == 2 && ids[2] == 4);

    /* filters: NULL, k = 0, k >= the live points, NaN ratio, small buffers; the mask has
     * next_index bytes, 0 for the removed index 1 */
    {
        nbhd_statistical_outlier_options so = nbhd_statistical_outlier_options_default();
        nbhd_radius_outlier_options ro = nbhd_radius_outlier_options_default();
        uint32_t kept[8];
        unsigned char mask[9];
        so.k = 2;
        CHECK_STATUS(nbhd_dynamic_remove_statistical_outliers(NULL, &so, kept, 8, &count, NULL),
                     NBHD_STATUS_NULL_POINTER);
        CHECK_STATUS(nbhd_dynamic_remove_statistical_outliers(dyn, &so, kept, 8, NULL, NULL),
                     NBHD_STATUS_NULL_POINTER);
        CHECK_STATUS(nbhd_dynamic_remove_radius_outliers(NULL, 1.0, NULL, kept, 8, &count, NULL),
                     NBHD_STATUS_NULL_POINTER);
        CHECK_STATUS(nbhd_dynamic_remove_statistical_outliers(dyn, &so, NULL, 8, &count, NULL),
                     NBHD_STATUS_NULL_POINTER);
        CHECK(count == 0);
        so.k = 0;
        CHECK_STATUS(nbhd_dynamic_remove_statistical_outliers(dyn, &so, kept, 8, &count, NULL),
                     NBHD_STATUS_INVALID_K);
        so.k = 7; /* 7 live points of 8 given */
        CHECK_STATUS(nbhd_dynamic_remove_statistical_outliers(dyn, &so, kept, 8, &count, NULL),
                     NBHD_STATUS_INVALID_OPTION);
        CHECK_MESSAGE("the tree holds 7");
        so.k = 6;
        so.std_ratio = NAN;
        CHECK_STATUS(nbhd_dynamic_remove_statistical_outliers(dyn, &so, kept, 8, &count, NULL),
                     NBHD_STATUS_INVALID_OPTION);
        CHECK_MESSAGE("std_ratio");
        so.std_ratio = 10.0;
        count = 99;
        CHECK_STATUS(nbhd_dynamic_remove_statistical_outliers(dyn, &so, kept, 6, &count, NULL),
                     NBHD_STATUS_BUFFER_TOO_SMALL);
        CHECK(count == 7);
        memset(mask, 5, sizeof mask);
        CHECK_STATUS(nbhd_dynamic_remove_statistical_outliers(dyn, &so, kept, 8, &count, mask),
                     NBHD_STATUS_OK);
        CHECK(count == 7 && kept[0] == 0 && kept[1] == 2 && kept[6] == 7);
        CHECK(mask[0] == 1 && mask[1] == 0 && mask[2] == 1 && mask[7] == 1 && mask[8] == 5);
        CHECK_STATUS(nbhd_dynamic_remove_radius_outliers(dyn, NAN, &ro, kept, 8, &count, NULL),
                     NBHD_STATUS_INVALID_RADIUS);
        CHECK(count == 0);
        ro.threads = 100000;
        CHECK_STATUS(nbhd_dynamic_remove_radius_outliers(dyn, 1.0, &ro, kept, 8, &count, NULL),
                     NBHD_STATUS_INVALID_OPTION);
        ro.threads = 0;
        CHECK_STATUS(nbhd_dynamic_remove_radius_outliers(dyn, 0.0, &ro, kept, 1, &count, mask),
                     NBHD_STATUS_BUFFER_TOO_SMALL);
        CHECK(count == 7);
        memset(mask, 5, sizeof mask);
        CHECK_STATUS(nbhd_dynamic_remove_radius_outliers(dyn, 0.0, NULL, kept, 8, &count, mask),
                     NBHD_STATUS_OK);
        /* four copies of (0, 0, 0) and three of (1, 1, 1) live: at least 2 others each */
        CHECK(count == 7 && mask[1] == 0 && mask[8] == 5);
    }

    /* queries: NaN, k = 0, small buffers, NULL stats */
    q[1] = NAN;
    CHECK_STATUS(nbhd_dynamic_knn(dyn, q, 3, ids, NULL, 3, &count),
                 NBHD_STATUS_NON_FINITE_QUERY);
    q[1] = 0;
    CHECK_STATUS(nbhd_dynamic_knn(dyn, q, 0, ids, NULL, 3, &count), NBHD_STATUS_INVALID_K);
    CHECK_STATUS(nbhd_dynamic_radius(dyn, q, -1.0, ids, NULL, 3, &count),
                 NBHD_STATUS_INVALID_RADIUS);
    CHECK_STATUS(nbhd_dynamic_knn(dyn, q, 5, ids, NULL, 3, &count),
                 NBHD_STATUS_BUFFER_TOO_SMALL);
    CHECK(count == 5);
    CHECK_STATUS(nbhd_dynamic_tree_stats(dyn, NULL), NBHD_STATUS_NULL_POINTER);
    CHECK_STATUS(nbhd_dynamic_tree_stats(NULL, &stats), NBHD_STATUS_NULL_POINTER);
    nbhd_dynamic_free(dyn);
    nbhd_dynamic_free(NULL);

    /* with SKIP a NaN point takes its index but is not live */
    o = nbhd_build_options_default();
    o.non_finite = NBHD_NON_FINITE_POLICY_SKIP;
    CHECK_STATUS(nbhd_dynamic_create(DIM, NBHD_SCALAR_TYPE_F64, &o, &dyn), NBHD_STATUS_OK);
    if (dyn == NULL) return;
    p.data = bad;
    CHECK_STATUS(nbhd_dynamic_insert(dyn, &p, &first), NBHD_STATUS_OK);
    CHECK_STATUS(nbhd_dynamic_knn_index(dyn, 1, false, 1, ids, NULL, 3, &count),
                 NBHD_STATUS_SKIPPED_POINT);
    ids[0] = 1;
    CHECK_STATUS(nbhd_dynamic_remove(dyn, ids, 1), NBHD_STATUS_SKIPPED_POINT);
    CHECK_STATUS(nbhd_dynamic_tree_stats(dyn, &stats), NBHD_STATUS_OK);
    CHECK(stats.live == 1 && stats.next_index == 2);
    nbhd_dynamic_free(dyn);
}

int main(int argc, char **argv) {
    make_pool();
    test_errors();
    test_saved(argc > 1 ? argv[1] : ".");
    test_interleaved(1);
    test_interleaved(0);
    printf("dynamic_test: %d checks, %d failures\n", checks, failures);
    return failures == 0 ? 0 : 1;
}
