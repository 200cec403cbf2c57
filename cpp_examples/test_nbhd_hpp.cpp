// ctest: the C++ layer <nbhd.hpp> where the caller changes things between calls, against a
// brute force. scripts/sanitize-test.sh also builds it under AddressSanitizer +
// UndefinedBehaviorSanitizer, where any read of freed or foreign memory fails it.
//
//   test_nbhd_hpp [N]          N random points (default 4000)
//
// 1. The tree keeps its own copy: built from a buffer that is then overwritten and freed,
//    every answer (k nearest, radius, k nearest within a radius, around coordinates and around
//    stored points, the all-point table through RowsF32) equals the brute force over the
//    points as they were.
// 2. Several threads query one tree, coordinate and index queries interleaved, each with its
//    own result buffers that grow and shrink, and tables of a list of query points in which
//    points repeat (nbhd_tree_neighborhoods_of): every answer equals the brute force.
// 3. Wrong uses fail cleanly: a row past the table (std::out_of_range), an index past the
//    points, k = 0 (nbhdpp::Error with the status).
// 4. The tree's nodes (nodes, tree_order, node_weights): the root covers the tree order, a
//    permutation of the points; every internal node's children split its range; each node's
//    weight sum equals the sum over its points; a wrong number of weights is an nbhdpp::Error.
// Exit 1 on any disagreement.
#include <nbhd.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <stdexcept>
#include <thread>
#include <vector>

static int failures = 0;
#define EXPECT(cond, ...)                                                        \
    do {                                                                         \
        if (!(cond)) {                                                           \
            ++failures;                                                          \
            std::fprintf(stderr, "FAIL %s:%d: %s: ", __FILE__, __LINE__, #cond); \
            std::fprintf(stderr, __VA_ARGS__);                                   \
            std::fprintf(stderr, "\n");                                          \
        }                                                                        \
    } while (0)

struct Pt {
    float x, y, z, pad;  // 16-byte stride, as PCL's point types
};

/// Squared distance summed x, y, z in order, as nbhd computes it in f32.
static float sq(const Pt& a, const float* q) {
    const float dx = a.x - q[0], dy = a.y - q[1], dz = a.z - q[2];
    return dx * dx + dy * dy + dz * dz;
}

/// nbhd's answer by brute force: within `r` (inclusive; r < 0: no limit) the `k` nearest
/// (k = 0: all), ordered by (squared distance, index), skipping index `self` (or none).
static nbhdpp::Result brute(const std::vector<Pt>& pts, const float* q, std::size_t k, double r,
                            long self = -1) {
    std::vector<std::pair<float, std::uint32_t>> all;
    const float lim = r < 0 ? INFINITY : static_cast<float>(r * r);
    for (std::size_t i = 0; i < pts.size(); ++i) {
        const float d = sq(pts[i], q);
        if (static_cast<long>(i) != self && d <= lim) all.emplace_back(d, static_cast<std::uint32_t>(i));
    }
    std::sort(all.begin(), all.end());
    if (k > 0 && all.size() > k) all.resize(k);
    nbhdpp::Result out;
    for (const auto& e : all) {
        out.idx.push_back(e.second);
        out.sq.push_back(e.first);
    }
    return out;
}

static bool same(const nbhdpp::Result& a, const nbhdpp::Result& b) {
    return a.idx == b.idx && a.sq == b.sq;
}

static std::vector<Pt> random_points(std::size_t n, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    std::vector<Pt> p(n);
    for (std::size_t i = 0; i < n; ++i) {
        p[i] = i > 0 && i % 50 == 0 ? p[rng() % i] : Pt{u(rng), u(rng), u(rng), 0.0f};
    }
    return p;
}

/// Section 1: the build's buffer overwritten and freed before any query.
static void own_copy(std::size_t n, double r) {
    const std::vector<Pt> kept = random_points(n, 5);
    nbhdpp::Tree tree;
    {
        std::vector<Pt>* buffer = new std::vector<Pt>(kept);
        tree = nbhdpp::build(nbhdpp::points_f32(&(*buffer)[0].x, n, sizeof(Pt)),
                             nbhd_build_options_default());
        for (Pt& p : *buffer) p = Pt{-7.0f, 9.0f, 1e30f, 0.0f};
        delete buffer;
    }
    std::size_t bad = 0;
    nbhdpp::Result got;
    for (std::size_t i = 0; i < n; i += 7) {
        const float q[3] = {kept[i].x, kept[i].y, kept[i].z};
        nbhdpp::knn(tree.get(), q, 10, got);
        bad += !same(got, brute(kept, q, 10, -1));
        nbhdpp::radius(tree.get(), q, r, got);
        bad += !same(got, brute(kept, q, 0, r));
        nbhdpp::knn_radius(tree.get(), q, 6, r, got);
        bad += !same(got, brute(kept, q, 6, r));
        nbhdpp::knn_index(tree.get(), i, true, 10, got);
        bad += !same(got, brute(kept, q, 10, -1, static_cast<long>(i)));
    }
    nbhd_neighborhood_spec spec = {NBHD_NEIGHBORHOOD_KIND_KNN_RADIUS, 9, r};
    const nbhdpp::Table table = nbhdpp::neighborhoods(tree.get(), spec, true, 2);
    const nbhdpp::RowsF32 rows(table.get());
    EXPECT(rows.rows() == n, "%zu rows", rows.rows());
    for (std::size_t i = 0; i < rows.rows(); i += 3) {
        const float q[3] = {kept[i].x, kept[i].y, kept[i].z};
        const nbhdpp::Row row = rows[i];
        nbhdpp::Result as_result;
        as_result.idx.assign(row.idx, row.idx + row.len);
        as_result.sq.assign(row.sq, row.sq + row.len);
        bad += !same(as_result, brute(kept, q, 9, r, static_cast<long>(i)));
    }
    std::printf("  buffer overwritten and freed after the build: %zu disagreements\n", bad);
    EXPECT(bad == 0, "own copy");
}

/// Section 2: `threads` threads on one tree, query forms interleaved.
static void threads_interleaved(std::size_t n, unsigned threads, double r) {
    const std::vector<Pt> pts = random_points(n, 9);
    const nbhdpp::Tree tree =
        nbhdpp::build(nbhdpp::points_f32(&pts[0].x, n, sizeof(Pt)), nbhd_build_options_default());
    std::vector<std::size_t> bad(threads, 0);
    std::vector<std::thread> pool;
    for (unsigned w = 0; w < threads; ++w) {
        pool.emplace_back([&, w] {
            nbhdpp::Result got;
            for (std::size_t j = w; j < n; j += threads) {
                const std::size_t i = (j * 7919) % n;
                const float q[3] = {pts[i].x, pts[i].y, pts[i].z};
                switch (j % 4) {
                    case 0:
                        nbhdpp::knn_index(tree.get(), i, false, 1 + j % 13, got);
                        bad[w] += !same(got, brute(pts, q, 1 + j % 13, -1));
                        break;
                    case 1:
                        nbhdpp::knn(tree.get(), q, 1 + j % 17, got);
                        bad[w] += !same(got, brute(pts, q, 1 + j % 17, -1));
                        break;
                    case 2:
                        nbhdpp::radius(tree.get(), q, r * (1 + j % 3), got);
                        bad[w] += !same(got, brute(pts, q, 0, r * (1 + j % 3)));
                        break;
                    default: {
                        // A table of a few query points, some listed twice or three times.
                        std::vector<Pt> list;
                        for (std::size_t m = 0; m < 5; ++m) list.push_back(pts[(i + m * 31) % n]);
                        list.push_back(list[0]);
                        list.push_back(list[2]);
                        list.push_back(list[0]);
                        const nbhd_points qd = nbhdpp::points_f32(&list[0].x, list.size(), sizeof(Pt));
                        const nbhd_neighborhood_spec spec = {NBHD_NEIGHBORHOOD_KIND_KNN, 7, 0.0};
                        nbhd_neighborhoods* raw = nullptr;
                        nbhdpp::check(nbhd_tree_neighborhoods_of(tree.get(), &qd, &spec, nullptr, &raw),
                                      "nbhd_tree_neighborhoods_of");
                        const nbhdpp::Table t(raw);
                        const nbhdpp::RowsF32 rows(t.get());
                        bad[w] += rows.rows() != list.size();
                        for (std::size_t m = 0; m < rows.rows() && m < list.size(); ++m) {
                            const float lq[3] = {list[m].x, list[m].y, list[m].z};
                            const nbhdpp::Row row = rows[m];
                            nbhdpp::Result as_result;
                            as_result.idx.assign(row.idx, row.idx + row.len);
                            as_result.sq.assign(row.sq, row.sq + row.len);
                            bad[w] += !same(as_result, brute(pts, lq, 7, -1));
                        }
                    }
                }
            }
        });
    }
    for (auto& th : pool) th.join();
    std::size_t total = 0;
    for (std::size_t b : bad) total += b;
    std::printf("  %u threads, index, coordinate and table queries interleaved: %zu disagreements\n",
                threads, total);
    EXPECT(total == 0, "threads");
}

/// Section 3: wrong uses.
static void wrong_uses(std::size_t n) {
    const std::vector<Pt> pts = random_points(n, 3);
    const nbhdpp::Tree tree =
        nbhdpp::build(nbhdpp::points_f32(&pts[0].x, n, sizeof(Pt)), nbhd_build_options_default());
    const nbhd_neighborhood_spec spec = {NBHD_NEIGHBORHOOD_KIND_KNN, 3, 0.0};
    const nbhdpp::Table table = nbhdpp::neighborhoods(tree.get(), spec, false);
    const nbhdpp::RowsF32 rows(table.get());
    bool threw = false;
    try {
        (void)rows[rows.rows()];
    } catch (const std::out_of_range&) {
        threw = true;
    }
    EXPECT(threw, "a row past the table must throw std::out_of_range");
    nbhdpp::Result got;
    nbhd_status status = NBHD_STATUS_OK;
    try {
        nbhdpp::knn_index(tree.get(), n, false, 3, got);
    } catch (const nbhdpp::Error& e) {
        status = e.status();
    }
    EXPECT(status == NBHD_STATUS_INDEX_OUT_OF_RANGE, "index past the points: status %d", status);
    status = NBHD_STATUS_OK;
    try {
        const float q[3] = {0, 0, 0};
        nbhdpp::knn(tree.get(), q, 0, got);
    } catch (const nbhdpp::Error& e) {
        status = e.status();
    }
    EXPECT(status == NBHD_STATUS_INVALID_K, "k = 0: status %d", status);
}

/// Section 4: the node list, the tree order and the weight sums through the sized() helpers.
static void nodes(std::size_t n) {
    const std::vector<Pt> pts = random_points(n, 4);
    const nbhdpp::Tree tree =
        nbhdpp::build(nbhdpp::points_f32(&pts[0].x, n, sizeof(Pt)), nbhd_build_options_default());
    const std::vector<nbhd_node> list = nbhdpp::nodes(tree.get());
    const std::vector<std::uint32_t> order = nbhdpp::tree_order(tree.get());
    std::vector<std::uint32_t> sorted = order;
    std::sort(sorted.begin(), sorted.end());
    bool permutation = sorted.size() == n;
    for (std::size_t i = 0; permutation && i < n; ++i) permutation = sorted[i] == i;
    EXPECT(permutation, "tree_order is not a permutation of the %zu points", n);
    EXPECT(list.size() == nbhdpp::stats(tree.get()).nodes && list[0].start == 0 && list[0].end == n,
           "%zu nodes, root %zu..%zu", list.size(), list[0].start, list[0].end);
    std::vector<double> w(n);
    for (std::size_t i = 0; i < n; ++i) w[i] = static_cast<double>(i % 5);
    const std::vector<double> sums = nbhdpp::node_weights(tree.get(), w);
    EXPECT(sums.size() == list.size(), "%zu sums", sums.size());
    for (std::size_t i = 0; i < list.size() && i < sums.size(); ++i) {
        const nbhd_node& node = list[i];
        double direct = 0.0;
        for (std::size_t p = node.start; p < node.end; ++p) direct += w[order[p]];
        EXPECT(sums[i] == direct, "node %zu: sum %g, over its points %g", i, sums[i], direct);
        if (!node.leaf) {
            EXPECT(node.left == i + 1 && list[node.left].start == node.start &&
                       list[node.left].end == list[node.right].start &&
                       list[node.right].end == node.end,
                   "node %zu: children %zu, %zu", i, node.left, node.right);
        }
    }
    nbhd_status status = NBHD_STATUS_OK;
    try {
        nbhdpp::node_weights(tree.get(), std::vector<double>(n - 1, 1.0));
    } catch (const nbhdpp::Error& e) {
        status = e.status();
    }
    EXPECT(status == NBHD_STATUS_INVALID_OPTION, "n - 1 weights: status %d", status);
}

int main(int argc, char** argv) {
    const std::size_t n = argc >= 2 ? std::strtoul(argv[1], nullptr, 10) : 4000;
    if (n < 100) {
        std::fprintf(stderr, "usage: %s [N >= 100]\n", argv[0]);
        return 2;
    }
    const double r = 1.3 / std::cbrt(static_cast<double>(n));
    std::printf("<nbhd.hpp> against a brute force, %zu random points\n", n);
    own_copy(n, r);
    threads_interleaved(n, 4, r);
    wrong_uses(n);
    nodes(n);
    std::printf("%s\n", failures == 0 ? "all agree" : "DISAGREEMENTS");
    return failures == 0 ? 0 : 1;
}
