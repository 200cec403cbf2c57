// bench_normals: nbhd_estimate_normals against PCL's NormalEstimation and NormalEstimationOMP,
// in one process, on the same cloud, in the same run (a benchmark, not a test).
//
//   bench_normals [--reps N] [--generated N] [--threads T] [--write FILE] [FILE...]
//
// Clouds: a torus (R = 1, tube r = 0.35) of N points, 1,000,000 by default (0 for none), from
// the generator of bench_neighbors (std::mt19937(1) bits turned into floats by hand); then every
// FILE, loaded with pcl::io::loadPCDFile<pcl::PointXYZ>, its NaN points dropped.
//
// Every method computes, for every point, the normal and PCL's curvature (the surface variation
// λ0/(λ0+λ1+λ2)) of the covariance of the point and its 15 nearest other points — PCL's
// setKSearch(16), whose 16 include the point itself — unoriented (nbhd) / toward PCL's default
// viewpoint at the origin (PCL: a sign flip per point), into a pcl::PointCloud<pcl::Normal>:
//   nbhd 1T / nbhd T-T    nbhd_estimate_normals, k = 15, epsilon = 1e30 ABSOLUTE (no radius cut),
//                         threads = 1 / T, writing straight into the pcl::Normal records; the call
//                         includes nbhd's tree build and search
//   PCL NE                pcl::NormalEstimation with a pcl::search::KdTree (its build included)
//   PCL OMP 1T / T-T      pcl::NormalEstimationOMP with setNumberOfThreads(1 / T)
// Prints the median of N repetitions (default 3; nbhd's one-thread and T-thread runs alternate) in milliseconds, wall and process CPU time (the
// CPU time of a one-thread row is the steadier measure on a loaded machine), and for every row
// the time of the fastest one-thread PCL row over it (> 1: faster than that PCL row), and checks that nbhd's
// normals agree with PCL's (|cos| > 0.999 for 99% of the points; exit 1 otherwise). T defaults
// to 2. --write FILE saves the torus as raw little-endian float32 x y z records, so that
// scripts/bench_normals_open3d.py times Open3D's estimate_normals on the very same points
// (scripts/bench-normals.sh runs both).
//
// Then the principal curvatures, the same way: nbhd_estimate_curvatures (k = 15, epsilon = 1e30
// ABSOLUTE; the Weingarten estimate of k1, k2 and their directions, with the normals and every
// other per-point value of nbhd_point_geometry) on 1 and T threads in alternation, against PCL's
// pipeline for principal curvatures: NormalEstimation (or NormalEstimationOMP on T threads) and
// then PrincipalCurvaturesEstimation, both with setKSearch(16) on one pcl::search::KdTree (its
// build included). PCL's pc1/pc2 are the eigenvalues of the covariance of the neighbours'
// normals projected on the tangent plane, not curvatures in 1/length: the rows time the same
// job (principal curvatures and directions of every point), not the same estimator, so only the
// times are compared (and nbhd's 1- and T-thread results checked identical).
#include <nbhd.h>

#include <pcl/features/normal_3d.h>
#include <pcl/features/normal_3d_omp.h>
#include <pcl/features/principal_curvatures.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <functional>
#include <random>
#include <string>
#include <vector>

namespace {

using Cloud = pcl::PointCloud<pcl::PointXYZ>;

float unit(std::mt19937& rng) { return static_cast<float>(rng() >> 8) * (1.0f / 16777216.0f); }

Cloud::Ptr torus(std::size_t n) {
    std::mt19937 rng(1);
    Cloud::Ptr c(new Cloud);
    c->resize(n);
    const float R = 1.0f, r = 0.35f, tau = 6.28318530718f;
    for (std::size_t i = 0; i < n; ++i) {
        float u = tau * unit(rng), v = tau * unit(rng);
        (*c)[i].x = (R + r * std::cos(v)) * std::cos(u);
        (*c)[i].y = (R + r * std::cos(v)) * std::sin(u);
        (*c)[i].z = r * std::sin(v);
    }
    return c;
}

// Median wall times and median CPU times of the process (all threads) over `reps` rounds that each
// run every one of `fs` once, in turn, in ms: runs compared this way share whatever load passes
// over a shared machine (one thread against several, above all). On a shared, loaded machine the
// CPU time of a one-thread run is the steadier of the two.
struct Times {
    double wall, cpu;
};

std::vector<Times> interleaved_median_ms(int reps, const std::vector<std::function<void()>>& fs) {
    std::vector<std::vector<double>> w(fs.size()), c(fs.size());
    for (int r = 0; r < reps; ++r) {
        for (std::size_t i = 0; i < fs.size(); ++i) {
            auto a = std::chrono::steady_clock::now();
            std::clock_t ca = std::clock();
            fs[i]();
            c[i].push_back(1000.0 * double(std::clock() - ca) / CLOCKS_PER_SEC);
            w[i].push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - a)
                               .count());
        }
    }
    std::vector<Times> out;
    for (std::size_t i = 0; i < fs.size(); ++i) {
        std::sort(w[i].begin(), w[i].end());
        std::sort(c[i].begin(), c[i].end());
        out.push_back({w[i][w[i].size() / 2], c[i][c[i].size() / 2]});
    }
    return out;
}

Times median_ms(int reps, const std::function<void()>& f) { return interleaved_median_ms(reps, {f})[0]; }

// The cloud as nbhd sees it: the pcl::PointXYZ records in place.
nbhd_points points_of(const Cloud& c) {
    return {c.points.data(), c.size(), 3, sizeof(pcl::PointXYZ), NBHD_SCALAR_TYPE_F32};
}

// The neighbourhoods of every nbhd row (normal or smoothing options): the point and its 15
// nearest others, no radius cut, on `threads` threads.
template <class Options>
Options neighbourhoods(Options o, std::size_t threads) {
    o.k = 15;
    o.epsilon = 1e30;
    o.epsilon_units = NBHD_UNITS_ABSOLUTE;
    o.threads = threads;
    return o;
}

// Whether an nbhd call succeeded (its message printed when not).
bool succeeded(nbhd_status s) {
    if (s != NBHD_STATUS_OK) std::fprintf(stderr, "nbhd: %s\n", nbhd_last_error_message());
    return s == NBHD_STATUS_OK;
}

bool nbhd_normals(const Cloud& c, std::size_t threads, pcl::PointCloud<pcl::Normal>& out) {
    out.resize(c.size());
    nbhd_points pts = points_of(c);
    nbhd_normal_options o = neighbourhoods(nbhd_normal_options_default(), threads);
    nbhd_normals_output w = {&out[0].normal_x, sizeof(pcl::Normal), NBHD_SCALAR_TYPE_F32,
                             &out[0].curvature, sizeof(pcl::Normal), nullptr};
    return succeeded(nbhd_estimate_normals(&pts, &o, &w));
}

bool nbhd_curvatures(const Cloud& c, std::size_t threads, std::vector<nbhd_point_geometry>& out) {
    out.resize(c.size());
    nbhd_points pts = points_of(c);
    nbhd_smooth_options o = neighbourhoods(nbhd_smooth_options_default(), threads);
    return succeeded(nbhd_estimate_curvatures(&pts, &o, out.data(), nullptr));
}

// PCL's principal curvatures: normals, then PrincipalCurvaturesEstimation over them, on one tree.
template <class NE>
void pcl_curvatures(const Cloud::Ptr& c, NE& ne, pcl::PointCloud<pcl::PrincipalCurvatures>& out) {
    pcl::search::KdTree<pcl::PointXYZ>::Ptr tree(new pcl::search::KdTree<pcl::PointXYZ>);
    pcl::PointCloud<pcl::Normal>::Ptr normals(new pcl::PointCloud<pcl::Normal>);
    ne.setInputCloud(c);
    ne.setSearchMethod(tree);
    ne.setKSearch(16);
    ne.compute(*normals);
    pcl::PrincipalCurvaturesEstimation<pcl::PointXYZ, pcl::Normal, pcl::PrincipalCurvatures> pc;
    pc.setInputCloud(c);
    pc.setInputNormals(normals);
    pc.setSearchMethod(tree);
    pc.setKSearch(16);
    pc.compute(out);
}

// The principal curvatures' rows (see the file's comment).
bool bench_curvatures(const Cloud::Ptr& c, int reps, int threads) {
    std::vector<nbhd_point_geometry> ours, ours_t;
    pcl::PointCloud<pcl::PrincipalCurvatures> ref, reft;
    bool ok = true;
    auto nbhd = interleaved_median_ms(reps, {[&] { ok = nbhd_curvatures(*c, 1, ours) && ok; },
                                             [&] { ok = nbhd_curvatures(*c, threads, ours_t) && ok; }});
    Times pcl1 = median_ms(reps, [&] {
        pcl::NormalEstimation<pcl::PointXYZ, pcl::Normal> ne;
        pcl_curvatures(c, ne, ref);
    });
    Times pclt = median_ms(reps, [&] {
        pcl::NormalEstimationOMP<pcl::PointXYZ, pcl::Normal> ne(threads);
        pcl_curvatures(c, ne, reft);
    });
    std::printf("\nprincipal curvatures, %zu points, 16-point neighbourhoods, median of %d\n"
                "| method | wall ms | PCL 1-thread pipeline / this (wall) | CPU ms | PCL 1-thread pipeline / this (CPU) |\n"
                "|---|---:|---:|---:|---:|\n",
                c->size(), reps);
    auto row = [&](const std::string& name, Times t) {
        std::printf("| %s | %.0f | %.2f | %.0f | %.2f |\n", name.c_str(), t.wall, pcl1.wall / t.wall, t.cpu,
                    pcl1.cpu / t.cpu);
    };
    row("nbhd_estimate_curvatures 1 thread", nbhd[0]);
    row("nbhd_estimate_curvatures " + std::to_string(threads) + " threads", nbhd[1]);
    row("PCL NormalEstimation + PrincipalCurvaturesEstimation", pcl1);
    row("PCL NormalEstimationOMP " + std::to_string(threads) + " threads + PrincipalCurvaturesEstimation", pclt);
    std::printf("nbhd curvatures scaling 1 -> %d threads (wall): %.2fx\n", threads, nbhd[0].wall / nbhd[1].wall);
    std::size_t same = 0;
    for (std::size_t i = 0; ok && i < c->size(); ++i)
        same += std::memcmp(&ours[i], &ours_t[i], offsetof(nbhd_point_geometry, normal_flags) + 3) == 0;
    std::printf("nbhd curvatures, 1- and %d-thread results identical: %zu of %zu\n", threads, same, c->size());
    if (!ok || same != c->size() || ref.size() != c->size()) {
        std::fprintf(stderr, "bench_normals: nbhd's curvatures failed or differ between thread counts\n");
        return false;
    }
    return true;
}

template <class NE>
void pcl_normals(const Cloud::Ptr& c, NE& ne, pcl::PointCloud<pcl::Normal>& out) {
    ne.setInputCloud(c);
    ne.setSearchMethod(pcl::search::KdTree<pcl::PointXYZ>::Ptr(new pcl::search::KdTree<pcl::PointXYZ>));
    ne.setKSearch(16);
    ne.compute(out);
}

bool bench(const std::string& name, const Cloud::Ptr& c, int reps, int threads) {
    std::printf("\n%s: %zu points, 16-point neighbourhoods, median of %d\n", name.c_str(), c->size(),
                reps);
    pcl::PointCloud<pcl::Normal> ours, ours_t, ref, omp1, ompt;
    bool ok = true;
    struct Row {
        std::string name;
        Times t;
        bool pcl_one_thread;
    };
    std::vector<Row> rows;
    // one thread and several in alternation: their ratio is the scaling
    auto nbhd = interleaved_median_ms(reps, {[&] { ok = nbhd_normals(*c, 1, ours) && ok; },
                                             [&] { ok = nbhd_normals(*c, threads, ours_t) && ok; }});
    rows.push_back({"nbhd 1 thread", nbhd[0], false});
    rows.push_back({"nbhd " + std::to_string(threads) + " threads", nbhd[1], false});
    rows.push_back({"PCL NormalEstimation", median_ms(reps, [&] {
                        pcl::NormalEstimation<pcl::PointXYZ, pcl::Normal> ne;
                        pcl_normals(c, ne, ref);
                    }),
                    true});
    rows.push_back({"PCL NormalEstimationOMP 1 thread", median_ms(reps, [&] {
                        pcl::NormalEstimationOMP<pcl::PointXYZ, pcl::Normal> ne(1);
                        pcl_normals(c, ne, omp1);
                    }),
                    true});
    rows.push_back({"PCL NormalEstimationOMP " + std::to_string(threads) + " threads",
                    median_ms(reps, [&] {
                        pcl::NormalEstimationOMP<pcl::PointXYZ, pcl::Normal> ne(threads);
                        pcl_normals(c, ne, ompt);
                    }),
                    false});
    double best_wall = 1e300, best_cpu = 1e300;
    for (const auto& r : rows)
        if (r.pcl_one_thread) best_wall = std::min(best_wall, r.t.wall), best_cpu = std::min(best_cpu, r.t.cpu);
    std::printf("| method | wall ms | fastest 1-thread PCL / this (wall) | CPU ms | fastest 1-thread PCL / this (CPU) |\n"
                "|---|---:|---:|---:|---:|\n");
    for (const auto& r : rows)
        std::printf("| %s | %.0f | %.2f | %.0f | %.2f |\n", r.name.c_str(), r.t.wall, best_wall / r.t.wall,
                    r.t.cpu, best_cpu / r.t.cpu);
    std::printf("nbhd scaling 1 -> %d threads (wall): %.2fx\n", threads, rows[0].t.wall / rows[1].t.wall);

    std::size_t agree = 0, same = 0, compared = 0;
    for (std::size_t i = 0; ok && i < c->size(); ++i) {
        const auto &a = ours[i], &b = ref[i], &t = ours_t[i];
        same += std::memcmp(&a, &t, 4 * sizeof(float)) == 0 && a.curvature == t.curvature;
        if (!std::isfinite(b.normal_x)) continue;
        compared++;
        double dot = double(a.normal_x) * b.normal_x + double(a.normal_y) * b.normal_y +
                     double(a.normal_z) * b.normal_z;
        agree += std::fabs(dot) > 0.999;
    }
    std::printf("normals within 2.6 deg of PCL's (up to sign): %zu of %zu; 1- and %d-thread results "
                "identical: %zu of %zu\n",
                agree, compared, threads, same, c->size());
    if (!ok || compared == 0 || agree < compared * 99 / 100 || same != c->size()) {
        std::fprintf(stderr, "bench_normals: nbhd failed or disagrees with PCL\n");
        return false;
    }
    return true;
}

}  // namespace

int main(int argc, char** argv) {
    int reps = 3, threads = 2;
    std::size_t generated = 1000000;
    std::vector<std::string> files;
    std::string write;
    for (int i = 1; i < argc; ++i) {
        std::string a = argv[i];
        if ((a == "--reps" || a == "--generated" || a == "--threads" || a == "--write") && i + 1 < argc) {
            const char* v = argv[++i];
            if (a == "--write") write = v;
            else if (a == "--reps") reps = std::max(1, std::atoi(v));
            else if (a == "--threads") threads = std::max(1, std::atoi(v));
            else generated = std::strtoull(v, nullptr, 10);
        } else if (!a.empty() && a[0] == '-') {
            std::fprintf(stderr, "usage: bench_normals [--reps N] [--generated N] [--threads T] [--write FILE] [FILE...]\n");
            return 2;
        } else {
            files.push_back(a);
        }
    }
    bool ok = true;
    if (generated > 0) {
        Cloud::Ptr t = torus(generated);
        if (!write.empty()) {
            std::FILE* f = std::fopen(write.c_str(), "wb");
            if (!f) return 2;
            for (const auto& p : t->points) std::fwrite(&p.x, sizeof(float), 3, f);
            if (std::fclose(f) != 0) return 2;
        }
        ok = bench("torus " + std::to_string(generated), t, reps, threads) && ok;
        ok = bench_curvatures(t, reps, threads) && ok;
    }
    for (const auto& f : files) {
        Cloud::Ptr raw(new Cloud), c(new Cloud);
        if (pcl::io::loadPCDFile<pcl::PointXYZ>(f, *raw) != 0) return 2;
        for (const auto& p : raw->points)
            if (pcl::isFinite(p)) c->push_back(p);
        ok = bench(f, c, reps, threads) && ok;
    }
    return ok ? 0 : 1;
}
