/*
 * Buffers changed between calls, index subsets with repeats, and index and coordinate queries
 * interleaved from several threads while a table is made. Every answer must equal a brute force
 * over the points as they were given. Run by tests/c_abi.rs (natively and under valgrind) and
 * by scripts/sanitize-test.sh (AddressSanitizer + UndefinedBehaviorSanitizer), where a read of
 * the caller's memory after the build, or past any buffer, fails it.
 *
 * 1. A static tree (f32 and f64) built from a malloc'd buffer that is overwritten and freed at
 *    once; a subset tree (nbhd_tree_build_indices) whose index array is freed too; a dynamic
 *    tree fed batches from buffers freed after each insert.
 * 2. Index lists with repeats: nbhd_tree_build_indices and nbhd_dynamic_remove refuse them and
 *    change nothing.
 * 3. THREADS threads on one tree: k nearest by index and by coordinates, radius by index and by
 *    coordinates, and an all-point table each, interleaved.
 */
#include "check.h"

#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdlib.h>

#define N 1500
#define DIM 3
#define K 9
#define RADIUS 0.09
#define THREADS 4

static uint64_t rng = 0x2545F4914F6CDD1DULL;
static double unit(void) {
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return (double)(rng >> 11) / 9007199254740992.0;
}

/* The points as given (f32 and f64 views of the same values). */
static float kept_f[N * DIM];
static double kept_d[N * DIM];

typedef struct {
    double d;
    uint32_t i;
} cand;

static int by_dist(const void *a, const void *b) {
    const cand *x = a, *y = b;
    if (x->d != y->d) return x->d < y->d ? -1 : 1;
    return (x->i > y->i) - (x->i < y->i);
}

/* Brute force in the scalar type `f32` says: within `r` (r < 0: any) the `k` nearest (0: all)
 * of the points with `listed[i]` (NULL: all), `self` excluded (or none: -1). */
static size_t brute(int f32, const double *q, size_t k, double r, long self,
                    const unsigned char *listed, cand *out) {
    size_t i, n = 0;
    for (i = 0; i < N; i++) {
        double d;
        if ((long)i == self || (listed && !listed[i])) continue;
        if (f32) {
            float qf[DIM], dd = 0.0f;
            int j;
            for (j = 0; j < DIM; j++) qf[j] = (float)q[j];
            for (j = 0; j < DIM; j++) {
                float t = kept_f[i * DIM + j] - qf[j];
                dd += t * t;
            }
            if (r >= 0.0 && dd > (float)r * (float)r) continue;
            d = dd;
        } else {
            int j;
            d = 0.0;
            for (j = 0; j < DIM; j++) {
                double t = kept_d[i * DIM + j] - q[j];
                d += t * t;
            }
            if (r >= 0.0 && d > r * r) continue;
        }
        out[n].d = d;
        out[n].i = (uint32_t)i;
        n++;
    }
    qsort(out, n, sizeof *out, by_dist);
    return k > 0 && n > k ? k : n;
}

/* Whether the answer (indices, squared distances in the tree's type) is the brute force's. */
static int same(int f32, const uint32_t *idx, const void *sq, size_t count, const cand *want,
                size_t nwant) {
    size_t i;
    if (count != nwant) return 0;
    for (i = 0; i < count; i++) {
        double d = f32 ? (double)((const float *)sq)[i] : ((const double *)sq)[i];
        if (idx[i] != want[i].i || d != want[i].d) return 0;
    }
    return 1;
}

/* A copy of the points in the given type, in a fresh malloc'd buffer the caller frees. */
static void *fresh_copy(int f32) {
    size_t bytes = f32 ? sizeof kept_f : sizeof kept_d;
    void *b = malloc(bytes);
    if (b) memcpy(b, f32 ? (const void *)kept_f : (const void *)kept_d, bytes);
    return b;
}

static void scribble_and_free(void *b, size_t bytes) {
    memset(b, 0x7f, bytes); /* huge finite values */
    free(b);
}

static nbhd_points describe(const void *data, size_t count, int f32) {
    nbhd_points p;
    p.data = data;
    p.count = count;
    p.dim = DIM;
    p.stride = 0;
    p.scalar_type = f32 ? NBHD_SCALAR_TYPE_F32 : NBHD_SCALAR_TYPE_F64;
    return p;
}

/* Queries around every 11th point (coordinates and index) against the brute force. */
static void check_tree(const nbhd_tree *tree, int f32, const unsigned char *listed) {
    uint32_t idx[N];
    double sq_d[N];
    cand want[N];
    size_t i, count, nwant;
    for (i = 0; i < N; i += 11) {
        double q[DIM];
        float qf[DIM];
        const void *qp = f32 ? (const void *)qf : (const void *)q;
        int j;
        for (j = 0; j < DIM; j++) {
            q[j] = f32 ? (double)kept_f[i * DIM + j] : kept_d[i * DIM + j];
            qf[j] = kept_f[i * DIM + j];
        }
        nwant = brute(f32, q, K, -1.0, -1, listed, want);
        CHECK_STATUS(nbhd_tree_knn(tree, qp, K, idx, sq_d, N, &count), NBHD_STATUS_OK);
        CHECK(same(f32, idx, sq_d, count, want, nwant));
        nwant = brute(f32, q, 0, RADIUS, -1, listed, want);
        CHECK_STATUS(nbhd_tree_radius(tree, qp, RADIUS, idx, sq_d, N, &count), NBHD_STATUS_OK);
        CHECK(same(f32, idx, sq_d, count, want, nwant));
        if (listed && !listed[i]) {
            CHECK_STATUS(nbhd_tree_knn_index(tree, i, true, K, idx, sq_d, N, &count),
                         NBHD_STATUS_SKIPPED_POINT);
            continue;
        }
        nwant = brute(f32, q, K, -1.0, (long)i, listed, want);
        CHECK_STATUS(nbhd_tree_knn_index(tree, i, true, K, idx, sq_d, N, &count), NBHD_STATUS_OK);
        CHECK(same(f32, idx, sq_d, count, want, nwant));
    }
}

static void static_trees(void) {
    int f32;
    for (f32 = 0; f32 <= 1; f32++) {
        size_t bytes = f32 ? sizeof kept_f : sizeof kept_d;
        void *buf = fresh_copy(f32);
        nbhd_points p = describe(buf, N, f32);
        nbhd_tree *tree = NULL;
        uint32_t *list;
        unsigned char listed[N];
        size_t i, m = 0;
        if (!buf) {
            CHECK(buf != NULL);
            return;
        }
        CHECK_STATUS(nbhd_tree_build(&p, NULL, &tree), NBHD_STATUS_OK);
        scribble_and_free(buf, bytes);
        if (tree) check_tree(tree, f32, NULL);
        nbhd_tree_free(tree);

        /* A subset: every third point; points and index array freed after the build. */
        buf = fresh_copy(f32);
        list = malloc(N * sizeof *list);
        if (!buf || !list) {
            CHECK(buf != NULL && list != NULL);
            free(buf);
            free(list);
            return;
        }
        memset(listed, 0, sizeof listed);
        for (i = 0; i < N; i += 3) {
            list[m++] = (uint32_t)i;
            listed[i] = 1;
        }
        p = describe(buf, N, f32);
        tree = NULL;
        CHECK_STATUS(nbhd_tree_build_indices(&p, list, m, NULL, &tree), NBHD_STATUS_OK);
        /* The same list with a repeat is refused, naming the index. */
        {
            nbhd_tree *t2 = (nbhd_tree *)&p;
            list[m] = list[m / 2];
            CHECK_STATUS(nbhd_tree_build_indices(&p, list, m + 1, NULL, &t2),
                         NBHD_STATUS_INVALID_ARGUMENT);
            CHECK(t2 == NULL);
        }
        memset(list, 0xff, N * sizeof *list);
        free(list);
        scribble_and_free(buf, bytes);
        if (tree) check_tree(tree, f32, listed);
        nbhd_tree_free(tree);
    }
}

static void dynamic_tree(void) {
    nbhd_dynamic_tree *dyn = NULL;
    size_t at = 0, batch = 1;
    uint32_t idx[N], rm[3];
    float sq[N];
    cand want[N];
    size_t count, nwant, i;
    nbhd_dynamic_stats st;
    CHECK_STATUS(nbhd_dynamic_create(DIM, NBHD_SCALAR_TYPE_F32, NULL, &dyn), NBHD_STATUS_OK);
    if (!dyn) return;
    /* Batches of growing size, each buffer scribbled on and freed right after its insert. */
    while (at < N) {
        size_t c = batch < N - at ? batch : N - at;
        float *b = malloc(c * DIM * sizeof *b);
        nbhd_points p = describe(b, c, 1);
        uint32_t first = 0;
        if (!b) {
            CHECK(b != NULL);
            break;
        }
        memcpy(b, &kept_f[at * DIM], c * DIM * sizeof *b);
        CHECK_STATUS(nbhd_dynamic_insert(dyn, &p, &first), NBHD_STATUS_OK);
        CHECK(first == at);
        scribble_and_free(b, c * DIM * sizeof *b);
        at += c;
        batch = batch * 2 + 1;
    }
    /* A removal list naming a point twice: refused, nothing removed. */
    rm[0] = 5;
    rm[1] = 700;
    rm[2] = 5;
    CHECK_STATUS(nbhd_dynamic_remove(dyn, rm, 3), NBHD_STATUS_REMOVED_POINT);
    CHECK_STATUS(nbhd_dynamic_tree_stats(dyn, &st), NBHD_STATUS_OK);
    CHECK(st.live == N);
    for (i = 0; i < N; i += 13) {
        double q[DIM] = {kept_f[i * DIM], kept_f[i * DIM + 1], kept_f[i * DIM + 2]};
        nwant = brute(1, q, K, -1.0, (long)i, NULL, want);
        CHECK_STATUS(nbhd_dynamic_knn_index(dyn, i, true, K, idx, sq, N, &count), NBHD_STATUS_OK);
        CHECK(same(1, idx, sq, count, want, nwant));
    }
    nbhd_dynamic_free(dyn);
}

/* ---- 3. threads ---------------------------------------------------------------------------- */

static nbhd_tree *shared_tree = NULL;
static int thread_bad[THREADS];

static void *worker(void *arg) {
    int w = (int)(intptr_t)arg;
    uint32_t idx[N];
    float sq[N];
    cand want[N];
    size_t j, count, nwant;
    int bad = 0;
    for (j = (size_t)w; j < N; j += THREADS) {
        size_t i = (j * 7919) % N;
        double q[DIM] = {kept_f[i * DIM], kept_f[i * DIM + 1], kept_f[i * DIM + 2]};
        float qf[DIM] = {kept_f[i * DIM], kept_f[i * DIM + 1], kept_f[i * DIM + 2]};
        nbhd_status s;
        switch (j % 4) {
            case 0:
                s = nbhd_tree_knn_index(shared_tree, i, false, K, idx, sq, N, &count);
                nwant = brute(1, q, K, -1.0, -1, NULL, want);
                break;
            case 1:
                s = nbhd_tree_knn(shared_tree, qf, K, idx, sq, N, &count);
                nwant = brute(1, q, K, -1.0, -1, NULL, want);
                break;
            case 2:
                s = nbhd_tree_radius_index(shared_tree, i, true, RADIUS, idx, sq, N, &count);
                nwant = brute(1, q, 0, RADIUS, (long)i, NULL, want);
                break;
            default:
                s = nbhd_tree_radius(shared_tree, qf, RADIUS, idx, sq, N, &count);
                nwant = brute(1, q, 0, RADIUS, -1, NULL, want);
        }
        bad += s != NBHD_STATUS_OK || !same(1, idx, sq, count, want, nwant);
        if (j % 97 == (size_t)w) {
            /* An all-point table in the middle of the queries, on two threads of its own. */
            nbhd_neighborhood_spec spec = {NBHD_NEIGHBORHOOD_KIND_KNN, K, 0.0};
            nbhd_table_options o = nbhd_table_options_default();
            nbhd_neighborhoods *t = NULL;
            const uint32_t *row = NULL;
            const void *row_sq = NULL;
            size_t len = 0;
            o.threads = 2;
            if (nbhd_tree_neighborhoods(shared_tree, &spec, &o, &t) != NBHD_STATUS_OK ||
                nbhd_neighborhoods_row(t, i, &row, &row_sq, &len) != NBHD_STATUS_OK) {
                bad++;
            } else {
                nwant = brute(1, q, K, -1.0, (long)i, NULL, want);
                bad += !same(1, row, row_sq, len, want, nwant);
            }
            nbhd_neighborhoods_free(t);
        }
    }
    thread_bad[w] = bad;
    return NULL;
}

static void threads_interleaved(void) {
    pthread_t th[THREADS];
    nbhd_points p = describe(kept_f, N, 1);
    int w;
    CHECK_STATUS(nbhd_tree_build(&p, NULL, &shared_tree), NBHD_STATUS_OK);
    if (!shared_tree) return;
    for (w = 0; w < THREADS; w++)
        CHECK(pthread_create(&th[w], NULL, worker, (void *)(intptr_t)w) == 0);
    for (w = 0; w < THREADS; w++) {
        pthread_join(th[w], NULL);
        CHECK(thread_bad[w] == 0);
    }
    nbhd_tree_free(shared_tree);
}

int main(void) {
    size_t i;
    for (i = 0; i < N * DIM; i++) {
        /* every 40th point a copy of the one before: ties that the (distance, index) order breaks */
        double v = (i / DIM) % 40 == 39 ? kept_d[i - DIM] : unit();
        kept_f[i] = (float)v;
        kept_d[i] = v;
    }
    static_trees();
    dynamic_tree();
    threads_interleaved();
    printf("mutate_test: %d checks, %d failures\n", checks, failures);
    return failures == 0 ? 0 : 1;
}
