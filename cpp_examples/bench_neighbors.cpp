// bench_neighbors: nbhd and its C++ peers side by side, in one process, on one thread.
//
//   bench_neighbors [--reps N] [--generated N] [FILE...]
//
// For every cloud (the FILEs, loaded as compare_neighbors loads them, then a torus and a uniform
// cube of N points each, 1,000,000 by default, 0 for none) and every library it times:
//   build       the tree
//   kNN 10/30   the k nearest of every point (the point itself included)
//   radius      all points within r, r giving about 20 neighbours on average
//   eps-k 16    the 16 nearest within that r
// for nbhd with each pivot policy (one thread; tables with nbhd_tree_neighborhoods), nbhd's
// sliding-midpoint tree asked one query per point in the caller's order through the C ABI
// (nbhd_tree_knn, nbhd_tree_radius, nbhd_tree_knn_radius: what a caller of PCL's nearestKSearch
// gets), nbhd's default policy on all cores, nanoflann (leaf 10; queries in the caller's order and, as a
// separate row, in the tree's leaf order), FLANN's KDTreeSingleIndex (leaf 10) and PCL's
// KdTreeFLANN. Every result is stored (kNN into n x k arrays, radius into growing arrays, nbhd
// into its table), so that no library is timed without its output. Prints the median of N
// repetitions in milliseconds and the ratio to nbhd (sliding midpoint, one thread); shared
// machines vary by 20-70% between runs, so compare ratios within one run only.
//
// nbhd's radius is inclusive (d2 <= r2), the peers' strict (d2 < r2): radius and eps-k totals may
// differ by the points exactly on the radius; kNN totals must agree (exit 1 otherwise).
// Points with NaN coordinates are skipped by nbhd and PCL; nanoflann and FLANN get a compact copy
// of the finite points (as compare_neighbors does), which is then built and queried.
#include "cloud_io.hpp"
#include <nbhd.hpp>

#include <flann/flann.hpp>
#include <nanoflann.hpp>
#include <pcl/kdtree/kdtree_flann.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <vector>

using examples::Cloud;

namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

// --- generated clouds (deterministic: mt19937 bits turned into floats by hand) -------------

float unit(std::mt19937& rng) { return static_cast<float>(rng() >> 8) * (1.0f / 16777216.0f); }

Cloud torus(std::size_t n) {
    std::mt19937 rng(1);
    std::vector<float> p;
    p.reserve(3 * n);
    const float R = 1.0f, r = 0.35f, tau = 6.28318530718f;
    for (std::size_t i = 0; i < n; ++i) {
        float u = tau * unit(rng), v = tau * unit(rng);
        p.push_back((R + r * std::cos(v)) * std::cos(u));
        p.push_back((R + r * std::cos(v)) * std::sin(u));
        p.push_back(r * std::sin(v));
    }
    return examples::make_cloud("torus " + std::to_string(n), std::move(p));
}

Cloud cube(std::size_t n) {
    std::mt19937 rng(2);
    std::vector<float> p(3 * n);
    for (float& x : p) x = unit(rng);
    return examples::make_cloud("uniform cube " + std::to_string(n), std::move(p));
}

// --- what every library answers -------------------------------------------------------------

/// The finite points packed (x, y, z), for the peers that cannot skip NaN, with the map back.
struct Compact {
    std::vector<float> xyz;
    const float* data;
    std::size_t stride;
    std::size_t n;
    std::vector<std::uint32_t> map;  // empty: identity
    explicit Compact(const Cloud& c) {
        if (!c.has_non_finite()) {
            data = c.xyz;
            stride = c.stride;
            n = c.count;
            return;
        }
        for (std::uint32_t i : c.finite) xyz.insert(xyz.end(), c.point(i), c.point(i) + 3);
        map = c.finite;
        data = xyz.data();
        stride = 3 * sizeof(float);
        n = c.finite.size();
    }
    const float* point(std::size_t i) const {
        return reinterpret_cast<const float*>(reinterpret_cast<const char*>(data) + i * stride);
    }
};

/// Output sinks, kept between calls so that every library writes its whole answer.
struct Sink {
    std::vector<std::uint32_t> idx;
    std::vector<float> sq;
    void reset_fixed(std::size_t n) {
        idx.assign(n, 0);
        sq.assign(n, 0.0f);
    }
};

struct Op {
    const char* name;
    int kind;  // 0 build, 1 knn, 2 radius, 3 eps-k
    std::size_t k;
};
const Op kOps[] = {{"build", 0, 0}, {"kNN k=10", 1, 10}, {"kNN k=30", 1, 30}, {"radius", 2, 0}, {"eps-k k=16", 3, 16}};
constexpr int kNumOps = 5;

/// One library: build, then answer an op; returns the number of neighbours it found.
struct Lib {
    std::string name;
    bool has_build = true;  // false: shares another row's tree (the row shows no build time)
    std::function<void()> build;
    std::function<std::size_t(const Op&, float r)> run;
    std::function<void()> release;
};

// nbhd
struct NbhdLib {
    const Cloud& c;
    nbhd_build_options o;
    std::size_t table_threads;
    nbhdpp::Tree tree;
    std::size_t run(const Op& op, float r) {
        nbhd_neighborhood_spec spec{};
        spec.kind = op.kind == 1 ? NBHD_NEIGHBORHOOD_KIND_KNN
                    : op.kind == 2 ? NBHD_NEIGHBORHOOD_KIND_RADIUS
                                   : NBHD_NEIGHBORHOOD_KIND_KNN_RADIUS;
        spec.k = op.k ? op.k : 1;
        spec.radius = r;
        nbhdpp::Table t = nbhdpp::neighborhoods(tree.get(), spec, /*exclude_self=*/false, table_threads);
        return nbhd_neighborhoods_total(t.get());
    }
};

// nbhd single queries through the C ABI, as a C or C++ caller asks them (and as PCL's
// nearestKSearch is called below): one nbhd_tree_knn / nbhd_tree_radius / nbhd_tree_knn_radius
// call per point, in the caller's order, on the reference row's tree, the results copied into
// n x k arrays (kNN, eps-k) or appended to growing arrays (radius).
struct NbhdSingleLib {
    const Cloud& c;
    const NbhdLib* ref;
    Sink sink;
    std::vector<std::uint32_t> idx;
    std::vector<float> sq;
    std::size_t run(const Op& op, float r) {
        const nbhd_tree* t = ref->tree.get();
        std::size_t total = 0;
        if (op.kind == 1 || op.kind == 3) {
            const std::size_t k = op.k;
            sink.reset_fixed(c.count * k);
            for (std::uint32_t i : c.finite) {
                std::size_t found = 0;
                nbhd_status s = op.kind == 1
                                    ? nbhd_tree_knn(t, c.point(i), k, &sink.idx[i * k], &sink.sq[i * k], k, &found)
                                    : nbhd_tree_knn_radius(t, c.point(i), k, r, &sink.idx[i * k], &sink.sq[i * k], k,
                                                           &found);
                nbhdpp::check(s, "nbhd single query");
                total += found;
            }
            return total;
        }
        sink.idx.clear();
        sink.sq.clear();
        if (idx.size() < 256) {
            idx.resize(256);
            sq.resize(256);
        }
        for (std::uint32_t i : c.finite) {
            std::size_t found = 0;
            nbhd_status s = nbhd_tree_radius(t, c.point(i), r, idx.data(), sq.data(), idx.size(), &found);
            if (s == NBHD_STATUS_BUFFER_TOO_SMALL) {  // grows to the largest neighbourhood seen
                idx.resize(found);
                sq.resize(found);
                s = nbhd_tree_radius(t, c.point(i), r, idx.data(), sq.data(), idx.size(), &found);
            }
            nbhdpp::check(s, "nbhd_tree_radius");
            sink.idx.insert(sink.idx.end(), idx.begin(), idx.begin() + found);
            sink.sq.insert(sink.sq.end(), sq.begin(), sq.begin() + found);
            total += found;
        }
        return total;
    }
};

// nanoflann over a strided buffer, read in place.
struct StridedAdaptor {
    const char* base;
    std::size_t n, stride;
    std::size_t kdtree_get_point_count() const { return n; }
    float kdtree_get_pt(std::size_t i, std::size_t d) const {
        return reinterpret_cast<const float*>(base + i * stride)[d];
    }
    template <class BBox>
    bool kdtree_get_bbox(BBox&) const { return false; }
};
using NanoTree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, StridedAdaptor>,
                                                     StridedAdaptor, 3, std::uint32_t>;

struct NanoLib {
    const Compact& pts;
    StridedAdaptor adaptor;
    std::unique_ptr<NanoTree> tree;
    Sink sink;
    std::vector<std::pair<std::uint32_t, float>> pairs;
    explicit NanoLib(const Compact& p)
        : pts(p), adaptor{reinterpret_cast<const char*>(p.data), p.n, p.stride} {}
    void build() {
        tree = std::make_unique<NanoTree>(3, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(10));
    }
    // The order in which the points are queried: 0..n-1, or the tree's leaf order.
    std::size_t run(const Op& op, float r, bool tree_order) {
        const std::size_t n = pts.n;
        const std::vector<std::uint32_t>* order = tree_order ? &tree->vAcc : nullptr;
        const float r2 = r * r;
        std::size_t total = 0;
        if (op.kind == 1 || op.kind == 3) {
            const std::size_t k = op.k;
            sink.reset_fixed(n * k);
            std::vector<std::size_t> count(n);
            for (std::size_t j = 0; j < n; ++j) {
                std::size_t i = order ? (*order)[j] : j;
                nanoflann::KNNResultSet<float, std::uint32_t> rs(k);
                rs.init(&sink.idx[i * k], &sink.sq[i * k]);
                // eps-k: nanoflann 1.4.3 has no such call; a kNN result set whose worst distance
                // starts at r2 keeps the k nearest with d2 < r2 and prunes with min(r2, k-th).
                if (op.kind == 3) sink.sq[i * k + k - 1] = r2;
                tree->findNeighbors(rs, pts.point(i), nanoflann::SearchParams(32, 0.0f, true));
                total += rs.size();
            }
        } else {
            sink.idx.clear();
            sink.sq.clear();
            for (std::size_t j = 0; j < n; ++j) {
                std::size_t i = order ? (*order)[j] : j;
                tree->radiusSearch(pts.point(i), r2, pairs, nanoflann::SearchParams(32, 0.0f, true));
                for (auto& p : pairs) {
                    sink.idx.push_back(p.first);
                    sink.sq.push_back(p.second);
                }
                total += pairs.size();
            }
        }
        return total;
    }
};

struct FlannLib {
    const Compact& pts;
    using Index = flann::KDTreeSingleIndex<flann::L2_Simple<float>>;
    std::unique_ptr<Index> index;
    Sink sink;
    std::vector<std::size_t> idx;
    std::vector<std::vector<std::size_t>> vi;
    std::vector<std::vector<float>> vd;
    explicit FlannLib(const Compact& p) : pts(p) {}
    flann::Matrix<float> matrix() const {
        return flann::Matrix<float>(const_cast<float*>(pts.data), pts.n, 3, pts.stride);
    }
    void build() {
        index = std::make_unique<Index>(matrix(), flann::KDTreeSingleIndexParams(10));
        index->buildIndex();
    }
    std::size_t run(const Op& op, float r) {
        flann::SearchParams p;
        p.checks = flann::FLANN_CHECKS_UNLIMITED;
        p.sorted = true;
        const std::size_t n = pts.n;
        if (op.kind == 1) {
            idx.assign(n * op.k, 0);
            sink.sq.assign(n * op.k, 0.0f);
            flann::Matrix<std::size_t> mi(idx.data(), n, op.k);
            flann::Matrix<float> md(sink.sq.data(), n, op.k);
            return static_cast<std::size_t>(index->knnSearch(matrix(), mi, md, op.k, p));
        }
        p.max_neighbors = op.kind == 3 ? static_cast<int>(op.k) : -1;
        return static_cast<std::size_t>(index->radiusSearch(matrix(), vi, vd, r * r, p));
    }
};

struct PclLib {
    const Cloud& c;
    std::unique_ptr<pcl::KdTreeFLANN<pcl::PointXYZ>> tree;
    Sink sink;
    pcl::Indices idx;
    std::vector<float> sq;
    void build() {
        tree = std::make_unique<pcl::KdTreeFLANN<pcl::PointXYZ>>();
        tree->setInputCloud(c.pcl);
    }
    std::size_t run(const Op& op, float r) {
        const auto& cloud = *c.pcl;
        std::size_t total = 0;
        if (op.kind == 1) {
            sink.reset_fixed(c.count * op.k);
            for (std::uint32_t i : c.finite) {
                int found = tree->nearestKSearch(cloud[i], static_cast<int>(op.k), idx, sq);
                std::copy(idx.begin(), idx.end(), sink.idx.begin() + i * op.k);
                std::copy(sq.begin(), sq.end(), sink.sq.begin() + i * op.k);
                total += static_cast<std::size_t>(found);
            }
            return total;
        }
        sink.idx.clear();
        sink.sq.clear();
        unsigned max_nn = op.kind == 3 ? static_cast<unsigned>(op.k) : 0u;
        for (std::uint32_t i : c.finite) {
            int found = tree->radiusSearch(cloud[i], static_cast<double>(r), idx, sq, max_nn);
            sink.idx.insert(sink.idx.end(), idx.begin(), idx.end());
            sink.sq.insert(sink.sq.end(), sq.begin(), sq.end());
            total += static_cast<std::size_t>(found);
        }
        return total;
    }
};

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    std::size_t m = v.size() / 2;
    return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

/// r giving about `target` neighbours (self included): the median over a sample of points of
/// the distance to their target-th nearest.
float choose_radius(const nbhd_tree* tree, const Cloud& c, std::size_t target) {
    std::size_t step = std::max<std::size_t>(1, c.finite.size() / 2000);
    std::vector<float> d2;
    nbhdpp::Result r;
    for (std::size_t j = 0; j < c.finite.size(); j += step) {
        nbhdpp::knn(tree, c.point(c.finite[j]), target, r);
        d2.push_back(r.sq.back());
    }
    std::nth_element(d2.begin(), d2.begin() + d2.size() / 2, d2.end());
    return std::sqrt(d2[d2.size() / 2]);
}

bool bench_cloud(const Cloud& c, int reps) {
    std::printf("\n%s: %zu points (%zu finite), %d repetitions, one thread unless said\n", c.name.c_str(),
                c.count, c.finite.size(), reps);
    const Compact compact(c);
    nbhd_build_options base = nbhd_build_options_default();
    base.threads = 1;
    if (c.has_non_finite()) base.non_finite = NBHD_NON_FINITE_POLICY_SKIP;

    float r = 0;
    {
        nbhdpp::Tree t = nbhdpp::build(nbhdpp::points_f32(c.xyz, c.count, c.stride), base);
        r = choose_radius(t.get(), c, 20);
    }

    std::vector<std::unique_ptr<NbhdLib>> nb;
    std::vector<Lib> libs;
    auto add_nbhd = [&](nbhd_pivot_policy pivot, std::size_t threads, std::string name) {
        nbhd_build_options o = base;
        o.pivot = pivot;
        o.threads = threads;
        nb.push_back(std::make_unique<NbhdLib>(NbhdLib{c, o, threads, nullptr}));
        NbhdLib* l = nb.back().get();
        libs.push_back(Lib{std::move(name), true,
                           [l] { l->tree = nbhdpp::build(nbhdpp::points_f32(l->c.xyz, l->c.count, l->c.stride), l->o); },
                           [l](const Op& op, float rr) { return l->run(op, rr); }, [l] { l->tree.reset(); }});
    };
    add_nbhd(NBHD_PIVOT_POLICY_SLIDING_MIDPOINT, 1, "nbhd sliding-midpoint");  // the reference
    // The reference row's tree, asked one query at a time (it is released after this row).
    NbhdSingleLib single{c, nb.back().get(), {}, {}, {}};
    libs.push_back(Lib{"nbhd single queries (C ABI)", false, [] {},
                       [&](const Op& op, float rr) { return single.run(op, rr); }, [&] { nb[0]->tree.reset(); }});
    add_nbhd(NBHD_PIVOT_POLICY_CYCLIC_MEDIAN, 1, "nbhd cyclic-median");
    add_nbhd(NBHD_PIVOT_POLICY_SPREAD_MEDIAN, 1, "nbhd spread-median");
    add_nbhd(NBHD_PIVOT_POLICY_CLOSEST_TO_MIDDLE, 1, "nbhd closest-to-middle");
    add_nbhd(NBHD_PIVOT_POLICY_SLIDING_MIDPOINT, 0, "nbhd sliding-mid., all cores");
    NanoLib nano(compact);
    libs.push_back(Lib{"nanoflann 1.4.3 leaf 10", true, [&] { nano.build(); },
                       [&](const Op& op, float rr) { return nano.run(op, rr, false); }, [] {}});
    libs.push_back(Lib{"nanoflann, tree order", false, [] {},
                       [&](const Op& op, float rr) { return nano.run(op, rr, true); }, [&] { nano.tree.reset(); }});
    FlannLib fl(compact);
    libs.push_back(Lib{"FLANN KDTreeSingleIndex", true, [&] { fl.build(); },
                       [&](const Op& op, float rr) { return fl.run(op, rr); }, [&] { fl.index.reset(); }});
    PclLib pc{c, nullptr, {}, {}, {}};
    libs.push_back(Lib{"PCL KdTreeFLANN", true, [&] { pc.build(); },
                       [&](const Op& op, float rr) { return pc.run(op, rr); }, [&] { pc.tree.reset(); }});

    const std::size_t L = libs.size();
    std::vector<std::vector<std::vector<double>>> ms(L, std::vector<std::vector<double>>(kNumOps));
    std::vector<std::vector<std::size_t>> found(L, std::vector<std::size_t>(kNumOps, 0));
    // Untimed warm-up (page faults of the first large allocations, the thread pool), so that the
    // reference row is not the one that pays for them.
    libs[0].build();
    libs[0].run(kOps[2], r);
    libs[0].release();
    for (int rep = 0; rep < reps; ++rep) {
        for (std::size_t l = 0; l < L; ++l) {
            Lib& lib = libs[l];
            if (lib.has_build) {
                auto t0 = Clock::now();
                lib.build();
                ms[l][0].push_back(ms_since(t0));
            }
            for (int o = 1; o < kNumOps; ++o) {
                auto t0 = Clock::now();
                found[l][o] = lib.run(kOps[o], r);
                ms[l][o].push_back(ms_since(t0));
            }
            // The nanoflann tree serves the next row (tree order) before it is released.
            if (l + 1 >= L || libs[l + 1].has_build) lib.release();
        }
    }

    std::printf("  radius r = %.6g; neighbours found (nbhd): kNN10 %zu, kNN30 %zu, radius %zu (%.1f a point), "
                "eps-k %zu\n",
                r, found[0][1], found[0][2], found[0][3], double(found[0][3]) / c.finite.size(), found[0][4]);
    std::printf("  %-30s", "ms (ratio to nbhd 1 thread)");
    for (int o = 0; o < kNumOps; ++o) std::printf(" %18s", kOps[o].name);
    std::printf("\n");
    std::vector<double> ref(kNumOps);
    for (int o = 0; o < kNumOps; ++o) ref[o] = median(ms[0][o]);
    bool ok = true;
    for (std::size_t l = 0; l < L; ++l) {
        std::printf("  %-30s", libs[l].name.c_str());
        for (int o = 0; o < kNumOps; ++o) {
            if (ms[l][o].empty()) {
                std::printf(" %18s", "-");
                continue;
            }
            double m = median(ms[l][o]);
            std::printf(" %10.1f (%5.2f)", m, m / ref[o]);
        }
        std::printf("\n");
        for (int o = 1; o < kNumOps; ++o) {
            bool knn = kOps[o].kind == 1;
            if (found[l][o] != found[0][o]) {
                // Inclusive vs strict radius: only the points exactly on it may differ.
                std::printf("    %s: %s found %zu neighbours, nbhd %zu%s\n", kOps[o].name, libs[l].name.c_str(),
                            found[l][o], found[0][o], knn ? " (MISMATCH)" : " (points exactly on the radius)");
                if (knn || found[l][o] > found[0][o]) ok = false;
            }
        }
    }
    return ok;
}

int usage() {
    std::fprintf(stderr, "usage: bench_neighbors [--reps N] [--generated N] [FILE...]\n");
    return 2;
}

}  // namespace

int main(int argc, char** argv) {
    int reps = 3;
    std::size_t generated = 1000000;
    std::vector<std::string> files;
    for (int a = 1; a < argc; ++a) {
        std::string arg = argv[a];
        if (arg == "--reps" && a + 1 < argc) {
            reps = std::atoi(argv[++a]);
            if (reps < 1) return usage();
        } else if (arg == "--generated" && a + 1 < argc) {
            generated = std::strtoul(argv[++a], nullptr, 10);
        } else if (!arg.empty() && arg[0] == '-') {
            return usage();
        } else {
            files.push_back(arg);
        }
    }
    std::setvbuf(stdout, nullptr, _IOLBF, 0);  // progress shows when redirected to a file
    std::printf("bench_neighbors: nbhd %s; nanoflann 0x%x; FLANN %s; PCL %s\n", nbhd_version_string(),
                NANOFLANN_VERSION, FLANN_VERSION_, PCL_VERSION_PRETTY);
    bool ok = true;
    try {
        for (const std::string& f : files) ok = bench_cloud(examples::load_cloud(f), reps) && ok;
        if (generated) {
            ok = bench_cloud(torus(generated), reps) && ok;
            ok = bench_cloud(cube(generated), reps) && ok;
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "bench_neighbors: %s\n", e.what());
        return 1;
    }
    return ok ? 0 : 1;
}
