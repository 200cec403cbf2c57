// Prepares the inputs of the meshlabserver tests and checks the files meshlabserver saved
// after applying the nbhd filters (meshlab_plugin/tests/CMakeLists.txt runs it):
//
//   check_meshlab_output prepare DATA_DIR OUT_DIR
//       fandisk_clean.ply, fandisk_noisy.ply (Gaussian noise 0.3 x the mean edge length per
//       coordinate, seed 1, faces kept) and milk.ply (tests/data/pcl/milk.pcd, loaded with
//       PCL, as a point cloud without faces), all ASCII PLY.
//   check_meshlab_output normals IN OUT K           normals against pcl::NormalEstimation
//   check_meshlab_output curvatures IN OUT K         quality = nbhd's mean curvature, colours
//   check_meshlab_output smoothing CLEAN NOISY ISO ANISO   surface distance drops
//   check_meshlab_output same-as-c-abi IN OUT        MeshLab's default anisotropic run equals
//                                                     nbhd_smooth with the C ABI's defaults
//   check_meshlab_output same-as-c-abi-robust IN OUT  the same for nbhd_smooth_robust
//   check_meshlab_output robust CLEAN NOISY ROBUST ISO     sharp edges kept (vertices on them
//                                                         closer to the clean surface)
//
// Exit status 1 on any failed check (each printed with FAIL).
#include <nbhd.h>

#include "ply_ascii.hpp"
#include "surface_distance.hpp"

#include <pcl/features/normal_3d.h>
#include <pcl/io/pcd_io.h>
#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/point_types.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <random>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

int failures = 0;
void check(bool ok, const std::string& what)
{
    std::printf("  %s %s\n", ok ? "ok  " : "FAIL", what.c_str());
    if (!ok) ++failures;
}
template <typename... T>
std::string fmt(const char* f, T... t)
{
    char b[512];
    std::snprintf(b, sizeof b, f, t...);
    return b;
}

using plyio::Mesh;
using plyio::Tri;
using plyio::readObj;
using plyio::readPly;
using plyio::writePly;

examples::V3 P(const std::vector<float>& xyz, size_t i) { return {xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]}; }
examples::V3 cross(examples::V3 a, examples::V3 b)
{
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
examples::V3 unit(examples::V3 a)
{
    double l = std::sqrt(examples::dot(a, a));
    return l > 0 ? (1.0 / l) * a : a;
}

double meanEdge(const Mesh& m)
{
    double s = 0;
    for (const Tri& t : m.tris)
        for (int e = 0; e < 3; ++e) {
            examples::V3 d = P(m.xyz, t[e]) - P(m.xyz, t[(e + 1) % 3]);
            s += std::sqrt(examples::dot(d, d));
        }
    return s / (3.0 * m.tris.size());
}

double angleDeg(const float* a, const float* b, bool upToSign)
{
    double d = double(a[0]) * b[0] + double(a[1]) * b[1] + double(a[2]) * b[2];
    double la = std::sqrt(double(a[0]) * a[0] + double(a[1]) * a[1] + double(a[2]) * a[2]);
    double lb = std::sqrt(double(b[0]) * b[0] + double(b[1]) * b[1] + double(b[2]) * b[2]);
    double c = d / (la * lb);
    if (upToSign) c = std::fabs(c);
    return std::acos(std::min(1.0, std::max(-1.0, c))) * 180.0 / M_PI;
}

int prepare(const std::string& data, const std::string& out)
{
    Mesh clean = readObj(data + "/meshes/fandisk.obj");
    writePly(out + "/fandisk_clean.ply", clean);
    Mesh noisy = clean;
    const double e = meanEdge(clean);
    std::mt19937_64 rng(1);
    std::normal_distribution<double> g(0.0, 1.0);
    for (float& c : noisy.xyz) c = float(c + 0.3 * e * g(rng));
    writePly(out + "/fandisk_noisy.ply", noisy);
    pcl::PointCloud<pcl::PointXYZ> milk;
    if (pcl::io::loadPCDFile(data + "/pcl/milk.pcd", milk) != 0) throw std::runtime_error("cannot load milk.pcd");
    Mesh cloud;
    for (const auto& p : milk)
        if (std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)) cloud.xyz.insert(cloud.xyz.end(), {p.x, p.y, p.z});
    writePly(out + "/milk.ply", cloud);
    std::printf("prepared fandisk (%zu vertices, %zu faces, noise 0.3 x mean edge %.4g) and milk (%zu points) in %s\n",
                clean.n(), clean.tris.size(), e, cloud.n(), out.c_str());
    return 0;
}

// MeshLab's normals (k nearest others, epsilon far beyond the bounding box) against PCL's
// NormalEstimation with setKSearch(k + 1) (the vertex itself and its k nearest others): the
// same covariance. Vertices where the (k+1)-th nearest point ties with the next one may get a
// different neighbour from FLANN (nbhd keeps the smaller index), so the tight bound is on the others.
int normals(const std::string& inPath, const std::string& outPath, int k)
{
    Mesh in = readPly(inPath), out = readPly(outPath);
    check(out.n() == in.n(), fmt("MeshLab saved every vertex (%zu of %zu)", out.n(), in.n()));
    check(out.normals.size() == out.xyz.size(), "MeshLab saved vertex normals");
    if (failures) return 1;
    auto cloud = pcl::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
    for (size_t i = 0; i < in.n(); ++i) cloud->push_back(pcl::PointXYZ(in.xyz[3 * i], in.xyz[3 * i + 1], in.xyz[3 * i + 2]));
    pcl::NormalEstimation<pcl::PointXYZ, pcl::Normal> ne;
    ne.setInputCloud(cloud);
    auto tree = pcl::make_shared<pcl::search::KdTree<pcl::PointXYZ>>();
    ne.setSearchMethod(tree);
    ne.setKSearch(k + 1);
    pcl::PointCloud<pcl::Normal> pn;
    ne.compute(pn);
    pcl::KdTreeFLANN<pcl::PointXYZ> kd;
    kd.setInputCloud(cloud);
    double sum = 0, maxAll = 0, maxUntied = 0;
    size_t tied = 0, unit = 0;
    std::vector<int> idx;
    std::vector<float> d2;
    for (size_t i = 0; i < in.n(); ++i) {
        const float* a = &out.normals[3 * i];
        const float b[3] = {pn[i].normal_x, pn[i].normal_y, pn[i].normal_z};
        double len = std::sqrt(double(a[0]) * a[0] + double(a[1]) * a[1] + double(a[2]) * a[2]);
        unit += std::fabs(len - 1) < 1e-4;
        double ang = angleDeg(a, b, true);
        sum += ang;
        maxAll = std::max(maxAll, ang);
        kd.nearestKSearch(cloud->points[i], k + 2, idx, d2);
        if (d2.size() == size_t(k + 2) && d2[k] == d2[k + 1]) ++tied;
        else maxUntied = std::max(maxUntied, ang);
    }
    const double mean = sum / double(in.n());
    std::printf("normals of %s: %zu vertices, k = %d: angle to PCL mean %.3g deg, max %.3g deg; "
                "%zu vertices with a tie at the k-th neighbour, max without them %.3g deg\n",
                inPath.c_str(), in.n(), k, mean, maxAll, tied, maxUntied);
    check(unit == in.n(), "every normal has unit length");
    check(mean < 1.0, fmt("mean angle to PCL NormalEstimation %.3g deg < 1 deg", mean));
    check(maxUntied < 0.1, fmt("max angle without tied neighbourhoods %.3g deg < 0.1 deg", maxUntied));
    return failures ? 1 : 0;
}

// The plugin's curvature filter (mean curvature, consistent orientation, the k nearest others
// within an epsilon beyond the bounding box) against nbhd_estimate_curvatures called here with
// the same options, and the colour ramp.
int curvatures(const std::string& inPath, const std::string& outPath, int k)
{
    Mesh in = readPly(inPath), out = readPly(outPath);
    check(out.n() == in.n() && out.quality.size() == in.n() && out.colors.size() == in.n(),
          "MeshLab saved every vertex with quality and colour");
    if (failures) return 1;
    nbhd_points pts{in.xyz.data(), in.n(), 3, 0, NBHD_SCALAR_TYPE_F32};
    nbhd_smooth_options o = nbhd_smooth_options_default();
    o.k = size_t(k);
    o.epsilon = 1e6;
    o.epsilon_units = NBHD_UNITS_ABSOLUTE;
    o.orientation = NBHD_ORIENTATION_PROPAGATE;
    std::vector<nbhd_point_geometry> g(in.n());
    // The plugin hands nbhd doubles; MeshLab's vertices are floats, so these are the same values.
    std::vector<double> xyz(in.xyz.begin(), in.xyz.end());
    pts = nbhd_points{xyz.data(), in.n(), 3, 0, NBHD_SCALAR_TYPE_F64};
    if (nbhd_estimate_curvatures(&pts, &o, g.data(), nullptr) != NBHD_STATUS_OK) {
        check(false, std::string("nbhd_estimate_curvatures: ") + nbhd_last_error_message());
        return 1;
    }
    double maxDiff = 0, scale = 0, qmin = 1e300, qmax = -1e300, maxNormal = 0;
    for (size_t i = 0; i < in.n(); ++i) {
        scale = std::max(scale, std::fabs(g[i].mean_curvature));
        maxDiff = std::max(maxDiff, std::fabs(double(out.quality[i]) - g[i].mean_curvature));
        qmin = std::min(qmin, double(out.quality[i]));
        qmax = std::max(qmax, double(out.quality[i]));
        const float n[3] = {float(g[i].normal[0]), float(g[i].normal[1]), float(g[i].normal[2])};
        maxNormal = std::max(maxNormal, angleDeg(&out.normals[3 * i], n, false));
    }
    std::set<std::array<int, 3>> colours(out.colors.begin(), out.colors.end());
    std::printf("curvatures of %s: mean curvature in [%.4g, %.4g], max |MeshLab - nbhd| = %.3g (scale %.3g), "
                "normals within %.3g deg, %zu distinct colours\n",
                inPath.c_str(), qmin, qmax, maxDiff, scale, maxNormal, colours.size());
    check(maxDiff <= 1e-5 * scale, "quality = nbhd's mean curvature at every vertex (to ASCII precision)");
    check(maxNormal < 0.01, "normals = nbhd's oriented normals (same sign)");
    check(qmax > qmin, "mean curvature not constant");
    check(colours.size() > 100, "the colour ramp colours the vertices by quality");
    return failures ? 1 : 0;
}

double surfaceRms(const Mesh& clean, const Mesh& m)
{
    examples::SurfaceDistance s(clean.xyz, clean.tris);
    return s.stats(m.xyz.data(), m.n()).rms;
}

int smoothing(const std::string& c, const std::string& n, const std::string& iso, const std::string& aniso)
{
    Mesh clean = readPly(c), noisy = readPly(n), mi = readPly(iso), ma = readPly(aniso);
    check(mi.n() == clean.n() && ma.n() == clean.n() && mi.tris.size() == clean.tris.size(),
          "MeshLab saved every vertex and face");
    if (failures) return 1;
    const double e = meanEdge(clean);
    double before = surfaceRms(clean, noisy), ri = surfaceRms(clean, mi), ra = surfaceRms(clean, ma);
    std::printf("fandisk, noise 0.3 x mean edge: RMS distance to the clean surface %.4g e -> isotropic %.4g e (%.3f), "
                "anisotropic %.4g e (%.3f)\n", before / e, ri / e, ri / before, ra / e, ra / before);
    check(ri <= 0.9 * before, fmt("isotropic smoothing in MeshLab: ratio %.3f <= 0.9", ri / before));
    check(ra <= 0.9 * before, fmt("anisotropic smoothing in MeshLab: ratio %.3f <= 0.9", ra / before));
    return failures ? 1 : 0;
}

// MeshLab's anisotropic smoothing with the dialog's defaults is nbhd_smooth with
// nbhd_smooth_options_default() (plus the plugin's default consistent orientation, which only
// orients the output normals).
int sameAsCAbi(const std::string& inPath, const std::string& outPath, bool robust)
{
    Mesh in = readPly(inPath), out = readPly(outPath);
    check(out.n() == in.n(), "MeshLab saved every vertex");
    if (failures) return 1;
    std::vector<double> xyz(in.xyz.begin(), in.xyz.end()), res(xyz.size());
    nbhd_points pts{xyz.data(), in.n(), 3, 0, NBHD_SCALAR_TYPE_F64};
    nbhd_smooth_summary sum{};
    const nbhd_smooth_options o = nbhd_smooth_options_default();
    const nbhd_robust_options r = nbhd_robust_options_default();
    nbhd_status s = robust ? nbhd_smooth_robust(&pts, &r, res.data(), nullptr, &sum)
                           : nbhd_smooth(&pts, &o, res.data(), nullptr, &sum);
    if (s != NBHD_STATUS_OK) {
        check(false, std::string("nbhd: ") + nbhd_last_error_message());
        return 1;
    }
    double maxDiff = 0, moved = 0;
    for (size_t i = 0; i < xyz.size(); ++i) {
        maxDiff = std::max(maxDiff, std::fabs(double(out.xyz[i]) - double(float(res[i]))));
        moved = std::max(moved, std::fabs(res[i] - xyz[i]));
    }
    std::printf("%s: %zu points, h = %.4g; MeshLab vs %s(defaults): max coordinate difference %.3g h "
                "(points moved up to %.3g h)\n", inPath.c_str(), in.n(), sum.spacing,
                robust ? "nbhd_smooth_robust" : "nbhd_smooth", maxDiff / sum.spacing,
                moved / sum.spacing);
    check(moved > 0.01 * sum.spacing, "the defaults move the points");
    check(maxDiff <= 1e-4 * sum.spacing, "MeshLab's result = the C ABI's with its defaults (to ASCII precision)");
    return failures ? 1 : 0;
}

// Sharp edges of the clean mesh: interior edges whose two faces meet at more than 30 degrees;
// their vertices lie on fandisk's feature lines. Isotropic fairing rounds the edges, pulling
// those vertices off the surface; the robust filter must bring them closer to the clean
// surface than the noisy input and than isotropic fairing, over all vertices as well.
int robust(const std::string& c, const std::string& n, const std::string& r, const std::string& iso)
{
    Mesh clean = readPly(c), noisy = readPly(n), mr = readPly(r), mi = readPly(iso);
    check(mr.n() == clean.n() && mr.tris.size() == clean.tris.size(), "MeshLab saved every vertex and face");
    if (failures) return 1;
    auto faceNormal = [&](const Tri& t) {
        return unit(cross(P(clean.xyz, t[1]) - P(clean.xyz, t[0]), P(clean.xyz, t[2]) - P(clean.xyz, t[0])));
    };
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::vector<size_t>> edges;
    for (size_t f = 0; f < clean.tris.size(); ++f)
        for (int e = 0; e < 3; ++e) {
            auto a = clean.tris[f][e], b = clean.tris[f][(e + 1) % 3];
            edges[{std::min(a, b), std::max(a, b)}].push_back(f);
        }
    std::set<std::uint32_t> onEdge;
    size_t sharp = 0;
    for (const auto& kv : edges) {
        if (kv.second.size() != 2) continue;
        double d = examples::dot(faceNormal(clean.tris[kv.second[0]]), faceNormal(clean.tris[kv.second[1]]));
        if (std::acos(std::min(1.0, std::max(-1.0, d))) * 180.0 / M_PI <= 30) continue;
        ++sharp;
        onEdge.insert(kv.first.first);
        onEdge.insert(kv.first.second);
    }
    examples::SurfaceDistance surface(clean.xyz, clean.tris);
    auto edgeRms = [&](const Mesh& m) {
        std::vector<float> sel;
        for (auto i : onEdge) sel.insert(sel.end(), {m.xyz[3 * i], m.xyz[3 * i + 1], m.xyz[3 * i + 2]});
        return surface.stats(sel.data(), onEdge.size()).rms;
    };
    const double e = meanEdge(clean);
    const double eN = edgeRms(noisy), eR = edgeRms(mr), eI = edgeRms(mi);
    const double before = surfaceRms(clean, noisy), after = surfaceRms(clean, mr);
    std::printf("fandisk, %zu sharp edges (> 30 deg), %zu vertices on them: RMS distance to the clean surface there "
                "noisy %.4g e, robust %.4g e (%.3f), isotropic %.4g e (%.3f); all vertices: robust ratio %.3f\n",
                sharp, onEdge.size(), eN / e, eR / e, eR / eN, eI / e, eI / eN, after / before);
    check(sharp > 100, "fandisk has sharp edges");
    check(eR <= 0.9 * eN, fmt("robust smoothing brings the edge vertices closer to the surface: ratio %.3f <= 0.9", eR / eN));
    check(eR < eI, "robust smoothing keeps the sharp edges better than isotropic fairing");
    check(after <= 0.9 * before, fmt("robust smoothing lowers the surface distance: ratio %.3f <= 0.9", after / before));
    return failures ? 1 : 0;
}

}  // namespace

int main(int argc, char** argv)
{
    try {
        std::string cmd = argc > 1 ? argv[1] : "";
        if (cmd == "prepare" && argc == 4) return prepare(argv[2], argv[3]);
        if (cmd == "normals" && argc == 5) return normals(argv[2], argv[3], std::atoi(argv[4]));
        if (cmd == "curvatures" && argc == 5) return curvatures(argv[2], argv[3], std::atoi(argv[4]));
        if (cmd == "smoothing" && argc == 6) return smoothing(argv[2], argv[3], argv[4], argv[5]);
        if (cmd == "same-as-c-abi" && argc == 4) return sameAsCAbi(argv[2], argv[3], false);
        if (cmd == "same-as-c-abi-robust" && argc == 4) return sameAsCAbi(argv[2], argv[3], true);
        if (cmd == "robust" && argc == 6) return robust(argv[2], argv[3], argv[4], argv[5]);
        std::fprintf(stderr, "usage: see the top of check_meshlab_output.cpp\n");
        return 2;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "check_meshlab_output: %s\n", e.what());
        return 1;
    }
}
