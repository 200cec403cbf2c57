// Benchmark (not a test): nbhd's filters against PCL's on generated million-point clouds, one
// and two nbhd threads in the same run (PCL 1.13's filters are single-threaded).
//
//   bench_filters [--n N] [--reps R]
//
// Clouds: the torus and the uniform cube of bench_neighbors (same generator, float points).
// Rows (best of R runs, milliseconds; nbhd times include building its tree where it needs one,
// as PCL's filters build theirs):
// - SOR: pcl::StatisticalOutlierRemoval (k = 20, alpha = 1) vs nbhd_remove_statistical_outliers
// - ROR: pcl::RadiusOutlierRemoval (radius r, m = 4) vs nbhd_remove_radius_outliers
// - voxel: pcl::VoxelGrid vs nbhd_voxel_grid
// - boxes: 1000 boxes of 1 % of the bounding volume: nbhd_tree_in_boxes on a built tree vs a scan
//   over all points per box vs pcl::CropBox per box (nanoflann 1.4.2, Debian's, has no box
//   search). Tree build time listed separately.
// Kept/voxel counts are printed next to the times, PCL's and nbhd's (they must agree).
#include <nbhd.h>

#include <pcl/filters/crop_box.h>
#include <pcl/filters/radius_outlier_removal.h>
#include <pcl/filters/statistical_outlier_removal.h>
#include <pcl/filters/voxel_grid.h>
#include <pcl/point_types.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <random>
#include <string>
#include <vector>

using Clock = std::chrono::steady_clock;
static double ms_since(Clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}
static float unit(std::mt19937 &rng) { return static_cast<float>(rng() >> 8) * (1.0f / 16777216.0f); }

static pcl::PointCloud<pcl::PointXYZ>::Ptr torus(std::size_t n) {
    std::mt19937 rng(1);
    pcl::PointCloud<pcl::PointXYZ>::Ptr c(new pcl::PointCloud<pcl::PointXYZ>);
    const float R = 1.0f, r = 0.35f, tau = 6.28318530718f;
    for (std::size_t i = 0; i < n; ++i) {
        float u = tau * unit(rng), v = tau * unit(rng);
        c->push_back(pcl::PointXYZ((R + r * std::cos(v)) * std::cos(u), (R + r * std::cos(v)) * std::sin(u),
                                   r * std::sin(v)));
    }
    return c;
}
static pcl::PointCloud<pcl::PointXYZ>::Ptr cube(std::size_t n) {
    std::mt19937 rng(2);
    pcl::PointCloud<pcl::PointXYZ>::Ptr c(new pcl::PointCloud<pcl::PointXYZ>);
    for (std::size_t i = 0; i < n; ++i) {
        float x = unit(rng), y = unit(rng), z = unit(rng);
        c->push_back(pcl::PointXYZ(x, y, z));
    }
    return c;
}

static int reps = 3;
static double best(const std::function<void()> &f) {
    double b = 1e300;
    for (int i = 0; i < reps; i++) {
        auto t = Clock::now();
        f();
        b = std::min(b, ms_since(t));
    }
    return b;
}

static nbhd_points view(const pcl::PointCloud<pcl::PointXYZ> &c) {
    nbhd_points p;
    p.data = c.points.data();
    p.count = c.size();
    p.dim = 3;
    p.stride = sizeof(pcl::PointXYZ);
    p.scalar_type = NBHD_SCALAR_TYPE_F32;
    return p;
}

static nbhd_tree *build(const pcl::PointCloud<pcl::PointXYZ> &c, size_t threads) {
    nbhd_points p = view(c);
    nbhd_build_options o = nbhd_build_options_default();
    o.threads = threads;
    nbhd_tree *t = nullptr;
    if (nbhd_tree_build(&p, &o, &t) != NBHD_STATUS_OK) std::abort();
    return t;
}

static void run(const char *name, pcl::PointCloud<pcl::PointXYZ>::Ptr cloud, double radius, float leaf) {
    const std::size_t n = cloud->size();
    std::vector<uint32_t> kept(n);
    std::size_t count = 0, pcl_count = 0;
    std::printf("\n%s, %zu points\n", name, n);
    std::printf("| filter | PCL ms | nbhd 1 thread ms | nbhd 2 threads ms | PCL / nbhd-1 | PCL / nbhd-2 | PCL count | nbhd count |\n");
    std::printf("|---|---:|---:|---:|---:|---:|---:|---:|\n");
    auto row = [&](const char *what, double p, double a, double b) {
        std::printf("| %s | %.1f | %.1f | %.1f | %.2f | %.2f | %zu | %zu |\n", what, p, a, b, p / a, p / b,
                    pcl_count, count);
    };
    {
        pcl::StatisticalOutlierRemoval<pcl::PointXYZ> f;
        pcl::PointCloud<pcl::PointXYZ> out;
        double p = best([&] {
            f.setInputCloud(cloud);
            f.setMeanK(20);
            f.setStddevMulThresh(1.0);
            f.filter(out);
        });
        pcl_count = out.size();
        double t[2];
        for (size_t th = 1; th <= 2; th++)
            t[th - 1] = best([&] {
                nbhd_tree *tree = build(*cloud, th);
                nbhd_statistical_outlier_options o = nbhd_statistical_outlier_options_default();
                o.k = 20;
                o.std_ratio = 1.0;
                o.threads = th;
                if (nbhd_remove_statistical_outliers(tree, &o, kept.data(), n, &count, nullptr) != NBHD_STATUS_OK)
                    std::abort();
                nbhd_tree_free(tree);
            });
        row("SOR k=20 alpha=1", p, t[0], t[1]);
    }
    {
        pcl::RadiusOutlierRemoval<pcl::PointXYZ> f;
        pcl::PointCloud<pcl::PointXYZ> out;
        double p = best([&] {
            f.setInputCloud(cloud);
            f.setRadiusSearch(radius);
            f.setMinNeighborsInRadius(4);
            f.filter(out);
        });
        pcl_count = out.size();
        double t[2];
        for (size_t th = 1; th <= 2; th++)
            t[th - 1] = best([&] {
                nbhd_tree *tree = build(*cloud, th);
                nbhd_radius_outlier_options o = nbhd_radius_outlier_options_default();
                o.min_neighbors = 4;
                o.threads = th;
                if (nbhd_remove_radius_outliers(tree, radius, &o, kept.data(), n, &count, nullptr) != NBHD_STATUS_OK)
                    std::abort();
                nbhd_tree_free(tree);
            });
        char what[64];
        std::snprintf(what, sizeof what, "ROR r=%g m=4", radius);
        row(what, p, t[0], t[1]);
    }
    {
        pcl::VoxelGrid<pcl::PointXYZ> f;
        pcl::PointCloud<pcl::PointXYZ> out;
        double p = best([&] {
            f.setInputCloud(cloud);
            f.setLeafSize(leaf, leaf, leaf);
            f.filter(out);
        });
        pcl_count = out.size();
        std::vector<double> cen(3 * n);
        std::vector<uint32_t> near(n);
        nbhd_points pts = view(*cloud);
        const double l = leaf;
        double t[2];
        for (size_t th = 1; th <= 2; th++)
            t[th - 1] = best([&] {
                nbhd_voxel_grid_options o = nbhd_voxel_grid_options_default();
                o.threads = th;
                if (nbhd_voxel_grid(&pts, &l, 1, &o, cen.data(), near.data(), n, &count) != NBHD_STATUS_OK)
                    std::abort();
            });
        char what[64];
        std::snprintf(what, sizeof what, "voxel leaf=%g", (double)leaf);
        row(what, p, t[0], t[1]);
    }
    {
        // 1000 boxes of 1 % of the bounding volume (edge 0.2154 of the box's edges)
        pcl::PointXYZ lo(1e30f, 1e30f, 1e30f), hi(-1e30f, -1e30f, -1e30f);
        for (const auto &q : *cloud) {
            lo.x = std::min(lo.x, q.x); lo.y = std::min(lo.y, q.y); lo.z = std::min(lo.z, q.z);
            hi.x = std::max(hi.x, q.x); hi.y = std::max(hi.y, q.y); hi.z = std::max(hi.z, q.z);
        }
        const int B = 1000;
        std::mt19937 rng(3);
        std::vector<float> boxes(B * 6);
        const float e = 0.2154f;
        for (int b = 0; b < B; b++) {
            float ext[3] = {hi.x - lo.x, hi.y - lo.y, hi.z - lo.z}, l0[3] = {lo.x, lo.y, lo.z};
            for (int a = 0; a < 3; a++) {
                float s = l0[a] + unit(rng) * ext[a] * (1 - e);
                boxes[b * 6 + a] = s;
                boxes[b * 6 + 3 + a] = s + e * ext[a];
            }
        }
        std::size_t scan_total = 0, crop_total = 0, total = 0;
        double scan = best([&] {
            scan_total = 0;
            for (int b = 0; b < B; b++) {
                const float *m = &boxes[b * 6];
                for (const auto &q : *cloud)
                    scan_total += m[0] <= q.x && q.x <= m[3] && m[1] <= q.y && q.y <= m[4] && m[2] <= q.z && q.z <= m[5];
            }
        });
        int saved = reps;
        reps = 1; // CropBox scans every point per box: one run
        double crop = best([&] {
            crop_total = 0;
            pcl::CropBox<pcl::PointXYZ> f;
            f.setInputCloud(cloud);
            pcl::Indices idx;
            for (int b = 0; b < B; b++) {
                const float *m = &boxes[b * 6];
                f.setMin(Eigen::Vector4f(m[0], m[1], m[2], 1.0f));
                f.setMax(Eigen::Vector4f(m[3], m[4], m[5], 1.0f));
                f.filter(idx);
                crop_total += idx.size();
            }
        });
        reps = saved;
        std::vector<size_t> offsets(B + 1);
        double t[2], bt[2];
        for (size_t th = 1; th <= 2; th++) {
            nbhd_tree *tree = nullptr;
            bt[th - 1] = best([&] {
                if (tree) nbhd_tree_free(tree);
                tree = build(*cloud, th);
            });
            size_t cap = 0;
            nbhd_box_options o = nbhd_box_options_default();
            o.threads = th;
            nbhd_tree_in_boxes(tree, boxes.data(), B, &o, offsets.data(), nullptr, 0, &cap);
            std::vector<uint32_t> idx(cap);
            t[th - 1] = best([&] {
                if (nbhd_tree_in_boxes(tree, boxes.data(), B, &o, offsets.data(), idx.data(), cap, &total) != NBHD_STATUS_OK)
                    std::abort();
            });
            nbhd_tree_free(tree);
        }
        std::printf("\n| 1000 boxes, 1 %% volume | ms | / nbhd-1 | points found |\n|---|---:|---:|---:|\n");
        std::printf("| nbhd_tree_in_boxes, 1 thread (tree built: %.1f ms) | %.1f | 1.00 | %zu |\n", bt[0], t[0], total);
        std::printf("| nbhd_tree_in_boxes, 2 threads (tree built: %.1f ms) | %.1f | %.2f | %zu |\n", bt[1], t[1], t[1] / t[0], total);
        std::printf("| scan over all points | %.1f | %.1f | %zu |\n", scan, scan / t[0], scan_total);
        std::printf("| pcl::CropBox per box | %.1f | %.1f | %zu |\n", crop, crop / t[0], crop_total);
    }
}

int main(int argc, char **argv) {
    std::size_t n = 1000000;
    for (int i = 1; i + 1 < argc; i += 2) {
        if (!std::strcmp(argv[i], "--n")) n = std::strtoul(argv[i + 1], nullptr, 10);
        else if (!std::strcmp(argv[i], "--reps")) reps = std::atoi(argv[i + 1]);
    }
    // radius about 3 spacings: torus area 4 pi^2 R r = 13.8, cube spacing n^(-1/3)
    const double h_torus = std::sqrt(13.8 / (double)n), h_cube = std::cbrt(1.0 / (double)n);
    run("torus", torus(n), 3 * h_torus, (float)(3 * h_torus));
    run("uniform cube", cube(n), 3 * h_cube, (float)(3 * h_cube));
    return 0;
}
