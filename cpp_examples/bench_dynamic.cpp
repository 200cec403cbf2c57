// nbhd's dynamic tree (through the C ABI, nbhd_dynamic_*) and nanoflann's
// KDTreeSingleIndexDynamicAdaptor side by side in one run, f32, on the workloads of
// benches/dynamic.rs (which compares the same forest with kiddo's mutable tree and with
// rebuilding nbhd's static tree every frame):
//
//   (a) accumulate POINTS points in frames of FRAME; after each frame the 10 nearest
//       neighbours of the frame's points among everything so far;
//   (b) sliding window: insert a frame, remove the oldest once WINDOW points are live,
//       FRAMES_B frames, the same queries after each frame.
//
// The points are a rolling terrain over 100 x 100 units in random order (the generator of
// benches/dynamic.rs). Queries run on `threads` threads: nbhd through its `threads` option,
// nanoflann's (const, thread-safe) searches split over std::threads. A benchmark, not a test.
//
//   bench_dynamic [POINTS [FRAME [WINDOW [FRAMES_B [THREADS]]]]]   (1000000 10000 200000 100 1)
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <thread>
#include <vector>

#include <nanoflann.hpp>

#include "nbhd.h"

using P = std::array<float, 3>;

static std::vector<P> terrain(size_t n, uint64_t seed) {
    uint64_t s = seed ? seed : 1;
    auto unit = [&s]() {
        s ^= s >> 12;
        s ^= s << 25;
        s ^= s >> 27;
        return double((s * 0x2545F4914F6CDD1DULL) >> 11) / double(1ULL << 53);
    };
    std::vector<P> v(n);
    for (auto &p : v) {
        double x = unit() * 100.0, y = unit() * 100.0;
        double z = 2.0 * std::sin(x / 7.0) * std::cos(y / 5.0) + 0.05 * (unit() - 0.5);
        p = {float(x), float(y), float(z)};
    }
    return v;
}

struct Cloud {
    std::vector<P> pts;
    size_t kdtree_get_point_count() const { return pts.size(); }
    float kdtree_get_pt(size_t i, size_t d) const { return pts[i][d]; }
    template <class B> bool kdtree_get_bbox(B &) const { return false; }
};
using Nano = nanoflann::KDTreeSingleIndexDynamicAdaptor<nanoflann::L2_Simple_Adaptor<float, Cloud>,
                                                        Cloud, 3, uint32_t>;

struct Cost {
    double update = 0, query = 0, check = 0;
    double total() const { return update + query; }
};

static double since(std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

static void ok(nbhd_status s, const char *what) {
    if (s != NBHD_STATUS_OK) {
        std::fprintf(stderr, "%s: %s\n", what, nbhd_last_error_message());
        std::exit(1);
    }
}

// kNN 10 of the frame's points in nanoflann's index, on `threads` threads; the sum of the
// squared distances.
static double nano_knn(const Nano &index, const P *frame, size_t m, unsigned threads) {
    std::vector<double> sums(threads, 0.0);
    auto work = [&](unsigned t) {
        uint32_t ids[10];
        float d[10];
        for (size_t i = t; i < m; i += threads) {
            nanoflann::KNNResultSet<float, uint32_t> rs(10);
            rs.init(ids, d);
            index.findNeighbors(rs, frame[i].data(), nanoflann::SearchParams());
            for (size_t j = 0; j < rs.size(); j++) sums[t] += d[j];
        }
    };
    std::vector<std::thread> pool;
    for (unsigned t = 1; t < threads; t++) pool.emplace_back(work, t);
    work(0);
    for (auto &th : pool) th.join();
    double s = 0;
    for (double x : sums) s += x;
    return s;
}

static double nbhd_knn(const nbhd_dynamic_tree *tree, const P *frame, size_t m,
                       unsigned threads) {
    nbhd_points q = {frame, m, 3, 0, NBHD_SCALAR_TYPE_F32};
    nbhd_neighborhood_spec spec = {NBHD_NEIGHBORHOOD_KIND_KNN, 10, 0.0};
    nbhd_table_options o = nbhd_table_options_default();
    o.exclude_self = false;
    o.threads = threads;
    nbhd_neighborhoods *t = nullptr;
    ok(nbhd_dynamic_neighborhoods_of(tree, &q, &spec, &o, &t), "nbhd_dynamic_neighborhoods_of");
    const float *d = static_cast<const float *>(nbhd_neighborhoods_sq_dists(t));
    double s = 0;
    for (size_t i = 0; i < nbhd_neighborhoods_total(t); i++) s += d[i];
    nbhd_neighborhoods_free(t);
    return s;
}

// One workload: frames of `frame` points from `pts`, the oldest removed once `window` are live
// (window 0: never). False if the two disagree (their sums of the neighbours' squared
// distances differ by more than rounding).
static bool run(const char *name, const std::vector<P> &pts, size_t frame, size_t window,
                unsigned threads) {
    size_t frames = pts.size() / frame, keep = window ? window / frame : frames;
    Cost a, b;
    {
        nbhd_build_options o = nbhd_build_options_default();
        o.threads = threads;
        nbhd_dynamic_tree *tree = nullptr;
        ok(nbhd_dynamic_create(3, NBHD_SCALAR_TYPE_F32, &o, &tree), "nbhd_dynamic_create");
        std::vector<uint32_t> old(frame);
        for (size_t f = 0; f < frames; f++) {
            const P *fp = &pts[f * frame];
            auto t = std::chrono::steady_clock::now();
            nbhd_points p = {fp, frame, 3, 0, NBHD_SCALAR_TYPE_F32};
            ok(nbhd_dynamic_insert(tree, &p, nullptr), "nbhd_dynamic_insert");
            if (f >= keep) {
                for (size_t j = 0; j < frame; j++) old[j] = uint32_t((f - keep) * frame + j);
                ok(nbhd_dynamic_remove(tree, old.data(), frame), "nbhd_dynamic_remove");
            }
            a.update += since(t);
            t = std::chrono::steady_clock::now();
            a.check += nbhd_knn(tree, fp, frame, threads);
            a.query += since(t);
        }
        nbhd_dynamic_free(tree);
    }
    {
        Cloud cloud;
        cloud.pts.reserve(pts.size());
        Nano index(3, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(10));
        for (size_t f = 0; f < frames; f++) {
            const P *fp = &pts[f * frame];
            auto t = std::chrono::steady_clock::now();
            cloud.pts.insert(cloud.pts.end(), fp, fp + frame);
            index.addPoints(uint32_t(f * frame), uint32_t((f + 1) * frame - 1));
            if (f >= keep) {
                for (size_t j = 0; j < frame; j++) index.removePoint((f - keep) * frame + j);
            }
            b.update += since(t);
            t = std::chrono::steady_clock::now();
            b.check += nano_knn(index, fp, frame, threads);
            b.query += since(t);
        }
    }
    std::printf("  %s:\n    %-34s %9s %9s %9s %14s\n", name, "method", "update s", "query s",
                "total s", "/ nbhd dynamic");
    std::printf("    %-34s %9.3f %9.3f %9.3f %14.2f\n", "nbhd dynamic (C ABI)", a.update, a.query,
                a.total(), 1.0);
    std::printf("    %-34s %9.3f %9.3f %9.3f %14.2f\n", "nanoflann DynamicAdaptor", b.update,
                b.query, b.total(), b.total() / a.total());
    double rel = std::fabs(a.check - b.check) / (a.check > 0 ? a.check : 1);
    std::printf("    answers agree (sum of squared distances, relative difference): %.1e\n", rel);
    return rel < 1e-6;
}

int main(int argc, char **argv) {
    size_t n = argc > 1 ? std::strtoull(argv[1], nullptr, 10) : 1000000;
    size_t frame = argc > 2 ? std::strtoull(argv[2], nullptr, 10) : 10000;
    size_t window = argc > 3 ? std::strtoull(argv[3], nullptr, 10) : 200000;
    size_t frames_b = argc > 4 ? std::strtoull(argv[4], nullptr, 10) : 100;
    unsigned threads = argc > 5 ? unsigned(std::strtoul(argv[5], nullptr, 10)) : 1;
    if (frame == 0 || n < frame || threads == 0) {
        std::fprintf(stderr, "usage: bench_dynamic [POINTS [FRAME [WINDOW [FRAMES_B [THREADS]]]]]\n");
        return 2;
    }
    auto pts = terrain(n > frame * frames_b ? n : frame * frames_b, 42);
    std::printf("dynamic trees, f32, terrain points in random order, threads %u\n", threads);
    bool same = run("(a) accumulate",
                    std::vector<P>(pts.begin(), pts.begin() + (n / frame) * frame), frame, 0,
                    threads);
    same &= run("(b) sliding window",
                std::vector<P>(pts.begin(), pts.begin() + frame * frames_b), frame, window,
                threads);
    if (!same) std::fprintf(stderr, "bench_dynamic: nbhd and nanoflann disagree\n");
    return same ? 0 : 1;
}
