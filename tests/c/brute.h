/*
 * The brute force the C tests of metric and periodic queries compare with, computed with the
 * library's arithmetic (keys folded over the axes in order, no fused multiply-adds), and the
 * search check built on it. The including file defines N (points), DIM and CAP (result room)
 * before including this header, fills `pts` / `ptsf` (the same points in f64 and f32) and
 * defines `key_d` and `key_f`, the key from a query to a point under its options (plain or
 * at the nearest periodic image).
 */
#ifndef NBHD_TEST_BRUTE_H
#define NBHD_TEST_BRUTE_H

#include <math.h>
#include <stdint.h>
#include <stdlib.h>

#include "check.h"

static double pts[N * DIM];
static float ptsf[N * DIM];

static double key_d(const nbhd_query_options *o, const double *q, const double *x);
static float key_f(const nbhd_query_options *o, const float *q, const float *x);

/* The running key `s` with the axis difference `t` folded in, under the metric. */
static inline double term_d(const nbhd_query_options *o, double s, double t) {
    switch (o->metric) {
    case NBHD_METRIC_EUCLIDEAN: return s + t * t;
    case NBHD_METRIC_MANHATTAN: return s + t;
    case NBHD_METRIC_CHEBYSHEV: return t > s ? t : s;
    default: return s + pow(t, o->p);
    }
}

static inline float term_f(const nbhd_query_options *o, float s, float t) {
    switch (o->metric) {
    case NBHD_METRIC_EUCLIDEAN: return s + t * t;
    case NBHD_METRIC_MANHATTAN: return s + t;
    case NBHD_METRIC_CHEBYSHEV: return t > s ? t : s;
    default: return s + powf(t, (float)o->p);
    }
}

/* The key of a radius r in the metric (in the tree's type for f32). */
static inline double radius_key(const nbhd_query_options *o, double r, int f32) {
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

static inline int by_key(const void *a, const void *b) {
    const entry *x = a, *y = b;
    if (x->key != y->key) return x->key < y->key ? -1 : 1;
    return x->index < y->index ? -1 : (x->index > y->index);
}

/* The key from the query q to point j, in the tree's type. */
static inline double key_between(const nbhd_query_options *o, int f32, const double *q, size_t j) {
    float qf[DIM];
    size_t a;
    if (!f32) return key_d(o, q, pts + j * DIM);
    for (a = 0; a < DIM; a++) qf[a] = (float)q[a];
    return (double)key_f(o, qf, ptsf + j * DIM);
}

/* Brute force: the k (or all, k = 0) points with key within the radius's (below it if
 * strict; no radius if r < 0), by (key, index). */
static inline size_t brute(const nbhd_query_options *o, int f32, const double *q, size_t k, double r,
                    entry *out) {
    size_t i, n = 0;
    double bound = r < 0 ? INFINITY : radius_key(o, r, f32);
    for (i = 0; i < N; i++) {
        double key = key_between(o, f32, q, i);
        if (o->strict ? key < bound : key <= bound) {
            out[n].key = key;
            out[n].index = (uint32_t)i;
            n++;
        }
    }
    qsort(out, n, sizeof(entry), by_key);
    return k > 0 && n > k ? k : n;
}

static inline nbhd_points points_of(int f32) {
    nbhd_points p;
    p.data = f32 ? (const void *)ptsf : (const void *)pts;
    p.count = N;
    p.dim = DIM;
    p.stride = 0;
    p.scalar_type = f32 ? NBHD_SCALAR_TYPE_F32 : NBHD_SCALAR_TYPE_F64;
    return p;
}

/* One search of either flavour (the static tree if not NULL, else the growing one), compared
 * with the brute force. */
static inline void check_search(const nbhd_tree *tree, const nbhd_dynamic_tree *dyn, int f32,
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
            fprintf(stderr,
                    "metric %d p %g strict %d kind %d f32 %d q (%g %g %g): entry %zu is (%u, %g), "
                    "brute (%u, %g)\n",
                    (int)o->metric, o->p, (int)o->strict, (int)spec->kind, f32, q[0], q[1], q[2],
                    i, idx[i], key, want[i].index, want[i].key);
            break;
        }
    }
    checks++;
}

#endif
