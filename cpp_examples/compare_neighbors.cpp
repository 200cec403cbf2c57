// compare_neighbors: nbhd's neighbourhoods checked, query by query, against FLANN's exact
// KDTreeSingleIndex and PCL's KdTreeFLANN on the same points.
//
//   compare_neighbors FILE [--check knn|radius|knn-radius|all] [--stride N]
//
// FILE is a .pcd (loaded with pcl::io::loadPCDFile as pcl::PointXYZ) or a mesh such as .obj
// (loaded with OpenMesh::IO::read_mesh). nbhd and FLANN read the loader's point buffer in place
// (PointXYZ: stride 16; OpenMesh float points: stride 12); PCL's tree gets the pcl::PointCloud.
//
// Conventions and how they are bridged:
// - Every query is a stored point, and the point itself counts as its own neighbour (at distance
//   0) everywhere: FLANN and PCL include it, so nbhd is asked with exclude_self = false (tables)
//   or with the point's coordinates (single queries).
// - nbhd orders a result by (squared distance, index). FLANN and PCL order by distance only, so
//   their results are sorted by (squared distance, index) before comparing. Squared distances
//   must then be bitwise equal position by position, and indices equal position by position,
//   except in the last run of tied distances of a result cut at k: there the peer may keep any
//   of the tied points, nbhd keeps the smallest indices. That run is checked against the full
//   set of points at that distance (asked from nbhd with a larger k): the peer's indices must be
//   distinct members of it, nbhd's must be its smallest ones.
// - Radius: nbhd's radius is plain and inclusive, |x - q| <= r, evaluated as d2 <= r*r in float.
//   FLANN takes the squared radius and keeps d2 < r2 (strict); PCL takes the plain radius, and
//   passes float(r*r) (computed in double) to FLANN, so it is strict too. r is chosen as a float
//   whose square r2 = r*r is exactly a squared distance that occurs in the cloud, so that the
//   boundary is exercised; r2 is the same float for all three libraries (checked at run time).
//   The comparison is: nbhd's answer without its points at d2 == r2 exactly (they sort last)
//   equals FLANN's and PCL's answers. Those boundary points are counted and printed.
// - epsilon-k (the k nearest within r, k = 16; r chosen as above for about 12 neighbours, so
//   that both the k limit and the radius limit occur) is compared with PCL's radiusSearch with
//   max_nn = k (and FLANN's radiusSearch with max_neighbors = k), bridged the same way: nbhd's
//   answer without the points at d2 == r2 equals the peers'. If any were dropped, the rest is
//   every point with d2 < r2 and no tie run is cut.
// - Points with a NaN or infinite coordinate (the organized PCD files have NaN holes): nbhd is
//   built with the non-finite policy "skip" and reports original indices; PCL's KdTreeFLANN
//   drops them itself and maps its indices back; FLANN cannot take them, so it gets a compact
//   copy of the finite points and its indices are mapped back. Such points are not queried;
//   nbhd's tables must give them empty rows and index queries must fail with SKIPPED_POINT.
//
// Any mismatch prints the first differing query (both answers) and the program exits with 1
// after finishing the check at hand.
#include "cloud_io.hpp"
#include <nbhd.hpp>

#include <flann/flann.hpp>
#include <pcl/kdtree/kdtree_flann.h>

#include <algorithm>
#include <chrono>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <numeric>
#include <sstream>
#include <string>
#include <vector>

using examples::Cloud;
using nbhdpp::Result;

namespace {

constexpr std::size_t kEpsK = 16;

double seconds_since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

/// Sorts a peer's answer by (squared distance, index), the order nbhd promises.
void sort_by_dist_index(Result& r) {
    std::vector<std::size_t> order(r.size());
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
        return r.sq[a] < r.sq[b] || (r.sq[a] == r.sq[b] && r.idx[a] < r.idx[b]);
    });
    Result s;
    s.idx.reserve(r.size());
    s.sq.reserve(r.size());
    for (std::size_t j : order) {
        s.idx.push_back(r.idx[j]);
        s.sq.push_back(r.sq[j]);
    }
    r = std::move(s);
}

bool same_bits(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }

std::string show(const Result& r, std::size_t limit = 40) {
    std::ostringstream o;
    o.precision(9);
    o << r.size() << " neighbours:";
    for (std::size_t j = 0; j < r.size() && j < limit; ++j) o << " " << r.idx[j] << "@" << r.sq[j];
    if (r.size() > limit) o << " ...";
    return o.str();
}

/// Is `r` strictly increasing in (squared distance, index)? Returns the first offending position.
std::size_t first_unordered(const Result& r) {
    for (std::size_t j = 1; j < r.size(); ++j) {
        bool ok = r.sq[j - 1] < r.sq[j] || (r.sq[j - 1] == r.sq[j] && r.idx[j - 1] < r.idx[j]);
        if (!ok) return j;
    }
    return r.size();
}

/// Every point of the tree at squared distance exactly `d2` from `q`, by increasing index.
std::vector<std::uint32_t> points_at(const nbhd_tree* tree, const float* q, float d2, std::size_t n) {
    Result r;
    for (std::size_t k = 64;; k *= 2) {
        nbhdpp::knn(tree, q, std::min(k, n), r);
        if (r.size() < std::min(k, n) || r.sq.back() > d2 || k >= n) break;
    }
    std::vector<std::uint32_t> out;
    for (std::size_t j = 0; j < r.size(); ++j)
        if (same_bits(r.sq[j], d2)) out.push_back(r.idx[j]);
    return out;
}

/// Tally of one check against one peer.
struct Tally {
    std::string what;
    std::size_t queries = 0, neighbours = 0, cut_tie_runs = 0, boundary = 0, mismatches = 0;
    std::string first;
};

/// Compares nbhd's answer `ours` with a peer's `peer` (already sorted by (d2, index)) for the
/// query at stored index `qi`. `cut` says the answer was cut at k, so that the last tie run may
/// differ. Returns an empty string when they agree.
std::string compare(const nbhd_tree* tree, std::size_t n_points, const float* q, const Result& ours,
                    const Result& peer, bool cut, Tally& t) {
    std::size_t u = first_unordered(ours);
    if (u != ours.size())
        return "nbhd's answer is not ordered by (squared distance, index) at position " + std::to_string(u);
    u = first_unordered(peer);
    if (u != peer.size())
        return "the peer's answer repeats index " + std::to_string(peer.idx[u]);
    if (ours.size() != peer.size())
        return "sizes differ: nbhd " + std::to_string(ours.size()) + ", peer " + std::to_string(peer.size());
    for (std::size_t j = 0; j < ours.size(); ++j)
        if (!same_bits(ours.sq[j], peer.sq[j]))
            return "squared distances differ at position " + std::to_string(j);
    std::size_t n = ours.size(), j = 0;
    while (j < n && ours.idx[j] == peer.idx[j]) ++j;
    if (j == n) return "";
    if (!cut) return "indices differ at position " + std::to_string(j);
    std::size_t s = n - 1;
    while (s > 0 && ours.sq[s - 1] == ours.sq[n - 1]) --s;
    if (j < s) return "indices differ at position " + std::to_string(j) + ", before the last tie run";
    std::vector<std::uint32_t> tied = points_at(tree, q, ours.sq[n - 1], n_points);
    if (tied.size() < n - s) return "fewer points at the last distance than the answer holds";
    for (std::size_t m = s; m < n; ++m) {
        if (ours.idx[m] != tied[m - s])
            return "nbhd's last tie run does not hold the smallest indices of the tied points";
        if (!std::binary_search(tied.begin(), tied.end(), peer.idx[m]))
            return "the peer's index " + std::to_string(peer.idx[m]) + " is not at the last distance";
    }
    ++t.cut_tie_runs;
    return "";
}

void record(Tally& t, const Cloud& c, std::size_t qi, const std::string& why, const Result& ours,
            const Result& peer) {
    ++t.mismatches;
    if (!t.first.empty()) return;
    const float* p = c.point(qi);
    std::ostringstream o;
    o.precision(9);
    o << t.what << ": first differing query is point " << qi << " (" << p[0] << ", " << p[1] << ", "
      << p[2] << "): " << why << "\n    nbhd: " << show(ours) << "\n    peer: " << show(peer);
    t.first = o.str();
}

/// FLANN's exact single-tree index over the cloud: the loader's buffer in place when every point
/// is finite, else a compact copy of the finite points (FLANN cannot take NaN).
class Flann {
public:
    explicit Flann(const Cloud& c) {
        float* base = const_cast<float*>(c.xyz);  // FLANN's Matrix is not const-correct; only read
        flann::Matrix<float> data;
        if (!c.has_non_finite()) {
            data = flann::Matrix<float>(base, c.count, 3, c.stride);
        } else {
            compact_.reserve(3 * c.finite.size());
            for (std::uint32_t i : c.finite) compact_.insert(compact_.end(), c.point(i), c.point(i) + 3);
            map_ = c.finite;
            data = flann::Matrix<float>(compact_.data(), c.finite.size(), 3);
        }
        index_ = std::make_unique<Index>(data, flann::KDTreeSingleIndexParams(10));
        index_->buildIndex();
        params_.checks = flann::FLANN_CHECKS_UNLIMITED;
        params_.eps = 0;
        params_.sorted = true;
    }
    void knn(const float* q, std::size_t k, Result& out) {
        flann::Matrix<float> query(const_cast<float*>(q), 1, 3);
        idx_.resize(k);
        sq_.resize(k);
        flann::Matrix<std::size_t> mi(idx_.data(), 1, k);
        flann::Matrix<float> md(sq_.data(), 1, k);
        index_->knnSearch(query, mi, md, k, params_);
        out.idx.assign(k, 0);
        out.sq.assign(sq_.begin(), sq_.end());
        for (std::size_t j = 0; j < k; ++j) out.idx[j] = original(idx_[j]);
    }
    /// FLANN's radius search takes the squared radius and keeps d2 < r2.
    void radius(const float* q, float r2, int max_neighbors, Result& out) {
        flann::Matrix<float> query(const_cast<float*>(q), 1, 3);
        flann::SearchParams p = params_;
        p.max_neighbors = max_neighbors;
        index_->radiusSearch(query, vi_, vd_, r2, p);
        out.idx.clear();
        for (std::size_t i : vi_[0]) out.idx.push_back(original(i));
        out.sq = vd_[0];
    }

private:
    using Index = flann::KDTreeSingleIndex<flann::L2_Simple<float>>;
    std::uint32_t original(std::size_t i) const {
        return map_.empty() ? static_cast<std::uint32_t>(i) : map_[i];
    }
    std::vector<float> compact_;
    std::vector<std::uint32_t> map_;
    std::unique_ptr<Index> index_;
    flann::SearchParams params_;
    std::vector<std::size_t> idx_;
    std::vector<float> sq_;
    std::vector<std::vector<std::size_t>> vi_;
    std::vector<std::vector<float>> vd_;
};

/// PCL's KdTreeFLANN over the cloud (it drops non-finite points and reports cloud indices).
class Pcl {
public:
    explicit Pcl(const Cloud& c) : cloud_(c.pcl) { tree_.setInputCloud(cloud_); }
    void knn(std::size_t qi, std::size_t k, Result& out) {
        tree_.nearestKSearch((*cloud_)[qi], static_cast<int>(k), idx_, sq_);
        fill(out);
    }
    /// PCL's radius search takes the plain radius; max_nn = 0 means all.
    void radius(std::size_t qi, double r, unsigned max_nn, Result& out) {
        tree_.radiusSearch((*cloud_)[qi], r, idx_, sq_, max_nn);
        fill(out);
    }

private:
    void fill(Result& out) {
        out.idx.assign(idx_.begin(), idx_.end());
        out.sq.assign(sq_.begin(), sq_.end());
    }
    pcl::PointCloud<pcl::PointXYZ>::Ptr cloud_;
    pcl::KdTreeFLANN<pcl::PointXYZ> tree_;
    pcl::Indices idx_;
    std::vector<float> sq_;
};

struct Context {
    const Cloud& cloud;
    nbhd_build_options options;
    nbhdpp::Tree tree;  // default pivot policy (sliding midpoint)
    Flann flann;
    Pcl pcl;
    std::size_t stride;  // query every stride-th finite point (for the checks that allow it)
    int failures = 0;
};

bool report(Context& ctx, const Tally& t, double secs) {
    std::printf("  %-52s %8zu queries %11zu neighbours  %6zu cut tie runs  %6zu boundary  %5.1f s  %s\n",
                t.what.c_str(), t.queries, t.neighbours, t.cut_tie_runs, t.boundary, secs,
                t.mismatches ? "MISMATCH" : "ok");
    if (t.mismatches) {
        std::printf("    %zu mismatching queries; first:\n    %s\n", t.mismatches, t.first.c_str());
        ++ctx.failures;
    }
    return t.mismatches == 0;
}

/// Points of the cloud that are queried: every finite point, or every stride-th one.
std::vector<std::uint32_t> query_points(const Context& ctx, std::size_t stride) {
    std::vector<std::uint32_t> q;
    for (std::size_t j = 0; j < ctx.cloud.finite.size(); j += stride) q.push_back(ctx.cloud.finite[j]);
    return q;
}

/// Checks that a table gives empty rows to the skipped (non-finite) points and that index
/// queries on them fail with NBHD_STATUS_SKIPPED_POINT.
void check_skipped(Context& ctx, const nbhdpp::RowsF32& rows, const char* what) {
    Tally t;
    t.what = std::string(what) + ": skipped points";
    std::size_t f = 0;
    for (std::size_t i = 0; i < ctx.cloud.count; ++i) {
        if (f < ctx.cloud.finite.size() && ctx.cloud.finite[f] == i) {
            ++f;
            continue;
        }
        ++t.queries;
        Result empty, none;
        if (rows[i].len != 0) {
            none.idx.assign(rows[i].idx, rows[i].idx + rows[i].len);
            none.sq.assign(rows[i].sq, rows[i].sq + rows[i].len);
            record(t, ctx.cloud, i, "a skipped point has a non-empty row", none, empty);
            continue;
        }
        std::uint32_t idx[1];
        float sq[1];
        std::size_t count = 7;
        nbhd_status s = nbhd_tree_knn_index(ctx.tree.get(), i, false, 1, idx, sq, 1, &count);
        if (s != NBHD_STATUS_SKIPPED_POINT || count != 0)
            record(t, ctx.cloud, i,
                   std::string("nbhd_tree_knn_index on a skipped point gave ") + nbhd_status_string(s),
                   empty, empty);
    }
    report(ctx, t, 0);
}

void copy_row(const nbhdpp::Row& row, Result& out) {
    out.idx.assign(row.idx, row.idx + row.len);
    out.sq.assign(row.sq, row.sq + row.len);
}

bool equal(const Result& a, const Result& b) {
    if (a.size() != b.size()) return false;
    for (std::size_t j = 0; j < a.size(); ++j)
        if (a.idx[j] != b.idx[j] || !same_bits(a.sq[j], b.sq[j])) return false;
    return true;
}

// --- k nearest -----------------------------------------------------------------------------

void check_knn(Context& ctx) {
    const Cloud& c = ctx.cloud;
    const std::size_t n = c.finite.size();
    for (std::size_t k : {std::size_t{1}, std::size_t{10}, std::size_t{30}}) {
        auto t0 = std::chrono::steady_clock::now();
        // k = 10 is checked at every point and through the tables users call; k = 1 and 30
        // through single queries (at every stride-th point if --stride is given).
        const bool table = k == 10;
        std::vector<std::uint32_t> qs = query_points(ctx, table ? 1 : ctx.stride);
        Tally tf, tp, tt;
        tf.what = "kNN k=" + std::to_string(k) + (table ? " (nbhd table)" : " (nbhd_tree_knn)") + " vs FLANN";
        tp.what = "kNN k=" + std::to_string(k) + (table ? " (nbhd table)" : " (nbhd_tree_knn)") + " vs PCL";
        tt.what = "kNN k=10: 4 pivot policies' tables, nbhd_tree_knn(_index) agree";
        nbhdpp::Table tab;
        std::vector<nbhdpp::Table> others;
        if (table) {
            nbhd_neighborhood_spec spec{NBHD_NEIGHBORHOOD_KIND_KNN, k, 0.0};
            tab = nbhdpp::neighborhoods(ctx.tree.get(), spec, /*exclude_self=*/false);
            for (nbhd_pivot_policy p : nbhdpp::kAllPivots) {
                if (p == ctx.options.pivot) continue;
                nbhd_build_options o = ctx.options;
                o.pivot = p;
                nbhdpp::Tree t = nbhdpp::build(nbhdpp::points_f32(c.xyz, c.count, c.stride), o);
                others.push_back(nbhdpp::neighborhoods(t.get(), spec, false));
            }
        }
        Result ours, single, fl, pc;
        for (std::uint32_t qi : qs) {
            const float* q = c.point(qi);
            if (table) {
                copy_row(nbhdpp::RowsF32(tab.get())[qi], ours);
                ++tt.queries;
                for (const nbhdpp::Table& o : others) {
                    copy_row(nbhdpp::RowsF32(o.get())[qi], single);
                    if (!equal(ours, single))
                        record(tt, c, qi, "another pivot policy's table row differs", ours, single);
                }
                nbhdpp::knn(ctx.tree.get(), q, k, single);
                if (!equal(ours, single)) record(tt, c, qi, "nbhd_tree_knn differs from the table row", ours, single);
                nbhdpp::knn_index(ctx.tree.get(), qi, false, k, single);
                if (!equal(ours, single))
                    record(tt, c, qi, "nbhd_tree_knn_index differs from the table row", ours, single);
            } else {
                nbhdpp::knn(ctx.tree.get(), q, k, ours);
            }
            ctx.flann.knn(q, k, fl);
            ctx.pcl.knn(qi, k, pc);
            sort_by_dist_index(fl);
            sort_by_dist_index(pc);
            const bool cut = k < n;
            for (auto [peer, t] : {std::pair{&fl, &tf}, std::pair{&pc, &tp}}) {
                ++t->queries;
                t->neighbours += peer->size();
                std::string why = compare(ctx.tree.get(), c.count, q, ours, *peer, cut, *t);
                if (!why.empty()) record(*t, c, qi, why, ours, *peer);
            }
        }
        double secs = seconds_since(t0);
        report(ctx, tf, secs);
        report(ctx, tp, secs);
        if (table) {
            report(ctx, tt, secs);
            if (c.has_non_finite()) check_skipped(ctx, nbhdpp::RowsF32(tab.get()), "kNN table");
        }
    }
}

// --- radius ----------------------------------------------------------------------------------

/// A radius with about `target` neighbours on average (self included) whose square is exactly a
/// squared distance occurring in the cloud, so that the inclusive/strict boundary is exercised.
/// Deterministic: the median of the target-th neighbour's squared distance over a fixed sample
/// of points, moved to the nearest sampled value whose float square root squares back to it.
float choose_radius(const Context& ctx, std::size_t target, bool* exact) {
    const Cloud& c = ctx.cloud;
    std::size_t step = std::max<std::size_t>(1, c.finite.size() / 2000);
    std::vector<float> d2;
    Result r;
    for (std::size_t j = 0; j < c.finite.size(); j += step) {
        nbhdpp::knn(ctx.tree.get(), c.point(c.finite[j]), target, r);
        d2.push_back(r.sq.back());
    }
    std::sort(d2.begin(), d2.end());
    std::size_t mid = d2.size() / 2;
    for (std::size_t off = 0; off < d2.size(); ++off) {
        for (std::size_t j : {mid + off, mid - off}) {
            if (j >= d2.size() || d2[j] <= 0) continue;
            float rf = std::sqrt(d2[j]);
            for (float cand : {rf, std::nextafter(rf, 0.0f), std::nextafter(rf, 1e30f)}) {
                if (cand * cand == d2[j]) {
                    *exact = true;
                    return cand;
                }
            }
        }
    }
    *exact = false;
    return std::sqrt(d2[mid]);
}

/// Drops the points at squared distance exactly r2 (they sort last): what a strict peer keeps.
std::size_t drop_boundary(Result& r, float r2) {
    std::size_t dropped = 0;
    while (!r.sq.empty() && r.sq.back() == r2) {
        r.sq.pop_back();
        r.idx.pop_back();
        ++dropped;
    }
    for (float d : r.sq)
        if (d > r2) return static_cast<std::size_t>(-1);  // outside the radius: reported below
    return dropped;
}

void check_radius(Context& ctx, bool eps_k) {
    const Cloud& c = ctx.cloud;
    auto t0 = std::chrono::steady_clock::now();
    bool exact = false;
    // radius: about 20 neighbours. eps-k: about 12, so that rows are limited by k (16) or by r,
    // and so that the sampled pair at exactly r lies within the 16 nearest and the boundary
    // bridging of eps-k is exercised too.
    const float rf = choose_radius(ctx, eps_k ? 12 : 20, &exact);
    const double r = rf;
    const float r2 = rf * rf;  // nbhd: the radius converted to float, squared in float
    const float r2_pcl = static_cast<float>(r * r);  // what PCL hands to FLANN
    if (!same_bits(r2, r2_pcl)) {
        std::printf("  radius %.9g: float(r*r) in double is not r*r in float; cannot bridge\n", r);
        ++ctx.failures;
        return;
    }
    std::printf("  radius r = %.9g (r^2 = %.9g%s)\n", r, static_cast<double>(r2),
                exact ? ", a squared distance occurring in the cloud" : "; no sampled distance squares exactly");

    const std::size_t k = kEpsK;
    nbhd_neighborhood_spec spec = eps_k ? nbhd_neighborhood_spec{NBHD_NEIGHBORHOOD_KIND_KNN_RADIUS, k, r}
                                        : nbhd_neighborhood_spec{NBHD_NEIGHBORHOOD_KIND_RADIUS, 0, r};
    nbhdpp::Table tab = nbhdpp::neighborhoods(ctx.tree.get(), spec, /*exclude_self=*/false);
    nbhdpp::RowsF32 rows(tab.get());
    const std::string name = eps_k ? "eps-k k=16 (nbhd table)" : "radius (nbhd table)";
    Tally tf, tp, ts;
    tf.what = name + " vs FLANN";
    tp.what = name + " vs PCL" + (eps_k ? " max_nn=16" : "");
    ts.what = eps_k ? "eps-k: nbhd_tree_knn_radius agrees with table" : "radius: nbhd_tree_radius agrees with table";
    Result ours, single, fl, pc;
    std::size_t boundary_queries = 0;
    for (std::uint32_t qi : query_points(ctx, 1)) {
        const float* q = c.point(qi);
        copy_row(rows[qi], ours);
        ++ts.queries;
        if (eps_k)
            nbhdpp::knn_radius(ctx.tree.get(), q, k, r, single);
        else
            nbhdpp::radius(ctx.tree.get(), q, r, single);
        if (!equal(ours, single)) record(ts, c, qi, "single query differs from the table row", ours, single);
        std::size_t first_bad = first_unordered(ours);
        if (first_bad != ours.size()) {
            record(ts, c, qi, "nbhd's row is not ordered by (squared distance, index)", ours, single);
            continue;
        }
        Result bridged = ours;
        std::size_t dropped = drop_boundary(bridged, r2);
        if (dropped == static_cast<std::size_t>(-1)) {
            record(ts, c, qi, "nbhd's row holds a point outside the radius", ours, single);
            continue;
        }
        if (dropped) ++boundary_queries;
        ctx.flann.radius(q, r2, eps_k ? static_cast<int>(k) : -1, fl);
        ctx.pcl.radius(qi, r, eps_k ? static_cast<unsigned>(k) : 0u, pc);
        sort_by_dist_index(fl);
        sort_by_dist_index(pc);
        // Cut at k only for eps-k with k answers and nothing dropped at the boundary.
        const bool cut = eps_k && dropped == 0 && bridged.size() == k;
        for (auto [peer, t] : {std::pair{&fl, &tf}, std::pair{&pc, &tp}}) {
            ++t->queries;
            t->neighbours += peer->size();
            t->boundary += dropped;
            std::string why = compare(ctx.tree.get(), c.count, q, bridged, *peer, cut, *t);
            if (!why.empty()) record(*t, c, qi, why + " (nbhd's answer less its points at d2 == r2)", bridged, *peer);
        }
    }
    double secs = seconds_since(t0);
    report(ctx, tf, secs);
    report(ctx, tp, secs);
    report(ctx, ts, secs);
    std::printf("  %zu queries had points exactly on the radius (kept by nbhd, not by FLANN/PCL); "
                "average %.1f neighbours per query\n",
                boundary_queries, tf.queries ? double(nbhd_neighborhoods_total(tab.get())) / tf.queries : 0.0);
    if (exact && boundary_queries == 0) {
        std::printf("  radius chosen on a distance of the cloud, yet no point lies on it\n");
        ++ctx.failures;
    }
    if (c.has_non_finite()) check_skipped(ctx, rows, eps_k ? "eps-k table" : "radius table");
}

int usage() {
    std::fprintf(stderr, "usage: compare_neighbors FILE [--check knn|radius|knn-radius|all] [--stride N]\n");
    return 2;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 2) return usage();
    std::string path = argv[1], which = "all";
    std::size_t stride = 1;
    for (int a = 2; a < argc; ++a) {
        std::string arg = argv[a];
        if (arg == "--check" && a + 1 < argc) {
            which = argv[++a];
        } else if (arg == "--stride" && a + 1 < argc) {
            stride = std::strtoul(argv[++a], nullptr, 10);
            if (stride == 0) return usage();
        } else {
            return usage();
        }
    }
    if (which != "all" && which != "knn" && which != "radius" && which != "knn-radius") return usage();
    if (nbhd_version() != NBHD_VERSION) {
        std::fprintf(stderr, "nbhd.h is version %d but the library is %s\n", NBHD_VERSION, nbhd_version_string());
        return 1;
    }
    try {
        auto t0 = std::chrono::steady_clock::now();
        Cloud cloud = examples::load_cloud(path);
        std::printf("%s: %zu points (%zu finite) from %s, stride %zu bytes, read in place by nbhd and FLANN\n",
                    cloud.name.c_str(), cloud.count, cloud.finite.size(), cloud.loader.c_str(), cloud.stride);
        nbhd_build_options options = nbhd_build_options_default();
        if (cloud.has_non_finite()) options.non_finite = NBHD_NON_FINITE_POLICY_SKIP;
        nbhdpp::Tree tree = nbhdpp::build(nbhdpp::points_f32(cloud.xyz, cloud.count, cloud.stride), options);
        nbhd_stats st = nbhdpp::stats(tree.get());
        if (st.points != cloud.finite.size() || st.source_points != cloud.count) {
            std::printf("nbhd_tree_stats: %zu points of %zu, expected %zu of %zu\n", st.points, st.source_points,
                        cloud.finite.size(), cloud.count);
            return 1;
        }
        Context ctx{cloud, options, std::move(tree), Flann(cloud), Pcl(cloud), stride};
        std::printf("  nbhd %s (%s pivots, leaf %zu, non-finite: %s), FLANN KDTreeSingleIndex leaf 10, "
                    "PCL KdTreeFLANN: built in %.2f s; self included in every answer\n",
                    nbhd_version_string(), nbhdpp::pivot_name(options.pivot), options.leaf_size,
                    cloud.has_non_finite() ? "skip" : "reject", seconds_since(t0));
        if (which == "all" || which == "knn") check_knn(ctx);
        if (which == "all" || which == "radius") check_radius(ctx, false);
        if (which == "all" || which == "knn-radius") check_radius(ctx, true);
        std::printf("%s: %s (%.1f s)\n", cloud.name.c_str(),
                    ctx.failures ? "MISMATCHES FOUND" : "all checks agree", seconds_since(t0));
        return ctx.failures ? 1 : 0;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "compare_neighbors: %s\n", e.what());
        return 1;
    }
}
