/*
 * Saving and loading trees through the C ABI: a tree saved to a file or a buffer loads back
 * into a tree with the same statistics and the same answers to every query (single queries
 * and tables, compared element by element with the original tree's), for float and double
 * trees, with skipped non-finite points; the size query of nbhd_tree_save_to_buffer; and every
 * error path: NULL and empty arguments, a missing file, a directory that does not exist, bytes
 * that are no tree, another format version, the other byte order, truncation, a flipped byte.
 * Run by tests/c_abi.rs with a scratch directory as argv[1] (also under valgrind).
 */
#include "nbhd.h"
#include "check.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define N 500
#define DIM 3
#define NQ 20
#define CAP N

static double pts[N * DIM];
static float ptsf[N * DIM];
static double queries[NQ * DIM];
static uint64_t rng_state = 0x243F6A8885A308D3ULL;

static double uniform01(void) {
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return (double)(rng_state >> 11) / 9007199254740992.0;
}

static void make_cloud(void) {
    size_t i;
    for (i = 0; i < N * DIM; i++) {
        /* a coarse grid: duplicates and distance ties */
        pts[i] = floor(uniform01() * 8.0) / 8.0;
    }
    for (i = 7; i < N; i += 31) {
        pts[i * DIM + i % DIM] = i % 2 ? NAN : INFINITY;
    }
    for (i = 0; i < N * DIM; i++) {
        ptsf[i] = (float)pts[i];
    }
    for (i = 0; i < NQ * DIM; i++) {
        queries[i] = uniform01();
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
    o.non_finite = NBHD_NON_FINITE_POLICY_SKIP;
    o.leaf_size = 4;
    CHECK_STATUS(nbhd_tree_build(&p, &o, &tree), NBHD_STATUS_OK);
    return tree;
}

/* The same answers, element by element: single queries of every kind and tables. */
static void check_same(const nbhd_tree *a, const nbhd_tree *b, int f32) {
    static uint32_t ia[CAP], ib[CAP];
    static double da[CAP], db[CAP];
    size_t ca, cb, q, i;
    size_t dsize = f32 ? sizeof(float) : sizeof(double);
    nbhd_stats sa, sb;
    nbhd_neighborhood_spec spec;
    CHECK_STATUS(nbhd_tree_stats(a, &sa), NBHD_STATUS_OK);
    CHECK_STATUS(nbhd_tree_stats(b, &sb), NBHD_STATUS_OK);
    /* Everything but the bytes, which count the reverse index map once a query by index made
     * it. */
    CHECK(sa.points == sb.points && sa.source_points == sb.source_points && sa.dim == sb.dim);
    CHECK(sa.depth == sb.depth && sa.nodes == sb.nodes && sa.leaves == sb.leaves);
    CHECK(sa.max_leaf_points == sb.max_leaf_points && sa.scalar_type == sb.scalar_type);
    for (q = 0; q < NQ; q++) {
        union {
            float f[DIM];
            double d[DIM];
        } c;
        for (i = 0; i < DIM; i++) {
            if (f32) {
                c.f[i] = (float)queries[q * DIM + i];
            } else {
                c.d[i] = queries[q * DIM + i];
            }
        }
        CHECK_STATUS(nbhd_tree_knn(a, &c, 12, ia, da, CAP, &ca), NBHD_STATUS_OK);
        CHECK_STATUS(nbhd_tree_knn(b, &c, 12, ib, db, CAP, &cb), NBHD_STATUS_OK);
        CHECK(ca == 12 && ca == cb && memcmp(ia, ib, ca * 4) == 0 &&
              memcmp(da, db, ca * dsize) == 0);
        CHECK_STATUS(nbhd_tree_radius(a, &c, 0.3, ia, da, CAP, &ca), NBHD_STATUS_OK);
        CHECK_STATUS(nbhd_tree_radius(b, &c, 0.3, ib, db, CAP, &cb), NBHD_STATUS_OK);
        CHECK(ca == cb && memcmp(ia, ib, ca * 4) == 0 && memcmp(da, db, ca * dsize) == 0);
        CHECK_STATUS(nbhd_tree_knn_radius(a, &c, 5, 0.2, ia, da, CAP, &ca), NBHD_STATUS_OK);
        CHECK_STATUS(nbhd_tree_knn_radius(b, &c, 5, 0.2, ib, db, CAP, &cb), NBHD_STATUS_OK);
        CHECK(ca == cb && memcmp(ia, ib, ca * 4) == 0 && memcmp(da, db, ca * dsize) == 0);
    }
    /* A skipped point stays skipped. */
    CHECK_STATUS(nbhd_tree_knn_index(b, 7, true, 3, ib, db, CAP, &cb), NBHD_STATUS_SKIPPED_POINT);
    CHECK_STATUS(nbhd_tree_knn_index(a, 8, true, 6, ia, da, CAP, &ca), NBHD_STATUS_OK);
    CHECK_STATUS(nbhd_tree_knn_index(b, 8, true, 6, ib, db, CAP, &cb), NBHD_STATUS_OK);
    CHECK(ca == cb && memcmp(ia, ib, ca * 4) == 0 && memcmp(da, db, ca * dsize) == 0);

    spec.kind = NBHD_NEIGHBORHOOD_KIND_KNN_RADIUS;
    spec.k = 8;
    spec.radius = 0.25;
    {
        nbhd_neighborhoods *ta = NULL, *tb = NULL;
        CHECK_STATUS(nbhd_tree_neighborhoods(a, &spec, NULL, &ta), NBHD_STATUS_OK);
        CHECK_STATUS(nbhd_tree_neighborhoods(b, &spec, NULL, &tb), NBHD_STATUS_OK);
        if (ta != NULL && tb != NULL) {
            size_t rows = nbhd_neighborhoods_rows(ta), total = nbhd_neighborhoods_total(ta);
            CHECK(rows == N && rows == nbhd_neighborhoods_rows(tb));
            CHECK(total > 0 && total == nbhd_neighborhoods_total(tb));
            CHECK(memcmp(nbhd_neighborhoods_offsets(ta), nbhd_neighborhoods_offsets(tb),
                         (rows + 1) * sizeof(size_t)) == 0);
            CHECK(memcmp(nbhd_neighborhoods_indices(ta), nbhd_neighborhoods_indices(tb),
                         total * 4) == 0);
            CHECK(memcmp(nbhd_neighborhoods_sq_dists(ta), nbhd_neighborhoods_sq_dists(tb),
                         total * dsize) == 0);
        }
        nbhd_neighborhoods_free(ta);
        nbhd_neighborhoods_free(tb);
    }
}

/* The bytes of a saved tree, in a buffer of exactly their size (for valgrind to see overreads). */
static unsigned char *saved(const nbhd_tree *tree, size_t *size) {
    unsigned char *buf;
    size_t again = 0;
    CHECK_STATUS(nbhd_tree_save_to_buffer(tree, NULL, 0, size), NBHD_STATUS_BUFFER_TOO_SMALL);
    CHECK(*size > 128);
    buf = (unsigned char *)malloc(*size);
    if (buf == NULL) {
        return NULL;
    }
    CHECK_STATUS(nbhd_tree_save_to_buffer(tree, buf, *size - 1, &again),
                 NBHD_STATUS_BUFFER_TOO_SMALL);
    CHECK(again == *size);
    CHECK_MESSAGE("buffer");
    CHECK_STATUS(nbhd_tree_save_to_buffer(tree, buf, *size, &again), NBHD_STATUS_OK);
    CHECK(again == *size);
    CHECK(memcmp(buf, "NBHDTREE", 8) == 0);
    return buf;
}

/* Loads `len` bytes of a copy of `bytes` (with byte `at` xor-ed with `flip` when `at` is in
 * range) and expects `status`, the handle NULL and the message to contain `needle`. */
static void refused(const unsigned char *bytes, size_t len, size_t at, unsigned char flip,
                    nbhd_status status, const char *needle) {
    unsigned char *copy = (unsigned char *)malloc(len ? len : 1);
    nbhd_tree *t = (nbhd_tree *)&t; /* not NULL: the call must set it */
    if (copy == NULL) {
        return;
    }
    memcpy(copy, bytes, len);
    if (at < len) {
        copy[at] ^= flip;
    }
    CHECK_STATUS(nbhd_tree_load_from_buffer(copy, len, &t), status);
    CHECK(t == NULL);
    CHECK_MESSAGE(needle);
    CHECK_MESSAGE("nbhd_tree_load_from_buffer");
    nbhd_tree_free(t);
    free(copy);
}

static void test_round_trips(const char *dir) {
    int f32;
    for (f32 = 0; f32 <= 1; f32++) {
        char path[4096];
        size_t size = 0;
        unsigned char *bytes;
        nbhd_tree *tree = build(f32), *from_buffer = NULL, *from_file = NULL;
        nbhd_stats st;
        if (tree == NULL) {
            continue;
        }
        bytes = saved(tree, &size);
        if (bytes == NULL) {
            nbhd_tree_free(tree);
            continue;
        }
        CHECK_STATUS(nbhd_tree_load_from_buffer(bytes, size, &from_buffer), NBHD_STATUS_OK);
        CHECK(nbhd_last_error_message()[0] == '\0');
        if (from_buffer != NULL) {
            CHECK_STATUS(nbhd_tree_stats(from_buffer, &st), NBHD_STATUS_OK);
            CHECK(st.scalar_type == (f32 ? NBHD_SCALAR_TYPE_F32 : NBHD_SCALAR_TYPE_F64));
            CHECK(st.points < N && st.source_points == N);
            check_same(tree, from_buffer, f32);
        }
        snprintf(path, sizeof path, "%s/tree-%s.nbhdtree", dir, f32 ? "f32" : "f64");
        CHECK_STATUS(nbhd_tree_save(tree, path), NBHD_STATUS_OK);
        CHECK_STATUS(nbhd_tree_load(path, &from_file), NBHD_STATUS_OK);
        if (from_file != NULL) {
            check_same(tree, from_file, f32);
        }
        /* The file holds the buffer's bytes. */
        {
            FILE *f = fopen(path, "rb");
            unsigned char *file_bytes = (unsigned char *)malloc(size + 1);
            if (f != NULL && file_bytes != NULL) {
                CHECK(fread(file_bytes, 1, size + 1, f) == size);
                CHECK(memcmp(file_bytes, bytes, size) == 0);
            }
            if (f != NULL) fclose(f);
            free(file_bytes);
        }

        /* Damaged and foreign bytes. */
        refused(bytes, 0, 0, 0, NBHD_STATUS_CORRUPT_DATA, "truncated");
        refused(bytes, 100, 0, 0, NBHD_STATUS_CORRUPT_DATA, "truncated");
        refused(bytes, size - 1, 0, 0, NBHD_STATUS_CORRUPT_DATA, "truncated");
        refused(bytes, size, 0, 0x20, NBHD_STATUS_FORMAT_MISMATCH, "not a saved nbhd tree");
        refused(bytes, size, 12, 0x02, NBHD_STATUS_FORMAT_MISMATCH, "format version 3");
        refused(bytes, size, 40, 0x01, NBHD_STATUS_CORRUPT_DATA, "header");
        refused(bytes, size, size / 2, 0x10, NBHD_STATUS_CORRUPT_DATA, "payload");
        refused((const unsigned char *)"ply\nformat ascii 1.0\n", 21, 99, 0,
                NBHD_STATUS_FORMAT_MISMATCH, "ply");
        {
            /* The byte-order mark reversed: a file of a big-endian machine. */
            unsigned char *other = (unsigned char *)malloc(size);
            if (other != NULL) {
                memcpy(other, bytes, size);
                other[8] = bytes[11];
                other[9] = bytes[10];
                other[10] = bytes[9];
                other[11] = bytes[8];
                refused(other, size, size, 0, NBHD_STATUS_FORMAT_MISMATCH, "big-endian");
                free(other);
            }
        }
        free(bytes);
        nbhd_tree_free(from_buffer);
        nbhd_tree_free(from_file);
        nbhd_tree_free(tree);
    }
}

static void test_errors(const char *dir) {
    nbhd_tree *tree = build(1);
    nbhd_tree *t = (nbhd_tree *)&t;
    char path[4096];
    size_t size = 99;
    unsigned char byte = 0;
    /* Saving. */
    CHECK_STATUS(nbhd_tree_save(NULL, "x"), NBHD_STATUS_NULL_POINTER);
    CHECK_MESSAGE("tree");
    CHECK_STATUS(nbhd_tree_save(tree, NULL), NBHD_STATUS_NULL_POINTER);
    CHECK_MESSAGE("path");
    CHECK_STATUS(nbhd_tree_save(tree, ""), NBHD_STATUS_INVALID_ARGUMENT);
    snprintf(path, sizeof path, "%s/no-such-dir/tree.nbhdtree", dir);
    CHECK_STATUS(nbhd_tree_save(tree, path), NBHD_STATUS_IO_ERROR);
    CHECK_MESSAGE("no-such-dir");
    CHECK_STATUS(nbhd_tree_save_to_buffer(tree, &byte, 1, NULL), NBHD_STATUS_NULL_POINTER);
    CHECK_MESSAGE("size");
    CHECK_STATUS(nbhd_tree_save_to_buffer(NULL, &byte, 1, &size), NBHD_STATUS_NULL_POINTER);
    CHECK(size == 0);
    CHECK_STATUS(nbhd_tree_save_to_buffer(tree, NULL, (size_t)-1, &size),
                 NBHD_STATUS_NULL_POINTER);
    CHECK_MESSAGE("buffer");
    CHECK(size > 0);
    /* Loading. */
    CHECK_STATUS(nbhd_tree_load(NULL, &t), NBHD_STATUS_NULL_POINTER);
    CHECK(t == NULL);
    CHECK_STATUS(nbhd_tree_load("x", NULL), NBHD_STATUS_NULL_POINTER);
    CHECK_MESSAGE("out_tree");
    t = (nbhd_tree *)&t;
    CHECK_STATUS(nbhd_tree_load("", &t), NBHD_STATUS_INVALID_ARGUMENT);
    CHECK(t == NULL);
    snprintf(path, sizeof path, "%s/missing.nbhdtree", dir);
    CHECK_STATUS(nbhd_tree_load(path, &t), NBHD_STATUS_IO_ERROR);
    CHECK_MESSAGE("missing.nbhdtree");
    CHECK(t == NULL);
    /* A directory is no file. */
    CHECK_STATUS(nbhd_tree_load(dir, &t), NBHD_STATUS_IO_ERROR);
    CHECK_STATUS(nbhd_tree_load_from_buffer(NULL, 10, &t), NBHD_STATUS_NULL_POINTER);
    CHECK_MESSAGE("data");
    CHECK_STATUS(nbhd_tree_load_from_buffer(&byte, (size_t)-1, &t),
                 NBHD_STATUS_INVALID_ARGUMENT);
    CHECK_STATUS(nbhd_tree_load_from_buffer(&byte, 1, NULL), NBHD_STATUS_NULL_POINTER);
    CHECK(strcmp(nbhd_status_string(NBHD_STATUS_IO_ERROR), "unknown status") != 0);
    CHECK(strcmp(nbhd_status_string(NBHD_STATUS_FORMAT_MISMATCH), "unknown status") != 0);
    CHECK(strcmp(nbhd_status_string(NBHD_STATUS_CORRUPT_DATA), "unknown status") != 0);
    nbhd_tree_free(tree);
}

int main(int argc, char **argv) {
    const char *dir = argc > 1 ? argv[1] : ".";
    make_cloud();
    test_round_trips(dir);
    test_errors(dir);
    printf("persist_test: %d checks, %d failures\n", checks, failures);
    return failures == 0 ? 0 : 1;
}
