// nbhd_pcl.hpp: nbhd as a pcl::search::Search backend, so that PCL's own algorithms
// (NormalEstimation(OMP), MovingLeastSquares, EuclideanClusterExtraction, RegionGrowing,
// FPFHEstimation(OMP), ... every class with setSearchMethod) search with nbhd's k-d tree:
//
//   #include <nbhd_pcl.hpp>
//   ne.setSearchMethod(std::make_shared<nbhd::PclSearch<pcl::PointXYZ>>());   // was KdTree
//
// Header-only, over nbhd's C API (nbhd.h) and PCL's headers; installed next to nbhd.h by
// scripts/install.sh (found as <nbhd_pcl.hpp> through the CMake package or pkg-config; the
// program links PCL itself). Nothing PCL-specific is in the library.
//
// It behaves as pcl::search::KdTree (PCL 1.13, KdTreeFLANN), so that switching changes the time
// and nothing else:
//
//   - PointT: any PCL point type with float x, y, z (pcl::PointXYZ, PointXYZI, PointXYZRGB(A),
//     PointNormal, PointXYZRGBNormal, ...). The cloud is read in place (stride sizeof(PointT));
//     the tree holds its own compact copy, as KdTreeFLANN does.
//   - setInputCloud(cloud) or setInputCloud(cloud, indices): points with a non-finite x, y or z
//     are left out (as KdTreeFLANN's DefaultPointRepresentation::isValid does); with indices,
//     only the listed points are searched (nbhd_tree_build_indices). Results are always indices
//     of the cloud, as PCL returns them. nearestKSearch(index, ...) / radiusSearch(index, ...)
//     take a position in `indices` when indices were given (as pcl::search::Search does), the
//     overloads with a cloud take a cloud index.
//   - k nearest: k is capped at the number of points searched; k <= 0 gives 0 results.
//   - Radius: PCL's convention, a plain radius r compared strictly, squared distance <
//     float(r * r) as KdTreeFLANN passes it to FLANN. nbhd's own radius is inclusive (d <= r);
//     the bridge asks nbhd for the smallest float radius whose float square is >= float(r * r)
//     and drops the tail of the (sorted) answer at squared distance >= float(r * r): exactly
//     FLANN's set. max_nn > 0 keeps the max_nn nearest within r (nbhd's k nearest within a
//     radius), as FLANN's max_neighbors does.
//   - Order: results come sorted by (squared distance, index) whether or not
//     setSortedResults(false) was called (unsorted answers are allowed any order). Where FLANN
//     keeps a different one of several points tied at the k-th distance, nbhd keeps the
//     smallest index.
//   - Squared distances: float, summed x, y, z in order, as FLANN's L2_Simple.
//   - A query point with a non-finite coordinate (PCL asserts) gives 0 results and empty
//     vectors; so does an index out of range of the cloud (or of the indices) as it is now.
//   - Queries read the query point where it is at call time, as PCL's do (pcl::search::Search
//     reads (*input_)[index]): the points searched are those of the last setInputCloud, the
//     point asked about is the cloud's current one. A point appended to the input cloud since
//     setInputCloud, or moved in place, is searched around its current coordinates among the
//     points the tree holds, exactly as pcl::search::KdTree answers it.
//   - Index queries take nbhd's index path (nbhd_tree_knn_index, ...) while the point is still
//     where the tree holds it (nbhd_tree_point compares its coordinates): the tree answers
//     around its own copy. So do queries by a point that is one of the input cloud's (its
//     address lies in the cloud's storage, as when EuclideanClusterExtraction passes
//     cloud[i]). A run of index
//     queries with the same k (or radius, max_nn) — what PCL's algorithms do, one per point —
//     is served, once the run is long (max(1024, points / 32) queries), from one table of
//     every point's answer computed at once on all cores (nbhd_tree_neighborhoods;
//     setTableThreads(n) for n threads): the same
//     rows, in less time than the single queries for k nearest and for radius answers of up to
//     64 points on average (measured, cpp_examples/README.md; larger radius answers stay single
//     queries). Tables are kept until the next setInputCloud (at most 4, each at most 2^25
//     neighbours; larger ones are not made). setTableRuns(false) turns this off.
//   - Threads: const queries share no buffer (only a relaxed atomic size hint for radius
//     answers), so any number of threads may query at once (NormalEstimationOMP,
//     FPFHEstimationOMP). setInputCloud must not run concurrently with queries, as for every
//     PCL search.
//
// Indices given to setInputCloud may repeat a point: as KdTreeFLANN, which copies every listed
// point, the point is then searched as that many points (a radius answer holds its index that
// many times, adjacent; k nearest count each copy). The tree holds it once and the answers are
// expanded. An index outside the cloud (KdTreeFLANN reads out of bounds) makes setInputCloud
// throw with nbhd's message naming the index.
// Errors of nbhd that PCL's interface cannot carry (out of memory while building, ...) throw
// std::runtime_error with nbhd's message; PCL's KdTree prints an error and searches nothing
// for an empty cloud, which this class does too (every query then gives 0 results).
#pragma once

#include <nbhd.h>

#include <pcl/point_cloud.h>
#include <pcl/search/search.h>
#include <pcl/type_traits.h>

#include <atomic>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

namespace nbhd {

namespace pcl_detail {

struct TreeFree {
    void operator()(nbhd_tree* t) const { nbhd_tree_free(t); }
};

/// The radius nbhd is asked for so that its inclusive answer holds every point FLANN keeps
/// (squared distance < `limit` = float(r * r)): the smallest float whose float square is >=
/// `limit`. Returns a negative value when PCL's search finds nothing (limit 0, NaN).
inline double inclusive_radius_for(float limit) {
    if (!(limit > 0.0f) || !std::isfinite(limit)) return -1.0;
    float r = std::sqrt(limit);
    while (r * r < limit) r = std::nextafter(r, INFINITY);
    while (r > 0.0f) {
        float smaller = std::nextafter(r, 0.0f);
        if (smaller * smaller < limit) break;
        r = smaller;
    }
    return static_cast<double>(r);
}

}  // namespace pcl_detail

/// pcl::search::KdTree's behaviour on nbhd's k-d tree (see the top of this file).
template <typename PointT>
class PclSearch : public pcl::search::Search<PointT> {
    static_assert(pcl::traits::has_xyz<PointT>::value, "nbhd::PclSearch needs x, y and z");
    static_assert(sizeof(pcl::index_t) == sizeof(std::uint32_t),
                  "nbhd::PclSearch needs PCL's 32-bit pcl::index_t");

public:
    using Base = pcl::search::Search<PointT>;
    using PointCloud = typename Base::PointCloud;
    using PointCloudConstPtr = typename Base::PointCloudConstPtr;
    using IndicesConstPtr = typename Base::IndicesConstPtr;
    using Ptr = std::shared_ptr<PclSearch<PointT>>;
    using ConstPtr = std::shared_ptr<const PclSearch<PointT>>;
    using Base::getIndices;
    using Base::getInputCloud;

    /// `sorted` as pcl::search::KdTree's (default true; results are sorted either way).
    explicit PclSearch(bool sorted = true) : Base("nbhd::PclSearch", sorted) {}

    /// Builds nbhd's tree over the finite points of `cloud` (or of `cloud[indices]`).
    void setInputCloud(const PointCloudConstPtr& cloud,
                       const IndicesConstPtr& indices = IndicesConstPtr()) override {
        table_.store(nullptr, std::memory_order_release);
        tables_.clear();
        refused_key_.store(0, std::memory_order_relaxed);
        run_key_.store(0, std::memory_order_relaxed);
        run_len_.store(0, std::memory_order_relaxed);
        tree_.reset();
        searched_ = 0;
        distinct_ = 0;
        source_points_ = 0;
        copies_.clear();
        input_ = cloud;
        indices_ = indices;
        if (!cloud || cloud->empty() || (indices && indices->empty())) return;
        nbhd_points pts = points_of(*cloud);
        nbhd_build_options opt = nbhd_build_options_default();
        opt.non_finite = NBHD_NON_FINITE_POLICY_SKIP;
        nbhd_tree* t = nullptr;
        nbhd_status s;
        if (indices) {
            // A point listed more than once is searched as that many points, as KdTreeFLANN
            // does (it copies each listed point): the tree holds it once and copies_ says how
            // many times each result is repeated.
            const pcl::Indices distinct = distinct_listed(*cloud, *indices);
            const pcl::Indices& list = distinct.empty() ? *indices : distinct;
            s = nbhd_tree_build_indices(&pts, reinterpret_cast<const std::uint32_t*>(list.data()),
                                        list.size(), &opt, &t);
        } else {
            s = nbhd_tree_build(&pts, &opt, &t);
        }
        if (s != NBHD_STATUS_OK)
            throw std::runtime_error(std::string("nbhd::PclSearch::setInputCloud: ") +
                                     nbhd_last_error_message());
        tree_.reset(t);
        nbhd_stats st{};
        nbhd_tree_stats(t, &st);
        if (st.points == 0) {  // no finite point: every query finds nothing
            tree_.reset();
            return;
        }
        distinct_ = st.points;
        searched_ = st.points;
        source_points_ = st.source_points;
        if (!copies_.empty())  // the extra copies of listed finite points count as points
            for (std::size_t c = 0; c < copies_.size(); ++c)
                if (copies_[c] > 1 && finite((*cloud)[c])) searched_ += copies_[c] - 1;
    }

    // ---- by point ------------------------------------------------------------------------

    int nearestKSearch(const PointT& point, int k, pcl::Indices& k_indices,
                       std::vector<float>& k_sqr_distances) const override {
        const std::ptrdiff_t c = own_index(point);
        if (c >= 0) return knn(at(*input_, static_cast<pcl::index_t>(c)), k, k_indices, k_sqr_distances);
        const float q[3] = {point.x, point.y, point.z};
        return knn(At{q, 0, false}, k, k_indices, k_sqr_distances);
    }

    int radiusSearch(const PointT& point, double radius, pcl::Indices& k_indices,
                     std::vector<float>& k_sqr_distances, unsigned int max_nn = 0) const override {
        const std::ptrdiff_t c = own_index(point);
        if (c >= 0)
            return within(at(*input_, static_cast<pcl::index_t>(c)), radius, k_indices,
                          k_sqr_distances, max_nn);
        const float q[3] = {point.x, point.y, point.z};
        return within(At{q, 0, false}, radius, k_indices, k_sqr_distances, max_nn);
    }

    // ---- by index (what PCL's algorithms call) -------------------------------------------

    /// Around `cloud[index]`: through nbhd's index path when `cloud` is the input cloud.
    int nearestKSearch(const PointCloud& cloud, pcl::index_t index, int k,
                       pcl::Indices& k_indices, std::vector<float>& k_sqr_distances) const override {
        return knn(at(cloud, index), k, k_indices, k_sqr_distances);
    }

    /// Around input point `index` (a position in the indices given to setInputCloud, if any).
    int nearestKSearch(pcl::index_t index, int k, pcl::Indices& k_indices,
                       std::vector<float>& k_sqr_distances) const override {
        return knn(at_own(index), k, k_indices, k_sqr_distances);
    }

    int radiusSearch(const PointCloud& cloud, pcl::index_t index, double radius,
                     pcl::Indices& k_indices, std::vector<float>& k_sqr_distances,
                     unsigned int max_nn = 0) const override {
        return within(at(cloud, index), radius, k_indices, k_sqr_distances, max_nn);
    }

    int radiusSearch(pcl::index_t index, double radius, pcl::Indices& k_indices,
                     std::vector<float>& k_sqr_distances, unsigned int max_nn = 0) const override {
        return within(at_own(index), radius, k_indices, k_sqr_distances, max_nn);
    }

    // ---- batches ---------------------------------------------------------------------------

    /// Around `cloud[indices[i]]` for every i (every point of `cloud` if `indices` is empty).
    void nearestKSearch(const PointCloud& cloud, const pcl::Indices& indices, int k,
                        std::vector<pcl::Indices>& k_indices,
                        std::vector<std::vector<float>>& k_sqr_distances) const override {
        const std::size_t n = indices.empty() ? cloud.size() : indices.size();
        k_indices.resize(n);
        k_sqr_distances.resize(n);
        for (std::size_t i = 0; i < n; ++i) {
            const pcl::index_t c = indices.empty() ? static_cast<pcl::index_t>(i) : indices[i];
            knn(at(cloud, c), k, k_indices[i], k_sqr_distances[i]);
        }
    }

    void radiusSearch(const PointCloud& cloud, const pcl::Indices& indices, double radius,
                      std::vector<pcl::Indices>& k_indices,
                      std::vector<std::vector<float>>& k_sqr_distances,
                      unsigned int max_nn = 0) const override {
        const std::size_t n = indices.empty() ? cloud.size() : indices.size();
        k_indices.resize(n);
        k_sqr_distances.resize(n);
        for (std::size_t i = 0; i < n; ++i) {
            const pcl::index_t c = indices.empty() ? static_cast<pcl::index_t>(i) : indices[i];
            within(at(cloud, c), radius, k_indices[i], k_sqr_distances[i], max_nn);
        }
    }

    /// Whether runs of same-k / same-radius index queries are served from one all-point table
    /// (default true; see the top of this file). Not to be changed while queries run.
    void setTableRuns(bool on) { table_runs_ = on; }

    /// Threads that compute a table (default 0: all cores, whatever the calling algorithm
    /// uses; 1 keeps the search on the caller's thread, as pcl::search::KdTree is). Not to be
    /// changed while queries run.
    void setTableThreads(std::size_t threads) { table_threads_ = threads; }

    /// nbhd's tree (NULL before setInputCloud or for a cloud without finite points).
    const nbhd_tree* tree() const { return tree_.get(); }

protected:
    using Base::indices_;
    using Base::input_;

private:
    /// Where a query is: coordinates (`q`), or a stored point of the tree by cloud index.
    struct At {
        const float* q;          // NULL: by index
        std::size_t index;       // cloud index, when q is NULL
        bool invalid;            // out of range or non-finite: 0 results
    };

    static nbhd_points points_of(const PointCloud& cloud) {
        // x, y, z are consecutive floats in every PCL point type that has them.
        const char* base = reinterpret_cast<const char*>(cloud.points.data());
        const std::size_t x_at =
            static_cast<std::size_t>(reinterpret_cast<const char*>(&cloud.points[0].x) - base);
        return nbhd_points{base + x_at, cloud.size(), 3, sizeof(PointT), NBHD_SCALAR_TYPE_F32};
    }

    /// `p`'s index in the input cloud when `p` is one of its points (PCL's algorithms pass
    /// `cloud[i]` to the by-point overloads: EuclideanClusterExtraction does), else -1: such a
    /// query takes the index path (and the table of its run) instead of a search by coordinates.
    std::ptrdiff_t own_index(const PointT& p) const {
        if (!input_ || input_->empty()) return -1;
        const auto a = reinterpret_cast<std::uintptr_t>(&p);
        const auto b = reinterpret_cast<std::uintptr_t>(input_->points.data());
        if (a < b || a - b >= input_->size() * sizeof(PointT) || (a - b) % sizeof(PointT) != 0)
            return -1;
        return static_cast<std::ptrdiff_t>((a - b) / sizeof(PointT));
    }

    /// Empty when `indices` lists no point twice; otherwise each listed index once (first
    /// occurrences, in order), with copies_[c] = the times cloud index c is listed.
    pcl::Indices distinct_listed(const PointCloud& cloud, const pcl::Indices& indices) {
        std::vector<std::uint32_t> times(cloud.size(), 0);
        bool repeated = false;
        for (pcl::index_t c : indices) {
            if (c < 0 || static_cast<std::size_t>(c) >= cloud.size()) continue;  // nbhd refuses it
            repeated |= times[static_cast<std::size_t>(c)]++ > 0;
        }
        if (!repeated) return pcl::Indices();
        pcl::Indices distinct;
        std::vector<bool> taken(cloud.size(), false);
        for (pcl::index_t c : indices) {
            if (c >= 0 && static_cast<std::size_t>(c) < cloud.size()) {
                if (taken[static_cast<std::size_t>(c)]) continue;
                taken[static_cast<std::size_t>(c)] = true;
            }
            distinct.push_back(c);
        }
        copies_ = std::move(times);
        return distinct;
    }

    /// Each result repeated as many times as its point was listed (copies_), then cut at
    /// `most` (the k or max_nn asked; 0: no cut). The order stays (squared distance, index).
    void repeat_copies(pcl::Indices& idx, std::vector<float>& dist, std::size_t most) const {
        if (copies_.empty()) return;
        std::size_t n = 0;
        for (pcl::index_t c : idx) n += copies_[static_cast<std::size_t>(c)];
        if (most > 0 && n > most) n = most;
        pcl::Indices i2;
        std::vector<float> d2;
        i2.reserve(n);
        d2.reserve(n);
        for (std::size_t j = 0; j < idx.size() && i2.size() < n; ++j)
            for (std::uint32_t t = 0; t < copies_[static_cast<std::size_t>(idx[j])] && i2.size() < n; ++t) {
                i2.push_back(idx[j]);
                d2.push_back(dist[j]);
            }
        idx.swap(i2);
        dist.swap(d2);
    }

    /// pcl_detail::inclusive_radius_for(limit), remembered for the last limit (a run of queries
    /// asks the same radius): one relaxed atomic holding both floats' bits.
    double inclusive_radius(float limit) const {
        std::uint32_t lb;
        std::memcpy(&lb, &limit, sizeof lb);
        const std::uint64_t memo = radius_memo_.load(std::memory_order_relaxed);
        if (static_cast<std::uint32_t>(memo >> 32) == lb && memo != 0) {
            float r;
            const auto rb = static_cast<std::uint32_t>(memo);
            std::memcpy(&r, &rb, sizeof r);
            return static_cast<double>(r);
        }
        const double r = pcl_detail::inclusive_radius_for(limit);
        if (r > 0.0) {
            const float rf = static_cast<float>(r);  // exact: r is a float
            std::uint32_t rb;
            std::memcpy(&rb, &rf, sizeof rb);
            radius_memo_.store((static_cast<std::uint64_t>(lb) << 32) | rb,
                               std::memory_order_relaxed);
        }
        return r;
    }

    static bool finite(const PointT& p) {
        return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
    }

    /// `cloud[index]` as it is now (an index out of the cloud's current range: invalid):
    /// through the tree's index path if it is a point of the input cloud that the tree holds
    /// at these coordinates, else by its coordinates (a point appended or moved since
    /// setInputCloud, skipped, or not listed), as PCL reads the query at call time.
    At at(const PointCloud& cloud, pcl::index_t index) const {
        if (index < 0 || static_cast<std::size_t>(index) >= cloud.size()) return At{nullptr, 0, true};
        const std::size_t i = static_cast<std::size_t>(index);
        const PointT& p = cloud[i];
        if (!finite(p)) return At{nullptr, 0, true};
        if (&cloud == input_.get() && held_as_is(i, p)) return At{nullptr, i, false};
        return At{&p.x, 0, false};
    }

    /// Whether the tree holds cloud point `i` at `p`'s current coordinates (bitwise equal
    /// values; the tree's copy was made by setInputCloud). False for an index past the points
    /// the tree was built over, and for a point it does not hold.
    bool held_as_is(std::size_t i, const PointT& p) const {
        if (!tree_ || i >= source_points_) return false;
        float xyz[3];
        if (nbhd_tree_point(tree_.get(), i, xyz) != NBHD_STATUS_OK) return false;
        return xyz[0] == p.x && xyz[1] == p.y && xyz[2] == p.z;
    }

    At at_own(pcl::index_t index) const {
        if (!input_) return At{nullptr, 0, true};
        if (indices_) {
            if (index < 0 || static_cast<std::size_t>(index) >= indices_->size())
                return At{nullptr, 0, true};
            return at(*input_, (*indices_)[static_cast<std::size_t>(index)]);
        }
        return at(*input_, index);
    }

    /// One nbhd query into `idx` / `dist`, grown once if nbhd asks for more room. `call(i, d,
    /// cap, &count)` is the nbhd function. Returns the status of the last call.
    template <class Call>
    static nbhd_status into(pcl::Indices& idx, std::vector<float>& dist, std::size_t want,
                            Call&& call) {
        if (idx.size() < want) idx.resize(want);
        if (dist.size() < want) dist.resize(want);
        std::size_t cap = idx.size() < dist.size() ? idx.size() : dist.size(), count = 0;
        nbhd_status s = call(reinterpret_cast<std::uint32_t*>(idx.data()), dist.data(), cap, &count);
        if (s == NBHD_STATUS_BUFFER_TOO_SMALL) {
            idx.resize(count);
            dist.resize(count);
            s = call(reinterpret_cast<std::uint32_t*>(idx.data()), dist.data(), count, &count);
        }
        if (s != NBHD_STATUS_OK) count = 0;
        idx.resize(count);
        dist.resize(count);
        return s;
    }

    int knn(At a, int k, pcl::Indices& idx, std::vector<float>& dist) const {
        const int n = knn_distinct(a, k, idx, dist);
        if (copies_.empty() || n == 0) return n;
        const std::size_t kk = static_cast<std::size_t>(k);
        repeat_copies(idx, dist, kk < searched_ ? kk : searched_);
        return static_cast<int>(idx.size());
    }

    /// k nearest among the points the tree holds (each listed point once).
    int knn_distinct(At a, int k, pcl::Indices& idx, std::vector<float>& dist) const {
        if (a.invalid || k <= 0 || !tree_) {
            idx.clear();
            dist.clear();
            return 0;
        }
        std::size_t kk = static_cast<std::size_t>(k) < distinct_ ? static_cast<std::size_t>(k)
                                                                  : distinct_;
        const nbhd_tree* t = tree_.get();
        // On an error `into` leaves the vectors empty: 0 results.
        if (a.q) {
            into(idx, dist, kk, [&](std::uint32_t* i, float* d, std::size_t c, std::size_t* n) {
                return nbhd_tree_knn(t, a.q, kk, i, d, c, n);
            });
        } else if (!from_table(make_key(NBHD_NEIGHBORHOOD_KIND_KNN, kk, 0.0f), kk, 0.0, a.index,
                               idx, dist)) {
            into(idx, dist, kk, [&](std::uint32_t* i, float* d, std::size_t c, std::size_t* n) {
                return nbhd_tree_knn_index(t, a.index, false, kk, i, d, c, n);
            });
        }
        return static_cast<int>(idx.size());
    }

    int within(At a, double radius, pcl::Indices& idx, std::vector<float>& dist,
               unsigned int max_nn) const {
        const int n = within_distinct(a, radius, idx, dist, max_nn);
        if (copies_.empty() || n == 0) return n;
        repeat_copies(idx, dist, max_nn > 0 && max_nn < searched_ ? max_nn : 0);
        return static_cast<int>(idx.size());
    }

    /// Within `radius` among the points the tree holds (each listed point once).
    int within_distinct(At a, double radius, pcl::Indices& idx, std::vector<float>& dist,
                        unsigned int max_nn) const {
        const float limit = static_cast<float>(radius * radius);  // as KdTreeFLANN
        const double r = inclusive_radius(limit);
        if (a.invalid || !tree_ || r < 0.0) {
            idx.clear();
            dist.clear();
            return 0;
        }
        const nbhd_tree* t = tree_.get();
        const bool capped = max_nn > 0 && max_nn < distinct_;
        const std::size_t k = max_nn;
        // Room for the answer, so that nbhd searches once: PCL's algorithms often pass fresh
        // vectors, so the hint (1.5 × the last answer's size, shared by all threads as a
        // relaxed atomic: a size, not a buffer) is the usual guess.
        std::size_t guess = capped ? k : size_hint_.load(std::memory_order_relaxed);
        if (!capped && idx.capacity() > guess) guess = idx.capacity();
        if (a.q) {
            into(idx, dist, guess, [&](std::uint32_t* i, float* d, std::size_t c, std::size_t* n) {
                return capped ? nbhd_tree_knn_radius(t, a.q, k, r, i, d, c, n)
                              : nbhd_tree_radius(t, a.q, r, i, d, c, n);
            });
        } else if (!from_table(make_key(capped ? NBHD_NEIGHBORHOOD_KIND_KNN_RADIUS
                                                  : NBHD_NEIGHBORHOOD_KIND_RADIUS,
                                           capped ? k : 0, limit),
                               capped ? k : 0, r, a.index, idx, dist)) {
            into(idx, dist, guess, [&](std::uint32_t* i, float* d, std::size_t c, std::size_t* n) {
                return capped ? nbhd_tree_knn_radius_index(t, a.index, false, k, r, i, d, c, n)
                              : nbhd_tree_radius_index(t, a.index, false, r, i, d, c, n);
            });
        }
        if (!capped) {  // written only when it moves by half or more (no cache-line ping-pong)
            const std::size_t want = dist.size() + dist.size() / 2 + 16;
            const std::size_t hint = size_hint_.load(std::memory_order_relaxed);
            if (want > hint || 2 * want < hint) size_hint_.store(want, std::memory_order_relaxed);
        }
        // FLANN's strict `<`: drop the sorted tail at squared distance >= float(r * r).
        std::size_t n = dist.size();
        while (n > 0 && !(dist[n - 1] < limit)) --n;
        idx.resize(n);
        dist.resize(n);
        return static_cast<int>(n);
    }

    // ---- runs of index queries served from one all-point table ------------------------------

    static constexpr std::size_t kMaxRadiusRow = 64;  // radius tables only up to this mean row
    using Key = std::uint64_t;  // kind (2 bits), k (30 bits), float bits of r*r (32 bits)
    static Key make_key(nbhd_neighborhood_kind kind, std::size_t k, float limit) {
        std::uint32_t bits;
        std::memcpy(&bits, &limit, sizeof bits);
        return (static_cast<Key>(kind) << 62) | (static_cast<Key>(k & 0x3FFFFFFF) << 32) | bits;
    }

    struct RowTable {
        Key key = 0;
        nbhd_neighborhoods* table = nullptr;
        std::size_t rows = 0;                // rows of the table (off has rows + 1 entries)
        const std::size_t* off = nullptr;
        const std::uint32_t* idx = nullptr;
        const float* dist = nullptr;
        ~RowTable() { nbhd_neighborhoods_free(table); }
    };

    /// Copies row `index` of the table of `key` into `idx` / `dist` if that table exists (and
    /// the row is not empty: an empty row is a point the tree does not hold); counts the run
    /// and makes the table when the run is long enough.
    bool from_table(Key key, std::size_t k, double r, std::size_t index, pcl::Indices& idx,
                    std::vector<float>& dist) const {
        // A key holds 30 bits of k: a larger k (over a billion points) is never a table's.
        if (!table_runs_ || k > 0x3FFFFFFF) return false;
        const RowTable* t = table_.load(std::memory_order_acquire);
        if (!t || t->key != key) {
            if (refused_key_.load(std::memory_order_relaxed) == key) return false;
            if (run_key_.load(std::memory_order_relaxed) != key) {
                run_key_.store(key, std::memory_order_relaxed);
                run_len_.store(1, std::memory_order_relaxed);
                return false;
            }
            const std::size_t threshold = distinct_ / 32 > 1024 ? distinct_ / 32 : 1024;
            if (run_len_.fetch_add(1, std::memory_order_relaxed) + 1 < threshold) return false;
            // Past the threshold every thread asks for the table: the first builds it (on all
            // cores), the others of a parallel algorithm wait on the lock instead of answering
            // single queries beside it (measured: that doubled work and crowded the cores).
            t = make_table(key, k, r);
            if (!t) {
                refused_key_.store(key, std::memory_order_relaxed);
                return false;
            }
        }
        if (index >= t->rows) return false;  // not a row of the table: a single query
        const std::size_t a = t->off[index], b = t->off[index + 1];
        if (a == b) return false;
        idx.resize(b - a);
        dist.resize(b - a);
        std::memcpy(idx.data(), t->idx + a, (b - a) * sizeof(std::uint32_t));
        std::memcpy(dist.data(), t->dist + a, (b - a) * sizeof(float));
        return true;
    }

    /// The table of `key` on all cores, or NULL if it would be too large or too many exist.
    const RowTable* make_table(Key key, std::size_t k, double r) const {
        std::lock_guard<std::mutex> lock(table_mutex_);
        const RowTable* cur = table_.load(std::memory_order_acquire);
        if (cur && cur->key == key) return cur;
        if (tables_.size() >= 4) return nullptr;
        const nbhd_neighborhood_kind kind = static_cast<nbhd_neighborhood_kind>(key >> 62);
        std::size_t per_point = k;
        if (kind == NBHD_NEIGHBORHOOD_KIND_RADIUS) {
            // The mean answer size, from 64 points spread over the tree's index range.
            nbhd_stats st{};
            nbhd_tree_stats(tree_.get(), &st);
            std::vector<std::uint32_t> i(1024);
            std::vector<float> d(1024);
            std::size_t total = 0, asked = 0;
            for (std::size_t j = 0; j < 64; ++j) {
                std::size_t n = 0;
                const std::size_t at = j * st.source_points / 64;
                if (nbhd_tree_radius_index(tree_.get(), at, false, r, i.data(), d.data(), i.size(),
                                           &n) == NBHD_STATUS_SKIPPED_POINT)
                    continue;
                total += n;
                ++asked;
            }
            per_point = asked ? total / asked : 0;
            // Measured (cpp_examples/README.md): with rows of about 72 points (MLS r = 5h, one
            // query per point) the single queries were faster than table + copy on one core;
            // with about 50 (FPFH r = 4h) and below, the table was.
            if (per_point > kMaxRadiusRow) return nullptr;
        }
        if (per_point > (std::size_t(1) << 25) / (distinct_ + 1)) return nullptr;
        nbhd_neighborhood_spec spec = {kind, k, r};
        nbhd_table_options o = nbhd_table_options_default();
        o.exclude_self = false;
        o.threads = table_threads_;
        std::unique_ptr<RowTable> t(new RowTable);
        if (nbhd_tree_neighborhoods(tree_.get(), &spec, &o, &t->table) != NBHD_STATUS_OK)
            return nullptr;
        t->key = key;
        t->rows = nbhd_neighborhoods_rows(t->table);
        t->off = nbhd_neighborhoods_offsets(t->table);
        t->idx = nbhd_neighborhoods_indices(t->table);
        t->dist = static_cast<const float*>(nbhd_neighborhoods_sq_dists(t->table));
        const RowTable* made = t.get();
        tables_.push_back(std::move(t));
        table_.store(made, std::memory_order_release);
        return made;
    }

    std::unique_ptr<nbhd_tree, pcl_detail::TreeFree> tree_;
    bool table_runs_ = true;
    std::size_t table_threads_ = 0;
    mutable std::mutex table_mutex_;
    mutable std::vector<std::unique_ptr<RowTable>> tables_;  // freed by setInputCloud
    mutable std::atomic<const RowTable*> table_{nullptr};    // the latest, read lock-free
    mutable std::atomic<Key> run_key_{0};
    mutable std::atomic<std::size_t> run_len_{0};
    mutable std::atomic<Key> refused_key_{0};  // a run whose table would be too large
    std::size_t searched_ = 0;  // points searched: in the tree, and the extra copies of listed ones
    std::size_t distinct_ = 0;  // points in the tree
    std::size_t source_points_ = 0;  // the input cloud's size at setInputCloud: the tree's indices
    std::vector<std::uint32_t> copies_;  // times each cloud index was listed, if one was repeated
    mutable std::atomic<std::size_t> size_hint_{64};  // expected radius answer size
    mutable std::atomic<std::uint64_t> radius_memo_{0};  // limit bits << 32 | radius bits
};

}  // namespace nbhd
