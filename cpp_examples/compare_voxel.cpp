// Voxel-grid downsampling, nbhd against PCL on a scan loaded with PCL's own reader:
// pcl::VoxelGrid<PointXYZ> vs nbhd_voxel_grid on the same float points (16-byte stride).
//
// - Same voxels in the same order: PCL's output count equals nbhd's, and nbhd's nearest point
//   of voxel v lies in PCL's voxel v (PCL's leaf layout, getCentroidIndex).
// - Centroids: both sum in float and divide by the count as a float, but PCL sorts its
//   (voxel, point) pairs with an unstable sort, so its order of summation inside a voxel is
//   not defined; nbhd sums in ascending index. Each coordinate must agree within the rounding
//   bound of two summation orders, 2 (n - 1) u S / n + 2 u |c| (u = 2^-24, S the sum of the
//   absolute values of the voxel's n points); the share of bit-identical centroids is printed.
// - The nearest point of every voxel is checked by brute force over the voxel's points (PCL's
//   membership) against nbhd's centroid, ties by index.
// - NaN points: PCL skips them on a non-dense cloud, nbhd always.
//
//   compare_voxel SCAN.pcd LEAF [MIN_POINTS]
//
// Exits 0 when every check passed.
#include <nbhd.h>

#include <pcl/filters/voxel_grid.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <vector>

static int failures = 0;
#define CHECK(cond, ...)                                                                           \
    do {                                                                                           \
        if (!(cond)) {                                                                             \
            if (failures < 20) {                                                                   \
                std::fprintf(stderr, "check failed: %s: ", #cond);                                 \
                std::fprintf(stderr, __VA_ARGS__);                                                 \
                std::fprintf(stderr, "\n");                                                        \
            }                                                                                      \
            failures++;                                                                            \
        }                                                                                          \
    } while (0)

int main(int argc, char **argv) {
    if (argc < 3) {
        std::fprintf(stderr, "usage: compare_voxel SCAN.pcd LEAF [MIN_POINTS]\n");
        return 2;
    }
    const float leaf = std::strtof(argv[2], nullptr);
    const unsigned min_points = argc > 3 ? (unsigned)std::strtoul(argv[3], nullptr, 10) : 0;
    pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
    if (pcl::io::loadPCDFile(argv[1], *cloud) != 0) {
        std::fprintf(stderr, "cannot read %s\n", argv[1]);
        return 2;
    }
    // PCL skips NaN points only on a cloud marked not dense
    bool any_nan = false;
    for (const auto &p : *cloud) any_nan |= !std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z);
    if (any_nan) cloud->is_dense = false;
    cloud->height = 1;
    cloud->width = (std::uint32_t)cloud->size();

    pcl::VoxelGrid<pcl::PointXYZ> vg;
    vg.setInputCloud(cloud);
    vg.setLeafSize(leaf, leaf, leaf);
    vg.setMinimumPointsNumberPerVoxel(min_points);
    vg.setSaveLeafLayout(true);
    pcl::PointCloud<pcl::PointXYZ> out;
    vg.filter(out);

    nbhd_points pts;
    pts.data = cloud->points.data();
    pts.count = cloud->size();
    pts.dim = 3;
    pts.stride = sizeof(pcl::PointXYZ);
    pts.scalar_type = NBHD_SCALAR_TYPE_F32;
    const double l = leaf; // exactly the float PCL uses
    std::size_t count = 0;
    std::vector<double> cen(cloud->size() * 3);
    std::vector<uint32_t> nearest(cloud->size());
    nbhd_voxel_grid_options o = nbhd_voxel_grid_options_default();
    o.min_points_per_voxel = min_points;
    o.threads = 2;
    nbhd_status st = nbhd_voxel_grid(&pts, &l, 1, &o, cen.data(), nearest.data(), cloud->size(),
                                     &count);
    CHECK(st == NBHD_STATUS_OK, "status %d", (int)st);
    CHECK(count == out.size(), "nbhd %zu voxels, PCL %zu", count, out.size());
    if (st != NBHD_STATUS_OK || count != out.size()) {
        std::printf("compare_voxel %s: FAILED\n", argv[1]);
        return 1;
    }
    // PCL's membership of every finite point
    std::vector<std::vector<uint32_t>> members(count);
    for (std::size_t i = 0; i < cloud->size(); i++) {
        const auto &p = (*cloud)[i];
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) continue;
        int v = vg.getCentroidIndex(p);
        if (v >= 0) members[(std::size_t)v].push_back((uint32_t)i);
    }
    const double u = std::ldexp(1.0, -24);
    std::size_t identical = 0;
    for (std::size_t v = 0; v < count; v++) {
        const auto &m = members[v];
        CHECK(!m.empty(), "voxel %zu has no member", v);
        if (m.empty()) continue;
        const double n = (double)m.size();
        const float pc[3] = {out[v].x, out[v].y, out[v].z};
        bool same = true;
        for (int a = 0; a < 3; a++) {
            double s = 0.0;
            for (uint32_t i : m) s += std::fabs((double)(*cloud)[i].data[a]);
            const double c = cen[v * 3 + a];
            const double bound = 2.0 * (n - 1.0) * u * s / n + 2.0 * u * std::fabs(c);
            CHECK(std::fabs(c - (double)pc[a]) <= bound, "voxel %zu coordinate %d: nbhd %.9g PCL %.9g bound %.3g",
                  v, a, c, (double)pc[a], bound);
            same &= c == (double)pc[a];
        }
        identical += same;
        // nearest: brute force over PCL's members against nbhd's centroid, ties by index
        uint32_t best = m[0];
        double bd = INFINITY;
        for (uint32_t i : m) {
            double d2 = 0.0;
            for (int a = 0; a < 3; a++) {
                const double t = (double)(*cloud)[i].data[a] - cen[v * 3 + a];
                d2 += t * t;
            }
            if (d2 < bd) {
                bd = d2;
                best = i;
            }
        }
        CHECK(nearest[v] == best, "voxel %zu: nbhd nearest %u, brute force %u", v, nearest[v], best);
    }
    std::printf("compare_voxel %s leaf %g min %u: %zu points -> %zu voxels (PCL %zu), "
                "%zu centroids bit-identical, %d failures\n",
                argv[1], (double)leaf, min_points, cloud->size(), count, out.size(), identical,
                failures);
    return failures == 0 ? 0 : 1;
}
