// ctest: nbhd::PclSearch (include/nbhd_pcl.hpp) against pcl::search::KdTree, on one cloud.
//
//   test_pcl_backend FILE.pcd [--crop COL ROW W H]     a scan (a window of an organized one)
//   test_pcl_backend --generated N                     a torus of N points
//
// 1. The search interface: every point, index and batch overload, with and without an index
//    subset in setInputCloud, k nearest, radius and radius with max_nn, on the cloud's own
//    points (NaN holes included: they are skipped) — squared distances must be bitwise equal
//    position by position, and indices equal except inside a run of points tied at the last
//    distance of an answer cut at k or max_nn (counted). Also PointXYZRGB and PointNormal, and
//    an index subset that lists points two and three times (KdTree finds each copy).
// 2. PCL's algorithms with each backend: NormalEstimation k = 16 and r = 3h,
//    NormalEstimationOMP on 2 threads, MovingLeastSquares r = 5h, EuclideanClusterExtraction
//    1.5h, RegionGrowing k = 30, FPFHEstimation r = 4h and FPFHEstimationOMP on 2 threads. The
//    outputs must agree: normals and curvatures within float rounding except at points with a
//    tie at the k-th distance (counted and bounded), cluster and region lists equal, MLS points
//    and FPFH histograms within rounding.
// Exit 1 on any disagreement.
#include <nbhd_pcl.hpp>

#include "common/pcl_algorithms.hpp"
#include "common/search_answers.hpp"

#include <pcl/io/pcd_io.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iostream>

using pclalg::Cloud;
using pclalg::Input;
using search_answers::compare;
using search_answers::failures;
using search_answers::Tally;

// ---- 1. the search interface ---------------------------------------------------------------

template <class PointT>
static void interface_checks(const typename pcl::PointCloud<PointT>::Ptr& cloud,
                             const pcl::IndicesConstPtr& subset, double h, std::size_t max_queries,
                             const char* label) {
    pcl::search::KdTree<PointT> kd;
    nbhd::PclSearch<PointT> nb;
    kd.setInputCloud(cloud, subset);
    nb.setInputCloud(cloud, subset);
    EXPECT(nb.getInputCloud() == cloud && nb.getIndices() == subset, "%s", label);
    const double r = 3.0 * h;
    Tally t;
    pcl::Indices pi, ni;
    std::vector<float> pd, nd;
    const std::size_t n = cloud->size();
    const std::size_t step = n > max_queries ? n / max_queries : 1;
    for (std::size_t i = 0; i < n; i += step) {
        const PointT& p = (*cloud)[i];
        const bool finite = std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
        const auto idx = static_cast<pcl::index_t>(i);
        if (!finite) {
            // PCL asserts on such a query; nbhd answers nothing.
            EXPECT(nb.nearestKSearch(*cloud, idx, 5, ni, nd) == 0 && ni.empty(), "%s", label);
            EXPECT(nb.radiusSearch(*cloud, idx, r, ni, nd) == 0 && ni.empty(), "%s", label);
            continue;
        }
        for (int k : {1, 16}) {
            int a = kd.nearestKSearch(p, k, pi, pd), b = nb.nearestKSearch(p, k, ni, nd);
            compare("knn point", pi, pd, ni, nd, a, b, true, t);
            a = kd.nearestKSearch(*cloud, idx, k, pi, pd);
            b = nb.nearestKSearch(*cloud, idx, k, ni, nd);
            compare("knn cloud index", pi, pd, ni, nd, a, b, true, t);
        }
        int a = kd.radiusSearch(p, r, pi, pd), b = nb.radiusSearch(p, r, ni, nd);
        compare("radius point", pi, pd, ni, nd, a, b, false, t);
        a = kd.radiusSearch(*cloud, idx, r, pi, pd);
        b = nb.radiusSearch(*cloud, idx, r, ni, nd);
        compare("radius cloud index", pi, pd, ni, nd, a, b, false, t);
        a = kd.radiusSearch(*cloud, idx, r, pi, pd, 8);
        b = nb.radiusSearch(*cloud, idx, r, ni, nd, 8);
        compare("radius max_nn 8", pi, pd, ni, nd, a, b, true, t);
    }
    // Runs of same-k / same-radius index queries over every point, as PCL's algorithms ask
    // them: past the run length nbhd serves them from one all-point table.
    for (int pass = 0; pass < 3; ++pass) {
        for (std::size_t i = 0; i < n; ++i) {
            const PointT& p = (*cloud)[i];
            if (!(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z))) continue;
            const auto idx = static_cast<pcl::index_t>(i);
            int a, b;
            if (pass == 0) {
                a = kd.nearestKSearch(*cloud, idx, 16, pi, pd);
                b = nb.nearestKSearch(*cloud, idx, 16, ni, nd);
            } else {
                const unsigned max_nn = pass == 1 ? 0 : 12;
                a = kd.radiusSearch(*cloud, idx, r, pi, pd, max_nn);
                b = nb.radiusSearch(*cloud, idx, r, ni, nd, max_nn);
            }
            compare(pass == 0 ? "knn run" : pass == 1 ? "radius run" : "max_nn run", pi, pd, ni,
                    nd, a, b, pass != 1, t);
        }
    }
    // Input positions (nearestKSearch(index)): positions in the subset when one was given.
    const std::size_t positions = subset ? subset->size() : n;
    for (std::size_t j = 0; j < positions; j += step) {
        const pcl::index_t c = subset ? (*subset)[j] : static_cast<pcl::index_t>(j);
        const PointT& p = (*cloud)[static_cast<std::size_t>(c)];
        if (!(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z))) continue;
        const auto pos = static_cast<pcl::index_t>(j);
        int a = kd.nearestKSearch(pos, 10, pi, pd), b = nb.nearestKSearch(pos, 10, ni, nd);
        compare("knn position", pi, pd, ni, nd, a, b, true, t);
        a = kd.radiusSearch(pos, r, pi, pd);
        b = nb.radiusSearch(pos, r, ni, nd);
        compare("radius position", pi, pd, ni, nd, a, b, false, t);
    }
    // Batches, over a list of finite cloud indices.
    pcl::Indices batch;
    for (std::size_t i = 0; i < n && batch.size() < 300; i += step) {
        const PointT& p = (*cloud)[i];
        if (std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z))
            batch.push_back(static_cast<pcl::index_t>(i));
    }
    std::vector<pcl::Indices> bpi, bni;
    std::vector<std::vector<float>> bpd, bnd;
    kd.nearestKSearch(*cloud, batch, 12, bpi, bpd);
    nb.nearestKSearch(*cloud, batch, 12, bni, bnd);
    EXPECT(bpi.size() == batch.size() && bni.size() == batch.size(), "%s", label);
    for (std::size_t i = 0; i < batch.size() && i < bni.size(); ++i)
        compare("knn batch", bpi[i], bpd[i], bni[i], bnd[i], static_cast<int>(bpi[i].size()),
                static_cast<int>(bni[i].size()), true, t);
    kd.radiusSearch(*cloud, batch, r, bpi, bpd, 0);
    nb.radiusSearch(*cloud, batch, r, bni, bnd, 0);
    for (std::size_t i = 0; i < batch.size() && i < bni.size(); ++i)
        compare("radius batch", bpi[i], bpd[i], bni[i], bnd[i], static_cast<int>(bpi[i].size()),
                static_cast<int>(bni[i].size()), false, t);
    // Unsorted results allowed: nbhd still answers the same set.
    nb.setSortedResults(false);
    kd.setSortedResults(false);
    if (!batch.empty()) {
        const PointT& p = (*cloud)[static_cast<std::size_t>(batch[0])];
        int a = kd.radiusSearch(p, r, pi, pd), b = nb.radiusSearch(p, r, ni, nd);
        compare("radius unsorted", pi, pd, ni, nd, a, b, false, t);
    }
    std::printf("  interface %-34s %7zu queries %9zu neighbours, %zu tie runs resolved, %zu "
                "mismatches\n",
                label, t.queries, t.neighbours, t.tie_runs, t.mismatches);
    EXPECT(t.mismatches == 0, "%s", label);
    EXPECT(t.queries > 0, "%s", label);
}

template <class PointT>
static typename pcl::PointCloud<PointT>::Ptr as_type(const Cloud& c) {
    typename pcl::PointCloud<PointT>::Ptr out(new pcl::PointCloud<PointT>);
    out->resize(c.size());
    for (std::size_t i = 0; i < c.size(); ++i) {
        (*out)[i].x = c[i].x;
        (*out)[i].y = c[i].y;
        (*out)[i].z = c[i].z;
    }
    out->width = c.width;
    out->height = c.height;
    out->is_dense = c.is_dense;
    return out;
}

// ---- 2. the algorithms -----------------------------------------------------------------------

/// Cloud indices whose k-th and (k+1)-th nearest (the point itself counted) are equally far.
static std::vector<bool> ties_at_k(const Input& in, int k) {
    nbhd::PclSearch<pcl::PointXYZ> s;
    s.setInputCloud(in.cloud);
    std::vector<bool> tie(in.cloud->size(), false);
    pcl::Indices i;
    std::vector<float> d;
    for (pcl::index_t p : *in.finite)
        if (s.nearestKSearch(*in.cloud, p, k + 1, i, d) == k + 1 && d[k - 1] == d[k])
            tie[static_cast<std::size_t>(p)] = true;
    return tie;
}

static void compare_normals(const char* what, const pclalg::Normals& a, const pclalg::Normals& b,
                            const std::vector<bool>* tie) {
    std::size_t finite = 0, off = 0, off_tied = 0, tied = 0, same_bits = 0;
    double worst = 0, worst_curv = 0;
    bool same_size = a.size() == b.size();
    EXPECT(same_size, "%s: %zu vs %zu normals", what, a.size(), b.size());
    if (!same_size) return;
    for (std::size_t i = 0; i < a.size(); ++i) {
        const auto &p = a[i], &q = b[i];
        const bool fp = std::isfinite(p.normal_x), fq = std::isfinite(q.normal_x);
        if (fp != fq) {
            ++off;
            continue;
        }
        if (!fp) continue;
        ++finite;
        const bool t = tie && (*tie)[i];
        tied += t;
        // Up to sign (PCL orients towards the viewpoint, the same for both).
        const double ang = std::max({std::fabs(double(p.normal_x) - q.normal_x),
                                     std::fabs(double(p.normal_y) - q.normal_y),
                                     std::fabs(double(p.normal_z) - q.normal_z)});
        const double dc = std::fabs(double(p.curvature) - q.curvature);
        same_bits += ang == 0 && dc == 0;
        // Float rounding: the covariance sums the same points, possibly in another order.
        const bool close = ang <= 1e-4 && dc <= 1e-4 * std::max(1e-2, double(p.curvature));
        if (!close) {
            if (t) ++off_tied;
            else ++off;
        } else {
            worst = std::max(worst, ang);
            worst_curv = std::max(worst_curv, dc);
        }
    }
    std::printf("  %-34s %7zu normals (%zu bitwise equal), max |dn| %.1e, max |dcurv| %.1e; %zu "
                "with a tie at k (%zu of them differ), %zu differ otherwise\n",
                what, finite, same_bits, worst, worst_curv, tied, off_tied, off);
    EXPECT(off == 0, "%s", what);
    // Ties change the neighbourhood's last point: bounded to 2% of the points.
    EXPECT(off_tied * 50 <= finite, "%s: %zu tie differences", what, off_tied);
}

static void algorithm_checks(const Input& in) {
    const pclalg::MakeSearch kd = [] {
        return pclalg::Search::Ptr(new pcl::search::KdTree<pcl::PointXYZ>);
    };
    const pclalg::MakeSearch nb = [] {
        return pclalg::Search::Ptr(new nbhd::PclSearch<pcl::PointXYZ>);
    };
    const double h = in.h;
    const auto tie16 = ties_at_k(in, 16);

    auto nk = pclalg::normals(in, kd, 16, 0, 1);
    compare_normals("NormalEstimation k=16", nk, pclalg::normals(in, nb, 16, 0, 1), &tie16);
    compare_normals("NormalEstimationOMP k=16, 2 threads", nk, pclalg::normals(in, nb, 16, 0, 2),
                    &tie16);
    compare_normals("NormalEstimation r=3h", pclalg::normals(in, kd, 0, 3 * h, 1),
                    pclalg::normals(in, nb, 0, 3 * h, 1), nullptr);

    {
        Cloud a = pclalg::mls(in, kd, 5 * h, 1), b = pclalg::mls(in, nb, 5 * h, 1);
        EXPECT(a.size() == b.size(), "MLS sizes %zu vs %zu", a.size(), b.size());
        double worst = 0;
        for (std::size_t i = 0; i < a.size() && i < b.size(); ++i)
            worst = std::max({worst, std::fabs(double(a[i].x) - b[i].x),
                              std::fabs(double(a[i].y) - b[i].y),
                              std::fabs(double(a[i].z) - b[i].z)});
        std::printf("  %-34s %7zu points, max |dx| %.2e (%.2e h)\n", "MovingLeastSquares r=5h",
                    a.size(), worst, worst / h);
        EXPECT(worst <= 1e-3 * h, "MLS max difference %g", worst);
    }
    {
        auto a = pclalg::clusters(in, kd, 1.5 * h), b = pclalg::clusters(in, nb, 1.5 * h);
        std::printf("  %-34s %7zu clusters (KdTree) %zu (nbhd), identical: %s\n",
                    "EuclideanClusterExtraction 1.5h", a.size(), b.size(), a == b ? "yes" : "no");
        EXPECT(a == b, "clusters differ");
    }
    {
        pclalg::Normals::Ptr n(new pclalg::Normals(nk));
        auto a = pclalg::regions(in, n, kd, 30), b = pclalg::regions(in, n, nb, 30);
        std::size_t in_a = 0, in_b = 0;
        for (auto& r : a) in_a += r.size();
        for (auto& r : b) in_b += r.size();
        std::printf("  %-34s %7zu regions (KdTree) %zu (nbhd), %zu / %zu points, identical: %s\n",
                    "RegionGrowing k=30", a.size(), b.size(), in_a, in_b, a == b ? "yes" : "no");
        EXPECT(a.size() == b.size(), "region counts differ");
        const auto tie30 = ties_at_k(in, 30);
        std::size_t tied = 0;
        for (bool t : tie30) tied += t;
        if (a != b) {
            // Only ties at the 30th distance may move points between regions.
            std::vector<int> ra(in.cloud->size(), -1), rb(in.cloud->size(), -1);
            for (std::size_t r = 0; r < a.size(); ++r) for (auto i : a[r]) ra[i] = int(r);
            for (std::size_t r = 0; r < b.size(); ++r) for (auto i : b[r]) rb[i] = int(r);
            std::size_t moved = 0;
            for (std::size_t i = 0; i < ra.size(); ++i) moved += ra[i] != rb[i];
            std::printf("    %zu points in other regions; %zu points have a tie at k = 30\n", moved,
                        tied);
            EXPECT(tied > 0 && moved * 50 <= in.finite->size(), "regions differ without ties");
        }
    }
    {
        pclalg::Normals::Ptr n(new pclalg::Normals(nk));
        auto a = pclalg::fpfh(in, n, kd, 4 * h, 1);
        for (int threads : {1, 2}) {
            auto b = pclalg::fpfh(in, n, nb, 4 * h, threads);
            EXPECT(a.size() == b.size(), "FPFH sizes");
            double worst = 0;
            std::size_t nan_mismatch = 0;
            for (std::size_t i = 0; i < a.size() && i < b.size(); ++i)
                for (int j = 0; j < 33; ++j) {
                    const float x = a[i].histogram[j], y = b[i].histogram[j];
                    if (std::isnan(x) || std::isnan(y)) nan_mismatch += std::isnan(x) != std::isnan(y);
                    else worst = std::max(worst, std::fabs(double(x) - y));
                }
            std::printf("  FPFH%-30s %7zu points, max |dbin| %.2e (bins sum to 300)\n",
                        threads == 1 ? "Estimation r=4h" : "EstimationOMP r=4h, 2 threads",
                        a.size(), worst);
            EXPECT(nan_mismatch == 0 && worst <= 1e-3, "FPFH %g, %zu NaN", worst, nan_mismatch);
        }
    }
}

int main(int argc, char** argv) {
    Cloud::Ptr cloud(new Cloud);
    std::string name;
    if (argc >= 3 && std::strcmp(argv[1], "--generated") == 0) {
        cloud = pclalg::torus(std::strtoul(argv[2], nullptr, 10));
        name = "torus " + std::to_string(cloud->size());
    } else if (argc >= 2) {
        if (pcl::io::loadPCDFile<pcl::PointXYZ>(argv[1], *cloud) != 0) {
            std::fprintf(stderr, "cannot load %s\n", argv[1]);
            return 1;
        }
        name = argv[1];
        if (argc >= 7 && std::strcmp(argv[2], "--crop") == 0) {
            cloud = pclalg::crop(*cloud, std::atoi(argv[3]), std::atoi(argv[4]), std::atoi(argv[5]),
                                 std::atoi(argv[6]));
            name += " (window)";
        }
    } else {
        std::fprintf(stderr, "usage: %s FILE.pcd [--crop COL ROW W H] | --generated N\n", argv[0]);
        return 2;
    }
    const Input in = pclalg::make_input(name, cloud);
    std::printf("%s: %zu points, %zu finite, h = %.6g\n", name.c_str(), cloud->size(),
                in.finite->size(), in.h);

    interface_checks<pcl::PointXYZ>(cloud, nullptr, in.h, 3000, "PointXYZ");
    {
        pcl::IndicesPtr every_third(new pcl::Indices);
        for (std::size_t i = 0; i < cloud->size(); i += 3)
            every_third->push_back(static_cast<pcl::index_t>(i));  // NaN holes included
        interface_checks<pcl::PointXYZ>(cloud, every_third, in.h, 3000,
                                        "PointXYZ, indices: every third");
    }
    {
        // Indices listing points more than once (NaN holes too): KdTreeFLANN copies every
        // listed point, so a point listed twice is found twice; nbhd must answer the same.
        pcl::IndicesPtr repeated(new pcl::Indices);
        for (std::size_t i = 0; i < cloud->size(); i += 3) {
            const auto c = static_cast<pcl::index_t>(i);
            repeated->push_back(c);
            if (i % 7 == 0) repeated->push_back(c);                       // twice, adjacent
            if (i % 11 == 0) repeated->insert(repeated->begin() + repeated->size() / 2, c);  // again
        }
        interface_checks<pcl::PointXYZ>(cloud, repeated, in.h, 3000,
                                        "PointXYZ, indices: some listed 2-3 times");
        // The fact itself, not only agreement: a finite point listed three times is found three
        // times around itself, at squared distance 0.
        nbhd::PclSearch<pcl::PointXYZ> nb;
        nb.setInputCloud(cloud, repeated);
        std::size_t checked = 0;
        for (std::size_t i = 0; i < cloud->size() && checked < 20; i += 3 * 7 * 11) {
            const auto& p = (*cloud)[i];
            if (!(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z))) continue;
            pcl::Indices ni;
            std::vector<float> nd;
            nb.radiusSearch(*cloud, static_cast<pcl::index_t>(i), in.h, ni, nd);
            const auto times = std::count(ni.begin(), ni.end(), static_cast<pcl::index_t>(i));
            EXPECT(times == 3 && nd.size() >= 3 && nd[0] == 0 && nd[2] == 0,
                   "point %zu listed 3 times found %ld times", i, static_cast<long>(times));
            ++checked;
        }
        EXPECT(checked > 0, "no point listed three times was checked");
    }
    interface_checks<pcl::PointXYZRGB>(as_type<pcl::PointXYZRGB>(*cloud), nullptr, in.h, 500,
                                       "PointXYZRGB");
    interface_checks<pcl::PointNormal>(as_type<pcl::PointNormal>(*cloud), in.finite, in.h, 500,
                                       "PointNormal, indices: finite");
    interface_checks<pcl::PointXYZI>(as_type<pcl::PointXYZI>(*cloud), nullptr, in.h, 500,
                                     "PointXYZI");
    algorithm_checks(in);
    std::printf("%s\n", failures == 0 ? "all agree" : "DISAGREEMENTS");
    return failures == 0 ? 0 : 1;
}
