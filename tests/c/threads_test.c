/*
 * One tree, many threads: THREADS pthreads query the same tree at once (every query kind, by
 * coordinates and by stored index) and must get exactly the answers one thread got before.
 * Each thread also fails a call on purpose and checks that nbhd_last_error_message() shows its
 * own error, not another thread's. Run by tests/c_abi.rs (also under valgrind, with fewer
 * points: the optional argument is the number of points, at most 3000).
 */
#include "nbhd.h"

#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define NMAX 3000
#define DIM 3
#define K 10
#define RADIUS 0.06
#define CAP NMAX
#define THREADS 4
#define ROUNDS 2

static size_t n = NMAX;
static float pts[NMAX * DIM];
static nbhd_tree *tree = NULL;

/* The answers of one thread, per point: k nearest (self excluded), and the sizes and first
 * neighbours of radius and k-radius queries around the point's coordinates. */
typedef struct {
    uint32_t knn[NMAX][K];
    float knn_d[NMAX][K];
    size_t radius_count[NMAX];
    uint32_t radius_first[NMAX];
    size_t knn_radius_count[NMAX];
    uint32_t knn_radius_last[NMAX];
} answers;

static answers reference;

static uint64_t rng = 0x9E3779B97F4A7C15ULL;
static float unit(void) {
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return (float)(rng >> 40) / (float)(1 << 24);
}

/* Computes every answer for points [0, n) into `a`; returns the number of failed calls. */
static int compute(answers *a) {
    uint32_t idx[CAP];
    float dist[CAP];
    size_t i, count;
    int bad = 0;
    for (i = 0; i < n; i++) {
        if (nbhd_tree_knn_index(tree, i, true, K, a->knn[i], a->knn_d[i], K, &count) !=
                NBHD_STATUS_OK ||
            count != K) {
            bad++;
        }
        if (nbhd_tree_radius(tree, &pts[i * DIM], RADIUS, idx, dist, CAP, &count) !=
            NBHD_STATUS_OK) {
            bad++;
        }
        a->radius_count[i] = count;
        a->radius_first[i] = count > 0 ? idx[0] : UINT32_MAX;
        if (nbhd_tree_knn_radius(tree, &pts[i * DIM], K / 2, RADIUS, idx, dist, CAP, &count) !=
            NBHD_STATUS_OK) {
            bad++;
        }
        a->knn_radius_count[i] = count;
        a->knn_radius_last[i] = count > 0 ? idx[count - 1] : UINT32_MAX;
    }
    return bad;
}

/* Whether `a` holds the same answers as the reference, for every point. */
static int same_answers(const answers *a) {
    size_t i;
    for (i = 0; i < n; i++) {
        if (memcmp(a->knn[i], reference.knn[i], sizeof a->knn[i]) != 0 ||
            memcmp(a->knn_d[i], reference.knn_d[i], sizeof a->knn_d[i]) != 0 ||
            a->radius_count[i] != reference.radius_count[i] ||
            a->radius_first[i] != reference.radius_first[i] ||
            a->knn_radius_count[i] != reference.knn_radius_count[i] ||
            a->knn_radius_last[i] != reference.knn_radius_last[i]) {
            fprintf(stderr, "  first difference at point %lu\n", (unsigned long)i);
            return 0;
        }
    }
    return 1;
}

typedef struct {
    int id;
    int failures;
} worker;

static void *run(void *arg) {
    worker *w = (worker *)arg;
    answers *mine = (answers *)malloc(sizeof *mine);
    char expected[64];
    size_t count, round;
    if (mine == NULL) {
        w->failures++;
        return NULL;
    }
    for (round = 0; round < ROUNDS; round++) {
        memset(mine, 0xAB, sizeof *mine);
        w->failures += compute(mine);
        if (!same_answers(mine)) {
            fprintf(stderr, "thread %d round %lu: answers differ from one thread's\n", w->id,
                    (unsigned long)round);
            w->failures++;
        }
        /* A failure of this thread's own, with its own index in the message. */
        if (nbhd_tree_knn_index(tree, n + (size_t)w->id, true, K, NULL, NULL, 0, &count) !=
            NBHD_STATUS_INDEX_OUT_OF_RANGE) {
            w->failures++;
        }
        sprintf(expected, "point index %lu is out of range", (unsigned long)(n + (size_t)w->id));
        if (strstr(nbhd_last_error_message(), expected) == NULL) {
            fprintf(stderr, "thread %d: last error \"%s\" lacks \"%s\"\n", w->id,
                    nbhd_last_error_message(), expected);
            w->failures++;
        }
    }
    free(mine);
    return NULL;
}

int main(int argc, char **argv) {
    nbhd_points desc;
    pthread_t threads[THREADS];
    worker workers[THREADS];
    int t, failures = 0;
    size_t i;
    if (argc > 1) {
        long v = atol(argv[1]);
        if (v < 2 * K || v > NMAX) {
            fprintf(stderr, "usage: %s [points, %d to %d]\n", argv[0], 2 * K, NMAX);
            return 2;
        }
        n = (size_t)v;
    }
    for (i = 0; i < n * DIM; i++) pts[i] = unit();
    desc.data = pts;
    desc.count = n;
    desc.dim = DIM;
    desc.stride = 0;
    desc.scalar_type = NBHD_SCALAR_TYPE_F32;
    if (nbhd_tree_build(&desc, NULL, &tree) != NBHD_STATUS_OK) {
        fprintf(stderr, "build failed: %s\n", nbhd_last_error_message());
        return 1;
    }
    failures += compute(&reference);
    for (t = 0; t < THREADS; t++) {
        workers[t].id = t;
        workers[t].failures = 0;
        if (pthread_create(&threads[t], NULL, run, &workers[t]) != 0) {
            fprintf(stderr, "pthread_create failed\n");
            return 1;
        }
    }
    for (t = 0; t < THREADS; t++) {
        pthread_join(threads[t], NULL);
        failures += workers[t].failures;
    }
    /* The main thread's message is untouched by the workers' failures. */
    if (nbhd_last_error_message()[0] != '\0') {
        fprintf(stderr, "main thread sees \"%s\"\n", nbhd_last_error_message());
        failures++;
    }
    nbhd_tree_free(tree);
    printf("threads_test: %d threads x %d rounds x %lu points, %d failures\n", THREADS, ROUNDS,
           (unsigned long)n, failures);
    return failures == 0 ? 0 : 1;
}
