/*
 * Worker threads: their number is bounded, a call's own pool is gone when the call returns, and
 * a child forked after parallel calls can call nbhd (issue 16, items 3 and 4). Run by
 * tests/c_abi.rs, natively only (Linux: the thread counts are read from /proc/self/status).
 *
 * 1. threads = 100000 fails at once with NBHD_STATUS_INVALID_OPTION naming the value, and no
 *    thread is started.
 * 2. threads = 1000 (more than the cores; the 2000 is now above NBHD_MAX_THREADS) leaves
 *    no thread behind; threads = 1 keeps one pool of one thread for the next call, and a second
 *    call reuses it.
 * 3. After tables on rayon's shared pool (threads = 0) and on a kept pool (threads = 2), the
 *    process forks. The child (and a grandchild it forks) computes the same tables with
 *    threads = 0, 1 and 2 and builds a new tree; every table must equal the parent's. An
 *    alarm() kills a child that hangs, which the parent reports as a failure.
 */
#define _POSIX_C_SOURCE 200809L

#include "check.h"
#include "nbhd.h"

#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#define N 20000
#define K 8

static float pts[N * 3];

static long process_threads(void) {
    FILE *f = fopen("/proc/self/status", "r");
    char line[256];
    long threads = -1;
    if (f == NULL) return -1;
    while (fgets(line, sizeof line, f) != NULL) {
        if (strncmp(line, "Threads:", 8) == 0) {
            threads = strtol(line + 8, NULL, 10);
            break;
        }
    }
    fclose(f);
    return threads;
}

/* The kNN table of every point with `threads` workers, or NULL (the failure is counted). */
static nbhd_neighborhoods *table(const nbhd_tree *tree, size_t threads) {
    nbhd_neighborhood_spec spec = {NBHD_NEIGHBORHOOD_KIND_KNN, K, 0.0};
    nbhd_table_options o = nbhd_table_options_default();
    nbhd_neighborhoods *t = NULL;
    o.threads = threads;
    CHECK_STATUS(nbhd_tree_neighborhoods(tree, &spec, &o, &t), NBHD_STATUS_OK);
    return t;
}

/* 1 when both tables hold the same rows (indices and squared distances). */
static int same(const nbhd_neighborhoods *a, const nbhd_neighborhoods *b) {
    size_t total;
    if (a == NULL || b == NULL) return 0;
    total = nbhd_neighborhoods_total(a);
    return nbhd_neighborhoods_rows(a) == nbhd_neighborhoods_rows(b) &&
           total == nbhd_neighborhoods_total(b) &&
           memcmp(nbhd_neighborhoods_offsets(a), nbhd_neighborhoods_offsets(b),
                  (nbhd_neighborhoods_rows(a) + 1) * sizeof(size_t)) == 0 &&
           memcmp(nbhd_neighborhoods_indices(a), nbhd_neighborhoods_indices(b),
                  total * sizeof(uint32_t)) == 0 &&
           memcmp(nbhd_neighborhoods_sq_dists(a), nbhd_neighborhoods_sq_dists(b),
                  total * sizeof(float)) == 0;
}

/* What a forked process does: tables on every kind of pool, equal to `reference`, and a new
 * tree. Returns the number of failed checks. */
static int child_work(const nbhd_tree *tree, const nbhd_neighborhoods *reference) {
    static const size_t counts[] = {0, 1, 2, 0, 2};
    nbhd_points desc = {pts, N, 3, 3 * sizeof(float), NBHD_SCALAR_TYPE_F32};
    nbhd_build_options bo = nbhd_build_options_default();
    nbhd_tree *fresh = NULL;
    size_t i;
    for (i = 0; i < sizeof counts / sizeof counts[0]; i++) {
        nbhd_neighborhoods *t = table(tree, counts[i]);
        CHECK(same(t, reference));
        nbhd_neighborhoods_free(t);
    }
    CHECK_STATUS(nbhd_tree_build(&desc, &bo, &fresh), NBHD_STATUS_OK);
    if (fresh != NULL) {
        nbhd_neighborhoods *t = table(fresh, 0);
        CHECK(same(t, reference));
        nbhd_neighborhoods_free(t);
        nbhd_tree_free(fresh);
    }
    return failures;
}

/* Forks; the child runs child_work (and, if `depth` > 1, forks once more itself) under an
 * alarm and exits 0 only if everything held. Checks the child's exit in the parent. */
static void fork_and_check(const nbhd_tree *tree, const nbhd_neighborhoods *reference, int depth) {
    pid_t pid;
    int status = 0;
    fflush(stdout);
    fflush(stderr);
    pid = fork();
    if (pid < 0) {
        CHECK(!"fork failed");
        return;
    }
    if (pid == 0) {
        alarm(60); /* a hang becomes a SIGALRM death the parent sees */
        failures = 0;
        child_work(tree, reference);
        if (depth > 1) fork_and_check(tree, reference, depth - 1);
        _exit(failures == 0 ? 0 : 1);
    }
    CHECK(waitpid(pid, &status, 0) == pid);
    if (WIFSIGNALED(status)) {
        fprintf(stderr, "fork_test: child (depth %d) killed by signal %d%s\n", depth,
                WTERMSIG(status), WTERMSIG(status) == SIGALRM ? " (it hung: alarm)" : "");
    }
    CHECK(WIFEXITED(status) && WEXITSTATUS(status) == 0);
}

int main(void) {
    nbhd_points desc = {pts, N, 3, 3 * sizeof(float), NBHD_SCALAR_TYPE_F32};
    nbhd_build_options bo = nbhd_build_options_default();
    nbhd_neighborhoods *reference, *t;
    nbhd_tree *tree = NULL;
    uint64_t rng = 0x2545F4914F6CDD1DULL;
    long cores = sysconf(_SC_NPROCESSORS_ONLN);
    long base;
    size_t i;

    for (i = 0; i < 3 * N; i++) {
        rng ^= rng << 13;
        rng ^= rng >> 7;
        rng ^= rng << 17;
        pts[i] = (float)(rng >> 40) / (float)(1 << 24);
    }

    /* 1. Far above the limit: refused before any thread starts. */
    base = process_threads();
    CHECK(base >= 1);
    bo.threads = 100000;
    CHECK_STATUS(nbhd_tree_build(&desc, &bo, &tree), NBHD_STATUS_INVALID_OPTION);
    CHECK_MESSAGE("100000");
    CHECK(tree == NULL);
    bo.threads = NBHD_MAX_THREADS + 1;
    CHECK_STATUS(nbhd_tree_build(&desc, &bo, &tree), NBHD_STATUS_INVALID_OPTION);
    CHECK(process_threads() == base);

    /* 2. A one-thread build: no pool at all. */
    bo.threads = 1;
    CHECK_STATUS(nbhd_tree_build(&desc, &bo, &tree), NBHD_STATUS_OK);
    CHECK(process_threads() == base);
    if (tree == NULL) return 1;
    {
        nbhd_table_options o = nbhd_table_options_default();
        nbhd_neighborhood_spec spec = {NBHD_NEIGHBORHOOD_KIND_KNN, K, 0.0};
        o.threads = 100000;
        t = NULL;
        CHECK_STATUS(nbhd_tree_neighborhoods(tree, &spec, &o, &t), NBHD_STATUS_INVALID_OPTION);
        CHECK_MESSAGE("100000");
        CHECK(t == NULL);
    }
    /* More threads than cores: the call's own pool, joined before the call returns. */
    reference = table(tree, 1000);
    CHECK(process_threads() == base);
    printf("fork_test: threads=1000 left %ld threads (before: %ld)\n", process_threads(), base);
    /* One thread: kept for the next call, and reused by it. */
    t = table(tree, 1);
    CHECK(same(t, reference));
    nbhd_neighborhoods_free(t);
    CHECK(process_threads() == base + 1);
    t = table(tree, 1);
    nbhd_neighborhoods_free(t);
    CHECK(process_threads() == base + 1);
    if (cores < 64) {
        /* Not kept (above the cores), and the kept one-thread pool stays. */
        t = table(tree, 64);
        CHECK(same(t, reference));
        nbhd_neighborhoods_free(t);
        CHECK(process_threads() == base + 1);
    }

    /* 3. Tables on the shared pool and on a kept pool of two, then fork. */
    t = table(tree, 0);
    CHECK(same(t, reference));
    nbhd_neighborhoods_free(t);
    t = table(tree, 2);
    CHECK(same(t, reference));
    nbhd_neighborhoods_free(t);
    fork_and_check(tree, reference, 2);

    /* The parent's pools still work after the fork. */
    t = table(tree, 0);
    CHECK(same(t, reference));
    nbhd_neighborhoods_free(t);
    t = table(tree, 2);
    CHECK(same(t, reference));
    nbhd_neighborhoods_free(t);

    nbhd_neighborhoods_free(reference);
    nbhd_tree_free(tree);
    printf("fork_test: %d checks, %d failures\n", checks, failures);
    return failures == 0 ? 0 : 1;
}
