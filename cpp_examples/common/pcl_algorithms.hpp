// PCL's own algorithms run with a search backend given by the caller (pcl::search::KdTree,
// pcl::search::Octree or nbhd::PclSearch): shared by test_pcl_backend (outputs compared) and
// bench_pcl_backend (times compared). Each runner takes the cloud (NaN holes allowed), the
// indices of its finite points, the spacing h and a factory of fresh search objects, and
// returns PCL's output.
#pragma once

#include <pcl/features/fpfh_omp.h>
#include <pcl/features/normal_3d.h>
#include <pcl/features/normal_3d_omp.h>
#include <pcl/filters/filter.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>
#include <pcl/search/search.h>
#include <pcl/segmentation/extract_clusters.h>
#include <pcl/segmentation/region_growing.h>
#include <pcl/surface/mls.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <memory>
#include <random>
#include <string>
#include <vector>

namespace pclalg {

using Cloud = pcl::PointCloud<pcl::PointXYZ>;
using Search = pcl::search::Search<pcl::PointXYZ>;
using MakeSearch = std::function<Search::Ptr()>;

/// A cloud with its finite points and its mean nearest-neighbour distance h.
struct Input {
    std::string name;
    Cloud::Ptr cloud;
    pcl::IndicesPtr finite;
    double h = 0;
};

inline Input make_input(std::string name, Cloud::Ptr cloud) {
    Input in;
    in.name = std::move(name);
    in.cloud = cloud;
    in.finite.reset(new pcl::Indices);
    for (std::size_t i = 0; i < cloud->size(); ++i) {
        const auto& p = (*cloud)[i];
        if (std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z))
            in.finite->push_back(static_cast<pcl::index_t>(i));
    }
    pcl::search::KdTree<pcl::PointXYZ> kd;
    kd.setInputCloud(cloud, in.finite);
    pcl::Indices idx;
    std::vector<float> d;
    double sum = 0;
    std::size_t n = 0;
    for (pcl::index_t i : *in.finite) {
        if (kd.nearestKSearch((*cloud)[i], 2, idx, d) == 2) {
            sum += std::sqrt(static_cast<double>(d[1]));
            ++n;
        }
    }
    in.h = n ? sum / static_cast<double>(n) : 1.0;
    return in;
}

/// A torus (R = 1, r = 0.35) of n points, uniform by area, from std::mt19937(seed) bits.
inline Cloud::Ptr torus(std::size_t n, unsigned seed = 1) {
    std::mt19937 rng(seed);
    auto unit = [&] { return static_cast<float>(rng() >> 8) * (1.0f / 16777216.0f); };
    Cloud::Ptr c(new Cloud);
    const float R = 1.0f, r = 0.35f, two_pi = 6.2831853f;
    while (c->size() < n) {
        float u = unit() * two_pi, v = unit() * two_pi, w = unit();
        // accept by the area element (R + r cos v) / (R + r)
        if (w * (R + r) > R + r * std::cos(v)) continue;
        c->push_back(pcl::PointXYZ((R + r * std::cos(v)) * std::cos(u),
                                   (R + r * std::cos(v)) * std::sin(u), r * std::sin(v)));
    }
    c->width = static_cast<std::uint32_t>(c->size());
    c->height = 1;
    c->is_dense = true;
    return c;
}

/// The w × h window of an organized cloud starting at (col0, row0), kept organized.
inline Cloud::Ptr crop(const Cloud& c, std::uint32_t col0, std::uint32_t row0, std::uint32_t w,
                       std::uint32_t h) {
    Cloud::Ptr out(new Cloud);
    for (std::uint32_t r = row0; r < row0 + h && r < c.height; ++r)
        for (std::uint32_t q = col0; q < col0 + w && q < c.width; ++q)
            out->push_back(c.at(q, r));
    out->width = std::min(w, c.width - col0);
    out->height = static_cast<std::uint32_t>(out->size() / out->width);
    out->is_dense = false;
    return out;
}

using Normals = pcl::PointCloud<pcl::Normal>;

/// NormalEstimation (threads == 1) or NormalEstimationOMP, k nearest (k > 0) or radius r.
inline Normals normals(const Input& in, const MakeSearch& make, int k, double r, int threads) {
    Normals out;
    if (threads == 1) {
        pcl::NormalEstimation<pcl::PointXYZ, pcl::Normal> ne;
        ne.setInputCloud(in.cloud);
        ne.setSearchMethod(make());
        if (k > 0) ne.setKSearch(k); else ne.setRadiusSearch(r);
        ne.compute(out);
    } else {
        pcl::NormalEstimationOMP<pcl::PointXYZ, pcl::Normal> ne(threads);
        ne.setInputCloud(in.cloud);
        ne.setSearchMethod(make());
        if (k > 0) ne.setKSearch(k); else ne.setRadiusSearch(r);
        ne.compute(out);
    }
    return out;
}

/// MovingLeastSquares, radius r, polynomial order 2, positions only, over the finite points.
inline Cloud mls(const Input& in, const MakeSearch& make, double r, int threads) {
    pcl::MovingLeastSquares<pcl::PointXYZ, pcl::PointXYZ> m;
    m.setInputCloud(in.cloud);
    m.setIndices(in.finite);
    m.setSearchMethod(make());
    m.setSearchRadius(r);
    m.setPolynomialOrder(2);
    m.setComputeNormals(false);
    m.setNumberOfThreads(static_cast<unsigned>(threads));
    Cloud out;
    m.process(out);
    return out;
}

/// EuclideanClusterExtraction with tolerance t over the finite points (clusters of >= 1 point),
/// each cluster's indices sorted, clusters sorted.
inline std::vector<std::vector<pcl::index_t>> clusters(const Input& in, const MakeSearch& make,
                                                       double t) {
    pcl::EuclideanClusterExtraction<pcl::PointXYZ> ec;
    ec.setInputCloud(in.cloud);
    ec.setIndices(in.finite);
    ec.setSearchMethod(make());
    ec.setClusterTolerance(t);
    ec.setMinClusterSize(1);
    ec.setMaxClusterSize(std::numeric_limits<int>::max());
    std::vector<pcl::PointIndices> found;
    ec.extract(found);
    std::vector<std::vector<pcl::index_t>> out;
    for (auto& c : found) {
        std::sort(c.indices.begin(), c.indices.end());
        out.push_back(c.indices);
    }
    std::sort(out.begin(), out.end());
    return out;
}

/// RegionGrowing with k neighbours on the given normals (min region 30 points, PCL's default
/// thresholds), regions sorted as in clusters().
inline std::vector<std::vector<pcl::index_t>> regions(const Input& in, const Normals::Ptr& n,
                                                      const MakeSearch& make, int k) {
    pcl::RegionGrowing<pcl::PointXYZ, pcl::Normal> rg;
    rg.setInputCloud(in.cloud);
    rg.setIndices(in.finite);
    rg.setInputNormals(n);
    rg.setSearchMethod(make());
    rg.setNumberOfNeighbours(k);
    rg.setMinClusterSize(30);
    rg.setSmoothnessThreshold(static_cast<float>(5.0 / 180.0 * M_PI));
    rg.setCurvatureThreshold(0.05f);
    std::vector<pcl::PointIndices> found;
    rg.extract(found);
    std::vector<std::vector<pcl::index_t>> out;
    for (auto& c : found) {
        std::sort(c.indices.begin(), c.indices.end());
        out.push_back(c.indices);
    }
    std::sort(out.begin(), out.end());
    return out;
}

/// FPFHEstimation(OMP) with radius r on the given normals, at the finite points.
inline pcl::PointCloud<pcl::FPFHSignature33> fpfh(const Input& in, const Normals::Ptr& n,
                                                  const MakeSearch& make, double r, int threads) {
    pcl::FPFHEstimationOMP<pcl::PointXYZ, pcl::Normal, pcl::FPFHSignature33> f(threads);
    f.setInputCloud(in.cloud);
    f.setIndices(in.finite);
    f.setInputNormals(n);
    f.setSearchMethod(make());
    f.setRadiusSearch(r);
    pcl::PointCloud<pcl::FPFHSignature33> out;
    f.compute(out);
    return out;
}

inline double seconds_since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace pclalg
