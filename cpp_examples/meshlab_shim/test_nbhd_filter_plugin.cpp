// Applies each filter of the MeshLab-style shim to a mesh loaded with OpenMesh (ctest: fandisk.obj)
// and checks the results:
//   - the plugin's lists: four filters, names, the thesis in every filterInfo, defaults in range;
//   - normals: unit length, and equal up to sign to PCL's pcl::NormalEstimation on the same points
//     with the same neighbourhoods (see pcl_normals): mean angle below 1 degree over all
//     vertices, and below 0.1 degree at every vertex whose k-th neighbour is not tied;
//   - curvatures: finite, not constant, their normals equal to the normal filter's up to sign;
//   - isotropic and anisotropic smoothing: Gaussian noise (0.3 x mean edge length per coordinate,
//     seed 1) added to the vertices, the RMS distance to the clean surface must drop to at most
//     0.9 of the noisy one; the shim's anisotropic defaults must give exactly nbhd_smooth's
//     default result;
//   - progress: every filter's callback sees fractions in [0, 1], non-decreasing, ending at 1;
//     returning false cancels (NBHD_STATUS_CANCELLED, mesh unchanged); a throwing callback's
//     exception comes out of applyFilter;
//   - bad parameters (k = 0, k = -3, epsilon < 0, lambda = 0, a missing parameter, an enum index
//     out of range) throw nbhd_filter_error with the right status and a message naming the
//     parameter, and leave the mesh unchanged.
// Prints what it measured; exits 1 if any check fails.
//
//   test_nbhd_filter_plugin MESH
#include "nbhd_filter_plugin.hpp"
#include "surface_distance.hpp"

#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <pcl/features/normal_3d.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <random>
#include <set>
#include <string>
#include <vector>

using nbhd_meshlab::nbhd_filter_error;
using nbhd_meshlab::NbhdFilterPlugin;
using nbhd_meshlab::RichParameter;
using nbhd_meshlab::RichParameterList;
using nbhd_meshlab::VertexArray;

namespace {

int failures = 0;

void check(bool ok, const std::string& what) {
    std::printf("%s %s\n", ok ? "  ok  " : "  FAIL", what.c_str());
    if (!ok) ++failures;
}

std::string fmt(const char* f, double a, double b = 0, double c = 0, double d = 0) {
    char buf[256];
    std::snprintf(buf, sizeof buf, f, a, b, c, d);
    return buf;
}

struct Loaded {
    VertexArray mesh;
    std::vector<std::array<std::uint32_t, 3>> tris;
    double mean_edge = 0;
};

Loaded load(const std::string& path) {
    using Mesh = OpenMesh::TriMesh_ArrayKernelT<>;
    Mesh m;
    if (!OpenMesh::IO::read_mesh(m, path)) throw std::runtime_error("OpenMesh cannot read " + path);
    Loaded l;
    const float* p = m.points()->data();
    l.mesh.xyz.assign(p, p + 3 * m.n_vertices());
    for (auto f : m.faces()) {
        std::array<std::uint32_t, 3> t{};
        int j = 0;
        for (auto v : f.vertices()) t[j++] = std::uint32_t(v.idx());
        l.tris.push_back(t);
    }
    double sum = 0;
    for (auto e : m.edges()) sum += m.calc_edge_length(e);
    l.mean_edge = sum / double(m.n_edges());
    return l;
}

bool all_unit(const std::vector<float>& n, double tol, double* worst) {
    *worst = 0;
    for (std::size_t i = 0; i + 2 < n.size(); i += 3) {
        double len = std::sqrt(double(n[i]) * n[i] + double(n[i + 1]) * n[i + 1] + double(n[i + 2]) * n[i + 2]);
        *worst = std::max(*worst, std::fabs(len - 1));
    }
    return *worst <= tol;
}

// Unsigned angle in degrees between two (unit) normals.
double angle_deg(const float* a, const float* b) {
    double d = double(a[0]) * b[0] + double(a[1]) * b[1] + double(a[2]) * b[2];
    double la = std::sqrt(double(a[0]) * a[0] + double(a[1]) * a[1] + double(a[2]) * a[2]);
    double lb = std::sqrt(double(b[0]) * b[0] + double(b[1]) * b[1] + double(b[2]) * b[2]);
    return std::acos(std::min(1.0, std::fabs(d) / (la * lb))) * 180.0 / M_PI;
}

struct AngleStats {
    double mean = 0, p99 = 0, max = 0;
    std::size_t over1 = 0, skipped = 0;
};

AngleStats angles(const std::vector<float>& a, const std::vector<float>& b) {
    std::vector<double> v;
    AngleStats s;
    for (std::size_t i = 0; i + 2 < a.size(); i += 3) {
        if (!std::isfinite(b[i]) || !std::isfinite(b[i + 1]) || !std::isfinite(b[i + 2])) {
            ++s.skipped;
            continue;
        }
        v.push_back(angle_deg(&a[i], &b[i]));
    }
    for (double x : v) {
        s.mean += x;
        s.max = std::max(s.max, x);
        if (x > 1) ++s.over1;
    }
    if (!v.empty()) {
        s.mean /= double(v.size());
        std::sort(v.begin(), v.end());
        s.p99 = v[std::size_t(0.99 * double(v.size() - 1))];
    }
    return s;
}

// PCL's normals of the same points: pcl::NormalEstimation over the k + 1 nearest points of each
// vertex, found by PCL's own kd-tree. PCL's query point is the vertex itself, which its kNN
// returns as its own nearest neighbour, so its neighbourhood is the vertex and its k nearest
// others; nbhd's normal (thesis eq. 2.8-2.10) is the covariance of the vertex and its
// eps-k-neighbourhood, the k nearest *other* points within eps. With eps far beyond the mesh
// (epsilon_absolute, 10 x the bounding box diagonal) the radius never cuts, and both take the
// covariance of the same k + 1 points about their centroid. The sets can still differ where
// several points tie for the k-th distance (nbhd keeps the smallest indices, PCL's FLANN any),
// and PCL accumulates the covariance in float where nbhd uses double, which matters where the
// two smallest eigenvalues nearly coincide (corners, where the normal is ill-defined anyway).
std::vector<float> pcl_normals(const std::vector<float>& xyz, int k_plus_self) {
    auto cloud = std::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
    for (std::size_t i = 0; i + 2 < xyz.size(); i += 3) cloud->push_back(pcl::PointXYZ(xyz[i], xyz[i + 1], xyz[i + 2]));
    pcl::NormalEstimation<pcl::PointXYZ, pcl::Normal> ne;
    ne.setInputCloud(cloud);
    ne.setSearchMethod(std::make_shared<pcl::search::KdTree<pcl::PointXYZ>>());
    ne.setKSearch(k_plus_self);
    pcl::PointCloud<pcl::Normal> out;
    ne.compute(out);
    std::vector<float> n;
    for (const auto& p : out) {
        n.push_back(p.normal_x);
        n.push_back(p.normal_y);
        n.push_back(p.normal_z);
    }
    return n;
}

double bbox_diagonal(const std::vector<float>& xyz) {
    float lo[3] = {xyz[0], xyz[1], xyz[2]}, hi[3] = {xyz[0], xyz[1], xyz[2]};
    for (std::size_t i = 0; i < xyz.size(); ++i) {
        lo[i % 3] = std::min(lo[i % 3], xyz[i]);
        hi[i % 3] = std::max(hi[i % 3], xyz[i]);
    }
    double d = 0;
    for (int j = 0; j < 3; ++j) d += double(hi[j] - lo[j]) * (hi[j] - lo[j]);
    return std::sqrt(d);
}

// Progress as a filter reports it.
struct Recorder {
    std::vector<double> fractions;
    std::set<std::string> stages;
    NbhdFilterPlugin::ProgressCallback callback() {
        return [this](double f, const char* stage) {
            fractions.push_back(f);
            stages.insert(stage);
            return true;
        };
    }
    void verify(const std::string& filter) const {
        bool in_range = true, monotone = true;
        for (std::size_t i = 0; i < fractions.size(); ++i) {
            in_range = in_range && fractions[i] >= 0 && fractions[i] <= 1;
            if (i) monotone = monotone && fractions[i] >= fractions[i - 1];
        }
        check(!fractions.empty() && in_range && monotone && fractions.back() == 1.0,
              filter + ": progress called " + std::to_string(fractions.size()) +
                  " times, in [0, 1], non-decreasing, last " +
                  (fractions.empty() ? std::string("-") : fmt("%.6g", fractions.back())) +
                  " (stages: " + std::to_string(stages.size()) + ")");
    }
};

// Expects applyFilter to throw nbhd_filter_error with `status` and a message containing `needle`,
// and the mesh to be unchanged.
void expect_error(const NbhdFilterPlugin& plugin, NbhdFilterPlugin::FilterId id, VertexArray mesh,
                  const RichParameterList& params, nbhd_status status, const std::string& needle,
                  const std::string& what) {
    const VertexArray before = mesh;
    try {
        plugin.applyFilter(id, mesh, params);
        check(false, what + ": no exception");
    } catch (const nbhd_filter_error& e) {
        bool unchanged = mesh.xyz == before.xyz && mesh.normals == before.normals && mesh.quality == before.quality;
        check(e.status() == status && std::string(e.what()).find(needle) != std::string::npos && unchanged,
              what + ": nbhd_filter_error " + nbhd_status_string(e.status()) + ", mesh " +
                  (unchanged ? "unchanged" : "CHANGED") + ": \"" + e.what() + "\"");
    } catch (const std::exception& e) {
        check(false, what + ": wrong exception type: " + e.what());
    }
}

}  // namespace

int main(int argc, char** argv) try {
    if (argc != 2) {
        std::fprintf(stderr, "usage: test_nbhd_filter_plugin MESH\n");
        return 2;
    }
    const Loaded clean = load(argv[1]);
    const std::size_t n = clean.mesh.size();
    std::printf("%s: %zu vertices, %zu triangles, mean edge length %.6g\n", argv[1], n, clean.tris.size(),
                clean.mean_edge);
    NbhdFilterPlugin plugin;

    std::printf("== the plugin's lists\n");
    {
        std::set<std::string> names;
        bool info = true, ranges = true, enums = true;
        for (auto id : plugin.types()) {
            names.insert(plugin.filterName(id));
            info = info && plugin.filterInfo(id).find("Neighborhood Computation of Point Set Surfaces") != std::string::npos;
            const RichParameterList list = plugin.initParameterList(id);
            for (const RichParameter& p : list.parameters()) {
                ranges = ranges && p.min <= p.default_value && p.default_value <= p.max && p.value == p.default_value &&
                         !p.description.empty();
                if (p.type == RichParameter::Type::Enum)
                    enums = enums && double(p.choices.size()) == p.max + 1;
            }
        }
        check(plugin.types().size() == 4 && names.size() == 4, "four filters with distinct names");
        check(info, "every filterInfo cites the thesis");
        check(ranges && enums, "every parameter has a description and its default within [min, max]");
    }

    std::printf("== compute normals vs pcl::NormalEstimation\n");
    const std::size_t k = 15;
    std::vector<float> normals_exact;
    {
        VertexArray m = clean.mesh;
        RichParameterList p = plugin.initParameterList(NbhdFilterPlugin::FP_COMPUTE_NORMALS);
        p.set("k", double(k));
        p.set("epsilon", 10 * bbox_diagonal(m.xyz));
        p.set("epsilon_absolute", 1);
        Recorder rec;
        auto out = plugin.applyFilter(NbhdFilterPlugin::FP_COMPUTE_NORMALS, m, p, rec.callback());
        rec.verify("normals");
        double worst = 0;
        check(m.normals.size() == 3 * n && all_unit(m.normals, 1e-5, &worst),
              fmt("normals unit length (largest | |n| - 1 | = %.2g)", worst));
        check(m.xyz == clean.mesh.xyz, "normals leave the vertices alone");
        normals_exact = m.normals;

        std::vector<float> pcl = pcl_normals(clean.mesh.xyz, int(k) + 1);
        AngleStats a = angles(m.normals, pcl);
        std::printf("  nbhd k = %zu others, eps = 10 x bbox diagonal; PCL setKSearch(%zu): mean %.3g deg, "
                    "99th percentile %.3g deg, max %.3g deg, %zu vertices over 1 deg, %zu PCL normals NaN, "
                    "%g degenerate nbhd normals\n",
                    k, k + 1, a.mean, a.p99, a.max, a.over1, a.skipped, out["degenerate_normals"]);
        check(a.skipped == 0 && a.mean < 1.0, fmt("mean angle to PCL's normals %.3g deg < 1 deg", a.mean));

        // Where no other point ties with the k-th nearest, both neighbourhoods are the same set of
        // points and the normals must agree to float precision; the vertices with a tie may take
        // different points (fandisk has exact ties on its regular patches).
        nbhd_build_options bo = nbhd_build_options_default();
        nbhdpp::Tree tree = nbhdpp::build(nbhdpp::points_f32(clean.mesh.xyz.data(), n, 12), bo);
        nbhdpp::Result r;
        std::vector<float> mine, theirs;
        std::size_t ties = 0;
        for (std::size_t i = 0; i < n; ++i) {
            nbhdpp::knn_index(tree.get(), i, true, k + 1, r);
            if (r.size() > k && r.sq[k - 1] == r.sq[k]) {
                ++ties;
                continue;
            }
            mine.insert(mine.end(), &m.normals[3 * i], &m.normals[3 * i] + 3);
            theirs.insert(theirs.end(), &pcl[3 * i], &pcl[3 * i] + 3);
        }
        AngleStats u = angles(mine, theirs);
        std::printf("  %zu vertices with a tie at the k-th distance left out: max %.3g deg, mean %.3g deg over "
                    "the other %zu\n",
                    ties, u.max, u.mean, mine.size() / 3);
        check(u.skipped == 0 && u.max < 0.1, fmt("without ties every normal within 0.1 deg of PCL's (max %.3g deg)", u.max));

        // For reference: nbhd's default neighbourhoods (15 others within 6h) against the same PCL run
        // (the same where 6h holds the 15 nearest, as it does everywhere on fandisk).
        VertexArray d = clean.mesh;
        plugin.applyFilter(NbhdFilterPlugin::FP_COMPUTE_NORMALS, d,
                           plugin.initParameterList(NbhdFilterPlugin::FP_COMPUTE_NORMALS));
        AngleStats b = angles(d.normals, pcl);
        std::printf("  (reference) nbhd defaults, 15 others within 6h: mean %.3g deg, max %.3g deg to PCL\n",
                    b.mean, b.max);
    }

    std::printf("== compute curvatures\n");
    {
        VertexArray m = clean.mesh;
        RichParameterList p = plugin.initParameterList(NbhdFilterPlugin::FP_COMPUTE_CURVATURES);
        p.set("k", double(k));
        p.set("epsilon", 10 * bbox_diagonal(m.xyz));
        p.set("epsilon_absolute", 1);
        Recorder rec;
        auto out = plugin.applyFilter(NbhdFilterPlugin::FP_COMPUTE_CURVATURES, m, p, rec.callback());
        rec.verify("curvatures");
        bool finite = m.quality.size() == n &&
                      std::all_of(m.quality.begin(), m.quality.end(), [](float q) { return std::isfinite(q); });
        check(finite, "mean curvature finite at every vertex");
        check(out["quality_max"] > out["quality_min"],
              fmt("mean curvature not constant: [%.4g, %.4g]", out["quality_min"], out["quality_max"]));
        AngleStats a = angles(m.normals, normals_exact);
        check(a.max < 1e-3, fmt("its normals equal the normal filter's up to sign (max %.2g deg)", a.max));

        p.setEnum("quality", "max_principal");
        plugin.applyFilter(NbhdFilterPlugin::FP_COMPUTE_CURVATURES, m, p);
        bool nonneg = std::all_of(m.quality.begin(), m.quality.end(), [](float q) { return std::isfinite(q) && q >= 0; });
        std::vector<float> s = m.quality;
        std::sort(s.begin(), s.end());
        std::printf("  max principal curvature: median %.4g, 90th percentile %.4g, max %.4g (1/units)\n",
                    s[s.size() / 2], s[s.size() * 9 / 10], s.back());
        check(nonneg, "max principal curvature finite and >= 0");
    }

    std::printf("== smoothing (noise 0.3 x mean edge length per coordinate, seed 1)\n");
    VertexArray noisy = clean.mesh;
    {
        std::mt19937_64 rng(1);
        std::normal_distribution<double> g(0.0, 1.0);
        for (float& c : noisy.xyz) c = float(c + 0.3 * clean.mean_edge * g(rng));
    }
    examples::SurfaceDistance surface(clean.mesh.xyz, clean.tris);
    const double before = surface.stats(noisy.xyz.data(), n).rms;
    for (auto id : {NbhdFilterPlugin::FP_ISOTROPIC_SMOOTHING, NbhdFilterPlugin::FP_ANISOTROPIC_SMOOTHING}) {
        VertexArray m = noisy;
        Recorder rec;
        auto out = plugin.applyFilter(id, m, plugin.initParameterList(id), rec.callback());
        const std::string name = id == NbhdFilterPlugin::FP_ISOTROPIC_SMOOTHING ? "isotropic" : "anisotropic";
        rec.verify(name);
        const double after = surface.stats(m.xyz.data(), n).rms;
        std::printf("  %s: h = %.4g, eps = %.4g, min neighbours %g; surface RMS %.4g -> %.4g (%.4g mean edge "
                    "lengths -> %.4g)\n",
                    name.c_str(), out["spacing"], out["epsilon"], out["min_neighbors"], before, after,
                    before / clean.mean_edge, after / clean.mean_edge);
        check(after <= 0.9 * before, name + fmt(": surface RMS ratio %.4f <= 0.9", after / before));
        double worst = 0;
        check(m.normals.size() == 3 * n && all_unit(m.normals, 1e-5, &worst) && m.quality.size() == n &&
                  std::all_of(m.quality.begin(), m.quality.end(), [](float q) { return std::isfinite(q); }),
              name + ": unit normals and finite mean curvature of the result");
        if (id == NbhdFilterPlugin::FP_ANISOTROPIC_SMOOTHING) {
            std::vector<float> direct = noisy.xyz;
            nbhd_points pts = {direct.data(), n, 3, 12, NBHD_SCALAR_TYPE_F32};
            nbhd_smooth_options o = nbhd_smooth_options_default();
            nbhd_status s = nbhd_smooth(&pts, &o, direct.data(), nullptr, nullptr);
            check(s == NBHD_STATUS_OK && direct == m.xyz,
                  "anisotropic with the shim's defaults == nbhd_smooth with nbhd_smooth_options_default()");
        }
    }

    std::printf("== cancelling and throwing callbacks\n");
    {
        VertexArray m = noisy;
        auto id = NbhdFilterPlugin::FP_ANISOTROPIC_SMOOTHING;
        try {
            plugin.applyFilter(id, m, plugin.initParameterList(id), [](double f, const char*) { return f < 0.5; });
            check(false, "cancel at 50%: no exception");
        } catch (const nbhd_filter_error& e) {
            check(e.status() == NBHD_STATUS_CANCELLED && m.xyz == noisy.xyz && m.normals.empty(),
                  std::string("cancel at 50%: ") + nbhd_status_string(e.status()) + ", mesh unchanged");
        }
        try {
            plugin.applyFilter(id, m, plugin.initParameterList(id),
                               [](double, const char*) -> bool { throw std::domain_error("from the callback"); });
            check(false, "throwing callback: no exception");
        } catch (const std::domain_error& e) {
            check(m.xyz == noisy.xyz, std::string("throwing callback: its std::domain_error came out (\"") +
                                          e.what() + "\"), mesh unchanged");
        }
    }

    std::printf("== bad parameters\n");
    {
        using F = NbhdFilterPlugin;
        RichParameterList p = plugin.initParameterList(F::FP_COMPUTE_NORMALS);
        p.set("k", 0);
        expect_error(plugin, F::FP_COMPUTE_NORMALS, clean.mesh, p, NBHD_STATUS_INVALID_K, "'k'", "k = 0");
        p.set("k", -3);
        expect_error(plugin, F::FP_COMPUTE_NORMALS, clean.mesh, p, NBHD_STATUS_INVALID_K, "'k'", "k = -3");
        p = plugin.initParameterList(F::FP_ISOTROPIC_SMOOTHING);
        p.set("epsilon", -1);
        expect_error(plugin, F::FP_ISOTROPIC_SMOOTHING, noisy, p, NBHD_STATUS_INVALID_OPTION, "epsilon",
                     "epsilon = -1");
        p = plugin.initParameterList(F::FP_ANISOTROPIC_SMOOTHING);
        p.set("lambda", 0);
        expect_error(plugin, F::FP_ANISOTROPIC_SMOOTHING, noisy, p, NBHD_STATUS_INVALID_OPTION, "lambda",
                     "lambda = 0");
        p.set("lambda", 0.2);
        p.set("feature", 7);
        expect_error(plugin, F::FP_ANISOTROPIC_SMOOTHING, noisy, p, NBHD_STATUS_INVALID_ARGUMENT, "'feature'",
                     "feature = 7");
        expect_error(plugin, F::FP_ANISOTROPIC_SMOOTHING, noisy, plugin.initParameterList(F::FP_COMPUTE_NORMALS),
                     NBHD_STATUS_INVALID_ARGUMENT, "'steps'", "normals' parameters given to anisotropic smoothing");
    }

    std::printf(failures ? "%d check(s) FAILED\n" : "all checks passed\n", failures);
    return failures ? 1 : 0;
} catch (const std::exception& e) {
    std::fprintf(stderr, "test_nbhd_filter_plugin: %s\n", e.what());
    return 1;
}
