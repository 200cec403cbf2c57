// A benchmark, not a test: PCL's algorithms with pcl::search::KdTree, pcl::search::Octree and
// nbhd::PclSearch (include/nbhd_pcl.hpp), on one and two threads, in one run.
//
//   bench_pcl_backend [--reps 3] [--generated 1000000] [--crop COL ROW W H] [--floor]
//                     [--table-threads row | --no-tables] [--cpu-time] [--only NAME] [FILE.pcd ...]
//
// For each cloud (the torus of --generated points, then every FILE, cropped to the window if
// --crop is given): NormalEstimation(OMP) k = 16 and r = 3h, MovingLeastSquares r = 5h (order 2,
// positions only), EuclideanClusterExtraction 1.5h, RegionGrowing k = 30 and
// FPFHEstimation(OMP) r = 4h, each timed with each backend (set-up, tree build and compute()),
// median of --reps; threads = 2 for the algorithms with a thread count (clustering and region
// growing have none in PCL 1.13). Normals for region growing and FPFH are computed once
// beforehand with KdTree. Octree's resolution is 4h. Prints ms and the ratio to KdTree.
// --table-threads row: nbhd's tables computed on the row's threads (default: all cores, even in a
// one-thread row); --no-tables: nbhd answers every query singly.
// --cpu-time times the process's CPU time (every thread's) instead of wall time: on a loaded
// machine, closer to what an idle one shows for one-thread rows, and the total work for others.
// --only NAME runs the algorithms whose name starts with NAME (e.g. "Euclidean").
// --floor adds PCL's own share of each row: the algorithm with a search that only copies answers
// computed beforehand (class Answered), and nbhd's and KdTree's times above it.
//
// Then the measurement behind nbhd::PclSearch's index path (issue 22, item 3): the same k = 16
// neighbourhoods of every point asked as single index queries (what PCL's algorithms do), and
// as one all-point table (nbhd_tree_neighborhoods) on one and on two threads.
#include <nbhd_pcl.hpp>

#include "common/pcl_algorithms.hpp"

#include <pcl/io/pcd_io.h>
#include <pcl/search/octree.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <array>
#include <atomic>
#include <map>
#include <mutex>
#include <stdexcept>

using pclalg::Cloud;
using pclalg::Input;
using Clock = std::chrono::steady_clock;

static int table_mode = 0;  // 0: nbhd's default (tables on all cores), 1: on the row's threads, 2: none

/// PCL's own share of an algorithm (its floor: what no backend can beat). A search that answers
/// every query from rows computed beforehand: the first run of an algorithm with one object fills
/// a row table per (kind, k, radius, max_nn) through nbhd::PclSearch (the same answers), later
/// runs only copy rows into PCL's vectors, which every backend must do. A query by point is
/// served from the table when the point is one of the input cloud's (PCL passes cloud[i]);
/// others (none in these algorithms; counted) are searched.
class Answered : public pcl::search::Search<pcl::PointXYZ> {
public:
    using Base = pcl::search::Search<pcl::PointXYZ>;
    Answered() : Base("Answered", true) { inner_.setTableRuns(false); }

    void setInputCloud(const PointCloudConstPtr& cloud,
                       const IndicesConstPtr& indices = IndicesConstPtr()) override {
        if (built_ && cloud == input_ && indices == indices_) return;  // answers kept
        input_ = cloud;
        indices_ = indices;
        inner_.setInputCloud(cloud, indices);
        count_.store(0);
        built_ = true;
    }
    int nearestKSearch(const pcl::PointXYZ& p, int k, pcl::Indices& i,
                       std::vector<float>& d) const override {
        const std::size_t c = own(p);
        if (c == kNone) { ++misses_; return inner_.nearestKSearch(p, k, i, d); }
        return row(Key{0, k, 0, 0}, c, i, d);
    }
    int radiusSearch(const pcl::PointXYZ& p, double r, pcl::Indices& i, std::vector<float>& d,
                     unsigned int max_nn = 0) const override {
        const std::size_t c = own(p);
        if (c == kNone) { ++misses_; return inner_.radiusSearch(p, r, i, d, max_nn); }
        return row(Key{1, 0, r, max_nn}, c, i, d);
    }
    int nearestKSearch(const PointCloud& cloud, pcl::index_t index, int k, pcl::Indices& i,
                       std::vector<float>& d) const override {
        return nearestKSearch(cloud[static_cast<std::size_t>(index)], k, i, d);
    }
    int nearestKSearch(pcl::index_t index, int k, pcl::Indices& i,
                       std::vector<float>& d) const override {
        return row(Key{0, k, 0, 0}, cloud_index(index), i, d);
    }
    int radiusSearch(const PointCloud& cloud, pcl::index_t index, double r, pcl::Indices& i,
                     std::vector<float>& d, unsigned int max_nn = 0) const override {
        return radiusSearch(cloud[static_cast<std::size_t>(index)], r, i, d, max_nn);
    }
    int radiusSearch(pcl::index_t index, double r, pcl::Indices& i, std::vector<float>& d,
                     unsigned int max_nn = 0) const override {
        return row(Key{1, 0, r, max_nn}, cloud_index(index), i, d);
    }
    std::size_t misses() const { return misses_.load(); }

private:
    static constexpr std::size_t kNone = ~std::size_t(0);
    struct Key {
        int kind, k;
        double r;
        unsigned max_nn;
        bool operator==(const Key& o) const {
            return kind == o.kind && k == o.k && r == o.r && max_nn == o.max_nn;
        }
    };
    struct Table {
        Key key;
        std::vector<std::size_t> off;
        pcl::Indices idx;
        std::vector<float> d;
    };
    std::size_t own(const pcl::PointXYZ& p) const {
        const auto a = reinterpret_cast<std::uintptr_t>(&p);
        const auto b = reinterpret_cast<std::uintptr_t>(input_->points.data());
        if (a < b || a >= b + input_->size() * sizeof(pcl::PointXYZ)) return kNone;
        return (a - b) / sizeof(pcl::PointXYZ);
    }
    std::size_t cloud_index(pcl::index_t pos) const {
        return indices_ ? static_cast<std::size_t>((*indices_)[static_cast<std::size_t>(pos)])
                        : static_cast<std::size_t>(pos);
    }
    int row(const Key& key, std::size_t c, pcl::Indices& i, std::vector<float>& d) const {
        const Table* t = nullptr;
        const int n = count_.load(std::memory_order_acquire);
        for (int j = 0; j < n && !t; ++j)
            if (tables_[j]->key == key) t = tables_[j].get();
        if (!t) t = make(key);
        i.assign(t->idx.begin() + t->off[c], t->idx.begin() + t->off[c + 1]);
        d.assign(t->d.begin() + t->off[c], t->d.begin() + t->off[c + 1]);
        return static_cast<int>(i.size());
    }
    const Table* make(const Key& key) const {
        std::lock_guard<std::mutex> lock(m_);
        const int n = count_.load();
        for (int j = 0; j < n; ++j)
            if (tables_[j]->key == key) return tables_[j].get();
        if (n == kTables) throw std::runtime_error("Answered: too many tables");
        std::unique_ptr<Table> t(new Table);
        t->key = key;
        pcl::Indices i;
        std::vector<float> d;
        t->off.push_back(0);
        for (std::size_t c = 0; c < input_->size(); ++c) {
            const auto q = static_cast<pcl::index_t>(c);
            if (key.kind == 0) inner_.nearestKSearch(*input_, q, key.k, i, d);
            else inner_.radiusSearch(*input_, q, key.r, i, d, key.max_nn);
            t->idx.insert(t->idx.end(), i.begin(), i.end());
            t->d.insert(t->d.end(), d.begin(), d.end());
            t->off.push_back(t->idx.size());
        }
        tables_[n] = std::move(t);
        count_.store(n + 1, std::memory_order_release);
        return tables_[n].get();
    }
    static constexpr int kTables = 8;
    nbhd::PclSearch<pcl::PointXYZ> inner_;
    bool built_ = false;
    mutable std::mutex m_;
    mutable std::array<std::unique_ptr<Table>, kTables> tables_;
    mutable std::atomic<int> count_{0};
    mutable std::atomic<std::size_t> misses_{0};
};

static bool cpu_time = false;  // --cpu-time: the process's CPU time (all threads), not wall time
static const char* only = nullptr;  // --only NAME: the algorithms whose name starts with NAME

static double cpu_seconds() {
    timespec ts{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

template <class F>
static double median_ms(int reps, F&& f) {
    std::vector<double> t;
    for (int i = 0; i < reps; ++i) {
        const auto t0 = Clock::now();
        const double c0 = cpu_seconds();
        f();
        t.push_back(1e3 * (cpu_time ? cpu_seconds() - c0 : pclalg::seconds_since(t0)));
    }
    std::sort(t.begin(), t.end());
    return t[t.size() / 2];
}

static void bench(const Input& in, int reps, bool floor) {
    const double h = in.h;
    std::printf("\n## %s: %zu points (%zu finite), h = %.6g\n\n", in.name.c_str(), in.cloud->size(),
                in.finite->size(), h);
    const std::vector<std::pair<const char*, pclalg::MakeSearch>> backends = {
        {"KdTree", [] { return pclalg::Search::Ptr(new pcl::search::KdTree<pcl::PointXYZ>); }},
        {"Octree",
         [h] { return pclalg::Search::Ptr(new pcl::search::Octree<pcl::PointXYZ>(4.0 * h)); }},
        {"nbhd", [] { return pclalg::Search::Ptr(new nbhd::PclSearch<pcl::PointXYZ>); }},
    };
    // nbhd with its tables on the row's threads (--table-threads row) or none (--no-tables).
    const auto nbhd_for = [&](int threads) -> pclalg::MakeSearch {
        if (table_mode == 0) return backends[2].second;
        return [threads] {
            auto s = std::make_shared<nbhd::PclSearch<pcl::PointXYZ>>();
            if (table_mode == 1) s->setTableThreads(static_cast<std::size_t>(threads));
            else s->setTableRuns(false);
            return pclalg::Search::Ptr(s);
        };
    };
    pclalg::Normals::Ptr normals(new pclalg::Normals(pclalg::normals(
        in, backends[0].second, 16, 0, 1)));
    struct Algo {
        const char* name;
        bool threaded;
        std::function<void(const pclalg::MakeSearch&, int)> run;
    };
    const std::vector<Algo> algos = {
        {"normals k=16", true, [&](const pclalg::MakeSearch& m, int t) { pclalg::normals(in, m, 16, 0, t); }},
        {"normals r=3h", true, [&](const pclalg::MakeSearch& m, int t) { pclalg::normals(in, m, 0, 3 * h, t); }},
        {"MLS r=5h", true, [&](const pclalg::MakeSearch& m, int t) { pclalg::mls(in, m, 5 * h, t); }},
        {"Euclidean clusters 1.5h", false, [&](const pclalg::MakeSearch& m, int) { pclalg::clusters(in, m, 1.5 * h); }},
        {"region growing k=30", false, [&](const pclalg::MakeSearch& m, int) { pclalg::regions(in, normals, m, 30); }},
        {"FPFH r=4h", true, [&](const pclalg::MakeSearch& m, int t) { pclalg::fpfh(in, normals, m, 4 * h, t); }},
    };
    if (floor)
        std::printf("| algorithm | threads | KdTree ms | Octree ms (/KdTree) | nbhd ms (/KdTree) | "
                    "PCL's own ms | nbhd − own (/ KdTree − own) |\n|---|---|---|---|---|---|---|\n");
    else
        std::printf("| algorithm | threads | KdTree ms | Octree ms (/KdTree) | nbhd ms (/KdTree) |\n"
                    "|---|---|---|---|---|\n");
    for (const auto& a : algos) {
        if (only && std::strncmp(a.name, only, std::strlen(only)) != 0) continue;
        for (int threads : {1, 2}) {
            if (threads == 2 && !a.threaded) continue;
            // PCL 1.13's search::Octree takes nearestKSearch(index)'s position in setIndices as
            // a cloud index (RegionGrowing then queries NaN holes and asserts): skipped there.
            const bool skip_octree = std::strcmp(a.name, "region growing k=30") == 0 &&
                                     in.finite->size() != in.cloud->size();
            // The floor: one Answered object per row, filled by an untimed first run.
            std::shared_ptr<Answered> answered;
            pclalg::MakeSearch by_table;
            if (floor) {
                answered = std::make_shared<Answered>();
                by_table = [answered] { return pclalg::Search::Ptr(answered); };
                a.run(by_table, threads);
            }
            const int columns = floor ? 4 : 3;
            // Interleaved repetitions: each repetition runs every backend once.
            std::vector<double> t[4];
            for (int r = 0; r < reps; ++r)
                for (int b = 0; b < columns; ++b)
                    t[b].push_back(b == 1 && skip_octree
                                       ? NAN
                                       : median_ms(1, [&] {
                                             a.run(b == 3 ? by_table : b == 2 ? nbhd_for(threads) : backends[b].second, threads);
                                         }));
            double ms[4];
            for (int b = 0; b < columns; ++b) {
                std::sort(t[b].begin(), t[b].end());
                ms[b] = t[b][t[b].size() / 2];
            }
            char octree[64];
            if (skip_octree) std::snprintf(octree, sizeof octree, "n/a");
            else std::snprintf(octree, sizeof octree, "%.0f (%.2f)", ms[1], ms[1] / ms[0]);
            std::printf("| %s | %d | %.0f | %s | %.0f (**%.2f**) |", a.name, threads, ms[0], octree,
                        ms[2], ms[2] / ms[0]);
            if (floor)
                std::printf(" %.0f | %.0f (%.2f)%s |", ms[3], ms[2] - ms[3],
                            (ms[2] - ms[3]) / (ms[0] - ms[3]),
                            answered->misses() ? " (some queries searched)" : "");
            std::printf("\n");
            std::fflush(stdout);
        }
    }

    if (only) return;
    // Single index queries against one all-point table, k = 16 with the point itself.
    nbhd::PclSearch<pcl::PointXYZ> s;
    s.setTableRuns(false);  // the single queries themselves
    s.setInputCloud(in.cloud);
    pcl::Indices idx;
    std::vector<float> d;
    const double single = median_ms(reps, [&] {
        for (pcl::index_t i : *in.finite) s.nearestKSearch(*in.cloud, i, 16, idx, d);
    });
    double table[2];
    for (int t = 0; t < 2; ++t) {
        nbhd_neighborhood_spec spec = {NBHD_NEIGHBORHOOD_KIND_KNN, 16, 0.0};
        nbhd_table_options o = nbhd_table_options_default();
        o.exclude_self = false;
        o.threads = static_cast<std::size_t>(t + 1);
        table[t] = median_ms(reps, [&] {
            nbhd_neighborhoods* tab = nullptr;
            if (nbhd_tree_neighborhoods(s.tree(), &spec, &o, &tab) == NBHD_STATUS_OK) {
                // what serving the rows costs: copy each into PCL's vectors
                const std::size_t* off = nbhd_neighborhoods_offsets(tab);
                const std::uint32_t* ti = nbhd_neighborhoods_indices(tab);
                const float* td = static_cast<const float*>(nbhd_neighborhoods_sq_dists(tab));
                for (pcl::index_t i : *in.finite) {
                    idx.assign(ti + off[i], ti + off[i + 1]);
                    d.assign(td + off[i], td + off[i + 1]);
                }
            }
            nbhd_neighborhoods_free(tab);
        });
    }
    std::printf("\nk = 16 of every point: single index queries %.0f ms; one table, 1 thread %.0f ms "
                "(%.2f), 2 threads %.0f ms (%.2f)\n",
                single, table[0], table[0] / single, table[1], table[1] / single);
}

int main(int argc, char** argv) {
    int reps = 3;
    bool floor = false;
    std::size_t generated = 1000000;
    int crop[4] = {0, 0, 0, 0};
    std::vector<std::string> files;
    for (int i = 1; i < argc; ++i) {
        if (!std::strcmp(argv[i], "--reps") && i + 1 < argc) reps = std::atoi(argv[++i]);
        else if (!std::strcmp(argv[i], "--generated") && i + 1 < argc)
            generated = std::strtoul(argv[++i], nullptr, 10);
        else if (!std::strcmp(argv[i], "--floor")) floor = true;
        else if (!std::strcmp(argv[i], "--table-threads") && i + 1 < argc && !std::strcmp(argv[i + 1], "row"))
            table_mode = 1, ++i;
        else if (!std::strcmp(argv[i], "--no-tables")) table_mode = 2;
        else if (!std::strcmp(argv[i], "--cpu-time")) cpu_time = true;
        else if (!std::strcmp(argv[i], "--only") && i + 1 < argc) only = argv[++i];
        else if (!std::strcmp(argv[i], "--crop") && i + 4 < argc)
            for (int j = 0; j < 4; ++j) crop[j] = std::atoi(argv[++i]);
        else files.push_back(argv[i]);
    }
    if (reps < 1) reps = 1;
    if (generated > 0)
        bench(pclalg::make_input("torus " + std::to_string(generated), pclalg::torus(generated)),
              reps, floor);
    for (const auto& f : files) {
        Cloud::Ptr c(new Cloud);
        if (pcl::io::loadPCDFile<pcl::PointXYZ>(f, *c) != 0) {
            std::fprintf(stderr, "cannot load %s\n", f.c_str());
            return 1;
        }
        std::string name = f.substr(f.find_last_of('/') + 1);
        if (crop[2] > 0 && c->height > 1) {
            c = pclalg::crop(*c, crop[0], crop[1], crop[2], crop[3]);
            name += " (window)";
        }
        bench(pclalg::make_input(name, c), reps, floor);
    }
    return 0;
}
