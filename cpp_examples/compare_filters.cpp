// Box queries and outlier removal, nbhd against PCL on a scan loaded with PCL's own reader:
// pcl::CropBox vs nbhd_tree_in_box, pcl::StatisticalOutlierRemoval vs
// nbhd_remove_statistical_outliers, pcl::RadiusOutlierRemoval vs nbhd_remove_radius_outliers.
// The kept sets must be identical, with PCL's conventions bridged explicitly:
//
// - CropBox tests `x < min || x > max` for outside: a closed box, as nbhd's. It skips NaN
//   points on a non-dense cloud; nbhd's tree (NBHD_NON_FINITE_POLICY_SKIP) never holds them.
// - StatisticalOutlierRemoval searches k + 1 and skips the first result (the point itself):
//   the same k as nbhd's k nearest *other* points; sample sigma (n - 1) in both. PCL 1.13
//   gives NaN points a mean distance 0 and so *keeps* them; nbhd never keeps a NaN point. The
//   check: PCL's kept set = nbhd's kept set + the NaN points, exactly.
//   PCL searches an organized cloud with pcl::search::OrganizedNeighbor (a projective
//   search); the test hands PCL the same points as an unorganized cloud (height 1, same
//   indices), so both searches are exact k-d tree searches.
// - RadiusOutlierRemoval keeps a point whose radius search, counting the point itself, finds
//   more than m: nbhd's "at least m other points", the same m. On a dense cloud PCL uses a
//   (k = m + 1)-nearest search with an inclusive radius, on a cloud with NaN points FLANN's
//   radius search, which is strict (d < r); nbhd's radius is inclusive. The test runs PCL's
//   strict variant with the radius r and nbhd's with the largest float below r, the same set
//   in float (the squared distances are compared in float in both). PCL's radius search
//   asserts on a NaN query point (Debian builds PCL with assertions), so PCL is given the
//   finite points' indices (setIndices); NaN points are kept by neither.
//
//   compare_filters SCAN.pcd K STD_RATIO RADIUS MIN_NEIGHBORS
//
// Exits 0 when every check passed.
#include <nbhd.h>

#include <pcl/filters/crop_box.h>
#include <pcl/filters/radius_outlier_removal.h>
#include <pcl/filters/statistical_outlier_removal.h>
#include <pcl/io/pcd_io.h>
#include <pcl/common/point_tests.h>
#include <pcl/point_types.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <vector>

static int failures = 0;
#define CHECK(cond, ...)                                                                           \
    do {                                                                                           \
        if (!(cond)) {                                                                             \
            std::fprintf(stderr, "check failed: %s: ", #cond);                                     \
            std::fprintf(stderr, __VA_ARGS__);                                                     \
            std::fprintf(stderr, "\n");                                                            \
            failures++;                                                                            \
        }                                                                                          \
    } while (0)

static double ms_since(std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
}

/// Number of positions where the two ascending index lists differ (symmetric difference).
static std::size_t differences(const std::vector<uint32_t> &a, const pcl::Indices &b) {
    std::size_t i = 0, j = 0, d = 0;
    while (i < a.size() || j < b.size()) {
        if (j == b.size() || (i < a.size() && a[i] < (uint32_t)b[j])) {
            d++, i++;
        } else if (i == a.size() || (uint32_t)b[j] < a[i]) {
            d++, j++;
        } else {
            i++, j++;
        }
    }
    return d;
}

int main(int argc, char **argv) {
    if (argc != 6) {
        std::fprintf(stderr, "usage: compare_filters SCAN.pcd K STD_RATIO RADIUS MIN_NEIGHBORS\n");
        return 2;
    }
    const int k = std::atoi(argv[2]);
    const double alpha = std::atof(argv[3]);
    const float radius = (float)std::atof(argv[4]);
    const int min_nb = std::atoi(argv[5]);
    pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
    if (pcl::io::loadPCDFile<pcl::PointXYZ>(argv[1], *cloud) != 0) return 2;
    const std::size_t n = cloud->size();
    std::vector<uint32_t> nan_points;
    pcl::PointXYZ lo(INFINITY, INFINITY, INFINITY), hi(-INFINITY, -INFINITY, -INFINITY);
    for (std::size_t i = 0; i < n; i++) {
        const auto &p = (*cloud)[i];
        if (!pcl::isFinite(p)) {
            nan_points.push_back((uint32_t)i);
            continue;
        }
        lo.x = std::min(lo.x, p.x), lo.y = std::min(lo.y, p.y), lo.z = std::min(lo.z, p.z);
        hi.x = std::max(hi.x, p.x), hi.y = std::max(hi.y, p.y), hi.z = std::max(hi.z, p.z);
    }
    std::printf("%s: %zu points, %zu NaN\n", argv[1], n, nan_points.size());

    nbhd_points pts = {cloud->points.data(), n, 3, sizeof(pcl::PointXYZ), NBHD_SCALAR_TYPE_F32};
    nbhd_build_options bo = nbhd_build_options_default();
    bo.non_finite = NBHD_NON_FINITE_POLICY_SKIP;
    nbhd_tree *tree = nullptr;
    CHECK(nbhd_tree_build(&pts, &bo, &tree) == NBHD_STATUS_OK, "%s", nbhd_last_error_message());
    if (!tree) return 1;
    std::vector<uint32_t> kept(n);
    std::size_t count = 0;

    // CropBox: boxes whose faces pass through actual coordinates (points on the faces).
    for (int b = 0; b < 4; b++) {
        // two finite points, the next ones from a spread of starting indices
        std::size_t ia = (std::size_t)(b * 7919 + 11) % n, ic = (std::size_t)(b * 104729 + 5) % n;
        while (!pcl::isFinite((*cloud)[ia])) ia = (ia + 1) % n;
        while (!pcl::isFinite((*cloud)[ic])) ic = (ic + 1) % n;
        const auto &a = (*cloud)[ia];
        const auto &c = (*cloud)[ic];
        float bmin[3] = {std::min(a.x, c.x), std::min(a.y, c.y), std::min(a.z, c.z)};
        float bmax[3] = {std::max(a.x, c.x), std::max(a.y, c.y), std::max(a.z, c.z)};
        if (b == 3) bmin[2] = lo.z, bmax[2] = hi.z; // a full-depth slab
        pcl::CropBox<pcl::PointXYZ> crop;
        crop.setInputCloud(cloud);
        crop.setMin(Eigen::Vector4f(bmin[0], bmin[1], bmin[2], 1.0f));
        crop.setMax(Eigen::Vector4f(bmax[0], bmax[1], bmax[2], 1.0f));
        pcl::Indices pcl_in;
        crop.filter(pcl_in);
        std::sort(pcl_in.begin(), pcl_in.end());
        nbhd_status st = nbhd_tree_in_box(tree, bmin, bmax, kept.data(), n, &count);
        CHECK(st == NBHD_STATUS_OK, "%s", nbhd_last_error_message());
        std::vector<uint32_t> ours(kept.begin(), kept.begin() + count);
        std::size_t d = differences(ours, pcl_in);
        std::printf("  crop box %d: PCL %zu, nbhd %zu, differences %zu\n", b, pcl_in.size(),
                    ours.size(), d);
        CHECK(d == 0, "crop box %d", b);
    }

    // Statistical outlier removal on the unorganized view of the same points.
    pcl::PointCloud<pcl::PointXYZ>::Ptr flat(new pcl::PointCloud<pcl::PointXYZ>(*cloud));
    flat->width = (uint32_t)n;
    flat->height = 1;
    {
        pcl::StatisticalOutlierRemoval<pcl::PointXYZ> sor;
        sor.setInputCloud(flat);
        sor.setMeanK(k);
        sor.setStddevMulThresh(alpha);
        pcl::Indices pcl_kept;
        auto t = std::chrono::steady_clock::now();
        sor.filter(pcl_kept);
        double pcl_ms = ms_since(t);
        std::sort(pcl_kept.begin(), pcl_kept.end());
        t = std::chrono::steady_clock::now();
        nbhd_statistical_outlier_options o = nbhd_statistical_outlier_options_default();
        o.k = (size_t)k;
        o.std_ratio = alpha;
        nbhd_status st = nbhd_remove_statistical_outliers(tree, &o, kept.data(), n, &count,
                                                          nullptr);
        double ours_ms = ms_since(t);
        CHECK(st == NBHD_STATUS_OK, "%s", nbhd_last_error_message());
        // the bridge: PCL keeps the NaN points
        std::vector<uint32_t> ours(kept.begin(), kept.begin() + count);
        ours.insert(ours.end(), nan_points.begin(), nan_points.end());
        std::sort(ours.begin(), ours.end());
        std::size_t d = differences(ours, pcl_kept);
        std::printf("  statistical k %d alpha %.2f: PCL keeps %zu (NaN included) in %.1f ms, "
                    "nbhd %zu + %zu NaN in %.1f ms, differences %zu\n",
                    k, alpha, pcl_kept.size(), pcl_ms, (std::size_t)count, nan_points.size(),
                    ours_ms, d);
        CHECK(d == 0, "statistical outlier removal");
        CHECK(count < n - nan_points.size(), "something removed");
    }

    // Radius outlier removal: PCL's strict radius search (the cloud marked non-dense) against
    // nbhd's inclusive one at the largest float below the radius.
    {
        flat->is_dense = false;
        pcl::RadiusOutlierRemoval<pcl::PointXYZ> ror;
        ror.setInputCloud(flat);
        // Debian's PCL 1.13 is built with assertions, and KdTreeFLANN::radiusSearch asserts on
        // a NaN query point: PCL is asked about the finite points only (setIndices), which
        // leaves the NaN points out of its kept set, as nbhd does.
        pcl::IndicesPtr finite(new pcl::Indices);
        for (std::size_t i = 0, h = 0; i < n; i++) {
            if (h < nan_points.size() && nan_points[h] == i) {
                h++;
            } else {
                finite->push_back((int)i);
            }
        }
        ror.setIndices(finite);
        ror.setRadiusSearch(radius);
        ror.setMinNeighborsInRadius(min_nb);
        pcl::Indices pcl_kept;
        auto t = std::chrono::steady_clock::now();
        ror.filter(pcl_kept);
        double pcl_ms = ms_since(t);
        std::sort(pcl_kept.begin(), pcl_kept.end());
        double below = (double)std::nextafter(radius, 0.0f);
        t = std::chrono::steady_clock::now();
        nbhd_radius_outlier_options o = nbhd_radius_outlier_options_default();
        o.min_neighbors = (size_t)min_nb;
        nbhd_status st = nbhd_remove_radius_outliers(tree, below, &o, kept.data(), n, &count,
                                                     nullptr);
        double ours_ms = ms_since(t);
        CHECK(st == NBHD_STATUS_OK, "%s", nbhd_last_error_message());
        std::vector<uint32_t> ours(kept.begin(), kept.begin() + count);
        std::size_t d = differences(ours, pcl_kept);
        std::printf("  radius r %g m %d: PCL keeps %zu in %.1f ms, nbhd %zu in %.1f ms, "
                    "differences %zu\n",
                    radius, min_nb, pcl_kept.size(), pcl_ms, ours.size(), ours_ms, d);
        CHECK(d == 0, "radius outlier removal");
    }
    nbhd_tree_free(tree);
    std::printf("%s\n", failures == 0 ? "ok" : "FAILED");
    return failures == 0 ? 0 : 1;
}
