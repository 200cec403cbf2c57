// bench_smoothing: nbhd's smoothing against PCL's MovingLeastSquares, in one process, on one
// thread, timed on the same clouds in the same run, with the quality of every result next to its
// time.
//
//   bench_smoothing [--reps N] [--generated N] [--noise A] [FILE...]
//
// Clouds: a torus (R = 1, tube r = 0.35) of N points, 80,000 by default (0 for none), sampled
// uniformly by area from std::mt19937(3) bits turned into floats by hand (as bench_neighbors
// generates its clouds), then moved by A * h * g per coordinate (g ~ N(0, 1) by Box-Muller from
// the same generator: along the normal and in the tangent plane alike, as
// docs/smoothing-results.md defines noise), A = 1 by default, h = the mean nearest-neighbour
// distance of the clean sample; then every FILE, loaded as bench_neighbors loads it (a .pcd with
// pcl::io::loadPCDFile<pcl::PointXYZ>), its NaN points dropped (nbhd_smooth rejects them and
// MovingLeastSquares needs a dense cloud), h = the mean nearest-neighbour distance of the scan.
//
// Methods, each given the same pcl::PointCloud<pcl::PointXYZ> (nbhd reads it in place, stride 16):
//   nbhd anisotropic   nbhd_smooth, nbhd_smooth_options_default() (g_sharp, lambda = 0.2/h_in,
//                      the 15 nearest other points within 6h_in, tau = 0.5) with steps = 10 and
//                      threads = 1; h_in is nbhd's own spacing estimate of the noisy input. The
//                      call includes nbhd's neighbourhood search (and its spacing estimate).
//   nbhd robust        nbhd_smooth_robust, nbhd_robust_options_default() with threads = 1.
//   nbhd isotropic     as anisotropic with weighting = NBHD_WEIGHTING_ISOTROPIC (reference).
//   PCL MLS            pcl::MovingLeastSquares<PointXYZ, PointNormal> with setNumberOfThreads(1)
//                      (its OpenMP loop on one thread; PCL 1.13 has no separate OMP class),
//                      search radius 5h, polynomial order 2, a pcl::search::KdTree, no
//                      upsampling, setComputeNormals(false): the
//                      settings docs/smoothing-results.md compares with, positions only
//                      (MLS fits the local plane and polynomial either way; the flag only copies
//                      the normal into the output). The call (process) includes PCL's tree build
//                      and radius searches. MLS leaves out a point with fewer than 3 points
//                      (itself included) within the radius; the table says how many, and such a
//                      point is measured at its input position.
// Each repetition runs every method once, in this order, on a fresh copy; the table shows the
// median of N repetitions (default 3) in milliseconds and PCL-MLS's time over the method's (> 1:
// the method is faster than PCL). Quality for the torus: RMS distance to the analytic surface
// | sqrt((sqrt(x^2 + y^2) - R)^2 + z^2) - r | and the mean signed distance (shrinkage, negative =
// shrank), in h; for every cloud the RMS distance each point moved (in h).
//
// Exit 1 if a method fails (an nbhd status, an empty or non-finite PCL output) or, on the torus,
// if a method's RMS distance is not below the noisy input's; exit 2 on bad arguments.
#include "cloud_io.hpp"
#include <nbhd.hpp>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>
#include <pcl/surface/mls.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

using Clock = std::chrono::steady_clock;
using CloudXYZ = pcl::PointCloud<pcl::PointXYZ>;

double ms_since(Clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    std::size_t m = v.size() / 2;
    return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

// --- the torus ------------------------------------------------------------------------------

constexpr double kR = 1.0, kTube = 0.35;

float unit(std::mt19937& rng) { return static_cast<float>(rng() >> 8) * (1.0f / 16777216.0f); }
// In (0, 1]: log() of it is finite.
double unit_open(std::mt19937& rng) { return (static_cast<double>(rng() >> 8) + 1.0) / 16777216.0; }

/// N(0, 1) by Box-Muller (both values used), so that the cloud does not depend on the standard
/// library's std::normal_distribution.
struct Gauss {
    std::mt19937& rng;
    double spare = 0;
    bool has_spare = false;
    double operator()() {
        if (has_spare) {
            has_spare = false;
            return spare;
        }
        double r = std::sqrt(-2.0 * std::log(unit_open(rng))), t = 6.283185307179586 * unit_open(rng);
        spare = r * std::sin(t);
        has_spare = true;
        return r * std::cos(t);
    }
};

/// n points uniformly by area on the torus (v accepted with probability (R + r cos v) / (R + r)).
std::vector<float> torus(std::size_t n, std::mt19937& rng) {
    std::vector<float> p;
    p.reserve(3 * n);
    const float R = static_cast<float>(kR), r = static_cast<float>(kTube), tau = 6.28318530718f;
    while (p.size() < 3 * n) {
        float u = tau * unit(rng), v = tau * unit(rng);
        if (unit(rng) * (R + r) > R + r * std::cos(v)) continue;
        p.push_back((R + r * std::cos(v)) * std::cos(u));
        p.push_back((R + r * std::cos(v)) * std::sin(u));
        p.push_back(r * std::sin(v));
    }
    return p;
}

/// Signed distance to the torus (positive outside the tube).
double torus_distance(const pcl::PointXYZ& p) {
    double rho = std::hypot(double(p.x), double(p.y)) - kR;
    return std::hypot(rho, double(p.z)) - kTube;
}

// --- helpers ----------------------------------------------------------------------------------

CloudXYZ::Ptr dense_cloud(const std::vector<float>& xyz) {
    auto c = std::make_shared<CloudXYZ>();
    c->resize(xyz.size() / 3);
    for (std::size_t i = 0; i < c->size(); ++i) (*c)[i] = pcl::PointXYZ(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
    c->width = static_cast<std::uint32_t>(c->size());
    c->height = 1;
    c->is_dense = true;
    return c;
}

nbhd_points view(const CloudXYZ& c) { return nbhdpp::points_f32(&c[0].x, c.size(), sizeof(pcl::PointXYZ)); }

/// Mean distance of a point to its nearest other point (nbhd's exact 1-NN table, one thread).
double mean_spacing(const CloudXYZ& c) {
    nbhd_build_options o = nbhd_build_options_default();
    o.threads = 1;
    nbhdpp::Tree tree = nbhdpp::build(view(c), o);
    nbhd_neighborhood_spec spec{NBHD_NEIGHBORHOOD_KIND_KNN, 1, 0.0};
    nbhdpp::Table table = nbhdpp::neighborhoods(tree.get(), spec, /*exclude_self=*/true, 1);
    nbhdpp::RowsF32 rows(table.get());
    double sum = 0;
    std::size_t n = 0;
    for (std::size_t i = 0; i < rows.rows(); ++i) {
        nbhdpp::Row row = rows[i];
        if (row.len) {
            sum += std::sqrt(double(row.sq[0]));
            ++n;
        }
    }
    if (n == 0) throw std::runtime_error("no point has a neighbour");
    return sum / double(n);
}

struct Quality {
    double rms = NAN, mean = NAN;  // distance to the torus (torus only)
    double moved = NAN;            // RMS distance from the input point
};

/// `out` against the analytic torus (if `is_torus`) and point i of `out` against point i of
/// `in`, all in units of h.
Quality quality(const CloudXYZ& out, const CloudXYZ& in, bool is_torus, double h) {
    Quality q;
    double s2 = 0, s1 = 0, m2 = 0;
    for (std::size_t i = 0; i < out.size(); ++i) {
        const pcl::PointXYZ& p = out[i];
        if (is_torus) {
            double d = torus_distance(p);
            s2 += d * d;
            s1 += d;
        }
        const pcl::PointXYZ& o = in[i];
        double dx = double(p.x) - o.x, dy = double(p.y) - o.y, dz = double(p.z) - o.z;
        m2 += dx * dx + dy * dy + dz * dz;
    }
    double n = double(out.size());
    if (is_torus) {
        q.rms = std::sqrt(s2 / n) / h;
        q.mean = s1 / n / h;
    }
    q.moved = std::sqrt(m2 / n) / h;
    return q;
}

template <class P>
bool all_finite(const pcl::PointCloud<P>& c) {
    for (const P& p : c)
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) return false;
    return true;
}

// --- the methods ------------------------------------------------------------------------------

struct Run {
    double ms = 0;     // the timed call only
    Quality q;
    std::string note;  // the spacing and radius nbhd used, or PCL's radius
};

struct Method {
    std::string name;
    // Smooths a copy of `in` once, timing only the library call; throws on failure.
    std::function<Run(const CloudXYZ& in, bool is_torus, double h)> run;
};

void check_finite_size(bool ok, std::size_t got, std::size_t want, const std::string& who) {
    if (!ok) throw std::runtime_error(who + ": non-finite output coordinates");
    if (got != want)
        throw std::runtime_error(who + ": " + std::to_string(got) + " output points for " + std::to_string(want));
}

Run nbhd_result(double ms, const CloudXYZ& out, const CloudXYZ& in, bool is_torus, double h,
                const nbhd_smooth_summary& s, const std::string& who) {
    check_finite_size(all_finite(out), out.size(), in.size(), who);
    char note[96];
    std::snprintf(note, sizeof note, "h_in = %.3gh, eps = %.3gh", s.spacing / h, s.epsilon / h);
    return Run{ms, quality(out, in, is_torus, h), note};
}

Method nbhd_faithful(std::string name, nbhd_weighting w) {
    return Method{std::move(name), [w](const CloudXYZ& in, bool is_torus, double h) {
                      CloudXYZ out = in;  // written in place: same 16-byte layout as the input
                      nbhd_points pts = view(in);
                      nbhd_smooth_options o = nbhd_smooth_options_default();
                      o.steps = 10;
                      o.threads = 1;
                      o.weighting = w;
                      nbhd_smooth_summary s{};
                      auto t0 = Clock::now();
                      nbhd_status st = nbhd_smooth(&pts, &o, &out[0].x, nullptr, &s);
                      double ms = ms_since(t0);
                      nbhdpp::check(st, "nbhd_smooth");
                      return nbhd_result(ms, out, in, is_torus, h, s, "nbhd_smooth");
                  }};
}

Method nbhd_robust() {
    return Method{"nbhd robust (defaults)", [](const CloudXYZ& in, bool is_torus, double h) {
                      CloudXYZ out = in;
                      nbhd_points pts = view(in);
                      nbhd_robust_options o = nbhd_robust_options_default();
                      o.threads = 1;
                      nbhd_smooth_summary s{};
                      auto t0 = Clock::now();
                      nbhd_status st = nbhd_smooth_robust(&pts, &o, &out[0].x, nullptr, &s);
                      double ms = ms_since(t0);
                      nbhdpp::check(st, "nbhd_smooth_robust");
                      return nbhd_result(ms, out, in, is_torus, h, s, "nbhd_smooth_robust");
                  }};
}

Method pcl_mls() {
    return Method{"PCL MovingLeastSquares", [](const CloudXYZ& in, bool is_torus, double h) {
                      // Shared so that setInputCloud sees the same points without taking ownership
                      // of a copy made inside the timing.
                      CloudXYZ::ConstPtr input(&in, [](const CloudXYZ*) {});
                      pcl::PointCloud<pcl::PointNormal> out;
                      auto t0 = Clock::now();
                      pcl::MovingLeastSquares<pcl::PointXYZ, pcl::PointNormal> mls;
                      mls.setNumberOfThreads(1);
                      mls.setInputCloud(input);
                      mls.setSearchMethod(pcl::search::KdTree<pcl::PointXYZ>::Ptr(new pcl::search::KdTree<pcl::PointXYZ>));
                      mls.setSearchRadius(5.0 * h);
                      mls.setPolynomialOrder(2);
                      mls.setComputeNormals(false);
                      mls.process(out);
                      double ms = ms_since(t0);
                      // MLS leaves out a point with fewer than 3 points (itself included) within
                      // the radius; such a point counts at its input position, so that every
                      // method is measured over the same points.
                      pcl::PointIndicesPtr src = mls.getCorrespondingIndices();
                      if (out.empty() || !all_finite(out))
                          throw std::runtime_error("PCL MovingLeastSquares: empty or non-finite output");
                      if (!src || src->indices.size() != out.size())
                          throw std::runtime_error("PCL MovingLeastSquares: no index of the input per output point");
                      CloudXYZ full = in;
                      for (std::size_t i = 0; i < out.size(); ++i) {
                          pcl::PointXYZ& q = full[std::size_t(src->indices[i])];
                          q.x = out[i].x;
                          q.y = out[i].y;
                          q.z = out[i].z;
                      }
                      std::string note = "radius 5h, order 2";
                      if (out.size() != in.size())
                          note += "; " + std::to_string(in.size() - out.size()) + " point(s) left out (< 3 in radius), counted unmoved";
                      return Run{ms, quality(full, in, is_torus, h), note};
                  }};
}

// --- one cloud --------------------------------------------------------------------------------

bool bench_cloud(const std::string& name, const CloudXYZ& in, bool is_torus, double h, int reps) {
    std::printf("\n%s: %zu points, h = %.6g (mean nearest-neighbour distance%s), %d repetition%s, one thread\n",
                name.c_str(), in.size(), h, is_torus ? " of the clean sample" : "", reps, reps == 1 ? "" : "s");
    std::vector<Method> ms = {nbhd_faithful("nbhd anisotropic, 10 steps", NBHD_WEIGHTING_SHARP), nbhd_robust(),
                              nbhd_faithful("nbhd isotropic, 10 steps", NBHD_WEIGHTING_ISOTROPIC), pcl_mls()};
    const std::size_t pcl = ms.size() - 1;
    std::vector<std::vector<double>> times(ms.size());
    std::vector<Run> last(ms.size());
    std::vector<std::string> failed(ms.size());
    for (int rep = 0; rep < reps; ++rep) {
        for (std::size_t m = 0; m < ms.size(); ++m) {
            if (!failed[m].empty()) continue;
            try {
                last[m] = ms[m].run(in, is_torus, h);
                times[m].push_back(last[m].ms);
            } catch (const std::exception& e) {
                failed[m] = e.what();
            }
        }
    }
    Quality noisy = quality(in, in, is_torus, h);
    bool ok = true;
    std::printf("  %-28s %10s %16s %9s %10s %9s  %s\n", "method", "ms", "PCL-MLS/method", "RMS [h]", "mean [h]",
                "moved [h]", "");
    if (is_torus) std::printf("  %-28s %10s %16s %9.3f %+10.3f %9s\n", "noisy input", "-", "-", noisy.rms, noisy.mean, "-");
    double pcl_ms = failed[pcl].empty() ? median(times[pcl]) : NAN;
    for (std::size_t m = 0; m < ms.size(); ++m) {
        if (!failed[m].empty()) {
            std::printf("  %-28s FAILED: %s\n", ms[m].name.c_str(), failed[m].c_str());
            ok = false;
            continue;
        }
        double t = median(times[m]);
        const Run& r = last[m];
        char rms[16] = "-", mean[16] = "-";
        if (is_torus) {
            std::snprintf(rms, sizeof rms, "%.3f", r.q.rms);
            std::snprintf(mean, sizeof mean, "%+.3f", r.q.mean);
        }
        std::printf("  %-28s %10.1f %16.2f %9s %10s %9.3f  %s\n", ms[m].name.c_str(), t, pcl_ms / t, rms, mean,
                    r.q.moved, r.note.c_str());
        if (is_torus && !(r.q.rms < noisy.rms)) {
            std::printf("    %s: RMS %.3fh is not below the noisy input's %.3fh\n", ms[m].name.c_str(), r.q.rms,
                        noisy.rms);
            ok = false;
        }
    }
    return ok;
}

int usage() {
    std::fprintf(stderr, "usage: bench_smoothing [--reps N] [--generated N] [--noise A] [FILE...]\n");
    return 2;
}

}  // namespace

int main(int argc, char** argv) {
    int reps = 3;
    std::size_t generated = 80000;
    double noise = 1.0;
    std::vector<std::string> files;
    for (int a = 1; a < argc; ++a) {
        std::string arg = argv[a];
        if (arg == "--reps" && a + 1 < argc) {
            reps = std::atoi(argv[++a]);
            if (reps < 1) return usage();
        } else if (arg == "--generated" && a + 1 < argc) {
            generated = std::strtoul(argv[++a], nullptr, 10);
        } else if (arg == "--noise" && a + 1 < argc) {
            noise = std::atof(argv[++a]);
            if (!(noise >= 0)) return usage();
        } else if (!arg.empty() && arg[0] == '-') {
            return usage();
        } else {
            files.push_back(arg);
        }
    }
    std::setvbuf(stdout, nullptr, _IOLBF, 0);
    std::printf("bench_smoothing: nbhd %s; PCL %s\n", nbhd_version_string(), PCL_VERSION_PRETTY);
    bool ok = true;
    try {
        if (generated) {
            std::mt19937 rng(3);
            std::vector<float> p = torus(generated, rng);
            double h = mean_spacing(*dense_cloud(p));
            Gauss g{rng};
            for (float& x : p) x = static_cast<float>(x + noise * h * g());
            char name[96];
            std::snprintf(name, sizeof name, "torus %zu (R = 1, r = 0.35), Gaussian noise %.3gh", generated, noise);
            ok = bench_cloud(name, *dense_cloud(p), true, h, reps) && ok;
        }
        for (const std::string& f : files) {
            examples::Cloud c = examples::load_cloud(f);
            std::vector<float> p;
            p.reserve(3 * c.finite.size());
            for (std::uint32_t i : c.finite) p.insert(p.end(), c.point(i), c.point(i) + 3);
            CloudXYZ::Ptr dense = dense_cloud(p);
            std::string name = c.name;
            if (c.has_non_finite()) name += " (" + std::to_string(c.count - c.finite.size()) + " NaN points dropped)";
            ok = bench_cloud(name, *dense, false, mean_spacing(*dense), reps) && ok;
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "bench_smoothing: %s\n", e.what());
        return 1;
    }
    return ok ? 0 : 1;
}
