// bench_denoise: the smoothing peers of the denoising protocol (docs/smoothing-results.md, "The
// denoising protocol"), in one process, on one thread, each cloud given to every method in the
// same run, the order of the methods rotating from cloud to cloud.
//
//   bench_denoise [--methods M,M...] DIR CLOUD...
//
// Reads DIR/CLOUD.noisy.f64 (raw little-endian double triples, as examples/denoise_protocol.rs
// --prepare writes them) and writes, per method M, DIR/CLOUD.M.f64 (the smoothed points, in the
// input's order) and DIR/CLOUD.M.s (the wall-clock seconds of the call); it prints the wall-clock
// and the process CPU seconds of each call (one thread each, so the CPU time is the method's own
// work, less disturbed than the wall clock by other processes on a shared machine). --methods runs
// only the methods listed (all three by default), e.g. to count one method's instructions under
// valgrind against a run with `--methods none` (reading the cloud and its spacing only). Methods:
//   robust  nbhd_smooth_robust, nbhd_robust_options_default() with threads = 1 (the call includes
//           nbhd's neighbourhood search and spacing estimate).
//   mls     pcl::MovingLeastSquares<PointXYZ, PointXYZ>, search radius 5h, polynomial order 2, one
//           thread, a pcl::search::KdTree, no upsampling, h = the mean nearest-neighbour distance of
//           the noisy cloud (computed outside the timing). A point MLS leaves out (fewer than 3
//           points within the radius) keeps its input position.
//   jet     CGAL::jet_smooth_point_set<Sequential_tag>, k = 24 (CGAL's advice for real-life
//           point sets), fitting and Monge degree 2 (its defaults).
// Exit 1 if a method fails or returns a non-finite point, 2 on bad arguments.
#include <nbhd.hpp>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>
#include <pcl/surface/mls.h>

#include <CGAL/Simple_cartesian.h>
#include <CGAL/jet_smooth_point_set.h>

#include <chrono>
#include <ctime>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

using Clock = std::chrono::steady_clock;

/// The CPU seconds the process has used so far.
double cpu_seconds() {
    timespec t{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}
using Points = std::vector<double>;  // x, y, z per point

Points read_f64(const std::string& path) {
    std::ifstream f(path, std::ios::binary | std::ios::ate);
    if (!f) throw std::runtime_error("cannot read " + path);
    std::streamsize bytes = f.tellg();
    f.seekg(0);
    Points v(std::size_t(bytes) / sizeof(double));
    f.read(reinterpret_cast<char*>(v.data()), std::streamsize(v.size() * sizeof(double)));
    if (v.empty() || v.size() % 3 != 0) throw std::runtime_error(path + ": not a list of 3-D points");
    return v;
}

void write_f64(const std::string& path, const Points& v) {
    std::ofstream f(path, std::ios::binary);
    f.write(reinterpret_cast<const char*>(v.data()), std::streamsize(v.size() * sizeof(double)));
    if (!f) throw std::runtime_error("cannot write " + path);
}

pcl::PointCloud<pcl::PointXYZ>::Ptr to_pcl(const Points& v) {
    pcl::PointCloud<pcl::PointXYZ>::Ptr c(new pcl::PointCloud<pcl::PointXYZ>);
    c->resize(v.size() / 3);
    for (std::size_t i = 0; i < c->size(); ++i)
        (*c)[i] = pcl::PointXYZ(float(v[3 * i]), float(v[3 * i + 1]), float(v[3 * i + 2]));
    return c;
}

/// The mean distance of a point to its nearest other point.
double mean_spacing(const pcl::PointCloud<pcl::PointXYZ>::Ptr& c) {
    pcl::search::KdTree<pcl::PointXYZ> tree;
    tree.setInputCloud(c);
    std::vector<int> idx(2);
    std::vector<float> d2(2);
    double sum = 0;
    for (std::size_t i = 0; i < c->size(); ++i) {
        tree.nearestKSearch((*c)[i], 2, idx, d2);
        sum += std::sqrt(double(d2[1]));
    }
    return sum / double(c->size());
}

Points robust(const Points& in, double) {
    Points out(in.size());
    nbhd_points pts{in.data(), in.size() / 3, 3, 0, NBHD_SCALAR_TYPE_F64};
    nbhd_robust_options o = nbhd_robust_options_default();
    o.threads = 1;
    nbhd_smooth_summary s{};
    nbhdpp::check(nbhd_smooth_robust(&pts, &o, out.data(), nullptr, &s), "nbhd_smooth_robust");
    return out;
}

Points mls(const Points& in, double h) {
    auto cloud = to_pcl(in);
    pcl::PointCloud<pcl::PointXYZ> out;
    pcl::MovingLeastSquares<pcl::PointXYZ, pcl::PointXYZ> m;
    m.setNumberOfThreads(1);
    m.setInputCloud(cloud);
    m.setSearchMethod(pcl::search::KdTree<pcl::PointXYZ>::Ptr(new pcl::search::KdTree<pcl::PointXYZ>));
    m.setSearchRadius(5.0 * h);
    m.setPolynomialOrder(2);
    m.setComputeNormals(false);
    m.process(out);
    pcl::PointIndicesPtr src = m.getCorrespondingIndices();
    if (!src || src->indices.size() != out.size()) throw std::runtime_error("MLS: no input index per output point");
    Points full = in;
    for (std::size_t i = 0; i < out.size(); ++i) {
        std::size_t j = std::size_t(src->indices[i]);
        full[3 * j] = out[i].x;
        full[3 * j + 1] = out[i].y;
        full[3 * j + 2] = out[i].z;
    }
    return full;
}

Points jet(const Points& in, double) {
    using Point = CGAL::Simple_cartesian<double>::Point_3;
    std::vector<Point> p;
    p.reserve(in.size() / 3);
    for (std::size_t i = 0; i < in.size(); i += 3) p.emplace_back(in[i], in[i + 1], in[i + 2]);
    CGAL::jet_smooth_point_set<CGAL::Sequential_tag>(p, 24);
    Points out;
    out.reserve(in.size());
    for (const Point& q : p) out.insert(out.end(), {q.x(), q.y(), q.z()});
    return out;
}

}  // namespace

int main(int argc, char** argv) {
    struct Method {
        const char* name;
        std::function<Points(const Points&, double)> run;
    };
    const std::vector<Method> all = {{"robust", robust}, {"mls", mls}, {"jet", jet}};
    std::vector<Method> methods = all;
    int first = 1;
    if (argc > 2 && std::string(argv[1]) == "--methods") {
        const std::string list = "," + std::string(argv[2]) + ",";
        methods.clear();
        for (const Method& m : all)
            if (list.find("," + std::string(m.name) + ",") != std::string::npos) methods.push_back(m);
        if (methods.empty() && list != ",none,") {
            std::fprintf(stderr, "bench_denoise: --methods takes robust, mls, jet or none, comma-separated\n");
            return 2;
        }
        first = 3;
    }
    if (argc < first + 2) {
        std::fprintf(stderr, "usage: bench_denoise [--methods M,M...] DIR CLOUD...\n");
        return 2;
    }
    const std::string dir = argv[first];
    try {
        for (int c = first + 1; c < argc; ++c) {
            const std::string base = dir + "/" + argv[c];
            const Points in = read_f64(base + ".noisy.f64");
            const double h = mean_spacing(to_pcl(in));
            std::printf("%s: %zu points, h = %.5g;", argv[c], in.size() / 3, h);
            for (std::size_t m = 0; m < methods.size(); ++m) {
                const Method& method = methods[(m + std::size_t(c)) % methods.size()];
                const double cpu0 = cpu_seconds();
                auto t0 = Clock::now();
                Points out = method.run(in, h);
                double s = std::chrono::duration<double>(Clock::now() - t0).count();
                const double cpu = cpu_seconds() - cpu0;
                for (double v : out)
                    if (!std::isfinite(v)) throw std::runtime_error(std::string(method.name) + ": a non-finite point");
                if (out.size() != in.size()) throw std::runtime_error(std::string(method.name) + ": point count changed");
                write_f64(base + "." + method.name + ".f64", out);
                std::ofstream(base + "." + method.name + ".s") << s << "\n";
                std::printf(" %s %.3f s (cpu %.3f s)", method.name, s, cpu);
            }
            std::printf("\n");
            std::fflush(stdout);
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "bench_denoise: %s\n", e.what());
        return 1;
    }
    return 0;
}
